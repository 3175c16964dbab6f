"""The measurement files: CSV and YAML in stated units, round trips, errors that name the place."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.calibrate.measurement_writer import write_measurements
from usar_arm.calibrate.measurements import (
    Measurement,
    MeasurementSet,
    read_measurements,
)
from usar_arm.core.errors import FileFormatError

JOINTS = ("joint_a1", "joint_a2", "rail")
PRISMATIC = (False, False, True)
finite = st.floats(-3.0, 3.0, allow_nan=False)


def _measurement(draw: st.DrawFn, i: int, sigma: float) -> Measurement:
    q = np.array([draw(finite) for _ in JOINTS])
    pos = np.array([draw(finite) for _ in range(3)])
    rpy = np.array([draw(finite) for _ in range(3)])
    # a reading may be quantised or not, but a file states a sigma for all readings or none
    # (an unquantised reading's sigma 0 would read as "stated exact")
    step = draw(st.sampled_from([0.0, 0.001] if sigma else [0.0]))
    return Measurement(q, pos, rpy, step, step, sigma, sigma / 2, f"m{i}")


@st.composite
def sets(draw: st.DrawFn) -> MeasurementSet:
    n = draw(st.integers(1, 5))
    sigma = draw(st.sampled_from([0.0, 5e-5]))
    return MeasurementSet(tuple(_measurement(draw, i, sigma) for i in range(n)), "tool0",
                          joint_names=JOINTS)


@settings(max_examples=40, deadline=None)
@given(data=sets(), length=st.sampled_from(["m", "mm"]), angle=st.sampled_from(["rad", "deg"]),
       suffix=st.sampled_from([".csv", ".yaml"]))
def test_write_then_read_gives_the_same_measurements(tmp_path_factory: pytest.TempPathFactory,
                                                     data: MeasurementSet, length: str,
                                                     angle: str, suffix: str) -> None:
    path = tmp_path_factory.mktemp("m") / f"m{suffix}"
    write_measurements(path, data, length, angle, PRISMATIC)
    back = read_measurements(path, JOINTS, prismatic=PRISMATIC)
    assert back.frame == "tool0" and back.length_unit == length and back.angle_unit == angle
    assert len(back.measurements) == len(data.measurements)
    for a, b in zip(data.measurements, back.measurements, strict=True):
        np.testing.assert_allclose(b.q, a.q, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(b.position, a.position, rtol=1e-12, atol=1e-15)
        assert a.rpy is not None and b.rpy is not None
        np.testing.assert_allclose(b.rpy, a.rpy, rtol=1e-12, atol=1e-15)
        assert b.step_m == pytest.approx(a.step_m) and b.step_rad == pytest.approx(a.step_rad)
        assert b.sigma_m == pytest.approx(a.sigma_m) and b.sigma_rad == pytest.approx(a.sigma_rad)
        assert b.label == a.label


def test_yaml_in_millimetres_and_degrees_is_read_in_si(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text("frame: tool0\nunits: {length: mm, angle: deg}\nmeasurements:\n"
                    "  - q: [90, 0, 100]\n    position: [1000, 0, 5]\n    rpy: [0, 90, 0]\n"
                    "    sigma_position: 0.05\n")
    m = read_measurements(path, JOINTS, prismatic=PRISMATIC).measurements[0]
    np.testing.assert_allclose(m.q, [np.pi / 2, 0, 0.1])
    np.testing.assert_allclose(m.position, [1.0, 0, 0.005])
    assert m.rpy is not None and m.rpy[1] == pytest.approx(np.pi / 2)
    assert m.sigma_m == pytest.approx(5e-5) and m.label.endswith("line 4")


HEADER = "# frame: tool0\njoint_a1_rad,joint_a2_rad,rail_m,x_m,y_m,z_m\n"
SIGMA = "# frame: tool0\njoint_a1_rad,joint_a2_rad,rail_m,x_m,y_m,z_m,sigma_mm\n"


@pytest.mark.parametrize(("text", "line", "says"), [
    ("# frame: tool0\njoint_a1_rad,rail_m,x_m,y_m,z_m\n", 2, "missing column(s) joint_a2"),
    (HEADER + "0,0,0,1,2,nan\n", 3, "not a finite number"),
    (HEADER + "0,0,0,1,2\n", 3, "5 values"),
    ("# frame: tool0\njoint_a1_rad,joint_a2_rad,rail_m,x_in,y_m,z_m\n0,0,0,1,2,3\n", 2,
     "unknown length unit 'in'"),
    ("# frame: tool0\njoint_a1_m,joint_a2_rad,rail_m,x_m,y_m,z_m\n0,0,0,1,2,3\n", 2,
     "unknown angle unit 'm'"),
    (HEADER + "0,0,0,1,2,3\n9,0,0,1,2,3\n", 4, "outside the limits"),
    ("joint_a1_rad,joint_a2_rad,rail_m,x_m,y_m,z_m\n", 1, "frame"),
    (SIGMA + "0,0,0,1,2,3,0.05\n0,0,0,1,2,3,-0.05\n", 4, "uncertainty of -5e-05"),
    (SIGMA + "0,0,0,1,2,3,0\n", 3, "uncertainty of 0 is not a 1-sigma"),
    (SIGMA.replace("sigma_mm", "step_mm") + "0,0,0,1,2,3,-1\n", 3, "negative step"),
])
def test_bad_csv_is_refused_naming_the_line(tmp_path: Path, text: str, line: int,
                                            says: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(FileFormatError) as info:
        read_measurements(path, JOINTS, prismatic=PRISMATIC, lower=np.array([-3, -3, 0]),
                          upper=np.array([3, 3, 1]))
    assert info.value.line == line and says in str(info.value)
    if "uncertainty" in says or "step" in says:
        assert info.value.field in ("sigma_mm", "step_mm")


def test_a_zero_sigma_beside_a_step_means_no_noise_beyond_the_truncation(tmp_path: Path
                                                                         ) -> None:
    """The wire's readings files state step 1 mm and sigma 0: that is not an error."""
    path = tmp_path / "m.csv"
    path.write_text("# frame: tool0\njoint_a1_rad,joint_a2_rad,rail_m,x_m,y_m,z_m,step_mm,"
                    "sigma_mm\n0,0,0,1,2,3,1,0\n")
    (m,) = read_measurements(path, JOINTS, prismatic=PRISMATIC).measurements
    assert (m.step_m, m.sigma_m) == (0.001, 0.0)


