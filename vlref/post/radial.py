"""Screen-space radial blur toward the light: GPU Gems 3 ch. 13 (Mitchell) and disenone's Unity port.

Coordinates: the image's own uv, ``u = (x + 0.5) / W`` right and ``v = (y + 0.5) / H`` *down*
(row 0 = top). The loop is linear in uv and the bilinear sampler is symmetric, so the result does
not depend on the uv orientation as long as the light's uv is given in the same convention
(:func:`light_screen_uv` does this from clip space).

Listing 13-1 (SOURCES §3.2), per pixel ``u`` with light ``l``:

    delta = (u - l) * (1/n * Density);  C = tex(u);  dec = 1
    repeat n times:  u -= delta;  C += tex(u) * (dec * Weight);  dec *= Decay
    out = C * Exposure

i.e. ``C = tex(u) + Weight sum_{i=1..n} Decay^(i-1) tex(u - i delta)``: the initial sample is
unweighted and undecayed; with ``Density = 1`` the last tap lands on the light.

Sampling is bilinear at uv with clamp addressing by default (the chapter and the Unity RTs leave the
wrap mode open [U]; ``"repeat"`` and ``"border"`` (zero outside) are offered). A light **off
screen** needs nothing special: the taps run outside ``[0, 1]`` and read the clamped edge. A light
**behind the camera** (clip ``w <= 0``) has no meaningful screen position; :func:`light_screen_uv`
then returns visibility 0, and ``radial_blur(..., visibility=0)`` is exactly 0 -- the effect is off.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import prange, types
from numba.extending import intrinsic

from vlref.jit import njit
from vlref.numeric import arrays_do_not_overlap, prefer_wide_vectors
from vlref.parallel import WORKERS, borrowed, take, task_counter
from vlref.post.resolution import check_choice

ADDRESS_MODES = ("clamp", "repeat", "border")
"""The texture address modes, by name; kernels take a mode's index, named below."""
ADDRESS_CLAMP, ADDRESS_REPEAT, ADDRESS_BORDER = (ADDRESS_MODES.index(m) for m in ADDRESS_MODES)


def _image(image) -> np.ndarray:
    a = np.asarray(image, dtype=np.float64)
    if a.ndim not in (2, 3):
        raise ValueError(f"image: expected (H, W) or (H, W, C), got shape {a.shape}")
    return a


@njit(cache=True, fastmath=False)
def _texel(i, n, mode):
    """Texel index after addressing (``ADDRESS_*``) and whether it reads the image."""
    if mode == ADDRESS_REPEAT:
        return i % n, True
    inside = 0 <= i < n
    return min(max(i, 0), n - 1), inside or mode == ADDRESS_CLAMP


@njit(cache=True, fastmath=False)
def _fetch_add(img, u, v, mode, w, acc):
    """``acc[ch] += w * bilinear(img, u, v)[ch]``; bilinear as ``a + t (b - a)`` along x, then y."""
    H, W = img.shape[0], img.shape[1]
    x = u * W - 0.5
    y = v * H - 0.5
    xf, yf = math.floor(x), math.floor(y)
    tx, ty = x - xf, y - yf
    xa, ina = _texel(int(xf), W, mode)
    xb, inb = _texel(int(xf) + 1, W, mode)
    ya, jna = _texel(int(yf), H, mode)
    yb, jnb = _texel(int(yf) + 1, H, mode)
    for ch in range(img.shape[2]):
        t00 = img[ya, xa, ch] if (ina and jna) else 0.0
        t10 = img[ya, xb, ch] if (inb and jna) else 0.0
        t01 = img[yb, xa, ch] if (ina and jnb) else 0.0
        t11 = img[yb, xb, ch] if (inb and jnb) else 0.0
        top = t00 + tx * (t10 - t00)
        bottom = t01 + tx * (t11 - t01)
        acc[ch] = acc[ch] + (top + ty * (bottom - top)) * w


