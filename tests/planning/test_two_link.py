"""The elbow both closed forms share (usar_arm.planning.two_link): its angles carry the point to
the target by the plane's own rotation (no code shared with the solve), the compiled kernel
gives the plain-Python reference's bits, and a target beyond the reach gets no angles."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.planning import two_link
from usar_arm.planning.two_link import TwoLink, elbow

U = (0.0, 1.0, 0.0)
"""Joints 2 and 3 turn about y, as on a KUKA."""


def _arm(flip: bool) -> TwoLink:
    return TwoLink.of(U, (0.0, -1.0, 0.0) if flip else U, (0.35, 0.0, 0.815),
                      (0.35, 0.0, 1.665), (1.17, 0.0, 1.62), 1e-3)


def _carried(arm: TwoLink, q2: float, q3: float) -> np.ndarray:
    """Where E lands in the plane: c turned by q2, e by q2 + t3 (2-D rotations, m)."""
    t3 = q3 * arm.s3

    def turn(v: tuple[float, float], a: float) -> np.ndarray:
        return np.array([math.cos(a) * v[0] - math.sin(a) * v[1],
                         math.sin(a) * v[0] + math.cos(a) * v[1]])

    return np.array(arm.p2) + turn(arm.p3p2, q2) + turn(arm.e, q2 + t3)


@settings(max_examples=200, deadline=None)
@given(st.floats(-math.pi, math.pi), st.floats(-2.5, 2.5), st.booleans())
def test_both_elbows_carry_the_point_to_the_target(q2: float, q3: float, flip: bool) -> None:
    arm = _arm(flip)
    target = _carried(arm, q2, q3)
    found = arm.angles(float(target[0]), float(target[1]))
    assert len(found) == 2
    for a2, a3 in found:
        assert np.allclose(_carried(arm, a2, a3), target, atol=1e-9)
    assert any(abs(math.remainder(a3 - q3, 2 * math.pi)) < 1e-6 for _, a3 in found)


@settings(max_examples=200, deadline=None)
@given(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0), st.booleans())
def test_the_kernel_gives_the_references_bits(x: float, y: float, flip: bool) -> None:
    arm = _arm(flip)
    c = np.concatenate([np.full(5, np.nan), arm.packed()])  # the block at an offset
    out = np.empty((2, 2))
    count = elbow(c, 5, x, y, out)
    assert [tuple(row) for row in out[:count]] == arm.angles(x, y)


def test_beyond_the_reach_and_its_slack_there_are_no_angles() -> None:
    arm = _arm(False)
    stretched = math.sqrt(arm.l2sq) + math.sqrt(arm.l3sq)  # m
    far = np.array(arm.p2) + (stretched + 0.01) * np.array([1.0, 0.0])
    near = np.array(arm.p2) + (stretched - 1e-6) * np.array([1.0, 0.0])
    assert len(arm.angles(float(near[0]), float(near[1]))) == 2
    assert arm.angles(float(far[0]), float(far[1])) == []
    assert elbow(np.asarray(arm.packed()), 0, float(far[0]), float(far[1]), np.empty((2, 2))) == 0
    assert two_link.SIZE == len(arm.packed())
