"""The whole ``render_reference`` call of two trees on one machine (BENCHMARKS.md, "The reference's fixed costs: one
worker per thread, the frame without NumPy's generic paths").

Run it once per tree, each in a fresh process with that tree first on ``PYTHONPATH``, alternated (main, tree, tree,
main) so load drifts hit both:

    PYTHONPATH=TREE python benchmarks/reference_call_ab.py --tag tree --vlref 7e-1/1/3,1/1/3 [--hashes]

The bench scene of ``mitsuba_ratio.py`` at 80x45. Per setting ``rel_tol/shadow_samples/rule``, after one warm-up
call, ``--rounds`` rounds of ``--calls`` calls each: the whole call's wall time, its part before the quadrature
(``stats["frame_seconds"]``), the same call given :func:`~vlref.reference.prepare_reference`'s frame, and
:func:`vlref.render.prepare_frame` alone (medians over every round); the sha256 of the result's images (inscatter,
transmittance, final, error, shadow boundaries). ``--hashes``: also the sha256 of ``prepare_frame``'s camera, rays,
G-buffer, scene colour and lights for every bundled scene at 96x54.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from mitsuba_ratio import bench_scene, parse_settings  # noqa: E402  (this folder, whichever tree is on the path)

from vlref.reference import prepare_reference, render_reference  # noqa: E402
from vlref.render import prepare_frame  # noqa: E402
from vlref.scene import bundled_scenes, load_scene  # noqa: E402


def sha(*arrays) -> str:
    digest = hashlib.sha256()
    for a in arrays:
        digest.update(np.ascontiguousarray(a).tobytes())
    return digest.hexdigest()[:16]


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tag", default="")
    ap.add_argument("--vlref", default="7e-1/1/3", help="settings rel_tol/shadow_samples/rule, comma-separated")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--calls", type=int, default=20)
    ap.add_argument("--hashes", action="store_true")
    args = ap.parse_args()
    scene = bench_scene(80, 45)
    for rel_tol, samples, rule in parse_settings(args.vlref):
        kw = {"rel_tol": rel_tol, "shadow_samples": samples, "rule": rule}
        times = {"whole": [], "frame": [], "reused": [], "prepare_frame": []}
        render_reference(scene, **kw)
        for _ in range(args.rounds):
            for _ in range(args.calls):
                start = time.perf_counter()
                result = render_reference(scene, **kw)
                times["whole"].append(time.perf_counter() - start)
                times["frame"].append(result.stats["frame_seconds"])
            prepared = prepare_reference(scene)
            for _ in range(args.calls):
                times["reused"].append(timed(lambda: render_reference(prepared, **kw)))
                times["prepare_frame"].append(timed(lambda: prepare_frame(scene)))
        row = {"tag": args.tag, "setting": f"{rel_tol:g}/{samples}/{rule}", "threads": numba.get_num_threads(),
               "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY"), "calls": len(times["whole"]),
               "sha": sha(result.inscatter, result.transmittance, result.final, result.error,
                          result.stats["shadow_boundaries"])}
        row.update({f"{k}_median_ms": 1e3 * float(np.median(v)) for k, v in times.items()})
        print(json.dumps(row), flush=True)
    if args.hashes:
        frames = {}
        for name in sorted(bundled_scenes()):
            f = prepare_frame(load_scene(name, ["render.width=96", "render.height=54"]))
            g = f.gbuffer
            frames[name] = sha(f.camera.rotation, f.camera.position, f.camera.ray_directions(), g.depth, g.distance,
                               g.normal, g.object_id, f.scene_colour, *f.lights)
        print(json.dumps({"tag": args.tag, "frames": frames}), flush=True)


if __name__ == "__main__":
    main()
