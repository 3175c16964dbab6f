"""An arm exactly as the server described it: its CONF and GEO, checked to form a serial chain.

Everything here is still in the USARSim protocol frame (x forward, y right, z down) and in the
server's own terms (1-based links, GEO locations in the actuator base frame, orientations
relative to the parent joint). Nothing is converted or rounded; see :mod:`.frames` for that.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from usar_arm.core.errors import DescriptionError
from usar_arm.discover.effectors import WireEffector
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import printed_resolution

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class WireJoint:
    """One actuator link as CONF and GEO report it.

    Attributes:
        link: 1-based link index. parent: the parent link (0: the actuator base).
        joint_type: ``Revolute`` or ``Prismatic``.
        min_value, max_value: limits (rad or m). max_torque: N·m or N (None if not sent).
        max_speed: rad/s or m/s, only from UT-era servers (None otherwise).
        location: offset from the parent joint's anchor, in the actuator base frame (m).
        orientation: roll, pitch, yaw of this joint's frame relative to the parent's (rad).
    """

    link: int
    parent: int
    joint_type: str
    min_value: float
    max_value: float
    max_torque: float | None
    max_speed: float | None
    location: Vec3
    orientation: Vec3


@dataclass(frozen=True)
class SensorMount:
    """A sensor on an arm link (the tip GroundTruth): GEO Location/Orientation, same
    conventions as a link's GEO, relative to link ``link``."""

    name: str
    link: int
    location: Vec3
    orientation: Vec3


@dataclass(frozen=True)
class WireArm:
    """A robot's arm as learnt over the wire.

    Attributes:
        robot_name: the platform's Name (its CONF), used as the robot name.
        platform_type: e.g. StaticPlatform. platform_class: the GEO ``Mount`` of the actuator.
        name: the actuator's name (used in ACT and ASTA).
        mount_location, mount_orientation: actuator pose on the platform (m, rad).
        joints: in chain order, from the base outwards.
        tip: the Tip offset from the last joint's anchor, in the actuator base frame (m).
        tip_sensor: the tip GroundTruth sensor, when the server has one.
        effectors: the tool changers and tools on the arm (:mod:`.effectors`), each after the
            one it rides on.
        location_resolution, orientation_resolution, tip_resolution: the smallest step the
            server printed for link Locations (m; UDK truncates to 0.001), link Orientations
            (rad; UDK rounds to 0.01) and the Tip (m; 0.01); 0 when unknown or exact.
    """

    robot_name: str
    platform_type: str
    platform_class: str
    name: str
    mount_location: Vec3
    mount_orientation: Vec3
    joints: tuple[WireJoint, ...]
    tip: Vec3
    tip_sensor: SensorMount | None = None
    effectors: tuple[WireEffector, ...] = ()
    location_resolution: float = 0.0
    orientation_resolution: float = 0.0
    tip_resolution: float = 0.0

    @property
    def dof(self) -> int:
        """Number of joints."""
        return len(self.joints)


def serial_order(parents: dict[int, int]) -> list[int]:
    """The links of a serial chain from the base outwards, given link -> parent link.

    Raises:
        DescriptionError: the parents do not form one unbranched chain starting at the base.
    """
    problems = []
    links = set(parents)
    for link, parent in sorted(parents.items()):
        if parent != 0 and parent not in links:
            problems.append(f"link {link} has parent {parent}, which is not a link "
                            f"(valid: 0 for the base, or one of {sorted(links)})")
        if parent == link:
            problems.append(f"link {link} is its own parent")
    roots = sorted(k for k, p in parents.items() if p == 0)
    if len(roots) != 1:
        problems.append(f"expected exactly one link with Parent 0 (the first joint), found "
                        f"{roots or 'none'}")
    children: dict[int, list[int]] = {}
    for link, parent in parents.items():
        children.setdefault(parent, []).append(link)
    for parent, kids in sorted(children.items()):
        if parent != 0 and len(kids) > 1:
            problems.append(f"link {parent} has several children {sorted(kids)}: a branching "
                            "tree, not a serial arm")
    if problems:
        raise DescriptionError("the GEO Parent indices do not form a serial chain: "
                               + "; ".join(problems))
    order = [roots[0]]
    while order[-1] in children:
        order.append(children[order[-1]][0])
        if len(order) > len(parents):
            break
    if len(order) != len(parents):
        missing = sorted(links - set(order))
        raise DescriptionError(f"the GEO Parent indices do not form a serial chain: links "
                               f"{missing} are not connected to the base (a cycle?)")
    return order


