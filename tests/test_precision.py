"""Numbers with the precision they mean: what a report keeps of a float, by its key."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from usar_arm.core.precision import DECIMALS, meaningful, with_precision

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)


@given(finite)
def test_a_length_or_angle_is_kept_to_a_nanounit_and_rounding_again_changes_nothing(
        x: float) -> None:
    kept = meaningful(x, "origin_xyz_m")
    assert abs(kept - x) <= 0.5 * 10.0 ** -DECIMALS + 1e-12 * abs(x)
    assert meaningful(kept, "origin_xyz_m") == kept


@given(st.floats(min_value=1e-12, max_value=1e3))
def test_a_standard_deviation_keeps_three_significant_digits(x: float) -> None:
    kept = meaningful(x, "std")
    assert math.isclose(kept, x, rel_tol=5e-3)
    assert kept == float(f"{kept:.3g}")


def test_statistics_keep_four_digits_and_negative_zero_becomes_zero() -> None:
    assert meaningful(10.532631444, "statistic") == 10.53
    assert meaningful(25.603622355, "threshold") == 25.6
    assert math.copysign(1.0, meaningful(-1e-12, "shift")) == 1.0


def test_a_tiny_blas_difference_disappears_from_what_is_written() -> None:
    """The fitted tool offset of the KR60 as two CPUs computed it (11th digit)."""
    xeon, epyc = -5.69436315526e-06, -5.69436315522e-06
    assert with_precision({"value": xeon}) == with_precision({"value": epyc})
    assert with_precision({"std": 2.62924548582e-05}) == {"std": 2.63e-05}


def test_nested_structures_take_the_key_of_their_nearest_entry() -> None:
    doc = {"base": [[0.999999979117, 1.5e-10]], "sigma_m_max": 0.000102238378835,
           "label": "t=1.7380 s", "rank": 30, "converged": True}
    assert with_precision(doc) == {"base": [[0.999999979, 0.0]], "sigma_m_max": 0.000102,
                                   "label": "t=1.7380 s", "rank": 30, "converged": True}
