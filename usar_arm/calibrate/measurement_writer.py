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
from usar_arm.core.fileio import write_atomic


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
    extra = _uncertainty_columns(data, length_unit, angle_unit)
    header += [name for name, _, _ in extra] + ["label"]
    buf = io.StringIO()
    buf.write(f"# frame: {data.frame}\n")
    if data.measured_in != "tracker":
        buf.write(f"# measured_in: {data.measured_in}\n")
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
        row += [repr(getattr(m, attr) / scale) for _, attr, scale in extra] + [m.label]
        w.writerow(row)
    return buf.getvalue()


def _uncertainty_columns(data: MeasurementSet, length_unit: str, angle_unit: str
                         ) -> list[tuple[str, str, float]]:
    """(column, Measurement attribute, unit scale) of the step and sigma columns to write: a
    step column when a reading is quantised, a sigma column when a reading states a sigma or a
    step (a reading's sigma 0 beside a step: no noise beyond the truncation; an unquantised
    reading without a sigma has none, which the reader reads as 'not stated'). Raises
    ValueError for readings that state a sigma beside readings that state none."""
    ls, ang = LENGTH_UNITS[length_unit], ANGLE_UNITS[angle_unit]
    out = []
    for kind, unit, scale in (("m", length_unit, ls), ("rad", angle_unit, ang)):
        steps = [getattr(m, f"step_{kind}") for m in data.measurements]
        sigmas = [getattr(m, f"sigma_{kind}") for m in data.measurements]
        if any(steps):
            out.append((f"step_{unit}", f"step_{kind}", scale))
        if any(steps) or any(sigmas):
            if any(sg == 0 and st == 0 for sg, st in zip(sigmas, steps, strict=True)):
                raise ValueError(f"some readings state a sigma_{kind} and others none; a "
                                 "file states it for all or none")
            out.append((f"sigma_{unit}", f"sigma_{kind}", scale))
    return sorted(out, key=lambda c: c[0].startswith("sigma"))


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
             *([f"measured_in: {data.measured_in}"] if data.measured_in != "tracker" else []),
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
