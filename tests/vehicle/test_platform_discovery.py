"""Learning the P3AT over real TCP from the embedded simulator: the facts are UDK's numbers
(docs/protocol.md section 9), the URDF is valid and its tree is base_footprint -> base_link ->
wheels and sensor frames; hidden and unknown sensors are reported, unknown steering refused."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from usar_arm.cli.main import main
from usar_arm.core.errors import ValidationError
from usar_arm.core.platform import SEED_FRAMES
from usar_arm.core.vehicle_errors import NotAVehicleError, UnsupportedSteeringError
from usar_arm.description.embedded import embedded_simulator
from usar_arm.description.platform import (
    PlatformResult,
    described,
    is_ground_vehicle,
    learn,
    write_platform,
)
from usar_arm.discover.platform import SensorReply, learn_platform, platform_from_replies
from usar_arm.urdf.platform import platform_urdf, validate_platform
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.codec import parse_line

CONF = ("CONF {Name P3AT} {Type GroundVehicle} {SteeringType SkidSteered} {Mass 11.9000} "
        "{MaxSpeed 1.2999} {MaxTorque 50000.0000} {MaxFrontSteer 0} {MaxRearSteer 0}")
GEO = ("GEO {Type GroundVehicle} {Name P3AT} {Dimensions 0.2480,0.3600,0.0000} "
       "{COG 0.0000,0.0000,0.0000} {WheelRadius 0.0980} {WheelSeparation 0.3600} "
       "{WheelBase 0.2480}")


@pytest.fixture(scope="module")
def learnt() -> PlatformResult:
    return learn("P3AT", timeout=5.0)


def test_the_facts_are_udks_numbers(learnt: PlatformResult) -> None:
    d = learnt.description
    assert (d.name, d.platform_type, d.steering_type) == ("P3AT", "GroundVehicle", "SkidSteered")
    assert (d.mass, d.max_speed, d.max_torque) == (11.9, 1.2999, 50000.0)
    assert (d.wheel_radius, d.wheel_separation, d.wheel_base) == (0.098, 0.36, 0.248)
    by_name = {s.name: s for s in d.sensors}
    assert set(by_name) == {"GndTruth", "InsTest", "lms200", "Odometer"}
    assert by_name["lms200"].xyz == pytest.approx((0.208, 0.0, 0.2))  # z-down -0.2 is up
    assert by_name["InsTest"].xyz == pytest.approx((0.0, 0.0, 0.2))
    scanner = by_name["lms200"].scanner
    assert scanner is not None
    assert (scanner.max_range, scanner.min_range, scanner.resolution, scanner.fov) == (
        20.0, 0.1, 0.0174, 3.1414)
    assert by_name["InsTest"].scan_interval == 0.2
    assert d.hidden == () and d.unknown == ()


def test_the_urdf_tree_is_footprint_base_wheels_sensors(learnt: PlatformResult) -> None:
    root = ET.fromstring(learnt.urdf)
    joints = {j.get("name"): j for j in root.iter("joint")}
    parent = {j.find("child").get("link"): j.find("parent").get("link") for j in joints.values()}
    assert parent["base_link"] == "base_footprint"
    for wheel in ("front_left", "front_right", "rear_left", "rear_right"):
        joint = joints[f"{wheel}_wheel_joint"]
        assert joint.get("type") == "continuous"
        assert joint.find("axis").get("xyz") == "0 1 0"
        assert parent[f"{wheel}_wheel"] == "base_link"
        y = float(joint.find("origin").get("xyz").split()[1])
        assert (y > 0) == ("left" in wheel)  # REP-103: y left
    for frame in ("gndtruth_link", "instest_link", "lms200_link", "odometer_link"):
        assert parent[frame] == "base_link"
    footprint = joints["base_footprint_joint"].find("origin").get("xyz").split()
    assert float(footprint[2]) == pytest.approx(0.098)  # base_link above the ground
    assert root.find("link[@name='base_link']/collision/geometry/box") is not None


def test_written_files_and_the_cli_choose_the_platform_path(learnt: PlatformResult,
                                                               tmp_path: Path) -> None:
    paths = write_platform(learnt, tmp_path)
    assert paths["urdf"].read_text() == learnt.urdf
    assert '"GETGEO {Type RangeScanner} {Name lms200}"' in paths["platform"].read_text()
    assert is_ground_vehicle("P3AT") and not is_ground_vehicle("USARBot.KR60")


def test_seed_frames_have_base_link_as_root_and_sensors_by_name(learnt: PlatformResult) -> None:
    urdf = platform_urdf(learnt.description, SEED_FRAMES)
    validate_platform(learnt.description, urdf, SEED_FRAMES)
    links = {lk.get("name") for lk in ET.fromstring(urdf).iter("link")}
    assert "base_footprint" not in links and {"lms200", "InsTest", "GndTruth"} <= links
    assert "odom" not in links  # the Odometry sensor is the odom frame itself in 2012


def _replies(conf: str = CONF) -> tuple[m.PlatformConf, m.Geo]:
    c, g = parse_line(conf), parse_line(GEO)
    assert isinstance(c, m.PlatformConf) and isinstance(g, m.Geo)
    return c, g


def test_an_unknown_steering_type_is_refused_naming_it_and_the_supported_ones() -> None:
    conf, geo = _replies(CONF.replace("SkidSteered", "OmniDrive"))
    with pytest.raises(UnsupportedSteeringError,
                       match=r"OmniDrive.*only SkidSteered and AckermanSteered") as info:
        platform_from_replies("USARBot.Omni", conf, geo, [])
    assert "\n" not in str(info.value)  # one line


def test_hidden_sensors_are_listed_not_placed() -> None:
    conf, geo = _replies()
    d = platform_from_replies("USARBot.P3AT", conf, geo,
                              [SensorReply("INS", "Secret", None, None)], ("Sonar S1",))
    assert d.sensors == () and d.hidden == ("INS Secret",) and d.unknown == ("Sonar S1",)
    urdf = platform_urdf(d)
    assert "hidden sensor (GETGEO gave nothing, no frame): INS Secret" in urdf
    assert "Sonar S1" in urdf and "secret_link" not in urdf


def test_an_arm_is_not_learnt_as_a_platform() -> None:
    with embedded_simulator() as server, UsarClient("127.0.0.1", server.port or 0,
                                                    timeout=5.0) as client:
        with pytest.raises(NotAVehicleError, match="StaticPlatform, not a ground vehicle: "
                                                   "describe an arm with usar-arm urdf"):
            learn_platform(client, "KR60", timeout=5.0)


def test_a_broken_description_is_refused_listing_the_problem(learnt: PlatformResult) -> None:
    import dataclasses

    bad = dataclasses.replace(learnt.description, wheel_radius=0.0)
    with pytest.raises(ValidationError, match="wheel radius must be > 0"):
        described(learnt.record, bad)
    assert math.isclose(learnt.description.footprint_radius, math.hypot(0.222, 0.205))


def test_the_urdf_command_describes_a_ground_vehicle(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["urdf", "--robot", "P3AT", "-o", str(tmp_path), "--json", "-q"])
    assert code == 0
    facts = json.loads(capsys.readouterr().out)
    assert (facts["steering"], facts["wheel_radius_m"], facts["max_wheel_speed_rad_s"]) == (
        "SkidSteered", 0.098, 1.2999)
    assert {s["frame"] for s in facts["sensors"]} == {"gndtruth_link", "instest_link",
                                                     "lms200_link", "odometer_link"}
    assert facts["hidden_sensors"] == [] and facts["unknown_sensors"] == []
    assert Path(facts["files"]["urdf"]).read_text().startswith('<?xml version="1.0"?>')
    assert sorted(p.name for p in tmp_path.iterdir()) == ["P3AT.platform.json", "P3AT.urdf"]
