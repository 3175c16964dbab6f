"""The compiled fast path of the analytic IK: one call per query, no Python objects.

For an ortho-parallel arm (:mod:`.opw`) and a tool target, :func:`nearest` computes every closed
form branch (up to 4 arm x 2 wrist), winds each into the limits nearest the seed, orders them by
distance to the seed and polishes them in that order by Newton steps on the product of
exponentials of the same URDF (:mod:`.poe`), returning the first that reaches the tolerance
inside the limits: the branch :meth:`IKSolver._solve_analytic <.ik.IKSolver>` would choose.

Whatever needs judgement it hands back (status :data:`.ik_kernel.FALLBACK`) to the Python
path: a wrist near its singularity (q5 ~ 0, where the Python path tries several splits of
q4 + q6), a solution a hair outside a limit (which the Python path retries on the limit), or no
branch at all (which the Python path turns into a numeric search or a typed error).

The arm's constants travel in one float vector built by :func:`pack` (indices ``C_*``).
"""

from __future__ import annotations

import math

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning import two_link
from usar_arm.planning.jit import inline_kernel, kernel
from usar_arm.planning.opw import OrthoParallelArm
from usar_arm.planning.two_link import elbow

SOLVED, FALLBACK = 0, 1
"""Statuses of :func:`nearest`."""

TWO_PI = 2.0 * math.pi

# Offsets into the constant vector (3-vectors unless noted).
(C_W, C_P, C_U, C_TW, C_W1XU, C_P1_2D, C_M6, C_MV, C_W4XW5, C_V) = (
    0, 18, 36, 39, 42, 45, 47, 50, 53, 56)
"""w (6x3) and p (6x3) of the joints, u, tool-to-wrist, w1 x u, p1 in the elbow's plane (2),
the wrist's m6, mv, w4 x w5 and v."""
(C_LATERAL, C_SLACK, C_C45, C_W5W6, C_CR2) = (59, 60, 61, 62, 63)
"""Scalars of the closed form (see :class:`.opw.OrthoParallelArm`)."""
C_ELBOW = 64
"""Where the elbow's block starts (:meth:`.two_link.TwoLink.packed`)."""
C_SIZE = C_ELBOW + two_link.SIZE


def pack(arm: OrthoParallelArm) -> Array:
    """The constant vector of ``arm`` for :func:`nearest`."""
    c = np.zeros(C_SIZE)
    c[C_W:C_W + 18] = np.ravel(arm.w)
    c[C_P:C_P + 18] = np.ravel(arm.p)
    for offset, value in ((C_U, arm.u), (C_TW, arm._tw), (C_W1XU, arm._w1xu),
                          (C_P1_2D, arm._p1_2d), (C_M6, arm._m6), (C_MV, arm._mv),
                          (C_W4XW5, arm._w4xw5), (C_V, arm._v)):
        c[offset:offset + len(value)] = value
    c[C_LATERAL], c[C_SLACK] = arm.lateral, arm.slack
    c[C_C45], c[C_W5W6], c[C_CR2] = arm._c45, arm._w5w6, arm._cr2
    c[C_ELBOW:] = arm.two_link.packed()
    return c


@kernel
def rodrigues(c: Array, w: int, angle: float, v: Array, out: Array) -> None:
    """Rodrigues: ``v`` rotated by ``angle`` about the unit axis at ``c[w:w+3]`` into ``out``."""
    w0, w1, w2 = c[w], c[w + 1], c[w + 2]
    co, si = math.cos(angle), math.sin(angle)
    k = (w0 * v[0] + w1 * v[1] + w2 * v[2]) * (1.0 - co)
    x0, x1, x2 = w1 * v[2] - w2 * v[1], w2 * v[0] - w0 * v[2], w0 * v[1] - w1 * v[0]
    out[0] = v[0] * co + x0 * si + w0 * k
    out[1] = v[1] * co + x1 * si + w1 * k
    out[2] = v[2] * co + x2 * si + w2 * k


@kernel
def subproblem1(c: Array, w: int, p: Array, q: Array) -> float:
    """Paden-Kahan subproblem 1: the angle about the unit axis ``c[w:w+3]`` taking p to q."""
    w0, w1, w2 = c[w], c[w + 1], c[w + 2]
    pw = w0 * p[0] + w1 * p[1] + w2 * p[2]
    qw = w0 * q[0] + w1 * q[1] + w2 * q[2]
    a0, a1, a2 = p[0] - w0 * pw, p[1] - w1 * pw, p[2] - w2 * pw
    b0, b1, b2 = q[0] - w0 * qw, q[1] - w1 * qw, q[2] - w2 * qw
    cross = w0 * (a1 * b2 - a2 * b1) + w1 * (a2 * b0 - a0 * b2) + w2 * (a0 * b1 - a1 * b0)
    return math.atan2(cross, a0 * b0 + a1 * b1 + a2 * b2)


