"""``usar-arm place``: where to stand the arm so that it reaches every target (inverse
reachability), ranked by the worst target's margin."""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import numpy as np

from usar_arm.cli import job_args as job
from usar_arm.cli.commands import add_command
from usar_arm.cli.common import out, progress, setup_logging, verbosity
from usar_arm.cli.robot_args import robot_from_args
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.core.spatial import matrix_to_rpy
from usar_arm.export.placement_plot import placement_png
from usar_arm.planning.scene import EMPTY
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace import jobs
from usar_arm.workspace.placement import PlaceSettings
from usar_arm.workspace.targets import load_targets


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "place",
        description="Try base poses on the floor (x, y on a grid, yaw in equal steps) and rank "
                    "those from which every target pose of --targets is reachable "
                    "collision-free in --scene by the worst target's margin (manipulability "
                    "and joint-limit distance, each normalised to [0, 1]). Writes "
                    "DIR/placement.json (the ranking, the best base and its IK solutions per "
                    "target) and DIR/placement.png (top view).")
    p.add_argument("--targets", required=True, metavar="FILE",
                   help="YAML file of named tool0 poses in the cell's frame (see "
                        "examples/workspace/table-targets.yaml)")
    p.add_argument("--scene", default=None, metavar="FILE",
                   help="obstacles in the cell's frame (a YAML file, or one of empty, table, "
                        "shelf, cage)")
    p.add_argument("--floor", type=float, default=0.0, metavar="Z",
                   help="height (m) of base_link in the cell (default 0)")
    p.add_argument("--step", type=float, default=0.1, metavar="M",
                   help="grid step of the base positions in metres (default 0.1)")
    p.add_argument("--yaw-steps", type=int, default=8, metavar="N",
                   help="headings tried per position (default 8: every 45 deg)")
    p.add_argument("--region", type=float, nargs=4, default=None,
                   metavar=("X_MIN", "X_MAX", "Y_MIN", "Y_MAX"),
                   help="where base positions may be (m; default: wherever every target is "
                        "within reach)")
    p.add_argument("--top", type=int, default=10, metavar="N",
                   help="candidates listed in the ranking (default 10)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    job.add_job_command_args(p, run)


def settings_from(args: argparse.Namespace) -> PlaceSettings:
    """PlaceSettings from the arguments (checked)."""
    if not (math.isfinite(args.step) and args.step > 0):
        raise InvalidInputError(f"--step is a distance in metres (> 0), got {args.step}")
    if args.yaw_steps < 1:
        raise InvalidInputError(f"--yaw-steps must be at least 1, got {args.yaw_steps}")
    if not math.isfinite(args.floor):
        raise InvalidInputError(f"--floor is a height in metres, got {args.floor}")
    region = tuple(args.region) if args.region else None
    if region and not (region[0] <= region[1] and region[2] <= region[3]):
        raise InvalidInputError(f"--region is X_MIN X_MAX Y_MIN Y_MAX with min <= max, got "
                                f"{list(region)}")
    return PlaceSettings(args.step, args.yaw_steps, args.floor, region)  # type: ignore[arg-type]


def _pose(t: np.ndarray) -> dict[str, list[float]]:
    return {"xyz": t[:3, 3].tolist(), "rpy": list(matrix_to_rpy(t[:3, :3]))}


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    settings = settings_from(args)
    targets = load_targets(args.targets)
    backend = job.backend_from_args(args)
    scene = load_scene(args.scene) if args.scene else EMPTY
    robot = robot_from_args(args)
    progress(f"{robot.chain.name}: {len(targets)} targets, base poses every {settings.step:g} m "
             f"x {settings.yaw_steps} headings, on {backend.describe()}")
    done = job.run_with_progress(args, "target checks", lambda bar: jobs.place(
        robot, scene, targets, settings, backend, args.out, args.resume, bar))
    c, r = done.candidates, done.ranking
    names = [t.name for t in targets]

    def entry(i: int) -> dict[str, Any]:
        worst = int(np.argmin(r.margins[i]))
        return {"x": float(c.x[i]), "y": float(c.y[i]), "yaw": float(c.yaw[i]),
                "yaw_deg": math.degrees(float(c.yaw[i])), "score": float(r.score[i]),
                "worst_target": names[worst],
                "margins": dict(zip(names, r.margins[i].tolist(), strict=True))}

    best_pose = c.pose(done.best, settings.floor)
    record: dict[str, Any] = {
        "robot": job.robot_record(robot), "scene": job.scene_record(scene),
        "targets": [{"name": t.name, **_pose(t.pose)} for t in targets],
        "settings": {"step_m": settings.step, "yaw_steps": settings.yaw_steps,
                     "floor_m": settings.floor,
                     "region_m": list(settings.region) if settings.region else None},
        "references": {"manipulability": done.references[0],
                       "joint_margin": done.references[1]},
        "counts": {"grid_candidates": done.grid_candidates, "within_reach": len(c),
                   "feasible": len(r.order)},
        "best": {**entry(done.best), "z": settings.floor, "base_pose": best_pose.tolist(),
                 "solutions": {t.name: [{"q": q.tolist(), "margin": float(m)}
                                        for q, m in zip(*done.solutions[k], strict=True)]
                               for k, t in enumerate(targets)}},
        "ranking": [entry(int(i)) for i in r.order[:max(args.top, 1)]],
        "run": job.run_record(done.stats),
        "versions": job.versions(),
    }
    picture = placement_png(c.x, c.y, c.yaw, r.score, done.best, settings.step,
                            [(t.name, t.pose) for t in targets], scene,
                            f"{robot.chain.name} base placement: {len(r.order):,} feasible of "
                            f"{len(c):,} base poses")
    written = job.publish(args, {"placement.png": picture,
                                 "placement.json": json.dumps(record, indent=2) + "\n"}, record)
    if args.json:
        return EXIT_OK
    b = record["best"]
    out(f"best base: x {b['x']:.3f} m, y {b['y']:.3f} m, yaw {b['yaw_deg']:.1f} deg, score "
        f"{b['score']:.3f} (worst target: {b['worst_target']}); {len(r.order):,} of {len(c):,} "
        f"base poses reach every target")
    for path in written:
        out(f"  {path}")
    return EXIT_OK
