"""MoveIt joint_limits.yaml applied to a chain: acceleration and jerk limits (and velocity)
per joint (rad/s, rad/s², rad/s³ or m/s...)."""

from __future__ import annotations

from usar_arm.core.model import Joint, JointLimits, KinematicChain
from usar_arm.core.yamlio import loads_yaml


def apply_joint_limits_text(chain: KinematicChain, text: str, name: str = "<joint_limits>"
                            ) -> KinematicChain:
    """The chain with acceleration/jerk (and velocity) limits from a MoveIt joint_limits.yaml's
    text."""
    return apply_joint_limits_data(chain, loads_yaml(text, name))


def apply_joint_limits_data(chain: KinematicChain, data: object) -> KinematicChain:
    """:func:`apply_joint_limits_text` from the loaded YAML document."""
    table = (data or {}).get("joint_limits", {}) if isinstance(data, dict) else {}
    joints = []
    for j in chain.joints:
        entry = table.get(j.name)
        if entry is None or j.limits is None:
            joints.append(j)
            continue
        lim = j.limits
        acc = float(entry["max_acceleration"]) if entry.get("has_acceleration_limits") else None
        jerk = float(entry["max_jerk"]) if entry.get("has_jerk_limits") else None
        vel = float(entry["max_velocity"]) if entry.get("has_velocity_limits") else lim.velocity
        joints.append(Joint(j.name, j.type, j.parent, j.child, j.origin, j.axis,
                            JointLimits(lim.lower, lim.upper, vel, lim.effort, acc, jerk)))
    return KinematicChain(chain.name, chain.links, tuple(joints), chain.frames, chain.notes)
