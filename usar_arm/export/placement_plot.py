"""Top view of a placement study: the feasible base positions coloured by their best score
(over the headings), the best base with its heading, the targets and the scene's outlines.
Targets above one another share a label (``pick, pick_above``); no two labels overlap."""

from __future__ import annotations

import io
from collections.abc import Sequence

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from usar_arm.core.spatial import Array
from usar_arm.export.reach_plot import outline, place_labels
from usar_arm.planning.scene import Scene


def placement_png(x: Array, y: Array, yaw: Array, score: Array, best: int, step: float,
                  targets: Sequence[tuple[str, Array]], scene: Scene | None = None,
                  title: str = "") -> bytes:
    """A PNG of the study.

    Args:
        x: (C,) candidate base positions' x (m).
        y: (C,) their y (m).
        yaw: (C,) their headings (rad).
        score: (C,) the worst target's margin
            in [0, 1], negative where some target is unreachable. best: the best candidate's
            index. step: m between positions. targets: (name, 4x4 pose) in the cell.
    """
    ix = np.round(x / step).astype(int)
    iy = np.round(y / step).astype(int)
    x0, y0 = ix.min(), iy.min()
    grid = np.full((ix.max() - x0 + 1, iy.max() - y0 + 1), np.nan)
    for i, j, s in zip(ix - x0, iy - y0, score, strict=True):
        if s >= 0 and not (grid[i, j] >= s):
            grid[i, j] = s
    fig = Figure(figsize=(7.5, 6.5), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    extent = ((x0 - 0.5) * step, (ix.max() + 0.5) * step, (y0 - 0.5) * step,
              (iy.max() + 0.5) * step)
    cmap = colormaps["viridis"].with_extremes(bad="#f2f2f2")
    image = ax.imshow(np.ma.masked_invalid(grid.T), origin="lower", extent=extent, cmap=cmap,
                      vmin=0.0, vmax=max(1e-6, float(np.nanmax(grid)) if np.isfinite(grid).any()
                                         else 1.0), interpolation="nearest")
    fig.colorbar(image, ax=ax, shrink=0.85, label="score: worst target's margin (best heading)")
    for obj in (scene.objects if scene is not None else ()):
        ring = outline(obj, 0, 1)
        ax.plot(ring[:, 0], ring[:, 1], color="#d62728", lw=1.0, ls="--")
    for _, pose in targets:
        ax.plot(pose[0, 3], pose[1, 3], "x", color="black", ms=7, zorder=5)
    bx, by, byaw = float(x[best]), float(y[best]), float(yaw[best])
    ax.plot(bx, by, "o", color="#ff7f0e", ms=9, label=f"best base ({bx:.2f}, {by:.2f}) m, "
                                                       f"yaw {np.degrees(byaw):.0f} deg")
    ax.annotate("", xy=(bx + 0.4 * np.cos(byaw), by + 0.4 * np.sin(byaw)), xytext=(bx, by),
                arrowprops={"arrowstyle": "->", "color": "#ff7f0e", "lw": 2})
    ax.set_xlabel("x (m, cell)")
    ax.set_ylabel("y (m, cell)")
    ax.set_aspect("equal")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or "base placement: feasible positions", fontsize=10)
    left_out = place_labels(ax, [(name, float(p[0, 3]), float(p[1, 3])) for name, p in targets],
                            "black", clear_points=10.0)
    if left_out:
        fig.text(0.02, 0.02, "not labelled: " + ", ".join(left_out), fontsize=7)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()