@kernel
def wrap(angle: float) -> float:
    return (angle + math.pi) % TWO_PI - math.pi


@kernel
def branches(rot: Array, pos: Array, c: Array, out: Array) -> int:
    """Every closed-form branch (rows of ``out`` (8, 6), rad in (-pi, pi]) for a tool pose;
    returns how many. The maths of :meth:`.opw.OrthoParallelArm.arm_branches` and
    ``wrist_branches``, in the same order."""
    tw = c[C_TW:C_TW + 3]
    d = np.empty(3)
    for i in range(3):
        d[i] = rot[i, 0] * tw[0] + rot[i, 1] * tw[1] + rot[i, 2] * tw[2] + pos[i] - c[C_P + i]
    h = c[C_W] * d[0] + c[C_W + 1] * d[1] + c[C_W + 2] * d[2]
    dh0, dh1, dh2 = d[0] - h * c[C_W], d[1] - h * c[C_W + 1], d[2] - h * c[C_W + 2]
    a = c[C_U] * dh0 + c[C_U + 1] * dh1 + c[C_U + 2] * dh2
    b = c[C_W1XU] * dh0 + c[C_W1XU + 1] * dh1 + c[C_W1XU + 2] * dh2
    rad = math.hypot(a, b)
    lateral = c[C_LATERAL]
    if rad < 1e-12 or abs(lateral) > rad + c[C_SLACK]:
        return 0
    base = math.atan2(b, a)
    spread = math.acos(max(-1.0, min(1.0, lateral / rad)))
    t6 = np.empty(3)
    tv = np.empty(3)
    for i in range(3):
        t6[i] = rot[i, 0] * c[C_M6] + rot[i, 1] * c[C_M6 + 1] + rot[i, 2] * c[C_M6 + 2]
        tv[i] = rot[i, 0] * c[C_MV] + rot[i, 1] * c[C_MV + 1] + rot[i, 2] * c[C_MV + 2]
    back = np.empty(3)
    tmp = np.empty(3)
    target = np.empty(3)
    rv = np.empty(3)
    z = np.empty(3)
    mv6 = np.empty(3)
    elbows = np.empty((2, 2))
    count = 0
    c45, w5w6 = c[C_C45], c[C_W5W6]
    den = c45 * c45 - 1.0
    ea, eb = C_ELBOW + two_link.EA, C_ELBOW + two_link.EB
    for sign1 in (1.0, -1.0):
        q1 = base + sign1 * spread
        rodrigues(c, C_W, -q1, d, back)
        x = c[ea] * back[0] + c[ea + 1] * back[1] + c[ea + 2] * back[2] + c[C_P1_2D]
        y = c[eb] * back[0] + c[eb + 1] * back[1] + c[eb + 2] * back[2] + c[C_P1_2D + 1]
        for r in range(elbow(c, C_ELBOW, x, y, elbows)):
            q1w, q2w, q3w = wrap(q1), wrap(elbows[r, 0]), wrap(elbows[r, 1])
            theta = q2w + c[C_ELBOW + two_link.S3] * q3w
            rodrigues(c, C_W, -q1w, t6, tmp)
            rodrigues(c, C_U, -theta, tmp, target)
            rodrigues(c, C_W, -q1w, tv, tmp)
            rodrigues(c, C_U, -theta, tmp, rv)
            w4, w5 = C_W + 9, C_W + 12
            t4 = c[w4] * target[0] + c[w4 + 1] * target[1] + c[w4 + 2] * target[2]
            alpha = (c45 * w5w6 - t4) / den
            beta = (c45 * t4 - w5w6) / den
            g2 = (1.0 - alpha * alpha - beta * beta - 2 * alpha * beta * c45) / c[C_CR2]
            n_g = 1 if g2 <= 1e-14 else 2
            for k in range(n_g):
                g = 0.0 if n_g == 1 else (math.sqrt(g2) if k == 0 else -math.sqrt(g2))
                for i in range(3):
                    z[i] = alpha * c[w4 + i] + beta * c[w5 + i] + g * c[C_W4XW5 + i]
                q5 = subproblem1(c, w5, c[C_W + 15:C_W + 18], z)
                q4 = subproblem1(c, w4, z, target)
                rodrigues(c, w4, -q4, rv, tmp)
                rodrigues(c, w5, -q5, tmp, mv6)
                q6 = subproblem1(c, C_W + 15, c[C_V:C_V + 3], mv6)
                out[count, 0], out[count, 1], out[count, 2] = q1w, q2w, q3w
                out[count, 3], out[count, 4], out[count, 5] = wrap(q4), wrap(q5), wrap(q6)
                count += 1
    return count


