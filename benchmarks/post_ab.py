"""Post-pass A/B of two trees on one machine (BENCHMARKS.md, "Post passes"): every pass of ``vlref bench``'s post
section (``vlref.bench.stages.post_passes``, which ``bench_post`` times) at 1080p on every core, the radial
blur (64 taps) and the bilateral blur H+V at 960x540 on one core, and a hash of each output (the trees must agree
bit for bit).

Run from a tree's root, once with ``warm`` (compiles into the tree's ``NUMBA_CACHE_DIR`` on a small image), then
with ``time``, alternating the trees:

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/post_ab.py warm LABEL
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/post_ab.py time LABEL

``--only NAME`` runs one pass (the warm phase of each pass can run in parallel processes). Medians of
``--repeats`` (default 3) after a warm-up call. The one-thread figures are CPU time under
``numba.set_num_threads(1)``: the radial blur's in nanoseconds per pixel and tap, the bilateral blur's per pixel and
pass (with ``--only``, the one of that pass, if it is one of them). One JSON line per run on stdout.
"""

import argparse
import hashlib
import json
import time

import numba
import numpy as np

from vlref.bench.config import median_time
from vlref.bench.stages import post_passes


def digest(result) -> str:
    arrays = result if isinstance(result, tuple) else (result,)
    return hashlib.sha256(b"".join(np.ascontiguousarray(a).tobytes() for a in arrays)).hexdigest()[:16]


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("phase", choices=("warm", "time"))
    parser.add_argument("label")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", help="one pass by name (to warm each pass in a process of its own)")
    args = parser.parse_args()
    h, w = (1080, 1920) if args.phase == "time" else (36, 64)
    report = {"label": args.label, "threads": numba.get_num_threads(), "ms": {}, "sha256": {}}
    for name, fn in post_passes(h, w).items():
        if args.only not in (None, name):
            continue
        report["sha256"][name] = digest(fn())
        if args.phase == "time":
            report["ms"][name] = round(1e3 * median_time(fn, args.repeats), 2)
    if args.phase == "time":
        small = post_passes(540, 960)
        numba.set_num_threads(1)
        if args.only in (None, "radial_blur_64"):
            one = median_time(small["radial_blur_64"], args.repeats, time.process_time)
            report["radial_one_thread_ns_per_tap"] = round(one / (540 * 960 * 65) * 1e9, 3)
        if args.only in (None, "bilateral_blur_hv"):
            one = median_time(small["bilateral_blur_hv"], args.repeats, time.process_time)
            report["bilateral_one_thread_ns_per_pixel_pass"] = round(one / (540 * 960 * 2) * 1e9, 2)
    print(json.dumps(report))


if __name__ == "__main__":
    main()
