"""The ROS stage: the live nodes measured from another process by clients of their own: the arm
on ROS 2 (``usar-arm ros``, embedded KR60) by ``bench/ros_probe.py``, the ground vehicle
(``usar-arm ros --robot P3AT``, against ``usar-arm sim --world rooms``) by
``bench/ros_platform.py``, and the arm on ROS 1 (``usar-arm ros --ros1``, its own roscore) by
``bench/ros1_probe.py``, a rospy client run in the ROS 1 interpreter (case ``KR60-ROS1``; the
same figures and targets as the ROS 2 arm's; skipped with the reason where Debian's ROS 1 is
missing).

The probe runs in a subprocess of the interpreter that runs the benchmark (the test venv, where
the ``ros`` extra and its message build live), so that ``bench/run.py`` itself never imports
rclpy. Quick mode watches /joint_states for 10 s and sends goals for 20 s; the full run watches
60 s and sends goals every 2 s for 10 minutes (the memory and thread growth target).
Without the ``ros`` extra or its message build the stage is reported as skipped, with the
reason the probe gave.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import common
from common import Context

PROBE = Path(__file__).resolve().with_name("ros_probe.py")
PLATFORM_PROBE = PROBE.with_name("ros_platform.py")
ROS1_PROBE = PROBE.with_name("ros1_probe.py")
PLATFORM_SECONDS = {"quick": 10.0, "full": 60.0}
"""Each of the platform probe's two windows (/scan, then cmd_vel) in seconds per mode."""
WINDOWS = {"quick": (10.0, 20.0), "full": (60.0, 600.0)}
"""(joint_states window, goal period) in seconds per mode."""
DOMAINS = {"ros_probe.json": 100, "ros_platform.json": 101, "ros1_probe.json": 0}
"""ROS_DOMAIN_ID of each probe and its node: one each, so that no participant of the first
probe's processes lingers in the second's graph, and outside the ids the tests lease (5..99,
tests/ros/helpers.py), so that a test session beside the benchmark never joins it."""


LOCK = Path(tempfile.gettempdir()) / "usar-arm-bench-ros.lock"
"""Held while a probe runs: two benchmarks at once on one machine (two test workers running the
quick benchmark did, under make test-slow) would otherwise share the domains above, each probe
seeing the other's node."""
LOCK_WAIT_S = 1800.0


@contextlib.contextmanager
def _stage_lock(wait_s: float = LOCK_WAIT_S) -> Iterator[None]:
    """Hold :data:`LOCK`, waiting up to ``wait_s`` for another benchmark's probe to end.

    Raises:
        TimeoutError: the lock was still held after ``wait_s`` seconds.
    """
    with open(LOCK, "w") as lock:
        end = time.monotonic() + wait_s
        while True:
            try:
                fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except OSError:
                if time.monotonic() > end:
                    raise TimeoutError(f"{LOCK} still held by another benchmark's ros probe "
                                       f"after {wait_s:.0f} s") from None
                time.sleep(1.0)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _probe(ctx: Context) -> tuple[dict[str, Any] | None, str]:
    seconds, goal_seconds = WINDOWS[ctx.mode]
    return _run(ctx, [str(PROBE), "--seconds", str(seconds), "--goal-seconds",
                      str(goal_seconds)], "ros_probe.json", 240 + seconds + goal_seconds * 1.5)


def _platform_probe(ctx: Context) -> tuple[dict[str, Any] | None, str]:
    seconds = PLATFORM_SECONDS[ctx.mode]
    return _run(ctx, [str(PLATFORM_PROBE), "--seconds", str(seconds)], "ros_platform.json",
                240 + 3 * seconds)


def _ros1_probe(ctx: Context) -> tuple[dict[str, Any] | None, str]:
    """The ROS 1 probe in the ROS 1 interpreter (its own roscore: no domain to choose)."""
    from usar_arm.ros import ros1_setup

    try:
        env = ros1_setup.setup()
    except ros1_setup.Ros1SetupError as exc:
        return None, str(exc)
    seconds, goal_seconds = WINDOWS[ctx.mode]
    return _run(ctx, [str(ROS1_PROBE), "--seconds", str(seconds), "--goal-seconds",
                      str(goal_seconds)], "ros1_probe.json", 240 + seconds + goal_seconds * 1.5,
                python=str(env.python), env=env.environ())


def _run(ctx: Context, command: list[str], name: str, budget: float,
         python: str = sys.executable, env: dict[str, str] | None = None
         ) -> tuple[dict[str, Any] | None, str]:
    """Run a probe (in this interpreter unless ``python``) on the stage's domain; (its
    results, '') or (None, why)."""
    out = ctx.work / name
    domain = ["--domain", str(DOMAINS[name])] if DOMAINS[name] else []
    try:
        done = subprocess.run(
            [python, *command, *domain, "--json", str(out)],
            capture_output=True, text=True, timeout=budget, env=env or {**os.environ})
    except subprocess.TimeoutExpired:
        return None, f"the probe did not finish within {budget:.0f} s"
    if done.returncode != 0 or not out.is_file():
        tail = (done.stderr.strip().splitlines() or ["(no output)"])[-1]
        return None, f"probe exit code {done.returncode}: {tail}"
    return common.read_json(out), ""


