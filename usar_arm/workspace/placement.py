"""Inverse reachability: where to stand the arm so that it reaches every target of a cell.

Candidate base poses lie on the floor: base_link at (x, y, floor), turned by yaw about z, on a
grid of ``step`` metres and ``yaw_steps`` headings; a candidate from which some target lies
beyond the arm's reach bound is dropped without a query. For each other candidate the targets
are moved into its base frame and every IK solution of each is found (:mod:`.solver`); when
some target has one, the scene is moved into the base frame (a new collision world, about 9 ms)
and every solution is judged for collisions. A solution's margin is
min(manipulability / m_ref, joint margin / d_ref), both in [0, 1]: m_ref is the arm's largest
manipulability (sampled), d_ref the joint margin of the configuration in the middle of every
range. A target's margin is its best collision-free solution's; a candidate's score is its
worst target's margin, and the ranking is by score.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.job_errors import UnreachableTargetError
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array, invert, rot_z, transform
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.scene import Scene, SceneObject
from usar_arm.workspace.arm_model import ArmBuilder, scene_fingerprint
from usar_arm.workspace.engine import Job, Result, digest
from usar_arm.workspace.grid import reach_bound
from usar_arm.workspace.solver import AllSolutions
from usar_arm.workspace.targets import Target

REFERENCE_SAMPLES = 10_000
"""Random configurations the arm's largest manipulability is sampled from."""


@dataclass(frozen=True)
class PlaceSettings:
    """Settings of a placement study.

    Attributes:
        step: m between candidate base positions. yaw_steps: headings per position.
        floor: m, the z of base_link. region: (x_min, x_max, y_min, y_max) m of the candidate
            positions, or None: every position within reach of every target.
        chunk_candidates: candidates per chunk.
    """

    step: float = 0.1
    yaw_steps: int = 8
    floor: float = 0.0
    region: tuple[float, float, float, float] | None = None
    chunk_candidates: int = 48


def base_pose(x: float, y: float, yaw: float, floor: float) -> Array:
    """The 4x4 pose of base_link in the cell."""
    return transform(rot_z(yaw), (x, y, floor))


def moved(scene: Scene, pose: Array) -> Scene:
    """``scene`` with every object's pose premultiplied by ``pose``."""
    return Scene(scene.name, tuple(SceneObject(o.name, o.shape, pose @ o.pose, o.allow)
                                   for o in scene.objects))


@dataclass(frozen=True)
class Candidates:
    """Candidate base poses (x, y, yaw: (C,) each, m and rad)."""

    x: Array
    y: Array
    yaw: Array

    def __len__(self) -> int:
        return int(self.x.shape[0])

    def pose(self, i: int, floor: float) -> Array:
        """Candidate ``i``'s base pose."""
        return base_pose(float(self.x[i]), float(self.y[i]), float(self.yaw[i]), floor)


def candidates(chain: KinematicChain, targets: list[Target], settings: PlaceSettings
               ) -> tuple[Candidates, int]:
    """The candidates within reach of every target, and how many the grid had in all.

    Raises:
        ValueError: a bad step, yaw count or region.
    """
    if not (math.isfinite(settings.step) and settings.step > 0):
        raise ValueError(f"--step is a positive distance in metres, got {settings.step}")
    if settings.yaw_steps < 1:
        raise ValueError(f"--yaw-steps must be at least 1, got {settings.yaw_steps}")
    bound = reach_bound(chain)
    points = np.array([t.pose[:3, 3] for t in targets])
    if settings.region is None:
        reach = bound.radius + float(np.abs(np.concatenate([bound.sweep_low,
                                                            bound.sweep_high])).max())
        lo, hi = points[:, :2].min(axis=0) - reach, points[:, :2].max(axis=0) + reach
    else:
        x0, x1, y0, y1 = settings.region
        if not (x0 <= x1 and y0 <= y1):
            raise ValueError(f"--region is X_MIN X_MAX Y_MIN Y_MAX, got {settings.region}")
        lo, hi = np.array([x0, y0]), np.array([x1, y1])
    xs = np.arange(math.ceil(lo[0] / settings.step), math.floor(hi[0] / settings.step) + 1)
    ys = np.arange(math.ceil(lo[1] / settings.step), math.floor(hi[1] / settings.step) + 1)
    yaws = np.arange(settings.yaw_steps) * (2 * math.pi / settings.yaw_steps)
    gx, gy, gyaw = np.meshgrid(xs * settings.step, ys * settings.step, yaws, indexing="ij")
    x, y, yaw = gx.ravel(), gy.ravel(), gyaw.ravel()
    keep = np.ones(len(x), bool)
    for target, p in zip(targets, points, strict=True):
        near = bound.distance(_to_base(p, x, y, yaw, settings.floor)) <= bound.radius
        if not near.any():
            raise UnreachableTargetError(target.name, len(x), "it lies beyond the arm's reach "
                                         "from every base pose of the grid")
        keep &= near
    return Candidates(x[keep], y[keep], yaw[keep]), len(x)


