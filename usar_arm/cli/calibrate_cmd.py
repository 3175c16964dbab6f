"""``usar-arm calibrate``: identify an arm's kinematic parameters from measured tool poses.

FILE mode (``--measurements FILE --urdf X.urdf``): a laser-tracker style file (CSV or YAML, see
usar_arm/calibrate/measurements.py), in base_link or in the tracker's own frame (registered);
two blocks of consecutive readings (20 %) are held out for validation and never fitted. The
calibrated URDF and <stem>.calibration.json are written atomically, and only after the fit is
consistent, within the plausibility bounds, and holds on the held-out readings.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from usar_arm.calibrate.bounds import Bounds
from usar_arm.calibrate.identification import CalibrationOptions, identify
from usar_arm.calibrate.measurements import MEASURED_IN, MeasurementSet, read_measurements
from usar_arm.calibrate.report import calibration_dict, check_validated
from usar_arm.calibrate.validation import held_out_note, split_held_out
from usar_arm.calibrate.written import check_written, written_check
from usar_arm.cli.calibration_text import (
    BOUND_OPTIONS,
    calibration_options,
    identifiability_line,
    milli,
    residual_line,
    tool_point_line,
    warn_lost,
)
from usar_arm.cli.commands import add_command
from usar_arm.cli.common import (
    add_verbosity,
    out,
    print_json,
    progress,
    setup_logging,
    verbosity,
)
from usar_arm.core.errors import EXIT_OK, FileFormatError, InvalidInputError
from usar_arm.core.fileio import write_tree_atomic
from usar_arm.core.model import JointType
from usar_arm.core.precision import with_precision
from usar_arm.urdf.description_reader import parse_urdf

POSES = 14  # poses of the --robot mode's tour (bench/results/calibrate.json: accuracy vs poses)



def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "calibrate",
        description="Kinematic calibration. FILE mode: fit URDF's joint frames, the measured "
                    "frame's offset and the base pose to the poses in FILE (CSV or YAML, units "
                    "stated), validate on two blocks of consecutive readings (20 %, held out), "
                    "and write the calibrated URDF and a calibration.json. Nothing is written "
                    "unless the readings are plausible for the URDF, the corrections within "
                    "their bounds, the fit consistent and holding on the held-out readings.")
    p.add_argument("--measurements", metavar="FILE", help="measured poses (CSV or YAML)")
    p.add_argument("--urdf", metavar="X.urdf", help="the description to calibrate")
    p.add_argument("--frame", help="FILE mode: measured frame (default: the file's)")
    p.add_argument("--measured-in", choices=MEASURED_IN, default=None,
                   help="FILE mode: the frame the poses are given in: tracker (the "
                        "instrument's own, registered from the readings; the default) or "
                        "base_link (the base correction is then folded into the URDF); "
                        "default: the file's '# measured_in:' line")
    p.add_argument("--out-dir", "--out", dest="out", default="calibrated", metavar="DIR",
                   help="where to write (default ./calibrated; --out is the same)")
    p.add_argument("--quantisation", default="auto",
                   choices=["auto", "midpoint", "set-membership", "likelihood"],
                   help="model of truncated readings (default auto = likelihood)")
    defaults = Bounds()
    for kind, flag, what in BOUND_OPTIONS:
        m, rad = defaults.of(kind)
        p.add_argument(flag, type=float, nargs=2, default=(m, rad), metavar=("M", "RAD"),
                       help=f"{what} (m, rad; default {m:g} {rad:g})")
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
    measured_in = _measured_in(args, data)
    in_base = measured_in == "base_link"
    options = calibration_options(args)
    readings = list(data.measurements)
    fit, held = split_held_out(readings)
    progress(f"fitting {len(fit)} readings of {frame} (measured in {measured_in}); "
             f"{len(held)} held out ({held_out_note()}) for validation...")
    cal = identify(urdf, frame, fit, np.eye(4) if in_base else None, options)
    validation = cal.validate(urdf, frame, held)
    warn_lost(cal)
    check_validated(cal, validation)
    source = (f"the measured frame {frame} is the tool point the tracker fixes; its offset is "
              "identified from these readings")
    written = cal.apply(urdf, fold_base=in_base)
    v = validation.summary()
    check = written_check(written, frame, np.eye(4) if in_base else cal.base, held)
    check_written(check, v["max_after_m"], v["max_after_rad"])
    report = calibration_dict(cal, validation, (
        f"file mode: {Path(args.measurements).name}, {len(fit)} readings fitted, {len(held)} "
        f"held out ({held_out_note()})", _meaning(measured_in)), source)
    report["measured_in"] = measured_in
    report["written_urdf_vs_held_out"] = {"max_m": check.max_m, "max_rad": check.max_rad,
                                          "readings": check.readings}
    stem = urdf_path.stem
    files = {f"{stem}.calibration.json": json.dumps(report, indent=2) + "\n",
             f"{stem}.urdf": written}
    if not in_base:
        files[f"{stem}.registration.json"] = json.dumps(
            {"tracker_from_base_link": with_precision(cal.base.tolist()),
             "meaning": _meaning(measured_in)}, indent=2) + "\n"
    paths = write_tree_atomic(args.out, files)
    f = cal.fit.summary()
    if args.json:
        print_json({"files": [str(p) for p in paths], "calibration": report})
        return EXIT_OK
    out(f"calibrated {stem} from {len(fit)} readings of {frame} in {cal.seconds:.2f} s "
        f"({cal.quantisation}, {len(cal.rejected)} rejected)")
    out(identifiability_line(cal))
    out(residual_line("fit", f))
    out(residual_line("held out", v, f" ({len(held)} readings)"))
    out(tool_point_line(cal, source))
    out(f"  written    {stem}.urdf reproduces the held-out readings within "
        f"{milli(check.max_m)} mm, {milli(check.max_rad)} mrad "
        f"({'in base_link' if in_base else 'through ' + stem + '.registration.json'})")
    out(f"  frame      {_meaning(measured_in)}")
    out(f"  bounds     readings {_bound(options, 'reading')}, joint frames "
        f"{_bound(options, 'joint')}, tool {_bound(options, 'tool')}, base "
        f"{_bound(options, 'base')}")
    for p in paths:
        out(f"  wrote {p}")
    return EXIT_OK


def _measured_in(args: argparse.Namespace, data: MeasurementSet) -> str:
    """The readings' frame: the command line's, else the file's; both stated and different is
    an error (which one is right cannot be guessed)."""
    if args.measured_in and data.measured_in != "tracker" and args.measured_in != \
            data.measured_in:
        raise InvalidInputError(f"--measured-in {args.measured_in}, but {args.measurements} "
                                f"says its readings are measured in {data.measured_in}")
    return str(args.measured_in or data.measured_in)


def _meaning(measured_in: str) -> str:
    """What the written URDF's base_link is, for the output and the report."""
    if measured_in == "base_link":
        return ("the readings are in base_link: the fitted base correction is folded into the "
                "first joint's origin, so the URDF reproduces the readings as they are")
    return ("the readings are in the tracker's own frame: the URDF's base_link is the robot's "
            "own base, and the tracker sees it through tracker_from_base_link "
            "(registration.json), which is not part of the URDF")


def _bound(options: CalibrationOptions, kind: str) -> str:
    m, rad = options.bounds.of(kind)
    return f"{m * 1e3:g} mm / {rad * 1e3:g} mrad"
