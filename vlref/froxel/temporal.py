"""Temporal reprojection of the froxel grid (Wronski 2014; Hillaire 2015; Unreal's volumetric fog).

History format (:class:`History`): the previous frame's *blended* scattering grid ``grid`` (gh, gw, D, 4)
= ``(S_r, S_g, S_b, σt)`` (the layout of :mod:`vlref.froxel.grid`), ``frames`` (gh, gw, D) the number
of frames accumulated in each froxel, and what reprojection needs of that frame: its camera (for the
view-projection), slice boundaries and ``tile_depth`` (gh, gw): per column, the farthest eye depth
of the pixels any bilinear lookup of that column can serve (:func:`tile_depth`).

Per froxel of the current frame (:func:`reproject_blend`, prange over columns):

1. the froxel CENTRE ``(c + ½, r + ½, k + ½)`` (not the jittered sample: the history holds the
   accumulated mean of every jitter) is placed in the world and projected with the previous
   view-projection: previous uv ``(u, v)`` and eye depth ``z'`` (clip ``w``);
2. rejection: out of the previous frustum (``z' <= 0``, ``u`` or ``v`` outside [0, 1], ``z'`` beyond the
   previous grid's far depth), or hidden: ``z'`` lies behind the previous ``tile_depth`` of the nearest previous
   column by more than one previous slice thickness at that depth (no pixel of the previous frame could
   read that froxel, so an engine that culls hidden froxels has no valid history there; this is the
   disocclusion test of a froxel grid). A rejected froxel takes the
   current value and restarts its count (``frames = 1``);
3. otherwise the history is fetched trilinearly (clamp to edge) at ``(u·gw - ½, v·gh - ½, s' - ½)``,
   ``s' = depth_to_slice(z')``, the frame count likewise; with ``clamp`` on it is first clamped per
   channel to the min/max of the current grid's 3x3x3 neighbourhood (TAA neighbourhood clamping
   [U: neither Wronski nor Hillaire states one; off by default]);
4. exponential blend ``out = h + α_n (cur - h)`` with ``α_n = max(α, 1/(n + 1))``, ``n`` the fetched
   count: a running mean over the first ``1/α`` frames, then the exponential moving average of weight
   ``α`` (Unreal's ``r.VolumetricFog.HistoryWeight`` = 0.9 is ``α = 0.1``, the default); the new count
   is ``min(n + 1, ⌈1/α⌉)``.

A static camera reprojects every centre onto itself, so the history is the exact per-froxel mean of
the jittered samples (for ``⌈1/α⌉`` frames), which is what the convergence test relies on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import prange

from ..camera import Camera
from ..jit import njit
from .grid import depth_to_slice

__all__ = ["History", "reproject_blend", "tile_depth"]


@dataclass
class History:
    """One frame's temporal state (module docstring)."""

    grid: np.ndarray
    frames: np.ndarray
    camera: Camera
    bounds: np.ndarray
    tile_depth: np.ndarray


