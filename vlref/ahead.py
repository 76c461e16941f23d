"""A cold ``vlref render``'s later stages compiled ahead in second processes (:func:`compile_ahead`).

Without a warm-up (:mod:`vlref.warmup`), ``vlref render`` spreads its compile over processes: while the
main process compiles the BVH build, second processes compile, each for the scene's types, the kernels of a
later stage on a 1×1 frame that needs no earlier stage's kernel (no objects, no shadow maps but the stage's
own, a G-buffer of sky: the same array types, empty): the march, the shadow maps, the ray cast, the surface
shading, in that order of priority, one process per core beyond the first (on two cores the march alone: with the
shadow maps too, that process became the longer one, BENCHMARKS.md "Cold first render on two cores"). The main
process picks each up from the cache when it reaches that stage (:class:`vlref.render.Frame` ticks each stage as it
ends; the next one waits for its process). The composite of the march's buffers (:func:`compile_composite`) is
compiled by whichever of the main process and the march's process gets to it first: the march's process after the
march, the main process when it reaches the march while that process still runs (a lock, taken once), so neither
waits for the other's share (BENCHMARKS.md "The ray cast's launcher takes the geometry once"). The 1×1 frame
keeps the lights' ``exact`` shadows, which choose the march's variant with the shadow-ray tracer
(:func:`vlref.march.physical.march_physical`). Cold, the
default scene rendered in 23–24 s on the idle 2-core dev box of 2026-11-25 with the march alone ahead (37–43 s
on the slower one of 2026-11-23, where the frame's kernels took about 38 s of compile, the longer half, and
the march without the ray tracer about 27 s; BENCHMARKS.md "Cold start", "Scheduling, borrowed records, a
leaner compile", "Tiles, Estrin's `exp`, a tighter PCF loop" and "The frame around the kernels").

A warm render's later stages are **loaded ahead on a thread** instead: Numba's load of a cached kernel is part
Python (the index, unpickling, under the GIL) and part LLVM (adding its object code; in other processes than the
render program's also parsing the library's bitcode and scanning its symbols, :mod:`vlref.jit_init` "Loaded libraries
linked on demand": llvmlite's calls release the GIL), so
a thread that loads the BVH build, the ray cast's, the shading's, the shadow maps' and the march's functions in the
order the render calls them (:data:`LOADED_AHEAD`) overlaps the LLVM parts with the main thread's own work (the
camera's rays on threads, the NumPy set-up of each stage); the main thread's call of a function being loaded waits
for the load under Numba's compiler lock, as it would for its own load. Only a signature the cache holds alone is
loaded (for the march's kernel: the one of the scene's precision and shadow-ray variant): a load ahead never adds
work the render would not do.

It imports only what a render imports anyway: ``vlref render`` imports it, and not :mod:`vlref.warmup`, which
also imports the quadrature reference.
"""

from __future__ import annotations

import contextlib
import dataclasses
import multiprocessing
import threading
from typing import Callable, Iterator

import numba
import numpy as np

from .camera import camera_from_settings
from .geometry import GBuffer, build_geometry, raycast
from .geometry.bvh import _build
from .geometry.raycast import _cast_rows, _raycast_kernel
from .geometry.scene_geometry import builds_trees
from .jit_init import initialise_numba
from .lights import pack_lights
from .lights.shading import _shade, _shade_rows, scene_colour
from .lights.shadow_cast import _cast_chunks, _cast_face, build_shadow_maps
from .march.physical import _march_kernel, _march_tasks
from .post.composite import _sum_composite, sum_and_composite
from .processes import declare_own_kernels_only, host_cores, ignoring_sigint
from .techniques import resolved
from .techniques.physical import march_buffers

__all__ = ["compile_ahead", "compile_stage", "compile_composite", "stage_cached", "AHEAD", "spawn_context"]


