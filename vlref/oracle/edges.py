"""Where a conformant rasteriser may legitimately differ from vlref: the edge zone of a comparison.

A rasteriser samples triangles at pixel centres, tessellates curved surfaces and quantises depth, and
a shadow map decides lit / shadowed per texel; two faithful renderers of one scene then differ only
*near geometry*: within a pixel or two of a depth discontinuity (a silhouette moves by a fraction of a
pixel) and within a texel or two of a shadow silhouette (the map's caster edge moves by a fraction of a
texel). :mod:`vlref.oracle.compare` applies its looser per-pixel tolerance (``edge_rel_tol``,
``edge_abs_tol``) in this zone only and allows no failing pixel outside it.

The zone is a width in pixels (``edge_pixels`` = k) around geometric features, so its share of the
image falls as ``1/resolution`` (a silhouette's length grows as W, the image's area as W²): the
allowance does not grow with the image, unlike a failing-pixel fraction. The shadow zone is a width in
the *light's* texels, so its share of the image is set by the map's resolution and stays constant as the
image grows; it does not grow either.

* :func:`depth_discontinuities`: pixels where inverse depth (affine over a plane in screen space) bends
  by more than ``DEPTH_JUMP`` of itself between neighbours: silhouettes, creases, sky next to a surface;
* :func:`dilate`: grown by k pixels in the chessboard metric (a (2k+1)² square);
* :func:`block_any`: a full-resolution zone carried to a lower-resolution buffer (a texel is in the
  zone when any pixel of its block is).

Shadow silhouettes measured in the light's texels are in :func:`vlref.oracle.verdict.silhouette_zone` (the
shading comparisons) and :func:`vlref.oracle.verdict.shadow_zone` (bias-sensitive map decisions).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

__all__ = ["DEPTH_JUMP", "depth_discontinuities", "dilate", "edge_zone", "block_any"]

DEPTH_JUMP = 0.05
"""Second difference of inverse depth, relative to the local inverse depth, that counts as a
discontinuity (:func:`depth_discontinuities`); zero on planes, ~``(pixel footprint / radius)²`` on a curved
surface, of order 1 at a silhouette."""


def depth_discontinuities(depth: np.ndarray, jump: float = DEPTH_JUMP) -> np.ndarray:
    """(H, W) bool: pixels at a depth discontinuity of ``depth`` (eye depth, inf = sky).

    Inverse depth ``w = 1/z`` (sky: 0) is affine in screen coordinates over a plane, so its second difference
    along a row or column vanishes there at every resolution and grazing angle; three consecutive pixels
    ``a, b, c`` are all marked where ``|a - 2b + c| > jump · max(a, b, c)``: a silhouette, a crease, or sky
    next to a surface."""
    z = np.asarray(depth, dtype=np.float64)
    ok = np.isfinite(z) & (z > 0)
    w = np.where(ok, 1.0 / np.where(ok, z, 1.0), 0.0)
    out = np.zeros(w.shape, bool)
    for axis in (0, 1):
        n = w.shape[axis]
        if n < 3:
            continue
        a, b, c = (np.take(w, range(k, n - 2 + k), axis=axis) for k in range(3))
        hit = np.abs(a - 2.0 * b + c) > jump * np.maximum(np.maximum(a, b), c)
        for k in range(3):
            index = [slice(None)] * 2
            index[axis] = slice(k, n - 2 + k)
            out[tuple(index)] |= hit
    return out


def dilate(mask: np.ndarray, k: int) -> np.ndarray:
    """``mask`` grown by ``k`` pixels (chessboard distance <= k)."""
    m = np.asarray(mask, dtype=bool)
    if k <= 0 or not m.any():
        return m.copy()
    return ndimage.binary_dilation(m, structure=np.ones((3, 3), bool), iterations=int(k))


def edge_zone(k: int, depths=(), features=()) -> np.ndarray:
    """The edge zone: depth discontinuities of every image in ``depths`` and the ``features`` (bool
    masks of other silhouettes, e.g. :func:`vlref.oracle.verdict.shadow_zone` on the image) together, dilated
    by ``k`` pixels. Needs at least one input."""
    masks = [depth_discontinuities(z) for z in depths] + [np.asarray(f, dtype=bool) for f in features]
    if not masks:
        raise ValueError("edge_zone needs a depth image or a feature mask")
    return dilate(np.logical_or.reduce(masks), k)


def block_any(mask: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """A full-resolution (H, W) ``mask`` on an (h, w) buffer of a technique at ``1/f`` resolution (``h =
    H // f``, vlref's and a port's rounding): texel (i, j) covers pixels ``[i·f, (i+1)·f)`` per axis (the last
    row and column also the pixels left over when f does not divide the size) and is true when any is."""
    m = np.asarray(mask, dtype=bool)
    H, W = m.shape
    h, w = shape
    fy, fx = H // h, W // w
    out = m[:h * fy, :w * fx].reshape(h, fy, w, fx).any(axis=(1, 3))
    out[-1, :] |= m[h * fy:, :w * fx].reshape(-1, w, fx).any(axis=(0, 2))
    out[:, -1] |= m[:, w * fx:].any(axis=1)[:h * fy].reshape(h, fy).any(axis=1)
    out[-1, -1] |= m[h * fy:, w * fx:].any()
    return out
