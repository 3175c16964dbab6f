"""Slice pictures of a reachability map: the index (colour) on a plane, with the scene's
obstacles and the arm at its zero configuration outlined.

Obstacles the slice cuts are drawn solid, the others dashed (their outline projected on the
plane). Their names, and those of a placement's targets, are placed where no two overlap:
objects at the same place share one label (``leg_front_left/right``), and a label moves to the
nearest free spot around its object, with a leader line when it had to move far.

Takes plain arrays (the map's index, origin and resolution), so it does not depend on the
workspace layer. Drawn with matplotlib's object API (never pyplot).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import Bbox
from numpy.typing import NDArray

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.model import JointType, KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Sphere

PLANES = {"xz": (0, 2, 1), "xy": (0, 1, 2), "yz": (1, 2, 0)}
"""Plane -> (horizontal axis, vertical axis, the axis the slice is taken across)."""
AXIS_NAMES = "xyz"
OBSTACLE = "#d62728"
LABEL_BOX = {"boxstyle": "round,pad=0.15", "fc": "white", "alpha": 0.75, "lw": 0}
"""A label's background, so it reads on any colour of the map."""
LABEL_OFFSETS = [(dx * r, dy * r) for r in (4, 12, 22, 34)
                 for dx, dy in ((0, 1), (1, 0), (0, -1.6), (-1, 0), (1, 1), (-1, 1), (1, -1.6),
                                (-1, -1.6))]
"""Where a label may go, in points from its anchor: near first, then farther around it."""


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


def join_names(names: Sequence[str]) -> str:
    """Names of objects at one place as one label: ``leg_front_left`` and ``leg_front_right``
    give ``leg_front_left/right``; unrelated names are joined by commas."""
    if len(names) == 1:
        return names[0]
    words = [n.split("_") for n in names]
    common = 0
    while all(len(w) > common + 1 and w[common] == words[0][common] for w in words):
        common += 1
    if common == 0:
        return ", ".join(names)
    return "_".join(words[0][:common]) + "_" + "/".join("_".join(w[common:]) for w in words)


