"""The golden suite: vlref's own renders of every bundled scene, stored to catch any change of behaviour.

``vlref golden build`` renders each *entry* (bundled scene x applicable technique) with the settings of
``vlref/data/golden_suite.toml`` (size, steps, shadow-map size cap) and writes, under ``data/golden/``,
``<technique>/<scene>/<buffer>.exr`` (float32, ZIP) for each listed buffer, plus ``manifest.json``:

* ``format``, ``vlref_version``, ``numpy``/``numba`` versions (informative), ``suite`` (the suite file's
  settings) and, per entry: ``name`` (``scene/technique``), ``scene``, ``technique``, ``overrides`` (the
  ``--set`` list that reproduces it with ``vlref render``), ``scene_hash`` and ``settings`` (the resolved
  scene, :func:`vlref.render.scene_settings_json`), ``preset``, and ``files``: buffer -> ``{path, sha256}``.

``vlref golden verify`` fails (exit 1) when a golden file's sha256 differs from the manifest (tampering
or a hand edit), a file is missing, the suite settings or the scene (``scene_hash``) changed since the
build (stale goldens: rebuild deliberately), or a re-render differs from a golden beyond the manifest's
tolerance preset (``float32``: last-ulp differences of exp/pow between machines pass, code changes
fail). Exit 2: bad input (unreadable manifest, unknown option). The command line is :mod:`vlref.cli.golden`.

Applicability (which techniques render which scene) is each technique's ``applies`` rule in the
registry (:data:`vlref.techniques.TECHNIQUES`): ``physical``, ``killzone``, ``slightlymad``, ``froxel``
every scene; ``urp`` scenes with a directional light (:func:`vlref.techniques.urp.has_main_light`);
``radial`` scenes whose radial light projects inside the frame (:func:`vlref.techniques.radial.light_in_frame`).
The suite's ``techniques`` default to every registered technique.

Animated scenes (an ``[animation]`` table) are rendered only by the suite's ``animation_techniques``,
one entry per frame of ``animation_frames``, named ``scene@F/technique`` and stored under
``<technique>/<scene>@F/``.
"""

from __future__ import annotations

import fnmatch
import hashlib
import json
import os
import shutil
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from .. import __version__
from ..work_items import Item, run_items
from ..errors import InputError
from ..io.exr import write_exr
from ..io.files import write_text
from ..io.images import read_image
from ..io.output_folders import output_dir
from ..render import render, scene_hash, scene_settings_json
from ..scene import bundled_scenes, load_scene
from ..sequence import render_sequence
from ..techniques import TECHNIQUES
from ..tomlfile import read_toml
from .compare import compare_arrays
from .presets import tolerance

__all__ = ["Entry", "GoldenSuite", "load_suite", "suite_entries", "select_entries", "render_entry",
           "build", "build_dir", "verify", "Outcome", "SUITE_FILE", "MANIFEST", "find_golden_dir",
           "golden_dir_candidates"]

SUITE_FILE = Path(__file__).resolve().parents[1] / "data" / "golden_suite.toml"
CHECKOUT_GOLDEN = Path(__file__).resolve().parents[2] / "data" / "golden"
MANIFEST = "manifest.json"
FORMAT = 1


def golden_dir_candidates() -> list[Path]:
    """Where the golden suite is looked for, in order: ``$VLREF_GOLDEN`` alone when set; else the source
    checkout's ``data/golden`` (development and editable installs) and ``<prefix>/share/vlref/golden``, where
    ``pip install`` puts it (``setup.cfg`` data_files), as :func:`vlref.scene.bundled.scenes_dir` does."""
    env = os.environ.get("VLREF_GOLDEN")
    if env:
        return [Path(env)]
    return [CHECKOUT_GOLDEN, Path(sys.prefix) / "share" / "vlref" / "golden"]


def find_golden_dir() -> Path:
    """The first candidate folder holding a manifest; :class:`InputError` naming every place looked at."""
    candidates = golden_dir_candidates()
    for c in candidates:
        if (c / MANIFEST).is_file():
            return c
    raise InputError("<command line>", "--dir", "no golden suite found (looked for manifest.json in "
                     + ", ".join(str(c) for c in candidates) + "); point --dir at a golden folder or set VLREF_GOLDEN")


