"""The installed distribution's version: the one version string (from pyproject.toml, through
the package metadata)."""

from __future__ import annotations

from importlib.metadata import version

__version__ = version("usar-arm")
"""The installed usar-arm distribution's version string (PEP 440), e.g. ``"0.1.0"``."""
