"""The numeric pieces of the IK (usar_arm/planning/ik_numeric.py): the least-squares step equals
numpy's ``lstsq`` (its LAPACK routine and cut-off, without its wrapping), on full-rank and
rank-deficient systems alike; and the Newton search held on the limits gives up as soon as it
settles on a residual, not after its whole budget, where the target lies beyond a limit, while
it still reaches a solution that sits on a limit."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from usar_arm.planning import ik_numeric
from usar_arm.planning.robot import Robot

FLOATS = st.floats(-10.0, 10.0, allow_nan=False, width=64)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 6).flatmap(lambda n: st.tuples(arrays(float, (6, n), elements=FLOATS),
                                                    arrays(float, 6, elements=FLOATS))),
       st.integers(0, 5))
def test_the_least_squares_step_is_numpys(system: tuple[np.ndarray, np.ndarray],
                                          repeat: int) -> None:
    a, b = system
    if a.shape[1] > 1 and repeat:  # a repeated column: rank deficient, minimum norm wanted
        a[:, repeat % a.shape[1]] = a[:, 0]
    expected = np.linalg.lstsq(a, b, rcond=None)[0]
    assert np.allclose(ik_numeric._lstsq(a.copy(), b.copy()), expected, rtol=1e-9, atol=1e-9)


def _count_evaluations(kr60: Robot, q: np.ndarray, target: np.ndarray) -> tuple[object, int]:
    ik = kr60.ik_solver()
    kin = ik.numeric.kin
    calls = [0]
    original = kin.local_error

    def counted(*args: object) -> object:
        calls[0] += 1
        return original(*args)

    kin.local_error = counted  # type: ignore[method-assign]
    try:
        found = ik.numeric.clamped(q, target[:3, :3], target[:3, 3])
    finally:
        del kin.local_error
    return found, calls[0]


def test_held_on_a_limit_the_target_lies_beyond_it_gives_up_early(kr60: Robot) -> None:
    # joint 5 at 2.4 rad, 0.324 rad past its upper limit: held there, no configuration reaches
    # the pose; the search settles on its least-squares residual and stops within a few steps
    # instead of running its 2 x newton_steps
    q = np.array([0.3, -0.3, 0.3, 0.5, 2.4, 0.3])
    target = kr60.kinematics.frame_pose(q, "tool0")
    found, evaluations = _count_evaluations(kr60, q, target)
    assert found is None
    budget = 2 * kr60.ik_solver().options.newton_steps
    assert evaluations <= ik_numeric.STALL_STEPS + 3 < budget


def test_held_on_a_limit_a_solution_on_it_is_still_reached(kr60: Robot) -> None:
    q = np.array([0.0, 0.0, 2.757, -2.0, 1.0, 2.0])  # joint 3 on its upper limit
    target = kr60.kinematics.frame_pose(q, "tool0")
    start = q + np.array([0.01, -0.01, 0.015, 0.01, 0.0, -0.01])  # joint 3 0.015 outside
    found, _ = _count_evaluations(kr60, start, target)
    assert found is not None
    assert np.max(np.abs(np.array(found.q) - q)) < 1e-5  # type: ignore[attr-defined]
