"""``usar-arm ros``: the simulated arm as a live ROS 2 robot (docs/ros.md)."""

from __future__ import annotations

import argparse

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, err, out, setup_logging, verbosity
from usar_arm.core.errors import EXIT_OK, InvalidInputError


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "ros",
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
                        "control_msgs) into the cache and exit; needs a C/C++ compiler")
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
    from usar_arm.ros.node import NodeOptions
    from usar_arm.ros.node import run as run_node

    options = NodeOptions(robot_type=args.robot, host=args.host or "", port=args.port,
                          start=args.start_position or "", controller=args.controller or "",
                          use_sim_time=args.use_sim_time, frame_prefix=args.frame_prefix,
                          rate_hz=args.rate, scene=args.scene or "",
                          wire_precision=args.wire_precision)
    code = run_node(options, list(args.ros_args))
    err("usar-arm ros: stopped; the arm held its position")
    return code


ARM_ONLY = (("scene", None), ("controller", None), ("frame_prefix", ""), ("rate", 100.0))
"""Options that mean something for an arm only, with their defaults."""


def _run_platform(args: argparse.Namespace) -> int:
    from usar_arm.ros.platform_node import PlatformNodeOptions

    for name, default in ARM_ONLY:
        if getattr(args, name) != default:
            raise InvalidInputError(f"--{name.replace('_', '-')} is an arm's option; "
                                    f"{args.robot} is a ground vehicle (its options: --frames, "
                                    "--odom-sensor, --cmd-timeout; docs/ros.md section 8)")
    from usar_arm.ros.platform_node import run as run_node

    options = PlatformNodeOptions(
        robot_type=args.robot, host=args.host or "", port=args.port,
        start=args.start_position or "", use_sim_time=args.use_sim_time, frames=args.frames,
        odom_sensor=args.odom_sensor, cmd_timeout=args.cmd_timeout,
        wire_precision=args.wire_precision)
    code = run_node(options, list(args.ros_args))
    err("usar-arm ros: stopped; the vehicle was stopped")
    return code
