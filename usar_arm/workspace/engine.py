"""The execution engine under reach, place and batch: a job cut into chunks, run by a backend.

A :class:`Job` is everything a worker needs, by value: ``prepare`` builds the worker's context
once per process (the robot from its URDF/SRDF text, the collision world from the scene:
wrapped C++ objects never travel), ``work`` turns one chunk into a result (a dict of numpy
arrays), and ``key`` names everything the results depend on. Backends (local processes in
:mod:`.pool`, Ray in :mod:`.ray_backend`, and :class:`InProcess` here) only decide where chunks
run: a chunk's result depends on the chunk alone, so the assembled result is the same whatever
the backend and worker count.

Finished chunks go to a :class:`ChunkStore` (one file each, written atomically), so an
interrupted run keeps them and ``resume`` continues; a chunk whose worker dies or raises is
retried once, then the run stops with :class:`~usar_arm.core.job_errors.ChunkFailedError`.
"""

from __future__ import annotations

import hashlib
import io
import json
import logging
import time
import traceback
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from usar_arm.core.fileio import write_atomic
from usar_arm.core.job_errors import ChunkFailedError, ResumeMismatchError

log = logging.getLogger("usar_arm.workspace")

Result = dict[str, np.ndarray]
ATTEMPTS = 2
"""Tries of one chunk before the run stops."""


@dataclass(frozen=True)
class Job:
    """A job for the engine (every field picklable).

    Attributes:
        name: what it is (for messages).
        prepare: builds a worker's context, once per worker process.
        work: (context, chunk) -> result, a dict of numpy arrays.
        chunks: the chunks, small descriptions of the work (e.g. voxel indices).
        key: a digest of everything the results depend on (checked on resume).
        units: work units per chunk (e.g. queries), for the progress rate.
        parts: the key's parts by name (``problems``, ``settings``...: a digest each), kept
            beside the chunks so that a refused resume can say what differs.
    """

    name: str
    prepare: Callable[[], Any]
    work: Callable[[Any, Any], Result]
    chunks: Sequence[Any]
    key: str
    units: Sequence[int]
    parts: Mapping[str, str] = field(default_factory=dict)


class Backend(Protocol):
    """Where chunks run.

    ``start`` may be called early (before the job is known), so that connecting to a cluster
    fails fast and its workers start while the caller plans; ``run`` starts the backend when
    nobody did and stops it at the end (``close``, which may also be called on any error
    before a run). ``start_seconds`` is the time ``start`` took (s): a run's time includes it.
    """

    workers: int
    start_seconds: float

    def start(self) -> bool:
        """Get ready to run chunks; False when already started (and not closed since)."""
        ...

    def run(self, job: Job, todo: Sequence[int]) -> Iterator[tuple[int, Result]]:
        """Yield (chunk index, result) for every chunk in ``todo``, in any order; retry a
        failed chunk once, then raise ChunkFailedError. Stops the backend at the end."""
        ...

    def close(self) -> None:
        """Stop whatever ``start`` started (idempotent)."""
        ...

    def describe(self) -> str:
        """One line: what runs the chunks."""
        ...


