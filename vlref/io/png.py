"""PNG previews: 8-bit sRGB codes encoded with ``tEXt`` chunks, and those chunks read back.

A preview PNG is the tone-mapped frame (:func:`vlref.io.tonemap.srgb8`) at zlib level 1 (the fastest; a 1080p
preview: 0.40 s at Pillow's default 6, 0.15 s at 1, 15 % larger); ``tEXt`` chunks record ``vlref_version``
and the exposure. Never compared.
"""

from __future__ import annotations

import zlib
from pathlib import Path
from typing import Mapping

import numpy as np

from .. import __version__
from .files import write_bytes
from .tonemap import srgb8

__all__ = ["png_bytes", "png_text", "write_png"]


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
