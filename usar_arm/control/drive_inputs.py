"""A drive's input files: velocity scripts and waypoint lists, checked, with the errors users
see (file, line, what was expected). Metres, seconds, radians; waypoints in the map frame
(REP-103: the world file's x, and its y negated).

* A script is YAML (a list of ``[duration_s, v_mps, w_radps]`` or of mappings with keys
  ``duration``, ``v``, ``w``) or CSV (``.csv``: one ``duration,v,w`` row per segment, an
  optional header row, ``#`` comments).
* Waypoints are ``x,y`` tokens, or a file: YAML (a list of ``[x, y]``) or CSV rows ``x,y``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from usar_arm.control.pursuit import Segment
from usar_arm.core.errors import FileFormatError, InvalidInputError
from usar_arm.core.vehicle_errors import OutsideWorldError
from usar_arm.core.world_file import Scenery
from usar_arm.core.yamlio import line_of, load_yaml


def _rows(path: Path, width: int, header: str) -> list[tuple[int, list[Any]]]:
    """(line, values) of each row of a CSV file or YAML list (``width`` numbers each)."""
    if path.suffix.lower() != ".csv":
        data = load_yaml(path)
        if not isinstance(data, list) or not data:
            raise FileFormatError(str(path), f"expected a non-empty list of {header}")
        return [(line_of(data, i) or 0, item) for i, item in enumerate(data)]
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise FileFormatError(str(path), f"cannot read: {exc}") from None
    rows: list[tuple[int, list[Any]]] = []
    for n, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line or (not rows and not line[0].lstrip("+-").replace(".", "")[:1].isdigit()):
            continue  # a blank or comment line, or the header row
        rows.append((n, [cell.strip() for cell in line.split(",")]))
    if not rows:
        raise FileFormatError(str(path), f"expected rows of {header}")
    return rows


def _numbers(item: Any, keys: Sequence[str], path: Path, line: int, header: str
             ) -> list[float]:
    values: Any = [item.get(k) for k in keys] if isinstance(item, dict) else item
    try:
        numbers = [float(v) for v in values]
    except (TypeError, ValueError):
        raise FileFormatError(str(path), f"expected {header}, got {item!r}", line=line) from None
    if len(numbers) != len(keys) or not all(math.isfinite(v) for v in numbers):
        raise FileFormatError(str(path), f"expected {len(keys)} finite numbers ({header}), got "
                              f"{item!r}", line=line)
    return numbers


def load_script(path: str | Path) -> tuple[Segment, ...]:
    """The segments of a velocity script file.

    Raises:
        FileFormatError: not a script (names the line), or a duration that is not positive.
    """
    p, header = Path(path), "duration (s), v (m/s), w (rad/s)"
    out = []
    for line, item in _rows(p, 3, header):
        duration, v, w = _numbers(item, ("duration", "v", "w"), p, line, header)
        if duration <= 0:
            raise FileFormatError(str(p), f"a segment's duration must be > 0 s, got {duration}",
                                  line=line)
        out.append(Segment(duration, v, w))
    return tuple(out)


def parse_waypoints(tokens: Sequence[str]) -> tuple[tuple[float, float], ...]:
    """Waypoints from ``x,y`` tokens (m), or from a file when the one token names one.

    Raises:
        InvalidInputError: a token is not two finite numbers. FileFormatError: a bad file.
    """
    if len(tokens) == 1 and "," not in tokens[0]:
        p, header = Path(tokens[0]), "x (m), y (m)"
        if not p.is_file():
            raise InvalidInputError(f"--waypoints: '{tokens[0]}' is neither x,y nor a file")
        return tuple((a, b) for a, b in (_numbers(item, ("x", "y"), p, line, header)
                                         for line, item in _rows(p, 2, header)))
    out = []
    for token in tokens:
        try:
            x, y = (float(v) for v in token.split(","))
        except ValueError:
            raise InvalidInputError(f"--waypoints: expected x,y in metres, got '{token}'"
                                    ) from None
        if not (math.isfinite(x) and math.isfinite(y)):
            raise InvalidInputError(f"--waypoints: '{token}' is not two finite numbers")
        out.append((x, y))
    if not out:
        raise InvalidInputError("--waypoints needs at least one x,y")
    return tuple(out)


def check_in_world(waypoints: Sequence[tuple[float, float]], scenery: Scenery,
                   world: str) -> None:
    """Refuse waypoints outside the world's boxes' extent or inside one of its boxes (map
    frame: the world file's y negated).

    Raises:
        OutsideWorldError: names the waypoint and the extent or the box.
    """
    if not scenery.boxes:
        return
    corners = [(x, -y) for box in scenery.boxes for x, y in box.corners_xy()]
    lo = (min(c[0] for c in corners), min(c[1] for c in corners))
    hi = (max(c[0] for c in corners), max(c[1] for c in corners))
    for i, (x, y) in enumerate(waypoints, start=1):
        if not (lo[0] < x < hi[0] and lo[1] < y < hi[1]):
            raise OutsideWorldError(i, (x, y), f"outside the world {world} (x {lo[0]:g} to "
                                    f"{hi[0]:g} m, y {lo[1]:g} to {hi[1]:g} m, map frame)")
        for box in scenery.boxes:
            c, s = math.cos(box.yaw), math.sin(box.yaw)
            dx, dy = x - box.center[0], -y - box.center[1]
            if abs(c * dx + s * dy) < box.half[0] and abs(-s * dx + c * dy) < box.half[1]:
                raise OutsideWorldError(i, (x, y), f"inside {box.name} of the world {world}")
