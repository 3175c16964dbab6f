"""The Fanuc on its rail, worked out by hand from its spec (usar_arm/sim/robots/fanuc_m16ib20.yaml)
and compared with what discovery learns over a full-precision wire and with the simulator's own
tool point. Nothing here uses usar-arm's rotation helpers: the formulas are written out below.

The spec, in USARSim's frame (x forward, y right, z down), metres and radians: each joint has an
absolute offset p and a Direction (roll, pitch, yaw); its axis is R(Direction) (0, 0, 1) with
R = Rz(yaw) Ry(pitch) Rx(roll), i.e. for the unit z vector:

    axis = (cos y sin p cos r + sin y sin r,  sin y sin p cos r - cos y sin r,  cos p cos r)

A revolute joint turns everything after it about its axis through p; the prismatic carriage slides
everything after it along its axis. The Fanuc has no TipOffset: its tool point is the last joint's
anchor, (1.036, 0, -1.256). REP-103 (z up) is (x, -y, -z) for points and axes alike.
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions

# (type, offset p, Direction (roll, pitch, yaw)) of the seven joints, copied from the spec.
SPEC = [
    ("prismatic", (0.0, 0.0, 0.0), (0.0, 1.5707, 0.0)),
    ("revolute", (0.052, 0.0, -0.384), (3.142, 0.0, 0.0)),
    ("revolute", (0.204, -0.112, -0.384), (-1.571, 1.571, 0.0)),
    ("revolute", (0.2, -0.112, -1.156), (-1.571, 0.0, 0.0)),
    ("revolute", (0.384, 0.0, -1.256), (-1.571, 0.0, -1.571)),
    ("revolute", (0.944, 0.0, -1.256), (1.571, 0.0, 0.0)),
    ("revolute", (1.036, 0.0, -1.256), (1.571, 0.0, -1.571)),
]
TOOL_POINT = (1.036, 0.0, -1.256)
UP = np.diag([1.0, -1.0, -1.0])


def _axis(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch),
                              math.sin(pitch), math.cos(yaw), math.sin(yaw))
    return np.array([cy * sp * cr + sy * sr, sy * sp * cr - cy * sr, cp * cr])


def _turn(axis: np.ndarray, angle: float, v: np.ndarray) -> np.ndarray:
    """Rodrigues: v turned by ``angle`` about the unit ``axis``."""
    return (v * math.cos(angle) + np.cross(axis, v) * math.sin(angle)
            + axis * float(axis @ v) * (1.0 - math.cos(angle)))


def tool_point_by_hand(q: np.ndarray) -> np.ndarray:
    """The tool point (z up) at joint values ``q``: apply the joints from the last to the
    first to the points after them (each joint's own anchor moves only with the ones before)."""
    point = np.array(TOOL_POINT)
    for k in range(len(SPEC) - 1, -1, -1):
        kind, p, direction = SPEC[k]
        axis = _axis(*direction)
        if kind == "prismatic":
            point = point + axis * q[k]
        else:
            point = np.array(p) + _turn(axis, q[k], point - np.array(p))
    return UP @ point


def test_the_joint_axes_and_anchors_are_the_hand_derived_ones() -> None:
    desc = describe(DescribeOptions(robot="Fanuc_M16iB20", wire_precision="full",
                                    acm_samples=100, accuracy_samples=0))
    frames = [(j, f) for j, f in desc.chain.joint_frames(np.zeros(7)) if j.actuated]
    assert [j.type.value for j, _ in frames] == [kind for kind, _, _ in SPEC]
    for (joint, frame), (_, p, direction) in zip(frames, SPEC, strict=True):
        axis = frame[:3, :3] @ np.asarray(joint.axis)
        assert np.allclose(axis, UP @ _axis(*direction), atol=1e-9), joint.name
        # the joint's anchor lies on its axis through the spec's offset
        offset = frame[:3, 3] - UP @ np.array(p)
        assert np.linalg.norm(np.cross(offset, axis)) < 1e-9, joint.name


def test_the_learnt_tool_point_follows_the_hand_derivation() -> None:
    desc = describe(DescribeOptions(robot="Fanuc_M16iB20", wire_precision="full",
                                    acm_samples=100, accuracy_samples=0))
    chain = desc.chain
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(200):
        q = rng.uniform(chain.lower(), chain.upper())
        flange = chain.frame_pose("flange", q)[:3, 3]
        assert np.allclose(flange, tool_point_by_hand(q), atol=1e-9), q
        checked += 1
    # Two literal points as a sanity check of the derivation itself: at zero the tool point is
    # the last anchor flipped to z up; with the carriage at 0.5 m it is 0.5 m further along
    # the carriage's axis (cos(1.5707) = 9.63e-5 of it along z).
    assert np.allclose(tool_point_by_hand(np.zeros(7)), (1.036, 0.0, 1.256), atol=1e-12)
    moved = tool_point_by_hand(np.array([0.5, 0, 0, 0, 0, 0, 0]))
    assert np.allclose(moved, (1.536, 0.0, 1.256 - 0.5 * math.cos(1.5707)), atol=1e-9)
    assert checked == 200