def digest(*parts: Any) -> str:
    """A short stable hash of JSON-able parts (strings, numbers, lists, dicts)."""
    text = json.dumps(parts, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


# ------------------------------------------------------------------ in the worker processes
_CONTEXTS: dict[str, Any] = {}


def run_chunk(job_key: str, prepare: Callable[[], Any], work: Callable[[Any, Any], Result],
              chunk: Any) -> Result:
    """Run one chunk in this process, building (and keeping) the job's context first."""
    context = _CONTEXTS.get(job_key)
    if context is None:
        _CONTEXTS.clear()  # one job at a time per worker
        context = _CONTEXTS[job_key] = prepare()
    return work(context, chunk)


def forget_contexts() -> None:
    """Drop the contexts this process built (a new worker starts from none)."""
    _CONTEXTS.clear()


def describe_failure(exc: BaseException) -> str:
    """The last line of a traceback: the exception and its message."""
    lines = traceback.format_exception_only(type(exc), exc)
    return lines[-1].strip() if lines else type(exc).__name__


class InProcess:
    """Chunks run one after the other in this process (no start-up cost: small jobs, tests)."""

    workers = 1
    start_seconds = 0.0

    def start(self) -> bool:
        """Nothing to start."""
        return True

    def close(self) -> None:
        """Nothing to stop."""

    def run(self, job: Job, todo: Sequence[int]) -> Iterator[tuple[int, Result]]:
        """:meth:`Backend.run`: every chunk of ``todo`` with its result, as each finishes."""
        for i in todo:
            failures: list[str] = []
            while True:
                try:
                    result = run_chunk(job.key, job.prepare, job.work, job.chunks[i])
                    break
                except Exception as exc:  # a chunk's failure, retried once
                    failures.append(describe_failure(exc))
                    if len(failures) >= ATTEMPTS:
                        raise ChunkFailedError(i, len(failures), failures[-1]) from exc
            yield i, result

    def describe(self) -> str:
        """:meth:`Backend.describe`: one line, what runs the chunks."""
        return "this process"


# ------------------------------------------------------------------ finished chunks on disk
class ChunkStore:
    """One ``.npz`` file per finished chunk in ``folder``, and ``job.json`` naming the job's
    key; written atomically, so a killed run leaves only whole chunks."""

    def __init__(self, folder: str | Path, job: Job):
        self.folder = Path(folder)
        self.job = job

    def path(self, i: int) -> Path:
        """The file of chunk ``i``."""
        return self.folder / f"chunk-{i:06d}.npz"

    def start(self, resume: bool) -> dict[int, Result]:
        """Prepare the folder; with ``resume``, the chunks a previous run of the same job
        finished (an unreadable one is run again).

        Raises:
            ResumeMismatchError: resuming a folder that holds another job's chunks (naming
                the parts of the key that differ).
        """
        meta = self.folder / "job.json"
        if resume and meta.exists():
            self._check_same_job(meta)
        elif not resume:
            for old in self.folder.glob("chunk-*.npz"):
                old.unlink()
        self.folder.mkdir(parents=True, exist_ok=True)
        write_atomic(meta, json.dumps({"job": self.job.name, "key": self.job.key,
                                       "parts": dict(self.job.parts),
                                       "chunks": len(self.job.chunks)}) + "\n")
        done: dict[int, Result] = {}
        if resume:
            for i in range(len(self.job.chunks)):
                if self.path(i).exists():
                    try:
                        with np.load(self.path(i), allow_pickle=False) as data:
                            done[i] = {k: data[k] for k in data.files}
                    except (OSError, ValueError) as exc:
                        log.warning("chunk file %s unreadable (%s): running it again",
                                    self.path(i), exc)
        return done

    def _check_same_job(self, meta: Path) -> None:
        """Refuse chunks of another job, naming what differs where the kept job says."""
        try:
            kept = json.loads(meta.read_text())
        except (OSError, ValueError):
            kept = {}
        found = kept.get("key") if isinstance(kept, dict) else None
        if found == self.job.key:
            return
        parts = kept.get("parts") if isinstance(kept, dict) else None
        differences = [name for name, value in self.job.parts.items()
                       if isinstance(parts, dict) and parts.get(name) != value]
        raise ResumeMismatchError(str(self.folder), found, self.job.key, differences)

    def save(self, i: int, result: Result) -> None:
        """Keep chunk ``i``'s result."""
        buffer = io.BytesIO()
        savez: Any = np.savez  # (numpy's stub types every keyword as allow_pickle)
        savez(buffer, **result)
        write_atomic(self.path(i), buffer.getvalue())

    def clear(self) -> None:
        """Remove the chunk files and the folder (after the job's outputs are written)."""
        for f in self.folder.glob("chunk-*.npz"):
            f.unlink()
        meta = self.folder / "job.json"
        if meta.exists():
            meta.unlink()
        try:
            self.folder.rmdir()
        except OSError:
            pass


@dataclass(frozen=True)
class RunStats:
    """How a job ran: chunks run now and found finished, units (queries), seconds (from the
    backend's start, included wherever it happened, to the last chunk's result and the
    backend's stop), the backend, its workers, the seconds its start took and the chunks the
    calling process ran itself while it started (``--ray local``)."""

    chunks_run: int
    chunks_resumed: int
    units: int
    seconds: float
    backend: str
    workers: int
    start_seconds: float = 0.0
    chunks_here: int = 0


Progress = Callable[[int, int], None]
"""Called with (units done, units in all) after each chunk."""


def run_job(job: Job, backend: Backend, store: ChunkStore | None = None, resume: bool = False,
            progress: Progress | None = None) -> tuple[list[Result], RunStats]:
    """Every chunk's result, in chunk order, and how the run went. The backend is stopped at
    the end, whatever happens (a refused resume, a failed chunk, Ctrl-C)."""
    start = time.perf_counter()
    try:
        results: dict[int, Result] = store.start(resume) if store is not None else {}
        resumed = len(results)
        total = int(sum(job.units))
        done_units = int(sum(job.units[i] for i in results))
        if progress is not None:
            progress(done_units, total)
        todo = [i for i in range(len(job.chunks)) if i not in results]
        # a start made before the run (to fail fast, or to start the workers while the
        # caller planned) is the run's time too
        started_before = 0.0 if not todo or backend.start() else backend.start_seconds
        for i, result in backend.run(job, todo) if todo else ():
            results[i] = result
            if store is not None:
                store.save(i, result)
            done_units += int(job.units[i])
            if progress is not None:
                progress(done_units, total)
    finally:
        backend.close()
    stats = RunStats(len(todo), resumed, total,
                     time.perf_counter() - start + started_before, backend.describe(),
                     backend.workers, backend.start_seconds,
                     int(getattr(backend, "chunks_here", 0)))
    return [results[i] for i in range(len(job.chunks))], stats
