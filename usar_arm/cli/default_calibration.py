"""Which description a command that discovers an arm writes: calibrated through the arm's tip
sensor by default (``usar-arm urdf``, ``tesseract-config``, ``moveit-config``), as learnt with
``--no-calibrate``, when the arm has no tip sensor, or when its calibration fails.

:func:`describe_calibrated` is the one path: discover, then take the calibration the description
cache holds for this arm (its CONF/GEO lines and the description options) made with the same
settings, unless ``--recalibrate``; else tour the arm (about 35 s for the KR60; the result is
cached for the next time), or fit a recorded tour's readings. Every fallback to the as-learnt
description is said on stderr, with its reason.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from dataclasses import dataclass, replace

from usar_arm.arm.tour_calibration import CalibrationSettings, cached_calibration
from usar_arm.cli.calibrate_cmd import POSES
from usar_arm.cli.calibrate_robot import calibrate, check_poses, has_tip_sensor
from usar_arm.cli.common import err, out
from usar_arm.cli.robot_args import options_from
from usar_arm.core.errors import CalibrationError, ExecutionAbortedError
from usar_arm.description.cache import cache_folder
from usar_arm.description.embedded import describe_discovered, run_discovery
from usar_arm.description.pipeline import DescribeOptions, Description
from usar_arm.planning.robot import Robot, robot_from_texts

Say = Callable[[str], None]


def add_calibration_args(p: argparse.ArgumentParser) -> None:
    """--no-calibrate, --poses and --recalibrate."""
    p.add_argument("--no-calibrate", action="store_true",
                   help="write the description as learnt; by default an arm with a tip pose "
                        "sensor is first calibrated through it (a tour of --poses poses)")
    p.add_argument("--poses", type=int, default=POSES, metavar="N",
                   help=f"poses of the calibration tour (default {POSES})")
    p.add_argument("--recalibrate", action="store_true",
                   help="tour again even when the description cache holds this arm's "
                        "calibration with the same settings")


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


def _skip_reason(desc: Description, options: DescribeOptions, calibrate_arm: bool) -> str:
    """Why ``desc`` is written as learnt ("": it is to be calibrated)."""
    if not calibrate_arm:
        return "not calibrating (--no-calibrate): the description is as learnt"
    if not has_tip_sensor(desc):
        return (f"not calibrating: the server reports no tip pose sensor on {desc.chain.name}'s "
                "arm, so the description is as learnt (calibrate --measurements FILE fits one "
                "to a tracker's readings)")
    if options.frame != "z-up":
        return "not calibrating: calibration works on z-up descriptions (--frame z-up)"
    return ""


def describe_calibrated(options: DescribeOptions, *, calibrate_arm: bool = True,
                        poses: int = POSES, readings: str | None = None,
                        recalibrate: bool = False, say: Say = out) -> Described:
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
    why = _skip_reason(desc, options, calibrate_arm)
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


@dataclass(frozen=True)
class Chosen:
    """The description a config command writes: its files as ``description``, the Robot
    parsed from them (the calibrated chain when calibrated), and which one it is."""

    description: Description
    robot: Robot
    calibrated: bool
    note: str


NOTES = {"cache": "calibrated through its tip sensor (the description cache's)",
         "tour": "calibrated through its tip sensor (a new tour)", None: "as learnt"}


def config_description(args: argparse.Namespace, say: Say = err) -> Chosen:
    """Discover the arm ``args`` name and choose its description as ``usar-arm urdf`` does by
    default (:func:`describe_calibrated`)."""
    options = options_from(args)
    where = "the embedded simulator" if options.host is None else f"{args.host}:{args.port}"
    err(f"discovering {options.robot_class} on {where}...")
    got = describe_calibrated(options, calibrate_arm=not args.no_calibrate, poses=args.poses,
                              recalibrate=args.recalibrate, say=say)
    desc, note = got.description, NOTES.get(got.source, "calibrated")
    robot = robot_from_texts(desc.files(), f"{desc.chain.name}.urdf",
                             f"{note} description of {desc.chain.name}")
    return Chosen(desc, robot, "calibration" in desc.discovery, note)