def build_dir() -> Path:
    """Where ``golden build`` writes without ``--dir``: ``$VLREF_GOLDEN``, else the checkout's ``data/golden``."""
    env = os.environ.get("VLREF_GOLDEN")
    if env:
        return Path(env)
    if CHECKOUT_GOLDEN.parent.joinpath("scenes").is_dir():
        return CHECKOUT_GOLDEN
    raise InputError("<command line>", "--dir", "not running from a source checkout: name the folder to build in")



@dataclass(frozen=True)
class GoldenSuite:
    """The settings of ``golden_suite.toml`` (see its comments)."""

    width: int
    height: int
    steps: int
    shadow_resolution: int
    preset: str
    buffers: tuple[str, ...]
    techniques: tuple[str, ...]
    technique_overrides: tuple[tuple[str, tuple[str, ...]], ...] = ()
    animation_frames: tuple[int, ...] = (0,)
    animation_techniques: tuple[str, ...] = ()

    def as_dict(self) -> dict:
        return {"width": self.width, "height": self.height, "steps": self.steps,
                "shadow_resolution": self.shadow_resolution, "preset": self.preset,
                "buffers": list(self.buffers), "techniques": list(self.techniques),
                "technique_overrides": {t: list(o) for t, o in self.technique_overrides},
                "animation_frames": list(self.animation_frames),
                "animation_techniques": list(self.animation_techniques)}


@dataclass(frozen=True)
class Entry:
    """One golden: a bundled scene under one technique, with the ``--set`` overrides that produce it."""

    scene: str
    technique: str
    overrides: tuple[str, ...]
    frame: int | None = None

    @property
    def name(self) -> str:
        """``scene/technique``; ``scene@frame/technique`` for a frame of an animated scene."""
        scene = self.scene if self.frame is None else f"{self.scene}@{self.frame}"
        return f"{scene}/{self.technique}"


def load_suite(path=SUITE_FILE) -> GoldenSuite:
    """Read and check a suite file; :class:`InputError` names the bad key."""
    path = Path(path)
    data = read_toml(path, "suite file")
    ints = {}
    for key in ("width", "height", "steps", "shadow_resolution"):
        value = data.get(key)
        if not isinstance(value, int) or isinstance(value, bool) or value < 1:
            raise InputError(str(path), key, f"must be an integer >= 1, got {value!r}")
        ints[key] = value
    preset = data.get("preset", "float32")
    try:
        tolerance(str(preset))
    except InputError as exc:
        raise InputError(str(path), "preset", exc.reason) from None
    buffers = tuple(data.get("buffers", ("final",)))
    techniques = tuple(data.get("techniques", TECHNIQUES))
    bad = [t for t in techniques if t not in TECHNIQUES]
    if bad or not techniques:
        raise InputError(str(path), "techniques", f"must name techniques among {', '.join(TECHNIQUES)}, got {bad}")
    if not buffers or not all(isinstance(b, str) and b.isidentifier() for b in buffers):
        raise InputError(str(path), "buffers", f"must be a non-empty list of buffer names, got {list(buffers)}")
    extra = data.get("technique_overrides", {})
    if not isinstance(extra, dict) or any(t not in techniques or not isinstance(o, list)
                                          or not all(isinstance(x, str) for x in o) for t, o in extra.items()):
        raise InputError(str(path), "technique_overrides", "must map suite techniques to lists of KEY.PATH=VALUE")
    frames = data.get("animation_frames", [0])
    if not isinstance(frames, list) or not frames or not all(
            isinstance(f, int) and not isinstance(f, bool) and f >= 0 for f in frames):
        raise InputError(str(path), "animation_frames", f"must be a non-empty list of frames >= 0, got {frames!r}")
    anim_techniques = data.get("animation_techniques", list(techniques))
    if not isinstance(anim_techniques, list) or any(t not in techniques for t in anim_techniques):
        raise InputError(str(path), "animation_techniques", f"must list suite techniques, got {anim_techniques!r}")
    return GoldenSuite(preset=str(preset), buffers=buffers, techniques=techniques,
                       technique_overrides=tuple((t, tuple(o)) for t, o in extra.items()),
                       animation_frames=tuple(frames), animation_techniques=tuple(anim_techniques), **ints)


