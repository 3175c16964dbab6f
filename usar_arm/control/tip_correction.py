"""Tip correction: move the joint goal until the *real* tool0 is where it should be.

The description learnt through UDK is off by 2-3 millimetres and a few tenths of a mrad at
the tool (UDK prints link offsets to the millimetre and orientations to 0.01 rad). Near one
pose that error is a nearly constant bias, which the tip GroundTruth sensor can measure -- but
it too prints truncated numbers (1 mm, 0.001 rad). So the arm visits :data:`DITHERS` poses a
fraction of a printed step apart in every number (:func:`dither_pose`), each reading bounds the
bias to a box, and :mod:`.tip_bias` intersects the boxes. The joint goal is then solved for the
target minus the bias.

Near gimbal lock (the sensor's x axis vertical, as for a tool pointing down) roll and yaw
separately are not smooth functions of the pose, so the readings are taken with the sensor
tilted :data:`LOCK_MARGIN` away from it; numbers near zero print as 0 over two steps, so they
are moved off zero first (:func:`reading_base`). The bias changes by far less than a step over
such small moves.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from usar_arm.control.tip import RawReading, TipSensor
from usar_arm.control.tip_bias import BiasEstimate, Reading, estimate_bias, interval
from usar_arm.control.tool_accuracy import TipCorrectionFigures, ToolAccuracy
from usar_arm.core.spatial import (
    Array,
    exp_so3,
    log_so3,
    matrix_to_rpy,
    pose_error,
    rpy_to_matrix,
    transform,
)

log = logging.getLogger("usar_arm.control")

DITHERS = 6
"""Readings per bias estimate (see :func:`dither_pose`)."""
MAX_ROUNDS = 3
"""Correction rounds at most (one suffices unless the sensor disagrees with the estimate)."""
TOLERANCE = (0.5e-3, 0.5e-3)
"""Estimated tool0 error (m, rad) a correction round must reach."""
LOCK_MARGIN = 0.05
"""rad: readings are taken with the sensor's pitch at least this far from +-pi/2."""


@dataclass(frozen=True)
class TipCorrection:
    """The outcome of :func:`correct_tip`.

    Attributes:
        goal: the joint goal finally held.
        before_m, before_rad: tool0's error (m, rad) read before the correction (each printed
            number at the middle of its step).
        after_m, after_rad: tool0's error estimated after it (the model at the measured joints
            plus the bias).
        readings: sensor readings taken.
        bias: the last estimate, with its uncertainty.
        rounds: correction rounds run. verified: the last check reading agreed with the
            estimate.
    """

    goal: Array
    before_m: float
    before_rad: float
    after_m: float
    after_rad: float
    readings: int
    bias: BiasEstimate
    rounds: int = 1
    verified: bool = True

    @property
    def figures(self) -> TipCorrectionFigures:
        """What the correction did, as a report keeps it (no arrays)."""
        return TipCorrectionFigures(
            self.before_m, self.before_rad, self.readings,
            float(np.linalg.norm(self.bias.position)), float(np.linalg.norm(self.bias.rotation)),
            self.bias.consistent, self.rounds, self.verified)

    def applied_to(self, tip: ToolAccuracy) -> ToolAccuracy:
        """``tip`` (the sensor's measurement before the correction) with the error estimated
        after it and the correction's figures."""
        return replace(tip, error_m=self.after_m, error_rad=self.after_rad,
                       correction=self.figures)


def away_from_lock(world: Array, margin: float = LOCK_MARGIN) -> Array:
    """``world`` (a z-down world pose) with its pitch moved to at most pi/2 - ``margin`` in
    magnitude (the sensor tilted about its origin, toward its current yaw)."""
    roll, pitch, yaw = matrix_to_rpy(world[:3, :3])
    limit = np.pi / 2 - margin
    if abs(pitch) <= limit:
        return world.copy()
    return transform(rpy_to_matrix((roll, float(np.copysign(limit, pitch)), yaw)), world[:3, 3])


ZERO_MARGIN = 2.0
"""Printed steps: numbers closer to zero than this are moved off it before the readings."""


