"""Bundled scenes: where they live and how a bare name finds one."""

from __future__ import annotations

import os
import sys
from pathlib import Path

from ..errors import InputError

DEFAULT_SCENE = "pillars"


def scenes_dir() -> Path:
    """The folder of bundled scenes.

    Looked up in order: ``$VLREF_SCENES``; the source checkout's ``data/scenes`` (development and
    editable installs); ``<prefix>/share/vlref/scenes`` where ``pip install`` puts them.
    """
    env = os.environ.get("VLREF_SCENES")
    candidates = [Path(env)] if env else []
    candidates.append(Path(__file__).resolve().parents[2] / "data" / "scenes")
    candidates.append(Path(sys.prefix) / "share" / "vlref" / "scenes")
    for c in candidates:
        if c.is_dir():
            return c
    raise InputError(str(candidates[-1]), "", "bundled scenes not found (looked in "
                     + ", ".join(str(c) for c in candidates) + "; set VLREF_SCENES)")


def bundled_scenes() -> dict[str, Path]:
    """Bundled scene name -> file, sorted by name."""
    return {p.stem: p for p in sorted(scenes_dir().glob("*.toml"))}


def find_bundled(scene: str | Path | None) -> Path:
    """A path for ``scene``: None -> the default scene; a bare bundled name -> its file; else the path."""
    if scene is None:
        scene = DEFAULT_SCENE
    text = str(scene)
    path = Path(text)
    if path.suffix or os.sep in text or "/" in text:
        if not path.is_file():
            raise InputError(text, "", "scene file not found")
        return path
    scenes = bundled_scenes()
    if text not in scenes:
        if path.is_file():
            return path
        raise InputError(text, "", f"no such scene file or bundled scene (bundled: {', '.join(scenes)})")
    return scenes[text]
