"""Images read and checked: EXR, PNG, NPY or NPZ as an ``(H, W, C)`` float array, row 0 on top.

Every reader checks type, shape, dtype, channel count and values (NaN always, inf on request) and raises
:class:`vlref.errors.InputError` ``(file, field, reason)``, naming the first bad pixel.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import InputError
from .exr import exr_order, read_exr
from .files import require_file

__all__ = ["read_image"]


def read_image(path, *, channels: int | Sequence[int] | None = None, allow_inf: bool = True,
               key: str | None = None) -> np.ndarray:
    """Read ``.exr``, ``.png``, ``.npy`` or ``.npz`` as an ``(H, W, C)`` float array (row 0 = top).

    * EXR: channels in R,G,B,A order when they are a subset of those, else in the written order
      (``vlref_channels``), else sorted by name; float32.
    * PNG: 8- or 16-bit code values scaled to [0, 1] (no sRGB decoding: PNGs compare with PNGs); float32.
    * NPY/NPZ: floating-point arrays only (half is widened to float32, float64 kept). An NPZ must hold
      one array, or ``key`` names it.

    ``channels`` restricts the channel count. ``±inf`` is a legal value by default (sky in the canonical
    depth buffer); ``allow_inf=False`` rejects it for inputs that must be finite. NaN is always rejected.
    Raises :class:`InputError` naming the file, the field and the reason.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".exr", ".png", ".npy", ".npz"):
        raise InputError(str(path), "", f"unsupported file type {suffix or '(none)'!r} "
                                        "(expected .exr, .png, .npy or .npz)")
    require_file(path)
    if suffix == ".exr":
        data, meta = read_exr(path)
        a, file = np.stack([data[n] for n in exr_order(list(data), meta)], axis=-1), str(path)
    elif suffix == ".png":
        a, file = _read_png(path), str(path)
    else:
        a, file = _read_numpy(path, key)
    return _check_image(a, file, channels, allow_inf)


def _check_image(a: np.ndarray, file: str, channels, allow_inf: bool) -> np.ndarray:
    """Validate an array as an image and return it as (H, W, C) float32/float64."""
    if a.dtype.kind != "f":
        raise InputError(file, "dtype", f"wrong dtype {a.dtype} (expected a floating-point array)")
    if a.dtype.itemsize < 4:
        a = a.astype(np.float32)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.size == 0:
        raise InputError(file, "shape", f"wrong shape {a.shape} (expected non-empty (H, W) or (H, W, C))")
    if channels is not None:
        allowed = (channels,) if isinstance(channels, int) else tuple(channels)
        if a.shape[2] not in allowed:
            want = " or ".join(str(c) for c in allowed)
            raise InputError(file, "channels", f"wrong channel count {a.shape[2]} (expected {want})")
    _reject(np.isnan(a), file, "NaN")
    if not allow_inf:
        _reject(np.isinf(a), file, "infinite")
    return a


def _reject(bad: np.ndarray, file: str, what: str) -> None:
    """Raise InputError when the (H, W, C) mask ``bad`` has any true value, naming the first pixel."""
    if bad.any():
        y, x, c = np.argwhere(bad)[0]
        raise InputError(file, "values", f"{int(bad.sum())} {what} value(s) present "
                                         f"(first at pixel x={x}, y={y}, channel {c})")


def _read_png(path: Path) -> np.ndarray:
    """8/16-bit PNG code values scaled to [0, 1], float32, (H, W) or (H, W, C)."""
    import imageio.v3 as iio
    try:
        raw = iio.imread(path, extension=".png")
    except Exception as exc:
        raise InputError(str(path), "", f"unreadable PNG file ({exc})") from exc
    if raw.dtype not in (np.uint8, np.uint16):
        raise InputError(str(path), "dtype", f"unsupported PNG sample type {raw.dtype}")
    return raw.astype(np.float32) / np.float32(np.iinfo(raw.dtype).max)


def _read_numpy(path: Path, key: str | None) -> tuple[np.ndarray, str]:
    """The array of an NPY file, or the only / the ``key`` array of an NPZ file, and its label."""
    file = str(path)
    try:
        loaded = np.load(path, allow_pickle=False)
    except Exception as exc:
        raise InputError(file, "", f"unreadable {path.suffix[1:].upper()} file ({exc})") from exc
    if isinstance(loaded, np.ndarray):
        return loaded, file
    with loaded:
        names = list(loaded.files)
        if key is None and len(names) != 1:
            raise InputError(file, "", f"holds arrays {', '.join(names) or '(none)'}; name one with a key")
        name = key if key is not None else names[0]
        if name not in names:
            raise InputError(file, name, f"no such array (has {', '.join(names) or 'none'})")
        try:
            return loaded[name], f"{file}[{name}]"
        except Exception as exc:
            raise InputError(file, name, f"unreadable array ({exc})") from exc
