"""Robots stage: two mesh arms that no one here wrote, example-robot-data's UR5 and Panda (their
STL collision meshes and SRDFs; ``robots_data.py``), on MotionBenchMaker's problems as VAMP's
repository carries them (table_pick, table_under_pick, box, bookshelf_small/tall/thin, cage:
boxes and cylinders, start and goal configurations), posed as MBM poses them: the UR5 stands
0.9144 m up, turned 1.57 rad, in the scene's frame, table_pick's objects at their own pose, the
Panda's fingers 0.065 m open each (``robots_data.py``).

Three tasks per robot, every solver (ours, each peer in its venv) on the same files, in
alternating rounds (``common.run_alternating``), every answer checked by a brute-force judge
that reads the URDF, the meshes, the SRDF and the scene YAML itself (``mesh_judge.py``):

* collision: uniformly random in-limit configurations in the scenes of the first valid problem
  of each set; usar-arm's ``CollisionWorld.in_collision`` beside roboplan and mplib; an answer
  is verified when it equals the judge's; missed (false negative) and invented (false
  positive) contacts counted. Plus, for exactness, pairs of configurations straddling the
  first contact on the straight line of the blocked problems (:data:`BOUNDARY_STEP` apart,
  the judge's bisection): ``boundary_missed`` / ``boundary_invented``.
* IK: a reachable pose of the tip (the judge's FK of a random self-collision-free
  configuration), a seed near that configuration; usar-arm's ``IKSolver.solve`` (the method it
  chose, closed form or numeric, is recorded; with the self-collision world, and without it as
  "usar-arm unchecked", the like of TRAC-IK) beside TRAC-IK (pytracik), roboplan and mplib;
  verified by the judge's FK within 1e-5 m / 1e-5 rad and the limits (and free of
  self-collision for the solvers that claim it).
* planning: the MBM problems whose start and goal are free and whose straight joint-space line
  is blocked, by the judge (only those); usar-arm's ``plan_to_joints`` beside roboplan's
  RRT-Connect + shortcutting and mplib's RRTConnect + simplification; a path is verified when
  it joins start and goal within the limits and the judge finds every configuration 0.005 rad
  apart along it free.

VAMP (vectorised CPU planning, on its sphere models of the robots MBM was made for) plans beside
them when a local build is present (``robots_vamp.py``): timed both ways, its own timer and the
Python call, its paths judged on the meshes like every other solver's. Without a build the stage
says how to make one. Its authors' published timings are quoted beside, as published.

Every planner is reseeded per problem (usar-arm's OMPL with the problem's seed before each plan,
roboplan and mplib with it, VAMP's sampler reset), so a problem's answer and time do not depend
on the problems solved before it in the process.

``BENCH_ROBOTS_TASKS`` (comma-separated, e.g. ``plan``) runs only those tasks (a stage run made
to measure one of them); every task by default.

As a solver (our side)::

    python bench/robots.py --task collision|ik|ik-unchecked|plan PROBLEMS.json RESULTS.json
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import Any

import common
import mesh_judge as mj
import numpy as np
import robots_data as data
import robots_vamp
from common import Context, peerio
from scenes import from_json as scene_from_json
from verify import PATH_STEP, densify

ROBOT_KEYS = ("ur5", "panda")
TASKS = ("collision", "ik", "plan")
TOLERANCE = {"position_m": 1e-5, "orientation_rad": 1e-5}
IK_TIMEOUT_S = 0.005
PLAN_TIME_LIMIT_S = 2.0
OMPL_PLANNER = "RRTConnect"
"""The OMPL planner run beside the default (the compiled one) as its A/B."""
SEED_SPREAD = 0.3
"""rad: an IK seed is the pose's configuration plus U(-SPREAD, SPREAD) per joint (clipped)."""
SIZES = {"quick": {"collision_scenes": 3, "collision_per_scene": 30, "ik": 100,
                   "plan_per_set": 1, "per_set_scanned": 6, "boundary_problems": 4},
         "full": {"collision_scenes": 7, "collision_per_scene": 150, "ik": 1000,
                  "plan_per_set": 8, "per_set_scanned": 40, "boundary_problems": 56}}
