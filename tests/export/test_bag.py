"""ROS 2 bag export: what a bag written for a planned KR60 motion holds, read back two ways."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.interfaces import ConnectionExtRosbag2, QosDurability
from rosbags.rosbag2 import Reader, Writer
from rosbags.typesys import Stores, get_typestore

from usar_arm.control.motion import plan_motion
from usar_arm.control.trajectory import Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.core.spatial import matrix_from_quat, transform
from usar_arm.export.bag import BagSummary, ExecutedSamples, write_bag
from usar_arm.planning.robot import Robot, robot_from_files

KR60_URDF = Path(__file__).resolve().parents[2] / "robots" / "generated" / "KR60.urdf"
GOAL = np.array([0.5, -0.5, 0.5, 0.5, 0.5, 0.5])
START_NS = 1_700_000_000 * 10**9
STORE = get_typestore(Stores.ROS2_HUMBLE)

TYPES = {
    "/robot_description": "std_msgs/msg/String",
    "/tf_static": "tf2_msgs/msg/TFMessage",
    "/planned_trajectory": "trajectory_msgs/msg/JointTrajectory",
    "/joint_states": "sensor_msgs/msg/JointState",
    "/tf": "tf2_msgs/msg/TFMessage",
}


@dataclass
class Bag:
    """A bag read back with rosbags: topic -> type, QoS profiles, [(stamp ns, message)]."""

    types: dict[str, str]
    qos: dict[str, list[Any]]
    messages: dict[str, list[tuple[int, Any]]]
    version: int

    def at(self, topic: str, stamp: int) -> Any:
        """The message of ``topic`` logged at ``stamp``."""
        found = [m for t, m in self.messages[topic] if t == stamp]
        assert len(found) == 1, f"{len(found)} messages on {topic} at {stamp}"
        return found[0]


def read_bag(path: Path) -> Bag:
    with Reader(path) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        assert all(isinstance(c.ext, ConnectionExtRosbag2) for c in reader.connections)
        qos = {c.topic: list(c.ext.offered_qos_profiles)  # type: ignore[union-attr]
               for c in reader.connections}
        messages: dict[str, list[tuple[int, Any]]] = {topic: [] for topic in types}
        for conn, stamp, raw in reader.messages():
            messages[conn.topic].append((stamp, STORE.deserialize_cdr(raw, conn.msgtype)))
        version = yaml.safe_load((path / "metadata.yaml").read_text())[
            "rosbag2_bagfile_information"]["version"]
    return Bag(types, qos, messages, version)


def stamp_ns(header: Any) -> int:
    return int(header.stamp.sec) * 10**9 + int(header.stamp.nanosec)


def pose_of(frame: str, *tf_messages: Any) -> np.ndarray:
    """The 4x4 pose of ``frame`` in ``world``, composed from TransformStamped lists."""
    edges = {}
    for message in tf_messages:
        for ts in message.transforms:
            r = ts.transform.rotation
            pos = ts.transform.translation
            edges[ts.child_frame_id] = (ts.header.frame_id, transform(
                matrix_from_quat([r.w, r.x, r.y, r.z]), [pos.x, pos.y, pos.z]))
    pose = np.eye(4)
    while frame != "world":
        frame, step = edges[frame]
        pose = step @ pose
    return pose


# --------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def robot() -> Robot:
    return robot_from_files(KR60_URDF)


@pytest.fixture(scope="module")
def planned(robot: Robot) -> Trajectory:
    plan = plan_motion(robot, robot.collision_world(), np.zeros(6), goal=GOAL)
    return plan.trajectory


@pytest.fixture(scope="module")
def executed(planned: Trajectory) -> ExecutedSamples:
    """The plan as ASTA feedback would report it: 10 Hz, with small measurement noise."""
    t = np.arange(0.0, planned.duration, 0.1)
    rng = np.random.default_rng(7)
    q = np.array([planned.at(float(s))[0] for s in t]) + rng.normal(0.0, 1e-3, (len(t), 6))
    return ExecutedSamples(t, q)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("bags")


@pytest.fixture(scope="module")
def planned_bag(robot: Robot, planned: Trajectory, folder: Path) -> tuple[BagSummary, Bag]:
    summary = write_bag(folder / "planned", robot.chain, robot.urdf, planned)
    return summary, read_bag(summary.path)


@pytest.fixture(scope="module")
def executed_bag(robot: Robot, planned: Trajectory, executed: ExecutedSamples,
                 folder: Path) -> tuple[BagSummary, Bag]:
    summary = write_bag(folder / "executed", robot.chain, robot.urdf, planned, executed)
    return summary, read_bag(summary.path)


@pytest.fixture
def failing_writer(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """rosbags' Writer raises on its 50th message."""
    original = Writer.write
    calls = [0]

    def write(self: Writer, *args: Any) -> None:
        calls[0] += 1
        if calls[0] == 50:
            raise OSError(28, "No space left on device")
        original(self, *args)

    monkeypatch.setattr(Writer, "write", write)
    yield


