"""The effectors of a learnt arm (tool changers, grippers) as the server described them.

UDK answers ``GETCONF``/``GETGEO {Type ToolChanger|Gripper} {Name n}`` for every effector that is
attached (docs/protocol.md, section 12): a tool changer's CONF carries its pick-up tolerances
(``{PositionTolerance m}{AngleTolerance rad}``) and its opcodes, a gripper's its opcodes; the GEO
of both is ``{Location} {Orientation}{Mount M}[{MountLink k}]{Tip}``:

* ``Mount`` is the actuator the effector rides on (``{MountLink k}``: on the part joint k moves,
  Location measured from joint k's anchor) or another effector (a gripper on its tool changer,
  Location measured from that effector's origin);
* Location and Orientation are differences of world-axis vectors and rotators, taken while the
  robot stands at its spawn pose: at the zero pose of an unrotated robot they are in the
  actuator base frame (USARSim's z-down frame, m and rad);
* ``Tip`` is the raw TipOffset in the effector's own frame (a vacuum's suction point, m).

Everything here is still in the wire's terms; :mod:`.tool_frames` turns it into frames.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.errors import DescriptionError
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import printed_resolution

Vec3 = tuple[float, float, float]

EFFECTOR_TYPES = ("ToolChanger", "Gripper")
"""The effector types (UDK ItemType) discovery asks about, in the order it asks: a tool changer
before the tools it holds."""


@dataclass(frozen=True)
class WireEffector:
    """One effector as CONF and GEO report it.

    Attributes:
        name: its ItemName (``toolchange``, ``KR60gripper``). type: its ItemType
            (``ToolChanger``, ``Gripper``; a VacuumGripper reports ``Gripper``).
        mount: the actuator or effector it rides on. mount_link: the actuator link (1-based)
            whose part carries it, None when it rides on an effector or an actuator's base.
        location: its origin from the mount's anchor, world axes at the spawn pose (m).
        orientation: roll, pitch, yaw relative to the robot (rad).
        tip: its TipOffset in its own frame (m; a vacuum's suction point).
        opcodes: the SET opcodes its CONF lists, in order (``Grip``, ``Close``, ``Open``).
        position_tolerance, angle_tolerance: a tool changer's pick-up tolerances (m, rad);
            None for other effectors.
        location_resolution, orientation_resolution, tip_resolution: the printed steps of its
            GEO numbers (m, rad, m; 0 when exact).
    """

    name: str
    type: str
    mount: str
    mount_link: int | None
    location: Vec3
    orientation: Vec3
    tip: Vec3
    opcodes: tuple[str, ...] = ()
    position_tolerance: float | None = None
    angle_tolerance: float | None = None
    location_resolution: float = 0.0
    orientation_resolution: float = 0.0
    tip_resolution: float = 0.0

    @property
    def is_tool_changer(self) -> bool:
        """True for a ToolChanger."""
        return self.type.lower() == "toolchanger"


def _number(item: m.ConfItem, key: str, where: str) -> float | None:
    text = item.get(key)
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        raise DescriptionError(f"{where}: {{{key} {text}}} is not a number") from None
    if not math.isfinite(value):
        raise DescriptionError(f"{where}: expected a finite {key}, got {text}")
    return value


def effector_from_replies(kind: str, conf: m.ConfItem, geo: m.GeoItem, geo_line: str = ""
                          ) -> WireEffector:
    """Combine one effector's CONF and GEO (``geo_line``: the raw GEO text, for its printed
    resolution).

    Raises:
        DescriptionError: the GEO lacks its pose or mount, or a number is not finite.
    """
    where = f"{kind} {geo.name}"
    missing = [k for k, v in (("Location", geo.location), ("Orientation", geo.orientation),
                              ("Mount", geo.mount)) if v is None]
    if missing:
        raise DescriptionError(f"{where}: its GEO lacks {', '.join(missing)} (expected "
                               "{Location x,y,z} {Orientation r,p,y}{Mount name})")
    assert geo.location is not None and geo.orientation is not None and geo.mount is not None
    tip = geo.tip or (0.0, 0.0, 0.0)
    bad = [f"{k} {v}" for k, v in (("Location", geo.location), ("Orientation", geo.orientation),
                                   ("Tip", tip)) if not all(math.isfinite(x) for x in v)]
    if bad:
        raise DescriptionError(f"{where}: expected finite numbers, got {'; '.join(bad)}")
    opcodes = tuple(v for k, v in conf.fields if k.lower() == "opcode")
    return WireEffector(
        geo.name, kind, geo.mount, geo.mount_link, geo.location, geo.orientation, tip, opcodes,
        _number(conf, "PositionTolerance", where), _number(conf, "AngleTolerance", where),
        printed_resolution(geo_line, "Location") if geo_line else 0.0,
        printed_resolution(geo_line, "Orientation") if geo_line else 0.0,
        printed_resolution(geo_line, "Tip") if geo_line else 0.0)


def mount_order(effectors: tuple[WireEffector, ...], actuator: str, links: tuple[int, ...]
                ) -> tuple[WireEffector, ...]:
    """The effectors that ride on ``actuator`` (directly, on one of its ``links``, or on another
    such effector), each after the one it rides on.

    Raises:
        DescriptionError: an effector's mount is neither the actuator nor a known effector, its
            MountLink is not one of the actuator's links, or mounts form a cycle.
    """
    by_name = {e.name.lower(): e for e in effectors}
    problems = []
    for e in effectors:
        if e.mount.lower() == actuator.lower():
            if e.mount_link is not None and e.mount_link not in links:
                problems.append(f"{e.type} {e.name} rides on link {e.mount_link} of {actuator}, "
                                f"which has links {list(links)}")
        elif e.mount.lower() not in by_name:
            problems.append(f"{e.type} {e.name} rides on '{e.mount}', which is neither the arm "
                            f"{actuator} nor one of the effectors "
                            f"{[x.name for x in effectors]}")
    if problems:
        raise DescriptionError("effector mounts: " + "; ".join(problems))
    placed: list[WireEffector] = []
    known = {actuator.lower()}
    while len(placed) < len(effectors):
        ready = [e for e in effectors if e not in placed and e.mount.lower() in known]
        if not ready:
            rest = [e.name for e in effectors if e not in placed]
            raise DescriptionError(f"effector mounts form a cycle: {rest}")
        for e in ready:
            placed.append(e)
            known.add(e.name.lower())
    return tuple(placed)
