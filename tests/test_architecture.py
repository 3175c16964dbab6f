"""The dependency rules of docs/architecture.md ("Layers and their rules"), checked by reading
every module's imports."""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "usar_arm"

# Layer of each module (the first path component below usar_arm, or the module itself).
UTILITIES = {"errors", "spatial", "yamlio", "fileio", "version"}
ALLOWED: dict[str, set[str]] = {
    "errors": set(),
    "spatial": set(),
    "yamlio": {"errors"},
    "fileio": set(),
    "version": set(),
    "model": {"spatial"},
    "usarsim": {"errors"},
    "sim": {"usarsim", "model"} | UTILITIES,
    "discover": {"usarsim", "model"} | UTILITIES,
    "urdf": {"model"} | UTILITIES,
    "planning": {"urdf", "model"} | UTILITIES,
    "control": {"usarsim", "planning", "model"} | UTILITIES,
    "export": {"control", "planning", "urdf", "model"} | UTILITIES,
    "calibrate": {"discover", "planning", "control", "urdf", "model"} | UTILITIES,
    "workspace": {"planning", "model"} | UTILITIES,
    # The live ROS 2 node: built on the public facade (`from usar_arm import Arm`, as the CLI
    # is) and the layers' own modules; never on the root facade modules (robot, motion...).
    "ros": {"Arm", "usarsim", "control", "planning", "urdf", "model", "discover", "sim"}
           | UTILITIES,
}
# orchestration
FACADES = {"cli", "arm", "cycle", "motion", "description", "embedded", "robot", "calibration",
           "jobs", "batch", "calibration_tour",
           "__init__",
           "__main__"}
THIRD_PARTY_LIMITS = {"numpy"}  # errors, spatial, model: numpy only
HEAVY = {"pinocchio": 1, "fcl": 1, "ompl": 1, "ruckig": 1, "mujoco": 1, "numba": 1, "ray": 1,
         "rclpy": 1}
ROS_MESSAGES = {"tf2_msgs", "control_msgs", "std_msgs", "sensor_msgs", "geometry_msgs",
                "trajectory_msgs", "builtin_interfaces", "rosgraph_msgs", "action_msgs",
                "unique_identifier_msgs", "nav_msgs", "visualization_msgs"}
"""ROS 2 message packages (the wheels' and the two usar-arm builds): only rclpy's module
imports them."""


def _modules() -> list[tuple[str, Path]]:
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).with_suffix("")
        out.append((".".join(rel.parts), path))
    return out


def _imports(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            if node.module == "usar_arm":  # `from usar_arm import x`: the package's x
                names += [f"usar_arm.{a.name}" for a in node.names]
            else:
                names.append(node.module)
    return names


def _layer(module: str) -> str:
    return module.split(".")[0]


@pytest.mark.parametrize(("module", "path"), _modules(), ids=lambda v: str(v))
def test_internal_imports_follow_the_dependency_arrows(module: str, path: Path) -> None:
    layer = _layer(module)
    if layer in FACADES:
        return
    assert layer in ALLOWED, f"{module}: layer '{layer}' has no dependency rule in this test"
    for name in _imports(path):
        if not name.startswith("usar_arm."):
            continue
        target = _layer(name.removeprefix("usar_arm."))
        if target == layer:
            continue
        assert target in ALLOWED[layer], \
            f"{module} imports {name}: {layer} may not depend on {target}"


@pytest.mark.parametrize("module", ["errors", "spatial", "model"])
def test_the_core_modules_use_numpy_only(module: str) -> None:
    third = {n.split(".")[0] for n in _imports(PACKAGE / f"{module}.py")
             if not n.startswith("usar_arm")}
    stdlib = {"__future__", "collections", "dataclasses", "enum", "typing", "math"}
    assert third - stdlib <= THIRD_PARTY_LIMITS | {"numpy"}


def test_each_heavy_library_is_imported_by_exactly_one_module() -> None:
    users: dict[str, list[str]] = defaultdict(list)
    for module, path in _modules():
        for name in _imports(path):
            root = name.split(".")[0]
            if root in HEAVY:
                users[root].append(module)
    for lib in HEAVY:
        assert len(set(users[lib])) == 1, f"{lib} is imported by {sorted(set(users[lib]))}"


def test_ros_messages_are_imported_only_where_rclpy_is() -> None:
    """One module owns ROS 2: rclpy and every message package (usar_arm.ros.node)."""
    users = {module for module, path in _modules() for name in _imports(path)
             if name.split(".")[0] in ROS_MESSAGES | {"rclpy"}}
    assert users == {"ros.node"}, f"ROS 2 is imported by {sorted(users)}"


def test_discovery_never_imports_the_simulator() -> None:
    for module, path in _modules():
        if _layer(module) == "discover":
            assert not any(n.startswith("usar_arm.sim") for n in _imports(path))


OFFLINE_PLAN = """
import sys
from pathlib import Path
from usar_arm import Arm
root = Path(sys.argv[1])
arm = Arm.from_files(root / "robots/generated/KR60.urdf", root / "robots/generated/KR60.srdf")
arm.plan(joints=[0.5, -0.5, 0.3, 0.0, 0.5, 0.0], scene="table")
loaded = sorted(m for m in sys.modules
                if m.split(".")[0] == "mujoco" or m.startswith("usar_arm.sim"))
print("\\n".join(loaded))
"""


def test_offline_planning_never_loads_the_simulator() -> None:
    """`from usar_arm import Arm`, an arm from files and a plan in a scene, in a fresh process:
    neither MuJoCo nor any module of the embedded simulator is imported."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    done = subprocess.run([sys.executable, "-c", OFFLINE_PLAN, str(root)], capture_output=True,
                          text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout.split() == [], f"offline planning imported {done.stdout.split()}"


def test_the_version_comes_from_the_package_metadata() -> None:
    from importlib.metadata import version

    import usar_arm

    assert usar_arm.__version__ == version("usar-arm")
    literal = [p for p in PACKAGE.rglob("*.py") if "__version__ = \"" in p.read_text()
               or ("version(\"usar-arm\")" in p.read_text() and p.name != "version.py")]
    assert literal == [], f"a second version string in {literal}"


def test_the_package_never_imports_tesseract() -> None:
    """Tesseract is a consumer of what usar-arm writes (tests/consumers, bench peers, each in
    its own venv), never a dependency."""
    users = [module for module, path in _modules() for name in _imports(path)
             if name.split(".")[0] in ("tesseract_robotics", "tesseract_robotics_viewer")]
    assert users == []
