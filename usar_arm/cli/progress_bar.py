"""A progress bar on stderr for long jobs: done / total, rate and time left.

On a terminal it redraws one line; otherwise (a log file, CI) it writes a line at every tenth
of the work, so a long run still shows it is alive. Silent with ``-q``.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

WIDTH = 30


def _count(n: float) -> str:
    for limit, suffix in ((1e9, "G"), (1e6, "M"), (1e3, "k")):
        if n >= limit:
            return f"{n / limit:.1f}{suffix}"
    return f"{n:.0f}"


def _clock(seconds: float) -> str:
    s = max(0, round(seconds))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


class ProgressBar:
    """Call it with (done, total) units; :meth:`close` ends the line."""

    def __init__(self, unit: str = "queries", stream: TextIO | None = None,
                 enabled: bool = True, interval: float = 0.25):
        self.unit = unit
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.interval = interval
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._start = time.perf_counter()
        self._first: int | None = None
        self._last_draw = 0.0
        self._last_tenth = -1
        self._drawn = False

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if self._first is None:
            self._first, self._start = done, now
        line = self.line(done, total, now - self._start)
        if self.tty:
            if now - self._last_draw >= self.interval or done >= total:
                self.stream.write("\r" + line)
                self.stream.flush()
                self._last_draw, self._drawn = now, True
            return
        tenth = 10 * done // max(total, 1)
        if tenth > self._last_tenth:
            self._last_tenth = tenth
            self.stream.write(line + "\n")
            self.stream.flush()

    def line(self, done: int, total: int, elapsed: float) -> str:
        """The bar's text after ``elapsed`` seconds."""
        fraction = done / total if total else 1.0
        filled = round(WIDTH * fraction)
        new = done - (self._first or 0)
        rate = new / elapsed if elapsed > 0 else 0.0
        left = (total - done) / rate if rate > 0 else float("nan")
        eta = _clock(left) if left == left else "?"
        return (f"[{'#' * filled}{'.' * (WIDTH - filled)}] {100 * fraction:5.1f} %  "
                f"{_count(done)}/{_count(total)} {self.unit}  {_count(rate)}/s  "
                f"{_clock(elapsed)} elapsed, {eta} left")

    def close(self) -> None:
        """End the bar's line (on a terminal)."""
        if self.enabled and self.tty and self._drawn:
            self.stream.write("\n")
            self.stream.flush()
            self._drawn = False
