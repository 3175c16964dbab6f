"""The process that owns ``--ray local``'s instance: it announces the instance, stops it when
its input closes (the command is done, or died however it died), and a start that fails is
reported with the process's own error output."""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from usar_arm.core.job_errors import ClusterUnavailableError
from usar_arm.workspace.local_head import LocalHead

pytest.importorskip("ray", reason="the ray extra is not installed (pip install 'usar-arm[ray]')")

REPO = Path(__file__).resolve().parents[2]


def _answers(address: str) -> bool:
    host, _, port = address.rpartition(":")
    try:
        socket.create_connection((host, int(port)), timeout=1.0).close()
    except OSError:
        return False
    return True


def _gone(pid: int, within: float) -> bool:
    deadline = time.monotonic() + within
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        time.sleep(0.1)
    return False


def _session_processes(sid: int) -> list[int]:
    """Processes of session ``sid`` (the head's: Ray's GCS, raylet, agents)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if os.getsid(int(entry.name)) == sid:
                    found.append(int(entry.name))
            except (ProcessLookupError, PermissionError):
                continue
    return found


def test_the_head_announces_its_instance_and_stops_it_when_its_input_closes() -> None:
    head = LocalHead(1, timeout=120.0)
    address = head.poll(wait=120.0)
    assert address is not None and _answers(address)
    assert 0 < head.ready_after < 120.0
    assert len(_session_processes(head.process.pid)) >= 3  # itself, GCS, raylet at least
    head.close()
    head.wait_stopped(60.0)
    assert head.process.returncode == 0
    assert not _answers(address)
    deadline = time.monotonic() + 10.0  # (Ray's processes leave one after the other)
    while _session_processes(head.process.pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert _session_processes(head.process.pid) == []


def test_a_head_that_cannot_start_is_reported_with_its_error_output() -> None:
    head = LocalHead(-1, timeout=60.0)  # (Ray refuses a negative CPU count)
    begin = time.monotonic()
    with pytest.raises(ClusterUnavailableError, match="the process starting Ray ended") as err:
        head.poll(wait=60.0)
    assert "'CPU': -1" in str(err.value)  # Ray's own words: the process's last error line
    assert time.monotonic() - begin < 30.0


DRIVER = """
import sys, time
from usar_arm.workspace.ray_backend import RayBackend
backend = RayBackend("local", 1)
backend.start()
assert backend.join(120.0)
print(backend.head.process.pid, backend.gcs_address, flush=True)
time.sleep(600)
"""


def test_the_instance_stops_when_the_command_is_killed() -> None:
    """SIGKILL leaves no handler to run: the head sees its input close and stops Ray."""
    driver = subprocess.Popen([sys.executable, "-c", DRIVER], cwd=REPO, text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        assert driver.stdout is not None
        pid, address = driver.stdout.readline().split()
        assert _answers(address)
        driver.send_signal(signal.SIGKILL)
        driver.wait(30)
        assert _gone(int(pid), within=30.0), "the head outlived the command"
        assert not _answers(address)
        deadline = time.monotonic() + 10.0
        while _session_processes(int(pid)) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert _session_processes(int(pid)) == []
    finally:
        if driver.poll() is None:
            driver.kill()
