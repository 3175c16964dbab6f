"""A calibration tour's readings file: it round-trips exactly, says what it is, and the fit
from it refuses readings that contradict each other (nothing is written then)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from usar_arm.arm.tour_calibration import fit_tour
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.tour_readings import TourReadings, read_tour
from usar_arm.core.errors import CalibrationError, FileFormatError
from usar_arm.urdf.description_reader import parse_urdf

ROOT = Path(__file__).resolve().parents[2]
LEARNT = (ROOT / "robots/generated/as-learnt/KR60.urdf").read_text()
READINGS = ROOT / "robots/generated/KR60.readings.csv"
CHAIN, _ = parse_urdf(LEARNT)
PRISMATIC = [False] * 6


def _tour() -> TourReadings:
    return read_tour(READINGS, CHAIN.joint_names, PRISMATIC, CHAIN.lower(), CHAIN.upper())


def test_a_tour_file_reads_back_exactly(tmp_path: Path) -> None:
    rows = tuple(Measurement(np.array([0.1234, -0.5, 0.0, 1.0, -2.0, 3.1]),
                             np.array([1.675, 0.019, -1.964]), np.array([0.0, -0.006, 3.14]),
                             0.001, 0.001, label=f"t={k:.4f} s", step_q=1e-4, q_rounded=True)
                 for k in range(3))
    tour = TourReadings(rows, "KR60ArmTipTruth", CHAIN.joint_names,
                        (0.3, -0.2, 0.0, 0.0, -0.0, 1.5707963267948966), 14, 33.7,
                        tuple(PRISMATIC))
    path = tmp_path / "KR60.readings.csv"
    path.write_text(tour.csv())
    back = read_tour(path, CHAIN.joint_names, PRISMATIC, CHAIN.lower(), CHAIN.upper())
    assert back.csv() == tour.csv()
    assert (back.sensor, back.platform, back.poses, back.seconds) == \
        ("KR60ArmTipTruth", tour.platform, 14, 33.7)
    for a, b in zip(tour.measurements, back.measurements, strict=True):
        assert a.q.tolist() == b.q.tolist() and a.position.tolist() == b.position.tolist()
        assert (b.step_q, b.q_rounded, b.label) == (1e-4, True, a.label)


@pytest.mark.parametrize("line", ["# platform:", "# tour:", "# measured in:"])
def test_a_file_that_is_not_a_tour_says_which_line_it_lacks(tmp_path: Path, line: str) -> None:
    text = "\n".join(row for row in READINGS.read_text().splitlines()
                     if not row.startswith(line)) + "\n"
    path = tmp_path / "x.csv"
    path.write_text(text)
    with pytest.raises(FileFormatError, match=f"no '{line} ...' line"):
        read_tour(path, CHAIN.joint_names, PRISMATIC, CHAIN.lower(), CHAIN.upper())


def test_the_recorded_tour_fits_and_a_base_moved_mid_tour_is_refused() -> None:
    """The checked-in tour fits consistently; the same readings with the arm's base moved by
    3 mm after the first half are refused (CalibrationError: nothing is written)."""
    tour = _tour()
    result = fit_tour(LEARNT, tour, 0.01)
    assert result.calibration.consistent and result.readings == len(tour.measurements)
    half = len(tour.measurements) // 2
    moved = tour.measurements[:half] + tuple(
        dataclasses.replace(m, position=m.position + np.array([0.003, 0.0, 0.0]))
        for m in tour.measurements[half:])
    with pytest.raises(CalibrationError, match=r"consistent: false|does not hold"):
        fit_tour(LEARNT, dataclasses.replace(tour, measurements=moved), 0.01)
