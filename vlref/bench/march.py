"""``vlref bench``: throughput of every stage of a frame, measured in one run, reported against the targets.

Sections of the report (``--json`` prints it as one JSON object; keys as below):

``machine``       CPU model, cores, Numba threads, Python/NumPy/Numba versions, date, command.
``march``         the physical march kernel (:func:`vlref.techniques.physical.render`, float64) on the
                  benchmark scene (:func:`bench_scene`): (a) ``one_spot`` -- one spot light with a PCF
                  shadow map, HG ``g = 0.5``, extinction on the view ray and on the light leg, height fog;
                  (b) ``four_lights`` -- two spot lights, a point light and a directional light, each with
                  PCF shadows. **Samples** are (pixel, light) pairs whose ray segment inside the light's
                  volume is not empty, times the step count: the work the kernel does.
``baseline``      the same computation as (a) in vectorised NumPy (:mod:`vlref.bench_baseline`), its
                  samples/s, its largest relative difference to the kernel, and the kernel/NumPy ratios;
                  and :func:`plain_march` (one ``exp``, one ``pow``, one hard shadow lookup per sample, on
                  (a)'s rays) at the full size on all threads and at the scaling size on one thread, with
                  the kernel/plain ratios.
``scaling``       (a) at 1, 2, 4, 8 and 16 Numba threads (counts above ``NUMBA_NUM_THREADS`` are skipped
                  and listed); speedup and parallel efficiency relative to one thread.
``raycast``       the G-buffer (primary rays/s); ``shadow_maps``: the four lights' maps (texels/s), and,
                  without ``--quick``, raycast and shadow maps of the bundled ``forest``, ``cage``, ``window``.
``post``          each post pass on a full-resolution frame (min-downsample, the three depth-aware
                  upsamples, bilateral blur H+V, radial blur, composite) and the ``preview`` render
                  (``killzone``, half resolution, 16 steps, post passes included).
``reference``     :func:`vlref.reference.render_reference` at ``rel_tol = 1e-4`` on a reduced
                  resolution of (a) (the same frustum): seconds per pixel, and the estimate for 640x360.
``first_render``  a fresh interpreter that imports vlref and renders (a) at 320x180, with a fresh
                  (``cold``) and then a filled (``warm``) ``NUMBA_CACHE_DIR``: process wall time.
``memory``        peak memory of a frame of (b) at the memory size (steps do not change allocations):
                  ``tracemalloc`` peak of the NumPy allocations in this process, and the peak resident
                  set of a subprocess that renders the same frame (``VmHWM``; ``ru_maxrss`` where there
                  is no ``/proc``: on Linux ``ru_maxrss`` carries the parent's peak across ``exec``).
``targets``       each target of issue 8, the measured figure, and whether it is met.

Timings are medians of ``repeats`` runs after one warm-up run (JIT compile excluded except in
``first_render``). Benchmarks report; they never fail on a timing. The core stack (NumPy, Numba,
SciPy) is all this module needs.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
import tracemalloc
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

from .lights.pack import (F_DX, F_DY, F_DZ, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UX, F_UY,
                          F_UZ)
from .march.physical import light_segment
from .scene.model import (Box, CameraSettings, Cylinder, HeightFog, Light, Medium, Plane, RenderSettings, Scene,
                          ShadowSettings, Sphere)

__all__ = ["BenchConfig", "FULL", "QUICK", "SECTIONS", "bench_scene", "run_bench", "main_bench"]

SECTIONS = ("machine", "march", "baseline", "scaling", "raycast", "shadow_maps", "post", "reference",
            "first_render", "memory", "targets")
THREADS = (1, 2, 4, 8, 16)


@dataclass(frozen=True)
class BenchConfig:
    """Sizes of one benchmark run (``FULL`` is issue 8's; ``QUICK`` a smoke run for CI)."""

    width: int = 1920
    height: int = 1080
    steps: int = 64
    repeats: int = 3
    small: tuple[int, int] = (480, 270)  # thread scaling
    baseline: tuple[int, int] = (240, 135)  # the NumPy baseline (about 60x slower than the kernel per core)
    preview: tuple[int, int, int] = (320, 180, 16)  # width, height, steps
    reference: tuple[int, int] = (64, 36)
    reference_target: tuple[int, int] = (640, 360)
    first_render: tuple[int, int] = (320, 180)
    memory_steps: int = 4
    bundled: tuple[str, ...] = ("forest", "cage", "window")
    shadow_resolution: int = 1024
    cold_cache: bool = True  # a cold first render compiles every kernel: ~90 s on 2 busy cores


FULL = BenchConfig()
QUICK = BenchConfig(width=48, height=27, steps=8, repeats=1, small=(32, 18), baseline=(16, 9), preview=(32, 18, 4),
                    reference=(4, 3),
                    first_render=(16, 9), memory_steps=2, bundled=(), shadow_resolution=64, cold_cache=False)


def bench_scene(width: int, height: int, steps: int, lights: str = "one", shadow_resolution: int = 1024,
                technique: str = "physical", resolution: str | None = None) -> Scene:
    """The benchmark scene: a floor, two boxes, a sphere and a pillar in height fog (HG g = 0.5).

    ``lights = "one"``: one PCF-shadowed spot light whose cone covers most of the view;
    ``"four"``: that spot, a second spot, a point light and a directional light, all PCF-shadowed.
    """
    sh = ShadowSettings(resolution=shadow_resolution, bias=0.03)
    spot = Light(type="spot", position=(0.0, 7.0, -3.0), direction=(0.0, -1.0, 0.6), spot_angle=110.0, range=30.0,
                 intensity=80.0, color=(1.0, 0.9, 0.75), shadows=sh)
    chosen = (spot,)
    if lights == "four":
        chosen = (spot,
                  Light(type="spot", position=(-4.0, 5.0, 2.0), direction=(0.5, -1.0, 0.2), spot_angle=60.0,
                        range=15.0, intensity=40.0, color=(0.6, 0.7, 1.0), shadows=sh),
                  Light(type="point", position=(3.0, 2.5, 2.0), range=8.0, intensity=15.0, color=(1.0, 0.5, 0.3),
                        shadows=dataclasses.replace(sh, resolution=max(8, shadow_resolution // 2))),
                  Light(type="directional", direction=(0.3, -0.8, 0.5), intensity=1.5,
                        shadows=dataclasses.replace(sh, cascades=2, distance=40.0)))
    objects = (Plane(), Box(center=(-2.5, 1.0, 1.0), size=(1.0, 2.0, 1.0)),
               Box(center=(2.0, 1.5, 2.5), size=(1.0, 3.0, 1.0), rotation=(0.0, 30.0, 0.0)),
               Sphere(center=(0.5, 1.0, 4.0), radius=1.0), Cylinder(center=(-0.8, 1.5, 0.5), radius=0.3, height=3.0))
    return Scene(render=RenderSettings(width=width, height=height, steps=steps, max_distance=40.0,
                                       technique=technique, resolution=resolution),
                 camera=CameraSettings(position=(0.0, 2.0, -8.0), look_at=(0.0, 1.5, 0.0), fov=60.0),
                 medium=Medium(scattering=0.05, absorption=0.01, anisotropy=0.5,
                               height_fog=HeightFog(base=0.0, falloff=0.15)),
                 lights=chosen, objects=objects)


def _median_time(fn, repeats: int) -> float:
    """Median wall time of ``repeats`` calls of ``fn`` after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return float(np.median(times))


@njit(cache=True, fastmath=False, parallel=True)
def _active(li, lf, origin, dirs, t_end, out):
    """``out[y, x]`` = number of lights whose volume the pixel ray crosses (non-empty segment)."""
    h, w = t_end.shape
    for p in prange(h * w):
        i, j = p // w, p % w
        n = 0
        for k in range(li.shape[0]):
            a, b = light_segment(li, lf, k, origin[0], origin[1], origin[2], dirs[i, j, 0], dirs[i, j, 1],
                                 dirs[i, j, 2], t_end[i, j])
            n += 1 if b > a else 0
        out[i, j] = n


def march_samples(scene: Scene, frame) -> int:
    """Samples the physical march of ``frame`` takes: active (pixel, light) pairs times ``render.steps``."""
    dirs = frame.camera.ray_directions()
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    count = np.empty(t_end.shape, dtype=np.int64)
    _active(frame.lights.ints, frame.lights.floats.astype(np.float64), np.asarray(frame.camera.position, float),
            dirs, t_end, count)
    return int(count.sum()) * int(scene.render.steps)


def _time_march(scene: Scene, repeats: int) -> dict:
    from .render import prepare_frame
    from .techniques import physical

    frame = prepare_frame(scene)
    frame.shadow_maps()
    seconds = _median_time(lambda: physical.render(scene, frame), repeats)
    samples = march_samples(scene, frame)
    threads = numba.get_num_threads()
    return {"width": scene.render.width, "height": scene.render.height, "steps": scene.render.steps,
            "lights": len(scene.lights), "threads": threads, "seconds": seconds, "samples": samples,
            "samples_per_s": samples / seconds, "samples_per_s_per_thread": samples / seconds / threads}


def bench_march(cfg: BenchConfig) -> dict:
    out = {}
    for name, lights in (("one_spot", "one"), ("four_lights", "four")):
        scene = bench_scene(cfg.width, cfg.height, cfg.steps, lights, cfg.shadow_resolution)
        out[name] = _time_march(scene, cfg.repeats)
    return out


@njit(cache=True, fastmath=False, parallel=True)
def plain_march(origin, dirs, seg, steps, sigma_t, lf, data, base, res, out):
    """The plain comparison kernel of issue 12 on (a)'s rays and spot light: per sample one ``exp`` (view
    transmittance ``e^{-σt t}``), one ``pow`` (``d^{-3}``, the shape of HG's denominator) and a hard
    (nearest-texel) shadow-map lookup; no fog, cone, light leg or phase. ``seg`` (1, H, W, 2) from
    :func:`vlref.bench_baseline.light_segments`; ``out`` (H, W)."""
    h, w = out.shape
    px, py, pz = lf[0, F_PX], lf[0, F_PY], lf[0, F_PZ]
    th = lf[0, F_TAN_HALF]
    for p in prange(h * w):
        i, j = p // w, p % w
        a, b = seg[0, i, j, 0], seg[0, i, j, 1]
        acc = 0.0
        if b > a:
            dt = (b - a) / steps
            for s in range(steps):
                t = a + (s + 0.5) * dt
                wx = origin[0] + t * dirs[i, j, 0] - px
                wy = origin[1] + t * dirs[i, j, 1] - py
                wz = origin[2] + t * dirs[i, j, 2] - pz
                d2 = wx * wx + wy * wy + wz * wz
                xl = wx * lf[0, F_RX] + wy * lf[0, F_RY] + wz * lf[0, F_RZ]
                yl = wx * lf[0, F_UX] + wy * lf[0, F_UY] + wz * lf[0, F_UZ]
                zl = wx * lf[0, F_DX] + wy * lf[0, F_DY] + wz * lf[0, F_DZ]
                lit = 1.0
                if zl > 0.0:
                    k = 0.5 / (zl * th)
                    col = min(max(int((0.5 + xl * k) * res), 0), res - 1)
                    row = min(max(int((0.5 - yl * k) * res), 0), res - 1)
                    ref = data[base + row * res + col]
                    lit = 1.0 if d2 <= ref * ref else 0.0
                acc += math.exp(-sigma_t * t) * lit * d2 ** -1.5 * dt
        out[i, j] = acc


def _one_spot_frame(cfg: BenchConfig, width: int, height: int):
    """Scene (a) at ``width x height`` and what the hand-written marches take: ``(scene, frame, shadow maps,
    ray directions, segment ends, light floats (float64), camera origin)``."""
    from .render import prepare_frame

    scene = bench_scene(width, height, cfg.steps, "one", cfg.shadow_resolution)
    frame = prepare_frame(scene)
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    origin = np.asarray(frame.camera.position, dtype=np.float64)
    return (scene, frame, frame.shadow_maps(), frame.camera.ray_directions(), t_end,
            frame.lights.floats.astype(np.float64), origin)


def _plain_rate(cfg: BenchConfig, width: int, height: int, threads: int) -> dict:
    """Samples/s of :func:`plain_march` on (a) at ``width x height`` with ``threads`` Numba threads."""
    from .bench_baseline import light_segments
    from .lights.shadowmaps import S_OFFSET, S_RES

    scene, frame, sm, dirs, t_end, lf, origin = _one_spot_frame(cfg, width, height)
    seg = np.empty((1, height, width, 2))
    light_segments(frame.lights.ints, lf, origin, dirs, t_end, seg)
    out = np.empty((height, width))
    before = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        seconds = _median_time(lambda: plain_march(origin, dirs, seg, cfg.steps, scene.medium.extinction, lf, sm.data,
                                                   int(sm.ints[0, S_OFFSET]), int(sm.ints[0, S_RES]), out), cfg.repeats)
    finally:
        numba.set_num_threads(before)
    samples = march_samples(scene, frame)
    return {"width": width, "height": height, "threads": numba.get_num_threads() if threads > 1 else 1,
            "seconds": seconds, "samples_per_s": samples / seconds}


def bench_baseline(cfg: BenchConfig, march: dict, scaling: dict) -> dict:
    """The NumPy baseline of (a) at ``cfg.baseline``, checked against the kernel's result (same size)."""
    from .bench_baseline import light_segments, march_spot_numpy
    from .march.patterns import offsets
    from .medium import pack_medium
    from .render import resolved
    from .techniques import physical

    w, h = cfg.baseline
    scene, frame, sm, dirs, t_end, lf, origin = _one_spot_frame(cfg, w, h)
    beta = offsets(resolved(scene, "sampling"), w, h, scene.render.seed)
    mp = pack_medium(scene).params

    def run():
        seg = np.empty((1, h, w, 2))
        light_segments(frame.lights.ints, lf, origin, dirs, t_end, seg)
        return march_spot_numpy(origin, dirs, t_end, beta, cfg.steps, mp, lf, sm.ints, sm.floats, sm.data, seg)

    seconds = _median_time(run, 1)
    ref = physical.render(scene, frame)["inscatter"]
    got = run()
    scale = max(float(np.abs(ref).max()), 1e-300)
    samples = march_samples(scene, frame)
    rate = samples / seconds
    one_thread = scaling["threads"].get("1", {}).get("samples_per_s")
    plain_all = _plain_rate(cfg, cfg.width, cfg.height, numba.get_num_threads())
    plain_one = _plain_rate(cfg, cfg.small[0], cfg.small[1], 1)
    return {"width": w, "height": h, "steps": cfg.steps, "seconds": seconds, "samples": samples,
            "samples_per_s": rate, "max_abs_diff_relative_to_peak": float(np.abs(got - ref).max()) / scale,
            "ratio_kernel_all_threads": march["one_spot"]["samples_per_s"] / rate,
            "ratio_kernel_one_thread": (one_thread / rate) if one_thread else None,
            "plain_all_threads": plain_all, "plain_one_thread": plain_one,
            "ratio_kernel_plain_all_threads": march["one_spot"]["samples_per_s"] / plain_all["samples_per_s"],
            "ratio_kernel_plain_one_thread": (one_thread / plain_one["samples_per_s"]) if one_thread else None}


def bench_scaling(cfg: BenchConfig) -> dict:
    """(a) at ``cfg.small`` for each thread count of ``THREADS`` that Numba allows."""
    limit = numba.config.NUMBA_NUM_THREADS
    before = numba.get_num_threads()
    w, h = cfg.small
    scene = bench_scene(w, h, cfg.steps, "one", cfg.shadow_resolution)
    runs, skipped = {}, [n for n in THREADS if n > limit]
    try:
        for n in (n for n in THREADS if n <= limit):
            numba.set_num_threads(n)
            runs[str(n)] = _time_march(scene, cfg.repeats)
    finally:
        numba.set_num_threads(before)
    base = runs["1"]["samples_per_s"]
    for n, r in runs.items():
        r["speedup"] = r["samples_per_s"] / base
        r["efficiency"] = r["speedup"] / int(n)
    return {"numba_num_threads": limit, "threads": runs, "skipped": skipped,
            "note": (f"thread counts {skipped} skipped: above NUMBA_NUM_THREADS = {limit}" if skipped else "")}


def bench_geometry(cfg: BenchConfig) -> tuple[dict, dict]:
    """Raycast (primary rays/s) and shadow maps (texels/s) of (b), plus the bundled scenes."""
    from .camera import camera_from_settings
    from .geometry import build_geometry, raycast
    from .lights import pack_lights
    from .lights.shadowmaps import build_shadow_maps
    from .scene import load_scene

    def measure(scene):
        cam = camera_from_settings(scene.camera, scene.render.width, scene.render.height)
        geo = build_geometry(scene)
        packed = pack_lights(scene)
        rc = _median_time(lambda: raycast(scene, cam, geo), cfg.repeats)
        sm_seconds = _median_time(lambda: build_shadow_maps(scene, cam, geo, packed), cfg.repeats)
        texels = int(build_shadow_maps(scene, cam, geo, packed).data.size)
        rays = scene.render.width * scene.render.height
        return ({"width": scene.render.width, "height": scene.render.height, "seconds": rc, "rays_per_s": rays / rc},
                {"texels": texels, "seconds": sm_seconds, "texels_per_s": texels / sm_seconds})

    rc, sm = measure(bench_scene(cfg.width, cfg.height, cfg.steps, "four", cfg.shadow_resolution))
    rc_out, sm_out = {"bench_four_lights": rc}, {"bench_four_lights": sm}
    for name in cfg.bundled:
        rc_out[name], sm_out[name] = measure(load_scene(name, ["render.width=320", "render.height=180"]))
    return rc_out, sm_out


def bench_post(cfg: BenchConfig) -> dict:
    """Each post pass at ``cfg.width x cfg.height`` (half-resolution inputs where the pass takes them)."""
    from .post.blur import blur_hv, thesis_blur_pass
    from .post.composite import composite_physical
    from .post.downsample import downsample_min
    from .post.radial import radial_blur
    from .post.upsample import thesis_upsample, urp_upsample, vl_upsample
    from .notebook import PreviewRenderer
    from .render import render

    h, w = cfg.height, cfg.width
    rng = np.random.default_rng(0)
    depth = rng.uniform(1.0, 30.0, size=(h, w))
    depth_lo = downsample_min(depth, "half")
    lo = rng.random(depth_lo.shape + (3,))
    full = rng.random((h, w, 3))
    trans = rng.random((h, w))
    passes = {
        "downsample_min_half": lambda: downsample_min(depth, "half"),
        "thesis_upsample": lambda: thesis_upsample(lo, depth_lo, depth),
        "vl_upsample": lambda: vl_upsample(lo, depth_lo, depth),
        "urp_upsample": lambda: urp_upsample(lo, depth_lo, depth),
        "bilateral_blur_hv": lambda: blur_hv(thesis_blur_pass, full, depth),
        "radial_blur_64": lambda: radial_blur(full, (0.5, 0.4), 64, 0.9, 0.5, 0.97, 0.3),
        "composite": lambda: composite_physical(full, trans, full),
    }
    out = {name: {"seconds": _median_time(fn, cfg.repeats), "width": w, "height": h} for name, fn in passes.items()}
    pw, ph, steps = cfg.preview
    scene = bench_scene(pw, ph, steps, "one", cfg.shadow_resolution, technique="killzone", resolution="half")
    # A slider move re-renders with the frame (geometry, G-buffer, shadow maps) reused, as the explorer
    # notebook does; the first render (frame included) is timed too.
    first = render(scene).timings
    renderer = PreviewRenderer()
    renderer.render(scene)
    variants = [scene.replace(medium=dataclasses.replace(scene.medium, anisotropy=g)) for g in (0.3, 0.5)]
    count = [0]

    def preview():
        count[0] += 1
        renderer.render(variants[count[0] % 2])

    seconds = _median_time(preview, cfg.repeats)
    out["preview"] = {"seconds": seconds, "width": pw, "height": ph, "steps": steps, "technique": "killzone",
                      "resolution": "half", "what": "re-render after a medium change, frame reused",
                      "first_render_stages": dict(first)}
    return out


def bench_reference(cfg: BenchConfig) -> dict:
    from .reference import render_reference

    w, h = cfg.reference
    scene = bench_scene(w, h, cfg.steps, "one", cfg.shadow_resolution)
    render_reference(bench_scene(2, 1, cfg.steps, "one", cfg.shadow_resolution), rel_tol=1e-4)  # JIT warm-up
    start = time.perf_counter()
    res = render_reference(scene, rel_tol=1e-4)
    seconds = time.perf_counter() - start
    per_pixel = seconds / (w * h)
    tw, th = cfg.reference_target
    return {"width": w, "height": h, "rel_tol": 1e-4, "seconds": seconds, "seconds_per_pixel": per_pixel,
            "threads": numba.get_num_threads(), "max_error": float(res.max_error),
            "estimate_target_size": [tw, th], "estimate_seconds": per_pixel * tw * th}


_CHILD = """
import json, resource, sys, time
t0 = time.perf_counter()
from vlref.bench import bench_scene
from vlref.render import render
t1 = time.perf_counter()
render(bench_scene({w}, {h}, {steps}, {lights!r}, {res}))
t2 = time.perf_counter()
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
try:  # VmHWM is this address space's own peak; ru_maxrss keeps the parent's across exec on Linux
    status = open("/proc/self/status").read().split("VmHWM:")[1]
    peak = int(status.split()[0]) * 1024
except (OSError, IndexError, ValueError):
    pass
print(json.dumps({{"import_s": t1 - t0, "render_s": t2 - t1, "maxrss_bytes": peak}}))
"""


def _child(cache_dir: str | None, w: int, h: int, steps: int, lights: str, res: int) -> dict:
    """Run a fresh interpreter that renders the benchmark scene; its report plus the process wall time.

    ``cache_dir``: the child's ``NUMBA_CACHE_DIR`` (None: this process's setting).
    """
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(Path(__file__).resolve().parents[1]),
                                                    env.get("PYTHONPATH")) if p)
    code = _CHILD.format(w=w, h=h, steps=steps, lights=lights, res=res)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    report["process_s"] = wall
    return report


def bench_first_render(cfg: BenchConfig) -> dict:
    """A fresh process renders (a): with a fresh cache, then with the cache it filled (``cold_cache``), else
    only with this process's cache (warm; ``cold`` is then None)."""
    w, h = cfg.first_render
    if not cfg.cold_cache:
        warm = _child(None, w, h, cfg.steps, "one", cfg.shadow_resolution)
        return {"width": w, "height": h, "cold": None, "warm": warm, "note": "cold run skipped (--quick)"}
    with tempfile.TemporaryDirectory(prefix="vlref_bench_cache_") as cache:
        cold = _child(cache, w, h, cfg.steps, "one", cfg.shadow_resolution)
        warm = _child(cache, w, h, cfg.steps, "one", cfg.shadow_resolution)
    return {"width": w, "height": h, "cold": cold, "warm": warm, "note": ""}


def bench_memory(cfg: BenchConfig) -> dict:
    from .render import render

    scene = bench_scene(cfg.width, cfg.height, cfg.memory_steps, "four", cfg.shadow_resolution)
    render(scene)  # JIT warm-up: compiling allocates too
    tracemalloc.start()
    try:
        render(scene)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    child = _child(None, cfg.width, cfg.height, cfg.memory_steps, "four", cfg.shadow_resolution)
    return {"width": cfg.width, "height": cfg.height, "lights": 4, "steps": cfg.memory_steps,
            "tracemalloc_peak_bytes": int(peak), "subprocess_maxrss_bytes": int(child["maxrss_bytes"])}


def _target(name, value, limit, unit, better="lower", note=""):
    met = value <= limit if better == "lower" else value >= limit
    ratio = value / limit if better == "lower" else limit / value
    return {"target": name, "measured": value, "limit": limit, "unit": unit, "met": bool(met),
            "factor_off": None if met else ratio, "note": note}


def targets(cfg: BenchConfig, r: dict) -> list[dict]:
    """Issue 8's targets against this run (meaningful only for the FULL sizes)."""
    one = r["march"]["one_spot"]
    cores = r["machine"]["numba_threads"]
    scaling = r["scaling"]["threads"]
    top = str(max(int(n) for n in scaling))
    per_core = scaling["1"]["samples_per_s"]
    ref = r["reference"]
    return [
        _target("march samples/s per core (one spot, float64, 1 thread)", per_core, 100e6, "samples/s", "higher"),
        _target(f"parallel efficiency at {top} threads", scaling[top]["efficiency"], 0.85, "", "higher",
                "target is at 16 threads on 16 cores" if top != "16" else ""),
        _target(f"{one['width']}x{one['height']} x {one['steps']} steps x 1 shadowed spot ({cores} threads)",
                one["seconds"], 0.25, "s", note="target is on 16 cores"),
        _target("preview re-render {}x{}, {} steps, half res, incl. post passes".format(*cfg.preview),
                r["post"]["preview"]["seconds"], 0.150, "s", note="target is on 2 cores"),
        _target("first render, fresh process, warm cache", r["first_render"]["warm"]["process_s"], 3.0, "s"),
        _target(f"reference 1e-4 at 640x360 (estimate, {ref['threads']} threads)", ref["estimate_seconds"], 120.0,
                "s", note="target is on 16 cores"),
        _target(f"peak memory, {cfg.width}x{cfg.height}, four shadowed lights (subprocess maxrss)",
                r["memory"]["subprocess_maxrss_bytes"] / 2**30, 1.0, "GiB"),
    ]


def machine_info(argv: list[str]) -> dict:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return {"cpu_model": model, "cores_available": cores, "cpu_count": os.cpu_count(),
            "numba_threads": numba.get_num_threads(), "numba_num_threads": numba.config.NUMBA_NUM_THREADS,
            "threading_layer": os.environ.get("NUMBA_THREADING_LAYER", "default"),
            "python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
            "platform": platform.platform(), "date": datetime.datetime.now(datetime.timezone.utc).isoformat(),
            "command": "vlref bench " + " ".join(argv)}


def run_bench(cfg: BenchConfig, argv: list[str] = (), log=None) -> dict:
    """Every section of the report (module docstring) for the sizes of ``cfg``.

    ``log(message, partial_report)`` is called before each section (cheapest and most-wanted first).
    """
    log = log or (lambda msg, report: None)
    r = {"machine": machine_info(list(argv)), "config": dataclasses.asdict(cfg)}
    steps = (("march", lambda: bench_march(cfg)), ("scaling", lambda: bench_scaling(cfg)),
             (("raycast", "shadow_maps"), lambda: bench_geometry(cfg)), ("post", lambda: bench_post(cfg)),
             ("reference", lambda: bench_reference(cfg)), ("memory", lambda: bench_memory(cfg)),
             ("baseline", lambda: bench_baseline(cfg, r["march"], r["scaling"])),
             ("first_render", lambda: bench_first_render(cfg)))
    for key, fn in steps:
        log(key if isinstance(key, str) else ", ".join(key), r)
        value = fn()
        if isinstance(key, str):
            r[key] = value
        else:
            r.update(zip(key, value))
    r["targets"] = targets(cfg, r)
    return r


def _fmt(x) -> str:
    return f"{x:.4g}" if isinstance(x, float) else str(x)


def format_report(r: dict) -> str:
    """A plain-text summary of the report."""
    m = r["machine"]
    lines = [f"vlref bench  {m['date']}", f"machine: {m['cpu_model']}, {m['cores_available']} cores, "
             f"{m['numba_threads']} Numba threads; numpy {m['numpy']}, numba {m['numba']}, python {m['python']}", ""]
    for name, s in r["march"].items():
        lines.append(f"march {name:12s} {s['width']}x{s['height']}x{s['steps']}: {s['seconds']:.3f} s, "
                     f"{s['samples_per_s'] / 1e6:.2f} M samples/s ({s['samples_per_s_per_thread'] / 1e6:.2f} per thread)")
    b = r["baseline"]
    lines.append(f"numpy baseline {b['width']}x{b['height']}: {b['samples_per_s'] / 1e6:.3f} M samples/s; kernel/numpy "
                 f"{b['ratio_kernel_all_threads']:.1f}x (all threads), {_fmt(b['ratio_kernel_one_thread'])}x (1 thread)")
    lines.append(f"plain one-exp kernel: {b['plain_all_threads']['samples_per_s'] / 1e6:.2f} M samples/s (all threads), "
                 f"{b['plain_one_thread']['samples_per_s'] / 1e6:.2f} (1 thread); kernel/plain "
                 f"{b['ratio_kernel_plain_all_threads']:.2f}x, {_fmt(b['ratio_kernel_plain_one_thread'])}x")
    for n, s in r["scaling"]["threads"].items():
        lines.append(f"threads {n:>2s}: {s['samples_per_s'] / 1e6:.2f} M samples/s, speedup {s['speedup']:.2f}, "
                     f"efficiency {s['efficiency']:.2f}")
    if r["scaling"]["note"]:
        lines.append(r["scaling"]["note"])
    for name, s in r["raycast"].items():
        sm = r["shadow_maps"][name]
        lines.append(f"{name}: raycast {s['width']}x{s['height']} {s['seconds']:.3f} s; shadow maps "
                     f"{sm['texels']} texels {sm['seconds']:.3f} s")
    for name, s in r["post"].items():
        lines.append(f"post {name}: {s['seconds'] * 1e3:.1f} ms")
    ref = r["reference"]
    lines.append(f"reference {ref['width']}x{ref['height']}: {ref['seconds_per_pixel'] * 1e3:.2f} ms/pixel, "
                 f"640x360 estimate {ref['estimate_seconds']:.1f} s")
    fr = r["first_render"]
    cold = f"{fr['cold']['process_s']:.2f} s" if fr["cold"] else "skipped"
    lines.append(f"first render: cold {cold}, warm {fr['warm']['process_s']:.2f} s")
    mem = r["memory"]
    lines.append(f"memory: tracemalloc peak {mem['tracemalloc_peak_bytes'] / 2**20:.0f} MiB, subprocess maxrss "
                 f"{mem['subprocess_maxrss_bytes'] / 2**20:.0f} MiB")
    lines.append("")
    for t in r["targets"]:
        status = "met" if t["met"] else f"missed ({t['factor_off']:.1f}x off)"
        lines.append(f"target {t['target']}: {_fmt(t['measured'])} {t['unit']} vs {_fmt(t['limit'])}: {status}"
                     + (f" [{t['note']}]" if t["note"] else ""))
    return "\n".join(lines)


def bench_parser() -> argparse.ArgumentParser:
    """The options of ``vlref bench``."""
    p = argparse.ArgumentParser(prog="vlref bench", description="benchmarks (see vlref.bench)")
    p.add_argument("--quick", action="store_true", help="tiny sizes, one repeat (CI smoke run; default: full sizes)")
    p.add_argument("--json", action="store_true", help="print the report as JSON (default: a text table)")
    p.add_argument("-o", "--output", help="also write the JSON report to this file (default: print only)")
    p.add_argument("--repeats", type=int, help="timed runs per figure (median); default 3, 1 with --quick")
    return p


def main_bench(argv: list[str]) -> int:
    """``vlref bench [--quick] [--json] [-o FILE]``; returns 0 (benchmarks never fail on a timing)."""
    p = bench_parser()
    try:
        args = p.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    if args.output:
        from .errors import InputError
        from .io import check_output_file
        try:
            check_output_file(args.output)
        except InputError as exc:
            print(f"vlref bench: error: {exc}", file=sys.stderr)
            return 2
    cfg = QUICK if args.quick else FULL
    if args.repeats:
        cfg = dataclasses.replace(cfg, repeats=max(1, args.repeats))
    def log(msg, partial):
        print(f"[bench] {msg}", file=sys.stderr, flush=True)
        if args.output:  # what is done so far survives a run cut short
            Path(args.output).write_text(json.dumps(partial, indent=1))

    report = run_bench(cfg, argv, log)
    text = json.dumps(report, indent=1)
    if args.output:
        Path(args.output).write_text(text)
    print(text if args.json else format_report(report))
    return 0
