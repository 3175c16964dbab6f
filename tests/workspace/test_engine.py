"""The execution engine: the same results whatever runs the chunks; a chunk whose worker dies
or raises is retried once, a second failure stops the run naming the chunk, and the finished
chunks let a later run resume."""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.job_errors import ChunkFailedError
from usar_arm.workspace.engine import ChunkStore, InProcess, Job, run_job
from usar_arm.workspace.pool import ProcessBackend

from . import faults

CHUNKS = [np.arange(10 * i, 10 * i + 10) for i in range(8)]


def _job(work: object, folder: Path, key: str = "") -> Job:
    return Job("test", functools.partial(faults.prepare, str(folder)), work,  # type: ignore[arg-type]
               CHUNKS, key or str(folder), [10] * len(CHUNKS))


def _squares(results: list[dict[str, np.ndarray]]) -> np.ndarray:
    return np.concatenate([r["squares"] for r in results])


@pytest.mark.parametrize("backend", [InProcess(), ProcessBackend(1), ProcessBackend(2),
                                     ProcessBackend(2, start_method="forkserver")],
                         ids=["in-process", "1 process", "2 processes", "2 forkserver"])
def test_every_backend_gives_the_results_in_chunk_order(backend: object,
                                                        tmp_path: Path) -> None:
    results, stats = run_job(_job(faults.square, tmp_path), backend)  # type: ignore[arg-type]
    assert np.array_equal(_squares(results), np.arange(80) ** 2)
    assert stats.chunks_run == 8 and stats.units == 80


def test_a_worker_that_dies_has_its_chunk_retried(tmp_path: Path) -> None:
    results, _ = run_job(_job(faults.dies_once_on_chunk_3, tmp_path), ProcessBackend(2))
    assert (tmp_path / "died").exists()
    assert np.array_equal(_squares(results), np.arange(80) ** 2)


def test_a_chunk_that_raises_is_retried(tmp_path: Path) -> None:
    for backend in (InProcess(), ProcessBackend(2)):
        for mark in tmp_path.glob("*"):
            mark.unlink()
        results, _ = run_job(_job(faults.raises_once_on_chunk_3, tmp_path), backend)
        assert np.array_equal(_squares(results), np.arange(80) ** 2)


def test_a_second_death_stops_the_run_naming_the_chunk_and_resume_finishes(
        tmp_path: Path) -> None:
    store_dir = tmp_path / "chunks"
    job = _job(faults.always_dies_on_chunk_3, tmp_path)
    with pytest.raises(ChunkFailedError) as err:
        run_job(job, ProcessBackend(2), ChunkStore(store_dir, job))
    assert err.value.chunk == 3 and err.value.attempts == 2
    assert "exit code 3" in str(err.value) and "--resume" in str(err.value)
    kept = sorted(p.name for p in store_dir.glob("chunk-*.npz"))
    assert "chunk-000003.npz" not in kept and len(kept) >= 1
    healthy = _job(faults.square, tmp_path)  # the same key: the same job, fixed
    results, stats = run_job(healthy, ProcessBackend(2), ChunkStore(store_dir, healthy),
                             resume=True)
    assert stats.chunks_resumed == len(kept) and stats.chunks_run == 8 - len(kept)
    assert np.array_equal(_squares(results), np.arange(80) ** 2)


def test_resuming_another_jobs_chunks_is_refused(tmp_path: Path) -> None:
    store_dir = tmp_path / "chunks"
    job = _job(faults.square, tmp_path, key="one")
    run_job(job, InProcess(), ChunkStore(store_dir, job))
    other = _job(faults.square, tmp_path, key="two")
    with pytest.raises(InvalidInputError, match="another job"):
        run_job(other, InProcess(), ChunkStore(store_dir, other), resume=True)


def test_without_resume_old_chunks_are_not_reused(tmp_path: Path) -> None:
    store_dir = tmp_path / "chunks"
    job = _job(faults.square, tmp_path)
    run_job(job, InProcess(), ChunkStore(store_dir, job))
    _, stats = run_job(job, InProcess(), ChunkStore(store_dir, job))
    assert stats.chunks_resumed == 0 and stats.chunks_run == 8
