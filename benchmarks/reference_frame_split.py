"""Where the reference's frame goes: each step of :func:`vlref.render.prepare_frame` and of
:func:`vlref.reference.prepare_reference` for the bench scene of ``mitsuba_ratio.py``, timed one by one in this
process (medians of ``--repeats`` after a warm-up), on ``--threads`` Numba threads (BENCHMARKS.md, "The reference at
Mitsuba's warm 1024 spp launch").

    python benchmarks/reference_frame_split.py --threads 16 [--width 80 --height 45]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mitsuba_ratio import bench_scene  # noqa: E402

from vlref.camera import camera_from_settings  # noqa: E402
from vlref.geometry import build_geometry, raycast  # noqa: E402
from vlref.lights.pack import pack_lights  # noqa: E402
from vlref.lights.shading import scene_colour  # noqa: E402
from vlref.reference import integrand, prepare_reference, render_reference  # noqa: E402
from vlref.render import prepare_frame  # noqa: E402
from vlref.scene.animation import scene_at  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, default=numba.get_num_threads())
    ap.add_argument("--width", type=int, default=80)
    ap.add_argument("--height", type=int, default=45)
    ap.add_argument("--repeats", type=int, default=40)
    args = ap.parse_args()
    numba.set_num_threads(args.threads)
    scene = bench_scene(args.width, args.height)
    render_reference(scene, rel_tol=1.0, shadow_samples=1, rule=3)
    steps: dict[str, list[float]] = {}

    def timed(name, fn, *a):
        start = time.perf_counter()
        out = fn(*a)
        steps.setdefault(name, []).append(time.perf_counter() - start)
        return out

    for _ in range(args.repeats):
        s = timed("scene_at", scene_at, scene)
        cam = timed("camera", camera_from_settings, s.camera, s.render.width, s.render.height)
        geo = timed("build_geometry", build_geometry, s)
        timed("ray_directions", cam.ray_directions)
        gb = timed("raycast", raycast, s, cam, geo)
        lights = timed("pack_lights", pack_lights, s)
        timed("scene_colour", scene_colour, gb, s, geo, lights)
        frame = timed("prepare_frame (all of the above)", prepare_frame, scene)
        timed("build_context", integrand.build_context, frame.scene, frame)
        prepared = timed("prepare_reference (the frame and the rays' ends)", prepare_reference, scene)
        timed("render_reference 1/1/3, frame reused", render_reference, prepared, 1.0, 1e-9, None, 1, 4000, None, 3)
        timed("render_reference 1/1/3, whole call", render_reference, scene, 1.0, 1e-9, None, 1, 4000, None, 3)
    out = {name: float(np.median(v)) for name, v in steps.items()}
    print(json.dumps({"threads": args.threads, "width": args.width, "height": args.height, "median_s": out}))
    for name, v in out.items():
        print(f"{name:52s} {1e3 * v:8.3f} ms", file=sys.stderr)


if __name__ == "__main__":
    main()