# --------------------------------------------------------------------------- contents


def test_a_planned_bag_has_the_five_topics_with_their_counts(
        planned_bag: tuple[BagSummary, Bag], planned: Trajectory) -> None:
    summary, bag = planned_bag
    assert bag.types == TYPES
    counts = {topic: len(msgs) for topic, msgs in bag.messages.items()}
    assert summary.topics == counts
    assert counts["/robot_description"] == counts["/tf_static"] == 1
    assert counts["/planned_trajectory"] == 1
    assert abs(counts["/joint_states"] - (planned.duration * 100 + 1)) <= 1
    assert abs(counts["/tf"] - (planned.duration * 50 + 1)) <= 1
    assert summary.start_ns == START_NS
    assert summary.duration_s == pytest.approx(planned.duration, abs=1e-9)
    assert bag.version == 8  # humble: the older of the two versions rosbags writes


def test_the_description_is_the_urdf_offered_transient_local(
        planned_bag: tuple[BagSummary, Bag], robot: Robot) -> None:
    summary, bag = planned_bag
    [(stamp, description)] = bag.messages["/robot_description"]
    assert (stamp, description.data) == (START_NS, robot.urdf)
    for topic in ("/robot_description", "/tf_static"):
        (qos,) = bag.qos[topic]
        assert qos.durability is QosDurability.TRANSIENT_LOCAL and qos.depth == 1
    (qos,) = bag.qos["/joint_states"]
    assert qos.durability is QosDurability.VOLATILE
    # What ros2 bag play reads: the MCAP channel metadata.
    with (summary.path / "planned.mcap").open("rb") as fh:
        channels = make_reader(fh).get_summary().channels.values()  # type: ignore[union-attr]
    profiles = {c.topic: yaml.safe_load(c.metadata["offered_qos_profiles"]) for c in channels}
    assert profiles["/robot_description"][0]["durability"] == 1  # transient_local
    assert profiles["/robot_description"][0]["reliability"] == 1  # reliable


def test_tf_static_holds_world_to_root_and_every_fixed_joint(
        planned_bag: tuple[BagSummary, Bag], robot: Robot) -> None:
    _, bag = planned_bag
    message = bag.at("/tf_static", START_NS)
    edges = {(ts.header.frame_id, ts.child_frame_id): ts for ts in message.transforms}
    fixed = {(j.parent, j.child) for j in robot.chain.joints if not j.actuated}
    assert set(edges) == {("world", "base_link")} | fixed
    assert all(stamp_ns(ts.header) == START_NS for ts in message.transforms)
    world = edges[("world", "base_link")].transform
    assert (world.rotation.w, world.translation.z) == (1.0, 0.0)


def test_joint_states_are_the_plan_sampled_at_100_hz(
        planned_bag: tuple[BagSummary, Bag], planned: Trajectory) -> None:
    _, bag = planned_bag
    states = bag.messages["/joint_states"]
    stamps = np.array([t for t, _ in states])
    assert stamps[0] == START_NS
    assert stamps[-1] == START_NS + round(planned.duration * 1e9)
    assert np.all(np.abs(np.diff(stamps)[:-1] - 10_000_000) <= 1)
    for stamp, msg in states:
        assert stamp_ns(msg.header) == stamp
        assert list(msg.name) == list(planned.joint_names)
        q, qd = planned.at((stamp - START_NS) / 1e9)
        np.testing.assert_allclose(msg.position, q, atol=1e-12)
        np.testing.assert_allclose(msg.velocity, qd, atol=1e-12)
        assert len(msg.effort) == 0
    np.testing.assert_allclose(states[-1][1].position, planned.q[-1], atol=1e-12)


