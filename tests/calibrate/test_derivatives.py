"""The analytic derivatives the fit uses agree with central differences of the error model,
for printed (roll, pitch, yaw) and tracker (rotation vector) readings, revolute and prismatic
joints."""

from __future__ import annotations

import numpy as np
import pytest

from tests.calibrate.synthetic import KR60, perturbed, random_q, readings
from tests.calibrate.test_identify import _on_a_rail
from usar_arm.calibrate import derivatives
from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.core.spatial import FLIP_X, transform, transform_from_xyz_rpy
from usar_arm.planning.kinematics import KinematicModel

BASE = transform(FLIP_X) @ transform_from_xyz_rpy([0.3, 0.2, 0.01], [0.01, -0.02, 0.4])


def _numeric(model: ErrorModel, p: np.ndarray, q: np.ndarray, t: qm.Targets,
             step: float = 1e-6) -> np.ndarray:
    out = np.empty((len(q), 6, model.size))
    for c in range(model.size):
        hi, lo = p.copy(), p.copy()
        hi[c] += step
        lo[c] -= step
        out[:, :, c] = (qm.errors(model.poses(hi, q, BASE), t)
                        - qm.errors(model.poses(lo, q, BASE), t)) / (2 * step)
    return out


@pytest.mark.parametrize(("urdf", "quantised"), [(KR60, True), (KR60, False),
                                                 (_on_a_rail(KR60), True)])
def test_parameter_derivatives_match_central_differences(urdf: str, quantised: bool) -> None:
    frame = "KR60ArmTipTruth"
    model = ErrorModel.from_urdf(urdf, frame)
    q = random_q(KinematicModel(urdf), 40, 3)
    data = readings(perturbed(urdf, 4), frame, BASE, q, 5, sigma_m=1e-4, sigma_rad=1e-4,
                    step_m=1e-3 if quantised else 0.0, step_rad=1e-3 if quantised else 0.0)
    t = qm.targets(data, 1e-4, 1e-4)
    p = np.random.default_rng(6).normal(0.0, 3e-3, model.size)  # away from the nominal
    poses, jac = derivatives.pose_jacobian(model, p, q, BASE)
    np.testing.assert_allclose(poses, model.poses(p, q, BASE), atol=1e-12)
    analytic = derivatives.number_jacobian(poses, jac, t)
    np.testing.assert_allclose(analytic, _numeric(model, p, q, t), atol=1e-7)


def test_joint_derivatives_match_central_differences() -> None:
    urdf = _on_a_rail(KR60)
    model = ErrorModel.from_urdf(urdf, "tool0")
    q = random_q(KinematicModel(urdf), 30, 7)
    t = qm.targets(readings(urdf, "tool0", BASE, q, 1, step_m=1e-3, step_rad=1e-3), 0, 0)
    poses, jac = derivatives.joint_pose_jacobian(model, np.zeros(model.size), q, BASE)
    analytic = derivatives.number_jacobian(poses, jac, t)
    numeric = np.empty_like(analytic)
    for j in range(q.shape[1]):
        hi, lo = q.copy(), q.copy()
        hi[:, j] += 1e-6
        lo[:, j] -= 1e-6
        numeric[:, :, j] = (qm.errors(model.poses(np.zeros(model.size), hi, BASE), t)
                            - qm.errors(model.poses(np.zeros(model.size), lo, BASE), t)) / 2e-6
    np.testing.assert_allclose(analytic, numeric, atol=1e-7)
