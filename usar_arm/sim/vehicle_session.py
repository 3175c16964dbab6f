"""The ground-vehicle half of a connection: DRIVE, the vehicle's CONF/GEO and its status stream.

DRIVE follows UDK (BotConnection.uc ProcessDrive; SkidSteeredVehicle.uc and
AckermanSteeredVehicle.uc Drive): ``Normalized`` and ``Light`` are remembered by the vehicle
whenever a DRIVE carries them; a skid-steered vehicle's wheels move only when both Left and
Right are given, an Ackermann vehicle's only when Speed, FrontSteer and RearSteer all are;
speeds beyond a wheel's MaxVelocity and angles beyond a steer joint's limits are clamped (and
logged here, where UDK clamps silently).
"""

from __future__ import annotations

import logging
import zlib
from collections.abc import Callable

from usar_arm.sim import vehicle_replies
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import RobotSpec
from usar_arm.sim.vehicle import VehicleSpec, drive_ackermann, drive_wheels
from usar_arm.sim.vehicle_sensors import VehicleSensors
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import UDK, NumberStyle

Reject = Callable[..., None]


class VehicleSession:
    """State of one spawned vehicle: its drive flags, its last steer angles and its sensors.

    Args:
        key: the robot's key in the physics world (seeds its noisy sensors).
        spec: the robot class.
    """

    def __init__(self, key: str, spec: RobotSpec):
        assert spec.vehicle is not None
        self.key = key
        self.spec = spec
        self.vehicle: VehicleSpec = spec.vehicle
        self.normalized = False
        self.light = False
        zero = UDK.fixed_at(0.0, 4) if spec.vehicle.ackermann else "0"
        self.steer_text: tuple[str, str] = (zero, zero)
        """STA's FrontSteer and RearSteer as printed (an Ackermann vehicle's last DRIVE)."""
        self.sensors = VehicleSensors(spec.vehicle, zlib.crc32(key.encode()))

    def drive(self, msg: m.Drive, world: PhysicsWorld, reject: Reject,
              style: NumberStyle = UDK) -> None:
        """Act on a DRIVE line."""
        if msg.normalized is not None:
            self.normalized = msg.normalized
        if msg.light is not None:
            self.light = msg.light
        if self.vehicle.ackermann:
            self._steer(msg, world, reject, style)
            return
        if msg.left is None or msg.right is None:
            reject("DRIVE without Left and Right", "DRIVE needs both {Left l} and {Right r} "
                   "to move the wheels (as UDK); the wheels keep their speeds",
                   level=logging.INFO)
            return
        cmd = drive_wheels(self.vehicle, msg.left, msg.right, self.normalized)
        if cmd.clamped:
            unit = "% of MaxVelocity" if self.normalized else " rad/s"
            reject("DRIVE clamped", "DRIVE {Left %g} {Right %g}%s beyond the wheels' limit "
                   "+-%g rad/s: %s clamped", msg.left, msg.right, unit,
                   self.vehicle.max_speed, ", ".join(cmd.clamped), level=logging.INFO)
        world.set_wheel_speeds(self.key, cmd.speeds)

    def _steer(self, msg: m.Drive, world: PhysicsWorld, reject: Reject,
               style: NumberStyle) -> None:
        """An Ackermann vehicle's DRIVE (docs/protocol.md section 10)."""
        if msg.speed is None or msg.front_steer is None or msg.rear_steer is None:
            reject("DRIVE without Speed and steers", "DRIVE needs {Speed s} {FrontSteer a} "
                   "{RearSteer b} to move an Ackermann vehicle (as UDK); it keeps its speed "
                   "and steer", level=logging.INFO)
            return
        cmd = drive_ackermann(self.vehicle, msg.speed, msg.front_steer, msg.rear_steer,
                              self.normalized)
        clamped = cmd.wheels.clamped + cmd.clamped
        if clamped:
            reject("DRIVE clamped", "DRIVE {Speed %g} {FrontSteer %g} {RearSteer %g} beyond "
                   "the wheels' or steer joints' limits: %s clamped", msg.speed,
                   msg.front_steer, msg.rear_steer, ", ".join(clamped), level=logging.INFO)
        self.steer_text = (style.fixed_at(msg.front_steer, 4),
                           style.fixed_at(msg.rear_steer, 4))
        world.set_wheel_speeds(self.key, cmd.wheels.speeds)
        world.set_steer_targets(self.key, cmd.targets)

    def set(self, msg: m.Set, reject: Reject) -> None:
        """Act on a SET line addressed to a sensor (no reply, as UDK)."""
        problem = self.sensors.command(msg.type, msg.name, msg.opcode, msg.params)
        if problem is not None:
            reject("SET refused", "SET ignored: %s", problem[:200], level=logging.INFO)

    def describe(self, msg: m.GetConf | m.GetGeo, style: NumberStyle) -> m.Message | None:
        """The CONF or GEO answering ``msg``, or None (no reply)."""
        veh, spec = self.vehicle, self.spec
        if isinstance(msg, m.GetConf):
            if msg.type == "Robot":
                return vehicle_replies.robot_conf(spec, veh, style)
            return vehicle_replies.sensor_conf(spec, veh, msg.type, msg.name, style)
        if msg.type == "Robot":
            return vehicle_replies.robot_geo(spec, veh, style)
        return vehicle_replies.sensor_geo(spec, veh, msg.type, msg.name)

    def status(self, t: float, world: PhysicsWorld) -> list[m.Message]:
        """STA and the SEN lines due at this status tick (time ``t``, s)."""
        return [vehicle_replies.status(self.spec, t, self.light, self.steer_text),
                *self.sensors.read(t, world, self.key)]
