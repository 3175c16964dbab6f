"""The vectorised sampler of Ruckig profiles equals Ruckig's own ``at_time``.

Ruckig is the reference here: it evaluates its own profiles one time at a time in C++; the
sampler evaluates every time at once from the profiles' constant-jerk phases. Random problems
cover brake pre-trajectories (start velocity above the limit), non-zero target velocities and
the three synchronisation modes.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from ruckig import InputParameter, Result, Ruckig, Synchronization, Trajectory

from usar_arm.control.timing import profile_states

SYNC = [Synchronization.Time, Synchronization.Phase, Synchronization.No]


def _problem(seed: int, dof: int, sync: int, moving_target: bool) -> Trajectory:
    rng = np.random.default_rng(seed)
    otg, inp = Ruckig(dof), InputParameter(dof)
    vmax = rng.uniform(0.5, 3.0, dof)
    inp.current_position = rng.uniform(-2, 2, dof).tolist()
    inp.target_position = rng.uniform(-2, 2, dof).tolist()
    inp.current_velocity = (rng.uniform(-1.5, 1.5, dof) * vmax).tolist()
    inp.target_velocity = (rng.uniform(-0.9, 0.9, dof) * vmax * moving_target).tolist()
    inp.current_acceleration = [0.0] * dof
    inp.target_acceleration = [0.0] * dof
    inp.max_velocity = vmax.tolist()
    inp.max_acceleration = rng.uniform(1, 6, dof).tolist()
    inp.max_jerk = rng.uniform(3, 40, dof).tolist()
    inp.synchronization = SYNC[sync]
    traj = Trajectory(dof)
    assert otg.calculate(inp, traj) in (Result.Working, Result.Finished)
    return traj


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**31), dof=st.integers(1, 7), sync=st.integers(0, 2),
       moving_target=st.booleans())
def test_sampler_equals_ruckig_at_every_time(seed: int, dof: int, sync: int,
                                             moving_target: bool) -> None:
    traj = _problem(seed, dof, sync, moving_target)
    times = np.linspace(0.0, traj.duration, 61)
    pos, vel, acc = profile_states(traj, times)
    for k, t in enumerate(times):
        p, v, a = traj.at_time(float(t))
        assert np.allclose(pos[k], p, rtol=0, atol=1e-9)
        assert np.allclose(vel[k], v, rtol=0, atol=1e-9)
        assert np.allclose(acc[k], a, rtol=0, atol=1e-9)


def test_times_outside_the_profile_are_clipped_to_its_ends() -> None:
    traj = _problem(3, 2, 0, False)
    pos, vel, _ = profile_states(traj, np.array([-1.0, traj.duration + 5.0]))
    first, last = traj.at_time(0.0), traj.at_time(traj.duration)
    assert np.allclose(pos[0], first[0]) and np.allclose(pos[1], last[0])
    assert np.allclose(vel[1], last[1], atol=1e-12)


@pytest.mark.parametrize("dof", [1, 6])
def test_a_brake_pre_trajectory_is_sampled(dof: int) -> None:
    otg, inp = Ruckig(dof), InputParameter(dof)
    inp.current_position, inp.target_position = [0.0] * dof, [1.0] * dof
    inp.current_velocity = [3.0] * dof  # three times the limit: Ruckig brakes first
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [1.0] * dof, [2.0] * dof, [10.0] * dof
    traj = Trajectory(dof)
    otg.calculate(inp, traj)
    assert traj.profiles[-1][0].brake.duration > 0.0
    times = np.linspace(0.0, traj.duration, 41)
    pos = profile_states(traj, times)[0]
    assert np.allclose(pos, [traj.at_time(float(t))[0] for t in times], atol=1e-9)
