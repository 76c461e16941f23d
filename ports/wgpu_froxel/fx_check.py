"""Check the WebGPU froxel port against vlref: every pass of every frame, every variant; prints the README's tables.

    python ports/wgpu_froxel/fx_check.py [--scene anim_spot] [--frames 4] [--size 96x54] [--grid 20x12x16]
                                         [--set K=V ...] [-o DIR] [--timing-size 1920x1080]
                                         [--verdict | --verdict-only]

Steps (docs/PORTING.md §5, in-process): the port renders frames 0 .. N-1 and exports each frame's raster
buffers and manifest (:func:`fx_port.export`); ``vlref march`` runs the froxel technique on them frame by
frame, carrying vlref's own history (:func:`vlref.port.march_sequence`, the CLI's ``vlref march
frame_0000/port.toml frame_0001/port.toml ... --stages``); each exported pass of each frame is compared
with vlref's buffer of that name under its preset (:data:`PASSES`); then every variant (:mod:`fx_variants`)
re-runs the froxel passes of the whole sequence on the same raster buffers and is judged the same way.
With ``--verdict``, the whole-frame sequence verdict too (``vlref verdict frame_0000/port.toml ...``,
:func:`sequence_verdict`): every frame on the port's own buffers and against the scene, history carried on
both sides, for the faithful port and each raster variant (whose bug only the scene side can see).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import fx_port  # noqa: E402
import kz_scene  # noqa: E402
from fx_variants import VARIANTS  # noqa: E402

from vlref.oracle.verdict import GROUP_OWN, GROUP_SCENE, judge_sequence  # noqa: E402

PASSES = fx_port.PASSES
"""(buffer, preset) of every exported pass (:data:`fx_port.PASSES`, which says why each preset)."""

APPLY_BUFFERS = ("inscatter", "transmittance", "final")
"""The apply pass's outputs: the only ones read through the hardware trilinear sampler of the integrated grid."""

SEQUENCE = ("techniques.froxel.temporal=true", "techniques.froxel.history_clamp=true")
"""Scene settings of every checked sequence: temporal with the clamp (which a planted bug leaves out)."""


def compare(ref, test, preset: str):
    """``vlref compare``'s rule on two arrays (a report: passed, checks, metrics)."""
    from vlref.oracle.compare import compare_arrays
    from vlref.oracle.presets import tolerance

    ref, test = np.asarray(ref, dtype=np.float64), np.asarray(test, dtype=np.float64)
    ref = ref[..., None] if ref.ndim == 2 else ref
    test = test[..., None] if test.ndim == 2 else test
    return compare_arrays(ref, test, tolerance(preset), None, flip=False)


def margins(report) -> tuple[float, float]:
    """(failing fraction / its bound, mean error / its bound); a bound of 0 (exact) counts any error as inf."""
    out = []
    for c in report.checks[:2]:
        out.append(c.value / c.bound if c.bound > 0 else (0.0 if c.value == 0 else np.inf))
    return out[0], out[1]


def setup(scene_ref: str, frames: int, overrides=(), dev=None, raster_variant: str = "faithful"):
    """The port's raster passes over ``frames`` frames (``raster_variant``'s raster switches):
    ``(port, overrides)``, ``SEQUENCE`` added."""
    overrides = [*SEQUENCE, *overrides]
    return fx_port.FroxelPort(kz_scene.load(scene_ref, overrides), range(frames), dev, raster_variant), overrides


def reference(port: fx_port.FroxelPort, scene_ref: str, overrides, out_dir: Path) -> list[dict]:
    """Export the port's raster buffers per frame and run vlref's froxel technique on them in sequence."""
    from vlref.port import load_port, march_sequence

    manifests = fx_port.export(port, out_dir, scene_ref, overrides)
    return list(march_sequence([load_port(m) for m in manifests]))


def judge(port_frames: list[dict], ref_frames: list[dict]):
    """``[(frame, buffer, preset, report)]`` for every pass of every frame."""
    rows = []
    for f, (got, want) in enumerate(zip(port_frames, ref_frames)):
        for name, preset in PASSES:
            if name in got:
                rows.append((f, name, preset, compare(want[name], got[name], preset)))
    return rows


def verdict(rows):
    """(passed, worst margin over every check, (frame, buffer) of the worst): a variant's summary."""
    worst, where = 0.0, None
    for f, name, _, rep in rows:
        m = max(margins(rep))
        if m > worst:
            worst, where = m, (f, name)
    return all(rep.passed for *_, rep in rows), worst, where


def first_failure(rows):
    """(frame, buffer, margin) of the first failing check in frame/pass order, or None."""
    return next(((f, name, max(margins(rep))) for f, name, _, rep in rows if not rep.passed), None)


