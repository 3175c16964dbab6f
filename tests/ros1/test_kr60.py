"""The KR60 on ROS 1, judged by Debian's tools: robot_state_publisher (unmodified) turns the
node's robot_description and joint_states into the node's own tf while the arm moves; rosbag
records every message; an actionlib SimpleActionClient runs the demo's cycle to the
simulator's truth and a malformed goal is rejected with joint_trajectory_controller's code."""

from __future__ import annotations

import json
import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.ros1.helpers import Master, Node, answer, client, session, start_client, stop
from tests.ros1.transforms import compare_trees, edges_by_stamp
from usar_arm.ros import ros1_setup

ACTION = "KR60Arm_controller/follow_joint_trajectory"
NAMES = [f"joint_a{i}" for i in range(1, 7)]
RSP = "/usr/lib/robot_state_publisher/robot_state_publisher"


@pytest.fixture(scope="module")
def kr60(ros1_env: ros1_setup.Ros1Environment, tmp_path_factory: pytest.TempPathFactory
         ) -> Iterator[tuple[Master, Node, Path]]:
    folder = tmp_path_factory.mktemp("ros1-kr60")
    # full-precision numbers on the wire, as the demo runs (UDK prints the truth in cm)
    with session(ros1_env, folder, ["--wire-precision", "full", "-v"]) as (master, node):
        yield master, node, folder


def _joints(master: Master, folder: Path) -> np.ndarray:
    client(master, "record", "--seconds", "1", "--out", str(folder / "js.json"),
           "/joint_states:sensor_msgs/JointState")
    got = json.loads((folder / "js.json").read_text())["/joint_states"]
    assert got, "no joint state"
    return np.array(got[-1][1]["position"])


def _goal(master: Master, points: list[tuple[float, list[float]]], names: list[str] = NAMES,
          **tolerances: Any) -> dict[str, Any]:
    spec = {"names": names, "points": [[t, list(q)] for t, q in points],
            "tolerances": tolerances}
    return client(master, "goal", "--action", ACTION, "--spec", json.dumps(spec))


def test_robot_state_publisher_computes_the_nodes_tf_while_the_arm_moves(
        kr60: tuple[Master, Node, Path]) -> None:
    master, _, folder = kr60
    rsp = subprocess.Popen([RSP, "tf:=/rsp/tf", "tf_static:=/rsp/tf_static", "__name:=rsp"],
                           env=master.env(), stdout=open(folder / "rsp.log", "w"),
                           stderr=subprocess.STDOUT)
    try:
        q0 = _joints(master, folder)
        recorder = start_client(master, "record", "--seconds", "6", "--out",
                                str(folder / "tf.json"), "/tf:tf2_msgs/TFMessage",
                                "/rsp/tf:tf2_msgs/TFMessage", "/tf_static:tf2_msgs/TFMessage",
                                "/rsp/tf_static:tf2_msgs/TFMessage",
                                "/joint_states:sensor_msgs/JointState", log=folder / "rec.log")
        moved = _goal(master, [(4.0, (q0 + np.array([0.4, -0.3, 0.3, 0.5, -0.4, 0.6]))
                                .tolist())])
        assert moved["status"] == "SUCCEEDED", moved
        answer(recorder)
    finally:
        stop(rsp)
    got = json.loads((folder / "tf.json").read_text())
    ours, theirs = edges_by_stamp(got["/tf"]), edges_by_stamp(got["/rsp/tf"])
    shared = sorted(set(ours) & set(theirs))
    assert len(shared) >= 30, f"only {len(shared)} tf messages matched by stamp"
    positions = np.array([m["position"] for _, m in got["/joint_states"]])
    assert np.ptp(positions, axis=0).max() > 0.3, "the arm moved while recorded"
    worst = compare_trees([(ours[k], theirs[k]) for k in shared])
    assert worst == (pytest.approx(0, abs=1e-9), pytest.approx(0, abs=1e-9)), worst
    static_ours = edges_by_stamp(got["/tf_static"], any_stamp=True)
    static_theirs = edges_by_stamp(got["/rsp/tf_static"], any_stamp=True)
    assert static_theirs, "robot_state_publisher published the fixed joints"
    mine = {k: v for s in static_ours.values() for k, v in s.items()}
    rsp_static = {k: v for s in static_theirs.values() for k, v in s.items()}
    assert set(rsp_static) <= set(mine), set(rsp_static) - set(mine)
    assert compare_trees([({k: mine[k] for k in rsp_static}, rsp_static)]) == \
        (pytest.approx(0, abs=1e-9), pytest.approx(0, abs=1e-9))


def test_an_actionlib_client_runs_the_demos_cycle_to_the_simulators_truth(
        kr60: tuple[Master, Node, Path]) -> None:
    master, _, _ = kr60
    moves = client(master, "cycle", "--action", ACTION, timeout=600)["moves"]
    assert len(moves) >= 6
    for move in moves:
        assert (move["status"], move["error_code"]) == ("SUCCEEDED", 0), move
        assert move["tool0_error_m"] < 1e-3, move  # the demo's target
        assert move["state_changed_s"] < 1.0, move  # the 20 ms target is the bench's


