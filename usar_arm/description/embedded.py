"""The embedded simulator as a source of descriptions: start it, learn an arm over the wire
(from it or from a remote USARSim server), and check a learnt chain against the simulator's own
model. The only module besides :class:`~usar_arm.arm.facade.Arm` that starts a
:class:`SimServer`.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterator
from typing import Any

from usar_arm.description.accuracy import accuracy_report
from usar_arm.description.pipeline import DescribeOptions, Description, describe_arm
from usar_arm.discover.interview import DiscoveryRecord, discover
from usar_arm.sim.robot_spec import builtin_robots
from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.sim.world_spec import load_world
from usar_arm.usarsim.client import UsarClient


def known_classes(vehicles: bool = False) -> tuple[str, ...]:
    """The robot classes the embedded simulator can spawn (package-qualified): the arms, and
    with ``vehicles`` the ground vehicles too."""
    return tuple(sorted(builtin_robots(vehicles=vehicles)))


def vehicle_classes() -> tuple[str, ...]:
    """The ground vehicle classes the embedded simulator can spawn (package-qualified)."""
    return tuple(sorted(name for name, spec in builtin_robots(vehicles=True).items()
                        if spec.vehicle is not None))


def start_simulator(wire_precision: str = "udk", speed: float = 1.0,
                    world: str | None = None) -> SimServer:
    """A started embedded simulator on a free loopback port (stop it with ``stop()``), serving
    the shipped world ``world`` (default: the arms' cell)."""
    server = SimServer(SimOptions(host="127.0.0.1", port=0, wire_precision=wire_precision,
                                  speed=speed),
                       world_spec=load_world(world) if world is not None else None)
    server.start()
    return server


@contextlib.contextmanager
def embedded_simulator(wire_precision: str = "udk", world: str | None = None,
                       **kwargs: Any) -> Iterator[SimServer]:
    """The embedded simulator on a free loopback port, for the duration of a ``with`` block;
    ``world``: a world file or the name of a shipped one (default: the arms' cell)."""
    server = SimServer(SimOptions(host="127.0.0.1", port=0, wire_precision=wire_precision,
                                  **kwargs), world_spec=load_world(world))
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
    """:func:`~usar_arm.description.pipeline.describe_arm`, plus the accuracy check against
    the simulator's own model when the arm came from the embedded simulator."""
    assert record.arm is not None
    desc = describe_arm(record, options)
    if options.host is not None:
        return desc
    spec = builtin_robots()[options.robot_class]
    act = next(a for a in spec.actuators if a.name == record.arm.name)
    accuracy = accuracy_report(desc.chain, act, options.frame, options.accuracy_samples)
    return dataclasses.replace(desc, discovery={**desc.discovery,
                                                "accuracy_vs_simulator": accuracy})
