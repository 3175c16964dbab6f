"""Each subpackage declares its public surface in ``__all__``: every name listed resolves, the
package's lazy map lists exactly those names, and importing every package loads none of the
heavy libraries (the names are imported from their modules on first use)."""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "usar_arm"
PACKAGES = ["usar_arm", *sorted(f"usar_arm.{p.parent.name}" for p in PACKAGE.glob("*/__init__.py"))]
HEAVY = ("pinocchio", "fcl", "ompl", "ruckig", "mujoco", "numba", "ray", "scipy", "matplotlib")


@pytest.mark.parametrize("name", PACKAGES)
def test_every_public_name_resolves(name: str) -> None:
    package = importlib.import_module(name)
    public = package.__all__
    assert public, f"{name} declares no public name"
    assert len(set(public)) == len(public), f"{name}.__all__ repeats a name"
    homes = getattr(package, "_HOMES", None)
    if homes is not None:
        listed = [n for names in homes.values() for n in names]
        assert sorted(listed) == sorted(public), f"{name}: _HOMES and __all__ differ"
    for attr in public:
        assert getattr(package, attr) is not None, f"{name}.{attr}"
    with pytest.raises(AttributeError, match="no attribute 'no_such_name'"):
        package.no_such_name  # noqa: B018


def test_importing_every_package_loads_no_heavy_library() -> None:
    code = (f"import sys\nfor p in {PACKAGES!r}: __import__(p)\n"
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)
    assert done.stdout.strip() == "", f"loaded by importing the packages: {done.stdout}"
