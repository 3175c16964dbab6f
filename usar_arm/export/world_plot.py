"""The top view of a world file: walls and boxes as filled polygons, in metres, REP-103.

World files are in the USARSim frame (x forward, y right, z down); the picture is the map frame
of REP-103 (x, and y to the left: the file's y negated), the frame every drive is recorded in.
Drawn with matplotlib's object API (Figure and the Agg canvas), never pyplot.
"""

from __future__ import annotations

import io
from pathlib import Path

from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Polygon

from usar_arm.core.fileio import write_atomic
from usar_arm.core.world_file import Scenery

WALL = "#5b6770"
LOW = "#b8c2cc"
"""Boxes lower than the P3AT's scanner (0.35 m): the scanner does not see them."""
SCAN_HEIGHT_M = 0.35


def draw_world(ax: Axes, scenery: Scenery) -> None:
    """Draw every box of ``scenery`` on ``ax`` (top view, map frame), axes labelled in m."""
    labels = {WALL: "walls and boxes", LOW: f"boxes below {SCAN_HEIGHT_M} m (unseen by "
                                             "the laser)"}
    for box in scenery.boxes:
        top = -(box.center[2] - box.half[2]) - (-scenery.floor_z)  # height above the floor
        corners = [(x, -y) for x, y in box.corners_xy()]
        color = WALL if top > SCAN_HEIGHT_M else LOW
        ax.add_patch(Polygon(corners, closed=True, facecolor=color, edgecolor="none",
                             zorder=1, label=labels.pop(color, None)))
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, color="0.9", zorder=0)


def save_png(fig: Figure, path: str | Path) -> None:
    """Render ``fig`` to a PNG written atomically at ``path``."""
    buffer = io.BytesIO()
    FigureCanvasAgg(fig).print_png(buffer)
    write_atomic(path, buffer.getvalue())


def render_world(path: str | Path, scenery: Scenery, title: str = "world",
                 size: tuple[int, int] = (1000, 850)) -> None:
    """A PNG of the world's top view at ``path`` (``size`` in pixels)."""
    fig = Figure(figsize=(size[0] / 100, size[1] / 100), dpi=100)
    ax = fig.add_subplot()
    draw_world(ax, scenery)
    ax.set_title(f"{title}: top view (map frame, REP-103)")
    if ax.get_legend_handles_labels()[0]:  # (a world without boxes has nothing to label)
        ax.legend(loc="upper right", fontsize=8, framealpha=0.9)
    fig.tight_layout()
    save_png(fig, path)
