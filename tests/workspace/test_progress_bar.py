"""The jobs' progress bar (tqdm's): queries done, rate and time left; one redrawn line on a
terminal, a line at every tenth of the work elsewhere, nothing with -q."""

from __future__ import annotations

import io
import threading

import pytest
import tqdm.std

from usar_arm.cli.progress_bar import ProgressBar


class Clock:
    """A clock the test moves (s)."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


@pytest.fixture
def clock(monkeypatch: pytest.MonkeyPatch) -> Clock:
    c = Clock()
    monkeypatch.setattr(tqdm.std, "time", c)  # (tqdm's clock)
    return c


def test_the_line_says_done_total_rate_and_time_left(clock: Clock) -> None:
    bar = ProgressBar("queries", io.StringIO())
    bar(0, 2_000_000)
    clock.now += 10.0
    bar(500_000, 2_000_000)
    line = bar.line()
    assert "25.0 %" in line and "500k/2.00M queries" in line
    assert "50.0k queries/s" in line  # 500,000 in 10 s
    assert "00:10 elapsed, 00:30 left" in line  # 1.5 M left at 50 k/s
    assert line.startswith("[" + "#" * 7 + "." * 23 + "]")  # (tqdm fills whole cells: 7.5)


def test_a_resumed_run_counts_its_rate_from_what_it_does_itself(clock: Clock) -> None:
    bar = ProgressBar("queries", io.StringIO())
    bar(600, 1000)  # 600 found finished
    clock.now += 4.0
    bar(800, 1000)
    line = bar.line()
    assert "50.0 queries/s" in line and "00:04 left" in line


def test_without_a_terminal_a_line_is_written_at_every_tenth(clock: Clock) -> None:
    out = io.StringIO()
    bar = ProgressBar("problems", out)
    for done in range(0, 1001, 25):
        clock.now += 0.5
        bar(done, 1000)
    bar.close()
    lines = out.getvalue().splitlines()
    assert len(lines) == 11 and "\r" not in out.getvalue()
    assert lines[0].lstrip("[.]").strip().startswith("0.0 %")
    assert "100.0 %" in lines[-1] and "1.00k/1.00k problems" in lines[-1]
    assert "00:00 left" in lines[-1]


def test_on_a_terminal_one_line_is_redrawn_at_most_every_interval_and_ended(
        clock: Clock) -> None:
    out = Terminal()
    bar = ProgressBar("queries", out, interval=0.25)
    bar(0, 100)
    clock.now += 0.1
    bar(10, 100)  # too soon: not drawn
    clock.now += 0.2
    bar(20, 100)
    clock.now += 0.01
    bar(100, 100)  # the end is always drawn
    assert out.getvalue().count("\r") == 3 and "\n" not in out.getvalue()
    bar.close()
    assert out.getvalue().rstrip(" ").endswith(
        "100.0 %  100/100 queries  323 queries/s  00:00 elapsed, 00:00 left\n")


def test_quiet_writes_nothing(clock: Clock) -> None:
    out = Terminal()
    bar = ProgressBar("queries", out, enabled=False)
    bar(0, 10)
    bar(10, 10)
    bar.close()
    assert out.getvalue() == ""


def test_the_bar_starts_no_thread(clock: Clock) -> None:
    """The bar is drawn before a job's workers start: a second thread would make the process
    pool start them by forkserver (seconds) instead of fork (milliseconds)."""
    before = threading.active_count()
    bar = ProgressBar("queries", Terminal())
    bar(0, 100)
    bar(50, 100)
    assert threading.active_count() == before
    bar.close()
