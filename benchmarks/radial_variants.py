"""Radial-blur variants in one process (BENCHMARKS.md, "The radial blur's tile sizes and loop shapes", "The radial blur
reads a texel's RGB as one vector"): copies of
``vlref/post/radial.py`` with one text replaced each (and ``--main``: another tree's, unchanged), checked bit for bit
against the first name on the bench's input, then timed alternated (the list, then the list reversed, ``--rounds``
rounds): 1080p, 64 taps on every core (wall ms) and 960x540 on one thread (CPU ns per pixel and tap); with
``--scaling``, 1080p at each thread count given. One JSON line on stdout (medians and every run).

Run from a tree's root (``PYTHONPATH=$PWD``); compile each copy first, in processes of their own (in parallel):

    python3 benchmarks/radial_variants.py warm DIR NAME [--main PATH]   # once per name; DIR: where the copies go
    python3 benchmarks/radial_variants.py time DIR NAME... [--main PATH]
"""

import argparse
import importlib
import json
import pathlib
import sys
import time

import numba
import numpy as np

SOURCE = pathlib.Path(__file__).resolve().parents[1] / "vlref" / "post" / "radial.py"
VARIANTS = {
    "tree": ("", ""),
    "main": ("", ""),  # the --main copy
    "tile128": ("RADIAL_TILE = 256", "RADIAL_TILE = 128"),
    "tile512": ("RADIAL_TILE = 256", "RADIAL_TILE = 512"),
    "run4": ("RADIAL_RUN = 16", "RADIAL_RUN = 4"),
    "run64": ("RADIAL_RUN = 16", "RADIAL_RUN = 64"),
    "ymm": ("    prefer_wide_vectors()\n    arrays_do_not_overlap()\n    for ch", "    arrays_do_not_overlap()\n    for ch"),
    "gathers": ("    rgb = C == 3\n", "    rgb = False\n"),  # RGB through the per-channel gather loop, as before
    "three_values": ("    if max(ra, rb) + row < np.uint64(flat.size):", "    if False:"),  # RGB texels read as 3 values
    "fixed_rows": ("_tap_rows_rgb(flat, ra, rb, yy - yf,", "_tap_rows_rgb(flat, np.uint64(0), np.uint64(0), yy - yf,"),
    "first_columns": ("                _tap_columns(u, n, W, C, lo_x, hi_x, offset, repeat, tx, ia, ib)\n",
                      "                if i == 0:\n                    _tap_columns(u, n, W, C, lo_x, hi_x, offset, repeat, tx, "
                      "ia, ib)\n"),
    "no_rows": ("_tap_rows_rgb(flat, ra, rb, yy - yf, tx, ia, ib, n, w, acc_rgb, row)", "acc_rgb[0] += tx[0] * w + yy"),
    "columns_ymm": ("    prefer_wide_vectors()\n    if repeat:", "    if repeat:"),
}
"""One replaced text each in this tree's radial.py (``tree``: none; ``main``: ``--main``'s file as it is). ``gathers``
and ``three_values`` (every texel read as three values, two loads and a shuffle) are the RGB kernel's predecessors.
``columns_ymm``: the column loop at the CPU's preferred width (256 bits on Intel's server cores). Not the blur's bits,
to split its time: ``fixed_rows`` (every tap reads texel row 0 twice: one row, 46 KB at 1920 columns, about the L1
cache), ``first_columns`` (the columns of the first tap reused by the others: no column loop) and ``no_rows`` (no texel
read: the column loop and the rest)."""


def variant(folder: pathlib.Path, name: str, source: pathlib.Path = SOURCE, change: tuple | None = None):
    """The copy of ``source`` (radial.py) with the replacement ``change`` (``VARIANTS[name]``; ``("", "")``: none),
    imported as ``STEM_NAME`` (``radial_NAME``) from ``folder``; benchmarks/blur_variants.py copies blur.py."""
    old, new = VARIANTS[name] if change is None else change
    text = source.read_text()
    if old and text.count(old) != 1:
        raise SystemExit(f"{name}: {old!r} is not in {source} exactly once")
    path = folder / f"{source.stem}_{name}.py"
    text = text.replace(old, new) if old else text
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))
    return importlib.import_module(f"{source.stem}_{name}")


def blur(module, image):
    return module.radial_blur(image, (0.5, 0.4), 64, 0.9, 0.5, 0.97, 0.3)  # the bench's call (post_passes)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("phase", choices=("warm", "time"))
    parser.add_argument("folder", type=pathlib.Path)
    parser.add_argument("names", nargs="+", choices=tuple(VARIANTS))
    parser.add_argument("--main", type=pathlib.Path, help="the radial.py copied unchanged as 'main'")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--scaling", type=lambda t: [int(n) for n in t.split(",")], default=[],
                        help="thread counts (e.g. 1,4,8,16) at which each variant then runs at 1080p (twice, alternated)")
    args = parser.parse_args()
    args.folder.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(0)
    modules = {name: variant(args.folder, name, args.main if name == "main" and args.main else SOURCE)
               for name in args.names}
    if args.phase == "warm":
        for module in modules.values():
            blur(module, rng.random((36, 64, 3)))
        return
    big, small = rng.random((1080, 1920, 3)), rng.random((540, 960, 3))
    reference = blur(modules[args.names[0]], big)
    same = {name: bool((blur(m, big) == reference).all()) for name, m in modules.items()}
    runs = {name: {"ms": [], "ns_one_thread": []} for name in args.names}
    order = args.names + args.names[::-1]
    for _ in range(args.rounds):
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        for name in order:
            start = time.perf_counter()
            blur(modules[name], big)
            runs[name]["ms"].append(round(1e3 * (time.perf_counter() - start), 2))
        numba.set_num_threads(1)
        for name in order:
            start = time.process_time()
            blur(modules[name], small)
            runs[name]["ns_one_thread"].append(round((time.process_time() - start) / (540 * 960 * 65) * 1e9, 3))
    scaling = {name: {} for name in args.names}
    for threads in args.scaling:
        numba.set_num_threads(threads)
        for name in order:
            start = time.perf_counter()
            blur(modules[name], big)
            scaling[name].setdefault(threads, []).append(round(1e3 * (time.perf_counter() - start), 2))
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    medians = {name: {key: float(np.median(values)) for key, values in run.items()} for name, run in runs.items()}
    print(json.dumps({"same_bits_as_first": same, "medians": medians, "runs": runs, "scaling_ms": scaling}))


if __name__ == "__main__":
    main()
