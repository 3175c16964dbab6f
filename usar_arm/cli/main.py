"""Entry point: builds the parser from the subcommand modules and maps errors to exit codes.

A command line that names a command loads that command's module alone (``usar-arm sim``
does not import OMPL, SciPy's statistics or the Tesseract exporter); ``usar-arm --help``, a
missing or an unknown command load none: the commands are listed from :data:`COMMANDS`'
one-line summaries (:mod:`.commands`, which the modules register them by too).
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from usar_arm.cli.commands import COMMANDS
from usar_arm.cli.common import EXIT_CODES_HELP, report_error
from usar_arm.core.version import __version__


def register(sub: argparse._SubParsersAction, module: str) -> None:  # type: ignore[type-arg]
    """Add the commands of ``usar_arm.cli.<module>`` (a :data:`COMMANDS` entry's module)."""
    loaded = importlib.import_module(f"usar_arm.cli.{module}")
    (getattr(loaded, "add_parsers", None) or loaded.add_parser)(sub)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser: with ``command`` (a key of :data:`COMMANDS`), only its module's commands;
    otherwise every command listed by its summary, none loaded."""
    parser = argparse.ArgumentParser(
        prog="usar-arm",
        description="Learn a USARSim robot arm over its TCP protocol, describe it (URDF, SRDF, "
                    "MoveIt 2 config), plan and execute collision-free, jerk-limited motions.",
        epilog=EXIT_CODES_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"usar-arm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    if command in COMMANDS:
        register(sub, COMMANDS[command].module)
    else:  # (listed only: a command line that names one is parsed by its own module's)
        for name, listed in COMMANDS.items():
            sub.add_parser(name, help=listed.summary, add_help=False)
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
