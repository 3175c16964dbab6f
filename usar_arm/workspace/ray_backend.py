"""The Ray execution backend: chunks as calls on Ray actors, on a cluster of any size.

The only module that imports ``ray`` (an optional extra: ``pip install 'usar-arm[ray]'``).
This module connects (or starts a local instance), creates and replaces the actors and leaves;
the dispatch of a job's chunks to them (calls queued per actor, deadlines, retries, a helper
while a local instance starts) is :mod:`.ray_dispatch`'s, through :meth:`RayBackend.wait_one`,
:meth:`RayBackend.answer` and :meth:`RayBackend.kill`; the address rules are
:mod:`.ray_address`'s.

:meth:`RayBackend.start` connects and creates the actors at once (for ``local``: starts the
instance's process, joined when it is up), so a bad address fails before any planning and
the actors' processes start (a fresh Python importing usar-arm, Pinocchio, FCL) while the
caller plans. One actor per free CPU of the
cluster (``workers`` asks for fewer or more: more than the free CPUs are not started, which a
log line says, as actors that cannot be scheduled would hold their chunks forever). Each actor
gets the job by value (URDF, SRDF and scene text: Pinocchio models, FCL geometry and OMPL
spaces do not pickle) and builds its context once.

``local`` starts its instance with workers at the priority of the process pool's, nice 0,
rather than Ray's default 15, and stops it at the end; a process already connected to another
Ray instance is refused rather than joined. The instance is started by a process of its own
(:mod:`.local_head`; run as ``python -m usar_arm.workspace.ray_backend N``,
:func:`serve_local`) while this one goes on, and until its actors are ready a helper runs
chunks (:mod:`.warm_up_helper`). The ``usar-arm`` executable starts that process before it
loads its commands (:mod:`usar_arm.__main__`). An address that does not answer within
``timeout`` seconds is an error saying so: a refused connection is found before Ray is asked,
and Ray's own retries (about one a second, 20 by default) are bounded by the timeout.
"""

from __future__ import annotations

import logging
import math
import os
import signal
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any, ClassVar

import ray

from usar_arm.core.job_errors import ClusterUnavailableError
from usar_arm.workspace.engine import Job, Result, run_chunk
from usar_arm.workspace.local_head import (
    ANNOUNCE,
    AUTH_VARIABLE,
    LocalHead,
    instance_cpus,
    take_early,
)
from usar_arm.workspace.ray_address import AUTO, LOCAL, host_port, where
from usar_arm.workspace.ray_dispatch import Run, Slot

log = logging.getLogger("usar_arm.workspace")

WAIT_VARIABLE = "RAY_gcs_server_port_wait_time_s"
"""Ray's own setting of how many ~1 s attempts it makes to reach a cluster's GCS (20 by
default): something may accept TCP on an address without being a Ray head (a proxy)."""
LOCAL_OBJECT_STORE = 256 * 2**20
"""Bytes of object store for a local instance (results are small; Ray's default takes 30 % of
the machine's memory)."""
LOCAL_SYSTEM_CONFIG = {"worker_niceness": 0}
"""Ray starts its workers at nice 15; a local instance is this command's own, so its actors
run at the priority of the process pool's workers (on a busy machine nice 15 gives them a
fraction of a core)."""
START_TIMEOUT = 120.0
"""s an actor may take to start (a fresh Python importing usar-arm: about 2 s on 2 cores)."""
CALL_TIMEOUT = 3600.0
"""s a chunk's call may run before it counts as failed (chunks take about 0.1 to 1 s)."""
STOP_TIMEOUT = 30.0
"""s to wait for the shutdown of a local instance before another start (it takes about 1.4 s:
Ray stops its processes one after the other, each given up to 1 s to leave)."""
FREE_WAIT = 3.0
"""s to wait for CPUs held by actors that are being killed before counting the free ones."""


class _ChunkActor:
    """Runs chunks of the job it was given last (its context built on the first chunk)."""

    def __init__(self) -> None:
        self.job: tuple[str, Callable[[], Any], Callable[[Any, Any], Result]] | None = None

    def setup(self, key: str, prepare: Callable[[], Any],
              work: Callable[[Any, Any], Result]) -> int:
        """Take the job; the process id (the actor is ready)."""
        self.job = (key, prepare, work)
        return os.getpid()

    def run(self, chunk: Any) -> Result:
        """One chunk's result."""
        assert self.job is not None, "setup comes first"
        return run_chunk(*self.job, chunk)


