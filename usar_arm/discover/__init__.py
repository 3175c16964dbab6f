"""Learning an arm from the wire: ``GETCONF``/``GETGEO`` replies (:mod:`.interview`) to what the
wire said with its printed precision (:mod:`.wire_arm`), frames in REP-103 snapped within the
print step (:mod:`.frames`), ROS-Industrial names (:mod:`.naming`), limits from data sheets
(:mod:`.limits`) and the kinematic chain (:mod:`.build`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.discover.build import build_chain
    from usar_arm.discover.interview import DiscoveryRecord, discover
    from usar_arm.discover.limits import MotionLimits, load_limits_file
    from usar_arm.discover.naming import Naming
    from usar_arm.discover.wire_arm import WireArm, arm_from_replies

_HOMES = {
    "build": ("build_chain",),
    "interview": ("DiscoveryRecord", "discover"),
    "limits": ("MotionLimits", "load_limits_file"),
    "naming": ("Naming",),
    "wire_arm": ("WireArm", "arm_from_replies"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["DiscoveryRecord", "MotionLimits", "Naming", "WireArm", "arm_from_replies",
           "build_chain", "discover", "load_limits_file"]

__getattr__ = exports(__name__, _HOMES)