@njit(cache=True, fastmath=False, parallel=True)
def _sample_kernel(img, u, v, mode):
    out = np.zeros((u.size, img.shape[2]))
    for p in prange(u.size):
        _fetch_add(img, u[p], v[p], mode, 1.0, out[p])
    return out


def bilinear_sample(image, u, v, address: str = "clamp") -> np.ndarray:
    """Bilinear texture fetch of ``image`` at uv arrays ``u``, ``v`` (same shape ``S``) -> ``S`` or ``S + (C,)``.

    Texel coordinate ``x = u W - 1/2``, ``x0 = floor(x)``, ``t = x - x0``; the four texels are
    combined as ``a + t (b - a)`` along x, then along y (a constant image stays exactly constant).
    ``border`` reads 0 outside the image.
    """
    check_choice("address", address, ADDRESS_MODES)
    img = _image(image)
    u, v = np.broadcast_arrays(np.asarray(u, dtype=np.float64), np.asarray(v, dtype=np.float64))
    img3 = img if img.ndim == 3 else img[..., None]
    out = _sample_kernel(np.ascontiguousarray(img3), u.ravel().copy(), v.ravel().copy(), ADDRESS_MODES.index(address))
    return out.reshape(u.shape + img.shape[2:])


RADIAL_TILE = 256
"""The most pixels of one row that the radial kernel carries through all its taps at once (:func:`_radial_tiles`)."""


@njit(cache=True, fastmath=False)
def _tap_columns(u, n, W, C, lo, hi, offset, repeat, tx, ia, ib):
    """Per pixel ``x < n`` of a tile: ``tx``, and where the texels left and right of ``u W - 1/2`` start in an image row of
    ``C`` channels, ``ia``, ``ib`` (``column * C``, unsigned: an index that needs no sign check).

    Texel ``i`` is column ``i mod W`` when ``repeat``, else ``clamp(i, lo, hi) + offset``; the clamp is taken on
    the integral float ``np.floor(x)``, the bound first, then converted to int32 (the same index as clamping the
    integer, and no integer overflow far off screen, where ``math.floor``'s int64 read the other edge beyond 2^63
    texels; AVX2 converts int64 lane by lane, and with them the blur took 1.45x as long: BENCHMARKS.md "The radial
    blur on AVX2"). :func:`_fetch_add`'s arithmetic, operation for operation.
    """
    prefer_wide_vectors()
    if repeat:
        for x in range(n):
            xx = u[x] * W - 0.5
            xf = math.floor(xx)
            tx[x] = xx - xf
            ia[x] = (int(xf) % W) * C
            ib[x] = ((int(xf) + 1) % W) * C
    else:
        for x in range(n):
            xx = u[x] * W - 0.5
            xf = np.floor(xx)
            tx[x] = xx - xf
            ia[x] = (np.int32(min(max(lo, xf), hi)) + offset) * C
            ib[x] = (np.int32(min(max(lo, xf + 1.0), hi)) + offset) * C


@njit(cache=True, fastmath=False)
def _tap_rows(flat, ra, rb, ty, tx, ia, ib, n, w, acc):
    """``acc[ch, x] += w * bilinear(...)`` for every pixel ``x < n`` of a tile and channel ``ch``: the texel rows start at
    ``ra``, ``rb`` in the flattened image ``flat``, the texels at ``ia[x]``, ``ib[x]`` in a row
    (:func:`_tap_columns`); bilinear as ``a + t (b - a)`` along x, then y (:func:`_fetch_add`'s order).

    One channel at a time over the tile's pixels: the loop has no inner loop, its stores (``acc``) cannot change
    what it reads (``flat``, declared with :func:`~vlref.numeric.arrays_do_not_overlap`) and its indices are
    unsigned sums (no sign checks, no multiplies), so LLVM vectorises it, the texel reads as gathers.
    """
    prefer_wide_vectors()
    arrays_do_not_overlap()
    for ch in range(acc.shape[0]):
        a0, b0 = ra + np.uint64(ch), rb + np.uint64(ch)
        for x in range(n):
            a, b, t = ia[x], ib[x], tx[x]
            t00 = flat[a0 + a]
            t10 = flat[a0 + b]
            t01 = flat[b0 + a]
            t11 = flat[b0 + b]
            top = t00 + t * (t10 - t00)
            bottom = t01 + t * (t11 - t01)
            acc[ch, x] = acc[ch, x] + (top + ty * (bottom - top)) * w


