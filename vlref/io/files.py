"""Files written atomically (bytes, text, NPY, NPZ), and the check that a file to read exists.

:func:`atomic_write` calls a writer on a temporary file next to the destination, fsyncs it, then renames it
into place (``os.replace``, atomic on POSIX file systems); on any failure the temporary file is removed, so a
reader sees the old file or the whole new one, never a partial file.
"""

from __future__ import annotations

import contextlib
import os
import uuid
from pathlib import Path
from typing import BinaryIO, Callable, Mapping

import numpy as np

from ..errors import InputError

__all__ = ["atomic_write", "fsync_dir", "require_file", "write_bytes", "write_text", "write_npy", "write_npz"]


def fsync_dir(directory: Path) -> None:
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


def atomic_write(path: str | os.PathLike, write: Callable[[BinaryIO], None]) -> Path:
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
    fsync_dir(path.parent)
    return path


def require_file(path: Path) -> None:
    """:class:`InputError` ``(path, "", reason)`` unless ``path`` is an existing file."""
    if not path.is_file():
        raise InputError(str(path), "", "file not found" if not path.exists() else "not a file")


def write_bytes(path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    return atomic_write(path, lambda fh: fh.write(data))


def write_text(path, text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    return write_bytes(path, text.encode("utf-8"))


def write_npy(path, array: np.ndarray) -> Path:
    """Write one array as ``.npy`` atomically (dtype and shape kept)."""
    a = np.asarray(array)
    return atomic_write(path, lambda fh: np.save(fh, a, allow_pickle=False))


def write_npz(path, arrays: Mapping[str, np.ndarray], compressed: bool = True) -> Path:
    """Write named arrays as ``.npz`` (zip-deflated when ``compressed``) atomically."""
    data = {str(k): np.asarray(v) for k, v in arrays.items()}
    save = np.savez_compressed if compressed else np.savez
    return atomic_write(path, lambda fh: save(fh, **data))
