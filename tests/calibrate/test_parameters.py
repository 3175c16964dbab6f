"""The error model: its own product of frames agrees with Pinocchio on the URDF it writes."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.calibrate.synthetic import KR60, random_q
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.core.spatial import FLIP_X, transform
from usar_arm.planning.kinematics import KinematicModel

MODEL = ErrorModel.from_urdf(KR60, "tool0")
NOMINAL = KinematicModel(KR60)


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31), size=st.sampled_from([1e-4, 1e-3, 1e-2]))
def test_corrected_poses_equal_pinocchio_on_the_corrected_urdf(seed: int, size: float) -> None:
    rng = np.random.default_rng(seed)
    p = rng.normal(0.0, size, MODEL.size)
    base = transform(FLIP_X, [0.3, 0.2, 0.0])
    q = random_q(NOMINAL, 8, seed)
    ours = MODEL.poses(p, q, base)
    written = KinematicModel(MODEL.apply(KR60, p))
    fitted_base = MODEL.base_pose(p, base)
    for k, qk in enumerate(q):
        np.testing.assert_allclose(ours[k], fitted_base @ written.frame_pose(qk, "tool0"),
                                   atol=5e-9)


def test_zero_corrections_change_no_number_and_parameters_are_named() -> None:
    again = KinematicModel(MODEL.apply(KR60, np.zeros(MODEL.size)))
    for qk in random_q(NOMINAL, 5, 1):
        np.testing.assert_allclose(again.frame_pose(qk, "tool0"),
                                   NOMINAL.frame_pose(qk, "tool0"), atol=1e-9)
    assert MODEL.size == 48 and MODEL.names[:2] == ("joint_a1.origin.x", "joint_a1.origin.y")
    assert MODEL.tool_joint == "flange-tool0" and MODEL.names[-1] == "base.yaw"
