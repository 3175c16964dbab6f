"""Reach, place and batch jobs for a described arm: the facade over :mod:`usar_arm.workspace`.

It picks the execution backend (in this process, a local process pool, or Ray), gives the job
a builder that rebuilds the arm from its description's text in each worker, and keeps the
finished chunks of a job in ``DIR/.chunks`` until its outputs are written, so an interrupted
run can be resumed.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from usar_arm.core.errors import IKError
from usar_arm.core.job_errors import ClusterUnavailableError, UnreachableTargetError
from usar_arm.core.spatial import Array
from usar_arm.core.version import __version__
from usar_arm.planning.robot import Robot, robot_from_texts
from usar_arm.planning.scene import Scene
from usar_arm.workspace.arm_model import ArmBuilder, scene_fingerprint
from usar_arm.workspace.edges import EdgeResult
from usar_arm.workspace.engine import (
    Backend,
    ChunkStore,
    InProcess,
    Job,
    Progress,
    RunStats,
    digest,
    run_job,
)
from usar_arm.workspace.placement import (
    Candidates,
    PlaceSettings,
    Ranking,
    candidates,
    place_job,
    prepare_context,
    rank,
    references,
    target_margins,
)
from usar_arm.workspace.pool import ProcessBackend
from usar_arm.workspace.reach import (
    ReachPlan,
    ReachSettings,
    add_edges,
    assemble,
    collision_checks,
    edge_search,
    plan_reach,
    reach_job,
)
from usar_arm.workspace.reach_map import ReachMap
from usar_arm.workspace.solver import AllSolutions
from usar_arm.workspace.targets import Target

CHUNKS = ".chunks"
"""Folder (inside a job's output folder) of its finished chunks."""


def backend_for(workers: int | None = None, ray: str | None = None,
                timeout: float = 10.0) -> Backend:
    """The backend: Ray at ``ray`` (an address: :mod:`.ray_address`), else ``workers`` local
    processes (0: this process; None: one per core).

    Raises:
        ClusterUnavailableError: Ray asked for but not installed.
    """
    if ray is not None:
        try:
            from usar_arm.workspace.ray_backend import RayBackend
        except ImportError as exc:
            raise ClusterUnavailableError(
                ray, f"Ray is not installed ({exc}); install the extra: "
                     "pip install 'usar-arm[ray]'") from None
        return RayBackend(ray, workers, timeout)
    if workers == 0:
        return InProcess()
    return ProcessBackend(workers)


def arm_builder(robot: Robot) -> ArmBuilder:
    """A picklable callable that rebuilds ``robot`` from its description's text."""
    urdf_name = next((n for n in robot.files if n.endswith(".urdf")), None)
    files = dict(robot.files) if urdf_name else {f"{robot.chain.name}.urdf": robot.urdf}
    return functools.partial(robot_from_texts, files, urdf_name or f"{robot.chain.name}.urdf",
                             robot.source, robot.options, robot.carried)


def description_text(robot: Robot) -> str:
    """What a job's results depend on in the description (URDF and SRDF text, and what the
    arm carries)."""
    srdf = next((t for n, t in robot.files.items() if n.endswith(".srdf")), "")
    carried = "".join(f"\ncarrying {b.key()!r}" for b in robot.carried)
    return robot.urdf + "\n" + srdf + carried


def _run(job: Job, backend: Backend, out_dir: str | Path | None, resume: bool,
         progress: Progress | None) -> tuple[list, RunStats, ChunkStore | None]:
    store = ChunkStore(Path(out_dir) / CHUNKS, job) if out_dir is not None else None
    results, stats = run_job(job, backend, store, resume, progress)
    return results, stats, store


def plan_map(robot: Robot, settings: ReachSettings) -> ReachPlan:
    """The grid, candidate voxels and memory estimate of a map (raises MapTooLargeError)."""
    return plan_reach(robot.chain, settings)


@dataclass(frozen=True)
class ReachRun:
    """A computed map, how the run went, its plan, the collision checks its centres cost and
    what the edge search found (None when the settings turn it off)."""

    map: ReachMap
    stats: RunStats
    plan: ReachPlan
    collision_checks: int
    edges: EdgeResult | None = None


def reach_map(robot: Robot, scene: Scene, settings: ReachSettings, backend: Backend,
              out_dir: str | Path | None = None, resume: bool = False,
              progress: Progress | None = None, plan: ReachPlan | None = None,
              before_edges: Callable[[], None] | None = None) -> ReachRun:
    """The reachability map of ``robot`` in ``scene``: every voxel centre on ``backend``,
    then (unless the settings turn it off) the edge search in this process, announced by
    ``before_edges``. With ``out_dir``, finished chunks are kept in ``out_dir/.chunks`` (and,
    with ``resume``, taken from there) until the caller has written the map and calls
    :func:`finish`."""
    plan = plan or plan_map(robot, settings)
    description = description_text(robot)
    job = reach_job(plan, arm_builder(robot), scene, description, __version__)
    job = replace(job, parts={  # what a refused --resume names (the key is reach_job's)
        "robot description": digest(description), "scene": digest(scene_fingerprint(scene)),
        "settings": digest(asdict(plan.settings)), "usar-arm version": __version__})
    results, stats, _ = _run(job, backend, out_dir, resume, progress)
    m = assemble(plan, results, robot.chain.joint_names)
    if not settings.edges:
        return ReachRun(m, stats, plan, collision_checks(results))
    if before_edges is not None:
        before_edges()
    found = edge_search(plan, robot, scene).run(m.index > 0, m.best_q.reshape(-1, robot.chain.dof))
    return ReachRun(add_edges(m, found), stats, plan, collision_checks(results), found)


def finish(out_dir: str | Path) -> None:
    """Drop a finished job's chunk files (its outputs are written)."""
    folder = Path(out_dir) / CHUNKS
    if folder.exists():
        for f in folder.iterdir():
            f.unlink()
        folder.rmdir()


@dataclass(frozen=True)
class PlaceRun:
    """A placement study: the candidates (and how many the grid had before the reach bound
    dropped some), their ranking, the references of the margins (m_ref, d_ref), how the run
    went, and for the best base each target's collision-free solutions with their margins,
    best first."""

    candidates: Candidates
    grid_candidates: int
    ranking: Ranking
    references: tuple[float, float]
    stats: RunStats
    best: int
    solutions: list[tuple[Array, Array]]


def place(robot: Robot, scene: Scene, targets: list[Target], settings: PlaceSettings,
          backend: Backend, out_dir: str | Path | None = None, resume: bool = False,
          progress: Progress | None = None) -> PlaceRun:
    """Rank candidate base poses on the floor by the worst target's margin.

    Raises:
        UnreachableTargetError: a target no candidate reaches collision-free (named).
        IKError: every target is reachable from some base, but none reaches them all.
    """
    found, total = candidates(robot.chain, targets, settings)
    build = arm_builder(robot)
    solver = AllSolutions(robot.chain, robot.ik_solver())
    refs = references(solver)
    job = place_job(found, build, scene, targets, settings, refs, description_text(robot),
                    __version__)
    results, stats, _ = _run(job, backend, out_dir, resume, progress)
    ranking = rank(results) if results else Ranking(np.zeros((0, len(targets))),
                                                    np.zeros(0), np.zeros(0, np.int64))
    if len(ranking.order) == 0:
        _explain_no_base(targets, ranking, len(found))
    best = int(ranking.order[0])
    context = prepare_context(build, scene, np.array([t.pose for t in targets]), settings.floor,
                            refs)
    _, solutions = target_margins(context, found.pose(best, settings.floor))
    return PlaceRun(found, total, ranking, refs, stats, best, solutions)


def _explain_no_base(targets: list[Target], ranking: Ranking, n: int) -> None:
    reached = (ranking.margins >= 0).sum(axis=0) if n else np.zeros(len(targets), int)
    for t, count in zip(targets, reached, strict=True):
        if count == 0:
            raise UnreachableTargetError(t.name, n, "the candidates are the base poses within "
                                                    "reach of every target: move it, or widen "
                                                    "--region")
    covers = (ranking.margins >= 0).sum(axis=1)
    best = int(np.argmax(covers))
    missing = [t.name for t, ok in zip(targets, ranking.margins[best] >= 0, strict=True)
               if not ok]
    raise IKError(f"no candidate base reaches all {len(targets)} targets (each is reachable "
                  f"from some); the best reaches {int(covers[best])}, missing "
                  f"{', '.join(missing)}")
