"""VAMP in the robots stage (bench/robots_vamp.py, bench/peers/venvs.py's hand-built peers,
bench/peers/run_vamp_plan.py): the build is found where the variable, the link or the default
folder says, and missing, the stage says in one line how to make one; VAMP's own timer reaches
the summary beside the Python call's time; the report shows a measured row with both timers
and the mesh judge's verdicts, or the reason it was not run, and always the published figures
as published. With a local build, the runner plans a small problem whose straight line a box
blocks, and its path passes the stage's checks (skipped without a build)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "bench"), str(ROOT / "bench" / "peers")]

import report  # noqa: E402
import robots_vamp  # noqa: E402
import venvs  # noqa: E402


def _fake_venv(folder: Path, package: bool = True) -> Path:
    (folder / "bin").mkdir(parents=True)
    (folder / "bin" / "python").write_text("")
    if package:
        site = folder / "lib" / "python3.11" / "site-packages" / "vamp"
        site.mkdir(parents=True)
        (site / "__init__.py").write_text("")
    return folder


def test_the_build_is_found_by_the_variable_first(tmp_path: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(venvs, "VENV_ROOT", tmp_path / "venvs")
    built = _fake_venv(tmp_path / "built")
    monkeypatch.setenv("USAR_ARM_VAMP_VENV", str(built))
    assert venvs.python_path("vamp") == built / "bin" / "python"
    assert venvs.is_ready("vamp")
    empty = _fake_venv(tmp_path / "empty", package=False)
    monkeypatch.setenv("USAR_ARM_VAMP_VENV", str(empty))
    assert not venvs.is_ready("vamp")
    reason = venvs.missing_reason("vamp")
    assert str(empty) in reason and "USAR_ARM_VAMP_VENV" in reason and "\n" not in reason


def test_without_the_variable_a_link_then_the_default_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("USAR_ARM_VAMP_VENV", raising=False)
    monkeypatch.setattr(venvs, "VENV_ROOT", tmp_path / "venvs")
    monkeypatch.setitem(venvs.EXTERNAL["vamp"], "default", str(tmp_path / "nowhere"))
    assert venvs.external_venv("vamp") == tmp_path / "nowhere"
    assert not venvs.is_ready("vamp")
    (tmp_path / "venvs").mkdir()
    (tmp_path / "venvs" / "vamp").symlink_to(_fake_venv(tmp_path / "build"))
    assert venvs.external_venv("vamp") == tmp_path / "venvs" / "vamp"
    assert venvs.is_ready("vamp")


def test_venvs_list_names_vamp_and_does_not_install_it(tmp_path: Path) -> None:
    env = {**os.environ, "USAR_ARM_VAMP_VENV": str(tmp_path / "none")}
    listed = subprocess.run([sys.executable, str(ROOT / "bench/peers/venvs.py"), "--list"],
                            capture_output=True, text=True, env=env, check=True).stdout
    assert any(line.startswith("vamp\t") and line.endswith("missing")
               for line in listed.splitlines())
    only = subprocess.run([sys.executable, str(ROOT / "bench/peers/venvs.py"), "--only", "vamp"],
                          capture_output=True, text=True, env=env)
    assert only.returncode == 0 and "not installed by this script" in only.stderr


def test_the_own_timer_reaches_the_summary() -> None:
    raw = {"verified": [True, False, True], "own_seconds": [1e-4, 2e-4, 3e-4],
           "plan_own_seconds": [4e-5, 5e-5, 6e-5], "simplify_own_seconds": [6e-5, 1.5e-4, 2.4e-4]}
    sm = robots_vamp.own_time_summary(raw)
    assert sm["own_time_all_s"]["median"] == pytest.approx(2e-4)
    assert sm["own_time_verified_s"]["median"] == pytest.approx(2e-4)  # of 1e-4 and 3e-4
    assert sm["plan_own_s"]["median"] == pytest.approx(5e-5)
    assert robots_vamp.own_time_summary({"verified": [True], "own_seconds": [None]}) == {}
    assert robots_vamp.passthrough({"seconds": 1.0})["own_seconds"] is None


def _plan_case(vamp: dict) -> dict:
    ours = {"kind": "ours", "summary": {"time_all_s": {"median": 0.02}}}
    return {"robots_panda_plan": {"solvers": {"usar-arm": ours, "vamp": vamp}}}


def test_a_measured_row_and_a_missing_build_in_the_summary_and_the_report() -> None:
    measured = {"kind": "peer", "version": "0.6.4", "summary": {
        "problems": 48, "answered": 48, "verified": 30, "paths_in_collision": 18,
        "time_all_s": {"median": 0.0016}, "own_time_all_s": {"median": 0.0002},
        "plan_own_s": {"median": 6e-5}, "simplify_own_s": {"median": 1.4e-4}}}
    summary = robots_vamp.summary(_plan_case(measured))
    row = summary["panda"]
    assert row["measured"] and row["verified_on_meshes"] == 30
    assert row["ratio_usar_to_vamp_call"] == pytest.approx(0.02 / 0.0016)
    assert row["ratio_usar_to_vamp_own"] == pytest.approx(100.0)
    lines = "\n".join(report._vamp_lines({"vamp": summary,
                                          "vamp_published": robots_vamp.PUBLISHED}))
    assert "VAMP measured here" in lines and "30/48" in lines and "200 us" in lines
    assert "1.6 ms" in lines and "not measured here" in lines  # the published figures too
    skipped = robots_vamp.summary(_plan_case({"kind": "peer", "skipped": "no vamp in /x: build"}))
    assert not skipped["panda"]["measured"]
    lines = "\n".join(report._vamp_lines({"vamp": skipped,
                                          "vamp_published": robots_vamp.PUBLISHED}))
    assert "VAMP not measured in this run: no vamp in /x: build" in lines
    assert "VAMP measured here" not in lines


BLOCKED = {"stage": "plan", "robot": "panda", "urdf": "", "srdf": "", "base_link": "panda_link0",
           "tip_link": "panda_hand", "time_limit_s": 2.0,
           "joint_names": [f"panda_joint{i}" for i in range(1, 8)],
           "scenes": {"box/0001": [{"name": "wall", "type": "box", "size": [0.05, 0.6, 0.6],
                                    "xyz": [0.45, 0.0, 0.5], "quat_wxyz": [1, 0, 0, 0]},
                                   {"name": "post", "type": "cylinder", "radius": 0.03,
                                    "length": 0.3, "xyz": [0.3, 0.5, 0.15]}]},
           "problems": [{"id": 0, "scene": "box/0001", "seed": 0,
                         "start": [-1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.785],
                         "goal": [1.2, 0.3, 0.0, -1.8, 0.0, 2.0, 0.785]}]}


@pytest.mark.skipif(not venvs.is_ready("vamp"),
                    reason="no local VAMP build (bench/README-peers.md says how to make one)")
def test_the_runner_plans_with_both_timers(tmp_path: Path) -> None:
    problems, results = tmp_path / "plan.json", tmp_path / "vamp.json"
    problems.write_text(json.dumps(BLOCKED))
    subprocess.run([str(venvs.python_path("vamp")), str(ROOT / "bench/peers/run_vamp_plan.py"),
                    str(problems), str(results)], check=True, cwd=ROOT, timeout=300)
    doc = json.loads(results.read_text())
    r = doc["results"][0]
    assert doc["peer"] == "vamp" and r["success"], r
    assert r["path"][0] == pytest.approx(BLOCKED["problems"][0]["start"], abs=1e-6)
    assert r["path"][-1] == pytest.approx(BLOCKED["problems"][0]["goal"], abs=1e-6)
    assert 0 < r["own_seconds"] <= r["seconds"]
    assert r["own_seconds"] == pytest.approx(r["plan_own_seconds"] + r["simplify_own_seconds"])