@pytest.mark.parametrize(("change", "code", "words"), [
    ("unknown joint", -2, "unknown ['joint_x']"),
    ("beyond a limit", -1, "outside its limits"),
    ("no points", -1, "no points"),
])
def test_a_malformed_goal_is_rejected_with_the_controllers_error_code(
        kr60: tuple[Master, Node, Path], change: str, code: int, words: str) -> None:
    master, _, folder = kr60
    q0 = _joints(master, folder)
    names, points = list(NAMES), [(2.0, (q0 + 0.1).tolist())]
    if change == "unknown joint":
        names[2] = "joint_x"
    elif change == "beyond a limit":
        points = [(2.0, (q0 + np.array([0, 0, 0, 0, 3.0, 0])).tolist())]
    elif change == "no points":
        points = []
    got = _goal(master, points, names)
    assert (got["status"], got["error_code"]) == ("REJECTED", code), got
    assert words in got["error_string"]
    assert np.max(np.abs(_joints(master, folder) - q0)) < 0.002, "nothing moved"


def test_a_newer_goal_preempts_the_running_one(kr60: tuple[Master, Node, Path]) -> None:
    master, _, folder = kr60
    q0 = _joints(master, folder)
    spec = {"names": NAMES, "first": [[6.0, (q0 + np.array([0.8, 0, 0, 0, 0, 0])).tolist()]],
            "second": [[2.5, q0.tolist()]]}
    got = client(master, "preempt", "--action", ACTION, "--spec", json.dumps(spec))
    assert got["second"]["status"] == "SUCCEEDED", got
    assert got["first"]["status"] == "PREEMPTED", got
    assert "pre-empted" in got["first"]["error_string"], got
    assert np.max(np.abs(_joints(master, folder) - q0)) < 0.002


_BAG = """import json, sys, rosbag
out = {}
with rosbag.Bag(sys.argv[1]) as bag:
    for topic, msg, _ in bag.read_messages():
        entry = out.setdefault(topic, {"n": 0, "seq": [], "stamps": []})
        entry["n"] += 1
        if topic == "/joint_states":
            entry["seq"].append(msg.header.seq)
            entry["stamps"].append([msg.header.stamp.secs, msg.header.stamp.nsecs])
        elif topic == "/tf":
            entry["stamps"].append([msg.transforms[0].header.stamp.secs,
                                    msg.transforms[0].header.stamp.nsecs])
print(json.dumps(out))
"""


def test_rosbag_records_every_message_the_node_published(
        ros1_env: ros1_setup.Ros1Environment, tmp_path: Path) -> None:
    """rosbag record (Debian's) from before the node starts to after it stops: the bag holds
    every joint state the node sent (header.seq 1..n without a gap; the node's count less the
    first few it published before rosbag had connected), the tf of each, tf_static once;
    Debian's rosbag and the rosbags package read the same messages."""
    import re
    import signal
    import time

    master = Master(ros1_env, tmp_path)
    bag = tmp_path / "node.bag"
    record = subprocess.Popen(["rosbag", "record", "-O", str(bag), "/joint_states", "/tf",
                               "/tf_static", "__name:=recorder"], env=master.env(),
                              stdout=open(tmp_path / "rosbag.log", "w"),
                              stderr=subprocess.STDOUT)
    try:
        time.sleep(3.0)
        node = Node(master, ["-v"], tmp_path / "node.log")
        client(master, "description", "--timeout", "240", timeout=300)
        time.sleep(10.0)
        assert node.stop() == 0, node.text()[-3000:]
        time.sleep(1.0)
    finally:
        stop(record, signal.SIGINT)
        master.close()
    published = dict((k, int(v)) for k, v in re.findall(
        r"(\w+) (\d+)", re.search(r"published: (.*)", node.text()).group(1)))  # type: ignore
    done = subprocess.run([str(ros1_env.python), "-c", _BAG, str(bag)], capture_output=True,
                          text=True, timeout=120, env=ros1_env.environ(), check=True)
    got = json.loads(done.stdout)
    seqs = got["/joint_states"]["seq"]
    assert got["/joint_states"]["n"] >= 90, "10 s of joint states at 10 Hz"
    # rospy numbers (header.seq) only what it sends to a connection, from 1: with rosbag the
    # only subscriber, 1..n without a gap is every message sent; the node's own count exceeds
    # n by what it published before rosbag's connection to it was made (its first few)
    assert seqs == list(range(1, len(seqs) + 1)), "every message sent is in the bag"
    assert 0 <= published["joint_states"] - len(seqs) <= 5, (len(seqs), published)
    tf_stamps = {tuple(s) for s in got["/tf"]["stamps"]}
    # rosbag connects to each topic's publisher on its own: from its first tf message on
    first_tf = min(tf_stamps)
    states = [tuple(s) for s in got["/joint_states"]["stamps"] if tuple(s) >= first_tf]
    assert len(states) >= 90 and all(s in tf_stamps for s in states), \
        "each joint state's transforms are in the bag"
    assert got["/tf_static"]["n"] == published["tf_static"] == 1
    from rosbags.rosbag1 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    typestore = get_typestore(Stores.ROS1_NOETIC)
    counts: dict[str, int] = {}
    with Reader(bag) as reader:
        types: dict[str, Any] = {}
        for connection in reader.connections:  # the definitions the bag carries (tf2_msgs...)
            text = getattr(connection.msgdef, "data", connection.msgdef)
            types.update(get_types_from_msg(text, connection.msgtype))
        typestore.register(types)
        for connection, _, raw in reader.messages():
            msg = typestore.deserialize_ros1(raw, connection.msgtype)
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
            if connection.topic == "/joint_states":
                assert msg.header.seq in set(seqs)
    assert counts == {t: v["n"] for t, v in got.items()}
