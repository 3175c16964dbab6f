"""The ``usar-arm`` executable starts a fresh local Ray instance before loading the commands
exactly when the command line will use one (``reach``/``place``/``batch`` with ``--ray
local``), with the CPUs the backend will ask for; a command line loads its own command's
module alone, and ``--help`` lists them all in order."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from usar_arm.__main__ import local_ray_cpus
from usar_arm.cli.commands import COMMANDS, add_command
from usar_arm.cli.main import build_parser, register

CORES = os.cpu_count() or 1


@pytest.mark.parametrize(("argv", "cpus"), [
    (["reach", "--urdf", "a.urdf", "--ray", "local", "--out", "d"], CORES),
    (["place", "--ray=local", "--targets", "t.yaml"], CORES),
    (["batch", "p.jsonl", "--ray", "local", "--workers", "1"], 1),
    (["reach", "--ray", "local", "--workers", "0"], CORES),  # (0 with --ray: one per CPU)
    (["reach", "--ray"], None),  # auto: a running cluster, nothing to start
    (["reach", "--ray", "10.0.0.1:6379"], None),
    (["reach", "--workers", "2"], None),
    (["plan", "--ray", "local"], None),  # (no such option there: its parser says so)
    (["reach", "--ray", "local", "--workers", "two"], None),
    ([], None),
])
def test_a_local_instance_is_started_first_only_for_the_commands_that_use_it(
        argv: list[str], cpus: int | None) -> None:
    assert local_ray_cpus(argv) == cpus


def test_python_dash_m_usar_arm_is_the_executable() -> None:
    done = subprocess.run([sys.executable, "-m", "usar_arm", "--version"], capture_output=True,
                          text=True, timeout=60, check=False,
                          cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0 and done.stdout.startswith("usar-arm "), done.stderr


def _subcommands(parser: argparse.ArgumentParser) -> list[str]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return list(action.choices)


def test_the_command_table_is_what_the_modules_register_in_the_order_of_help() -> None:
    assert _subcommands(build_parser()) == list(COMMANDS)
    for command, listed in COMMANDS.items():  # and one command loads its own module's only
        own = [c for c, other in COMMANDS.items() if other.module == listed.module]
        assert _subcommands(build_parser(command)) == own


def test_the_summaries_help_lists_are_what_the_modules_register() -> None:
    registered: dict[str, str | None] = {}
    for module in dict.fromkeys(c.module for c in COMMANDS.values()):
        action = argparse.ArgumentParser().add_subparsers()
        register(action, module)
        registered |= {a.dest: a.help for a in action._choices_actions}
    assert registered == {name: c.summary for name, c in COMMANDS.items()}


def test_a_command_outside_the_table_cannot_be_registered() -> None:
    with pytest.raises(KeyError, match="no-such-command"):
        add_command(argparse.ArgumentParser().add_subparsers(), "no-such-command")


HELP_ALONE = """
import sys
from usar_arm.cli.main import main
try:
    main(["--help"])
except SystemExit as exc:
    assert exc.code == 0, exc.code
print(",".join(m for m in sys.modules if m.startswith("usar_arm.cli.") and m.endswith(
    ("_cmd", "_cmds"))) or "none")
"""


def test_help_lists_the_commands_without_loading_them() -> None:
    done = subprocess.run([sys.executable, "-c", HELP_ALONE], capture_output=True, text=True,
                          timeout=60, check=False, cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "none"
    shown = "".join(done.stdout.split())  # (argparse wraps the lines, at hyphens too)
    assert all("".join(c.summary.split()) in shown for c in COMMANDS.values())


ONE_COMMAND = """
import sys
from usar_arm.cli.main import main
try:
    main(["sim", "--help"])
except SystemExit as exc:
    assert exc.code == 0, exc.code
loaded = [m for m in ("ompl", "scipy.stats", "usar_arm.cli.reach_cmd",
                      "usar_arm.cli.calibrate_cmd") if m in sys.modules]
print(",".join(loaded) or "none")
"""


def test_a_command_line_loads_only_its_command() -> None:
    done = subprocess.run([sys.executable, "-c", ONE_COMMAND], capture_output=True, text=True,
                          timeout=60, check=False, cwd=Path(__file__).resolve().parents[2])
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "none"
