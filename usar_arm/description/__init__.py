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

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.description.cache import robot_from_description as robot_from_description
    from usar_arm.description.embedded import describe as describe
    from usar_arm.description.embedded import start_simulator as start_simulator
    from usar_arm.description.pipeline import DescribeOptions as DescribeOptions
    from usar_arm.description.pipeline import Description as Description
    from usar_arm.description.pipeline import describe_arm as describe_arm
    from usar_arm.description.pipeline import write_description as write_description

__getattr__, __dir__, __all__ = exports(__name__, __file__)