def test_the_planned_trajectory_has_one_point_per_joint_state(
        planned_bag: tuple[BagSummary, Bag], planned: Trajectory) -> None:
    _, bag = planned_bag
    traj = bag.at("/planned_trajectory", START_NS)
    assert list(traj.joint_names) == list(planned.joint_names)
    assert stamp_ns(traj.header) == START_NS
    states = bag.messages["/joint_states"]
    assert len(traj.points) == len(states)
    for point, (stamp, state) in zip(traj.points, states, strict=True):
        offset = point.time_from_start.sec * 10**9 + point.time_from_start.nanosec
        assert START_NS + offset == stamp
        np.testing.assert_array_equal(point.positions, state.position)
        np.testing.assert_array_equal(point.velocities, state.velocity)
        assert len(point.accelerations) == 6
    np.testing.assert_allclose(traj.points[0].accelerations, planned.qdd[0], atol=1e-12)


@pytest.mark.parametrize("which", ["planned", "executed"])
def test_tf_composed_with_tf_static_gives_the_tool0_pose_of_the_published_q(
        which: str, planned_bag: tuple[BagSummary, Bag],
        executed_bag: tuple[BagSummary, Bag], robot: Robot) -> None:
    _, bag = planned_bag if which == "planned" else executed_bag
    static = bag.at("/tf_static", START_NS)
    state_stamps = {t for t, _ in bag.messages["/joint_states"]}
    common = sorted(state_stamps & {t for t, _ in bag.messages["/tf"]})
    assert len(common) >= 10
    for stamp in common[1::max(1, len(common) // 6)]:
        q = np.asarray(bag.at("/joint_states", stamp).position)
        moving = bag.at("/tf", stamp)
        assert {ts.child_frame_id for ts in moving.transforms} == {
            j.child for j in robot.chain.actuated_joints}
        assert all(stamp_ns(ts.header) == stamp for ts in moving.transforms)
        expected = robot.kinematics.frame_pose(q, "tool0")
        got = pose_of("tool0", static, moving)
        np.testing.assert_allclose(got[:3, 3], expected[:3, 3], atol=1e-6)
        np.testing.assert_allclose(got[:3, :3], expected[:3, :3], atol=1e-6)


def test_an_executed_bag_publishes_the_measured_q_and_the_plan_beside_it(
        executed_bag: tuple[BagSummary, Bag], planned_bag: tuple[BagSummary, Bag],
        executed: ExecutedSamples) -> None:
    summary, bag = executed_bag
    assert bag.types == TYPES | {"/planned/joint_states": "sensor_msgs/msg/JointState"}
    states = bag.messages["/joint_states"]
    assert [t for t, _ in states] == [START_NS + round(t * 1e9) for t in executed.t]
    for (_, msg), q in zip(states, executed.q, strict=True):
        np.testing.assert_array_equal(msg.position, q)
        assert len(msg.velocity) == 0
    plan_states = planned_bag[1].messages["/joint_states"]
    assert len(bag.messages["/planned/joint_states"]) == len(plan_states)
    for (t1, a), (t2, b) in zip(bag.messages["/planned/joint_states"], plan_states, strict=True):
        assert t1 == t2
        np.testing.assert_array_equal(a.position, b.position)
    span = executed.t[-1] - executed.t[0]
    assert abs(len(bag.messages["/tf"]) - (span * 50 + 1)) <= 1
    assert summary.topics["/planned/joint_states"] == len(plan_states)


def test_the_mcap_decodes_with_mcap_ros2_support(
        executed_bag: tuple[BagSummary, Bag], robot: Robot,
        executed: ExecutedSamples) -> None:
    summary, _ = executed_bag
    counts: dict[str, int] = {}
    positions = []
    with (summary.path / "executed.mcap").open("rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for schema, channel, _, ros_msg in reader.iter_decoded_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
            if channel.topic == "/robot_description":
                assert schema is not None and schema.name == "std_msgs/msg/String"
                assert ros_msg.data == robot.urdf
            elif channel.topic == "/joint_states":
                positions.append(list(ros_msg.position))
            elif channel.topic == "/tf":
                assert len(ros_msg.transforms) == 6
    assert counts == summary.topics
    np.testing.assert_array_equal(np.array(positions), executed.q)


# --------------------------------------------------------------------------- files


def test_the_same_inputs_give_the_same_bytes(
        robot: Robot, planned: Trajectory, executed: ExecutedSamples, tmp_path: Path) -> None:
    paths = [write_bag(tmp_path / name / "bag", robot.chain, robot.urdf, planned, executed,
                       distro="jazzy").path for name in ("one", "two")]
    for name in ("bag.mcap", "metadata.yaml"):
        assert (paths[0] / name).read_bytes() == (paths[1] / name).read_bytes()
    assert read_bag(paths[0]).version == 9


def test_an_existing_bag_is_not_overwritten_unless_asked(
        robot: Robot, planned: Trajectory, tmp_path: Path) -> None:
    first = write_bag(tmp_path / "bag", robot.chain, robot.urdf, planned)
    before = (first.path / "bag.mcap").read_bytes()
    with pytest.raises(InvalidInputError, match="overwrite=True"):
        write_bag(tmp_path / "bag", robot.chain, robot.urdf, planned, start_ns=START_NS + 1)
    assert (first.path / "bag.mcap").read_bytes() == before
    second = write_bag(tmp_path / "bag", robot.chain, robot.urdf, planned,
                       start_ns=START_NS + 10**9, overwrite=True)
    assert read_bag(second.path).messages["/tf_static"][0][0] == START_NS + 10**9
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


def test_overwrite_never_replaces_a_folder_that_is_not_a_bag(
        robot: Robot, planned: Trajectory, tmp_path: Path) -> None:
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "todo.txt").write_text("keep me")
    with pytest.raises(InvalidInputError, match="not a rosbag2 folder"):
        write_bag(tmp_path / "notes", robot.chain, robot.urdf, planned, overwrite=True)
    assert (tmp_path / "notes" / "todo.txt").read_text() == "keep me"


@pytest.mark.usefixtures("failing_writer")
def test_a_failed_write_leaves_no_partial_bag(
        robot: Robot, planned: Trajectory, tmp_path: Path) -> None:
    with pytest.raises(OSError, match="No space left"):
        write_bag(tmp_path / "bag", robot.chain, robot.urdf, planned)
    assert list(tmp_path.iterdir()) == []


def test_a_failed_overwrite_keeps_the_old_bag(
        robot: Robot, planned: Trajectory, tmp_path: Path,
        monkeypatch: pytest.MonkeyPatch) -> None:
    old = write_bag(tmp_path / "bag", robot.chain, robot.urdf, planned)
    before = {p.name: p.read_bytes() for p in old.path.iterdir()}

    def broken(self: Writer, *args: Any) -> None:
        raise RuntimeError("writer broke")

    monkeypatch.setattr(Writer, "write", broken)
    with pytest.raises(RuntimeError, match="writer broke"):
        write_bag(tmp_path / "bag", robot.chain, robot.urdf, planned, overwrite=True)
    assert {p.name: p.read_bytes() for p in old.path.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]


# --------------------------------------------------------------------------- bad input


def test_bad_input_is_refused_with_what_was_wrong(
        robot: Robot, planned: Trajectory, executed: ExecutedSamples, tmp_path: Path) -> None:
    chain, urdf = robot.chain, robot.urdf
    target = tmp_path / "bag"
    with pytest.raises(InvalidInputError, match="humble, iron, jazzy, kilted"):
        write_bag(target, chain, urdf, planned, distro="noetic")
    with pytest.raises(InvalidInputError, match="tf_rate"):
        write_bag(target, chain, urdf, planned, tf_rate=0.0)
    with pytest.raises(InvalidInputError, match="joint_a1"):
        write_bag(target, chain, urdf, planned, ExecutedSamples(executed.t, executed.q[:, :5]))
    backwards = ExecutedSamples(executed.t[::-1], executed.q)
    with pytest.raises(InvalidInputError, match="increase"):
        write_bag(target, chain, urdf, planned, backwards)
    with pytest.raises(InvalidInputError, match="URDF"):
        write_bag(target, chain, " ", planned)
    with pytest.raises(InvalidInputError, match="start_ns"):
        write_bag(target, chain, urdf, planned, start_ns=2**31 * 10**9)
    with pytest.raises(InvalidInputError, match="names the folder"):
        write_bag(tmp_path / "..", chain, urdf, planned)
    assert not target.exists()


def test_rates_set_the_sample_counts(robot: Robot, planned: Trajectory, tmp_path: Path) -> None:
    summary = write_bag(tmp_path / "bag", robot.chain, robot.urdf, planned,
                        joint_state_rate=25.0, tf_rate=10.0)
    assert summary.topics["/joint_states"] == math.ceil(planned.duration * 25 - 1e-6) + 1
    assert summary.topics["/tf"] == math.ceil(planned.duration * 10 - 1e-6) + 1