BOUNDARY_STEP = 1e-4
"""rad: the largest joint change between the two configurations straddling a contact (the
collision task's "boundary" configurations: a robot point moves ~0.1 mm or less between them,
so a checker with a margin, a convex hull or a coarse mesh answers one of them wrong)."""
CLOSED_FORM_EXPECTED = {
    "ur5": "not met: usar-arm solved the UR5 numerically, although it has a closed form for "
           "arms with three parallel axes (method analytic-ur): IKSolver.analytic_reason says "
           "why it was not used"}
"""6-joint robots whose IK the issue expects in closed form."""
COLLISION_CHECKED = ("usar-arm", "mplib", "roboplan")
"""IK solvers whose answers claim to be free of self-collision (ours: solved with the
self-collision world, as mplib and roboplan check theirs)."""

TESSERACT_GROUP = "manipulator"
"""The group the Tesseract config folder is written for: usar-arm's tesseract_config requires an
SRDF group of that name (the UR5's SRDF has no group, the Panda's is "arm"), so the SRDF text
handed to it gains ``<group name="manipulator"><chain base_link tip_link/></group>``, and
loses the groups made of other groups (and their states: the Panda's ``arm_and_hand``), which
Tesseract's SRDF parser refuses ("Group: 'arm_and_hand' is empty or multiple types were
provided"); its disabled pairs are the same."""

# ------------------------------------------------------------------------------ our side
def _robot(spec: dict[str, Any]) -> Any:
    from usar_arm.planning.robot import RobotOptions, robot_from_files

    return robot_from_files(spec["urdf"], spec["srdf"], options=RobotOptions.of(
        spec.get("group"), None if spec.get("group") else spec["base_link"], spec["tip_link"]))


def _check_order(robot: Any, spec: dict[str, Any]) -> None:
    if tuple(robot.chain.joint_names) != tuple(spec["joint_names"]):
        raise SystemExit(f"usar-arm's joints {robot.chain.joint_names} differ from the "
                         f"problem's {spec['joint_names']}")


def _solve_collision(spec: dict[str, Any]) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    robot = _robot(spec)
    _check_order(robot, spec)
    worlds: dict[str, Any] = {}

    def enter(name: str) -> None:
        worlds["now"] = robot.collision_world(scene_from_json(name, spec["scenes"][name]))

    def solve(p: dict[str, Any]) -> dict[str, Any]:
        hit, sec = peerio.timed(worlds["now"].in_collision, np.asarray(p["q"], float))
        return {"success": True, "seconds": sec, "collision": bool(hit)}

    return (peerio.solve_by_scene(spec["problems"], enter, solve, warmup=3),
            {"api": "CollisionWorld.in_collision(q)"})


def _solve_ik(spec: dict[str, Any], checked: bool = True
              ) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    from usar_arm.core.errors import IKError

    robot = _robot(spec)
    _check_order(robot, spec)
    ik = robot.ik_solver()
    world = robot.collision_world() if checked else None
    tip = spec["tip_link"]
    usar_tip = getattr(robot, "tip", None)

    def solve(p: dict[str, Any]) -> dict[str, Any]:
        target = peerio.pose_matrix(p["xyz"], p["quat_wxyz"])
        begin = time.perf_counter()
        try:
            q = ik.solve(target, np.asarray(p["seed"], float), collision=world).best.q
        except IKError as exc:
            return {"success": False, "seconds": time.perf_counter() - begin, "q": None,
                    "status": type(exc).__name__}
        return {"success": True, "seconds": time.perf_counter() - begin, "q": list(q)}

    results = peerio.solve_all(spec["problems"][:3], solve)  # warm-up, as the peers
    results = peerio.solve_all(spec["problems"], solve)
    return results, {"api": "IKSolver.solve(pose, seed" + (", collision=self-collision world)"
                                                           if checked else ")"),
                     "method": ik.method, "tip": tip, "usar_tip": str(usar_tip)}


