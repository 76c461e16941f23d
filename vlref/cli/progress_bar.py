"""The progress bar of long commands (``vlref render``, ``vlref reference``)."""

from __future__ import annotations

import contextlib
import functools
import sys

from ..progress import reporting

__all__ = ["StageBar"]


class StageBar:
    """Progress on stderr: a tqdm bar over a command's stages (or frames: ``unit``), then over the rows of each
    banded kernel.

    ``stage(name)`` completes a stage; ``rows(done, total)`` (a :mod:`vlref.progress` listener) counts
    the rows of a long kernel (the march, the quadrature), so the bar moves on long work and its time
    estimate is the kernel's. Each bar shows only once its work has lasted about a second. Quiet: none.
    """

    def __init__(self, quiet: bool, stages: int, desc: str, unit: str = "stage"):
        self.quiet, self.stages, self.desc, self.unit, self.done = quiet, stages, desc, unit, 0
        self.bar = None

    def _show(self, n: int, total: int, unit: str, desc: str) -> None:
        if self.quiet:
            return
        if self.bar is None or self.bar.unit != unit or self.bar.total != total:
            self.close()
            self.bar = _bar_class()(total=total, desc=desc, unit=unit, file=sys.stderr, delay=1.0, leave=False)
        self.bar.update(n - self.bar.n)

    def stage(self, name: str | None = None) -> None:
        self.done += 1
        self._show(self.done, self.stages, self.unit, self.desc)

    def rows(self, done: int, total: int) -> None:
        self._show(done, total, "row", f"{self.desc}, {self.unit} {self.done + 1}/{self.stages}")

    def close(self) -> None:
        """Close the bar and clear its line. ``tqdm.write`` (the :meth:`compiling` line) draws every bar of the
        stream, one still inside its ``delay`` too; tqdm's ``close`` then takes that bar for one never drawn and
        leaves its text, and the next line printed (a note) followed it on one line. So the line is cleared
        here first (a carriage return where nothing was drawn)."""
        if self.bar is not None:
            self.bar.clear()
            self.bar.close()
            self.bar = None

    def compiling(self) -> None:
        """Say once, above the bar, that the kernels are being compiled (Numba's first call of a kernel
        whose machine code is not in the cache yet): the bar may stand still meanwhile."""
        if not self.quiet and not self.said_compiling:
            from tqdm import tqdm
            self.said_compiling = True
            tqdm.write("vlref: compiling kernels (first run, cached afterwards; `vlref warmup` compiles them all "
                       "once)", file=sys.stderr)

    def __enter__(self):
        from numba.core.event import install_listener

        self.said_compiling = False
        self._listening = contextlib.ExitStack()
        self._listening.enter_context(reporting(self.rows))
        self._listening.enter_context(install_listener("numba:compile", _on_compile(self.compiling)))
        self._show(0, self.stages, self.unit, self.desc)
        return self

    def __exit__(self, *exc) -> None:
        self._listening.__exit__(*exc)
        self.close()


def _on_compile(callback):
    """A Numba event listener for ``numba:compile`` (fired only when a kernel compiles, not when the cache
    serves it) that calls ``callback()`` as each compilation starts."""
    from numba.core.event import Listener

    class OnCompile(Listener):
        def on_start(self, event):
            callback()

        def on_end(self, event):
            pass

    return OnCompile()


@functools.cache
def _bar_class():
    """tqdm's bar without its monitor thread. The monitor (every 10 s) redraws a bar that has not moved for
    ``maxinterval`` without the bar's lock, so a redraw could land after :meth:`StageBar.close` had cleared the
    line: the next line printed (a ``vlref: note:``) then followed the bar's text on one line (seen once in a
    test after a 23 s compile). These bars are moved by hand and need no monitor; tqdm is imported lazily (an
    optional dependency)."""
    from tqdm import tqdm

    class StageTqdm(tqdm):
        monitor_interval = 0

    return StageTqdm
