"""The compiled closed form of arms with three parallel axes (:mod:`.ur`): one call per query.

:func:`branches` is :meth:`.ur.ThreeParallelArm.solve` compiled (same maths, same order);
:func:`nearest` winds each branch into the limits nearest the seed, orders them by distance to
the seed and polishes them in that order by Newton steps on the exact chain
(:func:`.ik_kernel.polish`), returning the first inside the tolerances and the limits: the
branch the Python path (:meth:`.ik_branches.AnalyticBranches.ordered`) would choose. At the
wrist singularity q6 takes the seed's value, so unlike the OPW kernel it needs no fallback
there; a solution a hair outside a limit, or no branch at all, goes back to the Python path
(status :data:`.ik_kernel.FALLBACK`).

The arm's constants travel in one float vector built by :func:`pack` (indices ``C_*``).
Radians and metres.
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning import two_link
from usar_arm.planning.ik_kernel import pick_nearest, rodrigues, subproblem1, wrap
from usar_arm.planning.jit import kernel
from usar_arm.planning.two_link import elbow
from usar_arm.planning.ur import SINGULAR_WRIST, ThreeParallelArm

# Offsets into the constant vector (3-vectors unless noted).
(C_W, C_P, C_U, C_W1XU, C_T56, C_M6, C_RM, C_X, C_R4) = (0, 18, 36, 39, 42, 45, 48, 57, 60)
"""w (6x3) and p (6x3) of the joints, u, w1 x u, p56 and w6 in the tool frame, the tool's
rotation at zero (3x3, row-major), x and p56 - p4."""
(C_LATERAL, C_SLACK, C_D5, C_MAG5, C_PHASE5, C_M2M1, C_S4) = range(63, 70)
"""Scalars of the closed form (see :class:`.ur.ThreeParallelArm`)."""
C_ELBOW = 70
"""Where the elbow's block starts (:meth:`.two_link.TwoLink.packed`)."""
C_SIZE = C_ELBOW + two_link.SIZE
C_W5, C_W6 = C_W + 12, C_W + 15


def pack(arm: ThreeParallelArm) -> Array:
    """The constant vector of ``arm`` for :func:`branches` and :func:`nearest`."""
    c = np.zeros(C_SIZE)
    c[C_W:C_W + 18] = np.ravel(arm.w)
    c[C_P:C_P + 18] = np.ravel(arm.p)
    c[C_RM:C_RM + 9] = np.ravel(arm.rm)
    for offset, value in ((C_U, arm.u), (C_W1XU, arm.w1xu), (C_T56, arm.t56), (C_M6, arm.m6),
                          (C_X, arm.x), (C_R4, arm.r4)):
        c[offset:offset + len(value)] = value
    c[C_LATERAL:C_ELBOW] = (arm.lateral, arm.slack, arm.d5, arm.mag5, arm.phase5, arm.m2m1,
                            arm.s4)
    c[C_ELBOW:] = arm.two_link.packed()
    return c


@kernel
def _dot(c: Array, at: int, v: Array) -> float:
    """``c[at:at+3] . v``."""
    return c[at] * v[0] + c[at + 1] * v[1] + c[at + 2] * v[2]


@kernel
def _mul(m: Array, v: Array, transpose: bool, out: Array) -> None:
    """``out = m v`` (or m^T v) for a 3x3 array ``m``."""
    for i in range(3):
        if transpose:
            out[i] = m[0, i] * v[0] + m[1, i] * v[1] + m[2, i] * v[2]
        else:
            out[i] = m[i, 0] * v[0] + m[i, 1] * v[1] + m[i, 2] * v[2]


