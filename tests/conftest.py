"""Shared fixtures: simulators on free loopback ports."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from usar_arm.sim.server import SimOptions, SimServer


@pytest.fixture(scope="module")
def sim() -> Iterator[SimServer]:
    """A UDK-precision simulator with gravity, shared by a test module."""
    server = SimServer(SimOptions(port=0))
    server.start()
    yield server
    server.stop()


@pytest.fixture(scope="module")
def fast_sim() -> Iterator[SimServer]:
    """A simulator running 4x faster than real time (for settling tests)."""
    server = SimServer(SimOptions(port=0, speed=4.0))
    server.start()
    yield server
    server.stop()