def _solve_plan(spec: dict[str, Any], planner: str | None = None
                ) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    from plan import scene_solver  # (the plan stage's solver; imports usar-arm)

    from usar_arm.planning.ompl_adapter import OmplOptions, reseed

    robot = _robot(spec)
    _check_order(robot, spec)
    options = OmplOptions(time_limit=float(spec["time_limit_s"]), seed=0)
    if planner:
        options = OmplOptions(planner=planner, time_limit=options.time_limit, seed=0)
    enter, solve = scene_solver(spec, options, lambda plan: {
        "planner": "direct" if plan.ompl is None else plan.ompl.planner}, robot)

    def seeded(p: dict[str, Any]) -> dict[str, Any]:
        reseed(int(p["seed"]))  # (untimed) the plan depends on the problem's seed alone
        return solve(p)

    return (peerio.solve_by_scene(spec["problems"], enter, seeded),
            {"call": "planning.ptp.plan_to_joints", "ompl": vars(options),
             "seeding": "ompl_adapter.reseed(problem seed) before every plan"})


def solver_main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--task", choices=("collision", "ik", "ik-unchecked", "plan"),
                    required=True)
    ap.add_argument("--planner", help="the plan task's planner (default: OmplOptions')")
    ap.add_argument("problems")
    ap.add_argument("results")
    a = ap.parse_args(argv)
    spec = common.read_json(Path(a.problems))
    solve = {"collision": _solve_collision, "ik": _solve_ik,
             "plan": lambda spec: _solve_plan(spec, a.planner),
             "ik-unchecked": lambda spec: _solve_ik(spec, checked=False)}[a.task]
    results, settings = solve(spec)
    peerio.write(a.results, peer="usar-arm", dist="usar-arm", stage=f"robots {a.task}",
                 results=results, settings=settings)
    return 0


# ------------------------------------------------------------------------------ problem files
def _header(rf: data.RobotFiles) -> dict[str, Any]:
    return {"robot": rf.key, "urdf": str(rf.urdf), "urdf_mplib": str(rf.urdf_relative),
            "srdf": str(rf.srdf),
            **({"group": rf.group} if rf.group else {}), "base_link": rf.base,
            "tip_link": rf.tip, "joint_names": list(rf.joints)}


def _scan(rf: data.RobotFiles, robot: mj.MeshRobot, per_set: int, scanned: int
          ) -> tuple[dict[str, Any], dict[str, str]]:
    """The judge's verdict on the first ``scanned`` MBM problems of each set: valid (start and
    goal free), blocked (the straight line is not); and the scene texts."""
    texts = data.mbm_texts(rf.key, per_set=scanned)
    verdicts: dict[str, Any] = {}
    for name, (scene, request) in texts.items():
        judge = mj.MeshJudge(robot, mj.obstacles_from_scene_yaml(scene))
        start, goal = data.request_start_goal(request, rf.joints)
        ends = judge.colliding(np.array([start, goal]))
        inside = judge.inside(np.array(start)) and judge.inside(np.array(goal))
        valid = not ends.any() and inside
        blocked = valid and not judge.path_free(np.array([start, goal]))
        verdicts[name] = {"valid": bool(valid), "blocked": bool(blocked),
                          "start": start, "goal": goal}
    return verdicts, {k: v[0] for k, v in texts.items()}