def test_yaml_with_a_negative_sigma_names_its_line_and_key(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text("frame: tool0\nunits: {length: mm, angle: deg}\nmeasurements:\n"
                    "  - {q: [0, 0, 0], position: [1, 2, 3], sigma_position: 0.05}\n"
                    "  - {q: [0, 0, 0], position: [1, 2, 3], sigma_position: -0.05}\n")
    with pytest.raises(FileFormatError, match="uncertainty of -5e-05") as info:
        read_measurements(path, JOINTS, prismatic=PRISMATIC)
    assert info.value.line == 5 and info.value.field == "sigma_position"


def test_readings_stating_a_sigma_beside_readings_stating_none_cannot_be_written(
        tmp_path: Path) -> None:
    rows = (Measurement(np.zeros(3), np.zeros(3), None, sigma_m=5e-5),
            Measurement(np.zeros(3), np.zeros(3), None))
    with pytest.raises(ValueError, match="all or none"):
        write_measurements(tmp_path / "m.csv", MeasurementSet(rows, "tool0", joint_names=JOINTS))


def test_yaml_without_units_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "m.yaml"
    path.write_text("frame: tool0\nmeasurements: []\n")
    with pytest.raises(FileFormatError, match="missing key 'units'"):
        read_measurements(path, JOINTS)


def test_joint_values_printed_to_a_step_say_so_in_the_header(tmp_path: Path) -> None:
    """A wire's joint values (ASTA: rounded to 1e-4) keep their step and rounding through a
    CSV file, and other header lines are kept in order."""
    rows = tuple(Measurement(np.array([0.1234, -0.5, 0.25]), np.array([1.0, 2.0, 3.0]),
                             np.array([0.1, 0.2, 0.3]), 0.001, 0.001, label=f"t={k}",
                             step_q=1e-4, q_rounded=True) for k in range(2))
    data = MeasurementSet(rows, "sensor", joint_names=JOINTS,
                          header=(("platform", "0 0 0 0 0 0"), ("tour", "3 poses")))
    path = tmp_path / "m.csv"
    write_measurements(path, data, prismatic=PRISMATIC)
    text = path.read_text()
    assert "# joint step: 0.0001\n# joint values: rounded\n" in text
    back = read_measurements(path, JOINTS, prismatic=PRISMATIC)
    assert back.header == data.header
    assert all(m.step_q == 1e-4 and m.q_rounded for m in back.measurements)
    path.write_text(text.replace("values: rounded", "values: sometimes"))
    with pytest.raises(FileFormatError, match="expected rounded or truncated") as info:
        read_measurements(path, JOINTS, prismatic=PRISMATIC)
    assert info.value.line == 5
