"""``vlref reference`` against Mitsuba 3 on one machine: the time each takes to the same per-pixel error
(BENCHMARKS.md, "The reference against Mitsuba 3").

The scene: a point light in a box of homogeneous medium (HG ``g = 0.5``) with a black sphere and a black box
casting volumetric shadows (:func:`vlref.reference.mitsuba.mitsuba_scene` converts it). Both renderers compute the
in-scattered radiance along vlref's own pixel rays (pixel centres, :meth:`vlref.camera.Camera.ray_directions`):
Mitsuba's ``volpath`` integrator (``max_depth = 2``: exactly single scattering, with next-event estimation) is
called on those rays through its Python API, so no film filter or camera convention differs.

1. The converged answer: :func:`~vlref.reference.render_reference` at ``rel_tol = 1e-9``.
2. ``vlref reference`` at each setting ``rel_tol/shadow_samples[/rule]`` of ``--vlref`` (the default 1e-4/512/15
   and coarser ones; ``shadow_samples`` is the shadow-boundary grid, ``vlref reference --shadow-samples``; ``rule``
   the Gauss–Kronrod rule, ``--rule``, 15 when left out): its wall time (median of the timed runs after a warm-up:
   ``--repeats`` before Mitsuba's runs and as many after, so load drifts hit both renderers), the part of it spent
   before the quadrature (``stats["frame_seconds"]``: the frame, camera rays, G-buffer), with ``--one-thread`` one
   run on one Numba thread (the parallel efficiency), and its per-pixel error against the converged answer (max over
   RGB): median and 99th percentile. Beside the whole call, the same number of calls given the scene's
   :func:`~vlref.reference.prepare_reference` made once (``reused_seconds``: the frame reused, as Mitsuba's timed
   launches reuse its loaded scene and BVH; the same bits).
3. Mitsuba (``llvm_ad_rgb``, every core Dr.Jit finds) at increasing samples per pixel: wall time (after a warm-up
   pass that compiles its kernels) and the same error statistics. The next spp is skipped once its projected time
   (linear in spp) passes ``--mitsuba-budget`` seconds.
4. **Measured ratio at the same error**: for each Mitsuba run, the fastest vlref setting whose median *and* 99th
   percentile errors are both no larger than Mitsuba's; the ratio is Mitsuba's time over that setting's time (the
   whole call), and ``ratio_reused`` the same with the frame reused.
   Both are measured; vlref's error is then at most Mitsuba's (usually well below), so the ratio is a lower bound
   of the ratio at exactly equal error.
5. Context, the extrapolation (no measurement): the error vlref's default setting reaches, floored by what the
   comparison can resolve (per statistic the larger of vlref's error and the converged answer's own error bound
   ``ReferenceResult.error``). Mitsuba's spp for it follow from ``error ∝ spp^-1/2`` (the slope fitted to the
   measured runs is printed) and its time from its time per sample. Mitsuba's ``*_rgb`` variants compute in
   float32, whose round-off (~1e-7 relative) floors the error it can reach at any spp: far below Mitsuba's
   measured errors the extrapolation is a formal figure.

6. With ``--first-call``: what a user sees in a fresh process, each renderer in its own child process (this script
   with ``--child``): the first call (vlref: its kernels loaded from Numba's cache; Mitsuba: the variant loaded, the
   scene built and the first launch traced and compiled, or taken from Dr.Jit's kernel cache), then the same call
   again (warm), and the child's whole wall time (interpreter, imports, both calls).

Run from the repository root (``pip install mitsuba``):

    python benchmarks/mitsuba_ratio.py [--width 80 --height 45 --spp 256,1024,4096,16384 --out FILE.json]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time

import numba
import numpy as np

from vlref.reference import prepare_reference, render_reference
from vlref.reference.mitsuba import mitsuba_scene
from vlref.render import prepare_frame
from vlref.scene.model import Bounds, Box, CameraSettings, Light, Medium, RenderSettings, Scene, ShadowSettings, Sphere

SPP_PER_PASS = 1024  # Mitsuba's samples per pixel per launch (80x45: 3.7 M paths, 0.5 GB; faster than 64 or 256)


def bench_scene(width: int, height: int) -> Scene:
    """The point light, the medium box and the two occluders (opaque, black for Mitsuba)."""
    return Scene(render=RenderSettings(width=width, height=height, max_distance=40.0),
                 camera=CameraSettings(position=(0.0, 1.0, -10.0), look_at=(0.0, 1.0, 0.0), fov=50.0),
                 medium=Medium(scattering=0.2, absorption=0.05, anisotropy=0.5,
                               bounds=Bounds(min=(-4.0, -2.0, -4.0), max=(4.0, 4.0, 4.0))),
                 lights=(Light(type="point", position=(0.0, 2.0, 0.5), intensity=20.0, range=100.0,
                               shadows=ShadowSettings(filter="exact")),),
                 objects=(Sphere(center=(-0.9, 1.6, -1.2), radius=0.6),
                          Box(center=(1.4, 0.6, 1.5), size=(0.8, 1.6, 0.8))))


def errors(image: np.ndarray, converged: np.ndarray) -> dict:
    """Per-pixel error, max over RGB: median and 99th percentile, absolute and relative to the image's peak."""
    err = np.abs(image - converged).max(axis=-1)
    peak = float(converged.max())
    med, p99 = float(np.median(err)), float(np.percentile(err, 99))
    return {"median": med, "p99": p99, "median_rel_peak": med / peak, "p99_rel_peak": p99 / peak}


