"""Files written atomically (bytes, text, NPY, NPZ), and the check that a file to read exists.

:func:`atomic_write` calls a writer on a temporary file next to the destination, fsyncs it, then renames it
into place (``os.replace``, atomic on POSIX file systems); on any failure the temporary file is removed, so a
reader sees the old file or the whole new one, never a partial file.

Inside a folder of :func:`synced_beside` (the temporary folder of :func:`vlref.io.output_folders.output_dir`,
which nobody reads and which moves its files into place only once it is complete) a written file is renamed
within that folder at once and its fsync runs on a thread beside the writing of the next file (``os.fsync``
releases the GIL: the disk's work overlaps the next file's compression); the folder's owner waits for every
fsync before it moves a file into place, so what lands in the destination is on disk as before.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import os
import threading
import uuid
from pathlib import Path
from typing import BinaryIO, Callable, Iterator, Mapping

import numpy as np

from ..errors import InputError

__all__ = ["atomic_write", "fsync_dir", "synced_beside", "require_file", "write_bytes", "write_text", "write_npy",
           "write_npz"]


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


_SYNCED_BESIDE: dict = {}
"""The folders of :func:`synced_beside` now open: ``{folder: (thread pool, futures of its files' fsyncs)}``."""
_SYNCED_BESIDE_LOCK = threading.Lock()


def _fsync_file(path: Path) -> None:
    """Flush ``path``'s data to disk (POSIX: fsync of a new read-only descriptor flushes the file)."""
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def synced_beside(folder: Path, threads: int = 4) -> Iterator[Callable[[], None]]:
    """While the block runs, files that :func:`atomic_write` writes under ``folder`` are fsynced on ``threads``
    threads beside the writing instead of before their rename (module docstring); yields ``wait()``, which returns
    once every such file is on disk and raises the first fsync's error. For a folder that nobody reads until its
    owner has called ``wait()``: :func:`vlref.io.output_folders.output_dir`. On leaving the block the fsyncs
    still running are waited for (their errors then ignored: the block failed or did not wait)."""
    folder = Path(folder).absolute()
    pool = concurrent.futures.ThreadPoolExecutor(threads, thread_name_prefix="vlref-fsync")
    futures: list[concurrent.futures.Future] = []
    with _SYNCED_BESIDE_LOCK:
        _SYNCED_BESIDE[folder] = (pool, futures)

    def wait() -> None:
        for future in list(futures):
            future.result()

    try:
        yield wait
    finally:
        with _SYNCED_BESIDE_LOCK:
            del _SYNCED_BESIDE[folder]
        pool.shutdown(wait=True)


def _synced_by(folder: Path):
    """The (pool, futures) of the :func:`synced_beside` folder that holds ``folder``, None outside any."""
    if not _SYNCED_BESIDE:
        return None
    folder = folder.absolute()
    with _SYNCED_BESIDE_LOCK:
        for candidate in (folder, *folder.parents):
            if candidate in _SYNCED_BESIDE:
                return _SYNCED_BESIDE[candidate]
    return None


def atomic_write(path: str | os.PathLike, write: Callable[[BinaryIO], None]) -> Path:
    """Call ``write(fileobj)`` on a temporary file next to ``path``, fsync it, then rename it to ``path``.

    The temporary file is created with mode ``0o666`` minus the umask (so the result has ordinary
    permissions) and removed if ``write`` or any later step raises. Under a folder of :func:`synced_beside`
    the fsync runs on that folder's threads after the rename (module docstring).
    """
    path = Path(path)
    beside = _synced_by(path.parent)
    tmp = path.parent / f".{path.name}.{uuid.uuid4().hex[:12]}.tmp"
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            if beside is None:
                os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    if beside is None:
        fsync_dir(path.parent)
    else:
        pool, futures = beside
        futures.append(pool.submit(_fsync_file, path))
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
