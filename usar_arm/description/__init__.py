"""From an arm learnt over the wire to its validated description files, and back.

* :mod:`.pipeline`: discovery record -> chain -> URDF, SRDF, joint limits, discovery.json
  (validated before anything is written);
* :mod:`.cache`: descriptions kept under a key of the CONF/GEO lines they came from, with the
  calibrated descriptions of the same arm;
* :mod:`.embedded`: the embedded simulator as a source of descriptions (the only module that
  starts it to learn an arm);
* :mod:`.accuracy`: a learnt chain against the simulator's own model.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.description.cache import robot_from_description
    from usar_arm.description.embedded import describe, start_simulator
    from usar_arm.description.pipeline import (
        DescribeOptions,
        Description,
        describe_arm,
        write_description,
    )

_HOMES = {
    "cache": ("robot_from_description",),
    "embedded": ("describe", "start_simulator"),
    "pipeline": ("DescribeOptions", "Description", "describe_arm", "write_description"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["DescribeOptions", "Description", "describe", "describe_arm", "robot_from_description",
           "start_simulator", "write_description"]

__getattr__ = exports(__name__, _HOMES)
