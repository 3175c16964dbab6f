"""Pictures of the arm: link cylinders, scene obstacles, frames and the tool path, as a PNG.

Drawn with matplotlib's object API (:class:`~matplotlib.figure.Figure` and the Agg canvas), never
pyplot: rendering neither changes a user's backend nor leaves figures behind. Lengths are in m
(base_link frame, REP-103 z up); the view angles are matplotlib's ``view_init`` degrees.

Matplotlib sorts 3D polygons by their centroid depth (painter's algorithm), so long faces are
cut into short pieces and everything that may overlap is drawn as one collection. Obstacles far
larger than the arm (a floor) are clipped to the view and drawn first.
"""

from __future__ import annotations

import io
import logging
from collections.abc import Sequence
from pathlib import Path
from typing import cast

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from matplotlib.transforms import Bbox
from mpl_toolkits.mplot3d import Axes3D, proj3d
from mpl_toolkits.mplot3d.art3d import Line3DCollection

from usar_arm.control.trajectory import Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.fileio import write_atomic
from usar_arm.core.model import KinematicChain
from usar_arm.core.shapes import Capsule, CylinderShape
from usar_arm.core.spatial import Array
from usar_arm.export.surfaces import Faces, cylinder, outline, shape_faces
from usar_arm.planning.scene import Scene

log = logging.getLogger("usar_arm.export.render")

DEFAULT_VIEW = (24.0, -58.0)
"""Elevation and azimuth (deg): a 3/4 view from the front right, slightly from above."""
DEFAULT_LINK_COLOR = (0.62, 0.63, 0.66, 1.0)
OBSTACLE_COLOR = (0.55, 0.60, 0.67, 0.28)
OBSTACLE_EDGE = (0.22, 0.25, 0.30, 0.75)
GHOST_ALPHA = 0.22
PATH_COLOR = "#1f4fbf"
AXIS_COLORS = ("#d62728", "#2ca02c", "#1f77b4")


def _index(chain: KinematicChain, names: Sequence[str]) -> Array:
    """Column of each chain joint in a trajectory with joints ``names``."""
    missing = [n for n in chain.joint_names if n not in names]
    if missing:
        raise InvalidInputError(f"the trajectory has no values for joints {', '.join(missing)} "
                                f"(it has {', '.join(names)})")
    return np.array([list(names).index(n) for n in chain.joint_names])


def tool_path(chain: KinematicChain, trajectory: Trajectory, frame: str = "tool0",
              every: int = 1) -> Array:
    """Positions (m, base_link) of ``frame`` (a REP-199 role or a link name) along a trajectory.

    Args:
        every: keep one sample in ``every`` (the last sample is always kept).

    Returns:
        (m, 3) array.
    """
    if every < 1:
        raise InvalidInputError(f"every must be a positive sample count, got {every}")
    link = chain.frames.get(frame, frame)
    links = [lk.name for lk in chain.links]
    if link not in links:
        raise InvalidInputError(f"no frame '{frame}' on {chain.name}; frames: "
                                f"{', '.join(sorted(set(chain.frames) | set(links)))}")
    rows = list(range(0, len(trajectory.t), every))
    if rows[-1] != len(trajectory.t) - 1:
        rows.append(len(trajectory.t) - 1)
    q = trajectory.q[:, _index(chain, trajectory.joint_names)]
    return np.array([chain.link_poses(q[i].tolist())[link][:3, 3] for i in rows])


def _arm_faces(chain: KinematicChain, q: Array, alpha: float | None, faces: Faces) -> None:
    """Add the links' collision elements at ``q`` to ``faces`` (alpha: None = the material's
    own; a capsule is drawn as the cylinder around it)."""
    poses = chain.link_poses(q.tolist())
    for link in chain.links:
        rgba = np.array(link.color or DEFAULT_LINK_COLOR, dtype=float)
        if alpha is not None:
            rgba[3] = alpha
        for element in link.elements:
            s, pose = element.shape, poses[link.name] @ element.origin.matrix()
            if isinstance(s, CylinderShape | Capsule):
                length = s.length + (2 * s.radius if isinstance(s, Capsule) else 0.0)
                faces.add(cylinder(s.radius, length, pose), tuple(rgba))
            else:
                faces.add(shape_faces(s, pose), tuple(rgba))


