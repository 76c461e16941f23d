"""Child processes that leave Ctrl-C to their parent.

Ctrl-C sends SIGINT to the terminal's whole foreground process group: the ``vlref`` command and every
process it started (``vlref warmup``'s pool, ``vlref render``'s stage compilers, the workers of a
``--scheduler local`` Dask cluster). Each child would raise its own ``KeyboardInterrupt`` and print its
traceback. Children started inside :func:`ignoring_sigint` ignore SIGINT from their first instruction (an
ignored signal stays ignored across ``fork`` and ``exec``, and Python then installs no KeyboardInterrupt
handler, nor does asyncio); the parent alone handles it, and stops them (terminates its pool, closes its
cluster). :func:`host_cores` says how many processes or threads this one may keep busy;
:func:`declare_own_kernels_only` and :func:`own_kernels_only` say whether this process runs vlref's kernels alone,
:func:`not_importable` keeps a package out of an import that does not need it, and :func:`imported_lazily` lets
an import take a module that runs at its first use.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import signal
import sys
import threading
from typing import Iterator

__all__ = ["ignoring_sigint", "host_cores", "declare_own_kernels_only", "own_kernels_only", "not_importable",
           "imported_lazily"]

_OWN_KERNELS_ONLY = [False]


def declare_own_kernels_only() -> None:
    """Declare this process one that runs vlref's kernels alone: no user code, no plug-in (the ``vlref render``
    program's own process, :data:`vlref.cli.commands.OWN_KERNELS_ONLY`). Numba's initialisation then leaves out
    what serves only other code (:mod:`vlref.jit_init`). Kept here, in a module that imports nothing heavy, so
    that the program declares it before its command's imports (which it makes with the collector off)."""
    _OWN_KERNELS_ONLY[0] = True


def own_kernels_only() -> bool:
    """Whether :func:`declare_own_kernels_only` was called in this process."""
    return _OWN_KERNELS_ONLY[0]


@contextlib.contextmanager
def not_importable(name: str, when: bool = True) -> Iterator[None]:
    """Inside the block, where ``when`` holds and ``name`` is not imported yet, ``import name`` raises ImportError as
    where the package is not installed (``sys.modules[name] = None``); the entry is removed again after, so a later
    import is a complete one. For a package that another package's import tries and does without."""
    hide = when and name not in sys.modules
    if hide:
        sys.modules[name] = None
    try:
        yield
    finally:
        if hide and name in sys.modules and sys.modules[name] is None:
            del sys.modules[name]


@contextlib.contextmanager
def imported_lazily(name: str, when: bool = True) -> Iterator[None]:
    """Inside the block, where ``when`` holds and the module ``name`` is not imported yet, ``import name`` gives a
    module whose code runs at the first access to one of its attributes (:class:`importlib.util.LazyLoader`, the
    standard library's recipe for lazy imports): the same module, complete from its first use on, and it stays so
    after the block. For a module that another package's import imports for work the process may never do."""
    if when and name not in sys.modules:
        spec = importlib.util.find_spec(name)
        if spec is not None and spec.loader is not None and hasattr(spec.loader, "exec_module"):
            spec.loader = importlib.util.LazyLoader(spec.loader)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
            parent, _, child = name.rpartition(".")
            if parent:
                setattr(sys.modules[parent], child, module)
    yield


def host_cores() -> int:
    """Cores this process may run on (affinity mask where the OS has one)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


@contextlib.contextmanager
def ignoring_sigint() -> Iterator[None]:
    """SIGINT ignored inside the block, so that processes started there ignore it; the handler is restored
    after. A SIGINT that comes meanwhile is blocked in the calling (main) thread and in the threads it starts
    meanwhile (Linux holds a blocked signal pending even when ignored), and reaches this process's handler
    when the block ends; only one that the kernel hands to an older thread, which does not block it (tqdm's
    monitor), is lost. The children inherit the block too. Outside the main thread (where signals cannot
    be set) a no-op."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
