"""Build the ROS 2 message packages the package index lacks (tf2_msgs, control_msgs, and the
seed's usarsim_inf).

Their interface definitions ship in ``usar_arm/ros/interfaces/<package>/``; this module compiles
them with cmake, ament and rosidl against the installed ros-jazzy wheels into a cache folder
keyed by the definitions' bytes, the ros wheels' versions, the Python version and the
interpreter's prefix (the built libraries carry absolute RUNPATHs into both):

    <cache>/<key>/install/lib/libtf2_msgs__rosidl_*.so   (RUNPATH: $ORIGIN, <venv>/lib)
    <cache>/<key>/install/lib/python3.X/site-packages/tf2_msgs/...

``<cache>`` is ``$USAR_ARM_ROS_CACHE``, else ``$XDG_CACHE_HOME/usar-arm/ros-interfaces`` (or
``~/.cache/usar-arm/ros-interfaces``): beside the description cache, never in the repository.
Builds are serialised by a lock file and moved into place whole, so concurrent processes (test
workers) build once and never see half a build. This module never imports rclpy.
"""

from __future__ import annotations

import ctypes
import fcntl
import hashlib
import importlib.metadata
import importlib.util
import logging
import os
import platform
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from usar_arm.core.errors import UsarArmError

log = logging.getLogger("usar_arm.ros.build")

INTERFACES = Path(__file__).resolve().parent / "interfaces"
"""The interface definitions: ``<package>/{msg,action}/*.{msg,action}``."""

RECIPE = "usar-arm ros interfaces 1"
"""Changes when the build itself changes (CMakeLists, flags): part of the cache key."""

PACKAGES: dict[str, tuple[str, ...]] = {
    "tf2_msgs": ("builtin_interfaces", "geometry_msgs", "std_msgs"),
    "control_msgs": ("action_msgs", "builtin_interfaces", "geometry_msgs", "std_msgs",
                     "trajectory_msgs", "unique_identifier_msgs"),
    "usarsim_inf": ("builtin_interfaces", "std_msgs"),
}
"""Each package built, with the message packages its definitions use (from the wheels)."""

SETUP_COMMAND = "usar-arm ros --setup"
EXTRA_COMMAND = "pip install 'usar-arm[ros]'"
BUILD_TIMEOUT_S = 600.0
"""The longest a package's cmake step may take (s); measured: about 12 s each on 2 cores."""


class RosSetupError(UsarArmError):
    """The ROS 2 extra or its message build is missing or failed; the message says the fix."""

    exit_code = 69  # sysexits EX_UNAVAILABLE, like an unreachable simulator


@dataclass(frozen=True)
class BuiltInterfaces:
    """Where a build of the interfaces lives.

    Attributes:
        root: the cache entry. python_path: the folder to put on ``sys.path``.
        lib: the folder of the built shared libraries.
    """

    root: Path
    python_path: Path
    lib: Path


