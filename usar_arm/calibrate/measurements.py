"""Measured poses of one frame of the arm, and the CSV / YAML files that carry them.

A :class:`Measurement` is one pose of the measured frame in the measurement frame M at joint
values q. Files state their units: CSV in the column names (``joint_a1_deg``, ``x_mm``,
``roll_rad``, ``sigma_mm``...), YAML in a ``units:`` key. Inside, everything is SI (m, rad).

CSV::

    # frame: tool0
    joint_a1_deg,...,joint_a6_deg,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg,sigma_mm,sigma_deg,label

(``roll/pitch/yaw``, ``sigma_*``, ``step_*`` and ``label`` are optional; joint columns of a
prismatic joint take a length unit. Joint values printed to a step state it in SI whatever the
columns' units, and how they were printed: ``# joint step: 0.0001`` (rad, or m for prismatic
joints) and ``# joint values: rounded`` or ``truncated``. Other ``# key: value`` lines before
the header row are kept in :attr:`MeasurementSet.header`.) YAML::

    frame: tool0
    units: {length: mm, angle: deg}
    measurements:
      - {q: [..], position: [x, y, z], rpy: [r, p, y], sigma_position: 0.05, label: a}

Errors name the file, the line and the column (:class:`usar_arm.core.errors.FileFormatError`).
"""

from __future__ import annotations

import csv
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import Array
from usar_arm.core.yamlio import line_of, load_yaml

LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
ANGLE_UNITS = {"rad": 1.0, "deg": math.pi / 180}
POSITION = ("x", "y", "z")
ANGLES = ("roll", "pitch", "yaw")


@dataclass(frozen=True)
class Measurement:
    """One measured pose of the measured frame at joint values q, in the measurement frame M.

    ``q`` (n,) rad / m in the URDF's actuated joint order; ``position`` (3,) m; ``rpy`` (3,)
    rad with R = Rz(yaw) Ry(pitch) Rx(roll), or None (position only). ``step_m`` / ``step_rad``:
    each printed number truncated toward zero to this step (0: not quantised). ``sigma_m`` /
    ``sigma_rad``: 1-sigma noise of each number. ``label``: where it came from. ``step_q``: the
    joint values as printed, each truncated toward zero to this step (rad, or m for prismatic
    joints; 0: exact), or rounded to it with ``q_rounded`` (ASTA prints raw engine floats,
    rounded); the fit uses their intervals' middles and widens the pose intervals by what the
    joint intervals allow.
    """

    q: Array
    position: Array
    rpy: Array | None
    step_m: float = 0.0
    step_rad: float = 0.0
    sigma_m: float = 0.0
    sigma_rad: float = 0.0
    label: str = ""
    step_q: float = 0.0      # each joint value printed truncated toward zero to this step
    q_rounded: bool = False  # the joint values were printed rounded to step_q, not truncated


@dataclass(frozen=True)
class MeasurementSet:
    """Measurements of one frame; the units the file stated (already converted to SI)."""

    measurements: tuple[Measurement, ...]
    frame: str
    length_unit: str = "m"
    angle_unit: str = "rad"
    joint_names: tuple[str, ...] = field(default_factory=tuple)
    header: tuple[tuple[str, str], ...] = ()
    """Other ``# key: value`` lines of a CSV file, in order."""
    measured_in: str = "tracker"
    """The frame the poses are given in: ``tracker`` (the instrument's own, registered from the
    readings) or ``base_link`` (the description's base, e.g. a tracker already registered)."""


MEASURED_IN = ("tracker", "base_link")
"""The frames a file's poses may be given in (``# measured_in:`` / ``measured_in:``; a tour's
readings file, which states ``# measured in:`` the server's world, is read by
:mod:`usar_arm.calibrate.tour_readings`)."""


def _measured_in(value: str, path: str, line: int | None) -> str:
    if value not in MEASURED_IN:
        raise FileFormatError(path, f"the readings are measured in '{value}': expected "
                              f"{' or '.join(MEASURED_IN)}", line=line, field="measured_in")
    return value


