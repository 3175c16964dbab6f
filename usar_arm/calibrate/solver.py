"""The numerical core of the fit: the identification Jacobian, the identifiable columns, and
Levenberg-Marquardt on the weighted residuals (see identification.py for the method)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from usar_arm.calibrate import derivatives
from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.core.spatial import Array

RANK_TOL = 1e-6         # |R_kk| / |R_00| below this: the column adds nothing (scaled Jacobian)


def jacobian(model: ErrorModel, p: Array, cols: Sequence[int], q: Array, base: Array,
             t: qm.Targets) -> Array:
    """d errors / d p[cols] (N*6, len(cols)), analytic (:mod:`.derivatives`)."""
    poses, jac = derivatives.pose_jacobian(model, p, q, base)
    return derivatives.number_jacobian(poses, jac[:, :, list(cols)], t).reshape(
        q.shape[0] * 6, len(cols))


def joint_jacobian(model: ErrorModel, q: Array, base: Array, t: qm.Targets) -> Array:
    """(N, 6, n) d errors / d q at the nominal parameters (analytic)."""
    poses, jac = derivatives.joint_pose_jacobian(model, np.zeros(model.size), q, base)
    return derivatives.number_jacobian(poses, jac, t)


def select_identifiable(jac: Array, order: Sequence[int]) -> tuple[list[int], int]:
    """The identifiable columns, kept in ``order`` of preference, and the pivoted-QR rank."""
    from scipy.linalg import qr

    norms = np.linalg.norm(jac, axis=0)
    scaled = jac / np.where(norms > 0, norms, 1.0)
    r = qr(scaled, mode="r", pivoting=True)[0]
    diag = np.abs(np.diag(r))
    rank = int((diag > RANK_TOL * diag[0]).sum()) if len(diag) else 0
    kept: list[int] = []
    basis = np.zeros((jac.shape[0], 0))
    for c in order:
        if norms[c] == 0:
            continue
        v = scaled[:, c] - basis @ (basis.T @ scaled[:, c])
        v = v - basis @ (basis.T @ v)
        if np.linalg.norm(v) > math.sqrt(RANK_TOL):
            kept.append(c)
            basis = np.column_stack([basis, v / np.linalg.norm(v)])
    return kept, rank


@dataclass(frozen=True)
class Fitted:
    """Levenberg-Marquardt's answer: the parameters, the iterations taken, and whether it
    converged (relative cost change below 1e-10, or no step lowers the cost any more) rather
    than stopping at its cap."""

    p: Array
    iterations: int
    converged: bool


def levenberg_marquardt(model: ErrorModel, p: Array, cols: list[int], q: Array, base: Array,
                        t: qm.Targets, kind: str, iterations: int) -> Fitted:
    """Levenberg-Marquardt on the weighted residuals over the parameters ``cols``, at most
    ``iterations`` steps."""
    def cost(x: Array) -> tuple[float, Array, Array]:
        e = qm.errors(model.poses(x, q, base), t)
        r, d = qm.residuals(e, t, kind)
        return float((r ** 2).sum()), r.ravel(), d.ravel()

    c0, r, d = cost(p)
    lam = 1e-3
    it = 0
    while it < iterations:
        it += 1
        jac = jacobian(model, p, cols, q, base, t) * d[:, None]
        jtj, g = jac.T @ jac, jac.T @ r
        improved = False
        for _ in range(10):
            a = jtj + lam * np.diag(np.diag(jtj) + 1e-12)
            dp = -np.linalg.solve(a, g)
            trial = p.copy()
            trial[cols] += dp
            c1, r1, d1 = cost(trial)
            if c1 < c0:
                improved = True
                break
            lam *= 10
        if not improved:
            return Fitted(p, it, True)
        p, r, d = trial, r1, d1
        lam = max(lam / 10, 1e-9)
        done = c0 - c1 < 1e-10 * c0 + 1e-14
        c0 = c1
        if done:
            return Fitted(p, it, True)
    return Fitted(p, it, False)


def structural_columns(model: ErrorModel, rotations: bool = True, samples: int = 40
                       ) -> list[int]:
    """The parameters readings at generic configurations identify, chosen in the order of
    :func:`preference` (random configurations within the joint limits, seed 0; position-only
    when ``rotations`` is False)."""
    joints = [j for j in model.path if j.actuated]
    lo = np.array([j.limits.lower if j.limits else -np.pi for j in joints])
    hi = np.array([j.limits.upper if j.limits else np.pi for j in joints])
    q = np.random.default_rng(0).uniform(lo, hi, (samples, len(joints)))
    t = qm.targets([Measurement(qk, np.zeros(3), np.zeros(3) if rotations else None,
                                sigma_m=1e-3, sigma_rad=1e-3) for qk in q], 1e-3, 1e-3)
    jac = jacobian(model, np.zeros(model.size), range(model.size), q, np.eye(4), t)
    jac *= t.used.ravel()[:, None]
    return select_identifiable(jac, preference(model))[0]


def preference(model: ErrorModel) -> list[int]:
    idx = {n: i for i, n in enumerate(model.names)}
    first = [idx[n] for n in model.names if n.startswith(("base.", "tool."))]
    return first + [i for i in range(model.size) if i not in first]
