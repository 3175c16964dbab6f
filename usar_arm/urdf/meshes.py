"""Collision meshes from files (STL, OBJ, DAE...) with trimesh: the one module that imports it.

A mesh is read once per (file, scale, hull) and handed on as plain arrays (metres, in the
element's frame, scale applied). With ``convex_hull`` the file's convex hull stands in for the
mesh (the user's choice: fewer triangles, and a solid for FCL instead of a surface)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from usar_arm.core.shapes import Mesh


def load_mesh(path: Path, scale: tuple[float, float, float] = (1.0, 1.0, 1.0),
              convex_hull: bool = False) -> Mesh:
    """The triangles of ``path`` scaled per axis, as a :class:`~usar_arm.core.shapes.Mesh`.

    Raises:
        ValueError: the file holds no triangles or cannot be parsed (the message says why).
    """
    try:
        loaded = trimesh.load(str(path), force="mesh")
    except Exception as exc:  # trimesh raises many types for unreadable files
        raise ValueError(f"cannot read it ({type(exc).__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise ValueError("it holds no triangles")
    vertices = np.asarray(loaded.vertices, dtype=float) * np.asarray(scale, dtype=float)
    faces = np.asarray(loaded.faces, dtype=np.int64)
    if convex_hull:
        hull = trimesh.Trimesh(vertices, faces, process=False).convex_hull
        vertices, faces = np.asarray(hull.vertices, float), np.asarray(hull.faces, np.int64)
    vertices.setflags(write=False)
    faces.setflags(write=False)
    return Mesh(vertices, faces, str(path), convex_hull)  # type: ignore[arg-type]


def cylinder_mesh(radius: float, length: float, sections: int = 32) -> tuple[np.ndarray,
                                                                            np.ndarray]:
    """Vertices (m) and faces of a closed cylinder along z, centred at the origin (for
    pictures and viewers)."""
    mesh = trimesh.creation.cylinder(radius=radius, height=length, sections=sections)
    return np.asarray(mesh.vertices, float), np.asarray(mesh.faces, np.int64)
