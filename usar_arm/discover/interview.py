"""Ask a USARSim server about a robot, the way NIST's RosSim did, and keep every line it said.

1. ``GETSTARTPOSES`` (to check the start position, or take the first one);
2. ``INIT`` the robot class and wait for its first status line;
3. listen briefly to the status streams to learn the component names (ASTA: actuators, SEN:
   sensors);
4. ``GETCONF``/``GETGEO`` for the platform (``Type Robot``), then for each component, one request
   at a time.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from usar_arm.core.errors import (
    ConnectionLostError,
    DescriptionError,
    ResponseTimeoutError,
    UnknownStartError,
)
from usar_arm.discover.effectors import (
    EFFECTOR_TYPES,
    WireEffector,
    effector_from_replies,
    mount_order,
)
from usar_arm.discover.wire_arm import WireArm, arm_from_replies
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.client import UsarClient
from usar_arm.usarsim.codec import format_message

log = logging.getLogger("usar_arm.discover")

LISTEN_S = 0.35
"""How long to listen to the status streams after the spawn (s): more than one 10 Hz period."""
SETTLE_S, SETTLE_TOL, SETTLE_WAIT_S = 0.2, 2e-4, 3.0
"""The arm counts as settled when its joints moved less than SETTLE_TOL (rad or m: two ASTA
print steps) over SETTLE_S s of simulated time; at most SETTLE_WAIT_S s of wall time is spent
waiting (:func:`settled_joints`)."""


@dataclass(frozen=True)
class Exchange:
    """One request and the raw reply line (no terminator)."""

    request: str
    reply: str


@dataclass
class DiscoveryRecord:
    """Everything a discovery learnt, with the raw lines it was learnt from.

    Attributes:
        host, port: the server. robot_class: e.g. ``USARBot.KR60``. start: the start position.
        exchanges: each request and the raw reply, in order.
        components: ``Type Name`` of what the status streams announced.
        arm: the arm built from the replies (with its effectors).
        warnings: what the discovery could not learn, and why.
        spawn_rotation: the robot's roll, pitch, yaw at its start (rad, z-down world frame).
        effector_joints: the arm's joints (rad or m) while its effectors' GEO was asked (None:
            no effector).
    """

    host: str
    port: int
    robot_class: str
    start: str | None
    exchanges: list[Exchange] = field(default_factory=list)
    components: list[str] = field(default_factory=list)
    arm: WireArm | None = None
    warnings: list[str] = field(default_factory=list)
    spawn_rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)
    effector_joints: tuple[float, ...] | None = None

    def reply_lines(self) -> list[str]:
        """The raw CONF/GEO lines, in order (the cache key of a description)."""
        return [e.reply for e in self.exchanges if e.reply.startswith(("CONF", "GEO"))]


def discover(client: UsarClient, robot_class: str, robot_name: str | None = None,
             start: str | None = None, actuator: str | None = None,
             timeout: float | None = None, known_classes: tuple[str, ...] = ()
             ) -> DiscoveryRecord:
    """Spawn ``robot_class`` on the connected server and learn its arm.

    Args:
        client: a connected client (its connection will own the robot).
        robot_class: package-qualified class, e.g. ``USARBot.KR60`` (``KR60`` is qualified).
        robot_name: the INIT Name (default: the class name without package).
        start: a start position tag (default: the server's first).
        actuator: which actuator to learn when the robot has several (default: the one with
            the most links).
        known_classes: robot classes to name in the error if nothing spawns.

    Raises:
        UnknownStartError: no such start position (the server's are named).
        UnknownRobotError: no robot of that class appeared (the server's classes are named).
        UnknownComponentError: a GETCONF/GETGEO the server answered with nothing.
        ConnectionLostError: the server closed the connection.
        DescriptionError: what the server said is no arm usar-arm can describe.
    """
    record, ask = spawn_robot(client, robot_class, robot_name, start, timeout, known_classes)
    robot_class = record.robot_class
    actuators = _listen_for_actuators(client, robot_class, timeout)
    record.components = client.known_components()
    if not actuators:
        raise DescriptionError(f"{robot_class} reports no actuator (no ASTA line arrived within "
                               f"{LISTEN_S + (timeout or client.timeout):g} s of its spawn; "
                               "expected an arm); components seen: "
                               f"{', '.join(record.components) or 'none'}")
    platform = ask(m.GetConf("Robot"), m.PlatformConf)
    assert isinstance(platform, m.PlatformConf)
    ask(m.GetGeo("Robot"), m.Geo)
    confs = {}
    for act in actuators:
        conf = ask(m.GetConf("Actuator", act), m.Conf, act)
        assert isinstance(conf, m.Conf)
        confs[act] = next(i for i in conf.items if i.name.lower() == act.lower())
    actuator = _chosen_actuator(actuator, confs, robot_class)
    geo = ask(m.GetGeo("Actuator", actuator), m.Geo, actuator)
    geo_line = record.exchanges[-1].reply
    assert isinstance(geo, m.Geo)
    geo_item = next(i for i in geo.items if i.name.lower() == actuator.lower())
    sensors: list[m.GeoItem] = []
    for comp in record.components:
        kind, _, sname = comp.partition(" ")
        if kind == "GroundTruth":
            sgeo = ask(m.GetGeo("GroundTruth", sname), m.Geo, sname)
            assert isinstance(sgeo, m.Geo)
            sensors += [i for i in sgeo.items if i.name.lower() == sname.lower()]
    arm = arm_from_replies(platform, confs[actuator], geo_item, sensors, geo_line)
    links = tuple(j.link for j in arm.joints)
    if any(c.partition(" ")[0] in EFFECTOR_TYPES for c in record.components):
        record.effector_joints = settled_joints(client, arm.name, links)
        arm = replace(arm, effectors=mount_order(_effectors(record, ask), arm.name, links))
    record.arm = arm
    return record


def settled_joints(client: UsarClient, actuator: str, links: tuple[int, ...]
                   ) -> tuple[float, ...]:
    """The arm's joint values (rad or m, chain order) once two ASTA lines :data:`SETTLE_S` of
    simulated time apart differ by less than :data:`SETTLE_TOL` (a spawned arm sags under
    gravity for a moment); the latest ones after :data:`SETTLE_WAIT_S` s at most. Effector GEO
    lines are world-axis differences at the pose the arm is in, which these describe."""
    deadline = time.monotonic() + SETTLE_WAIT_S
    before = client.wait_asta(actuator)
    while True:
        later = client.wait_asta(actuator, after_time=before.time + SETTLE_S)
        q0, q1 = before.joints(links), later.joints(links)
        if q0 is None or q1 is None:
            raise DescriptionError(f"the ASTA lines of {actuator} lack some of its links "
                                   f"{list(links)}: {later}")
        if max(abs(a - b) for a, b in zip(q0, q1, strict=True)) < SETTLE_TOL \
                or time.monotonic() > deadline:
            return q1
        before = later


def _effectors(record: DiscoveryRecord, ask: Ask) -> tuple[WireEffector, ...]:
    """GETCONF and GETGEO of every effector the status streams announced (EFF lines), tool
    changers first. One that does not answer (a tool dropped since its last EFF line: UDK
    hides it) is left out, with a warning."""
    found = []
    for kind in EFFECTOR_TYPES:
        for comp in record.components:
            ctype, _, name = comp.partition(" ")
            if ctype != kind:
                continue
            try:
                conf = ask(m.GetConf(kind, name), m.Conf, name)
                geo = ask(m.GetGeo(kind, name), m.Geo, name)
            except ResponseTimeoutError as exc:
                record.warnings.append(f"{kind} {name} announced itself but did not answer "
                                       f"GETCONF/GETGEO ({exc}); it is not in the description")
                log.warning("%s", record.warnings[-1])
                continue
            assert isinstance(conf, m.Conf) and isinstance(geo, m.Geo)
            citem = next(i for i in conf.items if i.name.lower() == name.lower())
            gitem = next(i for i in geo.items if i.name.lower() == name.lower())
            found.append(effector_from_replies(kind, citem, gitem, record.exchanges[-1].reply))
    return tuple(found)


Ask = Callable[..., m.Message]
"""``ask(request, reply type, name=None, wait=None)``: one request (``wait``: its own timeout,
s), its reply kept in the record."""


def spawn_robot(client: UsarClient, robot_class: str, robot_name: str | None = None,
                start: str | None = None, timeout: float | None = None,
                known_classes: tuple[str, ...] = ()) -> tuple[DiscoveryRecord, Ask]:
    """Check the start position, spawn ``robot_class`` and wait for its first status line.

    Returns the record (the exchanges so far) and the ``ask`` function that adds each later
    request and reply to it. Raises as :func:`discover`.
    """
    if "." not in robot_class:
        robot_class = f"USARBot.{robot_class}"
    record = DiscoveryRecord(client.host, client.port, robot_class, start)

    def ask(msg: m.Message, accept_type: type, name: str | None = None,
            wait: float | None = None) -> m.Message:
        type_ = msg.type if isinstance(msg, (m.GetConf, m.GetGeo)) else ""
        rec = client.request(msg, _matches(accept_type, type_, name),
                             timeout if wait is None else wait)
        record.exchanges.append(Exchange(format_message(msg).strip(), rec.line))
        return rec.message

    poses = ask(m.GetStartPoses(), m.StartPoses)
    assert isinstance(poses, m.StartPoses)
    if start is None:
        start = poses.names[0] if poses.poses else None
    elif not any(n.lower() == start.lower() for n in poses.names):
        raise UnknownStartError(start, poses.names)
    record.start = start
    record.spawn_rotation = next((p.rotation for p in poses.poses
                                  if start is not None and p.name.lower() == start.lower()),
                                 (0.0, 0.0, 0.0))
    name = robot_name or robot_class.split(".")[-1]
    log.info("spawning %s '%s' at %s", robot_class, name, start or "the origin")
    first = client.spawn(robot_class, name, start=start,
                         location=None if start else (0.0, 0.0, 0.0),
                         rotation=None if start else (0.0, 0.0, 0.0),
                         timeout=timeout, known_classes=known_classes)
    record.exchanges.append(Exchange(f"INIT {{ClassName {robot_class}}} {{Name {name}}}"
                                     + (f" {{Start {start}}}" if start else ""), first.line))
    return record, ask

def _listen_for_actuators(client: UsarClient, robot_class: str, timeout: float | None
                          ) -> list[str]:
    """The actuators a just spawned robot reports in its status lines, listened to for
    :data:`LISTEN_S` s (longer until one arrives, up to the reply timeout more)."""
    deadline = time.monotonic() + max(LISTEN_S, 0.0)
    actuators: list[str] = []
    while time.monotonic() < deadline or not actuators:
        actuators = [c.split(" ", 1)[1] for c in client.known_components()
                     if c.startswith("Actuator ")]
        if client.closed_reason is not None:
            raise ConnectionLostError(f"listening to the status lines of {robot_class} after "
                                      "it spawned", client.closed_reason)
        if time.monotonic() > deadline + (timeout or client.timeout):
            break
        time.sleep(0.02)
    return actuators


def _chosen_actuator(asked: str | None, confs: dict[str, m.ConfItem], robot_class: str) -> str:
    """The actuator to learn, as the robot spells it: ``asked`` (any case), else the one with
    the most links."""
    actuators = list(confs)
    if asked is None:
        asked = max(actuators, key=lambda a: len(confs[a].links))
        if len(actuators) > 1:
            log.info("robot has actuators %s; learning %s (most links)", actuators, asked)
    elif asked.lower() not in (a.lower() for a in actuators):
        raise DescriptionError(f"no actuator '{asked}' on {robot_class}; it has: "
                               f"{', '.join(actuators)}")
    return next(a for a in actuators if a.lower() == asked.lower())


def _matches(kind: type, type_: str, name: str | None) -> Callable[[m.Message], bool]:
    def accept(msg: m.Message) -> bool:
        if not isinstance(msg, kind):
            return False
        if isinstance(msg, m.PlatformConf):
            return True
        if isinstance(msg, (m.Conf, m.Geo)):
            if type_ != "Robot" and msg.type.lower() != type_.lower():
                return False
            return name is None or any(i.name.lower() == name.lower() for i in msg.items)
        return True
    return accept
