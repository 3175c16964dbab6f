"""A griffe extension (mkdocs.yml, ``tools/docs_hooks.py``): a package's public names, for the
API reference, are those its ``if TYPE_CHECKING:`` block lists, read by the same function that
gives the package its ``__all__`` at run time (:func:`usar_arm.core.lazy.public_names`). griffe
reads ``__all__`` only from a literal; the package computes it from that one list."""

from __future__ import annotations

from typing import Any

import griffe

from usar_arm.core.lazy import public_names


class PublicNames(griffe.Extension):
    """Sets each ``usar_arm`` package's exports from its TYPE_CHECKING block."""

    def on_module_members(self, *, mod: griffe.Module, **kwargs: Any) -> None:
        """Give a package of ``usar_arm`` (its ``__init__.py``) the names its block lists."""
        if not mod.is_init_module or not mod.path.startswith("usar_arm") or mod.filepath is None:
            return
        source = mod.filepath.read_text(encoding="utf-8")  # type: ignore[union-attr]
        mod.exports = list(public_names(mod.path, source))
