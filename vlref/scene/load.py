"""Read a scene file (TOML or JSON), apply ``--set key.path=value`` overrides, validate.

``load_scene("pillars")`` finds a bundled scene by bare name; any other string is a path.
Paths inside a scene (meshes, cookies, noise volumes) are relative to the scene file.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any, Iterable

from ..errors import InputError
from ..tomlfile import TOMLDecodeError, loads as toml_loads
from .bundled import find_bundled
from .model import Scene
from .schema import build, join_path

__all__ = ["load_scene", "parse_scene", "apply_overrides", "parse_override"]

CLI = "<command line>"


def load_scene(scene: str | Path | None = None, overrides: Iterable[str] = ()) -> Scene:
    """Load, override and validate a scene.

    Parameters
    ----------
    scene : path, bundled scene name, or None for the bundled default scene.
    overrides : strings ``"key.path=value"``; ``value`` is read as a TOML value
        (``20``, ``[1, 2, 3]``, ``"half"``) and, failing that, as a bare string.
    """
    path = find_bundled(scene)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(str(path), "", f"cannot read scene file ({exc.strerror or exc})") from None
    data = parse_scene(text, str(path))
    overrides = [str(o) for o in overrides]
    parsed = [parse_override(o) for o in overrides]
    data = apply_overrides(data, parsed, str(path))
    try:
        scene_obj = build(Scene, data, str(path), path.resolve().parent)
    except InputError as exc:
        raise _blame_override(exc, overrides, parsed) from None
    return scene_obj.replace(source=str(path))


def _blame_override(exc: InputError, texts: list[str], parsed: list[tuple[list[str | int], Any]]) -> InputError:
    """``exc`` re-addressed to ``<command line>: --set KEY=VALUE`` when its key lies under an override's key
    (the last such override: the value that won); else ``exc`` unchanged."""
    for text, (parts, _) in reversed(list(zip(texts, parsed))):
        key = ""
        for part in parts:
            key = join_path(key, part)
        if exc.path == key or exc.path.startswith((key + ".", key + "[")):
            return InputError(CLI, f"--set {text.strip()}", exc.reason)
    return exc


def parse_scene(text: str, file: str) -> dict:
    """Parse TOML (or JSON, by the ``.json`` suffix) into plain dicts and lists."""
    if file.lower().endswith(".json"):
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputError(file, f"line {exc.lineno}", f"invalid JSON: {exc.msg}") from None
    else:
        try:
            data = toml_loads(text)
        except TOMLDecodeError as exc:
            raise InputError(file, "", f"invalid TOML: {exc}") from None
    if not isinstance(data, dict):
        raise InputError(file, "", "the top level must be a table")
    return data


def parse_override(text: str) -> tuple[list[str | int], Any]:
    """``"lights.0.intensity=20"`` -> ``(["lights", 0, "intensity"], 20)``."""
    if "=" not in text:
        raise InputError(CLI, f"--set {text}", "expected KEY.PATH=VALUE")
    key, raw = text.split("=", 1)
    parts: list[str | int] = [int(p) if p.isdigit() else p for p in key.strip().split(".")]
    if not key.strip() or any(p == "" for p in parts):
        raise InputError(CLI, f"--set {text}", "empty key")
    try:
        value = toml_loads(f"v = {raw}")["v"]
    except TOMLDecodeError:
        value = raw
    return parts, value


def apply_overrides(data: dict, overrides: list[tuple[list[str | int], Any]], file: str) -> dict:
    """Set each ``(key path, value)`` in a deep copy of ``data``; tables are created as needed."""
    data = copy.deepcopy(data)
    for parts, value in overrides:
        node: Any = data
        where = ""
        for i, part in enumerate(parts):
            last = i == len(parts) - 1
            if isinstance(node, list):
                if not isinstance(part, int) or part >= len(node):
                    raise InputError(CLI, join_path(where, part) if isinstance(part, int) else f"{where}.{part}",
                                     f"no such list element in {file} (the list has {len(node)})")
            elif isinstance(node, dict):
                if isinstance(part, int):
                    raise InputError(CLI, f"{where}.{part}", f"{where or 'the top level'} is a table, not a list")
                if not last and part not in node:
                    node[part] = {}
            else:
                raise InputError(CLI, where, "is a value, not a table or list")
            where = join_path(where, part)
            if last:
                node[part] = value
            else:
                node = node[part]
    return data
