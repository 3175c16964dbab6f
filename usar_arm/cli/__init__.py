"""The ``usar-arm`` command: argparse subcommands in the ``ros2 <verb>`` style
(:func:`usar_arm.cli.main.main`; the executable is :mod:`usar_arm.__main__`).

This package is the only place that prints, reads argv and sets exit codes. Results go to
stdout (``--json``: one JSON object with stable keys); logs and progress go to stderr. It
imports nothing itself: a command loads its own module alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:
    from usar_arm.cli.main import main

_HOMES = {
    "main": ("main",),
}
"""The module of each public name, imported on first use (usar_arm.core.lazy)."""

__all__ = ["main"]

__getattr__ = exports(__name__, _HOMES)