def timing(scene_ref: str, size: str, grid: str, frames: int, dev=None) -> tuple[str, dict, dict]:
    """Per-pass times at ``size`` and ``grid`` (gw x gh x D), ms per frame: the mean over frames 1 .. N-1 of a
    second run of the sequence (the first compiles the pipelines; frame 0 has no history to reproject):
    (kind of the first dict, GPU timestamps or wall time; CPU wall time around submit + wait)."""
    w, h = size.lower().split("x")
    gw, gh, d = grid.lower().split("x")
    sizes = [f"render.width={int(w)}", f"render.height={int(h)}", f"techniques.froxel.grid_width={int(gw)}",
             f"techniques.froxel.grid_height={int(gh)}", f"techniques.froxel.slices={int(d)}"]
    port, _ = setup(scene_ref, frames, sizes, dev)
    port.run()
    port.run()
    later = port.frame_timings[1:]
    kind = "GPU timestamps" if port.timestamps else "CPU wall time around submit + read-back"
    mean = [{k: 1e3 * sum(t[j][k] for t in later) / len(later) for k in later[0][j]} for j in (0, 1)]
    return kind, mean[0], mean[1]


def sequence_verdict(port: fx_port.FroxelPort, scene_ref: str, overrides, out_dir: Path, variant: str = "faithful",
                     cache: dict | None = None, reports: bool = True):
    """The whole-frame verdict of every frame (``vlref verdict frame_0000/port.toml frame_0001/port.toml ...``,
    :func:`vlref.oracle.verdict.judge_sequence`) on the port's buffers exported under ``out_dir``: each frame's
    passes on the port's own buffers against vlref's march carrying its history, and its raster inputs and
    final frame against vlref's render of that frame carrying its own; with ``reports``, the verdict's files
    in ``out_dir/verdict``. ``cache`` shares vlref's renders and marches between variants."""
    manifests = fx_port.export(port, out_dir, scene_ref, overrides, port.run(variant))
    return judge_sequence(manifests, out_dir=out_dir / "verdict" if reports else None, cache=cache)


def _times(margin: float) -> str:
    return "inf" if math.isinf(margin) else f"{margin:.3g}x"


