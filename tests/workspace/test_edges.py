"""The edge search's parts, each against Pinocchio's forward kinematics of the URDF and the
brute-force FCL judge: where tool0 lands (the compiled kernel), how a seed is moved into a cell,
what random draws find and estimate, and a whole map of the Fanuc on its rail."""

from __future__ import annotations

import numpy as np

from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import EMPTY
from usar_arm.workspace import edge_kernel, jobs
from usar_arm.workspace.cell_sampling import sample_cells
from usar_arm.workspace.grid import VoxelGrid, grid_for, reach_bound
from usar_arm.workspace.reach import ReachSettings
from usar_arm.workspace.solver import AllSolutions


def _tool0(robot: Robot, qs: np.ndarray) -> np.ndarray:
    return np.array([robot.kinematics.frame_pose(q, "tool0")[:3, 3] for q in qs])


def _grid(robot: Robot, resolution: float) -> VoxelGrid:
    return grid_for(reach_bound(robot.chain), resolution)


def test_the_landing_kernel_puts_tool0_where_pinocchio_does(kr60: Robot) -> None:
    solver = AllSolutions(kr60.chain, kr60.ik_solver())
    grid = _grid(kr60, 0.1)
    rng = np.random.default_rng(2)
    qs = rng.uniform(solver.lower, solver.upper, size=(2000, 6))
    open_cells = rng.random(grid.size) < 0.5
    cell = np.empty(len(qs), np.int64)
    count = edge_kernel.landings(qs, solver.axes, solver.points, solver.revolute, solver.tool,
                                 grid.origin, grid.resolution, np.array(grid.shape), open_cells,
                                 cell)
    ijk = np.floor((_tool0(kr60, qs) - grid.origin) / grid.resolution + 0.5).astype(int)
    flat = np.ravel_multi_index(ijk.T, grid.shape)
    expected = np.where(open_cells[flat], flat, -1)
    assert np.array_equal(cell, expected) and count == int(np.sum(expected >= 0)) > 500


def test_a_seed_moved_into_a_cell_is_inside_it_and_within_the_limits(kr60: Robot) -> None:
    """Cells 0.6 voxel from where random configurations put tool0: most tries end inside (by
    Pinocchio's FK), every try ends within the limits, and a try that says inside is."""
    solver = AllSolutions(kr60.chain, kr60.ik_solver())
    rng = np.random.default_rng(3)
    seeds = rng.uniform(solver.lower, solver.upper, size=(300, 1, 6))
    res = 0.1
    centres = _tool0(kr60, seeds[:, 0]) + rng.choice([-1, 1], size=(300, 3)) * 0.6 * res
    for keep in (0.0, 0.5):
        q = np.zeros_like(seeds)
        inside = np.zeros((300, 1), bool)
        edge_kernel.into_cells(centres, centres, res / 2, seeds, solver.lower, solver.upper,
                               solver.axes, solver.points, solver.revolute, solver.tool, 40,
                               0.3, keep, q, inside)
        assert inside.mean() > 0.9
        assert np.all(q >= solver.lower) and np.all(q <= solver.upper)
        landed = _tool0(kr60, q[inside[:, 0], 0])
        assert np.all(np.abs(landed - centres[inside[:, 0]]) <= res / 2)


def test_draws_find_cells_with_witnesses_and_count_what_they_found_once(kr60: Robot) -> None:
    solver = AllSolutions(kr60.chain, kr60.ik_solver())
    world = kr60.collision_world(EMPTY)
    grid = _grid(kr60, 0.2)
    open_cells = np.ones(grid.size, bool)
    found = sample_cells(solver, world, grid, open_cells, 20_000, seed=4)
    assert found.draws == 20_000 and found.landed == 20_000  # every cell is open
    assert np.all(np.diff(found.cells) > 0) and len(found.cells) > 500
    centres = grid.centres(found.cells)
    assert np.all(np.abs(_tool0(kr60, found.q) - centres) <= grid.resolution / 2 + 1e-12)
    for q in found.q[:100]:
        assert not world.contacts_brute_force(q)
    assert 0.5 < found.free_share <= 1.0
    assert found.miss_rate == found.singletons / found.draws / found.free_share
    again = sample_cells(solver, world, grid, open_cells, 20_000, seed=4)
    assert np.array_equal(again.cells, found.cells) and np.array_equal(again.q, found.q)


def test_the_fanuc_on_its_rail_reaches_into_marked_voxels_only(fanuc: Robot) -> None:
    """The numeric solver and a prismatic rail: 3,000 random poses all land in marked voxels;
    the edge voxels' witnesses are inside their cells."""
    run = jobs.reach_map(fanuc, EMPTY, ReachSettings(0.3, 16, edge_draws=1_000_000),
                         jobs.backend_for(0))
    m = run.map
    assert m.edge.any()
    world = fanuc.collision_world(EMPTY)
    rng = np.random.default_rng(6)
    qs = rng.uniform(fanuc.chain.lower(), fanuc.chain.upper(), size=(12_000, 7))
    qs = qs[~world.in_collision_many(qs)][:3000]
    assert np.all(m.lookup(_tool0(fanuc, qs)) > 0)
    for i, j, k in np.argwhere(m.edge)[:50]:
        p = _tool0(fanuc, m.best_q[i, j, k][None])[0]
        assert np.max(np.abs(p - m.centre(i, j, k))) <= m.resolution / 2