def _unit(name: str, table: dict[str, float], path: str, line: int | None, col: str,
          kind: str) -> float:
    if name not in table:
        raise FileFormatError(path, f"unknown {kind} unit '{name}' (expected one of "
                              f"{', '.join(table)})", line=line, field=col)
    return table[name]


def _number(text: Any, path: str, line: int | None, col: str) -> float:
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise FileFormatError(path, f"'{text}' is not a number", line=line, field=col) from None
    if not math.isfinite(value):
        raise FileFormatError(path, f"{value} is not a finite number", line=line, field=col)
    return value


def _check_limits(q: Array, names: Sequence[str], lower: Array | None, upper: Array | None,
                  path: str, line: int | None) -> None:
    if lower is None or upper is None:
        return
    for i, name in enumerate(names):
        if not lower[i] - 1e-9 <= q[i] <= upper[i] + 1e-9:
            raise FileFormatError(path, f"joint value {q[i]:.6g} outside the limits "
                                  f"[{lower[i]:.6g}, {upper[i]:.6g}] (SI units)",
                                  line=line, field=name)


def _check_uncertainty(vals: dict[str, float], path: str, line: int | None,
                       fields: dict[str, str]) -> None:
    """A stated sigma must be positive (zero only beside a step: no noise beyond the
    truncation); a step must not be negative. Keys ``sigma_m``, ``step_rad``... (SI)."""
    for kind in ("m", "rad"):
        sigma, step = vals.get(f"sigma_{kind}"), vals.get(f"step_{kind}", 0.0)
        if step < 0:
            raise FileFormatError(path, f"a negative step ({step:g}) is no step",
                                  line=line, field=fields[f"step_{kind}"])
        if sigma is not None and (sigma < 0 or (sigma == 0 and step == 0)):
            raise FileFormatError(
                path, f"an uncertainty of {sigma:g} is not a 1-sigma (it must be positive; "
                "leave the column out to have the noise estimated from the readings)",
                line=line, field=fields[f"sigma_{kind}"])


def _split(col: str) -> tuple[str, str]:
    base, _, unit = col.rpartition("_")
    return (base, unit) if base else (col, "")


@dataclass
class _Preamble:
    """What a CSV file's comment lines before its header say, and where the header is."""

    frame: str = ""
    step_q: float = 0.0
    rounded: bool = False
    comments: list[tuple[str, str]] = field(default_factory=list)
    header_line: int = 0
    measured_in: str = "tracker"


def _preamble(path: str, lines: list[str]) -> _Preamble:
    """The ``# key: value`` lines before the header (frame, joint step, joint values, others
    kept as comments) and the header's line number."""
    found = _Preamble()
    for i, raw in enumerate(lines, start=1):
        s = raw.strip()
        if not s:
            continue
        if s.startswith("#"):
            key, _, value = (part.strip() for part in s[1:].partition(":"))
            if key == "frame":
                found.frame = value
            elif key == "measured_in":
                found.measured_in = _measured_in(value, path, i)
            elif key == "joint step":
                found.step_q = _number(value, path, i, "# joint step")
            elif key == "joint values":
                if value not in ("rounded", "truncated"):
                    raise FileFormatError(path, f"'# joint values: {value}': expected rounded "
                                          "or truncated", line=i)
                found.rounded = value == "rounded"
            elif key:
                found.comments.append((key, value))
            continue
        found.header_line = i
        break
    if not found.header_line:
        raise FileFormatError(path, "no header row (expected joint, x, y, z columns)")
    if not found.frame:
        raise FileFormatError(path, "no '# frame: NAME' line before the header (which frame "
                              "was measured?)", line=1)
    return found


