"""The process that owns ``--ray local``'s Ray instance, seen from the command that started it.

``ray.init`` of a fresh instance takes 2.4 to 3.5 s on two cores (GCS, raylet, API server,
agents and monitors start, and Ray checks once a second whether its raylet has registered). Run
in the command's own process it cannot overlap anything: in a thread it shares the GIL with
whatever the command computes meanwhile (measured 2.4 s alone, 6.0 s beside a busy thread). So
the instance is started by a process of its own (``python -m usar_arm.workspace.ray_backend
N``, which imports nothing of usar-arm's numerics), started at once and left to it while the
command loads its robot, plans the job and runs the first chunks in a helper process; it joins the
instance when the process prints its address, and stops it by closing the process's standard
input (which also happens when the command dies, however it dies). The process runs in a
session of its own, so a Ctrl-C at the terminal reaches the command, which stops it, and not
Ray's processes directly.

This module does not import ``ray``: it starts and watches a process.
"""

from __future__ import annotations

import math
import os
import select
import signal
import subprocess
import sys
import tempfile
import time

from usar_arm.core.job_errors import ClusterUnavailableError
from usar_arm.workspace.ray_address import LOCAL

ANNOUNCE = "usar-arm local ray at "
"""The line (then the GCS address) by which the process says its instance is ready."""
AUTH_VARIABLE = "RAY_AUTH_MODE"
"""Ray's token authentication: a fresh local instance turns it on (with the token it keeps in
``~/.ray/auth_token``), and a process that joins it must send that token, which it does only
when this is ``token``. Set so for both processes unless the user set it."""
STOP_TIMEOUT = 30.0
"""s the process may take to stop its instance (about 1.5 s) before it is killed."""
TAIL = 500
"""Characters of the last line of the process's error output (its exception) quoted when it
fails."""


class LocalHead:
    """A process starting (then holding) a fresh local Ray instance of ``num_cpus`` CPUs.

    Args:
        num_cpus: CPUs of the instance. timeout: s it may take to say it is ready.
    """

    def __init__(self, num_cpus: int, timeout: float):
        self.num_cpus, self.timeout = num_cpus, timeout
        self.began = time.monotonic()
        self.ready_after = 0.0  # s from the start to its announcement
        self.address: str | None = None
        self._buffer = b""
        self._errors = tempfile.TemporaryFile()
        env = dict(os.environ)
        env.setdefault(AUTH_VARIABLE, "token")
        self.process = subprocess.Popen(
            [sys.executable, "-m", "usar_arm.workspace.ray_backend", str(num_cpus)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._errors, env=env,
            start_new_session=True)

    def poll(self, wait: float = 0.0) -> str | None:
        """The instance's GCS address once the process announced it, else None after at most
        ``wait`` seconds.

        Raises:
            ClusterUnavailableError: the process ended, or said nothing within the timeout.
        """
        deadline = time.monotonic() + wait
        while self.address is None:
            stdout = self.process.stdout
            assert stdout is not None
            left = max(0.0, min(deadline, self.began + self.timeout) - time.monotonic())
            readable, _, _ = select.select([stdout], [], [], left)
            if readable:
                chunk = os.read(stdout.fileno(), 4096)
                if not chunk:
                    self.process.wait(STOP_TIMEOUT)
                    raise ClusterUnavailableError(
                        LOCAL, f"the process starting Ray ended (exit code "
                                 f"{self.process.returncode}): {self._tail()}")
                self._buffer += chunk
                for line in self._buffer.decode(errors="replace").splitlines():
                    if line.startswith(ANNOUNCE):
                        self.address = line[len(ANNOUNCE):].strip()
                        self.ready_after = time.monotonic() - self.began
                continue
            if time.monotonic() - self.began >= self.timeout:
                self.close()
                self.wait_stopped()
                raise ClusterUnavailableError(
                    LOCAL, f"Ray did not start within {self.timeout:g} s: {self._tail()}")
            if time.monotonic() >= deadline:
                return None
        return self.address

    def close(self) -> None:
        """Tell the process to stop its instance (its input closes); it does so by itself
        (about 1.5 s), whether or not this process waits for it (:meth:`wait_stopped`)."""
        if self.process.stdin is not None and not self.process.stdin.closed:
            try:
                self.process.stdin.close()
            except OSError:
                pass

    def wait_stopped(self, timeout: float = STOP_TIMEOUT) -> None:
        """Wait for the process to end after :meth:`close` (its session, Ray's processes
        included, killed after ``timeout`` s)."""
        try:
            self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            try:
                os.killpg(self.process.pid, signal.SIGKILL)
            except OSError:
                pass
            self.process.wait(timeout)
        if self.process.stdout is not None:
            self.process.stdout.close()
        self._errors.close()

    def _tail(self) -> str:
        try:
            self._errors.seek(0)
            text = self._errors.read().decode(errors="replace").strip()
        except (OSError, ValueError):
            text = ""
        lines = [line for line in text.splitlines() if line.strip()]
        return lines[-1][-TAIL:] if lines else "(nothing on its error output)"


_EARLY: list[LocalHead] = []
"""The process :func:`start_early` began, until a backend takes it."""


def instance_cpus(workers: int | None) -> int:
    """The CPUs of the instance ``--ray local`` starts for ``--workers`` (None or 0: one per
    core of this machine): one actor each."""
    return workers if workers and workers > 0 else os.cpu_count() or 1


def start_early(num_cpus: int) -> None:
    """Start the instance's process now: the ``usar-arm`` executable does so for ``--ray
    local`` before it loads the rest of itself (about 1.5 s on which a core would otherwise
    idle); the backend's start takes it (:func:`take_early`) and sets its time bound. Not
    taken, it stops its instance when this process ends (its input closes)."""
    _EARLY.append(LocalHead(num_cpus, timeout=math.inf))


def take_early(num_cpus: int, timeout: float) -> LocalHead | None:
    """The process :func:`start_early` began, if it is for ``num_cpus`` CPUs and running
    (bound from now on by ``timeout`` s from its start)."""
    while _EARLY:
        head = _EARLY.pop()
        if head.num_cpus == num_cpus and head.process.poll() is None:
            head.timeout = timeout
            return head
        head.close()
    return None
