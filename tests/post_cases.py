"""Shared generators for the vlref.post tests: small random images and layered depth buffers."""

import numpy as np
from hypothesis import strategies as st

DEPTH_LEVELS = np.array([0.5, 1.0, 1.2, 3.0, 7.5, 40.0, np.inf])


def sizes(lo=4, hi=12):
    """(seed, H, W) with H, W in [lo, hi]."""
    return st.tuples(st.integers(0, 2**31 - 1), st.integers(lo, hi), st.integers(lo, hi))


def depth_image(rng, h, w, sky=True):
    """Layered linear eye depth: rectangles of a few levels (edges and flat runs), small slopes, optional inf."""
    levels = DEPTH_LEVELS if sky else DEPTH_LEVELS[:-1]
    z = np.full((h, w), rng.choice(levels))
    for _ in range(3):
        r0, c0 = rng.integers(0, h), rng.integers(0, w)
        z[r0:r0 + rng.integers(1, h + 1), c0:c0 + rng.integers(1, w + 1)] = rng.choice(levels)
    finite = np.isfinite(z)
    z[finite] += rng.random(finite.sum()) * rng.choice([0.0, 0.05, 0.6])
    return z


def raw_depth(rng, h, w):
    """Raw device depth in [0, 1] with flat runs (quantised to 1/8) and noise."""
    return np.clip(np.round(rng.random((h, w)) * 8) / 8 + rng.random((h, w)) * rng.choice([0.0, 1e-3]), 0, 1)


def image(rng, h, w, c=None):
    return rng.random((h, w) if c is None else (h, w, c)) * 4.0
