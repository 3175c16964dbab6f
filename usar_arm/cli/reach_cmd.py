"""``usar-arm reach``: a reachability map of tool0 (voxels x orientations, collision-free IK)."""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import numpy as np

from usar_arm.cli import job_args as job
from usar_arm.cli.commands import add_command
from usar_arm.cli.common import err, out, progress, setup_logging, verbosity
from usar_arm.cli.robot_args import robot_from_args
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.export.reach_plot import reach_slice_png, shoulder
from usar_arm.planning.scene import EMPTY
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace import jobs
from usar_arm.workspace.edges import EdgeResult
from usar_arm.workspace.reach import ReachSettings


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "reach",
        description="Voxelise the arm's reach (its extent from the description, a rail "
                    "included) and, at every voxel centre, solve collision-free IK for a "
                    "fixed, near-uniform set of tool orientations. Writes DIR/reach.npz "
                    "(index, manipulability, joint margin, a witness configuration per "
                    "voxel), DIR/reach.json and slice pictures through the base "
                    "DIR/reach-xz.png (y = 0) and DIR/reach-xy.png (z = 0), and at shoulder "
                    "height DIR/reach-xy-shoulder.png.")
    p.add_argument("--scene", default=None, metavar="FILE",
                   help="obstacles (a YAML file, or one of empty, table, shelf, cage)")
    p.add_argument("--resolution", type=float, default=0.05, metavar="M",
                   help="voxel edge in metres (default 0.05)")
    p.add_argument("--orientations", type=int, default=64, metavar="N",
                   help="tool orientations per voxel (default 64)")
    p.add_argument("--cone", type=float, default=None, metavar="DEG",
                   help="only orientations whose tool z axis is within DEG degrees of "
                        "--cone-axis (e.g. 30: pointing down +/- 30 deg)")
    p.add_argument("--cone-axis", type=float, nargs=3, default=(0.0, 0.0, -1.0),
                   metavar=("X", "Y", "Z"), help="the cone's axis in base_link (default down)")
    p.add_argument("--no-edges", action="store_true",
                   help="skip the edge search: voxels whose centre is out of reach but part "
                        "of whose cell the arm reaches stay 0 (faster; a reachable pose may "
                        "then land in a voxel of index 0)")
    p.add_argument("--edge-draws", type=int, default=4_000_000, metavar="N",
                   help="random configurations thrown at the cells the edge search left "
                        "unmarked, which also estimate the share of reachable poses the map "
                        "still misses (default 4,000,000; 0: none)")
    p.add_argument("--view", action="store_true",
                   help="afterwards, serve an interactive 3D view in a web browser until "
                        "Ctrl-C (needs the viz extra: pip install 'usar-arm[viz]')")
    p.add_argument("--view-port", type=int, default=8080, metavar="PORT",
                   help="port of the 3D view (default 8080; the next free one if taken)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    job.add_job_command_args(p, run)


def settings_from(args: argparse.Namespace) -> ReachSettings:
    """ReachSettings from the arguments (checked)."""
    if not (math.isfinite(args.resolution) and args.resolution > 0):
        raise InvalidInputError(f"--resolution is a voxel edge in metres (> 0), got "
                                f"{args.resolution}")
    if args.orientations < 1:
        raise InvalidInputError(f"--orientations must be at least 1, got {args.orientations}")
    if args.cone is not None and not 0 < args.cone <= 180:
        raise InvalidInputError(f"--cone is a half-angle in (0, 180] degrees, got {args.cone}")
    if not np.any(np.asarray(args.cone_axis) != 0):
        raise InvalidInputError("--cone-axis is a direction: not all zero")
    if args.edge_draws < 0:
        raise InvalidInputError(f"--edge-draws is a count (>= 0), got {args.edge_draws}")
    return ReachSettings(args.resolution, args.orientations, args.cone,
                         tuple(float(v) for v in args.cone_axis),  # type: ignore[arg-type]
                         edges=not args.no_edges, edge_draws=args.edge_draws)


def edges_record(found: EdgeResult | None) -> dict[str, Any] | None:
    """What the edge search did, for reach.json (None when it was skipped)."""
    if found is None:
        return None
    record: dict[str, Any] = {
        "voxels": len(found.voxels), "from_the_border": found.grown,
        "cell_searches": found.searched, "tries": found.tries, "rounds": found.rounds,
        "seconds": round(found.seconds, 3)}
    d = found.draws
    if d is not None:
        record["draws"] = {
            "configurations": d.draws, "landed_in_unmarked_cells": d.landed,
            "cells_found": len(d.cells), "collision_free_share": round(d.free_share, 6),
            "cells_found_once": d.singletons,
            "estimated_miss_rate": d.miss_rate,
            "meaning": "estimated chance that tool0 at a random collision-free configuration "
                       "(uniform within the limits) lands in a voxel of index 0 (Good-Turing "
                       "missing mass of the draws; before the search grew from what they "
                       "found)"}
    return record


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    settings = settings_from(args)
    backend = job.backend_from_args(args)
    scene = load_scene(args.scene) if args.scene else EMPTY
    robot = robot_from_args(args)
    plan = jobs.plan_map(robot, settings)
    progress(f"{robot.chain.name}: {len(plan.voxels):,} of {plan.grid.size:,} voxels within "
             f"reach ({plan.bound.radius:.3f} m of the first revolute joint), "
             f"{len(plan.orientations)} orientations: {plan.queries:,} queries on "
             f"{backend.describe()}")
    def before_edges() -> None:
        progress("searching the edge of the reach (cells whose centre the arm cannot reach "
                 f"but some point of which it may), then {settings.edge_draws:,} random "
                 "configurations...")

    done = job.run_with_progress(args, "queries", lambda bar: jobs.reach_map(
        robot, scene, settings, backend, args.out, args.resume, bar, plan, before_edges))
    if done.edges is not None:
        progress(f"edge search: {len(done.edges.voxels):,} more voxels reached somewhere in "
                 f"their cell ({done.edges.seconds:.1f} s)")
    reach, stats = done.map, done.stats
    reached = int((reach.index > 0).sum())
    record = {
        "robot": job.robot_record(robot), "scene": job.scene_record(scene),
        "settings": {"resolution_m": settings.resolution,
                     "orientations": len(plan.orientations), "cone_deg": settings.cone_deg,
                     "cone_axis": list(settings.cone_axis) if settings.cone_deg else None,
                     "frame": "base_link"},
        "grid": {"origin_m": plan.grid.origin.tolist(), "shape": list(plan.grid.shape),
                 "reach_radius_m": plan.bound.radius,
                 "sweep_m": [plan.bound.sweep_low.tolist(), plan.bound.sweep_high.tolist()]},
        "counts": {"voxels": plan.grid.size, "voxels_within_reach": len(plan.voxels),
                   "voxels_reached": reached,
                   "voxels_reached_at_the_centre": int(((reach.index > 0) & ~reach.edge).sum()),
                   "edge_voxels": int(reach.edge.sum()), "queries": plan.queries,
                   "collision_checks": done.collision_checks},
        "edges": edges_record(done.edges),
        "run": job.run_record(stats),
        "memory_estimate_bytes": plan.memory_bytes,
        "versions": job.versions(),
    }
    joint, height = shoulder(robot.chain)
    name = robot.chain.name
    files: dict[str, str | bytes] = {
        "reach.npz": reach.to_bytes(),
        "reach-xz.png": reach_slice_png(reach.index, reach.origin, reach.resolution, "xz",
                                        robot.chain, scene, 0.0,
                                        f"{name} reachability through the base"),
        "reach-xy.png": reach_slice_png(reach.index, reach.origin, reach.resolution, "xy",
                                        robot.chain, scene, 0.0,
                                        f"{name} reachability through the base"),
        "reach-xy-shoulder.png": reach_slice_png(
            reach.index, reach.origin, reach.resolution, "xy", robot.chain, scene, height,
            f"{name} reachability at shoulder height ({joint})"),
        "reach.json": json.dumps(record, indent=2) + "\n",
    }
    written = job.publish(args, files, record)
    if not args.json:
        out(f"{reached:,} voxels reached of {len(plan.voxels):,} within reach "
            f"({plan.queries:,} queries, {stats.seconds:.1f} s on {stats.backend})")
        for path in written:
            out(f"  {path}")
    if args.view:
        from usar_arm.export.reach_view import serve_reach

        viewer = serve_reach(robot.urdf, reach.index, reach.origin, reach.resolution, scene,
                             port=args.view_port)
        err(f"3D view at {viewer.url} (Ctrl-C to stop)")
        viewer.wait()
    return EXIT_OK