def _to_base(p: Array, x: Array, y: Array, yaw: Array, floor: float) -> Array:
    """A cell point in the base frames of many candidates (N, 3)."""
    dx, dy = p[0] - x, p[1] - y
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * dx + s * dy, -s * dx + c * dy, np.full_like(x, p[2] - floor)], axis=1)


def references(solver: AllSolutions, seed: int = 0) -> tuple[float, float]:
    """(m_ref, d_ref): the largest manipulability of random configurations and the joint
    margin of the configuration in the middle of every range (rad or m)."""
    rng = np.random.default_rng(seed)
    qs = rng.uniform(solver.lower, solver.upper, size=(REFERENCE_SAMPLES, solver.dof))
    best = float(np.max(solver.manipulability(qs)))
    return best, float(np.min(solver.upper - solver.lower) / 2)


@dataclass
class _Context:
    world: CollisionWorld
    solver: AllSolutions
    scene: Scene
    targets: Array
    floor: float
    refs: tuple[float, float]


def prepare_context(build: ArmBuilder, scene: Scene, targets: Array, floor: float,
             refs: tuple[float, float]) -> _Context:
    arm = build()
    world = arm.collision_world(scene)  # (checks the scene's allowed links against the arm)
    return _Context(world, AllSolutions(arm.chain, arm.ik_solver()), scene, targets, floor,
                    refs)


def target_margins(context: _Context, base: Array) -> tuple[Array, list[tuple[Array, Array]]]:
    """Each target's margin from ``base`` (-1 where no collision-free solution) and, per
    target, its collision-free solutions (k, n) with their margins (k,), best first."""
    local = invert(base) @ context.targets
    cand = context.solver.solve(local[:, :3, :3], local[:, :3, 3])
    n_t = len(local)
    out = np.full(n_t, -1.0)
    sols: list[tuple[Array, Array]] = [(np.zeros((0, cand.q.shape[2])), np.zeros(0))] * n_t
    if not np.any(cand.count > 0):
        return out, sols
    world = context.world.in_scene(moved(context.scene, invert(base)))
    valid = cand.valid
    hit = np.ones(valid.shape, bool)
    hit[valid] = np.asarray(world.in_collision_many(cand.q[valid]), bool)
    m_ref, d_ref = context.refs
    score = np.minimum(np.minimum(cand.manipulability / m_ref, 1.0), cand.margin / d_ref)
    for t in range(n_t):
        free = valid[t] & ~hit[t]
        if free.any():
            order = np.argsort(-score[t][free], kind="stable")
            sols[t] = (cand.q[t][free][order], score[t][free][order])
            out[t] = float(sols[t][1][0])
    return out, sols


def _chunk(context: _Context, chunk: Array) -> Result:
    """Per candidate of the chunk (rows x, y, yaw): the margin of every target."""
    margins = np.array([target_margins(context, base_pose(x, y, yaw, context.floor))[0]
                        for x, y, yaw in chunk])
    return {"margins": margins.reshape(len(chunk), len(context.targets))}


def place_job(found: Candidates, build: ArmBuilder, scene: Scene, targets: list[Target],
              settings: PlaceSettings, refs: tuple[float, float], description: str,
              version: str) -> Job:
    """The study's job: chunks of candidates."""
    rows = np.stack([found.x, found.y, found.yaw], axis=1)
    per = settings.chunk_candidates
    chunks = [rows[s:s + per] for s in range(0, len(rows), per)]
    poses = np.array([t.pose for t in targets])
    parts = {"robot description": digest(description),
             "scene": digest(scene_fingerprint(scene)), "targets": digest(poses.tolist()),
             "settings": digest(asdict(settings), refs), "usar-arm version": version}
    prepare = functools.partial(prepare_context, build, scene, poses, settings.floor, refs)
    return Job("placement study", prepare, _chunk, chunks, digest("place", parts),
               [len(c) * len(targets) for c in chunks], parts)


@dataclass(frozen=True)
class Ranking:
    """Every candidate's target margins (C, T; -1: unreachable), its score (the worst
    target's margin) and the feasible candidates' indices, best first."""

    margins: Array
    score: Array
    order: NDArray[np.int64]

    @property
    def feasible(self) -> NDArray[np.bool_]:
        """(C,): every target reached collision-free."""
        return np.asarray(self.score >= 0)


def rank(results: list[Result]) -> Ranking:
    """The ranking from every chunk's result (ties: the earlier candidate)."""
    margins = np.vstack([r["margins"] for r in results])
    score = margins.min(axis=1)
    feasible = np.flatnonzero(score >= 0)
    order = feasible[np.argsort(-score[feasible], kind="stable")]
    return Ranking(margins, score, order)
