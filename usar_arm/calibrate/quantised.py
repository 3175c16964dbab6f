"""The measurement model: each printed number stands for an interval, plus noise.

A number printed truncated toward zero to a step says the truth lies in a step-wide interval
(:func:`usar_arm.control.tip_bias.interval`). Three ways to fit a model to such intervals:

* ``midpoint``: the interval's middle is the measurement, its error uniform over the interval
  (variance step^2 / 12), added to the noise variance; an ordinary weighted least squares.
* ``set-membership``: only leaving the interval costs (a hinge, scaled like the midpoint's
  residual), plus a weak pull (:data:`PULL`) toward the middle that makes the minimum unique:
  the fit lands inside the set every reading allows, near its centre.
* ``likelihood``: each number's exact probability, its interval blurred by the Gaussian errors
  of noise and of quantised joint values (:mod:`.likelihood`): sharp edges where nothing blurs
  them, soft ones where the joints' printed steps do.

Joint values printed to a step (``Measurement.step_q``) stand for intervals too: the fit uses
their middles, widens every number's interval by what they allow at worst
(sum_j |d number / d q_j| step_q / 2) and, for the likelihood, blurs it by their 1-sigma
(sqrt(sum_j (d number / d q_j)^2) step_q / sqrt(12)).

Position numbers are compared per axis in M; quantised angles per printed roll, pitch, yaw
(wrapped); unquantised orientations by the rotation vector of R_model R_measured^T.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from usar_arm.calibrate import likelihood
from usar_arm.calibrate.measurements import Measurement
from usar_arm.control.tip_bias import interval, wrap
from usar_arm.core.spatial import Array, log_so3, rpy_to_matrix

MODELS = ("midpoint", "set-membership", "likelihood")
GIMBAL = 0.05  # |cos pitch| below this: printed roll and yaw are not smooth in the rotation
PULL = 0.05  # weight of the pull toward the middle in the set-membership residual


@dataclass(frozen=True)
class Targets:
    """Per measurement and number (N, 6: x, y, z, then 3 rotation numbers): the interval's
    middle (m, rad), its half-width, the noise sigma and whether the number is used."""

    mid: Array
    half: Array
    sigma: Array
    used: Array
    quantised_rot: Array      # (N,) bool: the rotation is compared as printed rpy
    rotations: Array          # (N, 3, 3) measured rotations (identity when position only)
    labels: tuple[str, ...]
    joint_sigma: Array | None = None  # (N, 6) 1-sigma of each number from quantised joints
    joint_extra: Array | None = None  # (N, 6) what the joints added to ``half``

    @property
    def scale(self) -> Array:
        """The 1-sigma of each number's total error: noise and uniform truncation (m, rad)."""
        return np.sqrt(self.sigma ** 2 + (2 * self.half) ** 2 / 12)


def targets(measurements: Sequence[Measurement], default_sigma_m: float,
            default_sigma_rad: float) -> Targets:
    """The intervals of the measurements (``default_sigma_*`` where a number has neither a
    stated sigma nor a step)."""
    n = len(measurements)
    mid, half, sigma = np.zeros((n, 6)), np.zeros((n, 6)), np.zeros((n, 6))
    used = np.ones((n, 6), bool)
    qrot = np.zeros(n, bool)
    rots = np.tile(np.eye(3), (n, 1, 1))
    for k, m in enumerate(measurements):
        for i in range(3):
            lo, hi = interval(float(m.position[i]), m.step_m)
            mid[k, i], half[k, i] = (lo + hi) / 2, (hi - lo) / 2
        sigma[k, :3] = m.sigma_m if (m.sigma_m > 0 or m.step_m > 0) else default_sigma_m
        if m.rpy is None:
            used[k, 3:] = False
            sigma[k, 3:] = 1.0
            continue
        sigma[k, 3:] = m.sigma_rad if (m.sigma_rad > 0 or m.step_rad > 0) else default_sigma_rad
        if m.step_rad > 0:
            qrot[k] = True
            box = [interval(float(v), m.step_rad) for v in m.rpy]
            mid[k, 3:] = [(lo + hi) / 2 for lo, hi in box]
            half[k, 3:] = [(hi - lo) / 2 for lo, hi in box]
            rots[k] = rpy_to_matrix(mid[k, 3:])
            if abs(np.cos(mid[k, 4])) < GIMBAL:  # roll and yaw not separable: position only
                used[k, 3:] = False
        else:
            rots[k] = rpy_to_matrix(m.rpy)
    return Targets(mid, half, sigma, used, qrot, rots, tuple(m.label for m in measurements))


