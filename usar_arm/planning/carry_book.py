"""What an arm carries: :class:`CarryBook`, the attached bodies and where the released ones
were put (``Arm.attach``/``detach`` keep one; so does a batch problem with an ``attach``).

Attaching a scene object takes its shape and its pose relative to the link at the
configuration it is attached at (the grasp), and from then on the object is no obstacle in any
scene the arm plans in: it moves with the link. Releasing it puts it back as an obstacle where
it was put (the link's pose there @ the grasp), in every later scene of the arm, in place of a
scene's object of that name.

An object picked up from where it rests (a part on a table) touches its support when it is
attached. The objects it touches no deeper than :data:`SUPPORT_DEPTH` are its supports: a plan
that starts with it resting on them (the lift) may touch them; the first plan that starts with
it clear of them ends that allowance (MoveIt's pick allows the support surface the same way
during the retreat). Deeper contacts, and any contact with a robot link other than its parent
and touch links, refuse the attachment
(:class:`~usar_arm.core.attach_errors.AttachedCollisionError`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usar_arm.core.attach_errors import AttachedCollisionError, AttachError
from usar_arm.core.shapes import ObstacleShape
from usar_arm.core.spatial import Array, invert
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Scene, SceneObject

SUPPORT_DEPTH = 0.002
"""m: a scene object an object to attach touches no deeper than this is what it rests on (a
physics engine leaves a resting body sunk into its support by a fraction of a millimetre)."""


@dataclass
class CarryBook:
    """The bodies an arm carries (in attachment order), the objects it released (name ->
    where it put them), and the supports each carried body still rests on.

    Attributes:
        bodies: the carried bodies. released: the released objects, as obstacles (base_link).
        supports: body name -> the scene objects it may touch until a plan starts clear of
            them.
    """

    bodies: tuple[AttachedBody, ...] = ()
    released: dict[str, SceneObject] = field(default_factory=dict)
    supports: dict[str, tuple[str, ...]] = field(default_factory=dict)
    _allow: dict[str, tuple[str, ...]] = field(default_factory=dict)
    """body name -> the links its scene object allowed (given back on release)."""

    @property
    def names(self) -> tuple[str, ...]:
        """The carried bodies' names."""
        return tuple(b.name for b in self.bodies)

    def view(self, scene: Scene) -> Scene:
        """``scene`` as the arm sees it now: without the carried objects, with the released
        ones where they were put (replacing the scene's objects of their names)."""
        carried = set(self.names)
        objects = [self.released.get(o.name, o) for o in scene.objects
                   if o.name not in carried]
        present = {o.name for o in objects}
        objects += [o for n, o in self.released.items() if n not in present and n not in carried]
        return Scene(scene.name, tuple(objects))

    def with_supports(self, scene: Scene) -> Scene:
        """``scene`` with each support allowing the body resting on it."""
        allow: dict[str, list[str]] = {}
        for body, objects in self.supports.items():
            for o in objects:
                allow.setdefault(o, []).append(body)
        return Scene(scene.name, tuple(
            SceneObject(o.name, o.shape, o.pose, (*o.allow, *allow[o.name]))
            if o.name in allow else o for o in scene.objects))

    def lift_off(self, robot: Robot, world: CollisionWorld, q: Array) -> CollisionWorld:
        """The world a plan from ``q`` is checked in: ``world`` when the carried bodies are
        clear of their supports at ``q`` (the allowance ends), the world with the supports
        allowed when the bodies rest on them and touch nothing else."""
        if not self.supports:
            return world
        found = world.contacts(q)
        resting = {(b, o) for b, objects in self.supports.items() for o in objects}
        touching = {p for p in found if p in resting or p[::-1] in resting}
        if not touching:
            self.supports.clear()
            return world
        if len(touching) < len(found):
            return world  # (in collision with more than its support: the plan says so)
        return robot.collision_world(self.with_supports(world.scene), world.padding)

    # ------------------------------------------------------------------ attach, detach
    def attach(self, robot: Robot, name: str, link: str, q: Array, scene: Scene | None,
               shape: ObstacleShape | None, pose: Array | None,
               touch_links: tuple[str, ...]) -> AttachedBody:
        """Attach ``name`` to ``link`` at ``q`` and return the body (``robot``: the arm
        carrying what the book holds). A scene object's shape and pose are taken from
        ``scene`` (or from where the arm released it) unless ``shape`` is given, which
        needs ``pose`` (in the link frame).

        Raises:
            AttachError: already carried, no such object, a shape without a pose, an unknown
                link or a name clash. AttachedCollisionError: see the module.
        """
        if name in self.names:
            raise AttachError(name, "it is carried already (detach it first)", self.names)
        links = [lk.name for lk in robot.chain.links]
        if link not in links:
            raise AttachError(name, f"no link '{link}' to attach it to", links)
        seen = self.view(scene) if scene is not None else Scene("released",
                                                                tuple(self.released.values()))
        link_pose = robot.kinematics.frame_pose(q, link)
        allow: tuple[str, ...] = ()
        if shape is not None:
            if pose is None:
                raise AttachError(name, "a new shape needs its pose in the link's frame")
            grasp = np.asarray(pose, float)
        else:
            obj = next((o for o in seen.objects if o.name == name), None)
            if obj is None:
                where = f"scene '{scene.name}'" if scene is not None else "what it released"
                raise AttachError(name, f"no object of that name in {where} (give a shape and "
                                        "a pose to attach a new one)",
                                  [o.name for o in seen.objects])
            shape, grasp, allow = obj.shape, invert(link_pose) @ obj.pose, obj.allow
        valid = set(links)
        body = AttachedBody(name, link, shape, grasp,
                            tuple(dict.fromkeys((*touch_links,
                                                 *(a for a in allow if a in valid)))))
        rest = Scene(seen.name, tuple(o for o in seen.objects if o.name != name))
        supports = self._check(robot, body, q, rest)
        self.bodies = (*self.bodies, body)
        self.released.pop(name, None)
        self._allow[name] = allow
        if supports:
            self.supports[name] = supports
        return body

    def _check(self, robot: Robot, body: AttachedBody, q: Array, scene: Scene
               ) -> tuple[str, ...]:
        """The supports of ``body`` at ``q`` in ``scene``; raises AttachedCollisionError for
        any other contact."""
        try:
            robot.check_attachable(body, q, scene)
        except AttachedCollisionError as exc:
            objects = {o.name for o in scene.objects}
            shallow = [c for c in exc.contacts if c[1] in objects and c[2] <= SUPPORT_DEPTH]
            if len(shallow) < len(exc.contacts):
                raise AttachedCollisionError(body.name, [c for c in exc.contacts
                                                         if c not in shallow]) from None
            return tuple(c[1] for c in shallow)
        return ()

    def detach(self, robot: Robot, name: str, q: Array) -> SceneObject:
        """Release ``name`` at ``q`` (``robot``: the arm carrying what the book holds): it is
        an obstacle again, at the link's pose at ``q`` @ its grasp.

        Raises:
            AttachError: nothing carried by that name.
        """
        body = next((b for b in self.bodies if b.name == name), None)
        if body is None:
            raise AttachError(name, "nothing of that name is carried", self.names)
        held = [b.name for b in self.bodies if b.link == name]
        if held:
            raise AttachError(name, f"'{held[0]}' is fixed to it (detach that first)",
                              self.names)
        placed = SceneObject(name, body.shape, robot.kinematics.frame_pose(q, body.link)
                             @ body.pose, self._allow.pop(name, ()))
        self.bodies = tuple(b for b in self.bodies if b.name != name)
        self.supports.pop(name, None)
        self.released[name] = placed
        return placed

