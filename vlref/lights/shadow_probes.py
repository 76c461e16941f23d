"""vlref's shadow maps probed by rays and points a caller chooses (a port's texel rays and visible points: the
verdict, :mod:`vlref.oracle.verdict`).

:func:`cast_rays` gives what a map texel with these rays stores (:func:`vlref.lights.shadow_cast.biased_distances`);
:func:`lit_at_points` what a light's map says at world points (:func:`vlref.lights.shadow_lookup.map_lit`).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from ..geometry import OPAQUE_ONLY, RAY_CHUNK, closest_hits, traversal_stack
from ..jit import njit
from .shadow_cast import biased_distances
from .shadow_lookup import map_lit

__all__ = ["cast_rays", "lit_at_points"]


def cast_rays(geometry, origins: np.ndarray, dirs: np.ndarray, start: np.ndarray, tmax: np.ndarray, bias: float,
              slope_bias: float) -> np.ndarray:
    """(N,) the biased distance ``start + t + bias + slope_bias · min(tan α, 10)`` of each ray's first opaque
    hit in ``(0, tmax)`` (``inf`` where none): what a map texel with these rays stores
    (:mod:`vlref.lights.shadow_pack`), for rays a caller chooses (a port's texel rays, :mod:`vlref.oracle.verdict`)."""
    out = np.empty(len(origins))
    _cast_rays(geometry.arrays, np.ascontiguousarray(origins, dtype=np.float64),
               np.ascontiguousarray(dirs, dtype=np.float64), np.ascontiguousarray(start, dtype=np.float64),
               np.ascontiguousarray(tmax, dtype=np.float64), float(bias), float(slope_bias), out)
    return out


@njit(cache=True, fastmath=False, parallel=True)
def _cast_rays(geo, origins, dirs, start, tmax, bias, slope_bias, out):
    """:func:`cast_rays` in chunks of ``RAY_CHUNK`` rays, each chunk on one thread."""
    n = origins.shape[0]
    for chunk in prange((n + RAY_CHUNK - 1) // RAY_CHUNK):
        s, e = chunk * RAY_CHUNK, min(n, (chunk + 1) * RAY_CHUNK)
        m = e - s
        stack = traversal_stack()
        t, obj, normal = np.empty(m), np.empty(m, dtype=np.int64), np.empty((m, 3))
        closest_hits(geo, origins[s:e], dirs[s:e], tmax[s:e], OPAQUE_ONLY, stack, t, obj, normal)
        biased_distances(t, obj, normal, dirs[s:e], start[s:e], bias, slope_bias, out[s:e])


@njit(cache=True, fastmath=False, parallel=True)
def lit_at_points(shadows, kind, lf, light, points, out):
    """``out[i]``: the mean over RGB of :func:`map_lit` of light ``light`` at world point ``points[i]`` (N, 3)."""
    for i in prange(points.shape[0]):
        r, g, b = map_lit(shadows, kind, lf, light, points[i, 0], points[i, 1], points[i, 2])
        out[i] = (r + g + b) / 3.0
