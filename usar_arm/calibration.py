"""Calibrating a live arm: a tour reading the arm's tip GroundTruth sensor
(:mod:`usar_arm.calibration_tour`), the fit, validation on held-out readings, and the calibrated
description. The fit depends on the as-learnt description and the tour's readings alone
(:class:`~usar_arm.calibrate.tour_readings.TourReadings`), so a description calibrated from a
readings file is the same byte for byte as the one calibrated on the tour that recorded them.

The readings are the sensor's world pose as the server prints it (USARSim world, z down), so the
fit runs in that frame: the measured frame is the sensor's frame with USARSim's axes (the URDF's
sensor frame turned by pi about x), and the base guess is the platform's GroundTruth pose with
the same turn. The calibrated URDF gets the sensor frame back in REP-103 axes. When the sensor
sits at the arm's Tip (the model puts them no farther apart than the Tip's printed step), the
flange and tool0 move onto the calibrated sensor point: the Tip is identified through the
sensor. Otherwise the printed Tip offset stays the only source of the tool point, and the
report says so.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from usar_arm.arm import Arm
from usar_arm.calibrate.identify import Calibration, CalibrationOptions, identify
from usar_arm.calibrate.parameters import replace_origin
from usar_arm.calibrate.report import calibration_dict, check_validated
from usar_arm.calibrate.residuals import Residuals
from usar_arm.calibrate.tour_readings import TourReadings, read_tour
from usar_arm.calibrate.validation import split_held_out
from usar_arm.calibration_tour import Progress, choose_configurations, collect
from usar_arm.description import DescribeOptions, Description, write_description
from usar_arm.errors import CalibrationError, InvalidInputError
from usar_arm.model import JointType
from usar_arm.robot import CALIBRATED
from usar_arm.spatial import FLIP_X, Array, transform
from usar_arm.urdf.reader import parse_urdf

log = logging.getLogger(__name__)
FLIP = transform(FLIP_X)
HOLD_OUT_EVERY = 5
"""Every fifth reading is held out for validation and never fitted."""



@dataclass(frozen=True)
class WireCalibration:
    """A calibration made on the wire: the fit, its validation on held-out readings, the
    calibrated URDF text, what fixes the tool point, and the tour's readings (``seconds``:
    how long the tour took)."""

    calibration: Calibration
    validation: Residuals
    urdf: str
    poses: int
    readings: int
    seconds: float
    tool_point: str
    tip_joint: str | None
    tour: TourReadings | None = None


def _usarsim_axes(urdf: str, joint: str, turn: Array) -> str:
    """``urdf`` with the fixed joint ``joint``'s origin turned by ``turn`` (4x4, right)."""
    chain, _ = parse_urdf(urdf)
    j = chain.joint(joint)
    return replace_origin(urdf, j, j.origin.matrix() @ turn)


def _fold_base(urdf: str, correction: Array) -> str:
    """``urdf`` with the fitted base correction (4x4, base_link before -> after) moved into
    the first joint's origin. base_link is where the platform's GroundTruth puts the arm; the
    fit finds where the chain really starts in the world, which the first joint's frame cannot
    tell apart from the base (its origin parameters are unidentifiable beside the base's)."""
    chain, _ = parse_urdf(urdf)
    first = next(j for j in chain.joints if j.actuated)
    if first.parent != chain.root:
        raise CalibrationError(f"the first joint '{first.name}' does not hang from the root "
                               f"'{chain.root}': cannot move the base correction into it")
    return replace_origin(urdf, first, correction @ first.origin.matrix())


def _tip_onto_sensor(calibrated: str, learnt: str, tip_joint: str, mount_joint: str) -> str:
    """``calibrated`` with the Tip joint (which carries the flange and tool0) moved onto the
    calibrated sensor frame: its position, and its rotation turned as the sensor's was (the
    sensor sits at the Tip, so the fit's turn of the sensor frame is the Tip's)."""
    after, _ = parse_urdf(calibrated)
    before, _ = parse_urdf(learnt)
    mount_after = after.joint(mount_joint).origin.matrix()
    mount_before = before.joint(mount_joint).origin.matrix()
    tip = before.joint(tip_joint)
    pose = mount_after @ np.linalg.inv(mount_before) @ tip.origin.matrix()
    pose[:3, 3] = mount_after[:3, 3]
    return replace_origin(calibrated, after.joint(tip_joint), pose)


