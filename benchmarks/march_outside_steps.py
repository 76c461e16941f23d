"""The march's cost outside its steps (BENCHMARKS.md, "The march outside its steps"), bench scene (a) at WIDTH x
HEIGHT (default 1920x1080) on every core, this tree on PYTHONPATH:

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc python3 benchmarks/march_outside_steps.py fit [STEPS ...]
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc python3 benchmarks/march_outside_steps.py outputs [STEPS]

``fit``: :func:`~vlref.techniques.physical.march_buffers` at each step count (default 64 16 1; medians of 7) and the
line through them: its intercept is the work per frame that does not grow with the steps (segments, set-up, view
transmittances, outputs). ``outputs``: at STEPS (default 1), alternated, medians of 9: ``march_buffers``; its kernel
on outputs already mapped (the same arrays every call); the kernel on new outputs (``np.empty`` every call); a
parallel fill of new arrays of the outputs' size (what mapping them costs when the threads take a stretch each).
One line per run on stdout.
"""

import os
import statistics
import sys
import time

import numpy as np
from numba import njit, prange

from vlref.bench.config import FULL, bench_scene, median_time
from vlref.march.patterns import offsets
from vlref.march.physical import march_physical
from vlref.medium import pack_medium
from vlref.render import prepare_frame
from vlref.scene.technique_params import resolved
from vlref.techniques import physical

W, H = int(os.environ.get("WIDTH", 1920)), int(os.environ.get("HEIGHT", 1080))


def _frame(steps: int):
    scene = bench_scene(W, H, steps, "one", FULL.shadow_resolution)
    frame = prepare_frame(scene)
    maps = frame.shadow_maps()
    return scene, frame, maps, lambda: physical.march_buffers(scene, frame.camera, frame.gbuffer.distance,
                                                              frame.lights, maps, frame.geometry.arrays, steps,
                                                              resolved(scene, "sampling"))


def fit(step_counts: list[int]) -> None:
    seconds = {}
    for steps in step_counts:
        seconds[steps] = median_time(_frame(steps)[3], 7)
    slope, intercept = np.polyfit(list(seconds), list(seconds.values()), 1)
    print(" ".join(f"{k} steps {v * 1e3:.2f} ms" for k, v in seconds.items()),
          f"| per frame {intercept * 1e3:.2f} ms, per step {slope * 1e3:.3f} ms", flush=True)


@njit(cache=True, parallel=True)
def _fill(flat_a, flat_b):
    for i in prange(flat_a.size // 4096):
        flat_a[i * 4096:(i + 1) * 4096] = 0.0
    for i in prange(flat_b.size // 4096):
        flat_b[i * 4096:(i + 1) * 4096] = 0.0


def outputs(steps: int) -> None:
    scene, frame, maps, march = _frame(steps)
    cam = frame.camera
    dirs = cam.ray_directions(W, H, copy=False)
    t_end = np.minimum(frame.gbuffer.distance, scene.render.max_distance)
    beta = offsets(resolved(scene, "sampling"), W, H, scene.render.seed)
    medium, lights = pack_medium(scene, np.float64), frame.lights.astype(np.float64)
    kept = np.empty((1, H, W, 3)), np.empty((H, W))
    position = np.asarray(cam.position, dtype=np.float64)

    def kernel(per_light, trans):
        march_physical(position, dirs, t_end, beta, steps, medium, lights, maps.table, None, True, 8, per_light, trans,
                       (np.int64(0), np.int64(H)))

    parts = {"march_buffers": march, "kernel, outputs mapped": lambda: kernel(*kept),
             "kernel, new outputs": lambda: kernel(np.empty((1, H, W, 3)), np.empty((H, W))),
             "parallel fill of new outputs": lambda: _fill(np.empty(H * W * 3), np.empty(H * W))}
    runs = {name: [] for name in parts}
    for fn in parts.values():
        fn()
    for _ in range(9):
        for name, fn in parts.items():
            start = time.perf_counter()
            fn()
            runs[name].append(time.perf_counter() - start)
    print(f"{steps} steps:", " | ".join(f"{k} {statistics.median(v) * 1e3:.2f} ms" for k, v in runs.items()),
          flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "fit":
        fit([int(s) for s in sys.argv[2:]] or [64, 16, 1])
    else:
        outputs(int(sys.argv[2]) if len(sys.argv) > 2 else 1)
