"""The likelihood quantisation model's residual is -2 log of the printed number's probability,
and joint values printed rounded (ASTA) stand for their own middle."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from usar_arm.calibrate import likelihood
from usar_arm.calibrate import quantised as qm
from usar_arm.calibrate.measurements import Measurement


def test_the_likelihood_residual_is_the_log_probability_of_the_printed_number() -> None:
    e = np.array([[0.0, 3e-4, -7e-4, 2e-3, -5e-3, 1e-5]])
    half, s = np.full_like(e, 5e-4), np.full_like(e, 1e-4)
    r, d = likelihood.residuals(e, half, s)

    def p(x: np.ndarray) -> np.ndarray:
        return norm.cdf((half - x) / s) - norm.cdf((-half - x) / s)

    near = [0, 1, 2, 3, 5]
    with np.errstate(divide="ignore"):
        exact = np.log(p(0 * e)) - np.log(p(e))
    np.testing.assert_allclose(r[0, near] ** 2 / 2, exact[0, near], rtol=1e-6, atol=1e-12)
    # far outside (P underflows in double): -log P(e) -> ((|e| - h) / s)^2 / 2 + log(...)
    far = (5e-3 - 5e-4) / 1e-4
    tail = far ** 2 / 2 + np.log(far * np.sqrt(2 * np.pi))  # Mills ratio, to O(1 / far^2)
    assert r[0, 4] ** 2 / 2 == pytest.approx(tail + np.log(p(0 * e)[0, 4]), rel=1e-3)
    assert np.all(np.sign(r) == np.sign(e))
    step = 1e-9
    numeric = (likelihood.residuals(e + step, half, s)[0]
               - likelihood.residuals(e - step, half, s)[0]) / (2 * step)
    np.testing.assert_allclose(d, numeric, rtol=1e-5, atol=1e-3)
    # no interval: the plain Gaussian residual
    r, d = likelihood.residuals(e, np.zeros_like(e), s)
    np.testing.assert_allclose(r, e / s)
    np.testing.assert_allclose(d, 1 / s)


def test_rounded_joint_values_stand_for_their_own_middle() -> None:
    printed = np.array([0.1234, -0.5, 0.0])
    rounded = Measurement(printed, np.zeros(3), None, step_q=1e-4, q_rounded=True)
    truncated = Measurement(printed, np.zeros(3), None, step_q=1e-4)
    np.testing.assert_allclose(qm.joint_midpoints([rounded])[0], printed)
    np.testing.assert_allclose(qm.joint_midpoints([truncated])[0],
                               [0.12345, -0.50005, 0.0])
