"""Where a plan's time goes: a plan file's problems once more, untimed against the peers, with
the collision world's entry points wrapped in timers.

    python bench/plan_profile.py PROBLEMS.json RESULTS.json [--planner NAME]

The plan stage runs it on the KR60's problems, the robots stage on the Panda's MotionBenchMaker
problems (a file with a ``group`` or ``base_link`` builds the robot from them, as the robots
stage does). Each problem is reseeded with its seed, as the stages do.

Two views, seconds per plan, means over the problems:

* by kind of work (``stages_s``): state checks (``in_collision``: a state's compiled verdicts and
  python-fcl), the compiled edge walk (``bounds_walk.walk``: forward kinematics,
  bounding-volume verdicts, clearance skipping), python-fcl on the configurations the walk left
  undecided (``ExactJudge.any_contact``), and the rest (:data:`REST`: the planner's own search
  and simplification, OMPL's or the compiled planner's, whose walks run inside its kernels and
  count here, and the Python glue between them);
* by phase (``phases_s``): the planner's search, its simplification, and the rest of
  ``plan_to_joints`` (the start and goal checks, the straight line, the dense check of the path
  and its repairs).

The wrappers cost a little themselves, so the total is a bit above the timed stage's; the
shares are what this table is for. ``seconds`` (median, p90) are the unwrapped plans' times.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scenes import from_json as scene_from_json

from usar_arm.core.errors import UsarArmError
from usar_arm.planning import bounds_walk, collision, exact
from usar_arm.planning.ompl_adapter import OmplOptions, reseed
from usar_arm.planning.ptp import plan_to_joints
from usar_arm.planning.robot import RobotOptions, robot_from_files

STAGES = ("state checks", "edge walk (compiled)", "edge exact (python-fcl)")
REST = "OMPL search, simplification and glue"
"""The rest of a plan's time (the key the docs' figures read): the planner's own search and
simplification (OMPL's, or the compiled planner's kernels, their walks included) and the Python
between."""
PHASES = ("search", "simplification", "checks, straight line, path check and repair")


def _timed(spent: dict[str, float], name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        begin = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            spent[name] += time.perf_counter() - begin
    return wrapper


def _robot(spec: dict[str, Any]) -> Any:
    if "group" in spec or "base_link" in spec:
        return robot_from_files(spec["urdf"], spec["srdf"], options=RobotOptions.of(
            spec.get("group"), None if spec.get("group") else spec["base_link"],
            spec["tip_link"]))
    return robot_from_files(spec["urdf"], spec["srdf"])


def profile(spec: dict[str, Any], planner: str | None = None) -> dict[str, Any]:
    """Per-stage and per-phase mean seconds per plan over ``spec``'s problems (one timed pass,
    one wrapped pass, after a warm one)."""
    robot = _robot(spec)
    chain = robot.chain
    options = OmplOptions(time_limit=float(spec["time_limit_s"]), seed=0)
    if planner:
        options = replace(options, planner=planner)
    worlds = {n: robot.collision_world(scene_from_json(n, s)) for n, s in spec["scenes"].items()}
    spent = dict.fromkeys(STAGES, 0.0)
    phases = dict.fromkeys(PHASES, 0.0)
    originals = (collision.CollisionWorld.in_collision, bounds_walk.walk,
                 exact.ExactJudge.any_contact)

    def solve_all(record: bool) -> list[float]:
        seconds = []
        for p in spec["problems"]:
            reseed(int(p.get("seed", 0)))
            begin = time.perf_counter()
            try:
                plan = plan_to_joints(worlds[p["scene"]], chain.joint_names, chain.lower(),
                                      chain.upper(), np.array(p["start"]), np.array(p["goal"]),
                                      options)
            except UsarArmError:
                seconds.append(time.perf_counter() - begin)
                continue
            seconds.append(time.perf_counter() - begin)
            if record:
                search = plan.ompl.planning_seconds if plan.ompl else 0.0
                simplify = plan.ompl.simplify_seconds if plan.ompl else 0.0
                phases[PHASES[0]] += search
                phases[PHASES[1]] += simplify
                phases[PHASES[2]] += max(0.0, seconds[-1] - search - simplify)
        return seconds

    def state_check(world: Any, q: Any) -> bool:
        exact_before, begin = spent[STAGES[2]], time.perf_counter()
        try:
            return bool(originals[0](world, q))
        finally:  # its FCL share is counted under the exact stage only
            spent[STAGES[0]] += (time.perf_counter() - begin
                                 - (spent[STAGES[2]] - exact_before))

    solve_all(False)  # warm: lazy models, compiled kernels loaded
    plain = solve_all(True)
    collision.CollisionWorld.in_collision = state_check  # type: ignore[method-assign]
    bounds_walk.walk = _timed(spent, STAGES[1], originals[1])
    exact.ExactJudge.any_contact = _timed(spent, STAGES[2], originals[2])  # type: ignore
    try:
        total = sum(solve_all(False))
    finally:
        (collision.CollisionWorld.in_collision, bounds_walk.walk,
         exact.ExactJudge.any_contact) = originals  # type: ignore[method-assign]
    n = len(spec["problems"])
    rows = {name: seconds / n for name, seconds in spent.items()}
    rows[REST] = max(0.0, total / n - sum(rows.values()))
    return {"problems": n, "planner": options.planner, "seconds_per_plan": total / n,
            "seconds": {"median": float(np.median(plain)),
                        "p90": float(np.percentile(plain, 90)), "mean": float(np.mean(plain))},
            "stages_s": rows, "phases_s": {k: v / n for k, v in phases.items()}}


def main(argv: list[str] | None = None) -> int:
    """Profile the problems of a plan file whose straight line is blocked (the others return
    the line before any planner runs)."""
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("problems", type=Path)
    ap.add_argument("results", type=Path)
    ap.add_argument("--planner", help="the planner (default: OmplOptions')")
    a = ap.parse_args(argv)
    spec = json.loads(a.problems.read_text())
    spec["problems"] = [p for p in spec["problems"] if p.get("line_blocked", True)]
    a.results.write_text(json.dumps(profile(spec, a.planner), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
