"""Reachability maps: the job (voxels x orientations -> collision-free IK), run on a backend.

:func:`plan_reach` sizes the grid from the arm (:mod:`.grid`) and refuses a map that would not
fit in memory; :func:`reach_job` cuts the candidate voxels into chunks of about
``chunk_queries`` queries (each well above the ~10 ms below which a distributed task gains
nothing); :func:`assemble` puts the chunks' results into a :class:`~.reach_map.ReachMap`. The
voxels the reach bound excludes are 0 without a query. A chunk's result depends on its voxels
alone, so the map is the same for any backend and any number of workers.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass, replace

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.scene import Scene
from usar_arm.workspace.arm_model import ArmBuilder, ArmModel, scene_fingerprint
from usar_arm.workspace.edges import EdgeResult, EdgeSearch, EdgeSettings
from usar_arm.workspace.engine import Job, Result, digest
from usar_arm.workspace.grid import (
    ReachBound,
    VoxelGrid,
    candidate_voxels,
    check_memory,
    grid_for,
    reach_bound,
)
from usar_arm.workspace.orientations import OrientationSet, orientation_set
from usar_arm.workspace.query import reachability
from usar_arm.workspace.reach_map import ReachMap
from usar_arm.workspace.solver import AllSolutions

SUB_BATCH = 8192
"""Queries solved at once inside a chunk (bounds the worker's memory)."""


@dataclass(frozen=True)
class ReachSettings:
    """Settings of a map.

    Attributes:
        resolution: m, the voxel edge. orientations: tool orientations per voxel.
        cone_deg: restrict the tool z axis to this half-angle (deg) about ``cone_axis``
            (base_link; default straight down), or None for all of SO(3).
        chunk_queries: about this many queries per chunk.
        edges: search the cells whose centre is out of reach but which the arm reaches
            somewhere (:mod:`.edges`); off, a reachable pose near the edge of the reach may
            land in a voxel of index 0. edge_draws: random configurations of that search
            (:mod:`.cell_sampling`).
    """

    resolution: float = 0.05
    orientations: int = 64
    cone_deg: float | None = None
    cone_axis: tuple[float, float, float] = (0.0, 0.0, -1.0)
    chunk_queries: int = 32768
    edges: bool = True
    edge_draws: int = 4_000_000


@dataclass(frozen=True)
class ReachPlan:
    """What a map will compute: the grid, the reach bound, the candidate voxels (flat
    indices), the orientations, the number of queries and the estimated memory (bytes)."""

    settings: ReachSettings
    grid: VoxelGrid
    bound: ReachBound
    voxels: NDArray[np.int64]
    orientations: OrientationSet
    queries: int
    memory_bytes: int


def plan_reach(chain: KinematicChain, settings: ReachSettings,
               available_memory: int | None = None) -> ReachPlan:
    """The plan of a map of ``chain``.

    Raises:
        ValueError: a bad resolution or orientation count.
        MapTooLargeError: the map would not fit in memory (nothing computed).
    """
    rotations = orientation_set(settings.orientations, settings.cone_deg, settings.cone_axis)
    bound = reach_bound(chain)
    grid = grid_for(bound, settings.resolution)
    memory = check_memory(grid, chain.dof, len(rotations), available_memory)
    voxels = candidate_voxels(grid, bound)
    return ReachPlan(settings, grid, bound, voxels, rotations, len(voxels) * len(rotations),
                     memory)


@dataclass
class _Context:
    """A worker's state: the solver, the collision world, the rotations and the grid."""

    solver: AllSolutions
    world: CollisionWorld
    rotations: Array
    grid: VoxelGrid


def _prepare(build: ArmBuilder, scene: Scene, rotations: Array, grid: VoxelGrid) -> _Context:
    arm = build()
    return _Context(AllSolutions(arm.chain, arm.ik_solver()), arm.collision_world(scene),
                    rotations, grid)


def _chunk(context: _Context, voxels: NDArray[np.int64]) -> Result:
    """Index, manipulability, margin, witness and bits of each voxel of a chunk."""
    world = context.world
    centres = context.grid.centres(voxels)
    n_o = len(context.rotations)
    dof = context.solver.dof
    per = max(1, SUB_BATCH // n_o)
    reach = np.zeros((len(voxels), n_o), bool)
    manip = np.full((len(voxels), n_o), -np.inf)
    room = np.full((len(voxels), n_o), -np.inf)
    qs = np.full((len(voxels), n_o, dof), np.nan)
    checks = 0
    for s in range(0, len(voxels), per):
        block = centres[s:s + per]
        rots = np.broadcast_to(context.rotations[None], (len(block), n_o, 3, 3))
        v = reachability(context.solver, world, rots.reshape(-1, 3, 3),
                         np.repeat(block, n_o, axis=0))
        reach[s:s + per] = v.reachable.reshape(-1, n_o)
        manip[s:s + per] = v.manipulability.reshape(-1, n_o)
        room[s:s + per] = v.margin.reshape(-1, n_o)
        qs[s:s + per] = v.q.reshape(-1, n_o, dof)
        checks += v.checks
    any_ = np.asarray(reach.any(axis=1))
    best = np.where(any_, np.argmax(manip, axis=1), -1).astype(np.int32)
    rows = np.arange(len(voxels))
    best_q = np.where(any_[:, None], qs[rows, np.maximum(best, 0)], np.nan)
    return {
        "voxels": voxels,
        "index": reach.mean(axis=1).astype(np.float32),
        "manipulability": np.where(any_, manip.max(axis=1), 0.0).astype(np.float32),
        "margin": np.where(any_, room.max(axis=1), 0.0).astype(np.float32),
        "best_q": best_q,
        "best_orientation": best,
        "reachable": np.packbits(reach, axis=1),
        "checks": np.int64(checks),
    }


def reach_job(plan: ReachPlan, build: ArmBuilder, scene: Scene, description: str,
              version: str) -> Job:
    """The map's job: chunks of consecutive candidate voxels.

    Args:
        build: builds the arm in a worker. description: the description's text (URDF, SRDF),
            for the job's key. version: usar-arm's version (results may change with it).
    """
    n_o = len(plan.orientations)
    per = max(1, math.ceil(plan.settings.chunk_queries / n_o))
    chunks = [plan.voxels[s:s + per] for s in range(0, len(plan.voxels), per)]
    key = digest("reach", version, description, scene_fingerprint(scene),
                 asdict(plan.settings), plan.grid.origin.tolist(), plan.grid.shape)
    prepare = functools.partial(_prepare, build, scene, plan.orientations.matrices(),
                                plan.grid)
    return Job("reachability map", prepare, _chunk, chunks, key, [len(c) * n_o for c in chunks])


def assemble(plan: ReachPlan, results: list[Result], joint_names: tuple[str, ...]) -> ReachMap:
    """The map from every chunk's result (voxels outside the reach bound stay 0)."""
    shape = plan.grid.shape
    n_o = len(plan.orientations)
    index = np.zeros(plan.grid.size, np.float32)
    manip = np.zeros(plan.grid.size, np.float32)
    room = np.zeros(plan.grid.size, np.float32)
    best_q = np.full((plan.grid.size, len(joint_names)), np.nan)
    best_o = np.full(plan.grid.size, -1, np.int32)
    bits = np.zeros((plan.grid.size, (n_o + 7) // 8), np.uint8)
    for r in results:
        v = r["voxels"]
        index[v], manip[v], room[v] = r["index"], r["manipulability"], r["margin"]
        best_q[v], best_o[v], bits[v] = r["best_q"], r["best_orientation"], r["reachable"]
    return ReachMap(index.reshape(shape), manip.reshape(shape), room.reshape(shape),
                    best_q.reshape(*shape, len(joint_names)), best_o.reshape(shape),
                    bits.reshape(*shape, bits.shape[1]), plan.grid.origin.copy(),
                    plan.grid.resolution, plan.orientations.quaternions.copy(), joint_names,
                    np.zeros(shape, bool))


def add_edges(m: ReachMap, edges: EdgeResult) -> ReachMap:
    """``m`` with the edge voxels the search found (:mod:`.edges`) marked."""
    n_o = len(m.orientations)
    index, manip, room = m.index.copy(), m.manipulability.copy(), m.margin.copy()
    best_q, best_o = m.best_q.copy(), m.best_orientation.copy()
    bits, edge = m.reachable.copy(), m.edge.copy()
    ijk = np.unravel_index(edges.voxels, m.shape)
    index[ijk] = 1.0 / n_o
    manip[ijk], room[ijk] = edges.manipulability, edges.margin
    best_q[ijk], best_o[ijk], edge[ijk] = edges.q, edges.orientation, True
    reached = np.zeros((len(edges.voxels), n_o), bool)
    reached[np.arange(len(edges.voxels)), edges.orientation] = True
    bits[ijk] = np.packbits(reached, axis=1)
    return replace(m, index=index, manipulability=manip, margin=room, best_q=best_q,
                   best_orientation=best_o, reachable=bits, edge=edge)


def edge_search(plan: ReachPlan, arm: ArmModel, scene: Scene) -> EdgeSearch:
    """The edge search of a map of ``arm`` in ``scene`` planned by ``plan``."""
    allowed = np.zeros(plan.grid.size, bool)
    allowed[plan.voxels] = True
    return EdgeSearch(AllSolutions(arm.chain, arm.ik_solver()), arm.collision_world(scene),
                      plan.orientations.matrices(), plan.grid, allowed.reshape(plan.grid.shape),
                      EdgeSettings(draws=plan.settings.edge_draws))


def collision_checks(results: list[Result]) -> int:
    """Collision checks the map cost in all."""
    return int(sum(int(r["checks"]) for r in results))
