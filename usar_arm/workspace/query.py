"""Reachability of tool poses: collision-free IK, best manipulability and joint margin.

A pose is reachable when at least one of its IK solutions (:mod:`.solver`) is free of
collisions (the collision world's verdict: compiled bounds, python-fcl where they cannot
decide). Collisions are checked lazily, in batches: first each pose's solutions in order of
decreasing manipulability until one is free (that one has the best manipulability of the free
solutions), then those with a larger joint margin than it, in order of decreasing margin, until
one is free. A pose costs one collision check when its best solution is free, at most K.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.spatial import Array
from usar_arm.planning.collision import CollisionWorld
from usar_arm.workspace.solver import AllSolutions, Candidates


@dataclass(frozen=True)
class PoseVerdicts:
    """Per pose (M,): reachable, the best manipulability and the best joint margin over its
    collision-free solutions (-inf when none), the configuration with the best manipulability
    (NaN when none), how many solutions it had inside the limits and how many collision checks
    it cost."""

    reachable: NDArray[np.bool_]
    manipulability: Array
    margin: Array
    q: Array
    solutions: NDArray[np.int64]
    checks: int


def judge(candidates: Candidates, world: CollisionWorld) -> PoseVerdicts:
    """Collision verdicts for the solutions of M poses, lazily (see the module)."""
    m_all, _, dof = candidates.q.shape
    some = np.flatnonzero(candidates.count > 0)
    sub = _judge(Candidates(candidates.q[some], candidates.count[some],
                            candidates.manipulability[some], candidates.margin[some]), world)
    reachable = np.zeros(m_all, bool)
    manip = np.full(m_all, -np.inf)
    room = np.full(m_all, -np.inf)
    q = np.full((m_all, dof), np.nan)
    reachable[some], manip[some], room[some], q[some] = (sub.reachable, sub.manipulability,
                                                         sub.margin, sub.q)
    return PoseVerdicts(reachable, manip, room, q, candidates.count.copy(), sub.checks)


def _judge(candidates: Candidates, world: CollisionWorld) -> PoseVerdicts:
    """:func:`judge` of poses that all have at least one solution."""
    m, k, dof = candidates.q.shape
    valid = candidates.valid
    manip, room = candidates.manipulability, candidates.margin
    checked = np.zeros((m, k), bool)
    best_m = np.full(m, -np.inf)
    best_d = np.full(m, -np.inf)
    best_q = np.full((m, dof), np.nan)
    rows_all = np.arange(m)
    checks = 0
    for _ in range(2 * k):
        open_ = valid & ~checked
        score_m = np.where(open_ & (manip > best_m[:, None]), manip, -np.inf)
        score_d = np.where(open_ & (room > best_d[:, None]), room, -np.inf)
        has_m = np.isfinite(score_m.max(axis=1))
        has_d = np.isfinite(score_d.max(axis=1))
        pick = np.where(has_m, score_m.argmax(axis=1), score_d.argmax(axis=1))
        rows = rows_all[has_m | has_d]
        if len(rows) == 0:
            break
        cols = pick[rows]
        hit = np.asarray(world.in_collision_many(candidates.q[rows, cols]), dtype=bool)
        checks += len(rows)
        checked[rows, cols] = True
        free_rows, free_cols = rows[~hit], cols[~hit]
        better = manip[free_rows, free_cols] > best_m[free_rows]
        best_m[free_rows[better]] = manip[free_rows[better], free_cols[better]]
        best_q[free_rows[better]] = candidates.q[free_rows[better], free_cols[better]]
        best_d[free_rows] = np.maximum(best_d[free_rows], room[free_rows, free_cols])
    return PoseVerdicts(np.isfinite(best_m), best_m, best_d, best_q,
                        candidates.count.copy(), checks)


def reachability(solver: AllSolutions, world: CollisionWorld, rots: Array, poss: Array
                 ) -> PoseVerdicts:
    """Verdicts for M tool poses (rotations (M, 3, 3), positions (M, 3), base_link)."""
    return judge(solver.solve(rots, poss), world)
