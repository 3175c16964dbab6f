"""One client connection of the simulator: its robot and how it answers each command.

Behaviour follows UDK's ``BotConnection.uc`` (docs/protocol.md sections 3, 4 and 6): no reply to
INIT (the robot appears at the next physics frame), commands other than INIT/GETSTARTPOSES are
dropped until the robot exists, no reply to a GETCONF/GETGEO that matches nothing, ACT links are
0-based and out-of-range links are ignored, targets are clamped to the joint limits.

Everything refused or ignored is counted per connection (:class:`Rejections`) and logged: the
first few of each kind in full, the rest as a count every :data:`SUMMARY_INTERVAL_S` and at
disconnect, so that a client flooding junk cannot flood the log.
"""

from __future__ import annotations

import logging
import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from usar_arm.core.spatial import matrix_to_rpy
from usar_arm.sim import replies
from usar_arm.sim.effectors import TYPES as EFFECTOR_TYPES
from usar_arm.sim.effectors import Effectors
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import ActuatorSpec, RobotSpec
from usar_arm.sim.vehicle_session import VehicleSession
from usar_arm.sim.world_controller import CLASS_NAME as WORLD_CONTROLLER
from usar_arm.sim.world_controller import FindRobot, WorldController
from usar_arm.sim.world_spec import WorldSpec
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import NumberStyle

log = logging.getLogger("usar_arm.sim")

Send = Callable[[m.Message], None]

LOG_FIRST = 3
"""Refusals of each kind per connection that are logged one by one."""
SUMMARY_INTERVAL_S = 10.0
"""Wall seconds between the counts of refusals that were not logged one by one."""
MAX_CACHED_REPLIES = 64
"""CONF/GEO replies a session remembers (they depend only on the robot and the request)."""


@dataclass
class Rejections:
    """What one connection sent and what of it was refused, with a throttled log.

    Attributes:
        peer: client address, for logs.
        received: complete lines received (including refused ones).
        served: lines handled without any refusal.
        bytes_in: bytes received.
        counts: refusals by kind (``malformed``, ``oversized``, ``binary``, ``unknown command``...).
    """

    peer: str
    received: int = 0
    served: int = 0
    bytes_in: int = 0
    total: int = 0
    """Refusals of every kind."""
    counts: Counter[str] = field(default_factory=Counter)
    _unlogged: Counter[str] = field(default_factory=Counter)
    _last_summary: float = field(default_factory=time.monotonic)

    def count(self, kind: str, n: int = 1) -> None:
        """Count refusals without logging them (the disconnect summary reports them)."""
        self.counts[kind] += n
        self.total += n

    def reject(self, kind: str, fmt: str, *args: object, level: int = logging.WARNING) -> None:
        """Count a refusal of ``kind``; log it in full if it is one of the first few."""
        n = self.counts[kind] = self.counts[kind] + 1
        self.total += 1
        if n <= LOG_FIRST:
            more = (f" (further '{kind}' refusals are only counted)" if n == LOG_FIRST else "")
            log.log(level, "%s: " + fmt + more, self.peer, *args)
            return
        self._unlogged[kind] += 1
        now = time.monotonic()
        if now - self._last_summary >= SUMMARY_INTERVAL_S:
            log.warning("%s: %d more refused in the last %.0f s, not logged one by one (%s)",
                        self.peer, sum(self._unlogged.values()), now - self._last_summary,
                        _kinds(self._unlogged))
            self._unlogged.clear()
            self._last_summary = now

    def summary(self) -> str:
        """One line for the disconnect log: lines, served, refused by kind, bytes."""
        refused = f", refused {self.total} ({_kinds(self.counts)})" if self.counts else ""
        return (f"{self.received} lines, served {self.served}{refused}; "
                f"{self.bytes_in} bytes in")


