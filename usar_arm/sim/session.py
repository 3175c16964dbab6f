"""One client connection of the simulator: its robot and how it answers each command.

Behaviour follows UDK's ``BotConnection.uc`` (usarsim-protocol.md sections 3, 4 and 6): no reply to
INIT (the robot appears at the next physics frame), commands other than INIT/GETSTARTPOSES are
dropped until the robot exists, no reply to a GETCONF/GETGEO that matches nothing, ACT links are
0-based and out-of-range links are ignored, targets are clamped to the joint limits.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from usar_arm.sim import describe
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import RobotSpec
from usar_arm.sim.world_spec import WorldSpec
from usar_arm.spatial import matrix_to_rpy
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import NumberStyle

log = logging.getLogger("usar_arm.sim")

Send = Callable[[m.Message], None]


@dataclass
class PendingSpawn:
    """A robot requested by INIT, spawned at the next physics frame."""

    spec: RobotSpec
    name: str
    location: m.Vector3
    rotation: m.Vector3


@dataclass
class Session:
    """State of one connection.

    Attributes:
        key: unique id of the connection (also the robot's key in the physics world).
        peer: client address, for logs.
        send: callback that writes a message to this client.
    """

    key: str
    peer: str
    send: Send
    robot: RobotSpec | None = None
    robot_name: str = ""
    pending: PendingSpawn | None = None
    targets: dict[str, list[float]] = field(default_factory=dict)
    next_status: float = 0.0

    # ------------------------------------------------------------------ commands
    def handle(self, msg: m.Message, world: PhysicsWorld, world_spec: WorldSpec,
               robots: dict[str, RobotSpec], style: NumberStyle) -> None:
        """Act on one command from the client (replies go through ``send``)."""
        if isinstance(msg, m.GetStartPoses):
            self.send(m.StartPoses(world_spec.start_poses))
        elif isinstance(msg, m.Init):
            self._init(msg, world_spec, robots)
        elif self.robot is None:
            log.warning("%s: %s before the robot exists (send INIT first); dropped, as UDK does",
                        self.peer, type(msg).__name__.upper())
        elif isinstance(msg, (m.GetConf, m.GetGeo)):
            self._describe(msg, style)
        elif isinstance(msg, m.Act):
            self._act(msg, world)
        elif isinstance(msg, (m.Set, m.Drive)):
            log.info("%s: %s ignored: a %s has no effectors or drive", self.peer,
                     type(msg).__name__.upper(), self.robot.platform_type)
        else:
            head = msg.head if isinstance(msg, m.Unknown) else type(msg).__name__.upper()
            log.warning("%s: unknown or unsupported command %s ignored", self.peer, head)

    def _init(self, msg: m.Init, world_spec: WorldSpec, robots: dict[str, RobotSpec]) -> None:
        if self.robot is not None or self.pending is not None:
            log.warning("%s: INIT ignored: this connection already has a robot (one per "
                        "connection)", self.peer)
            return
        spec = next((r for c, r in robots.items() if c.lower() == msg.class_name.lower()), None)
        if spec is None:
            log.warning("%s: INIT: unknown robot class '%s' (known: %s); nothing spawned",
                        self.peer, msg.class_name, ", ".join(sorted(robots)))
            return
        if msg.start is not None:
            pose = world_spec.find_start(msg.start)
            if pose is None:
                log.warning("%s: INIT: unknown start '%s' (known: %s); nothing spawned",
                            self.peer, msg.start, ", ".join(p.name for p in world_spec.start_poses))
                return
            location, rotation = pose.location, pose.rotation
        else:
            location = msg.location or (0.0, 0.0, 0.0)
            rotation = msg.rotation or (0.0, 0.0, 0.0)
        self.pending = PendingSpawn(spec, msg.name or spec.short_name, location, rotation)

    def spawn_pending(self, world: PhysicsWorld) -> None:
        """Create the robot requested by INIT (called by the server between physics frames)."""
        p = self.pending
        if p is None:
            return
        self.pending = None
        world.add_robot(self.key, p.spec, p.location, p.rotation)
        self.robot, self.robot_name = p.spec, p.name
        self.targets = {a.name: [0.0] * len(a.joints) for a in p.spec.actuators}
        self.next_status = world.time + describe.SCAN_INTERVAL
        log.info("%s: spawned %s '%s' at %s", self.peer, p.spec.class_name, p.name,
                 ",".join(f"{v:g}" for v in p.location))

    def _describe(self, msg: m.GetConf | m.GetGeo, style: NumberStyle) -> None:
        assert self.robot is not None
        reply: m.Message | None
        if isinstance(msg, m.GetConf):
            reply = describe.conf_reply(self.robot, self.robot_name, msg.type, msg.name)
        else:
            reply = describe.geo_reply(self.robot, self.robot_name, msg.type, msg.name, style)
        if reply is None:
            log.info("%s: %s {Type %s} {Name %s} matches nothing; no reply, as UDK does "
                     "(components: %s)", self.peer, type(msg).__name__.upper(), msg.type,
                     msg.name, ", ".join(describe.known_components(self.robot)))
            return
        self.send(reply)

    def _act(self, msg: m.Act, world: PhysicsWorld) -> None:
        assert self.robot is not None
        act = next((a for a in self.robot.actuators if a.name.lower() == msg.name.lower()), None)
        if act is None:
            log.warning("%s: ACT for unknown actuator '%s' (this robot has: %s)", self.peer,
                        msg.name, ", ".join(a.name for a in self.robot.actuators))
            return
        if not msg.targets:
            log.warning("%s: ACT without any {Link i} {Value v} pair (both keys are "
                        "case-sensitive)", self.peer)
        cmd = self.targets[act.name]
        for link, value in msg.targets:
            if 0 <= link < len(act.joints):
                jt = act.joints[link]
                if not np.isfinite(value):
                    log.warning("%s: ACT link %d value %r is not finite; ignored", self.peer, link,
                                value)
                    continue
                cmd[link] = min(jt.limit_high, max(jt.limit_low, value))
            else:
                log.warning("%s: ACT link %d out of range 0..%d (ACT links are 0-based); "
                            "ignored", self.peer, link, len(act.joints) - 1)
        world.set_targets(self.key, act.name, cmd)

    # ------------------------------------------------------------------ streams
    def status(self, world: PhysicsWorld, style: NumberStyle) -> None:
        """Send STA, SEN (GroundTruth) and ASTA when the 10 Hz status timer is due."""
        if self.robot is None or world.time + 1e-9 < self.next_status:
            return
        self.next_status += describe.SCAN_INTERVAL
        t = world.time
        spec = self.robot
        self.send(m.Sta(t, spec.battery, spec.platform_type))
        plat = world.platform_pose(self.key)
        for it in spec.items:
            if it.type.lower() == "groundtruth":
                self.send(_pose_sen(t, it.name, plat))
        for act in spec.actuators:
            if act.tip_sensor:
                self.send(_pose_sen(t, act.tip_sensor, world.tip_pose(self.key, act.name)))
        for act in spec.actuators:
            values = world.joint_values(self.key, act.name)
            self.send(m.Asta(t, act.name, tuple((i + 1, float(v)) for i, v in enumerate(values))))


def _pose_sen(t: float, name: str, pose: np.ndarray) -> m.Sen:
    p = pose[:3, 3]
    return m.Sen("GroundTruth", name, t, (float(p[0]), float(p[1]), float(p[2])),
                 matrix_to_rpy(pose[:3, :3]))
