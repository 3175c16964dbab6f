"""A description learnt over the wire matches the simulator's ground truth."""

from __future__ import annotations

import numpy as np
import pytest

from usar_arm.description.accuracy import accuracy_report
from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions
from usar_arm.sim.robot_spec import builtin_robots

ROBOTS = ("KR60", "Fanuc_M16iB20")
SPECS = builtin_robots()


def _report(robot: str, precision: str) -> tuple[dict, object]:
    desc = describe(DescribeOptions(robot=robot, wire_precision=precision, acm_samples=200,
                                    accuracy_samples=0))
    act = SPECS[f"USARBot.{robot}"].actuators[0]
    return accuracy_report(desc.chain, act, "z-up", samples=1000, seed=11), desc


# Measured (1,000 configurations, seed 11; 2026-11-24) -> the bounds below, at most 2x those:
#   KR60 udk: origin 1.42 mm, flange 3.22 mm, axis 1.28 mrad, axis at zero 0.288 mrad
#   Fanuc udk: origin 1.73 mm, flange 1.73 mm, axis 1.92 mrad, axis at zero 0.407 mrad
#   both, full: every figure below 1e-12 (m or rad)
UDK_BOUNDS = {  # origin m, flange m, axis rad, axis at the zero pose rad
    "KR60": (0.0025, 0.0060, 0.0025, 0.0005),
    "Fanuc_M16iB20": (0.0030, 0.0030, 0.0035, 0.0008),
}
FULL_BOUND = 1e-11


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_full_wire_precision_reproduces_the_simulator_model(robot: str) -> None:
    report, _ = _report(robot, "full")
    assert report["configurations"] >= 1000
    assert report["max_joint_origin_error_m"] < FULL_BOUND
    assert report["max_flange_error_m"] < FULL_BOUND
    assert report["max_joint_axis_error_rad"] < FULL_BOUND


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_udk_wire_is_as_accurate_as_its_rounding_allows(robot: str) -> None:
    report, desc = _report(robot, "udk")
    precision = desc.discovery["precision"]
    assert precision["location_resolution_m"] == 0.001
    assert precision["orientation_resolution_rad"] == 0.01
    origin, flange, axis, axis_zero = UDK_BOUNDS[robot]
    assert report["max_joint_origin_error_m"] < origin
    assert report["max_flange_error_m"] < flange
    assert report["max_joint_axis_error_rad"] < axis
    assert report["max_joint_axis_error_at_zero_pose_rad"] < axis_zero
    assert desc.discovery["precision"]["snapped"], "frames should have been snapped"


def test_kr60_z_down_matches_the_nist_2012_urdf() -> None:
    desc = describe(DescribeOptions(robot="KR60", frame="z-down", naming="legacy-2012",
                                    acm_samples=100, accuracy_samples=0))
    joints = desc.chain.actuated_joints
    assert [j.name for j in joints] == [f"KR60Arm_joint_{k}" for k in range(1, 7)]
    origins = [(0.070, 0.010, -0.413), (0.424, -0.210, -0.383), (-0.004, 0.060, -1.004),
               (0.491, 0.162, -0.169), (0.492, 0.068, 0.0), (0.152, -0.070, 0.0)]
    axes = [(0, 0, -1), (0, 1, 0), (0, 1, 0), (1, 0, 0), (0, -1, 0), (-1, 0, 0)]
    assert np.allclose([j.origin.xyz for j in joints], origins, atol=1e-9)
    assert np.allclose([j.axis for j in joints], axes, atol=1e-9)
    assert all(j.origin.rpy == (0.0, 0.0, 0.0) for j in joints)
    assert desc.chain.link("KR60Arm_link0").elements
    assert desc.chain.frames["flange"] == "KR60Arm_tip"
