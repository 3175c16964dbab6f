"""`usar-arm urdf` end to end: any serial arm, and every way a server can fail."""

from __future__ import annotations

import json
import math
import socket
import time
from pathlib import Path

import numpy as np
import pytest

from tests.discover.fake_usarsim import CONF, GEO, fake_usarsim
from tests.usarsim.fake_server import FakeServer, read_line
from usar_arm.cli.main import main
from usar_arm.core import errors
from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions


def test_a_general_arm_with_a_rotated_mount_a_slide_and_a_tip(tmp_path: Path) -> None:
    with fake_usarsim(CONF, GEO) as srv:
        desc = describe(DescribeOptions(robot="Anything", host="127.0.0.1", port=srv.port,
                                        acm_samples=50, timeout=2.0))
    chain = desc.chain
    assert [j.type.value for j in chain.actuated_joints] == ["revolute", "prismatic"]
    assert chain.name == "R"
    # The flange at q1 = 0.7 rad, d2 = 0.25 m, worked out by hand from the GEO line (z down):
    # - the mount: at (0.5, 0.2, -0.1), yaw 1.570 -> a quarter turn, (x, y, z) -> (-y, x, z);
    # - joint 1 at (0, 0, -0.3), frame roll 3.14 -> pi: its axis is -z, so q1 turns by -0.7
    #   about z; joint 2 is 0.4 m out along x, its frame pitched 1.57 -> pi/2 from joint 1's,
    #   so it slides along x; the Tip is 0.1 m further along x. At q1, everything beyond joint
    #   1 lies 0.4 + 0.25 + 0.1 = 0.75 m out along (cos 0.7, -sin 0.7, 0):
    #   (0.573631640463366, -0.483163265428268, -0.3) in the arm's frame;
    # - turned by the mount: (0.483163265428268, 0.573631640463366, -0.3), plus the mount's
    #   position: (0.983163265428268, 0.773631640463366, -0.4);
    # - z up (x, -y, -z):
    expected = (0.983163265428268, -0.773631640463366, 0.4)
    got = chain.frame_pose("flange", [0.7, 0.25])[:3, 3]
    assert np.allclose(got, expected, atol=1e-9), got
    assert desc.warnings == () or all("geometry" in w or "default" in w for w in desc.warnings)
    assert any("conservative default" in s for s in desc.limit_sources[0])


def test_the_fake_server_streams_the_targets_it_was_sent() -> None:
    from usar_arm.usarsim.client import UsarClient

    with fake_usarsim(CONF, GEO) as srv, UsarClient(port=srv.port, timeout=2.0) as client:
        client.spawn("USARBot.Anything")
        first = client.wait_asta("A")
        assert first.values == ((1, 0.0), (2, 0.0))
        client.act("A", [0.5, 0.125])  # ACT links 0 and 1 -> ASTA links 1 and 2
        later = client.wait_asta("A", after_time=first.time + 0.15)
        assert later.values == ((1, 0.5), (2, 0.125))


def _cli(tmp_path: Path, *args: str) -> tuple[int, float]:
    out = tmp_path / "out"
    start = time.monotonic()
    code = main(["urdf", "--out-dir", str(out), "--acm-samples", "50", "--no-calibrate", "-q",
                 *args])
    return code, time.monotonic() - start


