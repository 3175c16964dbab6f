"""``usar-arm ros``: the simulated arm (or a ground vehicle) as a live ROS 2 robot, or with
``--ros1`` a ROS 1 one (docs/ros.md)."""

from __future__ import annotations

import argparse
import os
import sys
import threading
from typing import TYPE_CHECKING, Any

from usar_arm.cli.common import add_verbosity, err, out, setup_logging, verbosity
from usar_arm.core.errors import EXIT_OK, InvalidInputError

if TYPE_CHECKING:
    from usar_arm.ros.node import NodeOptions
    from usar_arm.ros.platform_node import PlatformNodeOptions


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser(
        "ros", help="serve the arm on ROS 2: robot_description, joint_states, tf, "
                    "FollowJointTrajectory (a ground vehicle: cmd_vel, odom, scan)",
        description="Spawn ROBOT (the embedded simulator unless --host), learn it, and serve it "
                    "as a ROS 2 robot until Ctrl-C or SIGTERM (the arm then holds; exit 0): "
                    "robot_description, joint_states (one per ASTA), tf_static/tf, "
                    "<controller>/follow_joint_trajectory and <controller>/joint_trajectory "
                    "with joint_trajectory_controller's semantics, /clock with "
                    "--use-sim-time. Every setting is also a node parameter (--ros-args -p "
                    "robot_type:=KR60 -p host:=... -p port:=...); --ros-args -r __ns:=/name "
                    "moves the node under a namespace. Needs the ros extra and a one-time "
                    "message build: pip install 'usar-arm[ros]' && usar-arm ros --setup.")
    p.add_argument("--setup", action="store_true",
                   help="build the message packages the package index lacks (tf2_msgs, "
                        "control_msgs) into the cache and exit; needs a C/C++ compiler. With "
                        "--ros1: make the ROS 1 environment (a few seconds) and exit")
    p.add_argument("--ros1", action="store_true",
                   help="serve on ROS 1 (Debian's, through roscore) instead: node RosSim, "
                        "the seed's private parameters (~robotType, ~hostname, ~port, "
                        "~startPosition, ~odomSensor), robot_description on the parameter "
                        "server, actionlib; ROS 1 arguments (name:=value, __name:=, _param:=) "
                        "after --ros-args")
    p.add_argument("--robot", default="KR60", help="robot class to spawn (default KR60)")
    p.add_argument("--host", default=None, help="USARSim server host (default: embedded)")
    p.add_argument("--port", type=int, default=3000, help="USARSim server port (default 3000)")
    p.add_argument("--start-position", default=None, metavar="NAME",
                   help="start pose to spawn at (default: the server's first)")
    p.add_argument("--scene", default=None, metavar="SCENE",
                   help="refuse goals whose motion collides in this scene (a shipped name "
                        "such as table, or a YAML file); default: no obstacles checked")
    p.add_argument("--controller", default=None, metavar="NAME",
                   help="trajectory controller name (default <actuator>_controller, the name "
                        "`usar-arm moveit-config` writes into moveit_controllers.yaml)")
    p.add_argument("--use-sim-time", action="store_true",
                   help="publish /clock from the simulator and stamp with it")
    p.add_argument("--frame-prefix", default="", metavar="PREFIX",
                   help="prepend PREFIX to every tf frame (two robots in one tree)")
    p.add_argument("--wire-precision", choices=("udk", "full"), default="udk",
                   help="number format of the embedded simulator: udk (UDK's, default) or "
                        "full (every number exact; ignored with --host)")
    p.add_argument("--rate", type=float, default=100.0, metavar="HZ",
                   help="command rate of the executor (default 100 Hz)")
    v = p.add_argument_group("ground vehicles (--robot P3AT): cmd_vel, odom, scan, "
                             "ground_truth, tf (docs/ros.md, Mobile platform)")
    v.add_argument("--frames", choices=("rep105", "seed"), default="rep105",
                   help="frame names: rep105 (map/odom/base_footprint/base_link, default) or "
                        "seed (the 2012 usar_urdf node's: base_link root, sensors by name)")
    v.add_argument("--odom-sensor", default="", metavar="NAME",
                   help="the sensor odom comes from (default: the first INS)")
    v.add_argument("--cmd-timeout", type=float, default=0.5, metavar="S",
                   help="stop the vehicle when no cmd_vel came for S seconds (default 0.5)")
    add_verbosity(p)
    p.add_argument("--ros-args", nargs=argparse.REMAINDER, default=[], metavar="ARG",
                   help="ROS arguments, last on the line: -p name:=value, -r from:=to, "
                        "-r __ns:=/ns, -r __node:=name")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import logging

    setup_logging(verbosity(args), default=logging.INFO)
    if args.ros1:
        return _run_ros1(args)
    from usar_arm.ros.build import require_ros_extra, setup

    if args.setup:
        require_ros_extra()
        entry = setup()
        out(f"ROS 2 message packages ready in {entry.root}")
        return EXIT_OK
    from usar_arm.ros.build import ensure_importable

    ensure_importable()
    from usar_arm.description.platform import is_ground_vehicle

    if is_ground_vehicle(args.robot, args.host, args.port):
        return _run_platform(args)
    from usar_arm.ros import node, ros2

    code = ros2.run(_arm_options(args, "usar_arm"), list(args.ros_args), None, node.run)
    err("usar-arm ros: stopped; the arm held its position")
    return code