def _overrides(suite: GoldenSuite, scene, technique: str) -> tuple[str, ...]:
    out = [f"render.width={suite.width}", f"render.height={suite.height}", f"render.steps={suite.steps}",
           f'render.technique="{technique}"']
    for i, light in enumerate(scene.lights):
        if light.shadows is not None and light.shadows.resolution > suite.shadow_resolution:
            out.append(f"lights.{i}.shadows.resolution={suite.shadow_resolution}")
    out += dict(suite.technique_overrides).get(technique, ())
    return tuple(out)


def suite_entries(suite: GoldenSuite) -> list[Entry]:
    """Every (bundled scene, applicable technique) pair, scenes by name, techniques in suite order; an
    animated scene gets one entry per frame of ``animation_frames`` (``render.frame=F`` appended)."""
    entries = []
    for name, path in bundled_scenes().items():
        base = load_scene(path, [f"render.width={suite.width}", f"render.height={suite.height}"])
        animated = base.animation is not None
        frames = suite.animation_frames if animated else (None,)
        for technique in suite.techniques:
            if TECHNIQUES[technique].applies(base) and (not animated or technique in suite.animation_techniques):
                over = _overrides(suite, base, technique)
                entries += [Entry(name, technique, over) if f is None else
                            Entry(name, technique, over + (f"render.frame={f}",), f) for f in frames]
    return entries


def render_entry(entry: Entry, buffers: Sequence[str]):
    """``({buffer: array}, scene)`` of one entry; a buffer the technique lacks is an :class:`InputError`.

    A temporal entry (``froxel`` with ``temporal = true``) at frame F renders frames 0..F in sequence
    (:func:`vlref.sequence.render_sequence`) and keeps the last."""
    scene = load_scene(entry.scene, entry.overrides)
    if scene.render.technique == "froxel" and scene.techniques.froxel.temporal:
        result = list(render_sequence(scene, range(scene.render.frame + 1)))[-1][1]
    else:
        result = render(scene)
    missing = [b for b in buffers if b not in result.buffers]
    if missing:
        raise InputError(str(SUITE_FILE), "buffers", f"{entry.name} has no buffer(s) {', '.join(missing)}")
    return {b: result.buffers[b] for b in buffers}, scene


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def select_entries(entries: list[Entry], only: Sequence[str] | None) -> list[Entry]:
    """The entries whose name matches one of the ``only`` globs (all of them when ``only`` is empty).

    A glob that matches no entry is bad input (:class:`InputError`, named ``<command line>: --only``): a typo
    must not turn a check into one that passes on nothing."""
    if not only:
        return entries
    unmatched = [p for p in only if not any(fnmatch.fnmatchcase(e.name, p) for e in entries)]
    if unmatched:
        example = entries[0].name if entries else "pillars/physical"
        raise InputError("<command line>", "--only", f"{', '.join(map(repr, unmatched))} matches no entry of the "
                         f"suite (names are scene/technique, e.g. {example!r}; `vlref golden list` lists them)")
    return [e for e in entries if any(fnmatch.fnmatchcase(e.name, pattern) for pattern in only)]


def read_manifest(golden_dir) -> dict:
    """The manifest of ``golden_dir``; :class:`InputError` when it is missing or malformed."""
    path = Path(golden_dir) / MANIFEST
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(str(path), "", "no golden manifest (run `vlref golden build`)") from None
    except (OSError, json.JSONDecodeError) as exc:
        raise InputError(str(path), "", f"unreadable manifest ({exc})") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("entries"), list):
        raise InputError(str(path), "format", f"not a vlref golden manifest of format {FORMAT}")
    for k, e in enumerate(data["entries"]):
        if not (isinstance(e, dict) and isinstance(e.get("name"), str) and isinstance(e.get("files"), dict)):
            raise InputError(str(path), f"entries[{k}]", "needs a name and files")
    return data


