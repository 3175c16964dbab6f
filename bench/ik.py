"""IK stage: "the solution nearest a seed" for seeded reachable poses (KR60: analytic path;
Fanuc_M16iB20, 7 joints with a prismatic rail: numeric path), usar-arm beside TRAC-IK
(pytracik), mplib, roboplan, py-opw-kinematics and ikpy.

As a solver (our side, in its own process, like the peers' runners)::

    python bench/ik.py --api single|batch PROBLEMS.json RESULTS.json

``single``: ``IKSolver.solve(pose, seed)`` timed per pose (the first three poses solved once
before, untimed, as the peers). ``batch``: ``IKSolver.solve_batch`` over blocks of
:data:`BATCH` poses; a pose's time is its block's time / the block size (s per pose).

Every answer is checked here with Pinocchio FK of the shared URDF: within the problem's
tolerance (1e-5 m, 1e-5 rad) and the joint limits, or it is not a success. The answers of the
solvers that check collisions (:data:`COLLISION_CHECKED`: ``usar-arm checked``, mplib,
roboplan) must also be free of self-collision by the judge (``verify.Judge``, SRDF pairs
disabled, no obstacles), or they are not a success either.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import asdict, replace
from typing import Any

import common
import numpy as np
import verify
from common import Context, peerio
from judge_reading import JudgedRobot

from usar_arm.core.errors import IKError
from usar_arm.planning.robot import robot_from_files

BATCH = 1000
"""Poses per ``solve_batch`` call (at most; the per-pose cost levels off near 1,000)."""
ROBOTS = ("KR60", "Fanuc_M16iB20")
COLLISION_CHECKED = ("usar-arm checked", "mplib", "roboplan")
"""Solvers whose answers claim to be free of self-collision: the judge checks that too."""
SLOW_PEER_LIMIT = {("KR60", "ikpy"): 2000, ("Fanuc_M16iB20", "ikpy"): 1000}
"""Full run: ikpy (pure Python, ~15-30 ms a pose here) solves only the first poses of the set,
to keep the whole run under 30 minutes; its ratios are taken over those poses."""


def _solve_single(spec: dict[str, Any], checked: bool = False) -> list[dict[str, Any]]:
    robot = robot_from_files(spec["urdf"], spec["srdf"])
    ik = robot.ik_solver()
    world = robot.collision_world() if checked else None  # self-collisions, as mplib/roboplan

    def solve(p: dict[str, Any]) -> dict[str, Any]:
        target = verify.pose_matrix(p["xyz"], p["quat_wxyz"])
        seed = np.asarray(p["seed"], float)
        begin = time.perf_counter()
        try:
            q = ik.solve(target, seed, collision=world).best.q
        except IKError as exc:
            return {"success": False, "seconds": time.perf_counter() - begin, "q": None,
                    "status": type(exc).__name__}
        return {"success": True, "seconds": time.perf_counter() - begin, "q": q}

    return peerio.solve_all(spec["problems"], solve)


def _solve_batch(spec: dict[str, Any]) -> list[dict[str, Any]]:
    robot = robot_from_files(spec["urdf"], spec["srdf"])
    ik = robot.ik_solver()
    problems = spec["problems"]
    targets = np.array([verify.pose_matrix(p["xyz"], p["quat_wxyz"]) for p in problems])
    seeds = np.array([p["seed"] for p in problems], float)
    ik.solve_batch(targets[:3], seeds[:3])  # warm-up, as the single API and the peers
    out = []
    for lo in range(0, len(problems), BATCH):
        res, sec = peerio.timed(ik.solve_batch, targets[lo:lo + BATCH], seeds[lo:lo + BATCH])
        per = sec / len(res.success)
        for k, ok in enumerate(res.success):
            out.append({"id": problems[lo + k]["id"], "success": bool(ok), "seconds": per,
                        "q": res.q[k] if ok else None})
    return out


def solver_main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--api", choices=("single", "checked", "batch"), default="single")
    ap.add_argument("problems")
    ap.add_argument("results")
    a = ap.parse_args(argv)
    spec = common.read_json(common.Path(a.problems))
    robot = robot_from_files(spec["urdf"], spec["srdf"])
    ik = robot.ik_solver()
    results = (_solve_batch(spec) if a.api == "batch"
               else _solve_single(spec, checked=a.api == "checked"))
    api = {"single": "IKSolver.solve(pose, seed)",
           "checked": "IKSolver.solve(pose, seed, collision=self-collision world)",
           "batch": f"IKSolver.solve_batch, blocks of {BATCH}"}[a.api]
    peerio.write(a.results, peer=f"usar-arm ({a.api})", dist="usar-arm", stage="ik",
                 results=results, settings={"api": api, "method": ik.method,
                                            "options": asdict(ik.options)})
    return 0


# ------------------------------------------------------------------------------ the stage
def _solvers(ctx: Context, robot: str) -> list[common.Solver]:
    peers = ["pytracik", "mplib", "roboplan", "ikpy"] + (["opw"] if robot == "KR60" else [])
    notes = {"pytracik": "no collision check; TRAC-IK Speed, 5 ms timeout, 2 threads",
             "mplib": "collision-checked; Planner.IK: 20 CLIK starts",
             "roboplan": "collision-checked; SimpleIk, 2 restarts",
             "ikpy": "no collision check; scipy least_squares from the seed (full run: the "
                     "first poses only)",
             "opw": "no collision check; closed form; the KR60 is only nearly OPW (wrist 2 mm "
                    "off), so its answers are ~mm off the target"}
    return [common.ours("usar-arm", "ik.py", "--api", "single",
                        note="no collision check; IKSolver.solve(pose, seed), one call per pose"),
            common.ours("usar-arm checked", "ik.py", "--api", "checked",
                        note="collision-checked (self-collisions, as mplib and roboplan); "
                             "IKSolver.solve(pose, seed, collision=world)"),
            common.ours("usar-arm batch", "ik.py", "--api", "batch",
                        note=f"no collision check; IKSolver.solve_batch, {BATCH} poses per "
                             "call; time per pose"),
            *[ctx.peer(p, "ik", notes[p], SLOW_PEER_LIMIT.get((robot, p))) for p in peers],
            replace(ctx.peer("roboplan", "ik_unchecked",
                             "no collision check; SimpleIk, 2 restarts, check_collisions=False"),
                    name="roboplan unchecked")]


def run(ctx: Context) -> dict[str, Any]:
    """Run the IK cases and return the stage document."""
    started = time.perf_counter()
    cases: dict[str, Any] = {}
    for name in ROBOTS:
        path, spec = ctx.problem(f"ik_{name}")
        judged = JudgedRobot.from_files(spec["urdf"], spec["srdf"])
        kin = verify.Kinematics(judged, list(spec["joint_names"]))
        judge = verify.Judge(judged, [], list(spec["joint_names"]))
        tol = spec["tolerance"]
        outcomes = common.run_alternating(spec, _solvers(ctx, name), ctx.work, ctx.rounds,
                                          f"ik_{name}")

        def check(p: dict[str, Any], r: dict[str, Any], kin: Any = kin,
                  tol: dict[str, float] = tol) -> dict[str, Any]:
            c = verify.check_ik(kin, p, r, tol)
            return {"verified": c.verified, "position_error_m": c.position_error_m,
                    "orientation_error_rad": c.orientation_error_rad,
                    "within_limits": c.within_limits}

        def checked(p: dict[str, Any], r: dict[str, Any], judge: Any = judge,
                    check: Any = check) -> dict[str, Any]:
            row = check(p, r)  # (an answer off the target fails anyway: not checked)
            free = not judge.collides(np.asarray(r["q"], float)) if row["verified"] else None
            return {**row, "verified": row["verified"] and free is True, "collision_free": free}

        def extra(raw: dict[str, list[Any]]) -> dict[str, Any]:
            wrong = sum(1 for a, v in zip(raw["answered"], raw["verified"], strict=True)
                        if a and not v)
            pe = [x for x in raw["position_error_m"] if x is not None]
            oe = [x for x in raw["orientation_error_rad"] if x is not None]
            return {"answered_but_wrong": wrong,
                    "in_self_collision": sum(1 for f in raw.get("collision_free", [])
                                             if f is False),
                    "max_position_error_m": max(pe) if pe else None,
                    "max_orientation_error_rad": max(oe) if oe else None}

        cases[name] = {"robot": name, "dof": len(spec["joint_names"]), "tolerance": tol,
                       **common.build_case(path, spec, outcomes, check, extra,
                                           {n: checked for n in COLLISION_CHECKED})}
    return common.stage_document("ik", ctx.mode, {"rounds": ctx.rounds, "batch": BATCH},
                                 cases, _targets(cases), started)


def _targets(cases: dict[str, Any]) -> list[dict[str, Any]]:
    def s(case: str, solver: str) -> dict[str, Any]:
        return cases[case]["solvers"][solver].get("summary", {})

    kr, fa = s("KR60", "usar-arm"), s("KR60", "usar-arm batch")
    fs = s("Fanuc_M16iB20", "usar-arm")
    n = cases["KR60"]["problems"]["count"]
    return [
        common.target(f"IK KR60 success, {n} poses (single call)", kr.get("success_rate"),
                      0.999, ">=", "fraction"),
        common.target("IK KR60 mean time per pose, single call IKSolver.solve",
                      kr.get("time_all_s", {}).get("mean"), 1e-4, "<=", "s"),
        common.target("IK KR60 success (batch)", fa.get("success_rate"), 0.999, ">=",
                      "fraction"),
        common.target("IK KR60 mean time per pose, batch IKSolver.solve_batch",
                      fa.get("time_all_s", {}).get("mean"), 1e-4, "<=", "s"),
        common.target("IK Fanuc_M16iB20 (7 joints, numeric) success", fs.get("success_rate"),
                      0.995, ">=", "fraction"),
        common.target("IK Fanuc_M16iB20 mean time per pose (single call)",
                      fs.get("time_all_s", {}).get("mean"), 1e-3, "<=", "s"),
    ]


if __name__ == "__main__":
    sys.exit(solver_main())
