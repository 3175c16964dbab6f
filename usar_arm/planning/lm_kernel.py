"""The compiled Levenberg-Marquardt search of the numeric IK (any serial chain, any number of
joints): one call per start, no Python objects. Its pose error, Jacobian, 6x6 solve and capped
step are the closed forms' Newton polish's (:mod:`.ik_kernel`). Radians and metres."""

from __future__ import annotations

import numpy as np

from usar_arm.core.spatial import Array
from usar_arm.planning.ik_kernel import pose_error, solve6, take_step
from usar_arm.planning.jit import kernel


@kernel
def levenberg_marquardt(q: Array, target_rot: Array, target_pos: Array, axes: Array,
                        points: Array, rev: Array, tool: Array, tol_p: float, tol_r: float,
                        iterations: int, damping: float, floor: float, max_step: float
                        ) -> tuple[bool, float, float]:
    """Levenberg-Marquardt from ``q`` (in place) on any serial chain: (J^T J + lambda I) dq =
    J^T e with lambda = ``damping`` * |e|^2 + ``floor`` (large far from the target, vanishing
    near it), steps capped at ``max_step``. Returns (converged, position m, rotation rad)."""
    n = q.shape[0]
    err = np.empty(6)
    jac = np.empty((6, n))
    h = np.empty((n, n))
    g = np.empty(n)
    step = np.empty(n)
    for _ in range(iterations):
        pe, re = pose_error(q, target_rot, target_pos, axes, points, rev, tool, err, jac)
        if pe < tol_p and re < tol_r:
            return True, pe, re
        lam = damping * (pe * pe + re * re) + floor
        for a in range(n):
            s = 0.0
            for i in range(6):
                s += jac[i, a] * err[i]
            g[a] = s
            for b in range(n):
                s = 0.0
                for i in range(6):
                    s += jac[i, a] * jac[i, b]
                h[a, b] = s + (lam if a == b else 0.0)
        if not solve6(h, g, step):
            return False, pe, re
        take_step(q, step, max_step)
    pe, re = pose_error(q, target_rot, target_pos, axes, points, rev, tool, err, jac)
    return False, pe, re


def warm_up() -> None:
    """Compile :func:`levenberg_marquardt` for the argument types :class:`.ik_numeric.NumericIK`
    passes (numba caches the machine code on disk)."""
    z3 = np.zeros(3)
    levenberg_marquardt(np.zeros(7), np.eye(3), z3, np.zeros((7, 3)), np.zeros((7, 3)),
                        np.ones(7), np.eye(4), 1e-5, 1e-5, 1, 0.01, 1e-4, 0.5)