@kernel
def wind(q: Array, ref: Array, lo: Array, hi: Array, rev: Array, wide: Array) -> None:
    """Each revolute angle of ``q`` moved by whole turns into its limits (in place), to the
    winding nearest ``ref`` where the range is wider than 2 pi (as ``IKSolver._wind``)."""
    for i in range(q.shape[0]):
        if rev[i] < 0.5:
            continue
        v = q[i]
        if wide[i] > 0.5:
            v += TWO_PI * round((ref[i] - v) / TWO_PI)
            while v > hi[i]:
                v -= TWO_PI
            while v < lo[i]:
                v += TWO_PI
        elif v < lo[i] and v + TWO_PI - hi[i] < lo[i] - v:
            v += TWO_PI  # the other winding is inside, or less outside
        elif v > hi[i] and lo[i] - (v - TWO_PI) < v - hi[i]:
            v -= TWO_PI
        q[i] = v


@kernel
def _excess(q: Array, lo: Array, hi: Array) -> float:
    worst = -math.inf
    for i in range(q.shape[0]):
        worst = max(worst, lo[i] - q[i], q[i] - hi[i])
    return worst


@kernel
def pose_and_jacobian(q: Array, axes: Array, points: Array, rev: Array, tool: Array,
                       rot: Array, pos: Array, jac: Array) -> None:
    """The tool's pose (rot, pos) and its Jacobian (6, n; linear rows first, world axes) by
    the product of exponentials (as :class:`.poe.PoeModel`)."""
    n = q.shape[0]
    r = np.eye(3)
    t = np.zeros(3)
    cur_axes = np.empty((n, 3))
    cur_points = np.empty((n, 3))
    e = np.empty((3, 3))
    for i in range(n):
        w = axes[i]
        p = points[i]
        for a in range(3):
            cur_axes[i, a] = r[a, 0] * w[0] + r[a, 1] * w[1] + r[a, 2] * w[2]
            cur_points[i, a] = r[a, 0] * p[0] + r[a, 1] * p[1] + r[a, 2] * p[2] + t[a]
        if rev[i] > 0.5:
            co, si = math.cos(q[i]), math.sin(q[i])
            v = 1.0 - co
            e[0, 0], e[0, 1], e[0, 2] = co + w[0] * w[0] * v, w[0] * w[1] * v - w[2] * si, \
                w[0] * w[2] * v + w[1] * si
            e[1, 0], e[1, 1], e[1, 2] = w[1] * w[0] * v + w[2] * si, co + w[1] * w[1] * v, \
                w[1] * w[2] * v - w[0] * si
            e[2, 0], e[2, 1], e[2, 2] = w[2] * w[0] * v - w[1] * si, w[2] * w[1] * v + w[0] * si, \
                co + w[2] * w[2] * v
            d0 = p[0] - (e[0, 0] * p[0] + e[0, 1] * p[1] + e[0, 2] * p[2])
            d1 = p[1] - (e[1, 0] * p[0] + e[1, 1] * p[1] + e[1, 2] * p[2])
            d2 = p[2] - (e[2, 0] * p[0] + e[2, 1] * p[1] + e[2, 2] * p[2])
            for a in range(3):
                t[a] += r[a, 0] * d0 + r[a, 1] * d1 + r[a, 2] * d2
            for a in range(3):
                r0, r1, r2 = r[a, 0], r[a, 1], r[a, 2]
                for b in range(3):
                    r[a, b] = r0 * e[0, b] + r1 * e[1, b] + r2 * e[2, b]
        else:
            for a in range(3):
                t[a] += cur_axes[i, a] * q[i]
    for a in range(3):
        for b in range(3):
            rot[a, b] = r[a, 0] * tool[0, b] + r[a, 1] * tool[1, b] + r[a, 2] * tool[2, b]
        pos[a] = r[a, 0] * tool[0, 3] + r[a, 1] * tool[1, 3] + r[a, 2] * tool[2, 3] + t[a]
    for i in range(n):
        w = cur_axes[i]
        if rev[i] > 0.5:
            l0 = pos[0] - cur_points[i, 0]
            l1 = pos[1] - cur_points[i, 1]
            l2 = pos[2] - cur_points[i, 2]
            jac[0, i] = w[1] * l2 - w[2] * l1
            jac[1, i] = w[2] * l0 - w[0] * l2
            jac[2, i] = w[0] * l1 - w[1] * l0
            jac[3, i], jac[4, i], jac[5, i] = w[0], w[1], w[2]
        else:
            jac[0, i], jac[1, i], jac[2, i] = w[0], w[1], w[2]
            jac[3, i] = jac[4, i] = jac[5, i] = 0.0


