"""The ROS 2 platform stage: `usar-arm ros --robot P3AT` measured from another process by its
own rclpy client, on a private ROS domain on localhost.

    python bench/ros_platform.py [--seconds 20] [--json bench/results/ros_platform.json]

The node talks to a simulator (``usar-arm sim --world rooms``, a process of its own, so that its
physics never holds this process's interpreter) through a TCP relay of this script's own: the
relay forwards every byte both ways and notes the moment each DRIVE line from the node passes
it. Measures:

* /scan: messages per second, ranges per scan, and latency from the SEN line's arrival in the
  node (the message's stamp, without --use-sim-time) to this subscriber (p50, p99, max);
* /cmd_vel -> DRIVE: from publishing a Twist here to its DRIVE line on the wire (the relay),
  each Twist with its own speed so that each DRIVE is matched by its Left value (p50, p99);
* the node's CPU while streaming and driving; the load average and the machine's cores.

Needs the ros extra and its message build (usar-arm ros --setup).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import common
import numpy as np

from usar_arm.ros.build import ensure_importable

ensure_importable()

import rclpy  # noqa: E402
from geometry_msgs.msg import Twist  # noqa: E402
from sensor_msgs.msg import LaserScan  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TICKS = os.sysconf("SC_CLK_TCK")
WHEEL_RADIUS_M = 0.098
"""The P3AT's wheel radius (UDK's P3AT.uc): a straight Twist of v m/s is DRIVE Left v / r."""


class Relay:
    """A TCP relay between the node and the simulator that timestamps the DRIVE lines."""

    def __init__(self, target_port: int):
        self.target_port = target_port
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.drives: list[tuple[float, float]] = []  # (time.time(), Left)
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            upstream = socket.create_connection(("127.0.0.1", self.target_port), timeout=10)
            upstream.settimeout(None)
            threading.Thread(target=self._pump, args=(conn, upstream, True), daemon=True).start()
            threading.Thread(target=self._pump, args=(upstream, conn, False),
                             daemon=True).start()

    def _pump(self, src: socket.socket, dst: socket.socket, watch: bool) -> None:
        pending = b""
        while True:
            try:
                data = src.recv(65536)
            except OSError:
                data = b""
            if not data:
                dst.close()
                return
            now = time.time()
            if watch:
                pending += data
                *lines, pending = pending.split(b"\n")
                for line in lines:
                    if line.startswith(b"DRIVE"):
                        self.drives.append((now, _left(line.decode())))
            dst.sendall(data)


def _left(line: str) -> float:
    start = line.index("{Left ") + len("{Left ")
    return float(line[start:line.index("}", start)])


def _simulator() -> tuple[subprocess.Popen[bytes], int]:
    """``usar-arm sim --world rooms`` on a free port, once it accepts connections."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    sim = subprocess.Popen([sys.executable, "-m", "usar_arm", "sim", "--world", "rooms",
                            "--port", str(port), "-q"], cwd=ROOT)
    end = time.monotonic() + 120
    while time.monotonic() < end:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return sim, port
        except OSError:
            time.sleep(0.2)
    sim.kill()
    raise TimeoutError(f"usar-arm sim did not listen on port {port} within 120 s")


