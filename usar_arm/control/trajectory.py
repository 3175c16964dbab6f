"""Time-parameterised joint trajectories: samples, limits, JSON files, and limit checks."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.core.errors import FileFormatError
from usar_arm.core.fileio import write_atomic
from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class MotionLimits:
    """Per-joint limits a trajectory must respect (rad or m, per s, s^2, s^3)."""

    lower: Array
    upper: Array
    velocity: Array
    acceleration: Array
    jerk: Array

    @classmethod
    def from_chain(cls, chain: KinematicChain, scale: float = 1.0) -> MotionLimits:
        """The chain's limits with velocity, acceleration and jerk multiplied by ``scale``.

        Joints without an acceleration (jerk) limit get 2x their velocity (10x acceleration)
        per second, a conservative assumption.
        """
        if not 0 < scale <= 1:
            raise ValueError(f"speed scale must be in (0, 1], got {scale}")
        lims = chain.limits()
        vel = np.array([lim.velocity for lim in lims])
        acc = np.array([lim.acceleration or 2 * lim.velocity for lim in lims])
        jerk = np.array([lim.jerk or 10 * a for lim, a in zip(lims, acc, strict=True)])
        return cls(chain.lower(), chain.upper(), vel * scale, acc * scale, jerk * scale)

    def as_dict(self, names: Sequence[str]) -> dict[str, dict[str, float]]:
        """joint name -> {lower, upper, velocity, acceleration, jerk}."""
        return {n: {"lower": float(self.lower[i]), "upper": float(self.upper[i]),
                    "velocity": float(self.velocity[i]),
                    "acceleration": float(self.acceleration[i]), "jerk": float(self.jerk[i])}
                for i, n in enumerate(names)}


@dataclass(frozen=True)
class Trajectory:
    """A trajectory sampled on a uniform time grid.

    Attributes:
        joint_names: joint order of every array.
        t: sample times (s), from 0, uniform. q, qd, qdd: (m, n) positions, velocities,
            accelerations (rad or m, per s, per s^2).
        waypoints: (k, n) the geometric path it follows (collision-checked).
        limits: the limits it was timed with.
        motion: ``ptp`` or ``lin``. mode: ``stop`` (rest at every waypoint), ``blend``, ``lin``.
        info: free-form figures (planning time, path length...).
        scene: the scene it was planned in: a shipped scene's name or a scene file's absolute
            path (:mod:`usar_arm.core.named_file`), None when not known (a scene given as an
            object, or none). ``usar-arm view`` and ``render`` show it.
    """

    joint_names: tuple[str, ...]
    t: Array
    q: Array
    qd: Array
    qdd: Array
    waypoints: Array
    limits: MotionLimits
    motion: str = "ptp"
    mode: str = "stop"
    info: dict[str, Any] = field(default_factory=dict)
    scene: str | None = None

    @property
    def duration(self) -> float:
        """Duration (s)."""
        return float(self.t[-1])

    @property
    def rate(self) -> float:
        """Samples per second."""
        return (len(self.t) - 1) / self.duration if self.duration > 0 else math.inf

    def at(self, time: float) -> tuple[Array, Array]:
        """Position and velocity at ``time`` (s), by cubic Hermite interpolation of the
        samples; clamped to the first and last sample outside [0, duration]."""
        if time <= 0:
            return self.q[0].copy(), self.qd[0].copy()
        if time >= self.duration:
            return self.q[-1].copy(), np.zeros_like(self.qd[-1])
        dt = self.t[1] - self.t[0]
        k = min(int(time / dt), len(self.t) - 2)
        h = (time - self.t[k]) / dt
        h2, h3 = h * h, h * h * h
        q0, q1, v0, v1 = self.q[k], self.q[k + 1], self.qd[k] * dt, self.qd[k + 1] * dt
        q = ((2 * h3 - 3 * h2 + 1) * q0 + (h3 - 2 * h2 + h) * v0 + (-2 * h3 + 3 * h2) * q1
             + (h3 - h2) * v1)
        v = ((6 * h2 - 6 * h) * q0 + (3 * h2 - 4 * h + 1) * v0 + (-6 * h2 + 6 * h) * q1
             + (3 * h2 - 2 * h) * v1) / dt
        return q, v

    def acceleration(self, time: float) -> Array:
        """Acceleration at ``time`` (s): the samples interpolated linearly; zero outside
        [0, duration]."""
        if time <= 0 or time >= self.duration:
            return np.zeros(self.qdd.shape[1])
        dt = self.t[1] - self.t[0]
        k = min(int(time / dt), len(self.t) - 2)
        h = (time - self.t[k]) / dt
        out: Array = (1 - h) * self.qdd[k] + h * self.qdd[k + 1]
        return out

    # ------------------------------------------------------------------ files
    def to_json(self) -> dict[str, Any]:
        """The JSON document ``usar-arm plan --out`` writes."""
        return {"format": "usar-arm trajectory 1", "joint_names": list(self.joint_names),
                "motion": self.motion, "mode": self.mode, "duration": self.duration,
                "rate_hz": self.rate, "t": self.t.tolist(), "q": self.q.tolist(),
                "qd": self.qd.tolist(), "qdd": self.qdd.tolist(),
                "waypoints": self.waypoints.tolist(),
                "limits": self.limits.as_dict(self.joint_names), "info": self.info,
                **({"scene": self.scene} if self.scene is not None else {})}

    @classmethod
    def from_json(cls, doc: Any, path: str = "<trajectory>") -> Trajectory:
        """Read a trajectory document, naming the field of any error.

        Checks what the other methods rely on: joint names are distinct strings; ``t`` starts at
        0 s and is uniform (``at`` indexes it by ``time / dt``); q, qd, qdd are one finite row
        per sample; ``limits`` gives lower <= upper and positive velocity, acceleration and
        jerk for every joint; ``waypoints`` (optional) are rows of joint values.

        Raises:
            FileFormatError: the first problem found, with its field.
        """
        if not isinstance(doc, dict):
            raise FileFormatError(path, "expected a JSON object")
        for key in ("joint_names", "t", "q", "qd", "qdd", "limits"):
            if key not in doc:
                raise FileFormatError(path, f"missing '{key}'", field=key)
        names = _joint_names(doc["joint_names"], path)
        n = len(names)
        arrays = {key: _numbers(doc[key], path, key) for key in ("t", "q", "qd", "qdd")}
        t = arrays["t"]
        m = t.size
        if t.ndim != 1 or m < 2:
            raise FileFormatError(path, f"expected a list of at least 2 sample times (s), got "
                                  f"shape {t.shape}", field="t")
        for key in ("q", "qd", "qdd"):
            if arrays[key].shape != (m, n):
                raise FileFormatError(path, f"expected {m} rows of {n} values (one per joint "
                                      f"and sample), got shape {arrays[key].shape}", field=key)
        for key, a in arrays.items():
            if not np.all(np.isfinite(a)):
                raise FileFormatError(path, "contains NaN or infinite values", field=key)
        _check_uniform(t, path)
        limits = _limits(doc["limits"], names, path)
        raw = doc.get("waypoints")
        waypoints = arrays["q"][[0, -1]] if raw is None or raw == [] else \
            _numbers(raw, path, "waypoints")
        if waypoints.ndim != 2 or waypoints.shape[1:] != (n,) or not np.all(
                np.isfinite(waypoints)):
            raise FileFormatError(path, f"expected rows of {n} finite joint values, got shape "
                                  f"{waypoints.shape}", field="waypoints")
        texts = {}
        for key, default in (("motion", "ptp"), ("mode", "stop")):
            texts[key] = doc.get(key, default)
            if not isinstance(texts[key], str):
                raise FileFormatError(path, f"expected text (such as '{default}'), got "
                                      f"{_show(texts[key])}", field=key)
        info = doc.get("info", {})
        if not isinstance(info, dict):
            raise FileFormatError(path, f"expected an object, got {_show(info)}", field="info")
        scene = doc.get("scene")
        if scene is not None and not isinstance(scene, str):
            raise FileFormatError(path, f"expected a scene's name or path, got {_show(scene)}",
                                  field="scene")
        return cls(names, t, arrays["q"], arrays["qd"], arrays["qdd"], waypoints, limits,
                   texts["motion"], texts["mode"], dict(info), scene)

    def save(self, path: str | Path, executed: ExecutedSamples | None = None) -> None:
        """Write the JSON file atomically (with the ASTA samples of its execution, if any,
        under ``executed``: ``t`` s since the start, ``q`` one row per sample)."""
        doc = self.to_json()
        if executed is not None:
            doc["executed"] = {"t": executed.t.tolist(), "q": executed.q.tolist()}
        write_atomic(path, json.dumps(doc) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> Trajectory:
        """Read a JSON file written by :meth:`save` (or by hand, in that format)."""
        return cls.from_json(_read_json(path), str(path))


def _read_json(path: str | Path) -> Any:
    try:
        return json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise FileFormatError(str(path), f"cannot read: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:
        raise FileFormatError(str(path), f"not UTF-8 text: byte 0x{exc.object[exc.start]:02x} "
                              f"at offset {exc.start}") from None
    except json.JSONDecodeError as exc:
        raise FileFormatError(str(path), f"not valid JSON: {exc.msg}", line=exc.lineno) \
            from None
    except ValueError as exc:  # an integer literal of more than 4300 digits
        raise FileFormatError(str(path), f"not valid JSON: {exc}") from None
    except RecursionError:
        raise FileFormatError(str(path), "not valid JSON: nested too deeply") from None


def _show(value: Any, width: int = 60) -> str:
    """``repr(value)``, cut to ``width`` characters for an error message."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def _numbers(value: Any, path: str, field: str) -> Array:
    """A (possibly nested) list of numbers as a float array; anything else is a FileFormatError."""
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise FileFormatError(path, "expected numbers (lists of equal length)", field=field) \
            from None


