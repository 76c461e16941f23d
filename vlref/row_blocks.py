"""NumPy work over an image's rows, in blocks on threads.

NumPy releases the GIL inside its loops, so NumPy operations on blocks of whole rows run on several cores at
once, and each block's temporaries stay in a core's cache where the whole frame's would be hundreds of MB of
new pages (at 1080p the camera's ray directions made ~250 MB of them: BENCHMARKS.md "The stages around the
kernels"). Operations that are per pixel, or per row like ``matmul`` of a stack of rows, give the same bits
for every block split and thread count.
"""

from __future__ import annotations

import concurrent.futures
from typing import Callable

import numba

__all__ = ["BLOCK_ROWS", "in_row_blocks"]

BLOCK_ROWS = 16
"""Rows of a block: ~0.7 MB for an (rows, 1920, 3) float64 temporary."""


def in_row_blocks(height: int, fn: Callable[[int, int], None], threads: int | None = None,
                  rows: int = BLOCK_ROWS) -> None:
    """``fn(y0, y1)`` for the blocks ``[y0, y1)`` of ``rows`` rows covering ``0..height`` (the last one may be
    shorter), on ``threads`` threads (default: Numba's thread count, that of the kernels). ``fn`` writes its
    rows of a result allocated by the caller."""
    starts = range(0, int(height), int(rows))
    workers = max(1, min(numba.get_num_threads() if threads is None else int(threads), len(starts)))
    if workers == 1:
        for y0 in starts:
            fn(y0, min(y0 + rows, height))
        return
    with concurrent.futures.ThreadPoolExecutor(workers) as pool:
        list(pool.map(lambda y0: fn(y0, min(y0 + rows, height)), starts))
