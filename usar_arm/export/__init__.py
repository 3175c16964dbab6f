"""Exports of plans and executions to formats other tools read (ROS 2 bags)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.export.bag import BagSummary, write_bag
    from usar_arm.export.drive_bag import write_drive_bag
    from usar_arm.export.drive_plot import plot_drive
    from usar_arm.export.placement_plot import placement_png
    from usar_arm.export.plot import plot_trajectory
    from usar_arm.export.reach_plot import reach_slice_png
    from usar_arm.export.render import render_arm
    from usar_arm.export.residual_plot import plot_residuals
    from usar_arm.export.view import export_html, serve_replay
    from usar_arm.export.world_plot import render_world

_HOMES = {
    "bag": ("BagSummary", "write_bag"),
    "drive_bag": ("write_drive_bag",),
    "drive_plot": ("plot_drive",),
    "placement_plot": ("placement_png",),
    "plot": ("plot_trajectory",),
    "reach_plot": ("reach_slice_png",),
    "render": ("render_arm",),
    "residual_plot": ("plot_residuals",),
    "view": ("export_html", "serve_replay"),
    "world_plot": ("render_world",),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["BagSummary", "export_html", "placement_png", "plot_drive", "plot_residuals",
           "plot_trajectory", "reach_slice_png", "render_arm", "render_world", "serve_replay",
           "write_bag", "write_drive_bag"]

__getattr__ = exports(__name__, _HOMES)
