"""``usar-arm execute``: stream a saved trajectory to the arm and report how it went."""

from __future__ import annotations

import argparse

import numpy as np

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, out, print_json, setup_logging, verbosity
from usar_arm.cli.execution_args import (
    add_execution_args,
    check_bag_target,
    execution_options,
    print_report,
    save_bag,
)
from usar_arm.cli.plan_cmd import open_arm
from usar_arm.cli.robot_args import add_server_args
from usar_arm.control.trajectory import Trajectory
from usar_arm.core.errors import EXIT_OK, InvalidInputError


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "execute",
        description="Connect (the embedded simulator unless --host), spawn and learn the robot, "
                    "check the trajectory fits it and starts where the arm is, stream it as ACT "
                    "commands, settle, and report tracking, timing and tool0 errors.")
    p.add_argument("trajectory", metavar="TRAJ.json", help="a trajectory written by plan --out")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="write the trajectory again with the executed ASTA samples (for plot)")
    p.add_argument("--json", action="store_true", help="print one JSON report on stdout")
    add_execution_args(p)
    add_server_args(p)
    add_verbosity(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    traj = Trajectory.load(args.trajectory)
    options = execution_options(args)
    check_bag_target(args.bag)
    args.urdf = None
    with open_arm(args) as arm:
        if traj.joint_names != arm.joint_names:
            raise InvalidInputError(
                f"{args.trajectory}: its joints are {', '.join(traj.joint_names)}, the arm's "
                f"are {', '.join(arm.joint_names)}")
        here = arm.joints()
        gap = np.abs(here - traj.q[0])
        if np.max(gap) > options.start_tolerance:
            j = int(np.argmax(gap))
            raise InvalidInputError(
                f"{args.trajectory} starts {gap[j]:.3f} rad from where {arm.joint_names[j]} is "
                f"now (tolerance {options.start_tolerance}); plan from the arm's current "
                "joints, or move it to the start first")
        report = arm.execute(traj, tip_correction=args.tip_correction, options=options)
        if args.out:
            traj.save(args.out, report.executed)
        topics = save_bag(args.bag, arm, traj, report.executed) if args.bag else None
    if args.json:
        print_json({**report.as_json(), "out": args.out, "bag": args.bag})
    else:
        print_report(report, traj.joint_names)
        for what, path in (("trajectory + executed samples", args.out), ("bag", args.bag)):
            if path:
                out(f"wrote {what}: {path}")
        if topics:
            out("bag topics: " + ", ".join(f"{k} ({v})" for k, v in topics.items()))
    return EXIT_OK
