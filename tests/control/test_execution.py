"""Executing trajectories on the embedded simulator over real TCP: tracking, settling, the tip
error, tip correction, and every way a motion is stopped safely."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from tests.cpu_share import watched
from usar_arm import Arm
from usar_arm.control.executor import ExecutionOptions, Executor
from usar_arm.core.errors import ExecutionAbortedError, InvalidInputError
from usar_arm.core.spatial import rpy_to_matrix, transform

REPO = Path(__file__).resolve().parents[2]
DOWN = rpy_to_matrix((0.0, np.pi, 0.0))


@pytest.fixture(scope="module")
def arm() -> Iterator[Arm]:
    with Arm.connect("KR60") as live:
        yield live


def test_a_ptp_motion_is_tracked_and_settles_on_its_goal(arm: Arm) -> None:
    goal = np.array([0.6, -0.3, 0.35, 0.2, 0.6, -0.4])
    plan = arm.plan(joints=goal)
    aborted: ExecutionAbortedError | None = None
    with watched() as window:
        try:
            report = arm.execute(plan.trajectory)
        except ExecutionAbortedError as exc:
            aborted = exc
    if aborted is not None:  # (a starved simulator falls behind: a tracking error)
        window.judge_or_skip()
        raise aborted
    assert report.settled
    assert np.max(report.final_joint_error_rad) <= 2e-4  # tolerance 1e-4 + ASTA rounding
    assert report.tip is not None
    tip = report.tip.as_json()
    assert tip["tip_source"].startswith("GroundTruth sensor")
    # As learnt (the module's description cache is empty, so nothing is calibrated) and
    # without correction, the UDK-learnt model is off at the tool by what its printed precision
    # leaves: measured 2.30-2.42 mm and 0.17-0.30 mrad at this goal over repeated runs (3.1 mm at
    # worst over the benchmark's goals, bench/results/execution.json).
    assert tip["true_tip_error_m"] < 3.5e-3 and tip["true_tip_error_rad"] < 0.6e-3
    keys = report.as_json()
    assert {"final_joint_error_rad", "max_tracking_error_rad", "tip_error_m", "tip_error_rad",
            "rate_hz", "jitter_p99_ms"} <= set(keys)
    # Wall-clock targets: judged when the motion had the CPU (tests/cpu_share.py); 20.4 mrad
    # was measured once beside a load of about 5 on two cores, 0.9-2.4 mrad on an idle one.
    window.judge_or_skip()
    assert report.max_tracking_error_rad < 0.02  # feedforward removes the drives' lag
    assert report.rate_hz == pytest.approx(100, rel=0.1)
    assert len(report.executed.t) >= 10 * plan.trajectory.duration - 2


@pytest.mark.slow
def test_tip_correction_brings_the_real_tool_within_a_millimetre_and_a_milliradian(
        arm: Arm) -> None:
    # tool0 1.10 m high over the part: the KR60's suction cup, 0.19 m below tool0, is 11 cm
    # over the part's top (z = 0.80 m), clear of it and of the table.
    target = transform(DOWN, (1.45, -0.45, 1.10))
    plan = arm.plan(pose=target, scene="table")
    report = arm.execute(plan.trajectory, goal_pose=target, tip_correction=True)
    assert report.tip is not None
    tip = report.tip.as_json()
    assert tip["tip_bias_consistent"]
    assert tip["true_tip_error_m"] <= 1e-3 and tip["true_tip_error_rad"] <= 1e-3
    # The estimate after correction agrees with the simulator's truth.
    assert abs(tip["tip_error_m"] - tip["true_tip_error_m"]) < 0.5e-3
    assert np.max(report.final_joint_error_rad) <= 2e-4


def test_a_trajectory_that_does_not_start_where_the_arm_is_is_refused(arm: Arm) -> None:
    here = arm.joints()
    plan = arm.plan(joints=here + 0.2, start=here + 0.1)
    with pytest.raises(ExecutionAbortedError, match="not at the trajectory's start") as err:
        arm.execute(plan.trajectory)
    assert err.value.joint in arm.joint_names


def _still(arm: Arm) -> float:
    """How far the joints move in 0.5 s (rad)."""
    before = arm.joints()
    time.sleep(0.5)
    return float(np.max(np.abs(arm.joints() - before)))


def test_too_large_a_tracking_error_stops_the_arm_where_it_is(arm: Arm) -> None:
    start = arm.joints()
    plan = arm.plan(joints=start + np.array([0.5, 0, 0, 0, 0, 0]))
    tight = ExecutionOptions(max_tracking_error=0.002, feedforward=False)
    with pytest.raises(ExecutionAbortedError, match="tracking error") as err:
        arm.execute(plan.trajectory, options=tight)
    assert err.value.joint == arm.joint_names[0] and err.value.error_rad > 0.002
    assert err.value.at_time_s < plan.trajectory.duration
    time.sleep(0.5)
    assert _still(arm) < 2e-3
    assert abs(arm.joints()[0] - start[0]) < 0.4  # it stopped on the way
    arm.executor(ExecutionOptions())


def test_feedback_that_stops_coming_stops_the_motion(arm: Arm) -> None:
    plan = arm.plan(joints=arm.joints() + np.array([0, 0.2, 0, 0, 0, 0]))
    impatient = ExecutionOptions(feedback_timeout=0.02)  # ASTA comes every 0.1 s
    with pytest.raises(ExecutionAbortedError, match="no ASTA feedback"):
        arm.execute(plan.trajectory, options=impatient)
    time.sleep(0.5)
    assert _still(arm) < 2e-3
    arm.executor(ExecutionOptions())


def test_a_dropped_connection_aborts_with_a_clear_reason() -> None:
    with Arm.connect("KR60") as doomed:
        plan = doomed.plan(joints=doomed.joints() + np.array([0.8, 0, 0, 0, 0, 0]))
        doomed.executor().identify()
        server = doomed.server
        assert server is not None
        threading.Timer(0.5, server.stop).start()
        begin = time.perf_counter()
        with pytest.raises(ExecutionAbortedError) as err:
            doomed.execute(plan.trajectory)
        assert time.perf_counter() - begin < plan.trajectory.duration + 3
        assert "connection" in err.value.reason or "feedback" in err.value.reason


def test_an_offline_arm_refuses_to_execute() -> None:
    offline = Arm.from_files(REPO / "robots" / "generated" / "KR60.urdf")
    plan = offline.plan(joints=offline.home + 0.1)
    with pytest.raises(InvalidInputError, match="no connection"):
        offline.execute(plan.trajectory)


class _RecordingClient:
    """Stands in for a UsarClient: records the ACT targets sent."""

    def __init__(self) -> None:
        self.sent: list[dict[int, float]] = []
        self.bad_line_count = 0
        self.bad_lines: list[object] = []

    def act(self, actuator: str, targets: dict[int, float]) -> None:
        self.sent.append(dict(targets))


def test_a_non_finite_target_is_never_sent_and_a_hold_goes_where_it_is_told() -> None:
    client = _RecordingClient()
    executor = Executor(client, "Arm", (1, 2), ("j1", "j2"), np.array([-1.0, -1.0]),  # type: ignore[arg-type]
                        np.array([1.0, 1.0]))
    with pytest.raises(ExecutionAbortedError, match="non-finite"):
        executor.send(np.array([0.1, np.nan]))
    assert client.sent == []
    executor.hold(np.array([0.2, 5.0]))  # clamped into the limits
    assert client.sent == [{0: 0.2, 1: 1.0}]
    executor.hold(np.array([np.inf, 0.0]))  # refused, logged, nothing sent
    assert len(client.sent) == 1
