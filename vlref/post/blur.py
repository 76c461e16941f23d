"""Separable depth-aware ("bilateral") Gaussian blur: one function per pass and per source.

Each ``*_pass(values, depth, axis, ...)`` blurs along ``axis`` (1 = horizontal, 0 = vertical) and
returns its buffer; a source's blur is its horizontal pass followed by its vertical pass on the
result (:func:`blur_hv`). ``values`` is ``(H, W)`` or ``(H, W, C)``; every pass computes

    out = sum_k G_k W_k v_k / sum_k G_k W_k,

accumulated in the source's tap order (listed per pass) in float64. Taps beyond the image use
clamp addressing (the sources' RT wrap modes are [U], SOURCES §1.9/§7).

Depth weight ``W_k`` of a tap with depth difference ``dz = |z_k - z_0|`` (:func:`depth_delta`, with
``inf - inf = 0`` so sky matches sky): ``"gaussian"`` ``exp(-(dz * c) * (dz * c))`` (VL, URP) or
``"inverse"`` ``1 / (dz + eps)`` (the thesis's "in the same way as the bilateral up-sampling").

The URP passes run one Numba kernel (:func:`_blur_lines`) over tap tables built here: per texel along
the axis, the value texel and depth texel of each tap, in summation order. Vertical maps of the
passes defined in Unity's uv are turned into array rows (:func:`~vlref.post.resolution.uv_row_map`).
:func:`bilateral_pass` (thesis, VL), whose taps are symmetric integer offsets, runs
:func:`_bilateral_lines`: the same sums, each depth weight computed once for its pair of texels.
"""

from __future__ import annotations

import math

import numpy as np
from numba import get_num_threads, prange

from vlref.jit import njit
from vlref.numeric import arrays_do_not_overlap, glibc_exp, glibc_exp_normal, prefer_wide_vectors
from vlref.parallel import borrowed
from vlref.post.resolution import check_choice, check_positive, nearest_index, point_texel, uv_row_map

VL_KERNEL_RADIUS = {"full": 7, "half": 5, "quarter": 6}
"""``FULL/HALF/QUARTER_RES_BLUR_KERNEL_SIZE`` of VL's ``BilateralBlur.shader``."""

URP_GAUSS_WEIGHTS = (0.14446445, 0.13543542, 0.11153505, 0.08055309, 0.05087564, 0.02798160, 0.01332457,
                     0.00545096)
"""``gauss_filter_weights[0..7]`` of the URP tutorial (SOURCES §2.5)."""

DEPTH_WEIGHTS = ("gaussian", "inverse")

_GAUSSIAN, _UNIT, _INVERSE = 0, 1, 2   # depth-weight codes of the kernels (_UNIT: gaussian with factor 0)


def depth_delta(a, b) -> np.ndarray:
    """``|a - b|`` with equal values (``inf`` and ``inf`` included) giving exactly 0 (arrays)."""
    with np.errstate(invalid="ignore"):
        return np.where(a == b, 0.0, np.abs(np.subtract(a, b, dtype=np.float64)))


@njit(cache=True, fastmath=False)
def depth_delta_at(a, b):
    """:func:`depth_delta` of two scalars, for njit kernels."""
    return 0.0 if a == b else abs(a - b)


@njit(cache=True, fastmath=False, forceinline=True)
def _gaussian_weight(dz, factor):
    """``exp(-(dz*factor)^2)`` with libm's bits (:func:`~vlref.numeric.glibc_exp`: 1 at 0, 0 below ``-745.13``, no
    call, so a loop of them vectorises)."""
    s = dz * factor
    return glibc_exp(-(s * s))


@njit(cache=True, fastmath=False)
def _depth_weight(dz, code, factor, epsilon):
    """``exp(-(dz*factor)^2)`` (``_GAUSSIAN``, :func:`_gaussian_weight`), 1 (``_UNIT``) or ``1/(dz + epsilon)``
    (``_INVERSE``)."""
    if code == _GAUSSIAN:
        return _gaussian_weight(dz, factor)
    if code == _UNIT:
        return 1.0
    return 1.0 / (dz + epsilon)