def _arm_options(args: argparse.Namespace, name: str) -> NodeOptions:
    from usar_arm.ros.node import NodeOptions

    return NodeOptions(robot_type=args.robot, host=args.host or "", port=args.port,
                       start=args.start_position or "", controller=args.controller or "",
                       use_sim_time=args.use_sim_time, frame_prefix=args.frame_prefix,
                       rate_hz=args.rate, scene=args.scene or "",
                       wire_precision=args.wire_precision, node_name=name)


def _vehicle_options(args: argparse.Namespace, name: str) -> PlatformNodeOptions:
    from usar_arm.ros.platform_node import PlatformNodeOptions

    return PlatformNodeOptions(
        robot_type=args.robot, host=args.host or "", port=args.port,
        start=args.start_position or "", use_sim_time=args.use_sim_time, frames=args.frames,
        odom_sensor=args.odom_sensor, cmd_timeout=args.cmd_timeout,
        wire_precision=args.wire_precision, node_name=name)


ARM_ONLY = (("scene", None), ("controller", None), ("frame_prefix", ""), ("rate", 100.0))
"""Options that mean something for an arm only, with their defaults."""


def _run_platform(args: argparse.Namespace) -> int:
    _refuse_arm_options(args)
    from usar_arm.ros import platform_node, ros2

    code = ros2.run(_vehicle_options(args, "usar_arm"), list(args.ros_args), None,
                    platform_node.run)
    err("usar-arm ros: stopped; the vehicle was stopped")
    return code


def _refuse_arm_options(args: argparse.Namespace) -> None:
    for name, default in ARM_ONLY:
        if getattr(args, name) != default:
            raise InvalidInputError(f"--{name.replace('_', '-')} is an arm's option; "
                                    f"{args.robot} is a ground vehicle (its options: --frames, "
                                    "--odom-sensor, --cmd-timeout; docs/ros.md section 8)")


FORWARDED = (("robot", "--robot"), ("host", "--host"), ("port", "--port"),
             ("start_position", "--start-position"), ("scene", "--scene"),
             ("controller", "--controller"), ("frame_prefix", "--frame-prefix"),
             ("wire_precision", "--wire-precision"), ("rate", "--rate"), ("frames", "--frames"),
             ("odom_sensor", "--odom-sensor"), ("cmd_timeout", "--cmd-timeout"))
"""The options a ``--ros1`` command line carries into the ROS 1 interpreter."""


def _ros1_argv(args: argparse.Namespace) -> list[str]:
    """``ros --ros1 ...`` with every option given, for the ROS 1 interpreter."""
    out = ["ros", "--ros1"]
    for dest, flag in FORWARDED:
        value = getattr(args, dest)
        if value is not None and value != "":
            out += [flag, str(value)]
    if args.use_sim_time:
        out.append("--use-sim-time")
    out += ["-v"] * int(args.verbose) + (["-q"] if args.quiet else [])
    return out + (["--ros-args", *args.ros_args] if args.ros_args else [])


def _run_ros1(args: argparse.Namespace) -> int:
    """Make (once) the ROS 1 environment and re-execute in its interpreter; there, serve."""
    from usar_arm.ros import ros1_setup

    if not ros1_setup.in_ros1():
        ros1_setup.require_debian()
        env = ros1_setup.existing()
        if env is None:
            err("usar-arm ros --ros1: making the ROS 1 environment (once, a few seconds)")
            env = ros1_setup.setup()
        if args.setup:
            out(f"ROS 1 environment ready in {env.root}; for roslaunch: source "
                f"{env.root / 'setup.bash'}")
            return EXIT_OK
        sys.stdout.flush()
        sys.stderr.flush()
        command = ros1_setup.reexec_argv(_ros1_argv(args), env)
        os.execve(command[0], command, env.environ())
    if args.setup:
        out(f"ROS 1 environment ready ({sys.prefix}): this is its interpreter")
        return EXIT_OK
    from usar_arm.ros import ros1

    code = ros1.run(_arm_options(args, "RosSim"), list(args.ros_args), None,
                    lambda transport, options, stop: _serve_ros1(transport, options, stop, args))
    err("usar-arm ros --ros1: stopped")
    return code


def _serve_ros1(transport: Any, options: NodeOptions, stop: threading.Event,
                args: argparse.Namespace) -> int:
    """Serve an arm or a ground vehicle, as the node's parameters (robotType, hostname, port:
    ROS 1 reads them any time) name it."""
    from usar_arm.description.platform import is_ground_vehicle
    from usar_arm.ros import node, platform_node

    chosen = transport.parameters(options)
    if not is_ground_vehicle(chosen.robot_type, chosen.host or None, chosen.port):
        return node.run(transport, options, stop)
    vehicle = _vehicle_options(args, options.node_name)
    return platform_node.run(transport, vehicle, stop)