def _rgb_bilinear_codegen(lanes):
    """The code of :func:`_rgb_bilinear_add` (``lanes = 4``: each texel read as four values) or
    :func:`_rgb_bilinear_add_near_end` (``lanes = 3``)."""
    def codegen(context, builder, signature, args):
        flat_, ra_, rb_, a_, b_, tx_, ty_, w_, acc_, k_ = args
        f64, i32 = ir.DoubleType(), ir.IntType(32)
        vector, v4 = ir.VectorType(f64, lanes), ir.VectorType(f64, 4)
        data = context.make_array(signature.args[0])(context, builder, flat_).data
        sums = context.make_array(signature.args[8])(context, builder, acc_).data

        def texel(row, column):
            at = builder.gep(data, [builder.add(row, column)], inbounds=True)
            return builder.load(builder.bitcast(at, vector.as_pointer()), align=8)

        def splat(x):
            one = builder.insert_element(ir.Constant(vector, None), x, ir.Constant(i32, 0))
            everywhere = ir.Constant(ir.VectorType(i32, lanes), [0] * lanes)
            return builder.shuffle_vector(one, ir.Constant(vector, None), everywhere)

        t00, t10, t01, t11 = texel(ra_, a_), texel(ra_, b_), texel(rb_, a_), texel(rb_, b_)
        txv = splat(tx_)
        top = builder.fadd(t00, builder.fmul(txv, builder.fsub(t10, t00)))
        bottom = builder.fadd(t01, builder.fmul(txv, builder.fsub(t11, t01)))
        value = builder.fmul(builder.fadd(top, builder.fmul(splat(ty_), builder.fsub(bottom, top))), splat(w_))
        if lanes == 3:
            value = builder.shuffle_vector(value, ir.Constant(vector, [0.0, 0.0, 0.0]),
                                           ir.Constant(ir.VectorType(i32, 4), [0, 1, 2, 3]))
        at = builder.bitcast(builder.gep(sums, [k_], inbounds=True), v4.as_pointer())
        builder.store(builder.fadd(builder.load(at, align=8), value), at, align=8)
        return context.get_dummy_value()

    return codegen


def _rgb_bilinear_signature(flat, ra, rb, a, b, tx, ty, w, acc, k):
    """The signature of :func:`_rgb_bilinear_add` for these argument types; None (no match) unless ``flat`` and ``acc``
    are float64 arrays."""
    if not (isinstance(flat, types.Array) and flat.dtype == types.float64 and isinstance(acc, types.Array)
            and acc.dtype == types.float64):
        return None
    return types.none(flat, ra, rb, a, b, tx, ty, w, acc, k)


@intrinsic
def _rgb_bilinear_add(typingctx, flat, ra, rb, a, b, tx, ty, w, acc, k):
    """``acc[k + ch] += w * bilinear(...)[ch]`` for the three channels ``ch`` of one pixel: the texels' RGB triples
    start at ``flat[ra + a]``, ``flat[ra + b]``, ``flat[rb + a]``, ``flat[rb + b]`` (``flat`` a float64 image, flattened,
    three channels; ``ra``, ``rb``, ``a``, ``b``, ``k`` unsigned element indices). :func:`_fetch_add`'s operations
    in its order, on a 4-lane vector: each texel is one contiguous read of four values, its RGB and the value after
    it (the next texel's red, which must exist: ``flat`` holds at least ``max(ra, rb) + max(a, b) + 4`` values), so
    a pixel's tap is four vector loads and 11 vector operations (where a vectorised pixel loop gathers 12 values one
    lane at a time, and reading three values takes two loads and a shuffle each). ``acc[k : k + 4]`` holds the
    pixel's sums, its fourth value the sum of that spare lane (never read). LLVM IR without ``fast`` flags: IEEE
    operations per lane, the bits of the scalar loop. njit only."""
    sig = _rgb_bilinear_signature(flat, ra, rb, a, b, tx, ty, w, acc, k)
    return None if sig is None else (sig, _rgb_bilinear_codegen(4))


