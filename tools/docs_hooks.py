"""MkDocs hooks of ``make docs`` (mkdocs.yml ``hooks``): every public name of the package must
have a docstring, or the strict build fails; and the docstrings' Sphinx roles
(``:class:`Arm```) show as the code they name.

Public: each name ``usar_arm`` and each of its subpackages list (their ``__all__``: the
TYPE_CHECKING block, ``tools/griffe_public.py``), and the public
methods and properties of those that are classes (mkdocstrings renders these; without a
docstring it would leave them out silently). Read statically by griffe, as mkdocstrings reads
them: nothing is imported. Run alone, ``python tools/docs_hooks.py`` prints what is missing and
exits 1 if anything is.
"""

from __future__ import annotations

import logging
import re
import sys
from pathlib import Path
from typing import Any

import griffe

sys.path.insert(0, str(Path(__file__).resolve().parent))
from griffe_public import PublicNames

ROOT = Path(__file__).resolve().parents[1]
log = logging.getLogger("mkdocs.hooks.docstrings")
ROLE = re.compile(r":(?:class|mod|meth|func|attr|data|exc|obj):(?=<code>)")


def _documented(obj: Any) -> bool:
    return obj.docstring is not None and bool(obj.docstring.value.strip())


def _members(cls: Any) -> list[Any]:
    """The public methods and properties a class defines itself (inherited ones are checked
    where they are defined)."""
    out = []
    for name, member in cls.members.items():
        if name.startswith("_") or member.is_alias:
            continue
        if member.is_function or (member.is_attribute and "property" in member.labels):
            out.append(member)
    return out


def missing_docstrings(root: Path = ROOT) -> list[str]:
    """``package.name`` (or ``package.Class.member``) of every public name without a docstring,
    and of every name in an ``__all__`` that does not resolve."""
    extensions = griffe.load_extensions(PublicNames)
    package = griffe.load("usar_arm", search_paths=[str(root)], resolve_aliases=False,
                          extensions=extensions)
    packages = [package, *(m for n, m in package.members.items()
                           if not m.is_alias and m.is_module and m.is_subpackage)]
    missing = []
    for pkg in packages:
        for name in pkg.exports or []:
            where = f"{pkg.path}.{name}"
            try:
                member = pkg.members[name]
                target = member.final_target if member.is_alias else member
            except (KeyError, griffe.AliasResolutionError, griffe.CyclicAliasError):
                missing.append(f"{where}: listed in __all__ but not found")
                continue
            if not _documented(target):
                missing.append(f"{where} ({target.path}): no docstring")
            if target.is_class:
                missing += [f"{where}.{m.name} ({m.path}): no docstring"
                            for m in _members(target) if not _documented(m)]
    return missing


def on_pre_build(config: Any) -> None:
    """Warn (an error under ``mkdocs build --strict``) for every public name lacking a
    docstring."""
    for line in missing_docstrings():
        log.warning("public name without a docstring: %s", line)


def on_page_content(html: str, **_: Any) -> str:
    """Drop the role of a Sphinx cross-reference, which mkdocstrings leaves as text before the
    code it names."""
    return ROLE.sub("", html)


if __name__ == "__main__":
    found = missing_docstrings()
    print("\n".join(found) or "every public name has a docstring")
    sys.exit(1 if found else 0)
