"""The embedded simulator speaks the UDK protocol: what a client sees over TCP."""

from __future__ import annotations

import re
import socket
import time

import numpy as np
import pytest

from usar_arm.core.errors import UnknownComponentError, UnknownRobotError
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient

# UDK's KR60 numbers (docs/protocol.md sections 6 and 7) as UDK prints them.
KR60_CONF = (
    "CONF {Type Actuator} {Name KR60Arm} "
    "{Link 1} {JointType Revolute} {MaxTorque 600.0000} {MinValue -3.1400} {MaxValue 3.1400} "
    "{Link 2} {JointType Revolute} {MaxTorque 1500.0000} {MinValue -2.3560} {MaxValue 0.6100} "
    "{Link 3} {JointType Revolute} {MaxTorque 700.0000} {MinValue -2.0940} {MaxValue 2.7570} "
    "{Link 4} {JointType Revolute} {MaxTorque 100.0000} {MinValue -3.1400} {MaxValue 3.1400} "
    "{Link 5} {JointType Revolute} {MaxTorque 60.0000} {MinValue -2.0760} {MaxValue 2.0760} "
    "{Link 6} {JointType Revolute} {MaxTorque 25.0000} {MinValue -3.1400} {MaxValue 3.1400}")
KR60_GEO = (
    "GEO {Type Actuator} {Name KR60Arm} {Location 0.000,0.000,0.000} "
    "{Orientation 0.000,0.000,0.000}{Mount KR60} "
    "{Link 1} {Parent 0} {Location 0.070,0.010,-0.413} {Orientation 3.14,0.00,0.00} "
    "{Link 2} {Parent 1} {Location 0.424,-0.210,-0.383} {Orientation -2.00,-1.57,-2.71} "
    "{Link 3} {Parent 2} {Location -0.004,0.060,-1.004} {Orientation 0.00,0.00,-1.57} "
    "{Link 4} {Parent 3} {Location 0.491,0.162,-0.169} {Orientation 2.36,1.57,2.36} "
    "{Link 5} {Parent 4} {Location 0.492,0.068,0.000} {Orientation -0.79,-1.57,-2.36} "
    "{Link 6} {Parent 5} {Location 0.152,-0.070,0.000} {Orientation -2.36,-1.57,2.36}"
    "{Tip 0.05,0.00,0.00}")
"""UDK's GEO of the KR60 character by character: locations are the differences of the spec's
offsets truncated to 3 decimals (the reference's -1.004 for a true -1.005), orientations the
relative rotations of the spec's Directions to 2 decimals (checked below by hand), Tip 0.048 at
2 decimals, no space before {Mount or {Tip."""
KR60_DIRECTIONS = [(3.1415, 0, 0), (-1.571, 1.571, 0), (-1.571, 0, 0), (-1.571, 0, -1.571),
                   (1.571, 0, 0), (1.571, 0, -1.571)]
"""The joints' absolute Directions (roll, pitch, yaw) in kr60Arm.uc."""
KR60_AXES_ZDOWN = [(0, 0, -1), (0, 1, 0), (0, 1, 0), (1, 0, 0), (0, -1, 0), (-1, 0, 0)]


