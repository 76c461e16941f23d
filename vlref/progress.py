"""Progress of long kernels: the frame cut into bands of rows, each band reported when done.

A parallel kernel over a whole frame is one opaque call: the interpreter gets control back only when
it returns, so a progress bar cannot move and Ctrl-C waits for the end. Long kernels (the physical
march, the quadrature reference) therefore run once per band of rows (:func:`row_bands`); between
bands the interpreter runs (signal handlers included) and the band is reported to the listener
installed with :func:`reporting`. Pixels are independent, so banding changes no bit of a result.

Listeners receive ``(done, total)`` in rows of the current kernel; the ``vlref`` command turns them
into its progress bar (:mod:`vlref.cli`). Without a listener nothing is reported.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
from typing import Callable, Iterator

__all__ = ["BANDS", "bands_for", "row_bands", "reporting"]

# At most this many bands per kernel call (about 1.5 % of the frame each). Each band is one parallel
# launch, whose end waits for every thread: tens of microseconds on an idle machine, but a few
# milliseconds where other processes hold the cores, so callers size bands by their work (bands_for).
BANDS = 64

_listener: contextvars.ContextVar[Callable[[int, int], None] | None] = contextvars.ContextVar(
    "vlref_progress_listener", default=None)


@contextlib.contextmanager
def reporting(listener: Callable[[int, int], None]) -> Iterator[None]:
    """Within the block, every band of :func:`row_bands` calls ``listener(rows done, rows in total)``."""
    token = _listener.set(listener)
    try:
        yield
    finally:
        _listener.reset(token)


def bands_for(work: float, per_band: float) -> int:
    """``ceil(work / per_band)`` bands, at least 1 and at most :data:`BANDS` (``row_bands`` also caps
    them at the row count)."""
    return int(min(BANDS, max(1, math.ceil(work / per_band))))


def row_bands(height: int, bands: int | None = None, multiple: int = 1) -> Iterator[tuple[int, int]]:
    """Half-open row ranges ``[y0, y1)`` covering ``0..height`` in order: at most ``bands`` (default
    :data:`BANDS`) of them, each starting on a multiple of ``multiple`` rows (a kernel's tile height: a band
    that ends inside a tile leaves a strip of short tiles), their sizes in units of ``multiple`` rows differing
    by at most one (the last band may end short, at ``height``). After the caller has processed a band (the
    generator resumes) the listener, if any, is told the rows done so far."""
    units = -(-int(height) // int(multiple))
    n = max(1, min(units, int(BANDS if bands is None else bands)))
    listener = _listener.get()
    for i in range(n):
        y0, y1 = min(height, multiple * (units * i // n)), min(height, multiple * (units * (i + 1) // n))
        yield y0, y1
        if listener is not None:
            listener(y1, height)
