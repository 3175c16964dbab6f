"""Carrying stage: what planning with an attached object costs. The KR60's ``table`` problems of
the planning stage (``plan_KR60.json``), planned by usar-arm bare and carrying the table's part
(a 0.12 x 0.12 x 0.10 m box under the tool: centred 5 cm out along the TCP's axis, the gripper
allowed to touch it), in alternating rounds; every path judged by the independent judge
(``verify.Judge``), which is given the part (shape, link, grasp, touch links) and places it
itself. MPlib plans the same problems carrying the same part (its attached object,
``bench/peers/run_mplib_plan.py``). Problems whose start or goal the carried part makes collide
(by the judge) are left out of all, and counted.

As a solver (our side)::

    python bench/carry.py PROBLEMS.json RESULTS.json

plans with ``plan_to_joints`` for the robot carrying the problem file's ``attached`` objects
(``Robot.carrying``; the scene's object of a carried object's name is that object, not an
obstacle), as ``plan.py`` does for the bare arm (2 s budget, the same timing).
"""

from __future__ import annotations

import sys
import time
from typing import Any

import common
import numpy as np
import verify
from common import Context, peerio
from plan import scene_solver

from usar_arm.core.shapes import Box, CylinderShape, Sphere
from usar_arm.core.spatial import matrix_from_quat, transform
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.ompl_adapter import OmplOptions
from usar_arm.planning.robot import robot_from_files

PART = {"name": "part", "type": "box", "size": [0.12, 0.12, 0.10], "xyz": [0.0, 0.0, 0.05],
        "quat_wxyz": [1.0, 0.0, 0.0, 0.0], "link": "KR60gripper_tcp",
        "touch_links": ["KR60gripper"]}
"""The carried part, in the judge's format (a scene item in the link's frame, its link and
touch links)."""
SCENE = "table"
COST_LIMIT = 1.3
"""Target: the median time carrying the part / the median time bare, same problems."""


def body_of(item: dict[str, Any]) -> AttachedBody:
    """usar-arm's body of a problem file's ``attached`` item (box, cylinder or sphere)."""
    kind = item["type"]
    shape = (Box(tuple(float(v) for v in item["size"])) if kind == "box" else  # type: ignore[arg-type]
             CylinderShape(float(item["radius"]), float(item["length"])) if kind == "cylinder"
             else Sphere(float(item["radius"])))
    grasp = transform(matrix_from_quat(item["quat_wxyz"]), np.asarray(item["xyz"], float))
    return AttachedBody(item["name"], item["link"], shape, grasp,
                        tuple(item.get("touch_links", ())))


def solver_main(argv: list[str] | None = None) -> int:
    spec, out = peerio.args()
    bare = robot_from_files(spec["urdf"], spec["srdf"])
    robot = bare.carrying([body_of(item) for item in spec.get("attached", [])])
    options = OmplOptions(time_limit=float(spec["time_limit_s"]), seed=0)

    def planner(plan: Any) -> dict[str, Any]:
        return {"planner": "direct" if plan.ompl is None else plan.ompl.planner}

    enter, solve = scene_solver(spec, options, planner, robot=robot)
    peerio.write(out, peer="usar-arm carrying", dist="usar-arm", stage="carry",
                 results=peerio.solve_by_scene(spec["problems"], enter, solve),
                 settings={"call": "planning.ptp.plan_to_joints on Robot.carrying",
                           "ompl": vars(options), "attached": spec.get("attached", [])},
                 notes="seconds = start/goal checks + straight-line check + RRTConnect + "
                       "simplification; OMPL seeded once per process")
    return 0


# ------------------------------------------------------------------------------ the stage
def _problems(ctx: Context) -> tuple[dict[str, Any], int]:
    """The table problems of the planning set whose start and goal the carried part leaves
    free (by the judge), as a problem file carrying the part; and how many were left out."""
    _, spec = ctx.problem("plan_KR60")
    table = [p for p in spec["problems"] if p["scene"] == SCENE]
    carry = {**spec, "scenes": {SCENE: spec["scenes"][SCENE]},
             "scene_files": {k: v for k, v in (spec.get("scene_files") or {}).items()
                             if k == SCENE}, "attached": [PART]}
    judge = verify.Judge.for_scene(carry, SCENE)
    free = [p for p in table if not judge.collides(np.asarray(p["start"], float))
            and not judge.collides(np.asarray(p["goal"], float))]
    return {**carry, "problems": free}, len(table) - len(free)


