"""``vlref sweep SPEC.toml``: techniques × a grid (or list) of ``--set`` overrides, measured against the reference.

Sweep file (TOML; paths relative to it)::

    scene = "urp_sun"                          # bundled name or scene file
    set = ["render.width=64", "render.height=36"]   # overrides of every point
    techniques = ["physical", "killzone"]      # default: the scene's render.technique
    metrics = ["error", "time", "flip"]        # default: ["error"]
    rel_tol = 1e-4                             # tolerance of the quadrature reference
    [grid]                                     # every combination, the last key varying fastest
    "render.steps" = [4, 8, 16]
    "medium.anisotropy" = [0.0, 0.6]
    # or, instead of [grid]: points = [["render.steps=4"], ["render.steps=8", "render.sampling=bayer4"]]

Each (point, technique) is an item (:mod:`vlref.work_items`) that renders the scene and compares its
inscatter with the quadrature reference (:func:`vlref.reference.render_reference`) of the same
scene; points that differ only in what the reference ignores (``render.technique``, ``steps``,
``sampling``, ``resolution``, ``precision``, ``exposure``, the parameters of techniques other than
``physical``) share one reference item.

Output folder (all or nothing, :func:`vlref.io.output_folders.output_dir`), the same bytes whatever the scheduler:

* ``<technique>/<point>.exr``: the item's inscatter (float32), its overrides in the header;
* ``reference/<n>.exr``: each reference's inscatter;
* ``summary.csv`` (and ``summary.parquet`` when ``pyarrow`` is installed), one row per item:
  ``item, technique, point``, one column per varied key, ``reference``, and per metric:
  ``error`` -> ``mean_abs, max_abs, mean_rel, max_rel, ref_sum, ref_max``
  (:func:`vlref.reference.bias.inscatter_error`: ``mean_rel = Σ e / ref_sum``, ``ref_sum = Σ max_c R``;
  ``max_rel = max e / ref_max``, ``ref_max = max R``; different denominators, so ``mean_rel`` exceeds
  ``max_rel`` when the error sits on pixels dimmer than the brightest),
  ``flip`` -> ``flip``, the mean HDR-FLIP of the final image against the reference's final image
  (empty when ``flip-evaluator`` is missing); ``file``;
* ``timings.csv`` (metric ``time``): ``item, seconds`` of each render and reference, wall clock where it
  ran. Times differ from run to run, so they stay out of ``summary.csv``.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import itertools
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .work_items import After, Item, run_items
from .errors import InputError
from .io.exr import write_exr
from .io.files import write_bytes, write_text
from .io.output_folders import output_dir
from .oracle.metrics import hdr_flip
from .reference import render_reference
from .reference.bias import inscatter_error
from .render import render, scene_hash
from .scene import load_scene
from .scene.load import parse_override
from .scene.model import TECHNIQUES
from .tomlfile import read_toml

__all__ = ["SweepSpec", "load_sweep", "sweep_items", "run_sweep", "METRICS"]

METRICS = ("error", "time", "flip")
ERROR_COLUMNS = ("mean_abs", "max_abs", "mean_rel", "max_rel", "ref_sum", "ref_max")


@dataclass(frozen=True)
class SweepSpec:
    """A parsed sweep file: ``points`` are tuples of override strings, ``columns`` the keys they vary."""

    source: str
    scene: str
    base: tuple[str, ...]
    techniques: tuple[str, ...]
    metrics: tuple[str, ...]
    points: tuple[tuple[str, ...], ...]
    columns: tuple[str, ...]
    rel_tol: float


def _strings(value, file: str, key: str) -> tuple[str, ...]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise InputError(file, key, f"must be a list of strings, got {value!r}")
    return tuple(value)


def load_sweep(path) -> SweepSpec:
    """Read and check a sweep file (module docstring); :class:`InputError` names the bad key."""
    path = Path(path)
    file = str(path)
    data = read_toml(path, "sweep file")
    unknown = sorted(set(data) - {"scene", "set", "techniques", "metrics", "rel_tol", "grid", "points"})
    if unknown:
        raise InputError(file, unknown[0], "unknown key (expected scene, set, techniques, metrics, rel_tol, "
                                           "grid, points)")
    scene = data.get("scene")
    if not isinstance(scene, str) or not scene:
        raise InputError(file, "scene", "must name a bundled scene or a scene file")
    if (path.parent / scene).is_file():
        scene = str(path.parent / scene)
    base = _strings(data.get("set", []), file, "set")
    techniques = _strings(data.get("techniques", []), file, "techniques")
    if [t for t in techniques if t not in TECHNIQUES]:
        raise InputError(file, "techniques", f"must be among {', '.join(TECHNIQUES)}, got {list(techniques)}")
    metrics = _strings(data.get("metrics", ["error"]), file, "metrics")
    if not metrics or [m for m in metrics if m not in METRICS]:
        raise InputError(file, "metrics", f"must be among {', '.join(METRICS)}, got {list(metrics)}")
    rel_tol = data.get("rel_tol", 1e-4)
    if not isinstance(rel_tol, (int, float)) or isinstance(rel_tol, bool) or not rel_tol > 0:
        raise InputError(file, "rel_tol", f"must be a number > 0, got {rel_tol!r}")
    if "grid" in data and "points" in data:
        raise InputError(file, "points", "give [grid] or points, not both")
    if "grid" in data:
        grid = data["grid"]
        if not isinstance(grid, dict) or not grid or not all(isinstance(v, list) and v for v in grid.values()):
            raise InputError(file, "grid", "must map KEY.PATH to non-empty lists of values")
        columns = tuple(grid)
        points = tuple(tuple(f"{k}={json.dumps(v)}" for k, v in zip(columns, combo))
                       for combo in itertools.product(*grid.values()))
    else:
        raw = data.get("points", [[]])
        if not isinstance(raw, list) or not raw:
            raise InputError(file, "points", "must be a non-empty list of lists of KEY.PATH=VALUE strings")
        points = tuple(_strings(p, file, f"points[{i}]") for i, p in enumerate(raw))
        columns = tuple(dict.fromkeys(o.split("=", 1)[0].strip() for p in points for o in p))
    for i, point in enumerate(points):
        for o in point:
            try:
                parse_override(o)
            except InputError as exc:
                raise InputError(file, f"points[{i}]", exc.reason) from None
    return SweepSpec(file, scene, base, techniques, metrics, points, columns, float(rel_tol))


def _reference_scene(scene, base):
    """``scene`` with what the reference ignores set as in ``base`` (module docstring)."""
    keep = ("technique", "steps", "sampling", "resolution", "precision", "exposure")
    render = dataclasses.replace(scene.render, **{k: getattr(base.render, k) for k in keep})
    techniques = dataclasses.replace(base.techniques, physical=scene.techniques.physical)
    return scene.replace(render=render, techniques=techniques)


def _reference(scene, rel_tol: float) -> dict:
    """Item: the reference's inscatter and final image and its error bound."""
    ref = render_reference(scene, rel_tol=rel_tol)
    return {"inscatter": ref.inscatter, "final": ref.final, "max_error": ref.max_error}


