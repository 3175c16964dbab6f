"""Robot models of the embedded simulator, in USARSim's own terms (ground truth).

A robot is a platform carrying items (sensors) and actuators (arms). An arm is a set of parts
(rigid bodies) joined by joints; each joint has an ``offset`` (its anchor, in the actuator frame at
the zero pose) and a ``direction`` (roll, pitch, yaw of its frame); it rotates about, or slides
along, its frame's z axis. This is exactly what ``kr60Arm.uc`` declares. All numbers are in the
USARSim protocol frame (x forward, y right, z down), metres, radians, kg.

The models are data: one YAML file per robot in ``usar_arm/sim/robots/``.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import Array, Vector, exp_so3, invert, rpy_to_matrix, transform
from usar_arm.sim.effector_spec import (
    CollisionCapsule,
    ToolChangerSpec,
    VacuumSpec,
    Vec3,
    load_capsules,
    load_effectors,
    required,
    vec3,
)
from usar_arm.sim.vehicle import VehicleSpec, load_vehicle


@dataclass(frozen=True)
class PartSpec:
    """A rigid part: name, mass (kg), where its mesh is drawn (m, actuator frame), and its
    collision capsules (the simulator's own geometry; none: the part touches nothing)."""

    name: str
    mass: float
    mesh_offset: Vec3 | None = None
    collision: tuple[CollisionCapsule, ...] = ()


@dataclass(frozen=True)
class JointSpec:
    """A joint between two parts, as in a USARSim ``.uc`` file.

    Attributes:
        offset: anchor position in the actuator frame at the zero pose (m).
        direction: roll, pitch, yaw (rad) of the joint frame; motion is about/along its z axis.
        limit_low, limit_high: range (rad or m); ACT targets are clamped into it.
        max_force: drive stiffness and force limit (N·m or N), reported as CONF MaxTorque.
        damping: drive damping (N·m·s/rad or N·s/m).
        inverse_measure_angle: UDK flips the sign of the raw measurement of this joint.
    """

    name: str
    type: str
    parent: str
    child: str
    offset: Vec3
    direction: Vec3
    limit_low: float
    limit_high: float
    max_force: float
    damping: float
    inverse_measure_angle: bool = False

    @property
    def revolute(self) -> bool:
        """True for revolute joints, False for prismatic ones."""
        return self.type == "Revolute"

    def frame(self) -> Array:
        """4x4 pose of the joint frame in the actuator frame at the zero pose."""
        return transform(rpy_to_matrix(self.direction), self.offset)


@dataclass(frozen=True)
class ActuatorSpec:
    """An arm: its mount on the platform, parts, joints (in ``Joints.Add`` order), tip."""

    name: str
    class_name: str
    position: Vec3
    direction: Vec3
    tip_offset: Vec3
    body: str
    parts: tuple[PartSpec, ...]
    joints: tuple[JointSpec, ...]
    tip_sensor: str | None = None

    def parent_index(self, i: int) -> int:
        """Index of the joint whose child part is joint ``i``'s parent part, or -1 (the body)."""
        parent_part = self.joints[i].parent
        for k, jt in enumerate(self.joints):
            if jt.child == parent_part:
                return k
        return -1

    def mount(self) -> Array:
        """4x4 pose of the actuator frame in the platform frame."""
        return transform(rpy_to_matrix(self.direction), self.position)


@dataclass(frozen=True)
class ItemSpec:
    """A sensor fixed to the platform (GroundTruth)."""

    type: str
    name: str
    position: Vec3
    direction: Vec3


@dataclass(frozen=True)
class RobotSpec:
    """A robot class the simulator can spawn (``INIT {ClassName USARBot.KR60}``)."""

    class_name: str
    platform_type: str
    steering_type: str
    platform_mass: float
    battery: int
    items: tuple[ItemSpec, ...]
    actuators: tuple[ActuatorSpec, ...]
    vehicle: VehicleSpec | None = None
    """The chassis, wheels and sensors of a ground vehicle (None: a static platform)."""
    tool_changers: tuple[ToolChangerSpec, ...] = ()
    """The tool changers on the arms (``toolchange`` on the KR60's flange)."""
    tools: tuple[VacuumSpec, ...] = ()
    """The tools the robot spawns with (``KR60gripper``), attached or not."""

    @property
    def short_name(self) -> str:
        """The class name without its package: ``KR60``."""
        return self.class_name.split(".")[-1]


# ------------------------------------------------------------------------------- ground truth


def part_poses(act: ActuatorSpec, q: Vector) -> dict[str, Array]:
    """Pose (4x4, actuator frame) of every part's frame at joint values ``q``.

    A part's frame is the frame of the joint whose child it is; the body part's frame is the
    actuator frame. ``q`` is in joint order, radians or metres, positive = right-handed about (or
    along) the joint frame's z axis.
    """
    poses: dict[str, Array] = {act.body: np.eye(4)}
    zero: dict[str, Array] = {act.body: np.eye(4)}
    for jt, value in zip(act.joints, q, strict=True):
        if jt.parent not in poses:
            raise ValueError(f"joint {jt.name}: parent part {jt.parent} is not attached yet")
        f0 = jt.frame()
        frame = poses[jt.parent] @ invert(zero[jt.parent]) @ f0
        motion = (transform(exp_so3((0.0, 0.0, float(value)))) if jt.revolute
                  else transform(pos=(0.0, 0.0, float(value))))
        poses[jt.child] = frame @ motion
        zero[jt.child] = f0
    return poses


def joint_frames(act: ActuatorSpec, q: Vector) -> list[Array]:
    """World-free joint frames (4x4, actuator frame, before each joint's own motion) at ``q``."""
    poses = part_poses(act, q)
    out = []
    for jt in act.joints:
        parent = jt.parent
        parent_zero = np.eye(4) if parent == act.body else next(
            j.frame() for j in act.joints if j.child == parent)
        out.append(poses[parent] @ invert(parent_zero) @ jt.frame())
    return out


def tip_pose(act: ActuatorSpec, q: Vector) -> Array:
    """Pose (actuator frame) of the tip frame: at ``offset_n + tip_offset`` at the zero pose,
    aligned with the actuator frame there, and carried rigidly by the last part."""
    poses = part_poses(act, q)
    last = act.joints[-1]
    zero_tip = transform(pos=np.asarray(last.offset) + np.asarray(act.tip_offset))
    return poses[last.child] @ invert(last.frame()) @ zero_tip


# ------------------------------------------------------------------------------- loading


def _load_actuator(d: dict[str, Any], path: str, where: str) -> ActuatorSpec:
    parts = tuple(
        PartSpec(str(required(p, "name", path, f"{where}.parts[{i}]")),
                 float(required(p, "mass", path, f"{where}.parts[{i}]")),
                 vec3(p["mesh_offset"], path, f"{where}.parts[{i}].mesh_offset")
                 if "mesh_offset" in p else None,
                 load_capsules(p.get("collision"), path, f"{where}.parts[{i}].collision"))
        for i, p in enumerate(required(d, "parts", path, where)))
    joints = []
    for i, j in enumerate(required(d, "joints", path, where)):
        w = f"{where}.joints[{i}]"
        jtype = str(required(j, "type", path, w))
        if jtype not in ("Revolute", "Prismatic"):
            raise FileFormatError(path, f"type must be Revolute or Prismatic, got {jtype}",
                                  field=f"{w}.type")
        joints.append(JointSpec(
            name=str(required(j, "name", path, w)), type=jtype,
            parent=str(required(j, "parent", path, w)), child=str(required(j, "child", path, w)),
            offset=vec3(required(j, "offset", path, w), path, f"{w}.offset"),
            direction=vec3(required(j, "direction", path, w), path, f"{w}.direction"),
            limit_low=float(required(j, "limit_low", path, w)),
            limit_high=float(required(j, "limit_high", path, w)),
            max_force=float(required(j, "max_force", path, w)),
            damping=float(required(j, "damping", path, w)),
            inverse_measure_angle=bool(j.get("inverse_measure_angle", False))))
    act = ActuatorSpec(
        name=str(required(d, "name", path, where)), class_name=str(d.get("class", d["name"])),
        position=vec3(d.get("position", [0, 0, 0]), path, f"{where}.position"),
        direction=vec3(d.get("direction", [0, 0, 0]), path, f"{where}.direction"),
        tip_offset=vec3(d.get("tip_offset", [0, 0, 0]), path, f"{where}.tip_offset"),
        body=str(required(d, "body", path, where)), parts=parts, joints=tuple(joints),
        tip_sensor=d.get("tip_sensor"))
    names = {p.name for p in parts}
    for i, jt in enumerate(act.joints):
        for role in ("parent", "child"):
            if getattr(jt, role) not in names:
                raise FileFormatError(path, f"{role} part '{getattr(jt, role)}' is not a part "
                                      f"(parts: {', '.join(sorted(names))})",
                                      field=f"{where}.joints[{i}].{role}")
        if jt.limit_low >= jt.limit_high:
            raise FileFormatError(path, "limit_low must be below limit_high",
                                  field=f"{where}.joints[{i}]")
    return act


def load_robot(path: str | Path) -> RobotSpec:
    """Load one robot YAML file, naming the file and field of any error."""
    p = str(path)
    try:
        data = yaml.safe_load(Path(path).read_text())
    except yaml.YAMLError as exc:
        line = getattr(getattr(exc, "problem_mark", None), "line", None)
        raise FileFormatError(p, f"not valid YAML: {exc}",
                              line=None if line is None else line + 1) from None
    if not isinstance(data, dict):
        raise FileFormatError(p, "expected a mapping at the top level")
    plat = data.get("platform", {})
    items = tuple(ItemSpec(str(it["type"]), str(it["name"]),
                           vec3(it.get("position", [0, 0, 0]), p, f"items[{i}].position"),
                           vec3(it.get("direction", [0, 0, 0]), p, f"items[{i}].direction"))
                  for i, it in enumerate(data.get("items", [])))
    actuators = tuple(_load_actuator(a, p, f"actuators[{i}]")
                      for i, a in enumerate(data.get("actuators") or []))
    if not actuators and "vehicle" not in data:
        raise FileFormatError(p, "a robot needs actuators or a vehicle", field="robot.actuators")
    changers, tools = load_effectors(data.get("effectors") or {}, p)
    parts = {a.name: {q.name for q in a.parts} for a in actuators}
    for i, c in enumerate(changers):
        if c.parent not in parts.get(c.actuator, set()):
            raise FileFormatError(p, f"tool changer {c.name}: no part {c.parent} on actuator "
                                  f"{c.actuator}", field=f"effectors.tool_changers[{i}]")
    return RobotSpec(
        class_name=str(required(data, "class_name", p, "robot")),
        platform_type=str(plat.get("type", "StaticPlatform")),
        steering_type=str(plat.get("steering_type", "None")),
        platform_mass=float(plat.get("mass", 0)),
        battery=int(plat.get("battery", 99999)),
        items=items, actuators=actuators,
        vehicle=load_vehicle(data["vehicle"], p) if "vehicle" in data else None,
        tool_changers=changers, tools=tools)


def builtin_robots(vehicles: bool = False) -> dict[str, RobotSpec]:
    """The robot classes shipped with the simulator, by full class name (``USARBot.KR60``):
    the arms, and with ``vehicles`` the ground vehicles too (``USARBot.P3AT``)."""
    out: dict[str, RobotSpec] = {}
    folder = resources.files("usar_arm.sim") / "robots"
    for entry in sorted(folder.iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".yaml"):
            with resources.as_file(entry) as fp:
                spec = load_robot(fp)
            if vehicles or spec.vehicle is None:
                out[spec.class_name] = spec
    return out
