"""Entry point: builds the parser from the subcommand modules and maps errors to exit codes."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from usar_arm.cli import (
    batch_cmd,
    calibrate_cmd,
    demo_cmd,
    execute_cmd,
    ik_cmd,
    picture_cmds,
    place_cmd,
    plan_cmd,
    reach_cmd,
    sim_cmd,
    tesseract_cmd,
    urdf_cmd,
)
from usar_arm.cli.common import EXIT_CODES_HELP, report_error
from usar_arm.version import __version__

COMMANDS = [demo_cmd, sim_cmd, urdf_cmd, ik_cmd, plan_cmd, execute_cmd, calibrate_cmd,
            tesseract_cmd, reach_cmd, place_cmd, batch_cmd]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="usar-arm",
        description="Learn a USARSim robot arm over its TCP protocol, describe it (URDF, SRDF, "
                    "MoveIt 2 config), plan and execute collision-free, jerk-limited motions.",
        epilog=EXIT_CODES_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"usar-arm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in COMMANDS:
        module.add_parser(sub)
    picture_cmds.add_parsers(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
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
