"""Per-pixel start offsets of the march (interleaved sampling).

An offset ``β ∈ [0, 1)`` moves the first sample of a pixel's ray ``β`` steps forward.

* ``bayerN`` (N = 2, 4, 8): the standard recursive Bayer matrix
  ``B_{2n} = [[4 B_n, 4 B_n + 2], [4 B_n + 3, 4 B_n + 1]]`` with ``B_1 = [[0]]``, indexed
  ``B[y mod N, x mod N]`` with ``(x, y)`` the pixel's column and row *from the top* of the
  target it is marched in; ``β = B / N²``.
  (``bayer4`` is ``[[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]]``.)
* ``hash``: a seeded integer hash of ``(x, y, seed)`` (PCG-style), ``β = h / 2³²``.
* ``none``: ``β = 0``.
"""

from __future__ import annotations

import functools

import numpy as np

from ..jit import njit

PATTERNS = ("none", "bayer2", "bayer4", "bayer8", "hash")


def bayer_matrix(n: int) -> np.ndarray:
    """The n x n Bayer index matrix (n a power of two), int64 values 0..n²-1."""
    if n < 1 or n & (n - 1):
        raise ValueError(f"Bayer size must be a power of two, got {n}")
    b = np.zeros((1, 1), dtype=np.int64)
    while b.shape[0] < n:
        b = np.block([[4 * b, 4 * b + 2], [4 * b + 3, 4 * b + 1]])
    return b


@njit(cache=True, fastmath=False)
def pixel_hash(x, y, seed):
    """A 32-bit PCG-style hash of a pixel and a seed, as a float in [0, 1)."""
    h = (np.uint64(x) * np.uint64(0x9E3779B1) + np.uint64(y) * np.uint64(0x85EBCA77)
         + np.uint64(seed) * np.uint64(0xC2B2AE3D) + np.uint64(0x27D4EB2F)) & np.uint64(0xFFFFFFFF)
    h = (h * np.uint64(747796405) + np.uint64(2891336453)) & np.uint64(0xFFFFFFFF)
    shift = (h >> np.uint64(28)) + np.uint64(4)
    w = (((h >> shift) ^ h) * np.uint64(277803737)) & np.uint64(0xFFFFFFFF)
    w = (w >> np.uint64(22)) ^ w
    return float(w) / 4294967296.0


@njit(cache=True, fastmath=False, entry=True)
def _hash_offsets(width, height, seed):
    out = np.empty((height, width))
    for y in range(height):
        for x in range(width):
            out[y, x] = pixel_hash(x, y, seed)
    return out


@functools.lru_cache(maxsize=None)
def _bayer_offsets(n: int) -> np.ndarray:
    """``bayer_matrix(n) / n²`` (read-only: one per size, shared by every frame)."""
    b = bayer_matrix(n) / float(n * n)
    b.flags.writeable = False
    return b


def offsets(pattern: str, width: int, height: int, seed: int = 0) -> np.ndarray:
    """The (height, width) float64 offset buffer of ``pattern`` (row 0 at the top)."""
    if pattern == "none":
        return np.zeros((height, width))
    if pattern == "hash":
        return _hash_offsets(width, height, seed)
    if pattern.startswith("bayer"):
        n = int(pattern[5:])
        # one band of n rows written into every n rows of the result: one pass over new memory (tiling a larger
        # array and copying its corner were two, 1.4x the CPU time at 1080p)
        band = np.tile(_bayer_offsets(n), (1, width // n + 1))[:, :width]
        out = np.empty((height, width))
        whole = height - height % n
        out[:whole].reshape(whole // n, n, width)[...] = band
        out[whole:] = band[:height - whole]
        return out
    raise ValueError(f"unknown sampling pattern {pattern!r}; use one of {PATTERNS}")
