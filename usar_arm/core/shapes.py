"""Geometric primitives shared by a robot's collision elements and a scene's obstacles (numpy
only): boxes, cylinders, spheres, capsules and triangle meshes, each in its own frame (m)."""

from __future__ import annotations

from dataclasses import dataclass

from usar_arm.core.spatial import Array


@dataclass(frozen=True)
class Box:
    """A box with edge lengths ``size`` (m), centred on its pose."""

    size: tuple[float, float, float]


@dataclass(frozen=True)
class CylinderShape:
    """A cylinder along its pose's z axis, centred there; radius and length in m."""

    radius: float
    length: float


@dataclass(frozen=True)
class Sphere:
    """A sphere of ``radius`` m centred on its pose."""

    radius: float


@dataclass(frozen=True)
class Capsule:
    """A capsule along its pose's z axis, centred there: a cylinder of ``radius`` and
    ``length`` (m, between the centres of its two hemispherical caps) with those caps."""

    radius: float
    length: float


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh: vertices (m, in the object's frame) and faces (vertex indices).

    Attributes:
        source: the file it came from (for messages). convex_hull: True when this is the
            convex hull standing in for the file's (possibly concave) mesh.
    """

    vertices: Array
    faces: Array
    source: str = ""
    convex_hull: bool = False


ObstacleShape = Box | CylinderShape | Sphere | Mesh
"""What a scene's obstacles may be."""
Shape = Box | CylinderShape | Sphere | Capsule | Mesh
"""What a robot's collision elements may be."""
