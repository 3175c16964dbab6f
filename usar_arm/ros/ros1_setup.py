"""The ROS 1 side's environment: Debian's ROS 1 on Debian's interpreter, with usar-arm beside it.

Debian 12 ships ROS 1 (Noetic-era) for ``/usr/bin/python3`` only, and rospy cannot share an
interpreter with rclpy (the ROS 2 message packages shadow ROS 1's of the same names), so the
ROS 1 node runs in a process of its own: ``usar-arm ros --ros1`` re-executes itself in the
interpreter of a small virtual environment that :func:`setup` makes once (a few seconds):

    <cache>/ros1/<key>/venv/bin/python            Debian's interpreter (a venv of /usr/bin/python3)
    <cache>/ros1/<key>/venv/lib/python3.11/site-packages/
        control_msgs/                             generated from Noetic's definitions (genpy)
        std_msgs -> /usr/lib/python3/dist-packages/std_msgs, ...   (ROS 1's, first)
        usar_arm_ros1_site.py, usar_arm_ros1.pth  then this interpreter's packages (usar-arm,
                                                  Pinocchio, MuJoCo...), then Debian's others
    <cache>/ros1/<key>/share/usarsim/             the ROS 1 package: launch files, RViz configs,
                                                  the usarsim_node executable roslaunch runs
    <cache>/ros1/<key>/setup.bash                 puts that package on ROS_PACKAGE_PATH

The order on ``sys.path`` decides which of two same-named packages wins: Debian's ROS 1 packages
(every message package, rospy's own tools) come first, this interpreter's packages next (their
versions of numpy, cffi, PyYAML...), then the rest of Debian's. Nothing is copied: the ROS 1
interpreter imports the same usar-arm and libraries as this one. ``<cache>`` is the ROS 2
build's (:func:`usar_arm.ros.build.cache_root`); the key covers the definitions, the shipped
package files, both interpreters and this interpreter's packages. This module never imports
rospy.
"""

from __future__ import annotations

import fcntl
import hashlib
import os
import shutil
import site
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from usar_arm.ros.build import RosSetupError, cache_root

SYSTEM_PYTHON = Path("/usr/bin/python3")
DIST_PACKAGES = Path("/usr/lib/python3/dist-packages")
SYSTEM_SITES = (Path("/usr/local/lib/python3.11/dist-packages"), DIST_PACKAGES)
HERE = Path(__file__).resolve().parent
INTERFACES = HERE / "interfaces_ros1"
PACKAGE = HERE / "ros1_package"
"""The ROS 1 package ``usarsim`` as shipped (package.xml, launch/, rviz/)."""
RECIPE = "usar-arm ros1 environment 1"
SETUP_COMMAND = "usar-arm ros --ros1 --setup"

NODE_NEEDS: tuple[tuple[str, str], ...] = (
    ("/usr/bin/python3", "python3"),
    ("/usr/bin/roscore", "ros-core"),
    (f"{DIST_PACKAGES}/rospy", "python3-rospy"),
    (f"{DIST_PACKAGES}/actionlib", "python3-actionlib"),
    (f"{DIST_PACKAGES}/genpy", "python3-genpy"),
    (f"{DIST_PACKAGES}/sensor_msgs", "python3-sensor-msgs"),
    (f"{DIST_PACKAGES}/nav_msgs", "python3-nav-msgs"),
    (f"{DIST_PACKAGES}/trajectory_msgs", "python3-trajectory-msgs"),
    (f"{DIST_PACKAGES}/tf2_msgs", "python3-tf2-msgs"),
    ("/usr/share/std_msgs/msg", "ros-std-msgs"),
    ("/usr/share/geometry_msgs/msg", "ros-geometry-msgs"),
    ("/usr/share/trajectory_msgs/msg", "ros-trajectory-msgs"),
    ("/usr/share/actionlib_msgs/msg", "ros-actionlib-msgs"),
)
"""What the node needs (a path, the Debian package that installs it)."""

