"""Image files: float32 EXR, tone-mapped sRGB PNG previews, NPY/NPZ; checked readers; atomic writes.

Conventions
-----------
* Arrays are ``(H, W)`` or ``(H, W, C)``, row 0 = top row (EXR's natural ``INCREASING_Y`` order), linear
  HDR values. EXR files hold **float32** channels (or **half** where the caller asks: ``write_exr(half=True)``,
  ``vlref render --half-float``), ZIP-compressed on OpenEXR's thread pool (one thread per core), one
  scanline part.
* Channel names: ``(H, W)`` -> ``Y``; ``C = 2, 3, 4`` -> ``R,G`` / ``R,G,B`` / ``R,G,B,A``; other
  counts need explicit names. A dict ``name -> (H, W)`` writes those names. The written order is kept
  in the string attribute ``vlref_channels`` (EXR itself stores channels sorted by name).
* Metadata: string header attributes. ``vlref_version`` (``vlref.__version__``) is always written;
  non-string values (settings dicts) are stored as canonical JSON (sorted keys).
* PNG files are previews only, never compared: ``value * exposure`` -> ACES filmic fit (Narkowicz 2015,
  ``x(2.51x+0.03) / (x(2.43x+0.59)+0.14)``) clamped to [0, 1] -> sRGB OETF (IEC 61966-2-1) -> 8 bit,
  zlib level 1 (the fastest; a 1080p preview: 0.40 s at Pillow's default 6, 0.15 s at 1, 15 % larger).
  The exposure may come from a percentile (:func:`percentile_exposure`); PNG ``tEXt`` chunks record it.
* Every write is atomic: the bytes go to a temporary file in the destination folder, are fsync'ed,
  then ``os.replace`` moves them into place; on any failure the temporary file is removed and no
  partial file remains. :func:`output_dir` extends this to a set of files (all or nothing).
* Readers check type, shape, dtype, channel count and values (NaN always, inf on request) and raise
  :class:`vlref.errors.InputError` ``(file, field, reason)``.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import functools
import json
import os
import re
import shutil
import tempfile
import uuid
from pathlib import Path
from typing import BinaryIO, Callable, Iterator, Mapping, Sequence

import numpy as np

from . import __version__
from .errors import InputError

__all__ = [
    "write_exr", "read_exr", "read_image", "write_png", "write_npy", "write_npz", "save_buffers",
    "save_render", "output_dir", "check_output_dir", "check_output_file", "srgb8", "png_bytes", "png_text",
    "percentile_exposure", "luminance", "default_channel_names", "write_bytes", "write_text",
]

# Attributes every EXR header carries; user metadata may not reuse these names.
_EXR_STANDARD = frozenset({
    "channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
    "screenWindowCenter", "screenWindowWidth", "type", "tiles", "name", "version", "chunkCount",
})
_FLOAT32_EXACT_INT = 2 ** 24  # integers up to this magnitude are exact in float32
_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")


# --------------------------------------------------------------------------- atomic writes

def _fsync_dir(directory: Path) -> None:
    """Flush a folder's entries (the renames) to disk; a no-op where folders cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _atomic_write(path: str | os.PathLike, write: Callable[[BinaryIO], None]) -> Path:
    """Call ``write(fileobj)`` on a temporary file next to ``path``, fsync it, then rename it to ``path``.

    The temporary file is created with mode ``0o666`` minus the umask (so the result has ordinary
    permissions) and removed if ``write`` or any later step raises.
    """
    path = Path(path)
    tmp = path.parent / f".{path.name}.{uuid.uuid4().hex[:12]}.tmp"
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    _fsync_dir(path.parent)
    return path


def _probe(folder: Path, key: str, target: Path) -> None:
    """Create and remove a file in ``folder``: the only test of writability that holds for root too
    (``os.access`` says yes to root even on a read-only or virtual file system)."""
    try:
        fd, name = tempfile.mkstemp(prefix=".vlref-probe.", dir=folder)
        os.close(fd)
        os.unlink(name)
    except OSError as exc:
        raise InputError("<command line>", key, f"cannot write {target}: {exc.strerror or exc} "
                         f"(in {folder})") from None


