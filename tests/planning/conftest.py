"""Robots described by discovery against the embedded simulator (shared by the module)."""

from __future__ import annotations

import pytest

from usar_arm.description.cache import robot_from_description
from usar_arm.description.embedded import describe
from usar_arm.description.pipeline import DescribeOptions
from usar_arm.planning.robot import Robot


@pytest.fixture(scope="session")
def kr60() -> Robot:
    return robot_from_description(describe(DescribeOptions(accuracy_samples=0)))


@pytest.fixture(scope="session")
def fanuc() -> Robot:
    return robot_from_description(describe(DescribeOptions(robot="Fanuc_M16iB20",
                                                           accuracy_samples=0)))
