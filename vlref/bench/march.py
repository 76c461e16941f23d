"""Sections ``march``, ``scaling`` and ``baseline``: the physical march kernel's samples/s on the benchmark
scene, its thread scaling, and the vectorised NumPy (:mod:`.baseline`) and plain one-``exp`` kernels
(:func:`plain_march`) it is measured against."""

from __future__ import annotations

import dataclasses
import math

import numba
import numpy as np
from numba import prange

from ..jit import njit
from ..lights.pack import (F_DX, F_DY, F_DZ, F_PX, F_PY, F_PZ, F_RX, F_RY, F_RZ, F_TAN_HALF, F_UX, F_UY,
                           F_UZ)
from ..lights.shadow_pack import S_OFFSET, S_RES
from ..march.patterns import offsets
from ..march.segments import light_segment
from ..medium import pack_medium
from ..render import prepare_frame
from ..scene.model import Scene
from ..techniques import physical, resolved
from .baseline import light_segments, march_spot_numpy
from .ceiling import bench_ceiling
from .config import THREADS, BenchConfig, bench_scene, median_time

__all__ = ["march_samples", "bench_march", "plain_march", "bench_baseline", "bench_scaling"]


@njit(cache=True, fastmath=False, parallel=True)
def _active(lights, origin, dirs, t_end, out):
    """``out[y, x]`` = number of lights whose volume the pixel ray crosses (non-empty segment)."""
    h, w = t_end.shape
    for p in prange(h * w):
        i, j = p // w, p % w
        n = 0
        for k in range(lights.ints.shape[0]):
            a, b = light_segment(lights, k, origin[0], origin[1], origin[2], dirs[i, j, 0], dirs[i, j, 1],
                                 dirs[i, j, 2], t_end[i, j])
            n += 1 if b > a else 0
        out[i, j] = n


def march_samples(scene: Scene, frame) -> int:
    """Samples the physical march of ``frame`` takes: active (pixel, light) pairs times its steps (``render.steps``, or
    the technique's default where the scene leaves it unset)."""
    dirs = frame.camera.ray_directions()
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    count = np.empty(t_end.shape, dtype=np.int64)
    _active(frame.lights.astype(np.float64), np.asarray(frame.camera.position, float), dirs, t_end, count)
    return int(count.sum()) * int(resolved(scene, "steps"))


def _time_march(scene: Scene, repeats: int) -> dict:
    frame = prepare_frame(scene)
    frame.shadow_maps()
    seconds = median_time(lambda: physical.render(scene, frame), repeats)
    samples = march_samples(scene, frame)
    threads = numba.get_num_threads()
    return {"width": scene.render.width, "height": scene.render.height, "steps": scene.render.steps,
            "lights": len(scene.lights), "threads": threads, "seconds": seconds, "samples": samples,
            "samples_per_s": samples / seconds, "samples_per_s_per_thread": samples / seconds / threads}


def bench_march(cfg: BenchConfig) -> dict:
    """Scenes (a) ``one_spot`` and (b) ``four_lights`` in float64, then both in float32 (``render.precision``;
    keys ``one_spot_float32``, ``four_lights_float32``), then (a) in float64 without its height fog
    (``one_spot_no_fog``: a homogeneous medium, as in most bundled scenes)."""
    out = {}
    for precision, suffix in (("float64", ""), ("float32", "_float32")):
        for name, lights in (("one_spot", "one"), ("four_lights", "four")):
            scene = bench_scene(cfg.width, cfg.height, cfg.steps, lights, cfg.shadow_resolution)
            scene = dataclasses.replace(scene, render=dataclasses.replace(scene.render, precision=precision))
            out[name + suffix] = {"precision": precision, **_time_march(scene, cfg.repeats)}
    scene = bench_scene(cfg.width, cfg.height, cfg.steps, "one", cfg.shadow_resolution)
    scene = scene.replace(medium=dataclasses.replace(scene.medium, height_fog=None))
    out["one_spot_no_fog"] = {"precision": "float64", **_time_march(scene, cfg.repeats)}
    return out


@njit(cache=True, fastmath=False, parallel=True)
def plain_march(origin, dirs, seg, steps, sigma_t, lf, data, base, res, out):
    """The plain kernel of BENCHMARKS.md "Device run", on (a)'s rays and spot light: per sample one ``exp`` (view
    transmittance ``e^{-σt t}``), one ``pow`` (``d^{-3}``, the shape of HG's denominator) and a hard
    (nearest-texel) shadow-map lookup; no fog, cone, light leg or phase. ``seg`` (1, H, W, 2) from
    :func:`vlref.bench.baseline.light_segments`; ``out`` (H, W)."""
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
    scene = bench_scene(width, height, cfg.steps, "one", cfg.shadow_resolution)
    frame = prepare_frame(scene)
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    origin = np.asarray(frame.camera.position, dtype=np.float64)
    return (scene, frame, frame.shadow_maps(), frame.camera.ray_directions(), t_end,
            frame.lights.floats.astype(np.float64), origin)


def _plain_rate(cfg: BenchConfig, width: int, height: int, threads: int) -> dict:
    """Samples/s of :func:`plain_march` on (a) at ``width x height`` with ``threads`` Numba threads."""
    scene, frame, sm, dirs, t_end, lf, origin = _one_spot_frame(cfg, width, height)
    seg = np.empty((1, height, width, 2))
    light_segments(frame.lights._replace(floats=lf), origin, dirs, t_end, seg)
    out = np.empty((height, width))
    before = numba.get_num_threads()
    numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
    try:
        seconds = median_time(lambda: plain_march(origin, dirs, seg, cfg.steps, scene.medium.extinction, lf, sm.data,
                                                   int(sm.ints[0, S_OFFSET]), int(sm.ints[0, S_RES]), out), cfg.repeats)
    finally:
        numba.set_num_threads(before)
    samples = march_samples(scene, frame)
    return {"width": width, "height": height, "threads": numba.get_num_threads() if threads > 1 else 1,
            "seconds": seconds, "samples_per_s": samples / seconds}


def bench_baseline(cfg: BenchConfig, march: dict, scaling: dict) -> dict:
    """The NumPy baseline of (a) at ``cfg.baseline``, checked against the kernel's result (same size)."""
    w, h = cfg.baseline
    scene, frame, sm, dirs, t_end, lf, origin = _one_spot_frame(cfg, w, h)
    beta = offsets(resolved(scene, "sampling"), w, h, scene.render.seed)
    mp = pack_medium(scene).params

    def run():
        seg = np.empty((1, h, w, 2))
        light_segments(frame.lights._replace(floats=lf), origin, dirs, t_end, seg)
        return march_spot_numpy(origin, dirs, t_end, beta, cfg.steps, mp, lf, sm.ints, sm.floats, sm.data, seg)

    seconds = median_time(run, 1)
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
    """(a) at ``cfg.small`` for each thread count of ``THREADS`` that Numba allows, and the machine's own
    scaling at the same counts (``machine_ceiling``: :func:`vlref.bench.ceiling.bench_ceiling`)."""
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
    return {"numba_num_threads": limit, "threads": runs, "skipped": skipped, "machine_ceiling": bench_ceiling(cfg),
            "note": (f"thread counts {skipped} skipped: above NUMBA_NUM_THREADS = {limit}" if skipped else "")}
