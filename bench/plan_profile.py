"""Where a plan's time goes: the KR60 planning problems once more, untimed against the peers,
with the collision world's entry points wrapped in timers.

    python bench/plan_profile.py PROBLEMS.json RESULTS.json

Stages (seconds per plan, mean over the problems): state checks (``in_collision``, OMPL's state
validity), edge checks in the compiled walk (``bounds_walk.walk``: forward kinematics,
bounding-volume verdicts, clearance skipping), edge checks in python-fcl
(``ExactJudge.any_contact`` on the configurations the walk left undecided), and the rest (OMPL's
own search and simplification, the Python glue between them). The wrappers cost a little
themselves, so the total is a bit above the timed stage's; the shares are what this table is
for.
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from scenes import from_json as scene_from_json

from usar_arm.core.errors import UsarArmError
from usar_arm.planning import bounds_walk, collision, exact
from usar_arm.planning.ompl_adapter import OmplOptions
from usar_arm.planning.ptp import plan_to_joints
from usar_arm.planning.robot import robot_from_files

STAGES = ("state checks", "edge walk (compiled)", "edge exact (python-fcl)")


def _timed(spent: dict[str, float], name: str, fn: Callable[..., Any]) -> Callable[..., Any]:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        begin = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            spent[name] += time.perf_counter() - begin
    return wrapper


def profile(spec: dict[str, Any]) -> dict[str, Any]:
    """Per-stage mean seconds per plan over ``spec``'s problems (one pass after a warm one)."""
    robot = robot_from_files(spec["urdf"], spec["srdf"])
    chain = robot.chain
    options = OmplOptions(time_limit=float(spec["time_limit_s"]), seed=0)
    worlds = {n: robot.collision_world(scene_from_json(n, s)) for n, s in spec["scenes"].items()}
    spent = dict.fromkeys(STAGES, 0.0)
    originals = (collision.CollisionWorld.in_collision, bounds_walk.walk,
                 exact.ExactJudge.any_contact)

    def solve_all() -> float:
        begin = time.perf_counter()
        for p in spec["problems"]:
            try:
                plan_to_joints(worlds[p["scene"]], chain.joint_names, chain.lower(),
                               chain.upper(), np.array(p["start"]), np.array(p["goal"]), options)
            except UsarArmError:
                pass
        return time.perf_counter() - begin

    def state_check(world: Any, q: Any) -> bool:
        exact_before, begin = spent[STAGES[2]], time.perf_counter()
        try:
            return bool(originals[0](world, q))
        finally:  # its FCL share is counted under the exact stage only
            spent[STAGES[0]] += (time.perf_counter() - begin
                                 - (spent[STAGES[2]] - exact_before))

    solve_all()  # warm: lazy models, compiled kernels loaded
    collision.CollisionWorld.in_collision = state_check  # type: ignore[method-assign]
    bounds_walk.walk = _timed(spent, STAGES[1], originals[1])
    exact.ExactJudge.any_contact = _timed(spent, STAGES[2], originals[2])  # type: ignore
    try:
        total = solve_all()
    finally:
        (collision.CollisionWorld.in_collision, bounds_walk.walk,
         exact.ExactJudge.any_contact) = originals  # type: ignore[method-assign]
    n = len(spec["problems"])
    rows = {name: seconds / n for name, seconds in spent.items()}
    rows["OMPL search, simplification and glue"] = max(0.0, total / n - sum(rows.values()))
    return {"problems": n, "seconds_per_plan": total / n, "stages_s": rows}


def main(argv: list[str] | None = None) -> int:
    """Profile the problems of a plan file whose straight line is blocked (the others return
    the line before any planner runs)."""
    args = sys.argv[1:] if argv is None else argv
    spec = json.loads(Path(args[0]).read_text())
    spec["problems"] = [p for p in spec["problems"] if p.get("line_blocked", True)]
    Path(args[1]).write_text(json.dumps(profile(spec), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
