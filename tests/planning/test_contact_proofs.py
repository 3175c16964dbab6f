"""Contact proofs of the compiled broadphase beyond the balls on a cylinder's axis, and the box
that clears what a cylinder obstacle's capsule cannot (usar_arm.planning.gaps,
usar_arm.planning.bounds).

Each case is placed by the test's own geometry (a tilted cylinder's lowest point is
``h |z_z| + r sqrt(1 - z_z^2)`` below its centre) and judged by python-fcl's primitives: the
kernel may say CONTACT only where FCL sees a contact and CLEAR only where it sees none, and it
must decide where the depth is clear of the proof margin (0.1 mm): a rim 0.3 mm deep is proven,
a rim 1 um above a face is cleared.
"""

from __future__ import annotations

import fcl
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from tests.planning.test_bounds import _fcl_hit, _pose
from usar_arm.planning import bounds, gaps

CLEAR, CONTACT, UNDECIDED = bounds.CLEAR, bounds.CONTACT, bounds.UNDECIDED
DECISIVE = 3e-4
"""A rim this deep (m) is proven in contact: the proof's ball (2 margins) sits at most
sqrt(2) of its radius behind the rim, so 0.18 mm is the worst case."""


def _link_obstacle(link: np.ndarray, r: float, h: float, kind: int, obstacle: np.ndarray,
                   size: np.ndarray) -> int:
    verdicts = bounds.classify(np.ascontiguousarray(link[None, None, :3, :]), np.array([r]),
                               np.array([h]), np.zeros((0, 2), np.int64),
                               np.array([[0, 0]], np.int64), np.array([kind], np.int64),
                               np.ascontiguousarray(obstacle[None, :3, :]),
                               np.asarray(size, float).reshape(1, 3), bounds.EPS, bounds.MARGIN)
    return int(verdicts[0, 0])


def _link_link(a: np.ndarray, ra: float, ha: float, b: np.ndarray, rb: float, hb: float) -> int:
    world = np.ascontiguousarray(np.stack([a, b])[None, :, :3, :])
    verdicts = bounds.classify(world, np.array([ra, rb]), np.array([ha, hb]),
                               np.array([[0, 1]], np.int64), np.zeros((0, 2), np.int64),
                               np.zeros(0, np.int64), np.zeros((0, 3, 4)), np.zeros((0, 3)),
                               bounds.EPS, bounds.MARGIN)
    return int(verdicts[0, 0])


def _resting(rotvec: list[float], xy: list[float], r: float, h: float, top: float,
             depth: float) -> np.ndarray:
    """A cylinder (radius r, half-length h) turned by ``rotvec`` whose lowest point is
    ``depth`` below the plane z = ``top`` (negative: above it), its centre over ``xy``."""
    pose = _pose(np.array(rotvec), np.zeros(3))
    zz = abs(pose[2, 2])
    lowest = h * zz + r * np.sqrt(max(0.0, 1.0 - zz * zz))
    pose[:3, 3] = [xy[0], xy[1], top - depth + lowest]
    return pose


def _judged(verdict: int, truth: bool, depth: float, cleared: bool = True) -> None:
    """The verdict agrees with FCL and decides where it should (``cleared``: a rim above the
    face is to be cleared, not only proven free of contact)."""
    if verdict == CONTACT:
        assert truth, "a contact was proven that python-fcl does not see"
    if verdict == CLEAR:
        assert not truth, "a pair in contact was cleared"
    if depth >= DECISIVE:
        assert verdict == CONTACT, f"a rim {depth * 1e3:.3f} mm deep was left to FCL"
    if depth <= -1e-6 and cleared:
        assert verdict == CLEAR, f"a rim {-depth * 1e6:.1f} um above a face was not cleared"


SHAPES = dict(rotvec=st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3),
              xy=st.lists(st.floats(-0.1, 0.1), min_size=2, max_size=2),
              r=st.floats(0.01, 0.15), h=st.floats(0.01, 0.15),
              depth=st.one_of(st.floats(-2e-3, 2e-3), st.sampled_from([DECISIVE, -1e-6])))


OBSTACLES = {  # kind, size, FCL's shape, the height of the face the rim dips into
    "box": (bounds.BOX, np.array([1.0, 1.0, 0.5]), fcl.Box(2.0, 2.0, 1.0), 0.5),
    # a wide cylinder: its capsule reaches 0.5 m above its flat end, only its box clears there
    "cylinder": (bounds.CAPSULE, np.array([0.5, 0.1, 0.0]), fcl.Cylinder(0.5, 0.2), 0.1),
}