def _mount_joint(urdf: str, frame: str) -> str:
    chain, _ = parse_urdf(urdf)
    for j in chain.joints:
        if j.child == frame and not j.actuated:
            return j.name
    raise CalibrationError(f"the measured frame '{frame}' hangs from no fixed joint in the URDF")


def _tip_joint(urdf: str, frame: str, tip_step: float) -> tuple[str | None, str]:
    """The fixed joint that carries the flange when the sensor sits at the Tip, and a sentence
    saying what fixes the tool point."""
    chain, _ = parse_urdf(urdf)
    zero = np.zeros(chain.dof)
    gap = float(np.linalg.norm(chain.frame_pose("flange", zero)[:3, 3]
                               - chain.frame_pose(frame, zero)[:3, 3]))
    sensor_parent = next(j.parent for j in chain.joints if j.child == frame)
    flange = next((j for j in chain.joints if j.child == "flange"), None)
    if flange is not None and flange.parent == sensor_parent and tip_step > 0 \
            and gap <= tip_step:
        return flange.name, (
            f"the tip sensor {frame} sits at the Tip (the printed Tip, {tip_step * 1e3:.0f} mm "
            f"steps, is {gap * 1e3:.1f} mm from it): the flange and tool0 are put on the "
            "calibrated sensor point, so the Tip is identified through the sensor")
    return None, (
        f"the tip sensor {frame} is {gap * 1e3:.1f} mm from the printed Tip: the sensor-to-Tip "
        "offset is not observable from its readings, so the printed Tip offset (step "
        f"{tip_step * 1e3:.0f} mm) stays the only source of the tool point")


def fit_tour(urdf: str, tour: TourReadings, tip_step: float,
             options: CalibrationOptions | None = None) -> WireCalibration:
    """Fit ``urdf`` (as learnt) to a tour's readings, validate on the held-out ones and build
    the calibrated URDF (see the module; ``tip_step``: the Tip's printed step, m). Raises
    :class:`~usar_arm.errors.CalibrationError` when the readings are inconsistent or the fit
    does not hold on the held-out readings."""
    frame = tour.sensor
    mount = _mount_joint(urdf, frame)
    fit_urdf = _usarsim_axes(urdf, mount, FLIP)
    tip_joint, tool_point = _tip_joint(urdf, frame, tip_step)
    fit, held = split_held_out(list(tour.measurements), HOLD_OUT_EVERY)
    base_guess = tour.platform_pose() @ FLIP
    cal = identify(fit_urdf, frame, fit, base_guess, options or CalibrationOptions())
    validation = cal.validate(fit_urdf, frame, held)
    check_validated(cal, validation)
    calibrated = _usarsim_axes(cal.apply(fit_urdf), mount, FLIP)
    if tip_joint is not None:
        calibrated = _tip_onto_sensor(calibrated, urdf, tip_joint, mount)
    calibrated = _fold_base(calibrated, np.linalg.inv(base_guess) @ cal.base)
    return WireCalibration(cal, validation, calibrated, tour.poses, len(tour.measurements),
                           tour.seconds, tool_point, tip_joint, tour)


def calibrate_arm(arm: Arm, poses: int = 14, scene: str | None = None,
                  seed: int = 0, progress: Progress | None = None,
                  options: CalibrationOptions | None = None) -> WireCalibration:
    """Calibrate ``arm`` on its server: tour it, then :func:`fit_tour`. Raises
    :class:`~usar_arm.errors.CalibrationError` when the readings are inconsistent or the fit
    does not hold on the held-out readings; nothing is changed then."""
    sensor = arm.tip_sensor()
    if sensor is None:
        raise InvalidInputError(
            f"{arm.robot.chain.name} has no tip GroundTruth sensor on this server, so it "
            "cannot be calibrated from the wire (calibrate --measurements FILE takes a "
            "tracker's readings instead)")
    if poses < 3:
        raise InvalidInputError(f"calibration needs at least 3 poses (got {poses})")
    start = time.monotonic()
    chain = arm.robot.chain
    _mount_joint(arm.urdf, str(arm.robot.tip_sensor))  # a sensor the fit can use, first
    configurations = choose_configurations(arm, poses, scene, seed)
    sensor.read()  # the platform's pose, for the base guess
    readings = collect(arm, configurations, scene, progress)
    tour = TourReadings(tuple(readings), str(arm.robot.tip_sensor), chain.joint_names,
                        TourReadings.platform_numbers(sensor.platform_pose()),
                        len(configurations), round(time.monotonic() - start, 1),
                        tuple(j.type is JointType.PRISMATIC for j in chain.actuated_joints))
    return fit_tour(arm.urdf, tour, arm.tip_step(), options)


