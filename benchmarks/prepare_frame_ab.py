"""The reference's frame alone, :func:`vlref.render.prepare_frame` of ``mitsuba_ratio.py``'s bench scene at 80x45, in
one tree per process (BENCHMARKS.md, "The bilateral blur's divisions, its output, and the reference's frame"): the
median of ``--calls`` calls after 20 warm-up calls, on every Numba thread and on one. Run it per tree, fresh processes
alternated (main, tree, tree, main), with that tree first on ``PYTHONPATH``:

    PYTHONPATH=TREE python benchmarks/prepare_frame_ab.py --tag tree
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
from mitsuba_ratio import bench_scene  # noqa: E402  (this folder, whichever tree is on the path)

from vlref.render import prepare_frame  # noqa: E402


def median_us(fn, calls: int) -> float:
    for _ in range(20):
        fn()
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return round(float(np.median(times)) * 1e6, 1)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--tag", required=True)
    parser.add_argument("--calls", type=int, default=400)
    args = parser.parse_args()
    scene = bench_scene(80, 45)
    report = {"tag": args.tag, "threads": numba.get_num_threads()}
    report["prepare_frame_us"] = median_us(lambda: prepare_frame(scene), args.calls)
    numba.set_num_threads(1)
    report["prepare_frame_one_thread_us"] = median_us(lambda: prepare_frame(scene), args.calls)
    print(json.dumps(report))


if __name__ == "__main__":
    main()