def check_output_dir(path: str | os.PathLike, key: str = "output") -> Path:
    """Check, before any work, that ``path`` can become an output folder; returns its nearest existing ancestor.

    The check does what the write will do: it creates the missing folders up to ``path``, a file in the
    ancestor that will hold the temporary folder and one in ``path``, and removes all it created.
    :class:`InputError` ``("<command line>", key, reason)`` when ``path`` (or an ancestor) exists and is not
    a folder, or when any of that fails (read-only or virtual file system, permissions).
    """
    final = Path(path)
    if final.exists() and not final.is_dir():
        raise InputError("<command line>", key, f"{final} exists and is not a folder")
    anchor = final.absolute().parent
    while not anchor.exists():
        anchor = anchor.parent
    if not anchor.is_dir():
        raise InputError("<command line>", key, f"{anchor} is a file, not a folder: cannot create {final}")
    created = []
    try:
        for folder in reversed([final.absolute(), *final.absolute().parents]):
            if not folder.exists():
                try:
                    folder.mkdir()
                except OSError as exc:
                    raise InputError("<command line>", key, f"cannot create {final}: {exc.strerror or exc} "
                                     f"(at {folder})") from None
                created.append(folder)
        _probe(anchor, key, final)
        _probe(final, key, final)
    finally:
        for folder in reversed(created):
            folder.rmdir()
    return anchor


def check_output_file(path: str | os.PathLike, key: str = "output") -> None:
    """Check, before any work, that the file ``path`` can be written: not a folder, its folder exists and
    a file can be created there (:func:`_probe`), an existing ``path`` is writable;
    :class:`InputError` ``("<command line>", key, reason)`` otherwise."""
    target = Path(path)
    if target.is_dir():
        raise InputError("<command line>", key, f"{target} is a folder, not a file")
    folder = target.absolute().parent
    if not folder.is_dir():
        raise InputError("<command line>", key, f"folder {folder} does not exist")
    _probe(folder, key, target)
    if target.exists() and not os.access(target, os.W_OK):
        raise InputError("<command line>", key, f"{target} is not writable")


@contextlib.contextmanager
def output_dir(path: str | os.PathLike) -> Iterator[Path]:
    """Write a set of files all or nothing: yields a temporary folder, moved into ``path`` on success.

    The temporary folder is created next to ``path`` (inside its nearest existing ancestor, so the
    final renames stay on one file system). When the ``with`` block exits normally, missing parent
    folders and ``path`` are created and every file is moved in with ``os.replace`` (files already in
    ``path`` with the same names are replaced, others are kept). When the block raises, the temporary
    folder is deleted and ``path`` is left exactly as it was (not even created).
    """
    final = Path(path)
    anchor = check_output_dir(final)
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=".partial", dir=anchor))
    try:
        yield tmp
        final.mkdir(parents=True, exist_ok=True)
        for src in sorted(tmp.rglob("*")):  # parents sort before their contents
            dst = final / src.relative_to(tmp)
            if src.is_dir():
                dst.mkdir(exist_ok=True)
            else:
                os.replace(src, dst)
        _fsync_dir(final)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


# --------------------------------------------------------------------------- EXR

def default_channel_names(count: int) -> tuple[str, ...]:
    """EXR channel names for ``count`` channels: 1 -> Y, 2 -> R,G, 3 -> R,G,B, 4 -> R,G,B,A."""
    names = {1: ("Y",), 2: ("R", "G"), 3: ("R", "G", "B"), 4: ("R", "G", "B", "A")}
    if count not in names:
        raise ValueError(f"{count} channels need explicit channel names")
    return names[count]


