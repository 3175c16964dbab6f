"""Learning an arm from the wire: ``GETCONF``/``GETGEO`` replies (:mod:`.interview`) to what the
wire said with its printed precision (:mod:`.wire_arm`), frames in REP-103 snapped within the
print step (:mod:`.frames`), ROS-Industrial names (:mod:`.naming`), limits from data sheets
(:mod:`.limits`) and the kinematic chain (:mod:`.build`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.discover.build import build_chain as build_chain
    from usar_arm.discover.interview import DiscoveryRecord as DiscoveryRecord
    from usar_arm.discover.interview import discover as discover
    from usar_arm.discover.limits import MotionLimits as MotionLimits
    from usar_arm.discover.limits import load_limits_file as load_limits_file
    from usar_arm.discover.naming import Naming as Naming
    from usar_arm.discover.wire_arm import WireArm as WireArm
    from usar_arm.discover.wire_arm import arm_from_replies as arm_from_replies

__getattr__, __dir__, __all__ = exports(__name__, __file__)