def away_from_zero(world: Array, step_m: float, step_rad: float,
                   margin: float = ZERO_MARGIN) -> Array:
    """``world`` (a z-down world pose) with every location number and roll-pitch-yaw angle
    within ``margin`` steps of zero moved ``margin + 1`` steps further from it.

    A number truncated toward zero prints 0 anywhere in (-step, step): that box is two steps
    wide, and the dithers (under a step) cannot split it.
    """
    def off(value: float, step: float) -> float:
        if step <= 0 or abs(value) >= margin * step:
            return value
        return value + (margin + 1) * step * (1.0 if value >= 0 else -1.0)

    rpy = matrix_to_rpy(world[:3, :3])
    moved_rpy = tuple(off(a, step_rad) for a in rpy)
    out = world.copy()
    if moved_rpy != rpy:
        out[:3, :3] = rpy_to_matrix(moved_rpy)
    out[:3, 3] = [off(v, step_m) for v in world[:3, 3]]
    return out


def reading_base(world: Array, step_m: float, step_rad: float) -> Array:
    """Where the readings are taken: ``world`` away from gimbal lock and from zero."""
    return away_from_zero(away_from_lock(world), step_m, step_rad)


def dither_pose(world: Array, k: int, step_m: float, step_rad: float) -> Array:
    """``world`` (a z-down world pose) moved for the ``k``-th of :data:`DITHERS` readings, so
    that together the readings split every printed number's step-wide box into pieces.

    Location x, y, z and yaw move by k/N of a step, pitch by another ordering of the same
    fractions (toward zero), and roll by k/N against pitch's sign. When the sensor's x axis is
    near vertical the rotation about the vertical shows only in yaw - sign(pitch) * roll,
    which a reading bounds to two steps; it moves by 2k/N steps, splitting those boxes as
    finely.
    """
    f = k / DITHERS
    g = (k * (DITHERS - 1)) % DITHERS / DITHERS
    roll, pitch, yaw = matrix_to_rpy(world[:3, :3])
    sign = 1.0 if pitch >= 0 else -1.0
    rpy = (roll - sign * f * step_rad, pitch - sign * g * step_rad, yaw + f * step_rad)
    return transform(rpy_to_matrix(rpy), world[:3, 3] + f * step_m)


def model_tolerance(model_sensor_pose: Callable[[Array], Array], q: Array,
                    joint_step: float) -> tuple[float, float]:
    """How far (m, rad) the model's sensor pose may move when each joint is off by up to half
    ``joint_step`` (the measured joints' printed resolution): twice the RMS over the joints."""
    if joint_step <= 0:
        return 0.0, 0.0
    h = 1e-6
    base = model_sensor_pose(q)
    dp, dw = [], []
    for i in range(len(q)):
        dq = q.copy()
        dq[i] += h
        moved = model_sensor_pose(dq)
        dp.append(np.linalg.norm(moved[:3, 3] - base[:3, 3]) / h)
        dw.append(np.linalg.norm(log_so3(moved[:3, :3] @ base[:3, :3].T)) / h)
    half = joint_step / 2
    return 2 * half * float(np.linalg.norm(dp)), 2 * half * float(np.linalg.norm(dw))


def agrees(raw: RawReading, predicted: Array, tol_m: float, tol_rad: float) -> bool:
    """Whether a reading could have been printed from the ``predicted`` sensor pose (z-down
    world): each location number within half a step (+ ``tol_m``) of its box middle, and the
    rotation within 1.5 steps (+ ``tol_rad``) of the box middle's -- the farthest any rotation
    in a roll-pitch-yaw box lies from its middle, gimbal lock included."""
    mid_loc = np.array([sum(interval(v, raw.step_m)) / 2 for v in raw.location])
    mid_rpy = [sum(interval(v, raw.step_rad)) / 2 for v in raw.orientation]
    off_m = np.abs(mid_loc - predicted[:3, 3])
    off_rad = np.linalg.norm(log_so3(rpy_to_matrix(mid_rpy) @ predicted[:3, :3].T))
    return bool(np.all(off_m <= raw.step_m / 2 + tol_m + 1e-9)
                and off_rad <= 1.5 * raw.step_rad + tol_rad + 1e-9)


