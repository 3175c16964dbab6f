"""Exports of plans and executions to formats other tools read (ROS 2 bags)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.export.bag import BagSummary as BagSummary
    from usar_arm.export.bag import write_bag as write_bag
    from usar_arm.export.drive_bag import write_drive_bag as write_drive_bag
    from usar_arm.export.drive_plot import plot_drive as plot_drive
    from usar_arm.export.placement_plot import placement_png as placement_png
    from usar_arm.export.plot import plot_trajectory as plot_trajectory
    from usar_arm.export.reach_plot import reach_slice_png as reach_slice_png
    from usar_arm.export.render import render_arm as render_arm
    from usar_arm.export.residual_plot import plot_residuals as plot_residuals
    from usar_arm.export.view import export_html as export_html
    from usar_arm.export.view import serve_replay as serve_replay
    from usar_arm.export.world_plot import render_world as render_world

__getattr__, __dir__, __all__ = exports(__name__, __file__)
