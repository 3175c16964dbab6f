"""The soak and the 64-client load go first, so that in ``make test-slow`` (three workers,
``--dist loadgroup``) they overlap the rest of the slow suite."""

from __future__ import annotations

import pytest

FIRST = ("tests/sim/test_soak.py::", "tests/sim/test_load.py::test_sixty_four")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    items.sort(key=lambda item: not item.nodeid.startswith(FIRST))  # stable: the rest keep order
