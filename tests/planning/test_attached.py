"""Planning with what the arm carries: an attached body is checked with the arm in every path
(single, batch and segment verdicts against brute force), moves with its link, refuses to be
attached in collision, and its touch links are never checked against it."""

from __future__ import annotations

import numpy as np
import pytest

from usar_arm.core.attach_errors import AttachedCollisionError, AttachError
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Box
from usar_arm.planning.scene_file import load_scene

from .attached_bodies import GRIPPER, TCP, bar, body, kr60

KINDS = ("box", "cylinder", "sphere", "mesh")


@pytest.fixture(scope="module")
def arm() -> Robot:
    return kr60()


@pytest.mark.parametrize("scene_name", ["table", "cage"])
@pytest.mark.parametrize("kind", KINDS)
def test_verdicts_with_a_carried_body_agree_with_brute_force(arm: Robot, kind: str,
                                                             scene_name: str) -> None:
    """2000 random configurations: batch, single and segment verdicts are the brute-force
    answer (every pair with FCL), so nothing the carried body touches is missed or
    invented; and the body does touch both the arm's links and the scene's obstacles."""
    carried = arm.carrying([body(kind)])
    world = carried.collision_world(load_scene(scene_name))
    rng = np.random.default_rng(36 + KINDS.index(kind))
    qs = rng.uniform(arm.chain.lower(), arm.chain.upper(), size=(2000, arm.chain.dof))
    truth = [world.contacts_brute_force(q) for q in qs]
    assert world.contacts_many(qs) == truth
    assert world.in_collision_many(qs).tolist() == [bool(t) for t in truth]
    for q, expected in zip(qs[:300], truth[:300], strict=True):
        assert world.contacts(q) == expected
        assert world.in_collision(q) == bool(expected)
    obstacles = {o.name for o in world.scene.objects}
    touched = {b if a == "part" else a for t in truth for a, b in t if "part" in (a, b)}
    assert touched & obstacles and touched - obstacles, touched  # links and obstacles both
    for a, b in qs[300:500].reshape(-1, 2, arm.chain.dof):  # 100 segments of 8 steps
        steps = np.linspace(a, b, 9)
        free = not any(world.contacts_brute_force(q) for q in steps)
        assert world.segment_free(a, b, 8) == free


def test_the_body_moves_with_its_link(arm: Robot) -> None:
    held = body("box")
    carried = arm.carrying([held])
    for q in np.random.default_rng(1).uniform(arm.chain.lower(), arm.chain.upper(), (20, 6)):
        expected = arm.kinematics.frame_pose(q, TCP) @ held.pose
        np.testing.assert_allclose(carried.kinematics.frame_pose(q, "part"), expected,
                                   atol=1e-12)
        np.testing.assert_allclose(carried.chain.frame_pose("part", q), expected, atol=1e-12)
    assert len(carried.carried) == 1 and carried.carried[0].same_as(held)
    assert carried.bare is arm
    assert carried.chain.joint_names == arm.chain.joint_names
    assert arm.carrying([held]) is carried  # (cached per set of bodies)
    assert arm.carrying([]) is arm and carried.carrying([]) is arm


def test_touch_links_and_the_parent_are_never_checked_against_it(arm: Robot) -> None:
    """A body sunk 10 mm into the gripper: with the gripper as a touch link it is attachable
    and no checked pair names it; without, the attachment is refused naming the pair."""
    q = np.array(arm.home())
    deep = np.eye(4)
    deep[2, 3] = 0.03  # (the gripper's geometry reaches 10 mm past its suction point)
    inside = AttachedBody("part", TCP, Box((0.12, 0.12, 0.1)), deep, (GRIPPER,))
    carried = arm.carrying([inside])
    world = carried.collision_world()
    assert ("KR60gripper", "part") not in world.checked_pairs()
    assert all("part" not in p or TCP not in p for p in world.checked_pairs())
    assert world.contacts(q) == world.contacts_brute_force(q) == []
    arm.check_attachable(inside, q)
    bare = AttachedBody("part", TCP, inside.shape, deep)
    with pytest.raises(AttachedCollisionError) as info:
        arm.check_attachable(bare, q)
    assert info.value.contacts[0][:2] == ("part", GRIPPER) and info.value.contacts[0][2] > 0.005
    assert "part–KR60gripper" in str(info.value)


def test_attaching_into_an_obstacle_is_refused_naming_the_pair(arm: Robot) -> None:
    scene = load_scene("table")
    q = np.array(arm.home())
    tcp = arm.kinematics.frame_pose(q, TCP)
    grasp = np.linalg.inv(tcp) @ scene.object("tower").pose  # the body inside the tower
    with pytest.raises(AttachedCollisionError) as info:
        arm.check_attachable(AttachedBody("part", TCP, Box((0.1, 0.1, 0.1)), grasp), q, scene)
    assert ("part", "tower") == info.value.contacts[0][:2]
    # the scene's own object of the body's name is the one being attached: never an obstacle;
    # resting on the table, the part touches it (Arm.attach takes that for its support)
    part = scene.object("part")
    resting = AttachedBody("part", TCP, part.shape, np.linalg.inv(tcp) @ part.pose)
    with pytest.raises(AttachedCollisionError) as info:
        arm.check_attachable(resting, q, scene)
    assert [c[:2] for c in info.value.contacts] == [("part", "table_top")]
    assert info.value.contacts[0][2] < 1e-3
    lifted = np.linalg.inv(tcp) @ part.pose
    lifted[:3, 3] += np.linalg.inv(tcp)[:3, :3] @ [0.0, 0.0, 0.001]  # 1 mm up
    arm.check_attachable(AttachedBody("part", TCP, part.shape, lifted), q, scene)


