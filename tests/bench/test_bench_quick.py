"""The benchmark harness's quick mode, end to end, so that it never rots: it runs, and every
stage writes a well-formed results file, the README table and its plots."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
STAGES = ("ik", "collision", "plan", "carry", "timing", "discovery", "execution", "calibrate",
          "pickplace")
PEERS = {"ik": {"pytracik", "mplib", "roboplan", "ikpy"},
         "collision": {"mplib", "roboplan", "tesseract"},
         "plan": {"mplib", "roboplan", "tesseract", "tesseract trajopt"}, "carry": set(),
         "timing": {"toppra", "roboplan"},
         "discovery": set(), "execution": set(), "calibrate": set(), "pickplace": set()}
PNG = b"\x89PNG\r\n\x1a\n"
VENVS = ROOT / "bench" / ".venvs"

# One worker runs them all, so the quick benchmark runs once: under make test-slow's -n 3 the
# module's tests were spread over workers, each running the benchmark for its own fixture at the
# same time (twice the load, and two ros stages on the same ROS domains).
pytestmark = pytest.mark.xdist_group("bench-quick")


def _venv_of(peer: str) -> str:
    """The venv (bench/peers/venvs.py) a peer solver runs in."""
    return peer.split()[0]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    out = tmp_path_factory.mktemp("bench")
    proc = subprocess.run(
        [sys.executable, str(ROOT / "bench" / "run.py"), "--quick", "--out",
         str(out / "results"), "--problems", str(out / "problems")],
        cwd=ROOT, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return out / "results", proc.stderr


@pytest.mark.slow
@pytest.mark.parametrize("stage", STAGES)
def test_every_stage_writes_its_results_with_machine_versions_and_raw_figures(
        quick_run: tuple[Path, str], stage: str) -> None:
    doc = json.loads((quick_run[0] / f"{stage}.json").read_text())
    assert doc["stage"] == stage and doc["mode"] == "quick"
    assert {"cpu", "logical_cores", "ram_gib", "python", "os"} <= set(doc["machine"])
    assert doc["versions"]["usar-arm"] not in ("", "unknown")
    assert doc["cases"], "no case"
    for t in doc["targets"]:
        assert isinstance(t["pass"], bool) and t["target"]
        # the verdict follows from its own figures (a target judged on a missing peer's
        # ratio, NaN, cannot pass)
        measured, bound = t["measured"], t["threshold"]
        holds = (isinstance(measured, (int, float)) and math.isfinite(measured)
                 and (measured <= bound if t["better"] == "<=" else measured >= bound))
        assert t["pass"] == holds, t
    for name, case in doc["cases"].items():
        ours = case["solvers"]["usar-arm"]
        assert "summary" in ours and ours["raw"], f"{name}: our solver has no figures"
        for solver, s in case["solvers"].items():
            if "skipped" in s:  # a missing peer venv is reported, never silent
                assert s["kind"] == "peer" and s["skipped"].strip(), (name, solver)
                # make test-slow creates every peer's venv first: a peer said to have no venv
                # while its venv is there is a broken comparison, not a missing one (a skip by
                # design, such as Tesseract on the KR60's problems only, says so instead)
                assert not ("no venv" in s["skipped"] and (VENVS / _venv_of(solver)).is_dir()), \
                    f"{name}/{solver} skipped though its venv exists: {s['skipped']}"
                continue
            lengths = {len(v) for v in s["raw"].values()}
            assert len(lengths) == 1, f"{name}/{solver}: ragged raw columns"
        present = {n for n, s in case["solvers"].items() if s["kind"] == "peer"}
        assert PEERS[stage] <= present, f"{name}: peers missing from the results"


@pytest.mark.slow
def test_the_report_has_the_targets_table_and_every_plot_it_shows(
        quick_run: tuple[Path, str]) -> None:
    folder = quick_run[0]
    text = (folder / "README.md").read_text()
    assert "## Targets" in text and "| stage | target |" in text
    shown = [line.split("(")[-1].rstrip(")") for line in text.splitlines()
             if line.startswith("![")]
    assert shown, "no plot in the report"
    for name in shown:
        assert (folder / name).read_bytes()[:8] == PNG, name


@pytest.mark.slow
def test_the_ros_stage_measures_the_live_node_from_another_process(
        quick_run: tuple[Path, str]) -> None:
    doc = json.loads((quick_run[0] / "ros.json").read_text())
    assert doc["stage"] == "ros" and doc["mode"] == "quick"
    assert "skipped" not in doc["settings"], doc["settings"]  # make test installs the extra
    node = doc["cases"]["KR60"]
    assert node["joint_states"]["messages"] > 50 and node["tf"]["messages_checked"] > 0
    assert node["goals"]["goals"] >= 5
    vehicle = doc["cases"]["P3AT"]
    assert vehicle["scan"]["messages"] > 10, vehicle["scan"]
    assert vehicle["cmd_vel_to_drive"]["matched"] > 10, vehicle["cmd_vel_to_drive"]
    for t in doc["targets"]:
        measured, bound = t["measured"], t["threshold"]
        holds = measured <= bound if t["better"] == "<=" else measured >= bound
        assert t["pass"] == holds, t
    assert "## ROS 2 node (usar-arm ros)" in (quick_run[0] / "README.md").read_text()


@pytest.mark.slow
def test_the_plan_profile_and_the_summary_come_with_the_run(quick_run: tuple[Path, str]) -> None:
    """The plan stage's time breakdown ran (it broke silently once, when the exact judge moved)
    and the one-screen summary docs/performance.md includes is written."""
    profile = json.loads((quick_run[0] / "plan.json").read_text())["profile"]
    assert "error" not in profile, profile.get("error")
    assert profile["problems"] > 0 and sum(profile["stages_s"].values()) > 0
    summary = (quick_run[0] / "summary.md").read_text()
    assert "| stage | case | usar-arm | peers (same run) |" in summary
    assert "targets pass" in summary
