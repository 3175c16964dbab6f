"""Compiled kernel of the edge search (:mod:`.edges`): move tool0 into a voxel's cell.

:func:`into_cells` runs, for each cell and each seed configuration, damped least squares on
tool0's *position* only (the orientation is left free) toward a target point, with every joint
clamped to its limits after each step, and stops as soon as tool0 lies inside the cell (an
axis-aligned cube of half-edge ``half`` about the cell's centre): being anywhere in the cell is
the goal, not reaching the target exactly. A run that stops getting closer to the cell (an
unreachable cell: the arm is stretched, or a limit blocks the way) is abandoned after a few
steps, so cells beyond the reach cost little.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.spatial import Array
from usar_arm.planning import ik_kernel
from usar_arm.planning.jit import kernel

IndexArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

DAMPING = 1e-4
"""m^2: the damping of the normal equations (keeps singular arms finite)."""
STALL_STEPS = 4
"""Steps without getting at least :data:`STALL_GAIN` closer to the cell before a run gives up."""
STALL_GAIN = 1e-4
"""m."""


@kernel
def _outside(pos: Array, centre: Array, half: float) -> float:
    """How far (m, the largest axis excess) ``pos`` lies outside the cube; <= 0 inside."""
    worst = -math.inf
    for k in range(3):
        worst = max(worst, abs(pos[k] - centre[k]) - half)
    return worst


@kernel
def _step(jac: Array, err: Array, rows: int, weight: float, n: int, dq: Array) -> bool:
    """dq = J^T (J J^T + d I)^-1 err over the first ``rows`` rows of ``jac`` (3: position; 6:
    position and rotation, the rotation rows and error scaled by ``weight``, m/rad); False when
    the system is singular."""
    a = np.empty((rows, rows))
    b = np.empty(rows)
    x = np.empty(rows)
    for r in range(rows):
        wr = 1.0 if r < 3 else weight
        b[r] = err[r] * wr
        for c in range(rows):
            wc = 1.0 if c < 3 else weight
            s = 0.0
            for i in range(n):
                s += jac[r, i] * jac[c, i]
            a[r, c] = s * wr * wc + (DAMPING if r == c else 0.0)
    if not ik_kernel.solve6(a, b, x):
        return False
    for i in range(n):
        s = 0.0
        for r in range(rows):
            s += jac[r, i] * x[r] * (1.0 if r < 3 else weight)
        dq[i] = s
    return True


@kernel
def _rotation_error(target: Array, rot: Array, err: Array) -> None:
    """err[3:6] = the rotation vector (rad, base axes) of target rot^T."""
    m = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            m[a, b] = target[a, 0] * rot[b, 0] + target[a, 1] * rot[b, 1] + target[a, 2] * rot[b, 2]
    tr = min(1.0, max(-1.0, (m[0, 0] + m[1, 1] + m[2, 2] - 1.0) / 2.0))
    angle = math.acos(tr)
    scale = 0.5 if angle < 1e-6 else angle / max(2.0 * math.sin(angle), 1e-300)
    err[3] = (m[2, 1] - m[1, 2]) * scale
    err[4] = (m[0, 2] - m[2, 0]) * scale
    err[5] = (m[1, 0] - m[0, 1]) * scale


@kernel
def into_cells(targets: Array, centres: Array, half: float, seeds: Array, lo: Array,
               hi: Array, axes: Array, points: Array, rev: Array, tool: Array, iterations: int,
               max_step: float, keep_rotation: float, q_out: Array, inside: BoolArray) -> None:
    """For cell m (centre ``centres[m]``, target point ``targets[m]``, both (M, 3) m) and seed
    s (``seeds`` (M, S, n); a row starting with NaN is skipped): the configuration reached,
    ``q_out[m, s]``, and whether tool0 ended inside the cell, ``inside[m, s]``. With
    ``keep_rotation`` > 0 (m/rad) the steps also hold tool0's rotation at the seed's, weighted
    so: a free configuration beside an obstacle stays clear of it as tool0 moves over."""
    n = seeds.shape[2]
    rows = 6 if keep_rotation > 0.0 else 3
    rot = np.empty((3, 3))
    keep = np.empty((3, 3))
    pos = np.empty(3)
    jac = np.empty((6, n))
    q = np.empty(n)
    dq = np.empty(n)
    err = np.zeros(6)
    for m in range(seeds.shape[0]):
        for s in range(seeds.shape[1]):
            inside[m, s] = False
            if math.isnan(seeds[m, s, 0]):
                continue
            for i in range(n):
                q[i] = seeds[m, s, i]
            best = math.inf
            stalled = 0
            for it in range(iterations):
                ik_kernel.pose_and_jacobian(q, axes, points, rev, tool, rot, pos, jac)
                if it == 0:
                    for a in range(3):
                        for b in range(3):
                            keep[a, b] = rot[a, b]
                gap = _outside(pos, centres[m], half)
                if gap <= 0.0:
                    inside[m, s] = True
                    break
                if gap < best - STALL_GAIN:
                    best = gap
                    stalled = 0
                else:
                    stalled += 1
                    if stalled >= STALL_STEPS:
                        break
                for k in range(3):
                    err[k] = targets[m, k] - pos[k]
                if rows == 6:
                    _rotation_error(keep, rot, err)
                if not _step(jac, err, rows, keep_rotation, n, dq):
                    break
                largest = 0.0
                for i in range(n):
                    largest = max(largest, abs(dq[i]))
                scale = 1.0 if largest <= max_step else max_step / largest
                for i in range(n):
                    q[i] = min(hi[i], max(lo[i], q[i] + scale * dq[i]))
            for i in range(n):
                q_out[m, s, i] = q[i]


@kernel
def tool_poses(qs: Array, axes: Array, points: Array, rev: Array, tool: Array, rot_out: Array,
               pos_out: Array) -> None:
    """tool0's rotation (N, 3, 3) and position (N, 3; m) at configurations ``qs`` (N, n)."""
    n = qs.shape[1]
    rot = np.empty((3, 3))
    pos = np.empty(3)
    jac = np.empty((6, n))
    for k in range(qs.shape[0]):
        ik_kernel.pose_and_jacobian(qs[k], axes, points, rev, tool, rot, pos, jac)
        for a in range(3):
            pos_out[k, a] = pos[a]
            for b in range(3):
                rot_out[k, a, b] = rot[a, b]


