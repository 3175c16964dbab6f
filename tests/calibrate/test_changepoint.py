"""The moved-mid-run test: its statistic is the one documented, it finds a step where it is,
and its false-alarm rate on clean readings is measured here (the figure docs/calibration.md
quotes)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from tests.calibrate.synthetic import KR60, perturbed, random_q, readings
from usar_arm.calibrate.changepoint import ALPHA, change_point, split_statistic
from usar_arm.calibrate.identification import identify
from usar_arm.core.spatial import transform_from_xyz_rpy
from usar_arm.planning.kinematics import KinematicModel

NOMINAL = KinematicModel(KR60)


def _brute(x: np.ndarray, k: int) -> float:
    """Z^2 at split k, written out: the segments' means, the pooled variance about them, the
    lag-1 autocorrelation about the overall mean (clipped to [0, 0.9])."""
    n = len(x)
    before, after = x[:k], x[k:]
    pooled = (((before - before.mean(0)) ** 2).sum(0) + ((after - after.mean(0)) ** 2).sum(0)) \
        / (n - 2)
    r = x - x.mean(0)
    rho = np.clip((r[1:] * r[:-1]).sum(0) / (r ** 2).sum(0), 0.0, 0.9)
    var = pooled * (1 + rho) / (1 - rho)
    return float(((after.mean(0) - before.mean(0)) ** 2 / (var * (1 / k + 1 / (n - k)))).sum())


def test_the_statistic_is_the_documented_one_at_every_split() -> None:
    rng = np.random.default_rng(1)
    x = rng.normal(size=(40, 3))
    x[22:] += [0.4, 0.0, -0.2]
    stats, shifts = split_statistic(x)
    for i, k in enumerate(range(5, 36)):
        assert stats[i] == pytest.approx(_brute(x, k), rel=1e-10)
        np.testing.assert_allclose(shifts[i], x[k:].mean(0) - x[:k].mean(0), atol=1e-12)


def test_a_step_is_found_where_it_is_and_its_size_measured() -> None:
    rng = np.random.default_rng(2)
    x = rng.normal(0.0, 0.05, (120, 3))
    x[37:, 0] += 1.0
    found = change_point({"position": x, "orientation": rng.normal(0.0, 0.05, (120, 3))})
    assert found is not None and found.detected and found.group == "position"
    assert found.index == 37 and found.size == pytest.approx(1.0, abs=0.05)


def test_a_significant_shift_smaller_than_one_reading_s_error_is_not_a_move() -> None:
    """Over 400 readings a 0.3-step shift is highly significant; below the floor (one
    reading's own 1-sigma) it is reported, not called a move; the same shift is a move when
    the readings' error is smaller than it."""
    rng = np.random.default_rng(4)
    x = rng.normal(0.0, 0.05, (400, 3))
    x[200:, 0] += 0.3
    below = change_point({"orientation": x}, floors={"orientation": 0.5})
    assert below is not None and below.statistic > 5 * below.threshold
    assert not below.detected and below.size == pytest.approx(0.3, abs=0.03)
    above = change_point({"orientation": x}, floors={"orientation": 0.2})
    assert above is not None and above.detected and above.index == 200


def _ar1(rng: np.random.Generator, n: int, rho: float) -> np.ndarray:
    """(n, 6) independent AR(1) columns of unit variance and lag-1 autocorrelation rho."""
    e = rng.normal(size=(n, 6)) * np.sqrt(1 - rho ** 2)
    return lfilter([1.0], [1.0, -rho], e, axis=0)


@pytest.mark.parametrize(("n", "rho"), [(20, 0.0), (40, 0.5), (300, 0.0), (300, 0.8)])
def test_clean_series_are_called_moved_less_often_than_alpha(n: int, rho: float) -> None:
    """Measured over 2,000 clean series each (Gaussian, independent or autocorrelated): 0 %,
    0.05 %, 0 %, 0.1 % against the 1 % bound (Bonferroni over the splits is conservative)."""
    rng = np.random.default_rng(n + int(10 * rho))
    alarms = 0
    for _ in range(2000):
        x = _ar1(rng, n, rho)
        found = change_point({"position": x[:, :3], "orientation": x[:, 3:]})
        alarms += bool(found is not None and found.detected)
    assert alarms / 2000 <= ALPHA / 2, f"{alarms / 20:.2f} %"


def test_clean_tracker_files_without_stated_noise_are_not_called_moved() -> None:
    """Twelve clean synthetic tracker runs (50 readings, 0.05 mm / 0.05 mrad noise, no sigma
    column): every fit is consistent."""
    base = transform_from_xyz_rpy([0.002, -0.001, 0.0015], [0.003, -0.002, 0.004])
    for seed in range(12):
        data = readings(perturbed(KR60, 40 + seed), "tool0", base,
                        random_q(NOMINAL, 50, 60 + seed), seed, sigma_m=5e-5, sigma_rad=5e-5,
                        state_sigma=False)
        cal = identify(KR60, "tool0", data, None)
        assert cal.consistent and cal.change is not None and not cal.change.detected, \
            (seed, cal.problems)
