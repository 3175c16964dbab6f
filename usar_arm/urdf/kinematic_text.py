"""The kinematics of a planning chain as URDF text, for Pinocchio: links as bare frames, the
group's joints movable (revolute or prismatic, one coordinate each), every other joint fixed.
Numbers are written with ``repr`` so that they read back to the very floats of the chain."""

from __future__ import annotations

from collections.abc import Iterable
from xml.sax.saxutils import quoteattr

from usar_arm.core.model import JointType, KinematicChain


def _nums(values: Iterable[float]) -> str:
    return " ".join(repr(float(v)) for v in values)


def kinematic_urdf(chain: KinematicChain) -> str:
    """URDF text with ``chain``'s links (no geometry) and joints (metres, radians)."""
    lines = ['<?xml version="1.0"?>', f"<robot name={quoteattr(chain.name)}>"]
    lines += [f"  <link name={quoteattr(lk.name)}/>" for lk in chain.links]
    for j in chain.joints:
        lines += [f'  <joint name={quoteattr(j.name)} type="{j.type.value}">',
                  f'    <origin xyz="{_nums(j.origin.xyz)}" rpy="{_nums(j.origin.rpy)}"/>',
                  f"    <parent link={quoteattr(j.parent)}/>",
                  f"    <child link={quoteattr(j.child)}/>"]
        if j.type is not JointType.FIXED and j.limits is not None:
            lim = j.limits
            lines += [f'    <axis xyz="{_nums(j.axis)}"/>',
                      f'    <limit lower="{lim.lower!r}" upper="{lim.upper!r}" '
                      f'effort="{lim.effort!r}" velocity="{lim.velocity!r}"/>']
        lines.append("  </joint>")
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
