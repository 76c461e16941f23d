"""Sections ``reference``, ``first_render`` and ``memory``: whole renders, the last two in fresh interpreters."""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numba

from ..reference import render_reference
from ..render import render
from .config import BenchConfig, bench_scene

__all__ = ["bench_reference", "bench_first_render", "bench_memory", "bench_whole_render"]


def bench_reference(cfg: BenchConfig) -> dict:
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


def _child_env(cache_dir: str | None) -> dict:
    """The environment of a fresh interpreter: this one's, with this vlref first on the path and
    ``NUMBA_CACHE_DIR`` = ``cache_dir`` (None: this process's setting)."""
    env = dict(os.environ)
    if cache_dir is not None:
        env["NUMBA_CACHE_DIR"] = cache_dir
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(Path(__file__).resolve().parents[2]),
                                                    env.get("PYTHONPATH")) if p)
    return env


def _child(cache_dir: str | None, w: int, h: int, steps: int, lights: str, res: int) -> dict:
    """Run a fresh interpreter that renders the benchmark scene; its report plus the process wall time.

    ``cache_dir``: the child's ``NUMBA_CACHE_DIR`` (None: this process's setting).
    """
    env = _child_env(cache_dir)
    code = _CHILD.format(w=w, h=h, steps=steps, lights=lights, res=res)
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - start
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    report["process_s"] = wall
    return report


_WHOLE = """
import gc, json, pickle, sys, tempfile, time
t0, m0 = time.perf_counter(), time.monotonic()
from vlref.cli.commands import exit_at_once, program_command
render_to_folder = program_command("render").render_to_folder  # what `vlref render` imports, as it imports it
t1 = time.perf_counter()
with open(sys.argv[1], "rb") as fh:
    scene = pickle.load(fh)
with tempfile.TemporaryDirectory() as folder:
    result, _, write_s, _ = render_to_folder(scene, folder + "/out")
t2, m2 = time.perf_counter(), time.monotonic()
gc.freeze()
print(json.dumps({"import_s": t1 - t0, "stages": result.timings, "write_s": write_s, "in_process_s": t2 - t0,
                  "started": m0, "ended": m2}))
exit_at_once(0)  # as the vlref program ends a render (vlref.cli.commands.EXIT_AT_ONCE)
"""
"""The child of :func:`_whole`: it imports what ``vlref render`` imports (the scene comes pickled, so the
benchmark's own modules stay out of the import time) and ends as ``vlref render`` ends."""


def _whole(cache_dir: str | None, w: int, h: int, steps: int, lights: str, res: int) -> dict:
    """A fresh interpreter renders the benchmark scene as ``vlref render`` does (``_WHOLE``); its report, the
    process wall time and its split: the interpreter's start (from the process's launch to the child's first
    statement: Python's own start-up and its ``site`` imports), vlref's import, each render stage, the writing,
    the exit (from the child's last timing to the process's end), read on the system-wide monotonic clock
    (``time.monotonic``) both processes share. ``cache_dir``: the child's ``NUMBA_CACHE_DIR`` (None: this
    process's setting)."""
    env = _child_env(cache_dir)
    with tempfile.TemporaryDirectory(prefix="vlref_bench_scene_") as folder:
        scene_file = Path(folder) / "scene.pickle"
        scene_file.write_bytes(pickle.dumps(bench_scene(w, h, steps, lights, res)))
        start, launched = time.perf_counter(), time.monotonic()
        proc = subprocess.run([sys.executable, "-c", _WHOLE, str(scene_file)], env=env, capture_output=True,
                              text=True, check=True)
        report = json.loads(proc.stdout.strip().splitlines()[-1])
        report["process_s"], finished = time.perf_counter() - start, time.monotonic()
    report["render_s"] = sum(report["stages"].values())
    report["split"] = {"interpreter_start": report["started"] - launched, "import": report["import_s"],
                       **report["stages"], "write": report["write_s"], "exit": finished - report["ended"]}
    return report


def bench_whole_render(cfg: BenchConfig) -> dict:
    """``vlref render`` of (b) at ``cfg.width x cfg.height`` in a fresh process with this process's (warm) Numba
    cache, as the command does it (:func:`vlref.cli.render.render_to_folder`: render, preview exposure, EXR
    buffers and PNG into a folder): process wall time and its split (interpreter start and imports, each
    render stage, writing, exit)."""
    runs = [_whole(None, cfg.width, cfg.height, cfg.steps, "four", cfg.shadow_resolution)
            for _ in range(max(1, cfg.repeats))]
    best = sorted(runs, key=lambda r: r["process_s"])[len(runs) // 2]
    return {"width": cfg.width, "height": cfg.height, "steps": cfg.steps, "lights": 4, "seconds": best["process_s"],
            "split": best["split"], "what": "fresh process, warm cache: render (b) and write its default outputs"}


def bench_first_render(cfg: BenchConfig) -> dict:
    """A fresh process renders (a) and writes its outputs as ``vlref render`` does (its compile spread over
    processes: :func:`vlref.ahead.compile_ahead`): with a fresh cache, then with the cache it filled
    (``cold_cache``), else only with this process's cache (warm; ``cold`` is then None)."""
    w, h = cfg.first_render
    if not cfg.cold_cache:
        warm = _whole(None, w, h, cfg.steps, "one", cfg.shadow_resolution)
        return {"width": w, "height": h, "cold": None, "warm": warm, "note": "cold run skipped (--quick)"}
    with tempfile.TemporaryDirectory(prefix="vlref_bench_cache_") as cache:
        cold = _whole(cache, w, h, cfg.steps, "one", cfg.shadow_resolution)
        warm = _whole(cache, w, h, cfg.steps, "one", cfg.shadow_resolution)
    return {"width": w, "height": h, "cold": cold, "warm": warm, "note": ""}


def bench_memory(cfg: BenchConfig) -> dict:
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