def _scales(path: str, header_line: int, cols: dict[str, tuple[int, str]],
            joint_names: Sequence[str], prismatic: Sequence[bool]
            ) -> tuple[dict[str, float], dict[str, str]]:
    """(factor to SI of each column but label/sigma/step, the file's length and angle
    units)."""
    scale: dict[str, float] = {}
    units = {"length": "m", "angle": "rad"}
    for name, (_, unit) in cols.items():
        if name in ("label", "sigma", "step"):
            continue
        is_angle = name in ANGLES or (name in joint_names and
                                      not prismatic[list(joint_names).index(name)])
        table, kind = (ANGLE_UNITS, "angle") if is_angle else (LENGTH_UNITS, "length")
        scale[name] = _unit(unit, table, path, header_line, f"{name}_{unit}", kind)
        if name in POSITION:
            units["length"] = unit
        if name in ANGLES:
            units["angle"] = unit
    return scale, units


def _uncertainty_columns(path: str, header_line: int, header: list[str]
                         ) -> dict[str, tuple[int, float, bool]]:
    """sigma_m/sigma_rad/step_m/step_rad -> (column, factor to SI, is an angle): sigma and
    step may each appear twice (length and angle), so the raw header is scanned."""
    extra: dict[str, tuple[int, float, bool]] = {}
    for k, c in enumerate(header):
        base, unit = _split(c.strip())
        if base in ("sigma", "step"):
            angle = unit in ANGLE_UNITS
            _unit(unit, {**LENGTH_UNITS, **ANGLE_UNITS}, path, header_line, c.strip(),
                  "length or angle")
            extra[f"{base}_{'rad' if angle else 'm'}"] = (
                k, (ANGLE_UNITS if angle else LENGTH_UNITS)[unit], angle)
    return extra


def _read_csv(path: str, text: str, joint_names: Sequence[str], prismatic: Sequence[bool],
              lower: Array | None, upper: Array | None) -> MeasurementSet:
    rows = []
    lines = text.splitlines()
    pre = _preamble(path, lines)
    header_line = pre.header_line
    header = next(csv.reader([lines[header_line - 1]]))
    cols = {_split(c.strip())[0]: (k, _split(c.strip())[1]) for k, c in enumerate(header)}
    need = list(joint_names) + list(POSITION)
    missing = [n for n in need if n not in cols]
    if missing:
        raise FileFormatError(path, f"missing column(s) {', '.join(missing)} (columns are "
                              "NAME_UNIT, e.g. joint_a1_deg, x_mm)", line=header_line)
    has_rpy = [a in cols for a in ANGLES]
    if any(has_rpy) and not all(has_rpy):
        raise FileFormatError(path, "give all of roll, pitch, yaw or none", line=header_line)
    scale, units = _scales(path, header_line, cols, joint_names, prismatic)
    extra = _uncertainty_columns(path, header_line, header)
    for i, row in enumerate(csv.reader(lines[header_line:]), start=header_line + 1):
        if not row or (len(row) == 1 and not row[0].strip()) or row[0].lstrip().startswith("#"):
            continue
        if len(row) != len(header):
            raise FileFormatError(path, f"{len(row)} values, the header has {len(header)}",
                                  line=i)

        def get(name: str, line: int = i, row: list[str] = row) -> float:
            k, unit = cols[name]
            return _number(row[k], path, line, f"{name}_{unit}") * scale[name]

        q = np.array([get(n) for n in joint_names])
        _check_limits(q, joint_names, lower, upper, path, i)
        vals = {key: _number(row[k], path, i, header[k]) * s for key, (k, s, _) in extra.items()}
        _check_uncertainty(vals, path, i, {key: header[k] for key, (k, _, _) in extra.items()})
        label = row[cols["label"][0]] if "label" in cols else f"{Path(path).name} line {i}"
        rows.append(Measurement(
            q, np.array([get(n) for n in POSITION]),
            np.array([get(n) for n in ANGLES]) if all(has_rpy) else None,
            vals.get("step_m", 0.0), vals.get("step_rad", 0.0),
            vals.get("sigma_m", 0.0), vals.get("sigma_rad", 0.0), label, pre.step_q,
            pre.rounded))
    return MeasurementSet(tuple(rows), pre.frame, units["length"], units["angle"],
                          tuple(joint_names), tuple(pre.comments), pre.measured_in)


