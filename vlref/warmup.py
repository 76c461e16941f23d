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

Without a warm-up, ``vlref render`` of the ``physical`` technique splits its compile over two
processes (:func:`march_ahead`): while the main process compiles the frame kernels (BVH build, ray
cast, shading, shadow maps), a second process compiles the march for the scene's types on a 1×1
frame that needs none of them (no objects, no shadow maps: the same array types, empty), and the
main process picks it up from the cache when it reaches the march (the frame reports its shadow maps
as built just before: ``Frame.tick``). The 1×1 frame keeps the lights' ``exact`` shadows, which choose
the march's variant with the shadow-ray tracer (:func:`vlref.march.physical.march_physical`). Cold, the
default scene renders in 23–24 s on the idle 2-core dev box of 2026-11-25 (37–43 s on the slower one of
2026-11-23, where the frame's kernels took about 38 s of compile, the longer half, and the march without
the ray tracer about 27 s; BENCHMARKS.md "Cold start", "Scheduling, borrowed records, a leaner compile" and
"Tiles, Estrin's `exp`, a tighter PCF loop").
"""

from __future__ import annotations

import contextlib
import dataclasses
import multiprocessing
import os
import time
from typing import Callable, Iterator

import numpy as np

from .camera import camera_from_settings
from .geometry import build_geometry
from .lights import pack_lights
from .lights.shadowmaps import build_shadow_maps
from .march.physical import march_physical
from .processes import host_cores, ignoring_sigint
from .reference import render_reference
from .render import prepare_frame, render
from .scene import load_scene
from .sequence import render_sequence
from .techniques import resolved
from .techniques.physical import march_buffers

__all__ = ["TASKS", "warmup", "march_ahead", "compile_march", "march_cached"]

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


def _spawn():
    """The spawn context (a fresh interpreter per process: no forked Numba thread pool; compiled code is
    shared via the cache)."""
    return multiprocessing.get_context("spawn")


def warmup(jobs: int | None = None, progress=None) -> dict[str, float]:
    """Run every task of :data:`TASKS` (``frame`` first, the rest on ``jobs`` processes, default: the
    available cores); ``progress(name)`` after each. Returns ``{task: seconds in its process}``."""
    if not jobs:
        jobs = host_cores()
    progress = progress or (lambda name: None)
    times = {}
    with ignoring_sigint():  # Ctrl-C reaches the workers too: the parent alone handles it (vlref.processes)
        pool = _spawn().Pool(max(1, min(jobs, len(TASKS) - 1)))
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


def _exact(light) -> bool:
    """Whether ``light`` has ``exact`` shadows (the march variant with the ray tracer)."""
    return light.shadows is not None and light.shadows.enabled and light.shadows.filter == "exact"


def _kernel_frame(scene):
    """The physical march's inputs for a 1×1 frame of ``scene`` built without any njit call: no objects
    (empty geometry arrays), no shadow maps (empty tables; ``exact`` shadows are kept, they need no map),
    the sky at every pixel. Every array has the dtype, rank and layout of the full frame's, so the march
    compiled for it serves the real frame."""
    def bare_light(light):  # exact shadows are kept: they need no map, and choose the kernel's variant
        return light if _exact(light) else dataclasses.replace(light, shadows=None)

    bare = scene.replace(render=dataclasses.replace(scene.render, width=1, height=1), objects=(),
                         lights=tuple(bare_light(light) for light in scene.lights))
    camera = camera_from_settings(bare.camera, 1, 1)
    geometry = build_geometry(bare)
    lights = pack_lights(bare)
    return bare, camera, lights, build_shadow_maps(bare, camera, geometry, lights), geometry.arrays


def compile_march(scene) -> None:
    """Compile (or load) the physical march for ``scene``'s types on its 1×1 kernel frame (module docstring)."""
    bare, camera, lights, maps, geo = _kernel_frame(scene)
    march_buffers(bare, camera, np.full((1, 1), np.inf), lights, maps, geo, resolved(scene, "steps"),
                  resolved(scene, "sampling"))


def march_cached(scene) -> bool:
    """Whether Numba's cache holds the physical march for ``scene``'s precision and shadow-ray variant (its
    index, read without compiling). False when the index cannot be read."""
    import numba

    dtype = np.float32 if scene.render.precision == "float32" else np.float64
    rays = any(_exact(light) for light in scene.lights)
    try:
        cache = march_physical._cache
        codegen = march_physical.targetctx.codegen()
        _, magic, code = cache._index_key((), codegen)
        want = numba.typeof(np.zeros(3, dtype=dtype))
        geo = 8  # march_physical's argument ``geo``: None for the variant without the ray tracer
        return any(key[1] == magic and key[2] == code and len(key[0]) > geo and key[0][0] == want
                   and (key[0][geo] != numba.types.none) == rays for key in cache._cache_file._load_index())
    except Exception:  # a Numba without these internals: assume cold
        return False


@contextlib.contextmanager
def march_ahead(scene) -> Iterator[Callable[[], None]]:
    """Compile the physical march of ``scene`` in a second process while the block runs; yields ``ready()``,
    which waits for it (call it before the march: :class:`vlref.render.Frame` ticks ``"shadow maps"`` just
    before). A no-op for other techniques, a cached kernel or one core. The process is terminated when the
    block exits early (an error, an interrupt)."""
    cores = host_cores()
    if scene.render.technique != "physical" or cores < 2 or march_cached(scene):
        yield lambda: None
        return
    with ignoring_sigint():
        proc = _spawn().Process(target=compile_march, args=(scene,), daemon=True)
        proc.start()
    try:
        yield proc.join
    finally:
        if proc.is_alive():
            proc.terminate()
        proc.join()
