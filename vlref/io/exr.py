"""EXR files: float32 (or half) channels, ZIP-compressed on OpenEXR's thread pool, string metadata.

Conventions
-----------
* EXR files hold **float32** channels (or **half** where the caller asks: ``write_exr(half=True)``,
  ``vlref render --half-float``), ZIP-compressed at deflate level :data:`ZIP_LEVEL` on OpenEXR's thread pool (one
  thread per core), one scanline part; row 0 = top row (EXR's natural ``INCREASING_Y`` order).
* Channel names: ``(H, W)`` -> ``Y``; ``C = 2, 3, 4`` -> ``R,G`` / ``R,G,B`` / ``R,G,B,A``; other
  counts need explicit names. A dict ``name -> (H, W)`` writes those names. The written order is kept
  in the string attribute ``vlref_channels`` (EXR itself stores channels sorted by name).
* Metadata: string header attributes. ``vlref_version`` (``vlref.__version__``) is always written;
  non-string values (settings dicts) are stored as canonical JSON (sorted keys).
"""

from __future__ import annotations

import ctypes
import functools
import json
from pathlib import Path
from typing import BinaryIO, Mapping, Sequence

import numpy as np

from .. import __version__
from ..errors import InputError
from ..processes import host_cores
from .files import atomic_write, require_file

__all__ = ["write_exr", "read_exr", "default_channel_names", "checked_channels", "channel_dict", "exr_order",
           "ZIP_LEVEL"]

ZIP_LEVEL = 1
"""The deflate level of the files' ZIP compression: the fastest. OpenEXR's default is 4; at level 1 the four 1080p
default outputs of bench (b) take 0.39-0.41 s to write against 0.57 s on the dev box's two threads (0.69x) and are
49.69 MB against 48.91 MB (+1.6 %); on the 16-core device a fresh process's writing took 0.195 s against 0.214 s
(BENCHMARKS.md "The writing: EXR files at deflate level 1"). Lossless at any level: the same pixels."""

# Attributes every EXR header carries; user metadata may not reuse these names.
_EXR_STANDARD = frozenset({
    "channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
    "screenWindowCenter", "screenWindowWidth", "type", "tiles", "name", "version", "chunkCount",
})
_FLOAT32_EXACT_INT = 2 ** 24  # integers up to this magnitude are exact in float32


def default_channel_names(count: int) -> tuple[str, ...]:
    """EXR channel names for ``count`` channels: 1 -> Y, 2 -> R,G, 3 -> R,G,B, 4 -> R,G,B,A."""
    names = {1: ("Y",), 2: ("R", "G"), 3: ("R", "G", "B"), 4: ("R", "G", "B", "A")}
    if count not in names:
        raise ValueError(f"{count} channels need explicit channel names")
    return names[count]


def _checked(name: str, array: np.ndarray) -> np.ndarray:
    """A 2-D channel that float32 holds (``array`` itself): floats, or integers exact in float32 (|v| <= 2**24)."""
    a = np.asarray(array)
    if a.ndim != 2 or a.size == 0:
        raise ValueError(f"channel {name!r}: expected a non-empty (H, W) array, got shape {a.shape}")
    if a.dtype.kind in "iub":
        if a.size and np.abs(a.astype(np.int64)).max() > _FLOAT32_EXACT_INT:
            raise ValueError(f"channel {name!r}: integers beyond 2**24 are not exact in float32")
    elif a.dtype.kind != "f":
        raise ValueError(f"channel {name!r}: cannot store dtype {a.dtype} as float32")
    return a


def checked_channels(image_or_channels, channels: Sequence[str] | str | None) -> dict[str, np.ndarray]:
    """``{name: (H, W) array}`` of an array (names: ``channels`` or :func:`default_channel_names`) or of a dict of
    channels, each one that float32 holds, not yet converted (views of the given arrays); ValueError for bad shapes,
    dtypes or names."""
    if isinstance(image_or_channels, Mapping):
        if channels is not None:
            raise ValueError("channel names come from the dict's keys; do not pass channels=")
        items = list(image_or_channels.items())
    else:
        a = np.asarray(image_or_channels)
        if a.ndim == 2:
            a = a[:, :, None]
        if a.ndim != 3:
            raise ValueError(f"expected an (H, W) or (H, W, C) array, got shape {a.shape}")
        if isinstance(channels, str):
            channels = (channels,)
        names = tuple(channels) if channels is not None else default_channel_names(a.shape[2])
        if len(names) != a.shape[2]:
            raise ValueError(f"{len(names)} channel names for {a.shape[2]} channels")
        items = [(n, a[:, :, i]) for i, n in enumerate(names)]
    if not items:
        raise ValueError("no channels to write")
    if len({n for n, _ in items}) != len(items):
        raise ValueError("duplicate channel names")
    out = {str(n): _checked(str(n), v) for n, v in items}
    shapes = {v.shape for v in out.values()}
    if len(shapes) != 1:
        raise ValueError(f"channels differ in shape: {sorted(shapes)}")
    return out


def channel_dict(image_or_channels, channels: Sequence[str] | str | None) -> dict[str, np.ndarray]:
    """``{name: (H, W) float32}`` (contiguous) of the channels :func:`checked_channels` takes; ValueError for bad
    shapes, dtypes or names."""
    return {name: np.ascontiguousarray(a, dtype=np.float32)
            for name, a in checked_channels(image_or_channels, channels).items()}


