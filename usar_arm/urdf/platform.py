"""PlatformDescription -> URDF text, and its checks: deterministic (same description, same bytes).

The tree (REP-105 names by default, :class:`~usar_arm.core.platform.PlatformFrames`)::

    base_footprint (on the ground) -> base_link (the chassis: a box) -> <end>_<side>_wheel
    (continuous, axis y, a cylinder each) and one fixed frame per placed sensor

An Ackermann vehicle's steered wheels hang on a knuckle: base_link -> <end>_<side>_steer
(revolute about z, within +-the largest steer the CONF gives) -> <end>_<side>_wheel
(continuous): ROS tools see the steer as a joint of its own. With the 2012 names there is no
base_footprint: base_link is the root. Masses are not written: the wire gives the robot's total
mass only (kept in the comment).
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from usar_arm.core.errors import ValidationError
from usar_arm.core.platform import (
    REP105_FRAMES,
    WHEEL_WIDTH_M,
    PlatformDescription,
    PlatformFrames,
    Wheel,
)
from usar_arm.urdf.validation import structural_problems
from usar_arm.urdf.writer import comment_block, num, nums

HALF_PI = 1.5707963267948966
STEER_SPEED_RAD_S = 1.0
"""The steer joints' velocity limit written in the URDF (rad/s): the wire gives none (a
URDF limit needs one); labelled in the file's comment."""
BODY_RGBA = (0.8, 0.1, 0.1, 1.0)
WHEEL_RGBA = (0.1, 0.1, 0.1, 1.0)


def wheel_joint(name: str) -> str:
    """The continuous joint of a wheel (``front_left`` -> ``front_left_wheel_joint``)."""
    return f"{name}_wheel_joint"


def steer_joint(name: str) -> str:
    """The revolute steer joint of a steered wheel (``front_left`` ->
    ``front_left_steer_joint``)."""
    return f"{name}_steer_joint"


def steer_limit(desc: PlatformDescription, wheel: Wheel) -> float:
    """The largest steer angle (rad) of a wheel either way; 0 for a wheel that does not steer."""
    if not desc.ackermann:
        return 0.0
    return desc.max_front_steer if wheel.end == "front" else desc.max_rear_steer


def _steer(desc: PlatformDescription, wheel: Wheel, base: str, link: str) -> list[str]:
    """A steered wheel's knuckle: a frame at the wheel's centre turning about base_link's z
    (REP-103: positive to the left) within +-the steer limit; the wheel spins on it."""
    limit = steer_limit(desc, wheel)
    return [f"  <link name={quoteattr(link)}/>",
            f'  <joint name={quoteattr(steer_joint(wheel.name))} type="revolute">',
            f"    {_origin(wheel.xyz)}", f"    <parent link={quoteattr(base)}/>",
            f"    <child link={quoteattr(link)}/>", '    <axis xyz="0 0 1"/>',
            f'    <limit lower="{num(-limit)}" upper="{num(limit)}" '
            f'effort="{num(desc.max_torque)}" velocity="{num(STEER_SPEED_RAD_S)}"/>',
            "  </joint>"]


def _origin(xyz: tuple[float, ...], rpy: tuple[float, ...] = (0.0, 0.0, 0.0)) -> str:
    return f'<origin xyz="{nums(xyz)}" rpy="{nums(rpy)}"/>'


def _visible(name: str, geometry: str, material: str, origin: str) -> list[str]:
    return [f"  <link name={quoteattr(name)}>",
            f"    <visual>{origin}<geometry>{geometry}</geometry>"
            f"<material name={quoteattr(material)}/></visual>",
            f"    <collision>{origin}<geometry>{geometry}</geometry></collision>",
            "  </link>"]


def _fixed(name: str, parent: str, child: str, xyz: tuple[float, ...],
           rpy: tuple[float, ...] = (0.0, 0.0, 0.0)) -> list[str]:
    return [f'  <joint name={quoteattr(name)} type="fixed">', f"    {_origin(xyz, rpy)}",
            f"    <parent link={quoteattr(parent)}/>", f"    <child link={quoteattr(child)}/>",
            "  </joint>"]


