"""The soak and the 64-client load go first, so that in ``make test-slow`` (three workers,
``--dist loadgroup``) they overlap the rest of the slow suite."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from usar_arm.sim.server import SimOptions, SimServer
from usar_arm.sim.world_spec import load_world

FIRST = ("tests/sim/test_soak.py::", "tests/sim/test_load.py::test_sixty_four")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    items.sort(key=lambda item: not item.nodeid.startswith(FIRST))  # stable: the rest keep order


@pytest.fixture(scope="module")
def rooms_port() -> Iterator[int]:
    """The port of a simulator serving the shipped ``rooms`` world (one per test module)."""
    server = SimServer(SimOptions(port=0), world_spec=load_world("rooms"))
    port = server.start()
    yield port
    server.stop()
