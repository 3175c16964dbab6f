"""The soak test goes first, so that under ``pytest -n 2`` it overlaps the rest of the suite."""

from __future__ import annotations

import pytest

FIRST = ("tests/sim/test_soak.py::", "tests/sim/test_load.py::test_sixty_four")


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    items.sort(key=lambda item: not item.nodeid.startswith(FIRST))  # stable: the rest keep order