@pytest.mark.parametrize("obstacle", sorted(OBSTACLES))
@settings(max_examples=300, deadline=None)
@given(**SHAPES)
def test_a_rim_on_an_obstacles_face_is_proven_or_cleared_as_fcl_sees_it(
        obstacle: str, rotvec: list[float], xy: list[float], r: float, h: float,
        depth: float) -> None:
    kind, size, shape, top = OBSTACLES[obstacle]
    link = _resting(rotvec, xy, r, h, top, depth)
    verdict = _link_obstacle(link, r, h, kind, np.eye(4), size)
    truth = _fcl_hit(fcl.Cylinder(r, 2 * h), link, shape, np.eye(4))
    _judged(verdict, truth, depth)


@settings(max_examples=300, deadline=None)
@given(**SHAPES)
def test_a_rim_on_another_links_flat_end_is_proven_as_fcl_sees_it(
        rotvec: list[float], xy: list[float], r: float, h: float, depth: float) -> None:
    """Between two links only the proof is asked for: their capsules clear, not their boxes."""
    radius, half = 0.5, 0.1
    link = _resting(rotvec, xy, r, h, half, depth)
    verdict = _link_link(link, r, h, np.eye(4), radius, half)
    truth = _fcl_hit(fcl.Cylinder(r, 2 * h), link, fcl.Cylinder(radius, 2 * half), np.eye(4))
    _judged(verdict, truth, depth, cleared=False)


def test_a_link_through_a_wide_floor_far_from_its_centre_is_proven() -> None:
    """A thin link crossing a 6 m floor slab 3 m from the slab's centre: the axis point nearest
    the slab's centre is far above it, the one inside the slab proves the contact."""
    half = np.array([3.0, 3.0, 0.025])
    link = _pose(np.array([0.5, 0.2, 0.0]), np.array([2.5, -2.0, -0.05]))
    assert _fcl_hit(fcl.Cylinder(0.01, 0.6), link, fcl.Box(*(2 * half)), np.eye(4))
    assert _link_obstacle(link, 0.01, 0.3, bounds.BOX, np.eye(4), half) == CONTACT
    assert gaps.inner_box_contact(link[:3, 3].copy(), link[:3, 2].copy(), 0.01, 0.29,
                                  np.zeros(3), np.eye(3), half, bounds.MARGIN, np.empty(3))


def test_a_link_whose_balls_graze_a_box_is_proven_from_the_nearest_axis_point() -> None:
    """The axis passes 5 mm beside a box's edge, outside it; balls of 1 cm on the axis reach
    in, but only near the axis point closest to the edge (found by the search along the axis,
    not at its ends or at the point nearest the box's centre)."""
    half = np.array([0.5, 0.5, 0.5])
    edge = np.array([0.5, 0.5, 0.0])
    direction = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)  # along the edge's diagonal
    centre = edge + 0.005 * np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0) + 0.2 * direction
    pose = np.eye(4)
    pose[:3, :3] = Rotation.align_vectors([direction], [[0.0, 0.0, 1.0]])[0].as_matrix()
    pose[:3, 3] = centre
    assert _fcl_hit(fcl.Cylinder(0.01, 0.8), pose, fcl.Box(*(2 * half)), np.eye(4))
    assert _link_obstacle(pose, 0.01, 0.4, bounds.BOX, np.eye(4), half) == CONTACT


def test_a_link_over_a_cylinders_flat_end_is_cleared_where_its_capsule_is_not() -> None:
    """A link lying 1 cm above a wide cylinder's flat end, near its rim: the obstacle's
    capsule (radius 0.3 m about its 0.1 m axis) holds the link, its box does not."""
    link = _pose(np.array([0.0, np.pi / 2, 0.0]), np.array([0.25, 0.0, 0.1 + 0.01 + 0.02]))
    size = np.array([0.3, 0.05, 0.0])
    assert not _fcl_hit(fcl.Cylinder(0.02, 0.2), link, fcl.Cylinder(0.3, 0.1), np.eye(4))
    assert _link_obstacle(link, 0.02, 0.1, bounds.CAPSULE, np.eye(4), size) == CLEAR
