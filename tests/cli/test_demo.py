"""``usar-arm demo``, the main job: description, seven executed moves, table, pictures, bag."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from usar_arm.cli.main import main
from usar_arm.errors import EXIT_OK

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
