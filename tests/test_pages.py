"""New arrays faulted in on threads: the shape and type of ``np.empty``, the memory resident before any write."""

import sys

import numpy as np
import pytest

from vlref.pages import PAGE, SPAN, empty_faulted


def _resident_bytes() -> int:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * PAGE


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="resident memory read from Linux's /proc")
def test_empty_faulted_maps_every_page_before_the_kernel_writes():
    """``np.empty`` of 48 MB leaves it unmapped (resident memory grows by far less); ``empty_faulted`` maps it all,
    on several threads, with the requested shape and type."""
    shape = (2, 1000, 1000, 3)
    nbytes = 2 * 1000 * 1000 * 3 * 8
    before = _resident_bytes()
    plain = np.empty(shape)
    assert _resident_bytes() - before < nbytes // 4
    before = _resident_bytes()
    faulted = empty_faulted(shape)
    assert _resident_bytes() - before >= nbytes - 2 * SPAN
    assert faulted.shape == shape and faulted.dtype == np.float64 and faulted.flags.c_contiguous
    small = empty_faulted((5, 7), np.float32)
    assert small.shape == (5, 7) and small.dtype == np.float32
    del plain