TOOLS_NEED: tuple[tuple[str, str], ...] = (
    ("/usr/lib/robot_state_publisher/robot_state_publisher", "ros-robot-state-publisher"),
    ("/usr/bin/rviz", "rviz"),
    ("/usr/bin/rosbag", "python3-rosbag"),
    (f"{DIST_PACKAGES}/tf2_ros", "python3-tf2-ros"),
    ("/usr/lib/tf2_tools/view_frames.py", "tf2-tools"),
    ("/usr/bin/dot", "graphviz"),
    ("/usr/bin/xvfb-run", "xvfb"),
    ("/usr/bin/xauth", "xauth"),
    ("/usr/bin/convert", "imagemagick"),
    ("/usr/bin/tesseract", "tesseract-ocr"),
)
"""What the real tools that judge the node need (the tests, the RViz pictures)."""

ROS1_CORE = frozenset({"catkin_pkg", "rospkg", "genpy", "genmsg", "rospy", "rosgraph",
                       "roslib", "actionlib", "rosbag", "tf2_ros", "tf2_py"})
"""Debian packages that win over a same-named package of this interpreter (besides every
message package): ROS 1's own tools and their build helpers."""

_LOADER = '''"""Written by usar-arm (usar_arm/ros/ros1_setup.py): after this venv's own
packages, the packages of the interpreter that made it (without the ROS 2 wheels' re-executing
bootstrapper), then Debian's."""
import os
import site
import sys

ROS1 = True
HOST = {host!r}
SYSTEM = {system!r}
for _d in HOST:
    if os.path.isdir(_d) and _d not in sys.path:
        sys.path.append(_d)
        for _name in sorted(os.listdir(_d)):
            if _name.endswith(".pth") and _name != "ros_wheels_bootstrapper.pth":
                site.addpackage(_d, _name, None)
for _d in SYSTEM:
    if os.path.isdir(_d):
        site.addsitedir(_d)
'''


class Ros1SetupError(RosSetupError):
    """Debian's ROS 1 is missing, or the ROS 1 environment could not be made; the message
    says the fix in one line."""


@dataclass(frozen=True)
class Ros1Environment:
    """A finished ROS 1 environment.

    Attributes:
        root: its folder. python: its interpreter. site: its site-packages.
        share: the folder holding the ``usarsim`` ROS package (for ROS_PACKAGE_PATH).
    """

    root: Path

    @property
    def python(self) -> Path:
        """The interpreter (Debian's, through the venv)."""
        return self.root / "venv" / "bin" / "python"

    @property
    def site(self) -> Path:
        """The venv's site-packages."""
        return self.root / "venv" / "lib" / f"python{_system_version()}" / "site-packages"

    @property
    def share(self) -> Path:
        """The folder of the ``usarsim`` package."""
        return self.root / "share"

    def environ(self, base: dict[str, str] | None = None) -> dict[str, str]:
        """The environment a ROS 1 process runs in: ``base`` (default: this process's) with
        the usarsim package on ROS_PACKAGE_PATH and without the ROS 2 wheels' library folders
        on LD_LIBRARY_PATH (Debian's ROS 1 libraries must not meet them)."""
        env = dict(os.environ if base is None else base)
        kept = [p for p in env.get("LD_LIBRARY_PATH", "").split(os.pathsep)
                if p and not _is_host_library(p)]
        if kept:
            env["LD_LIBRARY_PATH"] = os.pathsep.join(kept)
        else:
            env.pop("LD_LIBRARY_PATH", None)
        paths = [str(self.share)] + [p for p in env.get("ROS_PACKAGE_PATH", "/usr/share")
                                     .split(os.pathsep) if p and p != str(self.share)]
        env["ROS_PACKAGE_PATH"] = os.pathsep.join(paths)
        return env


def _is_host_library(path: str) -> bool:
    """A loader path of the ROS 2 wheels (``ros_*.libs``) or of a virtual environment."""
    return ".libs" in Path(path).name or Path(path, "..", "pyvenv.cfg").resolve().is_file()


