"""KinematicChain -> URDF text: deterministic (same chain, same bytes), cylinders, REP-199 frames.

No ``<inertial>`` elements: the USARSim wire carries no masses, and KDL rejects inertia on the root
link anyway. Acceleration and jerk limits go to joint_limits.yaml (URDF's ``<limit>`` has none).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from xml.sax.saxutils import escape, quoteattr

from usar_arm.core.model import Cylinder, Joint, JointType, KinematicChain, Link, Origin
from usar_arm.core.precision import meaningful
from usar_arm.core.shapes import CylinderShape


def num(value: float) -> str:
    """A number as the generated files print it: with the precision it means (a length, an
    angle or a unitless number to 1e-9 of its unit: :func:`~usar_arm.core.precision.meaningful`,
    so a calibrated offset of 2.4e-5 m does not carry its fit's last bits, which differ between
    CPUs), in up to 10 significant digits, no ``-0``."""
    text = f"{meaningful(float(value)):.10g}"
    if text in ("-0", "-0.0"):
        return "0"
    return text


def nums(values: Iterable[float]) -> str:
    """Space-separated numbers."""
    return " ".join(num(v) for v in values)


def _origin(o: Origin) -> str:
    return f'<origin xyz="{nums(o.xyz)}" rpy="{nums(o.rpy)}"/>'


def _geometry(c: Cylinder | CylinderShape) -> str:
    return f'<geometry><cylinder radius="{num(c.radius)}" length="{num(c.length)}"/></geometry>'


def _link(link: Link) -> list[str]:
    """A link: each collision element also drawn as a visual (what is seen is what collides)."""
    elements = link.elements
    if not elements:
        return [f"  <link name={quoteattr(link.name)}/>"]
    material = f"<material name={quoteattr(link.material)}/>" if link.material else ""
    visuals, collisions = [], []
    for e in elements:
        if not isinstance(e.shape, CylinderShape):
            raise TypeError(f"link {link.name}: the writer writes cylinders (a learnt arm's "
                            f"shapes), not {type(e.shape).__name__}")
        shape = f"{_origin(e.origin)}{_geometry(e.shape)}"
        visuals.append(f"    <visual>{shape}{material}</visual>")
        collisions.append(f"    <collision>{shape}</collision>")
    return [f"  <link name={quoteattr(link.name)}>", *visuals, *collisions, "  </link>"]


def _joint(j: Joint) -> list[str]:
    lines = [f'  <joint name={quoteattr(j.name)} type="{j.type.value}">',
             f"    {_origin(j.origin)}",
             f"    <parent link={quoteattr(j.parent)}/>",
             f"    <child link={quoteattr(j.child)}/>"]
    if j.type is not JointType.FIXED:
        lines.append(f'    <axis xyz="{nums(j.axis)}"/>')
        lim = j.limits
        assert lim is not None, f"joint {j.name} has no limits"
        lines.append(f'    <limit lower="{num(lim.lower)}" upper="{num(lim.upper)}" '
                     f'effort="{num(lim.effort)}" velocity="{num(lim.velocity)}"/>')
    lines.append("  </joint>")
    return lines


def comment_block(notes: Sequence[str]) -> list[str]:
    """Notes as an XML comment (``--`` is not allowed inside comments)."""
    if not notes:
        return []
    body = [f"  {escape(n).replace('--', '- -')}" for n in notes]
    return ["<!--", *body, "-->"]


def urdf_text(chain: KinematicChain) -> str:
    """The URDF of ``chain``."""
    lines = ['<?xml version="1.0"?>', *comment_block(chain.notes),
             f"<robot name={quoteattr(chain.name)}>"]
    seen = {}
    for link in chain.links:
        if link.material and link.color and link.material not in seen:
            seen[link.material] = link.color
    for name, rgba in seen.items():
        lines.append(f'  <material name={quoteattr(name)}><color rgba="{nums(rgba)}"/></material>')
    for link in chain.links:
        lines += _link(link)
    for joint in chain.joints:
        lines += _joint(joint)
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