def _problem_files(ctx: Context, rf: data.RobotFiles, robot: mj.MeshRobot
                   ) -> tuple[dict[str, Any], dict[str, str], dict[str, Any]]:
    size = SIZES[ctx.mode]
    verdicts, scene_texts = _scan(rf, robot, size["plan_per_set"], size["per_set_scanned"])
    head = _header(rf)
    # planning: the first blocked problems of each set
    chosen = []
    for s in data.SETS:
        names = [n for n in verdicts if n.startswith(s + "/") and verdicts[n]["blocked"]]
        chosen += names[:size["plan_per_set"]]
    plan = {**head, "time_limit_s": PLAN_TIME_LIMIT_S,
            "scenes": {n: data.scene_json(scene_texts[n]) for n in chosen},
            "problems": [{"id": k, "scene": n, "start": verdicts[n]["start"],
                          "goal": verdicts[n]["goal"], "seed": k}
                         for k, n in enumerate(chosen)]}
    # collision: the scene of the first valid problem of each set
    rng = np.random.default_rng(7)
    scenes = []
    for s in data.SETS:
        first = [n for n in verdicts if n.startswith(s + "/") and verdicts[n]["valid"]]
        scenes += first[:1]
    scenes = scenes[:size["collision_scenes"]]
    problems = []
    for n in scenes:
        for q in rng.uniform(robot.lower, robot.upper,
                             (size["collision_per_scene"], len(rf.joints))):
            problems.append({"id": len(problems), "scene": n, "q": q.tolist()})
    # contact boundaries: on the straight line of each chosen blocked problem, the first
    # contact bisected to BOUNDARY_TOL; one configuration just before it (free) and one just
    # after (in contact), BOUNDARY_STEP apart along the line
    for n in chosen[:size["boundary_problems"]]:
        judge = mj.MeshJudge(robot, mj.obstacles_from_scene_yaml(scene_texts[n]))
        for q in _boundary(judge, np.array(verdicts[n]["start"]), np.array(verdicts[n]["goal"])):
            problems.append({"id": len(problems), "scene": n, "q": q.tolist(),
                             "kind": "boundary"})
    collision = {**head, "scenes": {n: data.scene_json(scene_texts[n])
                                    for n in sorted({p["scene"] for p in problems})},
                 "problems": problems}
    # IK: reachable poses from self-collision-free configurations
    empty = mj.MeshJudge(robot, [])
    ik_problems = []
    while len(ik_problems) < size["ik"]:
        q = rng.uniform(robot.lower, robot.upper)
        if empty.collides(q):
            continue
        robot.update(q)
        t = robot.frame(rf.tip)
        seed = np.clip(q + rng.uniform(-SEED_SPREAD, SEED_SPREAD, len(q)), robot.lower,
                       robot.upper)
        ik_problems.append({"id": len(ik_problems), "xyz": t[:3, 3].tolist(),
                            "quat_wxyz": _quat_wxyz(t[:3, :3]), "seed": seed.tolist(),
                            "q_source": q.tolist()})
    ik = {**head, "tolerance": TOLERANCE, "timeout_s": IK_TIMEOUT_S, "problems": ik_problems}
    counts = {s: {"scanned": sum(1 for n in verdicts if n.startswith(s + "/")),
                  "valid": sum(1 for n, v in verdicts.items()
                               if n.startswith(s + "/") and v["valid"]),
                  "blocked": sum(1 for n, v in verdicts.items()
                                 if n.startswith(s + "/") and v["blocked"])} for s in data.SETS}
    return {"collision": collision, "ik": ik, "plan": plan}, scene_texts, counts


def _boundary(judge: mj.MeshJudge, a: np.ndarray, b: np.ndarray) -> list[np.ndarray]:
    """Two configurations on the segment a-b straddling its first contact: the last free one
    and the first in contact, at most :data:`BOUNDARY_STEP` (rad, largest joint change) apart
    (found by the judge: densified walk, then bisection)."""
    dense = densify(np.array([a, b]), PATH_STEP)
    hits = judge.colliding(dense, stop_at_first=True)
    k = int(np.argmax(hits))
    if not hits[k] or k == 0:
        return []
    lo, hi = dense[k - 1], dense[k]
    while float(np.max(np.abs(hi - lo))) > BOUNDARY_STEP:
        mid = (lo + hi) / 2
        if judge.collides(mid):
            hi = mid
        else:
            lo = mid
    return [lo, hi]


def _quat_wxyz(r: np.ndarray) -> list[float]:
    import pinocchio as pin

    q = pin.Quaternion(r)
    return [float(q.w), float(q.x), float(q.y), float(q.z)]


