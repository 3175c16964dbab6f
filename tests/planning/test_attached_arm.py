"""Arm.attach and Arm.detach, as the demo's cycle calls them: the part is picked from the
scene with the gripper as its touch link, it is no obstacle while carried and moves with the
TCP in every plan, and released it is an obstacle where it was put."""

from __future__ import annotations

import numpy as np
import pytest

from usar_arm import Arm
from usar_arm.core.attach_errors import AttachedCollisionError, AttachError
from usar_arm.core.errors import StartInCollisionError
from usar_arm.planning.scene import Box, Scene, SceneObject
from usar_arm.planning.scene_file import load_scene

from .attached_bodies import GRIPPER, KR60, TCP


@pytest.fixture
def arm() -> Arm:
    return Arm.from_files(KR60)


def _tcp_down(arm: Arm, xyz: tuple[float, float, float]) -> np.ndarray:
    """tool0's pose that puts the TCP at ``xyz`` pointing down."""
    offset = np.linalg.inv(arm.fk(arm.home)) @ arm.fk(arm.home, TCP)
    target = np.diag([1.0, -1.0, -1.0, 1.0])
    target[:3, 3] = xyz
    return target @ np.linalg.inv(offset)


def _sunk(scene: Scene, name: str, depth: float) -> Scene:
    """``scene`` with object ``name`` sunk ``depth`` m into what it stands on (as physics
    leaves a resting body)."""
    objects = []
    for o in scene.objects:
        if o.name == name:
            pose = o.pose.copy()
            pose[2, 3] -= depth
            o = SceneObject(o.name, o.shape, pose, o.allow)
        objects.append(o)
    return Scene(scene.name, tuple(objects))


def test_the_demo_picks_carries_and_places_the_part(arm: Arm) -> None:
    scene = _sunk(load_scene("table"), "part", 0.0003)  # (a simulator's resting part)
    part = scene.object("part")
    top = part.pose[:3, 3] + [0.0, 0.0, 0.05]
    q = arm.ik(_tcp_down(arm, tuple(top)), seed=arm.home).best.q
    with pytest.raises(StartInCollisionError, match="KR60gripper–part"):
        arm.plan(pose=_tcp_down(arm, (1.45, -0.45, 1.1)), motion="lin", scene=scene, start=q)
    body = arm.attach("part", link="KR60gripper_tcp", scene=scene, touch_links=("KR60gripper",),
                      q=q)
    assert arm.attached == (body,) and body.touch_links == (GRIPPER,)
    np.testing.assert_allclose(arm.fk(q, TCP) @ body.pose, part.pose, atol=1e-9)
    np.testing.assert_allclose(arm.fk(q, "part"), part.pose, atol=1e-9)
    assert "part" not in {o.name for o in arm.world(scene).scene.objects}
    assert arm.world(scene).contacts(q) == [("part", "table_top")]  # resting on its support
    lift = arm.plan(pose=_tcp_down(arm, (1.45, -0.45, 1.1)), motion="lin", scene=scene,
                    start=q)  # (off the table it rests on)
    assert lift.trajectory.info["attached"] == [{"name": "part", "link": TCP}]
    up = lift.trajectory.q[-1]
    np.testing.assert_allclose(arm.fk(up, "part")[:3, 3], [1.45, -0.45, 1.05], atol=1e-6)
    over = arm.plan(pose=_tcp_down(arm, (1.45, 0.5, 1.1)), scene=scene, start=up)
    world = arm.world(scene)
    assert not any(world.contacts_brute_force(x) for x in over.trajectory.q)
    assert ("part", "tower") in world.checked_pairs()
    down = arm.plan(pose=_tcp_down(arm, (1.45, 0.5, 0.83)), motion="lin", scene=scene,
                    start=over.trajectory.q[-1]).trajectory.q[-1]
    placed = arm.detach("part", q=down)
    assert arm.attached == () and "attached" not in arm.plan(
        joints=arm.home, scene=scene, start=arm.ik(_tcp_down(arm, (1.45, 0.5, 1.1)),
                                                   seed=down).best.q).trajectory.info
    np.testing.assert_allclose(placed.pose[:3, 3], [1.45, 0.5, 0.78], atol=1e-6)
    again = arm.world(scene).scene.object("part")
    np.testing.assert_allclose(again.pose, placed.pose)
    assert arm.world("table").scene.object("part").pose[2, 3] == pytest.approx(0.78, abs=1e-6)


def test_an_object_sunk_deeper_than_resting_is_refused(arm: Arm) -> None:
    scene = _sunk(load_scene("table"), "part", 0.005)
    top = scene.object("part").pose[:3, 3] + [0.0, 0.0, 0.05]
    q = arm.ik(_tcp_down(arm, tuple(top)), seed=arm.home).best.q
    with pytest.raises(AttachedCollisionError, match="part–table_top"):
        arm.attach("part", link=TCP, scene=scene, touch_links=(GRIPPER,), q=q)
    assert arm.attached == ()


def test_a_new_shape_needs_its_pose_and_names_are_checked(arm: Arm) -> None:
    box = Box((0.1, 0.1, 0.1))
    with pytest.raises(AttachError, match="needs its pose"):
        arm.attach("tray", TCP, shape=box)
    with pytest.raises(AttachError, match=r"no object of that name in scene .table..*known: floor"):
        arm.attach("cup", TCP, scene=load_scene("table"))
    with pytest.raises(AttachError, match="no link 'hand'"):
        arm.attach("tray", "hand", shape=box, pose=np.eye(4))
    grasp = np.eye(4)
    grasp[2, 3] = 0.1
    arm.attach("tray", TCP, shape=box, pose=grasp, touch_links=[GRIPPER])
    with pytest.raises(AttachError, match="carried already"):
        arm.attach("tray", TCP, shape=box, pose=grasp)
    with pytest.raises(AttachError, match=r"nothing of that name is carried.*known: tray"):
        arm.detach("cup")
    placed = arm.detach("tray")  # (offline: at home)
    np.testing.assert_allclose(placed.pose, arm.fk(arm.home, TCP) @ grasp, atol=1e-12)
    assert arm.world().scene.object("tray") is placed  # (an obstacle of every scene now)
    body = arm.attach("tray", TCP, touch_links=[GRIPPER])  # re-picked from where it was put
    np.testing.assert_allclose(body.pose, grasp, atol=1e-9)
