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

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.arm.facade import Arm as Arm
    from usar_arm.core.version import __version__ as __version__

__getattr__, __dir__, __all__ = exports(__name__, __file__)
