"""Target poses of a placement study, from a YAML file.

```yaml
units: m-rad            # or mm-deg: positions in mm, angles in degrees
targets:                # tool0 poses in the cell's frame (the frame of the scene's obstacles)
  - name: pick
    xyz: [1.45, -0.45, 0.85]
    rpy: [3.14159, 0.0, 0.0]     # fixed axes: R = Rz(yaw) Ry(pitch) Rx(roll)
```

Every problem is collected and reported at once, each with its line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import Array, rpy_to_matrix, transform
from usar_arm.core.yamlio import line_of, load_yaml

UNITS = {"m-rad": (1.0, 1.0), "mm-deg": (1e-3, math.pi / 180.0)}


@dataclass(frozen=True)
class Target:
    """A named tool0 pose (4x4, m) in the cell's frame."""

    name: str
    pose: Array


def _numbers(value: Any, n: int) -> list[float] | None:
    if not isinstance(value, list) or len(value) != n:
        return None
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError):
        return None
    if isinstance(value[0], bool) or not all(math.isfinite(v) for v in out):
        return None
    return out


def parse_targets(data: Any, path: str) -> list[Target]:
    """Targets from a loaded YAML document.

    Raises:
        FileFormatError: naming the line and field of the first problem, and how many more.
    """
    problems: list[tuple[int | None, str, str]] = []
    if not isinstance(data, dict) or not isinstance(data.get("targets"), list):
        raise FileFormatError(path, "expected a mapping with a list 'targets' of poses "
                                    "(name, xyz, rpy)", line=line_of(data))
    units = data.get("units", "m-rad")
    if units not in UNITS:
        raise FileFormatError(path, f"units must be one of {', '.join(UNITS)}, got {units!r}",
                              line=line_of(data, "units"), field="units")
    scale, angle = UNITS[units]
    unknown = sorted(set(data) - {"units", "targets", "description"})
    if unknown:
        problems.append((line_of(data, unknown[0]), str(unknown[0]),
                         "unknown key (expected units, targets, description)"))
    targets: list[Target] = []
    seen: set[str] = set()
    for k, item in enumerate(data["targets"]):
        where = f"targets[{k}]"
        if not isinstance(item, dict):
            problems.append((line_of(data["targets"]), where, "expected name, xyz, rpy"))
            continue
        name = item.get("name")
        if not isinstance(name, str) or not name:
            problems.append((line_of(item), f"{where}.name", "a non-empty name is required"))
            continue
        if name in seen:
            problems.append((line_of(item, "name"), f"{where}.name",
                             f"duplicate target name '{name}'"))
        seen.add(name)
        xyz, rpy = _numbers(item.get("xyz"), 3), _numbers(item.get("rpy", [0, 0, 0]), 3)
        if xyz is None:
            problems.append((line_of(item, "xyz"), f"{where}.xyz",
                             f"expected 3 finite numbers ({'mm' if scale < 1 else 'm'})"))
        if rpy is None:
            problems.append((line_of(item, "rpy"), f"{where}.rpy",
                             f"expected 3 finite angles ({'deg' if angle < 1 else 'rad'})"))
        extra = sorted(set(item) - {"name", "xyz", "rpy"})
        if extra:
            problems.append((line_of(item, extra[0]), f"{where}.{extra[0]}",
                             "unknown key (expected name, xyz, rpy)"))
        if xyz is not None and rpy is not None:
            pose = transform(rpy_to_matrix(np.asarray(rpy) * angle), np.asarray(xyz) * scale)
            targets.append(Target(name, pose))
    if not problems and not targets:
        problems.append((line_of(data, "targets"), "targets", "no target poses"))
    if problems:
        line, field, text = problems[0]
        more = f" (and {len(problems) - 1} more problems)" if len(problems) > 1 else ""
        raise FileFormatError(path, text + more, line=line, field=field)
    return targets


def load_targets(path: str | Path) -> list[Target]:
    """Targets from a YAML file (see the module)."""
    return parse_targets(load_yaml(path), str(path))
