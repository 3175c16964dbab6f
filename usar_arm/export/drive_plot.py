"""The picture of a drive: the world's top view, the true path, the odometry and INS paths,
the waypoints and the laser hits placed by the ground truth (they should lie on the walls)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from matplotlib.collections import PathCollection
from matplotlib.figure import Figure

from usar_arm.control.drive_record import Drift, DriveRecord, laser_hits, odom_in_map
from usar_arm.core.world_file import Scenery
from usar_arm.export.world_plot import draw_world, save_png

TRUTH, ODOMETRY, INS, HITS = "#1b1b1b", "#e4572e", "#1f77b4", "#2ca02c"
MAX_HITS = 20000
"""At most about this many laser hits are drawn (every n-th scan)."""


def plot_drive(path: str | Path, record: DriveRecord, scenery: Scenery | None,
               drifts: Sequence[Drift] = (), title: str = "drive",
               size: tuple[int, int] = (1100, 900)) -> None:
    """A PNG of the drive at ``path``: world (when given), paths, waypoints and laser hits; the
    title states each drift (final position error, m and % of distance; heading error, rad)."""
    fig = Figure(figsize=(size[0] / 100, size[1] / 100), dpi=100)
    ax = fig.add_subplot()
    if scenery is not None:
        draw_world(ax, scenery)
    rays = max((len(s.ranges) for s in record.scans), default=1)
    hits = laser_hits(record, every=max(1, len(record.scans) * rays // MAX_HITS))
    if len(hits):
        ax.scatter(hits[:, 0], hits[:, 1], s=1, color=HITS, alpha=0.35, linewidths=0,
                   label="laser hits (placed by ground truth)", zorder=2)
    odo = odom_in_map(record)
    for track, color, label, style in ((record.truth, TRUTH, "ground truth", "-"),
                                       (odo, ODOMETRY, "odometry", "--"),
                                       (record.ins, INS, "INS", ":")):
        if len(track):
            ax.plot(track.pose[:, 0], track.pose[:, 1], style, color=color, lw=1.6,
                    label=label, zorder=3)
    if len(record.truth):
        ax.plot(*record.truth.pose[0, :2], "o", color=TRUTH, ms=7, label="start", zorder=4)
    if record.goals:
        gx, gy = zip(*record.goals, strict=True)
        ax.plot(gx, gy, "x", color="#9467bd", ms=9, mew=2, label="waypoints", zorder=4)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    lines = [f"{title}: {record.truth.length_m():.2f} m driven"
             + ("" if record.reached else " (goal not reached)")
             + (" (interrupted)" if record.interrupted else "")]
    lines += [f"{d.source} drift: {d.position_m:.3f} m ({d.percent_of_distance:.2f} % of "
              f"distance), heading {d.heading_rad:+.3f} rad" for d in drifts]
    ax.set_title("\n".join(lines), fontsize=10)
    legend = ax.legend(loc="best", fontsize=8, framealpha=0.9)
    for handle in legend.legend_handles:  # (the hits' dots are too small to see in a legend)
        if isinstance(handle, PathCollection):
            handle.set_sizes([24.0])
    fig.tight_layout()
    save_png(fig, path)
