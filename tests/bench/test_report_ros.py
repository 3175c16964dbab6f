"""The ros stage under trouble: its report says what was not measured instead of failing on it
(a CI run once crashed the whole benchmark's report on a cmd_vel window in which no DRIVE was
matched), and two benchmarks at once take turns with the probes' ROS domains."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import common  # noqa: E402
import report  # noqa: E402


def _vehicle(drive: dict[str, Any]) -> dict[str, Any]:
    latencies = common.stats([0.8, 0.9, 1.3])
    return {"scan": {"messages": 3, "rate_hz": 5.0, "ranges": [181], "latency_ms": latencies},
            "cmd_vel_to_drive": drive, "load_average_1min_at_end": 0.5,
            "node": {"cpu_streaming_fraction_of_a_core": 0.02,
                     "cpu_driving_fraction_of_a_core": 0.03}}


def _row(lines: list[str], figure: str) -> str:
    return next(line for line in lines if line.startswith(f"| {figure} |"))


def test_a_command_window_that_failed_says_why() -> None:
    drive = {"sent": 0, "matched": 0, "latency_ms": common.stats([]),
             "subscriber_matched_s": None, "failure": "no subscriber on cmd_vel within 60 s"}
    doc = {"settings": {}, "cases": {"P3AT": _vehicle(drive)}}
    row = _row(report.ros_section(doc), "cmd_vel -> DRIVE on the wire")
    assert "not measured: no subscriber on cmd_vel within 60 s" in row


def test_a_window_with_nothing_matched_shows_dashes_not_numbers() -> None:
    drive = {"sent": 200, "matched": 0, "latency_ms": common.stats([])}
    lines = report.ros_section({"settings": {}, "cases": {"P3AT": _vehicle(drive)}})
    row = _row(lines, "cmd_vel -> DRIVE on the wire")
    assert "0 of 200 matched: median - ms, p99 - ms, max - ms" in row


def test_a_measured_window_gives_its_figures_and_its_discovery_apart() -> None:
    drive = {"sent": 200, "matched": 199, "latency_ms": common.stats([0.5, 0.7, 1.1]),
             "subscriber_matched_s": 0.12, "first_drive_s": 0.05}
    lines = report.ros_section({"settings": {}, "cases": {"P3AT": _vehicle(drive)}})
    row = _row(lines, "cmd_vel -> DRIVE on the wire")
    assert "199 of 200 matched: median 0.70 ms, p99 1.09 ms, max 1.1 ms" in row
    assert "discovery, 0.12 s" in row and "first DRIVE, 0.05 s" in row


def test_a_second_benchmark_waits_for_the_first_ones_probe_then_says_so() -> None:
    import ros

    with ros._stage_lock():
        with pytest.raises(TimeoutError, match="still held by another benchmark's ros probe"):
            with ros._stage_lock(wait_s=0.2):
                pass
    with ros._stage_lock(wait_s=0.2):  # released with the first
        pass
