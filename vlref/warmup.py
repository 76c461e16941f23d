"""``vlref warmup``: compile every kernel once into Numba's cache, so that later commands start at once.

Numba compiles a kernel on its first call and keeps the machine code in its cache (``cache=True``:
``__pycache__`` beside the sources, or ``$NUMBA_CACHE_DIR``); a process that finds it there loads it in
milliseconds. The first render after an install therefore pays for compiling the kernels it uses.
``vlref warmup`` pays that once, for every kernel, by rendering a tiny frame of the default scene with
each technique and precision and solving a tiny reference:

1. ``frame``: geometry, BVH build, G-buffer ray cast, surface shading and shadow maps (every later
   task needs a frame, so this one runs first, alone);
2. then, in ``jobs`` worker processes at once (compiling is single-threaded, so a 2-core machine
   compiles two groups at a time): each technique's passes (``physical`` in float64 and float32) and
   the quadrature reference.

A task that finds its kernels cached only loads them: a second ``vlref warmup`` takes seconds.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import sys
import time

__all__ = ["TASKS", "warmup"]

TINY = ["render.width=16", "render.height=9", "render.steps=2"]
# name -> (what runs, overrides of the default scene at TINY size); see the module docstring
TASKS: dict[str, tuple[str, list[str]]] = {
    "frame": ("frame", []),
    "physical float64": ("render", ['render.technique="physical"']),
    "physical float32": ("render", ['render.technique="physical"', 'render.precision="float32"']),
    "killzone": ("render", ['render.technique="killzone"']),
    "slightlymad": ("render", ['render.technique="slightlymad"']),
    "urp": ("render", ['render.technique="urp"']),
    "radial": ("render", ['render.technique="radial"']),
    "reference": ("reference", ["render.width=4", "render.height=3"]),
}


def run_task(name: str) -> tuple[str, float]:
    """Compile (or load) the kernels of task ``name`` in this process; ``(name, seconds)``."""
    from .scene import load_scene

    start = time.perf_counter()
    what, overrides = TASKS[name]
    scene = load_scene(None, TINY + overrides)
    if what == "frame":
        from .render import prepare_frame
        prepare_frame(scene).shadow_maps()
    elif what == "reference":
        from .reference import render_reference
        render_reference(scene, rel_tol=1e-2, shadow_samples=8)
    else:
        from .render import render
        render(scene)
    return name, time.perf_counter() - start


def _ignore_signals() -> None:
    """Workers leave SIGINT/SIGTERM to the parent, which terminates them (no tracebacks from workers)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def warmup(jobs: int | None = None, progress=None) -> dict[str, float]:
    """Run every task of :data:`TASKS` (``frame`` first, the rest on ``jobs`` processes, default: the
    available cores); ``progress(name)`` after each. Returns ``{task: seconds in its process}``."""
    if not jobs:
        jobs = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    progress = progress or (lambda name: None)
    times = {}
    # spawn: a fresh interpreter per worker (no forked Numba thread pool), compiled code shared via the cache
    ctx = multiprocessing.get_context("spawn")
    with ctx.Pool(max(1, min(jobs, len(TASKS) - 1)), initializer=_ignore_signals) as pool:  # terminated on exit
        for name, seconds in pool.imap_unordered(run_task, ["frame"]):
            times[name] = seconds
            progress(name)
        for name, seconds in pool.imap_unordered(run_task, [t for t in TASKS if t != "frame"]):
            times[name] = seconds
            progress(name)
    return times


def cache_location() -> str:
    """Where Numba keeps the compiled kernels: ``$NUMBA_CACHE_DIR`` or ``__pycache__`` beside the sources."""
    import numba
    return numba.config.CACHE_DIR or f"__pycache__ folders under {os.path.dirname(os.path.abspath(__file__))}"


def main_warmup(argv: list[str]) -> int:
    """``vlref warmup [--jobs N]``: compile every kernel with a progress bar; prints the time taken."""
    import argparse

    from tqdm import tqdm

    p = argparse.ArgumentParser(prog="vlref warmup", description="compile every kernel into Numba's cache "
                                "once (a later first render then starts at once); a second run only loads")
    p.add_argument("--jobs", type=int, help="worker processes (default: the available cores)")
    try:
        args = p.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    start = time.perf_counter()
    with tqdm(total=len(TASKS), desc="vlref warmup", unit="group", file=sys.stderr, leave=False) as bar:
        def done(name):
            bar.set_postfix_str(name, refresh=False)
            bar.update(1)
        warmup(args.jobs, done)
    print(f"vlref warmup: {len(TASKS)} kernel groups compiled or loaded in {time.perf_counter() - start:.1f} s "
          f"(cache: {cache_location()})", file=sys.stderr)
    return 0