@kernel
def pose_error(q: Array, target_rot: Array, target_pos: Array, axes: Array, points: Array,
               rev: Array, tool: Array, err: Array, jac: Array) -> tuple[float, float]:
    """``err`` (6,) = (target - position, rotation vector of target R^T) and the Jacobian into
    ``jac``; returns the position (m) and rotation (rad) errors."""
    rot = np.empty((3, 3))
    pos = np.empty(3)
    pose_and_jacobian(q, axes, points, rev, tool, rot, pos, jac)
    for a in range(3):
        err[a] = target_pos[a] - pos[a]
    m = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            m[a, b] = (target_rot[a, 0] * rot[b, 0] + target_rot[a, 1] * rot[b, 1]
                       + target_rot[a, 2] * rot[b, 2])
    tr = min(1.0, max(-1.0, (m[0, 0] + m[1, 1] + m[2, 2] - 1.0) / 2.0))
    angle = math.acos(tr)
    s = math.sin(angle)
    scale = 0.5 if angle < 1e-6 else angle / max(2.0 * s, 1e-300)
    err[3] = (m[2, 1] - m[1, 2]) * scale
    err[4] = (m[0, 2] - m[2, 0]) * scale
    err[5] = (m[1, 0] - m[0, 1]) * scale
    pe = math.sqrt(err[0] ** 2 + err[1] ** 2 + err[2] ** 2)
    return pe, angle


@kernel
def solve6(a: Array, b: Array, x: Array) -> bool:
    """x = a^-1 b for a small square system (n = len(b)) by Gaussian elimination with partial
    pivoting (a and b are scratch: overwritten); False when a pivot vanishes (singular)."""
    n = b.shape[0]
    for k in range(n):
        best, row = abs(a[k, k]), k
        for i in range(k + 1, n):
            if abs(a[i, k]) > best:
                best, row = abs(a[i, k]), i
        if best < 1e-12:
            return False
        if row != k:
            for j in range(n):
                a[k, j], a[row, j] = a[row, j], a[k, j]
            b[k], b[row] = b[row], b[k]
        for i in range(k + 1, n):
            f = a[i, k] / a[k, k]
            for j in range(k, n):
                a[i, j] -= f * a[k, j]
            b[i] -= f * b[k]
    for k in range(n - 1, -1, -1):
        s = b[k]
        for j in range(k + 1, n):
            s -= a[k, j] * x[j]
        x[k] = s / a[k, k]
    return True


@inline_kernel
def take_step(q: Array, step: Array, max_step: float) -> None:
    """``q += step`` (in place), the step scaled down so that no joint moves more than
    ``max_step`` (rad or m)."""
    biggest = 0.0
    for k in range(q.shape[0]):
        biggest = max(biggest, abs(step[k]))
    scale = max_step / biggest if biggest > max_step else 1.0
    for k in range(q.shape[0]):
        q[k] += step[k] * scale


@kernel
def polish(q: Array, target_rot: Array, target_pos: Array, axes: Array, points: Array,
           rev: Array, tool: Array, tol_p: float, tol_r: float, steps: int, max_step: float
           ) -> tuple[bool, float, float]:
    """Newton steps on the exact chain from ``q`` (in place) until the tool is within the
    tolerances (m, rad); damped least squares where the Jacobian is singular; no step moves a
    joint more than ``max_step``. Returns (converged, position error, rotation error)."""
    n = q.shape[0]
    err = np.empty(6)
    jac = np.empty((6, n))
    step = np.empty(n)
    a = np.empty((6, 6))
    rhs = np.empty(6)
    y = np.empty(6)
    for _ in range(steps):
        pe, re = pose_error(q, target_rot, target_pos, axes, points, rev, tool, err, jac)
        if pe < tol_p and re < tol_r:
            return True, pe, re
        for i in range(6):
            rhs[i] = err[i]
            for j in range(6):
                a[i, j] = jac[i, j]
        if not solve6(a, rhs, step):
            for i in range(6):  # J^T (J J^T + 1e-6 I)^-1 e
                rhs[i] = err[i]
                for j in range(6):
                    s = 0.0
                    for k in range(n):
                        s += jac[i, k] * jac[j, k]
                    a[i, j] = s + (1e-6 if i == j else 0.0)
            solve6(a, rhs, y)
            for k in range(n):
                s = 0.0
                for i in range(6):
                    s += jac[i, k] * y[i]
                step[k] = s
        take_step(q, step, max_step)
    pe, re = pose_error(q, target_rot, target_pos, axes, points, rev, tool, err, jac)
    return (pe < tol_p and re < tol_r), pe, re