@kernel
def branches_free(rot: Array, pos: Array, c: Array, q6_free: float, out: Array) -> int:
    """Every closed-form branch (rows of ``out`` (8, 6), rad in (-pi, pi]) for a tool pose
    (rotation, position m), q6 = ``q6_free`` (rad) where the wrist is singular; returns how
    many. The maths of :meth:`.ur.ThreeParallelArm.solve`, in the same order."""
    rm = c[C_RM:C_RM + 9].reshape(3, 3)
    d, w6t, tmp, tmp2 = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    v, back, g, y, turned = np.empty(3), np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    _mul(rot, c[C_T56:C_T56 + 3], False, d)
    for i in range(3):
        d[i] = d[i] + pos[i] - c[C_P + i]
    h = _dot(c, C_W, d)
    for i in range(3):
        tmp[i] = d[i] - h * c[C_W + i]
    a, b = _dot(c, C_U, tmp), _dot(c, C_W1XU, tmp)
    rad = math.sqrt(a * a + b * b)
    lateral = c[C_LATERAL]
    if rad < 1e-12 or abs(lateral) > rad + c[C_SLACK]:
        return 0
    base = math.atan2(b, a)
    spread = math.acos(max(-1.0, min(1.0, lateral / rad)))
    _mul(rot, c[C_M6:C_M6 + 3], False, w6t)
    mag5 = c[C_MAG5]
    elbows = np.empty((2, 2))
    count = 0
    for sign1 in (1.0, -1.0):
        q1 = base + sign1 * spread
        rodrigues(c, C_W, -q1, w6t, tmp)
        k = _dot(c, C_U, tmp)
        s2 = 0.0
        for i in range(3):
            s2 += (tmp[i] - k * c[C_U + i]) ** 2
        sin2 = s2 + c[C_M2M1] + 2.0 * k * c[C_D5] - c[C_D5] * c[C_D5]
        if mag5 < 1e-12 or sin2 < -2e-9:
            continue
        spread5 = math.atan2(math.sqrt(max(0.0, sin2)), k - c[C_D5])
        rodrigues(c, C_W, q1, c[C_U:C_U + 3], tmp)
        _mul(rot, tmp, True, tmp2)
        _mul(rm, tmp2, False, v)  # R_w^T R1 u
        rodrigues(c, C_W, -q1, d, back)
        for sign5 in (1.0, -1.0):
            q5 = c[C_PHASE5] + sign5 * spread5
            rodrigues(c, C_W5, -q5, c[C_U:C_U + 3], g)
            gw = _dot(c, C_W6, g)
            gn = 0.0
            for i in range(3):
                gn += (g[i] - gw * c[C_W6 + i]) ** 2
            q6 = q6_free if gn < SINGULAR_WRIST ** 2 else subproblem1(c, C_W6, v, g)
            rodrigues(c, C_W5, -q5, c[C_X:C_X + 3], tmp)
            rodrigues(c, C_W6, -q6, tmp, tmp2)
            _mul(rm, tmp2, True, tmp)
            _mul(rot, tmp, False, tmp2)
            rodrigues(c, C_W, -q1, tmp2, y)
            theta = subproblem1(c, C_U, c[C_X:C_X + 3], y)
            rodrigues(c, C_U, theta, c[C_R4:C_R4 + 3], turned)
            for i in range(3):
                tmp[i] = back[i] - turned[i] + c[C_P + i]
            px, py = _dot(c, C_ELBOW + two_link.EA, tmp), _dot(c, C_ELBOW + two_link.EB, tmp)
            for r in range(elbow(c, C_ELBOW, px, py, elbows)):
                q2, q3 = elbows[r, 0], elbows[r, 1]
                q4 = c[C_S4] * (theta - q2 - c[C_ELBOW + two_link.S3] * q3)
                out[count, 0], out[count, 1], out[count, 2] = wrap(q1), wrap(q2), wrap(q3)
                out[count, 3], out[count, 4], out[count, 5] = wrap(q4), wrap(q5), wrap(q6)
                count += 1
    return count


@kernel
def branches(rot: Array, pos: Array, c: Array, out: Array) -> int:
    """:func:`branches_free` with q6 = 0 at the wrist singularity."""
    return branches_free(rot, pos, c, 0.0, out)


@kernel
def nearest(target_rot: Array, target_pos: Array, ref: Array, c: Array, lo: Array, hi: Array,
            rev: Array, wide: Array, axes: Array, points: Array, tool: Array, tol_p: float,
            tol_r: float, steps: int, max_step: float, analytic_slack: float, out: Array
            ) -> tuple[int, float, float]:
    """The solution nearest ``ref`` into ``out`` (6,): (SOLVED, position error m, rotation
    error rad), or (FALLBACK, ...) when the Python path must decide (see the module); the
    branches with the seed's q6 at the wrist singularity, chosen by
    :func:`.ik_kernel.pick_nearest`."""
    cand = np.empty((8, 6))
    count = branches_free(target_rot, target_pos, c, ref[5], cand)
    return pick_nearest(cand, count, target_rot, target_pos, ref, lo, hi, rev, wide, axes,
                        points, tool, tol_p, tol_r, steps, max_step, analytic_slack, out)


def warm_up() -> None:
    """Compile :func:`nearest` and :func:`branches_free` for the argument types
    :class:`.ik_branches.AnalyticBranches` passes (numba caches the machine code on disk)."""
    z3, z6 = np.zeros(3), np.zeros(6)
    nearest(np.eye(3), z3, z6, np.zeros(C_SIZE), z6 - 1.0, z6 + 1.0, z6 + 1.0, z6,
            np.zeros((6, 3)), np.zeros((6, 3)), np.eye(4), 1e-5, 1e-5, 8, 0.3, 0.05,
            np.empty(6))
    branches_free(np.eye(3), z3, np.zeros(C_SIZE), 0.0, np.empty((8, 6)))
