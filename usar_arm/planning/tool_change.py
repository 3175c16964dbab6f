"""The arm without its tool: what the planner plans for once the tool changer has let the tool
go (``SET {Type ToolChanger} ... {Opcode OPEN}``), and again with it once it is picked up.

A learnt description has the tool changer's link (frame role ``tool_changer``) and, below it,
the tool's links (the gripper with its collision body, its TCP). :func:`without_tool` cuts
every link below the tool changer's out of the chain: their collision bodies are no longer
checked, their frames (``tcp``) no longer exist, and nothing can be attached to them. The
tool changer's own link, which has no geometry, stays.
"""

from __future__ import annotations

import weakref

from usar_arm.core.model import KinematicChain
from usar_arm.planning.robot import Robot
from usar_arm.urdf.kinematic_text import kinematic_urdf

CHANGER_ROLE = "tool_changer"
"""The frame role of the tool changer's link in a learnt description."""

_CUT: dict[int, tuple[weakref.ref[Robot], Robot]] = {}
"""id of a description's bare Robot -> (a reference to it, the Robot without its tool)."""


def tool_links(chain: KinematicChain, changer: str) -> set[str]:
    """The links below ``changer`` (the tool's), by the chain's joints."""
    below: set[str] = set()
    frontier = {changer}
    while frontier:
        frontier = {j.child for j in chain.joints if j.parent in frontier} - below
        below |= frontier
    return below


def has_tool(robot: Robot) -> bool:
    """The robot's description has a tool changer holding a tool."""
    changer = robot.chain.frames.get(CHANGER_ROLE)
    return changer is not None and bool(tool_links(robot.chain, changer))


def without_tool(robot: Robot) -> Robot:
    """``robot`` (carrying nothing) with the links below its tool changer cut off (itself when
    it has no tool changer or no tool). Cached per description."""
    if not has_tool(robot):
        return robot
    bare = robot.bare
    known = _CUT.get(id(bare))
    if known is not None and known[0]() is bare:
        return known[1]
    chain = bare.chain
    cut = tool_links(chain, chain.frames[CHANGER_ROLE])
    frames = {role: link for role, link in chain.frames.items() if link not in cut}
    kept = KinematicChain(chain.name, tuple(lk for lk in chain.links if lk.name not in cut),
                          tuple(j for j in chain.joints if j.child not in cut), frames,
                          chain.notes)
    disabled = {p for p in bare.disabled if not set(p) & cut}
    found = Robot(kept, bare.urdf, disabled, bare.states, bare.actuator, bare.source,
                  bare.wire_links, bare.tip_sensor, bare.files, kinematic_urdf(kept),
                  bare.options)
    key = id(bare)
    _CUT[key] = (weakref.ref(bare, lambda _ref: _CUT.pop(key, None)), found)
    return found
