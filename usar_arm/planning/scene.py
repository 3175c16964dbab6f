"""Obstacle scenes: boxes, cylinders, spheres and triangle meshes, each with a name and a pose in
base_link. Loaded from YAML (see :mod:`usar_arm.planning.scene_file`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usar_arm.core.shapes import Box, Capsule, CylinderShape, Mesh, Sphere
from usar_arm.core.shapes import ObstacleShape as Shape
from usar_arm.core.spatial import Array

__all__ = ["EMPTY", "Box", "Capsule", "CylinderShape", "Mesh", "Scene", "SceneObject", "Shape",
           "Sphere"]


@dataclass(frozen=True, eq=False)
class SceneObject:
    """An obstacle.

    Attributes:
        name: unique name. shape: its geometry. pose: 4x4 pose in base_link.
        allow: robot links allowed to touch it (e.g. the base standing on a plinth).
    """

    name: str
    shape: Shape
    pose: Array
    allow: tuple[str, ...] = ()

    def bounding_radius(self) -> float:
        """Radius (m) of a sphere around the pose that contains the whole object."""
        s = self.shape
        if isinstance(s, Box):
            return float(np.linalg.norm(s.size) / 2)
        if isinstance(s, CylinderShape):
            return float(np.hypot(s.radius, s.length / 2))
        if isinstance(s, Sphere):
            return float(s.radius)
        return float(np.linalg.norm(s.vertices, axis=1).max())


@dataclass(frozen=True, eq=False)
class Scene:
    """A named set of obstacles (may be empty)."""

    name: str
    objects: tuple[SceneObject, ...] = field(default_factory=tuple)

    def object(self, name: str) -> SceneObject:
        """The object called ``name`` (KeyError lists the names)."""
        for o in self.objects:
            if o.name == name:
                return o
        raise KeyError(f"no object '{name}' in scene '{self.name}'; objects: "
                       f"{', '.join(o.name for o in self.objects)}")


EMPTY = Scene("empty")
