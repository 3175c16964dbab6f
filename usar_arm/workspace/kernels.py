"""Compiled kernels of the reachability queries: every IK solution of a batch of tool poses,
with each solution's manipulability and joint-limit margin.

:func:`analytic_solutions` (ortho-parallel arms, :mod:`usar_arm.planning.opw`) takes every
closed-form branch, winds it into the limits nearest the middle of each joint's range (the
winding with the widest margin), polishes it by Newton steps on the exact chain (the learnt arm
is never exactly OPW) and keeps it when it reaches the tolerance inside the limits.
:func:`numeric_solutions` (any serial chain) runs Levenberg-Marquardt from a fixed set of seeds.
Both drop duplicates (every joint within ``distinct``) and fill rows of a (M, K, n) array;
collisions are judged afterwards, in batches (:mod:`.query`).

Manipulability is Yoshikawa's sqrt(det(J J^T)) of tool0's 6 x n Jacobian (linear rows in m,
angular in rad; so it carries the units of the arm's size); the margin is the smallest distance
of any joint to one of its limits (rad, or m for a prismatic joint).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.spatial import Array
from usar_arm.planning import ik_kernel, lm_kernel
from usar_arm.planning.jit import kernel

IndexArray = NDArray[np.int64]

MAX_SOLUTIONS = 8
"""Rows per target: an ortho-parallel arm has at most 8 branches."""


@kernel
def manipulability(jac: Array) -> float:
    """Yoshikawa's measure sqrt(det(J J^T)) of a 6 x n Jacobian (0 at a singularity)."""
    n = jac.shape[1]
    a = np.empty((6, 6))
    for i in range(6):
        for j in range(6):
            s = 0.0
            for k in range(n):
                s += jac[i, k] * jac[j, k]
            a[i, j] = s
    det = 1.0
    for k in range(6):
        best, row = abs(a[k, k]), k
        for i in range(k + 1, 6):
            if abs(a[i, k]) > best:
                best, row = abs(a[i, k]), i
        if best < 1e-300:
            return 0.0
        if row != k:
            for j in range(6):
                a[k, j], a[row, j] = a[row, j], a[k, j]
            det = -det
        det *= a[k, k]
        for i in range(k + 1, 6):
            f = a[i, k] / a[k, k]
            for j in range(k, 6):
                a[i, j] -= f * a[k, j]
    return math.sqrt(det) if det > 0.0 else 0.0


@kernel
def manipulabilities(qs: Array, axes: Array, points: Array, rev: Array, tool: Array) -> Array:
    """:func:`manipulability` of tool0 at each configuration of ``qs`` (N, n)."""
    n = qs.shape[1]
    out = np.empty(qs.shape[0])
    err = np.empty(6)
    jac = np.empty((6, n))
    eye = np.eye(3)
    zero = np.zeros(3)
    for i in range(qs.shape[0]):
        ik_kernel.pose_error(qs[i], eye, zero, axes, points, rev, tool, err, jac)
        out[i] = manipulability(jac)
    return out


@kernel
def margin(q: Array, lo: Array, hi: Array) -> float:
    """The smallest distance (rad or m) of a joint to one of its limits (< 0 outside)."""
    worst = math.inf
    for i in range(q.shape[0]):
        worst = min(worst, q[i] - lo[i], hi[i] - q[i])
    return worst


@kernel
def _keep(q: Array, m: int, q_out: Array, count: int, distinct: float) -> bool:
    """True when ``q`` differs from every solution already kept for target ``m``."""
    for j in range(count):
        same = True
        for i in range(q.shape[0]):
            if abs(q[i] - q_out[m, j, i]) >= distinct:
                same = False
                break
        if same:
            return False
    return True


@kernel
def _store(q: Array, m: int, kept: int, rots: Array, poss: Array, lo: Array, hi: Array,
           rev: Array, wide: Array, mid: Array, axes: Array, points: Array, tool: Array,
           distinct: float, err: Array, jac: Array, q_out: Array, manip_out: Array,
           margin_out: Array) -> bool:
    """Wind a converged solution of target ``m`` nearest the middle of the limits and keep it
    as row ``kept`` (with its manipulability and margin) when it is inside the limits and new;
    True when kept."""
    ik_kernel.wind(q, mid, lo, hi, rev, wide)
    room = margin(q, lo, hi)
    if room < 0.0 or not _keep(q, m, q_out, kept, distinct):
        return False
    ik_kernel.pose_error(q, rots[m], poss[m], axes, points, rev, tool, err, jac)
    for i in range(q.shape[0]):
        q_out[m, kept, i] = q[i]
    manip_out[m, kept] = manipulability(jac)
    margin_out[m, kept] = room
    return True


