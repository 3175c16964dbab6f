"""Batch jobs: many IK or plan problems (:mod:`usar_arm.workspace.batch_file`), run in chunks
on a backend, answered in the input order, each failure typed on its own line.

Every problem's answer depends on that problem alone: before each, the IK solver's restarts
and OMPL's seed generator are reseeded with the batch's seed, so a results file is the same
whatever the backend, the number of workers or the chunk a problem fell into (the ``seconds``
field, a measured time, excepted).
"""

from __future__ import annotations

import functools
import json
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.control.motion import MotionOptions, plan_motion
from usar_arm.core.errors import UsarArmError
from usar_arm.core.inputs import joint_vector
from usar_arm.core.version import __version__
from usar_arm.planning.attach_file import DEFAULT_LINK
from usar_arm.planning.carry_book import CarryBook
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.ompl_adapter import reseed
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import EMPTY, Scene
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace.arm_model import ArmBuilder, scene_fingerprint
from usar_arm.workspace.batch_file import BadLine, Problem
from usar_arm.workspace.engine import (
    Backend,
    ChunkStore,
    Job,
    Progress,
    Result,
    RunStats,
    digest,
    run_job,
)
from usar_arm.workspace.jobs import CHUNKS, arm_builder, description_text

COST_US = {"ik": 40, "plan": 1000}
"""Typical microseconds one problem of each kind costs a worker (KR60, one core of the 2-core
machine of the README's figures, measured over 300 IK problems and 80 plans of random
reachable poses and random collision-free configurations): an IK problem 26 us median in the
empty scene, 37 us in ``table`` (39 us per problem in the old 480-problem chunks); a plan
0.9 ms median in ``table`` and 1.0 ms in ``shelf`` (most joint-space segments are free; an
RRTConnect plan costs 2 to 10 ms, a failed one its time limit)."""
CHUNK_US = 100_000
"""A chunk holds problems until their typical cost reaches this (us; 0.1 s: 2,500 IK problems
or 100 plans): twice the floor of 50 ms of work per chunk, below which a chunk's round trip
(pickling, the pipe or Ray, saving it) costs a noticeable share, so that a chunk of the
cheapest IK problems measured (26 us) still takes 65 ms. Chunks of hard plans take longer
(their cost is unknown before they run); on a large file their number keeps the workers
busy."""


def chunk_problems(problems: list[Problem]) -> list[list[Problem]]:
    """The problems cut, in input order, into chunks whose typical cost (:data:`COST_US`)
    reaches :data:`CHUNK_US` (the last one may cost less)."""
    chunks: list[list[Problem]] = []
    cost = CHUNK_US
    for p in problems:
        if cost >= CHUNK_US:
            chunks.append([])
            cost = 0
        chunks[-1].append(p)
        cost += COST_US[p.kind]
    return chunks


@dataclass(frozen=True)
class BatchOptions:
    """How problems are solved: the seed of every search, the planner's options, and whether a
    plan's answer carries its sampled trajectory."""

    seed: int = 0
    motion: MotionOptions = field(default_factory=MotionOptions)
    trajectories: bool = False


@dataclass
class _Context:
    robot: Robot
    scenes: dict[str, Scene]
    worlds: dict[str, CollisionWorld]
    options: BatchOptions

    def world(self, scene: str | None) -> CollisionWorld:
        key = scene or ""
        if key not in self.worlds:
            self.worlds[key] = self.robot.collision_world(self.scenes.get(key, EMPTY))
        return self.worlds[key]


def _prepare(build: ArmBuilder, scenes: dict[str, Scene], options: BatchOptions) -> _Context:
    robot = build()
    assert isinstance(robot, Robot)
    return _Context(robot, scenes, {}, options)


def _joints(robot: Robot, values: Any, what: str) -> np.ndarray:
    return joint_vector(values, robot.chain.joint_names, what)


