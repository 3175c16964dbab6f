"""Shared fixtures: simulators on free loopback ports, and a description cache of each test
module's own."""

from __future__ import annotations

import logging
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from usar_arm.sim.server import SimOptions, SimServer


@pytest.fixture(scope="module", autouse=True)
def _own_description_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """Every test module starts from an empty description cache (``USAR_ARM_CACHE``), so that
    no result depends on what the machine's cache holds (an arm calibrated there comes
    calibrated to every ``Arm.connect``), nor on the modules run before it; a test that needs
    another cache still sets its own."""
    path = tmp_path_factory.mktemp("usar-arm-cache")
    patch = pytest.MonkeyPatch()
    patch.setenv("USAR_ARM_CACHE", str(path))
    yield path
    patch.undo()


@pytest.fixture
def ctrl_c_reaches_children() -> Iterator[None]:
    """Commands started by the test act on SIGINT as at a terminal, where a user's Ctrl-C
    reaches them. A non-interactive shell starts a background job (``make test &`` in a
    script, ``nohup ... &``) with SIGINT ignored, and an ignored signal stays ignored through
    fork and exec, so Python would never raise KeyboardInterrupt in the command: the Ctrl-C
    tests failed in every run of a campaign started that way. While the test runs, this
    process catches SIGINT (Python's own handler), which exec resets to the default in the
    children."""
    previous = signal.getsignal(signal.SIGINT)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


@pytest.fixture(autouse=True)
def _root_logging_restored() -> Iterator[None]:
    """A command run in-process (``main([...])``) points the root logger at the test's captured
    stderr, which pytest closes after the test; a server thread of a later test logging there
    printed "--- Logging error ---" tracebacks into the run. Each test leaves the root logger's
    handlers and level as it found them."""
    root = logging.getLogger()
    handlers, level = list(root.handlers), root.level
    yield
    for h in root.handlers:
        if h not in handlers:
            root.removeHandler(h)
    for h in handlers:
        if h not in root.handlers:
            root.addHandler(h)
    root.setLevel(level)


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


@pytest.fixture(autouse=True)
def _package_loggers_enabled() -> Iterator[None]:
    """A library configuring logging in this process (``logging.config.dictConfig`` disables
    every logger that exists then, unless told not to) must not silence usar-arm's own for the
    tests that read what it logged: two tests of the WorldController's logged refusals found
    nothing in the full suite, and passed alone. Each test starts with usar-arm's loggers
    enabled and propagating to the root (where pytest's capture listens)."""
    logging.disable(logging.NOTSET)
    for name, found in list(logging.root.manager.loggerDict.items()):
        if name.startswith("usar_arm") and isinstance(found, logging.Logger):
            found.disabled = False
            found.propagate = True
    yield
