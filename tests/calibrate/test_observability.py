"""Pose selection for observability."""

from __future__ import annotations

import numpy as np

from tests.calibrate.synthetic import KR60, random_q
from usar_arm.calibrate.observability import (
    pose_jacobians,
    select_poses,
    smallest_singular_value,
)
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.solver import preference, select_identifiable
from usar_arm.core.spatial import Array
from usar_arm.planning.kinematics import KinematicModel

FRAME = "KR60ArmTipTruth"
NOMINAL = KinematicModel(KR60)


def _sigma_min(model: ErrorModel, q: Array, reference: Array) -> float:
    jac = pose_jacobians(model, q)
    cols, _ = select_identifiable(pose_jacobians(model, reference).reshape(-1, model.size),
                      preference(model))
    return smallest_singular_value(jac[:, :, cols].reshape(-1, len(cols)))


def test_selected_poses_are_better_conditioned_than_random_ones_within_limits() -> None:
    def free(q: Array) -> bool:
        return bool(q[1] < 0.3)  # a stand-in obstacle: half of joint 2's range is forbidden

    chosen = select_poses(KR60, FRAME, 30, free, seed=1)
    assert chosen.shape == (30, 6) and all(free(q) for q in chosen)
    assert np.all(chosen >= NOMINAL.lower) and np.all(chosen <= NOMINAL.upper)
    model = ErrorModel.from_urdf(KR60, FRAME)
    reference = random_q(NOMINAL, 60, 9, margin=0.0)
    random_scores = [_sigma_min(model, random_q(NOMINAL, 30, s, margin=0.0), reference)
                     for s in range(5)]
    assert _sigma_min(model, chosen, reference) > max(random_scores)
    np.testing.assert_array_equal(chosen, select_poses(KR60, FRAME, 30, free, seed=1))
