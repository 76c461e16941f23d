"""New arrays with their memory faulted in on every thread, before a parallel kernel writes them.

A new NumPy array of some MB is backed by pages the operating system maps on the first write: with transparent
huge pages (``madvise``, NumPy asks for them), 2 MB at a time, zeroed by the thread that faults. A kernel whose
threads take short rows or thin bands of rows (the march's bands, the scene colour's rows taken one at a time)
has all its threads write into the same few pages at once, and they wait for each other's faults: the march's
~215 MB of outputs at 1080p with four lights cost 0.03-0.07 s of first touch on 16 threads (BENCHMARKS.md "The
march in fewer bands"). :func:`empty_faulted` writes a zero into every 4 KiB of a new array, each thread a
contiguous block of 2 MB spans (:func:`vlref.row_blocks.in_row_blocks`; NumPy releases the GIL in the fill),
so that the faults run side by side. The values are unspecified, as ``np.empty``'s: the kernel writes every
element.
"""

from __future__ import annotations

import numpy as np

from .row_blocks import in_row_blocks

__all__ = ["PAGE", "SPAN", "empty_faulted"]

PAGE = 4096
"""Bytes of a base page: one write in each faults the whole array in (huge pages included)."""
SPAN = 2 * 1024 * 1024
"""Bytes of a block's unit (a transparent huge page), so that threads rarely fault the same page."""


def empty_faulted(shape, dtype=np.float64) -> np.ndarray:
    """``np.empty(shape, dtype)`` whose pages are faulted in by Numba's thread count of threads (module
    docstring); arrays under one span are left to the kernel."""
    out = np.empty(shape, dtype)
    flat = out.reshape(-1).view(np.uint8)
    spans = -(-flat.size // SPAN)
    if spans > 1:
        in_row_blocks(spans, lambda s0, s1: flat[s0 * SPAN:s1 * SPAN:PAGE].fill(0))
    return out
