"""The OMPL adapter's search, on a plane with a wall and a narrow door (no robot involved).

RRT-Connect grows its trees with OMPL's default step (a fifth of the space's extent) for
``WIDE_EDGES`` edge checks, then with steps of ``NARROW`` of the extent: these tests watch the
edges the planner asks the motion validator about.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import numpy as np
import pytest

from usar_arm.core.errors import NoPathError
from usar_arm.core.spatial import Array
from usar_arm.planning import ompl_adapter
from usar_arm.planning.ompl_adapter import NARROW, WIDE_EDGES, OmplOptions, plan_path, reseed

LOWER, UPPER = np.zeros(2), np.full(2, 10.0)
EXTENT = math.hypot(10.0, 10.0)
START, GOAL = np.array([1.0, 1.0]), np.array([9.0, 1.5])


def _free(q: Array) -> bool:
    """A wall at 4.9 <= x <= 5.1 with a door at 8.6 <= y <= 9.0."""
    return not (4.9 <= q[0] <= 5.1 and not 8.6 <= q[1] <= 9.0)


class Recorder:
    """The validity callbacks OMPL calls, and the lengths of the edges it asked about."""

    def __init__(self, free: Callable[[Array], bool] = _free) -> None:
        self.edges: list[float] = []
        self.free = free

    def state_valid(self, q: Array) -> bool:
        return self.free(q)

    def segment_free(self, a: Array, b: Array, steps: int) -> bool:
        self.edges.append(float(np.linalg.norm(b - a)))
        return all(self.free(a + (b - a) * t) for t in np.linspace(0.0, 1.0, steps + 1))


def _plan(seed: int, recorder: Recorder, planner: str = "RRTConnect") -> Array:
    reseed(seed)
    options = OmplOptions(planner=planner, time_limit=5.0, resolution=0.01, simplify=False)
    return plan_path(LOWER, UPPER, START, GOAL, recorder.state_valid, recorder.segment_free,
                     options).waypoints


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_through_a_narrow_door_the_steps_shrink_after_the_wide_edges(
        seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ompl_adapter, "WIDE_EDGES", 10)  # switch before the door is found
    recorder = Recorder()
    path = _plan(seed, recorder)
    narrow = NARROW * EXTENT + 1e-9
    wide = [k for k, length in enumerate(recorder.edges) if length > narrow]
    assert len(recorder.edges) > wide[-1] + 1, "the door was found with the wide steps"
    assert max(recorder.edges) <= 0.2 * EXTENT + 1e-9  # OMPL's default step
    # the switch comes between two iterations: one extension and a connection, which crosses
    # the plane in at most five default steps
    assert 10 <= wide[-1] + 1 <= 10 + 6
    for a, b in itertools.pairwise(path):  # the path itself goes through the door
        assert Recorder().segment_free(a, b, 1000)
    np.testing.assert_array_equal(path[[0, -1]], [START, GOAL])


def test_the_switch_counts_edges_so_a_seeded_plan_is_reproducible(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ompl_adapter, "WIDE_EDGES", 10)
    first, second = Recorder(), Recorder()
    np.testing.assert_array_equal(_plan(7, first), _plan(7, second))
    assert first.edges == second.edges


def test_an_open_plane_is_crossed_with_wide_steps_only() -> None:
    recorder = Recorder(free=lambda q: True)
    reseed(3)
    plan_path(LOWER, UPPER, START, GOAL, recorder.state_valid, recorder.segment_free,
              OmplOptions(time_limit=5.0, simplify=False))
    assert 0 < len(recorder.edges) < WIDE_EDGES


def test_other_planners_keep_their_own_step(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ompl_adapter, "WIDE_EDGES", 10)
    recorder = Recorder()
    _plan(0, recorder, planner="RRT")
    assert max(recorder.edges[10:], default=0.0) > 2 * NARROW * EXTENT


def test_a_walled_off_goal_is_a_no_path_error_within_the_budget(monkeypatch: pytest.MonkeyPatch
                                                                ) -> None:
    monkeypatch.setattr(ompl_adapter, "WIDE_EDGES", 5)
    reseed(0)
    with pytest.raises(NoPathError):
        plan_path(LOWER, UPPER, START, GOAL, lambda q: q[0] < 4.9 or q[0] > 5.1,
                  lambda a, b, steps: bool(max(a[0], b[0]) < 4.9 or min(a[0], b[0]) > 5.1),
                  OmplOptions(time_limit=0.3, simplify=False))
