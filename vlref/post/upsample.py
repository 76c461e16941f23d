"""Upsampling a low-res buffer to full resolution: plain and depth-aware, one function per source.

Every function maps low-res ``lo`` ``(h, w[, C])`` onto the full-res grid ``(H, W)``; full-res texel
centres map to low-res coordinates through :func:`~vlref.post.resolution.bilinear_footprint`
(texels ``i0``, ``i1 = i0 + 1``, weight ``t`` of ``i1``, clamp addressing) or
:func:`~vlref.post.resolution.nearest_index`. Depth differences use
:func:`vlref.post.blur.depth_delta` (``inf`` matches ``inf``).

Hardware bilinear is evaluated as ``a + t (b - a)`` along x, then along y, so a constant image
stays bit-for-bit constant; GPUs quantise ``t`` to about 8 bits [K] (exact for ``f = 2``, where
``t`` is 0.25 or 0.75).
"""

from __future__ import annotations

import numpy as np

from vlref.errors import InputError
from vlref.post.blur import depth_delta
from vlref.post.resolution import ARGUMENTS, bilinear_footprint, check_positive, nearest_index, uv_rows


def _lerp(a, b, t):
    return a + t * (b - a)


def _lo(lo) -> np.ndarray:
    a = np.asarray(lo, dtype=np.float64)
    if a.ndim not in (2, 3):
        raise InputError(ARGUMENTS, "lo", f"expected (h, w) or (h, w, C), got shape {a.shape}")
    return a


def _expand(t, a):
    """Broadcast an (H, W) weight over the channel axis of ``a``."""
    return t[..., None] if a.ndim == 3 else t


def _footprint(lo: np.ndarray, shape_hi):
    """The four low-res texels of each full-res centre, as (H, W[, C]) arrays, and (tx, ty) (H, W)."""
    H, W = shape_hi
    r0, r1, ty = bilinear_footprint(lo.shape[0], H)
    c0, c1, tx = bilinear_footprint(lo.shape[1], W)
    taps = {(a, b): lo[r][:, c] for a, c in ((0, c0), (1, c1)) for b, r in ((0, r0), (1, r1))}
    tx2, ty2 = np.broadcast_to(tx[None, :], (H, W)), np.broadcast_to(ty[:, None], (H, W))
    return taps, tx2, ty2, (r0, r1, c0, c1)


def _bilinear(taps, tx, ty, lo):
    tx, ty = _expand(tx, lo), _expand(ty, lo)
    return _lerp(_lerp(taps[0, 0], taps[1, 0], tx), _lerp(taps[0, 1], taps[1, 1], tx), ty)


def bilinear_upsample(lo, shape_hi) -> np.ndarray:
    """Hardware bilinear sample of ``lo`` at every full-res texel centre (clamp addressing)."""
    lo = _lo(lo)
    taps, tx, ty, _ = _footprint(lo, shape_hi)
    return _bilinear(taps, tx, ty, lo)


def nearest_upsample(lo, shape_hi, uv_origin: str = "bottom") -> np.ndarray:
    """Point sample of ``lo`` at every full-res texel centre (``nearest_index``; edges go up in uv)."""
    lo = uv_rows(_lo(lo), uv_origin)
    H, W = shape_hi
    return uv_rows(lo[nearest_index(lo.shape[0], H)][:, nearest_index(lo.shape[1], W)], uv_origin).copy()


def _depths(depth_lo, depth_hi, lo):
    zl, zh = np.asarray(depth_lo, dtype=np.float64), np.asarray(depth_hi, dtype=np.float64)
    if zl.shape != lo.shape[:2] or zh.ndim != 2:
        raise InputError(ARGUMENTS, "depth", f"low-res depth {zl.shape} must match {lo.shape[:2]}; "
                                             f"full-res depth must be (H, W), got {zh.shape}")
    return zl, zh


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
    taps, tx, ty, (r0, r1, c0, c1) = _footprint(lo, zh.shape)
    zt = {(a, b): zl[r][:, c] for a, c in ((0, c0), (1, c1)) for b, r in ((0, r0), (1, r1))}
    order = ((0, 0), (1, 0), (0, 1), (1, 1))
    bil = {(a, b): (tx if a else 1.0 - tx) * (ty if b else 1.0 - ty) for a, b in order}
    w = {k: bil[k] / (depth_delta(zh, zt[k]) + epsilon) for k in order}
    wsum = w[order[0]] + w[order[1]] + w[order[2]] + w[order[3]]
    dead = wsum == 0.0
    if dead.any():
        w = {k: np.where(dead, bil[k], w[k]) for k in order}
        wsum = np.where(dead, bil[order[0]] + bil[order[1]] + bil[order[2]] + bil[order[3]], wsum)
    acc = 0.0
    for k in order:
        acc = acc + _expand(w[k], lo) * taps[k]
    return acc / _expand(wsum, lo)


