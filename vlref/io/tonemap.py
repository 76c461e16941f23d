"""The tone map of previews: linear HDR -> exposure -> ACES filmic fit -> sRGB OETF -> 8-bit codes.

Previews are for eyes only, never compared: ``value * exposure`` -> ACES filmic fit (Narkowicz 2015,
``x(2.51x+0.03) / (x(2.43x+0.59)+0.14)``) clamped to [0, 1] -> sRGB OETF (IEC 61966-2-1) -> 8 bit. The
exposure may come from a percentile (:func:`vlref.io.exposure.percentile_exposure`).
"""

from __future__ import annotations

import concurrent.futures

import numpy as np

from ..processes import host_cores

__all__ = ["srgb8"]

_SRGB_BAND = 1 << 20
"""Values per band at least (smaller images run in one band): a 1080p preview in 5 bands, so at most 5 threads. Each
of a chunk's ~20 ufunc calls releases the GIL and takes it back, and many threads making many short calls queue for
it: on the 16-core device the preview's tone map took 75-78 ms in 16 bands of 2^16 values against 29 ms in 5 bands,
and the render's writing (the EXR files beside the preview) 0.176-0.178 s against 0.140 s (BENCHMARKS.md "The
writing: EXR files at deflate level 1")."""
_SRGB_CHUNK = 1 << 18
"""About the values a band evaluates at once (its rows in chunks: the chunk's three scratch arrays, 6 MB, are
allocated again and again from the same pages); fewer ufunc calls than chunks of 2^16, in arrays that stay small."""


def srgb8(image: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Tone-map a linear HDR image to 8-bit sRGB: ``(H, W)``/``(H, W, 1)`` -> grey, ``(H, W, 3)`` -> RGB.

    ``x = exposure * value`` (NaN -> 0, negatives -> 0, values above 1e6 clipped first), then the ACES
    filmic fit ``x(2.51x+0.03)/(x(2.43x+0.59)+0.14)`` clamped to [0, 1] (Narkowicz 2015), then the sRGB
    OETF ``12.92 y`` for ``y <= 0.0031308`` else ``1.055 y^(1/2.4) - 0.055``, then ``round(255 s)``.
    Returns ``(H, W, 3)`` uint8. Elementwise NumPy over bands of rows on threads (NumPy's ufuncs release the GIL;
    at most a thread per core, each band at least :data:`_SRGB_BAND` values), each band in chunks of rows
    (:data:`_SRGB_CHUNK`): the same codes as the whole array at once, without a kernel to compile.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"preview needs (H, W), (H, W, 1) or (H, W, 3), got shape {a.shape}")
    out = np.empty(a.shape, dtype=np.uint8)
    bands = min(host_cores(), max(1, a.size // _SRGB_BAND))
    edges = np.linspace(0, a.shape[0], bands + 1).astype(int)

    rows = max(1, _SRGB_CHUNK // (a.shape[1] * 3))

    def band(k: int) -> None:
        for r in range(edges[k], edges[k + 1], rows):
            end = min(r + rows, edges[k + 1])
            out[r:end] = _srgb8_values(a[r:end], float(exposure))

    if bands == 1:
        band(0)
    else:
        with concurrent.futures.ThreadPoolExecutor(bands) as pool:
            list(pool.map(band, range(bands)))
    return out


def _srgb8_values(a: np.ndarray, exposure: float) -> np.ndarray:
    """The formula of :func:`srgb8` on an array of values, evaluated in place in three arrays of ``a``'s size
    (written out, the formula makes about twenty: each a fresh allocation whose pages the first preview of a
    process faults in, on every band's thread at once). The same operations on the same values in the same
    order: the same codes."""
    x = a * exposure
    np.nan_to_num(x, copy=False, nan=0.0, posinf=1e6, neginf=0.0)
    np.clip(x, 0.0, 1e6, out=x)
    y = 2.51 * x  # x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)
    y += 0.03
    y *= x
    den = 2.43 * x
    den += 0.59
    den *= x
    den += 0.14
    y /= den
    np.clip(y, 0.0, 1.0, out=y)
    s = np.power(y, 1.0 / 2.4, out=den)  # 1.055 y^(1/2.4) - 0.055, or 12.92 y at and below 0.0031308
    s *= 1.055
    s -= 0.055
    np.multiply(y, 12.92, out=s, where=y <= 0.0031308)
    np.clip(s, 0.0, 1.0, out=s)
    s *= 255.0
    return np.round(s, out=s).astype(np.uint8)
