"""The progress bar of long commands (``vlref render``, ``vlref reference``)."""

from __future__ import annotations

import sys

from ..progress import reporting

__all__ = ["StageBar"]


class StageBar:
    """Progress on stderr: a tqdm bar over a command's stages, then over the rows of each banded kernel.

    ``stage(name)`` completes a stage; ``rows(done, total)`` (a :mod:`vlref.progress` listener) counts
    the rows of a long kernel (the march, the quadrature), so the bar moves on long work and its time
    estimate is the kernel's. Each bar shows only once its work has lasted about a second. Quiet: none.
    """

    def __init__(self, quiet: bool, stages: int, desc: str):
        self.quiet, self.stages, self.desc, self.done = quiet, stages, desc, 0
        self.bar = None

    def _show(self, n: int, total: int, unit: str, desc: str) -> None:
        if self.quiet:
            return
        if self.bar is None or self.bar.unit != unit or self.bar.total != total:
            from tqdm import tqdm
            self.close()
            self.bar = tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, delay=1.0, leave=False)
        self.bar.update(n - self.bar.n)

    def stage(self, name: str | None = None) -> None:
        self.done += 1
        self._show(self.done, self.stages, "stage", self.desc)

    def rows(self, done: int, total: int) -> None:
        self._show(done, total, "row", f"{self.desc}, stage {self.done + 1}/{self.stages}")

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None

    def __enter__(self):
        self._reporting = reporting(self.rows)
        self._reporting.__enter__()
        self._show(0, self.stages, "stage", self.desc)
        return self

    def __exit__(self, *exc) -> None:
        self._reporting.__exit__(*exc)
        self.close()
