"""The local execution backend: a pool of worker processes on this machine.

Each worker is a process forked from this one when this one runs a single thread (it then
starts in milliseconds with every module already imported), or started by the ``forkserver``
method otherwise (a clean process, whatever threads this one runs, e.g. an embedded
simulator: forking a threaded process can deadlock the child). It builds the job's context
once and then runs one chunk at a time, sent over its own pipe. The parent watches every pipe
and every process at once (:func:`multiprocessing.connection.wait`), so it always knows which
chunk a worker was running when it died: that chunk is retried once on a fresh worker, and a
second failure stops the run (:class:`~usar_arm.core.job_errors.ChunkFailedError`). Workers ignore
Ctrl-C; the parent terminates them when it is interrupted, or when it stops for any other
reason.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from multiprocessing.connection import Connection, wait
from multiprocessing.process import BaseProcess
from typing import Any

from usar_arm.core.job_errors import ChunkFailedError
from usar_arm.workspace.engine import (
    ATTEMPTS,
    Job,
    Result,
    describe_failure,
    forget_contexts,
    run_chunk,
)

SHUTDOWN_TIMEOUT = 5.0
"""s to wait for a worker to leave after being told to, before it is killed."""


def _serve(conn: Connection, key: str, prepare: Callable[[], Any],
           work: Callable[[Any, Any], Result]) -> None:
    """A worker's loop: (index, chunk) in, ("ok" | "error", index, result | reason) out."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    forget_contexts()  # (a forked worker builds its own, whatever its parent had)
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        i, chunk = message
        try:
            result = run_chunk(key, prepare, work, chunk)
        except Exception as exc:  # reported to the parent, which retries the chunk once
            conn.send(("error", i, describe_failure(exc)))
            continue
        conn.send(("ok", i, result))


@dataclass(eq=False)
class Worker:
    """A worker process, its pipe and the chunk it runs (None when idle)."""

    process: BaseProcess
    conn: Connection
    chunk: int | None = None
    closed: bool = field(default=False)

    def send(self, i: int, job: Job) -> None:
        """Give it chunk ``i`` of ``job`` (it must be idle)."""
        self.chunk = i
        self.conn.send((i, job.chunks[i]))

    def stop(self) -> None:
        if self.closed:
            return
        self.closed = True
        try:
            self.conn.send(None)
        except (OSError, ValueError):
            pass
        self.process.join(SHUTDOWN_TIMEOUT)
        if self.process.is_alive():
            self.process.kill()
            self.process.join(SHUTDOWN_TIMEOUT)
        self.conn.close()


def start_method(asked: str = "auto") -> str:
    """``fork`` while this process runs a single thread, else ``forkserver`` (or as asked)."""
    if asked != "auto":
        return asked
    return "fork" if threading.active_count() == 1 else "forkserver"


def start_worker(context: Any, job: Job) -> Worker:
    """A worker process for ``job`` (of a multiprocessing ``context``), waiting for chunks."""
    parent, child = context.Pipe()
    process = context.Process(target=_serve, args=(child, job.key, job.prepare, job.work),
                              daemon=True, name="usar-arm-worker")
    process.start()
    child.close()
    return Worker(process, parent)


def reply(w: Worker) -> tuple[str, int, Any] | None:
    """The worker's reply (("ok", index, result) or ("error", index, reason)), or None when
    it died before giving one."""
    try:
        if w.conn.poll():
            answer: tuple[str, int, Any] = w.conn.recv()
            return answer
    except (EOFError, OSError):
        pass
    w.process.join(SHUTDOWN_TIMEOUT)
    return None


class ProcessBackend:
    """Chunks run in ``workers`` local processes (default: one per core), started by each run
    (in milliseconds when forked) and stopped at its end."""

    start_seconds = 0.0

    def __init__(self, workers: int | None = None, start_method: str = "auto"):
        if workers is not None and workers < 1:
            raise ValueError(f"--workers must be at least 1, got {workers}")
        self.workers = int(workers or os.cpu_count() or 1)
        self.start_method = start_method

    def start(self) -> bool:
        """Nothing to start before the job is known (a run forks its workers)."""
        return True

    def close(self) -> None:
        """Nothing left running between runs."""

    def describe(self) -> str:
        """:meth:`.engine.Backend.describe`: one line, what runs the chunks."""
        return f"{self.workers} local worker process{'es' if self.workers > 1 else ''}"

    def run(self, job: Job, todo: Sequence[int]) -> Iterator[tuple[int, Result]]:
        """:meth:`.engine.Backend.run`: every chunk of ``todo`` with its result, as each
        finishes."""
        context = mp.get_context(start_method(self.start_method))
        queue = deque(todo)
        failures: dict[int, list[str]] = {}
        workers: list[Worker] = []
        try:
            workers = [start_worker(context, job) for _ in range(min(self.workers, len(queue)))]
            while queue or any(w.chunk is not None for w in workers):
                for w in workers:
                    if w.chunk is None and queue:
                        w.send(queue.popleft(), job)
                busy = [w for w in workers if w.chunk is not None]
                ready = set(wait([w.conn for w in busy] + [w.process.sentinel for w in busy]))
                for k, w in enumerate(workers):
                    if w.chunk is None or not (w.conn in ready or w.process.sentinel in ready):
                        continue
                    i = w.chunk
                    answer = reply(w)
                    if answer is not None and answer[0] == "ok":
                        w.chunk = None
                        if queue:  # its next chunk first: the worker runs while this is saved
                            w.send(queue.popleft(), job)
                        yield i, answer[2]
                        continue
                    reason = answer[2] if answer is not None else (
                        f"its worker process died (exit code {w.process.exitcode})")
                    failures.setdefault(i, []).append(reason)
                    if len(failures[i]) >= ATTEMPTS:
                        raise ChunkFailedError(i, len(failures[i]), reason)
                    queue.appendleft(i)
                    w.chunk = None
                    if answer is None:  # a dead worker is replaced by a fresh one
                        w.stop()
                        workers[k] = start_worker(context, job)
        finally:
            for w in workers:
                w.stop()

