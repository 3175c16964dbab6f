"""Validation on held-out readings: the calibrated URDF, as written, evaluated by Pinocchio."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.residuals import Residuals, distances
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import Array
from usar_arm.planning.kinematics import KinematicModel


def model_poses(urdf: str, frame: str, base: Array, q: Array) -> Array:
    """(N, 4, 4) poses of ``frame`` in M = base * FK(urdf) (Pinocchio; its joint order checked
    against the error model's, so q means the same to both)."""
    km = KinematicModel(urdf, ErrorModel.from_urdf(urdf, frame).joint_names)
    return np.array([base @ km.frame_pose(qi, frame) for qi in q]).reshape(-1, 4, 4)


def validate(urdf: str, calibrated: str, base_guess: Array, base: Array, measured_frame: str,
             held_out: Sequence[Measurement]) -> Residuals:
    """Before: ``urdf`` at ``base_guess``; after: the ``calibrated`` URDF at the fitted
    ``base`` (see :meth:`usar_arm.calibrate.result.Calibration.validate`)."""
    t = qm.targets(held_out, 0.0, 0.0)
    q = qm.joint_midpoints(held_out)
    before = distances(model_poses(urdf, measured_frame, base_guess, q), t)
    after = distances(model_poses(calibrated, measured_frame, base, q), t)
    return Residuals(t.labels, before[0], before[1], after[0], after[1])


BLOCKS = 10
"""The readings are cut into this many contiguous blocks in reading order."""
HELD_OUT_BLOCKS = (4, 9)
"""The blocks held out (the 5th and the 10th): 20 % of the readings, in two stretches of
consecutive readings, so the validation configurations are far from the fitted ones."""
MIN_HELD_OUT = 5
"""Fewest held-out readings a validation is judged on."""


def split_held_out(readings: Sequence[Measurement]
                   ) -> tuple[list[Measurement], list[Measurement]]:
    """(fit, held out): the readings cut into :data:`BLOCKS` contiguous blocks in reading
    order (sizes differing by at most one), blocks :data:`HELD_OUT_BLOCKS` held out and never
    fitted; deterministic. Raises :class:`~usar_arm.core.errors.CalibrationError` when fewer than
    :data:`MIN_HELD_OUT` readings would be held out."""
    n = len(readings)
    block = np.arange(n) * BLOCKS // max(n, 1)
    held_mask = np.isin(block, HELD_OUT_BLOCKS)
    held = [m for m, h in zip(readings, held_mask, strict=True) if h]
    if len(held) < MIN_HELD_OUT:
        share = len(HELD_OUT_BLOCKS) / BLOCKS
        raise CalibrationError(
            f"too few readings to validate: {n} readings hold out {len(held)} "
            f"({share:.0%} in {len(HELD_OUT_BLOCKS)} blocks), at least {MIN_HELD_OUT} needed",
            n, int(np.ceil(MIN_HELD_OUT / share)))
    return [m for m, h in zip(readings, held_mask, strict=True) if not h], held


def held_out_note() -> str:
    """How the readings are split, in words (for the reports)."""
    return (f"blocks {' and '.join(str(b + 1) for b in HELD_OUT_BLOCKS)} of {BLOCKS} "
            f"contiguous blocks in reading order, {len(HELD_OUT_BLOCKS) / BLOCKS:.0%}")
