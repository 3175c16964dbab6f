"""The fit: Levenberg-Marquardt on the pose residuals, reduced to the identifiable parameters.

0. Plausibility (:mod:`.plausibility`): every reading within :attr:`.bounds.Bounds.reading_m` /
   ``reading_rad`` of the nominal description, else an error naming the likely mistake.
1. Scale: every residual by its own 1-sigma (noise and truncation), every Jacobian column to
   unit norm. 2. Rank: QR with column pivoting of that scaled identification Jacobian gives the
   rank; the parameters kept are chosen in a fixed order of preference (base, tool, joint frames
   root to tip), a parameter whose column depends on those already kept being unidentifiable
   (named in the report); those that readings at generic configurations would identify but
   these do not are ``lost``. The fit needs twice as many numbers as the generic rank.
3. Levenberg-Marquardt to convergence (not converging within ``max_iterations`` makes the fit
   inconsistent). 4. Outliers: readings more than ``outlier_sigma`` outside their intervals
   are removed (worst first, at most 10 %) and the fit repeated. 5. Consistency
   (:mod:`.consistency`): no reading left above ``outlier_sigma``, no change point in the
   residuals in reading order (:mod:`.changepoint`: a base or tool moved mid-run), converged.
6. Bounds (:mod:`.bounds`): a fit whose corrections exceed them is an error. 7. Standard
   deviations from the residual covariance of the midpoint model at the solution.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.bounds import check_corrections, corrections
from usar_arm.calibrate.consistency import covariance, judge, tool_sigma
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.plausibility import check_readings
from usar_arm.calibrate.residuals import Residuals, distances
from usar_arm.calibrate.result import Calibration, CalibrationOptions, ParameterEstimate
from usar_arm.calibrate.solver import (
    jacobian,
    joint_jacobian,
    levenberg_marquardt,
    preference,
    select_identifiable,
    structural_columns,
)
from usar_arm.core.errors import CalibrationError
from usar_arm.core.spatial import Array

__all__ = ["AUTO_MODEL", "Calibration", "CalibrationOptions", "ParameterEstimate", "identify"]

# The quantisation model "auto" stands for: measured best on synthetic quantised readings
# (tests/calibrate/test_quantisation_choice.py; figures in docs/calibration.md).
AUTO_MODEL = "likelihood"
MAX_REJECTED = 0.10     # at most this fraction of the readings may be rejected as outliers
NUMBERS_PER_PARAMETER = 2
"""A well-posed fit has at least this many fitted numbers per generically identifiable
parameter."""


def _model_name(options: CalibrationOptions) -> str:
    kind = AUTO_MODEL if options.quantisation == "auto" else options.quantisation
    if kind not in qm.MODELS:
        raise CalibrationError(f"unknown quantisation model '{options.quantisation}' "
                               f"(expected auto, {', '.join(qm.MODELS)})")
    return kind


def identify(urdf: str, measured_frame: str, measurements: Sequence[Measurement],
             base_guess: Array | None, options: CalibrationOptions | None = None
             ) -> Calibration:
    """Fit the error model of ``urdf`` to the measured poses of ``measured_frame`` in M.

    ``base_guess``: M_from_base_link (4x4) known before the fit, or None when the readings'
    frame is unknown (a tracker in its own frame: the guess is registered from the readings).
    Raises :class:`~usar_arm.core.errors.CalibrationError` for too few readings, readings far from
    the nominal description, or corrections beyond ``options.bounds``.
    """
    start = time.perf_counter()
    options = options or CalibrationOptions()
    kind = _model_name(options)
    model = ErrorModel.from_urdf(urdf, measured_frame, options.base, options.tool)
    meas = list(measurements)
    if len(meas) < 3:
        raise CalibrationError("too few readings to identify anything", len(meas), 3)
    if base_guess is None and not options.base:
        raise CalibrationError("the readings' frame is unknown, so the base must be fitted")
    q = qm.joint_midpoints(meas)
    registration = check_readings(urdf, model, meas, q, base_guess, options.bounds)
    base_guess = registration.base
    t = qm.targets(meas, options.default_sigma_m, options.default_sigma_rad)
    step_q = np.array([m.step_q for m in meas])
    if step_q.any():
        t = qm.widen_for_joints(t, joint_jacobian(model, q, base_guess, t), step_q)
    p0 = np.zeros(model.size)
    jac0 = jacobian(model, p0, range(model.size), q, base_guess, t) / t.scale.ravel()[:, None]
    jac0 *= t.used.ravel()[:, None]
    cols, qr_rank = select_identifiable(jac0, preference(model))
    per = 6 if all(m.rpy is not None for m in meas) else 3
    generic = structural_columns(model, per == 6)
    numbers = int(t.used.sum())
    need = NUMBERS_PER_PARAMETER * len(generic)
    if len(cols) == 0 or numbers < need:
        raise CalibrationError(
            f"too few readings: {numbers} numbers to fit for the {len(generic)} parameters "
            f"readings of {measured_frame} identify; a well-posed fit needs "
            f"{NUMBERS_PER_PARAMETER}x as many ({need})", len(meas), math.ceil(need / per))
    t = _unstated_noise(model, cols, q, base_guess, t, meas, options)
    p, its, converged, keep = _fit_rejecting_outliers(model, p0, cols, q, base_guess, t, kind,
                                                      options)
    e = qm.errors(model.poses(p, q, base_guess), t)
    sc = qm.scores(e, t, kind)
    verdict = judge(e, t, sc, keep, converged, options)
    found = corrections(model, p)
    check_corrections(found, options.bounds)
    cov = covariance(model, p, cols, q[keep], base_guess, _subset(t, keep))
    before = distances(model.poses(p0, q, base_guess), t)
    after = distances(model.poses(p, q, base_guess), t)
    order = np.argsort(-np.where(keep, sc, np.inf), kind="stable")
    names = model.names
    return Calibration(
        parameters=tuple(ParameterEstimate(names[c], float(p[c]), float(s))
                         for c, s in zip(cols, np.sqrt(np.maximum(np.diag(cov), 0.0)),
                                         strict=True)),
        unidentifiable=tuple(names[c] for c in range(model.size) if c not in cols),
        rank=len(cols), base=model.base_pose(p, base_guess),
        fit=Residuals(t.labels, before[0], before[1], after[0], after[1]),
        consistent=not verdict.problems, worst=tuple(t.labels[k] for k in order[:5]),
        rejected=tuple(t.labels[k] for k in np.flatnonzero(~keep)), quantisation=kind,
        measured_frame=measured_frame, base_guess=base_guess, iterations=its, vector=p,
        tool=model.tool_joint is not None, base_fitted=options.base,
        qr_rank=qr_rank, seconds=time.perf_counter() - start, generic_rank=len(generic),
        lost=tuple(names[c] for c in generic if c not in cols), problems=verdict.problems,
        change=verdict.change, change_label=verdict.change_label, converged=converged,
        corrections=found, bounds=options.bounds,
        tool_sigma_m=tool_sigma(model, p, cols, q[keep], base_guess, cov),
        registered=registration.registered)


def _fit_rejecting_outliers(model: ErrorModel, p0: Array, cols: list[int], q: Array,
                            base: Array, t: qm.Targets, kind: str,
                            options: CalibrationOptions
                            ) -> tuple[Array, int, bool, NDArray[Any]]:
    """(parameters, iterations, converged, readings kept): the fit (midpoint first, then the
    ``kind`` model from there), refitted without the worst reading while it scores over
    ``options.outlier_sigma``, at most :data:`MAX_REJECTED` of the readings."""
    keep = np.ones(len(q), bool)
    p, its, converged = p0, 0, True
    limit = int(MAX_REJECTED * len(q))
    for _ in range(limit + 1):
        tk = _subset(t, keep)
        first = levenberg_marquardt(model, p, cols, q[keep], base, tk, "midpoint",
                                    options.max_iterations)
        p, its, converged = first.p, first.iterations, first.converged
        if kind != "midpoint":  # started from the midpoint solution: inside or near the set
            more = levenberg_marquardt(model, p, cols, q[keep], base, tk, kind,
                                       options.max_iterations)
            p, its, converged = more.p, its + more.iterations, converged and more.converged
        sc = qm.scores(qm.errors(model.poses(p, q, base), t), t, kind)
        sc[~keep] = 0.0
        worst = int(np.argmax(sc))
        if sc[worst] <= options.outlier_sigma or (~keep).sum() >= limit:
            break
        keep[worst] = False
    return p, its, converged, keep


def _unstated_noise(model: ErrorModel, cols: list[int], q: Array, base: Array, t: qm.Targets,
                    meas: Sequence[Measurement], options: CalibrationOptions) -> qm.Targets:
    """Targets whose numbers without a stated sigma or step get the noise the readings show:
    after a midpoint fit with the defaults, 1.4826 x the median absolute error of those numbers
    (position and angles separately; robust to a few outliers)."""
    pos = np.array([not (m.sigma_m > 0 or m.step_m > 0) for m in meas])
    rot = np.array([m.rpy is not None and not (m.sigma_rad > 0 or m.step_rad > 0) for m in meas])
    if not pos.any() and not rot.any():
        return t
    p = levenberg_marquardt(model, np.zeros(model.size), cols, q, base, t, "midpoint",
                            options.max_iterations).p
    e = np.abs(qm.errors(model.poses(p, q, base), t))
    dof = max(1.0 - len(cols) / max(int(t.used.sum()), 1), 0.1)
    sig_m = float(np.median(e[pos, :3]) * 1.4826 / np.sqrt(dof)) if pos.any() \
        else options.default_sigma_m
    sig_rad = float(np.median(e[rot, 3:]) * 1.4826 / np.sqrt(dof)) if rot.any() \
        else options.default_sigma_rad
    return qm.targets(meas, max(sig_m, 1e-9), max(sig_rad, 1e-9))


def _subset(t: qm.Targets, keep: Array) -> qm.Targets:
    return qm.Targets(t.mid[keep], t.half[keep], t.sigma[keep], t.used[keep],
                      t.quantised_rot[keep], t.rotations[keep],
                      tuple(lb for lb, k in zip(t.labels, keep, strict=True) if k),
                      None if t.joint_sigma is None else t.joint_sigma[keep],
                      None if t.joint_extra is None else t.joint_extra[keep])
