"""Calibrating a live arm: a tour reading the arm's tip GroundTruth sensor
(:mod:`usar_arm.arm.tour`), the fit, validation on held-out readings, and the calibrated
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
report says so (frame bookkeeping: :mod:`usar_arm.calibrate.wire_frames`).

A tour's calibrated description is cached in the description cache entry of the arm's CONF/GEO
lines, keyed by :class:`CalibrationSettings` (:func:`cached_calibration` finds it again).
"""

from __future__ import annotations

import logging
import time
from dataclasses import asdict, dataclass, field, replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.arm.facade import Arm
from usar_arm.arm.tour import Progress, choose_configurations, collect
from usar_arm.calibrate.identification import Calibration, CalibrationOptions, identify
from usar_arm.calibrate.report import calibration_dict, check_validated
from usar_arm.calibrate.residuals import Residuals
from usar_arm.calibrate.tour_readings import TourReadings, read_tour
from usar_arm.calibrate.validation import held_out_note, split_held_out
from usar_arm.calibrate.wire_frames import (
    FLIP,
    fold_base,
    mount_joint,
    tip_joint,
    tip_onto_sensor,
    usarsim_axes,
)
from usar_arm.core.errors import CalibrationError, InvalidInputError
from usar_arm.core.model import JointType
from usar_arm.description.cache import (
    CachedCalibration,
    calibrated_folder,
    load_calibrated,
    store_calibrated,
)
from usar_arm.description.pipeline import DescribeOptions, Description
from usar_arm.urdf.discovery_file import wire_facts

log = logging.getLogger(__name__)
_usarsim_axes, _fold_base = usarsim_axes, fold_base  # the names the tests knew them by


def embedded_cell(arm: Arm) -> str | None:
    """The scene a tour on the embedded simulator avoids when none is given: its world's work
    cell (``cell:`` of the world file, the one description the planner reads as a scene), or
    None when its world has none or the arm is on another server (nothing is known of it)."""
    if arm.server is None:
        return None
    return arm.server.cell or None


@dataclass(frozen=True)
class CalibrationSettings:
    """Everything a tour's calibration depends on besides the arm (and so the key of its
    cached result): the tour's ``poses``, the ``scene`` it avoids (a shipped name or a YAML
    file), the ``seed`` of the pose choice and the fit's ``options``."""

    poses: int = 14
    scene: str | None = None
    seed: int = 0
    options: CalibrationOptions = field(default_factory=CalibrationOptions)

    def key(self) -> dict[str, Any]:
        """The settings as JSON values (a scene file by its content)."""
        scene: str | None = self.scene
        if scene is not None and Path(scene).is_file():
            scene = Path(scene).read_text(encoding="utf-8")
        return {"poses": self.poses, "scene": scene, "seed": self.seed,
                "options": asdict(self.options), "held_out": held_out_note()}



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


def fit_tour(urdf: str, tour: TourReadings, tip_step: float,
             options: CalibrationOptions | None = None) -> WireCalibration:
    """Fit ``urdf`` (as learnt) to a tour's readings, validate on the held-out ones and build
    the calibrated URDF (see the module; ``tip_step``: the Tip's printed step, m). Raises
    :class:`~usar_arm.core.errors.CalibrationError` when the readings are inconsistent or the fit
    does not hold on the held-out readings."""
    frame = tour.sensor
    mount = mount_joint(urdf, frame)
    fit_urdf = usarsim_axes(urdf, mount, FLIP)
    tip, tool_point = tip_joint(urdf, frame, tip_step)
    fit, held = split_held_out(list(tour.measurements))
    base_guess = tour.platform_pose() @ FLIP
    cal = identify(fit_urdf, frame, fit, base_guess, options or CalibrationOptions())
    validation = cal.validate(fit_urdf, frame, held)
    check_validated(cal, validation)
    calibrated = usarsim_axes(cal.apply(fit_urdf), mount, FLIP)
    if tip is not None:
        calibrated = tip_onto_sensor(calibrated, urdf, tip, mount)
    calibrated = fold_base(calibrated, np.linalg.inv(base_guess) @ cal.base)
    return WireCalibration(cal, validation, calibrated, tour.poses, len(tour.measurements),
                           tour.seconds, tool_point, tip, tour)