def _clean(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def _carrying(context: _Context, p: Problem, at: np.ndarray | list[float]
              ) -> tuple[Robot, CollisionWorld]:
    """The arm carrying what ``p`` attaches (scene objects grasped at ``at``), and its world
    of the problem's scene (the carried objects out of it; a support allowed for the lift)."""
    book, robot, at = CarryBook(), context.robot, np.asarray(at, float)
    scene = context.scenes.get(p.scene or "", EMPTY)
    for a in p.attach:
        book.attach(robot.carrying(book.bodies), a.name, a.link or DEFAULT_LINK, at, scene,
                    a.shape, a.pose, a.touch_links)
    carrying = robot.carrying(book.bodies)
    world = carrying.collision_world(book.view(scene))
    return carrying, book.lift_off(carrying, world, at)


def solve(context: _Context, p: Problem) -> dict[str, Any]:
    """The answer to one problem (raises the problem's typed failure)."""
    robot, options = context.robot, context.options
    world = context.world(p.scene)
    if p.attach:
        at = p.start if p.kind == "plan" else p.seed  # (an IK problem's new body: at home)
        robot, world = _carrying(context, p, robot.home() if at is None else _joints(
            robot, at, "plan.start" if p.kind == "plan" else "ik.seed"))
    carried = {"attached": [{"name": a.name, "link": a.link or DEFAULT_LINK}
                            for a in p.attach]} if p.attach else {}
    ik = robot.ik_solver()
    ik.reseed(options.seed)
    if p.kind == "ik":
        assert p.pose is not None
        seed = None if p.seed is None else _joints(robot, p.seed, "ik.seed")
        result = ik.solve(p.pose, seed, all_solutions=p.all, collision=world)
        best = result.best
        out: dict[str, Any] = {"q": best.q.tolist(), "position_error": best.position_error,
                               "orientation_error": best.orientation_error,
                               "method": result.method}
        if p.all:
            out["solutions"] = [s.q.tolist() for s in result.solutions]
        return {**out, **carried}
    assert p.start is not None
    start = _joints(robot, p.start, "plan.start")
    goal = None if p.goal is None else _joints(robot, p.goal, "plan.goal")
    reseed(options.seed)
    plan = plan_motion(robot, world, start, goal=goal, pose=p.pose,
                       options=replace(options.motion, motion=p.motion))
    out = {"motion": p.motion, "goal_q": plan.goal.tolist(),
           "waypoints": plan.waypoints.tolist(), "duration_s": plan.trajectory.duration,
           "path_length": plan.path_length, "planner": plan.details.get("planner")}
    if options.trajectories:
        out["trajectory"] = {"t": plan.trajectory.t.tolist(), "q": plan.trajectory.q.tolist()}
    return {**out, **carried}


def answer(context: _Context, p: Problem) -> dict[str, Any]:
    """One result line: the answer, or the failure with its type and exit code."""
    head = {"line": p.line, "id": p.id, "type": p.kind}
    begin = time.perf_counter()
    try:
        body = {"ok": True, **solve(context, p)}
    except UsarArmError as exc:
        body = {"ok": False, "error": {"type": type(exc).__name__, "message": str(exc),
                                       "exit_code": exc.exit_code}}
    except (ValueError, ArithmeticError, RuntimeError) as exc:  # a bug; still this line only
        body = {"ok": False, "error": {"type": type(exc).__name__, "message": str(exc),
                                       "exit_code": 70}}
    return _clean({**head, **body, "seconds": time.perf_counter() - begin})


def _chunk(context: _Context, problems: list[Problem]) -> Result:
    lines = [json.dumps(answer(context, p)) for p in problems]
    return {"lines": np.array([p.line for p in problems], np.int64),
            "json": np.array(lines, dtype=np.str_)}


def bad_line(b: BadLine) -> dict[str, Any]:
    """The result line of a line that is not a problem."""
    return {"line": b.line, "id": b.id, "type": None, "ok": False,
            "error": {"type": "InvalidInputError", "message": b.message, "exit_code": 65}}


def batch_job(problems: list[Problem], build: ArmBuilder, scenes: dict[str, Scene],
              options: BatchOptions, description: str, version: str) -> Job:
    """The job: chunks of about :data:`CHUNK_US` of work, in input order. Its key covers
    every problem's content (line, id, kind, scene, poses, joints, flags), the chunk layout,
    the scenes' content, the description, the options and the version."""
    chunks = chunk_problems(problems)
    parts = {
        "problems": digest([p.content() for p in problems], [len(c) for c in chunks]),
        "robot description": digest(description),
        "scenes": digest({k: scene_fingerprint(s) for k, s in sorted(scenes.items())}),
        "settings": digest(options.seed, repr(options.motion), options.trajectories),
        "usar-arm version": version,
    }
    prepare = functools.partial(_prepare, build, scenes, options)
    return Job("batch", prepare, _chunk, chunks, digest("batch", parts),
               [len(c) for c in chunks], parts)


def merge(results: list[Result], bad: list[BadLine]) -> list[str]:
    """Every result line (JSON text), in input order."""
    rows: list[tuple[int, str]] = [(b.line, json.dumps(bad_line(b))) for b in bad]
    for r in results:
        rows += [(int(n), str(s)) for n, s in zip(r["lines"], r["json"], strict=True)]
    return [s for _, s in sorted(rows)]


def load_scenes(problems: list[Problem]) -> tuple[dict[str, Scene], list[Problem],
                                                    list[BadLine]]:
    """Every scene the problems name, loaded once; a problem whose scene cannot be loaded
    becomes a bad line saying why."""
    scenes: dict[str, Scene] = {}
    broken: dict[str, str] = {}
    for name in sorted({p.scene for p in problems if p.scene}):
        try:
            scenes[name] = load_scene(name)
        except UsarArmError as exc:
            broken[name] = str(exc)
    good = [p for p in problems if not p.scene or p.scene in scenes]
    bad = [BadLine(p.line, p.id, f"scene '{p.scene}': {broken[p.scene]}") for p in problems
           if p.scene and p.scene in broken]
    return scenes, good, bad


def run_batch(robot: Robot, problems: list[Problem], bad: list[BadLine], options: BatchOptions,
              backend: Backend, out_dir: str | Path | None = None, resume: bool = False,
              progress: Progress | None = None) -> tuple[list[str], RunStats]:
    """Every result line (JSON text) in input order, and how the run went."""
    scenes, good, unloadable = load_scenes(problems)
    job = batch_job(good, arm_builder(robot), scenes, options, description_text(robot),
                    __version__)
    store = ChunkStore(Path(out_dir) / CHUNKS, job) if out_dir is not None else None
    results, stats = run_job(job, backend, store, resume, progress)
    return merge(results, bad + unloadable), stats