def _joint_names(value: Any, path: str) -> tuple[str, ...]:
    """The ``joint_names`` list: at least one name, each a distinct non-empty string."""
    if not isinstance(value, list) or not value or not all(
            isinstance(v, str) and v for v in value):
        raise FileFormatError(path, f"expected a list of joint names, got {_show(value)}",
                              field="joint_names")
    if len(set(value)) != len(value):
        twice = next(v for v in value if value.count(v) > 1)
        raise FileFormatError(path, f"joint '{twice}' is listed twice", field="joint_names")
    return tuple(value)


def _check_uniform(t: Array, path: str) -> None:
    """Sample times must start at 0 and step uniformly (to 1e-6 of a step), as ``at`` assumes."""
    dt = np.diff(t)
    if np.any(dt <= 0):
        raise FileFormatError(path, "sample times must increase", field="t")
    step = (t[-1] - t[0]) / (t.size - 1)
    if abs(t[0]) > 1e-6 * step or np.max(np.abs(dt - step)) > 1e-6 * step:
        raise FileFormatError(path, f"sample times must start at 0 s and be uniform (a step of "
                              f"{step:g} s expected; found t[0] = {t[0]:g} s and steps from "
                              f"{dt.min():g} to {dt.max():g} s)", field="t")


def _limits(value: Any, names: tuple[str, ...], path: str) -> MotionLimits:
    """``limits``: joint name -> {lower, upper, velocity, acceleration, jerk}."""
    keys = ("lower", "upper", "velocity", "acceleration", "jerk")
    expected = "expected lower, upper, velocity, acceleration, jerk for every joint"
    if not isinstance(value, dict):
        raise FileFormatError(path, expected, field="limits")
    table: dict[str, list[float]] = {k: [] for k in keys}
    for j in names:
        entry = value.get(j)
        if not isinstance(entry, dict) or any(k not in entry for k in keys):
            raise FileFormatError(path, expected, field=f"limits.{j}")
        for k in keys:
            v = entry[k]
            bounds = k in ("lower", "upper")
            try:
                number = math.nan if isinstance(v, bool) else float(v)
            except (TypeError, ValueError, OverflowError):
                number = math.nan
            if isinstance(v, str) or math.isnan(number) or not (bounds or number > 0):
                kind = "a number (rad or m)" if bounds else "a positive number (per s^k)"
                raise FileFormatError(path, f"expected {kind}, got {_show(v)}",
                                      field=f"limits.{j}.{k}")
            table[k].append(number)
        if table["lower"][-1] > table["upper"][-1]:
            raise FileFormatError(path, f"lower {table['lower'][-1]:g} is above upper "
                                  f"{table['upper'][-1]:g}", field=f"limits.{j}")
    return MotionLimits(*(np.array(table[k]) for k in keys))


