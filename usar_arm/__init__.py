"""usar-arm: learn a USARSim robot arm over the wire, describe it, plan and move it.

The library's front door is :class:`usar_arm.Arm` (see ``examples/``). Importing it loads the
planning stack but never the embedded simulator (MuJoCo, the TCP server): that is started only
by ``Arm.connect()`` without a host, through :mod:`usar_arm.embedded`.
"""

from __future__ import annotations

from usar_arm.arm import Arm
from usar_arm.version import __version__

__all__ = ["Arm", "__version__"]
