"""The grid comes from the arm: the reach bound holds tool0 at every configuration (a rail
included), voxel centres sit on multiples of the resolution, and a map that would not fit in
memory is refused with the numbers."""

from __future__ import annotations

import numpy as np
import pytest

from usar_arm.core.job_errors import MapTooLargeError
from usar_arm.planning.robot import Robot
from usar_arm.workspace.grid import (
    bytes_per_voxel,
    candidate_voxels,
    check_memory,
    grid_for,
    reach_bound,
)


def _tool_positions(robot: Robot, n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    qs = rng.uniform(robot.chain.lower(), robot.chain.upper(), size=(n, robot.chain.dof))
    kin = robot.kinematics
    return np.array([kin.frame_pose(q, "tool0")[:3, 3] for q in qs])


def test_the_kr60_never_reaches_beyond_its_bound_and_the_bound_is_tight(kr60: Robot) -> None:
    bound = reach_bound(kr60.chain)
    d = bound.distance(_tool_positions(kr60, 20_000, 1))
    assert d.max() <= bound.radius
    assert d.max() > 0.9 * bound.radius  # not a loose constant: within 10 % of the sample
    assert np.allclose(bound.sweep_low, bound.sweep_high)  # no rail: one pivot point


def test_a_rail_stretches_the_bound_along_the_rail(fanuc: Robot) -> None:
    bound = reach_bound(fanuc.chain)
    rail = fanuc.chain.actuated_joints[0]
    assert rail.type.value == "prismatic"
    assert rail.limits is not None
    sweep = bound.sweep_high - bound.sweep_low
    assert np.isclose(sweep.max(), rail.limits.upper - rail.limits.lower)
    assert bound.distance(_tool_positions(fanuc, 20_000, 2)).max() <= bound.radius


def test_voxel_centres_lie_on_multiples_of_the_resolution(kr60: Robot) -> None:
    bound = reach_bound(kr60.chain)
    grid = grid_for(bound, 0.1)
    assert np.allclose(grid.origin / 0.1, np.round(grid.origin / 0.1))
    corner = grid.origin + (np.array(grid.shape) - 1) * 0.1
    assert np.all(grid.origin <= bound.low + 1e-9) and np.all(corner >= bound.high - 1e-9)
    flat = np.arange(grid.size)[::997]
    assert np.array_equal(np.ravel_multi_index(grid.index_of(grid.centres(flat)).T,
                                               grid.shape), flat)


def test_candidate_voxels_are_those_near_the_reach(kr60: Robot) -> None:
    bound = reach_bound(kr60.chain)
    grid = grid_for(bound, 0.2)
    near = candidate_voxels(grid, bound)
    centres = grid.centres(np.arange(grid.size))
    inside = bound.distance(centres) <= bound.radius + 0.2 * np.sqrt(3) / 2
    assert np.array_equal(near, np.flatnonzero(inside))
    assert 0.3 * grid.size < len(near) < 0.7 * grid.size  # a ball in its box: about pi/6


def test_a_map_too_fine_for_the_memory_is_refused_with_the_numbers(kr60: Robot) -> None:
    grid = grid_for(reach_bound(kr60.chain), 0.002)
    with pytest.raises(MapTooLargeError) as err:
        check_memory(grid, 6, 64, available=24 * 2**30)
    assert err.value.need_bytes > 12 * 2**30
    assert "GiB" in str(err.value) and "resolution of at least" in str(err.value)
    fits = grid_for(reach_bound(kr60.chain), err.value.resolution_that_fits_m)
    assert check_memory(fits, 6, 64, available=24 * 2**30) <= 12 * 2**30


def test_the_memory_estimate_counts_the_chunk_results_the_command_holds(kr60: Robot) -> None:
    """The chunks' results (every voxel's arrays and its index) are held until the map is
    assembled: they count beside the map and its compressed copy."""
    grid = grid_for(reach_bound(kr60.chain), 0.1)
    per_voxel = bytes_per_voxel(6, 64)
    assert per_voxel == 3 * 4 + 8 * 6 + 4 + 8 + 1  # ... the reachable bits, the edge flag
    assert check_memory(grid, 6, 64, available=2**40) == grid.size * (3 * per_voxel - 1 + 8)
