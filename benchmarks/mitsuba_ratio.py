"""``vlref reference`` against Mitsuba 3 on one machine: the time each takes to the same per-pixel error
(BENCHMARKS.md, "The reference against Mitsuba 3").

The scene: a point light in a box of homogeneous medium (HG ``g = 0.5``) with a black sphere and a black box
casting volumetric shadows (:func:`vlref.reference.mitsuba.mitsuba_scene` converts it). Both renderers compute the
in-scattered radiance along vlref's own pixel rays (pixel centres, :meth:`vlref.camera.Camera.ray_directions`):
Mitsuba's ``volpath`` integrator (``max_depth = 2``: exactly single scattering, with next-event estimation) is
called on those rays through its Python API, so no film filter or camera convention differs.

1. The converged answer: :func:`~vlref.reference.render_reference` at ``rel_tol = 1e-9``.
2. ``vlref reference`` at each ``--rel-tol`` (default 1e-4, the command's default, and 1e-2): its wall time (median of
   3 after a warm-up) and its per-pixel error against the converged answer (max over RGB): median and 99th
   percentile.
3. Mitsuba (``llvm_ad_rgb``, every core Dr.Jit finds) at increasing samples per pixel: wall time (after a warm-up
   pass that compiles its kernels) and the same error statistics.
4. The target is vlref's error, floored by what the comparison can resolve: per statistic the larger of vlref's
   error and the converged answer's own error bound (``ReferenceResult.error``; where vlref's result equals the
   converged one bit for bit its measured error is 0). Where Mitsuba's largest run is still above the target, the
   samples it would need follow from the Monte Carlo law ``error ∝ spp^-1/2`` (the slope fitted to the measured runs
   is printed) applied to each statistic, and its time from its measured time per sample (linear in spp). The ratio
   is Mitsuba's time to vlref's; ``lower_bound`` is the ratio of Mitsuba's largest run, whose error is still above
   the target (measured, no extrapolation). Mitsuba's ``*_rgb`` variants compute in float32, whose round-off
   (~1e-7 relative) floors the error it can reach at any spp: below that the extrapolation is a formal figure.
5. ``same_time``: Mitsuba's error in its run closest to vlref's time.

Run from the repository root (``pip install mitsuba``):

    python benchmarks/mitsuba_ratio.py [--width 80 --height 45 --spp 16,64,256,1024 --out FILE.json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time

import numba
import numpy as np

from vlref.reference import render_reference
from vlref.reference.mitsuba import mitsuba_scene
from vlref.render import prepare_frame
from vlref.scene.model import Bounds, Box, CameraSettings, Light, Medium, RenderSettings, Scene, ShadowSettings, Sphere

SPP_PER_PASS = 64  # Mitsuba's samples per pixel per launch (bounds the wavefront's memory)


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


def time_vlref(scene: Scene, rel_tol: float, converged: np.ndarray, repeats: int = 3) -> dict:
    render_reference(scene, rel_tol=rel_tol)  # compiles (first call) / warms
    seconds = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = render_reference(scene, rel_tol=rel_tol)
        seconds.append(time.perf_counter() - start)
    return {"rel_tol": rel_tol, "seconds": float(np.median(seconds)), "runs_s": seconds,
            **errors(result.inscatter, converged)}


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


def time_mitsuba(rays: MitsubaRays, spp_list: list[int], converged: np.ndarray) -> list[dict]:
    for size in sorted({min(SPP_PER_PASS, spp) for spp in spp_list}):  # compiles Dr.Jit's kernels, per pass size
        rays.radiance(size, seed=999)
    out = []
    for i, spp in enumerate(spp_list):
        start = time.perf_counter()
        image = rays.radiance(spp, seed=i + 1)
        out.append({"spp": spp, "seconds": time.perf_counter() - start, **errors(image, converged)})
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--width", type=int, default=80)
    ap.add_argument("--height", type=int, default=45)
    ap.add_argument("--rel-tol", default="1e-4,1e-2", help="vlref reference tolerances (comma-separated)")
    ap.add_argument("--spp", default="16,64,256,1024", help="Mitsuba samples per pixel (comma-separated)")
    ap.add_argument("--out", default=None, help="write the report as JSON here")
    args = ap.parse_args()
    scene = bench_scene(args.width, args.height)
    start = time.perf_counter()
    converged = render_reference(scene, rel_tol=1e-9, max_intervals=20000)
    report = {"machine": {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                          "numba_threads": numba.get_num_threads()},
              "width": args.width, "height": args.height,
              "converged": {"rel_tol": 1e-9, "seconds": time.perf_counter() - start,
                            "unconverged_pixels": int(converged.stats.get("unconverged", 0)),
                            "max_error_bound_rel_peak": float(converged.max_error / converged.inscatter.max())}}
    report["vlref"] = [time_vlref(scene, float(t), converged.inscatter) for t in args.rel_tol.split(",")]
    rays = MitsubaRays(scene)
    report["machine"]["drjit_threads"] = rays.dr.thread_count()
    report["mitsuba"] = time_mitsuba(rays, [int(s) for s in args.spp.split(",")], converged.inscatter)
    floor = {"median": float(np.median(converged.error)), "p99": float(np.percentile(converged.error, 99))}
    report["converged"]["error_bound"] = floor
    report["ratios"] = []
    for v in report["vlref"]:
        target = {s: max(v[s], floor[s]) for s in ("median", "p99")}
        need = needed(report["mitsuba"], target)
        last = report["mitsuba"][-1]
        same = min(report["mitsuba"], key=lambda m: abs(math.log(m["seconds"] / v["seconds"])))
        report["ratios"].append({"rel_tol": v["rel_tol"], "target": target, "mitsuba_spp": need["spp"],
                                 "mitsuba_seconds": need["seconds"], "measured": need["measured"],
                                 "slopes": need["slopes"], "ratio": need["seconds"] / v["seconds"],
                                 "spp_per_statistic": need["spp_per_statistic"],
                                 "ratio_per_statistic": {s: last["seconds"] * n / last["spp"] / v["seconds"]
                                                         for s, n in need["spp_per_statistic"].items()},
                                 "lower_bound": None if need["measured"] else last["seconds"] / v["seconds"],
                                 "same_time": same})
    print(f"machine: {report['machine']}; {args.width}x{args.height}; converged answer {report['converged']}")
    for v in report["vlref"]:
        print(f"vlref reference rel_tol {v['rel_tol']:g}: {v['seconds']:.3f} s, error median {v['median']:.3g} "
              f"p99 {v['p99']:.3g} ({v['median_rel_peak']:.2g} / {v['p99_rel_peak']:.2g} of the peak)")
    for m in report["mitsuba"]:
        print(f"mitsuba {m['spp']:6d} spp: {m['seconds']:.3f} s, error median {m['median']:.3g} p99 {m['p99']:.3g} "
              f"({m['median_rel_peak']:.2g} / {m['p99_rel_peak']:.2g} of the peak)")
    for r in report["ratios"]:
        how = "measured" if r["measured"] else "extrapolated by spp^-1/2"
        same = r["same_time"]
        print(f"rel_tol {r['rel_tol']:g}: target median {r['target']['median']:.3g} p99 {r['target']['p99']:.3g}; "
              f"Mitsuba needs {r['mitsuba_spp']:.3g} spp, {r['mitsuba_seconds']:.4g} s ({how}; fitted slopes median "
              f"{r['slopes']['median']:.2f}, p99 {r['slopes']['p99']:.2f}): vlref reference is {r['ratio']:.4g}x "
              f"faster (median alone {r['ratio_per_statistic']['median']:.3g}x, p99 alone "
              f"{r['ratio_per_statistic']['p99']:.3g}x; measured lower bound: {r['lower_bound'] or r['ratio']:.3g}x); "
              f"in about vlref's time "
              f"({same['seconds']:.3g} s, {same['spp']} spp) Mitsuba's error is median {same['median']:.3g}, "
              f"p99 {same['p99']:.3g}")
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(report, fh, indent=1)


if __name__ == "__main__":
    main()
