"""Where a camera ray's and a shadow-map texel's nanoseconds go (BENCHMARKS.md, "Whole frame"): CPU time per ray
of each part of the cast on the bench scene (b), one thread or all, so that shared machines give usable numbers.

    NUMBA_NUM_THREADS=1 PYTHONPATH=$PWD python3 benchmarks/ray_profile.py [WIDTH HEIGHT SHADOW_RES]

Rows: the whole ``raycast`` (buffers allocated, as the bench measures it), its kernel on buffers allocated once,
``closest_hits`` alone (no G-buffer writes; rows split by ``prange``, so uneven across threads), then
``build_shadow_maps`` per texel. Wall and CPU time (``time.process_time``, all threads summed) per ray, medians of 5.
(Timing the parts of a closest hit each in a kernel of its own gave numbers that do not add up to the whole: the
inlined query is not the sum of its parts. The attribution in BENCHMARKS.md comes from variants of the code.)
"""

import sys
import time

import numba
import numpy as np
from numba import njit, prange

from vlref.bench.config import bench_scene
from vlref.camera import camera_from_settings
from vlref.geometry import build_geometry, closest_hits, raycast, traversal_stack
from vlref.geometry.raycast import GBuffer, _cast_rows, _raycast_kernel, kernel_args
from vlref.lights import pack_lights
from vlref.lights.shadow_cast import build_shadow_maps
from vlref.parallel import COUNTER, work


@njit(cache=True, parallel=True)
def _hits_only(geo, origin, dirs, tmax):
    h, w = dirs.shape[0], dirs.shape[1]
    out = np.zeros(h)
    for y in prange(h):
        origins = np.empty((w, 3))
        for x in range(w):
            origins[x, 0], origins[x, 1], origins[x, 2] = origin[0], origin[1], origin[2]
        t, obj, normal = np.empty(w), np.empty(w, dtype=np.int64), np.empty((w, 3))
        closest_hits(geo, origins, dirs[y], tmax[y], True, traversal_stack(), t, obj, normal)
        out[y] = t[0]
    return out


def timed(fn, runs=5):
    fn()
    walls, cpus = [], []
    for _ in range(runs):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return float(np.median(walls)), float(np.median(cpus))


def main(width=480, height=270, res=512):
    scene = bench_scene(width, height, 16, "four", res)
    camera = camera_from_settings(scene.camera, width, height)
    geometry = build_geometry(scene)
    geo = geometry.arrays
    dirs = np.ascontiguousarray(camera.ray_directions(copy=False))
    cos_f = dirs @ camera.forward
    tmax = camera.far / cos_f
    origin = np.ascontiguousarray(camera.position, dtype=np.float64)
    n = width * height
    buf = GBuffer(depth=np.empty((height, width)), distance=np.empty((height, width)),
                  normal=np.zeros((height, width, 3)), object_id=np.empty((height, width), dtype=np.int32),
                  origin=origin, directions=dirs, object_albedo=geo.albedo, object_emission=geo.emission)
    args = kernel_args(geo, camera, buf)
    rows = {
        "raycast (buffers allocated)": lambda: raycast(scene, camera, geometry),
        "raycast kernel (buffers reused)": lambda: _raycast_kernel(*args, work(_cast_rows, COUNTER, *args), numba.get_num_threads()),
        "closest_hits only": lambda: _hits_only(geo, origin, dirs, tmax),
    }
    print(f"bench scene (b) {width}x{height}, {n} rays; ns per ray: wall / CPU")
    for name, fn in rows.items():
        wall, cpu = timed(fn)
        print(f"{name:34s} {wall / n * 1e9:8.1f} {cpu / n * 1e9:8.1f}")
    packed = pack_lights(scene)
    texels = build_shadow_maps(scene, camera, geometry, packed).data.size
    wall, cpu = timed(lambda: build_shadow_maps(scene, camera, geometry, packed))
    name = "build_shadow_maps per texel"
    print(f"{name:34s} {wall / texels * 1e9:8.1f} {cpu / texels * 1e9:8.1f}  ({texels} texels)")


if __name__ == "__main__":
    main(*map(int, sys.argv[1:]))