@intrinsic
def _rgb_bilinear_add_near_end(typingctx, flat, ra, rb, a, b, tx, ty, w, acc, k):
    """:func:`_rgb_bilinear_add` reading each texel's three values only (where the value after it may be past the end
    of ``flat``: a tap on the image's last row); the spare lane of ``acc`` gets 0."""
    sig = _rgb_bilinear_signature(flat, ra, rb, a, b, tx, ty, w, acc, k)
    return None if sig is None else (sig, _rgb_bilinear_codegen(3))


@njit(cache=True, fastmath=False)
def _tap_rows_rgb(flat, ra, rb, ty, tx, ia, ib, n, w, acc, row):
    """:func:`_tap_rows` for three channels, pixel by pixel (:func:`_rgb_bilinear_add`): the sums of pixel ``x`` in
    ``acc[4x : 4x + 4]``; ``row``: the values in an image row (a tap whose texel rows are followed by another reads
    four values per texel, one on the last row three)."""
    if max(ra, rb) + row < np.uint64(flat.size):
        for x in range(n):
            _rgb_bilinear_add(flat, ra, rb, ia[x], ib[x], tx[x], ty, w, acc, np.uint64(4 * x))
    else:
        for x in range(n):
            _rgb_bilinear_add_near_end(flat, ra, rb, ia[x], ib[x], tx[x], ty, w, acc, np.uint64(4 * x))


@njit(cache=True, fastmath=False)
def _row_index(yf, n, lo, hi, offset, repeat):
    """Array row of texel row ``yf`` (an integral float) of ``n``: ``yf mod n`` when ``repeat``, else
    ``clamp(yf, lo, hi) + offset`` (clamped as :func:`_tap_columns` does)."""
    return int(yf) % n if repeat else np.int32(min(max(lo, yf), hi)) + offset


RADIAL_RUN = 16
"""Consecutive tiles of :func:`_radial_tiles` taken as one task."""