def parse_settings(text: str) -> list[tuple[float, int, int]]:
    """``"1e-4/512,1e-1/1/7"`` -> ``[(1e-4, 512, 15), (0.1, 1, 7)]`` (rel_tol / shadow_samples / rule, 15 when left
    out)."""
    out = []
    for item in text.split(","):
        rel_tol, samples, *rule = item.split("/")
        out.append((float(rel_tol), int(samples), int(rule[0]) if rule else 15))
    return out


def reference(scene: Scene, setting: tuple[float, int, int]):
    rel_tol, samples, rule = setting
    return render_reference(scene, rel_tol=rel_tol, shadow_samples=samples, rule=rule)


def run_vlref(scene: Scene, setting: tuple[float, int, int], converged: np.ndarray, repeats: int,
              one_thread: bool = False) -> dict:
    """``repeats`` timed runs of one setting (after a warm-up run), their time before the quadrature, the result's
    error, and with ``one_thread`` the time of one run on one Numba thread."""
    reference(scene, setting)  # compiles (first call) / warms
    seconds, frame, reused = [], [], []
    for _ in range(repeats):
        start = time.perf_counter()
        result = reference(scene, setting)
        seconds.append(time.perf_counter() - start)
        frame.append(result.stats["frame_seconds"])
    prepared = prepare_reference(scene)
    for _ in range(repeats):
        start = time.perf_counter()
        again = reference(prepared, setting)
        reused.append(time.perf_counter() - start)
    assert np.array_equal(again.inscatter, result.inscatter)
    out = {"rel_tol": setting[0], "shadow_samples": setting[1], "rule": setting[2], "runs_s": seconds,
           "frame_runs_s": frame, "reused_runs_s": reused, **errors(result.inscatter, converged)}
    if one_thread:
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        start = time.perf_counter()
        reference(scene, setting)
        out["one_thread_s"] = time.perf_counter() - start
        numba.set_num_threads(threads)
    print(f"(progress) vlref {label(out)}: runs {seconds}, p99 {out['p99']:.3g}", file=sys.stderr, flush=True)
    return out


def label(v: dict) -> str:
    return f"{v['rel_tol']:g}/{v['shadow_samples']}/{v['rule']}"


