"""RViz (Debian's ROS 1 RViz, under Xvfb with software GL) showing `usar-arm ros --ros1` live:
the KR60 and the P3AT with its laser scan, each through the RViz configuration the ROS 1
package ships. Writes the screenshots (docs/images/rviz-kr60.png, rviz-p3at.png by default) and
records in each PNG what made it (text chunks: the command, the usar-arm commit, the SHA-256 of
the node's URDF and of the RViz configuration).

    python tools/rviz_pictures.py [--out docs/images] [--robots KR60 P3AT]

The picture regeneration calls :func:`render` per robot; the ROS 1 tests call it too and judge
the pixels and RViz's status (tests/ros1/test_rviz.py). Needs Debian's ROS 1 with rviz, xvfb and
imagemagick (usar_arm.ros.ros1_setup.TOOLS_NEED says the apt command).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from PIL import Image
from PIL.PngImagePlugin import PngInfo

ROOT = Path(__file__).resolve().parents[1]
SCREEN = (1280, 800)
CONFIGS = {"KR60": "usarsim_kr60.rviz", "P3AT": "usarsim_p3at.rviz"}
SETTLE_S = {"KR60": 12.0, "P3AT": 14.0}
"""How long RViz draws before the screenshot (s): the model loads, tf and scans arrive."""


@dataclass(frozen=True)
class Picture:
    """A screenshot and what made it: ``png`` (the file), ``urdf`` (the node's description),
    ``config`` (the RViz configuration), ``rviz_log`` (RViz's output), ``joints`` (the joint
    state when it was taken; empty for a robot without joint states)."""

    png: Path
    urdf: str
    config: Path
    rviz_log: str
    joints: tuple[float, ...]


_JOINTS = ("import json, rospy\nfrom sensor_msgs.msg import JointState\n"
           "rospy.init_node('usar_arm_pictures', anonymous=True, disable_signals=True)\n"
           "m = rospy.wait_for_message('/joint_states', JointState, timeout=10)\n"
           "print(json.dumps(list(m.position)))\n")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _stop(proc: subprocess.Popen[bytes], sig: int = signal.SIGINT) -> None:
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


def _xvfb(work: Path) -> tuple[subprocess.Popen[bytes], str]:
    """An Xvfb of the picture's size on a display number it picks itself."""
    read, write = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write), "-screen", "0",
                             f"{SCREEN[0]}x{SCREEN[1]}x24", "-nolisten", "tcp"],
                            pass_fds=(write,), stdout=subprocess.DEVNULL,
                            stderr=open(work / "xvfb.log", "w"))
    os.close(write)
    with os.fdopen(read) as f:
        display = f.readline().strip()
    if not display:
        raise RuntimeError(f"Xvfb did not start: {(work / 'xvfb.log').read_text()[-500:]}")
    return proc, f":{display}"


def _wait_param(python: Path, env: dict[str, str], name: str, timeout: float) -> str:
    code = ("import sys, time, rosgraph\n"
            f"end = time.time() + {timeout}\n"
            "p = rosgraph.Master('/usar_arm_pictures')\n"
            "while True:\n"
            f"    try:\n        print(p.getParam({name!r}), end=''); break\n"
            "    except Exception:\n"
            "        if time.time() > end: sys.exit('no parameter')\n"
            "        time.sleep(0.3)\n")
    done = subprocess.run([str(python), "-c", code], env=env, capture_output=True, text=True,
                          timeout=timeout + 30, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"no {name} parameter within {timeout} s: {done.stderr[-500:]}")
    return done.stdout


def render(robot: str, out: Path, work: Path | None = None) -> Picture:
    """Start roscore, the node (``--robot robot``) and RViz on its shipped configuration
    under Xvfb; screenshot the screen into ``out`` (PNG with the text chunks)."""
    from usar_arm.ros import ros1_setup

    env1 = ros1_setup.setup()
    work = Path(tempfile.mkdtemp(prefix=f"rviz-{robot}-")) if work is None else work
    port = _free_port()
    env = env1.environ({**os.environ, "ROS_MASTER_URI": f"http://127.0.0.1:{port}",
                        "ROS_HOSTNAME": "127.0.0.1", "ROS_HOME": str(work / "ros_home"),
                        "LIBGL_ALWAYS_SOFTWARE": "1"})
    config = env1.share / "usarsim" / "rviz" / CONFIGS[robot]
    procs: list[subprocess.Popen[bytes]] = []
    try:
        procs.append(subprocess.Popen(["roscore", "-p", str(port)], env=env,
                                      stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT))
        time.sleep(1.5)
        procs.append(subprocess.Popen(
            [sys.executable, "-m", "usar_arm", "ros", "--ros1", "--robot", robot, "-v"],
            env={**os.environ, **{k: env[k] for k in ("ROS_MASTER_URI", "ROS_HOSTNAME",
                                                      "ROS_HOME")}},
            stdout=open(work / "node.log", "w"), stderr=subprocess.STDOUT, cwd=ROOT))
        urdf = _wait_param(env1.python, env, "/robot_description", 240.0)
        xvfb, display = _xvfb(work)
        procs.append(xvfb)
        rviz_log = work / "rviz.log"
        rviz = subprocess.Popen(["rviz", "-d", str(config)], env={**env, "DISPLAY": display},
                                stdout=open(rviz_log, "w"), stderr=subprocess.STDOUT)
        procs.append(rviz)
        time.sleep(SETTLE_S[robot])
        joints: tuple[float, ...] = ()
        if robot != "P3AT":  # UDK's P3AT sends no wheel state
            done = subprocess.run([str(env1.python), "-c", _JOINTS], env=env,
                                  capture_output=True, text=True, timeout=60, check=True)
            joints = tuple(json.loads(done.stdout.strip().splitlines()[-1]))
        shot = work / "screen.png"
        subprocess.run(["import", "-display", display, "-window", "root", str(shot)],
                       check=True, timeout=60)
        _write_png(shot, out, robot, urdf, config)
        return Picture(out, urdf, config, rviz_log.read_text(), joints)
    finally:
        for proc in reversed(procs):
            _stop(proc)


def _commit() -> str:
    done = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True,
                          text=True, check=False)
    return done.stdout.strip() or "unknown"


def _write_png(shot: Path, out: Path, robot: str, urdf: str, config: Path) -> None:
    """The screenshot as ``out``, with what made it in its text chunks (written atomically)."""
    info = PngInfo()
    info.add_text("Software", "usar-arm tools/rviz_pictures.py (Debian's ROS 1 RViz, Xvfb)")
    info.add_text("usar-arm:command",
                  f"python tools/rviz_pictures.py --robots {robot}  (usar-arm ros --ros1 "
                  f"--robot {robot}; rviz -d {config.name})")
    info.add_text("usar-arm:inputs", json.dumps({
        "commit": _commit(), "urdf_sha256": hashlib.sha256(urdf.encode()).hexdigest(),
        "rviz_config": config.name,
        "rviz_config_sha256": hashlib.sha256(config.read_bytes()).hexdigest()}))
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".tmp.png")
    with Image.open(shot) as image:
        image.convert("RGB").save(tmp, pnginfo=info, optimize=True)
    os.replace(tmp, out)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    parser.add_argument("--robots", nargs="+", default=list(CONFIGS), choices=list(CONFIGS))
    args = parser.parse_args()
    for robot in args.robots:
        picture = render(robot, args.out / f"rviz-{robot.lower()}.png")
        print(picture.png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
