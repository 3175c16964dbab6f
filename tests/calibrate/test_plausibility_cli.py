"""`usar-arm calibrate --measurements`: readings that cannot belong to the description, or need
more than a calibration corrects, are refused with the likely cause, and nothing is written.
The files are written here, by the test's own formatting, from synthetic truths
(tests/calibrate/synthetic.py: a perturbed KR60, poses by Pinocchio)."""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from tests.calibrate.synthetic import KR60, perturbed, random_q, readings
from usar_arm.calibrate.measurements import Measurement
from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_OK
from usar_arm.core.spatial import transform_from_xyz_rpy
from usar_arm.planning.kinematics import KinematicModel

NOMINAL = KinematicModel(KR60)
BASE = transform_from_xyz_rpy([0.002, -0.001, 0.0015], [0.003, -0.002, 0.004])
JOINTS = NOMINAL.joint_names


def write_csv(path: Path, data: list[Measurement], length: tuple[float, str] = (1e3, "mm"),
              angle: tuple[float, str] = (180 / math.pi, "deg"), sigma: bool = True,
              frame: str = "tool0") -> Path:
    """A tracker CSV: joints in degrees; positions multiplied by ``length[0]`` and labelled
    ``length[1]``, angles likewise (so a wrong label is the test's own doing)."""
    ls, lu = length
    ang, au = angle
    cols = [f"{j}_deg" for j in JOINTS] + [f"{a}_{lu}" for a in "xyz"]
    cols += [f"{a}_{au}" for a in ("roll", "pitch", "yaw")]
    cols += ["sigma_mm", "sigma_deg"] if sigma else []
    lines = [f"# frame: {frame}", ",".join([*cols, "label"])]
    for m in data:
        assert m.rpy is not None
        row = [f"{math.degrees(v):.9f}" for v in m.q] + [f"{v * ls:.9f}" for v in m.position]
        row += [f"{v * ang:.9f}" for v in m.rpy]
        row += ["0.05", f"{math.degrees(5e-5):.9f}"] if sigma else []
        lines.append(",".join([*row, m.label]))
    path.write_text("\n".join(lines) + "\n")
    return path


def _tracker(truth: str, count: int = 50, seed: int = 3) -> list[Measurement]:
    data = readings(truth, "tool0", BASE, random_q(NOMINAL, count, seed), seed + 1,
                    sigma_m=5e-5, sigma_rad=5e-5)
    return [Measurement(m.q, m.position, m.rpy, label=f"r{k}") for k, m in enumerate(data)]


def _run(tmp_path: Path, csv: Path, *extra: str) -> int:
    urdf = tmp_path / "KR60.urdf"
    urdf.write_text(KR60)
    return main(["calibrate", "--measurements", str(csv), "--urdf", str(urdf), "--out-dir",
                 str(tmp_path / "out"), *extra])