def spawn_context():
    """The spawn context (a fresh interpreter per process: no forked Numba thread pool; compiled code is
    shared via the cache)."""
    return multiprocessing.get_context("spawn")


def _exact(light) -> bool:
    """Whether ``light`` has ``exact`` shadows (the march variant with the ray tracer)."""
    return light.shadows is not None and light.shadows.enabled and light.shadows.filter == "exact"


def _mapped(light) -> bool:
    """Whether ``light`` has shadow maps (enabled shadows other than ``exact``)."""
    return light.shadows is not None and light.shadows.enabled and light.shadows.filter != "exact"


def _bare(scene, maps: bool = False):
    """``scene`` at 1×1 with no objects; its lights keep ``exact`` shadows (they need no map, and choose the
    march's variant) and, with ``maps``, their shadow maps at the smallest size (8 texels a side); the others
    lose theirs."""
    def bare_light(light):
        if maps and _mapped(light):
            return dataclasses.replace(light, shadows=dataclasses.replace(light.shadows, resolution=8))
        return light if _exact(light) else dataclasses.replace(light, shadows=None)

    return scene.replace(render=dataclasses.replace(scene.render, width=1, height=1), objects=(),
                         lights=tuple(bare_light(light) for light in scene.lights))


def _sky_gbuffer() -> GBuffer:
    """A 1×1 G-buffer that sees the sky, built without the ray cast's kernel (the arrays it allocates)."""
    return GBuffer(depth=np.full((1, 1), np.inf), distance=np.full((1, 1), np.inf), normal=np.zeros((1, 1, 3)),
                   object_id=np.full((1, 1), -1, dtype=np.int32), origin=np.zeros(3), directions=np.zeros((1, 1, 3)),
                   object_albedo=np.zeros((0, 3)), object_emission=np.zeros((0, 3)))


def compile_stage(stage: str, scene) -> None:
    """Compile (or load) the kernels of ``stage`` (a key of :data:`AHEAD`) for ``scene``'s types on a 1×1 frame
    built without any other stage's kernel: no objects (empty geometry arrays, no BVH build), a G-buffer of sky,
    shadow maps only where the stage builds them (module docstring). Every array has the dtype, rank and
    layout of the full frame's, so the kernel compiled for it serves the real frame."""
    bare = _bare(scene, maps=stage == "shadow maps")
    camera = camera_from_settings(bare.camera, 1, 1)
    geometry = build_geometry(bare)
    lights = pack_lights(bare)
    if stage == "raycast":
        raycast(bare, camera, geometry)
    elif stage == "shading":
        scene_colour(_sky_gbuffer(), bare, geometry, lights)
    elif stage == "shadow maps":
        build_shadow_maps(bare, camera, geometry, lights)
    else:  # the march (its buffers' composite: compile_composite)
        maps = build_shadow_maps(bare, camera, geometry, lights)
        march_buffers(bare, camera, np.full((1, 1), np.inf), lights, maps, geometry.arrays, resolved(scene, "steps"),
                      resolved(scene, "sampling"))


def compile_composite(scene) -> None:
    """Compile (or load) what the physical technique does with the march's buffers, :func:`sum_and_composite`, for
    ``scene``'s types on 1×1 arrays: the buffers (one per light, as :func:`~vlref.lights.pack_lights` packs them;
    none, no kernel) and the transmittance in the march's precision, the scene colour in float64."""
    dtype = np.float32 if scene.render.precision == "float32" else np.float64
    sum_and_composite(np.zeros((len(scene.lights), 1, 1, 3), dtype), np.zeros((1, 1, 3)), np.ones((1, 1), dtype))


def _compile_composite_unless_claimed(claim, scene) -> None:
    """:func:`compile_composite` of ``scene`` where this process takes ``claim`` first (a lock of
    :func:`compile_ahead`'s, taken once and never released: the main process or the march's, whichever comes first,
    compiles the composite); nothing where ``claim`` is None or taken."""
    if claim is not None and claim.acquire(False):  # without blocking
        compile_composite(scene)