def _point(scene, reference: dict, metrics: tuple[str, ...]) -> dict:
    """Item: render ``scene``; its inscatter, the metric values (module docstring) and its render time."""
    result = render(scene)
    values = {}
    if "error" in metrics:
        values.update(inscatter_error(result.buffers["inscatter"], reference["inscatter"])[1])
    if "flip" in metrics:
        ref = reference["final"]
        flip = hdr_flip(ref, np.asarray(result.buffers["final"], dtype=np.float64), np.ones(ref.shape[:2], bool))
        values["flip"] = flip.mean if flip.available else ""
    return {"inscatter": result.buffers["inscatter"], "values": values, "seconds": sum(result.timings.values())}


def sweep_items(spec: SweepSpec):
    """``(items, rows)``: the reference and point items (:class:`vlref.work_items.Item`) and, per point item,
    its summary row without metric values. Every scene is loaded here, so bad overrides fail before any
    work (``InputError`` naming the sweep file and the point)."""
    base = load_scene(spec.scene, spec.base)
    techniques = spec.techniques or (base.render.technique,)
    references: dict[str, str] = {}
    ref_items, point_items, rows = [], [], []
    for i, point in enumerate(spec.points):
        for technique in techniques:
            try:
                scene = load_scene(spec.scene, [*spec.base, *point, f'render.technique="{technique}"'])
            except InputError as exc:
                raise InputError(spec.source, f"points[{i}]", f"{exc.path}: {exc.reason}") from None
            ref_scene = _reference_scene(scene, base)
            h = scene_hash(ref_scene)
            if h not in references:
                references[h] = f"reference/{len(references)}"
                ref_items.append(Item(references[h], _reference, (ref_scene, spec.rel_tol)))
            key = f"{technique}/{i:03d}"
            point_items.append(Item(key, _point, (scene, After(references[h]), spec.metrics)))
            values = {".".join(map(str, parse_override(o)[0])): parse_override(o)[1] for o in point}
            rows.append({"item": key, "technique": technique, "point": i,
                         **{c: values.get(c, "") for c in spec.columns},
                         "reference": int(references[h].split("/")[1]), "file": f"{key}.exr",
                         "overrides": list(point)})
    return ref_items + point_items, rows