def _kinds(counts: Counter[str]) -> str:
    return ", ".join(f"{kind} {n}" for kind, n in counts.most_common())


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
    vehicle: VehicleSession | None = None
    """The drive and sensors of a spawned ground vehicle (None for an arm)."""
    effectors: Effectors | None = None
    """The tool changers and tools of a spawned arm (None when it has none)."""
    world_controller: WorldController | None = None
    """Set when the connection INITed as a WorldController (it then has no robot)."""
    rejections: Rejections = field(init=False)
    _actuators: dict[str, ActuatorSpec] = field(default_factory=dict)
    _replies: dict[tuple[bool, str, str | None], m.Message | None] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.rejections = Rejections(self.peer)

    # ------------------------------------------------------------------ commands
    def handle(self, msg: m.Message, world: PhysicsWorld, world_spec: WorldSpec,
               robots: dict[str, RobotSpec], style: NumberStyle,
               find_robot: FindRobot = lambda name: None) -> None:
        """Act on one command from the client (replies go through ``send``); ``find_robot``
        gives the key of the robot a WorldController's AbsMove names (None: no such robot)."""
        reject = self.rejections.reject
        if isinstance(msg, m.Act) and self.robot is not None:
            self._act(msg, world)
        elif isinstance(msg, m.GetStartPoses):
            self.send(m.StartPoses(world_spec.start_poses))
        elif isinstance(msg, m.Init):
            self._init(msg, world_spec, robots)
        elif isinstance(msg, m.Control):
            self._control(msg, world, world_spec, find_robot)
        elif self.robot is None:
            head = msg.head if isinstance(msg, m.Unknown) else type(msg).__name__.upper()
            if self.world_controller is not None:
                reject("WorldController", "%s from a WorldController (it has no robot); "
                       "ignored, as UDK does", head[:40], level=logging.INFO)
            else:
                reject("before INIT", "%s before the robot exists (send INIT first); "
                       "dropped, as UDK does", head[:40])
        elif isinstance(msg, (m.GetConf, m.GetGeo)):
            self._describe(msg, style, world)
        elif isinstance(msg, m.Set) and self.effectors is not None:
            if msg.type == "Joint":
                reject("SET Joint", "SET {Type Joint} is not simulated (move joints with ACT); "
                       "ignored", level=logging.INFO)
            else:
                self.effectors.set(msg, world, reject)
        elif isinstance(msg, m.Drive) and self.vehicle is not None:
            self.vehicle.drive(msg, world, reject, style)
        elif isinstance(msg, m.Set) and self.vehicle is not None:
            self.vehicle.set(msg, reject)
        elif isinstance(msg, (m.Set, m.Drive)):
            reject("no effector", "%s ignored: a %s has no effectors or drive",
                   type(msg).__name__.upper(), self.robot.platform_type, level=logging.INFO)
        else:
            head = msg.head if isinstance(msg, m.Unknown) else type(msg).__name__.upper()
            reject("unknown command", "unknown or unsupported command %r ignored", head[:40])

    def _control(self, msg: m.Control, world: PhysicsWorld, world_spec: WorldSpec,
                 find_robot: FindRobot) -> None:
        wc = self.world_controller
        if wc is None:
            self.rejections.reject("not a WorldController", "CONTROL {Type %s}: BotConnection: "
                                   "Bot is not a world controller; ignored", msg.type[:40])
            return
        reply = wc.handle(msg, world, world_spec, find_robot)
        if reply is not None:
            self.send(reply)

    def _init(self, msg: m.Init, world_spec: WorldSpec, robots: dict[str, RobotSpec]) -> None:
        reject = self.rejections.reject
        if self.robot is not None or self.pending is not None or self.world_controller:
            reject("second INIT", "INIT ignored: this connection already has a robot (one per "
                   "connection)")
            return
        if msg.class_name.lower() == WORLD_CONTROLLER.lower():
            self.world_controller = WorldController(self.key, msg.name or "", reject)
            self.robot_name = msg.name or ""
            log.info("%s: a WorldController '%s'", self.peer, (msg.name or "")[:80])
            return
        spec = next((r for c, r in robots.items() if c.lower() == msg.class_name.lower()), None)
        if spec is None:
            reject("unknown class", "INIT: unknown robot class '%s' (known: %s); nothing spawned",
                   msg.class_name[:80], ", ".join(sorted(robots)))
            return
        if msg.start is not None:
            pose = world_spec.find_start(msg.start)
            if pose is None:
                reject("unknown start", "INIT: unknown start '%s' (known: %s); nothing spawned",
                       msg.start[:80], ", ".join(p.name for p in world_spec.start_poses))
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
        world.add_robot(self.key, p.spec, p.location, p.rotation, name=p.name)
        self.robot, self.robot_name = p.spec, p.name
        self.targets = {a.name: [0.0] * len(a.joints) for a in p.spec.actuators}
        self._actuators = {a.name.lower(): a for a in p.spec.actuators}
        if p.spec.vehicle is not None:
            self.vehicle = VehicleSession(self.key, p.spec)
        if p.spec.tool_changers:
            self.effectors = Effectors(self.key, p.spec)
        self.next_status = world.time + replies.SCAN_INTERVAL
        log.info("%s: spawned %s '%s' at %s", self.peer, p.spec.class_name, p.name,
                 ",".join(f"{v:g}" for v in p.location))

    def _describe(self, msg: m.GetConf | m.GetGeo, style: NumberStyle, world: PhysicsWorld
                  ) -> None:
        assert self.robot is not None
        reply: m.Message | None
        key = (isinstance(msg, m.GetConf), msg.type, msg.name)
        if self.effectors is not None and msg.type.lower() in {t.lower() for t in
                                                               EFFECTOR_TYPES}:
            reply = self._describe_effectors(msg, style, world)  # tools come and go
        elif key in self._replies:  # the answers never change: compute each once
            reply = self._replies[key]
        else:
            if self.vehicle is not None:
                reply = self.vehicle.describe(msg, style)
            elif isinstance(msg, m.GetConf):
                reply = replies.conf_reply(self.robot, self.robot_name, msg.type, msg.name)
            else:
                reply = replies.geo_reply(self.robot, self.robot_name, msg.type, msg.name, style)
            if len(self._replies) < MAX_CACHED_REPLIES:
                self._replies[key] = reply
        if reply is None:
            components = replies.known_components(self.robot)
            if self.effectors is not None:
                components += self.effectors.components(world)
            self.rejections.reject(
                "matches nothing", "%s {Type %s} {Name %s} matches nothing; no reply, as UDK "
                "does (components: %s)", type(msg).__name__.upper(), msg.type[:80],
                (msg.name or "")[:80], ", ".join(components),
                level=logging.INFO)
            return
        self.send(reply)

    def _describe_effectors(self, msg: m.GetConf | m.GetGeo, style: NumberStyle,
                            world: PhysicsWorld) -> m.Message | None:
        assert self.effectors is not None
        if isinstance(msg, m.GetConf):
            items = self.effectors.conf(msg.type, msg.name, world, style)
            return m.Conf(msg.type, tuple(items)) if items else None
        geo = self.effectors.geo(msg.type, msg.name, world)
        return m.Geo(msg.type, tuple(geo)) if geo else None

    def _act(self, msg: m.Act, world: PhysicsWorld) -> None:
        assert self.robot is not None
        reject = self.rejections.reject
        act = self._actuators.get(msg.name.lower())
        if act is None and self.effectors is not None and msg.gripper is not None:
            if self.effectors.act_gripper(msg.name, msg.gripper, world):
                return
        if act is None:
            reject("unknown actuator", "ACT for unknown actuator '%s' (this robot has: %s)",
                   msg.name[:80], ", ".join(a.name for a in self.robot.actuators))
            return
        if not msg.targets:
            reject("ACT without links", "ACT without any {Link i} {Value v} pair (both keys "
                   "are case-sensitive)")
        cmd = self.targets[act.name]
        joints = act.joints
        for link, value in msg.targets:
            if 0 <= link < len(joints):
                if not math.isfinite(value):
                    reject("non-finite value", "ACT link %d value %r is not finite; ignored",
                           link, value)
                    continue
                jt = joints[link]
                cmd[link] = min(jt.limit_high, max(jt.limit_low, value))
            else:
                reject("link out of range", "ACT link %d out of range 0..%d (ACT links are "
                       "0-based); ignored", link, len(joints) - 1)
        world.set_targets(self.key, act.name, cmd)

    # ------------------------------------------------------------------ streams
    def status(self, world: PhysicsWorld) -> list[m.Message]:
        """STA, SEN (GroundTruth) and ASTA when the 10 Hz status timer is due, else nothing.

        The caller sends them (in one write)."""
        if self.robot is None or world.time + 1e-9 < self.next_status:
            return []
        self.next_status += replies.SCAN_INTERVAL
        t = world.time
        if self.vehicle is not None:
            return self.vehicle.status(t, world)
        spec = self.robot
        out: list[m.Message] = [m.Sta(t, spec.battery, spec.platform_type)]
        plat = world.platform_pose(self.key)
        for it in spec.items:
            if it.type.lower() == "groundtruth":
                out.append(_pose_sen(t, it.name, plat))
        for act in spec.actuators:
            if act.tip_sensor:
                out.append(_pose_sen(t, act.tip_sensor, world.tip_pose(self.key, act.name)))
        for act in spec.actuators:
            values = world.joint_values(self.key, act.name).tolist()
            out.append(m.Asta(t, act.name, tuple(enumerate(values, start=1))))
        if self.effectors is not None:
            out += self.effectors.status(t, world)
        out.append(m.ContactReport(self.robot_name, world.contacts.take(self.key), t))
        return out


def _pose_sen(t: float, name: str, pose: np.ndarray) -> m.Sen:
    p = pose[:3, 3]
    return m.Sen("GroundTruth", name, t, (float(p[0]), float(p[1]), float(p[2])),
                 matrix_to_rpy(pose[:3, :3]))
