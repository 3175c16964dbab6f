"""The server side of ``usar-arm calibrate --robot`` and of ``usar-arm urdf``'s default
calibration: describe, calibrate on the server through the tip sensor, print before/after."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

from usar_arm.arm.tour_calibration import WireCalibration, calibrate_description
from usar_arm.calibrate.identification import CalibrationOptions
from usar_arm.cli import calibration_text as text
from usar_arm.cli.common import err, out, print_json
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.core.fileio import write_atomic
from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions, Description, write_description


def check_poses(poses: int) -> None:
    """Refuse a tour too short to calibrate before anything is spawned."""
    if poses < 3:
        raise InvalidInputError(f"--poses must be at least 3 (got {poses}): a calibration "
                                "tour needs three poses to identify anything")


def has_tip_sensor(desc: Description) -> bool:
    """Whether the server reported a tip pose sensor for the described arm."""
    return bool(desc.discovery.get("chain", {}).get("tip_sensor"))


def calibrate(desc: Description, options: DescribeOptions, poses: int, scene: str | None,
              seed: int, say: Callable[[str], None] = out, readings: str | None = None,
              calibration: CalibrationOptions | None = None, entry: Path | None = None
              ) -> tuple[Description, WireCalibration]:
    """Calibrate with a progress line on stderr, then ``say`` the before/after figures
    (``readings``: a recorded tour's readings file instead of a tour; ``entry``: the
    description cache's entry to cache the result in, default the spawned arm's)."""
    if readings is None:
        err(f"calibrating {desc.chain.name}: a tour through {poses} poses, reading its tip "
            "sensor...")
    else:
        err(f"calibrating {desc.chain.name} from the tour readings in {readings}...")

    def tick(done: int, total: int) -> None:
        err(f"  poses {done}/{total}")

    calibrated, result = calibrate_description(desc, options, poses, scene, seed, tick,
                                               readings, calibration=calibration, entry=entry)
    fit, val = result.calibration.fit.summary(), result.validation.summary()
    cal = result.calibration
    say(f"calibrated {desc.chain.name} from {result.readings} readings in {result.seconds:.1f} "
        f"s ({cal.quantisation}, {len(cal.rejected)} rejected)")
    say(text.identifiability_line(cal))
    text.warn_lost(cal)
    say(text.residual_line("fitted", fit, " (from each reading's interval middle)"))
    say(text.residual_line("held out", val))
    truth = calibrated.discovery.get("accuracy_vs_simulator")
    before = calibrated.discovery["calibration"].get("as_learnt_accuracy_vs_simulator")
    if truth and before:
        say(f"  against the simulator's own model ({truth['configurations']} configurations): "
            f"flange {text.milli(before['max_flange_error_m'])} -> "
            f"{text.milli(truth['max_flange_error_m'])} "
            f"mm, joint axes {text.milli(before['max_joint_axis_error_rad'])} -> "
            f"{text.milli(truth['max_joint_axis_error_rad'])} mrad")
    say(text.tool_point_line(cal, result.tool_point))
    return calibrated, result


def write_readings(result: WireCalibration, out_dir: str | Path, name: str) -> Path | None:
    """The tour's readings beside the description (``<name>.readings.csv``): what
    ``--readings`` takes to calibrate again without a tour, byte for byte the same."""
    if result.tour is None:
        return None
    return write_atomic(Path(out_dir) / f"{name}.readings.csv", result.tour.csv())


def residual_picture(result: WireCalibration, path: Path) -> Path:
    """The residuals-per-reading picture."""
    from usar_arm.export.residual_plot import plot_residuals

    f, v = result.calibration.fit, result.validation
    return plot_residuals(path, (f.before_m, f.before_rad, f.after_m, f.after_rad),
                          (v.before_m, v.before_rad, v.after_m, v.after_rad),
                          f"calibration of {path.stem.split('.')[0]}: {result.readings} "
                          f"readings, {result.poses} poses")


def calibrate_robot(args: argparse.Namespace) -> int:
    """``calibrate --robot``: describe, calibrate, write the calibrated description and the
    residual picture into --out."""
    check_poses(args.poses)
    options = DescribeOptions(robot=args.robot, host=args.host, port=args.port,
                              start=args.start_position, wire_precision=args.wire_precision,
                              timeout=args.timeout)
    err(f"discovering {options.robot_class}...")
    desc = describe(options)
    calibrated, result = calibrate(desc, options, args.poses, args.scene, args.seed,
                                   err if args.json else out, args.readings,
                                   text.calibration_options(args))
    paths = write_description(calibrated, args.out)
    recorded = write_readings(result, args.out, desc.chain.name)
    if recorded is not None:
        paths["readings"] = recorded
    picture = residual_picture(result, Path(args.out) / f"{desc.chain.name}.calibration.png")
    if args.json:
        print_json({"robot": desc.chain.name, "files": {k: str(p) for k, p in paths.items()},
                    "picture": str(picture), "calibration": calibrated.discovery["calibration"]})
        return EXIT_OK
    for kind, path in paths.items():
        out(f"wrote {path}  ({kind})")
    out(f"wrote {picture}  (residuals per reading)")
    return EXIT_OK
