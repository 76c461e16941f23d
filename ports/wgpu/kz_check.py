"""Check the WebGPU killzone port against vlref: every variant, pass by pass, and the conformance suite.

    python ports/wgpu/kz_check.py [--size 160x90] [--set K=V ...] [--variants a,b] [--suite] [-o DIR]

Per variant (:mod:`kz_variants`) on its scene (:data:`SCENES`) at the size asked: the port renders (a raster
variant re-renders passes 1-3 with its switches; the others re-run passes 4-9 on the faithful raster buffers),
exports its buffers, pass outputs and final frame (:func:`kz_port.export`, docs/PORTING.md), and
``vlref verdict`` judges it (:func:`vlref.oracle.verdict.judge`): every pass against ``vlref march`` on the
port's own buffers, and its depth, shadow maps, scene colour and final frame against the scene. The tables
name the first failing comparison of each variant and its margins (value / bound of each check; a failing
pixel over a bound of 0 is ``inf``). ``--suite`` runs every scene of data/conformance the port's scope covers,
at its own size, and lists the refusals with their reasons.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import kz_port  # noqa: E402
import kz_scene  # noqa: E402
from vlref.errors import InputError  # noqa: E402
from kz_variants import VARIANTS  # noqa: E402

SUITE = HERE.parents[1] / "data" / "conformance"
SCENES = {"pillars_point": HERE / "scenes" / "pillars_point.toml",
          **{p.stem: p for p in sorted(SUITE.glob("*.toml"))}}
"""The scenes variants name (``Variant.scene``): the port's own and the conformance suite's."""
SCENE = SCENES["pillars_point"]

PASSES = kz_port.PASSES


def size_overrides(scene_path, width: int, height: int) -> list[str]:
    """``render.width/height`` near ``width x height`` keeping the parity of the scene's own size, so that
    a scene written at an odd size (the downsample's partial last block) stays odd: 160x90 -> 161x91."""
    own = kz_scene.load(str(scene_path)).render
    w = width + (own.width % 2 != width % 2)
    h = height + (own.height % 2 != height % 2)
    return [f"render.width={w}", f"render.height={h}"]


def compare(ref_path: Path, test, preset: str, ignore_sky: bool = False, overrides=None):
    """``vlref compare`` of a vlref EXR with a port array (a report: passed, checks, metrics)."""
    from vlref.io.images import read_image
    from vlref.oracle.compare import build_mask, compare_arrays
    from vlref.oracle.presets import tolerance

    ref = read_image(ref_path)
    test = np.asarray(test)
    test = test[..., None] if test.ndim == 2 else test
    mask = build_mask(ref, ignore_sky="ref") if ignore_sky else None
    return compare_arrays(ref, test, tolerance(preset, overrides), mask, flip=False)


@dataclass
class PassResult:
    """One pass of one variant: its verdict, each check's margin (value / bound), and why it failed."""

    name: str
    preset: str
    passed: bool
    margins: dict = field(default_factory=dict)
    failing: int = 0
    compared: int = 0
    group: str = "own buffers"
    reason: str = ""

    @property
    def worst(self) -> float:
        return max(self.margins.values(), default=0.0 if self.passed else math.inf)


@dataclass
class VariantResult:
    name: str
    scene: str
    size: str
    passes: list

    @property
    def passed(self) -> bool:
        return all(p.passed for p in self.passes)

    @property
    def caught_by(self):
        """The first failing pass in pipeline order (None when every pass passes)."""
        return next((p for p in self.passes if not p.passed), None)

    @property
    def worst(self) -> float:
        """The largest margin over every pass and check."""
        return max((p.worst for p in self.passes), default=math.inf)


def pass_rows(passes: dict, marched: Path):
    """``[(port pass, vlref buffer, preset, report)]`` of a faithful port against a ``vlref march --stages``
    folder (the walk-through's ``vlref compare`` commands, one per pass)."""
    return [(p, r, preset or "gpu-half", compare(marched / f"{r}.exr", passes[p], preset or "gpu-half",
                                                 ignore_sky=(p == "depth_lo")))
            for p, r, preset in PASSES]


def render_and_march(out_dir: Path, overrides=(), dev=None, scene_path=SCENE):
    """The faithful port rendered and exported to ``out_dir/port``, vlref marched into ``out_dir/marched``:
    ``(port, passes, marched_dir, seconds of vlref march)``."""
    from vlref.cli import main

    scene = kz_scene.load(str(scene_path), overrides)
    port = kz_port.KillzonePort(scene, dev)
    passes = port.run("faithful")
    manifest = kz_port.export(port, out_dir / "port", str(scene_path), overrides, passes)
    start = time.perf_counter()
    if main(["march", str(manifest), "-o", str(out_dir / "marched"), "--stages", "-q"]) != 0:
        raise RuntimeError("vlref march failed on the port's buffers")
    return port, passes, out_dir / "marched", time.perf_counter() - start


def verdict(manifest: Path, preset: str, cache: dict | None):
    """:func:`vlref.oracle.verdict.judge` of a port manifest, sharing ``cache`` between a scene's variants."""
    from vlref.oracle.verdict import judge

    return judge(manifest, preset=preset, cache=cache)


def rows_of(v) -> list[PassResult]:
    """A verdict's comparisons as :class:`PassResult` rows, in the verdict's order (own buffers first)."""
    return [PassResult(p.name, p.preset, p.passed, p.metrics.get("margins", {}), p.metrics.get("failing_pixels", 0),
                       p.metrics.get("compared_pixels", 0), p.group, p.reason) for p in v.passes]


@dataclass
class SceneRun:
    """One scene at one size on one device: the faithful port (its raster passes shared by the post-pass
    variants) and the verdict's cache."""

    name: str
    path: Path
    overrides: list
    port: object
    out: Path
    cache: dict = field(default_factory=dict)


def scene_run(name: str, size, extra=(), dev=None, out: Path | None = None) -> SceneRun:
    path = SCENES[name]
    overrides = (size_overrides(path, *size) if size else []) + list(extra)
    out = Path(out or tempfile.mkdtemp(prefix=f"kz-{name}-"))
    port = kz_port.KillzonePort(kz_scene.load(str(path), overrides), dev)
    return SceneRun(name, path, overrides, port, out)


def judge_variant(run: SceneRun, variant: str, dev=None) -> VariantResult:
    """The verdict on ``variant`` on ``run``'s scene (module docstring), comparison by comparison."""
    spec = VARIANTS[variant]
    port = run.port
    if spec.raster:
        port = kz_port.KillzonePort(run.port.scene, dev or (run.port.adapter, run.port.device), variant)
    passes = port.run(variant)
    manifest = kz_port.export(port, run.out / variant, str(run.path), run.overrides, passes, spec.preset)
    size = f"{port.cam.width}x{port.cam.height}"
    try:
        rows = rows_of(verdict(manifest, spec.preset, run.cache))
    except InputError as exc:   # the verdict refuses the port's files (e.g. infinite values): a failure with its reason
        rows = [PassResult("port files", spec.preset, False, reason=str(exc))]
    return VariantResult(variant, run.name, size, rows)


@dataclass
class SuiteRow:
    scene: str
    size: str
    refused: str           # the port's reason, "" when it ran
    passes: list


def run_suite(dev=None, size=None, extra=(), out: Path | None = None) -> list[SuiteRow]:
    """Every conformance scene at its own size (or ``size``): the faithful port judged pass by pass, or the
    port's refusal with its reason (a scene outside its scope, or one vlref's killzone rejects)."""
    rows = []
    for name, path in SCENES.items():
        if path.parent != SUITE:
            continue
        overrides = ['render.technique="killzone"'] + (size_overrides(path, *size) if size else []) + list(extra)
        try:
            scene = kz_scene.load(str(path), overrides)
            port = kz_port.KillzonePort(scene, dev)
        except (ValueError, InputError) as exc:
            rows.append(SuiteRow(name, "", str(exc), []))
            continue
        target = Path(out or tempfile.mkdtemp(prefix="kz-suite-")) / name
        manifest = kz_port.export(port, target, str(path), overrides, port.run("faithful"))
        v = verdict(manifest, "gpu-half", None)
        rows.append(SuiteRow(name, f"{port.cam.width}x{port.cam.height}", "", rows_of(v)))
    return rows


def _fmt(x: float) -> str:
    return "inf" if math.isinf(x) else f"{x:.3g}x"


VARIANT_HEADER = ("| variant | scene | size | expected | result | caught by (first failing comparison) | there: "
                  "failing pixels, mean-error margin | worst margin (every comparison) |\n|---|---|---|---|---|---|---|---|")


def variant_row(r: VariantResult) -> str:
    """One row of the variant table (:data:`VARIANT_HEADER`)."""
    spec = VARIANTS[r.name]
    c = r.caught_by
    caught = f"{c.name} ({c.group}, {c.preset})" if c else "-"
    there = (f"{c.failing} of {c.compared}, {_fmt(c.margins.get('mean_abs_error', 0.0))}" if c and c.compared
             else (c.reason[:60] if c else "-"))
    return (f"| `{r.name}`: {spec.description} | {r.scene} | {r.size} | {spec.expect} | "
            f"{'PASS' if r.passed else 'FAIL'} | {caught} | {there} | {_fmt(r.worst)} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="160x90")
    ap.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    ap.add_argument("--variants", default=None, help="comma-separated variant names (default: all)")
    ap.add_argument("--suite", action="store_true", help="run the conformance suite instead of the variants")
    ap.add_argument("-o", "--output", default=None, help="keep the port and vlref buffers here")
    args = ap.parse_args(argv)
    out = Path(args.output or tempfile.mkdtemp(prefix="kz-check-"))
    dev = kz_port.device()
    if args.suite:
        ok = True
        print("| scene | size | result | worst margin | refused because |\n|---|---|---|---|---|")
        for row in run_suite(dev, extra=args.set, out=out):
            passed = all(p.passed for p in row.passes)
            ok &= passed
            worst = max((p.worst for p in row.passes), default=0.0)
            print(f"| {row.scene} | {row.size or '-'} | {'refused' if row.refused else 'PASS' if passed else 'FAIL'} "
                  f"| {_fmt(worst) if row.passes else '-'} | {row.refused} |")
        return 0 if ok else 1
    w, h = (int(v) for v in args.size.lower().split("x"))
    names = args.variants.split(",") if args.variants else list(VARIANTS)
    runs, ok = {}, True
    print(VARIANT_HEADER, flush=True)
    for name in names:
        scene = VARIANTS[name].scene
        todo = [name]
        if scene not in runs:
            runs[scene] = run = scene_run(scene, (w, h), args.set, dev, out / scene)
            print(f"{scene}: {run.port.cam.width}x{run.port.cam.height} on {run.port.adapter.info['device']}",
                  file=sys.stderr)
            todo = ["faithful"] * (name != "faithful") + todo   # the faithful port on every scene a variant uses
        for variant in todo:
            start = time.perf_counter()
            result = judge_variant(runs[scene], variant, dev)
            ok &= result.passed == (VARIANTS[variant].expect == "pass")
            print(variant_row(result), flush=True)
            print(f"  {variant}: {time.perf_counter() - start:.1f} s", file=sys.stderr)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
