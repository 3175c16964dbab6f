"""Effectors of a robot, in USARSim's terms: its tool changers and the tools they can hold.

As UDK declares them (``DefaultUSAR.ini``, ``ToolChanger.uc``, ``Vacuum.uc``,
``VacuumGripper.uc``): a tool changer rides on a part of an arm (``Parent="Joint7"``) at a
position and direction given in the arm's frame at the zero pose; a tool (a VacuumGripper) is
spawned at a pose relative to the robot and, being ``startAttached=false``, detached at once and
grabbed by the tool changer whose ``defaultItem`` names it. All numbers are in the USARSim frame
(x forward, y right, z down), metres, radians, kg.

Also here: the collision capsules of an arm's parts (the simulator's own link geometry, an
extension of the data UDK's meshes carry; docs/simulator.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import Array, rpy_to_matrix, transform

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class CollisionCapsule:
    """A capsule of a part's collision geometry: radius (m) and the two end points of its
    axis (m, actuator frame at the zero pose)."""

    radius: float
    start: Vec3
    end: Vec3


@dataclass(frozen=True)
class ToolChangerSpec:
    """A ToolChanger (``ToolChanger.uc``): a phantom body (no collision) on an arm part.

    Attributes:
        name: its ItemName (``toolchange``). actuator: the arm it rides on. parent: the part.
        position, direction: its pose in the actuator frame at the zero pose (m; roll, pitch,
            yaw rad); its local +z is the approach axis.
        default_item: the tool it grabs at startup (UDK's class-wide ``defaultItem``), when the
            robot has one of that name.
        position_tolerance: how far (m) a tool's origin may be for CLOSE to take it; CLOSE's
            ray is twice as long. angle_tolerance: how far (rad) each of the tool's x and y
            axes may point from the tool changer's.
    """

    name: str
    actuator: str
    parent: str
    position: Vec3
    direction: Vec3
    default_item: str | None = None
    position_tolerance: float = 0.5
    angle_tolerance: float = 0.5

    def frame(self) -> Array:
        """4x4 pose of the tool changer in the actuator frame at the zero pose."""
        return transform(rpy_to_matrix(self.direction), self.position)


@dataclass(frozen=True)
class VacuumSpec:
    """A vacuum tool (``VacuumGripper.uc`` on ``Vacuum.uc``), ItemType ``Gripper``.

    Attributes:
        name: its ItemName (``KR60gripper``). class_name: ``VacuumGripper``.
        position, direction: where it spawns, relative to the robot (m; rad).
        start_attached: False: detached at once (then grabbed by a tool changer's default).
        mass: kg. tip_offset: the suction point in the tool frame (m; 0.183 along +z).
        suction_length: how far (m) beyond the tip the suction ray reaches (0.125), and how
            far a held object may drift from where it was gripped before it is lost.
        drop_check_frequency: ticks skipped between suction checks (UDK's ini: 5).
        body_center, body_half: the body's collision box (m, tool frame).
    """

    name: str
    position: Vec3
    direction: Vec3
    mass: float
    tip_offset: Vec3
    suction_length: float
    body_center: Vec3
    body_half: Vec3
    class_name: str = "VacuumGripper"
    start_attached: bool = False
    drop_check_frequency: int = 5

    item_type = "Gripper"
    """The ItemType UDK reports (the Gripper class's, for every vacuum)."""


def vec3(value: Any, path: str, field: str) -> Vec3:
    """Three finite numbers from a YAML list, naming the file and field when they are not."""
    if not (isinstance(value, list) and len(value) == 3):
        raise FileFormatError(path, f"expected [x, y, z], got {value!r}", field=field)
    try:
        return (float(value[0]), float(value[1]), float(value[2]))
    except (TypeError, ValueError):
        raise FileFormatError(path, f"expected three numbers, got {value!r}", field=field) from None


def required(d: dict[str, Any], key: str, path: str, where: str) -> Any:
    """``d[key]``, or a FileFormatError naming ``where.key``."""
    if not isinstance(d, dict) or key not in d:
        raise FileFormatError(path, f"missing '{key}'", field=f"{where}.{key}")
    return d[key]


def load_capsules(entries: Any, path: str, where: str) -> tuple[CollisionCapsule, ...]:
    """A part's ``collision`` list: ``{radius: r, from: [x,y,z], to: [x,y,z]}`` each."""
    out = []
    for i, c in enumerate(entries or []):
        w = f"{where}[{i}]"
        radius = float(required(c, "radius", path, w))
        if not radius > 0:
            raise FileFormatError(path, f"radius must be > 0, got {radius}", field=f"{w}.radius")
        out.append(CollisionCapsule(radius, vec3(required(c, "from", path, w), path, f"{w}.from"),
                                    vec3(required(c, "to", path, w), path, f"{w}.to")))
    return tuple(out)


def load_effectors(data: dict[str, Any], path: str
                   ) -> tuple[tuple[ToolChangerSpec, ...], tuple[VacuumSpec, ...]]:
    """The ``tool_changers`` and ``tools`` of a robot file (both optional)."""
    changers = []
    for i, t in enumerate(data.get("tool_changers") or []):
        w = f"tool_changers[{i}]"
        changers.append(ToolChangerSpec(
            name=str(required(t, "name", path, w)), actuator=str(required(t, "actuator", path, w)),
            parent=str(required(t, "parent", path, w)),
            position=vec3(required(t, "position", path, w), path, f"{w}.position"),
            direction=vec3(required(t, "direction", path, w), path, f"{w}.direction"),
            default_item=t.get("default_item"),
            position_tolerance=float(t.get("position_tolerance", 0.5)),
            angle_tolerance=float(t.get("angle_tolerance", 0.5))))
    tools = []
    for i, t in enumerate(data.get("tools") or []):
        w = f"tools[{i}]"
        cls = str(t.get("class", "VacuumGripper"))
        if cls != "VacuumGripper":
            raise FileFormatError(path, f"only VacuumGripper tools are simulated, got {cls}",
                                  field=f"{w}.class")
        body = required(t, "body", path, w)
        tools.append(VacuumSpec(
            name=str(required(t, "name", path, w)),
            position=vec3(t.get("position", [0, 0, 0]), path, f"{w}.position"),
            direction=vec3(t.get("direction", [0, 0, 0]), path, f"{w}.direction"),
            mass=float(required(t, "mass", path, w)),
            tip_offset=vec3(required(t, "tip_offset", path, w), path, f"{w}.tip_offset"),
            suction_length=float(required(t, "suction_length", path, w)),
            body_center=vec3(required(body, "center", path, f"{w}.body"), path,
                             f"{w}.body.center"),
            body_half=vec3(required(body, "half", path, f"{w}.body"), path, f"{w}.body.half"),
            class_name=cls, start_attached=bool(t.get("start_attached", False)),
            drop_check_frequency=int(t.get("drop_check_frequency", 5))))
    names = [t.name for t in tools]
    for i, c in enumerate(changers):
        if c.default_item is not None and c.default_item not in names:
            changers[i] = ToolChangerSpec(c.name, c.actuator, c.parent, c.position, c.direction,
                                          None, c.position_tolerance, c.angle_tolerance)
    return tuple(changers), tuple(tools)