def place_labels(ax: Axes, anchors: Sequence[tuple[str, float, float]], color: str,
                 fontsize: float = 7.0, merge_points: float = 4.0,
                 clear_points: float = 0.0) -> list[str]:
    """Write each name near its anchor (data coordinates) so that no two labels overlap and
    none leaves the axes; names whose anchors lie within ``merge_points`` points of each other
    share a label, and none is placed closer than ``clear_points`` to its anchor (to leave a
    marker visible). Returns the labels that found no free spot (not drawn)."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    to_points = 72.0 / fig.dpi
    groups: list[tuple[list[str], Any]] = []
    for name, x, y in anchors:
        at = ax.transData.transform((x, y))
        for names, where in groups:
            if np.hypot(*(at - where)) * to_points <= merge_points:
                names.append(name)
                break
        else:
            groups.append(([name], at))
    frame = ax.get_window_extent(renderer)
    taken: list[Bbox] = []
    left_out: list[str] = []
    for names, where in groups:
        ax_, ay_ = ax.transData.inverted().transform(where)
        anchor = (float(ax_), float(ay_))
        label = join_names(names)
        for dx, dy in LABEL_OFFSETS:
            if max(abs(dx), abs(dy)) < clear_points:
                continue
            text = ax.annotate(label, anchor, xytext=(dx, dy), textcoords="offset points",
                               color=color, fontsize=fontsize, ha="center", va="center",
                               bbox=LABEL_BOX)
            box = text.get_window_extent(renderer).expanded(1.08, 1.15)
            if frame.contains(box.x0, box.y0) and frame.contains(box.x1, box.y1) and \
                    not any(box.overlaps(b) for b in taken):
                if abs(dx) + abs(dy) > 20:  # far from its object: a leader line
                    text.remove()
                    text = ax.annotate(label, anchor, xytext=(dx, dy),
                                       textcoords="offset points", color=color,
                                       fontsize=fontsize, ha="center", va="center",
                                       bbox=LABEL_BOX,
                                       arrowprops={"arrowstyle": "-", "color": color,
                                                   "lw": 0.6})
                taken.append(box)
                break
            text.remove()
        else:
            left_out.append(label)
    return left_out


def shoulder(chain: KinematicChain) -> tuple[str, float]:
    """The shoulder: the first revolute joint whose axis is horizontal at the zero
    configuration (a KR60's A2), with the height (m, base_link z) of its origin, where an arm
    usually reaches farthest; the first revolute joint when none is horizontal."""
    revolute = [(jt, frame) for jt, frame in chain.joint_frames([0.0] * chain.dof)
                if jt.type == JointType.REVOLUTE]
    if not revolute:
        return chain.root, 0.0
    for jt, frame in revolute:
        axis = frame[:3, :3] @ np.asarray(jt.axis, float)
        if abs(axis[2]) < 0.5 * np.linalg.norm(axis):
            return jt.name, float(frame[2, 3])
    return revolute[0][0].name, float(revolute[0][1][2, 3])


def slice_layer(shape: Sequence[int], origin: Array, resolution: float, plane: str,
                at: float) -> tuple[int, float]:
    """The voxel layer across ``plane`` nearest ``at`` (m) and its level (m)."""
    if plane not in PLANES:
        raise InvalidInputError(f"a slice plane is one of {', '.join(PLANES)}, got '{plane}'")
    across = PLANES[plane][2]
    layer = int(np.clip(round((at - origin[across]) / resolution), 0, shape[across] - 1))
    return layer, float(origin[across] + layer * resolution)


def reach_slice_png(index: NDArray[np.floating[Any]], origin: Array, resolution: float, plane: str,
                    chain: KinematicChain, scene: Scene | None = None, at: float = 0.0,
                    title: str = "") -> bytes:
    """A PNG of the map's index on ``plane`` (``xz``, ``xy`` or ``yz``) at the voxel layer
    nearest ``at`` (m) across it.

    Args:
        index: (nx, ny, nz) reachability index in [0, 1]. origin: (3,) m, centre of voxel
            (0, 0, 0). resolution: m.
        chain: the arm, drawn at its zero configuration. scene: obstacles, outlined.
        title: the first line of the title (default: the arm's name and "reachability").
    """
    layer, level = slice_layer(index.shape, origin, resolution, plane, at)
    h, v, across = PLANES[plane]
    picture = np.take(index, layer, axis=across)
    if h > v:
        picture = picture.T
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
    if not np.any(picture > 0):
        ax.text(0.5, 0.1, "no voxel of this layer is reached", transform=ax.transAxes,
                ha="center", fontsize=9, color="0.3")
    fig.colorbar(image, ax=ax, shrink=0.85,
                 label="reachability index (fraction of orientations reached)")
    poses = chain.link_poses([0.0] * chain.dof)
    joints = np.vstack([np.zeros(3), [poses[j.child][:3, 3] for j in chain.joints]])
    ax.plot(joints[:, h], joints[:, v], color="black", lw=2.0, marker="o", ms=3,
            label=f"{chain.name} at zero")
    ax.set_xlabel(f"{AXIS_NAMES[h]} (m, base_link)")
    ax.set_ylabel(f"{AXIS_NAMES[v]} (m, base_link)")
    ax.set_aspect("equal")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    objects = list(scene.objects) if scene is not None else []
    anchors = _draw_obstacles(ax, objects, h, v, across, level, resolution)
    handles = ax.get_legend_handles_labels()[0]
    if objects:
        handles += [Line2D([], [], color=OBSTACLE, lw=1.2, label="obstacle the slice cuts"),
                    Line2D([], [], color=OBSTACLE, lw=1.0, ls="--",
                           label="obstacle off the slice (projected)")]
    ax.legend(handles=handles, loc="upper right", fontsize=7)
    heading = title or f"{chain.name} reachability"
    ax.set_title(f"{heading}\n{plane} slice at {AXIS_NAMES[across]} = {level:.3f} m, "
                 f"{resolution * 100:g} cm voxels", fontsize=10)
    left_out = place_labels(ax, anchors, OBSTACLE)
    if left_out:
        fig.text(0.02, 0.02, "not labelled: " + ", ".join(left_out), fontsize=7,
                 color=OBSTACLE)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()


def _draw_obstacles(ax: Axes, objects: list[SceneObject], h: int, v: int, across: int,
                    level: float, resolution: float) -> list[tuple[str, float, float]]:
    """Outline each object (solid where the slice's voxel layer cuts it, and shaded when it is
    small enough not to hide the map); the anchors of their labels: an outline's centre, or,
    for one that spans most of the picture (a floor), the lower left corner of its visible
    part."""
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    span = max(x1 - x0, y1 - y0)
    anchors = []
    for obj in objects:
        corners = _corners(obj)
        ring = _hull(corners[:, [h, v]])
        low, high = corners[:, across].min(), corners[:, across].max()
        cut = low - resolution / 2 <= level <= high + resolution / 2
        big = np.ptp(ring, axis=0).max() > 0.5 * span
        ax.plot(ring[:, 0], ring[:, 1], color=OBSTACLE, lw=1.2 if cut else 1.0,
                ls="-" if cut else "--")
        if cut and not big:
            ax.fill(ring[:, 0], ring[:, 1], color=OBSTACLE, alpha=0.12, lw=0)
        if big:
            point = (max(ring[:, 0].min(), x0), max(ring[:, 1].min(), y0))
        else:
            point = tuple(ring[:-1].mean(axis=0))
        anchors.append((obj.name, float(point[0]), float(point[1])))
    return anchors