def _refuse_if_connected(address: str) -> None:
    """``local`` starts an instance of its own: not in a process joined to another one."""
    if ray.is_initialized():
        current = ray.get_runtime_context().gcs_address
        raise ClusterUnavailableError(
            address, f"this process is already connected to the Ray instance at {current}, "
                     "which local would not start; use --ray auto to run on it, or disconnect "
                     "(ray.shutdown()) first")


def _send_the_token() -> None:
    """Have this process send the token of ``~/.ray`` when it joins the local instance.

    Ray (from 2.5x) turns token authentication on for a fresh local instance, whose start
    wrote the token there, but a process joining by address sends it only in token mode, which
    Ray reads when it is imported: this is what Ray's own ``ray.init`` does for an instance it
    starts in-process (set the mode, re-read the configuration). A mode the user set is left
    alone (the head process got the same); a Ray without token authentication needs nothing.
    """
    if os.environ.get(AUTH_VARIABLE):
        return
    try:
        from ray._private.authentication.authentication_token_setup import _enable_token_auth
    except ImportError:
        return
    _enable_token_auth()


def _token_hint(answered: bool) -> str:
    """What to try when an address whose port answers did not take this process: Ray's own
    message says only that it failed to connect, and a head started with token authentication
    refuses every process that does not send the token (Ray's log lines then say
    "InvalidAuthToken")."""
    if not answered or os.environ.get(AUTH_VARIABLE, "").lower() == "token":
        return ""
    return (f"; if it is a Ray head with token authentication, this process must send the "
            f"token: set {AUTH_VARIABLE}=token, with the cluster's token in RAY_AUTH_TOKEN, "
            f"RAY_AUTH_TOKEN_PATH or ~/.ray/auth_token")


def _stop(disconnect: bool, head: LocalHead | None) -> None:
    """Leave the instance (and, for ``local``, tell its process to stop it: it does so by
    itself, and the next start waits for it, not the end of this process)."""
    if disconnect:
        ray.shutdown()
    if head is not None:
        head.close()


