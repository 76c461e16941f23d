"""Bilateral-blur variants in one process (BENCHMARKS.md, "The bilateral blur's stretches open and close their
sums"): copies of ``vlref/post/blur.py`` (this tree's, with one text replaced each, and ``--main``: another tree's,
unchanged) checked bit for bit against the first name on the bench's pass (``blur_hv(thesis_blur_pass, full, depth)``
on ``vlref.bench.stages.post_passes``'s inputs), then timed alternated (the list, then the list reversed, ``--rounds``
rounds): 1080p on every core (wall ms) and 960x540 on one thread (CPU ns per pixel and pass). One JSON line on stdout.

Run from a tree's root (``PYTHONPATH=$PWD``); compile each copy first, in processes of their own (in parallel):

    python3 benchmarks/blur_variants.py warm DIR NAME [--main PATH]   # once per name; DIR: where the copies go
    python3 benchmarks/blur_variants.py time DIR NAME... [--main PATH]
"""

import argparse
import hashlib
import json
import pathlib
import time

import numba
import numpy as np

from radial_variants import variant
from vlref.post.downsample import downsample_min

SOURCE = pathlib.Path(__file__).resolve().parents[1] / "vlref" / "post" / "blur.py"
VARIANTS = {
    "tree": ("", ""),
    "main": ("", ""),  # the --main copy
    "ymm": ("    prefer_wide_vectors()\n    H, W, C = v.shape\n", "    H, W, C = v.shape\n"),
    "planes512": ("    arrays_do_not_overlap()\n    W, C = v.shape[1], v.shape[2]\n",
                  "    arrays_do_not_overlap()\n    prefer_wide_vectors()\n    W, C = v.shape[1], v.shape[2]\n"),
    "blocks1": ("float(epsilon), 2 * get_num_threads(), lines)", "float(epsilon), get_num_threads(), lines)"),
    "exp_ymm": ("    prefer_wide_vectors()\n    n = out.size\n", "    n = out.size\n"),
    "blocks4": ("float(epsilon), 2 * get_num_threads(), lines)", "float(epsilon), 4 * get_num_threads(), lines)"),
    "frame": ("radius: int = 3, sigma", "radius: int = 0, sigma"),
    "no_div": ("""        texels[3 * i] = (a0 + w * rows[vrow, 0, j]) / s
        texels[3 * i + 1] = (a1 + w * rows[vrow, 1, j]) / s
        texels[3 * i + 2] = (a2 + w * rows[vrow, 2, j]) / s""", """        texels[3 * i] = (a0 + w * rows[vrow, 0, j]) * s
        texels[3 * i + 1] = (a1 + w * rows[vrow, 1, j]) * s
        texels[3 * i + 2] = (a2 + w * rows[vrow, 2, j]) * s"""),
    "no_exp": ("sigma: float = 1.5, depth_factor: float = 1.0", "sigma: float = 1.5, depth_factor: float = 0.0"),
}
"""One replaced text each in this tree's blur.py (``tree``: none; ``main``: ``--main``'s file as it is). ``ymm``: the
block's loops at the CPU's preferred width (256 bits on Intel's server cores); ``planes512``: the planes split with
512-bit vectors too; ``blocks1``, ``blocks4``: one or four blocks of rows per thread instead of two; ``exp_ymm``: the
Gaussian weights' loop at the CPU's preferred width. Not the pass's bits, to split its time: ``frame`` (radius 0: the
planes, the centre weight, the division and the output), ``no_exp`` (depth weight 1: no ``exp``) and ``no_div`` (the
RGB output multiplied by the weight sum instead of divided: the divider's share)."""


def inputs(h: int, w: int):
    """``post_passes(h, w)``'s ``full`` and ``depth`` (the same draws from ``default_rng(0)``)."""
    rng = np.random.default_rng(0)
    depth = rng.uniform(1.0, 30.0, size=(h, w))
    rng.random(downsample_min(depth, "half").shape + (3,))
    return rng.random((h, w, 3)), depth


def blur(module, image, depth):
    return module.blur_hv(module.thesis_blur_pass, image, depth)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("phase", choices=("warm", "time"))
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("names", nargs="+", choices=tuple(VARIANTS))
    parser.add_argument("--main", type=pathlib.Path, help="the blur.py copied unchanged as 'main'")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    args.folder.mkdir(parents=True, exist_ok=True)
    modules = {name: variant(args.folder, name, args.main if name == "main" else SOURCE, VARIANTS[name])
               for name in args.names}
    if args.phase == "warm":
        for module in modules.values():
            blur(module, *inputs(36, 64))
        return
    big, small = inputs(1080, 1920), inputs(540, 960)
    digests = {name: hashlib.sha256(b"".join(a.tobytes() for a in blur(m, *big))).hexdigest()[:16]
               for name, m in modules.items()}
    runs = {name: {"ms": [], "ns_one_thread": []} for name in args.names}
    order = args.names + args.names[::-1]
    for _ in range(args.rounds):
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        for name in order:
            start = time.perf_counter()
            blur(modules[name], *big)
            runs[name]["ms"].append(round(1e3 * (time.perf_counter() - start), 2))
        numba.set_num_threads(1)
        for name in order:
            start = time.process_time()
            blur(modules[name], *small)
            runs[name]["ns_one_thread"].append(round((time.process_time() - start) / (540 * 960 * 2) * 1e9, 2))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    medians = {name: {key: float(np.median(values)) for key, values in run.items()} for name, run in runs.items()}
    print(json.dumps({"sha256_hv": digests, "medians": medians, "runs": runs}))


if __name__ == "__main__":
    main()