class MitsubaRays:
    """Mitsuba's ``volpath`` along vlref's pixel rays: ``radiance(spp, seed)`` is the (H, W, 3) Monte Carlo mean."""

    def __init__(self, scene: Scene):
        import drjit as dr
        import mitsuba as mi

        mi.set_variant("llvm_ad_rgb")
        self.dr, self.mi = dr, mi
        self.scene = mi.load_dict(mitsuba_scene(scene))
        self.integrator = self.scene.integrator()
        frame = prepare_frame(scene)
        self.dirs = frame.camera.ray_directions().reshape(-1, 3)
        self.origin = np.asarray(frame.camera.position, dtype=np.float64)
        self.shape = (scene.render.height, scene.render.width)

    def _pass(self, spp: int, seed: int) -> np.ndarray:
        dr, mi = self.dr, self.mi
        n = self.dirs.shape[0]
        d = np.repeat(self.dirs, spp, axis=0).astype(np.float32)
        o = np.broadcast_to(self.origin.astype(np.float32), d.shape)
        ray = mi.Ray3f(mi.Point3f(*(mi.Float(np.ascontiguousarray(o[:, c])) for c in range(3))),
                       mi.Vector3f(*(mi.Float(np.ascontiguousarray(d[:, c])) for c in range(3))))
        sampler = mi.load_dict({"type": "independent"})
        sampler.seed(seed, n * spp)
        colour, _, _ = self.integrator.sample(self.scene, sampler, ray)
        dr.eval(colour)
        rgb = np.stack([np.asarray(colour.x), np.asarray(colour.y), np.asarray(colour.z)], axis=-1)
        return rgb.reshape(n, spp, 3).sum(axis=1)

    def radiance(self, spp: int, seed: int = 0) -> np.ndarray:
        total = np.zeros((self.dirs.shape[0], 3))
        for k, start in enumerate(range(0, spp, SPP_PER_PASS)):
            total += self._pass(min(SPP_PER_PASS, spp - start), seed * 100003 + k)
        return (total / spp).reshape(*self.shape, 3)


def time_mitsuba(rays: MitsubaRays, spp_list: list[int], converged: np.ndarray, budget: float) -> list[dict]:
    for size in sorted({min(SPP_PER_PASS, spp) for spp in spp_list}):  # compiles Dr.Jit's kernels, per pass size
        rays.radiance(size, seed=999)
    out = []
    for i, spp in enumerate(spp_list):
        if out and out[-1]["seconds"] * spp / out[-1]["spp"] > budget:
            break
        start = time.perf_counter()
        image = rays.radiance(spp, seed=i + 1)
        out.append({"spp": spp, "seconds": time.perf_counter() - start, **errors(image, converged)})
        print(f"(progress) mitsuba {spp} spp: {out[-1]['seconds']:.3f} s, p99 {out[-1]['p99']:.3g}", file=sys.stderr,
              flush=True)
    return out


def at_same_error(mitsuba: list[dict], vlref: list[dict]) -> list[dict]:
    """Per Mitsuba run, the fastest vlref setting with median and 99th percentile errors both no larger than
    Mitsuba's, and the time ratio (None where no setting reaches that error)."""
    out = []
    for m in mitsuba:
        fits = [v for v in vlref if v["median"] <= m["median"] and v["p99"] <= m["p99"]]
        best = min(fits, key=lambda v: v["seconds"]) if fits else None
        reused = min(fits, key=lambda v: v["reused_seconds"]) if fits else None
        out.append({"spp": m["spp"], "mitsuba_seconds": m["seconds"], "mitsuba_error": [m["median"], m["p99"]],
                    "vlref": None if best is None else {k: best[k] for k in ("rel_tol", "shadow_samples", "rule",
                                                                                "seconds", "median", "p99")},
                    "ratio": None if best is None else m["seconds"] / best["seconds"],
                    "vlref_reused": None if reused is None else {k: reused[k] for k in (
                        "rel_tol", "shadow_samples", "rule", "reused_seconds", "median", "p99")},
                    "ratio_reused": None if reused is None else m["seconds"] / reused["reused_seconds"]})
    return out


def needed(mitsuba: list[dict], target: dict) -> dict:
    """Mitsuba's spp and time to reach ``target``'s median and p99 error (``{"median": .., "p99": ..}``), from its
    largest run by ``error ∝ spp^-1/2`` (or measured, where a run already reached it), and the slope of log error
    against log spp."""
    spp = np.array([m["spp"] for m in mitsuba], dtype=float)
    slopes = {s: float(np.polyfit(np.log(spp), np.log([m[s] for m in mitsuba]), 1)[0]) for s in ("median", "p99")}
    reached = [m for m in mitsuba if m["median"] <= target["median"] and m["p99"] <= target["p99"]]
    last = mitsuba[-1]
    per_stat = {s: last["spp"] * max(1.0, (last[s] / target[s]) ** 2) for s in ("median", "p99")}
    if reached:
        first = reached[0]
        return {"spp": first["spp"], "seconds": first["seconds"], "measured": True, "slopes": slopes,
                "spp_per_statistic": per_stat}
    factor = max(per_stat.values()) / last["spp"]
    return {"spp": last["spp"] * factor, "seconds": last["seconds"] * factor, "measured": False, "slopes": slopes,
            "spp_per_statistic": per_stat}