def test_unknown_links_and_name_clashes_are_errors_naming_the_valid_names(arm: Robot) -> None:
    box = Box((0.1, 0.1, 0.1))
    with pytest.raises(AttachError, match=r"no link .gripper..*known: base_link, base, link_1"):
        arm.carrying([AttachedBody("part", "gripper", box)])
    with pytest.raises(AttachError, match=r"'link_3'.*already one of the robot's links"):
        arm.carrying([AttachedBody("link_3", TCP, box)])
    with pytest.raises(AttachError, match="two carried objects have that name"):
        arm.carrying([AttachedBody("part", TCP, box), AttachedBody("part", "tool0", box)])
    with pytest.raises(AttachError, match="no link 'finger' among its touch links"):
        arm.carrying([AttachedBody("part", TCP, box, touch_links=("finger",))])
    with pytest.raises(AttachError, match="finite 4x4"):
        AttachedBody("part", TCP, box, np.eye(3))
    stacked = arm.carrying([AttachedBody("tray", TCP, box),
                            AttachedBody("cup", "tray", box, touch_links=("tray",))])
    assert stacked.chain.link("cup") and ("cup", "tray") in stacked.disabled


def test_a_long_bar_changes_the_plan_and_its_path_is_free_with_it(arm: Robot) -> None:
    """PTP from home: the bare arm goes straight; that path sweeps the carried bar through
    something, and the plan made carrying it goes round (every sample free by brute force)."""
    from usar_arm.control.motion import MotionOptions, plan_motion

    scene = load_scene("table")
    carried = arm.carrying([bar(1.2)])
    bare_world, world = arm.collision_world(scene), carried.collision_world(scene)
    start = np.array(arm.home())
    goal = np.array([2.732, 0.064, -2.081, -0.649, 0.726, 0.083])
    straight = plan_motion(arm, bare_world, start, goal=goal, options=MotionOptions())
    assert world.in_collision_many(straight.trajectory.q).any()
    plan = plan_motion(carried, world, start, goal=goal, options=MotionOptions())
    assert not any(world.contacts_brute_force(q) for q in plan.trajectory.q)
    assert len(plan.trajectory.waypoints) > len(straight.trajectory.waypoints)


def _hanging(length: float) -> AttachedBody:
    """A bar hanging ``length`` m below the suction point (along the TCP's z axis)."""
    pose = np.eye(4)
    pose[2, 3] = length / 2
    return AttachedBody("bar", TCP, Box((0.04, 0.04, length)), pose, (GRIPPER,))


def _tcp_down(arm: Robot, xyz: tuple[float, float, float]) -> np.ndarray:
    """tool0's pose that puts the TCP at ``xyz`` pointing down."""
    q = np.array(arm.home())
    offset = np.linalg.inv(arm.kinematics.frame_pose(q, "tool0")) @ arm.kinematics.frame_pose(
        q, TCP)
    target = np.diag([1.0, -1.0, -1.0, 1.0])
    target[:3, 3] = xyz
    return target @ np.linalg.inv(offset)


def test_lin_carries_the_bar_down_to_the_table_and_no_further(arm: Robot) -> None:
    from usar_arm.core.errors import LinBlockedError
    from usar_arm.planning.lin import LinOptions, plan_lin

    scene = load_scene("table")
    carried = arm.carrying([_hanging(0.3)])
    world = carried.collision_world(scene)
    ik = carried.ik_solver()
    start_pose = _tcp_down(arm, (1.8, 0.35, 1.3))
    start = np.array(ik.solve(start_pose, np.array(arm.home()), collision=world).best.q)
    fine = plan_lin(ik, world, start, start_pose, _tcp_down(arm, (1.8, 0.35, 1.05)),
                    LinOptions())
    assert not any(world.contacts_brute_force(q) for q in fine.q)
    deep = _tcp_down(arm, (1.8, 0.35, 0.9))  # the bar's end 0.1 m into the table
    with pytest.raises(LinBlockedError, match="bar"):
        plan_lin(ik, world, start, start_pose, deep, LinOptions())
    plan_lin(arm.ik_solver(), arm.collision_world(scene), start, start_pose, deep,
             LinOptions())  # (the bare arm goes there)


def test_ik_refuses_solutions_where_only_the_carried_body_collides(arm: Robot) -> None:
    from usar_arm.core.errors import AllSolutionsInCollisionError

    scene = load_scene("table")
    pose = _tcp_down(arm, (1.8, 0.35, 0.9))
    bare = arm.ik_solver().solve(pose, all_solutions=True,
                                   collision=arm.collision_world(scene))
    assert bare.solutions
    carried = arm.carrying([_hanging(0.3)])
    with pytest.raises(AllSolutionsInCollisionError) as info:
        carried.ik_solver().solve(pose, all_solutions=True,
                                  collision=carried.collision_world(scene))
    assert all("bar" in p for p in info.value.pairs) and ("bar", "table_top") in info.value.pairs