@njit(cache=True, fastmath=False, error_model="numpy")
def _gaussian_weights(tap, at, factor, flags, out):
    """``out[c] = exp(-(dz f)^2)`` (:func:`_gaussian_weight`, ``dz = dz(tap[c], at[c])``, ``f = factor``) in two loops:
    a vectorised one, ``exp`` by :func:`~vlref.numeric.glibc_exp_normal` for arguments in ``[-708, 0]`` (about half
    the work of :func:`~vlref.numeric.glibc_exp` in a vector lane) and 0 below ``-746`` (glibc's ``exp`` is 0 from
    ``-745.14`` down), which marks the other lanes (subnormal results, NaN) in ``flags`` (bytes, read as 64-bit words:
    at least ``out.size`` rounded up to 8); then one that redoes the marked lanes with :func:`_gaussian_weight`,
    skipping each word of 8 unmarked lanes. The same bits as :func:`_gaussian_weight` on every lane."""
    prefer_wide_vectors()
    n = out.size
    marks = flags.view(np.uint8)
    for c in range(n):
        s = depth_delta_at(tap[c], at[c]) * factor
        x = -(s * s)
        normal = x >= -708.0
        out[c] = 0.0 if x < -746.0 else glibc_exp_normal(x if normal else 0.0)
        marks[c] = np.uint8(0 if normal or x < -746.0 else 1)
    for c in range(n, (n + 7) // 8 * 8):
        marks[c] = 0
    for word in range((n + 7) // 8):
        if flags[word] != 0:
            for c in range(8 * word, min(8 * word + 8, n)):
                if marks[c] != 0:
                    out[c] = _gaussian_weight(depth_delta_at(tap[c], at[c]), factor)


@njit(cache=True, fastmath=False, error_model="numpy")
def _depth_weights(tap, at, code, factor, epsilon, flags, out):
    """``out[c] = W(dz(tap[c], at[c]))`` (:func:`_depth_weight`, :func:`depth_delta_at`) for every ``c``: one loop
    per weight kind, which LLVM vectorises (NumPy's error model: ``epsilon > 0`` keeps the division finite); the
    Gaussian's by :func:`_gaussian_weights` (``flags`` its scratch)."""
    prefer_wide_vectors()
    if code == _GAUSSIAN:
        _gaussian_weights(tap, at, factor, flags, out)
    elif code == _UNIT:
        for c in range(out.size):
            out[c] = 1.0
    else:
        for c in range(out.size):
            out[c] = 1.0 / (depth_delta_at(tap[c], at[c]) + epsilon)


def _weight_code(kind: str, factor: float, epsilon: float) -> int:
    """The kernel code of a depth weight: ``"gaussian"`` ``exp(-(dz*factor)^2)`` (0 for ``dz = inf``;
    ``factor = 0`` gives 1 everywhere, no ``inf * 0`` for sky) or ``"inverse"`` ``1/(dz + epsilon)``,
    ``epsilon > 0``."""
    check_choice("depth_weight", kind, DEPTH_WEIGHTS)
    if kind == "gaussian":
        return _UNIT if factor == 0.0 else _GAUSSIAN
    check_positive("epsilon", epsilon)
    return _INVERSE


@njit(cache=True, fastmath=False, parallel=True)
def _blur_lines(v, z, axis, taps_v, taps_z, centre, cross, g, code, factor, epsilon, out):
    """``out = sum_t g_t W(dz_t) v_t / sum_t g_t W(dz_t)`` along ``axis``, taps in table order.

    ``v``, ``out`` ``(H, W, C)``; position ``j`` along the axis reads value texel ``taps_v[j, t]``
    (same line) and depth texel ``taps_z[j, t]`` of depth line ``cross[line]``; its reference depth
    is ``centre[j]`` of that line. Products and sums in float64, tap by tap in table order
    (``w = g_t W``, ``acc += w v``, ``wsum += w``, both from 0). Each output row is one iteration
    (taps outer, pixels inner, per-pixel sums in a row buffer), so the bits do not depend on the
    thread count.
    """
    H, W, C = v.shape
    for r in prange(H):
        wsum = np.zeros(W)
        out[r] = 0.0
        for t in range(g.shape[0]):
            if axis == 1:
                zr = z[cross[r]]
                for c in range(W):
                    w = g[t] * _depth_weight(depth_delta_at(zr[taps_z[c, t]], zr[centre[c]]), code, factor, epsilon)
                    p = taps_v[c, t]
                    for ch in range(C):
                        out[r, c, ch] += w * v[r, p, ch]
                    wsum[c] += w
            else:
                z0, zk, vk = z[centre[r]], z[taps_z[r, t]], v[taps_v[r, t]]
                for c in range(W):
                    x = cross[c]
                    w = g[t] * _depth_weight(depth_delta_at(zk[x], z0[x]), code, factor, epsilon)
                    for ch in range(C):
                        out[r, c, ch] += w * vk[c, ch]
                    wsum[c] += w
        for c in range(W):
            for ch in range(C):
                out[r, c, ch] /= wsum[c]


_CHUNK = 256
"""Columns that :func:`_bilateral_block` sums at a time: the sums of up to 4 channels and the weight sum stay in the L1
cache (10 KiB) while the taps add to them."""


@njit(cache=True, fastmath=False)
def _pair_tables(z, r, axis, K, code, factor, epsilon, flags, T, base):
    """The depth weights of line ``r`` (a row of ``z``) against its neighbours along ``axis``:
    ``T[base + m, c] = W(dz(z(p + m), z(p)))`` for ``m = 1..K`` (the neighbour clamped to the image), and
    ``T[base, c] = W(dz(z(p), z(p)))``, ``p`` the texel (row ``r``, column ``c``); vectorised
    (:func:`_depth_weights`), the horizontal neighbours clamped to the last column one by one; the centre's from
    the two values ``dz(z, z)`` can take."""
    H, W = z.shape
    zr = z[r]
    for m in range(1, K + 1):
        if axis == 1:
            inside = max(W - m, 0)
            _depth_weights(zr[m:], zr[:inside], code, factor, epsilon, flags, T[base + m, :inside])
            for c in range(inside, W):
                T[base + m, c] = _depth_weight(depth_delta_at(zr[W - 1], zr[c]), code, factor, epsilon)
        else:
            _depth_weights(z[min(r + m, H - 1)], zr, code, factor, epsilon, flags, T[base + m])
    same, nan = _depth_weight(0.0, code, factor, epsilon), _depth_weight(np.nan, code, factor, epsilon)
    for c in range(W):
        T[base, c] = same if zr[c] == zr[c] else nan  # dz(z, z): 0, or NaN for a NaN depth


@njit(cache=True, fastmath=False)
def _planar_row(v, r, pad, out):
    """``out[ch, pad + c] = v[r, c, ch]``, the row's channels as planes, with ``pad`` copies of the edge texels on
    each side (clamp addressing: tap ``k`` of texel ``c`` is ``out[ch, pad + c + k]`` for ``|k| <= pad``). Three
    channels (RGB) are read as one flat line by a loop with the channels spelled out (0.48 against 0.31 ms for the
    planes of a 960x540 image on one dev-box thread)."""
    arrays_do_not_overlap()
    W, C = v.shape[1], v.shape[2]
    if C == 3:
        texels, red, green, blue = v[r].reshape(3 * W), out[0, pad:pad + W], out[1, pad:pad + W], out[2, pad:pad + W]
        for c in range(W):
            red[c], green[c], blue[c] = texels[3 * c], texels[3 * c + 1], texels[3 * c + 2]
    else:
        for ch in range(C):
            for c in range(W):
                out[ch, pad + c] = v[r, c, ch]
    for ch in range(C):
        for c in range(pad):
            out[ch, c] = v[r, 0, ch]
            out[ch, pad + W + c] = v[r, W - 1, ch]


@njit(cache=True, fastmath=False, forceinline=True)
def _add_tap(gk, T, wrow, wshift, rows, vrow, vshift, first, end, c0, fresh, acc, wsum):
    """One tap on the columns ``first <= c < end`` of the stretch that starts at column ``c0``: ``w = gk *
    T[wrow, c + wshift]``, ``wsum[c - c0] += w``, ``acc[ch, c - c0] += w * rows[vrow, ch, c + vshift]`` (the indices
    unsigned: no wrap-around select, so the loops vectorise; ``w`` recomputed per channel, the same product). ``fresh``
    (the stretch's first tap): the sums start from 0 (``0 + w``, ``0 + w v``, what adding to zeroed sums computes) in
    place of the stored ones, so they need no zeroing pass (the stored value is read and not used: a select, no
    branch in the loop). Three channels (RGB): one loop, ``w`` once per texel, its four sums spelled out (fewer loads
    and stores of the sums and the weights)."""
    arrays_do_not_overlap()
    if acc.shape[0] == 3:
        for c in range(first, end):
            w, i, j = gk * T[wrow, np.uint64(c + wshift)], np.uint64(c - c0), np.uint64(c + vshift)
            s, a0, a1, a2 = _sums(wsum, acc, i, fresh)
            wsum[i] = s + w
            acc[0, i] = a0 + w * rows[vrow, 0, j]
            acc[1, i] = a1 + w * rows[vrow, 1, j]
            acc[2, i] = a2 + w * rows[vrow, 2, j]
        return
    for c in range(first, end):
        i = np.uint64(c - c0)
        s = wsum[i]
        wsum[i] = (0.0 if fresh else s) + gk * T[wrow, np.uint64(c + wshift)]
    for ch in range(acc.shape[0]):
        for c in range(first, end):
            i = np.uint64(c - c0)
            a = acc[ch, i]
            acc[ch, i] = (0.0 if fresh else a) + (gk * T[wrow, np.uint64(c + wshift)]) * rows[vrow, ch,
                                                                                             np.uint64(c + vshift)]


@njit(cache=True, fastmath=False, forceinline=True)
def _sums(wsum, acc, i, fresh):
    """The four sums of RGB texel ``i`` of a stretch, ``(wsum, acc_r, acc_g, acc_b)``, or four zeros where ``fresh``
    (the values are loaded either way, so the choice is a select)."""
    s, a0, a1, a2 = wsum[i], acc[0, i], acc[1, i], acc[2, i]
    return (0.0, 0.0, 0.0, 0.0) if fresh else (s, a0, a1, a2)


@njit(cache=True, fastmath=False, forceinline=True)
def _add_rgb_taps(ga, gb, T, weights, rows, values, first, end, c0, fresh, acc, wsum):
    """Two consecutive taps ``a``, ``b`` of :func:`_add_tap` on three channels in one loop: ``wsum = (wsum + w_a) + w_b``
    and ``acc = (acc + w_a v_a) + w_b v_b``, the same operations in the same order as two calls, the sums loaded and
    stored once. ``weights = (wrow_a, wshift_a, wrow_b, wshift_b)``, ``values = (vrow_a, vshift_a, vrow_b, vshift_b)``
    (:func:`_add_tap`'s ``wrow, wshift`` and ``vrow, vshift``); ``fresh`` as there."""
    arrays_do_not_overlap()
    wa, sa, wb, sb = weights
    va, ta, vb, tb = values
    for c in range(first, end):
        i, ja, jb = np.uint64(c - c0), np.uint64(c + ta), np.uint64(c + tb)
        w1, w2 = ga * T[wa, np.uint64(c + sa)], gb * T[wb, np.uint64(c + sb)]
        s, a0, a1, a2 = _sums(wsum, acc, i, fresh)
        wsum[i] = (s + w1) + w2
        acc[0, i] = (a0 + w1 * rows[va, 0, ja]) + w2 * rows[vb, 0, jb]
        acc[1, i] = (a1 + w1 * rows[va, 1, ja]) + w2 * rows[vb, 1, jb]
        acc[2, i] = (a2 + w1 * rows[va, 2, ja]) + w2 * rows[vb, 2, jb]


@njit(cache=True, fastmath=False, forceinline=True, error_model="numpy")
def _close_rgb(gk, T, wrow, wshift, rows, vrow, vshift, end, c0, fresh, acc, wsum, out, r):
    """The stretch's last tap on three channels (:func:`_add_tap` from column ``c0``) and its end, in one loop: the
    sums with the tap added are divided (``acc / wsum``) and written into ``out[r, c]``'s three channels, spelled
    out into the flat line; the sums are not stored back. The same operations and order as the tap, then the
    division (NumPy's error model, as :func:`_finish_stretch`)."""
    arrays_do_not_overlap()
    texels = out[r, c0:end].reshape(3 * (end - c0))
    for c in range(c0, end):
        w, i, j = gk * T[wrow, np.uint64(c + wshift)], np.uint64(c - c0), np.uint64(c + vshift)
        s, a0, a1, a2 = _sums(wsum, acc, i, fresh)
        s = s + w
        texels[3 * i] = (a0 + w * rows[vrow, 0, j]) / s
        texels[3 * i + 1] = (a1 + w * rows[vrow, 1, j]) / s
        texels[3 * i + 2] = (a2 + w * rows[vrow, 2, j]) / s


@njit(cache=True, fastmath=False, forceinline=True)
def _tap(t, K, axis, r, H, base, c0, c1):
    """Tap ``t`` (0 the centre, then ``k = -K..-1``, ``1..K``) of row ``r`` in the stretch ``c0 <= c < c1``:
    ``(k, vrow, vshift, first, wrow, wshift)``, the arguments of :func:`_add_tap` (``base``: the row's first table row
    in ``T``); ``first > c0`` where the stretch's first columns take tap ``k < 0`` clamped to column 0 (horizontal)."""
    k = 0 if t == 0 else (t - K - 1 if t <= K else t - K)
    vrow, vshift = (0, K + k) if axis == 1 else (min(max(r + k, 0), H - 1) % (2 * K + 1), 0)
    first, wrow, wshift = c0, base + abs(k), 0
    if k < 0 and axis == 1:
        first, wshift = min(max(c0, -k), c1), k
    elif k < 0:
        wrow = ((r + k) % (K + 1)) * (K + 1) - k if r + k >= 0 else r  # above row 0: row 0's pair (0, r)
    return k, vrow, vshift, first, wrow, wshift


@njit(cache=True, fastmath=False, forceinline=True, error_model="numpy")
def _finish_stretch(acc, wsum, n, out, r, c0):
    """``out[r, c0 + i, ch] = acc[ch, i] / wsum[i]`` for ``i < n`` (vectorised: NumPy's error model, so a zero ``wsum``
    would give ``inf``/NaN rather than raise; the centre tap's weight keeps it positive). Three channels (RGB) end
    in :func:`_close_rgb` instead."""
    arrays_do_not_overlap()
    for ch in range(acc.shape[0]):
        for i in range(n):
            acc[ch, i] = acc[ch, i] / wsum[i]
    line = out[r]
    for i in range(n):
        for ch in range(acc.shape[0]):
            line[c0 + i, ch] = acc[ch, i]


@njit(cache=True, fastmath=False)
def _bilateral_block(v, z, axis, g, code, factor, epsilon, r0, r1, out):
    """Rows ``r0 <= r < r1`` of :func:`_bilateral_lines` (one work item; a separate function keeps the parallel
    kernel small, which is most of its compile time): the block's scratch, then :func:`_bilateral_rows`."""
    H, W, C = v.shape
    K = g.size - 1
    scratch = (np.empty(((K + 1) * (K + 1), W)), np.empty((2 * K + 1 if axis == 0 else 1, C, W + 2 * K)),
               np.zeros((C, _CHUNK)), np.zeros(_CHUNK), np.empty(W // 8 + 1, np.uint64))
    _bilateral_rows(v, z, axis, g, code, factor, epsilon, r0, r1, scratch, out)


@njit(cache=True, fastmath=False)
def _bilateral_rows(v, z, axis, g, code, factor, epsilon, r0, r1, scratch, out):
    """The rows of :func:`_bilateral_block`. ``scratch``: ``(T, rows, acc, wsum, flags)``, the depth tables, the planes,
    the sums (zeros: a fresh tap loads them and does not use them, :func:`_sums`) and :func:`_gaussian_weights`'
    marks, owned by the caller for the call and used here without reference counts
    (:func:`~vlref.parallel.borrowed`: every tap of every stretch passes four of them to a function, and a counted
    array costs each such call an atomic add and subtract; :mod:`vlref.parallel`, "Calls that carry arrays")."""
    prefer_wide_vectors()
    T, rows, acc, wsum, flags = borrowed(scratch)
    H, W, C = v.shape
    K = g.size - 1
    S = K + 1
    if axis == 0:
        for p in range(max(r0 - K, 0), min(r0 + K, H)):
            _planar_row(v, p, 0, rows[p % (2 * K + 1)])
    for r in range(r0 if axis == 1 else max(r0 - K, 0), r1):
        slot = r % (K + 1)
        _pair_tables(z, r, axis, K, code, factor, epsilon, flags, T, slot * S)
        if r < r0:
            continue
        if axis == 1:
            _planar_row(v, r, K, rows[0])
        elif r + K <= H - 1:
            _planar_row(v, r + K, 0, rows[(r + K) % (2 * K + 1)])
        for c0 in range(0, W, _CHUNK):
            c1 = min(c0 + _CHUNK, W)
            t = 0
            while t < 2 * K + 1:
                k, vrow, vshift, first, wrow, wshift = _tap(t, K, axis, r, H, slot * S, c0, c1)
                k2, vrow2, vshift2, first2, wrow2, wshift2 = _tap(min(t + 1, 2 * K), K, axis, r, H, slot * S, c0, c1)
                gk = g[abs(k)]
                if C == 3 and t == 2 * K:  # the last tap (k = K, every column) ends the stretch
                    _close_rgb(gk, T, wrow, wshift, rows, vrow, vshift, c1, c0, t == 0, acc, wsum, out, r)
                    break
                if t + 1 < 2 * K and C == 3 and first == c0 and first2 == c0:
                    _add_rgb_taps(gk, g[abs(k2)], T, (wrow, wshift, wrow2, wshift2), rows,
                                  (vrow, vshift, vrow2, vshift2), first, c1, c0, t == 0, acc, wsum)
                    t += 2
                    continue
                for c in range(c0, first):  # tap k < 0 of column c < -k is clamped to column 0: its pair (0, c)
                    w = gk * T[slot * S + c, 0]
                    wsum[c - c0] += w
                    for ch in range(C):
                        acc[ch, c - c0] += w * rows[0, ch, K + k + c]
                _add_tap(gk, T, wrow, wshift, rows, vrow, vshift, first, c1, c0, t == 0, acc, wsum)
                t += 1
            if C != 3:
                _finish_stretch(acc, wsum, c1 - c0, out, r, c0)


@njit(cache=True, fastmath=False, parallel=True)
def _bilateral_lines(v, z, axis, g, code, factor, epsilon, blocks, out):
    """:func:`_blur_lines` for :func:`bilateral_pass`'s taps (offsets ``0, -K..-1, 1..K``, value and depth at the same
    texel, clamped), each depth weight computed once and the sums vectorised over a line.

    ``W(dz)`` of two texels ``m`` apart serves the tap ``+m`` of one and the tap ``-m`` of the other (``dz`` is
    symmetric: ``|a - b| = |b - a|`` exactly in floating point, :func:`depth_delta_at`), so a pixel costs ``K``
    weights, not ``2K`` (:func:`_pair_tables`): tap ``-m`` at position ``p`` is tap ``+m`` at ``p - m``, and a tap
    clamped to position 0 is position 0's tap ``+p`` (``p = 0``: its centre weight). Per pixel the same operations
    in the same order as :func:`_blur_lines` (``w = g_|k| W``, ``acc += w v``, ``wsum += w`` from 0, tap by tap,
    then ``acc / wsum``): the same bits.

    The values are read as planes of one line (:func:`_planar_row`), so a tap is one contiguous loop per channel
    (:func:`_add_tap`), and a line is summed in stretches of ``_CHUNK`` columns, all taps of a stretch before the next,
    so its sums stay in the L1 cache (summed over whole lines, each tap loaded and stored them from L2: a fifth slower
    on one thread). A line's depth tables are one array, ``K + 1`` rows per line (its centre, then ``m = 1..K``).
    ``blocks`` blocks of rows in parallel, each with its buffers allocated once. Vertical: the
    depth tables of the ``K + 1`` latest rows and the planes of the ``2K + 1`` source rows around the current one are
    kept in rings; a block computes the tables and planes of the ``K`` rows above it again (the only repeated
    work). The blocks get the arrays without reference counts (:func:`~vlref.parallel.borrowed`: each row passes
    them to several functions). ``g``: the Gaussian by ``|k|``, ``K + 1`` values.
    """
    H = v.shape[0]
    n_items = max(1, min(H, blocks))
    for b in prange(n_items):
        vb, zb, gb, ob = borrowed((v, z, g, out))
        _bilateral_block(vb, zb, axis, gb, code, factor, epsilon, b * H // n_items, (b + 1) * H // n_items, ob)


def _line_buffers(v, out=None):
    """``v`` (``(H, W)`` or ``(H, W, C)``) as a contiguous ``(H, W, C)`` array, and an output of that shape: ``out``
    viewed so where given (float64, C-contiguous, ``v``'s shape, not overlapping ``v``), else a new array."""
    v3 = np.ascontiguousarray(v).reshape(v.shape[0], v.shape[1], -1)
    if out is None:
        return v3, np.empty(v3.shape)
    if out.shape != v.shape or out.dtype != np.float64 or not out.flags.c_contiguous or not out.flags.writeable:
        raise ValueError(f"out: need a writeable C-contiguous float64 array of shape {v.shape}, got {out.dtype} "
                         f"{out.shape}")
    if np.may_share_memory(out, v3):
        raise ValueError("out: overlaps the values the pass reads")
    return v3, out.reshape(v3.shape)


def _run_blur(v, z, axis, taps_v, taps_z, centre, cross, g, code, factor=1.0, epsilon=1.0) -> np.ndarray:
    """:func:`_blur_lines` on ``(H, W)`` or ``(H, W, C)`` values; returns the shape of ``v``."""
    v3, out = _line_buffers(v)
    _blur_lines(v3, np.ascontiguousarray(z), axis, np.ascontiguousarray(taps_v, dtype=np.int64),
                np.ascontiguousarray(taps_z, dtype=np.int64), np.ascontiguousarray(centre, dtype=np.int64),
                np.ascontiguousarray(cross, dtype=np.int64), np.asarray(g, dtype=np.float64), code, float(factor),
                float(epsilon), out)
    return out.reshape(v.shape)


def gaussian_weights(radius: int, sigma: float) -> np.ndarray:
    """``G(i) = exp(-i^2 / (2 sigma^2)) / sqrt(2 pi sigma^2)``, ``i = 0..radius`` (VL ``GaussianWeight``)."""
    if radius < 0 or not sigma > 0:
        raise ValueError(f"blur: need radius >= 0 and sigma > 0, got {radius}, {sigma}")
    i = np.arange(radius + 1, dtype=np.float64)
    return (1.0 / math.sqrt(2.0 * math.pi * sigma * sigma)) * np.exp(-(i * i) / (2.0 * sigma * sigma))


def _values(values) -> np.ndarray:
    v = np.asarray(values, dtype=np.float64)
    if v.ndim not in (2, 3):
        raise ValueError(f"values: expected (H, W) or (H, W, C), got shape {v.shape}")
    return v


def bilateral_pass(values, depth, axis: int, gauss, depth_factor: float = 1.0, depth_weight_kind: str = "gaussian",
                   epsilon: float = 1e-3, keep_alpha: bool = False, out: np.ndarray | None = None) -> np.ndarray:
    """One pass with taps at integer texel offsets ``k = -K..K`` (``K = len(gauss) - 1``), value and
    depth read at the same texel of the same resolution (thesis §4.2.6; SOURCES §1.9).

    Tap order (VL ``BilateralBlur``): the centre, then ``k = -K..-1``, then ``k = 1..K``; tap ``k``
    weighs ``gauss[|k|] * W(dz_k)``, the centre ``gauss[0] * W(0)`` (1 for ``"gaussian"``). ``keep_alpha``: the last
    channel is the centre texel's, not blurred (VL's alpha carries the transmittance). ``out``: an array to write the
    result into and return (float64, C-contiguous, the shape of ``values``, not overlapping them), e.g. a buffer of
    the caller's that is no longer needed: its pages are already mapped, where a new 1080p RGB array's 50 MB are
    mapped and zeroed by the kernel on first touch (about a tenth of the two passes' time on 16 threads); default a
    new array. The same bits either way.
    """
    check_choice("axis", axis, (0, 1))
    v = _values(values)
    z = np.asarray(depth, dtype=np.float64)
    if z.shape != v.shape[:2]:
        raise ValueError(f"depth: depth shape {z.shape} does not match values {v.shape[:2]}")
    if keep_alpha and v.ndim != 3:
        raise ValueError("values: keep_alpha needs an (H, W, C) buffer")
    code = _weight_code(depth_weight_kind, depth_factor, epsilon)
    v3, lines = _line_buffers(v, out)
    _bilateral_lines(v3, np.ascontiguousarray(z), axis, np.asarray(gauss, dtype=np.float64), code, float(depth_factor),
                     float(epsilon), 2 * get_num_threads(), lines)
    out = lines.reshape(v.shape)
    if keep_alpha:
        out[..., -1] = v[..., -1]
    return out


def thesis_blur_pass(values, depth, axis: int, radius: int = 3, sigma: float = 1.5, depth_factor: float = 1.0,
                     depth_weight_kind: str = "gaussian", epsilon: float = 1e-3,
                     out: np.ndarray | None = None) -> np.ndarray:
    """The thesis's 7-tap pass (source pixel and 3 each side) on linear eye depth (§4.2.6).

    The thesis gives neither sigma nor the depth factor [U]: the defaults are
    ``vlref.scene.technique_params.KillzoneParams`` (sigma 1.5 texels, ``exp(-(1.0 dz)^2)`` with
    ``dz`` in metres); ``depth_weight_kind="inverse"`` is the literal reading "weights divided by the
    depth difference", with ``epsilon`` metres added against ``dz = 0``. ``out``: as :func:`bilateral_pass`'s.
    """
    return bilateral_pass(values, depth, axis, gaussian_weights(radius, sigma), depth_factor, depth_weight_kind,
                          epsilon, out=out)


def vl_blur_pass(values, depth, axis: int, resolution: str = "half", deviation: float = 1.5,
                 depth_factor: float = 0.5, kernel_radius: int | None = None) -> np.ndarray:
    """VolumetricLights' pass on an RGBA buffer ``(H, W, 4)`` (SOURCES §1.9).

    Radius ``K`` = 7 / 5 / 6 for full / half / quarter (``kernel_radius`` overrides it), Gaussian
    ``sigma = K / deviation`` (``GAUSS_BLUR_DEVIATION 1.5``), depth weight
    ``exp(-(0.5 |dz|)^2)`` (``BLUR_DEPTH_FACTOR 0.5``) on **linear eye depth** of the same level;
    alpha is the centre texel's alpha.
    """
    check_choice("resolution", resolution, tuple(VL_KERNEL_RADIUS))
    v = _values(values)
    if v.ndim != 3 or v.shape[2] != 4:
        raise ValueError(f"values: VL blurs an (H, W, 4) RGBA buffer, got shape {v.shape}")
    k = VL_KERNEL_RADIUS[resolution] if kernel_radius is None else kernel_radius
    return bilateral_pass(v, depth, axis, gaussian_weights(k, k / deviation), depth_factor, keep_alpha=True)


def _urp_gauss(taps: int, weights) -> np.ndarray:
    g = np.asarray(weights, dtype=np.float64)
    if not 0 <= taps <= len(g) - 1:
        raise ValueError(f"samples: taps each side must be in 0..{len(g) - 1}, got {taps}")
    return g


def _urp_axes(fog, depth_full, axis: int):
    check_choice("axis", axis, (0, 1))
    f = _values(fog)
    z = np.asarray(depth_full, dtype=np.float64)
    if z.ndim != 2 or z.shape[0] < f.shape[0] or z.shape[1] < f.shape[1]:
        raise ValueError(f"depth: full-res depth {z.shape} cannot feed low-res fog {f.shape[:2]}")
    return f, z


def _urp_pass(f, z, axis, taps_lo, taps_hi, centre_hi, g, falloff, uv_origin):
    """Shared URP accumulation over the tap tables ``(n_lo, 2n + 1)`` (``k = -n..n``), built in uv order.

    Tap ``k`` of low-res texel ``j`` reads fog texel ``taps_lo[j, k]`` and full-res depth texel
    ``taps_hi[j, k]``, weighed against depth texel ``centre_hi[j]``; the other axis reads the
    full-res texel under the low-res line (``nearest_index``). Vertical maps are turned into array
    rows (:func:`~vlref.post.resolution.uv_row_map`), so the arrays are read in place.
    """
    cross = nearest_index(z.shape[1 - axis], f.shape[1 - axis])
    if axis == 0:
        taps_lo = uv_row_map(taps_lo, f.shape[0], uv_origin)
        taps_hi = uv_row_map(taps_hi, z.shape[0], uv_origin)
        centre_hi = uv_row_map(centre_hi, z.shape[0], uv_origin)
    else:
        cross = uv_row_map(cross, z.shape[0], uv_origin)
    return _run_blur(f, z, axis, taps_lo, taps_hi, centre_hi, cross, g, _weight_code("gaussian", falloff, 1.0),
                     falloff)


def urp_article_blur_pass(fog, depth_full, axis: int, samples: int, amount: float, falloff: float = 100.0,
                          weights=URP_GAUSS_WEIGHTS, uv_origin: str = "bottom") -> np.ndarray:
    """The URP article's pass (P1, SOURCES §2.5) on the low-res fog ``(h, w)``.

    Tap ``k = -samples..samples`` sits at uv ``u_k = u + (k * amount) / 1000`` along the axis --
    **uv units**, so the blur width depends on resolution and aspect. The fog is point-sampled at
    ``u_k`` on the low-res buffer, the **raw** full-res depth at ``u`` and ``u_k`` (the other axis
    at the low-res texel's nearest full-res texel); weight
    ``exp(-(100 |z_k - z_0|)^2) * weights[|k|]`` (``BLUR_DEPTH_FALLOFF 100``); summed in order
    ``k = -n..n``. ``samples`` above 7 would index past the source's array: rejected.
    ``amount = 0`` puts every tap on the centre texel (the result is the centre value up to
    rounding). ``uv_origin`` fixes which texel an exact edge rounds to on the vertical axis.
    """
    g = _urp_gauss(samples, weights)
    f, z = _urp_axes(fog, depth_full, axis)
    n_lo, n_hi = f.shape[axis], z.shape[axis]
    k = np.arange(-samples, samples + 1)
    u = (np.arange(n_lo) + 0.5) / n_lo
    uk = u[:, None] + (k[None, :] * amount) / 1000.0
    return _urp_pass(f, z, axis, point_texel(uk, n_lo), point_texel(uk, n_hi), point_texel(u, n_hi), g[np.abs(k)],
                     falloff, uv_origin)


def urp_repo_blur_pass(fog, depth_full, axis: int, taps: int = 5, falloff: float = 100.0,
                       weights=URP_GAUSS_WEIGHTS, uv_origin: str = "bottom") -> np.ndarray:
    """The URP repository's pass (R, SOURCES §2.5): fixed ``n = 5``, integer texel offsets.

    The fog tap ``k`` is low-res texel ``j + k``; its depth is the raw full-res depth at the
    *full-res* texel ``c(j) + k``, ``c(j)`` the texel under the low-res centre -- the source's offset
    mismatch whenever ``f > 1``. Weights and order as :func:`urp_article_blur_pass`.
    """
    g = _urp_gauss(taps, weights)
    f, z = _urp_axes(fog, depth_full, axis)
    n_lo, n_hi = f.shape[axis], z.shape[axis]
    k = np.arange(-taps, taps + 1)
    c = nearest_index(n_hi, n_lo)
    lo = np.clip(np.arange(n_lo)[:, None] + k[None, :], 0, n_lo - 1)
    hi = np.clip(c[:, None] + k[None, :], 0, n_hi - 1)
    return _urp_pass(f, z, axis, lo, hi, c, g[np.abs(k)], falloff, uv_origin)


def blur_hv(pass_fn, values, depth, out: np.ndarray | None = None, **params) -> tuple[np.ndarray, np.ndarray]:
    """``(h, hv)``: ``pass_fn`` along axis 1, then along axis 0 on its output (both buffers returned). ``out``: where
    the vertical pass writes ``hv`` (``pass_fn``'s ``out``, :func:`bilateral_pass`); it may be ``values`` itself,
    which the horizontal pass has read by then (a caller that no longer needs its input saves a new array)."""
    h = pass_fn(values, depth, 1, **params)
    return h, pass_fn(h, depth, 0, **params) if out is None else pass_fn(h, depth, 0, out=out, **params)