def _window(points: Array) -> tuple[Array, Array]:
    """The view box around ``points`` (m): padded, no side under half the longest, standing on
    the ground (z = 0) when nothing is below it."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    longest = float(np.max(hi - lo))
    grow = np.maximum(0.5 * longest - (hi - lo), 0.0) / 2 + max(0.06 * longest, 0.05)
    ground = lo[2] >= -1e-9
    lo, hi = lo - grow, hi + grow
    if ground:
        hi[2] -= lo[2]
        lo[2] = 0.0
    return lo, hi


def render_arm(path: str | Path, chain: KinematicChain, q: Array | Sequence[float],
               scene: Scene | None = None, tool_path: Array | None = None, *,
               ghosts: Sequence[Array | Sequence[float]] = (), title: str | None = None,
               size: tuple[int, int] = (1000, 800),
               view: tuple[float, float] = DEFAULT_VIEW) -> Path:
    """Write a PNG picture of the arm at ``q`` (rad or m per joint, chain order).

    Args:
        path: the PNG to write (atomically; parent folders are created).
        chain: the arm; each link's cylinder is drawn in its material colour.
        q: the configuration drawn opaque. ghosts: more configurations, drawn translucent.
        scene: obstacles, drawn translucent grey with outlines.
        tool_path: (m, 3) tool0 positions (m), drawn as a line from a dot (start) to a
            square (end); see :func:`tool_path`.
        title: heading (default: the chain's name). size: width, height (pixels).
        view: elevation, azimuth (deg).

    Returns:
        ``path``.
    """
    width, height = (int(v) for v in size)
    if width < 100 or height < 100:
        raise InvalidInputError(f"picture size must be at least 100 x 100 pixels, got {size}")
    configs = _checked_configs(chain, q, ghosts)
    if tool_path is not None:
        tool_path = np.asarray(tool_path, dtype=float).reshape(-1, 3)

    arm = Faces()
    for g in configs[1:]:
        _arm_faces(chain, g, GHOST_ALPHA, arm)
    _arm_faces(chain, configs[0], None, arm)
    poses = chain.link_poses(configs[0].tolist())
    tool_link = chain.frames.get("tool0", chain.links[-1].name)
    tool = poses[tool_link]
    focus = [arm.points(), np.zeros((1, 3)), tool[:3, 3][None]]
    if tool_path is not None and len(tool_path):
        focus.append(tool_path)
    arm_lo, arm_hi = np.min(np.vstack(focus), axis=0), np.max(np.vstack(focus), axis=0)
    extent = float(np.max(arm_hi - arm_lo))

    near, far, edges, (lo, hi) = _scene_parts(scene, extent, focus)

    fig = Figure(figsize=(width / 100, height / 100), dpi=100)
    FigureCanvasAgg(fig)
    ax = cast(Axes3D, fig.add_axes((0.0, 0.0, 1.0, 0.93), projection="3d"))
    ax.computed_zorder = False
    ax.view_init(elev=view[0], azim=view[1])
    light = _light(view)
    if len(far):
        ax.add_collection3d(far.collection(light, zorder=1), autolim=False)
    if edges:
        ax.add_collection3d(Line3DCollection(edges, colors=[OBSTACLE_EDGE], linewidths=0.8,
                                             zorder=1.5), autolim=False)
    main = near + arm
    ax.add_collection3d(main.collection(light, zorder=2), autolim=False)
    bones = np.array([np.zeros(3), *(poses[j.child][:3, 3] for j in chain.path_to(tool_link))])
    ax.plot(*bones.T, color="0.25", linewidth=1.4, marker="o", markersize=3, zorder=1.8)
    _draw_frames(ax, tool, min(0.12 * float(np.max(hi - lo)), 0.15 * extent))
    if tool_path is not None and len(tool_path):
        _draw_tool_path(ax, tool_path)
    _style_axes(ax, lo, hi, ticks=max(3, min(width, height) // 110))
    top = _header(fig, title if title is not None else chain.name, configs, scene, width, height)
    if tool_path is not None and len(tool_path):
        fig.legend(*ax.get_legend_handles_labels(), loc="upper left", fontsize=8,
                   bbox_to_anchor=(6 / width, top), framealpha=0.85)
    _fit(fig, ax, lo, hi, top)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    log.debug("rendered %s at q=%s (%d faces)", chain.name, configs[0], len(main))
    return write_atomic(path, buf.getvalue())


def _checked_configs(chain: KinematicChain, q: Array | Sequence[float],
                     ghosts: Sequence[Array | Sequence[float]]) -> list[Array]:
    """``q`` then the ghosts as arrays, each of the chain's size."""
    configs = [np.asarray(q, dtype=float), *(np.asarray(g, dtype=float) for g in ghosts)]
    for c in configs:
        if c.shape != (chain.dof,):
            raise InvalidInputError(f"a configuration of {chain.name} needs {chain.dof} values "
                                    f"({', '.join(chain.joint_names)}), got {c.size}")
    return configs


def _scene_parts(scene: Scene | None, extent: float, focus: list[Array]
                 ) -> tuple[Faces, Faces, list[Array], tuple[Array, Array]]:
    """(near obstacles, far ones clipped to the view, outlines of the near ones, the view box)
    for an arm of size ``extent`` (m) whose points of interest are ``focus`` (extended here by
    what the obstacles add)."""
    # Obstacles up to twice the arm's size set the view. Bigger ones (walls, floors) are
    # clipped to the surroundings of the rest; those that reach above the ground widen the view.
    near, far = Faces(), Faces()
    edges: list[Array] = []
    big = []
    for obj in (scene.objects if scene is not None else ()):
        pts = np.vstack(shape_faces(obj.shape, obj.pose, np.inf))
        if float(np.max(pts.max(axis=0) - pts.min(axis=0))) > max(2.0 * extent, 1.0):
            big.append(obj)
            continue
        near.add(shape_faces(obj.shape, obj.pose), OBSTACLE_COLOR)
        edges += outline(obj.shape, obj.pose)
        focus.append(pts)
    every = np.vstack(focus)
    around = every.min(axis=0) - 0.25 * extent, every.max(axis=0) + 0.25 * extent
    for obj in big:
        part = Faces(shape_faces(obj.shape, obj.pose, np.inf), OBSTACLE_COLOR).clipped(*around)
        far += part
        if len(part) and part.points()[:, 2].max() > 0.01:
            focus.append(part.points())
    lo, hi = _window(np.vstack(focus))
    far = far.clipped(lo, hi)
    return near, far, edges, (lo, hi)


def _draw_frames(ax: Axes3D, tool: Array, size: float) -> None:
    """The axes (``size`` m long) and names of base_link and of tool0 (at pose ``tool``)."""
    for name, pose in (("base_link", np.eye(4)), ("tool0", tool)):
        for k, colour in enumerate(AXIS_COLORS):
            ax.plot(*np.array([pose[:3, 3], pose[:3, 3] + size * pose[:3, k]]).T,
                    color=colour, linewidth=2.2, zorder=3, solid_capstyle="round")
        ax.text(*(pose[:3, 3] + 0.35 * size * np.array([1.0, 1.0, -0.6])), name,
                fontsize=9, color="0.15", zorder=4)


def _draw_tool_path(ax: Axes3D, tool_path: Array) -> None:
    """The tool path as a line from a dot (start) to a square (end)."""
    ax.plot(*tool_path.T, color=PATH_COLOR, linewidth=2.0, zorder=3, label="tool0 path")
    ax.plot(*tool_path[0], "o", color=PATH_COLOR, markersize=6, zorder=3, label="start")
    ax.plot(*tool_path[-1], "s", color=PATH_COLOR, markersize=6, zorder=3,
            markerfacecolor="white", markeredgewidth=1.8, label="end")


def _header(fig: Figure, title: str, configs: list[Array], scene: Scene | None, width: int,
            height: int) -> float:
    """Title and a note (configuration, ghosts, scene) wrapped to the width (pixels); returns
    the figure fraction left below them."""
    parts = [f"q = ({', '.join(f'{v:+.2f}' for v in configs[0])}) rad"]
    if len(configs) > 1:
        parts.append(f"{len(configs) - 1} ghost configuration(s)")
    if scene is not None:
        parts.append(f"scene '{scene.name}' ({len(scene.objects)} obstacles)")
    lines = [parts[0]]
    for part in parts[1:]:
        if 7.0 * len(lines[-1] + part) + 60 < width:
            lines[-1] += f"   ·   {part}"
        else:
            lines.append(part)
    fig.text(0.5, 1 - 8 / height, title, ha="center", va="top", fontsize=14)
    fig.text(0.5, 1 - 34 / height, "\n".join(lines), ha="center", va="top", fontsize=9,
             color="0.3", linespacing=1.3)
    return 1 - (40 + 15 * len(lines)) / height


def _light(view: tuple[float, float]) -> Array:
    """A light from over the viewer's left shoulder (unit vector, world frame)."""
    elev, azim = np.radians(view[0] + 30.0), np.radians(view[1] - 35.0)
    return np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])


