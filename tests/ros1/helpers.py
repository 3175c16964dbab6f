"""A roscore of its own per test module, `usar-arm ros --ros1` in a subprocess (started from
this interpreter, so the re-execution into the ROS 1 interpreter is part of every test), and
ROS 1 clients (tests/ros1/client.py, and Debian's tools) in the ROS 1 interpreter. Nothing here
imports rospy: this process runs the ROS 2 wheels."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from usar_arm.ros.ros1_setup import Ros1Environment

CLIENT = Path(__file__).resolve().with_name("client.py")
ROOT = Path(__file__).resolve().parents[2]
STARTUP_TIMEOUT_S = 180.0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Master:
    """A roscore on a free port, its logs in ``folder``; :meth:`env` is a ROS 1 process's
    environment pointing at it."""

    def __init__(self, env: Ros1Environment, folder: Path):
        self.ros1 = env
        self.folder = folder
        self.port = free_port()
        self.uri = f"http://127.0.0.1:{self.port}"
        self._log = open(folder / "roscore.log", "w")
        self.proc = subprocess.Popen(["roscore", "-p", str(self.port)], env=self.env(),
                                     stdout=self._log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=0.5).close()
                return
            except OSError:
                time.sleep(0.1)
        raise RuntimeError(f"roscore did not listen on {self.port} within 30 s")

    def env(self, **extra: str) -> dict[str, str]:
        base = self.ros1.environ()
        return {**base, "ROS_MASTER_URI": self.uri, "ROS_HOSTNAME": "127.0.0.1",
                "ROS_HOME": str(self.folder / "ros_home"), "ROS_LOG_DIR": str(self.folder / "log"),
                **extra}

    def close(self) -> None:
        stop(self.proc, signal.SIGINT)
        self._log.close()


def stop(proc: subprocess.Popen[Any], sig: int = signal.SIGINT, timeout: float = 30.0) -> int:
    """Signal a process, wait for it (kill it after ``timeout``); its exit code."""
    if proc.poll() is None:
        proc.send_signal(sig)
    try:
        return proc.wait(timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        return proc.wait(10)


class Node:
    """`usar-arm ros --ros1 ARGS` (from this interpreter) against ``master``."""

    def __init__(self, master: Master, args: list[str], log: Path, **env: str):
        self.log = log
        self._file = open(log, "w")
        self.proc = subprocess.Popen([sys.executable, "-m", "usar_arm", "ros", "--ros1", *args],
                                     env={**os.environ, "ROS_MASTER_URI": master.uri,
                                          "ROS_HOSTNAME": "127.0.0.1",
                                          "ROS_HOME": str(master.folder / "ros_home"),
                                          "ROS_LOG_DIR": str(master.folder / "log"), **env},
                                     stdout=self._file, stderr=subprocess.STDOUT, cwd=ROOT)

    def text(self) -> str:
        return self.log.read_text()

    def stop(self, sig: int = signal.SIGINT) -> int:
        code = stop(self.proc, sig)
        self._file.close()
        return code


def client(master: Master, *args: str, timeout: float = 300.0) -> Any:
    """Run tests/ros1/client.py ARGS in the ROS 1 interpreter; its JSON answer."""
    done = subprocess.run([str(master.ros1.python), str(CLIENT), *args], env=master.env(),
                          capture_output=True, text=True, timeout=timeout, cwd=ROOT, check=False)
    assert done.returncode == 0, f"client {args[0]} failed ({done.returncode}):\n" \
                                 f"{done.stderr[-4000:]}"
    return json.loads(done.stdout.strip().splitlines()[-1])


def start_client(master: Master, *args: str, log: Path) -> subprocess.Popen[str]:
    """tests/ros1/client.py ARGS in the background (its JSON answer on its stdout)."""
    return subprocess.Popen([str(master.ros1.python), str(CLIENT), *args], env=master.env(),
                            stdout=subprocess.PIPE, stderr=open(log, "w"), text=True, cwd=ROOT)


def answer(proc: subprocess.Popen[str], timeout: float = 300.0) -> Any:
    """The JSON answer of a background client."""
    out, _ = proc.communicate(timeout=timeout)
    assert proc.returncode == 0, f"client failed ({proc.returncode})"
    return json.loads(out.strip().splitlines()[-1])


@contextlib.contextmanager
def session(env: Ros1Environment, folder: Path, args: list[str]
            ) -> Iterator[tuple[Master, Node]]:
    """A roscore and the node; waits for the node's robot_description parameter; the node
    must stop with exit 0 on SIGINT (what roslaunch sends)."""
    master = Master(env, folder)
    node = Node(master, args, folder / "node.log")
    try:
        got = client(master, "description", "--timeout", str(STARTUP_TIMEOUT_S),
                     timeout=STARTUP_TIMEOUT_S + 30)
        assert got["urdf"], node.text()[-3000:]
        yield master, node
    finally:
        code = node.stop()
        master.close()
        assert code == 0, node.text()[-3000:]