def _compile_stage_process(stage: str, scene, composite_claim=None) -> None:
    """What a process of :func:`compile_ahead` runs: :func:`compile_stage`, in a process that runs vlref's kernels
    alone (:func:`vlref.processes.declare_own_kernels_only`), with Numba initialised first as ``vlref render``'s own
    process initialises it (:func:`vlref.jit_init.initialise_numba`: without ``scipy.linalg``, cffi and the extension
    scan; on the dev box its first compile began 0.31 s after its frame was set up, 0.12 + 0.04 s with it). That
    process starts behind the main one (its interpreter, its imports), and the main process waits for it. With
    ``composite_claim`` (the march's process), then the composite of the march's buffers, unless the main process
    claimed it first (:func:`_compile_composite_unless_claimed`)."""
    declare_own_kernels_only()
    initialise_numba(compiling=True)
    compile_stage(stage, scene)
    _compile_composite_unless_claimed(composite_claim, scene)


def _march_wanted(dtype, rays: bool):
    """The march's cache entries for ``dtype`` and the shadow-ray variant (``rays``): its argument ``geo`` is
    None without the ray tracer."""
    want = numba.typeof(np.zeros(3, dtype=dtype))
    geo = 8  # _march_kernel's argument ``geo``
    return lambda sig: len(sig) > geo and sig[0] == want and (sig[geo] != numba.types.none) == rays


AHEAD: dict[str, tuple[str, object]] = {
    # stage -> (the render tick after which the main process calls its kernel, its kernel); in order of priority
    "march": ("shadow maps", _march_kernel),
    "shadow maps": ("shading", _cast_face),
    "raycast": ("geometry", _raycast_kernel),
    "shading": ("raycast", _shade),
}
"""The stages :func:`compile_ahead` may compile in second processes (the BVH build, first, stays in the main
one); the kernel of each is the one whose cache entry says the stage is compiled."""


def _cached_signatures(kernel, wanted=lambda sig: True) -> list:
    """The signatures ``wanted(sig)`` accepts for which Numba's cache holds ``kernel`` for its current source (its
    index, read without compiling); none when the index cannot be read."""
    try:
        cache = kernel._cache
        _, magic, code = cache._index_key((), kernel.targetctx.codegen())
        return [key[0] for key in cache._cache_file._load_index()
                if key[1] == magic and key[2] == code and wanted(key[0])]
    except Exception:  # a Numba without these internals: assume cold
        return []


def _kernel_cached(kernel, wanted=lambda sig: True) -> bool:
    """Whether Numba's cache holds ``kernel`` for its current source with a signature ``wanted(sig)`` accepts."""
    return bool(_cached_signatures(kernel, wanted))


def stage_cached(stage: str, scene) -> bool:
    """Whether Numba's cache holds the kernel of ``stage`` (for the march: for ``scene``'s precision and
    shadow-ray variant)."""
    if stage == "march":
        dtype = np.float32 if scene.render.precision == "float32" else np.float64
        return _kernel_cached(_march_kernel, _march_wanted(dtype, any(_exact(light) for light in scene.lights)))
    return _kernel_cached(AHEAD[stage][1])


def _stages_used(scene) -> dict[str, bool]:
    """Which stages of :data:`AHEAD` and :data:`LOADED_AHEAD` a render of ``scene`` runs with their kernels."""
    return {"geometry": builds_trees(scene), "march": scene.render.technique == "physical",
            "shadow maps": any(_mapped(light) for light in scene.lights), "raycast": True, "shading": True}


def _stages_ahead(scene) -> list[str]:
    """The stages of a render of ``scene`` worth a second process: used by the render, not cached, one per
    core beyond the first, in the order of :data:`AHEAD`."""
    used = _stages_used(scene)
    return [stage for stage in AHEAD if used[stage] and not stage_cached(stage, scene)][:host_cores() - 1]


