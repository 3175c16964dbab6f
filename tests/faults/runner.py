"""Run ``usar-arm`` commands in child processes, fast: each is forked from a server process that
has already imported usar_arm (multiprocessing's forkserver), so a run costs milliseconds of
start-up instead of seconds of imports, and a hang or crash stays in the child.

Each child runs :func:`usar_arm.cli.main.main` with its stdout and stderr in files and notes
when main() began and ended on the system-wide monotonic clock (comparable with the proxy's).
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

_CONTEXT = multiprocessing.get_context("forkserver")
# usar_arm.cli.main loads a command's module only when it runs it (a fast --help), so the
# commands these tests run are preloaded here: their imports (SciPy, Pinocchio, OMPL...) would
# otherwise count as time between a fault and the exit.
_CONTEXT.set_forkserver_preload(["usar_arm.cli.main", "usar_arm.cli.urdf_cmd",
                                 "usar_arm.cli.plan_cmd", "usar_arm.cli.execute_cmd",
                                 "tests.faults.runner"])


@dataclass(frozen=True)
class Run:
    """How a command ended: exit code, its output, when main() began and ended and when the
    process had exited (time.monotonic s)."""

    argv: tuple[str, ...]
    code: int | None
    stdout: str
    stderr: str
    began: float
    ended: float
    exited: float

    @property
    def seconds(self) -> float:
        """Wall time of main() (s)."""
        return self.ended - self.began


def _child(argv: list[str], folder: str) -> None:
    """In the child: stdout/stderr to files, run main(), note the times, exit with its code."""
    base = Path(folder)
    for fd, name in ((1, "stdout"), (2, "stderr")):
        handle = os.open(base / name, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        os.dup2(handle, fd)
        os.close(handle)
    sys.stdout = open(1, "w", closefd=False)
    sys.stderr = open(2, "w", closefd=False)
    from usar_arm.cli.main import main

    began = time.monotonic()
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    ended = time.monotonic()
    sys.stdout.flush()
    sys.stderr.flush()
    (base / "times").write_text(f"{began} {ended}\n")
    sys.exit(code)


def run_cli(argv: list[str], folder: Path, hard_timeout: float = 60.0) -> Run:
    """Run ``usar-arm ARGV`` in a child; kill it (and fail the test) after ``hard_timeout`` s."""
    folder.mkdir(parents=True, exist_ok=True)
    process = _CONTEXT.Process(target=_child, args=(list(argv), str(folder)), daemon=True)
    started = time.monotonic()
    process.start()
    process.join(hard_timeout)
    exited = time.monotonic()
    if process.is_alive():
        process.kill()
        process.join(5)
        stderr = (folder / "stderr").read_text(errors="replace")
        raise AssertionError(f"usar-arm {' '.join(argv)} hung: killed after {hard_timeout} s; "
                             f"stderr:\n{stderr}")
    times = folder / "times"
    began, ended = (map(float, times.read_text().split()) if times.exists()
                    else (started, time.monotonic()))
    return Run(tuple(argv), process.exitcode, (folder / "stdout").read_text(errors="replace"),
               (folder / "stderr").read_text(errors="replace"), began, ended, exited)
