"""MkDocs hooks of ``make docs`` (mkdocs.yml ``hooks``): every public name of the package must
have a docstring, and every cross-reference of a docstring must name an object
(``tools/griffe_roles.py``), or the strict build fails; each API page ends with its package's
modules, each with its docstring, so that a reference to a module has a place to link to.

Public: each name ``usar_arm`` and each of its subpackages list (their ``__all__``: the
TYPE_CHECKING block, ``tools/griffe_public.py``), and the public
methods and properties of those that are classes (mkdocstrings renders these; without a
docstring it would leave them out silently). Read statically by griffe, as mkdocstrings reads
them: nothing is imported. Run alone, ``python tools/docs_hooks.py`` prints what is missing and
exits 1 if anything is.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path
from typing import Any

import griffe

sys.path.insert(0, str(Path(__file__).resolve().parent))
from griffe_public import PublicNames

ROOT = Path(__file__).resolve().parents[1]
log = logging.getLogger("mkdocs.hooks.docstrings")


def _documented(obj: Any) -> bool:
    return obj.docstring is not None and bool(obj.docstring.value.strip())


def _inherits_doc(cls: Any, name: str) -> bool:
    """A method that overrides a documented one of a base class has that docstring (as
    ``inspect.getdoc`` reads it): an error's ``message()`` says what its base's says."""
    for base in cls.mro():
        found = base.members.get(name)
        if found is not None and not found.is_alias and _documented(found):
            return True
    return False


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
                            for m in _members(target)
                            if not _documented(m) and not _inherits_doc(target, m.name)]
    return missing


def on_pre_build(config: Any) -> None:
    """Warn (an error under ``mkdocs build --strict``) for every public name lacking a
    docstring."""
    for line in missing_docstrings():
        log.warning("public name without a docstring: %s", line)


def modules_section(package: str, root: Path = ROOT) -> str:
    """The markdown that renders each module of ``usar_arm.<package>`` with its docstring
    alone (its public names are on the page above)."""
    folder = root / "usar_arm" / package
    names = sorted(p.stem for p in folder.glob("*.py") if p.stem != "__init__")
    names += sorted(p.parent.name for p in folder.glob("*/__init__.py"))
    paths = [f"usar_arm.{package}.{name}" for name in names]
    if package == "cli":  # (the executable, python -m usar_arm, beside the command line)
        paths.append("usar_arm.__main__")
    blocks = [f"::: {path}\n    options:\n      members: false\n"
              f"      show_root_heading: true\n      heading_level: 3\n" for path in paths]
    return "\n\n## Modules\n\n" + "\n".join(blocks) if blocks else ""


def on_page_markdown(markdown: str, page: Any, **_: Any) -> str:
    """End each API page (``api/<package>.md``) with its package's modules."""
    source = Path(page.file.src_path)
    if source.parent.name == "api":
        return markdown + modules_section(source.stem)
    return markdown


def on_post_build(config: Any) -> None:
    """Warn (an error under ``--strict``) for every cross-reference that names no object."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from griffe_roles import UNRESOLVED

    for line in dict.fromkeys(UNRESOLVED):
        log.warning("cross-reference to nothing: %s", line)


if __name__ == "__main__":
    found = missing_docstrings()
    print("\n".join(found) or "every public name has a docstring")
    sys.exit(1 if found else 0)
