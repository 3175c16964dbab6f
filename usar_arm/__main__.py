"""The ``usar-arm`` executable (and ``python -m usar_arm``): what must start before the
command loads, then the command (:mod:`usar_arm.cli`).

Loading the commands takes about 1.5 s (Pinocchio, FCL, OMPL, SciPy, the compiled kernels).
A command that will run on a fresh local Ray instance (``reach``, ``place`` or ``batch`` with
``--ray local``) has that instance's process started first, so that Ray's own start (2.4 to
3.5 s) runs beside the loading instead of after it (:mod:`usar_arm.workspace.local_head`).
"""

from __future__ import annotations

import argparse
import sys

RAY_COMMANDS = ("reach", "place", "batch")
"""The commands that run their work on a backend."""


def local_ray_cpus(argv: list[str]) -> int | None:
    """The CPUs of the fresh local Ray instance this command line will start (``--ray local``,
    ``--workers N`` or one per core), or None when it starts none."""
    if not argv or argv[0] not in RAY_COMMANDS:
        return None
    from usar_arm.workspace.ray_address import AUTO, LOCAL

    parser = argparse.ArgumentParser(add_help=False, exit_on_error=False)
    parser.add_argument("--ray", nargs="?", const=AUTO)
    parser.add_argument("--workers", type=int)
    try:
        known, _ = parser.parse_known_args(argv[1:])
    except (argparse.ArgumentError, ValueError):
        return None  # (the command's own parser says what is wrong)
    if known.ray != LOCAL:
        return None
    from usar_arm.workspace.local_head import instance_cpus

    return instance_cpus(known.workers)


def main() -> int:
    """Run ``usar-arm`` with this process's arguments."""
    argv = sys.argv[1:]
    cpus = local_ray_cpus(argv)
    if cpus is not None:
        from usar_arm.workspace.local_head import start_early

        start_early(cpus)
    from usar_arm.cli.main import main as run

    return run(argv)


if __name__ == "__main__":
    sys.exit(main())
