"""The Ray execution backend: chunks as calls on Ray actors, on a cluster of any size.

The only module that imports ``ray`` (an optional extra: ``pip install 'usar-arm[ray]'``).
One actor per CPU of the cluster (or ``workers``) builds the job's context once from the job,
which travels by value (URDF, SRDF and scene text: Pinocchio models, FCL geometry and OMPL
spaces do not pickle), then runs one chunk at a time. The driver keeps one call in flight per
actor and collects them with ``ray.wait`` as they finish (never one ``ray.get`` of thousands of
references). A chunk whose actor dies or raises is retried once on a fresh actor; a second
failure stops the run.

Addresses: ``local`` always starts a fresh Ray instance on this machine (and stops it at the
end); ``auto`` joins the cluster ``RAY_ADDRESS`` names, or the one ``ray start`` left on this
machine; ``HOST:PORT`` (a head node's GCS, port 6379 by default) or ``ray://HOST:PORT`` joins
that cluster. An address that does not answer within ``timeout`` seconds is an error saying so:
a refused connection is found before Ray is asked, and Ray's own retries (about one a second,
20 by default) are bounded by the timeout.
"""

from __future__ import annotations

import logging
import math
import os
import socket
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import ray

from usar_arm.errors import ChunkFailedError, ClusterUnavailableError
from usar_arm.workspace.engine import ATTEMPTS, Job, Result, run_chunk

log = logging.getLogger("usar_arm.workspace")

WAIT_VARIABLE = "RAY_gcs_server_port_wait_time_s"
"""Ray's own setting of how many ~1 s attempts it makes to reach a cluster's GCS (20 by
default): something may accept TCP on an address without being a Ray head (a proxy)."""
LOCAL_OBJECT_STORE = 256 * 2**20
"""Bytes of object store for a local instance (results are small; Ray's default takes 30 % of
the machine's memory)."""


class _ChunkActor:
    """Runs chunks of one job (its context built on the first chunk)."""

    def __init__(self, key: str, prepare: Callable[[], Any],
                 work: Callable[[Any, Any], Result]):
        self.key, self.prepare, self.work = key, prepare, work

    def run(self, chunk: Any) -> Result:
        return run_chunk(self.key, self.prepare, self.work, chunk)


def _host_port(address: str) -> tuple[str, int] | None:
    """(host, port) of an address to probe, or None for ``local`` / an undetectable ``auto``."""
    if address == "auto":
        address = os.environ.get("RAY_ADDRESS", "") or "auto"
    if address in ("auto", "local"):
        return None
    bare = address.removeprefix("ray://")
    host, _, port = bare.rpartition(":")
    if not host or not port.isdigit():
        raise ClusterUnavailableError(address, "expected local, auto, HOST:PORT or "
                                               "ray://HOST:PORT")
    return host, int(port)


class RayBackend:
    """Chunks run on a Ray cluster (see the module for ``address``).

    Args:
        address: ``local``, ``auto``, ``HOST:PORT`` or ``ray://HOST:PORT``.
        workers: actors to start (default: the cluster's CPUs).
        timeout: s to wait for the cluster to answer.
    """

    def __init__(self, address: str = "auto", workers: int | None = None,
                 timeout: float = 10.0):
        self.address = address
        self.requested = workers
        self.workers = workers or 0
        self.timeout = timeout

    def describe(self) -> str:
        where = "a local Ray instance" if self.address == "local" else \
            f"the Ray cluster at {self.address}"
        return f"{self.workers} Ray actors on {where}"

    def _connect(self) -> bool:
        """Connect (or start); True when this backend started the Ray instance."""
        target = _host_port(self.address)
        if target is not None:
            try:
                socket.create_connection(target, timeout=self.timeout).close()
            except OSError as exc:
                raise ClusterUnavailableError(
                    self.address, f"no answer from {target[0]}:{target[1]} within "
                                  f"{self.timeout:g} s ({exc.strerror or exc})") from None
        if ray.is_initialized():  # this process already joined a cluster: only that one
            current = ray.get_runtime_context().gcs_address
            if self.address not in ("auto", "local") and target is not None and \
                    current.rpartition(":")[2] != str(target[1]):
                raise ClusterUnavailableError(
                    self.address, f"this process is already connected to the Ray cluster at "
                                  f"{current}")
            return False
        options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                   "logging_level": logging.WARNING}
        if self.address == "local":
            options.update(num_cpus=self.requested or os.cpu_count() or 1,
                           object_store_memory=LOCAL_OBJECT_STORE)
        wait = WAIT_VARIABLE not in os.environ and self.address != "local"
        if wait:  # Ray retries its GCS about once a second: bound the retries by the timeout
            os.environ[WAIT_VARIABLE] = str(max(1, math.ceil(self.timeout)))
        try:
            ray.init(address=self.address, **options)
        except (ConnectionError, RuntimeError, ValueError) as exc:
            raise ClusterUnavailableError(
                self.address, f"{str(exc).splitlines()[0]} (waited {self.timeout:g} s)"
            ) from None
        finally:
            if wait:
                del os.environ[WAIT_VARIABLE]
        return True

    def run(self, job: Job, todo: Sequence[int]) -> Iterator[tuple[int, Result]]:
        started = self._connect()
        actor_class: Any = ray.remote(num_cpus=1)(_ChunkActor)
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.workers = max(1, min(self.requested or cpus, len(todo) or 1))
        queue = deque(todo)
        failures: dict[int, list[str]] = {}
        actors: list[Any] = [actor_class.remote(job.key, job.prepare, job.work)
                  for _ in range(self.workers)]
        flying: dict[Any, tuple[int, int]] = {}  # reference -> (chunk, actor slot)
        try:
            while queue or flying:
                busy = {slot for _, slot in flying.values()}
                for slot in range(len(actors)):
                    if slot not in busy and queue:
                        i = queue.popleft()
                        flying[actors[slot].run.remote(job.chunks[i])] = (i, slot)
                ready, _ = ray.wait(list(flying), num_returns=1)
                for ref in ready:
                    i, slot = flying.pop(ref)
                    try:
                        result: Result = ray.get(ref)
                    except ray.exceptions.RayError as exc:
                        reason = str(exc).strip().splitlines()[-1][:300]
                        failures.setdefault(i, []).append(reason)
                        if len(failures[i]) >= ATTEMPTS:
                            raise ChunkFailedError(i, len(failures[i]), reason) from None
                        queue.appendleft(i)
                        ray.kill(actors[slot])
                        actors[slot] = actor_class.remote(job.key, job.prepare, job.work)
                        continue
                    yield i, result
        finally:
            for actor in actors:
                ray.kill(actor)
            if started:
                ray.shutdown()
