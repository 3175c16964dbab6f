"""``usar-arm plan``: plan a PTP or LIN motion (and, with --execute, run it on the arm)."""

from __future__ import annotations

import argparse

import numpy as np

from usar_arm.arm.facade import Arm
from usar_arm.cli.attach_args import add_attach_args, attach_from_args, attach_request
from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, out, print_json, progress, setup_logging, verbosity
from usar_arm.cli.execution_args import (
    add_execution_args,
    check_bag_target,
    execution_options,
    print_report,
    save_bag,
)
from usar_arm.cli.robot_args import (
    add_file_robot_args,
    add_server_args,
    check_file_options,
    robot_options,
)
from usar_arm.cli.units import UNITS, pose_from_args
from usar_arm.control.executor import ExecutionOptions
from usar_arm.control.motion import MotionOptions
from usar_arm.core import inputs
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.planning.lin import LinOptions
from usar_arm.planning.ompl_adapter import CHOICES, COMPILED, OmplOptions


def add_motion_args(p: argparse.ArgumentParser) -> None:
    """The motion options shared by plan and demo."""
    p.add_argument("--scene", default=None, metavar="FILE",
                   help="obstacles: a scene YAML file, or one of empty, table, shelf, cage")
    p.add_argument("--planner", choices=CHOICES, default=COMPILED,
                   help="PTP planner: CompiledRRTConnect (default: compiled, OMPL where it "
                        "finds nothing) or an OMPL geometric planner")
    p.add_argument("--time-limit", type=float, default=2.0, metavar="S",
                   help="planning budget in seconds (default 2)")
    p.add_argument("--resolution", type=float, default=0.01, metavar="RAD",
                   help="largest joint step between collision checks along edges (default 0.01)")
    p.add_argument("--speed-scale", type=float, default=0.5, metavar="F",
                   help="fraction of the velocity/acceleration/jerk limits (default 0.5)")
    p.add_argument("--blend", action="store_true",
                   help="PTP: pass through waypoints without stopping (re-checked; falls back "
                        "to stopping where the blended motion would collide or leave a limit)")
    p.add_argument("--seed", type=int, default=0, help="random seed of the planner (default 0)")


def motion_options(args: argparse.Namespace, motion: str) -> MotionOptions:
    """MotionOptions from the parsed arguments."""
    return MotionOptions(motion=motion, ompl=OmplOptions(
        planner=args.planner, time_limit=args.time_limit, resolution=args.resolution,
        seed=args.seed), lin=LinOptions(resolution=args.resolution),
        speed_scale=args.speed_scale, blend=args.blend)


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "plan",
        description="Plan a PTP motion (joint space, OMPL + Ruckig) or a LIN motion (straight "
                    "tool0 line, IK at every step + a jerk-limited profile) for the arm the "
                    "server describes, from its current joints (read from ASTA) or "
                    "--from-joints. Without --host the embedded simulator is used.")
    goal = p.add_mutually_exclusive_group(required=True)
    goal.add_argument("--pose", type=float, nargs=6, metavar=("X", "Y", "Z", "R", "P", "Y"),
                      help="goal pose of tool0 in base_link, in --units")
    goal.add_argument("--joints", type=float, nargs="+", metavar="Q",
                      help="goal joint values (rad/m)")
    p.add_argument("--units", choices=UNITS, default="m-rad",
                   help="m-rad (default); mm-deg; kuka: X Y Z mm, A B C deg of KUKA's tool "
                        "frame, as on a pendant")
    p.add_argument("--motion", choices=("ptp", "lin"), default="ptp",
                   help="ptp: joint space (default); lin: straight tool0 line")
    p.add_argument("--from-joints", type=float, nargs="+", metavar="Q",
                   help="start here instead of the arm's current joints")
    add_motion_args(p)
    add_attach_args(p)
    p.add_argument("--out", default=None, metavar="FILE", help="write the trajectory (JSON)")
    p.add_argument("--urdf", default=None, metavar="FILE",
                   help="plan for this URDF (SRDF and joint limits beside it) without a server")
    p.add_argument("--srdf", default=None, metavar="FILE", help="SRDF for --urdf")
    add_file_robot_args(p)
    p.add_argument("--json", action="store_true", help="print one JSON summary on stdout")
    p.add_argument("--execute", action="store_true",
                   help="execute the plan on the arm and report how it went")
    add_execution_args(p)
    add_server_args(p)
    add_verbosity(p)
    p.set_defaults(handler=run, robot_usage_error=p.error)


