"""Plots of a timed trajectory: position, velocity, acceleration and jerk of every joint against
time, with the limits it was timed with and, optionally, the joint values actually executed.

Drawn with matplotlib's object API (:class:`~matplotlib.figure.Figure` and the Agg canvas), never
pyplot, so a user's interactive session is left alone.
"""

from __future__ import annotations

import io
import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Protocol

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from usar_arm.control.trajectory import Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.fileio import write_atomic
from usar_arm.core.spatial import Array

log = logging.getLogger("usar_arm.export.plot")

PLANNED = "#1f4fbf"
EXECUTED = "#e4572e"
LIMIT = "0.35"
MAX_MARKERS = 120
"""At most this many executed markers per axes (evenly spaced) keep dense logs readable."""


class JointSamples(Protocol):
    """Joint values sampled while a trajectory ran.

    :class:`usar_arm.control.trajectory.ExecutedSamples` (the executor's result, which the bag
    exporter writes) has exactly these fields.

    Attributes:
        t: (m,) sample times (s) on the trajectory's clock (0 = its first sample).
        q: (m, n) joint values (rad or m), in the trajectory's joint order.
    """

    @property
    def t(self) -> Array: ...

    @property
    def q(self) -> Array: ...


def jerk_samples(trajectory: Trajectory) -> tuple[Array, Array]:
    """Jerk (rad/s^3 or m/s^3) by finite differences of the acceleration samples, with the
    times (s) it holds at: the midpoints of the sample intervals. Returns (t, jerk (m-1, n))."""
    dt = np.diff(trajectory.t)
    return trajectory.t[:-1] + dt / 2, np.diff(trajectory.qdd, axis=0) / dt[:, None]


def _executed(executed: JointSamples, n: int) -> tuple[Array, Array]:
    t, q = np.asarray(executed.t, dtype=float), np.asarray(executed.q, dtype=float)
    if t.ndim != 1 or q.shape != (len(t), n):
        raise InvalidInputError(f"executed samples need t of shape (m,) and q of shape (m, {n}) "
                                f"(one column per joint); got t {t.shape} and q {q.shape}")
    return t, q


def _limits(ax: Axes, low: float, high: float, data: Array, always: bool) -> bool:
    """Dashed lines at the limits and y limits around the data (rad, m and their rates).

    Position limits (``always`` False) are drawn only when the motion comes near them, so that
    a small motion is not flattened by a wide joint range. Returns True if both are drawn.
    """
    lo, hi = float(np.min(data)), float(np.max(data))
    span = max(hi - lo, 0.05)
    shown = [v for v in (low, high) if always or lo - 0.5 * span <= v <= hi + 0.5 * span]
    for v in shown:
        ax.axhline(v, color=LIMIT, linestyle="--", linewidth=0.9)
    top, bottom = max([hi, *shown]), min([lo, *shown])
    if top - bottom < span:
        mid = (top + bottom) / 2
        top, bottom = mid + span / 2, mid - span / 2
    pad = 0.08 * (top - bottom)
    ax.set_ylim(bottom - pad, top + pad)
    return len(shown) == 2


def _columns(trajectory: Trajectory, jerk: bool
             ) -> list[tuple[str, str, Array, Array, Array | None]]:
    """(quantity, unit suffix, times, values, limit) of each column: position, velocity,
    acceleration and, with ``jerk``, jerk by finite differences."""
    lim = trajectory.limits
    columns: list[tuple[str, str, Array, Array, Array | None]] = [
        ("position", "", trajectory.t, trajectory.q, None),
        ("velocity", "/s", trajectory.t, trajectory.qd, lim.velocity),
        ("acceleration", "/s²", trajectory.t, trajectory.qdd, lim.acceleration)]
    if jerk and len(trajectory.t) > 1:
        columns.append(("jerk", "/s³", *jerk_samples(trajectory), lim.jerk))
    return columns


def _legend(fig: Figure, exe: tuple[Array, Array] | None, width: int, height: int) -> None:
    """Planned, limits and (when there are) executed samples, at the top right."""
    handles = [Line2D([], [], color=PLANNED, label="planned"),
               Line2D([], [], color=LIMIT, linestyle="--", label="limits")]
    if exe is not None:
        handles.append(Line2D([], [], color=EXECUTED, marker="o", linestyle="",
                              markersize=4, label=f"executed ({len(exe[0])} samples)"))
    fig.legend(handles=handles, loc="upper right", bbox_to_anchor=(1 - 10 / width, 1 - 4 / height),
               ncols=len(handles), fontsize=8, frameon=False)


