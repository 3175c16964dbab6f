"""An Ackermann-steered vehicle (UDK's FrontAckerman, docs/protocol.md section 10) is learnt
from its replies, written as a URDF with steered front wheels, described by ``usar-arm urdf``
over real TCP, and driven to a waypoint by ``usar-arm drive``; a rear-steered one and an
unknown steering type get one clear line."""

from __future__ import annotations

import json
import math
import socket
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.usarsim.fake_server import FakeServer, read_line
from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_OK, DescriptionError
from usar_arm.core.platform import PlatformDescription
from usar_arm.core.vehicle_errors import UnsupportedSteeringError
from usar_arm.discover.platform import learn_platform, platform_from_replies
from usar_arm.urdf.platform import platform_urdf, validate_platform
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.codec import parse_line

CONF = ("CONF {Name FrontAckerman} {Type GroundVehicle} {SteeringType AckermanSteered} "
        "{Mass 147.0000} {MaxSpeed 0.5600} {MaxTorque 50000.0000} {MaxFrontSteer 1.0000} "
        "{MaxRearSteer 6.2800}")
GEO = ("GEO {Type GroundVehicle} {Name FrontAckerman} {Dimensions 0.9560,0.4520,0.0000} "
       "{COG 0.0000,0.0000,0.0000} {WheelRadius 0.1280} {WheelSeparation 0.4520} "
       "{WheelBase 0.9560}")
START = (7.0, -4.0)
"""RobotStart2 of the rooms world in the map frame (facing -y)."""
GOAL = (6.8, -5.6)


def _describe(conf: str = CONF) -> PlatformDescription:
    c, g = parse_line(conf), parse_line(GEO)
    assert isinstance(c, m.PlatformConf) and isinstance(g, m.Geo)
    return platform_from_replies("USARBot.FrontAckerman", c, g, [])


def test_an_ackermann_vehicle_is_described_with_its_steer_and_wheel_base() -> None:
    d = _describe()
    assert d.ackermann and d.steering_type == "AckermanSteered"
    assert (d.wheel_base, d.wheel_separation, d.wheel_radius) == (0.956, 0.452, 0.128)
    assert (d.max_front_steer, d.max_rear_steer) == (0.5, 0.0)  # half the range; 6.28: none


def test_a_rear_steered_vehicle_is_refused_in_one_line() -> None:
    """BasicAckermanRobot steers its rear wheels: MaxFrontSteer 6.28 (no front steer joint)."""
    with pytest.raises(DescriptionError, match="front wheels do not steer") as info:
        _describe(CONF.replace("{MaxFrontSteer 1.0000} {MaxRearSteer 6.2800}",
                               "{MaxFrontSteer 6.2800} {MaxRearSteer 1.6000}"))
    assert "\n" not in str(info.value)


def test_the_urdf_steers_the_front_wheels_on_revolute_knuckles() -> None:
    d = _describe()
    urdf = platform_urdf(d)
    validate_platform(d, urdf)
    root = ET.fromstring(urdf)
    joints = {j.get("name"): j for j in root.iter("joint")}
    parent = {j.find("child").get("link"): j.find("parent").get("link") for j in joints.values()}
    for side in ("left", "right"):
        steer = joints[f"front_{side}_steer_joint"]
        assert steer.get("type") == "revolute" and steer.find("axis").get("xyz") == "0 0 1"
        limit = steer.find("limit")
        assert (float(limit.get("lower")), float(limit.get("upper"))) == (-0.5, 0.5)
        assert parent[f"front_{side}_steer"] == "base_link"
        assert parent[f"front_{side}_wheel"] == f"front_{side}_steer"
        assert joints[f"front_{side}_wheel_joint"].find("origin").get("xyz") == "0 0 0"
        assert parent[f"rear_{side}_wheel"] == "base_link"
        assert f"rear_{side}_steer_joint" not in joints
    x = float(joints["front_left_steer_joint"].find("origin").get("xyz").split()[0])
    assert x == pytest.approx(0.478)  # half the wheel base ahead of base_link
    assert "front steer within +-0.5 rad" in urdf


def test_the_urdf_command_describes_the_embedded_front_ackerman(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["urdf", "--robot", "FrontAckerman", "-o", str(tmp_path), "--json", "-q"])
    assert code == EXIT_OK
    facts = json.loads(capsys.readouterr().out)
    assert (facts["steering"], facts["wheel_base_m"], facts["max_wheel_speed_rad_s"]) == (
        "AckermanSteered", 0.956, 0.56)
    assert {s["name"] for s in facts["sensors"]} == {"GndTruth", "InsTest"}
    urdf = Path(facts["files"]["urdf"]).read_text()
    assert 'name="front_left_steer_joint" type="revolute"' in urdf


def test_the_drive_command_takes_front_ackerman_to_a_waypoint(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "usar_arm", "drive", "--robot", "FrontAckerman",
         "--start-position", "RobotStart2", "--waypoints", f"{GOAL[0]},{GOAL[1]}",
         "--speed", "4", "--picture", "", "--json", "-q"],
        capture_output=True, text=True, cwd=tmp_path, timeout=120, check=False)
    assert done.returncode == EXIT_OK, done.stderr
    result = json.loads(done.stdout)
    assert result["reached"] and result["distance_m"] == pytest.approx(
        math.dist(START, GOAL), abs=0.2)
    commands = result["commands"]
    assert 0 < commands["largest_sent_radps"] <= commands["max_wheel_speed_radps"] == 0.56


def test_a_steering_type_it_cannot_drive_is_refused_before_any_sensor_is_asked() -> None:
    """A server (scripted, real TCP) whose vehicle reports {SteeringType OmniDrive}: learning it
    (the drive's and the description's first step) names that type and the ones usar-arm
    drives, right after the robot's CONF, before anything else is asked."""
    omni = CONF.replace("AckermanSteered", "OmniDrive").replace("FrontAckerman", "Omni")
    asked: list[str] = []

    def script(conn: socket.socket) -> None:
        conn.sendall(b"NFO {Gametype BotDeathMatch} {Level test} {TimeLimit 0}\r\n")
        read_line(conn)  # GETSTARTPOSES
        conn.sendall(b"NFO {StartPoses 1} {Start1 0.00,0.00,0.00 0.00,0.00,0.00}\r\n")
        read_line(conn)  # INIT
        conn.sendall(b"STA {Time 0.1} {Battery 99999} {Type GroundVehicle}\r\n")
        while line := read_line(conn, timeout=5.0):
            asked.append(line)
            if line == "GETCONF {Type Robot}":
                conn.sendall(omni.encode() + b"\r\n")

    with FakeServer(script) as srv, UsarClient(port=srv.port, timeout=2.0) as client, \
            pytest.raises(UnsupportedSteeringError,
                          match=r"OmniDrive.*only SkidSteered and AckermanSteered") as info:
        learn_platform(client, "USARBot.Omni", timeout=2.0)
    assert "\n" not in str(info.value)
    assert asked == ["GETCONF {Type Robot}"]
