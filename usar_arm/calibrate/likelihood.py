"""The ``likelihood`` quantisation model: each printed number's exact probability.

A number printed to a step says the truth lies in an interval of half-width h (m or rad) around
the interval's middle; what the model predicts misses the truth by the noise and by what the
printed joint values leave open (each joint value stands for its own interval, which the pose
Jacobian turns into an error of about sigma_q on this number). With e the model's error from the
middle and s the 1-sigma of those Gaussian errors together, the probability of the printed number
is

    P(e) = Phi((h - e) / s) - Phi((-h - e) / s)

(a uniform interval blurred by a Gaussian), largest at e = 0. The residual handed to the least
squares is ``sign(e) sqrt(2 (log P(0) - log P(e)))``, so the sum of squares is -2 log-likelihood
up to a constant. With sharp edges (s << h) it behaves like set-membership (flat inside, steep
outside); with a blur wider than the interval (s >> h) like the midpoint model. A small floor
(:data:`EDGE_FLOOR` of the interval's own 1-sigma) keeps the edges differentiable and the optimum
unique when nothing blurs them.
"""

from __future__ import annotations

import numpy as np
from scipy.special import log_ndtr

from usar_arm.core.spatial import Array

EDGE_FLOOR = 0.05
"""Smallest blur of an interval's edges, as a fraction of the interval's 1-sigma (2h/sqrt(12)):
measured on truncated tip-sensor readings (docs/calibration.md)."""
GAUSSIAN_BELOW = 1e-3
"""Intervals narrower than this fraction of their blur are treated as plain Gaussian."""
_LOG_SQRT_2PI = 0.5 * np.log(2 * np.pi)


def blur(sigma: Array, joint_sigma: Array, half: Array) -> Array:
    """The 1-sigma (m, rad) of the Gaussian errors that blur each interval's edges: noise,
    joint quantisation and the floor, combined."""
    floor = EDGE_FLOOR * 2 * half / np.sqrt(12)
    return np.sqrt(sigma ** 2 + joint_sigma ** 2 + floor ** 2 + 1e-30)


def _log_p(x: Array, h: Array, s: Array) -> Array:
    """log(Phi((h - x) / s) - Phi((-h - x) / s)) for x >= 0, accurate in the tails."""
    lb, la = log_ndtr((h - x) / s), log_ndtr((-h - x) / s)
    return lb + np.log1p(-np.exp(np.minimum(la - lb, -1e-300)))


def residuals(e: Array, half: Array, s: Array) -> tuple[Array, Array]:
    """Residuals r (see the module) of errors ``e`` from the interval middles and dr/de, for
    intervals of half-width ``half`` blurred by ``s`` (all (N, 6), m or rad)."""
    x = np.abs(e)
    narrow = half < GAUSSIAN_BELOW * s
    h = np.where(narrow, 1.0, half)  # placeholders where the Gaussian form is used
    s_ = np.where(narrow, 1.0, s)
    x_ = np.where(narrow, 0.0, x)
    lp0 = _log_p(np.zeros_like(x_), h, s_)
    lp = _log_p(x_, h, s_)
    g = np.sqrt(np.maximum(2.0 * (lp0 - lp), 0.0))
    # d log P / dx = -(phi(b) - phi(a)) / (s P), in log space
    b, a = (h - x_) / s_, (-h - x_) / s_
    dlp = -(np.exp(-0.5 * b ** 2 - _LOG_SQRT_2PI - lp)
            - np.exp(-0.5 * a ** 2 - _LOG_SQRT_2PI - lp)) / s_
    # at x -> 0: g'(0) = sqrt(-(log P)''(0)) = sqrt(2 h phi(h / s) / (s^3 P(0)))
    slope0 = np.sqrt(2 * h * np.exp(-0.5 * (h / s_) ** 2 - _LOG_SQRT_2PI - lp0) / s_ ** 3)
    small = x_ < 1e-4 * s_
    dg = np.where(small, slope0, -dlp / np.where(g > 0, g, 1.0))
    r = np.where(narrow, e / s, np.sign(e) * np.where(small, slope0 * x_, g))
    d = np.where(narrow, 1.0 / s, dg)
    return r, d