# ------------------------------------------------------------------------------ the stage
def _solvers(ctx: Context, task: str) -> list[common.Solver]:
    ours = common.ours("usar-arm", "robots.py", "--task", task,
                       note={"collision": "CollisionWorld.in_collision(q)",
                             "ik": "IKSolver.solve(pose, seed, collision=self-collision "
                                   "world)",
                             "plan": "plan_to_joints: straight line, else the compiled "
                                     "RRT-Connect + shortcut (OMPL's RRTConnect where it "
                                     "finds nothing)"}[task])
    if task == "collision":
        return [ours, ctx.peer("roboplan", "collision", "scene.hasCollisions (coal)"),
                ctx.peer("mplib", "collision", "set_qpos + is_state_colliding (FCL)"),
                ctx.peer("tesseract", "collision", "setState + contactTest (Bullet, the "
                         "config's default manager, margin 0); config folder written by "
                         "usar-arm's tesseract_config")]
    if task == "ik":
        unchecked = common.ours("usar-arm unchecked", "robots.py", "--task", "ik-unchecked",
                                note="IKSolver.solve(pose, seed) without a collision check "
                                     "(as TRAC-IK)")
        return [ours, unchecked,
                ctx.peer("pytracik", "ik", "no collision check; TRAC-IK Speed, 5 ms"),
                ctx.peer("roboplan", "ik", "collision-checked; SimpleIk"),
                ctx.peer("mplib", "ik", "collision-checked; Planner.IK, 20 CLIK starts")]
    ompl = common.ours("usar-arm ompl", "robots.py", "--task", "plan", "--planner",
                       OMPL_PLANNER, note="plan_to_joints with OMPL's RRTConnect + simplify "
                       "(the A/B of the default, the compiled planner)")
    return [ours, ompl, ctx.peer("roboplan", "plan", "RRT-Connect + PathShortcutter"),
            ctx.peer("mplib", "plan", "planner.plan (RRTConnect + simplify)"),
            robots_vamp.solver(ctx)]


def _summ(case: dict[str, Any], solver: str, key: str = "time_all_s",
          stat: str = "median") -> float | None:
    s = case["solvers"].get(solver, {}).get("summary", {})
    return (s.get(key) or {}).get(stat) if key.startswith("time") else s.get(key)


def run(ctx: Context) -> dict[str, Any]:
    started = time.perf_counter()
    cases: dict[str, Any] = {}
    notes: dict[str, Any] = {}
    targets: list[dict[str, Any]] = []
    for key in ROBOT_KEYS:
        rf = data.robot_files(key)
        robot = mj.MeshRobot(rf.urdf, rf.srdf, list(rf.joints))
        common.log(f"robots {key}: scanning MBM problems with the judge")
        specs, scene_texts, counts = _problem_files(ctx, rf, robot)
        notes[key] = {"mbm_scan": counts, "urdf": str(rf.urdf), "srdf": str(rf.srdf)}
        judges: dict[str, mj.MeshJudge] = {}

        def judge_of(scene: str, judges: dict[str, mj.MeshJudge] = judges,
                     texts: dict[str, str] = scene_texts, robot: mj.MeshRobot = robot
                     ) -> mj.MeshJudge:
            if scene not in judges:
                judges[scene] = (mj.MeshJudge(robot, []) if scene == "" else
                                 mj.MeshJudge(robot, mj.obstacles_from_scene_yaml(texts[scene])))
            return judges[scene]

        tasks = _tasks()
        if "collision" in tasks:
            specs["collision"] = _with_tesseract(specs["collision"], rf, ctx.work)
        for task in tasks:
            spec = specs[task]
            label = f"robots_{key}_{task}"
            path = ctx.work / f"{label}.json"
            common.write_json(path, spec, indent=None, digits=common.PROBLEM_DIGITS)
            if not spec["problems"]:
                cases[label] = {"skipped": "no problems"}
                continue
            outcomes = common.run_alternating(spec, _solvers(ctx, task), ctx.work, ctx.rounds,
                                              label)
            cases[label] = _case(task, path, spec, outcomes, judge_of, robot, rf)
        targets += _targets(key, cases)
    doc = common.stage_document("robots", ctx.mode, {
        "rounds": ctx.rounds, "sizes": SIZES[ctx.mode], "ik_tolerance": TOLERANCE,
        "ik_timeout_s": IK_TIMEOUT_S, "plan_time_limit_s": PLAN_TIME_LIMIT_S,
        "judge": "mesh_judge.MeshJudge (python-fcl BVH of the STL meshes, Pinocchio FK)",
        "files": "example-robot-data 6.0.0 (PyPI), derived URDFs (robots_data.py); MBM "
                 f"problems from VAMP {data.VAMP_COMMIT}",
        "machine_note": "shared machine: figures indicative"}, cases, targets, started)
    doc["robots"] = {k: _robot_summary(k, cases) for k in ROBOT_KEYS}
    doc["problem_scan"] = notes
    doc["vamp"] = robots_vamp.summary(cases)
    doc["vamp_published"] = robots_vamp.PUBLISHED
    return doc


