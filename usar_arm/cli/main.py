"""Entry point: builds the parser from the subcommand modules and maps errors to exit codes.

A command line that names a command loads that command's module alone (``usar-arm sim``
does not import OMPL, SciPy's statistics or the Tesseract exporter); ``usar-arm --help``, a
missing or an unknown command load them all, to list them.
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
    "view": "picture_cmds", "ros": "ros_cmd"}
"""Each command and the module of ``usar_arm.cli`` that defines it, in the order of --help (a
test checks it against what the modules register)."""


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser: with ``command`` (one of :data:`COMMANDS`), only its module's commands."""
    parser = argparse.ArgumentParser(
        prog="usar-arm",
        description="Learn a USARSim robot arm over its TCP protocol, describe it (URDF, SRDF, "
                    "MoveIt 2 config), plan and execute collision-free, jerk-limited motions.",
        epilog=EXIT_CODES_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"usar-arm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    names = [COMMANDS[command]] if command in COMMANDS else list(dict.fromkeys(COMMANDS.values()))
    for name in names:
        module = importlib.import_module(f"usar_arm.cli.{name}")
        register = getattr(module, "add_parsers", None) or module.add_parser
        register(sub)
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
