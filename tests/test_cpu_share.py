"""The CPU-share instrument of the wall-clock tests (tests/cpu_share.py)."""

from __future__ import annotations

import os
import threading
import time

import pytest

from tests.cpu_share import STARVED, Window, watched


def test_a_window_is_starved_when_a_thread_waited_more_than_its_share() -> None:
    assert not Window(wall_s=10.0, worst_wait_s=0.9 * STARVED * 10.0).starved
    assert Window(wall_s=10.0, worst_wait_s=1.1 * STARVED * 10.0).starved
    cpus = os.cpu_count() or 1  # (steal is summed over the CPUs)
    assert not Window(wall_s=10.0, steal_s=0.9 * STARVED * 10.0 * cpus).starved
    assert Window(wall_s=10.0, steal_s=1.1 * STARVED * 10.0 * cpus).starved
    assert not Window().starved  # (nothing measured yet)


def test_a_starved_window_skips_with_its_measurement() -> None:
    with pytest.raises(pytest.skip.Exception, match=r"waited 3\.00 s for a CPU"):
        Window(wall_s=4.0, worst_wait_s=3.0).judge_or_skip()
    Window(wall_s=4.0, worst_wait_s=0.0).judge_or_skip()  # (judged: no skip)


def test_the_window_measures_wall_time_and_the_waits_of_threads_started_inside() -> None:
    def spin() -> None:
        end = time.monotonic() + 0.2
        while time.monotonic() < end:
            pass

    with watched() as window:
        worker = threading.Thread(target=spin)
        worker.start()
        time.sleep(0.3)
        worker.join()
    assert 0.3 <= window.wall_s < 5.0
    assert 0.0 <= window.worst_wait_s <= window.wall_s
    assert window.steal_s >= 0.0
