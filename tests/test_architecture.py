"""The dependency rules of docs/architecture.md ("Layers and their rules"), checked by reading
every module's imports."""

from __future__ import annotations

import ast
import sys
from collections import defaultdict
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "usar_arm"

# Layer of each module: the first path component below usar_arm (docs/architecture.md draws
# the same table). A layer may import itself and the layers named here, nothing else.
LOWER = {"usarsim", "sim", "discover", "urdf", "planning", "control", "export", "calibrate",
         "workspace", "description"}
ALLOWED: dict[str, set[str]] = {
    "core": set(),
    "usarsim": {"core"},
    "sim": {"usarsim", "core"},
    "discover": {"usarsim", "core"},
    "urdf": {"core"},
    "planning": {"urdf", "core"},
    "control": {"usarsim", "planning", "core"},
    "export": {"control", "planning", "urdf", "core"},
    "calibrate": {"discover", "planning", "control", "urdf", "core"},
    "workspace": {"planning", "control", "core"},
    "description": {"discover", "urdf", "planning", "sim", "usarsim", "core"},
    "arm": LOWER | {"core"},
    # The live ROS 2 node: built on the public facade (`from usar_arm import Arm`, as the CLI
    # is) and the layers below it; it never starts the simulator itself.
    "ros": {"Arm", "arm", "description", "usarsim", "control", "planning", "urdf", "discover",
            "core"},
}
# The command line and the package's entry points string every layer together.
ENTRY_POINTS = {"cli", "__init__", "__main__"}
THIRD_PARTY_LIMITS = {"numpy", "yaml"}  # core: numpy, and PyYAML in yamlio
HEAVY = {"pinocchio": 1, "fcl": 1, "ompl": 1, "ruckig": 1, "mujoco": 1, "numba": 1, "ray": 1,
         "rclpy": 1, "rospy": 1, "yourdfpy": 1, "trimesh": 1}
ROS_MESSAGES = {"tf2_msgs", "control_msgs", "std_msgs", "sensor_msgs", "geometry_msgs",
                "trajectory_msgs", "builtin_interfaces", "rosgraph_msgs", "action_msgs",
                "unique_identifier_msgs", "nav_msgs", "visualization_msgs"}
"""ROS message packages (ROS 2's wheels and usar-arm's builds; ROS 1's of the same names from
Debian and the generated control_msgs): only the two transport modules import them."""
ROS1_ONLY = {"rospy", "actionlib", "actionlib_msgs", "rosgraph", "genpy", "genmsg"}
"""ROS 1's client library and tools (Debian's): only the ROS 1 transport (and genpy, the
generation it runs at setup) imports them."""


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
    if layer in ENTRY_POINTS:
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


@pytest.mark.parametrize("path", sorted((PACKAGE / "core").glob("*.py")), ids=lambda p: p.stem)
def test_the_core_modules_use_numpy_and_the_standard_library_only(path: Path) -> None:
    third = {n.split(".")[0] for n in _imports(path) if not n.startswith("usar_arm")}
    assert third - set(sys.stdlib_module_names) <= THIRD_PARTY_LIMITS


def test_each_heavy_library_is_imported_by_exactly_one_module() -> None:
    users: dict[str, list[str]] = defaultdict(list)
    for module, path in _modules():
        for name in _imports(path):
            root = name.split(".")[0]
            if root in HEAVY:
                users[root].append(module)
    for lib in HEAVY:
        assert len(set(users[lib])) == 1, f"{lib} is imported by {sorted(set(users[lib]))}"


def test_only_the_description_layer_starts_the_simulator_to_learn_an_arm() -> None:
    """The embedded simulator is a sink: besides its own package, only
    ``description.embedded`` (learning an arm) and the ``sim`` command import it."""
    users = {module for module, path in _modules() if _layer(module) != "sim"
             for name in _imports(path) if name.startswith("usar_arm.sim")}
    assert users == {"description.embedded", "description.accuracy", "cli.sim_cmd"}


def test_every_module_belongs_to_a_layer_with_a_rule() -> None:
    """No loose module at the package's root besides its entry points."""
    loose = {m for m, _ in _modules() if _layer(m) not in ALLOWED and _layer(m) not in ENTRY_POINTS}
    assert loose == set()


def _users(roots: set[str]) -> set[str]:
    return {module for module, path in _modules() for name in _imports(path)
            if name.split(".")[0] in roots}


def test_each_middleware_is_imported_by_its_transport_alone() -> None:
    """One module owns each middleware: rclpy by usar_arm.ros.ros2, rospy and actionlib by
    usar_arm.ros.ros1 (genpy also by ros1_build, which generates control_msgs at setup);
    the message packages by those two. The node logic (node, platform_node) imports none."""
    assert _users({"rclpy"}) == {"ros.ros2"}
    assert _users(ROS_MESSAGES) == {"ros.ros2", "ros.ros1"}, sorted(_users(ROS_MESSAGES))
    assert _users(ROS1_ONLY) == {"ros.ros1", "ros.ros1_build"}, sorted(_users(ROS1_ONLY))


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
