"""The WorldController's objects in the simulator's world (``WCObject``: a KActor).

Every object is a free rigid body made of its class's boxes (:mod:`usar_arm.core.wc_classes`,
mass = the class mass times the scale's product, spread over the boxes by volume). UDK moves an
object only when it was created with Physics ``RigidBody``, ``Falling`` or ``Ground``; any other
(absent included) is ``PHYS_None``: it stays where it is, still colliding. Here such an object is
held where it is by a stiff weld to the world (so a vacuum can take it and let it go without
rebuilding the model); a held object's weld is off, and on release it is on again where the
object is then (UDK restores the original physics mode: a ``PHYS_None`` object stays in mid-air).
Frames: the z-down world; an object's pose is its bounding box centre's.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usar_arm.core.spatial import FLIP_X, Array, matrix_from_quat, transform
from usar_arm.core.wc_classes import WcClass
from usar_arm.sim import mj
from usar_arm.sim.scenery import OBJECT_AFFINITY, OBJECT_BIT, quat

MOVING_PHYSICS = ("RigidBody", "Falling", "Ground")
"""Physics modes (compared exactly, as UDK's ``!=`` does) under which an object moves."""
STAY_SOLREF = (0.002, 1.0)
"""Time constant (s) and damping ratio of the weld that keeps a static object in place: the
stiffest MuJoCo allows at 1 ms steps."""
FLOATING = 1e-9
"""The gravity compensation every object is built with, none to speak of: MuJoCo compensates
gravity only for bodies that had some when the model was compiled, and a static or held object
gets all of it (1) at run time, so that it does not sag in its weld."""


@dataclass
class WcObject:
    """One spawned object and where it lives in the model.

    Attributes:
        uid: the world's id of it. name: its WorldController name. owner: the key of the
            WorldController connection that made it.
        wc_class, scale, physics, permanent, memory, material: as CONTROL Create gave them.
        pose: its pose (4x4, z-down world) when created or last moved (the model is built
            with it).
    """

    uid: int
    name: str
    owner: str
    wc_class: WcClass
    scale: tuple[float, float, float]
    physics: str
    permanent: bool
    memory: str
    material: str
    pose: Array
    body_id: int = -1
    qpos_adr: int = -1
    dof_adr: int = -1
    stay_eq: int = -1
    geoms: list[int] = field(default_factory=list)
    held: bool = False
    """Held by a vacuum (its stay weld is off meanwhile)."""

    @property
    def static(self) -> bool:
        """True when UDK would have set PHYS_None."""
        return self.physics not in MOVING_PHYSICS

    @property
    def body(self) -> str:
        """Its MuJoCo body's name."""
        return f"wc/{self.uid}"


class WorldObjects:
    """The objects of every WorldController, by uid."""

    def __init__(self) -> None:
        self.objects: dict[int, WcObject] = {}
        self._next = 0
        self.by_body: dict[int, WcObject] = {}
        """Body id -> object, after each rebuild."""

    def new_uid(self) -> int:
        """A fresh object id."""
        self._next += 1
        return self._next

    def build(self, spec: mj.Spec, obj: WcObject) -> None:
        """Add ``obj``'s body, boxes and stay weld to ``spec``."""
        pose = obj.pose
        body = spec.worldbody.add_body(name=obj.body, pos=pose[:3, 3].tolist(),
                                       quat=quat(pose[:3, :3]))
        body.add_freejoint(name=f"{obj.body}/free")
        body.gravcomp = FLOATING  # (MuJoCo applies gravity compensation only to bodies
        boxes = obj.wc_class.boxes(obj.scale)
        volumes = [float(np.prod(size)) for _, _, size in boxes]
        mass = max(obj.wc_class.scaled_mass(obj.scale), 1e-4)
        for (piece, centre, size), volume in zip(boxes, volumes, strict=True):
            c = FLIP_X @ np.asarray(centre)  # REP-103 object axes -> the z-down world's
            body.add_geom(name=f"{obj.body}/{piece}", type=mj.BOX,
                          size=[s / 2 for s in size], pos=c.tolist(),
                          mass=mass * volume / sum(volumes),
                          contype=OBJECT_BIT, conaffinity=OBJECT_AFFINITY)
        mj.add_weld(spec, f"{obj.body}/stay", "world", obj.body, STAY_SOLREF, obj.static)
        self.objects[obj.uid] = obj

    def delete(self, spec: mj.Spec, obj: WcObject) -> None:
        """Remove ``obj`` (and with its body its stay weld) from ``spec`` and the registry."""
        spec.delete(spec.body(obj.body))
        self.objects.pop(obj.uid, None)

    def index(self, m: mj.Model, d: mj.Data) -> None:
        """Find every object in a rebuilt model and re-apply its stay weld."""
        self.by_body = {}
        for obj in self.objects.values():
            obj.body_id = mj.name_id(m, "body", obj.body)
            j = mj.name_id(m, "joint", f"{obj.body}/free")
            obj.qpos_adr, obj.dof_adr = int(m.jnt_qposadr[j]), int(m.jnt_dofadr[j])
            obj.stay_eq = mj.name_id(m, "equality", f"{obj.body}/stay")
            obj.geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] == obj.body_id]
            self.by_body[obj.body_id] = obj
            self.hold_in_place(m, d, obj, obj.static and not obj.held)

    def pose_of(self, d: mj.Data, obj: WcObject) -> Array:
        """Where ``obj`` is now (4x4, z-down world)."""
        q = d.qpos[obj.qpos_adr:obj.qpos_adr + 7]
        return transform(matrix_from_quat(q[3:]), q[:3])

    def hold_in_place(self, m: mj.Model, d: mj.Data, obj: WcObject, on: bool) -> None:
        """Weld ``obj`` to the world where it is now (``on``), or let it move (under gravity
        unless a vacuum holds it)."""
        q = d.qpos[obj.qpos_adr:obj.qpos_adr + 7]
        mj.set_weld_pose(m, obj.stay_eq, 0, obj.body_id, q[:3].copy(), q[3:].copy())
        d.eq_active[obj.stay_eq] = on
        m.body_gravcomp[obj.body_id] = 1.0 if on or obj.held else FLOATING

    def set_pose(self, m: mj.Model, d: mj.Data, obj: WcObject, pose: Array) -> None:
        """Teleport ``obj`` to ``pose`` (4x4, z-down world), at rest (AbsMove, RelMove)."""
        d.qpos[obj.qpos_adr:obj.qpos_adr + 3] = pose[:3, 3]
        d.qpos[obj.qpos_adr + 3:obj.qpos_adr + 7] = quat(pose[:3, :3])
        d.qvel[obj.dof_adr:obj.dof_adr + 6] = 0.0
        obj.pose = pose.copy()
        if obj.static and not obj.held:
            self.hold_in_place(m, d, obj, True)

    def extent(self, m: mj.Model, d: mj.Data, obj: WcObject) -> Array:
        """The size (m) of ``obj``'s world-axis bounding box, as UDK's GetSTA measures it."""
        lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
        signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        for g in obj.geoms:
            corners = d.geom_xpos[g] + (signs * m.geom_size[g]) @ d.geom_xmat[g].reshape(3, 3).T
            lo, hi = np.minimum(lo, corners.min(axis=0)), np.maximum(hi, corners.max(axis=0))
        out: Array = hi - lo
        return out

    def owned_by(self, owner: str) -> list[WcObject]:
        """The objects of one WorldController, in creation order."""
        return [o for o in self.objects.values() if o.owner == owner]
