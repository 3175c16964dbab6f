"""The second-order drive model: ``b q'' + a q' + q = u + c``, for joints whose inertia is not
small next to their damping.

A position drive is torque = K (target - q) - D q'. Divided by K: b q'' + a q' + q = u + c with
the lag a = D/K (s) and the inertia b = M/K (s^2). For the KR60's axes b is a few ms^2 and the
first-order model of :mod:`.drive` describes them; a carriage on a soft rail (the Fanuc's: K 30
N/m, D 10 N s/m, ~9 kg riding on it) is an under-damped oscillator (natural period ~3.4 s) that
no first-order lag fits: fitted one, it comes out 1.5 s (the truth is D/K = 0.33 s), and its
feedforward throws the carriage off its path.

The response to piecewise-constant commands is computed exactly between command changes and
samples (the roots of b s^2 + a s + 1, complex when under-damped), for a whole grid of (a, b)
at once; the offset c enters linearly and is solved in closed form; the grid is refined twice
around its best point.
"""

from __future__ import annotations

import numpy as np

from usar_arm.core.spatial import Array

LAG_RANGE = (1e-3, 3.0)
"""Lags (s) the grid spans."""
INERTIA_RANGE = (1e-5, 10.0)
"""Inertias (s^2) the grid spans."""
GRID = 24
"""Grid points per axis (log-spaced), each refinement round included."""
ROUNDS = 3


def _roots(lag: Array, inertia: Array) -> tuple[Array, Array]:
    """Roots of b s^2 + a s + 1 = 0 (complex (m,) arrays), kept apart at critical damping."""
    disc = lag ** 2 - 4 * inertia
    disc = np.where(np.abs(disc) < 1e-9 * lag ** 2, 1e-9 * lag ** 2, disc).astype(complex)
    root = np.sqrt(disc)
    return (-lag + root) / (2 * inertia), (-lag - root) / (2 * inertia)


def simulate(times: Array, commands: Array, q0: float, lag: Array, inertia: Array,
             at: Array) -> Array:
    """Response of ``b q'' + a q' + q = u`` to piecewise-constant commands from rest at ``q0``
    for every (lag, inertia) pair at once.

    Args:
        times: (m,) when each command started (s, increasing); commands: (m,) their values.
        lag, inertia: (p,) model parameters (s, s^2). at: (k,) report times (s, increasing).

    Returns:
        (k, p) positions.
    """
    r1, r2 = _roots(np.asarray(lag, float), np.asarray(inertia, float))
    gap = r1 - r2
    q = np.full(r1.shape, float(q0))
    v = np.zeros(r1.shape)
    events = np.union1d(times, at)
    command_at = np.searchsorted(times, events, side="right") - 1
    want = {float(t): i for i, t in enumerate(at)}
    out = np.empty((len(at), len(r1)))
    t, prev = float(events[0]), int(command_at[0])
    decay: dict[float, tuple[Array, Array]] = {}  # most segments are one command period
    for e, k in zip(events, command_at, strict=True):
        h = float(e) - t
        if h > 0 and prev >= 0:  # before the first command the joint rests at q0
            u = commands[prev]
            y0 = q - u
            c1 = (v - r2 * y0) / gap
            c2 = y0 - c1
            key = round(h, 12)
            if key not in decay:
                decay[key] = (np.exp(r1 * h), np.exp(r2 * h))
            e1, e2 = decay[key]
            q = u + (c1 * e1 + c2 * e2).real
            v = (r1 * c1 * e1 + r2 * c2 * e2).real
            t = float(e)
        if float(e) in want:
            out[want[float(e)]] = q
        prev = int(k)
    return out


def step_response(start: float, lag: Array, inertia: Array, at: Array) -> Array:
    """(k, p) response to a unit command held from ``start`` (s), from rest at 0."""
    r1, r2 = _roots(np.asarray(lag, float), np.asarray(inertia, float))
    c1 = r2 / (r1 - r2)
    c2 = -1.0 - c1
    dt = np.maximum(np.asarray(at, float) - start, 0.0)[:, None]
    return 1.0 + (c1 * np.exp(r1 * dt) + c2 * np.exp(r2 * dt)).real


def fit_joint(times: Array, commands: Array, sample_times: Array, samples: Array
              ) -> tuple[float, float, float, float]:
    """(lag s, inertia s^2, offset, rms residual) of one joint from its commands and measured
    positions (the grid search of the module)."""
    q0 = float(samples[0])
    lo_a, hi_a = np.log(LAG_RANGE[0]), np.log(LAG_RANGE[1])
    lo_b, hi_b = np.log(INERTIA_RANGE[0]), np.log(INERTIA_RANGE[1])
    best = (0.0, 0.0, 0.0, np.inf)
    for _ in range(ROUNDS):
        la, lb = np.meshgrid(np.linspace(lo_a, hi_a, GRID), np.linspace(lo_b, hi_b, GRID))
        a, b = np.exp(la.ravel()), np.exp(lb.ravel())
        pred = simulate(times, commands, q0, a, b, sample_times)
        gain = step_response(float(times[0]), a, b, sample_times)
        rest = samples[:, None] - pred
        offset = (gain * rest).sum(axis=0) / np.maximum((gain * gain).sum(axis=0), 1e-12)
        rms = np.sqrt(np.mean((rest - offset * gain) ** 2, axis=0))
        k = int(np.argmin(rms))
        if rms[k] < best[3]:
            best = (float(a[k]), float(b[k]), float(offset[k]), float(rms[k]))
        step_a, step_b = (hi_a - lo_a) / (GRID - 1), (hi_b - lo_b) / (GRID - 1)
        ca, cb = np.log(best[0]), np.log(best[1])
        lo_a, hi_a = ca - 1.5 * step_a, ca + 1.5 * step_a
        lo_b, hi_b = cb - 1.5 * step_b, cb + 1.5 * step_b
    return best