def _vector(item: Any, key: str, n: int, s: float, path: str, line: int | None) -> Array:
    value = item.get(key)
    if not isinstance(value, list) or len(value) != n:
        raise FileFormatError(path, f"expected a list of {n} numbers", line=line, field=key)
    return np.array([_number(v, path, line, key) for v in value]) * s


def _read_yaml(path: str, joint_names: Sequence[str], prismatic: Sequence[bool],
               lower: Array | None, upper: Array | None) -> MeasurementSet:
    data = load_yaml(path)
    if not isinstance(data, dict):
        raise FileFormatError(path, "expected a mapping with frame, units, measurements")
    for key in ("frame", "units", "measurements"):
        if key not in data:
            raise FileFormatError(path, f"missing key '{key}'", line=line_of(data))
    units = data["units"]
    if not isinstance(units, dict):
        raise FileFormatError(path, "expected {length: m|mm, angle: rad|deg}",
                              line=line_of(data, "units"), field="units")
    lu, au = str(units.get("length", "")), str(units.get("angle", ""))
    ls = _unit(lu, LENGTH_UNITS, path, line_of(data, "units"), "units.length", "length")
    ang = _unit(au, ANGLE_UNITS, path, line_of(data, "units"), "units.angle", "angle")
    qs = np.array([ls if p else ang for p in prismatic])
    items = data["measurements"]
    if not isinstance(items, list):
        raise FileFormatError(path, "expected a list", line=line_of(data, "measurements"),
                              field="measurements")
    rows = []
    for k, item in enumerate(items):
        line = line_of(items, k)
        if not isinstance(item, dict):
            raise FileFormatError(path, "expected a mapping with q, position", line=line)
        for key in ("q", "position"):
            if key not in item:
                raise FileFormatError(path, f"missing key '{key}'", line=line, field=key)
        q = _vector(item, "q", len(joint_names), 1.0, path, line) * qs
        _check_limits(q, joint_names, lower, upper, path, line)
        rpy = _vector(item, "rpy", 3, ang, path, line) if "rpy" in item else None

        def scalar(key: str, s: float, item: Any = item, line: int | None = line) -> float:
            return _number(item[key], path, line, key) * s if key in item else 0.0

        keys = {"step_m": "step_position", "step_rad": "step_angle",
                "sigma_m": "sigma_position", "sigma_rad": "sigma_angle"}
        vals = {k: scalar(key, ls if k.endswith("_m") else ang) for k, key in keys.items()
                if key in item}
        _check_uncertainty(vals, path, line, keys)
        rows.append(Measurement(q, _vector(item, "position", 3, ls, path, line), rpy,
                                vals.get("step_m", 0.0), vals.get("step_rad", 0.0),
                                vals.get("sigma_m", 0.0), vals.get("sigma_rad", 0.0),
                                str(item.get("label", f"{Path(path).name} line {line}"))))
    measured_in = _measured_in(str(data.get("measured_in", "tracker")), path,
                               line_of(data, "measured_in") if "measured_in" in data else None)
    return MeasurementSet(tuple(rows), str(data["frame"]), lu, au, tuple(joint_names),
                          measured_in=measured_in)


def read_measurements(path: str | Path, joint_names: Sequence[str], *,
                      prismatic: Sequence[bool] | None = None, lower: Array | None = None,
                      upper: Array | None = None) -> MeasurementSet:
    """The measurements of a CSV or YAML file (by suffix: .csv, .yaml/.yml), in SI units.

    ``prismatic`` marks joints whose values are lengths (default: none); with ``lower`` /
    ``upper`` (SI) a joint value outside them is an error naming line and column.
    """
    p = str(path)
    kinds = list(prismatic) if prismatic is not None else [False] * len(joint_names)
    if p.endswith((".yaml", ".yml")):
        return _read_yaml(p, joint_names, kinds, lower, upper)
    try:
        text = Path(p).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise FileFormatError(p, f"cannot read: {exc}") from None
    return _read_csv(p, text, joint_names, kinds, lower, upper)
