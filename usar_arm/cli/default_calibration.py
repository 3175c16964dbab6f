"""Which description a command that discovers an arm writes: calibrated through the arm's tip
sensor by default (``usar-arm urdf``, ``tesseract-config``, ``moveit-config``), as learnt with
``--no-calibrate``, when the arm has no tip sensor, or when its calibration fails.

``urdf`` tours the arm every time (it records the tour's readings beside the description). The
config commands first take the calibrated description the description cache holds for the same
CONF/GEO lines and options (an earlier ``urdf``, ``calibrate``, ``demo`` or config command made
it), so a second call is instant; only without one do they tour (about 35 s for the KR60).
"""

from __future__ import annotations

import argparse
import json
import logging
from collections.abc import Callable
from dataclasses import dataclass, replace

from usar_arm.calibration import WireCalibration
from usar_arm.cli.calibrate_cmd import POSES
from usar_arm.cli.calibrate_robot import calibrate, check_poses, has_tip_sensor
from usar_arm.cli.common import err
from usar_arm.cli.robot_args import options_from
from usar_arm.description import DescribeOptions, Description
from usar_arm.discover.interview import DiscoveryRecord
from usar_arm.embedded import describe_discovered, run_discovery
from usar_arm.errors import CalibrationError, ExecutionAbortedError
from usar_arm.robot import CALIBRATED, Robot, cache_folder, robot_from_texts

log = logging.getLogger(__name__)
Say = Callable[[str], None]


def add_calibration_args(p: argparse.ArgumentParser) -> None:
    """--no-calibrate and --poses."""
    p.add_argument("--no-calibrate", action="store_true",
                   help="write the description as learnt; by default an arm with a tip pose "
                        "sensor is first calibrated through it (a tour of --poses poses)")
    p.add_argument("--poses", type=int, default=POSES, metavar="N",
                   help=f"poses of the calibration tour (default {POSES})")


def skip_reason(desc: Description, options: DescribeOptions, no_calibrate: bool) -> str | None:
    """Why ``desc`` is written as learnt (None: it is to be calibrated)."""
    if no_calibrate:
        return "not calibrating (--no-calibrate): the description is as learnt"
    if not has_tip_sensor(desc):
        return (f"not calibrating: the server reports no tip pose sensor on "
                f"{desc.chain.name}'s arm, so the description is as learnt (calibrate "
                "--measurements FILE fits one to a tracker's readings)")
    if options.frame != "z-up":
        return "not calibrating: calibration works on z-up descriptions (--frame z-up)"
    return None


def by_default(desc: Description, options: DescribeOptions, no_calibrate: bool, poses: int,
               say: Say, readings: str | None = None
               ) -> tuple[Description, WireCalibration | None]:
    """``desc`` calibrated (a tour of ``poses`` poses, or ``readings``) unless
    :func:`skip_reason` gives a reason, said on stderr; a failed calibration without
    ``readings`` leaves it as learnt, also said (with ``readings`` it raises)."""
    reason = skip_reason(desc, options, no_calibrate)
    if reason is not None:
        err(reason)
        return desc, None
    try:
        return calibrate(desc, options, poses, None, 0, say, readings)
    except (CalibrationError, ExecutionAbortedError) as exc:
        if readings is not None:
            raise
        err(f"calibration failed, so the description is as learnt: {exc}")
        return desc, None


def cached_calibration(record: DiscoveryRecord, options: DescribeOptions, desc: Description
                       ) -> Description | None:
    """The calibrated description of ``desc`` the description cache holds (None when it holds
    none, or one built with other options: a different SRDF or joint limits)."""
    folder = cache_folder(record, options) / CALIBRATED
    names = list(desc.files())
    try:
        files = {name: (folder / name).read_text() for name in names}
        discovery = json.loads(files[names[3]])
    except (OSError, ValueError):
        return None
    if files[names[1]] != desc.srdf or files[names[2]] != desc.joint_limits \
            or "calibration" not in discovery:
        log.info("ignoring the cached calibration in %s: made with other options", folder)
        return None
    return replace(desc, urdf=files[names[0]], discovery=discovery)


@dataclass(frozen=True)
class Chosen:
    """The description a config command writes: its files as ``description``, the Robot
    parsed from them (the calibrated chain when calibrated), and which one it is."""

    description: Description
    robot: Robot
    calibrated: bool
    note: str


def config_description(args: argparse.Namespace, say: Say = err) -> Chosen:
    """Discover the arm ``args`` name and choose its description as ``usar-arm urdf`` does by
    default (:func:`by_default`), taking a calibration the description cache holds first."""
    options = options_from(args)
    if not args.no_calibrate:
        check_poses(args.poses)
    where = "the embedded simulator" if options.host is None else f"{args.host}:{args.port}"
    err(f"discovering {options.robot_class} on {where}...")
    record = run_discovery(options)
    desc = describe_discovered(record, options)
    cached = None
    if skip_reason(desc, options, args.no_calibrate) is None:
        cached = cached_calibration(record, options, desc)
    if cached is not None:
        desc, note = cached, "calibrated through its tip sensor (the description cache's)"
        err(f"using the calibration of {desc.chain.name} the description cache holds (an "
            "earlier tour through its tip sensor; --no-calibrate: the description as learnt)")
    else:
        desc, _ = by_default(desc, options, args.no_calibrate, args.poses, say)
        note = ("calibrated through its tip sensor (a new tour)"
                if "calibration" in desc.discovery else "as learnt")
    calibrated = "calibration" in desc.discovery
    robot = robot_from_texts(desc.files(), f"{desc.chain.name}.urdf",
                             f"{note} description of {desc.chain.name}")
    return Chosen(desc, robot, calibrated, note)
