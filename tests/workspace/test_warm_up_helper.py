"""The helper that runs chunks while a local Ray instance starts is a worker like the pool's:
a result, a chunk that raises, a process that dies and a chunk that never ends are each told
apart, and none of them hangs the caller."""

from __future__ import annotations

import functools
import time
from pathlib import Path

import numpy as np

from usar_arm.workspace.engine import Job
from usar_arm.workspace.warm_up_helper import WarmUpHelper

from . import faults


def _job(work: object, folder: Path) -> Job:
    chunks = [np.arange(10 * i, 10 * i + 10) for i in range(6)]
    return Job("test", functools.partial(faults.prepare, str(folder)), work,  # type: ignore[arg-type]
               chunks, "k", [10] * 6)


def _wait(helper: WarmUpHelper, limit: float = 60.0) -> tuple[int, object]:
    while True:
        done = helper.result(0.05, limit)
        if done is not None:
            return done


def test_its_results_are_the_chunks_and_it_counts_them(tmp_path: Path) -> None:
    helper = WarmUpHelper(_job(faults.square, tmp_path))
    try:
        for i in (0, 4):
            helper.give(i)
            assert helper.busy
            k, result = _wait(helper)
            assert k == i and isinstance(result, dict)
            assert np.array_equal(result["squares"], np.arange(10 * i, 10 * i + 10) ** 2)
        assert helper.done == 2 and not helper.busy
    finally:
        helper.stop()


def test_a_chunk_that_raises_or_kills_it_is_a_failure_of_that_chunk(tmp_path: Path) -> None:
    helper = WarmUpHelper(_job(faults.raises_once_on_chunk_3, tmp_path))
    helper.give(3)
    k, why = _wait(helper)
    assert k == 3 and "a passing fault in chunk 3" in str(why)
    helper.stop()
    helper = WarmUpHelper(_job(faults.dies_once_on_chunk_3, tmp_path))
    helper.give(3)
    k, why = _wait(helper)
    assert k == 3 and why == "the helper process died (exit code 3)"
    assert helper.worker is None and helper.done == 0


def test_a_chunk_that_never_ends_is_stopped_at_its_limit(tmp_path: Path) -> None:
    helper = WarmUpHelper(_job(faults.hangs_on_chunk_3, tmp_path))
    helper.give(3)
    begin = time.monotonic()
    k, why = _wait(helper, limit=1.0)
    assert k == 3 and why == "no answer from the helper process within 1 s"
    assert time.monotonic() - begin < 5.0  # (killed, not waited for)
    assert helper.worker is None