def _as_float32(name: str, array: np.ndarray) -> np.ndarray:
    """A 2-D channel as contiguous float32; integers must be exact in float32 (|v| <= 2**24)."""
    a = np.asarray(array)
    if a.ndim != 2 or a.size == 0:
        raise ValueError(f"channel {name!r}: expected a non-empty (H, W) array, got shape {a.shape}")
    if a.dtype.kind in "iub":
        if a.size and np.abs(a.astype(np.int64)).max() > _FLOAT32_EXACT_INT:
            raise ValueError(f"channel {name!r}: integers beyond 2**24 are not exact in float32")
    elif a.dtype.kind != "f":
        raise ValueError(f"channel {name!r}: cannot store dtype {a.dtype} as float32")
    return np.ascontiguousarray(a, dtype=np.float32)


def _channel_dict(image_or_channels, channels: Sequence[str] | str | None) -> dict[str, np.ndarray]:
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
    out = {str(n): _as_float32(str(n), v) for n, v in items}
    shapes = {v.shape for v in out.values()}
    if len(shapes) != 1:
        raise ValueError(f"channels differ in shape: {sorted(shapes)}")
    return out


@functools.cache
def _openexr():
    """The OpenEXR module, its global thread pool set to this process's cores once: the writer compresses
    blocks of scanlines on it (a 1080p frame's four files, ZIP: 1.35 s on one thread, 0.22 s on 16; device)."""
    import OpenEXR

    OpenEXR.set_global_thread_count(_cores())
    return OpenEXR


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

    data = _channel_dict(image_or_channels, channels)
    if half:
        if any(a.dtype.kind != "f" for a in _source_arrays(image_or_channels)):
            raise ValueError("half: integer channels (object ids) stay float32")
        with np.errstate(over="ignore"):
            data = {name: a.astype(np.float16) for name, a in data.items()}
    header = _header(metadata, list(data))

    def write(fh: BinaryIO) -> None:
        with OpenEXR.File(header, data) as f:
            f.write(fh)

    return _atomic_write(path, write)


def _source_arrays(image_or_channels) -> list[np.ndarray]:
    """The arrays given to :func:`write_exr` (a dict's values, or the one array)."""
    if isinstance(image_or_channels, Mapping):
        return [np.asarray(v) for v in image_or_channels.values()]
    return [np.asarray(image_or_channels)]


def _require_file(path: Path) -> None:
    if not path.is_file():
        raise InputError(str(path), "", "file not found" if not path.exists() else "not a file")


