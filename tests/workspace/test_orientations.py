"""The orientation sets: deterministic, unit, spread over SO(3) better than random draws, and
restricted to a cone when asked."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.workspace.orientations import (
    geodesic,
    orientation_set,
    quaternions_to_matrices,
    super_fibonacci,
)


def _random_quaternions(n: int, rng: np.random.Generator) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _covering_radius(points: np.ndarray, probes: np.ndarray) -> float:
    """The largest distance (rad) from a probe rotation to its nearest point of the set."""
    return float(max(geodesic(points, p).min() for p in probes))


@given(st.integers(1, 400))
@settings(max_examples=40, deadline=None)
def test_every_set_is_unit_quaternions_with_a_non_negative_w(n: int) -> None:
    q = super_fibonacci(n)
    assert q.shape == (n, 4)
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0)
    assert np.all(q[:, 0] >= 0)
    r = quaternions_to_matrices(q)
    assert np.allclose(r @ r.transpose(0, 2, 1), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(r), 1.0)


def test_the_set_is_the_same_every_time() -> None:
    assert np.array_equal(orientation_set(64).quaternions, orientation_set(64).quaternions)
    assert np.array_equal(orientation_set(32, 30.0).quaternions,
                          orientation_set(32, 30.0).quaternions)


@pytest.mark.parametrize("n", [16, 64, 256])
def test_the_spiral_covers_so3_better_than_random_sets_of_its_size(n: int) -> None:
    rng = np.random.default_rng(1)
    probes = _random_quaternions(3000, rng)
    spiral = _covering_radius(super_fibonacci(n), probes)
    randoms = [_covering_radius(_random_quaternions(n, rng), probes) for _ in range(10)]
    assert spiral < min(randoms), (spiral, randoms)
    # no two orientations of the set are the same rotation
    q = super_fibonacci(n)
    nearest = min(float(np.sort(geodesic(q, q[i]))[1]) for i in range(n))
    assert nearest > 0.1 / n ** (1 / 3)


@pytest.mark.parametrize(("count", "cone"), [(16, 30.0), (64, 30.0), (40, 90.0)])
def test_a_cone_keeps_the_tool_axis_within_it_and_gives_the_count_asked(count: int,
                                                                          cone: float) -> None:
    s = orientation_set(count, cone, (0.0, 0.0, -1.0))
    assert len(s) == count
    z = s.matrices()[:, :, 2]
    angle = np.degrees(np.arccos(np.clip(-z[:, 2], -1, 1)))
    assert angle.max() <= cone + 1e-9
    # spread: the tool axes reach out to the cone's rim and turn about themselves
    assert angle.max() > 0.6 * cone
    roll = np.arctan2(s.matrices()[:, 1, 0], s.matrices()[:, 0, 0])
    assert np.ptp(roll) > math.pi


def test_bad_requests_say_what_was_expected() -> None:
    with pytest.raises(ValueError, match="at least 1"):
        orientation_set(0)
    with pytest.raises(ValueError, match=r"\(0, 180\]"):
        orientation_set(8, 200.0)
    with pytest.raises(ValueError, match="zero vector"):
        orientation_set(8, 30.0, (0.0, 0.0, 0.0))
