"""Random configurations thrown at a map's unmarked cells, and what they say of its coverage.

The edge search (:mod:`.edges`) grows the marked region from its border; a reachable cell cut
off from it (a pocket behind an obstacle, a sliver of reach the border search slid past) is
found here instead: configurations drawn uniformly within the joint limits (seeded), tool0
placed by forward kinematics (:func:`.edge_kernel.landings`), and those landing in a cell still
unmarked are checked for collisions; the first free one of each cell is its witness.

The same draws measure the map. Under the uniform distribution over the joint limits, the
probability that a random *collision-free* configuration puts tool0 in a cell no draw has
found is estimated by Good and Turing's missing mass: the number of cells found exactly once,
over the number of draws, divided by the share of draws that are collision-free (itself
measured on the first draws). That is the chance that a pose picked as "FK of a random
collision-free configuration" lands in an unmarked voxel, as the map stands after this pass
(before the edge search grows it further).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.spatial import Array
from usar_arm.planning.collision import CollisionWorld
from usar_arm.workspace import edge_kernel
from usar_arm.workspace.grid import VoxelGrid
from usar_arm.workspace.solver import AllSolutions

BATCH = 1 << 19
"""Draws per call of the kernel (bounds the memory: 4 MiB of configurations for 6 joints)."""
FREE_SHARE_DRAWS = 20_000
"""Draws whose collisions are all checked, for the share of collision-free configurations."""


@dataclass(frozen=True)
class CellSamples:
    """What the draws found.

    Attributes:
        cells: (K,) flat indices of the unmarked cells a free draw landed in, ascending.
        q: (K, n) the first free draw of each (within the limits, tool0 inside the cell).
        draws: configurations drawn. landed: draws that landed in an unmarked cell.
        free_share: the share of draws free of collisions (of the first ones).
        singletons: cells found by exactly one free draw.
        miss_rate: the estimated chance that a random collision-free configuration puts tool0
            in a cell no draw found (see the module).
    """

    cells: NDArray[np.int64]
    q: Array
    draws: int
    landed: int
    free_share: float
    singletons: int
    miss_rate: float


def sample_cells(solver: AllSolutions, world: CollisionWorld, grid: VoxelGrid,
                 open_cells: NDArray[np.bool_], draws: int, seed: int) -> CellSamples:
    """Throw ``draws`` configurations at the cells of ``open_cells`` (flat bool over
    ``grid``), seeded with ``seed``."""
    rng = np.random.default_rng(seed)
    shape = np.array(grid.shape, np.int64)
    mask = np.ascontiguousarray(open_cells.ravel(), np.bool_)
    counts: dict[int, int] = {}
    first: dict[int, Array] = {}
    landed = 0
    free_share = 1.0
    done = 0
    while done < draws:
        qs = rng.uniform(solver.lower, solver.upper, size=(min(BATCH, draws - done), solver.dof))
        if done == 0:
            head = qs[:FREE_SHARE_DRAWS]
            free_share = float(np.mean(~np.asarray(world.in_collision_many(head), bool)))
        cell = np.empty(len(qs), np.int64)
        landed += edge_kernel.landings(qs, solver.axes, solver.points, solver.revolute,
                                       solver.tool, np.ascontiguousarray(grid.origin, float),
                                       grid.resolution, shape, mask, cell)
        hit = np.flatnonzero(cell >= 0)
        if len(hit):
            free = ~np.asarray(world.in_collision_many(qs[hit]), bool)
            for k in hit[free]:
                c = int(cell[k])
                counts[c] = counts.get(c, 0) + 1
                if c not in first:
                    first[c] = qs[k]
        done += len(qs)
    cells = np.array(sorted(first), np.int64)
    q = np.array([first[int(c)] for c in cells]).reshape(len(cells), solver.dof)
    singletons = sum(1 for v in counts.values() if v == 1)
    miss = singletons / draws / free_share if draws and free_share > 0 else float("nan")
    return CellSamples(cells, q, draws, landed, free_share, singletons, miss)
