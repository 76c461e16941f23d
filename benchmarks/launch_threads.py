"""The physical march's kernel launched from the calling thread, from a new thread per call, and from one thread kept
for every call (BENCHMARKS.md, "The launch thread kept"): with Numba's ``omp`` threading layer each thread that starts
a parallel kernel gets an OpenMP team of its own.

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc python3 benchmarks/launch_threads.py [LIGHTS [WIDTH HEIGHT [ROUNDS]]]

Bench scene (a) (``LIGHTS = one``) or (b) (``four``) at ``WIDTH x HEIGHT`` (1920x1080) on all threads; the frame, its
shadow maps and the kernel's inputs and outputs prepared once; each variant once to warm up, then ``ROUNDS`` (9)
rounds of the three in turn. Prints the threading layer and each variant's median in ms.
"""

import math
import statistics
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import numba
import numpy as np

from vlref.bench.config import FULL, bench_scene
from vlref.march.patterns import offsets
from vlref.march.physical import march_physical
from vlref.medium import pack_medium
from vlref.render import prepare_frame
from vlref.scene.technique_params import resolved


def kernel_call(lights: str, width: int, height: int):
    """A function that marches the prepared frame once, from whatever thread calls it."""
    scene = bench_scene(width, height, FULL.steps, lights, FULL.shadow_resolution)
    frame = prepare_frame(scene)
    maps = frame.shadow_maps()
    h, w = frame.gbuffer.distance.shape
    steps = resolved(scene, "steps")
    packed = frame.lights.astype(np.float64)
    args = (np.asarray(frame.camera.position, float), frame.camera.ray_directions(w, h, copy=False),
            np.minimum(frame.gbuffer.distance, scene.render.max_distance),
            offsets(resolved(scene, "sampling"), w, h, scene.render.seed), int(steps), pack_medium(scene, np.float64),
            packed, maps.table, None, bool(scene.techniques.physical.light_extinction),
            int(math.ceil(math.sqrt(steps))), np.empty((packed.count, h, w, 3)), np.empty((h, w)),
            (np.int64(0), np.int64(h)))
    return lambda: march_physical(*args, np.zeros(1, dtype=np.int64))


def main(lights: str = "one", width: int = 1920, height: int = 1080, rounds: int = 9) -> None:
    march = kernel_call(lights, width, height)
    threads = numba.get_num_threads()

    def with_threads():
        numba.set_num_threads(threads)
        march()

    def new_thread():
        thread = threading.Thread(target=with_threads)
        thread.start()
        thread.join()

    kept = ThreadPoolExecutor(max_workers=1)
    variants = {"calling thread": march, "new thread": new_thread,
                "kept thread": lambda: kept.submit(with_threads).result()}
    times = {name: [] for name in variants}
    for fn in variants.values():
        fn()
    for _ in range(rounds):
        for name, fn in variants.items():
            start = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - start)
    print(lights, width, height, numba.threading_layer(),
          ", ".join(f"{name} {1e3 * statistics.median(t):.2f} ms" for name, t in times.items()), flush=True)
    kept.shutdown()


if __name__ == "__main__":
    a = sys.argv[1:]
    main(a[0] if a else "one", *(int(x) for x in a[1:4]))