def build(golden_dir=None, suite_path=SUITE_FILE, only: Sequence[str] | None = None,
          log=print, scheduler: str | None = None, quiet: bool = False) -> dict:
    """Render the suite (or the ``only`` glob patterns of entry names) into ``golden_dir`` (default
    :func:`build_dir`); returns the manifest.

    With ``only``, the other entries of an existing manifest are kept. Files of entries no longer in the
    suite are removed. All files are written atomically (:func:`vlref.io.output_folders.output_dir`). Entries are
    independent items rendered on ``scheduler`` (:func:`vlref.work_items.run_items`); the files and the
    manifest are the same bytes whatever the scheduler.
    """
    import numba

    suite = load_suite(suite_path)
    golden_dir = Path(golden_dir) if golden_dir is not None else build_dir()
    entries = suite_entries(suite)
    selected = select_entries(entries, only)
    old = {}
    if only and (golden_dir / MANIFEST).exists():
        old = {e["name"]: e for e in read_manifest(golden_dir)["entries"]}
    records = {}
    by_name = {entry.name: entry for entry in selected}
    with output_dir(golden_dir) as tmp:
        def write(key, rendered, seconds):
            entry = by_name[key]
            buffers, scene = rendered
            record = {"name": entry.name, "scene": entry.scene, "technique": entry.technique,
                      "overrides": list(entry.overrides), "scene_hash": scene_hash(scene),
                      "settings": json.loads(scene_settings_json(scene)), "preset": suite.preset, "files": {}}
            meta = {"scene_hash": record["scene_hash"], "technique": entry.technique, "golden": entry.name}
            for name, array in buffers.items():
                rel = f"{entry.technique}/{entry.name.split('/')[0]}/{name}.exr"
                (tmp / rel).parent.mkdir(parents=True, exist_ok=True)
                write_exr(tmp / rel, array, metadata=meta)
                record["files"][name] = {"path": rel, "sha256": _sha256(tmp / rel)}
            records[entry.name] = record
            log(f"built {entry.name} ({seconds:.2f} s)")

        run_items([Item(e.name, render_entry, (e, suite.buffers)) for e in selected], scheduler, write,
                  desc="golden build", quiet=quiet)
        kept = [old[e.name] if e.name not in records else records[e.name] for e in entries
                if e.name in records or e.name in old]
        manifest = {"format": FORMAT, "vlref_version": __version__, "numpy": np.__version__,
                    "numba": numba.__version__, "suite": suite.as_dict(), "entries": kept}
        write_text(tmp / MANIFEST, json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    keep = {f["path"] for e in manifest["entries"] for f in e["files"].values()}
    for e in old.values():  # entries left out of the suite: remove their files (only ours)
        for f in e["files"].values():
            if f["path"] not in keep:
                (golden_dir / f["path"]).unlink(missing_ok=True)
    for folder in sorted((p for p in golden_dir.rglob("*") if p.is_dir()), reverse=True):
        if not any(folder.iterdir()):
            shutil.rmtree(folder)
    return manifest


@dataclass
class Outcome:
    """The verdict on one entry: ``problems`` empty = pass; ``margins`` buffer -> failing fraction / bound."""

    name: str
    problems: list
    margins: dict


def _changed_keys(old, new, prefix: str = "") -> list[str]:
    """Dotted keys whose values differ between two settings trees (``+key`` added, ``-key`` removed)."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for k in sorted(set(old) | set(new)):
            key = f"{prefix}.{k}" if prefix else str(k)
            if k not in old:
                out.append(f"+{key}")
            elif k not in new:
                out.append(f"-{key}")
            else:
                out += _changed_keys(old[k], new[k], key)
        return out
    return [] if old == new else [prefix or "<settings>"]


def _check_files(golden_dir: Path, record: dict) -> list[str]:
    problems = []
    for buf, f in record["files"].items():
        path = golden_dir / str(f.get("path", ""))
        if not path.is_file():
            problems.append(f"{buf}: golden file {path} missing")
        elif _sha256(path) != f.get("sha256"):
            problems.append(f"{buf}: checksum of {path} differs from the manifest (tampered or edited; "
                            "rebuild deliberately with `vlref golden build`)")
    return problems


def verify(golden_dir=None, suite_path=SUITE_FILE, only: Sequence[str] | None = None,
           preset: str | None = None, log=print, scheduler: str | None = None,
           quiet: bool = False) -> list[Outcome]:
    """Check checksums, staleness and re-renders of the goldens in ``golden_dir`` (default
    :func:`find_golden_dir`; module docstring); one outcome per entry.

    The re-renders are independent items run on ``scheduler`` (:func:`vlref.work_items.run_items`) and
    compared here as they arrive; the outcomes are in entry-name order whatever the scheduler.
    """
    golden_dir = Path(golden_dir) if golden_dir is not None else find_golden_dir()
    manifest = read_manifest(golden_dir)
    suite = load_suite(suite_path)
    outcomes = []
    if manifest.get("suite") != suite.as_dict():
        outcomes.append(Outcome("<suite>", [f"suite settings changed since the build: manifest "
                                            f"{manifest.get('suite')} vs {suite_path} {suite.as_dict()}"], {}))
    expected = {e.name: e for e in select_entries(suite_entries(suite), only)}
    recorded = {e["name"]: e for e in manifest["entries"]}
    for name in sorted(expected.keys() - recorded.keys()):
        outcomes.append(Outcome(name, ["in the suite but not in the manifest (rebuild)"], {}))
    if not only:
        for name in sorted(recorded.keys() - expected.keys()):
            outcomes.append(Outcome(name, ["in the manifest but no longer in the suite (rebuild)"], {}))
    for o in outcomes:
        log(f"FAILED {o.name}: {o.problems[0]}")
    checked: dict[str, Outcome] = {}

    def report(name, problems, margins, seconds):
        checked[name] = Outcome(name, problems, margins)
        state = "ok" if not problems else "FAILED"
        log(f"{state:6s} {name} ({seconds:.2f} s)" + "".join(f"\n       {p}" for p in problems))

    def compare(name, rendered, seconds):
        record = recorded[name]
        buffers, scene = rendered
        problems, margins = [], {}
        if scene_hash(scene) != record.get("scene_hash"):
            keys = _changed_keys(record.get("settings"), json.loads(scene_settings_json(scene)))
            problems.append(f"the scene changed since the build (scene_hash differs: {', '.join(keys[:5])}"
                            f"{' ...' if len(keys) > 5 else ''}); rebuild deliberately")
        tol = preset or record.get("preset", suite.preset)
        for buf, array in buffers.items():
            ref = read_image(golden_dir / record["files"][buf]["path"])
            test = np.asarray(array, dtype=np.float64)
            mask = np.isfinite(ref).all(axis=2)
            result = compare_arrays(ref, test, tol, mask, flip=False,
                                    names=(str(golden_dir / record["files"][buf]["path"]), f"{name} {buf}"))
            frac, bound = result.metrics["frac_failing"], result.tolerance.max_fail_fraction
            margins[buf] = (frac, bound, result.metrics["max_abs"])
            if not result.passed:
                problems.append(f"{buf}: differs beyond preset {tol}: " + result.summary().replace("\n", "; "))
        report(name, problems, margins, seconds)

    items = []
    for name in sorted(expected.keys() & recorded.keys()):
        record, entry = recorded[name], expected[name]
        problems = _check_files(golden_dir, record)
        if list(entry.overrides) != record.get("overrides"):
            problems.append(f"overrides changed: manifest {record.get('overrides')} vs suite {list(entry.overrides)}")
        if problems:
            report(name, problems, {}, 0.0)
        else:
            items.append(Item(name, render_entry, (entry, list(record["files"]))))
    run_items(items, scheduler, compare, desc="golden verify", quiet=quiet)
    return outcomes + [checked[name] for name in sorted(checked)]
