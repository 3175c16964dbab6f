"""MuJoCo physics of the embedded simulator: one shared world, robots added and removed live.

Each joint is a position drive toward its (limit-clamped) target, as UDK's PhysX drive is:
stiffness = MaxForce, damping = Damping, force limit = MaxForce (docs/protocol.md section 6.3).
The world is expressed in the USARSim protocol frame (z down), so gravity is +z. Robots do not
collide with each other or with themselves (contacts are off); the planner keeps motions
collision-free.

This is the only module that imports ``mujoco``.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence

import mujoco
import numpy as np

from usar_arm.core.spatial import Array, invert, quat_from_matrix, rpy_to_matrix, transform
from usar_arm.sim.drive_gains import (
    STEER_KP,
    STEER_SIZE,
    WHEEL_DAMPING,
    WHEEL_FRICTION,
    WHEEL_KV,
)
from usar_arm.sim.heap import release_freed_memory
from usar_arm.sim.physics_index import ActuatorIndex, RobotEntry, VehicleIndex
from usar_arm.sim.robot_spec import ActuatorSpec, RobotSpec
from usar_arm.sim.vehicle import VehicleSpec
from usar_arm.sim.world_spec import SceneryBox

GRAVITY = 9.81
"""Gravitational acceleration (m/s²), along +z of the z-down world."""
LINK_RADIUS = 0.05
"""Radius (m) of the capsules that carry each part's mass."""
SCENERY_AFFINITY = 1
"""Contact bit of the floor and the scenery boxes: vehicles (contype 1) touch them; the arms
(contype 0) and vehicles among themselves do not touch anything else."""
VEHICLE_CONTYPE = 1
"""Contact type of a vehicle's chassis and wheels."""
FRESH_SPEC_AFTER = 50
"""Robot removals after which the MuJoCo spec is built anew: an ``MjSpec`` keeps about 2 KiB
for every robot ever deleted from it (mujoco 3.x), which a long-running server must not."""


def _quat(rot: Array) -> list[float]:
    return [float(v) for v in quat_from_matrix(rot)]


def _add_scenery(world: mujoco.MjsBody, scenery: Sequence[SceneryBox], floor_z: float) -> None:
    """The floor (a plane facing up, i.e. toward -z: its normal, +z, turned over about x) and
    the world's boxes, touched by vehicles only."""
    world.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 1.0],
                   pos=[0.0, 0.0, floor_z], quat=[0.0, 1.0, 0.0, 0.0],
                   contype=0, conaffinity=SCENERY_AFFINITY)
    for i, box in enumerate(scenery):
        world.add_geom(name=f"scenery/{i}/{box.name}", type=mujoco.mjtGeom.mjGEOM_BOX,
                       size=list(box.half), pos=list(box.center),
                       quat=_quat(rpy_to_matrix((0.0, 0.0, box.yaw))),
                       contype=0, conaffinity=SCENERY_AFFINITY)