def missing(needs: tuple[tuple[str, str], ...] = NODE_NEEDS) -> list[str]:
    """The Debian packages of ``needs`` whose files are absent (sorted, unique)."""
    return sorted({package for path, package in needs if not Path(path).exists()})


def apt_command(needs: tuple[tuple[str, str], ...] = NODE_NEEDS) -> str:
    """The one command that installs every package of ``needs``."""
    packages = sorted({package for _, package in needs})
    return "apt-get install -y --no-install-recommends " + " ".join(packages)


def require_debian(needs: tuple[tuple[str, str], ...] = NODE_NEEDS) -> None:
    """Raise :class:`Ros1SetupError` (one line, with the apt command) when any is missing."""
    absent = missing(needs)
    if absent:
        raise Ros1SetupError(f"Debian's ROS 1 is not installed (missing {', '.join(absent)}): "
                             f"run `{apt_command(needs)}` as root")


def in_ros1() -> bool:
    """Whether this interpreter is a ROS 1 environment's (its loader ran)."""
    return "usar_arm_ros1_site" in sys.modules


def _system_version() -> str:
    return f"{sys.version_info.major}.{sys.version_info.minor}" if in_ros1() else \
        _probe_version()


def _probe_version() -> str:
    """Debian's interpreter's X.Y (read from its standard library folder's name)."""
    real = SYSTEM_PYTHON.resolve().name  # python3.11
    return real.removeprefix("python") if real.startswith("python3.") else "3.11"


def host_sites() -> list[str]:
    """This interpreter's site-packages folders (what the ROS 1 interpreter imports after
    Debian's ROS 1 packages)."""
    sites = list(site.getsitepackages())
    if site.ENABLE_USER_SITE:
        sites.append(site.getusersitepackages())
    return [s for s in sites if Path(s).is_dir() and Path(s) not in SYSTEM_SITES]


def _top_level(folder: Path) -> dict[str, Path]:
    """Importable top-level names of a site folder (packages, modules, extension modules)."""
    out: dict[str, Path] = {}
    for path in sorted(folder.iterdir()) if folder.is_dir() else []:
        if path.is_dir() and (path / "__init__.py").is_file():
            out[path.name] = path
        elif path.suffix in (".py", ".so") and not path.name.startswith("_sandbox"):
            out[path.name.split(".")[0]] = path
    return out


def ros1_first(hosts: list[str]) -> dict[str, Path]:
    """Debian's packages that must come before this interpreter's same-named ones: every ROS 1
    message package (``msg`` inside) and :data:`ROS1_CORE` (name -> Debian's folder)."""
    debian = _top_level(DIST_PACKAGES)
    theirs: set[str] = set()
    for host in hosts:
        theirs |= set(_top_level(Path(host)))
    return {name: path for name, path in debian.items() if name in theirs and path.is_dir()
            and (name in ROS1_CORE or (path / "msg" / "__init__.py").is_file())}


def cache_key(hosts: list[str] | None = None) -> str:
    """A key of what the environment depends on (see the module docstring)."""
    hosts = host_sites() if hosts is None else hosts
    h = hashlib.sha256(RECIPE.encode())
    for folder in (INTERFACES, PACKAGE):
        for path in sorted(p for p in folder.rglob("*") if p.is_file()
                           and "__pycache__" not in p.parts):
            h.update(str(path.relative_to(folder)).encode() + b"\0" + path.read_bytes())
    h.update(f"{SYSTEM_PYTHON.resolve()}|{sys.prefix}|{sys.version}".encode())
    for host in hosts:
        h.update(host.encode() + b"\0" + "\n".join(sorted(_top_level(Path(host)))).encode())
    return h.hexdigest()[:20]


def root() -> Path:
    """The folder holding the environments."""
    return cache_root() / "ros1"


def existing() -> Ros1Environment | None:
    """The finished environment for this interpreter, if there is one."""
    entry = root() / cache_key()
    return Ros1Environment(entry) if (entry / "COMPLETE").is_file() else None