def _hops(js: dict[str, Any]) -> str:
    """The p99 of each hop of the joint states' path (ms), as the note of its target."""
    hops = {name.split(":")[0]: v["p99"] for name, v in js.get("hops_ms", {}).items()
            if "p99" in v}
    return ("p99 per hop (ms): " + ", ".join(f"{k} {v:.2f}" for k, v in hops.items())
            if hops else "")


def _targets(doc: dict[str, Any], prefix: str = "") -> list[dict[str, Any]]:
    """The arm node's targets (``prefix``: the middleware, for the ROS 1 case)."""
    js, tf, goals, refused = (doc["joint_states"], doc["tf"], doc["goals"],
                              doc["refused_goals"])

    def t(label: str, *rest: Any) -> dict[str, Any]:
        return common.target(prefix + label, *rest)

    out = [
        t("/joint_states: ASTA arrival -> subscriber in another process, p99",
          js["latency_ms"].get("p99"), 2.0, "<=", "ms", _hops(js)),
        t(f"/joint_states: lines missing over {js['seconds']:.0f} s", js["dropped"], 0, "<=",
          "messages"),
        t("/tf: tool0 composed vs FK of the joint state (position)",
          tf["tool0_max_error_m"], 1e-9, "<=", "m", "the probe's own Pinocchio FK"),
        t("/tf: tool0 composed vs FK of the joint state (rotation matrix entries)",
          tf["tool0_max_rotation_error"], 1e-9, "<=", "(unit-less)"),
        t("FollowJointTrajectory: goal accepted, p99", goals["accept_ms"].get("p99"), 20.0,
          "<=", "ms", f"{goals['goals']} goals, every 2 s"),
        t("FollowJointTrajectory: goals ending SUCCESSFUL",
          goals["error_codes"].get("0", 0) / max(goals["goals"], 1), 1.0, ">=", "fraction",
          "path and goal tolerances as the goals give them"),
        t("FollowJointTrajectory: refused goal (unknown joint) answered, p99",
          refused["refused_result_ms"].get("p99"), 20.0, "<=", "ms"),
    ]
    if "seq_gaps" in js:
        out.append(t("/joint_states: header.seq gaps (messages lost in ROS 1's transport)",
                     js["seq_gaps"], 0, "<=", "gaps"))
    if len(goals["node_over_time"]) < 3:  # quick mode: too short to judge growth
        return out
    return [
        *out,
        t("Node memory growth while executing goals, after the first 30 s",
          _growth(goals["node_over_time"], "rss_mb"), 2.0, "<=", "MB",
          f"{goal_seconds_of(goals):.0f} s of goals; the first goals load the executor"),
        t("Node thread growth while executing goals, after the first 30 s",
          _growth(goals["node_over_time"], "threads"), 0, "<=", "threads"),
    ]


def _ros1_targets(doc: dict[str, Any]) -> list[dict[str, Any]]:
    return _targets(doc, "ROS 1 ")


def goal_seconds_of(goals: dict[str, Any]) -> float:
    """How long goals were sent (s): the last sample's time."""
    return float(goals["node_over_time"][-1]["t_s"])


def _growth(samples: list[dict[str, float]], key: str) -> float | None:
    """Growth of ``key`` from the sample after the first 30 s chunk to the last (None with
    fewer than three samples: too short a run to tell)."""
    return None if len(samples) < 3 else samples[-1][key] - samples[1][key]


def _platform_targets(doc: dict[str, Any]) -> list[dict[str, Any]]:
    t = common.target
    return [
        t("P3AT /scan: SEN arrival -> subscriber in another process, p99",
          doc["scan"]["latency_ms"].get("p99"), 5.0, "<=", "ms",
          f"{doc['scan']['messages']} scans"),
        t("P3AT /cmd_vel -> DRIVE line on the wire, p99",
          doc["cmd_vel_to_drive"]["latency_ms"].get("p99"), 5.0, "<=", "ms",
          "the simulator in its own process, a relay on the wire"),
    ]


def run(ctx: Context) -> dict[str, Any]:
    """Run the probes and return the stage document (cases hold their figures as measured)."""
    started = time.perf_counter()
    seconds, goal_seconds = WINDOWS[ctx.mode]
    settings: dict[str, Any] = {
        "joint_states_window_s": seconds, "goal_period_s": goal_seconds,
        "platform_window_s": PLATFORM_SECONDS[ctx.mode], "ros_domain_ids": DOMAINS,
        "probes": ["bench/ros_probe.py", "bench/ros_platform.py", "bench/ros1_probe.py"]}
    cases: dict[str, Any] = {}
    targets: list[dict[str, Any]] = []
    skipped: dict[str, str] = {}
    for name, probe, judge in (("KR60", _probe, _targets),
                               ("P3AT", _platform_probe, _platform_targets),
                               ("KR60-ROS1", _ros1_probe, _ros1_targets)):
        with _stage_lock():
            doc, reason = probe(ctx)
        if doc is None:
            common.log(f"ros stage, {name}: skipped: {reason}")
            skipped[name] = reason
            continue
        cases[name] = doc
        targets += judge(doc)
    if skipped:
        settings["skipped"] = "; ".join(f"{k}: {v}" for k, v in skipped.items())
    return common.stage_document("ros", ctx.mode, settings, cases, targets, started)
