"""Arguments shared by every command that discovers a robot (urdf, moveit-config, ik, plan...)."""

from __future__ import annotations

import argparse
from dataclasses import replace

from usar_arm.description.cache import robot_from_record
from usar_arm.description.embedded import run_discovery
from usar_arm.description.pipeline import FRAMES, DescribeOptions
from usar_arm.discover.naming import SCHEMES
from usar_arm.planning.robot import Robot, RobotOptions, robot_from_files
from usar_arm.urdf.packages import parse_package_option


def add_server_args(p: argparse.ArgumentParser) -> None:
    """--robot, --host, --port, --start-position, --timeout, --wire-precision."""
    p.add_argument("--robot", default="KR60",
                   help="robot class to spawn, e.g. KR60 or Fanuc_M16iB20 (package USARBot. is "
                        "added when missing; default KR60)")
    p.add_argument("--host", default=None,
                   help="USARSim server host; without it the embedded simulator is started "
                        "in-process on a free loopback port")
    p.add_argument("--port", type=int, default=3000, help="USARSim server port (default 3000)")
    p.add_argument("--start-position", default=None, metavar="NAME",
                   help="start pose (PlayerStart tag) to spawn at; default: the server's first")
    p.add_argument("--timeout", type=float, default=5.0, metavar="S",
                   help="seconds to wait for each server reply (default 5)")
    p.add_argument("--wire-precision", choices=("udk", "full"), default="udk",
                   help="number format of the embedded simulator (ignored with --host)")


def add_description_args(p: argparse.ArgumentParser) -> None:
    """--naming, --frame, --velocity-limits, --acm-samples, --seed."""
    p.add_argument("--naming", choices=SCHEMES, default="ros-i",
                   help="joint/link names: ros-i (joint_a1..), kuka-ros2 (joint_1..), "
                        "legacy-2012 (KR60Arm_joint_1..); default ros-i")
    p.add_argument("--frame", choices=FRAMES, default="z-up",
                   help="z-up: REP-103 (default); z-down: USARSim's frame, as the 2012 node")
    p.add_argument("--velocity-limits", default=None, metavar="FILE",
                   help="YAML file with per-joint velocity/acceleration/jerk limits")
    p.add_argument("--acm-samples", type=int, default=10_000, metavar="N",
                   help="random states for the disabled-collision matrix (default 10000)")
    p.add_argument("--acm-seed", type=int, default=0, metavar="SEED",
                   help="seed of those states (default 0)")


def options_from(args: argparse.Namespace) -> DescribeOptions:
    """DescribeOptions from parsed arguments."""
    return DescribeOptions(
        robot=args.robot, host=args.host, port=args.port, start=args.start_position,
        naming=getattr(args, "naming", "ros-i"), frame=getattr(args, "frame", "z-up"),
        velocity_limits=getattr(args, "velocity_limits", None),
        wire_precision=args.wire_precision,
        acm_samples=getattr(args, "acm_samples", 10_000),
        acm_seed=getattr(args, "acm_seed", 0), timeout=args.timeout)


def add_robot_args(p: argparse.ArgumentParser) -> None:
    """Where the robot description comes from: --urdf/--srdf files, or discovery."""
    add_server_args(p)
    p.add_argument("--urdf", default=None, metavar="FILE",
                   help="use this URDF instead of discovering the robot (its SRDF and "
                        "joint_limits.yaml are read from beside it unless --srdf is given)")
    p.add_argument("--srdf", default=None, metavar="FILE", help="SRDF for --urdf")
    add_file_robot_args(p)
    p.add_argument("--naming", choices=SCHEMES, default="ros-i", help=argparse.SUPPRESS)
    p.add_argument("--frame", choices=FRAMES, default="z-up", help=argparse.SUPPRESS)
    p.set_defaults(robot_usage_error=p.error)


def add_file_robot_args(p: argparse.ArgumentParser) -> None:
    """--group, --base-link, --tip-link, --package-path, --convex-hull (with --urdf)."""
    p.add_argument("--group", default=None, metavar="NAME",
                   help="the SRDF's planning group to plan (default: its first group, or the "
                        "whole URDF when it is one chain)")
    p.add_argument("--base-link", default=None, metavar="LINK",
                   help="plan the chain from this link (with --tip-link; instead of a group)")
    p.add_argument("--tip-link", default=None, metavar="LINK",
                   help="the tool frame that poses refer to (default: the group's tip, tool0 "
                        "when below the last joint, or the last link of the chain)")
    p.add_argument("--package-path", action="append", default=[], metavar="NAME=DIR",
                   help="where package://NAME/ resources are (repeatable; before "
                        "ROS_PACKAGE_PATH, AMENT_PREFIX_PATH and the URDF's own ancestors)")
    p.add_argument("--convex-hull", action="store_true",
                   help="check collisions with the convex hull of each collision mesh "
                        "(conservative for concave meshes: may report contacts in hollows)")


FILE_ONLY = ("group", "base_link", "tip_link", "package_path", "convex_hull")
"""The options that only mean something with --urdf."""


def robot_options(args: argparse.Namespace) -> RobotOptions:
    """How to read --urdf: group, base and tip links, package paths, convex hulls (a bad
    --package-path is a usage error)."""
    try:
        explicit = dict(parse_package_option(t) for t in getattr(args, "package_path", []))
    except ValueError as exc:
        args.robot_usage_error(str(exc))
    return RobotOptions.of(getattr(args, "group", None), getattr(args, "base_link", None),
                           getattr(args, "tip_link", None), explicit,
                           bool(getattr(args, "convex_hull", False)))


def check_file_options(args: argparse.Namespace) -> None:
    """``--srdf``, ``--group``... without ``--urdf`` are usage errors (exit 2): they would be
    ignored."""
    if getattr(args, "urdf", None):
        return
    if getattr(args, "srdf", None):
        args.robot_usage_error("--srdf goes with --urdf (the SRDF of that URDF); a discovered "
                               "robot brings its own SRDF: give --urdf FILE too, or drop --srdf")
    given = [f"--{n.replace('_', '-')}" for n in FILE_ONLY if getattr(args, n, None)]
    if given:
        args.robot_usage_error(f"{', '.join(given)} go with --urdf FILE: a discovered robot "
                               "is planned as learnt")


def robot_from_args(args: argparse.Namespace) -> Robot:
    """The Robot the arguments name: from files, or discovered (embedded or --host) and cached.
    File options without ``--urdf`` are a usage error (exit 2): they would be ignored."""
    check_file_options(args)
    if args.urdf:
        return robot_from_files(args.urdf, args.srdf, options=robot_options(args))
    options = replace(options_from(args), accuracy_samples=0)
    record = run_discovery(options)
    return robot_from_record(record, options)
