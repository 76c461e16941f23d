"""Progress of long kernels, and their interruption: a frame watched while one launch marches it, or cut into bands.

A parallel kernel over a whole frame is one opaque call: the interpreter gets control back only when
it returns, so a progress bar cannot move and Ctrl-C waits for the end. Two ways around it:

* **One launch, watched** (:func:`watched`; the physical march). The kernel releases the GIL (``nogil=True``) and
  its threads take tasks from a counter (:func:`vlref.parallel.take`). It runs on a thread of its own while the
  calling thread waits on it, reading the counter every :data:`POLL_S` for the listener and handling signals (a
  lock's wait is interrupted by them). That thread is the calling thread's *launch thread*, made at its first launch
  and kept for the next: a daemon, named ``vlref-launch`` while it runs a launch and ``vlref-launch (idle)`` between
  launches, which ends once the calling thread has ended. A thread that starts a parallel kernel gets an OpenMP team
  of worker threads of its own, so a new thread per launch made a new team each time: 12-16 ms more than a launch
  from the calling thread, of a 0.21 s march (scene (a) at 1080p on 16 cores; BENCHMARKS.md "The launch thread
  kept"). When anything interrupts the wait (Ctrl-C or SIGTERM raising in the main thread, a listener's error), the
  counter is set past every task: each kernel thread ends with the task it holds (a tile: milliseconds), the launch
  returns, and only then does the exception go on, so no other parallel launch ever overlaps this one (Numba's
  ``workqueue`` threading layer aborts on that) and no array the kernel borrows is freed under it. One launch
  instead of bands: no launch, tail and first touch of the outputs per band (in one process 16 bands of (b) at 1080p
  took 0.05 s more than one on a 16-core server, BENCHMARKS.md "The march in fewer bands"; a fresh render's
  volumetric stage ~0.026 s less, "The march in one launch, watched").
* **Bands of rows** (:func:`row_bands`; the quadrature reference). The kernel runs once per band; between bands
  the interpreter runs (signal handlers included) and the band is reported.

Pixels are independent, so neither changes a bit of a result. Listeners receive ``(done, total)`` in rows of the
current kernel (installed with :func:`reporting`); the ``vlref`` command turns them into its progress bar
(:mod:`vlref.cli`). Without a listener nothing is reported.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import os
import queue
import threading
import weakref
from typing import Callable, Iterator

import numba
import numpy as np

__all__ = ["BANDS", "POLL_S", "EXHAUSTED", "bands_for", "row_bands", "reporting", "watched"]

# At most this many bands per kernel call (about 1.5 % of the frame each). Each band is one parallel
# launch, whose end waits for every thread: tens of microseconds on an idle machine, but a few
# milliseconds where other processes hold the cores, so callers size bands by their work (bands_for).
BANDS = 64

# How often :func:`watched` reads a launch's task counter for the listener, s
POLL_S = 0.05

# What :func:`watched` sets a task counter to when it stops a launch: past any task count, far from overflow
# however many threads add 1 after it
EXHAUSTED = np.iinfo(np.int64).max // 2

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


class _LaunchThread:
    """A daemon thread that runs the callables handed to :meth:`start` one at a time (module docstring).

    The thread holds only the queue, not this object: when the calling thread that owns this object has ended and it
    is collected, its finalizer hands the thread ``None`` and the thread ends."""

    IDLE = "vlref-launch (idle)"
    BUSY = "vlref-launch"

    def __init__(self) -> None:
        self.pid = os.getpid()  # a forked child has the object but not the thread
        self._work: queue.SimpleQueue = queue.SimpleQueue()
        threading.Thread(target=_serve, args=(self._work,), name=self.IDLE, daemon=True).start()
        weakref.finalize(self, self._work.put, None)

    def start(self, launch: Callable[[], None]) -> threading.Event:
        """Hand ``launch`` to the thread; the event is set once it has returned or raised."""
        done = threading.Event()
        self._work.put((launch, done))
        return done


def _serve(work: queue.SimpleQueue) -> None:
    """The launch thread's loop: run each callable (it catches its own exceptions), then set its event."""
    me = threading.current_thread()
    while (item := work.get()) is not None:
        launch, done = item
        me.name = _LaunchThread.BUSY
        try:
            launch()
        finally:
            me.name = _LaunchThread.IDLE
            done.set()


_launch_threads = threading.local()


def _launch_thread() -> _LaunchThread:
    """The calling thread's launch thread, made on first use (and again in a forked child)."""
    kept = getattr(_launch_threads, "kept", None)
    if kept is None or kept.pid != os.getpid():
        kept = _launch_threads.kept = _LaunchThread()
    return kept


def watched(launch: Callable[[], None], taken: np.ndarray, tasks: int, height: int, threaded: bool = True) -> None:
    """Run ``launch()`` on the calling thread's launch thread and wait for it, reporting progress and handling signals
    here (module docstring). ``launch`` calls a parallel kernel compiled ``nogil=True`` whose threads take the tasks
    ``0 .. tasks - 1`` (in row order of a frame of ``height`` rows) from ``taken``, a 1-element int64 array holding 0
    (:func:`vlref.parallel.take`), and nothing else. It runs with this thread's Numba thread count.

    While it runs, the listener (if any) gets ``(rows, height)`` whenever ``rows = min(height - 1, taken · height //
    tasks)`` (the tasks handed out, in rows) has grown since the last report, and ``(height, height)`` once it has
    returned. An exception raised here while waiting (a signal's) sets ``taken[0]`` to :data:`EXHAUSTED` (one aligned
    8-byte store, which the threads' atomic adds see whole: their next task is past the last), waits for the launch
    to end (ignoring a second signal meanwhile: a tile or so of work) and goes on; one raised by ``launch`` is raised
    here.

    ``threaded`` False (a launch too short for a bar or an interrupt to matter): ``launch()`` runs on this thread, then
    the listener gets ``(height, height)``; no thread to hand it to (0.5-3.5 ms more per launch on the busy dev box:
    BENCHMARKS.md "The march in one launch, watched")."""
    listener = _listener.get()
    if not threaded:
        launch()
        if listener is not None:
            listener(height, height)
        return
    threads = numba.get_num_threads()  # per thread in Numba: the launch's thread takes this one's
    failed: list[BaseException] = []

    def run() -> None:
        try:
            numba.set_num_threads(threads)
            launch()
        except BaseException as exc:  # raised again in the waiting thread
            failed.append(exc)

    done = _launch_thread().start(run)
    try:
        reported = 0
        while not done.is_set():
            done.wait(None if listener is None else POLL_S)
            rows = min(height - 1, int(taken[0]) * height // max(1, tasks))
            if listener is not None and not done.is_set() and rows > reported:
                listener(rows, height)
                reported = rows
    finally:
        if not done.is_set():  # interrupted: stop the launch, then let the exception go on
            taken[0] = EXHAUSTED
            while not done.is_set():
                try:
                    done.wait()
                except BaseException:
                    pass
    if failed:
        raise failed[0]
    if listener is not None:
        listener(height, height)
