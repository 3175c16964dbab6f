"""``usar-arm demo``, the main job: description, seven executed moves, table, pictures, bag."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_OK

MOVES = ["approach", "pick", "lift", "transfer", "place", "retreat", "home"]


@pytest.mark.slow
@pytest.mark.realtime
def test_the_demo_runs_the_cycle_and_writes_everything(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "demo"
    # Run alone (make test-slow runs the realtime tests after the others, one at a time), so
    # the default abort bounds and the rate and tracking targets apply as they are.
    assert main(["demo", "--out", str(folder), "--wire-precision", "full"]) == EXIT_OK
    captured = capsys.readouterr()
    assert "[4/4]" in captured.err  # progress on stderr
    table = captured.out
    for move in MOVES:
        assert move in table
    assert "tool0 within 1 mm and 1 mrad of every goal: yes" in table
    report = json.loads((folder / "report.json").read_text())
    rows = report["moves"]
    assert [r["move"] for r in rows] == MOVES
    for r in rows:  # the targets, on the simulator's truth
        assert r["true_tip_error_m"] <= 1e-3 and r["true_tip_error_rad"] <= 1e-3
        assert r["max_tracking_error_rad"] <= 0.010  # the tracking target
        assert r["rate_hz"] >= 99.0  # 100 Hz nominal
    for name in ("description/KR60.urdf", "description/KR60.srdf", "cycle-scene.png",
                 "cycle-joints.png", "cycle.json", "cycle.bag/metadata.yaml",
                 "moves/4-transfer.json"):
        assert (folder / name).exists(), name


@pytest.mark.slow
def test_the_default_demo_on_the_udk_wire_calibrates_and_reaches_every_goal(
        tmp_path: Path, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    """What a user gets from `make demo` on a fresh machine: the UDK wire, an empty description
    cache, no tip correction. The demo calibrates the KR60 first, and every move's true tool0
    error (the simulator's physics) is within the issue's 0.3 mm / 0.3 mrad (measured: 0.16 mm,
    0.10 mrad at worst); the verdict line says what the report's figures say."""
    monkeypatch.setenv("USAR_ARM_CACHE", str(tmp_path / "cache"))
    folder = tmp_path / "demo"
    assert main(["demo", "--out", str(folder), "--no-bag"]) == EXIT_OK
    captured = capsys.readouterr()
    assert "[0/4] calibrating the KR60" in captured.err
    rows = json.loads((folder / "report.json").read_text())["moves"]
    worst_m = max(r["true_tip_error_m"] for r in rows)
    worst_rad = max(r["true_tip_error_rad"] for r in rows)
    line = (f"tool0 within 1 mm and 1 mrad of every goal: yes (worst "
            f"{worst_m * 1000:.2f} mm, {worst_rad * 1000:.2f} mrad, simulator truth)")
    assert line in captured.out
    assert worst_m <= 3e-4 and worst_rad <= 3e-4
    assert '"calibration"' in (folder / "description/KR60.discovery.json").read_text()
