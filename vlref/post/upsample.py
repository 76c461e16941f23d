"""Upsampling a low-res buffer to full resolution: plain and depth-aware, one function per source.

Every function maps low-res ``lo`` ``(h, w[, C])`` onto the full-res grid ``(H, W)``; full-res texel
centres map to low-res coordinates through :func:`~vlref.post.resolution.bilinear_footprint`
(texels ``i0``, ``i1 = i0 + 1``, weight ``t`` of ``i1``, clamp addressing) or
:func:`~vlref.post.resolution.nearest_index`. Depth differences use
:func:`vlref.post.blur.depth_delta_at` (``inf`` matches ``inf``).

The depth-aware passes are Numba kernels, one output pixel per iteration (``prange`` over rows),
so the bits do not depend on the thread count. Passes defined in Unity's uv (``+v`` up) take
``uv_origin`` and read our top-first arrays in place through
:func:`~vlref.post.resolution.uv_row_map`.

Hardware bilinear is evaluated as ``a + t (b - a)`` along x, then along y, so a constant image
stays bit-for-bit constant; GPUs quantise ``t`` to about 8 bits [K] (exact for ``f = 2``, where
``t`` is 0.25 or 0.75).
"""

from __future__ import annotations

import numpy as np
from numba import prange

from vlref.jit import njit
from vlref.post.blur import depth_delta_at
from vlref.post.resolution import (bilinear_footprint, check_positive, nearest_index, uv_row_map,
                                   uv_rows)


def _lo(lo) -> np.ndarray:
    a = np.asarray(lo, dtype=np.float64)
    if a.ndim not in (2, 3):
        raise ValueError(f"lo: expected (h, w) or (h, w, C), got shape {a.shape}")
    return a


def _channels(a: np.ndarray) -> np.ndarray:
    """``a`` as a C-contiguous ``(h, w, C)`` array (``C = 1`` for a 2-D buffer), without copying if possible."""
    return np.ascontiguousarray(a).reshape(a.shape[0], a.shape[1], -1)


def _footprint(lo_shape, shape_hi, uv_origin: str = "top"):
    """Per full-res row and column, in array order: the footprint's low-res rows ``(ra, rb)`` and
    columns ``(ca, cb)`` (``a`` the ``0`` texel, ``b`` the ``1`` texel in uv) and the weights
    ``ty``, ``tx`` of ``rb``, ``cb`` (:func:`~vlref.post.resolution.bilinear_footprint`)."""
    H, W = shape_hi
    r0, r1, ty = bilinear_footprint(lo_shape[0], H)
    c0, c1, tx = bilinear_footprint(lo_shape[1], W)
    ra, rb = uv_row_map(r0, lo_shape[0], uv_origin), uv_row_map(r1, lo_shape[0], uv_origin)
    return ra, rb, np.ascontiguousarray(uv_rows(ty, uv_origin)), c0, c1, tx


@njit(cache=True, fastmath=False)
def _lerp(a, b, t):
    return a + t * (b - a)


@njit(cache=True, fastmath=False)
def _bilerp(lo, ra, rb, ca, cb, tx, ty, ch):
    """Hardware bilinear: ``a + t (b - a)`` along x on rows ``ra`` and ``rb``, then along y."""
    return _lerp(_lerp(lo[ra, ca, ch], lo[ra, cb, ch], tx), _lerp(lo[rb, ca, ch], lo[rb, cb, ch], tx), ty)


@njit(cache=True, fastmath=False, parallel=True)
def _bilinear_kernel(lo, ra, rb, ty, ca, cb, tx, out):
    H, W, C = out.shape
    for r in prange(H):
        for c in range(W):
            for ch in range(C):
                out[r, c, ch] = _bilerp(lo, ra[r], rb[r], ca[c], cb[c], tx[c], ty[r], ch)


def bilinear_upsample(lo, shape_hi) -> np.ndarray:
    """Hardware bilinear sample of ``lo`` at every full-res texel centre (clamp addressing)."""
    lo = _lo(lo)
    H, W = shape_hi
    out = np.empty((H, W) + lo.shape[2:])
    _bilinear_kernel(_channels(lo), *_footprint(lo.shape, (H, W)), out.reshape(H, W, -1))
    return out


