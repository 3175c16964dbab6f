"""`usar-arm urdf` when it cannot calibrate: an arm without a tip sensor, and a tour whose
readings contradict each other. Either way the as-learnt description is written and the
reason said."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.tour_readings import read_tour
from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_OK
from usar_arm.sim.robot_spec import builtin_robots
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.urdf.description_reader import parse_urdf

REPO = Path(__file__).resolve().parents[2]
AS_LEARNT = REPO / "robots" / "generated" / "as-learnt" / "KR60.urdf"


def test_an_arm_without_a_tip_sensor_is_described_as_learnt_and_says_why(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """A simulator whose KR60 carries no tip sensor (its spec with ``tip_sensor`` removed,
    served over --host as a remote USARSim would be)."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    spec = builtin_robots()["USARBot.KR60"]
    bare = dataclasses.replace(spec, actuators=tuple(
        dataclasses.replace(a, tip_sensor=None) for a in spec.actuators))
    server = SimServer(SimOptions(port=0), robots={"USARBot.KR60": bare})
    server.start()
    try:
        out = tmp_path / "out"
        assert main(["urdf", "--robot", "KR60", "--host", "127.0.0.1", "--port",
                     str(server.port), "--out-dir", str(out), "--json"]) == EXIT_OK
    finally:
        server.stop()
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert "not calibrating: the server reports no tip pose sensor" in captured.err
    assert doc["calibrated"] is False and doc["calibration_source"] is None
    assert "no tip pose sensor" in doc["not_calibrated_because"]
    assert sorted(p.name for p in out.iterdir()) == [
        "KR60.discovery.json", "KR60.joint_limits.yaml", "KR60.srdf", "KR60.urdf"]
    assert "calibration" not in json.loads((out / "KR60.discovery.json").read_text())


def _moved_tour_readings() -> list[Measurement]:
    """The checked-in tour's readings with the base moved 3 mm along x after the first half
    (as printed: truncated toward zero to 1 mm)."""
    chain, _ = parse_urdf(AS_LEARNT.read_text())
    tour = read_tour(REPO / "robots" / "generated" / "KR60.readings.csv", chain.joint_names,
                     [False] * 6, chain.lower(), chain.upper())
    half = len(tour.measurements) // 2
    return list(tour.measurements[:half]) + [
        dataclasses.replace(m, position=np.trunc((m.position + np.array([0.003, 0.0, 0.0])) / 1e-3)
                            * 1e-3) for m in tour.measurements[half:]]


def test_a_failed_calibration_writes_the_as_learnt_description_and_says_why(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """The tour's motion is replaced by readings that contradict each other (a real tour's,
    the base moved 3 mm half-way): the fit refuses them, `urdf` writes the description as
    learnt, says why, and caches no calibration."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))

    def contradicting_tour(*args: Any, **kwargs: Any) -> list[Measurement]:
        return _moved_tour_readings()

    monkeypatch.setattr("usar_arm.arm.tour_calibration.collect", contradicting_tour)
    out = tmp_path / "out"
    assert main(["urdf", "--robot", "KR60", "--out-dir", str(out), "--json"]) == EXIT_OK
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert "calibration failed, so the description is as learnt" in captured.err
    assert "consistent: false" in doc["not_calibrated_because"]
    assert doc["calibrated"] is False and doc["calibration_source"] is None
    assert (out / "KR60.urdf").read_text() == AS_LEARNT.read_text()
    assert not (out / "KR60.readings.csv").exists()
    assert not list((tmp_path / "cache").glob("*/calibrated-*"))
