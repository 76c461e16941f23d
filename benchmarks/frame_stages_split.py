"""Where a fresh process's render of (b) at 1920x1080xSTEPS spends its stages: every call of the functions the
stages are made of, wrapped with a timer (wall and process CPU, all threads; the first call of a kernel includes its
load from the Numba cache). BENCHMARKS.md, "The stages around the kernels".

    PYTHONPATH=$PWD python3 benchmarks/frame_stages_split.py [STEPS]
"""

import functools
import sys
import time

from vlref.bench import bench_scene
from vlref.camera import Camera
from vlref.cli.commands import command
from vlref.render import render

WRAPPED = {"vlref.geometry.raycast": ("_raycast_kernel", "per_object"), "vlref.lights.shading": ("_shade",),
           "vlref.lights.shadow_cast": ("_cast_face",),
           "vlref.techniques.physical": ("march_physical", "sum_and_composite", "offsets")}


def timed(f, name, log):
    @functools.wraps(f)
    def call(*args, **kwargs):
        wall, cpu = time.perf_counter(), time.process_time()
        result = f(*args, **kwargs)
        log.append((name, time.perf_counter() - wall, time.process_time() - cpu))
        return result
    return call


def main(steps: int) -> None:
    command("render")  # the modules `vlref render` imports
    log = []
    for module, names in WRAPPED.items():
        for name in names:
            setattr(sys.modules[module], name, timed(getattr(sys.modules[module], name), name, log))
    Camera.ray_directions = timed(Camera.ray_directions, "ray_directions", log)
    start = time.perf_counter()
    result = render(bench_scene(1920, 1080, steps, "four", 1024))
    print(f"render {time.perf_counter() - start:.3f} s:", {k: round(v, 4) for k, v in result.timings.items()})
    calls = {}
    for name, wall, cpu in log:
        c = calls.setdefault(name, [0, 0.0, 0.0, wall])
        c[0], c[1], c[2] = c[0] + 1, c[1] + wall, c[2] + cpu
    for name, (n, wall, cpu, first) in calls.items():
        print(f"  {name:18s} calls {n:3d}  wall {wall:.4f}  cpu {cpu:.4f}  first call {first:.4f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 64)
