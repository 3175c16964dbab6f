"""The embedded simulator as a source of descriptions: start it, learn an arm over the wire
(from it or from a remote USARSim server), and check a learnt chain against the simulator's own
model. The only facade besides :class:`~usar_arm.arm.Arm` that starts a :class:`SimServer`.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterator
from typing import Any

import numpy as np

from usar_arm.description import DescribeOptions, Description, describe_arm
from usar_arm.discover.interview import DiscoveryRecord, discover
from usar_arm.model import KinematicChain
from usar_arm.sim.robot_spec import ActuatorSpec, builtin_robots, joint_frames, tip_pose
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.spatial import FLIP_X, angle_between
from usar_arm.usarsim.client import UsarClient


def known_classes() -> tuple[str, ...]:
    """The robot classes the embedded simulator can spawn (package-qualified)."""
    return tuple(sorted(builtin_robots()))


def start_simulator(wire_precision: str = "udk", speed: float = 1.0) -> SimServer:
    """A started embedded simulator on a free loopback port (stop it with ``stop()``)."""
    server = SimServer(SimOptions(host="127.0.0.1", port=0, wire_precision=wire_precision,
                                  speed=speed))
    server.start()
    return server


@contextlib.contextmanager
def embedded_simulator(wire_precision: str = "udk", **kwargs: Any) -> Iterator[SimServer]:
    """The embedded simulator on a free loopback port, for the duration of a ``with`` block."""
    server = SimServer(SimOptions(host="127.0.0.1", port=0, wire_precision=wire_precision,
                                  **kwargs))
    server.start()
    try:
        yield server
    finally:
        server.stop()


def run_discovery(options: DescribeOptions) -> DiscoveryRecord:
    """Connect (embedded or remote), spawn and learn the robot's arm."""
    known = known_classes()
    if options.host is None:
        with embedded_simulator(options.wire_precision) as server:
            assert server.port is not None
            with UsarClient("127.0.0.1", server.port, timeout=options.timeout) as client:
                return discover(client, options.robot_class, start=options.start,
                                actuator=options.actuator, timeout=options.timeout,
                                known_classes=known)
    with UsarClient(options.host, options.port, timeout=options.timeout) as client:
        return discover(client, options.robot_class, start=options.start,
                        actuator=options.actuator, timeout=options.timeout)


def describe(options: DescribeOptions) -> Description:
    """Discover the robot and build its validated description (nothing is written); with the
    embedded simulator, the description's notes carry its accuracy against the simulator's own
    model (``accuracy_vs_simulator``)."""
    return describe_discovered(run_discovery(options), options)


def describe_discovered(record: DiscoveryRecord, options: DescribeOptions) -> Description:
    """:func:`~usar_arm.description.describe_arm`, plus the accuracy check against the
    simulator's own model when the arm came from the embedded simulator."""
    assert record.arm is not None
    desc = describe_arm(record, options)
    if options.host is not None:
        return desc
    spec = builtin_robots()[options.robot_class]
    act = next(a for a in spec.actuators if a.name == record.arm.name)
    accuracy = accuracy_report(desc.chain, act, options.frame, options.accuracy_samples)
    return dataclasses.replace(desc, discovery={**desc.discovery,
                                                "accuracy_vs_simulator": accuracy})


def accuracy_report(chain: KinematicChain, act: ActuatorSpec, frame: str, samples: int,
                    seed: int = 0) -> dict[str, Any]:
    """Forward kinematics of ``chain`` against the simulator's ground truth at seeded random
    configurations: the largest joint-origin, joint-axis and flange errors."""
    flip = FLIP_X if frame == "z-up" else np.eye(3)
    rng = np.random.default_rng(seed)
    lo = np.array([j.limit_low for j in act.joints])
    hi = np.array([j.limit_high for j in act.joints])
    origin = axis = flange = 0.0
    zero_axis = 0.0
    for i in range(samples + 1):
        q = np.zeros(len(lo)) if i == 0 else rng.uniform(lo, hi)
        truth = joint_frames(act, q)
        got = [(j, f) for j, f in chain.joint_frames(q) if j.actuated]
        for (jt, f), t in zip(got, truth, strict=True):
            origin = max(origin, float(np.linalg.norm(f[:3, 3] - flip @ t[:3, 3])))
            err = angle_between(f[:3, :3] @ np.asarray(jt.axis), flip @ t[:3, 2])
            axis = max(axis, err)
            if i == 0:
                zero_axis = max(zero_axis, err)
        tp = tip_pose(act, q)
        flange = max(flange, float(np.linalg.norm(chain.frame_pose("flange", q)[:3, 3]
                                                  - flip @ tp[:3, 3])))
    # 12 significant digits: the last bits of these maxima depend on which SIMD kernel numpy
    # picks for the matrix products, and the report is a checked-in golden file.
    return {"reference": "the embedded simulator's own model (ground truth)",
            "configurations": samples, "seed": seed,
            "max_joint_origin_error_m": _digits(origin), "max_joint_axis_error_rad": _digits(axis),
            "max_joint_axis_error_at_zero_pose_rad": _digits(zero_axis),
            "max_flange_error_m": _digits(flange)}


def _digits(value: float) -> float:
    """``value`` rounded to 12 significant digits."""
    return float(f"{value:.12g}")


def urdf_accuracy(urdf: str, options: DescribeOptions, samples: int = 1000) -> dict[str, Any]:
    """:func:`accuracy_report` of a URDF (e.g. a calibrated one) of a built-in robot."""
    from usar_arm.urdf.reader import parse_urdf

    chain, _ = parse_urdf(urdf)
    spec = builtin_robots()[options.robot_class]
    act = next(a for a in spec.actuators if a.tip_sensor) if len(spec.actuators) > 1 \
        else spec.actuators[0]
    return accuracy_report(chain, act, options.frame, samples)