@functools.cache
def _openexr():
    """The OpenEXR module, its global thread pool set to this process's cores once (the writer compresses blocks of
    scanlines on it: a 1080p frame's four files, ZIP: 1.35 s on one thread, 0.22 s on 16; device) and its default ZIP
    level to :data:`ZIP_LEVEL` (:func:`_set_default_zip_level`). Both are OpenEXR's process-wide settings: other
    code of the process that writes EXR files through OpenEXR afterwards gets them too."""
    import OpenEXR

    OpenEXR.set_global_thread_count(host_cores())
    _set_default_zip_level(OpenEXR, ZIP_LEVEL)
    return OpenEXR


def _set_default_zip_level(module, level: int) -> bool:
    """Set the deflate level of the ZIP files that OpenEXR writes from now on, through the call of its C API that
    the Python binding does not offer (``exr_set_default_zip_compression_level``, ``openexr_context.h``; the C++
    writer reads the same default), found in the binding's own extension module (``module.__file__``), where
    OpenEXR's library is linked in. True where it was set; False where the extension does not export the call
    (OpenEXR then writes at its own default level, the same pixels)."""
    try:
        setter = ctypes.CDLL(module.__file__).exr_set_default_zip_compression_level
    except (OSError, AttributeError):
        return False
    setter.argtypes, setter.restype = [ctypes.c_int], None
    setter(level)
    return True


def _header(metadata: Mapping[str, object] | None, order: Sequence[str]) -> dict:
    OpenEXR = _openexr()
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    for key, value in (metadata or {}).items():
        if key in _EXR_STANDARD:
            raise ValueError(f"metadata key {key!r} is a standard EXR attribute")
        header[key] = value if isinstance(value, str) else json.dumps(value, sort_keys=True)
    header["vlref_version"] = __version__
    header["vlref_channels"] = ",".join(order)
    return header


def write_exr(path, image_or_channels, channels: Sequence[str] | str | None = None,
              metadata: Mapping[str, object] | None = None, half: bool = False) -> Path:
    """Write a float32 (``half``: float16), ZIP-compressed EXR atomically.

    Parameters
    ----------
    path : file name (its folder must exist).
    image_or_channels : ``(H, W)`` or ``(H, W, C)`` array, or a dict ``name -> (H, W)`` array.
        Floats are cast to float32 (float64 rounds to nearest); integer arrays (e.g. object ids)
        must be exact in float32.
    channels : names for an array's channels (default: see :func:`default_channel_names`);
        a single string names a single channel.
    metadata : extra header attributes (strings, or JSON-serialisable values stored as JSON).
    half : store half-float channels (float32 rounded to nearest: 11 significant bits, finite up to 65504,
        larger magnitudes become inf); half the bytes. Readers widen them to float32 exactly.
    """
    OpenEXR = _openexr()

    data = channel_dict(image_or_channels, channels)
    if half:
        if any(a.dtype.kind != "f" for a in _source_arrays(image_or_channels)):
            raise ValueError("half: integer channels (object ids) stay float32")
        with np.errstate(over="ignore"):
            data = {name: a.astype(np.float16) for name, a in data.items()}
    header = _header(metadata, list(data))

    def write(fh: BinaryIO) -> None:
        with OpenEXR.File(header, data) as f:
            f.write(fh)

    return atomic_write(path, write)


def _source_arrays(image_or_channels) -> list[np.ndarray]:
    """The arrays given to :func:`write_exr` (a dict's values, or the one array)."""
    if isinstance(image_or_channels, Mapping):
        return [np.asarray(v) for v in image_or_channels.values()]
    return [np.asarray(image_or_channels)]


def read_exr(path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Read an EXR: ``({name: (H, W) float32}, {attribute: string})``.

    Half channels are widened to float32 (exact); integer (UINT) channels and subsampled channels are
    rejected. The metadata dict holds the file's string attributes (``vlref_version``, ``scene_hash``,
    ``settings`` JSON, ``vlref_channels``, ...), not the standard EXR ones.
    """
    import OpenEXR

    path = Path(path)
    require_file(path)
    try:
        with OpenEXR.File(str(path), separate_channels=True) as f:
            header = dict(f.header())  # copies: the File's own objects do not outlive it
            raw = {name: np.array(ch.pixels, copy=True) for name, ch in f.channels().items()}
    except Exception as exc:  # the binding raises RuntimeError, but be safe on corrupt data
        raise InputError(str(path), "", f"unreadable EXR file ({exc})") from exc
    (x0, y0), (x1, y1) = header["dataWindow"]
    shape = (int(y1) - int(y0) + 1, int(x1) - int(x0) + 1)
    out: dict[str, np.ndarray] = {}
    for name, px in raw.items():
        px = np.asarray(px)
        if px.dtype.kind != "f":
            raise InputError(str(path), name, f"wrong dtype {px.dtype} (expected float or half channels)")
        if px.shape != shape:
            raise InputError(str(path), name, f"subsampled channel of shape {px.shape}, image is {shape}")
        out[name] = px.astype(np.float32, copy=False)
    meta = {k: v for k, v in header.items() if isinstance(v, str) and k not in _EXR_STANDARD}
    return out, meta


def exr_order(names: Sequence[str], meta: Mapping[str, str]) -> list[str]:
    """The order of an EXR's channels for an image: RGBA order when the names are a subset of R,G,B,A; else
    the written order (``vlref_channels``); else sorted."""
    if set(names) <= set("RGBA"):
        return [c for c in "RGBA" if c in names]
    written = meta.get("vlref_channels", "").split(",")
    if sorted(written) == sorted(names):
        return written
    return sorted(names)