def cache_root() -> Path:
    """The folder that holds the builds (see the module docstring)."""
    if os.environ.get("USAR_ARM_ROS_CACHE"):
        return Path(os.environ["USAR_ARM_ROS_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "usar-arm" / "ros-interfaces"


def ros_extra_installed() -> bool:
    """Whether rclpy (the ``ros`` extra) can be imported in this interpreter."""
    return importlib.util.find_spec("rclpy") is not None


def require_ros_extra() -> None:
    """Raise :class:`RosSetupError` naming the install command when the extra is missing."""
    if not ros_extra_installed():
        raise RosSetupError(f"the ROS 2 extra is not installed (no rclpy): run "
                            f"`{EXTRA_COMMAND}`, then `{SETUP_COMMAND}`")


def interface_files() -> list[Path]:
    """Every definition file, sorted (relative order is part of the key)."""
    return sorted(p for p in INTERFACES.rglob("*") if p.suffix in (".msg", ".action"))


def cache_key() -> str:
    """A key of everything a build depends on: definitions, ros wheel versions, Python."""
    h = hashlib.sha256(RECIPE.encode())
    for path in interface_files():
        h.update(str(path.relative_to(INTERFACES)).encode() + b"\0" + path.read_bytes())
    versions = sorted(f"{d.metadata['Name']}=={d.version}"
                      for d in importlib.metadata.distributions()
                      if (d.metadata["Name"] or "").lower().replace("_", "-").startswith("ros-"))
    h.update("\n".join(versions).encode())
    h.update(f"{sys.version}|{platform.machine()}|{sys.prefix}".encode())
    return h.hexdigest()[:20]


def _layout(root: Path) -> BuiltInterfaces | None:
    """The build at ``root`` when complete (its marker file exists), else None."""
    if not (root / "COMPLETE").is_file():
        return None
    found = sorted((root / "install").glob("**/site-packages/tf2_msgs/__init__.py"))
    if not found:
        return None
    return BuiltInterfaces(root, found[0].parent.parent, root / "install" / "lib")


def built() -> BuiltInterfaces | None:
    """The build matching this interpreter, when it exists."""
    return _layout(cache_root() / cache_key())


def ensure_importable() -> BuiltInterfaces:
    """Put the built packages on ``sys.path`` and load their libraries (they find each other
    and the wheels' libraries by RUNPATH).

    Raises:
        RosSetupError: the extra is missing, or the messages were not built for it.
    """
    require_ros_extra()
    entry = built()
    if entry is None:
        raise RosSetupError(f"the ROS 2 message packages {', '.join(PACKAGES)} are not built "
                            f"for this Python and ros wheels: run `{SETUP_COMMAND}` (once, "
                            "about 30 s)")
    if str(entry.python_path) not in sys.path:
        sys.path.insert(0, str(entry.python_path))
    # rmw loads a package's type support by its bare library name (dlopen from the wheels'
    # libraries, whose search path does not hold the cache): load each one first, so that the
    # loader finds it among the loaded libraries by its soname.
    for library in sorted(entry.lib.glob("lib*.so")):
        ctypes.CDLL(str(library), mode=ctypes.RTLD_GLOBAL)
    return entry


def _compiler() -> str:
    """The C++ compiler cmake will use (``$CXX``, else c++/g++/clang++)."""
    for name in (os.environ.get("CXX"), "c++", "g++", "clang++"):
        if name and shutil.which(name):
            return str(shutil.which(name))
    raise RosSetupError("no C/C++ compiler found (looked for $CXX, c++, g++, clang++): the "
                        "ROS 2 message build needs one, e.g. `apt-get install g++`")


def _cmake() -> str:
    """cmake from this interpreter's scripts folder (the wheel), else the system's."""
    local = Path(sysconfig.get_path("scripts")) / "cmake"
    found = str(local) if local.is_file() else shutil.which("cmake")
    if not found:
        raise RosSetupError("no cmake found: `pip install cmake` (the ros extra pulls it)")
    return found


def setup(force: bool = False) -> BuiltInterfaces:
    """Build the interfaces into the cache unless a matching build exists; returns it.

    Raises:
        RosSetupError: the extra, a compiler or cmake is missing, or a build step failed
            (the message quotes the end of its log).
    """
    require_ros_extra()
    root = cache_root()
    key = cache_key()
    root.mkdir(parents=True, exist_ok=True)
    with open(root / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # a second process waits here, then finds the build
        entry = _layout(root / key)
        if entry is not None and not force:
            return entry
        compiler = _compiler()
        work = Path(tempfile.mkdtemp(prefix=f"{key}.", dir=root))
        try:
            started = time.perf_counter()
            for name, deps in PACKAGES.items():
                _build_package(name, deps, work, compiler)
            (work / "COMPLETE").write_text(f"{RECIPE}\nbuilt in "
                                           f"{time.perf_counter() - started:.1f} s\n")
            shutil.rmtree(root / key, ignore_errors=True)
            os.replace(work, root / key)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        entry = _layout(root / key)
        if entry is None:
            raise RosSetupError(f"the message build in {root / key} left no tf2_msgs package")
        return entry


def _build_package(name: str, deps: tuple[str, ...], work: Path, compiler: str) -> None:
    """Configure, build and install one message package into ``work/install``."""
    source = work / "src" / name
    shutil.copytree(INTERFACES / name, source)
    files = sorted(str(p.relative_to(source)) for p in source.rglob("*")
                   if p.suffix in (".msg", ".action"))
    (source / "package.xml").write_text(_package_xml(name, deps))
    (source / "CMakeLists.txt").write_text(_cmakelists(name, deps, files))
    install = work / "install"
    build = work / "build" / name
    import numpy  # the wheels' Python type support compiles against its headers

    env = {**os.environ, "AMENT_PREFIX_PATH": sys.prefix, "CMAKE_PREFIX_PATH": sys.prefix,
           "CXX": compiler, "PATH": f"{Path(sys.executable).parent}{os.pathsep}"
                                    f"{os.environ.get('PATH', '')}"}
    python_includes = f"{sysconfig.get_paths()['include']};{numpy.get_include()}"
    configure = [_cmake(), "-S", str(source), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
                 f"-DCMAKE_INSTALL_PREFIX={install}", f"-DPython3_EXECUTABLE={sys.executable}",
                 f"-DUSAR_PYTHON_INCLUDES={python_includes}", "-DBUILD_TESTING=OFF",
                 "-DCMAKE_POLICY_VERSION_MINIMUM=3.5",
                 # Relative to each library (lib/ and lib/python3.X/site-packages/<pkg>/), so
                 # the finished build can move into place; then the wheels' libraries.
                 f"-DCMAKE_INSTALL_RPATH=$ORIGIN;$ORIGIN/../../..;{Path(sys.prefix) / 'lib'}",
                 "-DCMAKE_BUILD_WITH_INSTALL_RPATH=ON"]
    jobs = str(max(1, min(os.cpu_count() or 1, 4)))
    for step in (configure, [_cmake(), "--build", str(build), "-j", jobs],
                 [_cmake(), "--install", str(build)]):
        log.info("%s: %s", name, " ".join(step))
        try:
            done = subprocess.run(step, env=env, capture_output=True, text=True,
                                  timeout=BUILD_TIMEOUT_S, check=False)
        except subprocess.TimeoutExpired as exc:
            raise RosSetupError(f"building {name}: `{' '.join(step[:2])}` took longer than "
                                f"{BUILD_TIMEOUT_S:.0f} s") from exc
        if done.returncode != 0:
            tail = (done.stdout + done.stderr).strip().splitlines()[-25:]
            raise RosSetupError(f"building {name} failed (exit {done.returncode}) at "
                                f"`{' '.join(step[:3])}`:\n" + "\n".join(tail))


def _package_xml(name: str, deps: tuple[str, ...]) -> str:
    """A minimal format-3 package manifest (what ament_package reads)."""
    depends = "".join(f"  <depend>{d}</depend>\n" for d in deps)
    return (f'<?xml version="1.0"?>\n<package format="3">\n  <name>{name}</name>\n'
            f"  <version>0.0.0</version>\n  <description>{name} built by usar-arm from its "
            "interface definitions</description>\n  <maintainer email=\"none@example.com\">"
            "usar-arm</maintainer>\n  <license>Apache-2.0</license>\n"
            "  <buildtool_depend>ament_cmake</buildtool_depend>\n"
            "  <buildtool_depend>rosidl_default_generators</buildtool_depend>\n"
            f"{depends}  <exec_depend>rosidl_default_runtime</exec_depend>\n"
            "  <member_of_group>rosidl_interface_packages</member_of_group>\n"
            "  <export><build_type>ament_cmake</build_type></export>\n</package>\n")


def _cmakelists(name: str, deps: tuple[str, ...], files: list[str]) -> str:
    """The package's CMakeLists: generate the interfaces, then point the wheels' imported
    Python targets at this machine's Python and numpy headers (the wheels carry the include
    paths of the machine that built them, which cmake refuses)."""
    finds = "".join(f"find_package({d} REQUIRED)\n" for d in deps)
    return (f"cmake_minimum_required(VERSION 3.16)\nproject({name})\n"
            "find_package(ament_cmake REQUIRED)\n"
            "find_package(rosidl_default_generators REQUIRED)\n" + finds +
            f"rosidl_generate_interfaces(${{PROJECT_NAME}} {' '.join(files)}\n"
            f"  DEPENDENCIES {' '.join(deps)})\n"
            "get_property(_imported DIRECTORY PROPERTY IMPORTED_TARGETS)\n"
            "foreach(_target IN LISTS _imported)\n"
            "  get_target_property(_inc ${_target} INTERFACE_INCLUDE_DIRECTORIES)\n"
            "  if(_inc AND NOT EXISTS \"${_inc}\" AND _inc MATCHES \"/opt/python\")\n"
            "    set_target_properties(${_target} PROPERTIES\n"
            "      INTERFACE_INCLUDE_DIRECTORIES \"${USAR_PYTHON_INCLUDES}\")\n"
            "  endif()\n"
            "endforeach()\n"
            "ament_export_dependencies(rosidl_default_runtime)\n"
            "ament_package()\n")
