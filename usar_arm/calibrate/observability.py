"""Which configurations to measure: observability-driven pose selection.

:func:`select_poses` picks configurations (within limits, ``is_free``) whose stacked
identification Jacobian -- pose of the measured frame (m, rad) w.r.t. the identifiable
parameters (m, rad), both in natural units so 1 mm weighs as 1 mrad -- has the largest smallest
singular value: a greedy pass over random candidates (D-optimal until the rank is reached, then
the smallest eigenvalue of J^T J), then one exchange pass. Deterministic for a seed.

No dithering is needed on the wire: the tour reads the sensor in motion, which moves every
printed number through its step (docs/calibration.md, "Pose selection and dithering").
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.quantised import log_many
from usar_arm.calibrate.solver import RANK_TOL, preference, select_identifiable
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import Array
from usar_arm.planning.kinematics import KinematicModel

STEP = 1e-6


def pose_jacobians(model: ErrorModel, q: Array) -> Array:
    """(N, 6, P) d(position m, rotation rad of the measured frame) / d parameters at zero."""
    base = np.eye(4)
    out = np.empty((len(q), 6, model.size))
    for c in range(model.size):
        hi, lo = np.zeros(model.size), np.zeros(model.size)
        hi[c], lo[c] = STEP, -STEP
        a, b = model.poses(hi, q, base), model.poses(lo, q, base)
        out[:, :3, c] = (a[:, :3, 3] - b[:, :3, 3]) / (2 * STEP)
        out[:, 3:, c] = log_many(a[:, :3, :3] @ np.transpose(b[:, :3, :3], (0, 2, 1))) \
            / (2 * STEP)
    return out


def _candidates(count: int, is_free: Callable[[Array], bool], rng: np.random.Generator,
                lower: Array, upper: Array) -> Array:
    out: list[Array] = []
    tries = 0
    while len(out) < count and tries < 50 * count:
        q = rng.uniform(lower, upper)
        tries += 1
        if is_free(q):
            out.append(q)
    if len(out) < count // 4:
        raise CalibrationError(f"only {len(out)} of {tries} random configurations are free")
    return np.array(out)


def smallest_singular_value(jac: Array) -> float:
    """sigma_min of a stacked (rows, P) Jacobian."""
    return float(np.linalg.svd(jac, compute_uv=False)[-1]) if jac.size else 0.0


def select_poses(urdf: str, measured_frame: str, count: int, is_free: Callable[[Array], bool],
                 seed: int, lower: Array | None = None, upper: Array | None = None,
                 candidates: int = 0) -> Array:
    """``count`` configurations (count, n) maximising the smallest singular value of the
    identification Jacobian over the identifiable parameters (see the module)."""
    model = ErrorModel.from_urdf(urdf, measured_frame)
    km = KinematicModel(urdf)
    lo = km.lower if lower is None else np.asarray(lower, float)
    hi = km.upper if upper is None else np.asarray(upper, float)
    rng = np.random.default_rng(seed)
    pool = _candidates(max(candidates, 6 * count, 120), is_free, rng, lo, hi)
    jac = pose_jacobians(model, pool)
    cols, _ = select_identifiable(jac.reshape(-1, model.size), preference(model))
    jac = jac[:, :, cols]
    grams = np.einsum("kri,krj->kij", jac, jac)
    gram = np.zeros((len(cols), len(cols)))
    chosen: list[int] = []
    for _ in range(min(count, len(pool))):
        score = np.array([_score(gram + g) for g in grams])
        score[chosen] = -np.inf
        best = int(np.argmax(score))
        chosen.append(best)
        gram += grams[best]
    for i in range(len(chosen)):  # one exchange pass
        rest = gram - grams[chosen[i]]
        score = np.array([_score(rest + g) for g in grams])
        score[chosen] = -np.inf
        best = int(np.argmax(score))
        if score[best] > _score(gram) * (1 + 1e-9):
            chosen[i] = best
            gram = rest + grams[best]
    return pool[chosen]


def _score(gram: Array) -> float:
    """Smallest eigenvalue once the rank is full; before that, the log-determinant of the
    non-zero part (a tie-breaker toward full rank), shifted far below any full-rank score."""
    ev = np.linalg.eigvalsh(gram)
    if ev[0] > RANK_TOL * max(ev[-1], 1e-300):
        return float(ev[0])
    big = ev[ev > RANK_TOL * max(ev[-1], 1e-300)]
    return -1e6 * (len(ev) - len(big)) + float(np.log(big).sum()) * 1e-3
