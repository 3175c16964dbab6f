"""The drive model: first-order response, identification from sampled data, excitation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from usar_arm.control import drive_inertia
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


# ------------------------------------------------------------------ second order (inertia)
def _rk4(times: np.ndarray, commands: np.ndarray, q0: float, lag: float, inertia: float,
         at: np.ndarray, dt: float = 1e-4) -> np.ndarray:
    """b q'' + a q' + q = u by fixed-step RK4 (a reference independent of the closed form)."""
    q, v, t, out, j = q0, 0.0, 0.0, [], 0
    for target in at:
        while t < target - 1e-12:
            while j + 1 < len(times) and times[j + 1] <= t + 1e-12:
                j += 1
            h = min(dt, target - t)
            u = commands[j]

            def f(q: float, v: float, u: float = u) -> tuple[float, float]:
                return v, (u - q - lag * v) / inertia

            k1 = f(q, v)
            k2 = f(q + h / 2 * k1[0], v + h / 2 * k1[1])
            k3 = f(q + h / 2 * k2[0], v + h / 2 * k2[1])
            k4 = f(q + h * k3[0], v + h * k3[1])
            q += h / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            v += h / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            t += h
        out.append(q)
    return np.array(out)


@pytest.mark.parametrize("lag, inertia", [(0.33, 0.3), (0.2, 0.005), (0.1, 0.0025)])
def test_the_second_order_response_is_exact(lag: float, inertia: float) -> None:
    """Under- and over-damped drives, against an independent integration."""
    times, commands = excitation(np.zeros(1), np.array([-3.0]), np.array([3.0]),
                                 np.array([0.03]), 2.0)
    at = np.arange(0.013, 2.5, 0.1)
    got = drive_inertia.simulate(times, commands[:, 0], 0.0, np.array([lag]),
                                 np.array([inertia]), at)[:, 0]
    np.testing.assert_allclose(got, _rk4(times, commands[:, 0], 0.0, lag, inertia, at),
                               atol=1e-8)


def test_a_carriage_on_a_soft_rail_is_identified_second_order() -> None:
    """The Fanuc's rail (K 30 N/m, D 10 N s/m, ~9 kg): a first-order lag fits it at ~1.4 s,
    four times its D/K; the second-order model recovers lag and inertia, and the fit takes it."""
    lag, inertia, offset = 10 / 30, 8.86 / 30, 0.002
    times, commands = excitation(np.zeros(1), np.array([-1.5]), np.array([1.5]),
                                 np.array([0.01]), 2.0)
    at = np.arange(0.013, 2.5, 0.1)
    samples = np.round(drive_inertia.simulate(times, commands[:, 0] + offset, 0.0,
                                              np.array([lag]), np.array([inertia]), at), 4)
    first = fit_joint(times, commands[:, 0], at, samples[:, 0])
    assert first[0] > 1.0  # the lag a first-order model needs: wrong by 4x
    model = fit(times, commands, at, samples)
    assert model.lag[0] == pytest.approx(lag, rel=0.05)
    assert model.inertia is not None and model.inertia[0] == pytest.approx(inertia, rel=0.05)
    assert model.offset[0] == pytest.approx(offset, abs=2e-4)
    # feeding forward lag q' + inertia q'' follows a sine the first-order model cannot
    # (after the start's transient, which rings down at lag / (2 inertia) = 0.56 / s)
    t = np.arange(0.0, 16.0, 0.001)
    wave = 0.2 * np.sin(2 * t)
    u = model.command(wave[:, None], (0.4 * np.cos(2 * t))[:, None],
                      (-0.8 * np.sin(2 * t))[:, None])[:, 0] + offset
    follow = drive_inertia.simulate(t, u, 0.0, np.array([lag]), np.array([inertia]),
                                    t[13000:])[:, 0]
    assert np.max(np.abs(follow - wave[13000:])) < 5e-3
    plain = DriveModel(np.array([first[0]]), np.array([first[1]]), np.zeros(1))
    u = plain.command(wave[:, None], (0.4 * np.cos(2 * t))[:, None])[:, 0] + offset
    follow = drive_inertia.simulate(t, u, 0.0, np.array([lag]), np.array([inertia]),
                                    t[13000:])[:, 0]
    assert np.max(np.abs(follow - wave[13000:])) > 0.05


def test_a_first_order_joint_stays_first_order() -> None:
    times, commands = excitation(np.zeros(1), np.array([-3.0]), np.array([3.0]),
                                 np.array([0.03]), 2.0)
    at = np.arange(0.013, 2.5, 0.1)
    samples = np.round(simulate(times, commands[:, 0], 0.0, 0.15, at), 4)
    model = fit(times, commands, at, samples[:, None])
    assert model.inertia is not None and model.inertia[0] == 0.0
    assert model.lag[0] == pytest.approx(0.15, rel=0.05)
