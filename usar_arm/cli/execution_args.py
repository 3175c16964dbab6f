"""Execution options shared by ``plan --execute``, ``execute`` and ``demo``, the bag target
check, and how an execution report is printed."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.arm.facade import Arm
from usar_arm.cli.common import out
from usar_arm.control.executor import ExecutionOptions, ExecutionReport
from usar_arm.control.trajectory import ExecutedSamples, Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.export.bag import write_bag


def add_execution_args(p: argparse.ArgumentParser, bag: bool = True) -> None:
    """--rate, --settle-tolerance, --max-tracking-error, --tip-correction, --bag."""
    g = p.add_argument_group("execution")
    g.add_argument("--rate", type=float, default=100.0, metavar="HZ",
                   help="ACT commands per second (default 100)")
    g.add_argument("--settle-tolerance", type=float, default=1e-4, metavar="RAD",
                   help="every joint must end this close to its goal (default 0.0001, the "
                        "resolution of UDK's ASTA values)")
    g.add_argument("--max-tracking-error", type=float, default=0.1, metavar="RAD",
                   help="stop the arm when a joint strays further from the plan (default 0.1)")
    g.add_argument("--tip-correction", action="store_true",
                   help="measure the tool with the tip GroundTruth sensor and correct the joint "
                        "goal until the real tool0 is within 0.5 mm / 0.5 mrad of its goal "
                        "(about 8 s per move; needed for 1 mm accuracy over a UDK wire)")
    if bag:
        g.add_argument("--bag", default=None, metavar="DIR",
                       help="write a rosbag2 (MCAP) folder: robot description, tf, planned (and "
                            "executed) joint states, the planned trajectory")


def execution_options(args: argparse.Namespace) -> ExecutionOptions:
    """ExecutionOptions from the parsed arguments (values checked)."""
    for name in ("rate", "settle_tolerance", "max_tracking_error"):
        value = getattr(args, name)
        if not value > 0:
            raise InvalidInputError(f"--{name.replace('_', '-')} must be positive, got {value}")
    return ExecutionOptions(rate_hz=args.rate, settle_tolerance=args.settle_tolerance,
                            max_tracking_error=args.max_tracking_error)


def check_bag_target(path: str | None) -> None:
    """Refuse before moving the arm when the bag folder exists (nothing is overwritten)."""
    if path and Path(path).exists():
        raise InvalidInputError(f"--bag {path}: that path exists; give a new folder name (a "
                                "bag is never overwritten)")


def save_bag(path: str, arm: Arm, planned: Trajectory, executed: ExecutedSamples | None
             ) -> dict[str, int]:
    """Write the bag; returns topic -> message count."""
    summary = write_bag(path, arm.robot.chain, arm.urdf, planned, executed)
    return summary.topics


def _mm(value: Any) -> str:
    return "-" if value is None else f"{value * 1000:.2f} mm"


def _mrad(value: Any) -> str:
    return "-" if value is None else f"{value * 1000:.2f} mrad"


def print_report(report: ExecutionReport, names: tuple[str, ...]) -> None:
    """The human-readable execution report (stdout)."""
    worst = int(np.argmax(report.tracking_error_per_joint))
    out(f"executed {report.duration_s:.2f} s at {report.rate_hz:.1f} Hz (jitter p50 "
        f"{report.jitter_p50_ms:.2f} ms, p99 {report.jitter_p99_ms:.2f} ms); max tracking "
        f"error {report.max_tracking_error_rad:.4f} rad ({names[worst]})")
    final = float(np.max(report.final_joint_error_rad))
    out(f"{'settled' if report.settled else 'NOT settled'} in {report.settle_seconds:.2f} s; "
        f"final joint error {final:.5f} rad")
    tip = report.tip.as_json() if report.tip is not None else {}
    line = (f"tool0 error {_mm(tip.get('tip_error_m'))}, {_mrad(tip.get('tip_error_rad'))} "
            f"({tip.get('tip_source', 'unknown source')})")
    if "tip_error_before_correction_m" in tip:
        line += (f"; before correction {_mm(tip['tip_error_before_correction_m'])}, "
                 f"{_mrad(tip['tip_error_before_correction_rad'])}")
    out(line)
    if "true_tip_error_m" in tip:
        out(f"true tool0 error (embedded simulator's physics) {_mm(tip['true_tip_error_m'])}, "
            f"{_mrad(tip['true_tip_error_rad'])}")
