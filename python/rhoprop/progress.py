"""Progress display for long runs, kept apart from the engines that report to it."""

from __future__ import annotations

from typing import Any


class ProgressBar:
    """A progress bar through ``tqdm`` (a terminal line on stderr, a widget in Jupyter),
    shown once a run has taken 1 s and only where someone can see it (a terminal or a
    notebook; not in logs).

    Called with the number of items done; :meth:`close` ends it.
    """

    def __init__(self, total: int, label: str, unit: str = "members") -> None:
        from tqdm.auto import tqdm

        self.total, self.label, self.unit = total, label, unit
        self._bar: Any = tqdm(
            total=total, desc=label, unit=f" {unit}", delay=1.0, disable=None, leave=True
        )
        self._done = 0

    def __call__(self, done: int) -> None:
        step = int(done) - self._done
        if step > 0:
            self._bar.update(step)
            self._done = int(done)

    def close(self) -> None:
        self._bar.close()
