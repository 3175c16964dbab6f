# ruff: noqa: E501  (the test robot's URDF reads best one element per line)
"""Robot-robot pairs proven never in contact (usar_arm/planning/never.py): the proof against an
independent sweep, and the pairs it must leave checked."""

from __future__ import annotations

from pathlib import Path

import fcl
import numpy as np
import pytest

from usar_arm.planning.never import STEP
from usar_arm.planning.robot import robot_from_files

URDF = """<?xml version="1.0"?>
<robot name="wrist">
  <link name="base_link"/>
  <link name="upper">
    <collision><origin xyz="0 0 0.2"/><geometry><box size="0.1 0.1 0.4"/></geometry></collision>
  </link>
  <link name="lower">
    <collision><origin xyz="0 0 0.1"/><geometry><cylinder radius="0.03" length="0.2"/></geometry></collision>
  </link>
  <link name="tool">
    <collision><origin xyz="{x} 0 0"/><geometry><box size="0.02 0.02 0.02"/></geometry></collision>
  </link>
  <joint name="j1" type="revolute">
    <parent link="base_link"/><child link="upper"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/>
  </joint>
  <joint name="j2" type="revolute">
    <origin xyz="0 0 0.45"/><parent link="upper"/><child link="lower"/><axis xyz="1 0 0"/>
    <limit lower="-{reach}" upper="{reach}" effort="1" velocity="1"/>
  </joint>
  <joint name="tool_joint" type="fixed">
    <origin xyz="0 0 0.2"/><parent link="lower"/><child link="tool"/>
  </joint>
</robot>
"""
SRDF = """<?xml version="1.0"?>
<robot name="wrist">
  <group name="arm"><chain base_link="base_link" tip_link="tool"/></group>
  <disable_collisions link1="upper" link2="lower" reason="Adjacent"/>
  <disable_collisions link1="lower" link2="tool" reason="Adjacent"/>
</robot>
"""


def _robot(tmp_path: Path, reach: float, x: float = 0.0):  # type: ignore[no-untyped-def]
    urdf, srdf = tmp_path / "wrist.urdf", tmp_path / "wrist.srdf"
    urdf.write_text(URDF.format(reach=reach, x=x))
    srdf.write_text(SRDF)
    return robot_from_files(urdf, srdf)


def _sweep_clearance(reach: float, x: float) -> float:
    """The tool box's least distance to the upper box over j2's range, 0.0005 rad apart, by
    python-fcl on shapes and poses written here from the URDF's numbers."""
    upper = fcl.CollisionObject(fcl.Box(0.1, 0.1, 0.4), fcl.Transform(np.eye(3), [0, 0, 0.2]))
    tool = fcl.CollisionObject(fcl.Box(0.02, 0.02, 0.02), fcl.Transform())
    least = np.inf
    for angle in np.arange(-reach, reach + 5e-4, 5e-4):
        c, s = np.cos(angle), np.sin(angle)
        rot = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        tool.setTransform(fcl.Transform(rot, np.array([0.0, 0.0, 0.45]) + rot @ [x, 0, 0.2]))
        least = min(least, fcl.distance(upper, tool, fcl.DistanceRequest(),
                                        fcl.DistanceResult()))
    return float(least)


def test_a_tool_that_one_joint_swings_clear_of_the_link_before_it_is_proven(
        tmp_path: Path) -> None:
    robot = _robot(tmp_path, reach=1.5)
    world = robot.collision_world()
    assert ("tool", "upper") in world.never
    assert _sweep_clearance(1.5, 0.0) > 0.005  # the independent sweep agrees: never closer
    qs = np.random.default_rng(2).uniform(robot.chain.lower(), robot.chain.upper(), (200, 2))
    assert not world.in_collision_many(qs).any()


@pytest.mark.parametrize("reach", [2.9, 3.0])
def test_a_tool_that_can_reach_the_link_before_it_stays_checked(tmp_path: Path,
                                                                 reach: float) -> None:
    """j2 folds the tool onto the upper box: in contact at the range's ends, so no proof, and
    the contact is found."""
    assert _sweep_clearance(reach, 0.0) <= 0.0
    robot = _robot(tmp_path, reach=reach)
    world = robot.collision_world()
    assert ("tool", "upper") not in world.never
    assert world.in_collision(np.array([0.0, reach]))


def test_a_clearance_within_the_bound_of_the_samples_is_no_proof(tmp_path: Path) -> None:
    """Clear everywhere, but by less than the reach times half the sampling step: the pair
    stays checked (the proof needs a margin, not luck)."""
    reach = 2.8
    clearance = _sweep_clearance(reach, 0.0)
    assert 0.0 < clearance < 0.2 * STEP / 2  # (the tool's centre is 0.2 m from j2's axis)
    assert ("tool", "upper") not in _robot(tmp_path, reach=reach).collision_world().never


def test_the_proof_is_made_once_per_robot_and_skips_the_pairs_the_srdf_disables(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from usar_arm.core.shapes import Sphere
    from usar_arm.planning.collision import CollisionWorld
    from usar_arm.planning.scene import Scene, SceneObject

    proofs: list[int] = []
    prove = CollisionWorld._prove_never
    monkeypatch.setattr(CollisionWorld, "_prove_never",
                        lambda self, disabled: proofs.append(1) or prove(self, disabled))
    robot = _robot(tmp_path, reach=1.5)
    first = robot.collision_world()
    ball = Scene("ball", (SceneObject("ball", Sphere(0.05), np.eye(4)),))
    second = robot.collision_world(ball)
    assert len(proofs) == 1 and second.never == first.never
    assert ("lower", "upper") not in first.never  # the SRDF disables it: not worth a proof
    robot.collision_world(padding=0.01)  # other shapes: proven again
    assert len(proofs) == 2