def _tasks() -> tuple[str, ...]:
    """The tasks to run: ``BENCH_ROBOTS_TASKS`` (comma-separated) or all three."""
    wanted = [t.strip() for t in os.environ.get("BENCH_ROBOTS_TASKS", "").split(",") if t.strip()]
    unknown = set(wanted) - set(TASKS)
    if unknown:
        raise ValueError(f"BENCH_ROBOTS_TASKS names {sorted(unknown)}; tasks: {', '.join(TASKS)}")
    return tuple(t for t in TASKS if t in wanted) if wanted else TASKS


def _with_tesseract(spec: dict[str, Any], rf: data.RobotFiles, work: Path) -> dict[str, Any]:
    """``spec`` plus the Tesseract config folder usar-arm's tesseract_config writes for the
    robot (see :data:`TESSERACT_GROUP`), as bench/tesseract_config.py does for the KR60."""
    import xml.etree.ElementTree as ET

    from usar_arm.core.fileio import write_tree_atomic
    from usar_arm.urdf.tesseract import tesseract_config

    robot = _robot(spec)
    root = ET.fromstring(Path(spec["srdf"]).read_text(encoding="utf-8"))
    nested = {g.get("name") for g in root.findall("group")
              if len(g) and all(c.tag == "group" for c in g)}
    for el in list(root):
        if (el.tag == "group" and el.get("name") in nested) or (
                el.tag == "group_state" and el.get("group") in nested):
            root.remove(el)
    ET.SubElement(ET.SubElement(root, "group", name=TESSERACT_GROUP), "chain",
                  base_link=rf.base, tip_link=rf.tip)
    srdf = ET.tostring(root, encoding="unicode")
    folder = work / "tesseract" / f"{robot.chain.name.lower()}_tesseract"
    config = tesseract_config(robot.chain, robot.urdf, srdf, folder.name,
                              robot.states.get("home"))
    write_tree_atomic(folder, config.files)
    return {**spec, "tesseract": str(folder), "tesseract_group": TESSERACT_GROUP}


