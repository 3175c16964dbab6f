"""The dispatch of one job's chunks to the actors of a :class:`~.ray_backend.RayBackend`.

Each actor always has :data:`IN_FLIGHT` calls queued, so it never waits for the driver while a
result travels; the answers are collected as they finish (never one wait for thousands of
references). No wait is unbounded: an actor that is not ready within the backend's
``start_timeout`` is an error naming it, and a call without an answer within its
``call_timeout`` counts as a failure of its chunk. A chunk whose actor dies or raises is
retried once (on a fresh actor when it died; the chunks queued behind it are not charged, and
when the death cannot be told apart from theirs, each runs alone before anyone is charged); a
second failure stops the run. While a local instance starts, a helper process
(:mod:`.warm_up_helper`) runs chunks too, at most one worker's share.

This module does not import ``ray``: the backend waits for, reads and kills actors for it.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from usar_arm.core.job_errors import ChunkFailedError, ClusterUnavailableError
from usar_arm.workspace.engine import ATTEMPTS, Job, Result
from usar_arm.workspace.local_head import LocalHead
from usar_arm.workspace.warm_up_helper import WarmUpHelper

IN_FLIGHT = 2
"""Calls queued per actor: the next chunk is there when one finishes."""
POLL = 1.0
"""s between checks of the deadlines while waiting."""
SETTLE = 5.0
"""s to wait for each call of a lost actor to settle: Ray fails the calls of a dead actor
within a second, and the answer of a chunk it finished just before dying may still be on its
way (taken as not answered, that chunk would be charged for the death of the next)."""
HELPER_POLL = 0.05
"""s between looks at the actors while the helper runs a chunk (a chunk takes 0.05 to 1 s)."""


@dataclass(eq=False)
class Slot:
    """An actor, its place among the actors and its calls, oldest first."""

    actor: Any
    name: str
    created: float
    ready: Any = None  # the reference of its setup call until it answered
    given: bool = False  # it was given the job (its setup call sent)
    calls: deque[tuple[Any, int]] = field(default_factory=deque)
    since: float = 0.0  # when its oldest call could start (s, monotonic)


class Actors(Protocol):
    """What the dispatch needs of its backend (:class:`~.ray_backend.RayBackend`)."""

    address: str
    slots: list[Slot]
    head: LocalHead | None  # (local: the process starting the instance)
    start_timeout: float  # s an actor may take to become ready
    call_timeout: float  # s a chunk's call may take
    chunks_here: int  # chunks the helper ran

    @property
    def joining(self) -> bool:
        """A local instance is starting, not yet joined."""

    def join(self, wait: float) -> bool:
        """Join the local instance once up (at most ``wait`` s) and create the actors."""

    def replace(self, k: int, job: Job) -> Slot:
        """A fresh actor in place of slot ``k``, given the job."""

    def kill(self, slot: Slot) -> None:
        """Kill the actor of ``slot``."""

    def wait_one(self, refs: list[Any], timeout: float) -> list[Any]:
        """The references of ``refs`` answered within ``timeout`` s (one at most)."""

    def answer(self, ref: Any, wait: float | None = None) -> tuple[str, Any]:
        """("ok", value), ("lost", why), ("raised", why) or, not answered within ``wait`` s,
        ("pending", None)."""


class Run:
    """One job's chunks through the backend's actors (:meth:`results`, as they finish)."""

    def __init__(self, backend: Actors, job: Job, todo: Sequence[int]):
        self.backend, self.job = backend, job
        self.queue = deque(todo)
        self.failures: dict[int, list[str]] = {}
        self.start_failures: dict[int, list[str]] = {}
        self.alone: set[int] = set()
        self.careful: set[int] = set()  # slots fed only once their actor's start is confirmed
        """Chunks lost with another when an actor died: each runs alone on its actor until
        it answers, so that a second death is charged to the chunk that caused it."""
        self.share = len(todo) // (backend.head.num_cpus + 1) if backend.head else 0
        """Chunks a helper may run while a local instance starts: one worker's share."""
        self.helper = WarmUpHelper(job)
        self._give_job()

    def _give_job(self) -> None:
        for slot in self.backend.slots:
            if not slot.given:
                slot.ready = slot.actor.setup.remote(self.job.key, self.job.prepare,
                                                     self.job.work)
                slot.given = True

    def results(self) -> Iterator[tuple[int, Result]]:
        """(chunk, result) of every chunk, as they finish (the helper stopped at the end)."""
        backend = self.backend
        try:
            while self.queue or any(s.calls for s in backend.slots) or self.helper.busy:
                if backend.joining and backend.join(0.0):
                    self._give_job()
                self._feed()
                self._keep_helper_busy()
                if self.helper.busy:
                    yield from self._helper_result(HELPER_POLL)
                elif backend.joining:  # nothing to do here but wait for the instance
                    if backend.join(POLL):
                        self._give_job()
                    continue
                slots = backend.slots
                waiting = [s.ready for s in slots if s.ready is not None] + [
                    ref for s in slots for ref, _ in s.calls]
                if waiting:
                    ready = backend.wait_one(waiting, 0.0 if self.helper.busy else POLL)
                    for ref in ready:
                        yield from self._collect(ref)
                yield from self._check_deadlines()
        finally:
            self.helper.stop()

    # ------------------------------------------------------------------ the helper
    def _keep_helper_busy(self) -> None:
        """While a local instance starts (until every actor is ready), the helper runs chunks
        too, at most one worker's share; then it is stopped."""
        b = self.backend
        warming = b.head is not None and (b.joining or any(s.ready is not None
                                                            for s in b.slots))
        if self.helper.busy:
            return
        if warming and self.queue and self.helper.done < self.share:
            self.helper.give(self.queue.popleft())
        else:
            self.helper.stop()

    def _helper_result(self, timeout: float) -> Iterator[tuple[int, Result]]:
        done = self.helper.result(timeout, self.backend.call_timeout)
        if done is None:
            return
        i, result = done
        if isinstance(result, str):
            self._failed(i, result)
            return
        self.backend.chunks_here = self.helper.done
        yield i, result

    # ------------------------------------------------------------------ the actors
    def _feed(self) -> None:
        """Keep :data:`IN_FLIGHT` calls queued on every actor (behind its setup; after it,
        once confirmed, for a :attr:`careful` slot)."""
        for k, slot in enumerate(self.backend.slots):
            if k in self.careful and slot.ready is not None:
                continue
            while self.queue and len(slot.calls) < IN_FLIGHT:
                if slot.calls and (self.queue[0] in self.alone
                                   or slot.calls[-1][1] in self.alone):
                    break
                i = self.queue.popleft()
                if not slot.calls:
                    slot.since = time.monotonic()
                slot.calls.append((slot.actor.run.remote(self.job.chunks[i]), i))

    def _collect(self, ref: Any) -> Iterator[tuple[int, Result]]:
        """The answer ``ref`` (a setup's or a chunk's) brought."""
        for k, slot in enumerate(self.backend.slots):
            if slot.ready is not None and slot.ready == ref:
                kind, answer = self.backend.answer(ref)
                if kind != "ok":
                    yield from self._actor_lost(k, f"it did not start: {answer}")
                    return
                slot.ready, slot.since = None, time.monotonic()
                return
            n = next((n for n, (call, _) in enumerate(slot.calls) if call == ref), None)
            if n is None:
                continue
            i = slot.calls[n][1]
            kind, answer = self.backend.answer(ref)
            if kind == "lost":
                yield from self._actor_lost(k, answer)
                return
            del slot.calls[n]
            if kind == "raised":  # the chunk raised; its actor lives on
                self._failed(i, answer)
                return
            slot.since = time.monotonic()
            self.alone.discard(i)
            yield i, answer
            return

    def _actor_lost(self, k: int, reason: str,
                    hung: bool = False) -> Iterator[tuple[int, Result]]:
        """The actor of slot ``k`` is gone: keep what it finished, charge the chunk it was
        running, queue the others again uncharged, and start a fresh actor.

        The chunk it was running is its oldest call without an answer, except that a chunk
        it finished just before dying may have lost its answer with it: so when the actor
        died (not ``hung``, killed for its oldest call's deadline) with more than one call
        unanswered, none is charged and each of them runs alone until it answers. Nothing is
        charged when the actor never started (its slot's start is).

        An actor that dies before its start's answer arrived, with calls queued behind the
        start, may have died in one of them: a worker that exits takes the start's answer, on
        its way, with it (seen under load). Neither is charged then: its calls run alone, and
        the slot's next actor gets calls only once its start is confirmed, so that its death
        is either a start failure (no calls) or a chunk's."""
        slot = self.backend.slots[k]
        again: list[int] = []
        for ref, i in slot.calls:  # (a finished chunk's answer may still be on its way)
            kind, answer = self.backend.answer(ref, wait=SETTLE)
            if kind == "ok":
                yield i, answer
                continue
            again.append(i)
        slot.calls.clear()
        charged = None
        if slot.ready is None and again:
            if hung or len(again) == 1:
                charged = again.pop(0)
            else:
                self.alone.update(again)
        self.queue.extendleft(reversed(again))
        if slot.ready is not None and again:  # it died in its start or in a chunk after it
            self.alone.update(again)
            self.careful.add(k)
        elif slot.ready is not None:  # it never became ready: no chunk of it ran
            self.start_failures.setdefault(k, []).append(reason)
            if len(self.start_failures[k]) >= ATTEMPTS:
                raise ClusterUnavailableError(
                    self.backend.address,
                    f"Ray {slot.name} failed to start {ATTEMPTS} times: {reason}")
        if charged is not None:
            self._failed(charged, reason)  # (queued again first)
        self.backend.replace(k, self.job)

    def _failed(self, i: int, reason: str) -> None:
        """Chunk ``i`` failed: queue it again first, or stop after :data:`ATTEMPTS`."""
        self.failures.setdefault(i, []).append(reason)
        if len(self.failures[i]) >= ATTEMPTS:
            raise ChunkFailedError(i, len(self.failures[i]), reason)
        self.queue.appendleft(i)

    def _check_deadlines(self) -> Iterator[tuple[int, Result]]:
        """No wait is unbounded: an actor not ready in time is an error naming it; a call
        without an answer in time is a failure of its chunk (and its actor is replaced)."""
        now = time.monotonic()
        backend = self.backend
        for k, slot in enumerate(backend.slots):
            if slot.ready is not None and now - slot.created > backend.start_timeout:
                raise ClusterUnavailableError(
                    backend.address,
                    f"Ray {slot.name} was not ready within {backend.start_timeout:g} s "
                    f"({len(backend.slots)} actors of 1 CPU each: is a node gone, or are "
                    "its CPUs taken by another job?)")
            if slot.ready is None and slot.calls and now - slot.since > backend.call_timeout:
                backend.kill(slot)
                yield from self._actor_lost(k, f"no answer within {backend.call_timeout:g} s",
                                            hung=True)
