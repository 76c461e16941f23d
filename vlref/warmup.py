"""``vlref warmup``: compile every kernel once into Numba's cache, so that later commands start at once.

Numba compiles a kernel on its first call and keeps the machine code in its cache (``cache=True``:
``__pycache__`` beside the sources, or ``$NUMBA_CACHE_DIR``); a process that finds it there loads it in
milliseconds. The first render after an install therefore pays for compiling the kernels it uses.
``vlref warmup`` pays that once, for every kernel, by rendering a tiny frame of the default scene with
each technique and precision (two frames of an animated scene for ``froxel``'s temporal pass) and
solving a tiny reference:

1. ``frame``: geometry, BVH build, G-buffer ray cast, surface shading and shadow maps (every later
   task needs a frame, so this one runs first, alone);
2. then, in ``jobs`` worker processes at once (compiling is single-threaded, so a 2-core machine
   compiles two groups at a time): each technique's passes (``physical`` in float64 and float32) and
   the quadrature reference.

A task that finds its kernels cached only loads them: a second ``vlref warmup`` takes seconds.

Without a warm-up, ``vlref render`` compiles a cold render's later stages ahead in second processes
(:mod:`vlref.ahead`).
"""

from __future__ import annotations

import os
import time

from .ahead import spawn_context
from .processes import host_cores, ignoring_sigint
from .reference import render_reference
from .render import prepare_frame, render
from .scene import load_scene
from .sequence import render_sequence

__all__ = ["TASKS", "warmup"]

TINY = ["render.width=16", "render.height=9", "render.steps=2"]
# name -> (what runs, bundled scene (None: the default), overrides at TINY size); see the module docstring
TASKS: dict[str, tuple[str, str | None, list[str]]] = {
    "frame": ("frame", None, []),
    "physical float64": ("render", None, ['render.technique="physical"']),
    "physical float32": ("render", None, ['render.technique="physical"', 'render.precision="float32"']),
    # the march with the shadow-ray tracer is a kernel of its own (vlref.march.physical.march_physical)
    "physical exact float64": ("render", None, ['render.technique="physical"', 'lights.0.shadows.filter="exact"']),
    "physical exact float32": ("render", None, ['render.technique="physical"', 'render.precision="float32"',
                                                'lights.0.shadows.filter="exact"']),
    "killzone": ("render", None, ['render.technique="killzone"']),
    "slightlymad": ("render", None, ['render.technique="slightlymad"']),
    "urp": ("render", "urp_sun", ['render.technique="urp"']),  # URP needs a directional main light
    "radial": ("render", None, ['render.technique="radial"']),
    # two frames of an animated scene, so the temporal reprojection compiles too (small grid: same types)
    "froxel": ("sequence", "anim_spot", ['render.technique="froxel"', "techniques.froxel.temporal=true",
                                         "techniques.froxel.grid_width=8", "techniques.froxel.grid_height=5",
                                         "techniques.froxel.slices=4"]),
    "reference": ("reference", None, ["render.width=4", "render.height=3"]),
}


def run_task(name: str) -> tuple[str, float]:
    """Compile (or load) the kernels of task ``name`` in this process; ``(name, seconds)``. A failure is
    raised as ``RuntimeError(message)`` (worker results must unpickle in the parent)."""
    start = time.perf_counter()
    what, scene_name, overrides = TASKS[name]
    try:
        scene = load_scene(scene_name, TINY + overrides)
        if what == "frame":
            prepare_frame(scene).shadow_maps()
        elif what == "sequence":
            for _ in render_sequence(scene, range(2)):
                pass
        elif what == "reference":
            render_reference(scene, rel_tol=1e-2, shadow_samples=8)
        else:
            render(scene)
    except Exception as exc:
        raise RuntimeError(f"warmup task {name!r}: {exc}") from None
    return name, time.perf_counter() - start


def warmup(jobs: int | None = None, progress=None) -> dict[str, float]:
    """Run every task of :data:`TASKS` (``frame`` first, the rest on ``jobs`` processes, default: the
    available cores); ``progress(name)`` after each. Returns ``{task: seconds in its process}``."""
    if not jobs:
        jobs = host_cores()
    progress = progress or (lambda name: None)
    times = {}
    with ignoring_sigint():  # Ctrl-C reaches the workers too: the parent alone handles it (vlref.processes)
        pool = spawn_context().Pool(max(1, min(jobs, len(TASKS) - 1)))
    with pool:  # terminated on exit, also on an interrupt
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