@njit(cache=True, fastmath=False)
def _radial_run(img, H, W, loop, mode, tile_w, first, end, buffers, out):
    """Tiles ``first <= tile < end`` of :func:`_radial_tiles` (one task of :func:`_radial_tasks`). ``buffers``: ``(u,
    du, tx, ia, ib, acc, acc_rgb)``, the task's scratch, owned by the caller for the call and used here without
    reference counts (:func:`~vlref.parallel.borrowed`: every tap passes four or five of them to :func:`_tap_columns`
    and :func:`_tap_rows_rgb`, 16 atomic adds and subtracts per tap and tile if counted; :mod:`vlref.parallel`, "Calls
    that carry arrays")."""
    u, du, tx, ia, ib, acc, acc_rgb = borrowed(buffers)
    lu, lv, scale, iterations, weight, tap_scale, decay, exposure, visibility = loop
    C = img.shape[2]
    flat = img.reshape(img.size)
    row = np.uint64(img.shape[1] * C)
    offset = 1 if mode == ADDRESS_BORDER else 0
    lo_x, hi_x = float(-offset), float(W - 1 + offset)
    lo_y, hi_y = float(-offset), float(H - 1 + offset)
    repeat = mode == ADDRESS_REPEAT
    rgb = C == 3
    for tile in range(first, end):
        y = tile % H
        x0 = (tile // H) * tile_w
        n = min(tile_w, W - x0)
        for x in range(n):
            u[x] = (x0 + x + 0.5) / W
            du[x] = (u[x] - lu) * scale
        if rgb:
            acc_rgb[:] = 0.0
        else:
            acc[:] = 0.0
        v = (y + 0.5) / H
        dv = (v - lv) * scale
        w = 1.0
        dec = 1.0
        for i in range(iterations + 1):
            if i > 0:
                for x in range(n):
                    u[x] = u[x] - du[x]
                v = v - dv
                w = dec * tap_scale * weight
                dec = dec * decay
            yy = v * H - 0.5
            yf = np.floor(yy)
            ra = np.uint64(_row_index(yf, H, lo_y, hi_y, offset, repeat)) * row
            rb = np.uint64(_row_index(yf + 1.0, H, lo_y, hi_y, offset, repeat)) * row
            _tap_columns(u, n, W, C, lo_x, hi_x, offset, repeat, tx, ia, ib)
            if rgb:
                _tap_rows_rgb(flat, ra, rb, yy - yf, tx, ia, ib, n, w, acc_rgb, row)
            else:
                _tap_rows(flat, ra, rb, yy - yf, tx, ia, ib, n, w, acc)
        for x in range(n):
            for ch in range(C):
                total = acc_rgb[4 * x + ch] if rgb else acc[ch, x]
                out[y, x0 + x, ch] = (total * exposure) * visibility


@njit(cache=True, fastmath=False)
def _radial_tasks(img, H, W, loop, mode, tile_w, taken, out):
    """Runs of :data:`RADIAL_RUN` consecutive tiles of :func:`_radial_tiles` (:func:`_radial_run`), taken on demand
    (:func:`~vlref.parallel.take`) until none is left; buffers allocated once, after the first task is taken (a
    separate function keeps the parallel kernel small, which is most of its compile time)."""
    tiles = (W + tile_w - 1) // tile_w * H
    first = take(taken) * RADIAL_RUN
    if first >= tiles:  # before any allocation: most workers find no task left
        return
    buffers = (np.empty(tile_w), np.empty(tile_w), np.empty(tile_w), np.empty(tile_w, np.uint64),
               np.empty(tile_w, np.uint64), np.empty((img.shape[2], tile_w)), np.empty(4 * tile_w))
    while first < tiles:
        _radial_run(img, H, W, loop, mode, tile_w, first, min(first + RADIAL_RUN, tiles), buffers, out)
        first = take(taken) * RADIAL_RUN


@njit(cache=True, fastmath=False, parallel=True)
def _radial_tiles(img, H, W, loop, mode):
    """Listing 13-1 on every pixel, then ``(C * exposure) * visibility``: (H, W, C). ``loop``: ``(lu, lv, scale,
    iterations, weight, tap_scale, decay, exposure, visibility)`` (:func:`_radial_loop`).

    The image is cut into tiles of one row, as wide as :data:`RADIAL_TILE` allows with column bands of equal width
    (1920 pixels: 8 bands of 240), ordered down the image column band by column band; the threads take runs of
    :data:`RADIAL_RUN` consecutive tiles on demand (:func:`_radial_tasks`: a thread's consecutive tiles read nearly
    the same texels, which stay in its cache; the tiles far from the light cost more, so an equal split would leave
    threads idle). The workers get the arrays without reference counts (:func:`~vlref.parallel.borrowed`: every tap
    passes the image to a function). Per tile, taps outer and pixels inner: the row's ``v`` (and so its texel row
    pair and ``ty``) is the same for every pixel at each tap, each pixel's ``u`` is stepped by the same repeated
    subtraction as the shaders, and the sums stay in a (C, tile) buffer; an RGB image's in a (tile, 4) one, a pixel's
    three channels read and summed as one vector (:func:`_tap_rows_rgb`). Per pixel the operations and their order
    are :func:`_fetch_add`'s, so the bits are those of the pixel-by-pixel loop and independent of the thread count
    and the tiling. ``mode``: an ``ADDRESS_*`` index; under ``ADDRESS_BORDER`` ``img`` is padded with one texel of 0
    on every side (a tap outside reads 0 where the clamped index lands in the padding).
    """
    out = np.empty((H, W, img.shape[2]))
    bands = (W + RADIAL_TILE - 1) // RADIAL_TILE
    tile_w = (W + bands - 1) // bands
    taken = task_counter()
    for _ in prange(WORKERS):
        im, o = borrowed((img, out))
        _radial_tasks(im, H, W, loop, mode, tile_w, taken, o)
    return out


def _radial_loop(image, light_uv, divisor: int, iterations: int, density: float, weight: float, tap_scale: float,
                 decay: float, address: str, exposure: float = 1.0, visibility: float = 1.0) -> np.ndarray:
    """``(C * exposure) * visibility`` with
    ``C = tex(u) + sum_{i=1..iterations} tex(u - i delta) * ((dec_i * tap_scale) * weight)``.

    ``delta = (u - l) * (1/divisor * density)``, ``u`` stepped by repeated subtraction, as the shaders do.
    """
    check_choice("address", address, ADDRESS_MODES)
    img = _image(image)
    if divisor < 1 or iterations < 0:
        raise ValueError(f"num_samples: need at least one sample, got {divisor}")
    if not np.isfinite(light_uv).all():
        raise ValueError(f"light_uv: must be finite, got {light_uv!r} (use light_screen_uv)")
    img3 = np.ascontiguousarray(img if img.ndim == 3 else img[..., None])
    H, W = img3.shape[:2]
    mode = ADDRESS_MODES.index(address)
    if address == "border":
        img3 = np.pad(img3, ((1, 1), (1, 1), (0, 0)))
    loop = (float(light_uv[0]), float(light_uv[1]), 1.0 / divisor * density, int(iterations), float(weight),
            float(tap_scale), float(decay), float(exposure), float(visibility))
    out = _radial_tiles(img3, H, W, loop, mode)
    return out if img.ndim == 3 else out[..., 0]


def radial_blur(image, light_uv, num_samples: int, density: float, weight: float, decay: float, exposure: float,
                address: str = "clamp", visibility: float = 1.0) -> np.ndarray:
    """GPU Gems 3 Listing 13-1 on ``image`` (the occlusion buffer), times ``exposure * visibility``.

    The book gives no defaults; the common ones (Sanglard's port: 100 samples, density 0.84,
    weight 5.65, decay 1.0, exposure 0.0034) are in ``vlref.scene.technique_params.RadialParams``.
    Output shape = ``image``'s; add it to the scene with ``composite.composite_add``.
    """
    return _radial_loop(image, light_uv, num_samples, num_samples, density, weight, 1.0, decay, address, exposure,
                        visibility)


def disenone_scatter(radiated, light_uv, density: float = 1.0, weight: float = 1.0 / 32.0, decay: float = 1.0,
                     num_samples: int = 32, iterations: int = 31, tap_scale: float = 0.03125,
                     address: str = "clamp") -> np.ndarray:
    """disenone's ``LightScattering`` loop (SOURCES §3.4) on the radiated occlusion, before exposure.

    ``delta = (u - l) * (1/32 * density)``; the initial term is ``tex(u)``; then **31** steps of
    ``u -= delta``, ``+= tex(u) * ((dec * 0.03125) * weight)``, ``dec *= decay`` -- so the last tap
    stops one step short of the light, and with the C# default ``weight = 1/32`` each tap weighs
    1/1024. The scene is *not* blurred: composite with
    ``composite_add(scene, light, disenone_exposure(...))``.
    """
    return _radial_loop(radiated, light_uv, num_samples, iterations, density, weight, tap_scale, decay, address)


def _pixel_uv(H: int, W: int):
    """uv of every pixel centre, (H, W) each."""
    u = (np.arange(W, dtype=np.float64)[None, :] + 0.5) / W
    v = (np.arange(H, dtype=np.float64)[:, None] + 0.5) / H
    return np.broadcast_to(u, (H, W)), np.broadcast_to(v, (H, W))


def radiate(occlusion, light_uv, radius_px: float = 100.0, peak: float = 0.5) -> np.ndarray:
    """disenone's ``LightRadiate`` pass: ``occ * saturate((R^2 - |d|^2) / R^2 * peak)``.

    ``d = ((u - l_u) W, (v - l_v) H)`` is the offset in *pixels of this target* (so the disc is
    round whatever the aspect), ``R = 100`` px (set by the C#; the material default is 50), peak
    0.5 at the light; ``occlusion`` is (H, W) or (H, W, C).
    """
    occ = _image(occlusion)
    H, W = occ.shape[:2]
    u, v = _pixel_uv(H, W)
    dx, dy = (u - light_uv[0]) * W, (v - light_uv[1]) * H
    r2 = radius_px * radius_px
    rho = np.clip((r2 - (dx * dx + dy * dy)) / r2 * peak, 0.0, 1.0)
    return occ * (rho[..., None] if occ.ndim == 3 else rho)


def disenone_exposure(exposure: float, angle_deg: float, half_fov_deg: float) -> float:
    """disenone's exposure dimming (SOURCES §3.4): 0 when ``angle + half_fov >= 90``, else
    ``exposure * (1 - (max(angle, half_fov) - half_fov) / half_fov)``.

    ``angle_deg`` is the angle between the camera forward and the direction to the light,
    ``half_fov_deg`` half the vertical field of view. Kept as the source has it: beyond
    ``angle = 2 half_fov`` the factor is negative (the effect subtracts light).
    """
    if angle_deg + half_fov_deg >= 90.0:
        return 0.0
    return exposure * (1.0 - (max(angle_deg, half_fov_deg) - half_fov_deg) / half_fov_deg)


def light_screen_uv(clip) -> tuple[tuple[float, float], float]:
    """Screen uv (row 0 = top) of a clip-space position ``(x, y, z, w)`` and its visibility factor.

    ``w > 0`` (in front of the camera): ``u = (x/w + 1) / 2``, ``v = (1 - y/w) / 2`` -- possibly
    outside ``[0, 1]`` when the light is off screen -- and visibility 1. ``w <= 0`` (behind the
    camera or in its plane): uv ``(0.5, 0.5)`` and visibility 0. A directional light's position is
    the point at infinity toward it, clip ``= VP @ (-direction, 0)``.
    """
    x, y, _, w = (float(c) for c in clip)
    if not w > 0.0 or not math.isfinite(x / w) or not math.isfinite(y / w):
        return (0.5, 0.5), 0.0
    return ((x / w + 1.0) * 0.5, (1.0 - y / w) * 0.5), 1.0


def occlusion_opaque(object_id, sky: float = 1.0) -> np.ndarray:
    """The occlusion pre-pass for opaque geometry: ``sky`` where nothing was hit (``object_id < 0``), 0 on objects."""
    oid = np.asarray(object_id)
    return np.where(oid < 0, sky, 0.0)


OCCLUSION_TRANSPARENCY = ("filter", "disenone")


def occlusion_transparent(occlusion, alpha, tint=None, mode: str = "filter") -> np.ndarray:
    """Lay one transparent layer (``alpha`` (H, W), 0 where absent or behind the opaque surface) over ``occlusion``.

    * ``"filter"``: the light the layer lets through, ``occ * (1 - alpha) * tint`` (``tint`` (H, W, 3)
      or RGB; white if ``None``) -- the chapter's "transparent objects occlude by their opacity".
    * ``"disenone"``: the port draws ``(1 - alpha)`` white with ``Blend SrcAlpha OneMinusSrcAlpha``,
      ``occ' = alpha (1 - alpha) + (1 - alpha) occ``, i.e. ``1 - alpha^2`` over the white background;
      ``tint`` is ignored.

    Layers are applied back to front. Returns (H, W, 3).
    """
    check_choice("mode", mode, OCCLUSION_TRANSPARENCY)
    occ = _image(occlusion)
    if occ.ndim == 2:
        occ = np.repeat(occ[..., None], 3, axis=2)
    a = np.asarray(alpha, dtype=np.float64)[..., None]
    if mode == "disenone":
        return a * (1.0 - a) + (1.0 - a) * occ
    t = np.ones(3) if tint is None else np.asarray(tint, dtype=np.float64)
    return occ * (1.0 - a) * t
