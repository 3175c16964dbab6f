"""The ``usar-arm`` command: argparse subcommands in the ``ros2 <verb>`` style
(:mod:`.main`; the executable is :mod:`usar_arm.__main__`).

This package is the only place that prints, reads argv and sets exit codes. Results go to
stdout (``--json``: one JSON object with stable keys); logs and progress go to stderr. It
imports nothing itself: a command loads its own module alone.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from usar_arm.core.lazy import exports

if TYPE_CHECKING:  # the public names, one per line, imported on first use (core/lazy.py)
    from usar_arm.cli.main import main as main

__getattr__, __dir__, __all__ = exports(__name__, __file__)

# ``usar_arm.cli.main`` is a module and the function it defines: importing the module (as the
# entry point and the tests do) binds the *module* as this package's attribute ``main``, over the
# lazy function. Bound here once, the function stays (cli.main loads no command module).
from usar_arm.cli.main import main as main  # noqa: E402
