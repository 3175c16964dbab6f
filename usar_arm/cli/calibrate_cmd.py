"""``usar-arm calibrate``: identify an arm's kinematic parameters from measured tool poses.

FILE mode (``--measurements FILE --urdf X.urdf``): a laser-tracker style file (CSV or YAML, see
usar_arm/calibrate/measurements.py) in base_link; every fifth reading (the 5th, 10th, ...) is held
out for validation and never fitted. The calibrated URDF and <stem>.calibration.json are written
atomically, and only after the fit is consistent and holds on the held-out readings.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from usar_arm.calibrate.identify import CalibrationOptions, identify
from usar_arm.calibrate.measurements import read_measurements
from usar_arm.calibrate.report import calibration_dict, check_validated
from usar_arm.calibrate.validation import split_held_out
from usar_arm.cli.common import add_verbosity, out, print_json, progress, setup_logging, verbosity
from usar_arm.errors import EXIT_OK, FileFormatError, InvalidInputError
from usar_arm.fileio import write_tree_atomic
from usar_arm.model import JointType
from usar_arm.urdf.reader import parse_urdf

HOLD_OUT_EVERY = 5  # every fifth reading is held out for validation
POSES = 14  # poses of the --robot mode's tour (bench/results/calibrate.json: accuracy vs poses)


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser(
        "calibrate", help="identify joint frames, tool and base from measured tool poses",
        description="Kinematic calibration. FILE mode: fit URDF's joint frames, the measured "
                    "frame's offset and the base pose to the poses in FILE (CSV or YAML, units "
                    "stated), validate on every fifth reading (held out), and write the "
                    "calibrated URDF and a calibration.json. Nothing is written unless the fit "
                    "is consistent and holds on the held-out readings.")
    p.add_argument("--measurements", metavar="FILE", help="measured poses (CSV or YAML)")
    p.add_argument("--urdf", metavar="X.urdf", help="the description to calibrate")
    p.add_argument("--frame", help="FILE mode: measured frame (default: the file's)")
    p.add_argument("--out", default="calibrated", metavar="DIR",
                   help="where to write (default ./calibrated)")
    p.add_argument("--quantisation", default="auto",
                   choices=["auto", "midpoint", "set-membership", "likelihood"],
                   help="model of truncated readings (default auto = likelihood)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_robot_mode(p)
    add_verbosity(p)
    p.set_defaults(handler=run)


def add_robot_mode(p: argparse.ArgumentParser) -> None:
    """The ``--robot`` mode's arguments: spawn the robot on a server (the embedded simulator
    unless --host), learn it, tour it through poses reading its tip sensor, fit, validate."""
    p.add_argument("--robot", default=None,
                   help="ROBOT mode: spawn and calibrate this robot class (e.g. KR60) on a "
                        "server through its tip GroundTruth sensor")
    p.add_argument("--host", default=None, help="USARSim server (default: the embedded one)")
    p.add_argument("--port", type=int, default=3000, help="server port (default 3000)")
    p.add_argument("--start-position", default=None, metavar="NAME", help="start pose")
    p.add_argument("--timeout", type=float, default=5.0, metavar="S",
                   help="seconds to wait for each server reply (default 5)")
    p.add_argument("--wire-precision", choices=("udk", "full"), default="udk",
                   help="number format of the embedded simulator (ignored with --host)")
    p.add_argument("--poses", type=int, default=POSES, metavar="N",
                   help=f"poses of the calibration tour (default {POSES})")
    p.add_argument("--scene", default=None,
                   help="scene the tour must avoid (a shipped name or a YAML file)")
    p.add_argument("--seed", type=int, default=0, help="seed of the pose choice (default 0)")
    p.add_argument("--readings", default=None, metavar="FILE",
                   help="calibrate from the readings of an earlier tour (the "
                        "<Robot>.readings.csv every calibration writes) instead of touring: "
                        "the same calibrated description, byte for byte")


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    if getattr(args, "robot", None):
        return run_robot(args)
    if not args.measurements or not args.urdf:
        raise InvalidInputError("calibrate needs --measurements FILE and --urdf X.urdf "
                                "(or --robot ROBOT)")
    return run_file(args)


def run_robot(args: argparse.Namespace) -> int:
    """The ``--robot`` mode: spawn, learn, tour the poses, fit, validate, write."""
    from usar_arm.cli.calibrate_robot import calibrate_robot

    return calibrate_robot(args)


def _milli(x: float) -> str:
    return f"{x * 1e3:.3f}"


def run_file(args: argparse.Namespace) -> int:
    urdf_path = Path(args.urdf)
    try:
        urdf = urdf_path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise FileFormatError(str(urdf_path), f"cannot read: {exc}") from None
    chain, _ = parse_urdf(urdf, str(urdf_path))
    joints = chain.actuated_joints
    data = read_measurements(args.measurements, chain.joint_names,
                             prismatic=[j.type is JointType.PRISMATIC for j in joints],
                             lower=chain.lower(), upper=chain.upper())
    frame = args.frame or data.frame
    readings = list(data.measurements)
    fit, held = split_held_out(readings, HOLD_OUT_EVERY)
    progress(f"fitting {len(fit)} readings of {frame}; {len(held)} held out (every "
             f"{HOLD_OUT_EVERY}th) for validation...")
    cal = identify(urdf, frame, fit, np.eye(4), CalibrationOptions(quantisation=args.quantisation))
    validation = cal.validate(urdf, frame, held)
    check_validated(cal, validation)
    report = calibration_dict(cal, validation, (
        f"file mode: {Path(args.measurements).name}, {len(fit)} readings fitted, {len(held)} "
        f"held out (every {HOLD_OUT_EVERY}th)",
        f"the measured frame {frame} is the tool point the tracker fixes; its offset is "
        "identified from these readings"))
    stem = urdf_path.stem

    paths = write_tree_atomic(args.out, {
        f"{stem}.calibration.json": json.dumps(report, indent=2) + "\n",
        f"{stem}.urdf": cal.apply(urdf)})
    f, v = cal.fit.summary(), validation.summary()
    if args.json:
        print_json({"files": [str(p) for p in paths], "calibration": report})
        return EXIT_OK
    out(f"calibrated {stem} from {len(fit)} readings of {frame} in {cal.seconds:.2f} s "
        f"({cal.quantisation}, rank {cal.rank}, {len(cal.unidentifiable)} unidentifiable, "
        f"{len(cal.rejected)} rejected)")
    out(f"  fit        max {_milli(f['max_before_m'])} -> {_milli(f['max_after_m'])} mm, "
        f"{_milli(f['max_before_rad'])} -> {_milli(f['max_after_rad'])} mrad")
    out(f"  held out   max {_milli(v['max_before_m'])} -> {_milli(v['max_after_m'])} mm, "
        f"{_milli(v['max_before_rad'])} -> {_milli(v['max_after_rad'])} mrad "
        f"({len(held)} readings)")
    for p in paths:
        out(f"  wrote {p}")
    return EXIT_OK
