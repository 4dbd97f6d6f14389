"""Progress display for long runs, kept apart from the engines that report to it."""

from __future__ import annotations

import sys
import time


class ProgressBar:
    """A one-line progress bar on a terminal (stderr), shown once a run has taken 1 s.

    Called with the number of items done; :meth:`close` ends the line.
    """

    def __init__(self, total: int, label: str, unit: str = "members") -> None:
        self.total, self.label, self.unit = total, label, unit
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, done: int) -> None:
        elapsed = time.perf_counter() - self.start
        if elapsed < 1.0 or not sys.stderr.isatty():
            return
        self.shown = True
        frac = done / self.total
        bar = "#" * int(30 * frac)
        sys.stderr.write(
            f"\r{self.label} [{bar:<30}] {done}/{self.total} {self.unit}  {elapsed:5.1f} s"
        )
        sys.stderr.flush()

    def close(self) -> None:
        if self.shown:
            sys.stderr.write("\n")
