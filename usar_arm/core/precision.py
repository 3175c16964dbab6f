"""Numbers written with the precision they mean, so that a report regenerates byte for byte on
every CPU.

A fitted value's last bits depend on the BLAS kernels the CPU selects (OpenBLAS picks other
ones on an AMD EPYC than on an Intel Xeon): two machines agree to about 1e-11 relative, not to
the last of 17 digits. So a report keeps what a number means and no more:

- lengths (m), angles (rad) and unitless fractions of one (unit vectors, rotation matrices):
  to 1e-9 of their unit (a nanometre, a nanoradian), far below any figure a robot holds;
- standard deviations and other spreads (keys ``std``, ``sigma*``): three significant digits;
- test statistics and their thresholds (``statistic``, ``threshold``): four significant digits.

A difference of 1e-11 relative crosses one of those rounding boundaries with a probability of
about 1e-11 / 1e-9 per number of order one, and far less for the small offsets a calibration
fits (a tests regenerates the calibrated descriptions under several OpenBLAS kernel sets).
"""

from __future__ import annotations

from typing import Any

DECIMALS = 9
"""Decimal places of a length (m), an angle (rad) or a unitless number: 1 nm, 1 nrad."""
SPREAD_DIGITS = 3
"""Significant digits of a standard deviation or spread."""
STATISTIC_DIGITS = 4
"""Significant digits of a test statistic and its threshold."""


def _significant(value: float, digits: int) -> float:
    return float(f"{value:.{digits}g}")


def meaningful(value: float, key: str | None = None) -> float:
    """``value`` rounded to the precision it means, which the dictionary ``key`` it stands
    under tells (see the module's docstring); negative zero comes out as zero."""
    if key is not None and (key == "std" or key.startswith("sigma")):
        out = _significant(value, SPREAD_DIGITS)
    elif key in ("statistic", "threshold"):
        out = _significant(value, STATISTIC_DIGITS)
    else:
        out = round(value, DECIMALS)
    return out + 0.0


def with_precision(value: Any, key: str | None = None) -> Any:
    """A JSON-ready structure (dicts, lists, tuples, scalars) with every float rounded by
    :func:`meaningful`; a float's key is that of the nearest enclosing dictionary entry."""
    if isinstance(value, float):
        return meaningful(value, key)
    if isinstance(value, dict):
        return {k: with_precision(v, k) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [with_precision(v, key) for v in value]
    return value