def vl_upsample(lo, depth_lo, depth_hi, threshold: float = 1.5, uv_origin: str = "bottom") -> np.ndarray:
    """VolumetricLights' ``BilateralUpsample`` (research §1.10), on linear eye depth in metres.

    The four low-res texels ``00, 10, 01, 11`` of the bilinear footprint (``1`` = ``+u`` / ``+v``)
    give ``d_k = |z_hi - z_k|``. If ``((d00 + d10) + d01) + d11 < threshold``
    (``UPSAMPLE_DEPTH_THRESHOLD 1.5``) the output is the hardware-bilinear sample, else the texel
    with the smallest ``d_k``, ties kept by strict ``<`` in the order ``00, 10, 01, 11``. ``+v`` is
    *up* in Unity: with ``uv_origin="bottom"`` texel ``01`` is the footprint's upper row.
    """
    lo = uv_rows(_lo(lo), uv_origin)
    zl, zh = _depths(uv_rows(np.asarray(depth_lo), uv_origin), uv_rows(np.asarray(depth_hi), uv_origin), lo)
    taps, tx, ty, (r0, r1, c0, c1) = _footprint(lo, zh.shape)
    order = ((0, 0), (1, 0), (0, 1), (1, 1))
    d = {(a, b): depth_delta(zh, zl[r][:, c]) for a, c in ((0, c0), (1, c1)) for b, r in ((0, r0), (1, r1))}
    best, best_d = taps[order[0]], d[order[0]]
    for k in order[1:]:
        closer = d[k] < best_d
        best = np.where(_expand(closer, lo), taps[k], best)
        best_d = np.where(closer, d[k], best_d)
    bilinear = _bilinear(taps, tx, ty, lo)
    smooth = ((d[0, 0] + d[1, 0]) + d[0, 1]) + d[1, 1] < threshold
    return uv_rows(np.where(_expand(smooth, lo), bilinear, best), uv_origin)


URP_NEIGHBOURS = ((0, 1), (0, -1), (1, 0), (-1, 0))
"""The URP tutorial's candidate offsets ``(du, dv)`` in low-res texels, in tie-breaking order (§2.7)."""


def urp_upsample(fog_lo, depth_lo, depth_hi, neighbours=URP_NEIGHBOURS, uv_origin: str = "bottom") -> np.ndarray:
    """The URP tutorial's nearest-depth upsample (pass 3, research §2.7), on raw depth.

    Full-res texel ``i`` starts from the low-res texel under it (``nearest_index``: ``floor(i / f)``)
    and considers only the cross neighbours ``(0,+1), (0,-1), (+1,0), (-1,0)`` (clamp addressing) --
    the co-located texel is never a candidate. The first candidate with the smallest
    ``|z_hi - z_k|`` wins, and its fog value is returned. With ``uv_origin="bottom"`` ``+v`` is up,
    so on flat depth every pixel takes the texel *above* it (one low-res row toward the top of
    our arrays); ``"top"`` makes ``+v`` point down the rows.
    """
    lo = uv_rows(_lo(fog_lo), uv_origin)
    zl, zh = _depths(uv_rows(np.asarray(depth_lo), uv_origin), uv_rows(np.asarray(depth_hi), uv_origin), lo)
    h, w = lo.shape[:2]
    rows = nearest_index(h, zh.shape[0])[:, None]
    cols = nearest_index(w, zh.shape[1])[None, :]
    best = best_d = None
    for du, dv in neighbours:
        r, c = np.clip(rows + dv, 0, h - 1), np.clip(cols + du, 0, w - 1)
        dk = depth_delta(zh, zl[r, c])
        if best is None:
            best, best_d = lo[r, c], dk
            continue
        closer = dk < best_d
        best = np.where(_expand(closer, lo), lo[r, c], best)
        best_d = np.where(closer, dk, best_d)
    return uv_rows(best, uv_origin)
