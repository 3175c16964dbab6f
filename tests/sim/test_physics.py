"""MuJoCo physics agrees with the robots' ground-truth kinematics, and the drives behave."""

from __future__ import annotations

import time

import numpy as np
import pytest

from usar_arm.core.errors import ConnectionLostError
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import builtin_robots, joint_frames, tip_pose
from usar_arm.sim.server import MAX_CONNECTIONS, SimOptions, SimServer
from usar_arm.usarsim.client import UsarClient

ROBOTS = builtin_robots()


@pytest.mark.parametrize("cls", sorted(ROBOTS))
def test_physics_bodies_follow_the_ground_truth_kinematics(cls: str) -> None:
    spec = ROBOTS[cls]
    act = spec.actuators[0]
    world = PhysicsWorld()
    world.add_robot("r", spec, (1.0, -2.0, 0.0), (0.0, 0.0, 0.7))
    rng = np.random.default_rng(7)
    for _ in range(50):
        q = [rng.uniform(j.limit_low, j.limit_high) for j in act.joints]
        world.set_joint_values("r", act.name, q)
        expected = world.platform_pose("r") @ act.mount() @ tip_pose(act, q)
        assert np.allclose(world.tip_pose("r", act.name), expected, atol=1e-9)
        assert np.allclose(world.joint_values("r", act.name), q, atol=1e-12)


def test_ground_truth_joint_axes_at_zero_are_the_directions() -> None:
    act = ROBOTS["USARBot.KR60"].actuators[0]
    frames = joint_frames(act, [0.0] * 6)
    axes = [f[:3, 2] for f in frames]
    expected = [(0, 0, -1), (0, 1, 0), (0, 1, 0), (1, 0, 0), (0, -1, 0), (-1, 0, 0)]
    assert np.allclose(axes, expected, atol=1e-3)


def test_gravity_leaves_a_small_steady_state_error_on_the_shoulder() -> None:
    act = ROBOTS["USARBot.KR60"].actuators[0]
    world = PhysicsWorld()
    world.add_robot("r", ROBOTS["USARBot.KR60"], (0, 0, 0), (0, 0, 0))
    target = [0.0, -1.0, 1.0, 0.0, 0.5, 0.0]
    world.set_joint_values("r", act.name, target)
    world.step(3000)
    err = np.abs(world.joint_values("r", act.name) - target)
    # A stiffness-only drive against the arm's weight: 4.79 mrad measured (deterministic
    # physics, 3,000 steps); the window is half to twice that.
    assert 2.4e-3 < err[1] < 9.6e-3
    world_off = PhysicsWorld(gravity=False)
    world_off.add_robot("r", ROBOTS["USARBot.KR60"], (0, 0, 0), (0, 0, 0))
    world_off.set_joint_values("r", act.name, target)
    world_off.step(3000)
    assert np.abs(world_off.joint_values("r", act.name) - target).max() < 1e-9


def test_removing_a_robot_keeps_the_others_state() -> None:
    spec = ROBOTS["USARBot.KR60"]
    world = PhysicsWorld()
    world.add_robot("a", spec, (0, 0, 0), (0, 0, 0))
    world.add_robot("b", spec, (3, 0, 0), (0, 0, 0))
    q = [0.3, -0.5, 0.4, 1.0, -0.7, 2.0]
    world.set_joint_values("b", "KR60Arm", q)
    world.remove_robot("a")
    assert world.robot_keys == ("b",)
    assert np.allclose(world.joint_values("b", "KR60Arm"), q)


def test_sixty_four_connections_each_with_a_robot_and_no_more() -> None:
    with SimServer(SimOptions(port=0)) as server:
        clients = []
        try:
            for _ in range(MAX_CONNECTIONS):
                c = UsarClient(port=server.port, timeout=10.0)
                c.connect()
                c.init("USARBot.KR60", start="RobotStart1")
                clients.append(c)
            for c in clients:
                c.wait_asta("KR60Arm", timeout=10.0)
            assert len(server.world.robot_keys) == MAX_CONNECTIONS
            extra = UsarClient(port=server.port, connect_timeout=2.0)
            with pytest.raises(ConnectionLostError):
                extra.connect()
            extra.close()
        finally:
            for c in clients:
                c.close()
        deadline = time.monotonic() + 5
        while server.world.robot_keys and time.monotonic() < deadline:
            time.sleep(0.05)
        assert server.world.robot_keys == ()
