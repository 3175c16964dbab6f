"""The drift figures: the odom frame anchored where truth and odometry agree, and the final
errors of an estimate against the truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usar_arm.control.drive_record import PoseTrack, compose, drift, odom_origin


def test_the_odom_frame_maps_the_first_odometry_pose_onto_the_first_truth() -> None:
    truth, odo = (2.0, -1.0, 0.7), (0.3, 0.1, -0.2)
    origin = odom_origin(truth, odo)
    assert compose(origin, np.array([odo]))[0] == pytest.approx(truth)


def test_drift_is_the_final_error_against_the_truth_at_the_same_time() -> None:
    t = np.arange(11.0)
    truth = PoseTrack(t, np.column_stack([t, np.zeros(11), np.zeros(11)]))  # 10 m along x
    estimate = PoseTrack(t, np.column_stack([t, 0.03 * t, np.full(11, 0.1)]))
    d = drift("odometry", estimate, truth)
    assert d is not None
    assert d.position_m == pytest.approx(0.3) and d.heading_rad == pytest.approx(0.1)
    assert d.distance_m == pytest.approx(10.0) and d.percent_of_distance == pytest.approx(3.0)


def test_heading_errors_wrap_across_pi() -> None:
    t = np.array([0.0, 1.0])
    truth = PoseTrack(t, np.array([[0, 0, math.pi - 0.05], [1, 0, math.pi - 0.05]]))
    estimate = PoseTrack(t, np.array([[0, 0, -math.pi + 0.05], [1, 0, -math.pi + 0.05]]))
    d = drift("INS", estimate, truth)
    assert d is not None and d.heading_rad == pytest.approx(0.1)


def test_no_drift_without_samples() -> None:
    empty = PoseTrack.of([])
    assert drift("INS", empty, PoseTrack.of([(0, 0, 0, 0), (1, 1, 0, 0)])) is None
