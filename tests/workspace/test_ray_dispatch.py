"""The dispatch's accounting of dead actors, on a scripted stand-in for the Ray backend whose
actors run chunks in order in this process: which chunk a death is charged to, when an actor
dies with several calls unanswered (including the case Ray produces under load, where the
chunk finished just before the death loses its answer with it). The real Ray path is in
test_ray.py; this one is deterministic."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import pytest

from usar_arm.core.job_errors import ChunkFailedError, ClusterUnavailableError
from usar_arm.workspace.engine import Job
from usar_arm.workspace.ray_dispatch import Run, Slot


@dataclass
class Ref:
    """A call: its chunk, and its outcome once the actor ran it."""

    chunk: int | None  # None: the setup call
    outcome: tuple[str, Any] | None = None


@dataclass
class Actor:
    """Runs its calls in order when the backend steps it; ``dies(chunk)`` says whether
    running ``chunk`` kills it and whether the answer of the chunk before is lost too."""

    dies: Callable[[int], tuple[bool, bool]]
    calls: list[Ref] = field(default_factory=list)
    dead: bool = False

    def __post_init__(self) -> None:
        self.setup = _Remote(lambda *a: self._call(None))
        self.run = _Remote(lambda chunk: self._call(int(chunk)))

    def _call(self, chunk: int | None) -> Ref:
        ref = Ref(chunk)
        if self.dead:
            ref.outcome = ("lost", "the actor is dead")
        self.calls.append(ref)
        return ref

    def step(self) -> None:
        """Run the oldest call not run yet."""
        pending = [r for r in self.calls if r.outcome is None]
        if not pending:
            return
        ref = pending[0]
        if ref.chunk is None:
            ref.outcome = ("ok", None)
            return
        dies, loses_last = self.dies(ref.chunk)
        if not dies:
            ref.outcome = ("ok", {"chunk": ref.chunk})
            return
        self.dead = True
        done = [r for r in self.calls if r.outcome is not None and r.chunk is not None]
        if loses_last and done:
            done[-1].outcome = ("lost", "the actor is dead")
        for r in self.calls:
            if r.outcome is None:
                r.outcome = ("lost", "the actor is dead")


@dataclass
class RacingActor(Actor):
    """Runs every queued call at once when stepped, and a death takes the start's answer with
    it: Ray under load, where the worker exits before its start's answer has left it."""

    def step(self) -> None:
        while not self.dead and any(r.outcome is None for r in self.calls):
            super().step()
        if self.dead:
            for r in self.calls:
                if r.chunk is None:
                    r.outcome = ("lost", "the actor is dead")


@dataclass
class StartlessActor(Actor):
    """Dies in its start, every time."""

    def step(self) -> None:
        if self.calls and self.calls[0].outcome is None:
            self.dead = True
            for r in self.calls:
                r.outcome = ("lost", "the actor is dead")


@dataclass
class _Remote:
    call: Callable[..., Ref]

    def remote(self, *args: Any) -> Ref:
        return self.call(*args)


class Scripted:
    """The backend protocol of :class:`Run`, over :class:`Actor` objects."""

    address = "scripted"
    head = None
    start_timeout = 60.0
    call_timeout = 60.0
    joining = False

    def __init__(self, actors: int, dies: Callable[[int], tuple[bool, bool]],
                 kind: type[Actor] = Actor):
        self.dies, self.kind = dies, kind
        self.slots = [self._slot(k) for k in range(actors)]
        self.chunks_here = 0
        self.replaced = 0

    def _slot(self, k: int) -> Slot:
        return Slot(self.kind(self.dies), f"actor {k}", time.monotonic())

    def join(self, wait: float) -> bool:
        return True

    def replace(self, k: int, job: Job) -> Slot:
        self.replaced += 1
        slot = self.slots[k] = self._slot(k)
        slot.ready = slot.actor.setup.remote()
        slot.given = True
        return slot

    def kill(self, slot: Slot) -> None:
        slot.actor.dead = True

    def wait_one(self, refs: list[Ref], timeout: float) -> list[Ref]:
        for slot in self.slots:
            slot.actor.step()
        return next(([r] for r in refs if r.outcome is not None), [])

    def answer(self, ref: Ref, wait: float | None = None) -> tuple[str, Any]:
        return ref.outcome if ref.outcome is not None else ("pending", None)


def _job(chunks: int = 8) -> Job:
    return Job("scripted", lambda: None, lambda context, chunk: {}, list(range(chunks)),
               "key", [1] * chunks)


def _run(backend: Scripted, chunks: int = 8) -> list[int]:
    return sorted(i for i, _ in Run(backend, _job(chunks), range(chunks)).results())


def test_a_chunk_that_dies_once_is_run_again_and_every_chunk_answers() -> None:
    died: set[int] = set()

    def dies(i: int) -> tuple[bool, bool]:
        first = i == 3 and i not in died
        died.add(i)
        return first, first
    backend = Scripted(2, dies)
    assert _run(backend) == list(range(8))
    assert backend.replaced == 1


@pytest.mark.parametrize("loses_last", [False, True],
                         ids=["answers-arrive", "the-last-answer-is-lost"])
def test_a_second_death_names_the_chunk_that_kills_its_actor(loses_last: bool) -> None:
    """Chunk 3 kills every actor that runs it; when the chunk its actor finished before it
    loses its answer with the death, that chunk must not be the one blamed."""
    backend = Scripted(2, lambda i: (i == 3, loses_last))
    with pytest.raises(ChunkFailedError) as err:
        _run(backend)
    assert err.value.chunk == 3 and err.value.attempts == 2


def test_chunks_lost_together_run_alone_until_they_answer() -> None:
    """An actor dying with two calls unanswered charges neither; both then run alone (no
    call is queued behind them), so the next death is charged exactly."""
    backend = Scripted(1, lambda i: (i == 3, True))
    run = Run(backend, _job(), range(8))
    with pytest.raises(ChunkFailedError) as err:
        for _ in run.results():
            for slot in backend.slots:
                alone = [i for _, i in slot.calls if i in run.alone]
                assert not alone or len(slot.calls) == 1
    assert err.value.chunk == 3 and 2 not in run.failures
    assert backend.replaced == 2  # (three deaths, one uncharged; the third stops the run)


def test_a_death_that_takes_the_starts_answer_with_it_is_charged_to_its_chunk() -> None:
    """Seen in a campaign run: the worker killed by chunk 3 took its start's answer with it, so
    the dispatch counted two start failures and blamed the cluster. An actor that dies before
    its start is confirmed, with calls queued, charges nothing; the slot's next actor gets
    calls only after its start, and the second death of chunk 3 names it."""
    backend = Scripted(2, lambda i: (i == 3, False), RacingActor)
    with pytest.raises(ChunkFailedError) as err:
        _run(backend)
    assert err.value.chunk == 3 and err.value.attempts == 2


def test_an_actor_that_dies_in_its_start_every_time_names_the_cluster() -> None:
    """The careful slot still ends a run whose actors never start: its next actors, given no
    calls, die in their start, and that is counted."""
    backend = Scripted(1, lambda i: (False, False), StartlessActor)
    with pytest.raises(ClusterUnavailableError, match="failed to start 2 times"):
        _run(backend)
