"""The embedded USARSim-compatible simulator (``usar-arm sim``): a TCP server speaking UDK's
dialect (:mod:`.server`, one asyncio loop owning every connection), MuJoCo physics
(:mod:`.physics`) and the robots it ships (:mod:`.robot_spec`, data in ``sim/robots/``). Only
:mod:`usar_arm.description.embedded` and the ``sim`` command start it."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.sim.robot_spec import RobotSpec as RobotSpec
    from usar_arm.sim.robot_spec import builtin_robots as builtin_robots
    from usar_arm.sim.robot_spec import load_robot as load_robot
    from usar_arm.sim.server import SimOptions as SimOptions
    from usar_arm.sim.server import SimServer as SimServer
    from usar_arm.sim.server import wait_for_port as wait_for_port

__getattr__, __dir__, __all__ = exports(__name__, __file__)