LOADED_AHEAD: dict[str, tuple] = {
    # stage -> the compiled functions it calls that Numba loads from its cache, in the order the render calls them
    "geometry": (_build,),
    "raycast": (_cast_rows, _raycast_kernel),
    "shading": (_shade_rows, _shade),
    "shadow maps": (_cast_chunks, _cast_face),
    "march": (_march_tasks, _march_kernel, _sum_composite),
}
"""What :func:`compile_ahead` loads on a thread where the stage is cached: the kernel of :data:`AHEAD` with the
functions it calls by address (:func:`vlref.parallel.work`), and for the march the composite of its buffers. First of
all the BVH build, the main thread's first kernel (no second process compiles it): the render calls it at once, while
the thread still initialises Numba, and where the thread took the compiler lock first, the main thread's own load
waited for the thread's next load as well; loaded first by the thread, it is there when the main thread gets the
lock."""


def _to_load_ahead(scene, cold: list[str]) -> list[tuple]:
    """``(function, signature)`` of :data:`LOADED_AHEAD` for the stages of ``scene``'s render that are cached (not in
    ``cold``), where the cache holds one signature for the function's current source (for the march's kernel: one
    of ``scene``'s precision and shadow-ray variant); where it holds several, the render loads the one it calls."""
    dtype = np.float32 if scene.render.precision == "float32" else np.float64
    march = _march_wanted(dtype, any(_exact(light) for light in scene.lights))
    used = _stages_used(scene)
    out = []
    for stage, functions in LOADED_AHEAD.items():
        if used[stage] and stage not in cold:
            for function in functions:
                sigs = _cached_signatures(function, march if function is _march_kernel else lambda sig: True)
                if len(sigs) == 1:
                    out.append((function, sigs[0]))
    return out


def _load(functions: list[tuple]) -> None:
    """Load each ``(function, signature)`` from Numba's cache, in order, after Numba's initialisation
    (:func:`vlref.jit_init.initialise_numba`); where an entry cannot be loaded after all, Numba compiles it here, as
    the render's call would have; an error stops the thread (the render then meets it in its own call)."""
    initialise_numba()
    for function, sig in functions:
        try:
            function.compile(sig)
        except Exception:
            return


@contextlib.contextmanager
def compile_ahead(scene) -> Iterator[Callable[[str], None]]:
    """Compile the cold kernels of ``scene``'s later stages in second processes while the block runs, and load the
    cached ones on a thread (module docstring); yields ``ready(tick)``, to be called with each render tick: it
    waits for the process compiling the stage that comes next (for the march's, while it still runs, it compiles
    the composite of the march's buffers unless that process has claimed it). A no-op on one core. The processes
    are terminated when the block exits early (an error, an interrupt); the thread ends with its current load."""
    procs = {}
    cold = _stages_ahead(scene)
    claim = spawn_context().Lock() if "march" in cold else None  # the composite's: module docstring
    with ignoring_sigint():  # Ctrl-C reaches the workers too: the parent alone handles it (vlref.processes)
        for stage in cold:
            args = (stage, scene, claim if stage == "march" else None)
            procs[AHEAD[stage][0]] = spawn_context().Process(target=_compile_stage_process, args=args, daemon=True)
            procs[AHEAD[stage][0]].start()
    loading = None
    if host_cores() > 1:
        loading = threading.Thread(target=_load, args=(_to_load_ahead(scene, cold),), name="vlref-load-ahead",
                                   daemon=True)
        loading.start()

    def ready(tick: str) -> None:
        if tick in procs:
            if tick == AHEAD["march"][0] and procs[tick].is_alive():
                _compile_composite_unless_claimed(claim, scene)
            procs[tick].join()

    try:
        yield ready
    finally:
        if loading is not None:
            loading.join()
        for proc in procs.values():
            if proc.is_alive():
                proc.terminate()
            proc.join()
