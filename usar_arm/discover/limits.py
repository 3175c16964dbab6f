"""Joint velocity, acceleration and jerk limits: from the server, a shipped table, or a file.

UDK's CONF carries position limits and MaxTorque but no speeds. Velocity comes, in order of
preference, from a user file (``--velocity-limits``), from CONF MaxSpeed (UT-era servers), from
the per-robot table shipped with usar-arm (``usar_arm/data/robot_limits.yaml``, labelled
estimates), or from conservative defaults that are announced as such. Never the 2012 node's
hard-coded 1.0 rad/s.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from usar_arm.core.errors import FileFormatError
from usar_arm.core.yamlio import line_of, load_yaml
from usar_arm.discover.wire_arm import WireArm

log = logging.getLogger("usar_arm.discover")

DEFAULTS = {
    "Revolute": {"velocity": 0.5, "acceleration": 1.0, "jerk": 10.0},
    "Prismatic": {"velocity": 0.25, "acceleration": 0.5, "jerk": 5.0},
}
"""Conservative defaults (rad or m, per s, s², s³) for joints nothing else describes."""
KEYS = ("velocity", "acceleration", "jerk")


@dataclass(frozen=True)
class MotionLimits:
    """Velocity, acceleration and jerk limits of one joint, and where each came from."""

    velocity: float
    acceleration: float
    jerk: float
    sources: tuple[str, str, str]


@dataclass(frozen=True)
class RobotTable:
    """A per-robot entry of the shipped table."""

    label: str
    sources: dict[str, str]
    joints: list[dict[str, float]]
    kuka_sign: list[float] | None = None
    kuka_offset_deg: list[float] | None = None
    home_kuka_deg: list[float] | None = None


def shipped_table() -> dict[str, RobotTable]:
    """The per-robot table shipped with usar-arm, keyed by actuator name."""
    with resources.as_file(resources.files("usar_arm") / "data" / "robot_limits.yaml") as fp:
        raw = load_yaml(fp)
    out = {}
    for name, entry in raw.items():
        axes = entry.get("kuka_axes") or {}
        out[name] = RobotTable(str(entry.get("label", "")), dict(entry.get("sources", {})),
                               [dict(j) for j in entry["joints"]], axes.get("sign"),
                               axes.get("offset_deg"), entry.get("home_kuka_deg"))
    return out


def load_limits_file(path: str | Path, n_joints: int, joint_names: list[str]
                     ) -> list[dict[str, float]]:
    """Read a user's limits file.

    Format: ``joints:`` followed by either a list in link order, or a mapping whose keys are
    1-based link numbers or joint names; each entry has any of velocity, acceleration, jerk
    (positive numbers, SI units)::

        joints:
          - {velocity: 2.0, acceleration: 4.0, jerk: 40.0}
          ...
    """
    p = str(path)
    data = load_yaml(path)
    if not isinstance(data, dict) or "joints" not in data:
        raise FileFormatError(p, "expected a mapping with a 'joints' entry", line=line_of(data))
    joints = data["joints"]
    out: list[dict[str, float]] = [{} for _ in range(n_joints)]
    if isinstance(joints, list):
        if len(joints) != n_joints:
            raise FileFormatError(p, f"lists {len(joints)} joints but the arm has {n_joints}",
                                  line=line_of(joints), field="joints")
        items: list[tuple[int, Any, int | None]] = [
            (i, e, line_of(joints, i)) for i, e in enumerate(joints)]
    elif isinstance(joints, dict):
        items = []
        for key, e in joints.items():
            if isinstance(key, int) and 1 <= key <= n_joints:
                idx = key - 1
            elif key in joint_names:
                idx = joint_names.index(key)
            else:
                raise FileFormatError(p, f"'{key}' is neither a link number 1..{n_joints} nor "
                                      f"a joint name ({', '.join(joint_names)})",
                                      line=line_of(joints, key), field=f"joints.{key}")
            items.append((idx, e, line_of(joints, key)))
    else:
        raise FileFormatError(p, "'joints' must be a list or a mapping",
                              line=line_of(data, "joints"), field="joints")
    for idx, entry, line in items:
        if not isinstance(entry, dict):
            raise FileFormatError(p, "expected {velocity: .., acceleration: .., jerk: ..}",
                                  line=line, field=f"joints[{idx}]")
        for key, value in entry.items():
            if key not in KEYS:
                raise FileFormatError(p, f"unknown key '{key}' (expected {', '.join(KEYS)})",
                                      line=line_of(entry, key), field=f"joints[{idx}].{key}")
            if not isinstance(value, (int, float)) or isinstance(value, bool) \
                    or not math.isfinite(value) or value <= 0:
                raise FileFormatError(p, f"must be a positive finite number, got {value!r}",
                                      line=line_of(entry, key), field=f"joints[{idx}].{key}")
            out[idx][key] = float(value)
    return out


def resolve(arm: WireArm, override: list[dict[str, float]] | None = None,
            table: dict[str, RobotTable] | None = None) -> tuple[list[MotionLimits], list[str]]:
    """Motion limits for each joint of ``arm`` and the warnings a user should see."""
    table = shipped_table() if table is None else table
    entry = table.get(arm.name)
    if entry is not None and len(entry.joints) != arm.dof:
        entry = None
    warnings = []
    out = []
    defaulted = []
    for i, jt in enumerate(arm.joints):
        values, sources = {}, {}
        for key in KEYS:
            if override and key in override[i]:
                values[key], sources[key] = override[i][key], "user file"
            elif key == "velocity" and jt.max_speed is not None and jt.max_speed > 0:
                values[key], sources[key] = jt.max_speed, "server CONF MaxSpeed"
            elif entry is not None and key in entry.joints[i]:
                values[key] = float(entry.joints[i][key])
                sources[key] = f"estimate ({entry.label})"
            else:
                values[key] = DEFAULTS[jt.joint_type][key]
                sources[key] = "conservative default"
                defaulted.append(f"link {jt.link} {key}")
        out.append(MotionLimits(values["velocity"], values["acceleration"], values["jerk"],
                                (sources["velocity"], sources["acceleration"], sources["jerk"])))
    if defaulted:
        warnings.append(f"no figures for {arm.name} ({', '.join(defaulted)}): conservative "
                        "defaults used (revolute 0.5 rad/s, 1 rad/s², 10 rad/s³; prismatic "
                        "0.25 m/s, 0.5 m/s², 5 m/s³), labelled as such; give real ones with "
                        "--velocity-limits FILE")
    for w in warnings:
        log.warning("%s", w)
    return out, warnings


def home_state(arm: WireArm, lower: list[float], upper: list[float],
               table: dict[str, RobotTable] | None = None) -> tuple[list[float], str]:
    """The ``home`` state (rad/m) and where it comes from.

    For a robot with a KUKA axis mapping in the table, KUKA's home (A2 = -90 deg, A3 = +90 deg)
    mapped through ``q = sign * (A - offset)``; otherwise each joint at 0, or mid-range when 0 is
    outside its limits.
    """
    import math

    table = shipped_table() if table is None else table
    entry = table.get(arm.name)
    if (entry is not None and entry.home_kuka_deg and entry.kuka_sign and entry.kuka_offset_deg
            and len(entry.home_kuka_deg) == arm.dof):
        q = [s * math.radians(a - o) for a, s, o in
             zip(entry.home_kuka_deg, entry.kuka_sign, entry.kuka_offset_deg, strict=True)]
        return [v + 0.0 for v in q], (f"KUKA home A1..A{arm.dof} = "
                                      f"{', '.join(f'{a:g}' for a in entry.home_kuka_deg)} deg "
                                      "mapped to this arm's zero and signs")
    q = [0.0 if lo <= 0 <= hi else (lo + hi) / 2 for lo, hi in zip(lower, upper, strict=True)]
    return q, "each joint at 0, or mid-range when 0 is outside its limits"
