"""NumPy work over an image's rows, in blocks on threads.

NumPy releases the GIL inside its loops, so NumPy operations on blocks of whole rows run on several cores at
once, and a block's temporaries are a few MB where the whole frame's were hundreds of MB of new pages (at
1080p the camera's ray directions made ~250 MB of them: BENCHMARKS.md "The stages around the kernels").
Operations that are per pixel, or per row like ``matmul`` of a stack of rows, give the same bits for every
block split and thread count.
"""

from __future__ import annotations

import concurrent.futures
from typing import Callable

import numba

__all__ = ["MAX_BLOCK_ROWS", "MIN_BLOCK_PIXELS", "block_count", "in_row_blocks"]

MAX_BLOCK_ROWS = 128
"""The most rows of a block: ~5.9 MB for an (rows, 1920, 3) float64 temporary."""

MIN_BLOCK_PIXELS = 32768
"""The fewest pixels worth a block of their own: NumPy does ~1 ms of this work on them, about what starting a
thread pool costs (dev box: an empty 16-thread pool 0.9 ms; the device's reference frame at 80x45 spent ~5 ms in
the pools of its two row-block calls). A frame of fewer pixels runs in the calling thread."""


def block_count(height: int, width: int, workers: int) -> int:
    """How many blocks :func:`in_row_blocks` makes of ``height`` rows of ``width`` pixels for ``workers``
    threads: as few as a multiple of the thread count allows with at most :data:`MAX_BLOCK_ROWS` rows each, and
    no more than one per :data:`MIN_BLOCK_PIXELS` pixels unless the row limit needs more (at least one)."""
    multiple = min(height, workers * -(-height // (workers * MAX_BLOCK_ROWS)))
    return max(1, -(-height // MAX_BLOCK_ROWS), min(multiple, height * width // MIN_BLOCK_PIXELS))


def in_row_blocks(height: int, width: int, fn: Callable[[int, int], None], threads: int | None = None) -> None:
    """``fn(y0, y1)`` for blocks ``[y0, y1)`` covering ``0..height`` (rows of ``width`` pixels), on ``threads``
    threads (default: Numba's thread count, that of the kernels); ``fn`` writes its rows of a result the caller
    allocated.

    The blocks (:func:`block_count`) are as few as a multiple of the thread count allows with at most
    :data:`MAX_BLOCK_ROWS` rows each, their sizes differing by at most one row: each NumPy call takes the GIL to
    start, and 16 threads running many small blocks wait for it (device, ray directions at 1080p: blocks of 16
    rows 0.022-0.029 s, one block of 68 rows per thread 0.018-0.020 s); a small frame makes fewer blocks
    (:data:`MIN_BLOCK_PIXELS`), one block runs in the calling thread."""
    height = int(height)
    if height <= 0:
        return
    workers = max(1, numba.get_num_threads() if threads is None else int(threads))
    blocks = block_count(height, int(width), workers)
    edges = [height * k // blocks for k in range(blocks + 1)]
    spans = list(zip(edges[:-1], edges[1:]))
    if min(workers, blocks) == 1:
        for y0, y1 in spans:
            fn(y0, y1)
        return
    with concurrent.futures.ThreadPoolExecutor(min(workers, blocks)) as pool:
        list(pool.map(lambda span: fn(*span), spans))
