"""The fit: Levenberg-Marquardt on the pose residuals, reduced to the identifiable parameters.

1. Scale: every residual by its own 1-sigma (noise and truncation), every Jacobian column to
   unit norm. 2. Rank: QR with column pivoting of that scaled identification Jacobian gives the
   rank; the parameters kept are chosen in a fixed order of preference (base, tool, joint frames
   root to tip), a parameter whose column depends on those already kept being unidentifiable
   (named in the report). 3. Levenberg-Marquardt to convergence. 4. Outliers: readings more than
   ``outlier_sigma`` outside their intervals are removed (worst first, at most 10 %) and the fit
   repeated; if that is not enough the result is ``consistent = False``. 5. Standard deviations
   from the residual covariance of the midpoint model at the solution.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.measurements import Measurement
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.residuals import Residuals, distances
from usar_arm.calibrate.solver import (
    jacobian,
    joint_jacobian,
    levenberg_marquardt,
    preference,
    select_identifiable,
    structural_rank,
)
from usar_arm.errors import CalibrationError
from usar_arm.spatial import Array

# The quantisation model "auto" stands for: measured best on synthetic quantised readings
# (tests/calibrate/test_quantisation_choice.py; figures in docs/calibration.md).
AUTO_MODEL = "likelihood"
MAX_REJECTED = 0.10     # at most this fraction of the readings may be rejected as outliers


@dataclass(frozen=True)
class CalibrationOptions:
    """How to fit (see the module)."""

    quantisation: str = "auto"        # "midpoint" | "set-membership" | "likelihood" | "auto"
    max_iterations: int = 20
    outlier_sigma: float = 4.0
    base: bool = True
    tool: bool = True
    default_sigma_m: float = 1e-4     # noise of a position number that states none (m)
    default_sigma_rad: float = 1e-4   # noise of an angle that states none (rad)


@dataclass(frozen=True)
class ParameterEstimate:
    """One identified parameter: its name, value and standard deviation (m or rad)."""

    name: str
    value: float
    std: float


@dataclass(frozen=True)
class Calibration:
    """The result of :func:`identify` (see docs/calibration.md)."""

    parameters: tuple[ParameterEstimate, ...]
    unidentifiable: tuple[str, ...]
    rank: int
    base: Array
    fit: Residuals
    consistent: bool
    worst: tuple[str, ...]
    rejected: tuple[str, ...]
    quantisation: str
    measured_frame: str = ""
    base_guess: Array = field(default_factory=lambda: np.eye(4))
    iterations: int = 0
    vector: Array = field(default_factory=lambda: np.zeros(0))
    tool: bool = True                 # the measured frame's offset was a parameter
    base_fitted: bool = True          # the base pose was a parameter
    qr_rank: int = 0                  # the pivoted QR's rank (equals rank unless ill-posed)
    seconds: float = 0.0              # time the fit took

    def apply(self, urdf: str, tip_joint: str | None = None) -> str:
        """The calibrated URDF text (joint origins and the measured frame's offset corrected;
        with ``tip_joint``, that fixed joint moved onto the measured frame: see
        :meth:`ErrorModel.apply`)."""
        model = ErrorModel.from_urdf(urdf, self.measured_frame, self.base_fitted, self.tool)
        return model.apply(urdf, self.vector, tip_joint)

    def validate(self, urdf: str, measured_frame: str,
                 held_out: Sequence[Measurement]) -> Residuals:
        """Residuals on readings never used for the fit: the nominal ``urdf`` at the base guess
        before, the calibrated URDF (evaluated by Pinocchio) at the fitted base after."""
        from usar_arm.calibrate.validation import validate

        return validate(self, urdf, measured_frame, held_out)


def _model_name(options: CalibrationOptions) -> str:
    kind = AUTO_MODEL if options.quantisation == "auto" else options.quantisation
    if kind not in qm.MODELS:
        raise CalibrationError(f"unknown quantisation model '{options.quantisation}' "
                               f"(expected auto, {', '.join(qm.MODELS)})")
    return kind


def identify(urdf: str, measured_frame: str, measurements: Sequence[Measurement],
             base_guess: Array, options: CalibrationOptions = CalibrationOptions()
             ) -> Calibration:
    """Fit the error model of ``urdf`` to the measured poses of ``measured_frame`` in M.

    ``base_guess``: M_from_base_link (4x4) known before the fit. Raises
    :class:`~usar_arm.errors.CalibrationError` for too few readings.
    """
    start = time.perf_counter()
    kind = _model_name(options)
    model = ErrorModel.from_urdf(urdf, measured_frame, options.base, options.tool)
    base_guess = np.asarray(base_guess, float)
    meas = list(measurements)
    rows = sum(6 if m.rpy is not None else 3 for m in meas)
    if len(meas) < 3:
        raise CalibrationError("too few readings to identify anything", len(meas), 3)
    q = qm.joint_midpoints(meas)
    t = qm.targets(meas, options.default_sigma_m, options.default_sigma_rad)
    step_q = np.array([m.step_q for m in meas])
    if step_q.any():
        t = qm.widen_for_joints(t, joint_jacobian(model, q, base_guess, t), step_q)
    p0 = np.zeros(model.size)
    jac0 = jacobian(model, p0, range(model.size), q, base_guess, t) / t.scale.ravel()[:, None]
    jac0 *= t.used.ravel()[:, None]
    cols, qr_rank = select_identifiable(jac0, preference(model))
    per = 6 if all(m.rpy is not None for m in meas) else 3
    full = structural_rank(model, per == 6)
    if len(cols) == 0 or rows < full + 6:
        raise CalibrationError(f"too few readings: {rows} numbers for {full} identifiable "
                               "parameters (and 6 more numbers to judge the fit)", len(meas),
                               math.ceil((full + 6) / per))
    t = _unstated_noise(model, cols, q, base_guess, t, meas, options)
    keep = np.ones(len(meas), bool)
    p, its = p0, 0
    limit = int(MAX_REJECTED * len(meas))
    for _ in range(limit + 1):
        tk = _subset(t, keep)
        p, its = levenberg_marquardt(model, p, cols, q[keep], base_guess, tk, "midpoint",
                                     options.max_iterations)
        if kind != "midpoint":  # started from the midpoint solution: inside or near the set
            p, more = levenberg_marquardt(model, p, cols, q[keep], base_guess, tk, kind,
                                          options.max_iterations)
            its += more
        sc = qm.scores(qm.errors(model.poses(p, q, base_guess), t), t, kind)
        sc[~keep] = 0.0
        worst = int(np.argmax(sc))
        if sc[worst] <= options.outlier_sigma or (~keep).sum() >= limit:
            break
        keep[worst] = False
    e = qm.errors(model.poses(p, q, base_guess), t)
    sc = qm.scores(e, t, kind)
    consistent = bool(sc[keep].max() <= options.outlier_sigma) if keep.any() else False
    std = _std(model, p, cols, q[keep], base_guess, _subset(t, keep))
    before = distances(model.poses(p0, q, base_guess), t)
    after = distances(model.poses(p, q, base_guess), t)
    order = np.argsort(-np.where(keep, sc, np.inf), kind="stable")
    names = model.names
    return Calibration(
        parameters=tuple(ParameterEstimate(names[c], float(p[c]), float(s))
                         for c, s in zip(cols, std, strict=True)),
        unidentifiable=tuple(names[c] for c in range(model.size) if c not in cols),
        rank=len(cols), base=model.base_pose(p, base_guess),
        fit=Residuals(t.labels, before[0], before[1], after[0], after[1]),
        consistent=consistent, worst=tuple(t.labels[k] for k in order[:5]),
        rejected=tuple(t.labels[k] for k in np.flatnonzero(~keep)), quantisation=kind,
        measured_frame=measured_frame, base_guess=base_guess, iterations=its, vector=p,
        tool=model.tool_joint is not None, base_fitted=options.base,
        qr_rank=qr_rank, seconds=time.perf_counter() - start)


def _unstated_noise(model: ErrorModel, cols: list[int], q: Array, base: Array, t: qm.Targets,
                    meas: Sequence[Measurement], options: CalibrationOptions) -> qm.Targets:
    """Targets whose numbers without a stated sigma or step get the noise the readings show:
    after a midpoint fit with the defaults, 1.4826 x the median absolute error of those numbers
    (position and angles separately; robust to a few outliers)."""
    pos = np.array([not (m.sigma_m > 0 or m.step_m > 0) for m in meas])
    rot = np.array([m.rpy is not None and not (m.sigma_rad > 0 or m.step_rad > 0) for m in meas])
    if not pos.any() and not rot.any():
        return t
    p, _ = levenberg_marquardt(model, np.zeros(model.size), cols, q, base, t, "midpoint",
                               options.max_iterations)
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


def _std(model: ErrorModel, p: Array, cols: list[int], q: Array, base: Array,
         t: qm.Targets) -> Array:
    """Standard deviations (m, rad) from the midpoint model's residual covariance."""
    e = qm.errors(model.poses(p, q, base), t)
    r, d = qm.residuals(e, t, "midpoint")
    jac = jacobian(model, p, cols, q, base, t) * d.ravel()[:, None]
    dof = max(int(t.used.sum()) - len(cols), 1)
    s2 = float((r ** 2).sum()) / dof
    cov = np.linalg.pinv(jac.T @ jac) * s2
    return np.sqrt(np.maximum(np.diag(cov), 0.0))
