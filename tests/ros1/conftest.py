"""The ROS 1 tests: real ROS 1 tools (Debian's) judge `usar-arm ros --ros1`. They run where
Debian's ROS 1 and the tools are installed (`make test` installs them where it can); elsewhere
each module skips with one line naming the apt command. The ROS 1 environment is made once for
the run (a lock serialises the xdist workers)."""

from __future__ import annotations

import os

import pytest

from usar_arm.ros import ros1_setup

NEEDS = ros1_setup.NODE_NEEDS + ros1_setup.TOOLS_NEED
ABSENT = ros1_setup.missing(NEEDS)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    ours = [i for i in items if "tests/ros1/" in str(i.fspath).replace("\\", "/")]
    if not ABSENT or not ours:
        return
    if os.environ.get("USAR_ARM_REQUIRE_ROS1"):  # CI: they must run, so each fails, saying why
        for item in ours:  # (an error raised here would end every xdist worker's session,
            item.add_marker(pytest.mark.usefixtures("_ros1_required"))  # blaming some test)
        return
    skip = pytest.mark.skip(reason=f"Debian's ROS 1 is not installed (missing "
                                   f"{', '.join(ABSENT)}): {ros1_setup.apt_command(NEEDS)}")
    for item in ours:
        item.add_marker(skip)


@pytest.fixture
def _ros1_required() -> None:
    """Fail the test: USAR_ARM_REQUIRE_ROS1 is set (CI) and Debian's ROS 1 is not whole."""
    pytest.fail(f"USAR_ARM_REQUIRE_ROS1 is set but Debian's ROS 1 is missing "
                f"{', '.join(ABSENT)}: {ros1_setup.apt_command(NEEDS)}", pytrace=False)


@pytest.fixture(scope="session")
def ros1_env() -> ros1_setup.Ros1Environment:
    """The ROS 1 environment (made on first use)."""
    return ros1_setup.setup()