def run(ctx: Context) -> dict[str, Any]:
    """Plan the same problems bare and carrying the part; judge each with what it carried."""
    started = time.perf_counter()
    spec, left_out = _problems(ctx)
    path = ctx.work / "carry_KR60.json"
    common.write_json(path, spec, indent=None, digits=common.PROBLEM_DIGITS)
    solvers = [common.ours("usar-arm", "plan.py", note="plan_to_joints, the bare arm"),
               common.ours("usar-arm carrying", "carry.py",
                           note="plan_to_joints, the arm carrying the part"),
               ctx.peer("mplib", "plan", "planner.plan (RRTConnect + simplify) carrying the "
                        "part: planning_world.attach_object with its touch links")]
    outcomes = common.run_alternating(spec, solvers, ctx.work, ctx.rounds, "carry_KR60")
    judges = {"usar-arm": verify.Judge.for_scene({**spec, "attached": []}, SCENE),
              "usar-arm carrying": verify.Judge.for_scene(spec, SCENE)}
    budget = float(spec["time_limit_s"])

    def check_with(judge: verify.Judge) -> common.Check:
        def check(p: dict[str, Any], r: dict[str, Any]) -> dict[str, Any]:
            c = verify.check_path(judge, p, r)
            in_time = r.get("seconds") is not None and r["seconds"] <= budget
            return {"verified": c.verified and in_time, "collision_free": c.collision_free,
                    "in_time": in_time, "waypoints": c.waypoints,
                    "line_blocked": p.get("line_blocked")}
        return check

    case = common.build_case(path, spec, outcomes, check_with(judges["usar-arm carrying"]),
                             checks={"usar-arm": check_with(judges["usar-arm"])})
    case["left_out"] = left_out
    case["attached"] = PART
    case["cost"] = _cost(case)
    cases = {"KR60 table, carrying the part": case}
    return common.stage_document("carry", ctx.mode, {"rounds": ctx.rounds,
                                                     "judge_step": verify.PATH_STEP,
                                                     "attached": PART}, cases,
                                 _targets(case), started)


def _cost(case: dict[str, Any]) -> dict[str, Any]:
    """Carrying / bare: the ratio of the medians, and the median of per-problem ratios (over
    the problems both answered in time), overall and on the problems whose straight line is
    blocked."""
    bare, held = (case["solvers"][n].get("raw") or {} for n in ("usar-arm", "usar-arm carrying"))
    if not bare or not held:
        return {}
    times = {i: t for i, t in zip(bare["id"], bare["seconds"], strict=True) if t}
    blocked = {i for i, b in zip(bare["id"], bare["line_blocked"], strict=True) if b}
    out: dict[str, Any] = {}
    for label, keep in (("all", None), ("line_blocked", blocked)):
        pairs = [(t, times[i]) for i, t in zip(held["id"], held["seconds"], strict=True)
                 if t and i in times and (keep is None or i in keep)]
        a, b = common.stats([x for x, _ in pairs]), common.stats([y for _, y in pairs])
        out[label] = {"problems": len(pairs), "median_ratio": common.ratio(a["median"],
                                                                           b["median"]),
                      "per_problem_median": float(np.median([x / y for x, y in pairs]))
                      if pairs else None, "carrying_s": a, "bare_s": b}
    return out


def _targets(case: dict[str, Any]) -> list[dict[str, Any]]:
    held = case["solvers"]["usar-arm carrying"].get("summary", {})
    cost = case.get("cost", {}).get("all", {})
    mp = case["ratios"].get("mplib", {}).get("usar-arm carrying", {})
    n = case["problems"]["count"]
    return [
        common.target(f"Plan KR60 carrying the part, {n} table problems: verified (the judge "
                      "carrying it too) within 2 s", held.get("success_rate"), 1.0, ">=",
                      "fraction"),
        common.target("Plan KR60 carrying the part, median time / the bare arm's median "
                      "(same problems, same run)", cost.get("median_ratio"), COST_LIMIT, "<=",
                      "ratio"),
        common.target("Plan KR60 carrying the part, median time / mplib's median carrying it "
                      "(same problems, same run)", mp.get("median"), 0.5, "<=", "ratio",
                      "" if mp else "mplib not run"),
    ]


if __name__ == "__main__":
    sys.exit(solver_main())
