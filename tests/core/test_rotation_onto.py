"""usar_arm.core.spatial.rotation_onto, the smallest rotation taking one axis onto a direction
(a flange's x, a tool link's z): a rotation, it lands where asked, it turns about their common
normal only, and it makes the half turn it is told to where the two are opposite."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from usar_arm.core.spatial import rotation_onto

AXES = [np.eye(3)[i] for i in range(3)]


@given(st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3), st.integers(0, 2))
def test_it_takes_the_axis_onto_the_direction_turning_about_their_normal(
        v: list[float], i: int) -> None:
    d = np.array(v)
    if np.linalg.norm(d) < 1e-3 or np.linalg.norm(d / np.linalg.norm(d) + AXES[i]) < 1e-3:
        return  # no direction, or (nearly) opposite: the half turn's test
    r = rotation_onto(AXES[i], d, AXES[(i + 1) % 3])
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-12) and np.isclose(np.linalg.det(r), 1.0)
    # within 1.4 urad of the axis (1 - cos < 1e-12) it is the identity
    assert np.allclose(r @ AXES[i], d / np.linalg.norm(d), atol=1.5e-6)
    normal = np.cross(AXES[i], d)
    if np.linalg.norm(normal) > 1e-6:
        assert np.allclose(r @ normal, normal, atol=1e-12)  # the rotation's axis


def test_opposite_it_makes_the_half_turn_it_is_told() -> None:
    assert np.array_equal(rotation_onto((1.0, 0.0, 0.0), (-2.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
                          np.diag([-1.0, -1.0, 1.0]))
    assert np.array_equal(rotation_onto((0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (1.0, 0.0, 0.0)),
                          np.diag([1.0, -1.0, -1.0]))
    assert np.array_equal(rotation_onto((0.0, 0.0, 1.0), (0.0, 0.0, 5.0), (1.0, 0.0, 0.0)),
                          np.eye(3))
