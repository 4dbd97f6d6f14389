"""Progress display for long runs, kept apart from the engines that report to it."""

from __future__ import annotations

import sys
import threading
import time
from typing import Any

#: Seconds between plain progress lines when stderr is not a terminal (a log file, a
#: pipe, a batch job): the first comes after this long, then one every this long while
#: the run lasts, whether or not work was reported in between (a heartbeat), and a last
#: one when a run that printed any ends. 8 s so that, with the moments between one
#: stage's last line and the next stage's start, a log hears from a run at least every
#: 10 s (at 10.0 the longest gap of a whole-catalog run was 10.4 s).
LINE_INTERVAL = 8.0
#: One plain progress line is written at a time, whichever run it belongs to.
_WRITE = threading.Lock()
#: When the last plain line was written (time.monotonic), by any run: a stage that starts
#: right after another's last line waits only what is left of the interval, so the log
#: hears from the process every LINE_INTERVAL s across stages (a per-stage timer left
#: 12-13 s between a stage's last line and the next one's first).
_LAST_LINE = [0.0]
#: How often (s) a beat thread checks whether a line is due.
_POLL = 0.25


def _plain() -> bool:
    """Whether progress goes out as plain lines: stderr is not a terminal and this is not
    a notebook (where ``tqdm.auto`` draws a widget)."""
    from tqdm.auto import tqdm

    if "notebook" in getattr(tqdm, "__module__", ""):
        return False
    isatty = getattr(sys.stderr, "isatty", None)
    return not (callable(isatty) and isatty())


class _Lines:
    """Plain progress lines on stderr every :data:`LINE_INTERVAL` s from a background
    thread (so a stage that reports nothing for minutes still shows it is alive)."""

    def __init__(self, total: int, label: str, unit: str) -> None:
        self.total, self.label, self.unit = total, label, unit
        self.done = 0
        self.start = time.monotonic()
        self.printed = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, daemon=True, name="rhoprop-progress")
        self._thread.start()

    def line(self) -> str:
        elapsed = time.monotonic() - self.start
        share = self.done / self.total if self.total else 0.0
        text = (
            f"{self.label}: {self.done}/{self.total} {self.unit} ({100 * share:.0f} %), "
            f"{elapsed:.0f} s"
        )
        if 0 < share < 1:
            text += f", about {elapsed * (1 - share) / share:.0f} s left"
        return text

    def _beat(self) -> None:
        while not self._stop.wait(min(_POLL, LINE_INTERVAL)):
            last = _LAST_LINE[0]
            # The interval runs from the last line of any run if it came within one
            # interval before this one started, else from this one's start.
            anchor = max(last, self.start) if self.start - last >= LINE_INTERVAL else last
            if time.monotonic() - anchor >= LINE_INTERVAL:
                self.emit()

    def emit(self) -> None:
        # One write of the whole line under a lock: print() writes the text and the
        # newline apart, and two runs reporting at once (models sampled in parallel)
        # joined their lines ("... 12 ssampling ...").
        with _WRITE:
            sys.stderr.write(self.line() + "\n")
            sys.stderr.flush()
            _LAST_LINE[0] = time.monotonic()
        self.printed = True

    def close(self) -> None:
        self._stop.set()
        self._thread.join()
        if self.printed:
            self.emit()


class ProgressBar:
    """Progress of a long run: a ``tqdm`` bar on a terminal (stderr) or in a notebook,
    shown once the run has taken 1 s; elsewhere (stderr sent to a file or a pipe) plain
    lines every :data:`LINE_INTERVAL` s, so logs show the run is alive.

    Called with the number of items done; :meth:`close` ends it.
    """

    def __init__(self, total: int, label: str, unit: str = "members") -> None:
        from tqdm.auto import tqdm

        self.total, self.label, self.unit = total, label, unit
        self._done = 0
        self._lines: _Lines | None = None
        self._bar: Any = None
        if _plain():
            self._lines = _Lines(total, label, unit)
        else:
            self._bar = tqdm(
                total=total, desc=label, unit=f" {unit}", delay=1.0, disable=None, leave=True
            )

    def __call__(self, done: int) -> None:
        step = int(done) - self._done
        if step > 0:
            self._done = int(done)
            if self._lines is not None:
                self._lines.done = self._done
            else:
                self._bar.update(step)

    def close(self) -> None:
        if self._lines is not None:
            self._lines.close()
        else:
            self._bar.close()
