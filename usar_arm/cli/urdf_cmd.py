"""``usar-arm urdf`` and ``usar-arm moveit-config``: describe a robot learnt over the wire.

:func:`describe_calibrated` is the calibrating description every describing command can share:
discover, then calibrate through the tip sensor (from the description cache when the same arm
was calibrated with the same settings before), falling back to the as-learnt description with
the reason said.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from usar_arm.calibration import CalibrationSettings, cached_calibration
from usar_arm.cli.calibrate_cmd import POSES
from usar_arm.cli.calibrate_robot import calibrate, check_poses, has_tip_sensor
from usar_arm.cli.common import add_verbosity, err, out, print_json, setup_logging, verbosity
from usar_arm.cli.robot_args import add_description_args, add_server_args, options_from
from usar_arm.description import DescribeOptions, Description, write_description
from usar_arm.embedded import describe, describe_discovered, run_discovery
from usar_arm.errors import EXIT_OK, CalibrationError, ExecutionAbortedError, InvalidInputError
from usar_arm.fileio import write_atomic, write_tree_atomic
from usar_arm.robot import cache_folder
from usar_arm.urdf.moveit import moveit_files, package_name


@dataclass(frozen=True)
class Described:
    """What :func:`describe_calibrated` gives: the description to write (calibrated or as
    learnt), the tour's readings file text to write beside it (None when not calibrated from
    a tour), and where the calibration came from: ``tour``, ``cache``, ``readings`` or None
    (as learnt; ``why`` says why)."""

    description: Description
    readings_csv: str | None
    source: str | None
    why: str = ""


def describe_calibrated(options: DescribeOptions, *, calibrate_arm: bool = True,
                        poses: int = POSES, readings: str | None = None,
                        recalibrate: bool = False, say: Callable[[str], None] = out
                        ) -> Described:
    """Discover the arm ``options`` name and describe it calibrated through its tip sensor:
    from the description cache when this arm (its CONF/GEO lines and the description options)
    was calibrated with the same settings before, unless ``recalibrate``; else by a tour of
    ``poses`` poses (cached for the next time), or from a tour's ``readings`` file. An arm
    without a tip sensor, ``calibrate_arm`` False, or a failed tour (inconsistent readings, an
    aborted motion) give the as-learnt description and the reason (on stderr and in ``why``).
    Progress goes to stderr, the calibration's figures to ``say``."""
    if calibrate_arm:
        check_poses(poses)
    record = run_discovery(options)
    desc = describe_discovered(record, options)
    why = ""
    if not calibrate_arm:
        why = "not calibrating (--no-calibrate): the description is as learnt"
    elif not has_tip_sensor(desc):
        why = (f"not calibrating: the server reports no tip pose sensor on {desc.chain.name}'s "
               "arm, so the description is as learnt (calibrate --measurements FILE fits one "
               "to a tracker's readings)")
    elif options.frame != "z-up":
        why = "not calibrating: calibration works on z-up descriptions (--frame z-up)"
    if why:
        err(why)
        return Described(desc, None, None, why)
    entry = cache_folder(record, options)
    settings = CalibrationSettings(poses)
    hit = None if readings is not None or recalibrate else \
        cached_calibration(entry, desc.chain.name, settings)
    if hit is not None:
        name = desc.chain.name
        say(f"calibrated description from the cache, made {hit.made} from {hit.readings} "
            "readings; --recalibrate to tour again")
        cached = replace(desc, urdf=hit.files[f"{name}.urdf"],
                         discovery=json.loads(hit.files[f"{name}.discovery.json"]))
        return Described(cached, hit.files.get(f"{name}.readings.csv"), "cache")
    try:
        calibrated, result = calibrate(desc, options, poses, None, 0, say, readings,
                                       settings.options, entry)
    except (CalibrationError, ExecutionAbortedError) as exc:
        if readings is not None:
            raise
        why = f"calibration failed, so the description is as learnt: {exc}"
        err(why)
        return Described(desc, None, None, why)
    csv = result.tour.csv() if result.tour is not None else None
    return Described(calibrated, csv, "readings" if readings is not None else "tour")


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser(
        "urdf", help="spawn a robot, learn its arm over the wire, write URDF/SRDF/limits",
        description="The successor of the 2012 usar_urdf node: spawn ROBOT on a USARSim server "
                    "(the embedded simulator unless --host), read its actuator's CONF and GEO, "
                    "and write <Robot>.urdf, <Robot>.srdf, <Robot>.joint_limits.yaml and "
                    "<Robot>.discovery.json (the raw lines received and the chain built from "
                    "them). An arm with a tip pose sensor is calibrated first (a tour through "
                    "--poses poses reading it; --no-calibrate skips it). Every file is "
                    "validated first and written atomically.")
    add_server_args(p)
    add_description_args(p)
    p.add_argument("--out-dir", default="robots/generated", metavar="DIR",
                   help="where to write (default robots/generated)")
    p.add_argument("--no-calibrate", action="store_true",
                   help="write the description as learnt; by default an arm with a tip pose "
                        "sensor is first calibrated through it (a tour of --poses poses)")
    p.add_argument("--poses", type=int, default=POSES, metavar="N",
                   help=f"poses of the calibration tour (default {POSES})")
    p.add_argument("--readings", default=None, metavar="FILE",
                   help="calibrate from the readings of an earlier tour (the "
                        "<Robot>.readings.csv a calibration writes beside the description) "
                        "instead of touring: the same calibrated description, byte for byte")
    p.add_argument("--recalibrate", action="store_true",
                   help="tour again even when the description cache holds this arm's "
                        "calibration with the same settings")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_verbosity(p)
    p.set_defaults(handler=run_urdf)

    m = sub.add_parser(
        "moveit-config", help="write a complete MoveIt 2 config package for a robot",
        description="Discover ROBOT as `usar-arm urdf` does and write a MoveIt 2 config package "
                    "(SRDF, kinematics.yaml, joint_limits.yaml with acceleration and jerk, "
                    "pilz_cartesian_limits.yaml, ros2_controllers.yaml, moveit_controllers.yaml, "
                    "ros2_control xacro, initial_positions.yaml, .setup_assistant, package.xml, "
                    "CMakeLists.txt, launch wrappers) into DIR. Build it with colcon and run "
                    "`ros2 launch <robot>_moveit_config demo.launch.py`.")
    add_server_args(m)
    add_description_args(m)
    m.add_argument("--out", required=True, metavar="DIR", help="package folder to write")
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
    desc = describe(options_from(args))
    arm_name = desc.discovery["robot"]["actuator"]
    files = moveit_files(desc.chain, desc.urdf, desc.srdf, desc.joint_limits,
                         f"{arm_name}_controller", desc.home)
    root = Path(args.out)
    paths = write_tree_atomic(root, files)
    if args.json:
        print_json({"robot": desc.chain.name, "package": package_name(desc.chain.name),
                    "folder": str(root), "files": sorted(str(p) for p in paths),
                    "warnings": list(desc.warnings)})
        return EXIT_OK
    out(f"wrote MoveIt 2 package {package_name(desc.chain.name)} ({len(paths)} files) in {root}")
    for p in sorted(paths):
        out(f"  {p}")
    return EXIT_OK