def read_exr(path) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Read an EXR: ``({name: (H, W) float32}, {attribute: string})``.

    Half channels are widened to float32 (exact); integer (UINT) channels and subsampled channels are
    rejected. The metadata dict holds the file's string attributes (``vlref_version``, ``scene_hash``,
    ``settings`` JSON, ``vlref_channels``, ...), not the standard EXR ones.
    """
    import OpenEXR

    path = Path(path)
    _require_file(path)
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


def _exr_order(names: Sequence[str], meta: Mapping[str, str]) -> list[str]:
    """RGBA order when the names are a subset of R,G,B,A; else the written order; else sorted."""
    if set(names) <= set("RGBA"):
        return [c for c in "RGBA" if c in names]
    written = meta.get("vlref_channels", "").split(",")
    if sorted(written) == sorted(names):
        return written
    return sorted(names)


# --------------------------------------------------------------------------- readers

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
    _require_file(path)
    if suffix == ".exr":
        data, meta = read_exr(path)
        a, file = np.stack([data[n] for n in _exr_order(list(data), meta)], axis=-1), str(path)
    elif suffix == ".png":
        a, file = _read_png(path), str(path)
    else:
        a, file = _read_numpy(path, key)
    return _check_image(a, file, channels, allow_inf)


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


# --------------------------------------------------------------------------- previews, NPY/NPZ

def srgb8(image: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Tone-map a linear HDR image to 8-bit sRGB: ``(H, W)``/``(H, W, 1)`` -> grey, ``(H, W, 3)`` -> RGB.

    ``x = exposure * value`` (NaN -> 0, negatives -> 0, values above 1e6 clipped first), then the ACES
    filmic fit ``x(2.51x+0.03)/(x(2.43x+0.59)+0.14)`` clamped to [0, 1] (Narkowicz 2015), then the sRGB
    OETF ``12.92 y`` for ``y <= 0.0031308`` else ``1.055 y^(1/2.4) - 0.055``, then ``round(255 s)``.
    Returns ``(H, W, 3)`` uint8. Elementwise NumPy over bands of rows on a thread per core (NumPy's ufuncs
    release the GIL): the same codes as the whole array at once, without a kernel to compile.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"preview needs (H, W), (H, W, 1) or (H, W, 3), got shape {a.shape}")
    out = np.empty(a.shape, dtype=np.uint8)
    bands = min(_cores(), max(1, a.size // _SRGB_BAND))
    edges = np.linspace(0, a.shape[0], bands + 1).astype(int)

    def band(k: int) -> None:
        out[edges[k]:edges[k + 1]] = _srgb8_values(a[edges[k]:edges[k + 1]], float(exposure))

    if bands == 1:
        band(0)
    else:
        with concurrent.futures.ThreadPoolExecutor(bands) as pool:
            list(pool.map(band, range(bands)))
    return out


_SRGB_BAND = 1 << 16
"""Values per band at least (smaller images run in one band)."""


def _srgb8_values(a: np.ndarray, exposure: float) -> np.ndarray:
    """The formula of :func:`srgb8` on an array of values."""
    x = np.clip(np.nan_to_num(a * exposure, nan=0.0, posinf=1e6, neginf=0.0), 0.0, 1e6)
    y = np.clip(x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0)
    s = np.where(y <= 0.0031308, 12.92 * y, 1.055 * np.power(y, 1.0 / 2.4) - 0.055)
    return np.round(np.clip(s, 0.0, 1.0) * 255.0).astype(np.uint8)


def _cores() -> int:
    """CPU cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


LUMINANCE = (0.2126, 0.7152, 0.0722)
"""Rec. 709 / sRGB luminance weights of linear RGB."""


def luminance(image: np.ndarray) -> np.ndarray:
    """Rec. 709 luminance ``0.2126 R + 0.7152 G + 0.0722 B`` of ``(H, W, 3)``; ``(H, W)``/(H, W, 1) pass through."""
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 3 and a.shape[2] == 1:
        return a[:, :, 0]
    return a @ np.asarray(LUMINANCE) if a.ndim == 3 else a


def percentile_exposure(values: np.ndarray, percentile: float = 99.0) -> tuple[float, float]:
    """``(1 / level, level)``, ``level`` the ``percentile`` of the finite ``values``: the exposure that maps that
    level to 1 before the tone map (where the ACES fit gives 0.80, sRGB code 231). ``(1, level)`` when the
    level is not positive (a black image)."""
    v = np.asarray(values, dtype=np.float64)
    v = v[np.isfinite(v)]
    level = float(np.percentile(v, percentile)) if v.size else 0.0
    return (1.0 / level if level > 0.0 else 1.0), level


def png_text(data: bytes) -> dict[str, str]:
    """The ``tEXt`` chunks of PNG ``data`` as ``{keyword: text}`` (Latin-1)."""
    out, pos = {}, 8
    while pos + 8 <= len(data):
        length = int.from_bytes(data[pos:pos + 4], "big")
        kind = data[pos + 4:pos + 8]
        if kind == b"tEXt":
            key, _, text = data[pos + 8:pos + 8 + length].partition(b"\0")
            out[key.decode("latin-1")] = text.decode("latin-1")
        pos += 12 + length
    return out


