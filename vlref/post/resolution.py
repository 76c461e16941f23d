"""Reduced-resolution buffers: sizes and the texel-footprint maps every post pass uses.

Conventions (``docs/ARCHITECTURE.md``): arrays are ``(H, W)`` or ``(H, W, C)`` with row 0 at the top.
A texel ``i`` of an axis with ``n`` texels has its centre at ``u = (i + 0.5) / n``; a low-res buffer
of ``n_lo`` texels and its full-res source of ``n_hi`` texels both span ``u`` in ``[0, 1]`` (a Unity
``Blit``), so when ``n_hi`` is not a multiple of the factor the maps below follow the uv, not a
plain ``f * j`` stride. Every map is computed with integer arithmetic, so it is exact.

Unity textures have ``v = 0`` at the *bottom*. Where a source's result depends on that orientation
(rounding at an exact texel edge, a tie order in ``+v``, a pixel parity), the pass takes
``uv_origin``: ``"bottom"`` (Unity, the default there) or ``"top"``. :func:`uv_rows` flips an array
so that its row index grows with ``v``; the maps are symmetric under ``v -> 1 - v`` applied to both
resolutions at once, so a pass runs on flipped inputs and its output is flipped back.
"""

from __future__ import annotations

import numpy as np


RESOLUTION_FACTORS = {"full": 1, "half": 2, "third": 3, "quarter": 4}
UV_ORIGINS = ("top", "bottom")


def check_choice(key: str, value, choices) -> None:
    """Raise :class:`ValueError` unless ``value`` is one of ``choices``."""
    if value not in choices:
        raise ValueError(f"{key}: {value!r} is not one of {', '.join(map(str, choices))}")


def check_positive(key: str, value) -> None:
    """Raise :class:`ValueError` unless ``value`` is a finite number > 0."""
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{key}: must be a finite number > 0, got {value!r}")


def resolution_factor(resolution) -> int:
    """The divisor ``f`` of a resolution name (full 1, half 2, third 3, quarter 4) or of an int ``f >= 1``."""
    if isinstance(resolution, (int, np.integer)) and not isinstance(resolution, bool):
        if resolution < 1:
            raise ValueError(f"resolution: factor must be >= 1, got {resolution}")
        return int(resolution)
    check_choice("resolution", resolution, tuple(RESOLUTION_FACTORS))
    return RESOLUTION_FACTORS[resolution]


def low_res_size(width: int, height: int, resolution) -> tuple[int, int]:
    """``(floor(W / f), floor(H / f))``, the size Unity gives a ``W/f`` render texture (VL §1.1, VM §2.1)."""
    f = resolution_factor(resolution)
    w, h = int(width) // f, int(height) // f
    if w < 1 or h < 1:
        raise ValueError(f"resolution: {width}x{height} divided by {f} leaves no texel")
    return w, h


def uv_rows(a: np.ndarray, uv_origin: str) -> np.ndarray:
    """``a`` with its rows ordered by increasing ``v`` (flipped when ``uv_origin == "bottom"``).

    Our arrays store the top row first; with Unity's ``v = 0`` at the bottom, row ``r`` of an
    ``H``-row array is uv row ``H - 1 - r``. The flip is an involution: apply it again to go back.
    """
    check_choice("uv_origin", uv_origin, UV_ORIGINS)
    return a[::-1] if uv_origin == "bottom" else a


def uv_row_map(index, n_src: int, uv_origin: str) -> np.ndarray:
    """A row map computed in uv rows, re-expressed in array rows.

    ``index[i]`` (first axis: destination row ``i`` counted in increasing ``v``) is the source row
    it reads, also counted in ``v``; the result gives, per destination *array* row, the source's
    *array* row: ``index`` itself for ``"top"``, ``n_src - 1 - index[::-1]`` for ``"bottom"``
    (:func:`uv_rows` applied to both sides). A pass that works in uv rows can thus read its
    top-first arrays in place.
    """
    flipped = uv_rows(np.asarray(index), uv_origin)
    return n_src - 1 - flipped if uv_origin == "bottom" else flipped


