"""Arguments and helpers shared by the workspace jobs (reach, place, batch): where the chunks
run, resuming, and what a job's JSON record says about the run."""

from __future__ import annotations

import argparse
import platform
from collections.abc import Callable
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from usar_arm.cli.common import add_verbosity, err, print_json, verbosity
from usar_arm.cli.progress_bar import ProgressBar
from usar_arm.cli.robot_args import add_robot_args
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.fileio import write_tree_atomic
from usar_arm.workspace import jobs, ray_address
from usar_arm.workspace.engine import Backend, Progress, RunStats

if TYPE_CHECKING:
    from usar_arm.planning.robot import Robot
    from usar_arm.planning.scene import Scene

T = TypeVar("T")

VERSIONED = ("usar-arm", "numpy", "numba", "pin", "python-fcl", "ray")


def add_job_args(p: argparse.ArgumentParser) -> None:
    """--out, --workers, --ray, --ray-timeout, --resume."""
    p.add_argument("--out", required=True, metavar="DIR", help="output folder")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="local worker processes (default: one per core; 0: in this process)")
    p.add_argument("--ray", nargs="?", const=ray_address.AUTO, default=None, metavar="ADDRESS",
                   help=ray_address.HELP)
    p.add_argument("--ray-timeout", type=float, default=10.0, metavar="S",
                   help="seconds to wait for the Ray cluster to answer (default 10)")
    p.add_argument("--resume", action="store_true",
                   help="continue an interrupted run from the chunks it kept in DIR/.chunks")


def add_job_command_args(p: argparse.ArgumentParser,
                         handler: Callable[[argparse.Namespace], int]) -> None:
    """What every job command (reach, place, batch) ends its arguments with: the job's
    (:func:`add_job_args`), the robot's, verbosity, and its ``handler``."""
    add_job_args(p)
    add_robot_args(p)
    add_verbosity(p)
    p.set_defaults(handler=handler)


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


def robot_record(robot: Robot) -> dict[str, Any]:
    """The robot of a job's JSON record: name, source, joints."""
    return {"name": robot.chain.name, "source": robot.source,
            "joints": list(robot.chain.joint_names)}


def scene_record(scene: Scene) -> dict[str, Any]:
    """The scene of a job's JSON record: name and objects."""
    return {"name": scene.name, "objects": [o.name for o in scene.objects]}


def publish(args: argparse.Namespace, files: dict[str, str | bytes],
            record: dict[str, Any]) -> list[Path]:
    """Write a job's outputs (:func:`write_outputs`) into ``--out``; with ``--json``, print
    ``record`` and the files written."""
    written = write_outputs(args.out, files)
    if args.json:
        print_json({**record, "files": [str(p) for p in written]})
    return written


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
