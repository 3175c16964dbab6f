"""Did something move during the readings? A change-point test on the fit's residuals in the
order the readings were taken (a tracker file's rows, a tour's time order).

A base or tool that moves mid-run shifts every later reading by about the same amount; the fit,
which has one base and one tool, splits the difference, so the readings before the move sit on
one side and those after on the other. When the file states no uncertainty the noise is
estimated from the scatter, which such a shift inflates, so the per-reading scores miss it; the
mean residual does not. For each split point k (at least :data:`MIN_SEGMENT` readings on each
side) and each group of numbers (the three positions, the three orientation numbers), the
statistic is

    Z^2(k) = sum over the group's numbers of (mean after - mean before)^2 / (s^2 (1/k + 1/(n-k)))

with s^2 the pooled variance of the residuals about their own segment's mean, inflated by
(1 + rho) / (1 - rho) for the lag-1 autocorrelation rho of the residuals about their overall
mean (consecutive readings on a tour need not be independent; a shift raises rho, which only
makes the test more cautious). Without a shift Z^2(k) / 3 is about F(3, n - 2); the threshold is
3 times its 1 - alpha / (splits x groups) quantile (Bonferroni over every split tried), so the
chance that clean readings are called moved is at most alpha (:data:`ALPHA`). A significant
shift is called a move only when it is also at least as large as one reading's own error (the
group's ``floor``: the norm of a reading's 1-sigma, noise and truncation): over hundreds of
readings a tour's unmodelled structure can make a tenth of a printed step significant (a KR60
tour read 0.3 mrad, statistic 27 against 26, where a printed step is 1 mrad), and a shift
below what one reading can tell does not move the description by more than its readings can.
Measured on 2,000 Gaussian series each (tests/calibrate/test_changepoint.py): 0 % for 20 and for 300
independent readings, 0.05 % for 40 readings with lag-1 autocorrelation 0.5, 0.1 % for 300
with 0.8; none of 12 clean synthetic tracker fits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import f as f_dist

from usar_arm.core.spatial import Array

ALPHA = 0.01
"""Family-wise false-alarm bound of the test over all splits and both groups."""
MIN_SEGMENT = 5
"""Fewest readings on either side of a split."""
MAX_RHO = 0.9
"""Largest lag-1 autocorrelation the variance inflation uses."""


@dataclass(frozen=True)
class ChangePoint:
    """The strongest split of a residual series.

    Attributes:
        index: the first reading after the split (0-based, in the series' order).
        statistic: Z^2 there (see the module); threshold: the Bonferroni bound.
        shift: the mean residual after minus before, per number of the group (m or rad).
        group: ``position`` or ``orientation``. floor: the smallest shift called a move (m or
        rad; see the module).
    """

    index: int
    statistic: float
    threshold: float
    shift: tuple[float, ...]
    group: str
    floor: float = 0.0

    @property
    def detected(self) -> bool:
        """Whether the split is significant and its shift at least the floor."""
        return self.statistic > self.threshold and self.size >= self.floor

    @property
    def size(self) -> float:
        """The shift's norm (m or rad)."""
        return float(np.linalg.norm(self.shift))


def split_statistic(x: Array, min_segment: int = MIN_SEGMENT) -> tuple[Array, Array]:
    """Z^2 (K,) at every split k = min_segment .. n - min_segment of a series x (n, d), and the
    mean shifts there (K, d): all splits at once from prefix sums."""
    x = np.asarray(x, float)
    n = len(x)
    ks = np.arange(min_segment, n - min_segment + 1)
    if len(ks) == 0:
        return np.zeros(0), np.zeros((0, x.shape[1]))
    zero = np.zeros((1, x.shape[1]))
    c1 = np.vstack([zero, np.cumsum(x, axis=0)])             # c1[j] = sum of x[:j]
    c2 = np.vstack([zero, np.cumsum(x ** 2, axis=0)])
    k = ks[:, None].astype(float)
    before, after = c1[ks] / k, (c1[n] - c1[ks]) / (n - k)
    ss = c2[n] - k * before ** 2 - (n - k) * after ** 2      # about each segment's own mean
    var = ss / max(n - 2, 1) * inflation(x)
    diff = after - before
    stats = (diff ** 2 / np.maximum(var * (1 / k + 1 / (n - k)), 1e-300)).sum(axis=1)
    return stats, diff


def inflation(x: Array) -> Array:
    """(1 + rho) / (1 - rho) per column of x (n, d), rho the lag-1 autocorrelation about the
    series' mean, clipped to [0, :data:`MAX_RHO`] (a shift raises it: conservative)."""
    r = x - x.mean(axis=0)
    ss = (r ** 2).sum(axis=0)
    rho = np.clip((r[1:] * r[:-1]).sum(axis=0) / np.where(ss > 0, ss, 1.0), 0.0, MAX_RHO)
    out: Array = (1 + rho) / (1 - rho)
    return out


def threshold(n: int, d: int, alpha: float, tests: int) -> float:
    """The Bonferroni threshold of Z^2 for a group of d numbers over n readings: d times the
    1 - alpha / tests quantile of F(d, n - 2) (the variance is estimated)."""
    return float(d * f_dist.isf(alpha / tests, d, max(n - 2, 1)))


def change_point(groups: dict[str, Array], alpha: float = ALPHA,
                 min_segment: int = MIN_SEGMENT, floors: dict[str, float] | None = None
                 ) -> ChangePoint | None:
    """The strongest split over the residual series of ``groups`` (name -> (n, d), rows in
    reading order; a group with too few rows is skipped), judged against the Bonferroni
    threshold and the group's ``floors`` (m or rad; 0 when not given); None when no group is
    long enough to split."""
    usable = {g: x for g, x in groups.items() if len(x) >= 2 * min_segment}
    splits = sum(len(x) - 2 * min_segment + 1 for x in usable.values())
    best: ChangePoint | None = None
    for group, x in usable.items():
        stats, shifts = split_statistic(np.asarray(x, float), min_segment)
        k = int(np.argmax(stats))
        found = ChangePoint(k + min_segment, float(stats[k]),
                            threshold(len(x), x.shape[1], alpha, splits),
                            tuple(float(v) for v in shifts[k]), group,
                            (floors or {}).get(group, 0.0))
        if best is None or found.statistic / found.threshold > best.statistic / best.threshold:
            best = found
    return best
