"""Tool changers and vacuum tools in the simulator's world: how a tool rides on an arm, how a
vacuum holds an object, and the traces both make (``ToolChanger.uc``, ``Vacuum.uc``).

UDK attaches a tool kinematically (``SetBase`` on the tool changer, its physics off) and holds a
gripped object by a constraint to the tool, so neither loads the arm's drives. Here a tool is a
free rigid body; each tool changer has a *carrier*, a kinematic (mocap) body that follows the
tool changer's frame on the arm every physics step, and a held tool is welded to its carrier
(zero offset: UDK snaps the tool onto the tool changer). A gripped object is welded to the tool
at the pose it had when gripped. Nothing is welded to an arm link, so the arm's joints move
exactly as without a tool. A dropped tool's weld is off: it falls as a free body, still holding
its object. The carrier follows the pose the arm had at the start of each step (one step,
1 ms, behind).

The UDK semantics (what CLOSE and OPEN do, what EFF says) are :mod:`.effectors`'; this module
is their physics.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import Array, angle_between, invert, transform
from usar_arm.sim import mj
from usar_arm.sim.effector_spec import ToolChangerSpec, VacuumSpec
from usar_arm.sim.scenery import FREE_TOOL_AFFINITY, HELD_TOOL_AFFINITY, TOOL_BIT, quat
from usar_arm.sim.world_objects import WcObject, WorldObjects

HOLD_SOLREF = (0.002, 1.0)
"""Weld of a tool to its carrier: the stiffest MuJoCo allows at 1 ms steps."""
GRIP_SOLREF = (0.03, 1.0)
"""Weld of a gripped object to the tool: softer than a contact (MuJoCo's default time constant
0.02 s), so that an object driven into an obstacle is held back by it, off its grip pose (and
the suction is lost, as UDK's check finds), rather than driven through. A held object does not
sag in it: gravity is compensated while it is held (:mod:`.world_objects`)."""


@dataclass
class ToolState:
    """A tool (a vacuum) and its state.

    Attributes:
        key: the robot that spawned it. spec: its data. holder: the tool changer holding it.
        on: the Gripper's IsOn (CLOSE sets it at once, whatever it grips).
        held: the object it grips. grip_pose: that object's pose in the tool frame when
            gripped (UDK's GripPos). steps_to_check: physics steps to the next suction check.
    """

    key: str
    spec: VacuumSpec
    holder: ChangerState | None = None
    on: bool = False
    held: WcObject | None = None
    grip_pose: Array | None = None
    steps_to_check: int = 0
    body_id: int = -1
    qpos_adr: int = -1
    dof_adr: int = -1
    grip_eq: int = -1

    geom_id: int = -1

    @property
    def body(self) -> str:
        """Its MuJoCo body's name."""
        return f"{self.key}/tool/{self.spec.name}"

    @property
    def geom(self) -> str:
        """Its collision geom's name."""
        return f"{self.body}/body"


@dataclass
class ChangerState:
    """A tool changer, its carrier and the tool it holds."""

    key: str
    actuator: str
    spec: ToolChangerSpec
    site: str
    tool: ToolState | None = None
    site_id: int = -1
    mocap: int = -1
    carrier_id: int = -1
    hold_eq: int = -1

    @property
    def carrier(self) -> str:
        """Its carrier's MuJoCo body name."""
        return f"{self.key}/{self.actuator}/{self.spec.name}/carrier"


class ToolRig:
    """Every tool changer and tool of the world, by robot key and name."""

    def __init__(self) -> None:
        self.changers: dict[tuple[str, str], ChangerState] = {}
        self.tools: dict[tuple[str, str], ToolState] = {}
        self._followers: list[mj.Follower] = []
        """The carriers holding a tool (those that move), as views of the data."""

    # ------------------------------------------------------------------ building
    def build(self, spec: mj.Spec, key: str, changers: list[tuple[str, ToolChangerSpec, str]],
              tools: list[tuple[VacuumSpec, Array]]) -> None:
        """Add a robot's tool changers (actuator, spec, site) and its tools (spec, spawn pose in
        the z-down world) to ``spec``."""
        for actuator, cspec, site in changers:
            state = ChangerState(key, actuator, cspec, site)
            self.changers[(key, cspec.name)] = state
            spec.worldbody.add_body(name=state.carrier, mocap=True)
            mj.add_weld(spec, f"{state.carrier}/hold", state.carrier, "world", HOLD_SOLREF, False)
        for tspec, pose in tools:
            tool = ToolState(key, tspec)
            self.tools[(key, tspec.name)] = tool
            self._build_tool(spec, tool, pose)

    def _build_tool(self, spec: mj.Spec, tool: ToolState, pose: Array) -> None:
        s = tool.spec
        body = spec.worldbody.add_body(name=tool.body, pos=pose[:3, 3].tolist(),
                                       quat=quat(pose[:3, :3]))
        body.add_freejoint(name=f"{tool.body}/free")
        body.add_geom(name=tool.geom, type=mj.BOX, size=list(s.body_half),
                      pos=list(s.body_center), mass=s.mass, contype=TOOL_BIT,
                      conaffinity=FREE_TOOL_AFFINITY)
        mj.add_weld(spec, f"{tool.body}/grip", tool.body, "world", GRIP_SOLREF, False)

    def rebuild(self, spec: mj.Spec, key: str) -> None:
        """Add a robot's carriers, welds and tools to a fresh ``spec`` (their state is kept;
        the tools' poses are carried over by the caller with every joint's)."""
        for state in self.changers.values():
            if state.key == key:
                spec.worldbody.add_body(name=state.carrier, mocap=True)
                mj.add_weld(spec, f"{state.carrier}/hold", state.carrier, "world", HOLD_SOLREF,
                            False)
        for tool in self.tools.values():
            if tool.key == key:
                self._build_tool(spec, tool, np.eye(4))

    def delete(self, spec: mj.Spec | None, key: str) -> None:
        """Remove a robot's carriers, tools and welds from the registry and from ``spec``
        (None: a fresh spec is being built without them). Another robot's tool on one of its
        tool changers falls; an object one of its vacuums held is let go."""
        for name, state in list(self.changers.items()):
            if state.key == key:
                if state.tool is not None:
                    state.tool.holder = None
                if spec is not None:  # (its weld goes with it)
                    spec.delete(spec.body(state.carrier))
                del self.changers[name]
        for name, tool in list(self.tools.items()):
            if tool.key == key:
                if tool.holder is not None:
                    tool.holder.tool = None
                if tool.held is not None:
                    tool.held.held = False
                if spec is not None:  # (its welds and contact pairs go with it)
                    spec.delete(spec.body(tool.body))
                del self.tools[name]

    def index(self, m: mj.Model, d: mj.Data) -> None:
        """Find everything in a rebuilt model (after ``mj_forward``) and re-apply the welds."""
        self._followers = []
        for c in self.changers.values():
            c.site_id = mj.name_id(m, "site", c.site)
            c.carrier_id = mj.name_id(m, "body", c.carrier)
            c.mocap = int(m.body_mocapid[c.carrier_id])
            c.hold_eq = mj.name_id(m, "equality", f"{c.carrier}/hold")
        for t in self.tools.values():
            t.body_id = mj.name_id(m, "body", t.body)
            j = mj.name_id(m, "joint", f"{t.body}/free")
            t.qpos_adr, t.dof_adr = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            t.grip_eq = mj.name_id(m, "equality", f"{t.body}/grip")
            t.geom_id = mj.name_id(m, "geom", t.geom)
            m.geom_conaffinity[t.geom_id] = FREE_TOOL_AFFINITY
        for c in self.changers.values():
            mj.follow([mj.follower(d, c.mocap, c.site_id)])
            if c.tool is not None:
                self._weld_tool(m, d, c, c.tool, snap=False)
        for t in self.tools.values():
            if t.held is not None and t.grip_pose is not None:
                self._weld_object(m, d, t, t.held, t.grip_pose)

    # ------------------------------------------------------------------ every step
    def follow(self, d: mj.Data) -> None:
        """Move every carrier that holds a tool to its tool changer's frame (where the arm
        is now); an empty carrier carries nothing and need not move."""
        if self._followers:
            mj.follow(self._followers)

    def _refresh(self, d: mj.Data) -> None:
        self._followers = [mj.follower(d, c.mocap, c.site_id) for c in self.changers.values()
                           if c.tool is not None]

    # ------------------------------------------------------------------ poses
    def tool_pose(self, d: mj.Data, tool: ToolState) -> Array:
        """Where a tool is (4x4, z-down world)."""
        return transform(d.xmat[tool.body_id].reshape(3, 3).copy(), d.xpos[tool.body_id].copy())

    def changer_pose(self, d: mj.Data, c: ChangerState) -> Array:
        """Where a tool changer's frame is (4x4, z-down world)."""
        return transform(d.site_xmat[c.site_id].reshape(3, 3).copy(), d.site_xpos[c.site_id].copy())

    # ------------------------------------------------------------------ tool changer
    def attach(self, m: mj.Model, d: mj.Data, c: ChangerState, tool: ToolState) -> None:
        """Snap ``tool`` onto ``c`` (zero offset) and weld it to the carrier."""
        c.tool, tool.holder = tool, c
        self._weld_tool(m, d, c, tool, snap=True)

    def _weld_tool(self, m: mj.Model, d: mj.Data, c: ChangerState, tool: ToolState,
                   snap: bool) -> None:
        if snap:
            pose = self.changer_pose(d, c)
            d.qpos[tool.qpos_adr:tool.qpos_adr + 3] = pose[:3, 3]
            d.qpos[tool.qpos_adr + 3:tool.qpos_adr + 7] = quat(pose[:3, :3])
            d.qvel[tool.dof_adr:tool.dof_adr + 6] = 0.0
            if tool.held is not None and tool.grip_pose is not None:
                self._place(d, tool.held, pose @ tool.grip_pose)
        mj.set_weld_pose(m, c.hold_eq, c.carrier_id, tool.body_id, np.zeros(3),
                         np.array([1.0, 0.0, 0.0, 0.0]))
        d.eq_active[c.hold_eq] = True
        m.geom_conaffinity[tool.geom_id] = HELD_TOOL_AFFINITY
        self._refresh(d)

    def detach(self, m: mj.Model, d: mj.Data, c: ChangerState) -> ToolState | None:
        """Let go of ``c``'s tool (it falls freely); the tool, or None when there was none."""
        tool = c.tool
        if tool is None:
            return None
        d.eq_active[c.hold_eq] = False
        m.geom_conaffinity[tool.geom_id] = FREE_TOOL_AFFINITY
        c.tool, tool.holder = None, None
        self._refresh(d)
        return tool

    def tool_in_reach(self, m: mj.Model, d: mj.Data, c: ChangerState) -> ToolState | None:
        """UDK's CLOSE trace: the free tool whose body the tool changer's +z ray (twice the
        position tolerance long) hits first, if it is within the tolerances; else None."""
        pose = self.changer_pose(d, c)
        dist, geom = mj.ray(m, d, pose[:3, 3], pose[:3, 2], c.carrier_id)
        if geom < 0 or dist > 2 * c.spec.position_tolerance:
            return None
        body = int(m.geom_bodyid[geom])
        tool = next((t for t in self.tools.values() if t.body_id == body), None)
        if tool is None or tool.holder is not None:
            return None
        tp = self.tool_pose(d, tool)
        near = float(np.linalg.norm(tp[:3, 3] - pose[:3, 3])) <= c.spec.position_tolerance
        tol = c.spec.angle_tolerance
        aligned = (angle_between(pose[:3, 0], tp[:3, 0]) <= tol
                   and angle_between(pose[:3, 1], tp[:3, 1]) <= tol)
        return tool if near and aligned else None

    # ------------------------------------------------------------------ vacuum
    def suction_target(self, m: mj.Model, d: mj.Data, objects: WorldObjects, tool: ToolState
                       ) -> tuple[WcObject | None, str]:
        """UDK's grip trace from the tip along the tool's +z, SuctionLength long: the object
        hit first, or None and what was hit instead (``""`` for nothing)."""
        pose = self.tool_pose(d, tool)
        tip = pose @ np.array([*tool.spec.tip_offset, 1.0])
        dist, geom = mj.ray(m, d, tip[:3], pose[:3, 2], tool.body_id)
        if geom < 0 or dist > tool.spec.suction_length:
            return None, ""
        body = int(m.geom_bodyid[geom])
        obj = objects.by_body.get(body)
        if obj is not None:
            return obj, ""
        return None, mj.id_name(m, "geom", geom) or mj.id_name(m, "body", body)

    def grip(self, m: mj.Model, d: mj.Data, objects: WorldObjects, tool: ToolState,
             obj: WcObject) -> None:
        """Hold ``obj`` to ``tool`` where it is now."""
        rel = invert(self.tool_pose(d, tool)) @ objects.pose_of(d, obj)
        tool.held, tool.grip_pose = obj, rel
        tool.steps_to_check = tool.spec.drop_check_frequency + 1
        obj.held = True
        objects.hold_in_place(m, d, obj, False)
        self._weld_object(m, d, tool, obj, rel)

    def _weld_object(self, m: mj.Model, d: mj.Data, tool: ToolState, obj: WcObject,
                     rel: Array) -> None:
        mj.set_weld_pose(m, tool.grip_eq, tool.body_id, obj.body_id, rel[:3, 3].copy(),
                         np.asarray(quat(rel[:3, :3])))
        d.eq_active[tool.grip_eq] = True

    def release(self, m: mj.Model, d: mj.Data, objects: WorldObjects, tool: ToolState
                ) -> WcObject | None:
        """Let go of the held object (returned; None when there was none); it takes its own
        physics again (a static one stays where it is)."""
        obj, tool.held, tool.grip_pose = tool.held, None, None
        d.eq_active[tool.grip_eq] = False
        if obj is not None:
            obj.held = False
            objects.hold_in_place(m, d, obj, obj.static)
        return obj

    def drift(self, d: mj.Data, objects: WorldObjects, tool: ToolState) -> float:
        """How far (m) the held object is from its grip pose, in the tool frame."""
        if tool.held is None or tool.grip_pose is None:
            return 0.0
        rel = invert(self.tool_pose(d, tool)) @ objects.pose_of(d, tool.held)
        return float(np.linalg.norm(rel[:3, 3] - tool.grip_pose[:3, 3]))

    def check_suction(self, m: mj.Model, d: mj.Data, objects: WorldObjects, steps: int
                      ) -> list[tuple[ToolState, WcObject]]:
        """UDK's suction check, every ``drop_check_frequency + 1`` physics steps of a grip:
        an object that drifted more than SuctionLength from its grip pose is let go and the
        vacuum turns off (``IsOn = 0``: its status says OPEN with no command). ``steps``: the
        physics steps since the last call. Returns the tools that lost their object, each
        with that object."""
        lost = []
        for tool in self.tools.values():
            if tool.held is None:
                continue
            tool.steps_to_check -= steps
            if tool.steps_to_check > 0:
                continue
            tool.steps_to_check += tool.spec.drop_check_frequency + 1
            if self.drift(d, objects, tool) > tool.spec.suction_length:
                obj = self.release(m, d, objects, tool)
                tool.on = False
                if obj is not None:
                    lost.append((tool, obj))
        return lost

    def _place(self, d: mj.Data, obj: WcObject, pose: Array) -> None:
        d.qpos[obj.qpos_adr:obj.qpos_adr + 3] = pose[:3, 3]
        d.qpos[obj.qpos_adr + 3:obj.qpos_adr + 7] = quat(pose[:3, :3])
        d.qvel[obj.dof_adr:obj.dof_adr + 6] = 0.0
