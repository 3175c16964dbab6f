"""``usar-arm urdf`` and ``usar-arm moveit-config``: describe a robot learnt over the wire."""

from __future__ import annotations

import argparse
from pathlib import Path

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, err, out, print_json, setup_logging, verbosity
from usar_arm.cli.default_calibration import (
    add_calibration_args,
    config_description,
    describe_calibrated,
)
from usar_arm.cli.out_folder import check_out_folder, other_files, report_other_files
from usar_arm.cli.platform_urdf import run_platform_urdf
from usar_arm.cli.robot_args import add_description_args, add_server_args, options_from
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.core.fileio import write_atomic, write_tree_atomic
from usar_arm.description.pipeline import Description, write_description
from usar_arm.description.platform import is_ground_vehicle
from usar_arm.urdf.moveit import moveit_files, package_name
from usar_arm.urdf.moveit_planning import DEFAULT_DISTRO, ROS_DISTROS


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "urdf",
        description="The successor of the 2012 usar_urdf node: spawn ROBOT on a USARSim server "
                    "(the embedded simulator unless --host), read its actuator's CONF and GEO, "
                    "and write <Robot>.urdf, <Robot>.srdf, <Robot>.joint_limits.yaml and "
                    "<Robot>.discovery.json (the raw lines received and the chain built from "
                    "them). An arm with a tip pose sensor is calibrated first (a tour through "
                    "--poses poses reading it; --no-calibrate skips it). A ground vehicle "
                    "(CONF {Type GroundVehicle}, e.g. P3AT) gets <Robot>.urdf (base_footprint, "
                    "base_link, four wheels, a frame per sensor) and <Robot>.platform.json "
                    "instead. Every file is validated first and written atomically.")
    add_server_args(p)
    add_description_args(p)
    p.add_argument("-o", "--out-dir", default="robots/generated", metavar="DIR",
                   help="where to write (default robots/generated)")
    add_calibration_args(p)
    p.add_argument("--readings", default=None, metavar="FILE",
                   help="calibrate from the readings of an earlier tour (the "
                        "<Robot>.readings.csv a calibration writes beside the description) "
                        "instead of touring: the same calibrated description, byte for byte")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_verbosity(p)
    p.set_defaults(handler=run_urdf)

    m = add_command(
        sub, "moveit-config",
        description="Discover ROBOT as `usar-arm urdf` does and write a MoveIt 2 config package "
                    "(SRDF, kinematics.yaml, joint_limits.yaml with acceleration and jerk, "
                    "pilz_cartesian_limits.yaml, ros2_controllers.yaml, moveit_controllers.yaml, "
                    "ros2_control xacro, initial_positions.yaml, .setup_assistant, package.xml, "
                    "CMakeLists.txt, launch wrappers) into DIR. Build it with colcon and run "
                    "`ros2 launch <robot>_moveit_config demo.launch.py`. The description is "
                    "the one `usar-arm urdf` writes: calibrated through the arm's tip sensor "
                    "(the description cache's calibration when it holds one; --no-calibrate: "
                    "as learnt).")
    add_server_args(m)
    add_description_args(m)
    add_calibration_args(m)
    m.add_argument("--out", required=True, metavar="DIR", help="package folder to write")
    m.add_argument("--ros-distro", choices=ROS_DISTROS, default=DEFAULT_DISTRO,
                   help="ROS 2 distribution the package is for: ompl_planning.yaml's adapter "
                        f"keys differ (default {DEFAULT_DISTRO}, the current LTS)")
    m.add_argument("--gripper", action="store_true",
                   help="also drive the vacuum gripper: a virtual joint <gripper>_suction (0 "
                        "off, 1 on) in the package's xacro and SRDF, and a GripperCommand "
                        "controller on the node's <gripper>/gripper_cmd (run the node with "
                        "`--ros-args -p gripper_joint_states:=true`)")
    m.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_verbosity(m)
    m.set_defaults(handler=run_moveit)


def _joint_rows(desc: Description) -> list[dict[str, object]]:
    rows: list[dict[str, object]] = []
    for jt, src in zip(desc.chain.actuated_joints, desc.limit_sources, strict=True):
        lim = jt.limits
        assert lim is not None
        rows.append({"name": jt.name, "type": jt.type.value, "lower": lim.lower,
                     "upper": lim.upper, "velocity": lim.velocity,
                     "acceleration": lim.acceleration, "jerk": lim.jerk, "effort": lim.effort,
                     "parent": jt.parent, "child": jt.child, "velocity_source": src[0]})
    return rows


def _print_table(desc: Description) -> None:
    out(f"{'joint':<20} {'type':<10} {'lower':>8} {'upper':>8} {'vel':>7} {'acc':>7} "
        f"{'jerk':>7} {'effort':>7}  parent -> child")
    for r in _joint_rows(desc):
        out(f"{r['name']:<20} {r['type']:<10} {r['lower']:>8.4f} {r['upper']:>8.4f} "
            f"{r['velocity']:>7.3f} {r['acceleration']:>7.3f} {r['jerk']:>7.2f} "
            f"{r['effort']:>7.1f}  {r['parent']} -> {r['child']}")


def run_urdf(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    options = options_from(args)
    if is_ground_vehicle(options.robot_class, options.host, options.port, options.timeout):
        return run_platform_urdf(args, options)
    if args.readings is not None and args.no_calibrate:
        raise InvalidInputError("--readings calibrates; it cannot go with --no-calibrate")
    err(f"discovering {options.robot_class} on "
        f"{'the embedded simulator' if options.host is None else f'{args.host}:{args.port}'}...")
    got = describe_calibrated(options, calibrate_arm=not args.no_calibrate, poses=args.poses,
                              readings=args.readings, recalibrate=args.recalibrate,
                              say=err if args.json else out)
    desc = got.description
    paths = write_description(desc, args.out_dir)
    if got.readings_csv is not None:
        paths["readings"] = write_atomic(Path(args.out_dir) / f"{desc.chain.name}.readings.csv",
                                         got.readings_csv)
    if args.json:
        print_json({"robot": desc.chain.name, "files": {k: str(p) for k, p in paths.items()},
                    "joints": _joint_rows(desc), "warnings": list(desc.warnings),
                    "calibrated": "calibration" in desc.discovery,
                    "calibration_source": got.source, "not_calibrated_because": got.why})
        return EXIT_OK
    _print_table(desc)
    for kind, path in paths.items():
        out(f"wrote {path}  ({kind})")
    return EXIT_OK


def run_moveit(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    root = check_out_folder(args.out)
    chosen = config_description(args)
    desc, chain = chosen.description, chosen.robot.chain
    arm_name = desc.discovery["robot"]["actuator"]
    files = moveit_files(chain, desc.urdf, desc.srdf, desc.joint_limits,
                         f"{arm_name}_controller", desc.home, args.ros_distro, args.gripper)
    paths = write_tree_atomic(root, files)
    others = other_files(root, paths)
    if others:
        err(report_other_files(root, others))
    if args.json:
        print_json({"robot": chain.name, "package": package_name(chain.name),
                    "folder": str(root), "files": sorted(str(p) for p in paths),
                    "other_files": others, "calibrated": chosen.calibrated,
                    "ros_distro": args.ros_distro,
                    "description": chosen.note, "warnings": list(desc.warnings)})
        return EXIT_OK
    out(f"wrote MoveIt 2 package {package_name(chain.name)} for ROS 2 {args.ros_distro} "
        f"({len(paths)} files; description {chosen.note}) in {root}")
    for p in sorted(paths):
        out(f"  {p}")
    return EXIT_OK