def _rpy(r: float, p: float, y: float) -> np.ndarray:
    """R = Rz(y) Ry(p) Rx(r), written out (no usar-arm helper)."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1)))


def spawn(port: int, cls: str = "USARBot.KR60", timeout: float = 3.0) -> UsarClient:
    client = UsarClient(port=port, timeout=timeout)
    client.connect()
    client.spawn(cls, start="RobotStart1")
    return client


def test_nfo_on_connect_and_at_least_two_start_poses(sim: SimServer) -> None:
    with UsarClient(port=sim.port) as client:
        assert client.game_info is not None and client.game_info.level == "usar-arm-cell"
        poses = client.get_start_poses()
    assert len(poses.poses) >= 2 and poses.names[0] == "RobotStart1"


def test_kr60_conf_and_geo_are_the_reference_numbers(sim: SimServer) -> None:
    with spawn(sim.port) as client:
        conf_line = client.request(m.GetConf("Actuator", "KR60Arm"),
                                   lambda x: isinstance(x, m.Conf)).line
        geo_line = client.request(m.GetGeo("Actuator", "KR60Arm"),
                                  lambda x: isinstance(x, m.Geo)).line
        platform = client.get_conf("Robot")
        platform_geo = client.get_geo("Robot")
    assert conf_line == KR60_CONF
    assert geo_line == KR60_GEO
    # Each printed orientation is the relative rotation of the spec's Directions (parent^T
    # child) to within its 2 decimals, and accumulating them gives each joint's axis.
    printed = [tuple(float(v) for v in block.split(","))
               for block in re.findall(r"\{Link \d\} \{Parent \d\} \{Location [^}]*\} "
                                       r"\{Orientation ([^}]*)\}", geo_line)]
    parent = np.eye(3)
    absolute = np.eye(3)
    for rpy, direction, axis in zip(printed, KR60_DIRECTIONS, KR60_AXES_ZDOWN, strict=True):
        child = _rpy(*direction)
        assert _angle(_rpy(*rpy), parent.T @ child) < 0.01, rpy
        parent = child
        absolute = absolute @ _rpy(*rpy)
        assert np.allclose(absolute[:, 2], axis, atol=0.02)
    assert platform == m.PlatformConf("KR60", "StaticPlatform",
                                      (("SteeringType", "None"), ("Mass", "0")))
    assert platform_geo == m.Geo("StaticPlatform", (m.GeoItem("KR60"),))


def test_full_wire_precision_sends_exact_numbers() -> None:
    with SimServer(SimOptions(port=0, wire_precision="full")) as server, \
            spawn(server.port) as client:
        geo = client.get_geo("Actuator", "KR60Arm")
    assert geo.items[0].links[2].location[2] == pytest.approx(-1.005, abs=1e-12)
    assert geo.items[0].tip == (0.048, 0.0, 0.0)


def test_groundtruth_conf_and_geo_with_and_without_name(sim: SimServer) -> None:
    with spawn(sim.port) as client:
        every = client.get_conf("GroundTruth")
        tip = client.get_geo("GroundTruth", "kr60armtiptruth")  # names match case-insensitively
        with pytest.raises(UnknownComponentError):
            client.get_geo("GroundTruth", "NoSuchSensor", timeout=0.5)
    assert isinstance(every, m.Conf)
    assert [i.name for i in every.items] == ["GroundTruth", "KR60ArmTipTruth"]
    assert tip.items[0].mount == "KR60Arm" and tip.items[0].mount_link == 6


def test_status_streams_arrive_at_10_hz_of_simulated_time(sim: SimServer) -> None:
    times: list[float] = []
    with spawn(sim.port) as client:
        client.subscribe(lambda r: times.append(r.message.time)
                         if isinstance(r.message, m.Asta) else None)
        time.sleep(0.65)
        assert client.latest_sen("GroundTruth") is not None
        assert client.latest_sen("KR60ArmTipTruth") is not None
    steps = np.diff(times)
    assert len(times) >= 4 and np.allclose(steps, 0.1, atol=0.006)


def test_act_link_0_moves_the_joint_asta_reports_as_link_1(fast_sim: SimServer) -> None:
    with spawn(fast_sim.port) as client:
        client.act("KR60Arm", {0: 0.4})
        t0 = client.wait_asta("KR60Arm").time
        asta = client.wait_asta("KR60Arm", after_time=t0 + 1.5, timeout=5)
    q = dict(asta.values)
    assert q[1] == pytest.approx(0.4, abs=2e-3)
    assert abs(q[2]) < 0.02 and abs(q[4]) < 1e-3 and abs(q[6]) < 1e-3


def test_targets_beyond_the_limits_are_clamped(fast_sim: SimServer) -> None:
    with spawn(fast_sim.port) as client:
        client.act("KR60Arm", {1: 5.0, 4: -9.0})  # J2 max 0.61, J5 min -2.076
        t0 = client.wait_asta("KR60Arm").time
        asta = client.wait_asta("KR60Arm", after_time=t0 + 2.5, timeout=5)
    q = dict(asta.values)
    assert q[2] == pytest.approx(0.61, abs=0.02)
    assert q[5] == pytest.approx(-2.076, abs=0.01)


def test_a_joint_settles_on_its_target_as_a_first_order_drive() -> None:
    # No gravity: the drive (stiffness 600, damping 100) is a first-order lag with tau = 1/6 s.
    with SimServer(SimOptions(port=0, speed=4.0, gravity=False)) as server, \
            spawn(server.port) as client:
        client.act("KR60Arm", {0: 1.0})
        t0 = client.wait_asta("KR60Arm").time
        samples = []
        while True:
            a = client.wait_asta("KR60Arm", after_time=t0 if not samples else samples[-1][0])
            samples.append((a.time, dict(a.values)[1]))
            if a.time > t0 + 1.5:
                break
    final = samples[-1][1]
    assert final == pytest.approx(1.0, abs=1e-3)
    # Within 3 time constants (0.5 s) it covers > 90 % of the step.
    mid = [v for t, v in samples if t0 + 0.5 <= t <= t0 + 0.6]
    assert mid and mid[0] > 0.9 * 1.0 * (1 - np.exp(-0.5 / (100 / 600))) - 0.1


def test_two_clients_each_get_their_own_robot(fast_sim: SimServer) -> None:
    with spawn(fast_sim.port) as a, spawn(fast_sim.port) as b:
        assert len(fast_sim.world.robot_keys) >= 2
        a.act("KR60Arm", {0: 0.8})
        t0 = a.wait_asta("KR60Arm").time
        qa = dict(a.wait_asta("KR60Arm", after_time=t0 + 1.5, timeout=5).values)
        qb = dict(b.wait_asta("KR60Arm", after_time=t0 + 1.5, timeout=5).values)
    assert qa[1] == pytest.approx(0.8, abs=5e-3) and abs(qb[1]) < 1e-3


def test_the_robot_is_destroyed_when_its_connection_closes(sim: SimServer) -> None:
    before = set(sim.world.robot_keys)
    client = spawn(sim.port)
    assert len(set(sim.world.robot_keys) - before) == 1
    client.close()
    deadline = time.monotonic() + 3
    while set(sim.world.robot_keys) - before and time.monotonic() < deadline:
        time.sleep(0.02)
    assert set(sim.world.robot_keys) == before


def test_commands_before_init_are_dropped_and_unknown_classes_spawn_nothing(sim: SimServer) -> None:
    with UsarClient(port=sim.port, timeout=0.5) as client:
        with pytest.raises(UnknownComponentError):
            client.get_conf("Actuator", "KR60Arm")
        with pytest.raises(UnknownRobotError) as info:
            client.spawn("USARBot.KR61", start="RobotStart1", known_classes=sorted(sim.robots))
    assert "USARBot.KR61" in str(info.value) and "USARBot.KR60" in str(info.value)


def test_bad_clients_do_not_disturb_the_others(sim: SimServer) -> None:
    with spawn(sim.port) as good:
        bad = socket.create_connection(("127.0.0.1", sim.port))
        bad.sendall(b"ASTA {Time {broken}}\r\nFOO {Bar 1}\r\nACT {Name X} {Link 0}\r\n")
        bad.sendall(b"INIT {ClassName USARBot.KR60} {Start RobotStart1}\r\n")
        bad.sendall(b"ACT {Name KR60Arm} {Link 99} {Value 1} {Link 0} {Value nan}\r\n")
        bad.sendall(b"Y" * 70_000 + b"\r\nGETSTARTPOSES\r\n")
        bad.sendall(b"GETCONF {Type Actua")  # and vanish mid-line
        time.sleep(0.3)
        bad.close()
        t0 = good.wait_asta("KR60Arm").time
        assert good.wait_asta("KR60Arm", after_time=t0, timeout=2).time > t0
        assert isinstance(good.get_conf("Actuator", "KR60Arm"), m.Conf)


def test_the_port_is_freed_on_stop() -> None:
    server = SimServer(SimOptions(port=0))
    port = server.start()
    with spawn(port):
        pass
    server.stop()
    with socket.socket() as s:
        s.bind(("127.0.0.1", port))  # would raise EADDRINUSE if still held


def test_the_second_arm_has_a_prismatic_rail_and_seven_joints(sim: SimServer) -> None:
    with spawn(sim.port, "USARBot.Fanuc_M16iB20") as client:
        conf = client.get_conf("Actuator")
        geo = client.get_geo("Actuator")
    assert isinstance(conf, m.Conf)
    links = conf.items[0].links
    assert [ln.joint_type for ln in links] == ["Prismatic"] + ["Revolute"] * 6
    assert geo.items[0].tip == (0.0, 0.0, 0.0)
