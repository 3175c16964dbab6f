"""Planning stage: collision-free joint-space paths between seeded start/goal pairs (KR60 in
empty, table, shelf, cage; the 7-joint Fanuc_M16iB20 in the same scenes; the KR60 among 1 to
1,000 boxes), usar-arm beside mplib (``plan_qpos``'s RRTConnect + simplification) and roboplan
(RRT-Connect + shortcutting).

As a solver (our side)::

    python bench/plan.py PROBLEMS.json RESULTS.json

Timed: ``usar_arm.planning.ptp.plan_to_joints`` (start/goal checks, the straight line when it is
free, else OMPL RRTConnect + simplification), 2 s budget; ``seconds`` is planning +
simplification, as the peers'. ``duration_s``: our default timing (Ruckig, stop at waypoints,
full limits) of that path, timed separately (``topp_seconds``). OMPL's RNG is seeded once per
process (an OMPL 2.x limitation), so our figures are reproducible per process, not per problem;
mplib and roboplan are seeded per problem.

Every returned path is checked with the judge (``verify.check_path``): it must start at the
start, end at the goal, stay within the limits, and be collision-free at every configuration
0.005 rad apart along it; and it must have been found within the 2 s budget.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import common
import numpy as np
import verify
from common import Context, peerio
from scenes import from_json as scene_from_json
from tesseract_config import with_tesseract

from usar_arm.control.timing import stop_at_waypoints
from usar_arm.control.trajectory import MotionLimits
from usar_arm.core.errors import UsarArmError
from usar_arm.planning.ompl_adapter import OmplOptions
from usar_arm.planning.ptp import PtpPlan, plan_to_joints
from usar_arm.planning.robot import Robot, robot_from_files

CASES = (("KR60", "plan_KR60"), ("Fanuc_M16iB20", "plan_Fanuc_M16iB20"),
         ("boxes", "plan_KR60_boxes"))


def scene_solver(spec: dict[str, Any], options: OmplOptions,
                 extra: Callable[[PtpPlan], dict[str, Any]], robot: Robot | None = None
                 ) -> tuple[Callable[[str], None], Callable[[dict[str, Any]], dict[str, Any]]]:
    """``enter(scene)`` (untimed: builds the scene's collision world once) and
    ``solve(problem)`` (``plan_to_joints`` with ``options``, timed; ``extra(plan)`` adds fields
    to an answer, untimed) for the robot (default: the problem file's URDF and SRDF) and scenes
    of a problem file."""
    robot = robot if robot is not None else robot_from_files(spec["urdf"], spec["srdf"])
    chain = robot.chain
    lo, hi = chain.lower(), chain.upper()
    worlds: dict[str, Any] = {}

    def enter(name: str) -> None:
        if name not in worlds:
            worlds[name] = robot.collision_world(scene_from_json(name, spec["scenes"][name]))
        worlds["current"] = worlds[name]

    def solve(p: dict[str, Any]) -> dict[str, Any]:
        begin = time.perf_counter()
        try:
            plan = plan_to_joints(worlds["current"], chain.joint_names, lo, hi,
                                  np.array(p["start"]), np.array(p["goal"]), options)
        except UsarArmError as exc:
            return {"success": False, "seconds": time.perf_counter() - begin, "path": None,
                    "status": f"{type(exc).__name__}: {exc}"}
        sec = time.perf_counter() - begin
        return {"success": True, "seconds": sec, "path": plan.waypoints, **extra(plan)}

    return enter, solve


def solver_main(argv: list[str] | None = None) -> int:
    planner = None
    if len(sys.argv) > 2 and sys.argv[1] == "--planner":  # (the A/B's OMPL side)
        planner = sys.argv[2]
        del sys.argv[1:3]
    spec, out = peerio.args()
    chain = robot_from_files(spec["urdf"], spec["srdf"]).chain
    limits = MotionLimits.from_chain(chain, 1.0)
    options = OmplOptions(time_limit=float(spec["time_limit_s"]), seed=0)
    if planner:
        options = replace(options, planner=planner)

    def timing(plan: PtpPlan) -> dict[str, Any]:
        timed, topp = peerio.timed(stop_at_waypoints, chain.joint_names, plan.waypoints, limits)
        return {"duration_s": timed.duration, "topp_seconds": topp,
                "planner": "direct" if plan.ompl is None else plan.ompl.planner,
                "simplify_seconds": None if plan.ompl is None else plan.ompl.simplify_seconds}

    enter, solve = scene_solver(spec, options, timing)
    peerio.write(out, peer="usar-arm", dist="usar-arm", stage="plan",
                 results=peerio.solve_by_scene(spec["problems"], enter, solve),
                 settings={"call": "planning.ptp.plan_to_joints", "ompl": vars(options),
                           "duration": "control.timing.stop_at_waypoints, speed scale 1.0"},
                 notes="seconds = start/goal checks + straight-line check + RRTConnect + "
                       "simplification; OMPL seeded once per process")
    return 0


# ------------------------------------------------------------------------------ the stage
def _solvers(ctx: Context, case: str) -> list[common.Solver]:
    ompl = ctx.peer("tesseract", "plan", "task composer OMPLPipeline, default profiles (5 s "
                    "RRTConnect, not settable from Python), contact check and iterative spline")
    trajopt = replace(ompl, name="tesseract trajopt",
                      command=(*ompl.command, "--pipeline", "TrajOptPipeline"),
                      note="task composer TrajOptPipeline, default profiles (seeded with the "
                           "straight joint line), contact check and iterative spline")
    if case != "KR60":
        ompl = replace(ompl, skip=ompl.skip or "run on the KR60 problem set only")
        trajopt = replace(trajopt, skip=trajopt.skip or "run on the KR60 problem set only")
    return [common.ours("usar-arm", "plan.py", note="plan_to_joints: the compiled RRT-Connect "
                        "+ shortcut (OMPL's RRTConnect where it finds nothing)"),
            common.ours("usar-arm ompl", "plan.py", "--planner", "RRTConnect",
                        note="plan_to_joints with OMPL's RRTConnect + simplify (the A/B of "
                             "the default)"),
            ctx.peer("mplib", "plan", "planner.plan (RRTConnect + simplify), as plan_qpos; "
                     "checks edges at discrete states only"),
            ctx.peer("roboplan", "plan", "RRT-Connect + PathShortcutter"), ompl, trajopt]


FREE_LINE_RULE = ("cases: the problems whose straight start-goal line is blocked (the "
                  "planner must plan), and every target and slope on them; free_line: the "
                  "problems whose straight line is free (returned before any planner runs), "
                  "reported apart")


def run(ctx: Context) -> dict[str, Any]:
    """Run the planning cases and return the stage document: ``cases`` holds the problems
    whose straight line is blocked, ``free_line`` the others (see :data:`FREE_LINE_RULE`)."""
    started = time.perf_counter()
    cases: dict[str, Any] = {}
    free_line: dict[str, Any] = {}
    for case, key in CASES:
        path, spec = ctx.problem(key)
        if case == "KR60":
            spec = with_tesseract(spec, ctx.work)
        outcomes = common.run_alternating(spec, _solvers(ctx, case), ctx.work, ctx.rounds, key)
        robot = robot_from_files(spec["urdf"], spec["srdf"])
        judges = {n: verify.Judge.for_scene(spec, n) for n in spec["scenes"]}
        budget = float(spec["time_limit_s"])

        def check(p: dict[str, Any], r: dict[str, Any], robot: Any = robot,
                  judges: dict[str, Any] = judges, budget: float = budget) -> dict[str, Any]:
            c = verify.check_path(judges[p["scene"]], p, r)
            in_time = r.get("seconds") is not None and r["seconds"] <= budget
            return {"verified": c.verified and in_time, "ends_match": c.ends_match,
                    "ends_off_by_turns": c.ends_off_by_turns, "in_time": in_time,
                    "within_limits": c.within_limits, "collision_free": c.collision_free,
                    "path_length": c.length, "waypoints": c.waypoints,
                    "duration_s": r.get("duration_s"), "scene": p["scene"],
                    "line_blocked": p.get("line_blocked")}

        groups = ([(n, [p for p in spec["problems"] if p["scene"] == n])
                   for n in spec["scenes"]] if case == "boxes" else
                  [(case, spec["problems"])])
        for name, group in groups:
            head = {"robot": spec["robot"], "dof": len(spec["joint_names"])}
            if case == "boxes":
                head["obstacles"] = len(spec["scenes"][name])
            for blocked, into in ((True, cases), (False, free_line)):
                part = [p for p in group if bool(p.get("line_blocked")) is blocked]
                if part:
                    into[name] = {**head, "scenes": list(dict.fromkeys(p["scene"] for p in part)),
                                  "straight_line": "blocked" if blocked else "free",
                                  **common.build_case(path, {**spec, "problems": part},
                                                      common.subset(outcomes, {
                                                          p["id"] for p in part}),
                                                      check, _extra)}
    doc = common.stage_document("plan", ctx.mode, {"rounds": ctx.rounds,
                                                   "judge_step": verify.PATH_STEP,
                                                   "cases": FREE_LINE_RULE},
                                cases, _targets(cases), started)
    doc["free_line"] = free_line
    doc["profile"] = _profile(ctx)
    return doc


def _profile(ctx: Context) -> dict[str, Any]:
    """Where a KR60 plan's time goes (``plan_profile.py``, its own process, untimed against the
    peers)."""
    path, _ = ctx.problem("plan_KR60")
    out = ctx.work / "plan_profile.json"
    proc = subprocess.run([sys.executable, str(Path(__file__).parent / "plan_profile.py"),
                           str(path), str(out)], env={**os.environ, **common.ENVIRONMENT},
                          capture_output=True, text=True, timeout=600, check=False)
    if proc.returncode != 0:
        return {"error": proc.stderr[-2000:]}
    return dict(json.loads(out.read_text()))


def _extra(raw: dict[str, list[Any]]) -> dict[str, Any]:
    """Wrong answers (answered, not verified) and per-scene medians."""
    wrong = sum(1 for a, v in zip(raw["answered"], raw["verified"], strict=True) if a and not v)
    hits = sum(1 for c in raw["collision_free"] if c is False)
    per_scene = {}
    for sc in dict.fromkeys(raw["scene"]):
        rows = [k for k, s in enumerate(raw["scene"]) if s == sc]
        secs = [raw["seconds"][k] for k in rows]
        per_scene[sc] = {"problems": len(rows),
                         "verified": sum(1 for k in rows if raw["verified"][k]),
                         "time_all_s": common.stats(secs)}
    durations = [d for d, v in zip(raw["duration_s"], raw["verified"], strict=True) if v and d]
    turns = sum(1 for t in raw["ends_off_by_turns"] if t)
    late = sum(1 for a, t in zip(raw["answered"], raw["in_time"], strict=True) if a and not t)
    return {"answered_but_wrong": wrong, "paths_in_collision": hits,
            "ends_off_by_whole_turns": turns, "answered_after_budget": late,
            "duration_s": common.stats(durations), "by_scene": per_scene}


NO_CASE: dict[str, Any] = {"solvers": {"usar-arm": {}}, "ratios": {}, "problems": {"count": 0}}
"""A case none of whose problems has a blocked straight line: its targets fail as missing."""


def _targets(cases: dict[str, Any]) -> list[dict[str, Any]]:
    """The targets, on the problems whose straight line is blocked."""
    cases = {"KR60": NO_CASE, "Fanuc_M16iB20": NO_CASE, **cases}
    kr = cases["KR60"]
    ours = kr["solvers"]["usar-arm"].get("summary", {})
    mp = kr["ratios"].get("mplib", {}).get("usar-arm", {})
    n = kr["problems"]["count"]
    fa = cases["Fanuc_M16iB20"]["solvers"]["usar-arm"].get("summary", {})
    return [
        common.target(f"Plan KR60, {n} problems over 4 scenes (blocked straight line): "
                      "verified within 2 s",
                      ours.get("success_rate"), 1.0, ">=", "fraction"),
        common.target("Plan KR60 median planning + simplification",
                      (ours.get("time_all_s") or {}).get("median"), 0.020, "<=", "s"),
        common.target("Plan KR60 median time / mplib's median (same problems, same run)",
                      mp.get("median"), 0.5, "<=", "ratio",
                      "" if mp else "mplib not run"),
        common.target("Plan Fanuc_M16iB20 (7 joints, blocked straight line): verified within "
                      "2 s",
                      fa.get("success_rate"), 1.0, ">=", "fraction"),
        *_speed_targets(ours, fa),
        *_peer_targets(cases),
    ]


SPEED_MEDIAN_S = {"KR60": 0.3e-3, "Fanuc_M16iB20": 0.4e-3}
"""The planning-speed issue's medians (planning + simplification, blocked straight line)."""


def _speed_targets(kr60: dict[str, Any], fanuc: dict[str, Any]) -> list[dict[str, Any]]:
    """The planning-speed issue's targets: each learnt arm's median against its bound."""
    return [common.target(f"Plan {robot} median (planning-speed target)",
                          (summary.get("time_all_s") or {}).get("median"),
                          SPEED_MEDIAN_S[robot], "<=", "s")
            for robot, summary in (("KR60", kr60), ("Fanuc_M16iB20", fanuc))]


def _ratio(a: float | None, b: float | None) -> float | None:
    return a / b if a and b else None


def _peer_targets(cases: dict[str, Any]) -> list[dict[str, Any]]:
    """The speed targets against the fastest peer (roboplan), same problems, same run."""
    out = []
    for robot, limit in (("KR60", 0.8), ("Fanuc_M16iB20", 1.0)):
        solvers = cases[robot]["solvers"]
        ours = (solvers["usar-arm"].get("summary", {}).get("time_all_s") or {})
        peer = (solvers.get("roboplan", {}).get("summary", {}).get("time_all_s") or {})
        note = "" if peer else "roboplan not run"
        out.append(common.target(f"Plan {robot} median / roboplan's median",
                                 _ratio(ours.get("median"), peer.get("median")), limit, "<=",
                                 "ratio", note))
        if robot == "KR60":
            out.append(common.target("Plan KR60 p90 / roboplan's p90",
                                     _ratio(ours.get("p90"), peer.get("p90")), 1.0, "<=",
                                     "ratio", note))
    empty = (cases["KR60"]["solvers"]["usar-arm"].get("summary", {}).get("by_scene", {})
             .get("empty", {}).get("time_all_s") or {})
    out.append(common.target("Plan KR60 in the empty scene, median", empty.get("median"),
                             0.002, "<=", "s"))
    boxes = cases.get("boxes_1000", {}).get("solvers", {}).get("usar-arm", {}).get("summary")
    if boxes:
        out.append(common.target("Plan KR60 among 1,000 boxes: verified within 2 s",
                                 boxes.get("success_rate"), 1.0, ">=", "fraction"))
        out.append(common.target("Plan KR60 among 1,000 boxes, median",
                                 (boxes.get("time_all_s") or {}).get("median"), 0.1, "<=", "s"))
    return out


if __name__ == "__main__":
    sys.exit(solver_main())