@kernel
def analytic_solutions(rots: Array, poss: Array, c: Array, lo: Array, hi: Array, rev: Array,
                       wide: Array, mid: Array, axes: Array, points: Array, tool: Array,
                       tol_p: float, tol_r: float, steps: int, max_step: float, slack: float,
                       distinct: float, q_out: Array, count_out: IndexArray, manip_out: Array,
                       margin_out: Array) -> None:
    """Every solution of each target (rots (M, 3, 3), poss (M, 3)) of an ortho-parallel arm
    (constants ``c`` from :func:`usar_arm.planning.ik_kernel.pack`) into ``q_out`` (M, 8, 6),
    with their count (M,), manipulability and margin (M, 8)."""
    cand = np.empty((8, 6))
    q = np.empty(6)
    err = np.empty(6)
    jac = np.empty((6, 6))
    for m in range(rots.shape[0]):
        n = ik_kernel.branches(rots[m], poss[m], c, cand)
        kept = 0
        for b in range(n):
            for i in range(6):
                q[i] = cand[b, i]
            ik_kernel.wind(q, mid, lo, hi, rev, wide)
            if -margin(q, lo, hi) > slack:
                continue
            ok, _, _ = ik_kernel.polish(q, rots[m], poss[m], axes, points, rev, tool, tol_p,
                                        tol_r, steps, max_step)
            if ok and _store(q, m, kept, rots, poss, lo, hi, rev, wide, mid, axes, points,
                             tool, distinct, err, jac, q_out, manip_out, margin_out):
                kept += 1
        count_out[m] = kept


@kernel
def numeric_solutions(rots: Array, poss: Array, seeds: Array, lo: Array, hi: Array,
                      rev: Array, wide: Array, mid: Array, axes: Array, points: Array,
                      tool: Array, tol_p: float, tol_r: float, iterations: int, damping: float,
                      floor: float, max_step: float, distinct: float, q_out: Array,
                      count_out: IndexArray, manip_out: Array, margin_out: Array) -> None:
    """Solutions of each target for any serial chain: Levenberg-Marquardt from every row of
    ``seeds`` (S, n), up to ``q_out.shape[1]`` distinct ones inside the limits."""
    n = seeds.shape[1]
    q = np.empty(n)
    err = np.empty(6)
    jac = np.empty((6, n))
    cap = q_out.shape[1]
    for m in range(rots.shape[0]):
        kept = 0
        for s in range(seeds.shape[0]):
            if kept == cap:
                break
            for i in range(n):
                q[i] = seeds[s, i]
            ok, _, _ = lm_kernel.levenberg_marquardt(q, rots[m], poss[m], axes, points, rev,
                                                     tool, tol_p, tol_r, iterations, damping,
                                                     floor, max_step)
            if not ok:
                continue
            if _store(q, m, kept, rots, poss, lo, hi, rev, wide, mid, axes, points, tool,
                      distinct, err, jac, q_out, manip_out, margin_out):
                kept += 1
        count_out[m] = kept


def _warm_up_arrays() -> tuple[tuple, tuple]:
    """Arguments of the types :class:`usar_arm.workspace.solver.AllSolutions` passes to each
    kernel (float64 arrays, floats, ints: only the types matter to what is compiled)."""
    z3, z6, rot = np.zeros((1, 3)), np.zeros(6), np.eye(3)[None]
    outs = (np.zeros((1, MAX_SOLUTIONS, 6)), np.zeros(1, np.int64),
            np.zeros((1, MAX_SOLUTIONS)), np.zeros((1, MAX_SOLUTIONS)))
    analytic = (rot, z3, np.zeros(ik_kernel.C_SIZE), z6 - 1, z6 + 1, z6 + 1, z6, z6,
                np.zeros((6, 3)), np.zeros((6, 3)), np.eye(4), 1e-5, 1e-5, 8, 0.3, 0.05, 1e-3,
                *outs)
    numeric = (rot, z3, np.zeros((1, 6)), z6 - 1, z6 + 1, z6 + 1, z6, z6, np.zeros((6, 3)),
               np.zeros((6, 3)), np.eye(4), 1e-5, 1e-5, 1, 0.01, 1e-4, 0.5, 1e-3, *outs)
    return analytic, numeric


def warm_up() -> None:
    """Compile the kernels for the argument types :mod:`.solver` passes (numba caches the
    machine code on disk; ``make`` runs this once after installing)."""
    analytic, numeric = _warm_up_arrays()
    analytic_solutions(*analytic)
    numeric_solutions(*numeric)
    z = np.zeros((1, 6))
    manipulabilities(z, np.zeros((6, 3)), np.zeros((6, 3)), np.ones(6), np.eye(4))
    from usar_arm.workspace import edge_kernel

    edge_kernel.warm_up()