def tile_depth(depth: np.ndarray, gw: int, gh: int) -> np.ndarray:
    """(gh, gw): per column, the largest eye depth over the pixels of its own and its 8 neighbours' tiles
    (tile of column ``c``: pixel columns ``floor(c W/gw) .. ceil((c+1) W/gw) - 1``, likewise rows), i.e.
    every pixel whose bilinear apply lookup reads that column; ``inf`` where any of them is sky."""
    from scipy.ndimage import maximum_filter

    h, w = depth.shape
    out = np.empty((gh, gw))
    for r in range(gh):
        rows = slice(r * h // gh, -(-(r + 1) * h // gh))
        for c in range(gw):
            out[r, c] = depth[rows, c * w // gw:-(-(c + 1) * w // gw)].max()
    return maximum_filter(out, size=3, mode="nearest")


@njit(cache=True, fastmath=False, forceinline=True)
def _fetch(grid, frames, gx, gy, gz, out):
    """Trilinear, clamp-to-edge fetch of the 4 channels into ``out`` (4,); returns the fetched frame count."""
    gh, gw, d = grid.shape[0], grid.shape[1], grid.shape[2]
    fx, fy, fz = math.floor(gx), math.floor(gy), math.floor(gz)
    wx, wy, wz = gx - fx, gy - fy, gz - fz
    n = 0.0
    for ch in range(4):
        out[ch] = 0.0
    for a in range(2):
        r = min(max(int(fy) + a, 0), gh - 1)
        ay = wy if a else 1.0 - wy
        for b in range(2):
            c = min(max(int(fx) + b, 0), gw - 1)
            bx = wx if b else 1.0 - wx
            for e in range(2):
                k = min(max(int(fz) + e, 0), d - 1)
                wgt = ay * bx * (wz if e else 1.0 - wz)
                for ch in range(4):
                    out[ch] += wgt * grid[r, c, k, ch]
                n += wgt * frames[r, c, k]
    return n


@njit(cache=True, fastmath=False, parallel=True)
def reproject_blend(current, dirs, origin, forward, bounds, prev_vp, prev_grid, prev_frames, prev_bounds,
                    prev_tile_depth, alpha, clamp, out, out_frames, valid):
    """Blend ``current`` (gh, gw, D, 4) with the reprojected history into ``out`` (module docstring).

    ``dirs`` (gh, gw, 3) the current columns' centre rays; ``prev_vp`` the previous 4x4 view-projection
    (``clip = VP (x, 1)``, ``w`` = eye depth); ``prev_tile_depth`` the previous :func:`tile_depth`.
    ``out_frames`` (gh, gw, D) the new counts, ``valid`` (gh, gw, D) 1 where the history was used.
    """
    gh, gw, d = current.shape[0], current.shape[1], current.shape[2]
    pd = prev_bounds.shape[0] - 1
    pgh, pgw = prev_grid.shape[0], prev_grid.shape[1]
    cap = math.ceil(1.0 / alpha)
    for p in prange(gh * gw):
        r, c = p // gw, p % gw
        dx, dy, dz = dirs[r, c, 0], dirs[r, c, 1], dirs[r, c, 2]
        inv_cos = 1.0 / (dx * forward[0] + dy * forward[1] + dz * forward[2])
        h = np.empty(4)
        for k in range(d):
            t = 0.5 * (bounds[k] + bounds[k + 1]) * inv_cos
            x, y, z = origin[0] + t * dx, origin[1] + t * dy, origin[2] + t * dz
            cx = prev_vp[0, 0] * x + prev_vp[0, 1] * y + prev_vp[0, 2] * z + prev_vp[0, 3]
            cy = prev_vp[1, 0] * x + prev_vp[1, 1] * y + prev_vp[1, 2] * z + prev_vp[1, 3]
            cw = prev_vp[3, 0] * x + prev_vp[3, 1] * y + prev_vp[3, 2] * z + prev_vp[3, 3]
            ok = cw > 0.0 and cw <= prev_bounds[pd]
            u, v = 0.0, 0.0
            if ok:
                u, v = 0.5 + 0.5 * cx / cw, 0.5 - 0.5 * cy / cw
                ok = 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0
            s = 0.0
            if ok:
                s = depth_to_slice(prev_bounds, cw)
                px, py = min(int(u * pgw), pgw - 1), min(int(v * pgh), pgh - 1)
                sk = min(int(s), pd - 1)
                ok = cw <= prev_tile_depth[py, px] + (prev_bounds[sk + 1] - prev_bounds[sk])
            n = 0.0
            if ok:
                n = _fetch(prev_grid, prev_frames, u * pgw - 0.5, v * pgh - 0.5, s - 0.5, h)
                if clamp:
                    for ch in range(4):
                        lo, hi = np.inf, -np.inf
                        for rr in range(max(r - 1, 0), min(r + 2, gh)):
                            for cc in range(max(c - 1, 0), min(c + 2, gw)):
                                for kk in range(max(k - 1, 0), min(k + 2, d)):
                                    lo = min(lo, current[rr, cc, kk, ch])
                                    hi = max(hi, current[rr, cc, kk, ch])
                        h[ch] = min(max(h[ch], lo), hi)
            a = max(alpha, 1.0 / (n + 1.0))
            for ch in range(4):
                out[r, c, k, ch] = current[r, c, k, ch] if not ok else h[ch] + a * (current[r, c, k, ch] - h[ch])
            out_frames[r, c, k] = min(n + 1.0, cap) if ok else 1.0
            valid[r, c, k] = 1.0 if ok else 0.0
