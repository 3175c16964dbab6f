"""A progress bar on stderr for long jobs: done / total, rate and time left (tqdm's).

On a terminal tqdm redraws one line (at most every ``interval`` s, and always at the end);
otherwise (a log file, CI) the bar's text is written as a line at every tenth of the work, so a
long run still shows it is alive without a log full of carriage returns. Silent with ``-q``.
The rate counts only the units done since the first call: a resumed run's finished chunks do
not make it look faster.
"""

from __future__ import annotations

import math
import sys
from typing import Any, TextIO

from tqdm import tqdm

WIDTH = 30
"""Characters of the bar itself."""
FORMAT = ("[{bar:" + str(WIDTH) + "}] {percentage:5.1f} %  {done}/{whole}{unit}  "
          "{rate_noinv_fmt}  {elapsed} elapsed, {remaining} left")
"""The line: bar, percentage, done/total, rate, time spent and left."""


def _count(n: float | None) -> str:
    """A count as people write it: 40, 999, 1.00k, 2.50M (tqdm writes 40.0)."""
    return "?" if n is None else f"{n:.0f}" if n < 1000 else tqdm.format_sizeof(n)


class _Bar(tqdm):  # type: ignore[type-arg]
    """tqdm with the counts of :func:`_count` (``done`` and ``whole`` in :data:`FORMAT`), and
    without tqdm's monitor thread: the bar is drawn before the job's workers start, and a
    process pool forks its workers (milliseconds) only while this process runs one thread."""

    monitor_interval = 0

    @property
    def format_dict(self) -> dict[str, Any]:
        """tqdm's fields and ours."""
        fields: dict[str, Any] = super().format_dict
        return fields | {"done": _count(self.n), "whole": _count(self.total)}


class _Nowhere:
    """Where tqdm draws when the stream is no terminal (the lines are written by the bar)."""

    def write(self, text: str) -> None:
        """Drop ``text``."""

    def flush(self) -> None:
        """Nothing to flush."""


class ProgressBar:
    """Call it with (done, total) units; :meth:`close` ends the line."""

    def __init__(self, unit: str = "queries", stream: TextIO | None = None,
                 enabled: bool = True, interval: float = 0.25):
        self.unit = unit
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.interval = interval
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.bar: _Bar | None = None
        self._last_tenth = -1

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        if self.bar is None:  # (from the first call on: a resumed run's rate is its own)
            self.bar = _Bar(
                total=total, initial=done, unit=" " + self.unit, unit_scale=True, ascii=".#",
                bar_format=FORMAT, smoothing=0, miniters=1, dynamic_ncols=False,
                mininterval=self.interval if self.tty else math.inf,
                file=self.stream if self.tty else _Nowhere())
        bar = self.bar
        bar.total = total
        if done >= total and self.tty:
            bar.n = done
            bar.refresh()  # (the end is always drawn)
        else:
            bar.update(done - bar.n)
        if not self.tty:
            tenth = 10 * done // max(total, 1)
            if tenth > self._last_tenth:
                self._last_tenth = tenth
                self.stream.write(str(bar) + "\n")
                self.stream.flush()

    def line(self) -> str:
        """The bar's text now ('' before the first call)."""
        return str(self.bar) if self.bar is not None else ""

    def close(self) -> None:
        """End the bar's line (on a terminal); again, nothing."""
        if self.bar is not None:
            self.bar.close()
            self.bar = None
