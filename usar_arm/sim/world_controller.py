"""The WorldController: a connection that INITs as ``USARBotAPI.WorldController`` has no robot
and creates, moves and destroys objects with CONTROL (``WorldController.uc``,
``BotConnection.uc ProcessWorldController``, ``WCObject.uc``).

UDK's rules, reproduced: CONTROL's Type is compared exactly (``Create``, not ``create``); every
vector goes through ``Utilities.ParseVector`` (:func:`parse_vector`: a missing component reads
0, so ``5`` is (0, 0, 5), a word reads 0), and a malformed one is logged here (UDK says
nothing); an unqualified class means ``USARPhysObj.<name>`` (logged); an unknown class, a
duplicate name (compared without regard to case) and an object that would spawn inside existing
geometry are refused and logged, the connection kept; only Physics ``RigidBody``, ``Falling``
and ``Ground`` move, anything else (absent included) is static; Kill and AbsMove find an object
by name without regard to case, GetSTA's name filter is exact, its class filter is an
unqualified class or superclass name; KillAll's box is compared in Unreal units, whose z is the
wire's negated; permanent objects survive KillAll; when the WorldController's connection closes
(``cleanOnClose=true`` in DefaultUSAR.ini) it KillAlls: every non-permanent object in the world
goes, other WorldControllers' included. Nothing but GetSTA is ever answered.
"""

from __future__ import annotations

import logging
import math
import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from usar_arm.core.spatial import Array, matrix_to_rpy, rpy_to_matrix, transform
from usar_arm.core.wc_classes import PACKAGE, find_class
from usar_arm.sim.physics import PhysicsWorld
from usar_arm.sim.world_objects import WcObject
from usar_arm.sim.world_spec import WorldSpec
from usar_arm.usarsim import messages as m

log = logging.getLogger("usar_arm.sim")

CLASS_NAME = "USARBotAPI.WorldController"
"""INIT's ClassName that makes a connection a WorldController (matched without regard to
case, as Unreal's class lookup)."""
SPAWN_OVERLAP = 0.001
"""Deepest overlap (m) with existing geometry a new object may have (UDK's Spawn refuses an
actor that encroaches; resting on a surface is a touch, not an overlap)."""
ALL_CLASSES = ("wcobject", "kactor", "dynamicsmactor", "actor", "object")
"""Class names every WorldController object is (``isA``)."""
_NUMBER = re.compile(r"\s*[-+]?(\d+\.?\d*([eE][-+]?\d+)?|\.\d+([eE][-+]?\d+)?)")

Log = Callable[..., None]
FindRobot = Callable[[str], str | None]


def udk_float(text: str) -> tuple[float, bool]:
    """UnrealScript's ``float(string)`` (C's ``atof``): the leading number of the text, 0 when
    there is none; and whether the whole text was that number."""
    match = _NUMBER.match(text)
    if match is None:
        return 0.0, text.strip() == ""
    value = float(match.group(0))
    clean = match.end() == len(text.rstrip()) and math.isfinite(value)
    return (value if math.isfinite(value) else 0.0), clean


def parse_vector(text: str | None) -> tuple[tuple[float, float, float], bool]:
    """``Utilities.ParseVector``: x before the first comma, y before the next, z the rest;
    a missing comma leaves that component 0 (``"5"`` is (0, 0, 5), ``"1,2"`` is (1, 0, 2)).
    Returns the vector and whether the text was a well-formed ``x,y,z``."""
    if not text:
        return (0.0, 0.0, 0.0), text is None or text == ""
    parts = text.split(",")
    i = text.find(",")
    x, ok_x = udk_float(text[:i]) if i >= 0 else (0.0, False)
    rest = text[i + 1:] if i >= 0 else text
    j = rest.find(",")
    y, ok_y = udk_float(rest[:j]) if j >= 0 else (0.0, False)
    z, ok_z = udk_float(rest[j + 1:] if j >= 0 else rest)
    return (x, y, z), len(parts) == 3 and ok_x and ok_y and ok_z