def serve_local(num_cpus: int) -> int:
    """Start a fresh local instance of ``num_cpus`` CPUs, announce its GCS address on standard
    output (:data:`~usar_arm.workspace.local_head.ANNOUNCE`), and stop it when standard input
    closes: the process that owns ``--ray local``'s instance (see :mod:`.local_head`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # (the command stops it: by closing stdin)
    ray.init(address=LOCAL, include_dashboard=False, log_to_driver=False,
             logging_level=logging.WARNING, num_cpus=num_cpus,
             object_store_memory=LOCAL_OBJECT_STORE, _system_config=dict(LOCAL_SYSTEM_CONFIG))
    print(ANNOUNCE + ray.get_runtime_context().gcs_address, flush=True)
    sys.stdin.read()
    ray.shutdown()
    return 0


class RayBackend:
    """Chunks run on a Ray cluster.

    Args:
        address: ``local``, ``auto``, ``HOST:PORT`` or ``ray://HOST:PORT`` (:mod:`.ray_address`).
        workers: actors to start (default: one per free CPU of the cluster; never more).
        timeout: s to wait for the cluster to answer.
        start_timeout: s an actor may take to become ready.
        call_timeout: s a chunk's call may take.
    """

    stopping: ClassVar[threading.Thread | None] = None
    """Leaving the instance, under way in the background (it overlaps what the caller does with
    the results; a later start waits for it, and so does the interpreter at exit). One per
    process, as Ray's connection is."""
    leaving: ClassVar[LocalHead | None] = None
    """The process of the last local instance, stopping it: a later start waits for it (two
    instances would share this machine's CPUs), the end of this process does not (it stops
    its instance by itself)."""

    def __init__(self, address: str = AUTO, workers: int | None = None,
                 timeout: float = 10.0, start_timeout: float = START_TIMEOUT,
                 call_timeout: float = CALL_TIMEOUT):
        host_port(address)  # (a malformed address is refused at once)
        self.address = address
        self.requested = workers
        self.workers = workers or 0
        self.timeout = timeout
        self.start_timeout = start_timeout
        self.call_timeout = call_timeout
        self.start_seconds = 0.0
        self.gcs_address = ""  # (the instance's, once connected)
        self.slots: list[Slot] = []
        self.head: LocalHead | None = None  # (local: the process starting the instance)
        self.chunks_here = 0  # chunks a helper process ran while the actors started
        self._begin = 0.0
        self._owns_ray = False
        self._started = self._counted = False
        self._actor_class: Any = None

    def describe(self) -> str:
        if not self._counted:  # (before it connects, it does not know how many)
            count = f"{self.requested} Ray actors (at most one" if self.requested else \
                "Ray actors (one"
            return f"{count} per free CPU) on {where(self.address)}"
        return (f"{self.workers} Ray actor{'s' if self.workers != 1 else ''} on "
                f"{where(self.address)}")

    # ------------------------------------------------------------------ start and stop
    def start(self) -> bool:
        """Connect (or start a local instance) and create the actors; False when already
        started.

        Raises:
            ClusterUnavailableError: no answer, another instance already connected for
                ``local``, or no free CPU.
        """
        if self._started:
            return False
        self._begin = time.perf_counter()
        if RayBackend.stopping is not None:
            RayBackend.stopping.join(STOP_TIMEOUT)
            RayBackend.stopping = None
        if RayBackend.leaving is not None:
            RayBackend.leaving.wait_stopped()
            RayBackend.leaving = None
        self.chunks_here, self.gcs_address = 0, ""
        if self.address == LOCAL:
            _refuse_if_connected(self.address)
            cpus = instance_cpus(self.requested)
            self.head = take_early(cpus, self.start_timeout) or LocalHead(cpus,
                                                                          self.start_timeout)
            self._started = True
            self.start_seconds = time.perf_counter() - self._begin
            return True  # (joined when the head announces its instance: :meth:`join`)
        self._owns_ray = self._connect()
        self._started = True
        self._make_actors()
        return True

    @property
    def joining(self) -> bool:
        """A local instance is starting, not yet joined."""
        return self.head is not None and not self.gcs_address

    def join(self, wait: float) -> bool:
        """Join the local instance when its process announced it (waiting at most ``wait`` s)
        and create the actors; False while it is still starting.

        Raises:
            ClusterUnavailableError: the instance did not start.
        """
        assert self.head is not None
        address = self.head.poll(wait)
        if address is None:
            return False
        _send_the_token()
        try:
            ray.init(address=address, log_to_driver=False, logging_level=logging.WARNING)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            self.close()
            raise ClusterUnavailableError(
                self.address, f"the local instance at {address} did not answer: "
                              f"{str(exc).splitlines()[0]}") from None
        self._make_actors()
        return True

    def _make_actors(self) -> None:
        try:
            self.gcs_address = ray.get_runtime_context().gcs_address
            self._actor_class = ray.remote(num_cpus=1)(_ChunkActor)
            self.workers, self._counted = self._actor_count(), True
            self.slots = [self._new_slot(k) for k in range(self.workers)]
        except BaseException:
            self.close()
            raise
        self.start_seconds = time.perf_counter() - self._begin

    def close(self) -> None:
        """Kill the actors and leave the instance in the background (:attr:`stopping`, while
        the caller has results to write); a local instance's process is told to stop it, which
        it does by itself (Ray gives each of its processes up to 1 s to leave, one after the
        other): the next start waits for that (:attr:`leaving`), the end of this process
        does not."""
        if ray.is_initialized():
            for slot in self.slots:
                ray.kill(slot.actor)
        self.slots = []
        head, joined = self.head, bool(self.gcs_address) and self.head is not None
        if self._owns_ray or head is not None:
            RayBackend.stopping = threading.Thread(
                target=_stop, args=(self._owns_ray or joined, head), name="ray-shutdown")
            RayBackend.stopping.start()
            RayBackend.leaving = head
        self.head = None
        self._owns_ray = self._started = False

    def _connect(self) -> bool:
        """Connect (or start); True when this backend started the Ray instance."""
        target = host_port(self.address)
        if target is not None:
            try:
                socket.create_connection(target, timeout=self.timeout).close()
            except OSError as exc:
                raise ClusterUnavailableError(
                    self.address, f"no answer from {target[0]}:{target[1]} within "
                                  f"{self.timeout:g} s ({exc.strerror or exc})") from None
        if ray.is_initialized():  # this process already joined a cluster: only that one
            current = ray.get_runtime_context().gcs_address
            if target is not None and current.rpartition(":")[2] != str(target[1]):
                raise ClusterUnavailableError(
                    self.address, f"this process is already connected to the Ray cluster at "
                                  f"{current}")
            return False
        options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                   "logging_level": logging.WARNING}
        wait = WAIT_VARIABLE not in os.environ
        if wait:  # Ray retries its GCS about once a second: bound the retries by the timeout
            os.environ[WAIT_VARIABLE] = str(max(1, math.ceil(self.timeout)))
        try:
            ray.init(address=self.address, **options)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            raise ClusterUnavailableError(
                self.address, f"{str(exc).splitlines()[0]} (waited {self.timeout:g} s)"
                              f"{_token_hint(answered=target is not None)}") from None
        finally:
            if wait:
                del os.environ[WAIT_VARIABLE]
        return True

    def _actor_count(self) -> int:
        """The actors to start: as many as asked for (default: the cluster's CPUs), but no
        more than the CPUs free now."""
        total = float(ray.cluster_resources().get("CPU", 0.0))
        asked = self.requested or int(total)
        deadline = time.monotonic() + FREE_WAIT
        while (free := int(ray.available_resources().get("CPU", 0.0))) < min(asked, total) \
                and time.monotonic() < deadline:
            time.sleep(0.1)  # (the actors of a run that just ended may still be leaving)
        if free < 1:
            raise ClusterUnavailableError(
                self.address, f"no CPU free for an actor (the cluster has {total:g}, all in "
                              "use)")
        if asked > free:
            log.warning("%d Ray actors asked for, but the cluster at %s has %d CPUs free (of "
                        "%g): starting %d", asked, self.address, free, total, free)
        return min(asked, free)

    def _new_slot(self, k: int) -> Slot:
        return Slot(self._actor_class.remote(), f"actor {k + 1} of {self.workers}",
                     time.monotonic())

    # ------------------------------------------------------------------ the run
    def run(self, job: Job, todo: Sequence[int]) -> Iterator[tuple[int, Result]]:
        self.start()
        try:
            yield from Run(self, job, todo).results()
        finally:
            self.close()

    # ------------------------------------------------------------------ for the dispatch
    def replace(self, k: int, job: Job) -> Slot:
        """A fresh actor in place of slot ``k`` (its old one killed), given the job."""
        self.kill(self.slots[k])
        slot = self.slots[k] = self._new_slot(k)
        slot.ready, slot.given = slot.actor.setup.remote(job.key, job.prepare, job.work), True
        return slot

    @staticmethod
    def kill(slot: Slot) -> None:
        """Kill the actor of ``slot``."""
        ray.kill(slot.actor)

    @staticmethod
    def wait_one(refs: list[Any], timeout: float) -> list[Any]:
        """The references of ``refs`` answered within ``timeout`` s (one at most)."""
        ready, _ = ray.wait(refs, num_returns=1, timeout=timeout)
        return list(ready)

    @staticmethod
    def answer(ref: Any, wait: float | None = None) -> tuple[str, Any]:
        """What the call ``ref`` answered: ("ok", its value); ("lost", why) when its actor
        died; ("raised", why) when the call raised; with ``wait`` (s), ("pending", None) when
        it has not answered within that time (without, it has answered already)."""
        try:
            if wait is not None and not ray.wait([ref], timeout=wait)[0]:
                return "pending", None
            return "ok", ray.get(ref)
        except ray.exceptions.RayActorError as exc:
            return "lost", _reason(exc)
        except ray.exceptions.RayError as exc:
            return "raised", _reason(exc)


def _reason(exc: BaseException) -> str:
    """The last line of a Ray error (the worker's exception), at most 300 characters."""
    return str(exc).strip().splitlines()[-1][:300]


if __name__ == "__main__":
    sys.exit(serve_local(int(sys.argv[1])))