def plot_trajectory(path: str | Path, trajectory: Trajectory,
                    executed: JointSamples | None = None, *, jerk: bool = True,
                    units: Sequence[str] | None = None, title: str | None = None,
                    width: int = 1600) -> Path:
    """Write a PNG of a trajectory: one row per joint, one column per quantity (position,
    velocity, acceleration and, with ``jerk``, jerk by finite differences).

    Why a grid and not one axes per quantity with all joints: every joint has its own limits
    (a KR60's wrist is twice as fast as its base), so one shared axes would need 2n dashed
    limit lines in n colours and would squash the small joints under the large ones. A row per
    joint shows each joint's use of each of its limits at a glance, and the executed markers
    sit on the one curve they belong to. The time axis is shared down each column.

    Args:
        path: the PNG to write (atomically; parent folders are created).
        trajectory: the planned samples; ``trajectory.limits`` gives the dashed lines (± the
            velocity, acceleration and jerk limits; lower/upper on position, shown when the
            motion comes near them).
        executed: joint values measured while it ran (drawn as markers on the positions).
        units: position unit of each joint (default ``rad`` for all; ``m`` for prismatic).
        title: heading (default: motion, mode and duration). width: pixels; the height grows
            with the number of joints.

    Returns:
        ``path``.
    """
    names, n = trajectory.joint_names, len(trajectory.joint_names)
    units = list(units) if units is not None else ["rad"] * n
    if len(units) != n:
        raise InvalidInputError(f"units needs one entry per joint ({n}), got {len(units)}")
    exe = _executed(executed, n) if executed is not None else None
    lim = trajectory.limits
    columns = _columns(trajectory, jerk)
    height = 125 * n + 110
    fig = Figure(figsize=(width / 100, height / 100), dpi=100)
    FigureCanvasAgg(fig)
    margins = {"left": 95 / width, "right": 1 - 12 / width, "top": 1 - 62 / height,
               "bottom": 48 / height, "wspace": 0.24, "hspace": 0.14}
    axes = fig.subplots(n, len(columns), sharex=True, squeeze=False, gridspec_kw=margins)
    for c, (quantity, suffix, t, values, bound) in enumerate(columns):
        for j in range(n):
            ax = axes[j, c]
            ax.plot(t, values[:, j], color=PLANNED, linewidth=1.4, zorder=3)
            if c == 0:
                data = values[:, j] if exe is None else np.concatenate([values[:, j],
                                                                         exe[1][:, j]])
                both = _limits(ax, lim.lower[j], lim.upper[j], data, always=False)
                label = f"{names[j]} ({units[j]})"
                if not both:
                    label += f"\nlimits {lim.lower[j]:+.2f} … {lim.upper[j]:+.2f}"
                ax.set_ylabel(label, fontsize=8)
            else:
                _limits(ax, -bound[j], bound[j], values[:, j], always=True)  # type: ignore[index]
                ax.set_ylabel(f"{units[j]}{suffix}", fontsize=7, color="0.4")
            if exe is not None and c == 0:
                every = max(1, len(exe[0]) // MAX_MARKERS)
                ax.plot(exe[0], exe[1][:, j], "o", color=EXECUTED, markersize=2.8,
                        markevery=every, alpha=0.7, zorder=2)
            ax.grid(True, color="0.9", linewidth=0.6)
            ax.tick_params(labelsize=7)
            ax.ticklabel_format(axis="y", useOffset=False)
        axes[0, c].set_title(quantity, fontsize=10)
        axes[-1, c].set_xlabel("time (s)", fontsize=8)
    _legend(fig, exe, width, height)
    fig.suptitle(title if title is not None else
                 f"{trajectory.motion.upper()} trajectory ({trajectory.mode}), "
                 f"{trajectory.duration:.2f} s, {len(trajectory.t)} samples at "
                 f"{trajectory.rate:.0f} Hz", fontsize=11, x=10 / width, y=1 - 8 / height,
                 ha="left", va="top")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    log.debug("plotted a %d-joint trajectory of %.3f s", n, trajectory.duration)
    return write_atomic(path, buf.getvalue())
