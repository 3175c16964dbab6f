"""Entry point: builds the parser from the subcommand modules and maps errors to exit codes.

A command line that names a command loads that command's module alone (``usar-arm sim``
does not import OMPL, SciPy's statistics or the Tesseract exporter); ``usar-arm --help``, a
missing or an unknown command load none: the commands are listed from :data:`COMMANDS`'
one-line summaries (a test checks them against what the modules register).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from usar_arm.cli.common import EXIT_CODES_HELP, report_error
from usar_arm.core.version import __version__

COMMANDS: dict[str, str] = {
    "demo": "demo_cmd", "sim": "sim_cmd", "urdf": "urdf_cmd", "moveit-config": "urdf_cmd",
    "ik": "ik_cmd", "plan": "plan_cmd", "execute": "execute_cmd", "calibrate": "calibrate_cmd",
    "tesseract-config": "tesseract_cmd", "reach": "reach_cmd", "place": "place_cmd",
    "batch": "batch_cmd", "render": "picture_cmds", "plot": "picture_cmds",
    "view": "picture_cmds", "ros": "ros_cmd", "drive": "drive_cmd"}
"""Each command and the module of ``usar_arm.cli`` that defines it, in the order of --help (a
test checks it against what the modules register)."""

SUMMARIES: dict[str, str] = {
    "demo": "the main job: describe the KR60 and run a pick-and-place cycle",
    "sim": "run the embedded USARSim-compatible simulator (MuJoCo physics)",
    "urdf": "spawn a robot, learn its arm over the wire, write URDF/SRDF/limits "
                "(a ground vehicle: its URDF)",
    "moveit-config": "write a complete MoveIt 2 config package for a robot",
    "ik": "inverse kinematics: joint values that put tool0 at a pose",
    "plan": "plan a collision-free, jerk-limited motion to a pose or joint values",
    "execute": "execute a saved trajectory (JSON from plan --out) on the arm",
    "calibrate": "identify joint frames, tool and base from measured tool poses",
    "tesseract-config": "write a Tesseract config folder for a robot",
    "reach": "reachability map: where tool0 reaches, in how many orientations",
    "place": "base placement: where the arm reaches every target, with most margin",
    "batch": "solve many IK or plan problems from a JSON Lines file",
    "render": "draw the arm (and a trajectory's tool path) in its scene as a PNG",
    "plot": "plot a trajectory's joints against their limits as a PNG",
    "view": "replay a trajectory in an interactive 3D page (needs usar-arm[viz])",
    "ros": "serve the arm on ROS 2: robot_description, joint_states, tf, "
           "FollowJointTrajectory (a ground vehicle: cmd_vel, odom, scan)",
    "drive": "drive a ground vehicle (P3AT, FrontAckerman) by waypoints or a script; bag, "
             "picture, drift"}
"""Each command's line in --help, as its module registers it (a test checks they agree): what
``usar-arm --help`` shows without loading the commands."""


def register(sub: argparse._SubParsersAction, module: str) -> None:  # type: ignore[type-arg]
    """Add the commands of ``usar_arm.cli.<module>`` (one of :data:`COMMANDS`' values)."""
    loaded = importlib.import_module(f"usar_arm.cli.{module}")
    (getattr(loaded, "add_parsers", None) or loaded.add_parser)(sub)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser: with ``command`` (one of :data:`COMMANDS`), only its module's commands;
    otherwise every command listed by its summary, none loaded."""
    parser = argparse.ArgumentParser(
        prog="usar-arm",
        description="Learn a USARSim robot arm over its TCP protocol, describe it (URDF, SRDF, "
                    "MoveIt 2 config), plan and execute collision-free, jerk-limited motions.",
        epilog=EXIT_CODES_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"usar-arm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    if command in COMMANDS:
        register(sub, COMMANDS[command])
    else:  # (listed only: a command line that names one is parsed by its own module's)
        for name, summary in SUMMARIES.items():
            sub.add_parser(name, help=summary, add_help=False)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args_list = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(args_list[0] if args_list else None)
    args = parser.parse_args(args_list)
    if not getattr(args, "handler", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        return int(args.handler(args))
    except BaseException as exc:
        if isinstance(exc, SystemExit):
            raise
        return report_error(exc)


if __name__ == "__main__":
    sys.exit(main())
