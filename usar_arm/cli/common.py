"""Helpers shared by the subcommands: logging set-up, JSON output, error reporting."""

from __future__ import annotations

import argparse
import json
import logging
import math
import sys
from typing import Any

from usar_arm.core import errors

_QUIET = False


def setup_logging(verbosity: int, default: int = logging.WARNING) -> None:
    """Log to stderr: -q -> errors only, default ``default``, -v INFO, -vv DEBUG (wire lines).
    -q also silences :func:`progress`."""
    global _QUIET
    _QUIET = verbosity < 0
    level = default
    if verbosity < 0:
        level = logging.ERROR
    elif verbosity == 1:
        level = min(default, logging.INFO)
    elif verbosity >= 2:
        level = logging.DEBUG
    logging.basicConfig(level=level, stream=sys.stderr,
                        format="%(asctime)s %(levelname)-7s %(name)s: %(message)s",
                        datefmt="%H:%M:%S", force=True)
    if level > logging.DEBUG:
        for name in ("usar_arm.sim.wire", "usar_arm.usarsim.wire"):
            logging.getLogger(name).setLevel(logging.INFO)


def add_verbosity(p: argparse.ArgumentParser) -> None:
    """-v / -q flags."""
    p.add_argument("-v", "--verbose", action="count", default=0,
                   help="more log output on stderr (-v info, -vv debug incl. protocol lines)")
    p.add_argument("-q", "--quiet", action="store_true", help="only errors on stderr")


def verbosity(args: argparse.Namespace) -> int:
    """-1 for --quiet, else the -v count."""
    return -1 if getattr(args, "quiet", False) else int(getattr(args, "verbose", 0))


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if hasattr(value, "tolist"):
        return _clean(value.tolist())
    return value


def print_json(obj: dict[str, Any]) -> None:
    """One JSON object on stdout."""
    sys.stdout.write(json.dumps(_clean(obj), indent=2, sort_keys=False) + "\n")
    sys.stdout.flush()


def out(text: str = "") -> None:
    """A line of human-readable result on stdout."""
    sys.stdout.write(text + "\n")
    sys.stdout.flush()


def err(text: str) -> None:
    """A message on stderr."""
    sys.stderr.write(text + "\n")
    sys.stderr.flush()


def progress(text: str) -> None:
    """A progress message on stderr (not with -q)."""
    if not _QUIET:
        err(text)


def report_error(exc: BaseException) -> int:
    """Print an error for a user and return the exit code for it."""
    if isinstance(exc, errors.UsarArmError):
        err(f"usar-arm: error: {exc}")
        return exc.exit_code
    if isinstance(exc, KeyboardInterrupt):
        err("usar-arm: interrupted")
        return errors.EXIT_INTERRUPTED
    raise exc


EXIT_CODES_HELP = f"""exit codes:
  {errors.EXIT_OK}    success
  {errors.EXIT_USAGE}    usage error (bad or missing arguments)
  {errors.EXIT_NO_IK}    no inverse-kinematics solution
  {errors.EXIT_NO_PLAN}    no motion plan
  {errors.EXIT_IN_COLLISION}    start, goal or every IK solution in collision
  {errors.EXIT_EXECUTION_ABORTED}    execution aborted (the arm holds its position)
  {errors.EXIT_UNKNOWN_ROBOT}   the server spawned no robot of that class
  {errors.EXIT_UNKNOWN_START}   unknown start position
  {errors.EXIT_CONNECTION_LOST}   the server closed the connection mid-way
  {errors.EXIT_BAD_DESCRIPTION}   invalid data from the server: a line that is not USARSim (garbage,
       not UTF-8, too long, malformed), or an arm description failing its checks
  {errors.EXIT_WORKER_FAILED}   a chunk of a reach/place/batch job failed twice (--resume continues)
  {errors.EXIT_INVALID_INPUT}   invalid input (file or value)
  {errors.EXIT_UNAVAILABLE}   simulator or Ray cluster unreachable, not answering, or answering too
       slowly (within --timeout); Ray not installed
  {errors.EXIT_INTERRUPTED}  interrupted (Ctrl-C)"""
