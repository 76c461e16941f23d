"""Post-pass A/B of two trees on one machine (BENCHMARKS.md, "Post passes"): every pass of ``vlref bench``'s post
section (``vlref.bench.stages.bench_post``: the same inputs, the preview left out) at 1080p on every core, the radial
blur (64 taps) and the bilateral blur H+V at 960x540 on one core, and a hash of each output (the trees must agree
bit for bit).

Run from a tree's root, once with ``warm`` (compiles into the tree's ``NUMBA_CACHE_DIR`` on a small image), then
with ``time``, alternating the trees:

    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/post_ab.py warm LABEL
    PYTHONPATH=$PWD NUMBA_CACHE_DIR=/tmp/nc-LABEL python3 benchmarks/post_ab.py time LABEL

``--only NAME`` runs one pass (the warm phase of each pass can run in parallel processes). Medians of
``--repeats`` (default 3) after a warm-up call. The one-thread figures are CPU time under
``numba.set_num_threads(1)``: the radial blur's in nanoseconds per pixel and tap, the bilateral blur's per pixel and
pass. One JSON line per run on stdout.
"""

import argparse
import hashlib
import json
import time

import numba
import numpy as np

from vlref.post.blur import blur_hv, thesis_blur_pass
from vlref.post.composite import composite_physical
from vlref.post.downsample import downsample_min
from vlref.post.radial import radial_blur
from vlref.post.upsample import thesis_upsample, urp_upsample, vl_upsample


def passes(h: int, w: int) -> dict:
    """``bench_post``'s passes on its inputs (``default_rng(0)``, drawn in its order)."""
    rng = np.random.default_rng(0)
    depth = rng.uniform(1.0, 30.0, size=(h, w))
    depth_lo = downsample_min(depth, "half")
    lo = rng.random(depth_lo.shape + (3,))
    full = rng.random((h, w, 3))
    trans = rng.random((h, w))
    return {
        "radial_blur_64": lambda: radial_blur(full, (0.5, 0.4), 64, 0.9, 0.5, 0.97, 0.3),
        "bilateral_blur_hv": lambda: blur_hv(thesis_blur_pass, full, depth)[1],
        "downsample_min_half": lambda: downsample_min(depth, "half"),
        "thesis_upsample": lambda: thesis_upsample(lo, depth_lo, depth),
        "vl_upsample": lambda: vl_upsample(lo, depth_lo, depth),
        "urp_upsample": lambda: urp_upsample(lo, depth_lo, depth),
        "composite": lambda: composite_physical(full, trans, full),
    }


def median_seconds(fn, repeats: int, clock=time.perf_counter) -> float:
    fn()
    times = []
    for _ in range(repeats):
        start = clock()
        fn()
        times.append(clock() - start)
    return float(np.median(times))


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
    for name, fn in passes(h, w).items():
        if args.only not in (None, name):
            continue
        report["sha256"][name] = digest(fn())
        if args.phase == "time":
            report["ms"][name] = round(1e3 * median_seconds(fn, args.repeats), 2)
    if args.phase == "time":
        small = passes(540, 960)
        numba.set_num_threads(1)
        one = median_seconds(small["radial_blur_64"], args.repeats, time.process_time)
        report["radial_one_thread_ns_per_tap"] = round(one / (540 * 960 * 65) * 1e9, 3)
        one = median_seconds(small["bilateral_blur_hv"], args.repeats, time.process_time)
        report["bilateral_one_thread_ns_per_pixel_pass"] = round(one / (540 * 960 * 2) * 1e9, 2)
    print(json.dumps(report))


if __name__ == "__main__":
    main()