def _case(task: str, path: Path, spec: dict[str, Any], outcomes: dict[str, common.Outcome],
          judge_of: Any, robot: mj.MeshRobot, rf: data.RobotFiles) -> dict[str, Any]:
    if task == "collision":
        truth = {p["id"]: bool(judge_of(p["scene"]).collides(np.array(p["q"])))
                 for p in spec["problems"]}

        def check(p: dict[str, Any], r: dict[str, Any]) -> dict[str, Any]:
            answer = r.get("collision") if r.get("success") else None
            return {"verified": answer is not None and answer == truth[p["id"]],
                    "collision": answer, "truth": truth[p["id"]],
                    "kind": p.get("kind", "uniform")}

        def extra(raw: dict[str, list[Any]]) -> dict[str, Any]:
            pairs = list(zip(raw["collision"], raw["truth"], strict=True))
            edge = [(a, t) for (a, t), k in zip(pairs, raw["kind"], strict=True)
                    if k == "boundary"]
            return {"missed_contacts": sum(1 for a, t in pairs if a is False and t),
                    "invented_contacts": sum(1 for a, t in pairs if a is True and not t),
                    "colliding_fraction": float(np.mean(raw["truth"])) if pairs else None,
                    "boundary_configurations": len(edge),
                    "boundary_missed": sum(1 for a, t in edge if a is False and t),
                    "boundary_invented": sum(1 for a, t in edge if a is True and not t)}

        return common.build_case(path, spec, outcomes, check, extra)
    if task == "ik":
        empty = judge_of("")

        def ik_check(checked: bool) -> Any:
            def check(p: dict[str, Any], r: dict[str, Any]) -> dict[str, Any]:
                q = r.get("q") if r.get("success") else None
                if q is None:
                    return {"verified": False, "position_error_m": None,
                            "orientation_error_rad": None}
                q = np.asarray(q, float)
                robot.update(q)
                t = robot.frame(rf.tip)
                target = peerio.pose_matrix(p["xyz"], p["quat_wxyz"])
                dp = float(np.linalg.norm(t[:3, 3] - target[:3, 3]))
                do = mj.rotation_angle(t[:3, :3], target[:3, :3])
                ok = (dp <= TOLERANCE["position_m"] and do <= TOLERANCE["orientation_rad"]
                      and empty.inside(q))
                free = None
                if checked:
                    free = not empty.collides(q)
                    ok = ok and free
                return {"verified": ok, "position_error_m": dp, "orientation_error_rad": do,
                        "self_collision_free": free}
            return check

        return common.build_case(path, spec, outcomes, ik_check(False),
                                 checks={n: ik_check(True) for n in COLLISION_CHECKED})

    def plan_check(p: dict[str, Any], r: dict[str, Any]) -> dict[str, Any]:
        pts = r.get("path") if r.get("success") else None
        if not pts:
            return {"verified": False, "ends_match": None, "collision_free": None,
                    **robots_vamp.passthrough(r)}
        a = np.asarray(pts, float)
        ends = bool(np.allclose(a[0], p["start"], atol=1e-6)
                    and np.allclose(a[-1], p["goal"], atol=1e-6))
        inside = bool(all(judge_of(p["scene"]).inside(q) for q in a))
        free = judge_of(p["scene"]).path_free(a)
        in_time = r.get("seconds") is not None and r["seconds"] <= spec["time_limit_s"] * 1.05
        return {"verified": ends and inside and free and in_time, "ends_match": ends,
                "within_limits": inside, "collision_free": free, "waypoints": len(a),
                "length": float(np.sum(np.linalg.norm(np.diff(a, axis=0), axis=1))),
                **robots_vamp.passthrough(r)}

    def plan_extra(raw: dict[str, list[Any]]) -> dict[str, Any]:
        return {"paths_in_collision": sum(1 for f in raw.get("collision_free", [])
                                          if f is False),
                **robots_vamp.own_time_summary(raw)}

    case = common.build_case(path, spec, outcomes, plan_check, plan_extra)
    case["scenes"] = sorted(spec["scenes"])
    return case


