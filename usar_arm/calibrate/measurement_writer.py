"""Measurement sets written as CSV or YAML in chosen units (what read_measurements reads back:
numbers as Python's repr, so a write-read round trip is exact)."""

from __future__ import annotations

import csv
import io
import json
from collections.abc import Sequence
from pathlib import Path

from usar_arm.calibrate.measurements import (
    ANGLE_UNITS,
    ANGLES,
    LENGTH_UNITS,
    POSITION,
    MeasurementSet,
)
from usar_arm.fileio import write_atomic


def csv_text(data: MeasurementSet, length_unit: str = "m", angle_unit: str = "rad",
             prismatic: Sequence[bool] | None = None) -> str:
    """The CSV text of a measurement set (numbers with 17 significant digits: round trips)."""
    ls, ang = LENGTH_UNITS[length_unit], ANGLE_UNITS[angle_unit]
    kinds = list(prismatic) if prismatic is not None else [False] * len(data.joint_names)
    has_rpy = all(m.rpy is not None for m in data.measurements) and bool(data.measurements)
    header = [f"{n}_{length_unit if k else angle_unit}" for n, k in zip(data.joint_names, kinds,
                                                                       strict=True)]
    header += [f"{a}_{length_unit}" for a in POSITION]
    header += [f"{a}_{angle_unit}" for a in ANGLES] if has_rpy else []
    header += [f"step_{length_unit}", f"step_{angle_unit}", f"sigma_{length_unit}",
               f"sigma_{angle_unit}", "label"]
    buf = io.StringIO()
    buf.write(f"# frame: {data.frame}\n")
    for key, value in data.header:
        buf.write(f"# {key}: {value}\n")
    steps = {(m.step_q, m.q_rounded) for m in data.measurements}
    if len(steps) > 1:
        raise ValueError("the measurements' joint values were printed with different steps "
                         f"({sorted(steps)}); a CSV file states one")
    if data.measurements and data.measurements[0].step_q > 0:
        first = data.measurements[0]
        buf.write(f"# joint step: {first.step_q!r}\n")
        buf.write(f"# joint values: {'rounded' if first.q_rounded else 'truncated'}\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    qs = [ls if k else ang for k in kinds]
    for m in data.measurements:
        row = [repr(float(v / s)) for v, s in zip(m.q, qs, strict=True)]
        row += [repr(float(v / ls)) for v in m.position]
        row += [repr(float(v / ang)) for v in m.rpy] if has_rpy and m.rpy is not None else []
        row += [repr(m.step_m / ls), repr(m.step_rad / ang), repr(m.sigma_m / ls),
                repr(m.sigma_rad / ang), m.label]
        w.writerow(row)
    return buf.getvalue()


def write_measurements(path: str | Path, data: MeasurementSet, length_unit: str = "m",
                       angle_unit: str = "rad", prismatic: Sequence[bool] | None = None) -> Path:
    """Write a measurement set atomically: YAML for a .yaml / .yml path, else CSV."""
    text = (yaml_text if str(path).endswith((".yaml", ".yml")) else csv_text)(
        data, length_unit, angle_unit, prismatic)
    return write_atomic(path, text)


def yaml_text(data: MeasurementSet, length_unit: str = "m", angle_unit: str = "rad",
              prismatic: Sequence[bool] | None = None) -> str:
    """The YAML text of a measurement set (numbers as Python's repr: round trips)."""
    ls, ang = LENGTH_UNITS[length_unit], ANGLE_UNITS[angle_unit]
    kinds = list(prismatic) if prismatic is not None else [False] * len(data.joint_names)
    qs = [ls if k else ang for k in kinds]

    def seq(values: Sequence[float]) -> str:
        return "[" + ", ".join(repr(float(v)) for v in values) + "]"

    lines = [f"frame: {json.dumps(data.frame)}",
             f"units: {{length: {length_unit}, angle: {angle_unit}}}",
             f"joints: [{', '.join(json.dumps(n) for n in data.joint_names)}]",
             "measurements:"]
    for m in data.measurements:
        lines.append(f"  - q: {seq([v / s for v, s in zip(m.q, qs, strict=True)])}")
        lines.append(f"    position: {seq([v / ls for v in m.position])}")
        if m.rpy is not None:
            lines.append(f"    rpy: {seq([v / ang for v in m.rpy])}")
        for key, value, s in (("step_position", m.step_m, ls), ("step_angle", m.step_rad, ang),
                              ("sigma_position", m.sigma_m, ls),
                              ("sigma_angle", m.sigma_rad, ang)):
            if value:
                lines.append(f"    {key}: {float(value / s)!r}")
        lines.append(f"    label: {json.dumps(m.label)}")
    return "\n".join(lines) + "\n"
