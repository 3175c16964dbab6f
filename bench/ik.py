"""IK stage: "the solution nearest a seed" for seeded reachable poses (KR60: analytic path;
Fanuc_M16iB20, 7 joints with a prismatic rail: numeric path), usar-arm beside TRAC-IK
(pytracik), mplib, roboplan, py-opw-kinematics and ikpy.

Besides the uniform sets, :data:`EDGES` is a KR60 set of the poses that leave the closed form's
compiled path (4 % of uniform poses, most of their CPU time: a wrist near its singularity, a
branch a hair outside a limit, where the solver judges branches in Python and searches with
joints held on their limits): poses of configurations with one joint within
:data:`EDGE_MARGIN` of a limit, or joint 5 within it of 0, drawn by :func:`edge_set`.

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
from pathlib import Path
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
EDGES = "KR60 near limits"
"""The case of the poses near the joint limits and the wrist singularity (its solvers: the
KR60's)."""
EDGE_MARGIN = 0.05
"""rad: an edge configuration has one joint this close to a limit (two in three) or joint 5
this close to 0, the wrist singularity (one in three)."""
EDGE_SIZE = {"quick": 20, "full": 2000}
EDGE_SEED = 20_260_421
SLOW_PEER_LIMIT = {("KR60", "ikpy"): 2000, ("Fanuc_M16iB20", "ikpy"): 1000,
                   (EDGES, "ikpy"): 500}
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
def _solvers(ctx: Context, robot: str, case: str) -> list[common.Solver]:
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
            *[ctx.peer(p, "ik", notes[p], SLOW_PEER_LIMIT.get((case, p))) for p in peers],
            replace(ctx.peer("roboplan", "ik_unchecked",
                             "no collision check; SimpleIk, 2 restarts, check_collisions=False"),
                    name="roboplan unchecked")]


def edge_set(spec: dict[str, Any], n: int) -> dict[str, Any]:
    """The KR60 problem file ``spec`` with ``n`` problems of its own: FK (the judge's
    Pinocchio) of self-collision-free configurations, each with one joint within
    :data:`EDGE_MARGIN` of a limit, or (every third) joint 5 within it of 0; seed mid-range."""
    import pinocchio as pin

    names = list(spec["joint_names"])
    judged = JudgedRobot.from_files(spec["urdf"], spec["srdf"])
    kin = verify.Kinematics(judged, names)
    judge = verify.Judge(judged, [], names)
    lo, hi = np.array(spec["lower"], float), np.array(spec["upper"], float)
    problems = []
    for i in range(n):
        rng = np.random.default_rng([EDGE_SEED, 3, i])
        while True:
            q = rng.uniform(lo, hi)
            if i % 3 == 2:
                q[4] = rng.uniform(-EDGE_MARGIN, EDGE_MARGIN)
            else:
                j = int(rng.integers(len(q)))
                q[j] = (lo[j] + rng.uniform(0, EDGE_MARGIN) if rng.random() < 0.5
                        else hi[j] - rng.uniform(0, EDGE_MARGIN))
            if not judge.colliding(q)[0]:
                break
        kin.update(q)
        pose = kin.frame(spec["tip_link"])
        quat = pin.Quaternion(pose[:3, :3])
        problems.append({"id": i, "xyz": pose[:3, 3].tolist(),
                         "quat_wxyz": [float(quat.w), float(quat.x), float(quat.y),
                                       float(quat.z)],
                         "seed": ((lo + hi) / 2).tolist(), "q_true": q.tolist()})
    return {**spec, "generator": f"bench/ik.py edge_set (seed {EDGE_SEED})",
            "problems": problems}


def _case_files(ctx: Context) -> list[tuple[str, str, Path, dict[str, Any]]]:
    """(case, robot, problem file, its contents) of every case: the shared sets of
    :data:`ROBOTS`, then :data:`EDGES`, written into the work folder."""
    out = []
    for name in ROBOTS:
        path, spec = ctx.problem(f"ik_{name}")
        out.append((name, name, path, spec))
    kr60 = next(spec for name, _, _, spec in out if name == "KR60")
    edges = edge_set(kr60, EDGE_SIZE[ctx.mode])
    path = ctx.work / "ik_KR60_edges.json"
    common.write_json(path, edges, indent=None, digits=common.PROBLEM_DIGITS)
    out.append((EDGES, "KR60", path, edges))
    return out


def run(ctx: Context) -> dict[str, Any]:
    """Run the IK cases and return the stage document."""
    started = time.perf_counter()
    cases: dict[str, Any] = {}
    for name, robot, path, spec in _case_files(ctx):
        judged = JudgedRobot.from_files(spec["urdf"], spec["srdf"])
        kin = verify.Kinematics(judged, list(spec["joint_names"]))
        judge = verify.Judge(judged, [], list(spec["joint_names"]))
        tol = spec["tolerance"]
        outcomes = common.run_alternating(spec, _solvers(ctx, robot, name), ctx.work,
                                          ctx.rounds, f"ik_{name.replace(' ', '_')}")

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

        cases[name] = {"robot": robot, "dof": len(spec["joint_names"]), "tolerance": tol,
                       "set": "edges" if name == EDGES else "uniform",
                       **common.build_case(path, spec, outcomes, check, extra,
                                           {n: checked for n in COLLISION_CHECKED})}
    return common.stage_document("ik", ctx.mode, {
        "rounds": ctx.rounds, "batch": BATCH,
        "edges": f"{EDGES}: one joint within {EDGE_MARGIN} rad of a limit (2 in 3) or joint 5 "
                 f"within it of 0 (1 in 3), self-collision-free, seed mid-range"},
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
        *_edge_targets(cases),
    ]


def _edge_targets(cases: dict[str, Any]) -> list[dict[str, Any]]:
    """The near-limit KR60 set's targets: its success as the uniform set's, and a mean per
    pose within ten times the uniform set's target (they leave the compiled path)."""
    if EDGES not in cases:
        return []
    s = cases[EDGES]["solvers"]["usar-arm"].get("summary", {})
    return [common.target(f"IK {EDGES} success (single call)", s.get("success_rate"), 0.999,
                          ">=", "fraction"),
            common.target(f"IK {EDGES} mean time per pose, single call IKSolver.solve",
                          s.get("time_all_s", {}).get("mean"), 1e-3, "<=", "s")]


if __name__ == "__main__":
    sys.exit(solver_main())