@kernel
def pick_nearest(cand: Array, count: int, target_rot: Array, target_pos: Array, ref: Array,
                 lo: Array, hi: Array, rev: Array, wide: Array, axes: Array, points: Array,
                 tool: Array, tol_p: float, tol_r: float, steps: int, max_step: float,
                 analytic_slack: float, out: Array) -> tuple[int, float, float]:
    """Of the first ``count`` closed-form branches in ``cand`` (8, 6), the one nearest ``ref``
    into ``out`` (6,): each is wound into the limits nearest ``ref`` (in place), they are taken
    in order of distance to ``ref`` (stable), and the first within ``analytic_slack`` rad of
    the limits that Newton steps polish to the tolerances is returned, wound again, as
    (SOLVED, position error m, rotation error rad). (FALLBACK, ...) when that one ends a hair
    outside a limit or no branch qualifies: the Python path decides. Shared by every closed
    form (this module's and :mod:`.ur_kernel`'s)."""
    dist = np.empty(count)
    for k in range(count):
        wind(cand[k], ref, lo, hi, rev, wide)
        s = 0.0
        for i in range(6):
            s += (cand[k, i] - ref[i]) ** 2
        dist[k] = s
    order = np.argsort(dist, kind="mergesort")
    q = np.empty(6)
    for r in range(count):
        k = order[r]
        if _excess(cand[k], lo, hi) > analytic_slack:
            continue
        for i in range(6):
            q[i] = cand[k, i]
        ok, pe, re = polish(q, target_rot, target_pos, axes, points, rev, tool, tol_p, tol_r,
                            steps, max_step)
        if not ok:
            continue
        wind(q, ref, lo, hi, rev, wide)
        if _excess(q, lo, hi) > 1e-9:
            return FALLBACK, 0.0, 0.0  # outside a limit: the Python path clamps or goes on
        for i in range(6):
            out[i] = q[i]
        return SOLVED, pe, re
    return FALLBACK, 0.0, 0.0


@kernel
def nearest(target_rot: Array, target_pos: Array, ref: Array, c: Array, lo: Array, hi: Array,
            rev: Array, wide: Array, axes: Array, points: Array, tool: Array, tol_p: float,
            tol_r: float, steps: int, max_step: float, analytic_slack: float,
            wrist_singular: float, out: Array) -> tuple[int, float, float]:
    """The solution nearest ``ref`` into ``out`` (6,): (SOLVED, position error m, rotation
    error rad), or (FALLBACK, ...) when the Python path must decide (see the module): any
    branch with its wrist near the singularity (|sin q5| below ``wrist_singular`` with q5
    near 0 rather than pi) first, then as :func:`pick_nearest`."""
    cand = np.empty((8, 6))
    count = branches(target_rot, target_pos, c, cand)
    for k in range(count):
        q5 = cand[k, 4]
        if abs(math.sin(q5)) < wrist_singular and abs(math.cos(q5)) > 0.5:
            return FALLBACK, 0.0, 0.0
    return pick_nearest(cand, count, target_rot, target_pos, ref, lo, hi, rev, wide, axes,
                        points, tool, tol_p, tol_r, steps, max_step, analytic_slack, out)


def warm_up() -> None:
    """Compile :func:`nearest` for the argument types :class:`.ik.IKSolver` passes (numba
    caches the machine code on disk; ``make`` runs this once after installing)."""
    z3, z6 = np.zeros(3), np.zeros(6)
    nearest(np.eye(3), z3, z6, np.zeros(C_SIZE), z6 - 1.0, z6 + 1.0, z6 + 1.0, z6,
            np.zeros((6, 3)), np.zeros((6, 3)), np.eye(4), 1e-5, 1e-5, 8, 0.3, 0.05, 0.05,
            np.empty(6))
