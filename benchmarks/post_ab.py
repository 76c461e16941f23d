"""Post-pass A/B of two trees on one machine (BENCHMARKS.md, "Post passes"): the radial blur (64 taps) and the
bilateral blur (thesis pass, H then V) on the bench's 1080p inputs (``vlref.bench.stages.bench_post``'s), on every
core and on one, plus a hash of each output (the trees must agree bit for bit).

Run from a tree's root, once with ``warm`` (compiles into the tree's ``NUMBA_CACHE_DIR`` on a small image), then
with ``time``, alternating the trees:

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/post_ab.py warm LABEL
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/post_ab.py time LABEL

The one-thread figure runs the radial blur at 960x540 under ``numba.set_num_threads(1)`` (nanoseconds per tap,
CPU time). One JSON line per run on stdout.
"""

import hashlib
import json
import sys
import time

import numba
import numpy as np

from vlref.post.blur import blur_hv, thesis_blur_pass
from vlref.post.radial import radial_blur


def inputs(h: int, w: int):
    """The bench's post inputs (``bench_post``: ``default_rng(0)``, depth first, then the images)."""
    rng = np.random.default_rng(0)
    depth = rng.uniform(1.0, 30.0, size=(h, w))
    rng.random(((h + 1) // 2, (w + 1) // 2, 3))  # the half-resolution image bench_post draws next
    return depth, rng.random((h, w, 3))


def median_seconds(fn, repeats: int, clock=time.perf_counter) -> float:
    fn()
    times = []
    for _ in range(repeats):
        start = clock()
        fn()
        times.append(clock() - start)
    return float(np.median(times))


def main(phase: str, label: str) -> None:
    h, w = (1080, 1920) if phase == "time" else (36, 64)
    depth, full = inputs(h, w)
    radial = lambda: radial_blur(full, (0.5, 0.4), 64, 0.9, 0.5, 0.97, 0.3)  # noqa: E731
    blur = lambda: blur_hv(thesis_blur_pass, full, depth)  # noqa: E731
    digest = hashlib.sha256(radial().tobytes() + blur()[1].tobytes()).hexdigest()[:16]
    report = {"label": label, "threads": numba.get_num_threads(), "sha256": digest}
    if phase == "time":
        report["radial_64_s"] = median_seconds(radial, 5)
        report["bilateral_hv_s"] = median_seconds(blur, 5)
        small_depth, small = inputs(540, 960)
        numba.set_num_threads(1)
        one = median_seconds(lambda: radial_blur(small, (0.5, 0.4), 64, 0.9, 0.5, 0.97, 0.3), 3, time.process_time)
        report["radial_one_thread_ns_per_tap"] = one / (540 * 960 * 65) * 1e9
        report["bilateral_hv_one_thread_s"] = median_seconds(lambda: blur_hv(thesis_blur_pass, small, small_depth), 3,
                                                             time.process_time)
    print(json.dumps(report))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