def _add_vehicle(spec: mujoco.MjSpec, entry: RobotEntry, veh: VehicleSpec, floor_z: float
                 ) -> VehicleIndex:
    """A free chassis on its wheels: boxes and bumper masses on one body, one hinge per wheel
    (positive spin forward; a steered one on a position-driven knuckle) driven within MaxForce.

    The chassis is placed no lower than resting on the floor (INIT's z is the chassis
    origin, as UDK's CenterItem location)."""
    loc = list(entry.location)
    loc[2] = min(loc[2], floor_z - veh.rest_height)
    name = f"{entry.key}/platform"
    body = spec.worldbody.add_body(name=name, pos=loc, quat=_quat(entry.platform_pose[:3, :3]))
    body.add_freejoint(name=f"{name}/free")
    for box in veh.chassis:
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=list(box.half),
                      pos=list(box.center), mass=box.mass, contype=VEHICLE_CONTYPE,
                      conaffinity=0)
    for _, offset, mass in veh.extra_masses:
        body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.01, 0, 0], pos=list(offset),
                      mass=mass, contype=0, conaffinity=0)
    joints: dict[str, str] = {}
    steers: dict[str, str] = {}
    for w in veh.wheels:
        holder, at = body, list(w.offset)
        if w.steer is not None:  # a knuckle turning about z (down: positive turns right)
            s = w.steer
            holder, at = body.add_body(name=f"{name}/{s.name}", pos=at), [0.0, 0.0, 0.0]
            steers[s.name] = f"{name}/{s.name}/steer"
            holder.add_joint(name=steers[s.name], type=mujoco.mjtJoint.mjJNT_HINGE,
                             axis=[0.0, 0.0, 1.0], range=[s.limit_low, s.limit_high],
                             limited=True)
            holder.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[STEER_SIZE, 0, 0],
                            mass=s.mass, contype=0, conaffinity=0)
            _drive(spec, steers[s.name], s.max_force).set_to_position(kp=STEER_KP,
                                                                      kv=s.damping)
        wheel = holder.add_body(name=f"{name}/{w.name}", pos=at)
        jname = f"{name}/{w.name}/spin"
        wheel.add_joint(name=jname, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, -1.0, 0.0],
                        damping=WHEEL_DAMPING)
        wheel.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[veh.wheel_radius, 0, 0],
                       mass=w.mass, contype=VEHICLE_CONTYPE, conaffinity=0,
                       friction=[WHEEL_FRICTION, 0.005, 0.0001])
        if w.driven:
            _drive(spec, jname, w.max_force).set_to_velocity(kv=WHEEL_KV)
        joints[w.name] = jname
    return VehicleIndex(veh, name, joints, steers)


def _drive(spec: mujoco.MjSpec, joint: str, max_force: float) -> mujoco.MjsActuator:
    """A joint's actuator ``<joint>/drive``, its force limited to +-``max_force``."""
    drive = spec.add_actuator(name=f"{joint}/drive", target=joint,
                              trntype=mujoco.mjtTrn.mjTRN_JOINT)
    drive.forcelimited = True
    drive.forcerange = [-max_force, max_force]
    return drive


def _joint_state(m: mujoco.MjModel, d: mujoco.MjData
                 ) -> tuple[dict[str, tuple[float, float]], dict[str, tuple[Array, Array]]]:
    """Position and velocity of every joint by name: hinges and slides, and free joints."""
    qpos, free_state = {}, {}
    for j in range(m.njnt):
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j)
        qa, da = m.jnt_qposadr[j], m.jnt_dofadr[j]
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            free_state[name] = (d.qpos[qa:qa + 7].copy(), d.qvel[da:da + 6].copy())
        else:
            qpos[name] = (d.qpos[qa], d.qvel[da])
    return qpos, free_state


def _index_vehicle(m: mujoco.MjModel, d: mujoco.MjData, veh: VehicleIndex,
                   qpos: dict[str, tuple[float, float]],
                   free_state: dict[str, tuple[Array, Array]], ctrl: dict[str, float]) -> None:
    """Find a vehicle's addresses in a rebuilt model and carry its state over."""
    veh.body_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, veh.body)
    free = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, f"{veh.body}/free")
    if f"{veh.body}/free" in free_state:
        qa, da = m.jnt_qposadr[free], m.jnt_dofadr[free]
        d.qpos[qa:qa + 7], d.qvel[da:da + 6] = free_state[f"{veh.body}/free"]
    veh.wheel_qpos, veh.wheel_ctrl, veh.steer_qpos, veh.steer_ctrl = {}, {}, {}, {}
    for joints, at, drives in ((veh.wheel_joints, veh.wheel_qpos, veh.wheel_ctrl),
                               (veh.steer_joints, veh.steer_qpos, veh.steer_ctrl)):
        for part, jname in joints.items():
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jname)
            at[part] = int(m.jnt_qposadr[j])
            if jname in qpos:
                d.qpos[m.jnt_qposadr[j]], d.qvel[m.jnt_dofadr[j]] = qpos[jname]
            a = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, f"{jname}/drive")
            if a >= 0:
                drives[part] = a
                d.ctrl[a] = ctrl.get(f"{jname}/drive", 0.0)


