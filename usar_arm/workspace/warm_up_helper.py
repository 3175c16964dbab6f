"""A worker process of this machine's that runs chunks while a fresh local Ray instance starts.

Ray's start and its actors' take seconds of CPU; a process pool's forked worker starts in
milliseconds with everything imported. So ``--ray local`` runs chunks in one (forked, or from
the forkserver, as the pool's: :func:`usar_arm.workspace.pool.start_worker`) until every actor
is ready, at most one worker's share of them. It is a worker like the pool's: a chunk that
raises or kills it is a failure of that chunk (one of its two attempts), and a helper that
died is not replaced (the actors take over).
"""

from __future__ import annotations

import multiprocessing as mp
import time
from multiprocessing.connection import wait

from usar_arm.workspace.engine import Job, Result
from usar_arm.workspace.pool import Worker, reply, start_method, start_worker


class WarmUpHelper:
    """One worker process for ``job``, started on first use; ``done`` counts its chunks."""

    def __init__(self, job: Job):
        self.job = job
        self.worker: Worker | None = None
        self.done = 0
        self.since = 0.0  # when its chunk was given (s, monotonic)

    @property
    def busy(self) -> bool:
        """It runs a chunk."""
        return self.worker is not None and self.worker.chunk is not None

    def give(self, i: int) -> None:
        """Run chunk ``i`` (starting the process first if needed); it must not be busy."""
        assert not self.busy
        if self.worker is None:
            self.worker = start_worker(mp.get_context(start_method()), self.job)
        self.since = time.monotonic()
        self.worker.send(i, self.job)

    def result(self, timeout: float, limit: float) -> tuple[int, Result | str] | None:
        """(chunk, its result) when it finished within ``timeout`` s, (chunk, why it failed)
        when it raised, the process died or the chunk ran ``limit`` s (then the process is
        stopped), None while it still runs."""
        w = self.worker
        assert w is not None and w.chunk is not None
        if not wait([w.conn, w.process.sentinel], timeout):
            if time.monotonic() - self.since <= limit:
                return None
            i = w.chunk
            self.stop()
            return i, f"no answer from the helper process within {limit:g} s"
        i, w.chunk = w.chunk, None
        answer = reply(w)
        if answer is not None and answer[0] == "ok":
            self.done += 1
            return i, answer[2]
        if answer is None:
            self.stop()
            return i, f"the helper process died (exit code {w.process.exitcode})"
        return i, str(answer[2])

    def stop(self) -> None:
        """Stop the process (killed at once when it runs a chunk: its result is not wanted)."""
        if self.worker is not None:
            if self.worker.chunk is not None and self.worker.process.is_alive():
                self.worker.process.kill()
            self.worker.stop()
            self.worker = None
