"""Validation on held-out readings: the calibrated URDF, as written, evaluated by Pinocchio."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.residuals import Residuals, distances
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.spatial import Array

if TYPE_CHECKING:
    from usar_arm.calibrate.identify import Calibration


def model_poses(urdf: str, frame: str, base: Array, q: Array) -> Array:
    """(N, 4, 4) poses of ``frame`` in M = base * FK(urdf) (Pinocchio; its joint order checked
    against the error model's, so q means the same to both)."""
    km = KinematicModel(urdf, ErrorModel.from_urdf(urdf, frame).joint_names)
    return np.array([base @ km.frame_pose(qi, frame) for qi in q]).reshape(-1, 4, 4)


def validate(cal: Calibration, urdf: str, measured_frame: str,
             held_out: Sequence[Measurement]) -> Residuals:
    """Before: ``urdf`` at the base guess; after: ``cal.apply(urdf)`` at the fitted base."""
    t = qm.targets(held_out, 0.0, 0.0)
    q = qm.joint_midpoints(held_out)
    before = distances(model_poses(urdf, measured_frame, cal.base_guess, q), t)
    after = distances(model_poses(cal.apply(urdf), measured_frame, cal.base, q), t)
    return Residuals(t.labels, before[0], before[1], after[0], after[1])


def split_held_out(readings: Sequence[Measurement], every: int = 5
                   ) -> tuple[list[Measurement], list[Measurement]]:
    """(fit, held out): every ``every``-th reading (the every-th, 2 every-th, ...) is held out
    and never fitted; deterministic, and spread over the run like the readings themselves."""
    held = [m for k, m in enumerate(readings) if k % every == every - 1]
    fit = [m for k, m in enumerate(readings) if k % every != every - 1]
    return fit, held
