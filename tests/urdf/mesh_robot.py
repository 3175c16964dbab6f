# ruff: noqa: E501  (the test robot's URDF reads best one element per line)
"""A small arm written for the tests: a ROS-style package folder with STL and OBJ collision
meshes made by trimesh (one concave: a ring), boxes, spheres, a capsule, several collision
elements on one link, scaled meshes, a gripper branch with a mimic joint, and an SRDF."""

from __future__ import annotations

from pathlib import Path

import trimesh

PACKAGE = "toy_arm_description"


def write_meshes(folder: Path) -> None:
    """meshes/ring.stl (concave), meshes/rod.obj, meshes/cup.stl (concave, scaled in use)."""
    folder.mkdir(parents=True, exist_ok=True)
    trimesh.creation.annulus(r_min=0.03, r_max=0.06, height=0.08).export(folder / "ring.stl")
    rod = trimesh.creation.box(extents=(0.05, 0.05, 0.30))
    rod.apply_translation((0.0, 0.0, 0.15))
    rod.export(folder / "rod.obj")
    cup = trimesh.creation.annulus(r_min=0.6, r_max=0.9, height=1.0)  # scaled by 0.05 in use
    cup.export(folder / "cup.stl")


URDF = """<?xml version="1.0"?>
<robot name="toy">
  <link name="base_link">
    <collision><geometry><mesh filename="package://{pkg}/meshes/ring.stl"/></geometry></collision>
  </link>
  <link name="link_1">
    <collision><origin xyz="0 0 0.1" rpy="0 0 0"/><geometry><cylinder radius="0.04" length="0.2"/></geometry></collision>
  </link>
  <link name="link_2">
    <collision><geometry><mesh filename="package://{pkg}/meshes/rod.obj"/></geometry></collision>
    <collision><origin xyz="0 0 0.3" rpy="0.3 0 0"/><geometry><sphere radius="0.045"/></geometry></collision>
  </link>
  <link name="link_3">
    <collision><origin xyz="0 0 0.12" rpy="0 0.2 0"/><geometry><box size="0.04 0.06 0.24"/></geometry></collision>
    <collision><origin xyz="0.05 0 0.2" rpy="0 0 0"/><geometry><capsule radius="0.02" length="0.08"/></geometry></collision>
  </link>
  <link name="link_4">
    <collision><origin xyz="0 0 0.04" rpy="1.2 0 0"/><geometry><mesh filename="file://{folder}/meshes/cup.stl" scale="0.05 0.05 0.05"/></geometry></collision>
  </link>
  <link name="tool0"/>
  <link name="finger_l">
    <collision><origin xyz="0 0 0.02" rpy="0 0 0"/><geometry><box size="0.01 0.02 0.04"/></geometry></collision>
  </link>
  <link name="finger_r">
    <collision><origin xyz="0 0 0.02" rpy="0 0 0"/><geometry><box size="0.01 0.02 0.04"/></geometry></collision>
  </link>
  <joint name="joint_1" type="revolute">
    <origin xyz="0 0 0.05" rpy="0 0 0"/><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="10" velocity="2"/>
  </joint>
  <joint name="joint_2" type="revolute">
    <origin xyz="0 0 0.2" rpy="0 0 0"/><parent link="link_1"/><child link="link_2"/>
    <axis xyz="0 1 0"/><limit lower="-2.5" upper="2.5" effort="10" velocity="2"/>
  </joint>
  <joint name="joint_3" type="continuous">
    <origin xyz="0 0 0.3" rpy="0 0 0"/><parent link="link_2"/><child link="link_3"/>
    <axis xyz="0 1 0"/><limit effort="10" velocity="2"/>
  </joint>
  <joint name="joint_4" type="prismatic">
    <origin xyz="0 0 0.24" rpy="0 0 0"/><parent link="link_3"/><child link="link_4"/>
    <axis xyz="0 0 1"/><limit lower="0" upper="0.1" effort="10" velocity="0.5"/>
  </joint>
  <joint name="tool0_joint" type="fixed">
    <origin xyz="0 0 0.08" rpy="0 0 0"/><parent link="link_4"/><child link="tool0"/>
  </joint>
  <joint name="finger_l_joint" type="prismatic">
    <origin xyz="0 0.03 0.06" rpy="0 0 0"/><parent link="link_4"/><child link="finger_l"/>
    <axis xyz="0 1 0"/><limit lower="0.01" upper="0.03" effort="1" velocity="0.1"/>
  </joint>
  <joint name="finger_r_joint" type="prismatic">
    <origin xyz="0 -0.03 0.06" rpy="0 0 0"/><parent link="link_4"/><child link="finger_r"/>
    <axis xyz="0 -1 0"/><limit lower="0.01" upper="0.03" effort="1" velocity="0.1"/>
    <mimic joint="finger_l_joint" multiplier="1" offset="0"/>
  </joint>
</robot>
"""

SRDF = """<?xml version="1.0"?>
<robot name="toy">
  <group name="arm"><chain base_link="base_link" tip_link="tool0"/></group>
  <group name="wrist"><joint name="joint_4"/><joint name="joint_3"/></group>
  <group name="gripper"><joint name="finger_l_joint"/></group>
  <group name="forearm"><link name="link_3"/><link name="link_4"/></group>
  <group name="typo"><joint name="joint_3"/><joint name="joint_44"/></group>
  <disable_collisions link1="base_link" link2="link_1" reason="Adjacent"/>
  <disable_collisions link1="link_1" link2="link_2" reason="Adjacent"/>
  <disable_collisions link1="link_2" link2="link_3" reason="Adjacent"/>
  <disable_collisions link1="link_3" link2="link_4" reason="Adjacent"/>
  <disable_collisions link1="finger_l" link2="link_4" reason="Adjacent"/>
  <disable_collisions link1="finger_r" link2="link_4" reason="Adjacent"/>
</robot>
"""
DISABLED = {("base_link", "link_1"), ("link_1", "link_2"), ("link_2", "link_3"),
            ("link_3", "link_4"), ("finger_l", "link_4"), ("finger_r", "link_4")}


def write_robot(root: Path) -> tuple[Path, Path]:
    """The package under ``root / 'ws' / PACKAGE`` (urdf/toy.urdf, meshes/, srdf beside the
    URDF): the URDF's and the SRDF's paths."""
    pkg = root / "ws" / PACKAGE
    write_meshes(pkg / "meshes")
    (pkg / "urdf").mkdir(parents=True, exist_ok=True)
    urdf = pkg / "urdf" / "toy.urdf"
    urdf.write_text(URDF.format(pkg=PACKAGE, folder=pkg))
    srdf = pkg / "urdf" / "toy.srdf"
    srdf.write_text(SRDF)
    return urdf, srdf