def calibrate_description(desc: Description, options: DescribeOptions, poses: int = 14,
                          scene: str | None = None, seed: int = 0,
                          progress: Progress | None = None, readings: str | Path | None = None
                          ) -> tuple[Description, WireCalibration]:
    """Spawn the arm ``desc`` describes again (same server and options), calibrate it, and
    return the calibrated description (its URDF, and discovery.json with a ``calibration``
    section; on the embedded simulator also the calibrated description's accuracy against the
    simulator's own model) and the calibration. The calibrated description is cached beside
    the as-learnt one, so that the next plan or demo of this arm uses it. With ``readings``
    (a tour's readings file) nothing is spawned: the fit uses those readings."""
    if options.frame != "z-up":
        raise InvalidInputError("calibration works on REP-103 (z-up) descriptions; describe "
                                f"with --frame z-up (got {options.frame})")
    entry = None
    if readings is not None:
        chain = desc.chain
        tour = read_tour(readings, chain.joint_names,
                         [j.type is JointType.PRISMATIC for j in chain.actuated_joints],
                         chain.lower(), chain.upper())
        tip_step = float(desc.discovery.get("precision", {}).get("tip_resolution_m") or 0.0)
        result = fit_tour(desc.urdf, tour, tip_step)
    else:
        with Arm.connect(robot=options.robot, host=options.host, port=options.port,
                         start=options.start, timeout=options.timeout, naming=options.naming,
                         wire_precision=options.wire_precision,
                         velocity_limits=options.velocity_limits, calibrated=False) as arm:
            if arm.urdf != desc.urdf:
                raise CalibrationError("the arm spawned for calibration is described "
                                       "differently from the description to calibrate (did "
                                       "the server change?)")
            result = calibrate_arm(arm, poses, scene, seed, progress)
            entry = arm.cache_entry
    notes = (f"{result.readings} tip-sensor readings on a tour through {result.poses} poses "
             f"({result.seconds:.0f} s; {desc.chain.name}.readings.csv); every "
             f"{HOLD_OUT_EVERY}th reading held out", result.tool_point)
    discovery = {**desc.discovery,
                 "calibration": calibration_dict(result.calibration, result.validation, notes)}
    if "accuracy_vs_simulator" in desc.discovery and options.host is None:
        from usar_arm.embedded import urdf_accuracy

        discovery["calibration"]["as_learnt_accuracy_vs_simulator"] = \
            desc.discovery["accuracy_vs_simulator"]
        discovery["accuracy_vs_simulator"] = urdf_accuracy(result.urdf, options)
    calibrated = replace(desc, urdf=result.urdf, discovery=discovery)
    if entry is not None:
        try:
            write_description(calibrated, entry / CALIBRATED)
        except OSError as exc:
            log.warning("cannot cache the calibrated description in %s: %s", entry, exc)
    return calibrated, result


def is_calibrated(arm: Arm) -> bool:
    """Whether ``arm``'s description carries a calibration (discovery.json section)."""
    return any(name.endswith(".discovery.json") and '"calibration"' in text
               for name, text in arm.robot.files.items())


def ensure_calibrated(options: DescribeOptions, poses: int = 14,
                      progress: Progress | None = None) -> WireCalibration | None:
    """Calibrate the arm ``options`` name unless the description cache already holds its
    calibrated description or it has no tip sensor; the calibration (None when none was
    made). The next :meth:`Arm.connect` of it comes calibrated."""
    with Arm.connect(robot=options.robot, host=options.host, port=options.port,
                     start=options.start, timeout=options.timeout, naming=options.naming,
                     wire_precision=options.wire_precision,
                     velocity_limits=options.velocity_limits) as arm:
        if is_calibrated(arm) or arm.tip_sensor() is None:
            return None
    from usar_arm.embedded import describe

    _, result = calibrate_description(describe(options), options, poses, None, 0, progress)
    return result
