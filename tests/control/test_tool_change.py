"""A tool change changes the robot the planner plans for: once the KR60's tool changer lets its
vacuum gripper go (``SET {Type ToolChanger} {Name toolchange} {Opcode OPEN}``, confirmed by its
EFF), the gripper's links are no longer checked (nor its TCP a frame); picked up again
(``CLOSE`` within the changer's tolerance), they are. Over real TCP, on the embedded simulator."""

from __future__ import annotations

import numpy as np
import pytest

from usar_arm.arm.cycle import TOOL_DOWN, tcp_offset
from usar_arm.arm.facade import Arm
from usar_arm.core.spatial import invert, transform
from usar_arm.planning.scene import Scene
from usar_arm.planning.scene_file import load_scene
from usar_arm.planning.tool_change import tool_links, without_tool

pytestmark = pytest.mark.xdist_group("pick-place")

SPOT = (1.75, -0.60)
"""A free spot of the table (x, y; m): clear of the part, the tower, the bin and the fixture."""


def _tool_pose(arm: Arm, z: float) -> np.ndarray:
    """tool0's pose putting the suction cup at ``z`` (m) over :data:`SPOT`, pointing down."""
    out: np.ndarray = transform(TOOL_DOWN, (*SPOT, z)) @ invert(tcp_offset(arm.robot))
    return out


def test_without_the_tool_the_links_below_the_changer_are_gone_and_the_rest_is_kept() -> None:
    robot = Arm.from_files("robots/generated/KR60.urdf").robot
    bare = without_tool(robot)
    assert tool_links(robot.chain, "toolchange") == {"KR60gripper", "KR60gripper_tcp"}
    names = {lk.name for lk in bare.chain.links}
    assert "toolchange" in names and not names & {"KR60gripper", "KR60gripper_tcp"}
    assert "tcp" not in bare.chain.frames and bare.chain.frames["tool0"] == "tool0"
    assert all("KR60gripper" not in p for p in bare.disabled)
    assert bare.chain.joint_names == robot.chain.joint_names
    assert without_tool(robot) is bare and without_tool(bare) is bare
    q = np.random.default_rng(3).uniform(robot.chain.lower(), robot.chain.upper(), (50, 6))
    for x in q:  # the arm's own kinematics is untouched
        assert np.allclose(bare.kinematics.frame_pose(x, "tool0"),
                           robot.kinematics.frame_pose(x, "tool0"), atol=1e-12)


def test_a_tool_change_over_the_wire_changes_the_planning_robot() -> None:
    scene = load_scene("table")
    table = Scene("table, no objects", tuple(o for o in scene.objects
                                             if o.name != "part" and not o.name.startswith("bin")))
    with Arm.connect("KR60", wire_precision="full") as arm:
        assert arm.client is not None
        client = arm.client
        low = arm.ik(_tool_pose(arm, 0.70), seed=arm.home).best.q  # the cup on the table
        assert arm.world(table).in_collision(low)  # the gripper is in the table
        above = _tool_pose(arm, 0.72)  # its tip 1 cm above the table
        arm.execute(arm.plan(pose=above, scene=table).trajectory)
        client.set_effector("ToolChanger", "toolchange", "OPEN")
        client.wait_effector("toolchange", "OPEN", timeout=5.0)
        robot = arm.planning_robot
        assert "KR60gripper" not in {lk.name for lk in robot.chain.links}
        assert not arm.world(table).in_collision(low)  # no gripper, nothing to collide
        # up 5 cm (the gripper stands on the table below), and pick it up again
        arm.execute(arm.plan(pose=_tool_pose(arm, 0.77), motion="lin",
                             scene=table).trajectory)
        client.set_effector("ToolChanger", "toolchange", "CLOSE")
        closed = client.wait_effector("toolchange", "CLOSED", timeout=5.0)
        assert closed.get("Tool") == "KR60gripper"
        assert "KR60gripper" in {lk.name for lk in arm.planning_robot.chain.links}
        assert arm.world(table).in_collision(low)