def joint_vector(values: list[float] | None, arm: Arm, what: str) -> np.ndarray | None:
    """A joint vector from the command line, checked against the arm's joint count."""
    if values is None:
        return None
    return inputs.joint_vector(values, arm.joint_names, what, noun="values")


def goal_pose(args: argparse.Namespace, arm: Arm) -> np.ndarray | None:
    """The goal pose of tool0, converted from --units."""
    if args.pose is None:
        return None
    zero = np.zeros(len(arm.joint_names))
    tool0_in_flange = np.linalg.inv(arm.fk(zero, "flange")) @ arm.fk(zero, "tool0")
    return pose_from_args(args.pose, args.units, tool0_in_flange)


def open_arm(args: argparse.Namespace) -> Arm:
    """The arm: offline from --urdf, or live (embedded simulator or --host); ``--srdf``
    without ``--urdf`` is a usage error (exit 2), not ignored."""
    check_file_options(args)
    if getattr(args, "urdf", None):
        o = robot_options(args)
        return Arm.from_files(args.urdf, args.srdf, o.choice.group, o.choice.tip,
                              base=o.choice.base, package_paths=o.read.packages.explicit,
                              convex_hull=o.read.convex_hull)
    where = "the embedded simulator" if args.host is None else f"{args.host}:{args.port}"
    progress(f"connecting to {where} and discovering {args.robot}...")
    return Arm.connect(args.robot, args.host, args.port, args.start_position, args.timeout,
                       wire_precision=args.wire_precision)


def _check_execute_args(args: argparse.Namespace) -> ExecutionOptions | None:
    """The execution options, or None without --execute (where execution flags are errors)."""
    if args.execute:
        if args.urdf:
            raise InvalidInputError("--execute needs a live arm: drop --urdf (the description "
                                    "then comes from the server)")
        if args.from_joints is not None:
            raise InvalidInputError("--execute starts from the arm's current joints: drop "
                                    "--from-joints")
        return execution_options(args)
    if args.tip_correction:
        raise InvalidInputError("--tip-correction needs --execute")
    return None


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    execution = _check_execute_args(args)
    check_bag_target(args.bag)
    attach_request(args)  # (bad --attach options fail before an arm is opened)
    with open_arm(args) as arm:
        start = joint_vector(args.from_joints, arm, "--from-joints")
        carried = attach_from_args(arm, args, start)
        plan = arm.plan(joints=joint_vector(args.joints, arm, "--joints"),
                        pose=goal_pose(args, arm), motion=args.motion, scene=args.scene,
                        start=start, options=motion_options(args, args.motion))
        report = None
        if execution is not None:
            progress(f"executing {plan.trajectory.duration:.2f} s of motion...")
            report = arm.execute(plan.trajectory, goal_pose=plan.goal_pose,
                                 tip_correction=args.tip_correction, options=execution)
        if args.bag:
            save_bag(args.bag, arm, plan.trajectory, report.executed if report else None)
        if args.out:
            plan.trajectory.save(args.out, report.executed if report else None)
    summary = {**plan.summary(), "out": args.out,
               "attached": plan.trajectory.info.get("attached", [])}
    if args.json:
        print_json({**summary, **(report.as_json() if report else {}), "bag": args.bag})
        return EXIT_OK
    out(f"{plan.motion.upper()} plan: {plan.planning_seconds * 1000:.1f} ms planning, "
        f"{plan.trajectory.duration:.2f} s motion, {len(plan.waypoints)} waypoints, "
        f"path {plan.path_length:.3f} rad")
    out("goal: " + " ".join(f"{v:.4f}" for v in plan.goal))
    if carried is not None:
        out(f"carrying: {carried.name} on {carried.link}"
            + (f" (may touch {', '.join(carried.touch_links)})" if carried.touch_links else ""))
    if report is not None:
        print_report(report, plan.trajectory.joint_names)
    for what, path in (("trajectory", args.out), ("bag", args.bag)):
        if path:
            out(f"wrote {what}: {path}")
    return EXIT_OK
