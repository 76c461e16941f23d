"""Output folders written all or nothing, and output paths checked before any work.

:func:`output_dir` yields a temporary folder next to the destination and moves its files in only when the
block ends normally. :func:`check_output_dir` and :func:`check_output_file` do, before a command's work, what
the write will do (create folders, create and remove a file), so that a bad ``-o`` fails in a second with
:class:`vlref.errors.InputError` instead of after a long render.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from pathlib import Path
from typing import Iterator

from ..errors import InputError
from .files import fsync_dir, synced_beside

__all__ = ["output_dir", "check_output_dir", "check_output_file"]


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

    The files written into the temporary folder through :mod:`vlref.io.files` are fsynced on threads beside the
    writing (:func:`vlref.io.files.synced_beside`); every one is on disk before the first is moved in.
    """
    final = Path(path)
    anchor = check_output_dir(final)
    tmp = Path(tempfile.mkdtemp(prefix=f".{final.name}.", suffix=".partial", dir=anchor))
    try:
        with synced_beside(tmp) as wait_synced:
            yield tmp
            wait_synced()
        final.mkdir(parents=True, exist_ok=True)
        for src in sorted(tmp.rglob("*")):  # parents sort before their contents
            dst = final / src.relative_to(tmp)
            if src.is_dir():
                dst.mkdir(exist_ok=True)
            else:
                os.replace(src, dst)
        fsync_dir(final)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
