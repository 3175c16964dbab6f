"""The P3AT's model, its DRIVE mapping, the scanner's ray steps, and the world files."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_arm.core.errors import FileFormatError
from usar_arm.sim.robot_spec import builtin_robots, load_robot
from usar_arm.sim.vehicle import drive_wheels, scan_yaws
from usar_arm.sim.world_spec import load_world, shipped_worlds

P3AT = builtin_robots(vehicles=True)["USARBot.P3AT"]


def test_the_p3at_has_the_uc_masses_wheels_and_sensors() -> None:
    veh = P3AT.vehicle
    assert veh is not None and not P3AT.actuators
    # P3AT.uc: ChassisMiddle 1, ChassisBottom 10, four wheels of 0.1, ten bumpers of 0.05.
    assert veh.mass == pytest.approx(11.9, abs=1e-5)
    assert veh.wheel_radius == 0.098 and veh.max_speed == 1.3
    assert {(w.name, w.side, w.offset) for w in veh.wheels} == {
        ("FRWheel", "Right", (0.124, 0.18, 0.048)), ("FLWheel", "Left", (0.124, -0.18, 0.048)),
        ("BRWheel", "Right", (-0.124, 0.18, 0.048)), ("BLWheel", "Left", (-0.124, -0.18, 0.048))}
    assert [(s.type, s.name, s.position) for s in veh.sensors] == [
        ("GroundTruth", "GndTruth", (0, 0, 0)), ("Odometry", "Odometer", (0, 0, 0)),
        ("INS", "InsTest", (0, 0, -0.2)), ("RangeScanner", "lms200", (0.2085, 0, -0.2))]


def test_the_arm_list_is_unchanged_unless_vehicles_are_asked_for() -> None:
    assert sorted(builtin_robots()) == ["USARBot.Fanuc_M16iB20", "USARBot.KR60"]
    assert "USARBot.P3AT" in builtin_robots(vehicles=True)


def test_drive_maps_sides_and_clamps_each_wheel() -> None:
    veh = P3AT.vehicle
    assert veh is not None
    cmd = drive_wheels(veh, 0.5, -2.0, normalized=False)
    assert cmd.speeds == {"FRWheel": -1.3, "FLWheel": 0.5, "BRWheel": -1.3, "BLWheel": 0.5}
    assert set(cmd.clamped) == {"FRWheel", "BRWheel"}
    cmd = drive_wheels(veh, 50.0, -100.0, normalized=True)
    assert cmd.speeds["FLWheel"] == pytest.approx(0.65) and cmd.speeds["FRWheel"] == -1.3
    assert not cmd.clamped


def test_scan_rays_step_in_unreal_units_as_rangescanner_uc() -> None:
    yaws, res, fov = scan_yaws(0.01745, 3.14159)
    assert len(yaws) == 181
    assert yaws[0] == pytest.approx(16383 / 10430.3783505)
    assert yaws[1] - yaws[0] == pytest.approx(-182 / 10430.3783505)
    assert res == pytest.approx(0.017449, abs=1e-6) and fov == pytest.approx(3.141497, abs=1e-6)
    with pytest.raises(ValueError, match="below one Unreal unit"):
        scan_yaws(1e-5, 3.0)


def test_unsupported_steering_is_refused_with_a_clear_message(tmp_path: Path) -> None:
    text = (Path(__file__).resolve().parents[2] / "usar_arm/sim/robots/p3at.yaml").read_text()
    bad = tmp_path / "omni.yaml"
    bad.write_text(text.replace("  steering_type: SkidSteered\n  wheel_radius",
                                "  steering_type: OmniDrive\n  wheel_radius"))
    with pytest.raises(FileFormatError, match="OmniDrive is not supported"):
        load_robot(bad)
    unsteered = tmp_path / "ackermann.yaml"  # Ackermann steering needs steer joints
    unsteered.write_text(text.replace("  steering_type: SkidSteered\n  wheel_radius",
                                      "  steering_type: AckermanSteered\n  wheel_radius"))
    with pytest.raises(FileFormatError, match="if and only if it is AckermanSteered"):
        load_robot(unsteered)


def test_shipped_worlds_load_by_name_and_the_arms_cell_is_unchanged() -> None:
    assert {"default", "rooms"} <= set(shipped_worlds())
    default = load_world()
    assert default.level == "usar-arm-cell" and default.boxes == () and default.floor_z == 0
    assert [p.name for p in default.start_poses] == ["RobotStart1", "RobotStart2", "RobotStart3"]
    rooms = load_world("rooms")
    assert rooms.level == "usar-arm-rooms" and len(rooms.boxes) == 13


def test_bad_world_files_name_the_problem(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="shipped world: default, rooms"):
        load_world(tmp_path / "nosuch.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("boxes:\n  - {center: [0, 0], half: [1, 1, 1]}\n")
    with pytest.raises(FileFormatError, match=r"boxes\[0\]"):
        load_world(bad)
    bad.write_text("boxes:\n  - {center: [0, 0, 0], half: [1, 0, 1]}\n")
    with pytest.raises(FileFormatError, match="half sizes > 0"):
        load_world(bad)
