"""The calibration picture: each reading's distance from the model before and after the fit,
fitted readings and held-out readings side by side (position in mm, rotation in mrad).

Drawn with matplotlib's object API and the Agg canvas, never pyplot.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from usar_arm.core.fileio import write_atomic
from usar_arm.core.spatial import Array

BEFORE = "#e4572e"
AFTER = "#1f4fbf"


def plot_residuals(path: str | Path, fit: tuple[Array, Array, Array, Array],
                   held_out: tuple[Array, Array, Array, Array], title: str) -> Path:
    """Write a PNG (atomically) of the residuals per reading.

    ``fit`` and ``held_out``: (before m, before rad, after m, after rad), one value per
    reading, in reading order.
    """
    fig = Figure(figsize=(11, 6.5), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 2, sharey="row", squeeze=False)
    for col, (name, data) in enumerate((("fitted readings", fit), ("held-out readings",
                                                                  held_out))):
        before_m, before_rad, after_m, after_rad = (np.asarray(a, float) for a in data)
        k = np.arange(len(before_m))
        for row, (b, a, unit, scale) in enumerate(((before_m, after_m, "mm", 1e3),
                                                   (before_rad, after_rad, "mrad", 1e3))):
            ax = axes[row][col]
            ax.plot(k, b * scale, ".", ms=3, color=BEFORE,
                    label=f"as learnt (max {np.max(b, initial=0) * scale:.3f} {unit})")
            ax.plot(k, a * scale, ".", ms=3, color=AFTER,
                    label=f"calibrated (max {np.max(a, initial=0) * scale:.3f} {unit})")
            ax.set_ylabel(f"{'position' if row == 0 else 'rotation'} residual ({unit})")
            ax.grid(alpha=0.3)
            ax.legend(loc="upper right", fontsize=8)
            if row == 0:
                ax.set_title(f"{name} ({len(k)})")
            else:
                ax.set_xlabel("reading (in the order taken)")
    fig.suptitle(title + "\nresidual = distance from each reading's printed interval "
                 "middle to the model's pose", fontsize=10)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return write_atomic(path, buf.getvalue())
