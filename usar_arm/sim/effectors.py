"""A robot's effectors as UDK has them: its tool changers and the tools on them (EFF, SET, ACT
Gripper, GETCONF and GETGEO; ``Effector.uc``, ``Gripper.uc``, ``ToolChanger.uc``, ``Vacuum.uc``,
``USARVehicle.uc``), over the physics of :mod:`.tools`.

UDK's rules, reproduced: a SET goes to every part whose ItemType and ItemName match without
regard to case (an empty name matches all), nested actuators included, and is never answered;
a Gripper's CLOSE turns it on at once (``IsOn = 1``) and only then tries to grip, so CLOSE over
nothing still reports CLOSED; a dropped tool is out of the robot's parts: silent, and invisible
to SET, GETCONF and GETGEO. What UDK does not say, whether the grip took and what is held, is
the ``GripTruth`` extension (:meth:`Effectors.grip_truth`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np

from usar_arm.core.spatial import matrix_to_rpy
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.robot_spec import RobotSpec
from usar_arm.sim.tools import ChangerState, ToolState
from usar_arm.usarsim import messages as m
from usar_arm.usarsim.numbers import NumberStyle

log = logging.getLogger("usar_arm.sim")

Reject = Callable[..., None]
GRIPPER = "Gripper"
TOOL_CHANGER = "ToolChanger"
TYPES = (GRIPPER, TOOL_CHANGER)


def _matches(item_type: str, item_name: str, type_: str, name: str | None) -> bool:
    return item_type.upper() == type_.upper() and (not name or item_name.upper() == name.upper())


class Effectors:
    """The tool changers of one robot and the tools they hold now."""

    def __init__(self, key: str, spec: RobotSpec):
        self.key = key
        self.spec = spec

    # ------------------------------------------------------------------ the parts
    def changers(self, world: PhysicsWorld) -> list[ChangerState]:
        """This robot's tool changers, in the order of its data."""
        return [world.rig.changers[(self.key, c.name)] for c in self.spec.tool_changers]

    def tools(self, world: PhysicsWorld) -> list[ToolState]:
        """The tools on this robot's tool changers now (a dropped tool is not a part)."""
        return [c.tool for c in self.changers(world) if c.tool is not None]

    def components(self, world: PhysicsWorld) -> list[str]:
        """``Type Name`` of each effector, for log messages."""
        return ([f"{TOOL_CHANGER} {c.spec.name}" for c in self.changers(world)]
                + [f"{GRIPPER} {t.spec.name}" for t in self.tools(world)])

    # ------------------------------------------------------------------ commands
    def set(self, msg: m.Set, world: PhysicsWorld, reject: Reject) -> None:
        """``SET {Type T} {Name n} {Opcode op} [{Params p}]``, routed as UDK routes it (no reply
        either way; a match or a miss shows only in the next EFF)."""
        hits = 0
        for c in self.changers(world):
            if _matches(TOOL_CHANGER, c.spec.name, msg.type, msg.name):
                hits += 1
                self._changer_set(c, msg.opcode, world)
        for tool in self.tools(world):  # (a tool CLOSE just took is not asked again)
            if _matches(GRIPPER, tool.spec.name, msg.type, msg.name) and tool.holder is not None:
                hits += 1
                self._gripper_set(tool, msg.opcode, msg.params, world)
        if hits == 0:
            reject("no such effector", "SET {Type %s} {Name %s} matches no effector; ignored "
                   "(UDK sends nothing either way; effectors: %s)", msg.type[:40],
                   msg.name[:40], ", ".join(self.components(world)) or "none",
                   level=logging.INFO)

    def act_gripper(self, name: str, value: int, world: PhysicsWorld) -> bool:
        """``ACT {Name <tool>} {Gripper v}``: True when ``name`` is one of the tools on this
        robot (it then reaches ``SetGripper(v)``)."""
        for tool in self.tools(world):
            if tool.spec.name.upper() == name.upper():
                self.set_gripper(tool, value, world)
                return True
        return False

    def _changer_set(self, c: ChangerState, opcode: str, world: PhysicsWorld) -> None:
        op = opcode.upper()
        if op == "CLOSE" and c.tool is None:
            tool = world.rig.tool_in_reach(world.model, world.data, c)
            if tool is None:
                log.info("%s: %s CLOSE: no free tool within %.2f m and %.2f rad along its "
                         "axis (FAILED, as UDK: nothing is sent)", self.key, c.spec.name,
                         c.spec.position_tolerance, c.spec.angle_tolerance)
                return
            world.rig.attach(world.model, world.data, c, tool)
            log.info("%s: %s picked up %s", self.key, c.spec.name, tool.spec.name)
        elif op == "OPEN" and c.tool is not None:
            tool = world.rig.detach(world.model, world.data, c)
            log.info("%s: %s dropped %s", self.key, c.spec.name, tool.spec.name if tool else "")

    def _gripper_set(self, tool: ToolState, opcode: str, params: str | None,
                     world: PhysicsWorld) -> None:
        op = opcode.upper()
        if op == "GRIP":  # SetGripper(int(Params)); UDK's int() of a non-number is 0
            self.set_gripper(tool, _udk_int(params or ""), world)
        elif op == "CLOSE":
            self.set_gripper(tool, 1, world)
        elif op == "OPEN":
            self.set_gripper(tool, 0, world)

    def set_gripper(self, tool: ToolState, value: int, world: PhysicsWorld) -> None:
        """``Gripper.SetGripper``: IsOn first, then the vacuum operates."""
        tool.on = value != 0
        if tool.on and tool.held is None:
            obj, other = world.rig.suction_target(world.model, world.data, world.objects, tool)
            if obj is not None:
                world.grip(tool, obj)
                log.info("%s: %s picked up '%s'", self.key, tool.spec.name, obj.name)
            elif other:
                log.info("%s: %s: not placed or oriented properly (the suction ray hits %s); "
                         "nothing gripped", self.key, tool.spec.name, other)
        elif not tool.on and tool.held is not None:
            world.release(tool)

    # ------------------------------------------------------------------ streams
    def status(self, t: float, world: PhysicsWorld) -> list[m.Message]:
        """The EFF lines of every attached effector, then their GripTruth extension lines."""
        out: list[m.Message] = []
        for c in self.changers(world):
            data: tuple[m.Block, ...] = (("Status", "OPEN"),)
            if c.tool is not None:
                data = (("Status", "CLOSED"), ("ToolType", c.tool.spec.item_type),
                        ("Tool", c.tool.spec.name))
            out.append(m.Eff(TOOL_CHANGER, c.spec.name, t, data))
        tools = self.tools(world)
        for tool in tools:
            out.append(m.Eff(GRIPPER, tool.spec.name, t,
                             (("Status", "CLOSED" if tool.on else "OPEN"),)))
        out += self.grip_truth(t, tools)
        return out

    def grip_truth(self, t: float, tools: list[ToolState]) -> list[m.GripTruth]:
        """``SEN {Type GripTruth}`` of each attached vacuum (an extension): holding what."""
        return [m.GripTruth(tool.spec.name, tool.held is not None,
                            tool.held.name if tool.held is not None else None, t)
                for tool in tools]

    # ------------------------------------------------------------------ CONF and GEO
    def conf(self, type_: str, name: str | None, world: PhysicsWorld, style: NumberStyle
             ) -> list[m.ConfItem]:
        """The CONF items of the matching effectors (UDK's ``GetConfData``)."""
        items = []
        for c in self.changers(world):
            if _matches(TOOL_CHANGER, c.spec.name, type_, name):
                items.append(m.ConfItem(c.spec.name, (
                    ("PositionTolerance", style.scalar(c.spec.position_tolerance)),
                    ("AngleTolerance", style.scalar(c.spec.angle_tolerance)),
                    ("Opcode", "Close"), ("Opcode", "Open"))))
        for tool in self.tools(world):
            if _matches(GRIPPER, tool.spec.name, type_, name):
                items.append(m.ConfItem(tool.spec.name, (
                    ("Opcode", "Grip"), ("MaxVal", "1"), ("MinVal", "0"), ("Opcode", "Close"),
                    ("Opcode", "Open"))))
        return items

    def geo(self, type_: str, name: str | None, world: PhysicsWorld) -> list[m.GeoItem]:
        """The GEO items of the matching effectors, as ``Effector.GetGeoData`` computes them
        now: a tool changer's Location from the joint its part hangs on (MountLink), a tool's
        from its tool changer, both in world axes; Orientation relative to the robot."""
        d = world.data
        platform = world.platform_pose(self.key)
        base_rpy = np.array(matrix_to_rpy(platform[:3, :3]))
        items = []
        for c in self.changers(world):
            if not _matches(TOOL_CHANGER, c.spec.name, type_, name):
                continue
            act = next(a for a in self.spec.actuators if a.name == c.actuator)
            link = next(i for i, jt in enumerate(act.joints) if jt.child == c.spec.parent)
            pose = world.rig.changer_pose(d, c)
            anchor = world.joint_anchor(self.key, act.name, link)
            items.append(m.GeoItem(c.spec.name, _vec(pose[:3, 3] - anchor),
                                   _vec(np.array(matrix_to_rpy(pose[:3, :3])) - base_rpy),
                                   mount=act.name, mount_link=link + 1, tip=(0.0, 0.0, 0.0)))
        for tool in self.tools(world):
            if not _matches(GRIPPER, tool.spec.name, type_, name) or tool.holder is None:
                continue
            pose = world.rig.tool_pose(d, tool)
            holder = world.rig.changer_pose(d, tool.holder)
            items.append(m.GeoItem(tool.spec.name, _vec(pose[:3, 3] - holder[:3, 3]),
                                   _vec(np.array(matrix_to_rpy(pose[:3, :3])) - base_rpy),
                                   mount=tool.holder.spec.name, tip=tool.spec.tip_offset))
        return items


def _vec(v: np.ndarray) -> m.Vector3:
    return (float(v[0]), float(v[1]), float(v[2]))


def _udk_int(text: str) -> int:
    """UnrealScript's ``int(string)``: the leading integer of the text, 0 when there is none."""
    text = text.strip()
    digits = ""
    for i, ch in enumerate(text):
        if ch.isdigit() or (i == 0 and ch in "+-"):
            digits += ch
        else:
            break
    try:
        return int(digits)
    except ValueError:
        return 0