def _fit(fig: Figure, ax: Axes3D, lo: Array, hi: Array, top: float) -> None:
    """Zoom and move the 3D axes so that the box with its ticks and labels fills the figure
    below ``top`` (figure fraction) without being clipped."""
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1])
                        for z in (lo[2], hi[2])])
    zoom, region = 1.0, Bbox([[0.01, 0.01], [0.99, top]])
    for _ in range(4):
        ax.set_box_aspect(tuple(hi - lo), zoom=zoom)
        renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
        fig.draw_without_rendering()
        x, y, _z = proj3d.proj_transform(*corners.T, ax.get_proj())
        xy = ax.transData.transform(np.column_stack([x, y]))
        boxes = [Bbox.from_extents(*xy.min(axis=0), *xy.max(axis=0))]
        boxes += [a.get_tightbbox(renderer) for a in (ax.xaxis, ax.yaxis, ax.zaxis)]
        used = Bbox.union([b for b in boxes if b is not None]).transformed(
            fig.transFigure.inverted())
        scale = min(region.width / used.width, region.height / used.height)
        dx = region.x0 + region.x1 - used.x0 - used.x1
        dy = region.y0 + region.y1 - used.y0 - used.y1
        pos = ax.get_position()
        ax.set_position((pos.x0 + dx / 2, pos.y0 + dy / 2, pos.width, pos.height))
        if abs(scale - 1.0) < 0.01 and abs(dx) + abs(dy) < 0.01:
            break
        zoom *= scale


def _style_axes(ax: Axes3D, lo: Array, hi: Array, ticks: int) -> None:
    """Equal-aspect limits, light panes with a grid (the ground grid at the bottom), labels."""
    ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]))
    for axis, label in zip((ax.xaxis, ax.yaxis, ax.zaxis), ("x (m)", "y (m)", "z (m)"),
                           strict=True):
        axis.set_pane_color((0.95, 0.95, 0.96, 1.0) if label[0] == "z" else (1, 1, 1, 0))
        axis.label.set_text(label)
        axis.label.set_fontsize(10)
        axis.set_major_locator(MaxNLocator(nbins=ticks, steps=[1, 2, 2.5, 5, 10]))
    ax.tick_params(labelsize=8, pad=0)
