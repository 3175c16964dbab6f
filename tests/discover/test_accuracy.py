"""A description learnt over the wire matches the simulator's ground truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from usar_arm.description import DescribeOptions
from usar_arm.embedded import accuracy_report, describe
from usar_arm.sim.robot_spec import builtin_robots

ROBOTS = ("KR60", "Fanuc_M16iB20")
SPECS = builtin_robots()


def _report(robot: str, precision: str) -> tuple[dict, object]:
    desc = describe(DescribeOptions(robot=robot, wire_precision=precision, acm_samples=200,
                                    accuracy_samples=0))
    act = SPECS[f"USARBot.{robot}"].actuators[0]
    return accuracy_report(desc.chain, act, "z-up", samples=1000, seed=11), desc


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_full_wire_precision_reproduces_the_simulator_model(robot: str) -> None:
    report, _ = _report(robot, "full")
    assert report["configurations"] >= 1000
    assert report["max_joint_origin_error_m"] < 1e-5  # 0.01 mm
    assert report["max_flange_error_m"] < 1e-5
    assert report["max_joint_axis_error_rad"] < 1e-5


@pytest.mark.slow
@pytest.mark.parametrize("robot", ROBOTS)
def test_udk_wire_is_as_accurate_as_its_rounding_allows(robot: str) -> None:
    report, desc = _report(robot, "udk")
    precision = desc.discovery["precision"]
    assert precision["location_resolution_m"] == 0.001
    assert precision["orientation_resolution_rad"] == 0.01
    n = len(desc.chain.joint_names)
    # Each joint's own axis, after snapping: within 0.001 rad.
    assert report["max_joint_axis_error_at_zero_pose_rad"] < 0.001
    # Compounded along the chain at random configurations: the simulator's directions are
    # 1.571 rad, not pi/2, which 2-decimal orientations cannot carry (~0.0003 rad per joint).
    assert report["max_joint_axis_error_rad"] < n * 0.0003
    # Origins: millimetre truncation per link along the chain, plus that axis error over the
    # arm's reach (2.5 m).
    bound = math.sqrt(3) * 0.001 * n + report["max_joint_axis_error_rad"] * 2.5
    assert report["max_joint_origin_error_m"] < bound
    # The flange also carries the Tip, printed with 2 decimals (0.048 -> 0.05).
    assert report["max_flange_error_m"] < bound + math.sqrt(3) * 0.005
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
    assert desc.chain.link("KR60Arm_link0").geometry is not None
    assert desc.chain.frames["flange"] == "KR60Arm_tip"