def setup(force: bool = False) -> Ros1Environment:
    """Make the ROS 1 environment unless a finished one exists (idempotent; concurrent callers
    wait for one another and build once).

    Raises:
        Ros1SetupError: Debian's ROS 1 is missing (the message names the apt command), or a
            step failed (the message quotes it).
    """
    require_debian()
    hosts = host_sites()
    key = cache_key(hosts)
    base = root()
    base.mkdir(parents=True, exist_ok=True)
    with open(base / f"{key}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if (base / key / "COMPLETE").is_file() and not force:
            return Ros1Environment(base / key)
        work = Path(tempfile.mkdtemp(prefix=f"{key}.", dir=base))
        try:
            _make(Ros1Environment(work), hosts)
            shutil.rmtree(base / key, ignore_errors=True)
            os.replace(work, base / key)
            final = Ros1Environment(base / key)
            _write_package(final)  # its executable names the interpreter where it now lives
            (final.root / "COMPLETE").write_text(f"{RECIPE}\n")
        finally:
            shutil.rmtree(work, ignore_errors=True)
        return final


def _run(step: list[str], what: str, env: dict[str, str] | None = None) -> None:
    done = subprocess.run(step, capture_output=True, text=True, timeout=300, check=False,
                          env=env)
    if done.returncode != 0:
        tail = (done.stdout + done.stderr).strip().splitlines()[-5:]
        raise Ros1SetupError(f"{what} failed (exit {done.returncode}): " + " | ".join(tail))


def _make(env: Ros1Environment, hosts: list[str]) -> None:
    """Create the venv, its loader and the generated messages (a venv may move: its
    interpreter finds its folder by its pyvenv.cfg)."""
    _run([str(SYSTEM_PYTHON), "-m", "venv", "--without-pip", "--clear", str(env.root / "venv")],
         "making the ROS 1 venv")
    env.site.mkdir(parents=True, exist_ok=True)
    for name, path in ros1_first(hosts).items():
        (env.site / name).symlink_to(path)
    (env.site / "usar_arm_ros1_site.py").write_text(
        _LOADER.format(host=hosts, system=[str(s) for s in SYSTEM_SITES]))
    (env.site / "usar_arm_ros1.pth").write_text("import usar_arm_ros1_site\n")
    bin_dir = Path(sys.executable).parent
    for tool in ("check_urdf",):  # what the library runs from its interpreter's folder
        if (bin_dir / tool).exists():
            (env.python.parent / tool).symlink_to(bin_dir / tool)
    _run([str(env.python), "-m", "usar_arm.ros.ros1_build", str(env.site)],
         "generating control_msgs with genpy", env.environ())


def _write_package(env: Ros1Environment) -> None:
    """The usarsim package: the shipped files, the node executable, and setup.bash."""
    target = env.share / "usarsim"
    shutil.rmtree(target, ignore_errors=True)
    shutil.copytree(PACKAGE, target, ignore=shutil.ignore_patterns("__pycache__", "*.py"))
    node = target / "usarsim_node"
    node.write_text("#!/bin/sh\n# roslaunch's node: usar-arm's ROS 1 node (private parameters "
                    "as in the seed's Table 1).\n"
                    f'exec "{env.python}" -m usar_arm ros --ros1 --ros-args "$@"\n')
    node.chmod(0o755)
    (env.root / "setup.bash").write_text(
        "# usar-arm's ROS 1 environment (usar-arm ros --ros1 --setup): roslaunch finds the\n"
        "# usarsim package (roslaunch usarsim usarsim.launch).\n"
        f'export ROS_PACKAGE_PATH="{env.share}:${{ROS_PACKAGE_PATH:-/usr/share}}"\n')


def reexec_argv(argv: list[str], env: Ros1Environment) -> list[str]:
    """The command line that runs ``usar-arm ARGV`` in the ROS 1 interpreter."""
    return [str(env.python), "-m", "usar_arm", *argv]