def test_positions_in_metres_labelled_mm_are_refused_as_a_unit_mix_up(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    csv = write_csv(tmp_path / "t.csv", _tracker(perturbed(KR60, 1)), length=(1.0, "mm"))
    assert _run(tmp_path, csv) == EXIT_INVALID_INPUT
    text = capsys.readouterr().err
    assert "40 of 40 readings" in text and "1,000x too small" in text  # the fitted 80 %
    assert "metres labelled mm?" in text and not (tmp_path / "out").exists()


def test_angles_in_degrees_labelled_rad_are_refused_as_a_unit_mix_up(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    csv = write_csv(tmp_path / "t.csv", _tracker(perturbed(KR60, 2)),
                    angle=(180 / math.pi, "rad"))
    assert _run(tmp_path, csv) == EXIT_INVALID_INPUT
    text = capsys.readouterr().err
    assert "57x too large" in text and "degrees labelled rad?" in text
    assert not (tmp_path / "out").exists()


def test_tool0_readings_fitted_as_the_flange_are_refused_naming_tool0(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """tool0 is the flange turned +90 degrees about y (ROS-Industrial): readings of tool0
    called the flange's sit a constant 90 degrees off, and the error says where they fit."""
    csv = write_csv(tmp_path / "t.csv", _tracker(perturbed(KR60, 3)))
    assert _run(tmp_path, csv, "--frame", "flange") == EXIT_INVALID_INPUT
    text = capsys.readouterr().err
    # 90 degrees about the flange's y, give or take the perturbation (5 mrad per number)
    assert re.search(r"constant \d\.\d mm and (89|90|91)\.\d deg about \(-?0\.00, 1\.00, "
                     r"-?0\.00\) off flange in its own axes", text), text
    assert "tool0 sits there (--frame tool0)" in text and not (tmp_path / "out").exists()


def _longer_upper_arm(urdf: str, metres: float) -> str:
    """``urdf`` with joint_a3 (the upper arm's far end) moved ``metres`` along its parent's z."""
    root = ET.fromstring(urdf)
    origin = next(j for j in root.findall("joint") if j.get("name") == "joint_a3").find("origin")
    assert origin is not None
    xyz = np.array(origin.get("xyz", "0 0 0").split(), float)
    xyz[2] += metres
    origin.set("xyz", " ".join(repr(float(v)) for v in xyz))
    return ET.tostring(root, encoding="unicode")


def test_a_fit_needing_a_joint_correction_beyond_its_bound_writes_nothing(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """An upper arm 30 mm longer than described: the readings lie within the 100 mm reading
    bound, but the fit needs joint_a3 moved 30 mm, beyond the 20 mm joint bound. With the
    bound raised to 50 mm the same file calibrates."""
    truth = _longer_upper_arm(perturbed(KR60, 4, metres=2e-4, radians=1e-3), 0.03)
    csv = write_csv(tmp_path / "t.csv", _tracker(truth))
    assert _run(tmp_path, csv) == EXIT_INVALID_INPUT
    text = capsys.readouterr().err
    assert re.search(r"beyond the plausible: joint_a3 (29|30)\.\d mm", text), text
    assert "--max-joint-correction" in text
    assert not (tmp_path / "out").exists()
    assert _run(tmp_path, csv, "--max-joint-correction", "0.05", "0.05") == EXIT_OK
    report = (tmp_path / "out" / "KR60.calibration.json").read_text()
    assert '"joint_m": 0.05' in report


def test_a_base_moved_1mm_mid_file_without_an_uncertainty_column_is_refused_at_r25(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """No sigma column: the noise is estimated from the scatter, which a 1 mm move of the
    tracker after reading r25 inflates, so no single reading stands out; the residuals in
    file order do."""
    truth = perturbed(KR60, 6)
    q = random_q(NOMINAL, 50, 8)
    moved = BASE @ transform_from_xyz_rpy([0.001, 0.0, 0.0], [0.0, 0.0, 0.0])
    data = (readings(truth, "tool0", BASE, q[:25], 1, sigma_m=5e-5, sigma_rad=5e-5)
            + readings(truth, "tool0", moved, q[25:], 2, sigma_m=5e-5, sigma_rad=5e-5))
    data = [Measurement(m.q, m.position, m.rpy, label=f"r{k}") for k, m in enumerate(data)]
    assert _run(tmp_path, write_csv(tmp_path / "t.csv", data, sigma=False)) \
        == EXIT_INVALID_INPUT
    text = capsys.readouterr().err
    assert "consistent: false" in text and "readings from r25 on sit" in text
    assert "the base or the tool moved" in text and not (tmp_path / "out").exists()


def test_eight_readings_are_too_few_to_validate(tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    csv = write_csv(tmp_path / "t.csv", _tracker(perturbed(KR60, 7), count=8))
    assert _run(tmp_path, csv) == EXIT_INVALID_INPUT
    text = capsys.readouterr().err
    assert "too few readings to validate: 8 readings" in text and "at least 25 needed" in text
    assert not (tmp_path / "out").exists()