def child(which: str, scene: Scene, setting: tuple[float, int, int], spp: int) -> dict:
    """One renderer's first and second call in this (fresh) process (step 6 of the module docstring)."""
    start = time.perf_counter()
    if which == "vlref":
        reference(scene, setting)
        first = time.perf_counter()
        reference(scene, setting)
        return {"setup_s": 0.0, "first_s": first - start, "warm_s": time.perf_counter() - first}
    rays = MitsubaRays(scene)
    setup = time.perf_counter()
    rays.radiance(spp, seed=1)
    first = time.perf_counter()
    rays.radiance(spp, seed=2)
    return {"setup_s": setup - start, "first_s": first - setup, "warm_s": time.perf_counter() - first}


def first_calls(args, setting: str, spp: int) -> dict:
    """Each renderer in a child process (:func:`child`): its report and the child's wall time (or the end of its
    error output, where it failed)."""
    out = {}
    for which in ("vlref", "mitsuba"):
        cmd = [sys.executable, __file__, "--child", which, "--width", str(args.width), "--height", str(args.height),
               "--vlref", setting, "--spp", str(spp)]
        start = time.perf_counter()
        run = subprocess.run(cmd, capture_output=True, text=True)
        if run.returncode != 0:
            out[which] = {"error": run.stderr[-2000:]}
            continue
        out[which] = {**json.loads(run.stdout.splitlines()[-1]), "process_s": time.perf_counter() - start}
        print(f"(progress) first call {which}: {out[which]}", file=sys.stderr, flush=True)
    return {"setting": setting, "spp": spp, **out}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--width", type=int, default=80)
    ap.add_argument("--height", type=int, default=45)
    ap.add_argument("--vlref", default="1e-4/512,1e-2/64,1e-2/16,1e-1/8,1e-1/4",
                    help="vlref reference settings rel_tol/shadow_samples (comma-separated; the first is the context "
                         "of the extrapolation)")
    ap.add_argument("--repeats", type=int, default=3, help="timed vlref runs before and after Mitsuba's (each)")
    ap.add_argument("--spp", default="256,1024,4096,16384", help="Mitsuba samples per pixel (comma-separated)")
    ap.add_argument("--mitsuba-budget", type=float, default=120.0,
                    help="skip a Mitsuba run whose projected time passes this many seconds")
    ap.add_argument("--one-thread", action="store_true", help="also time one run of each setting on one thread")
    ap.add_argument("--first-call", metavar="SETTING", default=None,
                    help="also time each renderer's first and second call in a fresh process: vlref at this setting "
                         "(rel_tol/shadow_samples/rule), Mitsuba at the first --spp")
    ap.add_argument("--child", choices=("vlref", "mitsuba"), help=argparse.SUPPRESS)
    ap.add_argument("--out", default=None, help="write the report as JSON here")
    args = ap.parse_args()
    scene = bench_scene(args.width, args.height)
    settings = parse_settings(args.vlref)
    spp_list = [int(s) for s in args.spp.split(",")]
    if args.child:
        print(json.dumps(child(args.child, scene, settings[0], spp_list[0])))
        return
    start = time.perf_counter()
    converged = render_reference(scene, rel_tol=1e-9, max_intervals=20000)
    report = {"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                          "numba_threads": numba.get_num_threads()},
              "width": args.width, "height": args.height,
              "converged": {"rel_tol": 1e-9, "seconds": time.perf_counter() - start,
                            "unconverged_pixels": int(converged.stats.get("unconverged", 0)),
                            "max_error_bound_rel_peak": float(converged.max_error / converged.inscatter.max())}}
    report["vlref"] = [run_vlref(scene, s, converged.inscatter, args.repeats, args.one_thread) for s in settings]
    rays = MitsubaRays(scene)
    report["machine"]["drjit_threads"] = rays.dr.thread_count()
    report["mitsuba"] = time_mitsuba(rays, spp_list, converged.inscatter, args.mitsuba_budget)
    for v, s in zip(report["vlref"], settings):  # the same runs after Mitsuba's: load drifts hit both renderers
        again = run_vlref(scene, s, converged.inscatter, args.repeats)
        for key in ("runs_s", "frame_runs_s", "reused_runs_s"):
            v[key] += again[key]
        v["seconds"] = float(np.median(v["runs_s"]))
        v["frame_seconds"] = float(np.median(v["frame_runs_s"]))
        v["reused_seconds"] = float(np.median(v["reused_runs_s"]))
    report["same_error"] = at_same_error(report["mitsuba"], report["vlref"])
    floor = {"median": float(np.median(converged.error)), "p99": float(np.percentile(converged.error, 99))}
    report["converged"]["error_bound"] = floor
    default = report["vlref"][0]
    target = {s: max(default[s], floor[s]) for s in ("median", "p99")}
    need = needed(report["mitsuba"], target)
    last = report["mitsuba"][-1]
    report["extrapolated"] = {"rel_tol": default["rel_tol"], "shadow_samples": default["shadow_samples"],
                              "rule": default["rule"],
                              "target": target, "mitsuba_spp": need["spp"], "mitsuba_seconds": need["seconds"],
                              "measured": need["measured"], "slopes": need["slopes"],
                              "ratio": need["seconds"] / default["seconds"],
                              "spp_per_statistic": need["spp_per_statistic"],
                              "ratio_per_statistic": {s: last["seconds"] * n / last["spp"] / default["seconds"]
                                                      for s, n in need["spp_per_statistic"].items()}}
    print(f"machine: {report['machine']}; {args.width}x{args.height}; converged answer {report['converged']}")
    for v in report["vlref"]:
        one = f", one thread {v['one_thread_s']:.4f} s" if "one_thread_s" in v else ""
        print(f"vlref reference {label(v)} (rel_tol/shadow_samples/rule): {v['seconds']:.4f} s "
              f"(runs {', '.join(f'{t:.4f}' for t in v['runs_s'])}; before the quadrature {v['frame_seconds']:.4f} s"
              f"{one}; the frame reused {v['reused_seconds']:.4f} s), error median {v['median']:.3g} p99 "
              f"{v['p99']:.3g} ({v['median_rel_peak']:.2g} / {v['p99_rel_peak']:.2g} of the peak)")
    for m in report["mitsuba"]:
        print(f"mitsuba {m['spp']:6d} spp: {m['seconds']:.3f} s, error median {m['median']:.3g} p99 {m['p99']:.3g} "
              f"({m['median_rel_peak']:.2g} / {m['p99_rel_peak']:.2g} of the peak)")
    for r in report["same_error"]:
        v = r["vlref"]
        if v is None:
            print(f"mitsuba {r['spp']} spp: no vlref setting reaches its error")
            continue
        print(f"same error as Mitsuba {r['spp']} spp ({r['mitsuba_seconds']:.3f} s, median {r['mitsuba_error'][0]:.3g}"
              f" p99 {r['mitsuba_error'][1]:.3g}): vlref {label(v)}, {v['seconds']:.4f} s, median "
              f"{v['median']:.3g} p99 {v['p99']:.3g}: "
              f"**{r['ratio']:.4g}x** (measured, the whole call); the frame reused: {label(r['vlref_reused'])}, "
              f"{r['vlref_reused']['reused_seconds']:.4f} s, **{r['ratio_reused']:.4g}x**")
    e = report["extrapolated"]
    how = "measured" if e["measured"] else "extrapolated by spp^-1/2"
    print(f"context: vlref's default error (median {e['target']['median']:.3g}, p99 {e['target']['p99']:.3g}) needs "
          f"Mitsuba {e['mitsuba_spp']:.3g} spp, {e['mitsuba_seconds']:.4g} s ({how}; fitted slopes median "
          f"{e['slopes']['median']:.2f}, p99 {e['slopes']['p99']:.2f}): {e['ratio']:.4g}x (median alone "
          f"{e['ratio_per_statistic']['median']:.3g}x, p99 alone {e['ratio_per_statistic']['p99']:.3g}x)")
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(report, fh, indent=1)
    if args.first_call:  # last: the measurements above are printed and written whatever happens here
        report["first_call"] = first_calls(args, args.first_call, spp_list[0])
        for which in ("vlref", "mitsuba"):
            f = report["first_call"][which]
            if "error" in f:
                print(f"fresh process, {which}: failed: {f['error']}")
                continue
            print(f"fresh process, {which} ({args.first_call if which == 'vlref' else spp_list[0]}): set-up "
                  f"{f['setup_s']:.3f} s, first call {f['first_s']:.3f} s, second call {f['warm_s']:.3f} s, the whole "
                  f"process {f['process_s']:.2f} s")
        if args.out:
            with open(args.out, "w") as fh:
                json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main()