def calibrate_arm(arm: Arm, poses: int = 14, scene: str | None = None,
                  seed: int = 0, progress: Progress | None = None,
                  options: CalibrationOptions | None = None) -> WireCalibration:
    """Calibrate ``arm`` on its server: tour it, then :func:`fit_tour`. Raises
    :class:`~usar_arm.core.errors.CalibrationError` when the readings are inconsistent or the fit
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
    mount_joint(arm.urdf, str(arm.robot.tip_sensor))  # a sensor the fit can use, first
    if scene is None:
        # The embedded simulator's world has a work cell (sim/worlds/default.yaml: the table),
        # and the arm's links hit its scenery: a tour through it stops at its first contact.
        scene = embedded_cell(arm)
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
                          progress: Progress | None = None, readings: str | Path | None = None,
                          *, calibration: CalibrationOptions | None = None,
                          entry: Path | None = None) -> tuple[Description, WireCalibration]:
    """Spawn the arm ``desc`` describes again (same server and options), calibrate it, and
    return the calibrated description (its URDF, and discovery.json with a ``calibration``
    section; on the embedded simulator also the calibrated description's accuracy against the
    simulator's own model) and the calibration. A tour's result is cached in the description
    cache's ``entry`` (default: the spawned arm's), keyed by the settings
    (:class:`CalibrationSettings`), so that the next plan or demo of this arm uses it and
    :func:`cached_calibration` finds it. With ``readings`` (a tour's readings file) nothing is
    spawned or cached: the fit uses those readings."""
    if options.frame != "z-up":
        raise InvalidInputError("calibration works on REP-103 (z-up) descriptions; describe "
                                f"with --frame z-up (got {options.frame})")
    settings = CalibrationSettings(poses, scene, seed, calibration or CalibrationOptions())
    if readings is not None:
        chain = desc.chain
        tour = read_tour(readings, chain.joint_names,
                         [j.type is JointType.PRISMATIC for j in chain.actuated_joints],
                         chain.lower(), chain.upper())
        tip_step = wire_facts(desc.discovery).tip_resolution_m
        result = fit_tour(desc.urdf, tour, tip_step, settings.options)
    else:
        with Arm.connect(robot=options.robot, host=options.host, port=options.port,
                         start=options.start, timeout=options.timeout, naming=options.naming,
                         wire_precision=options.wire_precision,
                         velocity_limits=options.velocity_limits, calibrated=False) as arm:
            if arm.urdf != desc.urdf:
                raise CalibrationError("the arm spawned for calibration is described "
                                       "differently from the description to calibrate (did "
                                       "the server change?)")
            result = calibrate_arm(arm, poses, scene, seed, progress, settings.options)
            entry = entry or arm.cache_entry
    calibrated = _calibrated(desc, options, result)
    if entry is not None and readings is None:
        _store(entry, settings, calibrated, result)
    return calibrated, result


def _calibrated(desc: Description, options: DescribeOptions, result: WireCalibration
                ) -> Description:
    """``desc`` with the calibrated URDF and the ``calibration`` section in discovery.json."""
    notes = (f"{result.readings} tip-sensor readings on a tour through {result.poses} poses "
             f"({result.seconds:.0f} s; {desc.chain.name}.readings.csv); held out: "
             f"{held_out_note()}",)
    discovery = {**desc.discovery, "calibration": calibration_dict(
        result.calibration, result.validation, notes, result.tool_point)}
    if "accuracy_vs_simulator" in desc.discovery and options.host is None:
        from usar_arm.description.accuracy import urdf_accuracy

        discovery["calibration"]["as_learnt_accuracy_vs_simulator"] = \
            desc.discovery["accuracy_vs_simulator"]
        discovery["accuracy_vs_simulator"] = urdf_accuracy(result.urdf, options)
    return replace(desc, urdf=result.urdf, discovery=discovery)


def _store(entry: Path, settings: CalibrationSettings, calibrated: Description,
           result: WireCalibration) -> None:
    """Cache the calibrated description and its readings (a failure only logged)."""
    files = calibrated.files()
    if result.tour is not None:
        files[f"{calibrated.chain.name}.readings.csv"] = result.tour.csv()
    made = datetime.now(timezone.utc).isoformat(timespec="seconds")
    try:
        store_calibrated(calibrated_folder(entry, settings.key()), files,
                         f"{calibrated.chain.name}.urdf", made, result.readings,
                         settings.key())
    except OSError as exc:
        log.warning("cannot cache the calibrated description in %s: %s", entry, exc)


def cached_calibration(entry: Path, robot_name: str, settings: CalibrationSettings
                       ) -> CachedCalibration | None:
    """The calibrated description a tour with ``settings`` cached in the description cache's
    ``entry`` (the arm's CONF/GEO lines and description options), or None."""
    return load_calibrated(calibrated_folder(entry, settings.key()), robot_name)


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
    from usar_arm.description.embedded import describe

    _, result = calibrate_description(describe(options), options, poses, None, 0, progress)
    return result
