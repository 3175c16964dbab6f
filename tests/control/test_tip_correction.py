"""The dither poses the tip correction visits."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.control.tip_bias import BiasEstimate
from usar_arm.control.tip_correction import (
    DITHERS,
    LOCK_MARGIN,
    ZERO_MARGIN,
    TipCorrection,
    away_from_lock,
    away_from_zero,
    dither_pose,
    model_tolerance,
)
from usar_arm.control.tool_accuracy import ToolAccuracy, sensor_accuracy
from usar_arm.core.spatial import log_so3, matrix_to_rpy, rpy_to_matrix, transform

angles = st.floats(-3.0, 3.0)


@given(angles, st.floats(-1.5707, 1.5707), angles)
@settings(max_examples=200, deadline=None)
def test_dithers_split_every_step_and_never_cross_gimbal_lock(r: float, p: float,
                                                              y: float) -> None:
    base = transform(rpy_to_matrix((r, p, y)), (1.0, -0.5, -1.2))
    tilted = away_from_lock(base)
    assert abs(matrix_to_rpy(tilted[:3, :3])[1]) <= np.pi / 2 - LOCK_MARGIN + 1e-12
    shifts = []
    for k in range(DITHERS):
        pose = dither_pose(tilted, k, 1e-3, 1e-3)
        assert np.linalg.norm(pose[:3, 3] - tilted[:3, 3]) < 2e-3
        assert np.linalg.norm(log_so3(pose[:3, :3] @ tilted[:3, :3].T)) < 0.1
        shifts.append((pose[0, 3] - tilted[0, 3]) / 1e-3)
    assert sorted(np.round(shifts, 9)) == pytest.approx([k / DITHERS for k in range(DITHERS)])


def test_poses_away_from_gimbal_lock_are_left_alone() -> None:
    base = transform(rpy_to_matrix((0.1, 0.4, -2.0)), (0.3, 0.2, 0.1))
    assert np.array_equal(away_from_lock(base), base)
    down = transform(rpy_to_matrix((0.0, np.pi / 2, 0.3)), (0.3, 0.2, 0.1))
    tilted = away_from_lock(down)
    turned = np.linalg.norm(log_so3(tilted[:3, :3] @ down[:3, :3].T))
    assert turned == pytest.approx(LOCK_MARGIN)
    assert np.array_equal(tilted[:3, 3], down[:3, 3])


def test_numbers_near_zero_are_moved_off_it_and_others_are_kept() -> None:
    step = 1e-3
    base = transform(rpy_to_matrix((0.0004, -0.0015, 0.7)), (1.6, -0.0003, -1.9))
    moved = away_from_zero(base, step, step)
    rpy = matrix_to_rpy(moved[:3, :3])
    assert rpy[0] == pytest.approx(0.0004 + (ZERO_MARGIN + 1) * step)
    assert rpy[1] == pytest.approx(-0.0015 - (ZERO_MARGIN + 1) * step)
    assert rpy[2] == pytest.approx(0.7)
    assert moved[:3, 3] == pytest.approx([1.6, -0.0003 - (ZERO_MARGIN + 1) * step, -1.9])
    assert np.array_equal(away_from_zero(base, 0.0, 0.0), base)  # full precision: no need


def test_the_model_tolerance_follows_the_joint_resolution() -> None:
    def pose(q: np.ndarray) -> np.ndarray:  # a planar 2-link arm, 1 m links
        rot = rpy_to_matrix((0.0, 0.0, q[0] + q[1]))
        return transform(rot, (np.cos(q[0]) + np.cos(q[0] + q[1]),
                               np.sin(q[0]) + np.sin(q[0] + q[1]), 0.0))

    assert model_tolerance(pose, np.zeros(2), 0.0) == (0.0, 0.0)
    tol_m, tol_rad = model_tolerance(pose, np.zeros(2), 1e-4)
    # RMS over joints of |d pose/dq| (2 m and 1 m; 1 rad and 1 rad), times the half step, x2.
    assert tol_m == pytest.approx(1e-4 * np.sqrt(5), rel=1e-4)
    assert tol_rad == pytest.approx(1e-4 * np.sqrt(2), rel=1e-4)


def test_a_sensor_measurement_is_the_pose_error_to_the_target() -> None:
    target = transform(rpy_to_matrix((0.0, np.pi, 0.0)), (1.0, 0.0, 1.0))
    measured = transform(rpy_to_matrix((0.002, np.pi, 0.0)), (1.003, 0.004, 1.0))
    tip = sensor_accuracy("KR60ArmTipTruth", target, measured, 0.001)
    assert tip.source == "KR60ArmTipTruth" and tip.sensor_step_m == 0.001
    assert tip.error_m == pytest.approx(0.005) and tip.error_rad == pytest.approx(0.002)


def test_a_correction_replaces_the_error_and_reports_its_figures() -> None:
    bias = BiasEstimate(np.array([0.003, 0.0, 0.004]), np.array([0.0, 0.0, 2e-4]),
                        np.full(3, 1e-4), 1e-4, True)
    fix = TipCorrection(np.zeros(6), 2.1e-3, 4e-4, 1e-4, 5e-5, 12, bias, rounds=2,
                        verified=False)
    before = ToolAccuracy("sensor", 2.1e-3, 4e-4, sensor_step_m=0.001)
    after = fix.applied_to(before)
    assert (after.source, after.sensor_step_m) == ("sensor", 0.001)
    assert (after.error_m, after.error_rad) == (1e-4, 5e-5)
    figures = after.correction
    assert figures is not None
    assert (figures.before_m, figures.before_rad, figures.readings) == (2.1e-3, 4e-4, 12)
    assert figures.bias_m == pytest.approx(0.005) and figures.bias_rad == pytest.approx(2e-4)
    assert (figures.bias_consistent, figures.rounds, figures.verified) == (True, 2, False)