def _not_finite(conf_item: m.ConfItem, geo_item: m.GeoItem, sensors: list[m.GeoItem]
                ) -> list[str]:
    """Each number of the replies that is NaN or infinite, as 'where key value'."""
    found: list[str] = []

    def check(where: str, key: str, value: float | tuple[float, ...] | None) -> None:
        values = (value,) if isinstance(value, float | int) else value or ()
        if not all(math.isfinite(v) for v in values):
            found.append(f"{where} {key} {value}")

    for c in conf_item.links:
        for key in ("min_value", "max_value", "max_torque", "max_speed"):
            check(f"CONF link {c.link}", key, getattr(c, key))
    for g in geo_item.links:
        check(f"GEO link {g.link}", "Location", g.location)
        check(f"GEO link {g.link}", "Orientation", g.orientation)
    for item in (geo_item, *sensors):
        for key in ("location", "orientation", "tip"):
            check(f"GEO {item.name}", key, getattr(item, key))
    return found


def arm_from_replies(platform: m.PlatformConf, conf_item: m.ConfItem, geo_item: m.GeoItem,
                     sensors: list[m.GeoItem], geo_line: str = "") -> WireArm:
    """Combine the platform CONF, one actuator's CONF and GEO, and the GroundTruth GEOs.

    ``geo_line`` is the raw GEO text, from which the printed resolution of the numbers is read.

    Raises:
        DescriptionError: CONF and GEO disagree, a joint type is unknown, limits are inverted,
            or the links do not form a serial chain. Every problem found is listed.
    """
    problems: list[str] = []
    conf_links = {ln.link: ln for ln in conf_item.links}
    geo_links = {ln.link: ln for ln in geo_item.links}
    if not geo_links:
        raise DescriptionError(f"actuator {geo_item.name}: its GEO lists no links")
    not_finite = _not_finite(conf_item, geo_item, sensors)
    if not_finite:
        raise DescriptionError(f"actuator {geo_item.name}: expected finite numbers, got "
                               + "; ".join(not_finite))
    if set(conf_links) != set(geo_links):
        problems.append(f"CONF describes links {sorted(conf_links)} but GEO describes "
                        f"{sorted(geo_links)}")
    order = serial_order({k: ln.parent for k, ln in geo_links.items()})
    joints = []
    for k in order:
        g, c = geo_links[k], conf_links.get(k)
        if c is None:
            continue
        if c.joint_type not in ("Revolute", "Prismatic"):
            problems.append(f"link {k}: joint type '{c.joint_type}' (expected Revolute or "
                            "Prismatic)")
        if c.min_value is None or c.max_value is None:
            problems.append(f"link {k}: CONF has no MinValue/MaxValue")
            continue
        if not c.min_value < c.max_value:
            problems.append(f"link {k}: MinValue {c.min_value} is not below MaxValue "
                            f"{c.max_value}")
        joints.append(WireJoint(k, g.parent, c.joint_type, c.min_value, c.max_value,
                                c.max_torque, c.max_speed, g.location, g.orientation))
    if problems:
        raise DescriptionError(f"actuator {geo_item.name}: " + "; ".join(problems))
    # Resolutions of the link groups only (the actuator's own pose is printed differently).
    first_link = geo_line.find("{Link")
    links_text = geo_line[first_link:] if first_link >= 0 else geo_line
    tip_sensor = None
    for s in sensors:
        if (s.mount or "").lower() == geo_item.name.lower() and s.mount_link is not None \
                and s.location is not None and s.orientation is not None:
            tip_sensor = SensorMount(s.name, s.mount_link, s.location, s.orientation)
    return WireArm(
        robot_name=platform.name, platform_type=platform.type,
        platform_class=geo_item.mount or platform.name, name=geo_item.name,
        mount_location=geo_item.location or (0.0, 0.0, 0.0),
        mount_orientation=geo_item.orientation or (0.0, 0.0, 0.0),
        joints=tuple(joints), tip=geo_item.tip or (0.0, 0.0, 0.0), tip_sensor=tip_sensor,
        location_resolution=printed_resolution(links_text, "Location") if geo_line else 0.0,
        orientation_resolution=printed_resolution(links_text, "Orientation") if geo_line else 0.0,
        tip_resolution=printed_resolution(geo_line, "Tip") if geo_line else 0.0)
