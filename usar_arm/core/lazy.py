"""A package's public names, written once and imported from their modules when first asked for
(PEP 562).

A subpackage's ``__init__.py`` lists its public surface in one place: the block under
``if TYPE_CHECKING:``, one ``from usar_arm.<package>.<module> import Name as Name`` per name (the
form type checkers read as a re-export). Type checkers and editors read that block; at run time
it is never executed: :func:`exports` reads it from the file and gives the package its
``__getattr__``, ``__dir__`` and ``__all__``, so importing the package loads none of those modules
and a process that needs one layer (a workspace worker, ``usar-arm sim``, ``usar-arm --help``)
does not pay for Pinocchio, FCL, OMPL or the compiled kernels it never touches. The
documentation site reads the same block (``tools/griffe_public.py``).
"""

from __future__ import annotations

import ast
import importlib
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["exports", "public_names"]


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def public_names(package: str, source: str) -> dict[str, str]:
    """Each public name of ``package`` and the module that defines it (``{"Robot":
    "usar_arm.planning.robot"}``), in the order listed, read from the ``if TYPE_CHECKING:`` block
    of the package's ``__init__.py`` text ``source``.

    Raises:
        ImportError: the block is missing, holds anything but ``from <package>.<module> import
            Name as Name`` statements, or lists a name twice (the message says which line).
    """
    blocks = [node for node in ast.parse(source).body
              if isinstance(node, ast.If) and _is_type_checking(node.test)]
    if len(blocks) != 1:
        raise ImportError(f"{package}: expected one 'if TYPE_CHECKING:' block listing the "
                          f"public names, found {len(blocks)}")
    names: dict[str, str] = {}
    for statement in blocks[0].body:
        module = statement.module if isinstance(statement, ast.ImportFrom) else None
        if (not isinstance(statement, ast.ImportFrom) or statement.level or module is None
                or not module.startswith(f"{package}.")):
            raise ImportError(f"{package}, line {statement.lineno}: the TYPE_CHECKING block "
                              f"holds only 'from {package}.<module> import Name as Name'")
        for alias in statement.names:
            if alias.asname != alias.name or alias.name in names:
                problem = "listed twice" if alias.name in names else (
                    f"expected 'import {alias.name} as {alias.name}' (a re-export)")
                raise ImportError(f"{package}, line {statement.lineno}: {alias.name}: {problem}")
            names[alias.name] = module
    return names


def exports(package: str, init_file: str) -> tuple[Callable[[str], Any], Callable[[], list[str]],
                                                     list[str]]:
    """The module-level ``__getattr__``, ``__dir__`` and ``__all__`` of ``package``, whose
    ``__init__.py`` is ``init_file`` (both as the package passes them: ``__name__``,
    ``__file__``). A public name (:func:`public_names`) is imported from its module on first use;
    any other name raises :class:`AttributeError`, as a missing attribute does."""
    where = public_names(package, Path(init_file).read_text(encoding="utf-8"))

    def __getattr__(name: str) -> Any:
        home = where.get(name)
        if home is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(home), name)

    def __dir__() -> list[str]:
        return sorted(set(where) | {n for n in vars(importlib.import_module(package))})

    return __getattr__, __dir__, list(where)
