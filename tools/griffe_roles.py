"""A griffe extension (mkdocs.yml): the docstrings' cross-references become links on the site.

The project writes Google-style docstrings (``Args:``, ``Returns:``, ``Raises:``,
``Attributes:`` sections, which mkdocstrings renders as sections) and names other objects with
Sphinx's roles, the form editors and Sphinx read: ``:class:`~usar_arm.core.errors.IKError```
(shown as ``IKError``), ``:func:`usar_arm.planning.warm_up```, ``:mod:`.cycle``` (relative to the
package), ``:meth:`connect``` (a member of the class at hand). Each role is rewritten, before
rendering, into an autorefs link to the object's full path, resolved in the docstring's own
scope (its class, its module's names and imports, its package). A reference that resolves to
nothing stays code and is listed in :data:`UNRESOLVED`, which ``tools/docs_hooks.py`` turns into
a warning: under ``mkdocs build --strict`` the build fails naming it.
"""

from __future__ import annotations

import builtins
import re
import sys
from typing import Any

import griffe

ROLE = re.compile(r":(?:class|mod|meth|func|attr|data|exc|obj):`(?P<target>[^`]+)`")
UNRESOLVED: list[str] = []
"""``owner: reference`` of every role that resolved to no object (filled while loading)."""


def _lookup(owner: griffe.Object, path: str) -> griffe.Object | griffe.Alias | None:
    try:
        found = owner.modules_collection[path]
        return found.final_target if found.is_alias else found
    except (KeyError, ValueError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return None


EXTERNAL = {*sys.stdlib_module_names, *dir(builtins), "numpy", "np", "matplotlib", "scipy",
            "mujoco", "ompl", "fcl", "pinocchio", "ruckig", "ray", "viser", "yaml", "numba"}
"""First names of references to objects outside usar-arm: shown as code (the site has no
inventory of other projects' documentation)."""


def resolve(owner: griffe.Object, target: str) -> str | None:
    """The full path of the object ``target`` names in ``owner``'s docstring, or None."""
    module = owner if owner.is_module else owner.module
    candidates: list[str] = []
    if target.startswith("."):  # relative to the package (of a module: its parent's)
        package = module if module.is_init_module else module.parent
        candidates.append(f"{package.path if package else ''}{target}")
    else:
        first, _, rest = target.partition(".")
        scopes = [owner] if owner.is_class else []
        scopes += [owner.parent] if owner.parent is not None and owner.parent.is_class else []
        for scope in (*scopes, module):
            try:
                found = scope.resolve(first)
            except (griffe.NameResolutionError, ValueError):
                continue
            candidates.append(f"{found}.{rest}" if rest else found)
        candidates.append(target)
    for path in candidates:
        found = _lookup(owner, path)
        if found is not None:
            return found.path
    for path in candidates:  # a name griffe does not see (``A, B = 0, 1``): its module
        while "." in path:
            path = path.rsplit(".", 1)[0]
            found = _lookup(owner, path)
            if found is not None and path.startswith("usar_arm"):
                return found.path
    return None


def shown_on_the_site(package: griffe.Module) -> set[str]:
    """The full paths the API reference renders: every module (each page ends with its
    package's modules, ``tools/docs_hooks.py``), each public name of a package and the public
    members of those that are classes."""
    shown: set[str] = set()

    def modules(mod: griffe.Module) -> None:
        shown.add(mod.path)
        for member in mod.members.values():
            if not member.is_alias and member.is_module:
                modules(member)  # type: ignore[arg-type]
            if mod.is_init_module and member.name in (mod.exports or ()):
                target = _lookup(mod, member.target_path if member.is_alias else member.path)
                if target is not None and not target.is_alias:
                    shown.add(target.path)
                    shown.update(f"{target.path}.{n}" for n in target.members
                                 if not n.startswith("_"))

    modules(package)
    return shown - {package.path}  # (the package itself has no page: its subpackages do)


def rewrite(owner: griffe.Object, text: str, shown: set[str]) -> str:
    """``text`` with each role turned into an autorefs link (or code, when unresolved). An
    object the site does not render (a module's constant, an internal class) links to the
    nearest that it does: its class, or its module."""
    def link(match: re.Match[str]) -> str:
        target = re.sub(r"\s+", "", match.group("target"))
        titled = re.fullmatch(r"(?P<title>.+)<(?P<target>[^>]+)>", target)
        short = target.startswith("~")
        target = titled.group("target") if titled else target.lstrip("~")
        text = titled.group("title") if titled else (
            target.rsplit(".", 1)[-1] if short else target.lstrip("."))
        path = resolve(owner, target)
        if path is None:
            if target.split(".")[0] not in EXTERNAL and owner.path in shown:
                UNRESOLVED.append(f"{owner.path}: {match.group(0)}")
            return f"`{text}`"
        while path not in shown and "." in path:
            path = path.rsplit(".", 1)[0]
        if path not in shown:
            if owner.path in shown:
                UNRESOLVED.append(f"{owner.path}: {match.group(0)} (not on the site)")
            return f"`{text}`"
        return f"[`{text}`][{path}]"
    return ROLE.sub(link, text)


class SphinxRoles(griffe.Extension):
    """Rewrites every docstring's Sphinx roles into autorefs links once the package is loaded."""

    def on_package(self, *, pkg: griffe.Module, **kwargs: Any) -> None:
        """Rewrite the roles of ``pkg`` and everything in it (aliases are skipped: their
        targets are rewritten where they are defined)."""
        shown = shown_on_the_site(pkg)

        def visit(obj: griffe.Object) -> None:
            if obj.docstring is not None and ":" in obj.docstring.value:
                obj.docstring.value = rewrite(obj, obj.docstring.value, shown)
            for member in obj.members.values():
                if not member.is_alias:
                    visit(member)  # type: ignore[arg-type]

        visit(pkg)
