"""``usar-arm ik``: inverse kinematics of tool0 for a pose."""

from __future__ import annotations

import argparse

import numpy as np

from usar_arm.cli.commands import add_command
from usar_arm.cli.common import add_verbosity, out, print_json, setup_logging, verbosity
from usar_arm.cli.robot_args import add_robot_args, robot_from_args
from usar_arm.cli.units import UNITS, pose_from_args
from usar_arm.core.errors import EXIT_OK, InvalidInputError
from usar_arm.planning.ik import IKOptions
from usar_arm.planning.scene_file import load_scene


def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = add_command(
        sub, "ik",
        description="Solve for the joint values that put tool0 at a pose in base_link: the "
                    "solution nearest --seed-q (default: the zero configuration), or every "
                    "solution with --all. Analytic (all branches, Newton-polished) for "
                    "ortho-parallel arms such as the KR60; numeric for any arm.")
    p.add_argument("--pose", type=float, nargs=6, required=True,
                   metavar=("X", "Y", "Z", "R", "P", "Y"),
                   help="tool0 pose in base_link, in --units")
    p.add_argument("--units", choices=UNITS, default="m-rad",
                   help="m-rad (default); mm-deg; kuka: X Y Z mm and A B C deg of KUKA's tool "
                        "frame (x out of the flange), as on a pendant")
    p.add_argument("--seed-q", type=float, nargs="+", default=None, metavar="Q",
                   help="joint values (rad/m) to stay near")
    p.add_argument("--all", action="store_true", help="every distinct solution")
    p.add_argument("--scene", default=None, metavar="FILE",
                   help="drop solutions in collision with this scene (a YAML file, or one of "
                        "empty, table, shelf, cage)")
    p.add_argument("--tolerance", type=float, default=1e-5, metavar="M",
                   help="position (m) and orientation (rad) tolerance (default 1e-5)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    add_robot_args(p)
    add_verbosity(p)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    setup_logging(verbosity(args))
    robot = robot_from_args(args)
    chain = robot.chain
    tool0_in_flange = np.linalg.inv(chain.frame_pose("flange", [0.0] * chain.dof)) @ \
        chain.frame_pose("tool0", [0.0] * chain.dof)
    target = pose_from_args(args.pose, args.units, tool0_in_flange)
    seed = None
    if args.seed_q is not None:
        if len(args.seed_q) != chain.dof:
            names = ", ".join(chain.joint_names)
            raise InvalidInputError(f"--seed-q needs {chain.dof} values ({names}), got "
                                    f"{len(args.seed_q)}")
        seed = np.array(args.seed_q)
    collision = robot.collision_world(load_scene(args.scene)) if args.scene else None
    options = IKOptions(position_tolerance=args.tolerance, orientation_tolerance=args.tolerance)
    result = robot.ik_solver(options).solve(target, seed, all_solutions=args.all,
                                            collision=collision)
    sols = result.solutions
    if args.json:
        print_json({"solutions": [s.q.tolist() for s in sols],
                    "joint_names": list(chain.joint_names),
                    "residuals": [[s.position_error, s.orientation_error] for s in sols],
                    "seconds": result.seconds, "method": result.method})
        return EXIT_OK
    out(f"{len(sols)} solution(s) ({result.method}, {result.seconds * 1000:.2f} ms); "
        "residuals: position m, orientation rad")
    out("  ".join(f"{n:>10}" for n in chain.joint_names))
    for s in sols:
        out("  ".join(f"{v:>10.5f}" for v in s.q)
            + f"   {s.position_error:.1e} {s.orientation_error:.1e}")
    return EXIT_OK