def test_unknown_robot_class(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _ = _cli(tmp_path, "--robot", "KR61", "--timeout", "1")
    assert code == errors.EXIT_UNKNOWN_ROBOT
    assert "USARBot.KR60" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_unknown_start_position(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _ = _cli(tmp_path, "--start-position", "Nowhere")
    assert code == errors.EXIT_UNKNOWN_START
    assert "RobotStart1" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_server_that_never_answers(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with fake_usarsim(CONF, GEO, answer=False) as srv:
        code, seconds = _cli(tmp_path, "--host", "127.0.0.1", "--port", str(srv.port),
                             "--timeout", "1")
    assert code == errors.EXIT_UNAVAILABLE and seconds < 10
    assert "GETSTARTPOSES" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_server_that_closes_mid_geo(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with fake_usarsim(CONF, GEO, close_mid_geo=True) as srv:
        code, seconds = _cli(tmp_path, "--host", "127.0.0.1", "--port", str(srv.port),
                             "--timeout", "2")
    assert code == errors.EXIT_CONNECTION_LOST and seconds < 10
    assert "GETGEO" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_geo_parents_that_are_not_a_chain(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    bad = GEO.replace("{Link 2} {Parent 1}", "{Link 2} {Parent 0}")
    with fake_usarsim(CONF, bad) as srv:
        code, _ = _cli(tmp_path, "--host", "127.0.0.1", "--port", str(srv.port))
    assert code == errors.EXIT_BAD_DESCRIPTION
    assert "Parent 0" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_server_that_closes_right_after_the_spawn_is_a_lost_connection(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Not 'reports no actuator' after the timeout: the connection is gone, say so at once."""
    def script(conn: socket.socket) -> None:
        conn.sendall(b"NFO {Gametype BotDeathMatch} {Level fake} {TimeLimit 0}\r\n")
        read_line(conn)  # GETSTARTPOSES
        conn.sendall(b"NFO {StartPoses 1} {Start1 0.00,0.00,0.00 0.00,0.00,0.00}\r\n")
        read_line(conn)  # INIT
        conn.sendall(b"STA {Time 0.1} {Battery 99999} {Type StaticPlatform}\r\n")
        time.sleep(0.1)
        conn.shutdown(socket.SHUT_RDWR)

    with FakeServer(script) as srv:
        code, seconds = _cli(tmp_path, "--host", "127.0.0.1", "--port", str(srv.port),
                             "--timeout", "3")
    assert code == errors.EXIT_CONNECTION_LOST and seconds < 2.5
    assert "listening to the status lines of USARBot.KR60" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_nobody_listening(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _ = _cli(tmp_path, "--host", "127.0.0.1", "--port", "9")
    assert code == errors.EXIT_UNAVAILABLE
    assert "cannot connect" in capsys.readouterr().err


def test_json_output_names_files_and_joints(tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    code, _ = _cli(tmp_path, "--robot", "Fanuc_M16iB20", "--json", "--naming", "kuka-ros2")
    assert code == errors.EXIT_OK
    doc = json.loads(capsys.readouterr().out)
    assert set(doc["files"]) == {"urdf", "srdf", "joint_limits", "discovery"}
    assert [j["name"] for j in doc["joints"]] == [f"joint_{k}" for k in range(1, 8)]
    assert doc["joints"][0]["type"] == "prismatic"
    assert {"lower", "upper", "velocity", "effort", "parent", "child"} <= set(doc["joints"][0])
    for path in doc["files"].values():
        assert Path(path).exists()
    discovery = json.loads(Path(doc["files"]["discovery"]).read_text())
    assert any(e["reply"].startswith("GEO {Type Actuator}") for e in discovery["exchanges"])


def test_velocity_limits_file_overrides_and_bad_files_name_line_and_field(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    good = tmp_path / "limits.yaml"
    good.write_text("joints:\n  1: {velocity: 0.7}\n  joint_a6: {jerk: 99}\n")
    code, _ = _cli(tmp_path, "--velocity-limits", str(good), "--json")
    assert code == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["joints"][0]["velocity"] == 0.7 and doc["joints"][5]["jerk"] == 99
    bad = tmp_path / "bad.yaml"
    bad.write_text("joints:\n  - {velocity: 1}\n  - {velocity: -2}\n  - {}\n  - {}\n  - {}\n"
                   "  - {}\n")
    code, _ = _cli(tmp_path, "--velocity-limits", str(bad))
    assert code == errors.EXIT_INVALID_INPUT
    message = capsys.readouterr().err
    assert "bad.yaml:3" in message and "velocity" in message


def test_usage_errors_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["urdf", "--naming", "klingon"])
    assert info.value.code == 2
    assert "ros-i" in capsys.readouterr().err


@pytest.mark.parametrize("command", [["ik", "--pose", "1", "0", "1", "0", "0", "0"],
                                     ["plan", "--pose", "1", "0", "1", "0", "0", "0"],
                                     ["reach", "--out", "never-written"]])
def test_an_srdf_without_its_urdf_is_a_usage_error(command: list[str], tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    # (was ignored: the robot was discovered and the SRDF never read)
    with pytest.raises(SystemExit) as info:
        main([*command, "--srdf", str(tmp_path / "KR60.srdf")])
    assert info.value.code == errors.EXIT_USAGE
    assert "--srdf goes with --urdf" in capsys.readouterr().err
    assert not Path("never-written").exists()


def test_no_inertial_on_the_root_and_effort_from_max_torque(tmp_path: Path) -> None:
    desc = describe(DescribeOptions(acm_samples=50, accuracy_samples=0))
    assert "<inertial" not in desc.urdf
    assert [j.limits.effort for j in desc.chain.actuated_joints] == [600, 1500, 700, 100, 60, 25]
    assert desc.home == {f"joint_a{k}": 0.0 for k in range(1, 7)}
    assert math.isclose(desc.chain.joint("joint_a2").limits.velocity, math.radians(102),
                        rel_tol=1e-6)
