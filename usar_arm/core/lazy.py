"""A package's public names, imported from their modules when first asked for (PEP 562).

Each subpackage lists its public surface in ``__all__`` and maps every name to the module that
defines it. Importing the package loads none of those modules: a process that needs one layer
(a workspace worker, ``usar-arm sim``, ``usar-arm --help``) does not pay for Pinocchio, FCL,
OMPL or the compiled kernels it never touches.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def exports(package: str, homes: Mapping[str, tuple[str, ...]]) -> Callable[[str], Any]:
    """The module-level ``__getattr__`` of ``package``: a name of ``homes`` (module below
    ``package`` -> the names it defines, e.g. ``{"robot": ("Robot",)}``) is imported from its
    module on first use; any other name raises :class:`AttributeError`, as a missing attribute
    does."""
    where = {name: module for module, names in homes.items() for name in names}

    def __getattr__(name: str) -> Any:
        home = where.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{home}"), name)

    return __getattr__