def png_bytes(rgb8: np.ndarray, text: Mapping[str, str] | None = None) -> bytes:
    """Encode an ``(H, W, 3)`` uint8 image as PNG bytes (imageio), with ``text`` as ``tEXt`` chunks after IHDR."""
    import zlib

    import imageio.v3 as iio
    data = iio.imwrite("<bytes>", np.ascontiguousarray(rgb8, dtype=np.uint8), extension=".png", compress_level=1)
    if not text:
        return data
    chunks = b""
    for key, value in text.items():
        body = b"tEXt" + key.encode("latin-1") + b"\0" + str(value).encode("latin-1", "replace")
        chunks += (len(body) - 4).to_bytes(4, "big") + body + zlib.crc32(body).to_bytes(4, "big")
    ihdr_end = 8 + 12 + int.from_bytes(data[8:12], "big")
    return data[:ihdr_end] + chunks + data[ihdr_end:]


def write_png(path, rgb: np.ndarray, exposure: float = 1.0, text: Mapping[str, str] | None = None) -> Path:
    """Write a tone-mapped sRGB 8-bit preview PNG (see :func:`srgb8`) atomically, with ``tEXt`` chunks
    ``vlref_version``, ``vlref_exposure`` and ``text``. Never compared."""
    meta = {"vlref_version": __version__, "vlref_exposure": f"{float(exposure):.6g}", **(text or {})}
    return write_bytes(path, png_bytes(srgb8(rgb, exposure), meta))


def write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    return _atomic_write(path, lambda fh: fh.write(data))


def write_text(path, text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    return write_bytes(path, text.encode("utf-8"))


def write_npy(path, array: np.ndarray) -> Path:
    """Write one array as ``.npy`` atomically (dtype and shape kept)."""
    a = np.asarray(array)
    return _atomic_write(path, lambda fh: np.save(fh, a, allow_pickle=False))


def write_npz(path, arrays: Mapping[str, np.ndarray], compressed: bool = True) -> Path:
    """Write named arrays as ``.npz`` (zip-deflated when ``compressed``) atomically."""
    data = {str(k): np.asarray(v) for k, v in arrays.items()}
    save = np.savez_compressed if compressed else np.savez
    return _atomic_write(path, lambda fh: save(fh, **data))


# --------------------------------------------------------------------------- buffer sets

def save_buffers(out_dir, buffers: Mapping[str, np.ndarray], metadata: Mapping[str, object] | None = None,
                 half: Sequence[str] = ()) -> list[Path]:
    """Write ``<name>.exr`` for each buffer into the existing folder ``out_dir``; returns the paths.

    Every buffer is validated (name, shape, dtype) before the first file is written, and each file is
    written atomically; wrap the call in :func:`output_dir` for an all-or-nothing set. The buffers named in
    ``half`` are stored as half floats (:func:`write_exr`).
    """
    out_dir = Path(out_dir)
    prepared = []
    for name, array in buffers.items():
        if not _SAFE_NAME.match(name):
            raise ValueError(f"buffer name {name!r} is not a safe file name")
        if name in half and np.asarray(array).dtype.kind != "f":
            raise ValueError(f"buffer {name!r}: integer buffers stay float32 (half asked)")
        prepared.append((out_dir / f"{name}.exr", _channel_dict(array, None), name in half))
    return [write_exr(path, data, metadata=metadata, half=h) for path, data, h in prepared]


def save_render(out_dir, result, stages: bool, main: Sequence[str], exposure: float = 1.0,
                png_meta: Mapping[str, str] | None = None, half: Sequence[str] = ()) -> list[Path]:
    """Write a :class:`vlref.render.RenderResult`: the ``main`` buffers (all with ``stages``) as EXR
    with the result's metadata (those in ``half`` as half floats), plus the ``final.png`` preview at
    ``exposure`` (``png_meta``: its tEXt). The preview is encoded on a second thread while the EXR files are
    written (zlib and OpenEXR release the GIL)."""
    names = list(result.buffers) if stages else [n for n in main if n in result.buffers]
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        png = pool.submit(write_png, Path(out_dir) / "final.png", result.buffers["final"], exposure, png_meta)
        paths = save_buffers(out_dir, {n: result.buffers[n] for n in names}, result.metadata, half)
        paths.append(png.result())
    return paths
