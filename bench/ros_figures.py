"""The figures both ROS probes compute (bench/ros_probe.py on ROS 2, bench/ros1_probe.py on
ROS 1), from plain numbers: no middleware here, so each probe imports its own and the two
stages' figures mean the same thing.

* :func:`proc`: a process's CPU seconds, resident memory and threads (from /proc);
* :func:`stats`: n, p50, p99, max;
* :func:`matrix`: a transform from translation and quaternion (the probe's own, not the node's);
* :func:`joint_state_figures`: rate, drops and latency of a joint_states window;
* :func:`tool0_error`: tool0 composed from tf against FK of the joint state with the same stamp.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

TICKS = os.sysconf("SC_CLK_TCK")


def proc(pid: int) -> dict[str, float]:
    """CPU seconds (user + system), resident MB and thread count of process ``pid``."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    status = Path(f"/proc/{pid}/status").read_text()
    rss = next(int(line.split()[1]) for line in status.splitlines() if line.startswith("VmRSS"))
    return {"cpu_s": (int(fields[11]) + int(fields[12])) / TICKS, "rss_mb": rss / 1024,
            "threads": int(fields[17])}


def stats(values: list[float]) -> dict[str, float]:
    """n, p50, p99 and max of ``values`` (just n when empty)."""
    a = np.asarray(values, float)
    return {"n": len(a), "p50": float(np.percentile(a, 50)), "p99": float(np.percentile(a, 99)),
            "max": float(a.max())} if len(a) else {"n": 0}


def matrix(translation: Any, rotation: Any) -> np.ndarray:
    """4x4 of a translation (x, y, z attributes) and a unit quaternion (x, y, z, w)."""
    x, y, z, w = rotation.x, rotation.y, rotation.z, rotation.w
    out = np.eye(4)
    out[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                   [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                   [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    out[:3, 3] = (translation.x, translation.y, translation.z)
    return out


def joint_state_figures(stamps: np.ndarray, received: np.ndarray) -> dict[str, Any]:
    """Rate, drops, gaps and latency (receipt - stamp) of a window of joint states (s)."""
    gaps = np.diff(stamps)
    period = float(np.median(gaps))
    seconds = float(stamps[-1] - stamps[0])
    return {"messages": len(stamps), "seconds": seconds, "rate_hz": (len(stamps) - 1) / seconds,
            # the ASTA lines the window should hold at the stream's period, less those received
            # (a late line followed by an early one is not a drop)
            "dropped": max(0, round(seconds / period) + 1 - len(stamps)),
            "late_gaps_over_1.8_periods": int(np.sum(gaps > 1.8 * period)),
            "max_gap_s": float(gaps.max()),
            "latency_ms": stats(((received - stamps) * 1000).tolist())}


Tree = dict[str, tuple[str, np.ndarray]]
"""child frame -> (parent frame, 4x4)."""


def tool0_error(static: Tree, messages: list[tuple[Any, Tree]], positions: dict[Any, Any],
                model: Any) -> dict[str, Any]:
    """tool0 composed from ``static`` and each tf message (stamp, tree) against
    ``model.frame_pose`` of the joint positions with the same stamp."""
    worst_m = worst_rad = 0.0
    checked = 0
    for stamp, moving in messages:
        tree = {**static, **moving}
        q = positions.get(stamp)
        if q is None or "tool0" not in tree or "link_6" not in tree:
            continue
        pose, frame = np.eye(4), "tool0"
        while frame != "base_link":
            parent, m = tree[frame]
            pose, frame = m @ pose, parent
        fk = model.frame_pose(np.array(q), "tool0")
        worst_m = max(worst_m, float(np.max(np.abs(pose[:3, 3] - fk[:3, 3]))))
        worst_rad = max(worst_rad, float(np.max(np.abs(pose[:3, :3] - fk[:3, :3]))))
        checked += 1
    return {"messages_checked": checked, "tool0_max_error_m": worst_m,
            "tool0_max_rotation_error": worst_rad}


def goal_period(send: Callable[[float], dict[str, Any]], pid: int, seconds: float
                ) -> tuple[dict[str, Any], float]:
    """Goals for ``seconds`` in 30 s chunks (``send(chunk_s)`` returns a chunk's goals,
    latencies, error codes and errors), sampling node ``pid`` after each: the period's figures
    and the node's CPU (fraction of a core)."""
    before = proc(pid)["cpu_s"]
    t0 = time.perf_counter()
    chunks, samples = [], [{"t_s": 0.0, **proc(pid)}]
    while time.perf_counter() - t0 < seconds - 1:
        chunks.append(send(min(30.0, seconds)))
        samples.append({"t_s": time.perf_counter() - t0, **proc(pid)})
    busy = (proc(pid)["cpu_s"] - before) / (time.perf_counter() - t0)
    return {"goals": sum(c["goals"] for c in chunks),
            "accept_ms": stats([v for c in chunks for v in c["latencies"]]),
            "error_codes": {k: sum(c["error_codes"].get(k, 0) for c in chunks)
                            for k in sorted({k for c in chunks for k in c["error_codes"]})},
            "errors": [e for c in chunks for e in c["errors"]][:5],
            "node_over_time": [{k: round(v, 3) for k, v in x.items() if k != "cpu_s"}
                               for x in samples]}, busy


def node_figures(idle: float, busy: float, start: dict[str, float], end: dict[str, float]
                 ) -> dict[str, float]:
    """The node's CPU (fractions of a core, idle and executing) and its memory and threads
    at the start and the end."""
    return {"cpu_idle_fraction_of_a_core": idle, "cpu_executing_fraction_of_a_core": busy,
            "rss_mb_start": start["rss_mb"], "rss_mb_end": end["rss_mb"],
            "threads_start": start["threads"], "threads_end": end["threads"]}


def emit(doc: dict[str, Any], path: Path | None) -> None:
    """Print the probe's document and write it to ``path`` (when given)."""
    text = json.dumps(doc, indent=1)
    print(text)
    if path:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text + "\n")
