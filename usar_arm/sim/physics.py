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
import ctypes
import ctypes.util
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

import mujoco
import numpy as np

from usar_arm.core.spatial import Array, invert, quat_from_matrix, rpy_to_matrix, transform
from usar_arm.sim.robot_spec import ActuatorSpec, RobotSpec

GRAVITY = 9.81
"""Gravitational acceleration (m/s²), along +z of the z-down world."""
LINK_RADIUS = 0.05
"""Radius (m) of the capsules that carry each part's mass."""
FRESH_SPEC_AFTER = 50
"""Robot removals after which the MuJoCo spec is built anew: an ``MjSpec`` keeps about 2 KiB
for every robot ever deleted from it (mujoco 3.x), which a long-running server must not."""


def _heap_trimmer() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim`` (None elsewhere)."""
    name = ctypes.util.find_library("c")
    try:
        trim = getattr(ctypes.CDLL(name), "malloc_trim", None) if name else None
    except OSError:
        return None
    return trim if callable(trim) else None


_MALLOC_TRIM = _heap_trimmer()


def release_freed_memory() -> None:
    """Give the heap's free pages back to the system (glibc; elsewhere nothing).

    Every model rebuild frees and reallocates a few MiB; glibc keeps the freed pages and the
    heap fragments, so a server whose robots come and go grew by ~15 KiB per robot removed
    (17 MiB over 1,100 spawn/remove cycles, measured) while holding no more live memory.
    Trimming after a removal keeps it flat; it frees only what is free, so a real leak still
    shows in the soak test's memory slope.
    """
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)


@dataclass
class _ActuatorIndex:
    spec: ActuatorSpec
    joint_names: list[str]
    actuator_names: list[str]
    signs: Array
    qpos_adr: Array = field(default_factory=lambda: np.zeros(0, dtype=int))
    dof_adr: Array = field(default_factory=lambda: np.zeros(0, dtype=int))
    ctrl_idx: Array = field(default_factory=lambda: np.zeros(0, dtype=int))
    tip_site: str = ""
    tip_site_id: int = -1
    drives: list[tuple[int, float, float, float]] = field(default_factory=list)
    """Per joint: ctrl index, sign, low and high limit (USARSim sign), for :meth:`set_targets`."""


@dataclass
class _RobotEntry:
    key: str
    spec: RobotSpec
    location: tuple[float, ...]
    rotation: tuple[float, ...]
    platform_pose: Array
    actuators: dict[str, _ActuatorIndex]


def _quat(rot: Array) -> list[float]:
    return [float(v) for v in quat_from_matrix(rot)]


class PhysicsWorld:
    """A MuJoCo world holding any number of USARSim robots.

    Args:
        timestep: physics step (s); the default 1 ms gives 1 kHz physics.
        gravity: apply gravity (on in UDK).
    """

    def __init__(self, timestep: float = 0.001, gravity: bool = True):
        self.timestep = timestep
        self.gravity = gravity
        self._spec = self._new_spec()
        self._robots: dict[str, _RobotEntry] = {}
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
        return spec

    # ------------------------------------------------------------------ robots
    def add_robot(self, key: str, spec: RobotSpec, location: Sequence[float],
                  rotation: Sequence[float]) -> None:
        """Spawn ``spec`` at a world pose (m, roll/pitch/yaw rad); ``key`` must be unique."""
        if key in self._robots:
            raise ValueError(f"robot key {key} already in use")
        entry = _RobotEntry(key, spec, tuple(float(v) for v in location),
                            tuple(float(v) for v in rotation),
                            transform(rpy_to_matrix(rotation), location), {})
        self._build(entry)
        self._robots[key] = entry
        self._changed()

    def _build(self, entry: _RobotEntry) -> None:
        """Add a robot's bodies, joints and drives to the spec (its indices are set on the next
        rebuild of the model)."""
        platform = self._spec.worldbody.add_body(
            name=f"{entry.key}/platform", pos=list(entry.location),
            quat=_quat(entry.platform_pose[:3, :3]))
        platform.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.05, 0, 0], mass=1.0,
                          contype=0, conaffinity=0)
        entry.actuators = {act.name: self._add_actuator(entry.key, platform, act)
                           for act in entry.spec.actuators}

    def _add_actuator(self, key: str, platform: mujoco.MjsBody, act: ActuatorSpec
                      ) -> _ActuatorIndex:
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
        return _ActuatorIndex(act, joint_names, actuator_names, np.array(signs), tip_site=tip_site)

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
        qpos = {}
        for j in range(old_m.njnt):
            name = mujoco.mj_id2name(old_m, mujoco.mjtObj.mjOBJ_JOINT, j)
            qpos[name] = (old_d.qpos[old_m.jnt_qposadr[j]], old_d.qvel[old_m.jnt_dofadr[j]])
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

    def _index(self, key: str, actuator: str) -> _ActuatorIndex:
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
        """World pose (4x4) of a robot's platform."""
        return self._robots[key].platform_pose.copy()

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
