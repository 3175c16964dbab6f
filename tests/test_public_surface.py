"""Each subpackage lists its public surface once, in its ``if TYPE_CHECKING:`` block (one
``from usar_arm.<package>.<module> import Name as Name`` per name, usar_arm.core.lazy): every name
listed resolves to the object its module defines, ``__all__`` and ``dir()`` are those names, a
block in any other form is refused with its line, and importing every package loads none of the
heavy libraries (the names are imported from their modules on first use)."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from usar_arm.core.lazy import public_names

PACKAGE = Path(__file__).resolve().parents[1] / "usar_arm"
PACKAGES = ["usar_arm", *sorted(f"usar_arm.{p.parent.name}" for p in PACKAGE.glob("*/__init__.py"))]
HEAVY = ("pinocchio", "fcl", "ompl", "ruckig", "mujoco", "numba", "ray", "scipy", "matplotlib")


@pytest.mark.parametrize("name", PACKAGES)
def test_every_public_name_resolves(name: str) -> None:
    package = importlib.import_module(name)
    public = package.__all__
    assert public, f"{name} declares no public name"
    assert len(set(public)) == len(public), f"{name}.__all__ repeats a name"
    source = Path(package.__file__).read_text()
    homes = public_names(name, source)
    assert list(homes) == public, f"{name}: __all__ is not the TYPE_CHECKING block's names"
    assert set(public) <= set(dir(package)), f"{name}: dir() misses public names"
    for attr, home in homes.items():
        assert getattr(package, attr) is getattr(importlib.import_module(home), attr), \
            f"{name}.{attr}"
    statements = [n for n in ast.parse(source).body
                  if not isinstance(n, (ast.ImportFrom, ast.If, ast.Expr))]
    assert len(statements) == 1, f"{name}: the package does more than list its names"
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        package.no_such_name  # noqa: B018


def test_importing_every_package_loads_no_heavy_library() -> None:
    code = (f"import sys\nfor p in {PACKAGES!r}: __import__(p)\n"
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)
    assert done.stdout.strip() == "", f"loaded by importing the packages: {done.stdout}"


@pytest.mark.parametrize(("block", "problem"), [
    ("    from usar_arm.x.y import A\n", "expected 'import A as A'"),
    ("    from usar_arm.x.y import A as B\n", "expected 'import A as A'"),
    ("    from usar_arm.x.y import A as A\n    from usar_arm.x.z import A as A\n",
     "A: listed twice"),
    ("    from numpy import A as A\n", "line 4: the TYPE_CHECKING block holds only"),
    ("    from .y import A as A\n", "holds only"),
    ("    import usar_arm.x.y\n", "holds only"),
])
def test_a_list_in_another_form_is_refused_with_its_line(block: str, problem: str) -> None:
    source = f'"""Doc."""\nfrom typing import TYPE_CHECKING\nif TYPE_CHECKING:\n{block}'
    with pytest.raises(ImportError, match=problem):
        public_names("usar_arm.x", source)


def test_a_package_without_its_list_is_refused() -> None:
    with pytest.raises(ImportError, match="found 0"):
        public_names("usar_arm.x", '"""Doc."""\n__all__ = ["A"]\n')


def test_the_list_keeps_its_order_and_names_each_home() -> None:
    source = ("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
              "    from usar_arm.x.b import Z as Z\n    from usar_arm.x.a import A as A\n")
    assert public_names("usar_arm.x", source) == {"Z": "usar_arm.x.b", "A": "usar_arm.x.a"}