def correct_tip(sensor: TipSensor, model_sensor_pose: Callable[[Array], Array],
                solve: Callable[[Array, Array], Array], settle: Callable[[Array], object],
                measure: Callable[[], Array], goal: Array, target: Array,
                joint_step: float = 0.0, tolerance: tuple[float, float] = TOLERANCE
                ) -> TipCorrection:
    """Move the joint goal so that the real tool0 reaches ``target`` (4x4, base_link).

    One round: read the bias (:data:`DITHERS` readings), solve the goal for the target minus
    the bias, settle there, and check with one more reading that the sensor agrees with the
    prediction. Rounds repeat (at most :data:`MAX_ROUNDS`) while it does not, or while the
    estimated error is above ``tolerance``.

    Args:
        sensor: the tip sensor (its platform pose is refreshed by every reading).
        model_sensor_pose: q -> the sensor frame's world pose (4x4, z-down) by the model.
        solve: (tool0 pose in base_link, seed q) -> joint values (IK on the model).
        settle: moves to a joint goal and waits there. measure: the joints now (rad, m).
        goal: the joint goal the arm holds now. joint_step: the measured joints' printed
            resolution (0 = exact). tolerance: (m, rad) of the estimated tool0 error.
    """
    first = sensor.read_raw()
    _, before_m, before_rad = pose_error(target, sensor.tool0_from_raw(first))

    def reading(raw: RawReading, q: Array) -> Reading:
        tol_m, tol_rad = model_tolerance(model_sensor_pose, q, joint_step)
        return Reading(raw.location, raw.orientation, raw.step_m, raw.step_rad,
                       model_sensor_pose(q), tol_m, tol_rad)

    def fresh() -> RawReading:
        return sensor.read_raw(after=sensor.read_raw().time)

    taken, latest = 1, first
    for round_ in range(1, MAX_ROUNDS + 1):
        readings = [reading(latest, measure())]
        if latest.step_m > 0 or latest.step_rad > 0:
            base = model_sensor_pose(goal)
            tilted = reading_base(base, latest.step_m, latest.step_rad)
            if not np.allclose(tilted, base):
                readings = []  # near gimbal lock or zero: every reading is taken moved
            for k in range(len(readings), DITHERS):
                world = dither_pose(tilted, k, latest.step_m, latest.step_rad)
                settle(solve(sensor.tool0_from_world(world), goal))
                readings.append(reading(fresh(), measure()))
                taken += 1
        bias = estimate_bias(readings)
        # The sensor pose the model must show so that the real one is the target's.
        wanted = sensor.world_from_tool0(target)
        shown = transform(exp_so3(-bias.rotation) @ wanted[:3, :3],
                          wanted[:3, 3] - bias.position)
        goal = solve(sensor.tool0_from_world(shown), goal)
        settle(goal)
        latest = fresh()
        taken += 1
        q = measure()
        predicted = model_sensor_pose(q)
        estimate = transform(exp_so3(bias.rotation) @ predicted[:3, :3],
                             predicted[:3, 3] + bias.position)
        _, after_m, after_rad = pose_error(target, sensor.tool0_from_world(estimate))
        tol_m, tol_rad = model_tolerance(model_sensor_pose, q, joint_step)
        ok = agrees(latest, estimate, tol_m + float(np.max(bias.position_halfwidth)),
                    tol_rad + max(bias.rotation_radius, 0.0))
        if ok and after_m <= tolerance[0] and after_rad <= tolerance[1]:
            break
        log.info("tip correction round %d: estimated error %.2f mm %.2f mrad, sensor %s; "
                 "again", round_, after_m * 1e3, after_rad * 1e3,
                 "agrees" if ok else "disagrees")
    return TipCorrection(goal, before_m, before_rad, after_m, after_rad, taken, bias,
                         round_, ok)
