"""Shared helpers of the peer runners (stdlib + numpy only).

Every runner is ``python run_<peer>_<stage>.py PROBLEMS.json RESULTS.json`` and does:

    spec, out = peerio.args()                       # read the problem file
    ...build the peer's solver once (not timed)...
    results = peerio.solve_all(spec["problems"], solve_one)   # never raises
    peerio.write(out, peer="pytracik", dist="pytracik", stage="ik", results=results)

``solve_one(problem) -> dict`` returns the result fields; it times only the peer call with
:func:`timed`.  An exception becomes ``{"id", "success": false, "error": "..."}``.
"""

from __future__ import annotations

import importlib.metadata
import json
import math
import sys
import time
import traceback
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

SAMPLE_DT = 0.01  # 100 Hz, the rate of "samples" in the topp results


def args() -> tuple[dict, str]:
    """(problem file contents, results path) from ``sys.argv``."""
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} PROBLEMS.json RESULTS.json")
    with open(sys.argv[1], encoding="utf-8") as f:
        return json.load(f), sys.argv[2]


def timed(fn: Callable, *a, **kw) -> tuple[Any, float]:
    """(fn(*a, **kw), wall seconds of that call alone, time.perf_counter)."""
    t0 = time.perf_counter()
    r = fn(*a, **kw)
    return r, time.perf_counter() - t0


def version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "unknown"


def quat_to_matrix(wxyz: Iterable[float]) -> np.ndarray:
    """3x3 rotation of a unit quaternion (w, x, y, z); normalised first."""
    w, x, y, z = np.asarray(list(wxyz), float) / np.linalg.norm(list(wxyz))
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def pose_matrix(xyz: Iterable[float], quat_wxyz: Iterable[float]) -> np.ndarray:
    """4x4 homogeneous transform from a position and a (w, x, y, z) quaternion."""
    t = np.eye(4)
    t[:3, :3] = quat_to_matrix(quat_wxyz)
    t[:3, 3] = list(xyz)
    return t


def nearest(qs: list, seed: Iterable[float]) -> list | None:
    """The configuration of ``qs`` nearest (Euclidean, joint space) to ``seed``."""
    if not qs:
        return None
    s = np.asarray(list(seed), float)
    return list(min(qs, key=lambda q: float(np.linalg.norm(np.asarray(q, float) - s))))


def sample_times(duration: float, dt: float = SAMPLE_DT) -> np.ndarray:
    """0, dt, 2 dt, ... and the end time itself (so the last sample is the goal)."""
    n = math.floor(duration / dt + 1e-9)
    t = np.arange(n + 1) * dt
    if duration - t[-1] > 1e-9:
        t = np.append(t, duration)
    return t


def chain_path(urdf: str, base: str, tip: str) -> list[tuple[str, str, str]]:
    """[(joint name, joint type, child link), ...] of the URDF chain from ``base`` to ``tip``."""
    import xml.etree.ElementTree as ET

    joints = {j.find("child").get("link"): j for j in ET.parse(urdf).getroot().findall("joint")}
    path, link = [], tip
    while link != base:
        if link not in joints:
            raise ValueError(f"{tip!r} is not below {base!r} in {urdf}")
        j = joints[link]
        path.insert(0, (j.get("name"), j.get("type"), link))
        link = j.find("parent").get("link")
    return path


def reorder(q: Iterable[float], names: list[str], wanted: list[str]) -> list[float]:
    """``q`` given in ``names`` order, returned in ``wanted`` order."""
    d = dict(zip(names, list(q), strict=True))
    return [float(d[n]) for n in wanted]


def waypoints(p: dict, dof: int) -> np.ndarray:
    """The problem's waypoints as an (n, dof) finite array; ValueError otherwise (checked here
    because a native peer may crash on a malformed path instead of raising)."""
    wp = np.array(p["waypoints"], float)
    if wp.ndim != 2 or wp.shape[1] != dof or len(wp) < 1 or not np.all(np.isfinite(wp)):
        raise ValueError(
            f"waypoints must be an (n >= 1, {dof}) array of numbers, got shape {wp.shape}"
        )
    return wp


