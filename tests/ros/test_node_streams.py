"""What `usar-arm ros` publishes, read by a real rclpy client in this process while the node
runs in another: the description, joint states (one per ASTA), and a tf tree that equals
forward kinematics."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="the ros extra is not installed: pip install "
                                    "'usar-arm[ros]'")

from sensor_msgs.msg import JointState
from tf2_msgs.msg import TFMessage

from tests.ros.helpers import (
    LATCHED,
    Client,
    NodeProcess,
    domain_id,
)
from usar_arm.planning.kinematics import KinematicModel

ROOT = Path(__file__).resolve().parents[2]
JAZZY_TF_HASH = "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087"


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Client, str, Path]]:
    """A node (fresh description cache) and a client on their own domain; the node must stop
    with exit 0 on SIGTERM."""
    folder = tmp_path_factory.mktemp("ros-streams")
    domain = domain_id()
    node = NodeProcess(domain, ["-v"], folder / "node.log",
                       USAR_ARM_CACHE=str(folder / "cache"))
    client = Client(domain)
    try:
        urdf = client.description()
        yield client, urdf, folder
    finally:
        client.close()
        code = node.stop()
        assert code == 0, node.text()[-3000:]


def test_the_description_is_the_urdf_usar_arm_urdf_writes(
        session: tuple[Client, str, Path]) -> None:
    _, urdf, folder = session
    done = subprocess.run([sys.executable, "-m", "usar_arm", "urdf", "--no-calibrate",
                           "--out-dir", str(folder / "out"), "-q"], capture_output=True,
                          text=True, timeout=300, check=False, cwd=ROOT,
                          env={**__import__("os").environ,
                               "USAR_ARM_CACHE": str(folder / "cache")})
    assert done.returncode == 0, done.stderr[-2000:]
    assert urdf == (folder / "out" / "KR60.urdf").read_text()


def test_joint_states_come_one_per_asta_stamped_in_urdf_names(
        session: tuple[Client, str, Path]) -> None:
    client, _urdf, _ = session
    got = client.collect(JointState, "joint_states", 3.0)
    # The ASTA stream is 10 Hz of simulated time; a loaded machine's simulator runs slower
    # (test_node_world checks one message per ASTA exactly, by simulated time).
    assert len(got) >= 15, f"{len(got)} joint states in 3 s"
    msgs = [m for _, m in got]
    assert all(list(m.name) == [f"joint_a{i}" for i in range(1, 7)] for m in msgs)
    assert all(len(m.position) == 6 and np.all(np.isfinite(m.position)) for m in msgs)
    stamps = np.array([m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 for m in msgs])
    gaps = np.diff(stamps)
    assert np.all(gaps > 0), "stamps must increase"
    assert 0.07 < float(np.median(gaps)) < 0.2, f"median period {np.median(gaps):.3f} s"
    received = np.array([t for t, _ in got])
    assert np.max(np.abs(received - stamps)) < 0.5, "stamps are the time of arrival"


def _compose(edges: dict[str, tuple[str, np.ndarray]], frame: str, root: str) -> np.ndarray:
    out = np.eye(4)
    while frame != root:
        parent, matrix = edges[frame]
        out = matrix @ out
        frame = parent
    return out


def _matrix(t: object) -> np.ndarray:
    tr, q = t.transform.translation, t.transform.rotation  # type: ignore[attr-defined]
    x, y, z, w = q.x, q.y, q.z, q.w
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = r, (tr.x, tr.y, tr.z)
    return out


def test_tf_is_complete_and_equals_forward_kinematics(
        session: tuple[Client, str, Path]) -> None:
    client, urdf, _ = session
    static = client.collect(TFMessage, "tf_static", 10.0, LATCHED, until=bool)
    assert static, "no tf_static"
    states: list[tuple[float, JointState]] = []
    moving: list[tuple[float, TFMessage]] = []

    subs = [client.node.create_subscription(JointState, "joint_states",
                                            lambda m: states.append((time.time(), m)), 100),
            client.node.create_subscription(TFMessage, "tf",
                                            lambda m: moving.append((time.time(), m)), 100)]
    time.sleep(2.0)
    for sub in subs:
        client.node.destroy_subscription(sub)
    edges = {t.child_frame_id: (t.header.frame_id, _matrix(t))
             for t in static[0][1].transforms}
    assert edges["base_link"][0] == "world"
    assert np.allclose(edges["base_link"][1], np.eye(4), atol=0.011), \
        "the KR60 stands at the world's origin (RobotStart1)"
    model = KinematicModel(urdf)
    by_stamp = {(m.header.stamp.sec, m.header.stamp.nanosec): m for _, m in states}
    checked = 0
    for _, msg in moving:
        stamp = msg.transforms[0].header.stamp
        state = by_stamp.get((stamp.sec, stamp.nanosec))
        if state is None:
            continue
        tree = dict(edges)
        tree.update({t.child_frame_id: (t.header.frame_id, _matrix(t)) for t in msg.transforms})
        assert set(model.link_names) - {"universe"} <= set(tree) | {"world", "base_link"}, \
            f"frames missing from tf: {set(model.link_names) - set(tree)}"
        q = np.array(state.position)
        for frame in ("tool0", "flange", "link_6", "link_3"):
            composed = _compose(tree, frame, "base_link")
            fk = model.frame_pose(q, frame)
            assert np.max(np.abs(composed[:3, 3] - fk[:3, 3])) < 1e-9, frame
            assert np.max(np.abs(composed[:3, :3] - fk[:3, :3])) < 1e-9, frame
        checked += 1
    assert checked >= 10, f"only {checked} tf messages matched a joint state by stamp"
    truth = [t for _, msg in moving for t in msg.transforms
             if t.child_frame_id == "KR60ArmTipTruth_truth"]
    assert len(truth) >= 10, "the tip GroundTruth sensor's frame, as the simulator reports it"
    reported = _matrix(truth[-1])
    modelled = model.frame_pose(np.array(states[-1][1].position), "KR60ArmTipTruth")
    assert truth[-1].header.frame_id == "base_link"
    assert np.max(np.abs(reported[:3, 3] - modelled[:3, 3])) < 0.011  # UDK prints cm


def test_tf_advertises_ros2_jazzys_type_hash(session: tuple[Client, str, Path]) -> None:
    client, _, _ = session
    infos = client.node.get_publishers_info_by_topic("/tf")
    assert infos and {str(i.topic_type_hash) for i in infos} == {JAZZY_TF_HASH}


def test_the_moveit_package_names_the_nodes_controller_and_action(
        session: tuple[Client, str, Path]) -> None:
    import os

    import yaml
    from rclpy.action import get_action_names_and_types

    client, _, folder = session
    done = subprocess.run([sys.executable, "-m", "usar_arm", "moveit-config", "--no-calibrate",
                           "--out", str(folder / "moveit"), "-q"], capture_output=True,
                          text=True, timeout=300, check=False, cwd=ROOT,
                          env={**os.environ, "USAR_ARM_CACHE": str(folder / "cache")})
    assert done.returncode == 0, done.stderr[-2000:]
    config = yaml.safe_load((folder / "moveit" / "config" / "moveit_controllers.yaml")
                            .read_text())["moveit_simple_controller_manager"]
    (name,) = config["controller_names"]
    wanted = f"/{name}/{config[name]['action_ns']}"
    served = {n: t for n, t in get_action_names_and_types(client.node)}
    assert served.get(wanted) == ["control_msgs/action/FollowJointTrajectory"], served