def platform_urdf(desc: PlatformDescription, frames: PlatformFrames = REP105_FRAMES) -> str:
    """The URDF of a ground vehicle (m, rad)."""
    notes = (f"{desc.robot_class}: {desc.platform_type}, {desc.steering_type}, mass "
             f"{num(desc.mass)} kg, wheel speed limit {num(desc.max_speed)} rad/s, learnt over "
             "the USARSim wire by usar-arm", *desc.notes,
             *((f"front steer within +-{num(desc.max_front_steer)} rad (half the CONF's "
                "MaxFrontSteer range); the steer joints' velocity limit "
                f"{num(STEER_SPEED_RAD_S)} rad/s is assumed: the wire gives none",)
               if desc.ackermann else ()),
             *(f"hidden sensor (GETGEO gave nothing, no frame): {h}" for h in desc.hidden),
             *(f"sensor of an unknown type (not described): {u}" for u in desc.unknown))
    lines = ['<?xml version="1.0"?>', *comment_block(notes),
             f"<robot name={quoteattr(desc.name)}>",
             f'  <material name="body"><color rgba="{nums(BODY_RGBA)}"/></material>',
             f'  <material name="wheel"><color rgba="{nums(WHEEL_RGBA)}"/></material>']
    base = frames.base
    if frames.footprint is not None:
        lines.append(f"  <link name={quoteattr(frames.footprint)}/>")
        lines += _fixed(f"{frames.footprint}_joint", frames.footprint, base,
                        (0.0, 0.0, desc.footprint_height))
    sx, sy, sz = desc.body_size
    lines += _visible(base, f'<box size="{nums((sx, sy, sz))}"/>', "body", _origin((0, 0, 0)))
    cylinder = f'<cylinder radius="{num(desc.wheel_radius)}" length="{num(WHEEL_WIDTH_M)}"/>'
    for wheel in desc.wheels:
        link = f"{wheel.name}_wheel"
        parent, at = base, wheel.xyz
        if steer_limit(desc, wheel) > 0:
            parent, at = f"{wheel.name}_steer", (0.0, 0.0, 0.0)
            lines += _steer(desc, wheel, base, parent)
        lines += _visible(link, cylinder, "wheel", _origin((0, 0, 0), (HALF_PI, 0.0, 0.0)))
        lines += [f'  <joint name={quoteattr(wheel_joint(wheel.name))} type="continuous">',
                  f"    {_origin(at)}", f"    <parent link={quoteattr(parent)}/>",
                  f"    <child link={quoteattr(link)}/>", '    <axis xyz="0 1 0"/>',
                  f'    <limit effort="{num(desc.max_torque)}" '
                  f'velocity="{num(desc.max_speed)}"/>', "  </joint>"]
    for sensor in desc.sensors:
        if not frames.placed(sensor):
            continue
        frame = frames.sensor(sensor)
        lines.append(f"  <link name={quoteattr(frame)}/>")
        lines += _fixed(f"{frame}_joint", base, frame, sensor.xyz, sensor.rpy)
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def platform_problems(desc: PlatformDescription, frames: PlatformFrames = REP105_FRAMES
                      ) -> list[str]:
    """What is wrong with the description before it is written (none: an empty list)."""
    problems = []
    for label, value in (("wheel radius", desc.wheel_radius),
                         ("wheel separation", desc.wheel_separation),
                         ("wheel base", desc.wheel_base), ("max speed", desc.max_speed)):
        if not value > 0:
            problems.append(f"{label} must be > 0 m (or rad/s), got {value}")
    names = [frames.sensor(s) for s in desc.sensors if frames.placed(s)]
    reserved = {frames.base, frames.root, *(f"{w.name}_wheel" for w in desc.wheels),
                *(f"{w.name}_steer" for w in desc.wheels)}
    for name in sorted({n for n in names if names.count(n) > 1 or n in reserved}):
        problems.append(f"sensor frame '{name}' repeats another frame's name")
    if len(desc.wheels) != 4 or len({w.name for w in desc.wheels}) != 4:
        problems.append(f"expected four distinct wheels, got {[w.name for w in desc.wheels]}")
    return problems


def validate_platform(desc: PlatformDescription, urdf: str,
                      frames: PlatformFrames = REP105_FRAMES) -> None:
    """Raise :class:`ValidationError` listing every problem of the description and its URDF
    (check_urdf and yourdfpy, as for an arm)."""
    joints = [j for w in desc.wheels for j in ((steer_joint(w.name),) if steer_limit(desc, w) > 0
                                               else ()) + (wheel_joint(w.name),)]  # file order
    problems = platform_problems(desc, frames) + structural_problems(urdf, joints)
    if problems:
        raise ValidationError(f"platform description of {desc.name}", problems)