def _csv(rows: list[dict], columns: list[str]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([json.dumps(row[c]) if isinstance(row[c], (list, dict, bool)) else row[c] for c in columns])
    return buf.getvalue()


def _parquet(rows: list[dict], columns: list[str]) -> bytes | None:
    """The rows as Parquet bytes, or None without ``pyarrow``."""
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return None
    table = pa.table({c: [row[c] if not isinstance(row[c], (list, dict)) else json.dumps(row[c]) for row in rows]
                      for c in columns})
    buf = io.BytesIO()
    pq.write_table(table, buf)
    return buf.getvalue()


def run_sweep(spec: SweepSpec, output, scheduler: str | None = None, quiet: bool = False) -> list[dict]:
    """Run the sweep on ``scheduler`` (:func:`vlref.work_items.run_items`) into ``output``; returns the summary
    rows (dicts with the columns of ``summary.csv``, metric values as numbers)."""
    items, rows = sweep_items(spec)
    by_item = {row["item"]: row for row in rows}
    seconds: dict[str, float] = {}
    with output_dir(output) as tmp:
        def write(key, result, item_seconds):
            (tmp / key).parent.mkdir(parents=True, exist_ok=True)
            if key in by_item:
                row = by_item[key]
                row.update(result["values"])
                write_exr(tmp / row["file"], result["inscatter"], metadata={"overrides": row["overrides"]})
                seconds[key] = result["seconds"]
            else:
                write_exr(tmp / f"{key}.exr", result["inscatter"], metadata={"max_error": repr(result["max_error"])})
                seconds[key] = item_seconds

        run_items(items, scheduler, write, desc="sweep", quiet=quiet)
        metric_columns = [*(ERROR_COLUMNS if "error" in spec.metrics else ()),
                          *(("flip",) if "flip" in spec.metrics else ())]
        columns = ["item", "technique", "point", *spec.columns, "reference", *metric_columns, "file"]
        write_text(tmp / "summary.csv", _csv(rows, columns))
        parquet = _parquet(rows, columns)
        if parquet is not None:
            write_bytes(tmp / "summary.parquet", parquet)
        if "time" in spec.metrics:
            times = [{"item": item.key, "seconds": seconds[item.key]} for item in items]
            write_text(tmp / "timings.csv", _csv(times, ["item", "seconds"]))
    return rows
