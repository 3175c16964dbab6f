"""The commands of ``usar-arm``: each one's module and its line in ``--help``, in the order of
``--help``, written once. ``usar-arm --help`` lists them from here without loading a command's
module; each module registers its commands through :func:`add_command`, which gives them the
same line."""

from __future__ import annotations

import argparse
from typing import Any, NamedTuple


class Command(NamedTuple):
    """A command of ``usar-arm``."""

    module: str
    """The module of ``usar_arm.cli`` that defines it (its ``add_parser`` or ``add_parsers``)."""
    summary: str
    """Its line in ``usar-arm --help``."""


COMMANDS: dict[str, Command] = {
    "demo": Command("demo_cmd", "the main job: describe the KR60 and run a pick-and-place cycle"),
    "sim": Command("sim_cmd", "run the embedded USARSim-compatible simulator (MuJoCo physics)"),
    "urdf": Command("urdf_cmd", "spawn a robot, learn its arm over the wire, write "
                                "URDF/SRDF/limits (a ground vehicle: its URDF)"),
    "moveit-config": Command("urdf_cmd", "write a complete MoveIt 2 config package for a robot"),
    "ik": Command("ik_cmd", "inverse kinematics: joint values that put tool0 at a pose"),
    "plan": Command("plan_cmd", "plan a collision-free, jerk-limited motion to a pose or joint "
                                "values"),
    "execute": Command("execute_cmd", "execute a saved trajectory (JSON from plan --out) on the "
                                      "arm"),
    "calibrate": Command("calibrate_cmd", "identify joint frames, tool and base from measured "
                                          "tool poses"),
    "tesseract-config": Command("tesseract_cmd", "write a Tesseract config folder for a robot"),
    "reach": Command("reach_cmd", "reachability map: where tool0 reaches, in how many "
                                  "orientations"),
    "place": Command("place_cmd", "base placement: where the arm reaches every target, with "
                                  "most margin"),
    "batch": Command("batch_cmd", "solve many IK or plan problems from a JSON Lines file"),
    "render": Command("picture_cmds", "draw the arm (and a trajectory's tool path) in its scene "
                                      "as a PNG"),
    "plot": Command("picture_cmds", "plot a trajectory's joints against their limits as a PNG"),
    "view": Command("picture_cmds", "replay a trajectory in an interactive 3D page (needs "
                                    "usar-arm[viz])"),
    "ros": Command("ros_cmd", "serve the arm on ROS 2: robot_description, joint_states, tf, "
                              "FollowJointTrajectory (a ground vehicle: cmd_vel, odom, scan)"),
    "drive": Command("drive_cmd", "drive a ground vehicle (P3AT, FrontAckerman) by waypoints or "
                                  "a script; bag, picture, drift"),
}
"""Each command, in the order of ``--help``."""


def add_command(sub: argparse._SubParsersAction, name: str,  # type: ignore[type-arg]
                **options: Any) -> argparse.ArgumentParser:
    """Register command ``name`` (a key of :data:`COMMANDS`) on ``sub`` with its summary as its
    help line; ``options`` go to ``add_parser`` (``description``, ``formatter_class``...).

    Raises:
        KeyError: ``name`` is not in :data:`COMMANDS`.
    """
    parser: argparse.ArgumentParser = sub.add_parser(name, help=COMMANDS[name].summary, **options)
    return parser
