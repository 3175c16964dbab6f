"""The set-membership bias estimate from truncated GroundTruth readings.

Synthetic readings are printed exactly as UDK prints GroundTruth poses (FloatString, 3 decimals,
truncated in float32), from model poses dithered as the correction dithers them, with a known
bias, including poses at gimbal lock (a tool pointing straight down).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.control.tip_bias import Reading, estimate_bias, interval, rpy_rate
from usar_arm.control.tip_correction import DITHERS, dither_pose, reading_base
from usar_arm.spatial import exp_so3, matrix_to_rpy, rpy_to_matrix, transform
from usar_arm.usarsim.numbers import udk_float_string

STEP = 1e-3


def printed(value: float) -> float:
    return float(udk_float_string(value, 3))


def readings_for(base: np.ndarray, bias_p: np.ndarray, bias_w: np.ndarray,
                 rng: np.random.Generator, joint_noise: float = 0.0) -> list[Reading]:
    """The readings the correction would take around ``base`` (z-down world pose)."""
    out = []
    tilted = reading_base(base, STEP, STEP)
    for k in range(DITHERS):
        model = dither_pose(tilted, k, STEP, STEP)
        truth = transform(exp_so3(bias_w) @ model[:3, :3], model[:3, 3] + bias_p)
        seen = model.copy()  # the model at inexactly measured joints
        if joint_noise:
            axis = rng.normal(size=3)
            seen[:3, :3] = exp_so3(axis / np.linalg.norm(axis) * rng.uniform(0, joint_noise)) \
                @ seen[:3, :3]
            seen[:3, 3] += rng.uniform(-joint_noise, joint_noise, 3)
        out.append(Reading(tuple(printed(v) for v in truth[:3, 3]),
                           tuple(printed(v) for v in matrix_to_rpy(truth[:3, :3])),
                           STEP, STEP, seen, 2 * joint_noise, 2 * joint_noise))
    return out


def test_a_truncated_number_stands_for_a_step_toward_zero() -> None:
    assert interval(1.234, STEP) == (1.234, pytest.approx(1.235))
    assert interval(-1.234, STEP) == (pytest.approx(-1.235), -1.234)
    assert interval(0.0, STEP) == (-STEP, STEP)
    assert interval(0.5, 0.0) == (0.5, 0.5)


@given(st.floats(-3.1, 3.1), st.floats(-1.5, 1.5), st.floats(-3.1, 3.1))
@settings(max_examples=200, deadline=None)
def test_rpy_rate_is_the_derivative_of_roll_pitch_yaw(r: float, p: float, y: float) -> None:
    rot = rpy_to_matrix((r, p, y))
    jac = rpy_rate((r, p, y))
    h = 1e-7
    for i in range(3):
        dw = np.zeros(3)
        dw[i] = h
        moved = np.array(matrix_to_rpy(exp_so3(dw) @ rot))
        numeric = (moved - np.array((r, p, y)) + np.pi) % (2 * np.pi) - np.pi
        assert np.allclose(numeric / h, jac[:, i], atol=1e-4 / np.cos(p) ** 2)


@pytest.mark.parametrize("case", ["free", "gimbal-lock", "near-zero"])
def test_the_estimate_is_within_a_fraction_of_a_step_of_the_bias(case: str) -> None:
    rng = np.random.default_rng(7)
    rot_err, pos_err = [], []
    for _ in range(60):
        rpy = (rng.uniform(-3, 3), rng.uniform(-1.4, 1.4), rng.uniform(-3, 3))
        xyz = rng.uniform(-2, 2, 3)
        if case == "gimbal-lock":
            rpy = (rpy[0], np.sign(rng.uniform(-1, 1)) * (np.pi / 2 - rng.uniform(0, 1e-3)),
                   rpy[2])
        elif case == "near-zero":  # a tool pointing straight ahead at y = 0: numbers print 0
            rpy, xyz = tuple(rng.uniform(-1e-3, 1e-3, 3)), (1.6, rng.uniform(-1e-3, 1e-3), -1.9)
        base = transform(rpy_to_matrix(rpy), xyz)
        bias_p = rng.uniform(-1.5e-3, 1.5e-3, 3)
        bias_w = rng.normal(size=3)
        bias_w *= rng.uniform(0, 1e-3) / np.linalg.norm(bias_w)
        est = estimate_bias(readings_for(base, bias_p, bias_w, rng))
        assert est.consistent
        rot_err.append(np.linalg.norm(est.rotation - bias_w))
        pos_err.append(np.linalg.norm(est.position - bias_p))
    # One reading alone is only good to half a step per number (0.87 step overall).
    assert np.percentile(rot_err, 90) < 0.2 * STEP and max(rot_err) < 0.7 * STEP
    assert np.percentile(pos_err, 90) < 0.25 * STEP and max(pos_err) < 0.6 * STEP


def test_inexact_joints_widen_the_boxes_instead_of_breaking_them() -> None:
    rng = np.random.default_rng(3)
    errors = []
    for _ in range(30):
        base = transform(rpy_to_matrix((0.3, np.pi / 2 - 2e-4, -1.0)), (1.4, -0.4, -1.0))
        bias_w = rng.normal(size=3) * 3e-4
        est = estimate_bias(readings_for(base, np.zeros(3), bias_w, rng, joint_noise=1e-4))
        errors.append(np.linalg.norm(est.rotation - bias_w))
        assert est.consistent
    assert max(errors) < 0.5 * STEP


def test_readings_that_contradict_each_other_are_flagged() -> None:
    rng = np.random.default_rng(5)
    base = transform(rpy_to_matrix((0.2, 0.3, 0.4)), (1.0, 0.5, -1.2))
    readings = readings_for(base, np.zeros(3), np.zeros(3), rng)
    moved = readings[3]
    readings[3] = Reading(moved.location, (moved.orientation[0] + 0.01, *moved.orientation[1:]),
                          STEP, STEP, moved.model)
    est = estimate_bias(readings)
    assert not est.consistent and est.rotation_radius < 0
    assert np.linalg.norm(est.rotation) < 0.01  # still the least-violating point, not garbage


def test_full_precision_readings_give_the_bias_exactly() -> None:
    model = transform(rpy_to_matrix((0.2, 1.0, -0.4)), (1.0, 0.5, -1.2))
    bias_w = np.array([1e-4, -2e-4, 3e-4])
    truth = transform(exp_so3(bias_w) @ model[:3, :3], model[:3, 3] + [1e-3, 0, -2e-3])
    reading = Reading(tuple(truth[:3, 3]), matrix_to_rpy(truth[:3, :3]), 0.0, 0.0, model)
    est = estimate_bias([reading])
    assert np.allclose(est.rotation, bias_w, atol=1e-12)
    assert np.allclose(est.position, [1e-3, 0, -2e-3], atol=1e-12)
