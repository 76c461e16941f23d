"""``vlref reference`` of two trees on one machine: the bench scene of ``mitsuba_ratio.py`` at each setting, timed in
this process (BENCHMARKS.md, "The reference at Mitsuba's 1024 spp error: ...").

Run it once per tree, each in a fresh process with that tree first on ``PYTHONPATH``, alternated (main, tree, tree,
main) so load drifts hit both:

    PYTHONPATH=MAIN python benchmarks/reference_ab.py --tag main --vlref 1/1/7,1e-1/1/7
    PYTHONPATH=TREE python benchmarks/reference_ab.py --tag tree --vlref 1/1/7,1/1/3

Per setting ``rel_tol/shadow_samples/rule``: one warm-up call (it compiles or loads the kernels), then ``--repeats``
timed calls on every Numba thread (wall time, median and min; the part before the quadrature,
``stats["frame_seconds"]``), where the tree has :func:`~vlref.reference.prepare_reference` as many calls given the
scene's prepared frame (``reused_median_s``: the frame reused), and with ``--one-thread`` as many whole calls on one
thread (process CPU time, min), plus the sha256 of the inscatter image (the same setting in two trees: the same
bits or not).
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

import vlref.reference as reference  # noqa: E402
from vlref.reference import render_reference  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tag", default="")
    ap.add_argument("--vlref", default="1/1/7", help="settings rel_tol/shadow_samples/rule, comma-separated")
    ap.add_argument("--width", type=int, default=80)
    ap.add_argument("--height", type=int, default=45)
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--one-thread", action="store_true")
    args = ap.parse_args()
    scene = bench_scene(args.width, args.height)
    for rel_tol, samples, rule in parse_settings(args.vlref):
        kw = {"rel_tol": rel_tol, "shadow_samples": samples, "rule": rule}
        result = render_reference(scene, **kw)
        wall, frame = [], []
        for _ in range(args.repeats):
            start = time.perf_counter()
            result = render_reference(scene, **kw)
            wall.append(time.perf_counter() - start)
            frame.append(result.stats["frame_seconds"])
        row = {"tag": args.tag, "setting": f"{rel_tol:g}/{samples}/{rule}", "threads": numba.get_num_threads(),
               "median_s": float(np.median(wall)), "min_s": min(wall), "frame_s": float(np.median(frame)),
               "intervals": result.stats["intervals"],
               "sha": hashlib.sha256(result.inscatter.tobytes()).hexdigest()[:16]}
        if hasattr(reference, "prepare_reference"):  # trees before it: the whole call only
            prepared, reused = reference.prepare_reference(scene), []
            for _ in range(args.repeats):
                start = time.perf_counter()
                render_reference(prepared, **kw)
                reused.append(time.perf_counter() - start)
            row["reused_median_s"] = float(np.median(reused))
        if args.one_thread:
            threads = numba.get_num_threads()
            numba.set_num_threads(1)
            cpu = []
            for _ in range(args.repeats):
                start = time.process_time()
                render_reference(scene, **kw)
                cpu.append(time.process_time() - start)
            numba.set_num_threads(threads)
            row["one_thread_cpu_min_s"] = min(cpu)
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