def nearest_upsample(lo, shape_hi, uv_origin: str = "bottom") -> np.ndarray:
    """Point sample of ``lo`` at every full-res texel centre (``nearest_index``; edges go up in uv)."""
    lo = uv_rows(_lo(lo), uv_origin)
    H, W = shape_hi
    return uv_rows(lo[nearest_index(lo.shape[0], H)][:, nearest_index(lo.shape[1], W)], uv_origin).copy()


def _depths(depth_lo, depth_hi, lo):
    zl, zh = np.asarray(depth_lo, dtype=np.float64), np.asarray(depth_hi, dtype=np.float64)
    if zl.shape != lo.shape[:2] or zh.ndim != 2:
        raise ValueError(f"depth: low-res depth {zl.shape} must match {lo.shape[:2]}; "
                                             f"full-res depth must be (H, W), got {zh.shape}")
    return np.ascontiguousarray(zl), np.ascontiguousarray(zh)


@njit(cache=True, fastmath=False, parallel=True)
def _thesis_kernel(lo, zl, zh, ra, rb, ty, ca, cb, tx, epsilon, out):
    """Taps ``00, 10, 01, 11``: ``w_k = b_k / (dz_k + eps)``, ``sum w_k v_k / sum w_k`` summed in that order."""
    H, W, C = out.shape
    for r in prange(H):
        for c in range(W):
            z = zh[r, c]
            bx, by = tx[c], ty[r]
            b00, b10, b01, b11 = (1.0 - bx) * (1.0 - by), bx * (1.0 - by), (1.0 - bx) * by, bx * by
            r0, r1, c0, c1 = ra[r], rb[r], ca[c], cb[c]
            w00 = b00 / (depth_delta_at(z, zl[r0, c0]) + epsilon)
            w10 = b10 / (depth_delta_at(z, zl[r0, c1]) + epsilon)
            w01 = b01 / (depth_delta_at(z, zl[r1, c0]) + epsilon)
            w11 = b11 / (depth_delta_at(z, zl[r1, c1]) + epsilon)
            wsum = ((w00 + w10) + w01) + w11
            if wsum == 0.0:                   # every tap infinitely far: the bilinear weights alone
                w00, w10, w01, w11 = b00, b10, b01, b11
                wsum = ((b00 + b10) + b01) + b11
            for ch in range(C):
                acc = ((0.0 + w00 * lo[r0, c0, ch]) + w10 * lo[r0, c1, ch]) + w01 * lo[r1, c0, ch]
                out[r, c, ch] = (acc + w11 * lo[r1, c1, ch]) / wsum


def thesis_upsample(lo, depth_lo, depth_hi, epsilon: float = 1e-3) -> np.ndarray:
    """The thesis's depth-aware bilateral upsample (§4.2.4), on linear eye depth in metres.

    For the four nearest low-res texels ``k`` (order ``00, 10, 01, 11``, x first, row 0 = top):
    bilinear weight ``b_k`` (9/16, 3/16, 3/16, 1/16 at half resolution), divided by the depth
    difference: ``w_k = b_k / (|z_hi - z_k| + epsilon)``; output ``sum w_k v_k / sum w_k``.
    ``epsilon`` (metres, default 1e-3) is ours: the thesis divides by the bare difference, which is
    0 on flat regions. A tap whose difference is infinite (sky against a surface) gets weight 0; if
    all four do, the bilinear weights are used alone, so the result is always finite.
    """
    check_positive("epsilon", epsilon)
    lo = _lo(lo)
    zl, zh = _depths(depth_lo, depth_hi, lo)
    out = np.empty(zh.shape + lo.shape[2:])
    _thesis_kernel(_channels(lo), zl, zh, *_footprint(lo.shape, zh.shape), float(epsilon),
                   out.reshape(zh.shape[0], zh.shape[1], -1))
    return out


@njit(cache=True, fastmath=False, parallel=True)
def _vl_kernel(lo, zl, zh, ra, rb, ty, ca, cb, tx, threshold, out):
    """Bilinear where ``((d00 + d10) + d01) + d11 < threshold``, else the first texel of least ``d``."""
    H, W, C = out.shape
    for r in prange(H):
        for c in range(W):
            z = zh[r, c]
            r0, r1, c0, c1 = ra[r], rb[r], ca[c], cb[c]
            d00, d10 = depth_delta_at(z, zl[r0, c0]), depth_delta_at(z, zl[r0, c1])
            d01, d11 = depth_delta_at(z, zl[r1, c0]), depth_delta_at(z, zl[r1, c1])
            if ((d00 + d10) + d01) + d11 < threshold:
                for ch in range(C):
                    out[r, c, ch] = _bilerp(lo, r0, r1, c0, c1, tx[c], ty[r], ch)
                continue
            br, bc, bd = r0, c0, d00
            if d10 < bd:
                br, bc, bd = r0, c1, d10
            if d01 < bd:
                br, bc, bd = r1, c0, d01
            if d11 < bd:
                br, bc = r1, c1
            for ch in range(C):
                out[r, c, ch] = lo[br, bc, ch]


