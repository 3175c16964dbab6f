"""The embedded USARSim-compatible simulator (``usar-arm sim``): a TCP server speaking UDK's
dialect (:mod:`.server`, one asyncio loop owning every connection), MuJoCo physics
(:mod:`.physics`) and the robots it ships (:mod:`.robot_spec`, data in ``sim/robots/``). Only
:mod:`usar_arm.description.embedded` and the ``sim`` command start it."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.sim.robot_spec import RobotSpec, builtin_robots, load_robot
    from usar_arm.sim.server import SimOptions, SimServer, wait_for_port

_HOMES = {
    "robot_spec": ("RobotSpec", "builtin_robots", "load_robot"),
    "server": ("SimOptions", "SimServer", "wait_for_port"),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["RobotSpec", "SimOptions", "SimServer", "builtin_robots", "load_robot", "wait_for_port"]

__getattr__ = exports(__name__, _HOMES)
