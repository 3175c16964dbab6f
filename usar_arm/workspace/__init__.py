"""Workspace analysis: reachability maps, base placement and batch jobs, on any backend.

A layer above :mod:`usar_arm.planning` (docs/workspace.md). Its modules:

* :mod:`.orientations`: deterministic near-uniform tool orientations (Super-Fibonacci), or
  those within a cone;
* :mod:`.grid`: the reach bound from the description (a rail included), the voxel grid and the
  memory estimate;
* :mod:`.kernels`, :mod:`.solver`: every IK solution of a batch of poses, compiled, with its
  manipulability and joint margin;
* :mod:`.query`: collision verdicts of those solutions, lazily and in batches;
* :mod:`.reach`, :mod:`.reach_map`: the map's job, its assembly and its file (``reach.npz``);
* :mod:`.placement`, :mod:`.targets`: inverse reachability (base poses ranked by the worst
  target's margin) and its targets file;
* :mod:`.batch_file`: the JSON Lines problems of a batch job;
* :mod:`.engine`, :mod:`.pool`, :mod:`.ray_backend`: jobs cut into chunks, run in this process,
  in local worker processes or on a Ray cluster (the optional ``ray`` extra), with retries,
  Ctrl-C and resume;
* :mod:`.arm_model`: what a job needs of an arm, and how a worker rebuilds it from text.

On a described arm (a :class:`usar_arm.planning.robot.Robot`, e.g.
``Arm.from_files(...).robot``), :mod:`.jobs` runs them: ``jobs.reach_map(robot, scene,
ReachSettings(...), jobs.backend_for(workers=2))``, ``jobs.place(...)``; :mod:`.batch_job` runs
batch jobs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.workspace.engine import InProcess as InProcess
    from usar_arm.workspace.engine import RunStats as RunStats
    from usar_arm.workspace.grid import ReachBound as ReachBound
    from usar_arm.workspace.grid import VoxelGrid as VoxelGrid
    from usar_arm.workspace.grid import reach_bound as reach_bound
    from usar_arm.workspace.orientations import OrientationSet as OrientationSet
    from usar_arm.workspace.orientations import orientation_set as orientation_set
    from usar_arm.workspace.placement import PlaceSettings as PlaceSettings
    from usar_arm.workspace.pool import ProcessBackend as ProcessBackend
    from usar_arm.workspace.reach import ReachPlan as ReachPlan
    from usar_arm.workspace.reach import ReachSettings as ReachSettings
    from usar_arm.workspace.reach_map import ReachMap as ReachMap
    from usar_arm.workspace.targets import Target as Target
    from usar_arm.workspace.targets import load_targets as load_targets

__getattr__, __dir__, __all__ = exports(__name__, __file__)