def solve_all(
    problems: list[dict], solve_one: Callable[[dict], dict], warmup: int = 3
) -> list[dict]:
    """Run ``solve_one`` on every problem; an exception is recorded, never raised.

    The first ``warmup`` problems are solved once before, untimed and discarded: first calls
    in a process pay for lazy initialisation, page faults and thread start-up (TRAC-IK's first
    calls take ~4 ms instead of ~0.3 ms)."""
    for p in problems[:warmup]:
        try:
            solve_one(p)
        except Exception:
            pass
    out = []
    for p in problems:
        try:
            r = {"id": p["id"], **solve_one(p)}
        except Exception as e:
            r = {
                "id": p.get("id"),
                "success": False,
                "seconds": None,
                "error": f"{type(e).__name__}: {e}".strip(),
            }
            if "--traceback" in sys.argv or "PEERS_TRACEBACK" in __import__("os").environ:
                traceback.print_exc()
        out.append(r)
    return out


def solve_by_scene(
    problems: list[dict],
    enter_scene: Callable[[str], None],
    solve_one: Callable[[dict], dict],
    warmup: int = 1,
) -> list[dict]:
    """Like :func:`solve_all` for plan problems: problems are grouped by their "scene",
    ``enter_scene(name)`` (untimed: builds or swaps the obstacles) runs once before each group,
    the group's first ``warmup`` problems are solved once, untimed, in every scene (a scene's
    first calls pay for its own lazy set-up; usar-arm's solvers warm up the same way), and the
    results come back in the problems' order."""
    groups: dict[str, list[int]] = {}
    for i, p in enumerate(problems):
        groups.setdefault(p.get("scene", ""), []).append(i)
    out: list[dict | None] = [None] * len(problems)
    for scene, idx in groups.items():
        group = [problems[i] for i in idx]
        try:
            enter_scene(scene)
            res = solve_all(group, solve_one, warmup=warmup)
        except Exception as e:
            res = [
                {
                    "id": p.get("id"),
                    "success": False,
                    "seconds": None,
                    "error": f"scene {scene!r}: {type(e).__name__}: {e}",
                }
                for p in group
            ]
        for i, r in zip(idx, res, strict=True):
            out[i] = r
    return out  # type: ignore[return-value]


def joint_limits_yaml(names: list[str], vmax: list[float] | None, amax: list[float] | None) -> str:
    """A MoveIt-style joint_limits YAML (roboplan's importJointLimitsFromConfig wants each
    value as a one-element sequence)."""
    lines = ["joint_limits:"]
    for i, n in enumerate(names):
        lines.append(f"  {n}:")
        if vmax is not None:
            lines += ["    has_velocity_limits: true", f"    max_velocity: [{float(vmax[i])!r}]"]
        if amax is not None:
            lines += [
                "    has_acceleration_limits: true",
                f"    max_acceleration: [{float(amax[i])!r}]",
            ]
    return "\n".join(lines) + "\n"


def _plain(x: Any) -> Any:
    """JSON-safe copy: numpy to Python numbers/lists, NaN and infinities to null."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return _plain(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        f = float(x)
        return f if math.isfinite(f) else None
    return x


def write(
    path: str, *, peer: str, dist: str, stage: str, results: list[dict], **extra: Any
) -> None:
    """Write the results file and print a one-line summary to stderr."""
    doc = _plain(
        {"peer": peer, "version": version(dist), "stage": stage, **extra, "results": results}
    )
    with open(path, "w", encoding="utf-8") as f:
        json.dump(doc, f, allow_nan=False)
        f.write("\n")
    ok = [r for r in results if r.get("success")]
    secs = [r["seconds"] for r in ok if r.get("seconds") is not None]
    mean = f"{1e3 * sum(secs) / len(secs):.3f} ms" if secs else "n/a"
    errors = sum(1 for r in results if "error" in r)
    print(
        f"[{peer} {doc['version']} {stage}] {len(ok)}/{len(results)} succeeded, "
        f"mean {mean} over successes, {errors} error(s) -> {path}",
        file=sys.stderr,
    )
