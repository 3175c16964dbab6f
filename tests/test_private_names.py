"""What one module of usar_arm needs from another is that module's public surface: no module
imports another's underscore-private names, nor reads them through the module (``m._name``). A
module that needs another's private helper is a sign of one idea cut in two (issue 39: the
closed forms shared their vector maths that way, the reach view took the replay's page parts).
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

ALLOWED: set[tuple[str, str]] = set()


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _module_of(path: Path, root: Path) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def private_uses(root: Path) -> list[tuple[str, str, int]]:
    """(file, module.name, line) of every private name of a usar_arm module that another
    module of ``root/usar_arm`` imports or reads through the module."""
    found = []
    for path in sorted((root / "usar_arm").rglob("*.py")):
        here, tree = _module_of(path, root), ast.parse(path.read_text())
        modules: dict[str, str] = {}  # local name -> usar_arm module it is bound to
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for alias in node.names:
                    if alias.name.startswith("usar_arm.") and alias.asname:
                        modules[alias.asname] = alias.name
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("usar_arm"):
                for alias in node.names:
                    home = f"{node.module}.{alias.name}"
                    if _private(alias.name) and node.module != here:
                        found.append((str(path.relative_to(root)), home, node.lineno))
                    elif (root / Path(*home.split("."))).with_suffix(".py").is_file():
                        modules[alias.asname or alias.name] = home
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and _private(node.attr)
                    and isinstance(node.value, ast.Name) and node.value.id in modules
                    and modules[node.value.id] != here):
                found.append((str(path.relative_to(root)),
                              f"{modules[node.value.id]}.{node.attr}", node.lineno))
    return found


def test_no_module_uses_another_modules_private_names() -> None:
    found = [f"{file}:{line}: {name}" for file, name, line in private_uses(ROOT)
             if (file, name) not in ALLOWED]
    assert found == [], "private names used across modules:\n" + "\n".join(found)


def test_every_allowed_use_still_exists() -> None:
    # (so that the allow-list empties as the uses go, and cannot hide a new one)
    uses = {(file, name) for file, name, _ in private_uses(ROOT)}
    assert ALLOWED <= uses, f"allowed but gone, remove from ALLOWED: {sorted(ALLOWED - uses)}"


def test_the_scan_sees_an_import_and_a_read_through_the_module(tmp_path: Path) -> None:
    package = tmp_path / "usar_arm" / "x"
    package.mkdir(parents=True)
    (package / "a.py").write_text("def _helper() -> None: ...\n")
    (package / "b.py").write_text("from usar_arm.x.a import _helper\n")
    (package / "c.py").write_text("from usar_arm.x import a\n\na._helper()\n")
    (package / "d.py").write_text("import usar_arm.x.a as m\n\nm._helper()\n")
    (package / "e.py").write_text("def _own() -> None: ...\n\n_own()\n")
    assert sorted((f, n) for f, n, _ in private_uses(tmp_path)) == [
        ("usar_arm/x/b.py", "usar_arm.x.a._helper"), ("usar_arm/x/c.py", "usar_arm.x.a._helper"),
        ("usar_arm/x/d.py", "usar_arm.x.a._helper")]
