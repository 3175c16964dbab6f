"""A Ray cluster of the benchmark's own (``ray start --head``), stopped without touching any other.

``ray stop`` stops every Ray process on the machine: run beside a test session or another user's
job, it killed their instances (a test worker of a ``make test`` running beside the quick
benchmark died with its instance). This head gets a free port and a temporary folder of its own,
and is stopped by ending the processes whose command line names either, and their descendants.
Commands join it with ``--ray auto`` (the cluster ``ray start`` left on this machine).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

RAY = str(Path(sys.executable).parent / "ray")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _table() -> dict[int, tuple[int, str]]:
    """pid -> (parent pid, command line) of every process this user can read."""
    out: dict[int, tuple[int, str]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            parent = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        out[int(entry.name)] = (parent, cmd)
    return out


def processes_of(marks: list[str]) -> set[int]:
    """The processes whose command line contains one of ``marks``, with their descendants."""
    table = _table()
    found = {pid for pid, (_, cmd) in table.items() if any(m in cmd for m in marks)}
    found.discard(os.getpid())
    grew = True
    while grew:
        more = {pid for pid, (parent, _) in table.items() if parent in found} - found
        found |= more
        grew = bool(more)
    return found


def _end(pids: set[int], wait_s: float = 15.0) -> None:
    """SIGTERM, then SIGKILL whatever is left after ``wait_s``."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        for pid in pids:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, sig)
        end = time.monotonic() + wait_s
        while time.monotonic() < end and any(Path(f"/proc/{p}").exists() for p in pids):
            time.sleep(0.2)


@contextlib.contextmanager
def own_cluster(num_cpus: int) -> Iterator[list[str]]:
    """A head node of ``num_cpus`` CPUs for the ``with`` block -> what marks its processes'
    command lines (its folder, its GCS port); they are ended afterwards, and only they."""
    port = _free_port()
    folder = Path(tempfile.mkdtemp(prefix="uab-ray-"))  # (short: Ray's socket paths)
    marks = [str(folder), f":{port} ", f"port={port} "]
    try:
        subprocess.run([RAY, "start", "--head", "--port", str(port), "--temp-dir", str(folder),
                        "--ray-client-server-port", str(_free_port()),  # (10001 otherwise)
                        "--num-cpus", str(num_cpus), "--include-dashboard=false",
                        "--disable-usage-stats"], capture_output=True, check=True, timeout=300,
                       env={**os.environ, "RAY_worker_niceness": "0"})
        yield marks
    finally:
        _end(processes_of(marks))
        shutil.rmtree(folder, ignore_errors=True)
