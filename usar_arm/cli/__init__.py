"""The ``usar-arm`` command: argparse subcommands in the ``ros2 <verb>`` style.

This package is the only place that prints, reads argv and sets exit codes. Results go to
stdout (``--json``: one JSON object with stable keys); logs and progress go to stderr.
"""

from __future__ import annotations

from usar_arm.cli.main import main

__all__ = ["main"]
