"""Slice pictures of a reachability map: the index (colour) on a plane through the base, with
the scene's obstacles and the arm at its zero configuration outlined.

Takes plain arrays (the map's index, origin and resolution), so it does not depend on the
workspace layer. Drawn with matplotlib's object API (never pyplot).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from numpy.typing import NDArray

from usar_arm.errors import InvalidInputError
from usar_arm.fileio import write_atomic
from usar_arm.model import KinematicChain
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Sphere
from usar_arm.spatial import Array

PLANES = {"xz": (0, 2, 1), "xy": (0, 1, 2), "yz": (1, 2, 0)}
"""Plane -> (horizontal axis, vertical axis, the axis the slice is taken across)."""
AXIS_NAMES = "xyz"


def _corners(obj: SceneObject) -> Array:
    """Points (m, base_link) whose projections outline the object."""
    s = obj.shape
    if isinstance(s, Box):
        half = np.asarray(s.size) / 2
        local = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * half
    elif isinstance(s, CylinderShape):
        a = np.linspace(0, 2 * np.pi, 25)
        ring = np.stack([s.radius * np.cos(a), s.radius * np.sin(a)], axis=1)
        local = np.vstack([np.column_stack([ring, np.full(len(a), h)])
                           for h in (-s.length / 2, s.length / 2)])
    elif isinstance(s, Sphere):
        a = np.linspace(0, 2 * np.pi, 25)
        c, si = np.cos(a) * s.radius, np.sin(a) * s.radius
        z = np.zeros_like(a)
        local = np.vstack([np.column_stack([c, si, z]), np.column_stack([c, z, si]),
                           np.column_stack([z, c, si])])
    else:
        assert isinstance(s, Mesh)
        local = np.asarray(s.vertices, float)
    return np.asarray(local @ obj.pose[:3, :3].T + obj.pose[:3, 3])


def _hull(points: Array) -> Array:
    """The convex hull (closed polygon) of 2-D points (monotone chain)."""
    pts = sorted(set(map(tuple, np.round(points, 9))))
    if len(pts) < 3:
        return np.array(pts + pts[:1])

    def half(seq: list) -> list:
        out: list = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    ring = lower[:-1] + upper[:-1]
    return np.array([*ring, ring[0]])


def outline(obj: SceneObject, h: int, v: int) -> Array:
    """The closed outline (k, 2) of an object projected on the plane of axes ``h``, ``v``."""
    return _hull(_corners(obj)[:, [h, v]])


def plot_reach_slice(path: str | Path, index: NDArray[np.floating[Any]], origin: Array,
                     resolution: float, plane: str, chain: KinematicChain,
                     scene: Scene | None = None, at: float = 0.0, title: str = "") -> Path:
    """Write :func:`reach_slice_png` to ``path`` (atomically)."""
    return write_atomic(path, reach_slice_png(index, origin, resolution, plane, chain, scene,
                                              at, title))


def reach_slice_png(index: NDArray[np.floating[Any]], origin: Array, resolution: float, plane: str,
                    chain: KinematicChain, scene: Scene | None = None, at: float = 0.0,
                    title: str = "") -> bytes:
    """A PNG of the map's index on ``plane`` (``xz``, ``xy`` or ``yz``) at the voxel layer
    nearest ``at`` (m) across it.

    Args:
        index: (nx, ny, nz) reachability index in [0, 1]. origin: (3,) m, centre of voxel
            (0, 0, 0). resolution: m.
        chain: the arm, drawn at its zero configuration. scene: obstacles, outlined.
    """
    if plane not in PLANES:
        raise InvalidInputError(f"a slice plane is one of {', '.join(PLANES)}, got '{plane}'")
    h, v, across = PLANES[plane]
    layer = int(np.clip(round((at - origin[across]) / resolution), 0, index.shape[across] - 1))
    picture = np.take(index, layer, axis=across)
    if h > v:
        picture = picture.T
    level = origin[across] + layer * resolution
    extent = (origin[h] - resolution / 2, origin[h] + (index.shape[h] - 0.5) * resolution,
              origin[v] - resolution / 2, origin[v] + (index.shape[v] - 0.5) * resolution)
    fig = Figure(figsize=(7.5, 6.5), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    cmap = ListedColormap(colormaps["viridis"](np.linspace(0, 1, 256))).with_extremes(
        under="white")
    shown = np.where(picture > 0, picture, -1.0).T  # rows = vertical axis
    image = ax.imshow(shown, origin="lower", extent=extent, cmap=cmap, vmin=1e-6, vmax=1.0,
                      interpolation="nearest")
    fig.colorbar(image, ax=ax, shrink=0.85,
                 label="reachability index (fraction of orientations reached)")
    for obj in (scene.objects if scene is not None else ()):
        ring = outline(obj, h, v)
        ax.plot(ring[:, 0], ring[:, 1], color="#d62728", lw=1.2, ls="--")
        ax.annotate(obj.name, ring[:-1].mean(axis=0), color="#d62728", fontsize=7,
                    ha="center")
    poses = chain.link_poses([0.0] * chain.dof)
    joints = np.array([poses[j.child][:3, 3] for j in chain.joints])
    joints = np.vstack([np.zeros(3), joints])
    ax.plot(joints[:, h], joints[:, v], color="black", lw=2.0, marker="o", ms=3,
            label=f"{chain.name} at zero")
    ax.set_xlabel(f"{AXIS_NAMES[h]} (m, base_link)")
    ax.set_ylabel(f"{AXIS_NAMES[v]} (m, base_link)")
    ax.set_aspect("equal")
    ax.legend(loc="upper right", fontsize=8)
    heading = title or f"{chain.name} reachability"
    ax.set_title(f"{heading}\n{plane} slice at {AXIS_NAMES[across]} = {level:.3f} m, "
                 f"{resolution * 100:g} cm voxels", fontsize=10)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()
