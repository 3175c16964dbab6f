"""After the fit: is it consistent, and how well does it fix the measured frame?

A fit is consistent when (1) no kept reading scores above ``outlier_sigma``, (2) the residuals
in reading order show no change point (:mod:`.changepoint`: a base or tool that moved mid-run,
by at least one reading's own 1-sigma, its noise and truncation)
and (3) Levenberg-Marquardt converged. Each failure is one sentence in
:attr:`Verdict.problems`. The parameters' covariance is the midpoint model's residual
covariance s^2 (J^T J)^-1 at the solution; propagated through the measured frame's position
Jacobian it gives that frame's 1-sigma at each fitted configuration (m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.calibrate import derivatives
from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.changepoint import ChangePoint, change_point
from usar_arm.calibrate.parameters import ErrorModel
from usar_arm.calibrate.result import CalibrationOptions
from usar_arm.calibrate.solver import jacobian
from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class Verdict:
    """Why the fit is not consistent (empty: it is), and the strongest change point of its
    residuals with the label of the first reading after it."""

    problems: tuple[str, ...]
    change: ChangePoint | None
    change_label: str


def judge(e: Array, t: qm.Targets, scores: Array, keep: Array, converged: bool,
          options: CalibrationOptions) -> Verdict:
    """The verdict on errors ``e`` (N, 6; m, rad) of the readings ``keep`` marks as fitted,
    in reading order (see the module)."""
    problems = []
    over = int((scores[keep] > options.outlier_sigma).sum())
    if over:
        problems.append(f"{over} reading(s) still lie more than {options.outlier_sigma:g} "
                        "sigma outside their intervals after rejecting the worst 10 %")
    rows = np.flatnonzero(keep)
    oriented = rows[t.used[rows, 3:].all(axis=1)]
    scale = t.scale
    floors = {"position": float(np.median(np.linalg.norm(scale[rows, :3], axis=1)))
              if len(rows) else 0.0,
              "orientation": float(np.median(np.linalg.norm(scale[oriented, 3:], axis=1)))
              if len(oriented) else 0.0}
    change = change_point({"position": e[rows, :3], "orientation": e[oriented, 3:]},
                          options.change_alpha, floors=floors)
    label = ""
    if change is not None:
        label = t.labels[(rows if change.group == "position" else oriented)[change.index]]
        if change.detected:
            size = (f"{change.size * 1e3:.1f} mm" if change.group == "position"
                    else f"{change.size * 1e3:.1f} mrad")
            problems.append(
                f"readings from {label} on sit {size} off those before (change-point "
                f"statistic {change.statistic:.0f}, threshold {change.threshold:.0f}): the "
                "base or the tool moved")
    if not converged:
        problems.append(f"the fit did not converge within {options.max_iterations} "
                        "Levenberg-Marquardt iterations")
    return Verdict(tuple(problems), change, label)


def covariance(model: ErrorModel, p: Array, cols: list[int], q: Array, base: Array,
               t: qm.Targets) -> Array:
    """The covariance (len(cols) x len(cols); m, rad) of the parameters ``cols`` from the
    midpoint model's residual covariance."""
    e = qm.errors(model.poses(p, q, base), t)
    r, d = qm.residuals(e, t, "midpoint")
    jac = jacobian(model, p, cols, q, base, t) * d.ravel()[:, None]
    dof = max(int(t.used.sum()) - len(cols), 1)
    s2 = float((r ** 2).sum()) / dof
    return np.asarray(np.linalg.pinv(jac.T @ jac) * s2, float)


def tool_sigma(model: ErrorModel, p: Array, cols: list[int], q: Array, base: Array,
               cov: Array) -> tuple[float, float]:
    """Median and largest 1-sigma (m) of the measured frame's position over configurations
    ``q``, from the parameters' covariance ``cov``."""
    _, jac = derivatives.pose_jacobian(model, p, q, base)
    j = jac[:, :3, :][:, :, cols]
    var = np.einsum("nij,jk,nik->n", j, cov, j)
    sigma = np.sqrt(np.maximum(var, 0.0))
    return float(np.median(sigma)), float(np.max(sigma))
