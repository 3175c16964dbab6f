"""The model's tool bias from truncated GroundTruth readings: a set-membership estimate.

UDK prints a GroundTruth pose with every number truncated toward zero to a step (1 mm,
0.001 rad). A reading therefore says only that the truth lies in a box: location per axis, and
roll, pitch, yaw each in a step-wide interval. If the model's sensor pose M_k at the reading's
configuration is off from the truth by a constant bias (p, w) -- truth location = M_k location
+ p, truth rotation = exp(w) M_k rotation, world frame -- every reading bounds (p, w), and a few
readings whose numbers sit at different places inside their steps bound it tightly.

* Position: per axis, the intersection of intervals; the estimate is its middle.
* Rotation: each reading's three intervals bound three smooth functions of w. Linearised at the
  current estimate (and again at the new one: twice suffices, the bias is a few mrad) they are
  a polytope; the estimate is its analytic centre (the point farthest, in the log-barrier
  sense, from every face), which for a long thin set sits in its middle, not at a vertex.

When the boxes do not intersect (the bias drifted, or a reading was stale) the estimate is the
point that breaks them least (the Chebyshev centre with a negative radius), and
:attr:`BiasEstimate.consistent` is False.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import Array, exp_so3, log_so3, matrix_to_rpy, rpy_to_matrix


@dataclass(frozen=True)
class Reading:
    """One GroundTruth reading as printed (z-down world; location m, roll-pitch-yaw rad) with
    its steps (m, rad; 0 = full precision), the model's sensor pose (4x4) at the joints
    measured when it was taken, and how far that pose may be off because the joints were
    measured inexactly (m, rad): each box is widened by it."""

    location: tuple[float, float, float]
    orientation: tuple[float, float, float]
    step_m: float
    step_rad: float
    model: Array
    model_tol_m: float = 0.0
    model_tol_rad: float = 0.0


@dataclass(frozen=True)
class BiasEstimate:
    """The bias (position m, rotation vector rad; world frame) and its uncertainty: the
    half-width of the position set per axis (m) and the radius of the largest ball inside the
    rotation set (rad; negative when the readings disagree by that much)."""

    position: Array
    rotation: Array
    position_halfwidth: Array
    rotation_radius: float
    consistent: bool


def interval(printed: float, step: float) -> tuple[float, float]:
    """Where a number printed truncated toward zero to ``step`` lies (``-0.000`` and ``0.000``
    both stand for (-step, step))."""
    if step <= 0:
        return printed, printed
    if printed > 0:
        return printed, printed + step
    if printed < 0:
        return printed - step, printed
    return -step, step


def wrap(a: Array) -> Array:
    """Angles wrapped into [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def rpy_rate(rpy: tuple[float, float, float]) -> Array:
    """d(roll, pitch, yaw) / dw (3x3) for a world-frame rotation exp(dw) R, R = Rz Ry Rx.

    The world angular velocity of R = Rz(yaw) Ry(pitch) Rx(roll) is
    yaw' e_z + pitch' Rz e_y + roll' Rz Ry e_x; this is that map's inverse (singular at
    gimbal lock, where roll and yaw are not separable).
    """
    _, pitch, yaw = rpy
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    rates = np.array([[cy * cp, -sy, 0.0],
                      [sy * cp, cy, 0.0],
                      [-sp, 0.0, 1.0]])  # columns: roll, pitch, yaw
    return np.linalg.inv(rates)


def position_bias(readings: list[Reading]) -> tuple[Array, Array, bool]:
    """The middle of the per-axis intersection of location intervals (m), its half-widths,
    and whether every axis's intervals intersect (if not: the mean of the midpoints)."""
    lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
    mids = []
    for r in readings:
        box = np.array([interval(v, r.step_m) for v in r.location])
        box += np.array([-r.model_tol_m, r.model_tol_m])
        lo = np.maximum(lo, box[:, 0] - r.model[:3, 3])
        hi = np.minimum(hi, box[:, 1] - r.model[:3, 3])
        mids.append(box.mean(axis=1) - r.model[:3, 3])
    ok = lo <= hi
    centre = np.where(ok, (lo + hi) / 2, np.mean(mids, axis=0))
    return centre, np.where(ok, (hi - lo) / 2, 0.0), bool(ok.all())


def _constraints(readings: list[Reading], w: Array) -> tuple[Array, Array]:
    """The rotation boxes linearised at ``w``: rows A, b with A dw <= b for dw = w' - w."""
    rows, bounds = [], []
    for r in readings:
        rot = exp_so3(w) @ r.model[:3, :3]
        rpy = matrix_to_rpy(rot)
        jac = rpy_rate(rpy)
        for j in range(3):
            lo, hi = interval(r.orientation[j], r.step_rad)
            centre = (lo + hi) / 2
            half = (hi - lo) / 2 + float(np.linalg.norm(jac[j])) * r.model_tol_rad
            g = float(wrap(np.array(rpy[j] - centre)))
            rows += [jac[j], -jac[j]]
            bounds += [half - g, half + g]
    return np.array(rows), np.array(bounds)


def _chebyshev(a: Array, b: Array, bound: float) -> tuple[Array, float]:
    """The centre and radius of the largest ball in {x : a x <= b, |x_i| <= bound}; the
    radius is negative (and the point the least violating) when the set is empty."""
    norms = np.linalg.norm(a, axis=1)
    c = np.array([0.0, 0.0, 0.0, -1.0])
    # Imported here: scipy.optimize costs ~0.5 s of start-up that offline planning never needs.
    from scipy.optimize import linprog

    res = linprog(c, A_ub=np.hstack([a, norms[:, None]]), b_ub=b,
                  bounds=[(-bound, bound)] * 3 + [(None, bound)], method="highs")
    if res.status != 0:
        return np.zeros(3), -np.inf
    return res.x[:3], float(res.x[3])


def _analytic_centre(a: Array, b: Array, x: Array, iterations: int = 100) -> Array:
    """The minimiser of -sum(log(b - a x)) from a strictly feasible ``x``: damped Newton
    steps x += dx / (1 + decrement), which stay feasible for this self-concordant barrier."""
    for _ in range(iterations):
        s = b - a @ x
        grad = a.T @ (1 / s)
        hess = (a / s[:, None] ** 2).T @ a
        dx = -np.linalg.lstsq(hess, grad, rcond=None)[0]
        decrement = math.sqrt(max(float(-grad @ dx), 0.0))
        if decrement < 1e-9:
            break
        x = x + dx / (1 + decrement)
    return x


def rotation_bias(readings: list[Reading], start: Array | None = None,
                  rounds: int = 3) -> tuple[Array, float]:
    """The rotation bias (world rotation vector, rad) at the centre of the set every
    reading's roll-pitch-yaw box allows, and the radius of that set's largest ball (rad).

    ``start`` (default: from the first reading's box middle) is where the boxes are first
    linearised. Readings must stay away from gimbal lock (|cos pitch| >> step): there roll
    and yaw separately are not smooth functions of the rotation.
    """
    if start is None:
        first = readings[0]
        mid = [sum(interval(v, first.step_rad)) / 2 for v in first.orientation]
        start = log_so3(rpy_to_matrix(mid) @ first.model[:3, :3].T)
    w = np.asarray(start, float)
    radius = -np.inf
    scale = max(r.step_rad for r in readings)
    for _ in range(rounds):
        a, b = _constraints(readings, w)
        dw, radius = _chebyshev(a, b, bound=50 * scale)
        if radius > 0:
            dw = _analytic_centre(a, b, dw)
        w = w + dw
    return w, radius


def estimate_bias(readings: list[Reading]) -> BiasEstimate:
    """The bias of the model's sensor pose that every reading allows (see the module)."""
    position, halfwidth, pos_ok = position_bias(readings)
    if all(r.step_rad <= 0 for r in readings):
        r = readings[0]
        w = log_so3(rpy_to_matrix(r.orientation) @ r.model[:3, :3].T)
        return BiasEstimate(position, w, halfwidth, 0.0, pos_ok)
    w, radius = rotation_bias(readings)
    return BiasEstimate(position, w, halfwidth, radius, pos_ok and radius >= 0)