@kernel
def landings(qs: Array, axes: Array, points: Array, rev: Array, tool: Array, origin: Array,
             resolution: float, shape: IndexArray, open_cells: BoolArray,
             cell_out: IndexArray) -> int:
    """For configurations ``qs`` (N, n): the flat voxel index where tool0 lands, kept only
    when that voxel is one of ``open_cells`` (flat bool over the grid of ``shape`` (3,) int64,
    voxel centres at origin + ijk * resolution); ``cell_out[k]`` = the voxel, or -1. Returns
    how many landed in an open voxel."""
    n = qs.shape[1]
    rot = np.empty((3, 3))
    pos = np.empty(3)
    jac = np.empty((6, n))
    count = 0
    for k in range(qs.shape[0]):
        cell_out[k] = -1
        ik_kernel.pose_and_jacobian(qs[k], axes, points, rev, tool, rot, pos, jac)
        flat = 0
        inside = True
        for a in range(3):
            v = math.floor((pos[a] - origin[a]) / resolution + 0.5)
            if v < 0 or v >= shape[a]:
                inside = False
                break
            flat = flat * shape[a] + v
        if inside and open_cells[flat]:
            cell_out[k] = flat
            count += 1
    return count


def warm_up() -> None:
    """Compile the kernels for the argument types :mod:`.edges` passes."""
    z6 = np.zeros(6)
    into_cells(np.zeros((1, 3)), np.zeros((1, 3)), 0.05, np.zeros((1, 1, 6)), z6 - 1, z6 + 1,
               np.zeros((6, 3)), np.zeros((6, 3)), z6 + 1, np.eye(4), 1, 0.3, 0.0,
               np.zeros((1, 1, 6)), np.zeros((1, 1), np.bool_))
    tool_poses(np.zeros((1, 6)), np.zeros((6, 3)), np.zeros((6, 3)), z6 + 1, np.eye(4),
               np.zeros((1, 3, 3)), np.zeros((1, 3)))
    landings(np.zeros((1, 6)), np.zeros((6, 3)), np.zeros((6, 3)), z6 + 1, np.eye(4),
             np.zeros(3), 0.1, np.ones(3, np.int64), np.ones(1, np.bool_),
             np.zeros(1, np.int64))
