"""MuJoCo physics of the embedded simulator: one shared world, robots and objects added and
removed live.

Each joint is a position drive toward its (limit-clamped) target, as UDK's PhysX drive is:
stiffness = MaxForce, damping = Damping, force limit = MaxForce (docs/protocol.md section 6.3).
The world is expressed in the USARSim protocol frame (z down), so gravity is +z. Arm links
collide with the scenery, the WorldController's objects, tools and each other except across a
joint (:mod:`.arm_bodies`); tools ride on their tool changers and vacuums hold objects
(:mod:`.tools`); the WorldController's objects are :mod:`.world_objects`'; contacts are kept as
ground truth (:mod:`.contacts`). MuJoCo itself is reached through :mod:`.mj`.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator, Sequence

import numpy as np

from usar_arm.core.cell import StaticPiece
from usar_arm.core.spatial import Array, rpy_to_matrix, transform
from usar_arm.core.world_file import SceneryBox
from usar_arm.sim import mj
from usar_arm.sim.arm_bodies import add_arm, add_pairs, part_body, part_geoms
from usar_arm.sim.contacts import ContactLog
from usar_arm.sim.heap import release_freed_memory
from usar_arm.sim.physics_index import RobotEntry
from usar_arm.sim.robot_access import RobotAccess
from usar_arm.sim.robot_spec import RobotSpec
from usar_arm.sim.scenery import add_scenery, quat
from usar_arm.sim.tools import ToolRig, ToolState
from usar_arm.sim.vehicle_bodies import add_vehicle, index_vehicle
from usar_arm.sim.world_objects import WcObject, WorldObjects

log = logging.getLogger("usar_arm.sim")

GRAVITY = 9.81
"""Gravitational acceleration (m/s²), along +z of the z-down world."""
FRESH_SPEC_AFTER = 50
"""Robot removals after which the MuJoCo spec is built anew: an ``MjSpec`` keeps about 2 KiB
for every robot ever deleted from it (mujoco 3.x), which a long-running server must not."""


def _joint_state(m: mj.Model, d: mj.Data) -> dict[str, tuple[Array, Array]]:
    """Position and velocity of every joint by name (hinges, slides and free joints)."""
    out = {}
    for j in range(m.njnt):
        qa, da = m.jnt_qposadr[j], m.jnt_dofadr[j]
        nq, nv = (7, 6) if m.jnt_type[j] == mj.FREE else (1, 1)
        out[mj.id_name(m, "joint", j)] = (d.qpos[qa:qa + nq].copy(), d.qvel[da:da + nv].copy())
    return out


def body_names(m: mj.Model, robots: dict[str, RobotEntry], rig: ToolRig,
               objects: WorldObjects) -> dict[int, tuple[str, str, bool]]:
    """Body id -> (its contact report name, its robot's key, whether its contacts are kept)
    for every arm part, tool and WorldController object (a held object belongs to the robot
    whose vacuum holds it)."""
    names: dict[int, tuple[str, str, bool]] = {}
    for robot in robots.values():
        for act in robot.spec.actuators:
            for part in act.parts:
                body = mj.name_id(m, "body", part_body(f"{robot.key}/{act.name}", part.name))
                names[body] = (f"link:{robot.name}/{part.name}", robot.key, True)
    for tool in rig.tools.values():
        owner = robots.get(tool.key)
        label = owner.name if owner is not None else tool.key
        names[tool.body_id] = (f"tool:{label}/{tool.spec.name}", tool.key, True)
    holders = {id(t.held): t.key for t in rig.tools.values() if t.held is not None}
    for obj in objects.objects.values():
        holder = holders.get(id(obj), "")
        names[obj.body_id] = (f"object:{obj.name}", holder, bool(holder))
    return names


class PhysicsWorld(RobotAccess):
    """A MuJoCo world holding any number of USARSim robots and WorldController objects.

    Args:
        timestep: physics step (s); the default 1 ms gives 1 kHz physics.
        gravity: apply gravity (on in UDK).
        scenery, floor_z: a world file's boxes and floor height (m, z down).
        cell: a work cell's static pieces (REP-103, the cell's frame at the world origin).
    """

    def __init__(self, timestep: float = 0.001, gravity: bool = True,
                 scenery: Sequence[SceneryBox] = (), floor_z: float = 0.0,
                 cell: Sequence[StaticPiece] = ()):
        self.timestep = timestep
        self.gravity = gravity
        self.scenery = tuple(scenery)
        self.floor_z = floor_z
        self.cell = tuple(cell)
        self.objects = WorldObjects()
        self.rig = ToolRig()
        self.contacts = ContactLog()
        self._spec = self._new_spec()
        self._robots: dict[str, RobotEntry] = {}
        self._batching = False
        self._removed_since_trim = False
        self._dirty = False
        self._removals = 0
        self._defaults: list[str] = []
        self._leaving: list[str] = []
        self._model = self._spec.compile()
        self._data = mj.new_data(self._model)
        self._index()

    def _new_spec(self) -> mj.Spec:
        spec = mj.new_spec(self.timestep, GRAVITY if self.gravity else 0.0)
        add_scenery(spec, self.scenery, self.floor_z, self.cell)
        return spec

    @property
    def model(self) -> mj.Model:
        """The compiled model (its ids change at every rebuild)."""
        return self._model

    @property
    def data(self) -> mj.Data:
        """The simulation state."""
        return self._data

    # ------------------------------------------------------------------ robots
    def add_robot(self, key: str, spec: RobotSpec, location: Sequence[float],
                  rotation: Sequence[float], name: str = "") -> None:
        """Spawn ``spec`` at a world pose (m, roll/pitch/yaw rad); ``key`` must be unique.
        Its tools start on the tool changers whose default item they are."""
        if key in self._robots:
            raise ValueError(f"robot key {key} already in use")
        entry = RobotEntry(key, spec, tuple(float(v) for v in location),
                           tuple(float(v) for v in rotation),
                           transform(rpy_to_matrix(rotation), location), {},
                           name=name or spec.short_name)
        self._build(entry, fresh=True)
        self._robots[key] = entry
        self._defaults.append(key)
        self._changed()

    def _build(self, entry: RobotEntry, fresh: bool = False) -> None:
        """Add a robot's bodies, joints, drives and tools to the spec (its indices are set on
        the next rebuild of the model)."""
        if entry.spec.vehicle is not None:
            entry.vehicle = add_vehicle(self._spec, entry, entry.spec.vehicle, self.floor_z)
            return
        platform = self._spec.worldbody.add_body(
            name=f"{entry.key}/platform", pos=list(entry.location),
            quat=quat(entry.platform_pose[:3, :3]))
        platform.add_geom(type=mj.SPHERE, size=[0.05, 0, 0], mass=1.0, contype=0,
                          conaffinity=0, group=mj.MASS_GROUP)
        spec = entry.spec
        entry.actuators = {act.name: add_arm(self._spec, platform, entry.key, act,
                                             [c for c in spec.tool_changers
                                              if c.actuator == act.name])
                           for act in spec.actuators}
        if fresh:
            sites = [(c.actuator, c, entry.actuators[c.actuator].changer_sites[c.name])
                     for c in spec.tool_changers]
            tools = [(t, entry.platform_pose @ transform(rpy_to_matrix(t.direction),
                                                         t.position)) for t in spec.tools]
            self.rig.build(self._spec, entry.key, sites, tools)
        else:
            self.rig.rebuild(self._spec, entry.key)
        self._tool_pairs(entry)

    def _tool_pairs(self, entry: RobotEntry) -> None:
        """Contact pairs between a robot's default tools and its own links, but the tool
        changer's part and that part's parent (which the tool sits against)."""
        for c in entry.spec.tool_changers:
            tool = self.rig.tools.get((entry.key, c.default_item or ""))
            if tool is None:
                continue
            act = next(a for a in entry.spec.actuators if a.name == c.actuator)
            near = {c.parent} | {jt.parent for jt in act.joints if jt.child == c.parent}
            geoms = [g for p in act.parts if p.name not in near
                     for g in part_geoms(f"{entry.key}/{act.name}", p)]
            add_pairs(self._spec, [tool.geom], geoms)

    def remove_robot(self, key: str) -> None:
        """Destroy a robot (when its connection closes) and its tools; unknown keys are
        ignored. Objects its vacuum held are let go."""
        if self._robots.pop(key, None) is None:
            return
        self._removals += 1
        self.contacts.forget(key)
        self._leaving.append(key)
        self._removed_since_trim = True
        self._changed()

    def _delete_leaving(self) -> None:
        """Take the robots that left out of the spec: one by one (deleting a body, with its
        welds and contact pairs, costs about 1.5 ms per robot left in the spec, and a robot
        has up to three: platform, tool, carrier), or, when that would cost more than building
        the spec anew (about 25 ms per remaining robot), or after :data:`FRESH_SPEC_AFTER`
        removals, by building it anew."""
        leaving, self._leaving = self._leaving, []
        if not leaving:
            return
        total = len(self._robots) + len(leaving)
        if self._removals >= FRESH_SPEC_AFTER or len(leaving) * total > 5.5 * len(self._robots):
            self._removals = 0
            for key in leaving:
                self.rig.delete(None, key)
            self._spec = self._new_spec()
            for entry in self._robots.values():
                self._build(entry)
            for obj in self.objects.objects.values():
                self.objects.build(self._spec, obj)
            return
        for key in leaving:
            self.rig.delete(self._spec, key)
            self._spec.delete(self._spec.body(f"{key}/platform"))

    # ------------------------------------------------------------------ objects
    def add_object(self, obj: WcObject) -> None:
        """Spawn a WorldController object at ``obj.pose``."""
        self.objects.build(self._spec, obj)
        self._changed()

    def remove_object(self, obj: WcObject) -> None:
        """Destroy a WorldController object (a vacuum holding it lets go)."""
        for tool in self.rig.tools.values():
            if tool.held is obj:
                self.rig.release(self._model, self._data, self.objects, tool)
        self.objects.delete(self._spec, obj)
        self._changed()

    def object_pose(self, obj: WcObject) -> Array:
        """Where an object is now (4x4, z-down world)."""
        return self.objects.pose_of(self._data, obj)

    def move_object(self, obj: WcObject, pose: Array) -> None:
        """Teleport an object to ``pose`` (4x4, z-down world), at rest."""
        self.objects.set_pose(self._model, self._data, obj, pose)
        mj.forward(self._model, self._data)

    def object_extent(self, obj: WcObject) -> Array:
        """The size (m) of an object's world-axis bounding box."""
        return self.objects.extent(self._model, self._data, obj)

    def penetration(self, obj: WcObject) -> float:
        """How deep (m) ``obj`` overlaps anything now (0 when it touches nothing)."""
        geoms, dist = mj.contacts(self._data)
        mine = np.isin(geoms, obj.geoms).any(axis=1)
        return float(max(0.0, -dist[mine].min())) if mine.any() else 0.0

    @contextlib.contextmanager
    def batch(self) -> Iterator[None]:
        """Add and remove several robots with one model rebuild (a rebuild takes about 0.5 ms
        per robot in the world); their state is not readable until the block ends."""
        if self._batching:
            yield
            return
        self._batching = True
        try:
            yield
        finally:
            self._batching = False
            if self._dirty:
                self._recompile()

    def _changed(self) -> None:
        if self._batching:
            self._dirty = True
        else:
            self._recompile()

    def _recompile(self) -> None:
        """Rebuild the model, carrying every remaining robot's state over by name (and, after
        a removal, give the freed heap back: :func:`release_freed_memory`)."""
        self._dirty = False
        self._delete_leaving()
        self._rebuild()
        if self._removed_since_trim:
            self._removed_since_trim = False
            release_freed_memory()

    def _rebuild(self) -> None:
        old_m, old_d = self._model, self._data
        joints = _joint_state(old_m, old_d)
        ctrl = {mj.id_name(old_m, "actuator", a): old_d.ctrl[a] for a in range(old_m.nu)}
        self._model = self._spec.compile()
        self._data = mj.new_data(self._model)
        m, d = self._model, self._data
        d.time = old_d.time
        for j in range(m.njnt):
            state = joints.get(mj.id_name(m, "joint", j))
            if state is not None:
                qa, da = m.jnt_qposadr[j], m.jnt_dofadr[j]
                d.qpos[qa:qa + len(state[0])], d.qvel[da:da + len(state[1])] = state
        for a in range(m.nu):
            d.ctrl[a] = ctrl.get(mj.id_name(m, "actuator", a), 0.0)
        for robot in self._robots.values():
            for idx in robot.actuators.values():
                jids = [mj.name_id(m, "joint", n) for n in idx.joint_names]
                idx.qpos_adr = np.array([m.jnt_qposadr[j] for j in jids], dtype=int)
                idx.dof_adr = np.array([m.jnt_dofadr[j] for j in jids], dtype=int)
                idx.ctrl_idx = np.array([mj.name_id(m, "actuator", n)
                                         for n in idx.actuator_names], dtype=int)
                idx.tip_site_id = mj.name_id(m, "site", idx.tip_site)
                idx.drives = [(int(c), float(sign), jt.limit_low, jt.limit_high) for c, sign, jt
                              in zip(idx.ctrl_idx, idx.signs, idx.spec.joints, strict=True)]
            if robot.vehicle is not None:
                index_vehicle(m, d, robot.vehicle, ctrl)
        mj.forward(m, d)
        self._index()

    def _index(self) -> None:
        """Find the objects and tools in the new model, attach new robots' default tools, and
        name every body for the contact log."""
        m, d = self._model, self._data
        self.objects.index(m, d)
        self.rig.index(m, d)
        for key in self._defaults:
            for c in self.rig.changers.values():
                tool = self.rig.tools.get((key, c.spec.default_item or ""))
                if c.key == key and tool is not None and tool.holder is None:
                    self.rig.attach(m, d, c, tool)
        self._defaults.clear()
        mj.forward(m, d)
        self.contacts.index(m, body_names(m, self._robots, self.rig, self.objects))

    # ------------------------------------------------------------------ stepping and state
    @property
    def time(self) -> float:
        """Simulated time (s) since the world was created."""
        return float(self._data.time)

    def step(self, n: int = 1) -> None:
        """Advance the physics by ``n`` steps of ``timestep``.

        Before each step the tool carriers follow their tool changers; after it, the step's
        robot contacts are kept (:class:`~.contacts.ContactLog`). ``mj_step`` computes the
        frames (``site_xpos``...) from the positions it starts from and then integrates them,
        so afterwards the frames lag the joint values by one step; they are brought up to date
        here, so that the tip's pose and the joints read at one time are one state (1 ms apart
        they differ by ~2.5 mm at the KR60's tip moving 1 rad/s). Then the vacuums' suction
        is checked (:meth:`.tools.ToolRig.check_suction`).
        """
        m, d, rig, contacts = self._model, self._data, self.rig, self.contacts
        for _ in range(n):
            rig.follow(d)
            t = d.time
            mj.step(m, d, 1)
            contacts.collect(d, t)
        mj.kinematics(m, d)
        if rig.tools:
            for tool, obj in rig.check_suction(m, d, self.objects, n):
                self.contacts.hold(obj.body_id, tool.key, False)
                log.info("%s: suction lost: %s let go of '%s'", tool.key, tool.spec.name,
                         obj.name)

    def grip(self, tool: ToolState, obj: WcObject) -> None:
        """Hold ``obj`` to a vacuum ``tool`` where it is now."""
        self.rig.grip(self._model, self._data, self.objects, tool, obj)
        self.contacts.hold(obj.body_id, tool.key, True)

    def release(self, tool: ToolState) -> None:
        """Let a vacuum's object go (it takes its own physics mode again)."""
        obj = self.rig.release(self._model, self._data, self.objects, tool)
        if obj is not None:
            self.contacts.hold(obj.body_id, tool.key, False)
