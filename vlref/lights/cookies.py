"""Light cookies: a 2D texture that modulates a light, and texture addressing/filtering.

Texture convention: texel ``(row r, column c)`` of an ``h x w`` texture has its centre at
``u = (c + 0.5)/w``, ``v = (r + 0.5)/h``, and row 0 is ``v = 0`` (Unity's ``GetPixels`` order,
bottom row first). Images are read with imageio (row 0 = top of the picture) and flipped on
load, so the picture appears upright with ``v`` up.

Projection, in the light frame ``(x_l, y_l, z_l)`` = (right, up, forward) of
``look_rotation(light.direction)``:

* spot: ``u = 0.5 + 0.5 · x_l / (z_l · tan(spot_angle/2))``, ``v = 0.5 + 0.5 · y_l / (z_l · tan(spot_angle/2))``
  (``z_l > 0``): the picture fills the square circumscribing the cone's cross-section, its right edge
  along the light's right axis and its top along the light's up axis (Unity's spot-cookie matrix,
  SOURCES §1.6).
* directional: ``u = 0.5 + x_l/size``, ``v = 0.5 + y_l/size`` with ``(x_l, y_l)`` measured from the
  light's ``position``: one tile of ``cookie.size`` metres centred on it; it tiles only with
  ``wrap = "repeat"``.

Filtering: ``nearest`` reads texel ``floor(u·w)``; ``bilinear`` blends the 2x2 texels around
``(u·w - 0.5, v·h - 0.5)``. Addressing: ``clamp`` (to the edge texel) or ``repeat``. Coordinates
and weights are computed in float64 (GPUs use their own fixed point); the value is then rounded
to the march's float type by the caller.

Channel: ``luminance`` = ``0.2126 R + 0.7152 G + 0.0722 B`` of the stored values (grey images: the
value), ``alpha`` (1 where the image has none), ``rgb`` (a coloured cookie). Values are the
stored 8/16-bit numbers scaled to [0, 1], used as linear factors (no sRGB decoding).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..jit import njit

__all__ = ["WRAP_CODES", "FILTER_CODES", "load_cookie", "filter_taps", "sample_texture", "spot_cookie_uv",
           "directional_cookie_uv"]

WRAP_CODES = {"clamp": 0, "repeat": 1}
FILTER_CODES = {"bilinear": 0, "nearest": 1}


def load_cookie(cookie, file: str, key: str) -> np.ndarray:
    """Read ``cookie.path`` into an (h, w, 3) float64 array in the texture convention above."""
    import imageio.v3 as iio

    try:
        img = np.asarray(iio.imread(cookie.path))
    except Exception as exc:  # imageio raises many types for unreadable files
        raise InputError(file, key + ".path", f"cannot read cookie image {cookie.path}: {exc}") from None
    if img.dtype == np.uint8:
        img = img / 255.0
    elif img.dtype == np.uint16:
        img = img / 65535.0
    elif img.dtype.kind == "f":
        img = img.astype(np.float64)
    else:
        raise InputError(file, key + ".path", f"unsupported cookie pixel type {img.dtype}")
    if img.ndim == 2:
        img = img[:, :, None]
    if img.ndim != 3 or img.shape[2] not in (1, 2, 3, 4) or min(img.shape[:2]) < 1:
        raise InputError(file, key + ".path", f"expected a 2D grey/RGB(A) image, got shape {img.shape}")
    grey = img.shape[2] <= 2
    rgb = np.repeat(img[:, :, :1], 3, axis=2) if grey else img[:, :, :3]
    if cookie.channel == "alpha":
        alpha = img[:, :, -1] if img.shape[2] in (2, 4) else np.ones(img.shape[:2])
        out = np.repeat(alpha[:, :, None], 3, axis=2)
    elif cookie.channel == "luminance":
        lum = rgb @ np.array([0.2126, 0.7152, 0.0722])
        out = np.repeat(lum[:, :, None], 3, axis=2)
    else:
        out = rgb
    return np.ascontiguousarray(out[::-1], dtype=np.float64)


@njit(cache=True, fastmath=False)
def _address(i, n, repeat):
    if repeat:
        return i % n
    return min(max(i, 0), n - 1)


@njit(cache=True, fastmath=False)
def filter_taps(u, n, repeat):
    """Bilinear taps along one axis of ``n`` texels: ``(i0, i1, weight of i1)`` at coordinate ``u``."""
    s = float(u) * n - 0.5
    f = math.floor(s)
    i0 = int(f)
    return _address(i0, n, repeat), _address(i0 + 1, n, repeat), s - f


@njit(cache=True, fastmath=False)
def sample_texture(texels, offset, w, h, repeat, nearest, u, v):
    """RGB of the (h, w) texture stored row-major at ``texels[offset:offset + w*h]`` at ``(u, v)`` (float64)."""
    if nearest:
        c = _address(int(math.floor(float(u) * w)), w, repeat)
        r = _address(int(math.floor(float(v) * h)), h, repeat)
        k = offset + r * w + c
        return float(texels[k, 0]), float(texels[k, 1]), float(texels[k, 2])
    c0, c1, fc = filter_taps(u, w, repeat)
    r0, r1, fr = filter_taps(v, h, repeat)
    w00, w01, w10, w11 = (1.0 - fc) * (1.0 - fr), fc * (1.0 - fr), (1.0 - fc) * fr, fc * fr
    k00, k01, k10, k11 = offset + r0 * w + c0, offset + r0 * w + c1, offset + r1 * w + c0, offset + r1 * w + c1
    red, green, blue = np.int64(0), np.int64(1), np.int64(2)  # not literals: _blend compiles once, not per channel
    return (_blend(texels, red, k00, k01, k10, k11, w00, w01, w10, w11),
            _blend(texels, green, k00, k01, k10, k11, w00, w01, w10, w11),
            _blend(texels, blue, k00, k01, k10, k11, w00, w01, w10, w11))


@njit(cache=True, fastmath=False)
def _blend(texels, ch, k00, k01, k10, k11, w00, w01, w10, w11):
    return (w00 * float(texels[k00, ch]) + w01 * float(texels[k01, ch]) + w10 * float(texels[k10, ch])
            + w11 * float(texels[k11, ch]))


@njit(cache=True, fastmath=False)
def spot_cookie_uv(xl, yl, zl, tan_half):
    """Spot cookie coordinates of a light-frame point with ``zl > 0`` (module docstring)."""
    k = 0.5 / (float(zl) * float(tan_half))
    return 0.5 + float(xl) * k, 0.5 + float(yl) * k


@njit(cache=True, fastmath=False)
def directional_cookie_uv(xl, yl, size):
    """Directional cookie coordinates of light-frame offsets from the light's position."""
    return 0.5 + float(xl) / float(size), 0.5 + float(yl) / float(size)
