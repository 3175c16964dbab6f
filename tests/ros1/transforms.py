"""tf messages as ROS 1 delivered them (tests/ros1/client.py's JSON) compared edge by edge: the
judge's own quaternion -> matrix, no code of the node's."""

from __future__ import annotations

from typing import Any

import numpy as np

Edges = dict[tuple[str, str], np.ndarray]


def matrix(transform: dict[str, Any]) -> np.ndarray:
    """4x4 of a geometry_msgs/Transform (as JSON)."""
    q, p = transform["rotation"], transform["translation"]
    x, y, z, w = q["x"], q["y"], q["z"], q["w"]
    out = np.eye(4)
    out[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    out[:3, 3] = (p["x"], p["y"], p["z"])
    return out


def edges_by_stamp(messages: list[tuple[float, dict[str, Any]]], any_stamp: bool = False
                   ) -> dict[tuple[int, int], Edges]:
    """Stamp -> (parent, child) -> 4x4, over every message (``any_stamp``: all under one key)."""
    out: dict[tuple[int, int], Edges] = {}
    for _, msg in messages:
        for t in msg["transforms"]:
            stamp = (0, 0) if any_stamp else tuple(t["header"]["stamp"])
            edges = out.setdefault(stamp, {})  # type: ignore[arg-type]
            edges[(t["header"]["frame_id"], t["child_frame_id"])] = matrix(t["transform"])
    return out


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle (rad) between two rotations, from the skew part (exact near zero)."""
    r = a[:3, :3].T @ b[:3, :3]
    skew = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / 2
    return float(np.arcsin(min(1.0, np.linalg.norm(skew)))) if np.trace(r) > 1 else np.pi


def compare_trees(pairs: list[tuple[Edges, Edges]]) -> tuple[float, float]:
    """The largest position (m) and rotation (rad) difference of the edges of each pair's
    second tree (which must all be in the first)."""
    worst_p = worst_r = 0.0
    for mine, theirs in pairs:
        missing = set(theirs) - set(mine)
        assert not missing, f"edges missing: {sorted(missing)}"
        for key, m in theirs.items():
            worst_p = max(worst_p, float(np.max(np.abs(mine[key][:3, 3] - m[:3, 3]))))
            worst_r = max(worst_r, rotation_angle(mine[key], m))
    return worst_p, worst_r
