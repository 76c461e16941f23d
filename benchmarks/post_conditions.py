"""The two blurs of ``vlref bench``'s post section (``vlref.bench.stages.post_passes``: the bilateral blur H+V and the
radial blur, 1080p, every core) timed in one process under the conditions that the bench's earlier sections leave
behind, to tell which of them makes the blurs slower inside the bench than in a fresh process (BENCHMARKS.md, "Post
passes"). One JSON line on stdout, in milliseconds, each figure the median of ``--repeats`` calls after a warm-up:

* ``fresh``: as benchmarks/post_ab.py measures them;
* ``threads``: after ``numba.set_num_threads(n)`` for ``n = 1, 2, 4, 8`` and back to all, with a parallel call at each
  count (what the bench's ``scaling`` section does);
* ``hot``: right after ``--heat`` seconds of the radial blur on every core (the bench's march and ray casting keep
  every core busy with wide vector code for minutes before its post section).

``--keep-pages``: glibc's ``malloc`` told to keep freed memory (``mallopt``: ``M_MMAP_THRESHOLD`` 1 GiB,
``M_TRIM_THRESHOLD`` 2 GiB, before NumPy allocates), so that each call's output arrays reuse the pages of the previous
call's instead of fresh pages that the kernel zeroes on first touch (a 1080p RGB buffer is 50 MB, above glibc's
largest ``mmap`` threshold, 32 MiB). Run from a tree's root:

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/post_conditions.py LABEL [--keep-pages]
"""

import argparse
import ctypes
import json
import time

import numba

from vlref.bench.config import median_time
from vlref.bench.stages import post_passes

BLURS = ("bilateral_blur_hv", "radial_blur_64")
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3


def timed(passes, repeats) -> dict:
    return {name: round(1e3 * median_time(passes[name], repeats), 2) for name in BLURS}


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("label")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--heat", type=float, default=10.0, help="seconds of the radial blur before the hot figures")
    parser.add_argument("--keep-pages", action="store_true")
    args = parser.parse_args()
    if args.keep_pages:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(M_MMAP_THRESHOLD, 1 << 30)
        libc.mallopt(M_TRIM_THRESHOLD, 1 << 31)
    passes = post_passes(1080, 1920)
    report = {"label": args.label, "keep_pages": args.keep_pages, "numba_threads": numba.get_num_threads()}
    report["fresh"] = timed(passes, args.repeats)
    small = post_passes(270, 480)
    every = numba.get_num_threads()
    for n in (1, 2, 4, 8, every):
        numba.set_num_threads(min(n, every))
        small["bilateral_blur_hv"]()
    report["threads"] = timed(passes, args.repeats)
    end = time.perf_counter() + args.heat
    while time.perf_counter() < end:
        passes["radial_blur_64"]()
    report["hot"] = timed(passes, args.repeats)
    print(json.dumps(report))


if __name__ == "__main__":
    main()
