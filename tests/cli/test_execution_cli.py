"""``usar-arm plan --execute``, ``execute``, ``render``, ``plot`` and ``view`` as a user runs
them: exit codes, what they print, and the files they write."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from tests.cpu_share import watched
from usar_arm.cli.main import main
from usar_arm.control.trajectory import load_with_executed
from usar_arm.core.errors import EXIT_INVALID_INPUT, EXIT_OK

REPO = Path(__file__).resolve().parents[2]
URDF = str(REPO / "robots" / "generated" / "KR60.urdf")
ABOVE_PART = ["1.45", "-0.45", "1.1", "0", "3.14159265", "0"]


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A PTP from home planned offline (the embedded arm starts at home)."""
    path = tmp_path_factory.mktemp("plans") / "ptp.json"
    assert main(["plan", "--urdf", URDF, "--pose", *ABOVE_PART, "--scene", "table",
                 "--out", str(path), "-q"]) == EXIT_OK
    return path


def test_plan_execute_prints_the_report_keys_and_writes_trajectory_and_bag(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out, bag = tmp_path / "t.json", tmp_path / "run.bag"
    with watched() as window:
        code = main(["plan", "--pose", *ABOVE_PART, "--scene", "table", "--execute", "--json",
                     "--out", str(out), "--bag", str(bag), "-q"])
    if code != EXIT_OK:  # (aborted on a tracking error, when the simulator was starved)
        window.judge_or_skip()
    assert code == EXIT_OK
    doc = json.loads(capsys.readouterr().out)
    for key in ("planning_seconds", "duration", "final_joint_error_rad", "max_tracking_error_rad",
                "tip_error_m", "tip_error_rad", "rate_hz", "jitter_p99_ms"):
        assert isinstance(doc[key], float), key
    assert (bag / "metadata.yaml").exists()
    # The tracking target (10 mrad): 2.8 mrad on an idle machine (bench/results/execution.json),
    # 3.3-4.9 mrad measured beside a load of 6 on two cores (the in-process simulator lags),
    # an abort (156 mrad, beyond the 100 mrad bound) once beside a load of about 5: judged
    # when the motion had the CPU (tests/cpu_share.py); the rate, 99.95-100 Hz there.
    window.judge_or_skip()
    assert doc["max_tracking_error_rad"] < 0.010 and doc["rate_hz"] > 90
    _, executed = load_with_executed(out)
    assert executed is not None and len(executed.t) >= 15 and np.all(executed.t >= 0)


def test_execute_runs_a_saved_trajectory_and_plot_overlays_what_ran(
        planned: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ran = tmp_path / "ran.json"
    assert main(["execute", str(planned), "--out", str(ran), "-q"]) == EXIT_OK
    text = capsys.readouterr().out
    assert "Hz" in text and "max tracking error" in text and "tool0 error" in text
    picture = tmp_path / "ran.png"
    assert main(["plot", str(ran), "--out", str(picture), "-q"]) == EXIT_OK
    assert "executed samples" in capsys.readouterr().out
    assert imread(picture).shape[1] == 1600


def test_execute_refuses_a_trajectory_of_other_joints_before_moving(
        planned: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    doc = json.loads(planned.read_text())
    doc["joint_names"] = [f"j{i}" for i in range(6)]
    doc["limits"] = {f"j{i}": v for i, v in enumerate(doc["limits"].values())}
    other = tmp_path / "other.json"
    other.write_text(json.dumps(doc))
    assert main(["execute", str(other), "-q"]) == EXIT_INVALID_INPUT
    assert "its joints are j0, j1" in capsys.readouterr().err


def test_execute_refuses_a_trajectory_that_starts_elsewhere(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "elsewhere.json"
    assert main(["plan", "--urdf", URDF, "--joints", "0.5", "-0.5", "0.3", "0", "0.5", "0",
                 "--from-joints", "0.4", "-0.4", "0.3", "0", "0.5", "0", "--out", str(path),
                 "-q"]) == EXIT_OK
    assert main(["execute", str(path), "-q"]) == EXIT_INVALID_INPUT
    message = capsys.readouterr().err
    assert re.search(r"starts 0\.[45]\d\d rad from where joint_a5 is now", message)


@pytest.mark.parametrize("argv, expected", [
    (["plan", "--urdf", URDF, "--joints", "0", "0", "0", "0", "0", "0", "--tip-correction"],
     "--tip-correction needs --execute"),
    (["plan", "--urdf", URDF, "--joints", "0", "0", "0", "0", "0", "0", "--execute"],
     "--execute needs a live arm"),
    (["plan", "--joints", "0", "0", "0", "0", "0", "0", "--execute", "--rate", "0"],
     "--rate must be positive"),
])
def test_execution_flags_that_cannot_work_are_refused(
        argv: list[str], expected: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*argv, "-q"]) == EXIT_INVALID_INPUT
    assert expected in capsys.readouterr().err


def test_an_existing_bag_is_never_overwritten(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "old.bag").mkdir()
    assert main(["plan", "--urdf", URDF, "--joints", "0.1", "0", "0", "0", "0", "0",
                 "--bag", str(tmp_path / "old.bag"), "-q"]) == EXIT_INVALID_INPUT
    assert "a bag is never overwritten" in capsys.readouterr().err


def test_plan_writes_a_bag_of_the_plan_alone(tmp_path: Path) -> None:
    bag = tmp_path / "plan.bag"
    assert main(["plan", "--urdf", URDF, "--joints", "0.3", "-0.2", "0.1", "0", "0.4", "0",
                 "--bag", str(bag), "-q"]) == EXIT_OK
    assert "/planned_trajectory" in (bag / "metadata.yaml").read_text()


def test_render_draws_the_arm_with_a_trajectory_at_the_asked_size(
        planned: Path, tmp_path: Path) -> None:
    picture = tmp_path / "arm.png"
    assert main(["render", "--urdf", URDF, "--scene", "table", "--trajectory", str(planned),
                 "--out", str(picture), "--size", "640", "480", "-q"]) == EXIT_OK
    assert imread(picture).shape[:2] == (480, 640)


@pytest.mark.parametrize("argv, expected", [
    (["--joints", "0", "0"], "--joints needs 6 values"),
    (["--size", "10", "10"], "--size must be at least"),
    (["--scene", "no-such-scene"], "no-such-scene"),
])
def test_render_names_what_was_wrong(argv: list[str], expected: str, tmp_path: Path,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["render", "--urdf", URDF, "--out", str(tmp_path / "x.png"), *argv, "-q"])
    assert code == EXIT_INVALID_INPUT
    assert expected in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


def test_view_exports_an_html_replay_or_says_how_to_install_it(
        planned: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    page = tmp_path / "replay.html"
    code = main(["view", str(planned), "--urdf", URDF, "--html", str(page), "-q"])
    try:
        import viser  # noqa: F401
    except ImportError:
        assert code == EXIT_INVALID_INPUT
        assert "pip install 'usar-arm[viz]'" in capsys.readouterr().err
    else:
        assert code == EXIT_OK and page.stat().st_size > 100_000
