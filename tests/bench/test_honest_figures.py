"""What the benchmark measures, as issue 23 asked: the planners are ranked on problems whose
straight line is blocked with a tie rule blind to the current default, every solver warms up
in every scene alike, and a solver that claims more (collision-free IK answers) is judged on
that claim too."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import common  # noqa: E402
import peerio  # noqa: E402
import planners  # noqa: E402


def _planner(success: float, median: float) -> dict[str, Any]:
    return {"summary": {"success_rate": success, "verified": round(10 * success),
                        "problems": 10, "time_all_s": {"median": median, "p90": median}}}


def test_planners_tied_within_noise_are_ordered_alphabetically_not_by_the_default() -> None:
    ranking = planners.rank({"RRTConnect": _planner(1.0, 0.0030), "RRT": _planner(1.0, 0.0032),
                             "KPIECE": _planner(1.0, 0.0031), "PRM": _planner(1.0, 0.0040),
                             "RRTstar": _planner(0.9, 0.0010)})
    assert [r["planner"] for r in ranking] == ["KPIECE", "RRT", "RRTConnect", "PRM", "RRTstar"]
    assert ranking[0]["tied_with"] == ["RRTConnect", "RRT"] and ranking[3]["tied_with"] == []
    assert "alphabetically" in planners.RANKING_RULE


def test_the_planners_run_on_blocked_problems_of_every_scene_and_free_ones_apart() -> None:
    spec = {"scenes": {"empty": [], "table": []},
            "problems": [{"id": i, "scene": "empty" if i < 6 else "table",
                          "line_blocked": i % 2 == 0} for i in range(12)]}
    chosen = planners.problems(spec, per_scene=2)
    assert [(p["id"], p["line_blocked"]) for p in chosen] == [
        (0, True), (1, False), (2, True), (3, False),
        (6, True), (7, False), (8, True), (9, False)]
    assert len(planners.problems(spec, None)) == 12


def test_every_scene_is_warmed_up_alike() -> None:
    calls: list[int] = []
    problems = [{"id": i, "scene": "a" if i < 3 else "b"} for i in range(6)]
    out = peerio.solve_by_scene(problems, lambda _: None,
                                lambda p: calls.append(p["id"]) or {"success": True})
    assert calls == [0, 0, 1, 2, 3, 3, 4, 5]  # the first of each scene once, untimed
    assert [r["id"] for r in out] == list(range(6))


def test_a_solver_that_claims_more_is_judged_on_it(tmp_path: Path) -> None:
    spec = {"problems": [{"id": 0}, {"id": 1}]}
    (tmp_path / "p.json").write_text("{}")
    results = [{"id": 0, "success": True, "seconds": 1e-3}, {"id": 1, "success": True,
                                                              "seconds": 1e-3}]
    outcomes = {n: common.Outcome(common.Solver(n, "ours", ()), list(results))
                for n in ("plain", "checked")}
    case = common.build_case(tmp_path / "p.json", spec, outcomes,
                             lambda p, r: {"verified": True},
                             checks={"checked": lambda p, r: {"verified": p["id"] == 0}})
    assert case["solvers"]["plain"]["summary"]["verified"] == 2
    assert case["solvers"]["checked"]["summary"]["verified"] == 1


def test_a_solver_process_knows_when_it_was_launched(monkeypatch: Any) -> None:
    import time

    monkeypatch.setenv(common.LAUNCHED_AT, repr(time.time() - 2.0))
    assert 2.0 <= common.since_launch() < 10.0


def test_a_later_run_of_some_stages_is_recorded_beside_the_whole_run(tmp_path: Path) -> None:
    import run

    path = tmp_path / "run.json"
    whole = {"stages": list(run.STAGES), "finished": "t0"}
    assert run._run_record(path, whole) == whole  # nothing there yet
    common.write_json(path, whole)
    later = {"stages": ["workspace"], "finished": "t1"}
    assert run._run_record(path, later) == {**whole, "later_runs": [later]}
    assert run._run_record(path, {"stages": list(run.STAGES), "finished": "t2"})["finished"] \
        == "t2"