class PhysicsWorld:
    """A MuJoCo world holding any number of USARSim robots.

    Args:
        timestep: physics step (s); the default 1 ms gives 1 kHz physics.
        gravity: apply gravity (on in UDK).
    """

    def __init__(self, timestep: float = 0.001, gravity: bool = True,
                 scenery: Sequence[SceneryBox] = (), floor_z: float = 0.0):
        self.timestep = timestep
        self.gravity = gravity
        self.scenery = tuple(scenery)
        self.floor_z = floor_z
        self._spec = self._new_spec()
        self._robots: dict[str, RobotEntry] = {}
        self._batching = False
        self._removed_since_trim = False
        self._dirty = False
        self._removals = 0
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)

    def _new_spec(self) -> mujoco.MjSpec:
        spec = mujoco.MjSpec()
        spec.compiler.degree = False
        spec.option.timestep = self.timestep
        spec.option.gravity = [0.0, 0.0, GRAVITY if self.gravity else 0.0]
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        spec.modelname = "usar_arm_world"
        _add_scenery(spec.worldbody, self.scenery, self.floor_z)
        return spec

    # ------------------------------------------------------------------ robots
    def add_robot(self, key: str, spec: RobotSpec, location: Sequence[float],
                  rotation: Sequence[float]) -> None:
        """Spawn ``spec`` at a world pose (m, roll/pitch/yaw rad); ``key`` must be unique."""
        if key in self._robots:
            raise ValueError(f"robot key {key} already in use")
        entry = RobotEntry(key, spec, tuple(float(v) for v in location),
                            tuple(float(v) for v in rotation),
                            transform(rpy_to_matrix(rotation), location), {})
        self._build(entry)
        self._robots[key] = entry
        self._changed()

    def _build(self, entry: RobotEntry) -> None:
        """Add a robot's bodies, joints and drives to the spec (its indices are set on the next
        rebuild of the model)."""
        if entry.spec.vehicle is not None:
            entry.vehicle = _add_vehicle(self._spec, entry, entry.spec.vehicle, self.floor_z)
            return
        platform = self._spec.worldbody.add_body(
            name=f"{entry.key}/platform", pos=list(entry.location),
            quat=_quat(entry.platform_pose[:3, :3]))
        platform.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.05, 0, 0], mass=1.0,
                          contype=0, conaffinity=0)
        entry.actuators = {act.name: self._add_actuator(entry.key, platform, act)
                           for act in entry.spec.actuators}

    def _add_actuator(self, key: str, platform: mujoco.MjsBody, act: ActuatorSpec
                      ) -> ActuatorIndex:
        prefix = f"{key}/{act.name}"
        mount = act.mount()
        bodies = {act.body: platform.add_body(name=f"{prefix}/{act.body}",
                                              pos=mount[:3, 3].tolist(),
                                              quat=_quat(mount[:3, :3]))}
        zero = {act.body: np.eye(4)}
        masses = {p.name: p.mass for p in act.parts}
        children: dict[str, list[Array]] = {p.name: [] for p in act.parts}
        joint_names, actuator_names, signs = [], [], []
        for jt in act.joints:
            f0 = jt.frame()
            rel = invert(zero[jt.parent]) @ f0
            children[jt.parent].append(rel[:3, 3])
            body = bodies[jt.parent].add_body(name=f"{prefix}/{jt.child}",
                                              pos=rel[:3, 3].tolist(), quat=_quat(rel[:3, :3]))
            sign = -1.0 if jt.inverse_measure_angle else 1.0
            lo, hi = sorted((sign * jt.limit_low, sign * jt.limit_high))
            jname = f"{prefix}/{jt.name}"
            body.add_joint(name=jname, type=(mujoco.mjtJoint.mjJNT_HINGE if jt.revolute
                                             else mujoco.mjtJoint.mjJNT_SLIDE),
                           axis=[0.0, 0.0, sign], range=[lo, hi], limited=True)
            drive = self._spec.add_actuator(name=f"{jname}/drive", target=jname,
                                            trntype=mujoco.mjtTrn.mjTRN_JOINT)
            drive.set_to_position(kp=jt.max_force, kv=jt.damping)
            drive.forcelimited = True
            drive.forcerange = [-jt.max_force, jt.max_force]
            drive.ctrllimited = True
            drive.ctrlrange = [lo, hi]
            bodies[jt.child] = body
            zero[jt.child] = f0
            joint_names.append(jname)
            actuator_names.append(f"{jname}/drive")
            signs.append(sign)
        last = act.joints[-1]
        tip_rel = invert(last.frame()) @ transform(
            pos=np.asarray(last.offset) + np.asarray(act.tip_offset))
        children[last.child].append(tip_rel[:3, 3])
        for name, body in bodies.items():
            self._add_mass(body, masses[name], children[name])
        tip_site = f"{prefix}/tip"
        bodies[last.child].add_site(name=tip_site, pos=tip_rel[:3, 3].tolist(),
                                    quat=_quat(tip_rel[:3, :3]))
        return ActuatorIndex(act, joint_names, actuator_names, np.array(signs), tip_site=tip_site)

    @staticmethod
    def _add_mass(body: mujoco.MjsBody, mass: float, ends: list[Array]) -> None:
        """Spread a part's mass over capsules from its frame origin to the next anchors."""
        segments = [e for e in ends if np.linalg.norm(e) > 1e-6]
        if not segments:
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[LINK_RADIUS, 0, 0],
                          mass=max(mass, 1e-3), contype=0, conaffinity=0)
            return
        for end in segments:
            body.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[LINK_RADIUS, 0, 0],
                          fromto=[0.0, 0.0, 0.0, *end.tolist()],
                          mass=max(mass, 1e-3) / len(segments),
                          contype=0, conaffinity=0)

    def remove_robot(self, key: str) -> None:
        """Destroy a robot (when its connection closes); unknown keys are ignored."""
        if self._robots.pop(key, None) is None:
            return
        self._removals += 1
        if self._removals >= FRESH_SPEC_AFTER:
            self._removals = 0
            self._spec = self._new_spec()
            for entry in self._robots.values():
                self._build(entry)
        else:
            self._spec.delete(self._spec.body(f"{key}/platform"))
        self._removed_since_trim = True
        self._changed()

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
        self._rebuild()
        if self._removed_since_trim:
            self._removed_since_trim = False
            release_freed_memory()

    def _rebuild(self) -> None:
        old_m, old_d = self._model, self._data
        qpos, free_state = _joint_state(old_m, old_d)
        ctrl = {mujoco.mj_id2name(old_m, mujoco.mjtObj.mjOBJ_ACTUATOR, a): old_d.ctrl[a]
                for a in range(old_m.nu)}
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)
        m, d = self._model, self._data
        d.time = old_d.time
        for robot in self._robots.values():
            for idx in robot.actuators.values():
                jids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n) for n in idx.joint_names]
                idx.qpos_adr = np.array([m.jnt_qposadr[j] for j in jids], dtype=int)
                idx.dof_adr = np.array([m.jnt_dofadr[j] for j in jids], dtype=int)
                idx.ctrl_idx = np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, n)
                                         for n in idx.actuator_names], dtype=int)
                idx.tip_site_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, idx.tip_site)
                idx.drives = [(int(c), float(sign), jt.limit_low, jt.limit_high) for c, sign, jt
                              in zip(idx.ctrl_idx, idx.signs, idx.spec.joints, strict=True)]
                for k, name in enumerate(idx.joint_names):
                    if name in qpos:
                        d.qpos[idx.qpos_adr[k]], d.qvel[idx.dof_adr[k]] = qpos[name]
                for k, name in enumerate(idx.actuator_names):
                    d.ctrl[idx.ctrl_idx[k]] = ctrl.get(name, 0.0)
            if robot.vehicle is not None:
                _index_vehicle(m, d, robot.vehicle, qpos, free_state, ctrl)
        mujoco.mj_forward(m, d)

    # ------------------------------------------------------------------ stepping and state
    @property
    def time(self) -> float:
        """Simulated time (s) since the world was created."""
        return float(self._data.time)

    def step(self, n: int = 1) -> None:
        """Advance the physics by ``n`` steps of ``timestep``.

        ``mj_step`` computes the frames (``site_xpos``...) from the positions it starts from and
        then integrates them, so afterwards the frames lag the joint values by one step; they
        are brought up to date here, so that the tip's pose and the joints read at one time
        are one state (1 ms apart they differ by ~2.5 mm at the KR60's tip moving 1 rad/s).
        """
        mujoco.mj_step(self._model, self._data, nstep=n)
        mujoco.mj_kinematics(self._model, self._data)

    def _index(self, key: str, actuator: str) -> ActuatorIndex:
        return self._robots[key].actuators[actuator]

    def set_targets(self, key: str, actuator: str, targets: Sequence[float]) -> None:
        """Set every joint's drive target (rad or m, USARSim sign), clamped to its limits."""
        ctrl = self._data.ctrl
        for (c, sign, low, high), value in zip(self._index(key, actuator).drives, targets,
                                               strict=True):
            ctrl[c] = sign * min(high, max(low, float(value)))

    def joint_values(self, key: str, actuator: str) -> Array:
        """Measured joint values (rad or m), positive right-handed about each joint's z axis."""
        idx = self._index(key, actuator)
        return idx.signs * self._data.qpos[idx.qpos_adr]

    def set_joint_values(self, key: str, actuator: str, values: Sequence[float]) -> None:
        """Teleport the joints (and their targets) to ``values``, at rest (for tests)."""
        idx = self._index(key, actuator)
        v = idx.signs * np.asarray(values, dtype=float)
        self._data.qpos[idx.qpos_adr] = v
        self._data.qvel[idx.dof_adr] = 0.0
        self._data.ctrl[idx.ctrl_idx] = v
        mujoco.mj_forward(self._model, self._data)

    def platform_pose(self, key: str) -> Array:
        """World pose (4x4) of a robot's platform (a vehicle's chassis where it is now)."""
        entry = self._robots[key]
        if entry.vehicle is None:
            return entry.platform_pose.copy()
        b = entry.vehicle.body_id
        return transform(self._data.xmat[b].reshape(3, 3).copy(), self._data.xpos[b].copy())

    def set_wheel_speeds(self, key: str, speeds: dict[str, float]) -> None:
        """Set the target spin (rad/s, positive forward) of a vehicle's driven wheels."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        for wheel, speed in speeds.items():
            self._data.ctrl[veh.wheel_ctrl[wheel]] = speed

    def set_steer_targets(self, key: str, targets: dict[str, float]) -> None:
        """Set the target angle (rad, positive turns right) of steer joints by UDK name."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        for joint, angle in targets.items():
            self._data.ctrl[veh.steer_ctrl[joint]] = angle

    def steer_angles(self, key: str) -> dict[str, float]:
        """The angle (rad, positive turning right) of every steer joint of a vehicle."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        return {s: float(self._data.qpos[a]) for s, a in veh.steer_qpos.items()}

    def wheel_angles(self, key: str) -> dict[str, float]:
        """The accumulated spin (rad, positive forward) of every wheel of a vehicle."""
        veh = self._robots[key].vehicle
        assert veh is not None, f"{key} is not a vehicle"
        return {w: float(self._data.qpos[a]) for w, a in veh.wheel_qpos.items()}

    def cast_rays(self, key: str, origin: Array, directions: Array, max_range: float) -> Array:
        """Distance (m) along each unit direction (n x 3, world) from ``origin`` to the first
        surface of the world that is not the robot ``key``'s chassis; ``max_range`` where
        nothing is nearer."""
        n = len(directions)
        dist = np.empty(n)
        geom = np.empty(n, dtype=np.int32)
        entry = self._robots[key]
        exclude = entry.vehicle.body_id if entry.vehicle is not None else -1
        mujoco.mj_multiRay(self._model, self._data, np.asarray(origin, dtype=float),
                           np.ascontiguousarray(directions, dtype=float).reshape(-1), None, True,
                           exclude, geom, dist, None, n, max_range)
        return np.where((geom < 0) | (dist < 0) | (dist > max_range), max_range, dist)

    def tip_pose(self, key: str, actuator: str) -> Array:
        """World pose (4x4) of an arm's tip frame."""
        idx = self._index(key, actuator)
        sid = idx.tip_site_id
        return transform(self._data.site_xmat[sid].reshape(3, 3).copy(),
                         self._data.site_xpos[sid].copy())

    @property
    def robot_keys(self) -> tuple[str, ...]:
        """Keys of the robots in the world."""
        return tuple(self._robots)
