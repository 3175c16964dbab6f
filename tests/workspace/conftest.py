"""Arms and a small reachability map shared by the workspace tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_arm.description.cache import robot_from_description
from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.planning.scene import EMPTY
from usar_arm.workspace import jobs
from usar_arm.workspace.reach import ReachSettings

ROOT = Path(__file__).resolve().parents[2]
SMALL = ReachSettings(resolution=0.25, orientations=24, edge_draws=200_000)
"""A map that takes a few seconds: 25 cm voxels, 24 orientations, the edge search with
200,000 draws."""


@pytest.fixture(scope="session")
def kr60() -> Robot:
    """The KR60 of the checked-in description."""
    return robot_from_files(ROOT / "robots/generated/KR60.urdf")


@pytest.fixture(scope="session")
def fanuc() -> Robot:
    """The Fanuc M16iB20 on its rail (7 joints, the first prismatic), as discovered."""
    return robot_from_description(describe(DescribeOptions(robot="Fanuc_M16iB20",
                                                           accuracy_samples=0)))


@pytest.fixture(scope="session")
def small_map(kr60: Robot) -> jobs.ReachRun:
    """:data:`SMALL` map of the KR60 in the empty scene, computed in this process."""
    return jobs.reach_map(kr60, EMPTY, SMALL, jobs.backend_for(0))
