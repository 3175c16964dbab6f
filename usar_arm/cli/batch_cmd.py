"""``usar-arm batch``: many IK or plan problems from a JSON Lines file, answered in order."""

from __future__ import annotations

import argparse
import json
from collections import Counter
from typing import Any

from usar_arm.cli import job_args as job
from usar_arm.cli.commands import add_command
from usar_arm.cli.common import out, progress, setup_logging, verbosity
from usar_arm.cli.robot_args import robot_from_args
from usar_arm.control.motion import MotionOptions
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.planning.ompl_adapter import OmplOptions
from usar_arm.workspace import batch_job as batch
from usar_arm.workspace.batch_file import read_problems


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "batch",
        description="Read one problem per line (an IK pose, or a plan from joints to joints or "
                    "to a pose, each with an optional scene), solve them in chunks on the "
                    "chosen backend and write DIR/results.jsonl: one JSON object per problem, "
                    "in the input order, with the answer or the failure's type, message and "
                    "exit code; DIR/batch.json summarises the run. The format is in "
                    "docs/workspace.md.")
    p.add_argument("file", metavar="FILE", help="the problems, one JSON object per line")
    p.add_argument("--seed", type=int, default=0, metavar="N",
                   help="seed of every search (IK restarts, OMPL), reseeded per problem "
                        "(default 0)")
    p.add_argument("--time-limit", type=float, default=2.0, metavar="S",
                   help="planning budget per plan problem in seconds (default 2)")
    p.add_argument("--trajectories", action="store_true",
                   help="include each plan's sampled trajectory (t, q) in its result")
    p.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    job.add_job_command_args(p, run)


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    if args.seed < 0:
        raise InvalidInputError(f"--seed must be >= 0, got {args.seed}")
    options = batch.BatchOptions(args.seed, MotionOptions(
        ompl=OmplOptions(time_limit=args.time_limit, seed=args.seed)), args.trajectories)
    problems, bad = read_problems(args.file)
    backend = job.backend_from_args(args)
    robot = robot_from_args(args)
    progress(f"{len(problems)} problems and {len(bad)} invalid lines from {args.file}, on "
             f"{backend.describe()}")
    lines, stats = job.run_with_progress(args, "problems", lambda bar: batch.run_batch(
        robot, problems, bad, options, backend, args.out, args.resume, bar))
    docs = [json.loads(line) for line in lines]
    failures = Counter(d["error"]["type"] for d in docs if not d["ok"])
    summary: dict[str, Any] = {
        "file": args.file, "robot": {"name": robot.chain.name, "source": robot.source},
        "counts": {"results": len(docs), "ok": sum(d["ok"] for d in docs),
                   "failed": sum(not d["ok"] for d in docs), "failures": dict(failures)},
        "settings": {"seed": args.seed, "time_limit_s": args.time_limit,
                     "trajectories": args.trajectories},
        "run": job.run_record(stats), "versions": job.versions(),
    }
    written = job.publish(args, {
        "results.jsonl": "".join(line + "\n" for line in lines),
        "batch.json": json.dumps(summary, indent=2) + "\n"}, summary)
    if args.json:
        return EXIT_OK
    c = summary["counts"]
    kinds = ", ".join(f"{n} {k}" for k, n in failures.most_common()) or "none"
    out(f"{c['ok']} of {c['results']} problems solved ({stats.seconds:.1f} s on "
        f"{stats.backend}); failures: {kinds}")
    for path in written:
        out(f"  {path}")
    return EXIT_OK