def _robot_summary(key: str, cases: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for task in ("collision", "ik", "plan"):
        case = cases.get(f"robots_{key}_{task}", {})
        per: dict[str, Any] = {}
        for name, s in case.get("solvers", {}).items():
            if "skipped" in s:
                per[name] = {"skipped": s["skipped"]}
                continue
            sm = s.get("summary", {})
            row = {"problems": sm.get("problems"), "verified": sm.get("verified"),
                   "success_rate": sm.get("success_rate"),
                   "median_s": (sm.get("time_all_s") or {}).get("median"),
                   "median_verified_s": (sm.get("time_verified_s") or {}).get("median")}
            if task == "collision":
                row.update({k: sm.get(k) for k in (
                    "missed_contacts", "invented_contacts", "colliding_fraction",
                    "boundary_configurations", "boundary_missed", "boundary_invented")})
            if task == "ik" and name.startswith("usar-arm"):
                row["method"] = (s.get("settings") or {}).get("method")
            if task == "plan":
                row["paths_in_collision"] = sm.get("paths_in_collision")
                if sm.get("own_time_all_s"):
                    row["median_own_s"] = sm["own_time_all_s"]["median"]
            per[name] = row
        ratio = {p: r.get("usar-arm", {}).get("median") for p, r in case.get("ratios",
                                                                               {}).items()}
        out[task] = {"solvers": per, "median_ratio_usar_to_peer": ratio}
    return out


def _targets(key: str, cases: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    col = cases.get(f"robots_{key}_collision", {})
    if "solvers" in col:
        ours, peer = _summ(col, "usar-arm"), _summ(col, "roboplan")
        out.append(common.target(f"{key}: collision query median / roboplan's (same meshes)",
                                 common.ratio(ours, peer), 1.0, "<=", "ratio",
                                 "" if peer else "roboplan not run"))
        out.append(common.target(f"{key}: collision answers equal to the judge's",
                                 _summ(col, "usar-arm", "success_rate"), 1.0, ">=",
                                 "fraction"))
    plan = cases.get(f"robots_{key}_plan", {})
    if "solvers" in plan:
        ours, peer = _summ(plan, "usar-arm"), _summ(plan, "roboplan")
        out.append(common.target(f"{key}: planning median on blocked MBM problems / "
                                 "roboplan's", common.ratio(ours, peer), 0.8, "<=", "ratio",
                                 "" if peer else "roboplan not run"))
        so, sp = _summ(plan, "usar-arm", "verified"), _summ(plan, "roboplan", "verified")
        out.append(common.target(f"{key}: planning verified successes minus roboplan's",
                                 None if so is None or sp is None else so - sp, 0, ">=",
                                 "problems"))
        out += _vamp_targets(key, plan)
    ik = cases.get(f"robots_{key}_ik", {})
    if "solvers" in ik:
        method = (ik["solvers"]["usar-arm"].get("settings") or {}).get("method")
        closed = method not in (None, "numeric")
        out.append(common.target(f"{key}: IK success ({method}; target "
                                 f"{'closed form' if closed else 'numeric'})",
                                 _summ(ik, "usar-arm", "success_rate"),
                                 0.999 if closed else 0.995, ">=", "fraction",
                                 "" if closed or key == "panda" else
                                 "the numeric target is stated for 7 joints; applied to the "
                                 "6-joint UR5 because usar-arm solves it numerically"))
        out.append(common.target(f"{key}: IK median per call ({method}, collision-checked)",
                                 _summ(ik, "usar-arm"), 30e-6 if closed else 150e-6, "<=",
                                 "s", "each answer checked against the robot's own meshes"))
        if "usar-arm unchecked" in ik["solvers"]:
            out.append(common.target(
                f"{key}: IK median per call ({method}, no collision check, as TRAC-IK)",
                _summ(ik, "usar-arm unchecked"), 30e-6 if closed else 150e-6, "<=", "s"))
        if key in CLOSED_FORM_EXPECTED and not closed:
            out.append(common.target(f"{key}: IK by a closed form (>= 99.9 %, <= 30 us)", None,
                                     0.999, ">=", "fraction", CLOSED_FORM_EXPECTED[key]))
    return out


PANDA_MEDIAN_S = 1.5e-3
"""The planning-speed issue's bound on the Panda's median plan (with simplification)."""
PANDA_P90_OVER_MEDIAN = 3.0
"""... and on its p90 as a multiple of that median."""
VAMP_OWN_GOAL = 5.0
"""The issue's goal for the Panda's median over VAMP's own timer's (reported, not a bound)."""


def _vamp_targets(key: str, plan: dict[str, Any]) -> list[dict[str, Any]]:
    """The planning-speed issue's targets for ``key``'s plans: every path verified on the
    meshes; the Panda's median and p90 against fixed bounds, with the ratio to VAMP's own timer
    beside them; the UR5's median against VAMP's Python call in the same run."""
    ours = _summ(plan, "usar-arm")
    out = [common.target(f"{key}: planning verified on the meshes (planning-speed target)",
                         _summ(plan, "usar-arm", "success_rate"), 1.0, ">=", "fraction")]
    vamp = robots_vamp.row(plan)
    missing = "" if vamp["measured"] else f"VAMP not measured: {vamp['skipped']}"
    if key == "panda":
        out.append(common.target("panda: planning median (planning-speed target)", ours,
                                 PANDA_MEDIAN_S, "<=", "s"))
        p90 = _summ(plan, "usar-arm", stat="p90")
        out.append(common.target("panda: planning p90 / its median (planning-speed target)",
                                 common.ratio(p90, ours), PANDA_P90_OVER_MEDIAN, "<=", "ratio"))
        out.append(common.target("panda: planning median / VAMP's own timer's (goal)",
                                 vamp.get("ratio_usar_to_vamp_own"), VAMP_OWN_GOAL, "<=",
                                 "ratio", missing))
    else:
        out.append(common.target(f"{key}: planning median / VAMP's Python call's "
                                 "(planning-speed target)", vamp.get("ratio_usar_to_vamp_call"),
                                 1.0, "<=", "ratio", missing))
    return out


if __name__ == "__main__":
    sys.exit(solver_main())
