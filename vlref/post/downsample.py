"""Depth downsampling to the reduced calculation resolution (one function per source rule).

* :func:`downsample_min` / :func:`downsample_max`: the closest / farthest surface of each low-res
  texel's block of full-res pixels, on **linear eye depth** (thesis §4.2.3: "finding the smallest
  value using a min function ... the closest surface in all these pixels"). The block is
  :func:`~vlref.post.resolution.block_ranges` (the ``f x f`` block when the size divides).
  ``inf`` (sky) is an ordinary value here.
* :func:`downsample_chessboard`: VolumetricLights' ``DOWNSAMPLE_DEPTH_MODE 2`` (SOURCES §1.8) on
  **raw device depth**, one halving step; :func:`downsample_vl` chains it (quarter = twice half).
* :func:`downsample_point`: the URP tutorial's pass 4 (SOURCES §2.6), a point sample of the raw
  full-res depth at the low-res texel centre.

The raw-depth rules operate on the array exactly as given: ``min`` of raw depth is the nearest
surface with standard Z (0 at near) and the *farthest* with reversed Z (1 at near), just as on the
GPU, so encode the depth with the convention being emulated (``vlref.camera.linear_to_raw``).
"""

from __future__ import annotations

import numpy as np

from vlref.post.resolution import (block_ranges, check_choice, gather_footprint, low_res_size,
                                   nearest_index, resolution_factor, uv_rows)


def _block_reduce(a: np.ndarray, n_lo: int, axis: int, ufunc) -> np.ndarray:
    start, stop = block_ranges(a.shape[axis], n_lo)
    out = a.take(start, axis=axis)
    for d in range(1, int((stop - start).max())):
        out = ufunc(out, a.take(np.minimum(start + d, stop - 1), axis=axis))
    return out


def _check_depth(depth) -> np.ndarray:
    depth = np.asarray(depth)
    if depth.ndim != 2:
        raise ValueError(f"depth: expected an (H, W) depth buffer, got shape {depth.shape}")
    return depth


def _block(depth, resolution, ufunc) -> np.ndarray:
    depth = _check_depth(depth)
    w, h = low_res_size(depth.shape[1], depth.shape[0], resolution)
    return _block_reduce(_block_reduce(depth, h, 0, ufunc), w, 1, ufunc)


def downsample_min(depth, resolution) -> np.ndarray:
    """Min of each low-res texel's full-res block: ``(floor(H/f), floor(W/f))``, same dtype."""
    return _block(depth, resolution, np.minimum)


def downsample_max(depth, resolution) -> np.ndarray:
    """Max of each low-res texel's full-res block: ``(floor(H/f), floor(W/f))``, same dtype."""
    return _block(depth, resolution, np.maximum)


def downsample_chessboard(raw, uv_origin: str = "bottom") -> np.ndarray:
    """One VL chessboard step: raw depth ``(H, W)`` -> ``(floor(H/2), floor(W/2))``.

    Low-res texel ``(j, k)`` (column, uv row) gathers the 2x2 footprint at its centre
    (:func:`~vlref.post.resolution.gather_footprint`, ``2j..2j+1`` for even sizes) and returns
    ``min`` of the four raw depths when ``q = (j mod 2) + (k mod 2) == 1``, else ``max``.

    The parity uses the shader's ``SV_Position`` of the target, whose row index Unity counts from
    the image's *bottom* both on GL (window origin) and on D3D (Unity renders render textures
    flipped) [I]; ``uv_origin="bottom"`` counts ``k`` from the bottom row of our top-first arrays,
    ``"top"`` from the top row (a port that counts pixel rows from the top).
    """
    raw = uv_rows(_check_depth(raw), uv_origin)
    w, h = low_res_size(raw.shape[1], raw.shape[0], 2)
    r0, r1 = gather_footprint(raw.shape[0], h)
    c0, c1 = gather_footprint(raw.shape[1], w)
    taps = [raw[r][:, c] for r in (r0, r1) for c in (c0, c1)]
    lo = np.minimum(np.minimum(taps[0], taps[1]), np.minimum(taps[2], taps[3]))
    hi = np.maximum(np.maximum(taps[0], taps[1]), np.maximum(taps[2], taps[3]))
    q = (np.arange(h)[:, None] % 2) + (np.arange(w)[None, :] % 2)
    return uv_rows(np.where(q == 1, lo, hi), uv_origin)


def downsample_vl(raw, resolution, uv_origin: str = "bottom") -> np.ndarray:
    """VL's depth buffer at ``resolution``: full -> a copy, half -> one chessboard step, quarter -> two.

    Quarter downsamples the *half-res chessboard result* (passes 4 then 6, SOURCES §1.8), so its
    size is ``floor(floor(W/2)/2) = floor(W/4)``.
    """
    check_choice("resolution", resolution, ("full", "half", "quarter"))
    out = np.array(_check_depth(raw), copy=True)
    for _ in range({"full": 0, "half": 1, "quarter": 2}[resolution]):
        out = downsample_chessboard(out, uv_origin)
    return out


def downsample_point(raw, resolution, uv_origin: str = "bottom") -> np.ndarray:
    """The full-res texel a point sampler returns at each low-res texel centre (URP pass 4).

    :func:`~vlref.post.resolution.nearest_index` per axis: with ``f = 2`` uv column ``2j + 1`` and
    uv row ``2k + 1`` (exact texel edges go to the upper texel in uv); ``f = 3`` -> ``3j + 1``;
    ``f = 4`` -> ``4j + 2``. With ``uv_origin="bottom"`` the row rule applies counting from the
    bottom, so for even ``H`` and ``f = 2`` low-res row ``r`` (from the top) reads full-res row
    ``2r``. The source then remaps ``2z - 1`` on GL and stores R16 UNORM; compose those with
    ``vlref.post.composite.unorm16`` where emulated.
    """
    f = resolution_factor(resolution)
    raw = uv_rows(_check_depth(raw), uv_origin)
    w, h = low_res_size(raw.shape[1], raw.shape[0], f)
    out = raw[nearest_index(raw.shape[0], h)][:, nearest_index(raw.shape[1], w)]
    return uv_rows(out, uv_origin).copy()