def nearest_index(n_src: int, n_dst: int) -> np.ndarray:
    """The source texel a point sampler returns at each destination texel centre.

    ``floor(u * n_src)`` with ``u = (i + 0.5) / n_dst``, i.e. ``floor((2i + 1) n_src / (2 n_dst))``,
    clamped to ``[0, n_src - 1]``. An exact texel edge goes to the *upper* texel (D3D's 8-bit
    sub-texel fixed point, SOURCES §2.3/§6.5): with ``f = 2`` low-res texel ``j`` reads full-res
    texel ``2j + 1``, with ``f = 3`` texel ``3j + 1``, with ``f = 4`` texel ``4j + 2``; full-res
    texel ``i`` reads low-res texel ``floor(i / f)``.
    """
    i = np.arange(n_dst, dtype=np.int64)
    return np.minimum(((2 * i + 1) * n_src) // (2 * n_dst), n_src - 1)


def point_texel(u, n: int, subtexel_bits: int = 8) -> np.ndarray:
    """Point-sampled texel index at uv ``u`` on ``n`` texels, clamp addressing.

    The texel coordinate ``u n`` is first rounded to ``subtexel_bits`` fractional bits (D3D's 8-bit
    sub-texel precision [K], SOURCES §6.5), so a coordinate a rounding error below a texel edge
    reads the upper texel as the GPU does; then ``floor`` and clamp to ``[0, n - 1]``.
    """
    scale = float(1 << subtexel_bits)
    return np.clip(np.floor(np.rint(np.asarray(u, dtype=np.float64) * n * scale) / scale), 0, n - 1).astype(np.int64)


def block_ranges(n_hi: int, n_lo: int) -> tuple[np.ndarray, np.ndarray]:
    """The full-res texels ``[start, stop)`` whose area overlaps low-res texel ``j``.

    ``start = floor(j n_hi / n_lo)``, ``stop = ceil((j + 1) n_hi / n_lo)``: exactly the ``f x f``
    block ``f j .. f j + f - 1`` when ``n_hi = f n_lo``; with a remainder, the blocks overlap by a
    texel and cover every full-res texel (so a min over them is never deeper than any pixel it
    represents).
    """
    j = np.arange(n_lo, dtype=np.int64)
    return (j * n_hi) // n_lo, -((-(j + 1) * n_hi) // n_lo)


def gather_footprint(n_hi: int, n_lo: int) -> tuple[np.ndarray, np.ndarray]:
    """The two texels (per axis) a ``Gather`` at low-res centre ``j`` reads from ``n_hi`` texels.

    ``i0 = floor(u n_hi - 1/2)`` with ``u = (j + 0.5) / n_lo``, computed exactly as
    ``floor(((2j + 1) n_hi - n_lo) / (2 n_lo))``, and ``i1 = i0 + 1``, both clamped to
    ``[0, n_hi - 1]`` (``2j`` and ``2j + 1`` when ``n_hi = 2 n_lo``; VL §1.8).
    """
    j = np.arange(n_lo, dtype=np.int64)
    i0 = ((2 * j + 1) * n_hi - n_lo) // (2 * n_lo)
    return np.clip(i0, 0, n_hi - 1), np.clip(i0 + 1, 0, n_hi - 1)


def bilinear_footprint(n_lo: int, n_hi: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The two low-res texels and the weight of the second one for each full-res texel centre.

    With ``p = u n_lo - 1/2`` and ``u = (i + 0.5) / n_hi`` (computed exactly from the integer
    ``(2i + 1) n_lo - n_hi`` over ``2 n_hi``): ``i0 = floor(p)``, ``i1 = i0 + 1`` and
    ``t = p - i0``; indices are clamped to ``[0, n_lo - 1]`` (clamp addressing). For ``f = 2``,
    ``t`` is 0.75 or 0.25, so the 2-D weights are the thesis's 9/16, 3/16, 3/16, 1/16.
    """
    i = np.arange(n_hi, dtype=np.int64)
    num = (2 * i + 1) * n_lo - n_hi
    i0 = num // (2 * n_hi)
    t = (num - i0 * 2 * n_hi) / float(2 * n_hi)
    return np.clip(i0, 0, n_lo - 1), np.clip(i0 + 1, 0, n_lo - 1), t