def load_with_executed(path: str | Path) -> tuple[Trajectory, ExecutedSamples | None]:
    """A trajectory file and the executed samples saved with it (None when it has none)."""
    doc = _read_json(path)
    traj = Trajectory.from_json(doc, str(path))
    done = doc.get("executed")
    if done is None:
        return traj, None
    try:
        t = np.asarray(done["t"], dtype=float)
        q = np.asarray(done["q"], dtype=float).reshape(len(t), len(traj.joint_names))
        ok = t.ndim == 1 and bool(np.all(np.isfinite(t))) and bool(np.all(np.isfinite(q)))
    except (KeyError, TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise FileFormatError(str(path), "expected t (finite times) and q (one row of finite "
                              "joint values per time)", field="executed")
    return traj, ExecutedSamples(t, q)


@dataclass(frozen=True)
class ExecutedSamples:
    """Joint values measured on the robot (from ASTA feedback) during an execution.

    Attributes:
        t: (m,) s since the start of the trajectory. q: (m, n) in the trajectory's joint order.
    """

    t: Array
    q: Array


@dataclass(frozen=True)
class LimitReport:
    """The largest use of each limit over a sampled trajectory (1.0 = at the limit)."""

    position_margin: float
    velocity_ratio: float
    acceleration_ratio: float
    jerk_ratio: float
    worst_joint: dict[str, str]

    def within(self, tolerance: float = 1e-6) -> bool:
        """True when no limit is exceeded (beyond ``tolerance`` relative)."""
        return (self.position_margin >= -tolerance and self.velocity_ratio <= 1 + tolerance
                and self.acceleration_ratio <= 1 + tolerance and self.jerk_ratio <= 1 + tolerance)


def check_limits(t: Array, q: Array, qd: Array, qdd: Array, limits: MotionLimits,
                 names: Sequence[str]) -> LimitReport:
    """How close samples come to the limits; jerk by finite differences of acceleration."""
    dt = np.diff(t)
    jerk = np.diff(qdd, axis=0) / dt[:, None] if len(t) > 1 else np.zeros_like(qdd)
    margin = np.minimum(q - limits.lower, limits.upper - q)
    ratios = {"velocity": np.abs(qd) / limits.velocity,
              "acceleration": np.abs(qdd) / limits.acceleration,
              "jerk": np.abs(jerk) / limits.jerk if len(jerk) else np.zeros((1, len(names)))}
    worst = {k: names[int(np.argmax(v.max(axis=0)))] for k, v in ratios.items()}
    worst["position"] = names[int(np.argmin(margin.min(axis=0)))]
    return LimitReport(float(margin.min()), float(ratios["velocity"].max()),
                       float(ratios["acceleration"].max()), float(ratios["jerk"].max()), worst)
