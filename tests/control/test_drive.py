"""The drive model: first-order response, identification from sampled data, excitation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from usar_arm.control.drive import DriveModel, excitation, fit, fit_joint, simulate


@given(lag=st.floats(0.01, 2.0), q0=st.floats(-1, 1), u=st.floats(-1, 1),
       t=st.floats(0.0, 5.0))
def test_a_step_response_is_the_closed_form(lag: float, q0: float, u: float, t: float) -> None:
    got = simulate(np.array([0.0]), np.array([u]), q0, lag, np.array([t]))[0]
    assert got == pytest.approx(u + (q0 - u) * np.exp(-t / lag), abs=1e-12)


def test_piecewise_commands_compose() -> None:
    """Two half-length holds of the same command equal one hold."""
    one = simulate(np.array([0.0]), np.array([0.7]), 0.1, 0.2, np.array([0.5, 1.0]))
    two = simulate(np.array([0.0, 0.5]), np.array([0.7, 0.7]), 0.1, 0.2, np.array([0.5, 1.0]))
    assert np.allclose(one, two)


@pytest.mark.parametrize("lag, offset", [(0.05, 0.0), (0.12, -0.004), (0.4, 0.01)])
def test_identification_recovers_lag_and_offset_from_10hz_rounded_samples(
        lag: float, offset: float) -> None:
    times, commands = excitation(np.zeros(1), np.array([-3.0]), np.array([3.0]),
                                 np.array([0.03]), 2.0)
    at = np.arange(0.013, 2.5, 0.1)  # ASTA at 10 Hz, not aligned with the commands
    true = simulate(times, commands[:, 0] + offset, 0.0, lag, at)
    samples = np.round(true, 4)  # UDK prints joint values with 4 decimals
    got_lag, got_offset, rms = fit_joint(times, commands[:, 0], at, samples)
    assert got_lag == pytest.approx(lag, rel=0.05)
    assert got_offset == pytest.approx(offset, abs=2e-4)
    assert rms < 1e-4


def test_fit_handles_every_joint_and_feedforward_cancels_the_lag() -> None:
    lags = np.array([0.08, 0.15])
    times, commands = excitation(np.zeros(2), np.full(2, -3.0), np.full(2, 3.0),
                                 np.full(2, 0.03), 2.0)
    at = np.arange(0.0, 2.0, 0.1)
    samples = np.column_stack([simulate(times, commands[:, j], 0.0, lags[j], at)
                               for j in range(2)])
    model = fit(times, commands, at, samples)
    assert np.allclose(model.lag, lags, rtol=0.02)
    # Following q_d = sin(t) with u = q_d + lag q_d' leaves (almost) no lag.
    t = np.arange(0.0, 3.0, 0.001)
    u = model.command(np.sin(t)[:, None], np.cos(t)[:, None])
    follow = simulate(t, u[:, 0], 0.0, lags[0], t[1000:])
    assert np.max(np.abs(follow - np.sin(t[1000:]))) < 2e-3


def test_excitation_stays_inside_the_limits_and_starts_and_ends_at_rest() -> None:
    start = np.array([0.0, 2.99, -0.5])
    lower, upper = np.full(3, -3.0), np.array([3.0, 3.0, -0.49])
    times, commands = excitation(start, lower, upper, np.full(3, 0.03), 2.0)
    assert np.all(commands >= lower) and np.all(commands <= upper)
    assert np.allclose(commands[0], commands[-1], atol=1e-3)
    assert times[1] - times[0] == pytest.approx(0.01)


def test_no_model_commands_the_trajectory_itself() -> None:
    none = DriveModel.none(3)
    assert np.array_equal(none.command(np.ones(3), np.ones(3)), np.ones(3))
