"""glibc's ``malloc`` in a process that renders one frame and ends: freed memory kept for the next allocation.

A render allocates and frees many buffers of 40 KB-30 MB (NumPy's temporaries, the rows' scratch arrays that the
kernels allocate on every worker thread, the float32 copies of the written channels). glibc's defaults hand such
memory back to the kernel as soon as it is freed: an allocation of 128 KiB or more (a threshold that adapts
upwards to 32 MiB) is its own ``mmap`` and ``munmap``, and a heap whose free top exceeds 128 KiB is trimmed
(``sbrk`` / ``madvise(MADV_DONTNEED)`` for a thread's arena). The next allocation then takes the same amount of
fresh pages again: a page fault and the zeroing of each 4 KiB page. :func:`keep_freed_memory` sets, with
``mallopt``:

* ``M_MMAP_THRESHOLD`` = 32 MiB (glibc's largest; fixing it also stops its adaptation): allocations below it come
  from the heaps, and go back to them when freed;
* ``M_TRIM_THRESHOLD`` = 256 MiB and ``M_TOP_PAD`` = 64 MiB: a heap keeps up to 256 MiB of freed memory at its top
  and grows in steps of 64 MiB (address space: pages are faulted in only where written).

Larger buffers (the march's per-light outputs, 200 MB at 1080p) still get their own mappings, where NumPy asks
for huge pages. Nothing computed changes: only where the bytes live. The cost is memory kept, not returned to
the kernel before the process ends: the ``vlref render`` program's process, which ends with its command, is the
only caller (:func:`vlref.cli.commands.program_command`). Dev box (2 cores), a fresh process rendering (b) at
1080p: the ray cast's minor page faults 11 300-12 300 -> 7 300-7 800, the whole process's ~47 000 -> ~40 000.
"""

from __future__ import annotations

import ctypes
import sys

__all__ = ["keep_freed_memory", "MALLOPT_SETTINGS"]

_M_TRIM_THRESHOLD, _M_TOP_PAD, _M_MMAP_THRESHOLD = -1, -2, -3  # glibc's <malloc.h>
MALLOPT_SETTINGS = ((_M_MMAP_THRESHOLD, 32 << 20), (_M_TRIM_THRESHOLD, 256 << 20), (_M_TOP_PAD, 64 << 20))
"""``(parameter, value)`` pairs :func:`keep_freed_memory` passes to ``mallopt`` (module docstring)."""


def keep_freed_memory() -> bool:
    """Tell glibc's ``malloc`` to keep freed memory for reuse in this process (module docstring). True where it
    took every setting; False on a C library without ``mallopt`` (macOS, Windows, musl's does nothing), where
    nothing changes."""
    if not sys.platform.startswith("linux"):
        return False
    mallopt = getattr(ctypes.CDLL(None), "mallopt", None)
    if mallopt is None:
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return all([mallopt(parameter, value) == 1 for parameter, value in MALLOPT_SETTINGS])