def _proc_cpu(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def _matched(node: Any, pub: Any, seconds: float) -> float | None:
    """Spin until ``pub`` has a subscriber (the node's cmd_vel); the seconds it took, or None."""
    begin = time.monotonic()
    while time.monotonic() - begin < seconds:
        if pub.get_subscription_count() > 0:
            return time.monotonic() - begin
        rclpy.spin_once(node, timeout_sec=0.05)
    return None


def _first_drive(node: Any, pub: Any, relay: Relay, seconds: float) -> float | None:
    """Publish until a DRIVE line reaches the wire (the command path works end to end); the
    seconds it took, or None. Its speeds (0.2 m/s and up) are outside the measured window's."""
    begin, k = time.monotonic(), 0
    while time.monotonic() - begin < seconds:
        k += 1
        msg = Twist()
        msg.linear.x = 0.2 + 1e-4 * k
        pub.publish(msg)
        rclpy.spin_once(node, timeout_sec=0.05)
        if relay.drives:
            return time.monotonic() - begin
    return None


def _cmd_vel(node: Any, relay: Relay, seconds: float) -> dict[str, Any]:
    """Twists at 20 Hz, each with its own small speed; latency to its DRIVE on the wire. The
    window starts once the publisher is matched and a first DRIVE came through: discovery
    is not part of the command path, and is reported apart (``subscriber_matched_s``,
    ``first_drive_s``)."""
    pub = node.create_publisher(Twist, "cmd_vel", 10)
    out: dict[str, Any] = {"sent": 0, "matched": 0, "latency_ms": common.stats([])}
    out["subscriber_matched_s"] = _matched(node, pub, 60.0)
    if out["subscriber_matched_s"] is None:
        return {**out, "failure": "no subscriber on cmd_vel within 60 s"}
    out["first_drive_s"] = _first_drive(node, pub, relay, 30.0)
    if out["first_drive_s"] is None:
        return {**out, "failure": "cmd_vel matched, but no DRIVE line on the wire within 30 s"}
    time.sleep(0.2)
    relay.drives.clear()
    sent: dict[float, float] = {}
    k, end = 0, time.monotonic() + seconds
    while time.monotonic() < end:
        k += 1
        v = (0.01 + 1e-5 * (k % 4000)) * (1 if k % 2 else -1)  # unique, back and forth
        msg = Twist()
        msg.linear.x = v
        sent[round(v / WHEEL_RADIUS_M, 6)] = time.time()
        pub.publish(msg)
        rclpy.spin_once(node, timeout_sec=0.05)
    time.sleep(0.5)
    latencies, unmatched = [], []
    drives = list(relay.drives)
    for at, left in drives:
        begin = sent.pop(round(left, 6), None)
        if begin is not None and at >= begin:
            latencies.append((at - begin) * 1000)
        else:
            unmatched.append(left)
    out.update(sent=k, matched=len(latencies), latency_ms=common.stats(latencies),
               drive_lines=len(drives), unmatched_lefts=unmatched[:5])
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seconds", type=float, default=20.0, help="each window (s)")
    ap.add_argument("--json", type=Path, default=None, help="write the results here")
    ap.add_argument("--domain", type=int, default=101, help="ROS_DOMAIN_ID (default 101)")
    a = ap.parse_args(argv)
    os.environ["ROS_DOMAIN_ID"] = str(a.domain)
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    sim, port = _simulator()
    relay = Relay(port)
    node = subprocess.Popen([sys.executable, "-m", "usar_arm", "ros", "--robot", "P3AT", "-q",
                             "--host", "127.0.0.1", "--port", str(relay.port)], cwd=ROOT)
    rclpy.init()
    probe = rclpy.create_node("usar_arm_bench_platform")
    scans: list[tuple[float, Any]] = []
    probe.create_subscription(LaserScan, "scan", lambda m: scans.append((time.time(), m)), 100)
    doc: dict[str, Any] = {}
    try:
        end = time.monotonic() + 180
        while not scans and time.monotonic() < end:
            rclpy.spin_once(probe, timeout_sec=0.05)
        if not scans:
            raise TimeoutError("no /scan within 180 s of the node's start")
        scans.clear()
        before, t0 = _proc_cpu(node.pid), time.monotonic()
        end = t0 + a.seconds
        while time.monotonic() < end:
            rclpy.spin_once(probe, timeout_sec=0.05)
        idle_cpu = (_proc_cpu(node.pid) - before) / (time.monotonic() - t0)
        stamps = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for _, m in scans])
        received = np.array([t for t, _ in scans])
        scan = {"messages": len(scans), "rate_hz": (len(scans) - 1) / float(np.ptp(stamps)),
                "ranges": sorted({len(m.ranges) for _, m in scans}),
                "latency_ms": common.stats(((received - stamps) * 1000).tolist())}
        before, t0 = _proc_cpu(node.pid), time.monotonic()
        drive = _cmd_vel(probe, relay, a.seconds)
        busy_cpu = (_proc_cpu(node.pid) - before) / (time.monotonic() - t0)
        doc = {"stage": "ros_platform", "scan": scan, "cmd_vel_to_drive": drive,
               "node": {"cpu_streaming_fraction_of_a_core": idle_cpu,
                        "cpu_driving_fraction_of_a_core": busy_cpu},
               "targets": {"scan_latency_p99_ms<=5": (scan["latency_ms"]["p99"] or 1e9) <= 5,
                           "cmd_vel_to_drive_p99_ms<=5": (drive["latency_ms"]["p99"]
                                                          or 1e9) <= 5},
               "load_average_1min_at_end": os.getloadavg()[0], "cpus": os.cpu_count(),
               "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    finally:
        probe.destroy_node()
        rclpy.shutdown()
        node.send_signal(signal.SIGINT)
        code = node.wait(60)
        relay.listener.close()
        sim.send_signal(signal.SIGINT)
        sim.wait(60)
    doc["node_exit_code"] = code
    print(json.dumps(common.plain(doc), indent=1))
    if a.json:
        common.write_json(a.json, doc)
    return 0


if __name__ == "__main__":
    sys.exit(main())
