"""The voxel grid of a reachability map, sized from the arm itself.

The reach bound comes from the description, never from a constant: joints before the first
revolute one (a rail) move everything along fixed axes, so the first revolute joint's origin
sweeps a box; from there on every rigid segment keeps its length under rotation, so tool0 lies
within the sum of the segment lengths (plus the travel of any later prismatic joint) of that
box. The grid's voxel centres sit on multiples of the resolution in base_link, so a slice
through the base (y = 0, z = 0) is a row of voxel centres.
"""

from __future__ import annotations

import itertools
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.job_errors import MapTooLargeError
from usar_arm.core.model import Joint, JointType, KinematicChain
from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class ReachBound:
    """Where tool0 can be, conservatively.

    Attributes:
        sweep_low, sweep_high: corners (m, base_link) of the box the first revolute joint's
            origin sweeps (a point when the arm has no rail).
        radius: m; tool0 lies within this distance of that box.
    """

    sweep_low: Array
    sweep_high: Array
    radius: float

    def distance(self, points: Array) -> Array:
        """Distance (m) of points (N, 3) from the sweep box."""
        outside = np.maximum(self.sweep_low - points, 0.0) + np.maximum(
            points - self.sweep_high, 0.0)
        return np.asarray(np.linalg.norm(outside, axis=-1))

    @property
    def low(self) -> Array:
        """Corner (m) of the axis-aligned box holding every reachable tool0 position."""
        return self.sweep_low - self.radius

    @property
    def high(self) -> Array:
        """The opposite corner (m)."""
        return self.sweep_high + self.radius


def reach_bound(chain: KinematicChain, frame: str = "tool0") -> ReachBound:
    """The reach bound of ``frame`` for ``chain`` (m, base_link)."""
    zero = np.zeros(chain.dof)
    path = [j for j in chain.path_to(chain.frames.get(frame, frame)) if j.actuated]
    frames = {j.name: f for j, f in chain.joint_frames(zero)}
    tool = chain.frame_pose(frame, zero)[:3, 3]
    rail = list(itertools.takewhile(lambda j: j.type == JointType.PRISMATIC, path))
    rest = path[len(rail):]
    pivot = frames[rest[0].name][:3, 3] if rest else tool
    low, high = _rail_sweep(rail, frames, pivot)
    radius = 0.0
    previous = pivot
    for joint in rest:
        point = frames[joint.name][:3, 3]
        radius += float(np.linalg.norm(point - previous))
        previous = point
        if joint.type == JointType.PRISMATIC and joint.limits is not None:
            radius += max(abs(joint.limits.lower), abs(joint.limits.upper))
    radius += float(np.linalg.norm(tool - previous))
    return ReachBound(low, high, radius)


def _rail_sweep(rail: list[Joint], frames: dict[str, Array], point: Array
                ) -> tuple[Array, Array]:
    """The box ``point`` sweeps when the prismatic joints before the first revolute one (the
    ``rail``) run through their limits."""
    low, high = point.copy(), point.copy()
    for joint in rail:
        axis = frames[joint.name][:3, :3] @ np.asarray(joint.axis, float)
        lo, hi = (joint.limits.lower, joint.limits.upper) if joint.limits else (0.0, 0.0)
        low = low + np.minimum(axis * lo, axis * hi)
        high = high + np.maximum(axis * lo, axis * hi)
    return low, high


@dataclass(frozen=True)
class VoxelGrid:
    """Voxel centres at ``origin + (i, j, k) * resolution`` (m, base_link), (nx, ny, nz)."""

    origin: Array
    resolution: float
    shape: tuple[int, int, int]

    @property
    def size(self) -> int:
        """Number of voxels."""
        return int(np.prod(self.shape))

    def centres(self, flat: NDArray[np.int64]) -> Array:
        """Centres (N, 3) of voxels given by flat (C-order) indices."""
        ijk = np.stack(np.unravel_index(flat, self.shape), axis=1)
        return np.asarray(self.origin + ijk * self.resolution)

    def index_of(self, points: Array) -> NDArray[np.int64]:
        """(N, 3) integer voxel indices of points (may fall outside the grid)."""
        return np.floor((points - self.origin) / self.resolution + 0.5).astype(np.int64)


def grid_for(bound: ReachBound, resolution: float) -> VoxelGrid:
    """The smallest grid on multiples of ``resolution`` that covers the reach bound."""
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"the resolution is a positive length in metres, got {resolution}")
    first = np.floor(bound.low / resolution).astype(np.int64)
    last = np.ceil(bound.high / resolution).astype(np.int64)
    shape = tuple(int(v) for v in last - first + 1)
    origin = np.asarray(first * resolution, dtype=np.float64)
    return VoxelGrid(origin, float(resolution), (shape[0], shape[1], shape[2]))


def candidate_voxels(grid: VoxelGrid, bound: ReachBound) -> NDArray[np.int64]:
    """Flat indices of the voxels whose centre may be reachable (within the bound plus half a
    voxel diagonal); every other voxel is 0 without a query."""
    slack = grid.resolution * math.sqrt(3.0) / 2.0
    out = []
    step = 1 << 18
    for start in range(0, grid.size, step):
        flat = np.arange(start, min(start + step, grid.size), dtype=np.int64)
        near = bound.distance(grid.centres(flat)) <= bound.radius + slack
        out.append(flat[near])
    return np.concatenate(out) if out else np.zeros(0, np.int64)


def bytes_per_voxel(dof: int, orientations: int) -> int:
    """Memory (bytes) one voxel of a map takes: index, manipulability, joint margin (float32),
    best configuration (float64 x dof), its orientation (int32), the reachable bits and the
    edge flag (bool)."""
    return 3 * 4 + 8 * dof + 4 + (orientations + 7) // 8 + 1


def available_memory() -> int:
    """Bytes of memory available to a new allocation (MemAvailable, else total RAM)."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))


def chunk_bytes_per_voxel(dof: int, orientations: int) -> int:
    """Memory (bytes) one voxel takes in a chunk's result, held by the command until the map
    is assembled: the voxel's arrays (no edge flag) and its flat index (int64)."""
    return bytes_per_voxel(dof, orientations) - 1 + 8


def check_memory(grid: VoxelGrid, dof: int, orientations: int,
                 available: int | None = None) -> int:
    """The estimated peak memory (bytes) of a map on ``grid``: the chunks' results the command
    holds until it has assembled them, the assembled arrays, and a second copy of them (the
    edge search's marked copy, then the compressed copy on saving, as large at worst), every
    voxel of the grid counted (the candidates are fewer).
    Refuses a map above half the available memory.

    Raises:
        MapTooLargeError: with the estimate, the memory available and a resolution that fits.
    """
    need = grid.size * (2 * bytes_per_voxel(dof, orientations)
                        + chunk_bytes_per_voxel(dof, orientations))
    have = available_memory() if available is None else available
    if need > have // 2:
        fits = grid.resolution * (need / (have // 2)) ** (1.0 / 3.0)
        raise MapTooLargeError(grid.size, need, have, math.ceil(fits * 1000) / 1000)
    return need
