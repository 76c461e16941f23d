"""Check the WebGPU killzone port against vlref: every pass, every variant, the conformance suite; prints tables.

    python ports/wgpu/kz_check.py [--size 160x90] [--set K=V ...] [--variants a,b] [--suite] [-o DIR]

Steps (the walk-through of docs/PORTING.md, in-process): per scene (:data:`SCENES`), render the port's faithful
variant and export its buffers (:func:`kz_port.export`), run ``vlref march PORT.toml --stages`` on them, and
compare each pass's output with the matching vlref stage under its preset (:data:`PASSES`). A post-pass variant
(:mod:`kz_variants`) re-runs passes 4-9 on the same raster buffers and is judged pass by pass against that march
(its inputs are bit-identical to the faithful port's, so is vlref's march on them); a raster variant re-renders
passes 1-3 and is judged by vlref's march on ITS buffers and against the scene (:func:`judge_raster`).
``--suite`` runs every scene of data/conformance the port's scope covers at its own size and lists the
refusals with their reasons.
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
from kz_variants import VARIANTS  # noqa: E402

SUITE = HERE.parents[1] / "data" / "conformance"
SCENES = {"pillars_point": HERE / "scenes" / "pillars_point.toml",
          **{p.stem: p for p in sorted(SUITE.glob("*.toml"))}}
"""The scenes variants name (``Variant.scene``): the port's own and the conformance suite's."""
SCENE = SCENES["pillars_point"]

PASSES = (("depth_lo", "depth_half", "float32"), ("march", "march_half", "gpu-half"),
          ("upsample", "upsample", "gpu-half"), ("blur_h", "blur_h", "gpu-half"), ("blur_v", "blur_v", "gpu-half"),
          ("transmittance", "transmittance", "gpu-half"), ("final", "final", "gpu-half"))
"""(port output, vlref ``--stages`` buffer, preset). The march runs at half resolution and the light
buffers are fp16: ``gpu-half`` (a float32 variant: ``float32``). The min-depth downsample is exact up to
float32 decoding: ``float32`` (sky pixels, ``inf`` in both, are left out with ``--ignore-sky ref``)."""


def size_overrides(scene_path, width: int, height: int) -> list[str]:
    """``render.width/height`` near ``width x height`` keeping the parity of the scene's own size, so that
    a scene written at an odd size (the downsample's partial last block) stays odd: 160x90 -> 161x91."""
    own = kz_scene.load(str(scene_path)).render
    w = width + (own.width % 2 != width % 2)
    h = height + (own.height % 2 != height % 2)
    return [f"render.width={w}", f"render.height={h}"]


def compare(ref_path: Path, test, preset: str, ignore_sky: bool = False, overrides=None):
    """``vlref compare`` of a vlref EXR with a port array (a report: passed, checks, metrics)."""
    from vlref.io import read_image
    from vlref.oracle.compare import build_mask, compare_arrays
    from vlref.oracle.presets import tolerance

    ref = read_image(ref_path)
    test = np.asarray(test)
    test = test[..., None] if test.ndim == 2 else test
    mask = build_mask(ref, ignore_sky="ref") if ignore_sky else None
    return compare_arrays(ref, test, tolerance(preset, overrides), mask, flip=False)


def ratio(value: float, bound: float) -> float:
    """``value / bound``; a zero bound gives 0 for a zero value and ``inf`` otherwise (never divides by 0)."""
    if bound > 0:
        return value / bound
    return 0.0 if value == 0 else math.inf


def margins(report) -> dict[str, float]:
    """Each evaluated check of a compare report as value / bound (:func:`ratio`)."""
    return {c.name: ratio(c.value, c.bound) for c in report.checks if c.value is not None}


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


def judge_pass(name: str, ref: Path, test, preset: str, ignore_sky: bool = False) -> PassResult:
    """Compare one port output with one vlref buffer; bad output (NaN, inf) is a failure with its reason."""
    from vlref.errors import InputError

    try:
        rep = compare(ref, test, preset, ignore_sky)
    except InputError as exc:
        return PassResult(name, preset, False, reason=str(exc))
    reason = "" if rep.passed else ", ".join(f"{c.name} {c.value:.3g} > {c.bound:.3g}" for c in rep.checks
                                             if c.passed is False)
    return PassResult(name, preset, rep.passed, margins(rep), int(rep.metrics["failing_pixels"]),
                      int(rep.metrics["compared_pixels"]), reason=reason)


def pass_results(passes: dict, marched: Path, preset: str = "gpu-half") -> list[PassResult]:
    """:data:`PASSES` of a port run against ``vlref march --stages`` output (float32 variants: every pass float32)."""
    return [judge_pass(p, marched / f"{r}.exr", passes[p], "float32" if preset == "float32" else pre,
                       ignore_sky=(p == "depth_lo")) for p, r, pre in PASSES]


def pass_rows(passes: dict, marched: Path):
    """``[(port pass, vlref buffer, preset, report)]`` for :data:`PASSES` (the faithful port's table)."""
    return [(p, r, preset, compare(marched / f"{r}.exr", passes[p], preset, ignore_sky=(p == "depth_lo")))
            for p, r, preset in PASSES]


def march_on(port, out_dir: Path, scene_ref: str, overrides, passes: dict):
    """Export ``port``'s buffers to ``out_dir/port`` and run ``vlref march --stages`` into ``out_dir/marched``:
    ``(manifest, marched dir, seconds of vlref march)``."""
    from vlref.cli import main

    manifest = kz_port.export(port, out_dir / "port", scene_ref, overrides, passes)
    start = time.perf_counter()
    if main(["march", str(manifest), "-o", str(out_dir / "marched"), "--stages", "-q"]) != 0:
        raise RuntimeError("vlref march failed on the port's buffers")
    return manifest, out_dir / "marched", time.perf_counter() - start


def render_and_march(out_dir: Path, overrides=(), dev=None, scene_path=SCENE):
    """The faithful port rendered and exported to ``out_dir/port``, vlref marched into ``out_dir/marched``:
    ``(port, passes, marched_dir, seconds of vlref march)``."""
    scene = kz_scene.load(str(scene_path), overrides)
    port = kz_port.KillzonePort(scene, dev)
    passes = port.run("faithful")
    _, marched, seconds = march_on(port, out_dir, str(scene_path), overrides, passes)
    return port, passes, marched, seconds


def scene_reference(scene, ref_dir: Path) -> Path:
    """vlref's scene colour and ``vlref render`` final of ``scene`` as EXRs in ``ref_dir`` (computed once)."""
    from vlref.io import write_exr
    from vlref.render import render

    if not (ref_dir / "final.exr").exists():
        result = render(scene, stages=True)
        ref_dir.mkdir(parents=True, exist_ok=True)
        write_exr(ref_dir / "colour.exr", result.buffers["scene_colour"].astype(np.float32))
        write_exr(ref_dir / "final.exr", result.buffers["final"].astype(np.float32))
    return ref_dir


def judge_raster(port, scene_path, overrides, variant: str, out_dir: Path) -> list[PassResult]:
    """A raster variant (passes 1-3 planted): vlref's march on the variant's own exported buffers, pass by
    pass ("own buffers"), then the port's raster inputs and final image against vlref's render of the scene
    ("against the scene": depth, shadow maps, scene colour, end to end)."""
    passes = port.run(variant)
    _, marched, _ = march_on(port, out_dir, str(scene_path), overrides, passes)
    rows = pass_results(passes, marched, VARIANTS[variant].preset)
    ref_dir = scene_reference(port.scene, out_dir.parent / "scene")
    for name, path, test in (("scene_colour", "colour.exr", port.raster_buffers()["colour"]),
                             ("end_to_end", "final.exr", passes["final"])):
        r = judge_pass(name, ref_dir / path, test, "gpu-half")
        r.group = "against the scene"
        rows.append(r)
    return rows


@dataclass
class SceneRun:
    """The faithful port of one scene at one size, and vlref's march on its buffers."""

    name: str
    path: Path
    overrides: list
    port: object
    passes: dict
    marched: Path
    out: Path
    march_seconds: float


def scene_run(name: str, size, extra=(), dev=None, out: Path | None = None) -> SceneRun:
    path = SCENES[name]
    overrides = (size_overrides(path, *size) if size else []) + list(extra)
    out = Path(out or tempfile.mkdtemp(prefix=f"kz-{name}-"))
    port, passes, marched, seconds = render_and_march(out, overrides, dev, path)
    return SceneRun(name, path, overrides, port, passes, marched, out, seconds)


def judge_variant(run: SceneRun, variant: str, dev=None, label: str | None = None) -> VariantResult:
    """Judge ``variant`` pass by pass on ``run``'s scene (module docstring)."""
    spec = VARIANTS[variant]
    size = f"{run.port.cam.width}x{run.port.cam.height}"
    if spec.raster:
        port = kz_port.KillzonePort(run.port.scene, dev or (run.port.adapter, run.port.device), variant)
        rows = judge_raster(port, run.path, run.overrides, variant, run.out / variant)
    else:
        rows = pass_results(run.port.run(variant), run.marched, spec.preset)
    return VariantResult(variant, label or run.name, size, rows)


@dataclass
class SuiteRow:
    scene: str
    size: str
    refused: str           # the port's reason, "" when it ran
    passes: list


def run_suite(dev=None, size=None, extra=(), out: Path | None = None) -> list[SuiteRow]:
    """Every conformance scene at its own size (or ``size``): the faithful port judged pass by pass, or the
    port's refusal with its reason (a scene outside its scope, or one vlref's killzone rejects)."""
    from vlref.errors import InputError

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
        passes = port.run("faithful")
        _, marched, _ = march_on(port, target, str(path), overrides, passes)
        rows.append(SuiteRow(name, f"{port.cam.width}x{port.cam.height}", "", pass_results(passes, marched)))
    return rows


def _fmt(x: float) -> str:
    return "inf" if math.isinf(x) else f"{x:.3g}x"


def print_variants(results) -> bool:
    """The variant table; True when every variant is judged as expected."""
    ok = True
    print("| variant | scene | size | expected | result | caught by | its margin | worst margin (every pass) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in results:
        spec = VARIANTS[r.name]
        ok &= r.passed == (spec.expect == "pass")
        c = r.caught_by
        caught = f"{c.name} ({c.group}, {c.preset})" if c else "-"
        print(f"| `{r.name}`: {spec.description} | {r.scene} | {r.size} | {spec.expect} | "
              f"{'PASS' if r.passed else 'FAIL'} | {caught} | {_fmt(c.worst) if c else '-'} | {_fmt(r.worst)} |")
    return ok


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
    results, runs = [], {}
    for name in names:
        scene = VARIANTS[name].scene
        if scene not in runs:
            runs[scene] = run = scene_run(scene, (w, h), args.set, dev, out / scene)
            print(f"{scene}: {run.port.cam.width}x{run.port.cam.height} on {run.port.adapter.info['device']}; "
                  f"vlref march {run.march_seconds:.2f} s", file=sys.stderr)
            if scene != VARIANTS["faithful"].scene:   # the faithful port on every scene a variant uses
                results.append(judge_variant(run, "faithful", dev, scene))
        results.append(judge_variant(runs[scene], name, dev))
    run = runs.get("pillars_point")
    if run is not None:
        print("| port pass | vlref buffer | preset | result | failing pixels | margins |\n|---|---|---|---|---|---|")
        for p in pass_results(run.passes, run.marched):
            print(f"| {p.name} | {dict((a, b) for a, b, _ in PASSES)[p.name]} | {p.preset} | "
                  f"{'PASS' if p.passed else 'FAIL'} | {p.failing} of {p.compared} | "
                  + ", ".join(f"{k} {_fmt(v)}" for k, v in p.margins.items()) + " |")
        print()
    return 0 if print_variants(results) else 1


if __name__ == "__main__":
    sys.exit(main())
