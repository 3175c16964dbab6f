"""The set-membership bias estimate from truncated GroundTruth readings.

Synthetic readings are printed as UDK prints GroundTruth poses (3 decimals, truncated toward
zero), from model poses dithered by fractions of a step, with a known bias, including poses at
gimbal lock (a tool pointing straight down) and near zero. Everything that makes the readings is
written out in this file: no usar-arm rotation, printing or dithering helper is involved.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.control.tip_bias import Reading, estimate_bias, interval, rpy_rate

STEP = 1e-3
DITHERS = 6
"""Readings per estimate, as the correction takes them."""

# The readings below are made with this file's own formulas (no usar-arm helper): poses, their
# roll-pitch-yaw, UDK's truncation, and where the readings are taken (away from gimbal lock and
# from zero, dithered by fractions of a step), so the estimator is checked against readings it
# had no hand in making.


def _rot(r: float, p: float, y: float) -> np.ndarray:
    """R = Rz(y) Ry(p) Rx(r)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _rpy(m: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw of R = Rz(y) Ry(p) Rx(r) (pitch in [-pi/2, pi/2])."""
    pitch = float(np.arcsin(np.clip(-m[2, 0], -1.0, 1.0)))
    return (float(np.arctan2(m[2, 1], m[2, 2])), pitch, float(np.arctan2(m[1, 0], m[0, 0])))


def _turn(w: np.ndarray) -> np.ndarray:
    """The rotation by the rotation vector ``w`` (Rodrigues)."""
    angle = float(np.linalg.norm(w))
    if angle < 1e-15:
        return np.eye(3)
    k = w / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx


def _pose(rpy: tuple[float, float, float], xyz: object) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = _rot(*rpy)
    out[:3, 3] = np.asarray(xyz, float)
    return out


def printed(value: float) -> float:
    """UDK's FloatString(v, 3): three decimals, the fraction truncated toward zero."""
    return math.trunc(round(value * 1000.0, 6)) / 1000.0


def _taken_at(rpy: tuple[float, float, float], xyz: np.ndarray
              ) -> tuple[tuple[float, float, float], np.ndarray]:
    """Where the readings are taken: pitch at least 0.05 rad from +-pi/2, every number at least
    two steps from zero (a number truncated toward zero prints 0 over two steps)."""
    r, p, y = rpy
    p = float(np.clip(p, -np.pi / 2 + 0.05, np.pi / 2 - 0.05))

    def off(v: float) -> float:
        return v if abs(v) >= 2 * STEP else v + 3 * STEP * (1.0 if v >= 0 else -1.0)

    return (off(r), off(p), off(y)), np.array([off(float(v)) for v in xyz])


def readings_for(base: np.ndarray, bias_p: np.ndarray, bias_w: np.ndarray,
                 rng: np.random.Generator, joint_noise: float = 0.0) -> list[Reading]:
    """``DITHERS`` readings around ``base`` (z-down world pose) of a sensor biased by
    ``bias_p`` (m) and ``bias_w`` (rad): each of the six numbers moved by its own shuffled
    fractions k/DITHERS of a step, so that together they split every printed box."""
    rpy, xyz = _taken_at(_rpy(base[:3, :3]), base[:3, 3])
    order = np.random.default_rng(11).permuted(np.tile(np.arange(DITHERS), (6, 1)), axis=1)
    out = []
    for k in range(DITHERS):
        f = order[:, k] / DITHERS * STEP
        model = np.eye(4)
        model[:3, :3] = _rot(rpy[0] + f[3], rpy[1] - np.sign(rpy[1]) * f[4], rpy[2] + f[5])
        model[:3, 3] = xyz + f[:3]
        truth_rot = _turn(bias_w) @ model[:3, :3]
        truth_pos = model[:3, 3] + bias_p
        seen = model.copy()  # the model at inexactly measured joints
        if joint_noise:
            axis = rng.normal(size=3)
            seen[:3, :3] = _turn(axis / np.linalg.norm(axis) * rng.uniform(0, joint_noise)) \
                @ seen[:3, :3]
            seen[:3, 3] += rng.uniform(-joint_noise, joint_noise, 3)
        out.append(Reading(tuple(printed(v) for v in truth_pos),
                           tuple(printed(v) for v in _rpy(truth_rot)),
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
    rot = _rot(r, p, y)
    jac = rpy_rate((r, p, y))
    h = 1e-7
    for i in range(3):
        dw = np.zeros(3)
        dw[i] = h
        moved = np.array(_rpy(_turn(dw) @ rot))
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
        base = _pose(rpy, xyz)
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
        base = _pose((0.3, np.pi / 2 - 2e-4, -1.0), (1.4, -0.4, -1.0))
        bias_w = rng.normal(size=3) * 3e-4
        est = estimate_bias(readings_for(base, np.zeros(3), bias_w, rng, joint_noise=1e-4))
        errors.append(np.linalg.norm(est.rotation - bias_w))
        assert est.consistent
    assert max(errors) < 0.5 * STEP


def test_readings_that_contradict_each_other_are_flagged() -> None:
    rng = np.random.default_rng(5)
    base = _pose((0.2, 0.3, 0.4), (1.0, 0.5, -1.2))
    readings = readings_for(base, np.zeros(3), np.zeros(3), rng)
    moved = readings[3]
    readings[3] = Reading(moved.location, (moved.orientation[0] + 0.01, *moved.orientation[1:]),
                          STEP, STEP, moved.model)
    est = estimate_bias(readings)
    assert not est.consistent and est.rotation_radius < 0
    assert np.linalg.norm(est.rotation) < 0.01  # still the least-violating point, not garbage


def test_full_precision_readings_give_the_bias_exactly() -> None:
    model = _pose((0.2, 1.0, -0.4), (1.0, 0.5, -1.2))
    bias_w = np.array([1e-4, -2e-4, 3e-4])
    truth = np.eye(4)
    truth[:3, :3] = _turn(bias_w) @ model[:3, :3]
    truth[:3, 3] = model[:3, 3] + [1e-3, 0, -2e-3]
    reading = Reading(tuple(truth[:3, 3]), _rpy(truth[:3, :3]), 0.0, 0.0, model)
    est = estimate_bias([reading])
    assert np.allclose(est.rotation, bias_w, atol=1e-12)
    assert np.allclose(est.position, [1e-3, 0, -2e-3], atol=1e-12)
