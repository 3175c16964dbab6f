"""A model of each joint's drive, learnt from the arm's own response, for feedforward.

A USARSim joint is a position drive: torque = K (target - q) - D q' (PhysX in UDK, MuJoCo in the
embedded simulator). Its inertia is small next to its damping, so it behaves like a first-order
lag: ``a q' + q = u + c`` with the lag ``a = D/K`` (s) and ``c`` the steady offset gravity leaves.
Streaming the plain trajectory would trail it by ``a q'`` (0.15 rad at 1 rad/s for a KR60 axis);
commanding ``u = q_d + a q_d' - c`` cancels that.

The wire reports neither D nor masses, so ``a`` and ``c`` are identified from a short
excitation: the commands sent are known exactly, the first-order response to them is simulated
exactly between the 10 Hz ASTA samples, and ``a`` (golden-section search) and ``c`` (least
squares) are fitted per joint. A joint whose inertia matters (``b q'' + a q' + q = u + c``,
:mod:`.drive_inertia`: a carriage on a soft rail) is recognised by that model fitting its
samples far better (:data:`INERTIA_GAIN`); its feedforward then adds ``b q_d''``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import Array

LAG_RANGE = (1e-3, 3.0)
"""Lags (s) the identification searches."""
INERTIA_GAIN = 0.5
"""The second-order model is taken for a joint when its RMS residual is below this fraction of
the first-order model's."""
RESOLUTION = 1e-4
"""Residuals below this (rad or m; the ASTA print step) cannot tell the models apart."""


@dataclass(frozen=True)
class DriveModel:
    """Per-joint lag (s), inertia (s^2; 0 for a first-order joint) and steady offset (rad or
    m), and how they were obtained."""

    lag: Array
    offset: Array
    residual: Array
    """RMS fit residual per joint (rad or m)."""
    source: str = "identified"
    inertia: Array | None = None

    @classmethod
    def none(cls, n: int) -> DriveModel:
        """No feedforward."""
        return cls(np.zeros(n), np.zeros(n), np.zeros(n), "none")

    def command(self, q: Array, qd: Array, qdd: Array | None = None) -> Array:
        """The target that makes the joints follow position ``q`` moving at ``qd`` and
        accelerating at ``qdd``."""
        out = q + self.lag * qd - self.offset
        if self.inertia is not None and qdd is not None:
            out = out + self.inertia * qdd
        return out


def simulate(times: Array, commands: Array, q0: float, lag: float, at: Array) -> Array:
    """First-order response ``lag q' + q = u`` to piecewise-constant commands.

    Args:
        times: (m,) when each command started (s, increasing). commands: (m,) their values.
        q0: the position at ``times[0]``. at: (k,) times to report (s, increasing).
    """
    out = np.empty(len(at))
    q, t, j = q0, times[0], 0
    for k, target in enumerate(at):
        while j < len(times) and times[j] <= target:
            nxt = times[j + 1] if j + 1 < len(times) else math.inf
            end = min(nxt, target)
            if end > t:
                q = commands[j] + (q - commands[j]) * math.exp(-(end - t) / lag)
                t = end
            if nxt <= target:
                j += 1
            else:
                break
        out[k] = q
    return out


def fit_joint(times: Array, commands: Array, sample_times: Array, samples: Array
              ) -> tuple[float, float, float]:
    """(lag, offset, rms residual) of one joint from its commands and measured positions.

    For a given lag the offset enters linearly (the response to ``u + c`` from the measured
    start is the response to ``u`` plus ``c (1 - exp(-t / lag))``), so it is solved in closed
    form; the lag is found by golden-section search on the residual.
    """
    q0 = float(samples[0])
    elapsed = sample_times - sample_times[0]

    def residual(lag: float) -> tuple[float, float]:
        pred = simulate(times, commands, q0, lag, sample_times)
        gain = 1.0 - np.exp(-elapsed / lag)
        rest = samples - pred
        offset = float(gain @ rest / max(float(gain @ gain), 1e-12))
        return float(np.sqrt(np.mean((rest - offset * gain) ** 2))), offset

    lo, hi = math.log(LAG_RANGE[0]), math.log(LAG_RANGE[1])
    ratio = (math.sqrt(5) - 1) / 2
    a, b = hi - ratio * (hi - lo), lo + ratio * (hi - lo)
    fa, fb = residual(math.exp(a))[0], residual(math.exp(b))[0]
    for _ in range(40):
        if fa < fb:
            hi, b, fb = b, a, fa
            a = hi - ratio * (hi - lo)
            fa = residual(math.exp(a))[0]
        else:
            lo, a, fa = a, b, fb
            b = lo + ratio * (hi - lo)
            fb = residual(math.exp(b))[0]
    lag = math.exp((lo + hi) / 2)
    rms, offset = residual(lag)
    return lag, offset, rms


def fit(times: Array, commands: Array, sample_times: Array, samples: Array) -> DriveModel:
    """Fit every joint (commands (m, n), samples (k, n)): first order, or second order where
    that fits far better (see the module)."""
    from usar_arm.control import drive_inertia

    n = commands.shape[1]
    lag, inertia, offset, residual = (np.zeros(n) for _ in range(4))
    for j in range(n):
        lag[j], offset[j], residual[j] = fit_joint(times, commands[:, j], sample_times,
                                                   samples[:, j])
        if residual[j] <= RESOLUTION:
            continue
        a, b, c, rms = drive_inertia.fit_joint(times, commands[:, j], sample_times,
                                               samples[:, j])
        if rms < INERTIA_GAIN * residual[j]:
            lag[j], inertia[j], offset[j], residual[j] = a, b, c, rms
    return DriveModel(lag, offset, residual, inertia=inertia)


def excitation(start: Array, lower: Array, upper: Array, amplitude: Array, duration: float
               ) -> tuple[Array, Array]:
    """A smooth identification motion: each joint swings around ``start`` by ``amplitude`` at
    its own frequency (0.6-1.1 Hz), faded in and out, inside the limits.

    Returns ``(times, commands)`` sampled every 10 ms.
    """
    n = len(start)
    times = np.arange(0.0, duration, 0.01)
    freqs = 0.6 + 0.5 * np.arange(n) / max(1, n - 1)
    fade = np.sin(np.pi * times / duration) ** 2
    swing = amplitude * np.sin(2 * np.pi * np.outer(times, freqs)) * fade[:, None]
    centre = np.clip(start, lower + amplitude, upper - amplitude)
    return times, np.clip(centre + swing, lower, upper)
