"""usar-arm: learn a USARSim robot arm over the wire, describe it, plan and move it.

The library's front door is :class:`usar_arm.Arm` (see ``examples/``). Importing it loads the
planning stack but never the embedded simulator (MuJoCo, the TCP server): that is started only
by ``Arm.connect()`` without a host, through :mod:`usar_arm.description.embedded`. ``Arm`` is
imported on first use, so a process that needs one layer (a workspace worker, ``usar-arm
--help``) does not pay for the others.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports
from usar_arm.core.version import __version__

if TYPE_CHECKING:
    from usar_arm.arm.facade import Arm

__all__ = ["Arm", "__version__"]

__getattr__ = exports(__name__, {"arm.facade": ("Arm",)})