def print_sequence_verdicts(scene: str, frames: int, overrides, dev, out: Path) -> bool:
    """Print the sequence verdict of the faithful port of ``scene`` (reports in ``out/<scene>_verdict``) and a
    row per raster variant (:attr:`fx_variants.Variant.is_raster`: own buffers and against the scene); whether
    each is judged as expected."""
    start = time.perf_counter()
    port, overrides = setup(scene, frames, overrides, dev)
    cache: dict = {}
    v = sequence_verdict(port, scene, overrides, out / f"{scene}_verdict", cache=cache)
    print(f"\n### `vlref verdict` of {frames} frames of {scene} ({time.perf_counter() - start:.1f} s): "
          f"{'PASS' if v.passed else 'FAIL'}\n\n{v.table()}")
    ok = v.passed
    print("\n| raster variant | expected | own buffers | against the scene | failing (frame: passes, worst margin) |")
    print("|---|---|---|---|---|")
    for name, spec in VARIANTS.items():
        if not spec.is_raster or spec.scene not in (None, scene):
            continue
        rport, _ = setup(scene, frames, overrides, dev, name)
        rv = sequence_verdict(rport, scene, overrides, out / f"{scene}_{name}", name, cache, reports=False)
        groups = {g: all(p.passed for f in rv.frames for p in f.passes if p.group == g)
                  for g in (GROUP_OWN, GROUP_SCENE)}
        by_frame: dict = {}
        for i, p in rv.failures():
            by_frame.setdefault(i, []).append((p.name, max(p.metrics.get("margins", {"-": math.inf}).values())))
        where = "; ".join(f"{i}: {', '.join(n for n, _ in fails)}, {_times(max(m for _, m in fails))}"
                          for i, fails in by_frame.items()) or "-"
        good = groups[GROUP_OWN] and not groups[GROUP_SCENE] if spec.expect == "fail" else rv.passed
        ok &= good
        print(f"| `{name}`: {spec.description} | {spec.expect} | {'PASS' if groups[GROUP_OWN] else 'FAIL'} | "
              f"{'PASS' if groups[GROUP_SCENE] else 'FAIL'}{'' if good else ' (WRONG)'} | {where} |")
    return ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", action="append", default=None, help="bundled scene or file (repeatable; "
                    "default anim_spot and anim_sun)")
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--size", default="96x54")
    ap.add_argument("--grid", default="20x12x16", help="froxel grid gw x gh x D")
    ap.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE")
    ap.add_argument("-o", "--output", default=None, help="keep the exported buffers here")
    ap.add_argument("--timing-size", default=None, help="also time the passes at WxH (e.g. 1920x1080)")
    ap.add_argument("--timing-grid", default="160x90x64", help="grid of the timing run (default 160x90x64)")
    ap.add_argument("--verdict", action="store_true", help="also judge every frame of each scene with `vlref "
                    "verdict` (own buffers and against the scene, history carried on both sides), the faithful "
                    "port and the raster variants, at the scenes' own shadow-map resolutions")
    ap.add_argument("--verdict-only", action="store_true", help="only the `--verdict` tables")
    args = ap.parse_args(argv)
    w, h = args.size.lower().split("x")
    gw, gh, d = args.grid.lower().split("x")
    base = [f"render.width={int(w)}", f"render.height={int(h)}", f"techniques.froxel.grid_width={int(gw)}",
            f"techniques.froxel.grid_height={int(gh)}", f"techniques.froxel.slices={int(d)}", *args.set]
    out = Path(args.output or tempfile.mkdtemp(prefix="fx-check-"))
    dev = fx_port.device()
    print(f"device: {dev[0].info['device']}; {w}x{h}, grid {gw}x{gh}x{d}, {args.frames} frames; buffers in {out}")
    ok = True
    results: dict[str, dict] = {}
    scenes = args.scene or ["anim_spot", "anim_sun"]
    for scene in scenes:
        if args.verdict or args.verdict_only:
            ok &= print_sequence_verdicts(scene, args.frames, base, dev, out)
        if args.verdict_only:
            continue
        overrides = [*base, "lights.0.shadows.resolution=128"] if scene == "anim_spot" else base
        start = time.perf_counter()
        port, overrides = setup(scene, args.frames, overrides, dev)
        refs = reference(port, scene, overrides, out / scene)
        t_ref = time.perf_counter() - start
        rows = judge(port.run("faithful"), refs)
        print(f"\n### {scene} (raster + vlref march {t_ref:.1f} s)\n")
        print("| frame | buffer | preset | result | failing pixels | failing fraction | mean error |")
        print("|---|---|---|---|---|---|---|")
        for f, name, preset, rep in rows:
            fr, me = margins(rep)
            ok &= rep.passed
            print(f"| {f} | {name} | {preset} | {'PASS' if rep.passed else 'FAIL'} | "
                  f"{int(rep.metrics['failing_pixels'])} of {int(rep.metrics['compared_pixels'])} | {fr:.3f}x | "
                  f"{me:.3f}x |")
        for name in ("faithful", "weights8"):
            frames = port.run(name)
            reps = [(f, b, compare(refs[f][b], frames[f][b], "gpu-full")) for f in range(len(refs))
                    for b in APPLY_BUFFERS]
            worst = max(((max(margins(r)), f, b) for f, b, r in reps), key=lambda t: t[0])
            print(f"\n`{name}` apply passes under gpu-full: {'PASS' if all(r.passed for *_, r in reps) else 'FAIL'}, "
                  f"worst {worst[0]:.3f}x (frame {worst[1]}, {worst[2]})")
        for name, v in VARIANTS.items():
            if not v.is_raster:
                results.setdefault(name, {})[scene] = judge(port.run(name), refs) if name != "faithful" else rows
    if not args.verdict_only:
        print("\n| variant | expected | verdict | first failing (scene, frame, pass): margin "
              "| worst margin (scene, frame, pass) |")
        print("|---|---|---|---|---|")
    for name, v in VARIANTS.items():
        if args.verdict_only or v.is_raster:
            continue
        per = results[name]
        passed = all(verdict(rows)[0] for rows in per.values())
        worst = max(((verdict(rows)[1], s, verdict(rows)[2]) for s, rows in per.items()), key=lambda t: t[0])
        first = next(((s, first_failure(rows)) for s, rows in per.items() if first_failure(rows)), None)
        good = passed if v.expect == "pass" else not passed
        good &= worst[0] <= 0.5 if v.expect == "pass" else True
        ok &= good
        where = f"{first[0]}, {first[1][0]}, {first[1][1]}: {first[1][2]:.3g}x" if first else "-"
        print(f"| `{name}`: {v.description} | {v.expect} | {'PASS' if passed else 'FAIL'}{'' if good else ' (WRONG)'}"
              f" | {where} | {worst[0]:.3g}x ({worst[1]}, {worst[2][0]}, {worst[2][1]}) |")
    if args.timing_size:
        for scene in args.scene or ["anim_spot", "anim_sun"]:
            kind, ms, wall = timing(scene, args.timing_size, args.timing_grid, 4, dev)
            print(f"\n{scene} at {args.timing_size}, grid {args.timing_grid}: ms per frame ({kind} | CPU wall)")
            for k in ms:
                print(f"| {k} | {ms[k]:.3f} | {wall[k]:.3f} |")
            print(f"| total | {sum(ms.values()):.3f} | {sum(wall.values()):.3f} |")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