def vl_upsample(lo, depth_lo, depth_hi, threshold: float = 1.5, uv_origin: str = "bottom") -> np.ndarray:
    """VolumetricLights' ``BilateralUpsample`` (SOURCES §1.10), on linear eye depth in metres.

    The four low-res texels ``00, 10, 01, 11`` of the bilinear footprint (``1`` = ``+u`` / ``+v``)
    give ``d_k = |z_hi - z_k|``. If ``((d00 + d10) + d01) + d11 < threshold``
    (``UPSAMPLE_DEPTH_THRESHOLD 1.5``) the output is the hardware-bilinear sample, else the texel
    with the smallest ``d_k``, ties kept by strict ``<`` in the order ``00, 10, 01, 11``. ``+v`` is
    *up* in Unity: with ``uv_origin="bottom"`` texel ``01`` is the footprint's upper row.
    """
    lo = _lo(lo)
    zl, zh = _depths(depth_lo, depth_hi, lo)
    out = np.empty(zh.shape + lo.shape[2:])
    _vl_kernel(_channels(lo), zl, zh, *_footprint(lo.shape, zh.shape, uv_origin), float(threshold),
               out.reshape(zh.shape[0], zh.shape[1], -1))
    return out


URP_NEIGHBOURS = ((0, 1), (0, -1), (1, 0), (-1, 0))
"""The URP tutorial's candidate offsets ``(du, dv)`` in low-res texels, in tie-breaking order (§2.7)."""


@njit(cache=True, fastmath=False, parallel=True)
def _nearest_depth_kernel(lo, zl, zh, rows, cols, out):
    """Candidate ``t`` of full-res ``(r, c)`` is low-res ``(rows[r, t], cols[c, t])``; the first of least ``d`` wins."""
    H, W, C = out.shape
    for r in prange(H):
        for c in range(W):
            z = zh[r, c]
            br, bc = rows[r, 0], cols[c, 0]
            bd = depth_delta_at(z, zl[br, bc])
            for t in range(1, rows.shape[1]):
                d = depth_delta_at(z, zl[rows[r, t], cols[c, t]])
                if d < bd:
                    br, bc, bd = rows[r, t], cols[c, t], d
            for ch in range(C):
                out[r, c, ch] = lo[br, bc, ch]


def urp_upsample(fog_lo, depth_lo, depth_hi, neighbours=URP_NEIGHBOURS, uv_origin: str = "bottom") -> np.ndarray:
    """The URP tutorial's nearest-depth upsample (pass 3, SOURCES §2.7), on raw depth.

    Full-res texel ``i`` starts from the low-res texel under it (``nearest_index``: ``floor(i / f)``)
    and considers only the cross neighbours ``(0,+1), (0,-1), (+1,0), (-1,0)`` (clamp addressing) --
    the co-located texel is never a candidate. The first candidate with the smallest
    ``|z_hi - z_k|`` wins, and its fog value is returned. With ``uv_origin="bottom"`` ``+v`` is up,
    so on flat depth every pixel takes the texel *above* it (one low-res row toward the top of
    our arrays); ``"top"`` makes ``+v`` point down the rows.
    """
    lo = _lo(fog_lo)
    zl, zh = _depths(depth_lo, depth_hi, lo)
    if len(neighbours) == 0:
        raise ValueError("neighbours: need at least one candidate offset")
    h, w = lo.shape[:2]
    du, dv = np.array([n[0] for n in neighbours]), np.array([n[1] for n in neighbours])
    rows = np.clip(nearest_index(h, zh.shape[0])[:, None] + dv[None, :], 0, h - 1)
    cols = np.clip(nearest_index(w, zh.shape[1])[:, None] + du[None, :], 0, w - 1)
    out = np.empty(zh.shape + lo.shape[2:])
    _nearest_depth_kernel(_channels(lo), zl, zh, np.ascontiguousarray(uv_row_map(rows, h, uv_origin)),
                          cols, out.reshape(zh.shape[0], zh.shape[1], -1))
    return out
