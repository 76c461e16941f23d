"""PNG previews: 8-bit sRGB codes encoded with ``tEXt`` chunks, and those chunks read back.

A preview PNG is the tone-mapped frame (:func:`vlref.io.tonemap.srgb8`), encoded here with :mod:`zlib` alone
(no imaging library to import: Pillow through imageio cost ~0.2 s of a fresh process's first write on the dev
box): every row filtered with PNG's *Sub* filter (type 1: each byte minus the byte three to its left, modulo
256), the filtered rows deflated at level 1 (the fastest) in blocks of :data:`_ROWS_PER_BLOCK` rows on a
thread per core, the blocks joined into one zlib stream as parallel gzip does (each block a raw deflate
stream primed with the 32 KiB of data before it and ended on a byte boundary by a sync flush, the last one
finished; the stream's Adler-32 over all the filtered rows). The blocks are fixed by the image, not by the
cores: the same bytes on every machine with the same zlib. ``tEXt`` chunks record ``vlref_version`` and the
exposure. Never compared; any PNG reader decodes the codes exactly (tested against imageio).
"""

from __future__ import annotations

import concurrent.futures
import struct
import zlib
from pathlib import Path
from typing import Mapping

import numpy as np

from .. import __version__
from ..processes import host_cores
from .files import write_bytes
from .tonemap import srgb8

__all__ = ["png_bytes", "png_text", "write_png"]

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_ROWS_PER_BLOCK = 64
"""Rows deflated as one block (a 1080p preview: 17 blocks of ~370 kB)."""
_WINDOW = 32768
"""Deflate's window: each block is primed with this much of the data before it."""


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
    """Encode an ``(H, W, 3)`` uint8 image as PNG bytes (8-bit RGB, not interlaced), with ``text`` as ``tEXt``
    chunks after IHDR (module docstring: Sub filter, level-1 deflate in blocks of rows on threads)."""
    img = np.ascontiguousarray(rgb8, dtype=np.uint8)
    if img.ndim != 3 or img.shape[2] != 3 or img.shape[0] == 0 or img.shape[1] == 0:
        raise ValueError(f"PNG preview needs a non-empty (H, W, 3) array, got shape {img.shape}")
    h, w = img.shape[:2]
    rows = img.reshape(h, 3 * w)
    filtered = np.empty((h, 3 * w + 1), dtype=np.uint8)  # each row: its filter type, then the filtered bytes
    filtered[:, 0] = 1
    filtered[:, 1:4] = rows[:, :3]
    np.subtract(rows[:, 3:], rows[:, :-3], out=filtered[:, 4:])  # uint8 arithmetic wraps modulo 256
    chunks = [_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))]
    for key, value in (text or {}).items():
        chunks.append(_chunk(b"tEXt", key.encode("latin-1") + b"\0" + str(value).encode("latin-1", "replace")))
    chunks += [_chunk(b"IDAT", _zlib_stream(filtered.reshape(-1), filtered.shape[1] * _ROWS_PER_BLOCK)),
               _chunk(b"IEND", b"")]
    return _SIGNATURE + b"".join(chunks)


def _chunk(kind: bytes, body: bytes) -> bytes:
    """A PNG chunk: length, type, body, CRC-32 of type and body."""
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def _zlib_stream(data: np.ndarray, block: int) -> bytes:
    """``data`` (uint8, 1-D) as one zlib stream (RFC 1950/1951) at level 1, deflated in blocks of ``block`` bytes
    on a thread per core (zlib releases the GIL): each block a raw deflate stream primed with the window before
    it, sync-flushed (the last finished), concatenated after the zlib header, then the Adler-32 of ``data``."""
    starts = range(0, data.size, block)

    def deflate(start: int) -> bytes:
        primed = {"zdict": data[max(0, start - _WINDOW):start].tobytes()} if start else {}
        comp = zlib.compressobj(1, zlib.DEFLATED, -15, **primed)
        last = start + block >= data.size
        return comp.compress(data[start:start + block]) + comp.flush(zlib.Z_FINISH if last else zlib.Z_SYNC_FLUSH)

    workers = min(host_cores(), len(starts))
    if workers == 1:
        parts = [deflate(s) for s in starts]
    else:
        with concurrent.futures.ThreadPoolExecutor(workers) as pool:
            parts = list(pool.map(deflate, starts))
    return b"\x78\x01" + b"".join(parts) + struct.pack(">I", zlib.adler32(data))


def write_png(path, rgb: np.ndarray, exposure: float = 1.0, text: Mapping[str, str] | None = None) -> Path:
    """Write a tone-mapped sRGB 8-bit preview PNG (see :func:`srgb8`) atomically, with ``tEXt`` chunks
    ``vlref_version``, ``vlref_exposure`` and ``text``. Never compared."""
    meta = {"vlref_version": __version__, "vlref_exposure": f"{float(exposure):.6g}", **(text or {})}
    return write_bytes(path, png_bytes(srgb8(rgb, exposure), meta))
