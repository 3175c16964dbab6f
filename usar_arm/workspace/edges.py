"""Edge voxels: cells the arm reaches somewhere, though not at their centre.

The map's first pass asks each voxel's *centre* in each orientation of the set. At the edge of
the reach, and beside obstacles, a voxel's centre can be out of reach (or reachable only in
collision, or only in orientations between those of the set) while part of its cell is reached:
a pose the arm reaches would land in a voxel of index 0 (1.9 % of random reachable KR60 poses
did, at 10 cm). The edge search closes that gap, deterministically.

It grows the marked region outward. Each unmarked voxel beside a marked one (a *frontier*
cell; only voxels within the reach bound) is searched from the witness configurations of its
marked neighbours (face neighbours first): damped least squares on tool0's position, joints
clamped to their limits, toward the cell's centre, stopping as soon as tool0 is anywhere in
the cell (:mod:`.edge_kernel`); then toward its eight half-way points (centre +- a quarter
voxel on each axis: a cell whose reachable part is a corner); and, for a cell reached only in
collision (beside an obstacle), the same nine targets again with tool0's rotation held at the
seed's, so the tool keeps the attitude its free neighbour had. A configuration inside the cell,
within the limits and free of collisions in the scene is the cell's witness; the cell is
marked, and its unmarked neighbours are searched in the next round, until a round finds
nothing. Then random configurations are thrown at the cells still unmarked
(:mod:`.cell_sampling`: pockets the border search cannot reach), the border search resumes
from what they find, and the draws' count of cells found once estimates what is still
missed.

An edge voxel's index counts the orientations of the set nearest its witnesses' (one witness
per cell: 1 / m). It is a lower bound of the fraction of orientations the cell admits, where an
interior voxel's index is exact at its centre; ``ReachMap.edge`` tells them apart.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.spatial import Array
from usar_arm.planning.collision import CollisionWorld
from usar_arm.workspace import edge_kernel
from usar_arm.workspace.cell_sampling import CellSamples, sample_cells
from usar_arm.workspace.grid import VoxelGrid
from usar_arm.workspace.solver import AllSolutions

_OFFSETS = np.array(sorted(((a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1)
                            for c in (-1, 0, 1) if (a, b, c) != (0, 0, 0)),
                           key=lambda o: (abs(o[0]) + abs(o[1]) + abs(o[2]), o)))
"""The 26 neighbours of a voxel, face neighbours first (a deterministic order)."""
_HALFWAY = np.array([(a, b, c) for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)]) * 0.25
"""The second targets in a cell, in voxels from its centre."""


@dataclass(frozen=True)
class EdgeSettings:
    """How hard the edge search tries.

    Attributes:
        seeds: witnesses of marked neighbours tried per cell.
        iterations: least-squares steps per try at most. max_step: rad (or m) per step.
        rounds: growth rounds at most. keep_rotation: m/rad, the weight of tool0's rotation
            (held at the seed's) in the second passes. draws: random configurations thrown at
            the unmarked cells (0: none). seed: of the draws.
    """

    seeds: int = 6
    iterations: int = 40
    max_step: float = 0.3
    rounds: int = 100
    keep_rotation: float = 0.5
    draws: int = 4_000_000
    seed: int = 0


@dataclass(frozen=True)
class EdgeResult:
    """The cells the search marked, with their witnesses.

    Attributes:
        voxels: (K,) flat voxel indices. q: (K, n) witnesses (tool0 inside the cell, within
            the limits, collision-free). orientation: (K,) the row of the set orientation
            nearest each witness's tool0 rotation. manipulability: (K,) Yoshikawa's measure of
            each witness. margin: (K,) its distance to the nearest joint limit (rad or m).
        searched: cell searches in all (a cell may be searched in several rounds). tries:
            least-squares runs. rounds: growth rounds run. grown: cells found from the border
            before the draws. draws: what the random draws found and measured (None when
            they are turned off). seconds: wall time.
    """

    voxels: NDArray[np.int64]
    q: Array
    orientation: NDArray[np.int32]
    manipulability: Array
    margin: Array
    searched: int
    tries: int
    rounds: int
    grown: int
    draws: CellSamples | None
    seconds: float


class EdgeSearch:
    """The edge search of one map: the arm's kinematics, the scene and the grid.

    Args:
        solver: the map's IK solver (its kinematic arrays and manipulability).
        world: the collision world of the scene. rotations: (m, 3, 3) the map's orientations.
        grid: the map's grid. allowed: (nx, ny, nz) the voxels within the reach bound.
    """

    def __init__(self, solver: AllSolutions, world: CollisionWorld, rotations: Array,
                 grid: VoxelGrid, allowed: NDArray[np.bool_],
                 settings: EdgeSettings | None = None):
        self.solver = solver
        self.world = world
        self.rotations = np.asarray(rotations, float)
        self.grid = grid
        self.allowed = allowed
        self.settings = settings or EdgeSettings()
        self.tries = 0

    def run(self, marked: NDArray[np.bool_], witnesses: Array) -> EdgeResult:
        """Grow ``marked`` (nx, ny, nz) whose witnesses are ``witnesses`` (nx*ny*nz, n; NaN
        rows where unmarked) into the cells the arm reaches off-centre: from the border, then
        from the cells random draws find (:mod:`.cell_sampling`), then from the border again."""
        start = time.perf_counter()
        self._mark = marked.copy()
        self._wit = np.array(witnesses, float)
        self._found: list[tuple[NDArray[np.int64], Array]] = []
        self._searched = self._rounds = 0
        self._grow(self._mark)
        grown = sum(len(c) for c, _ in self._found)
        draws = None
        if self.settings.draws > 0:
            draws = sample_cells(self.solver, self.world, self.grid,
                                 self.allowed & ~self._mark, self.settings.draws,
                                 self.settings.seed)
            if len(draws.cells):
                self._add(draws.cells, draws.q)
                source = np.zeros_like(self._mark)
                source.flat[draws.cells] = True
                self._grow(source)
        voxels = np.concatenate([c for c, _ in self._found]) if self._found else \
            np.zeros(0, np.int64)
        q = np.vstack([w for _, w in self._found]) if self._found else \
            np.zeros((0, self.solver.dof))
        order = np.argsort(voxels, kind="stable")
        voxels, q = voxels[order], q[order]
        return EdgeResult(voxels, q, self._orientations(q), self.solver.manipulability(q),
                          np.min(np.minimum(q - self.solver.lower, self.solver.upper - q),
                                 axis=1) if len(q) else np.zeros(0),
                          self._searched, self.tries, self._rounds, grown, draws,
                          time.perf_counter() - start)

    def _add(self, cells: NDArray[np.int64], qs: Array) -> None:
        self._mark.flat[cells] = True
        self._wit[cells] = qs
        self._found.append((cells, qs))

    def _grow(self, source: NDArray[np.bool_]) -> None:
        """Search the frontier of ``source``, round after round, until a round finds nothing."""
        front = self._frontier(self._mark, source)
        while len(front) and self._rounds < self.settings.rounds:
            self._rounds += 1
            self._searched += len(front)
            cells, qs = self._search(front, self._mark, self._wit)
            if not len(cells):
                break
            self._add(cells, qs)
            new = np.zeros_like(self._mark)
            new.flat[cells] = True
            front = self._frontier(self._mark, new)

    def _frontier(self, mark: NDArray[np.bool_], source: NDArray[np.bool_]
                  ) -> NDArray[np.int64]:
        """Flat indices of the unmarked, allowed voxels beside a voxel of ``source``."""
        near = np.zeros_like(mark)
        pad = np.pad(source, 1)
        nx, ny, nz = mark.shape
        for a, b, c in _OFFSETS:
            near |= pad[1 + a:1 + a + nx, 1 + b:1 + b + ny, 1 + c:1 + c + nz]
        return np.flatnonzero(near & ~mark & self.allowed)

    def _seeds(self, cells: NDArray[np.int64], mark: NDArray[np.bool_], wit: Array) -> Array:
        """(C, S, n) witnesses of each cell's marked neighbours (NaN rows where fewer)."""
        shape = np.array(mark.shape)
        ijk = np.stack(np.unravel_index(cells, mark.shape), axis=1)
        seeds = np.full((len(cells), self.settings.seeds, self.solver.dof), np.nan)
        filled = np.zeros(len(cells), np.int64)
        for off in _OFFSETS:
            nb = ijk + off
            ok = np.all((nb >= 0) & (nb < shape), axis=1) & (filled < self.settings.seeds)
            flat = np.ravel_multi_index(nb[ok].T, mark.shape) if ok.any() else np.zeros(0, int)
            rows = np.flatnonzero(ok)[mark.flat[flat]]
            seeds[rows, filled[rows]] = wit[np.ravel_multi_index(ijk[rows].T + off[:, None],
                                                                 mark.shape)]
            filled[rows] += 1
        return seeds

    def _search(self, cells: NDArray[np.int64], mark: NDArray[np.bool_], wit: Array
                ) -> tuple[NDArray[np.int64], Array]:
        """The cells of ``cells`` found this round, and their witnesses."""
        seeds = self._seeds(cells, mark, wit)
        centres = self.grid.centres(cells)
        witness = np.full((len(cells), self.solver.dof), np.nan)
        open_ = np.ones(len(cells), bool)
        passes = [(offset, 0.0) for offset in (np.zeros(3), *_HALFWAY)]
        passes += [(offset, self.settings.keep_rotation) for offset in (np.zeros(3), *_HALFWAY)]
        collided = np.zeros(len(cells), bool)
        for offset, keep in passes:
            rows = np.flatnonzero(open_ & collided) if keep else np.flatnonzero(open_)
            if not len(rows):
                continue
            q, inside = self._tries(centres[rows] + offset * self.grid.resolution,
                                    centres[rows], seeds[rows], keep)
            hit_rows, hit_seeds = np.nonzero(inside)
            if not len(hit_rows):
                continue
            free = ~np.asarray(self.world.in_collision_many(q[hit_rows, hit_seeds]), bool)
            collided[rows[hit_rows[~free]]] = True
            for r, s in zip(hit_rows[free], hit_seeds[free], strict=True):
                cell = rows[r]
                if open_[cell]:
                    witness[cell] = q[r, s]
                    open_[cell] = False
        done = ~open_ & ~np.isnan(witness[:, 0])
        return cells[done], witness[done]

    def _tries(self, targets: Array, centres: Array, seeds: Array, keep: float
               ) -> tuple[Array, NDArray[np.bool_]]:
        s = self.solver
        q = np.zeros_like(seeds)
        inside = np.zeros(seeds.shape[:2], np.bool_)
        edge_kernel.into_cells(np.ascontiguousarray(targets), np.ascontiguousarray(centres),
                               self.grid.resolution / 2.0 * (1.0 - 1e-9),
                               np.ascontiguousarray(seeds), s.lower, s.upper, s.axes, s.points,
                               s.revolute, s.tool, self.settings.iterations,
                               self.settings.max_step, keep, q, inside)
        self.tries += int(np.sum(~np.isnan(seeds[:, :, 0])))
        return q, inside

    def _orientations(self, q: Array) -> NDArray[np.int32]:
        """The set orientation nearest tool0's rotation at each configuration."""
        if not len(q):
            return np.zeros(0, np.int32)
        s = self.solver
        rot = np.zeros((len(q), 3, 3))
        pos = np.zeros((len(q), 3))
        edge_kernel.tool_poses(np.ascontiguousarray(q), s.axes, s.points, s.revolute, s.tool,
                               rot, pos)
        return np.argmax(np.einsum("oij,kij->ko", self.rotations, rot), axis=1).astype(np.int32)
