"""The part of :class:`~usar_arm.arm.facade.Arm` that attaches and detaches what it carries
(:class:`Carrier`); the book of what is carried is :class:`~usar_arm.planning.carry_book.
CarryBook`."""

from __future__ import annotations

from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from usar_arm.control.motion import MotionPlan
from usar_arm.core.shapes import ObstacleShape
from usar_arm.core.spatial import Array
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.carry_book import CarryBook
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Scene, SceneObject
from usar_arm.usarsim.client import UsarClient


class Carrier:
    """What :class:`~usar_arm.arm.facade.Arm` does with what it carries (a part of it, kept
    here: ``attach``, ``detach``, ``attached``, ``planning_robot``)."""

    robot: Robot
    client: UsarClient | None
    _carry: CarryBook
    _scenes: dict[str, tuple[Scene, CollisionWorld]]

    if TYPE_CHECKING:  # (the Arm's own)
        def joints(self, timeout: float = 2.0, newer_than: float | None = None) -> Array:
            """Current joint values."""

        @property
        def home(self) -> Array:
            """The home configuration."""

    @property
    def attached(self) -> tuple[AttachedBody, ...]:
        """The bodies the arm carries, in attachment order."""
        return self._carry.bodies

    @property
    def planning_robot(self) -> Robot:
        """The robot plans, IK and worlds use: the arm carrying :attr:`attached`."""
        return self.robot.carrying(self._carry.bodies)

    def _here(self, q: Array | None) -> Array:
        """``q``, or the live joints when connected, or home offline (rad/m)."""
        if q is not None:
            return np.asarray(q, float)
        return self.joints() if self.client is not None else self.home

    def attach(self, name: str, link: str = "tool0", *, scene: Scene | None = None,
               shape: ObstacleShape | None = None, pose: Array | None = None,
               touch_links: tuple[str, ...] | list[str] = (), q: Array | None = None
               ) -> AttachedBody:
        """Fix an object to ``link``: from now on it moves with it in every plan, IK and
        world of this arm, and is no obstacle of any scene.

        Args:
            name: a scene object's name (its shape and its pose relative to ``link`` at ``q``
                are taken), or a new object's (give ``shape`` and ``pose``).
            link: the link it is fixed to (``KR60gripper_tcp``).
            scene: the Scene the object is in (without it: the objects this arm released).
            shape: a new object's geometry (m). pose: its 4x4 pose in ``link``'s frame.
            touch_links: links it may touch (the gripper holding it).
            q: the configuration it is attached at (default: the live joints, or home).

        Raises:
            AttachError: unknown link or object, name clash, a shape without its pose.
            AttachedCollisionError: it is in collision at ``q`` with something but its parent
                and touch links (resting on a support is allowed, see :mod:`.carry`).
        """
        body = self._carry.attach(self.planning_robot, name, link, self._here(q), scene, shape,
                                  pose, tuple(touch_links))
        self._scenes.clear()
        return body

    def detach(self, name: str, q: Array | None = None) -> SceneObject:
        """Release a carried object at ``q`` (default: the live joints, or home): it becomes an
        obstacle again where it was put, in every later scene of this arm; returns it."""
        placed = self._carry.detach(self.planning_robot, name, self._here(q))
        self._scenes.clear()
        return placed

    def _carried_world(self, world: CollisionWorld, start: Array) -> CollisionWorld:
        """The world a plan from ``start`` is checked in (supports allowed for the lift)."""
        return self._carry.lift_off(self.planning_robot, world, start)

    def _recorded(self, plan: MotionPlan) -> MotionPlan:
        """``plan`` with its trajectory's ``info['attached']`` naming what was carried."""
        if not self._carry.bodies:
            return plan
        info = {**plan.trajectory.info,
                "attached": [{"name": b.name, "link": b.link} for b in self._carry.bodies]}
        return replace(plan, trajectory=replace(plan.trajectory, info=info))