@dataclass
class WorldController:
    """One WorldController connection: its key, name, and the spawn pose INIT gave it."""

    key: str
    name: str
    log_refusal: Log

    def vector(self, field: str, text: str | None) -> tuple[float, float, float]:
        """A vector field, as UDK reads it; a malformed one is logged."""
        vec, ok = parse_vector(text)
        if not ok:
            self.log_refusal("malformed vector", "CONTROL {%s %s} is not x,y,z; UDK reads it "
                             "as %s", field, (text or "")[:60], ",".join(f"{v:g}" for v in vec))
        return vec

    # ------------------------------------------------------------------ commands
    def handle(self, msg: m.Control, world: PhysicsWorld, world_spec: WorldSpec,
               find_robot: FindRobot) -> m.WcStatus | None:
        """Act on one CONTROL; the GetSTA reply, or None (nothing else is answered)."""
        name = msg.name or ""
        if msg.type == "Create":
            self._create(msg, world, world_spec)
        elif msg.type == "Kill":
            obj = self.find(world, name)
            if obj is None:
                log.info("WorldController: Object '%s' not found", name[:80])
            else:
                world.remove_object(obj)
        elif msg.type == "KillAll":
            self._kill_all(msg, world)
        elif msg.type in ("AbsMove", "RelMove"):
            self._move(msg, world, find_robot)
        elif msg.type == "GetSTA":
            return self.get_sta(world, msg.class_name or "", name)
        elif msg.type in ("Rotate", "AddWP", "ClearWP", "SetWP", "Conveyor"):
            self.log_refusal("not simulated", "CONTROL {Type %s} is not simulated; ignored",
                             msg.type)
        else:
            self.log_refusal("unsupported", "BotConnection: Unsupported world controller "
                             "command %s", msg.type[:40])
        return None

    def find(self, world: PhysicsWorld, name: str) -> WcObject | None:
        """``GetObjectByName``: this controller's object called ``name`` (any case)."""
        return next((o for o in world.objects.owned_by(self.key)
                     if o.name.upper() == name.upper()), None)

    def _create(self, msg: m.Control, world: PhysicsWorld, world_spec: WorldSpec) -> None:
        name = msg.name or ""
        start = world_spec.find_start(msg.start) if msg.start else None
        if start is not None:
            loc, rot = start.location, start.rotation
        else:
            loc, rot = self.vector("Location", msg.location), self.vector("Rotation", msg.rotation)
        scale = self.vector("Scale", msg.scale) if msg.scale is not None else (0.0, 0.0, 0.0)
        if scale == (0.0, 0.0, 0.0):
            scale = (1.0, 1.0, 1.0)
        if self.find(world, name) is not None:
            self.log_refusal("duplicate name", "WorldController: Object named '%s' already "
                             "exists", name[:80])
            return
        class_name = msg.class_name or ""
        if "." not in class_name:
            class_name = f"{PACKAGE}.{class_name}"
            log.info("WorldController: Object not fully qualified, assuming %s", class_name)
        cls = find_class(class_name)
        if cls is None:
            self.log_refusal("unknown class", "WorldController: Invalid class name %s",
                             class_name[:80])
            return
        if min(abs(s) for s in scale) <= 0:
            self.log_refusal("bad scale", "WorldController: Scale %s has a zero or negative "
                             "axis; the object is not created", scale)
            return
        obj = WcObject(world.objects.new_uid(), name, self.key, cls,
                       tuple(abs(s) for s in scale), msg.physics or "",  # type: ignore[arg-type]
                       (msg.permanent or "").upper() == "TRUE", msg.memory or "",
                       msg.material or "", transform(rpy_to_matrix(rot), loc))
        world.add_object(obj)
        depth = world.penetration(obj)
        if depth > SPAWN_OVERLAP:
            world.remove_object(obj)
            self.log_refusal("inside geometry", "WorldController: Cannot spawn object (is it "
                             "inside existing geometry?) '%s' would overlap %.3f m", name[:80],
                             depth)
            return
        if obj.static:
            log.info("WorldController: '%s' (%s) is static: Physics '%s' is not RigidBody, "
                     "Falling or Ground", name[:80], cls.name, obj.physics[:40])

    def _kill_all(self, msg: m.Control, world: PhysicsWorld) -> None:
        if not msg.min_pos or not msg.max_pos:
            low = high = np.zeros(3)
        else:  # in Unreal units, whose z is the wire's negated
            low = np.array(self.vector("MinPos", msg.min_pos)) * (1, 1, -1)
            high = np.array(self.vector("MaxPos", msg.max_pos)) * (1, 1, -1)
        everything = bool(np.array_equal(low, high))
        with world.batch():
            for obj in world.objects.owned_by(self.key):
                at = world.object_pose(obj)[:3, 3] * (1, 1, -1)
                inside = everything or bool(np.all(at > low) and np.all(at < high))
                if inside and not obj.permanent:
                    world.remove_object(obj)
            if everything:  # and every other controller's (or orphan's) but the permanent
                for obj in list(world.objects.objects.values()):
                    if not obj.permanent:
                        world.remove_object(obj)

    def _move(self, msg: m.Control, world: PhysicsWorld, find_robot: FindRobot) -> None:
        name = msg.name or ""
        loc = np.array(self.vector("Location", msg.location))
        rot = self.vector("Rotation", msg.rotation)
        obj = self.find(world, name)
        robot = find_robot(name) if obj is None else None
        if obj is None and robot is None:
            log.info("WorldController: No object named %s", name[:80])
            return
        if obj is not None:
            pose = transform(rpy_to_matrix(rot), loc)
            if msg.type == "RelMove":
                now = world.object_pose(obj)
                pose = transform(rpy_to_matrix(np.add(matrix_to_rpy(now[:3, :3]), rot)),
                                 now[:3, 3] + loc)
            world.move_object(obj, pose)
            return
        assert robot is not None
        now = world.platform_pose(robot)
        if msg.type == "RelMove":
            loc = now[:3, 3] + loc
            rot = tuple(np.add(matrix_to_rpy(now[:3, :3]), rot))
        world.move_platform(robot, loc.tolist(), rot)

    # ------------------------------------------------------------------ status
    def get_sta(self, world: PhysicsWorld, class_name: str, name: str) -> m.WcStatus:
        """``GetSTA``: this controller's objects, filtered by class (``isA``: an unqualified
        class or superclass name, any case) and by name (exactly)."""
        out = []
        for obj in world.objects.owned_by(self.key):
            if class_name and class_name.lower() not in (obj.wc_class.name.lower(),
                                                         *ALL_CLASSES):
                continue
            if name and name != obj.name:
                continue
            pose = world.object_pose(obj)
            size = world.object_extent(obj)
            out.append(m.WcObjectStatus(obj.name, _vec(size), _vec(pose[:3, 3]), obj.memory,
                                        matrix_to_rpy(pose[:3, :3])))
        return m.WcStatus(tuple(out))

    def close(self, world: PhysicsWorld) -> None:
        """The connection closed: ``cleanOnClose`` KillAll (every non-permanent object)."""
        self._kill_all(m.Control("KillAll"), world)


def _vec(v: Array) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))
