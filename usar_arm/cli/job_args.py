"""Arguments and helpers shared by the workspace jobs (reach, place, batch): where the chunks
run, resuming, and what a job's JSON record says about the run."""

from __future__ import annotations

import argparse
import platform
from collections.abc import Callable
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, TypeVar

from usar_arm.cli.common import err, verbosity
from usar_arm.cli.progress_bar import ProgressBar
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.fileio import write_tree_atomic
from usar_arm.workspace import jobs
from usar_arm.workspace.engine import Backend, Progress, RunStats

T = TypeVar("T")

VERSIONED = ("usar-arm", "numpy", "numba", "pin", "python-fcl", "ray")


def add_job_args(p: argparse.ArgumentParser) -> None:
    """--out, --workers, --ray, --ray-timeout, --resume."""
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="local worker processes (default: one per core; 0: in this process)")
    p.add_argument("--ray", nargs="?", const="auto", default=None, metavar="ADDRESS",
                   help="run the chunks on a Ray cluster: auto (RAY_ADDRESS, or the cluster "
                        "'ray start' left on this machine; the default without ADDRESS), "
                        "HOST:PORT of a head node, or local (start a fresh Ray here); needs "
                        "pip install 'usar-arm[ray]'")
    p.add_argument("--ray-timeout", type=float, default=10.0, metavar="S",
                   help="seconds to wait for the Ray cluster to answer (default 10)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run from the chunks it kept in DIR/.chunks")


def backend_from_args(args: argparse.Namespace) -> Backend:
    """The backend the arguments name, started: a Ray cluster that does not answer fails
    before anything is planned, and Ray's actors start while the command plans (the job's run
    stops it; Ray's own exit handler, should the command fail before)."""
    if args.workers is not None and args.workers < 0:
        raise InvalidInputError(f"--workers is a number of processes (0 or more), got "
                                f"{args.workers}")
    backend = jobs.backend_for(args.workers, args.ray, args.ray_timeout)
    backend.start()
    return backend


def versions() -> dict[str, str]:
    """Versions of Python and the libraries a job's numbers depend on."""
    out = {"python": platform.python_version()}
    for name in VERSIONED:
        try:
            out[name] = version(name)
        except PackageNotFoundError:
            out[name] = "not installed"
    return out


def run_record(stats: RunStats) -> dict[str, Any]:
    """The timings of a run, for a job's JSON record."""
    rate = stats.units / stats.seconds if stats.seconds > 0 and stats.chunks_resumed == 0 \
        else None
    return {"backend": stats.backend, "workers": stats.workers, "seconds": stats.seconds,
            "backend_start_seconds": stats.start_seconds,
            "units": stats.units, "chunks_run": stats.chunks_run,
            "chunks_resumed": stats.chunks_resumed,
            "chunks_run_by_the_command_while_ray_started": stats.chunks_here,
            "units_per_second": rate,
            "units_per_second_per_worker": rate / stats.workers if rate else None}


def run_with_progress(args: argparse.Namespace, unit: str, work: Callable[[Progress], T]) -> T:
    """``work(progress)`` with a progress bar on stderr (not with -q); on Ctrl-C, say where the
    finished chunks are kept, then let the interruption go on (exit code 130)."""
    bar = ProgressBar(unit, enabled=verbosity(args) >= 0)
    try:
        return work(bar)
    except KeyboardInterrupt:
        bar.close()
        interrupted(args.out)
        raise
    finally:
        bar.close()


def write_outputs(out_dir: str | Path, files: dict[str, str | bytes]) -> list[Path]:
    """Write a job's outputs together (the last one named last), then drop its chunks."""
    written = write_tree_atomic(out_dir, files)
    jobs.finish(out_dir)
    return written


def interrupted(out_dir: str | Path) -> None:
    """Say where the finished chunks of an interrupted job are."""
    folder = Path(out_dir) / jobs.CHUNKS
    kept = len(list(folder.glob("chunk-*.npz"))) if folder.exists() else 0
    err(f"interrupted: {kept} finished chunks kept in {folder}; nothing else was written. "
        "Run the same command with --resume to continue.")
