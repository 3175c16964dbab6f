"""`usar-arm calibrate --measurements FILE --urdf X.urdf`: fits, validates on held-out
readings, writes only then; bad files and contradicting readings write nothing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tests.calibrate.synthetic import KR60, perturbed, random_q, readings, tool_errors
from usar_arm.calibrate.measurement_writer import write_measurements
from usar_arm.calibrate.measurements import Measurement, MeasurementSet
from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_OK
from usar_arm.core.spatial import transform_from_xyz_rpy
from usar_arm.planning.kinematics import KinematicModel

NOMINAL = KinematicModel(KR60)
BASE = transform_from_xyz_rpy([0.002, -0.001, 0.0015], [0.003, -0.002, 0.004])


def _files(tmp_path: Path, data: list[Measurement], measured_in: str = "tracker"
           ) -> tuple[Path, Path]:
    urdf = tmp_path / "KR60.urdf"
    urdf.write_text(KR60)
    path = tmp_path / "tracker.csv"
    write_measurements(path, MeasurementSet(tuple(data), "tool0",
                                            joint_names=NOMINAL.joint_names,
                                            measured_in=measured_in), "mm", "deg")
    return urdf, path


def test_file_mode_writes_a_validated_calibrated_urdf_and_report(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    truth = perturbed(KR60, 11)
    data = readings(truth, "tool0", BASE, random_q(NOMINAL, 60, 1), 2, sigma_m=5e-5,
                    sigma_rad=5e-5)
    urdf, path = _files(tmp_path, data)
    out = tmp_path / "out"
    assert main(["calibrate", "--measurements", str(path), "--urdf", str(urdf), "--out",
                 str(out)]) == EXIT_OK  # --out: the older name of --out-dir
    text = capsys.readouterr().out
    assert "48 readings of tool0" in text and "held out" in text and "(12 readings)" in text
    assert "18 unidentifiable, kept as in the URDF: joint_a1.origin.{x,y,z,roll,pitch,yaw}, " \
        in text
    assert "tool point tool0: 1-sigma 0.0" in text  # hundredths of a mm from 0.05 mm noise
    report = json.loads((out / "KR60.calibration.json").read_text())
    assert report["consistent"] and report["rank"] == 30 and len(report["unidentifiable"]) == 18
    assert report["bounds"] == {"reading_m": 0.1, "reading_rad": 0.1, "joint_m": 0.02,
                                "joint_rad": 0.05, "tool_m": 0.05, "tool_rad": 0.1,
                                "base_m": 0.05, "base_rad": 0.1}
    assert 0 < report["tool_point"]["sigma_m_median"] <= report["tool_point"]["sigma_m_max"]
    assert report["validation"]["summary"]["max_after_m"] < 3e-4
    assert len(report["validation"]["readings"]) == 12
    calibrated = (out / "KR60.urdf").read_text()
    err = tool_errors(truth, BASE, calibrated, np.array(report["base"]), "tool0",
                      random_q(NOMINAL, 200, 3))
    assert err[0] < 1e-4


def test_contradicting_readings_write_nothing(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    truth = perturbed(KR60, 12)
    q = random_q(NOMINAL, 40, 4)
    moved = BASE @ transform_from_xyz_rpy([0.003, 0, 0], [0, 0, 0.002])
    data = (readings(truth, "tool0", BASE, q[:20], 1, sigma_m=5e-5, sigma_rad=5e-5)
            + readings(truth, "tool0", moved, q[20:], 2, sigma_m=5e-5, sigma_rad=5e-5))
    urdf, path = _files(tmp_path, data)
    code = main(["calibrate", "--measurements", str(path), "--urdf", str(urdf), "--out",
                 str(tmp_path / "out")])
    assert code == EXIT_INVALID_INPUT
    assert "consistent: false" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_a_file_with_a_missing_column_writes_nothing(tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    urdf = tmp_path / "KR60.urdf"
    urdf.write_text(KR60)
    path = tmp_path / "bad.csv"
    path.write_text("# frame: tool0\njoint_a1_deg,joint_a2_deg,x_mm,y_mm,z_mm\n1,2,3,4,5\n")
    code = main(["calibrate", "--measurements", str(path), "--urdf", str(urdf), "--out",
                 str(tmp_path / "out")])
    assert code == EXIT_INVALID_INPUT
    assert "bad.csv:2" in capsys.readouterr().err and not (tmp_path / "out").exists()


def test_readings_where_a_joint_never_moves_warn_which_parameters_they_cannot_identify(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """joint_a1 still at 0.3 rad: joint_a2's frame is then rigidly attached to the base, so
    the four of its parameters generic readings identify (all but z and yaw, which merge with
    joint_a1's zero; tests/calibrate/test_identify.py) cannot be told from the base's."""
    truth = perturbed(KR60, 14)
    q = random_q(NOMINAL, 50, 15)
    q[:, 0] = 0.3
    urdf, path = _files(tmp_path, readings(truth, "tool0", BASE, q, 3, sigma_m=5e-5,
                                           sigma_rad=5e-5))
    assert main(["calibrate", "--measurements", str(path), "--urdf", str(urdf),
                 "--out-dir", str(tmp_path / "out")]) == EXIT_OK
    captured = capsys.readouterr()
    assert "rank 26 of 30 generically identifiable" in captured.out
    assert ("warning: these readings cannot identify joint_a2.origin.{x,y,roll,pitch}"
            in captured.err)
    assert "only validated over the configurations sampled" in captured.err


def test_readings_in_base_link_give_a_urdf_that_reproduces_them_as_written(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Every joint origin off by up to 1 mm / 3 mrad, tool0 measured in base_link: the base
    correction is folded into the first joint, so the URDF file itself (read back, no
    registration) puts tool0 where the truth has it at configurations never measured."""
    truth = perturbed(KR60, 21, metres=1e-3, radians=3e-3)
    data = readings(truth, "tool0", np.eye(4), random_q(NOMINAL, 50, 5), 6, sigma_m=2e-5,
                    sigma_rad=2e-5)
    urdf, path = _files(tmp_path, data, "base_link")
    assert "# measured_in: base_link" in path.read_text()
    out = tmp_path / "out"
    assert main(["calibrate", "--measurements", str(path), "--urdf", str(urdf), "--out-dir",
                 str(out)]) == EXIT_OK
    text = capsys.readouterr().out
    assert "KR60.urdf reproduces the held-out readings within" in text and "in base_link" in text
    assert sorted(p.name for p in out.iterdir()) == ["KR60.calibration.json", "KR60.urdf"]
    written = (out / "KR60.urdf").read_text()
    before = tool_errors(truth, np.eye(4), KR60, np.eye(4), "tool0", random_q(NOMINAL, 100, 7))
    after = tool_errors(truth, np.eye(4), written, np.eye(4), "tool0", random_q(NOMINAL, 100, 7))
    assert before[0] > 2e-3  # what the readings correct: millimetres
    assert after[0] < 5e-5 and after[1] < 5e-5
    report = json.loads((out / "KR60.calibration.json").read_text())
    assert report["measured_in"] == "base_link"
    assert report["written_urdf_vs_held_out"]["max_m"] <= \
        report["validation"]["summary"]["max_after_m"] + 1e-6


def test_readings_in_the_trackers_frame_write_the_registration_beside_the_urdf(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    truth = perturbed(KR60, 22)
    data = readings(truth, "tool0", BASE, random_q(NOMINAL, 50, 8), 9, sigma_m=2e-5,
                    sigma_rad=2e-5)
    urdf, path = _files(tmp_path, data)
    out = tmp_path / "out"
    assert main(["calibrate", "--measurements", str(path), "--urdf", str(urdf), "--out-dir",
                 str(out), "--measured-in", "tracker"]) == EXIT_OK
    assert "the URDF's base_link is the robot's own base" in capsys.readouterr().out
    registration = np.array(json.loads((out / "KR60.registration.json").read_text())
                            ["tracker_from_base_link"])
    written = (out / "KR60.urdf").read_text()
    err = tool_errors(truth, BASE, written, registration, "tool0", random_q(NOMINAL, 100, 10))
    assert err[0] < 5e-5 and err[1] < 5e-5


def test_a_command_line_frame_that_contradicts_the_file_writes_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = readings(KR60, "tool0", np.eye(4), random_q(NOMINAL, 30, 11), 12)
    urdf, path = _files(tmp_path, data, "base_link")
    code = main(["calibrate", "--measurements", str(path), "--urdf", str(urdf), "--out-dir",
                 str(tmp_path / "out"), "--measured-in", "tracker"])
    assert code == EXIT_INVALID_INPUT
    assert "says its readings are measured in base_link" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
    bad = tmp_path / "bad.csv"
    bad.write_text(path.read_text().replace("# measured_in: base_link", "# measured_in: world"))
    code = main(["calibrate", "--measurements", str(bad), "--urdf", str(urdf), "--out-dir",
                 str(tmp_path / "out")])
    assert code == EXIT_INVALID_INPUT
    assert "measured in 'world': expected tracker or base_link" in capsys.readouterr().err
