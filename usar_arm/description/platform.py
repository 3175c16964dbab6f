"""A ground vehicle's description, learnt over the wire and written: ``usar-arm urdf --robot P3AT``.

Which path a robot takes (arm or platform) is decided by its class when the embedded simulator
knows it, else (a remote server) by the spawned robot's first status line
(:func:`is_ground_vehicle`); the platform path checks the robot's ``CONF {Type GroundVehicle}``
before anything is learnt. The arm path (:mod:`.pipeline`) is untouched by this module.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from usar_arm.core.fileio import write_tree_atomic
from usar_arm.core.platform import REP105_FRAMES, PlatformDescription, PlatformFrames
from usar_arm.core.version import __version__
from usar_arm.description.embedded import (
    embedded_simulator,
    known_classes,
    start_simulator,
    vehicle_classes,
)
from usar_arm.discover.interview import DiscoveryRecord, spawn_robot
from usar_arm.discover.platform import GROUND_VEHICLE, learn_platform
from usar_arm.urdf.platform import platform_urdf, validate_platform
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.codec import parse_line


@dataclass(frozen=True)
class PlatformResult:
    """A learnt, validated platform: its description, URDF and the raw exchanges."""

    description: PlatformDescription
    urdf: str
    record: DiscoveryRecord
    frames: PlatformFrames = REP105_FRAMES

    def discovery_json(self) -> str:
        """``<Robot>.platform.json``: what was learnt and the lines it was learnt from."""
        data: dict[str, Any] = {
            "usar_arm_version": __version__,
            "robot": {"class": self.record.robot_class, "start": self.record.start,
                      "host": self.record.host},
            "platform": dataclasses.asdict(self.description),
            "footprint_radius_m": self.description.footprint_radius,
            "exchanges": [{"request": e.request, "reply": e.reply}
                          for e in self.record.exchanges]}
        return json.dumps(data, indent=2, sort_keys=True) + "\n"


def is_ground_vehicle(robot_class: str, host: str | None = None, port: int = 3000,
                      timeout: float = 5.0) -> bool:
    """Whether ``robot_class`` is described as a ground vehicle.

    A class the embedded simulator knows decides by itself (``USARBot.P3AT`` is a vehicle, the
    arms are not), so the arm path keeps its exchanges unchanged; a class it does not know, on a
    remote server, is spawned once on a connection of its own and its first status line
    decides (``STA {Type GroundVehicle}``). The platform path then checks the spawned robot's
    ``CONF {Type GroundVehicle}`` before it learns anything.
    """
    qualified = robot_class if "." in robot_class else f"USARBot.{robot_class}"
    if qualified.lower() in (c.lower() for c in vehicle_classes()):
        return True
    if host is None or qualified.lower() in (c.lower() for c in known_classes()):
        return False
    with UsarClient(host, port, timeout=timeout) as client:
        record, _ = spawn_robot(client, qualified, timeout=timeout)
    first = parse_line(record.exchanges[-1].reply)
    return isinstance(first, m.Sta) and first.type == GROUND_VEHICLE


def learn(robot_class: str, host: str | None = None, port: int = 3000,
          start: str | None = None, timeout: float = 5.0, wire_precision: str = "udk",
          frames: PlatformFrames = REP105_FRAMES) -> PlatformResult:
    """Spawn the vehicle (the embedded simulator when ``host`` is None), learn it and build its
    validated URDF (nothing is written)."""
    known = vehicle_classes() if host is None else ()
    if host is None:
        with embedded_simulator(wire_precision) as server:
            assert server.port is not None
            with UsarClient("127.0.0.1", server.port, timeout=timeout) as client:
                record, desc = learn_platform(client, robot_class, start, timeout, known)
    else:
        with UsarClient(host, port, timeout=timeout) as client:
            record, desc = learn_platform(client, robot_class, start, timeout)
    return described(record, desc, frames)


def described(record: DiscoveryRecord, desc: PlatformDescription,
              frames: PlatformFrames = REP105_FRAMES) -> PlatformResult:
    """The validated URDF of a learnt platform."""
    urdf = platform_urdf(desc, frames)
    validate_platform(desc, urdf, frames)
    return PlatformResult(desc, urdf, record, frames)


def write_platform(result: PlatformResult, out_dir: str | Path) -> dict[str, Path]:
    """Write ``<Robot>.urdf`` and ``<Robot>.platform.json``, each atomically (the URDF first)."""
    name = result.description.name
    files = {f"{name}.urdf": result.urdf, f"{name}.platform.json": result.discovery_json()}
    paths = write_tree_atomic(out_dir, files)
    by_name = {p.name: p for p in paths}
    return {"urdf": by_name[f"{name}.urdf"], "platform": by_name[f"{name}.platform.json"]}


class LivePlatform:
    """A spawned vehicle kept alive for a driver: its connection (and the embedded simulator
    when no host is given) and its learnt description. Close it to destroy the robot.

    Args: as :func:`learn`; ``world`` names the embedded simulator's world (default ``rooms``,
    the shipped world for ground vehicles).
    """

    def __init__(self, robot_class: str, host: str | None = None, port: int = 3000,
                 start: str | None = None, timeout: float = 5.0, wire_precision: str = "udk",
                 frames: PlatformFrames = REP105_FRAMES, world: str = "rooms"):
        self.server = start_simulator(wire_precision, world=world) if host is None else None
        try:
            address = ("127.0.0.1", self.server.port) if self.server is not None else (host, port)
            assert address[0] is not None and address[1] is not None
            self.client = UsarClient(address[0], address[1], timeout=timeout)
            self.client.connect()
            known = vehicle_classes() if host is None else ()
            record, desc = learn_platform(self.client, robot_class, start, timeout, known)
            self.result = described(record, desc, frames)
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        """Close the connection (the robot is destroyed) and stop the embedded simulator."""
        client = getattr(self, "client", None)
        if client is not None:
            client.close()
        if self.server is not None:
            self.server.stop()