def rpy_many(rot: Array) -> Array:
    """(N, 3) roll, pitch, yaw (rad) of (N, 3, 3) rotations (away from gimbal lock)."""
    return np.stack([np.arctan2(rot[:, 2, 1], rot[:, 2, 2]),
                     np.arcsin(np.clip(-rot[:, 2, 0], -1.0, 1.0)),
                     np.arctan2(rot[:, 1, 0], rot[:, 0, 0])], axis=1)


def log_many(rot: Array) -> Array:
    """(N, 3) rotation vectors (rad) of (N, 3, 3) rotations of angle < pi - 1e-6."""
    c = np.clip((np.trace(rot, axis1=1, axis2=2) - 1) / 2, -1.0, 1.0)
    angle = np.arccos(c)
    w = np.stack([rot[:, 2, 1] - rot[:, 1, 2], rot[:, 0, 2] - rot[:, 2, 0],
                  rot[:, 1, 0] - rot[:, 0, 1]], axis=1)
    s = np.sin(angle)
    factor = np.where(angle < 1e-9, 0.5, angle / (2 * np.where(s == 0, 1.0, s)))
    out = w * factor[:, None]
    for k in np.flatnonzero(np.pi - angle < 1e-6):
        out[k] = log_so3(rot[k])
    return out


def errors(poses: Array, t: Targets) -> Array:
    """(N, 6) model minus measurement: position (m), then rotation numbers (rad)."""
    e = np.zeros((len(poses), 6))
    e[:, :3] = poses[:, :3, 3] - t.mid[:, :3]
    rot = poses[:, :3, :3]
    e[:, 3:] = np.where(t.quantised_rot[:, None], wrap(rpy_many(rot) - t.mid[:, 3:]),
                        log_many(rot @ np.transpose(t.rotations, (0, 2, 1))))
    return np.where(t.used, e, 0.0)


def residuals(e: Array, t: Targets, model: str) -> tuple[Array, Array]:
    """The weighted residuals (N, 6) of errors ``e`` and their derivative d r / d e."""
    s = t.scale
    if model == "midpoint":
        r, d = e / s, 1 / s
    elif model == "set-membership":
        excess = np.sign(e) * np.maximum(np.abs(e) - t.half, 0.0)
        r = (excess + PULL * e) / s
        d = (np.where(np.abs(e) > t.half, 1.0, 0.0) + PULL) / s
    elif model == "likelihood":
        joints = t.joint_sigma if t.joint_sigma is not None else np.zeros_like(e)
        own = t.half - (t.joint_extra if t.joint_extra is not None else 0.0)
        r, d = likelihood.residuals(e, own, likelihood.blur(t.sigma, joints, own))
    else:
        raise ValueError(f"unknown quantisation model '{model}' (expected {', '.join(MODELS)})")
    return np.where(t.used, r, 0.0), np.where(t.used, d, 0.0)


def scores(e: Array, t: Targets, model: str = "midpoint") -> Array:
    """(N,) how far each reading is outside its intervals, in its own 1-sigma (0: inside).

    For the likelihood model, the largest |residual| of its numbers: how improbable the
    printed number is, in sigmas of the Gaussian that blurs its interval's edges (noise and the
    joints' printed steps); for the others, the excess over the (worst-case widened) interval
    in units of the interval's own 1-sigma."""
    if model == "likelihood":
        r, _ = residuals(e, t, model)
        return np.abs(r).max(axis=1)
    excess = np.maximum(np.abs(e) - t.half, 0.0) / t.scale
    return np.where(t.used, excess, 0.0).max(axis=1)


def joint_midpoints(measurements: Sequence[Measurement]) -> Array:
    """(N, n) joint values: the middles of the printed values' intervals when truncated."""
    return np.array([[sum(interval(float(v), m.step_q)) / 2 for v in m.q]
                     if m.step_q > 0 and not m.q_rounded
                     else np.asarray(m.q, float) for m in measurements], float)


def widen_for_joints(t: Targets, joint_jacobian: Array, step_q: Array) -> Targets:
    """Targets whose intervals also hold what printed joint values allow: each number's
    half-width grows by sum_j |d number / d q_j| step_q / 2 (``joint_jacobian`` (N, 6, n)),
    and its blur (``joint_sigma``) is the 1-sigma of the uniform joint errors it sums."""
    extra = np.abs(joint_jacobian).sum(axis=2) * step_q[:, None] / 2
    sig = np.sqrt((joint_jacobian ** 2).sum(axis=2) / 12) * step_q[:, None]
    extra = np.where(t.used, extra, 0.0)
    return replace(t, half=t.half + extra, joint_extra=extra,
                   joint_sigma=np.where(t.used, sig, 0.0))
