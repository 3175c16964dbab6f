"""The shared problem set: seeded, written to JSON files, the same inputs for every solver.

    python bench/problems.py [--quick] [--out bench/problems/full]

Files (formats of ``bench/README-peers.md``; lengths m, angles rad, poses of tool0 in
base_link):

* ``ik_<robot>.json``: FK of uniformly random in-limit, self-collision-free configurations of
  KR60 and Fanuc_M16iB20 (``q_true`` kept); seed = mid-range of the limits (TRAC-IK protocol);
  tolerance 1e-5 m and 1e-5 rad; 5 ms timeout for the peers that take one.
* ``collision_KR60.json``: uniformly random in-limit configurations in ``table`` and in the
  ``boxes_N`` scenes (N = 1, 10, 100, 1000 boxes of 0.1 m).
* ``plan_KR60.json``: start/goal pairs in empty, table, shelf and cage; both collision-free with
  1 cm to spare; per problem, among up to :data:`PAIR_TRIES` seeded candidates the first pair
  whose straight joint-space line is blocked (``line_blocked``; a problem none of whose
  candidates is blocked keeps the first, ``line_blocked: false``: the stages report those
  apart). ``plan_Fanuc_M16iB20.json``: the same for the 7-joint arm.
  ``plan_KR60_boxes.json``: fixed pairs in every ``boxes_N`` scene (nested: the first N of the
  same 1,000 boxes, none touching the arm at any start or goal), chosen the same way in the
  empty scene (a line the arm itself blocks stays blocked among any boxes).
* Every file with scenes names each scene's YAML file (``scene_files``: the shipped
  ``robots/scenes/*.yaml``, the boxes scenes written to ``<out>/scenes``): the judge reads
  those, the solvers the obstacle lists (``scenes``).
* ``topp_KR60.json``: the geometric paths our planner returns for the first plan problems
  (fixed in the file, so that every time-parameteriser gets exactly the same path), with the
  description's velocity and acceleration limits (and jerk, which only Ruckig uses).

Problem ``i`` of a set draws from ``default_rng([SEED, set, i])``, so a quick set is the start
of the full one. The Fanuc description is discovered from the embedded simulator into
``<out>/robots/`` (deterministic); the KR60's is the checked-in ``robots/generated/as-learnt``.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import common
import numpy as np
import scenes
from judge_reading import JudgedRobot, read_scene_file
from verify import Judge, densify

from usar_arm.control.trajectory import MotionLimits
from usar_arm.core.spatial import Array, quat_from_matrix
from usar_arm.planning.ompl_adapter import OmplOptions, edge_configurations
from usar_arm.planning.ptp import plan_to_joints
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.planning.scene import Scene

SEED = 20_260_421
KR60 = "KR60"
FANUC = "Fanuc_M16iB20"
ROBOT_KEY = {KR60: 0, FANUC: 1}
"""Index of each robot in the random streams."""
SCENES = ("empty", "table", "shelf", "cage")
WALK_SEGMENTS = 3
"""Free straight segments of a witness walk from a start to its goal."""
BOX_PAIRS = 10
"""start/goal pairs the boxes are kept clear of (always the full number: nested quick sets)."""
TOLERANCE = {"position_m": 1e-5, "orientation_rad": 1e-5}
IK_TIMEOUT_S = 0.005
PLAN_TIME_LIMIT_S = 2.0
CLEARANCE = 0.01
"""m: start and goal configurations keep at least this much from everything."""
PAIR_TRIES = 100
"""Witness walks tried per plan problem for one whose straight start-goal line is blocked."""


@dataclass(frozen=True)
class Sizes:
    """How many problems of each set (quick mode: a few of each)."""

    ik_kr60: int
    ik_fanuc: int
    collision_table: int
    collision_boxes: int
    plan_per_scene: int
    plan_fanuc_per_scene: int
    plan_box_pairs: int
    plan_box_counts: tuple[int, ...]
    topp: int


FULL = Sizes(10_000, 2_000, 10_000, 2_000, 25, 10, BOX_PAIRS, scenes.BOX_COUNTS, 100)
QUICK = Sizes(30, 20, 200, 50, 2, 1, 1, scenes.BOX_COUNTS[:3], 6)


def robot_paths(name: str, out: Path) -> tuple[Path, Path]:
    """(URDF, SRDF) of a benchmark robot; the Fanuc is described on first use."""
    if name == KR60:
        d = common.ROOT / "robots" / "generated" / "as-learnt"  # deterministic, golden
    else:
        d = out / "robots" / name
        if not (d / f"{name}.urdf").is_file():
            from usar_arm.description.embedded import describe
            from usar_arm.description.pipeline import DescribeOptions, write_description

            common.log(f"describing {name} from the embedded simulator into {d}")
            write_description(describe(DescribeOptions(robot=name, accuracy_samples=0)), d)
    return d / f"{name}.urdf", d / f"{name}.srdf"


def load_robot(urdf: str | Path) -> Robot:
    return robot_from_files(urdf)


def _judge(robot: Robot, scene_file: Path) -> Judge:
    """The benchmark's judge of ``robot`` in the scene of ``scene_file`` (YAML), built from the
    same text a problem file names (the judge reads no usar-arm object)."""
    srdf = next((text for name, text in robot.files.items() if name.endswith(".srdf")), None)
    return Judge(JudgedRobot.from_text(robot.urdf, srdf), read_scene_file(scene_file),
                 list(robot.chain.joint_names))


# ------------------------------------------------------------------------------ scenes
_BOXES: dict[str, Any] = {}


def box_pairs(robot: Robot) -> list[dict[str, Any]]:
    """The start/goal pairs of the boxes scenes (free of self-collision with 1 cm to spare,
    each with its witness path), and the 1,000 box centres, kept clear of every witness."""
    if "pairs" not in _BOXES:
        empty = Scene("empty")
        pairs = [_pair(robot, empty, np.random.default_rng([SEED, 8, i]))
                 for i in range(BOX_PAIRS)]
        dense = np.vstack([densify(np.array(p["witness"]), 0.01) for p in pairs])
        _BOXES["pairs"] = pairs
        judge = _judge(robot, scenes.shipped_file("empty"))
        _BOXES["centres"] = scenes.box_centres(max(scenes.BOX_COUNTS), judge.capsules(dense),
                                               SEED + 9)
    return _BOXES["pairs"]


def scene(name: str) -> Scene:
    """A shipped scene or ``boxes_N`` (the KR60's)."""
    if name.startswith("boxes_"):
        box_pairs(load_robot(robot_paths(KR60, Path())[0]))
        return scenes.boxes(_BOXES["centres"], int(name.removeprefix("boxes_")))
    return scenes.shipped(name)


def scene_json(sc: Scene, out: Path) -> list[dict[str, Any]]:
    return scenes.to_json(sc, out)


def scene_files(names: Any, out: Path) -> dict[str, str]:
    """Scene name -> its YAML file (absolute), what the judge reads; the boxes scenes are
    written into ``out/scenes``."""
    files = {}
    for name in names:
        if name.startswith("boxes_"):
            scene(name)  # the centres
            path = scenes.write_boxes_file(_BOXES["centres"], int(name.removeprefix("boxes_")),
                                           out / "scenes")
        else:
            path = scenes.shipped_file(name)
        files[name] = str(path.resolve())
    return files


# ------------------------------------------------------------------------------ sets
def _robot_header(stage: str, name: str, robot: Robot, urdf: Path, srdf: Path
                  ) -> dict[str, Any]:
    limits = MotionLimits.from_chain(robot.chain, 1.0)
    return {"stage": stage, "robot": name, "urdf": str(urdf.resolve()),
            "srdf": str(srdf.resolve()), "base_link": "base_link", "tip_link": "tool0",
            "group": "manipulator", "joint_names": list(robot.chain.joint_names),
            "lower": robot.chain.lower().tolist(), "upper": robot.chain.upper().tolist(),
            "vmax": limits.velocity.tolist(), "amax": limits.acceleration.tolist(),
            "jmax": limits.jerk.tolist()}


def ik_set(name: str, n: int, out: Path) -> dict[str, Any]:
    urdf, srdf = robot_paths(name, out)
    robot = load_robot(urdf)
    judge = _judge(robot, scenes.shipped_file("empty"))
    lo, hi = robot.chain.lower(), robot.chain.upper()
    mid = ((lo + hi) / 2).tolist()
    problems = []
    for i in range(n):
        rng = np.random.default_rng([SEED, 1, ROBOT_KEY[name], i])
        q = rng.uniform(lo, hi)
        while judge.colliding(q)[0]:
            q = rng.uniform(lo, hi)
        pose = robot.kinematics.frame_pose(q, "tool0")
        problems.append({"id": i, "xyz": pose[:3, 3].tolist(),
                         "quat_wxyz": quat_from_matrix(pose[:3, :3]).tolist(), "seed": mid,
                         "q_true": q.tolist()})
    doc = {**_robot_header("ik", name, robot, urdf, srdf), "tolerance": TOLERANCE,
           "timeout_s": IK_TIMEOUT_S, "problems": problems}
    if name == KR60:
        from make_test_problems import opw_parameters

        doc["opw"] = opw_parameters(robot.kinematics.model, robot.kinematics.data)
    return doc


def collision_set(sizes: Sizes, out: Path) -> dict[str, Any]:
    urdf, srdf = robot_paths(KR60, out)
    robot = load_robot(urdf)
    lo, hi = robot.chain.lower(), robot.chain.upper()
    names = ["table", *[f"boxes_{n}" for n in scenes.BOX_COUNTS]]
    problems = []
    for k, sc in enumerate(names):
        count = sizes.collision_table if sc == "table" else sizes.collision_boxes
        for i in range(count):
            q = np.random.default_rng([SEED, 2, k, i]).uniform(lo, hi)
            problems.append({"id": len(problems), "scene": sc, "q": q.tolist()})
    return {**_robot_header("collision", KR60, robot, urdf, srdf),
            "scenes": {sc: scene_json(scene(sc), out) for sc in names},
            "scene_files": scene_files(names, out), "problems": problems}


def _pair(robot: Robot, sc: Scene, rng: np.random.Generator, tries: int = PAIR_TRIES
          ) -> dict[str, Any]:
    """A start/goal pair with a witness: the goal is the end of a walk of up to
    :data:`WALK_SEGMENTS` free straight segments (1 cm to spare) from the start to uniformly
    random free configurations, so a path exists by construction. Among ``tries`` walks, the
    first whose straight start-goal line is blocked, else the first walk."""
    lo, hi = robot.chain.lower(), robot.chain.upper()
    padded = robot.collision_world(sc, padding=CLEARANCE)
    world = robot.collision_world(sc)
    judge = _judge(robot, scenes.shipped_file(sc.name))

    def sample() -> Array:
        for _ in range(10_000):
            q = rng.uniform(lo, hi)
            if not padded.in_collision(q) and not judge.colliding(q)[0]:
                return q
        raise RuntimeError(f"no free configuration of {robot.chain.name} in {sc.name}")

    def free(a: Array, b: Array) -> bool:
        qs = edge_configurations(a, b, 0.01)  # coarse to fine: most blocks show early
        return not any(padded.in_collision_many(qs[lo:hi]).any()
                       for lo, hi in ((0, 16), (16, 128), (128, len(qs))) if lo < len(qs))

    first: dict[str, Any] | None = None
    for _ in range(tries):
        walk = [sample()]
        for _ in range(WALK_SEGMENTS):
            for _ in range(50):
                c = sample()
                if free(walk[-1], c):
                    walk.append(c)
                    break
        if len(walk) < 2:
            continue
        blocked = bool(world.in_collision_many(edge_configurations(walk[0], walk[-1],
                                                                   0.01)).any())
        found = {"start": walk[0].tolist(), "goal": walk[-1].tolist(), "line_blocked": blocked,
                 "witness": np.array(walk).tolist()}
        first = first or found
        if blocked:
            return found
    if first is None:
        raise RuntimeError(f"no free walk of {robot.chain.name} in {sc.name}")
    return first


def plan_set(name: str, per_scene: int, out: Path) -> dict[str, Any]:
    urdf, srdf = robot_paths(name, out)
    robot = load_robot(urdf)
    problems = []
    for k, sc_name in enumerate(SCENES):
        sc = scene(sc_name)
        for i in range(per_scene):
            rng = np.random.default_rng([SEED, 3, ROBOT_KEY[name], k, i])
            problems.append({"id": len(problems), "scene": sc_name, "seed": 1 + len(problems),
                             **_pair(robot, sc, rng)})
    return {**_robot_header("plan", name, robot, urdf, srdf),
            "scenes": {s: scene_json(scene(s), out) for s in SCENES},
            "scene_files": scene_files(SCENES, out), "time_limit_s": PLAN_TIME_LIMIT_S,
            "problems": problems}


def plan_boxes_set(pairs: int, counts: tuple[int, ...], out: Path) -> dict[str, Any]:
    urdf, srdf = robot_paths(KR60, out)
    robot = load_robot(urdf)
    chosen = box_pairs(robot)[:pairs]
    names = [f"boxes_{n}" for n in counts]
    worlds = {sc: robot.collision_world(scene(sc)) for sc in names}
    problems = []
    for i, pair in enumerate(chosen):
        for k, sc in enumerate(names):
            line = edge_configurations(np.array(pair["start"]), np.array(pair["goal"]), 0.01)
            problems.append({"id": len(names) * i + k, "scene": sc, "seed": 1 + i, **pair,
                             "line_blocked": bool(worlds[sc].in_collision_many(line).any())})
    return {**_robot_header("plan", KR60, robot, urdf, srdf),
            "scenes": {s: scene_json(scene(s), out) for s in names},
            "scene_files": scene_files(names, out), "time_limit_s": PLAN_TIME_LIMIT_S,
            "problems": problems}


def topp_set(plan_doc: dict[str, Any], n: int, out: Path) -> dict[str, Any]:
    """Our planner's paths for the first ``n`` plan problems (planned in this process: the
    OMPL seed is per process, so the paths are reproducible from a fresh process)."""
    robot = load_robot(plan_doc["urdf"])
    lo, hi = robot.chain.lower(), robot.chain.upper()
    worlds: dict[str, Any] = {}
    problems = []
    for p in plan_doc["problems"][:n]:
        world = worlds.setdefault(p["scene"], robot.collision_world(scene(p["scene"])))
        path = plan_to_joints(world, robot.chain.joint_names, lo, hi, np.array(p["start"]),
                              np.array(p["goal"]), OmplOptions(seed=0))
        problems.append({"id": p["id"], "scene": p["scene"],
                         "waypoints": path.waypoints.tolist()})
    keep = ("robot", "urdf", "srdf", "joint_names", "lower", "upper", "vmax", "amax", "jmax",
            "scenes", "scene_files")
    return {"stage": "topp", **{k: plan_doc[k] for k in keep}, "speed_scale": 1.0,
            "source": "usar-arm plan_to_joints (RRTConnect + simplification, OMPL seed 0) on "
                      "the first plan_KR60 problems", "problems": problems}


def topp_neutral_set(plan_doc: dict[str, Any], n: int) -> dict[str, Any]:
    """Paths no planner made: 3 to 7 random waypoints in the empty scene, each straight segment
    clear of self-collision by 1 cm everywhere along it (usar-arm's padded world walks it with
    its continuous guarantee; the judge checks it too), drawn with the set's seed. On these a
    spline that leaves the polyline costs nothing, and any sampling of the polyline is free, so
    every solver's durations compare on equal terms."""
    robot = load_robot(plan_doc["urdf"])
    lo, hi = np.array(plan_doc["lower"]), np.array(plan_doc["upper"])
    padded = robot.collision_world(scene("empty"), padding=CLEARANCE)
    levers = padded.lever_arms()
    empty = {"empty": str(scenes.shipped_file("empty").resolve())}
    judge = Judge.for_scene({**plan_doc, "scenes": {"empty": []}, "scene_files": empty},
                            "empty")
    rng = np.random.default_rng(SEED + 7)
    problems: list[dict[str, Any]] = []

    def free(a: Array, b: Array) -> bool:
        steps = max(1, int(np.ceil(float(levers @ np.abs(b - a)) / 0.005)))
        return padded.segment_free(a, b, steps) and judge.path_free(np.array([a, b]))

    while len(problems) < n:
        count = int(rng.integers(3, 8))
        points = [rng.uniform(lo, hi)]
        if padded.in_collision(points[0]):
            continue
        while len(points) < count:
            step = np.clip(points[-1] + rng.normal(0.0, 0.6, len(lo)), lo, hi)
            if free(points[-1], step):
                points.append(step)
        problems.append({"id": len(problems), "scene": "empty",
                         "waypoints": np.array(points).tolist()})
    keep = ("robot", "urdf", "srdf", "joint_names", "lower", "upper", "vmax", "amax", "jmax")
    return {"stage": "topp", **{k: plan_doc[k] for k in keep}, "speed_scale": 1.0,
            "scenes": {"empty": []}, "scene_files": empty,
            "source": "random self-collision-free polylines, 3-7 waypoints, empty scene",
            "problems": problems}


def generate(sizes: Sizes, out: Path) -> dict[str, Path]:
    """Write every problem file into ``out``; returns set name -> path."""
    out.mkdir(parents=True, exist_ok=True)
    docs: dict[str, dict[str, Any]] = {}
    common.log(f"generating problems into {out}")
    docs[f"ik_{KR60}"] = ik_set(KR60, sizes.ik_kr60, out)
    docs[f"ik_{FANUC}"] = ik_set(FANUC, sizes.ik_fanuc, out)
    docs[f"collision_{KR60}"] = collision_set(sizes, out)
    docs[f"plan_{KR60}"] = plan_set(KR60, sizes.plan_per_scene, out)
    docs[f"plan_{FANUC}"] = plan_set(FANUC, sizes.plan_fanuc_per_scene, out)
    docs[f"plan_{KR60}_boxes"] = plan_boxes_set(sizes.plan_box_pairs, sizes.plan_box_counts,
                                                out)
    docs[f"topp_{KR60}"] = topp_set(docs[f"plan_{KR60}"], sizes.topp, out)
    docs[f"topp_{KR60}_neutral"] = topp_neutral_set(docs[f"plan_{KR60}"], sizes.topp)
    paths = {}
    for key, doc in docs.items():
        doc["generator"] = {"script": "bench/problems.py", "seed": SEED, "sizes": asdict(sizes),
                            "usar_arm": common.peerio.version("usar-arm")}
        paths[key] = out / f"{key}.json"
        common.write_json(paths[key], doc, indent=None)
        common.log(f"  {key}: {len(doc['problems'])} problems")
    return paths


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a few problems of each set")
    ap.add_argument("--out", type=Path, help="folder (default bench/problems/<quick|full>)")
    a = ap.parse_args(argv)
    mode = "quick" if a.quick else "full"
    generate(QUICK if a.quick else FULL, a.out or common.BENCH / "problems" / mode)
    return 0


if __name__ == "__main__":
    sys.exit(main())

