"""The Tesseract config folder the Tesseract peer runs on: written by usar-arm's own
``tesseract-config`` (the library call) for a problem file's URDF and SRDF, so that the
benchmark also exercises what usar-arm hands to Tesseract users. Tesseract then reads the folder
itself (bench/peers/ts_scene.py); it imports nothing from usar-arm."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from usar_arm.core.fileio import write_tree_atomic
from usar_arm.planning.robot import robot_from_files
from usar_arm.urdf.tesseract import tesseract_config


def with_tesseract(spec: dict[str, Any], work: Path) -> dict[str, Any]:
    """``spec`` plus ``"tesseract"``: the folder written for its robot under ``work``."""
    robot = robot_from_files(spec["urdf"], spec["srdf"])
    folder = work / "tesseract" / f"{robot.chain.name.lower()}_tesseract"
    config = tesseract_config(robot.chain, robot.urdf, Path(spec["srdf"]).read_text(),
                              folder.name, robot.states.get("home"))
    write_tree_atomic(folder, config.files)
    return {**spec, "tesseract": str(folder), "tesseract_ik_solver": config.solver}
