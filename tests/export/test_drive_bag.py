"""The drive bag from a record built by hand (no simulator): REP-103/105 frames, the scanner's
mount converted from the wire's z-down frame, LaserScan angles, atomic refusal to overwrite."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore

from usar_arm.control.drive_record import Command, DriveRecord, PoseTrack, Scan
from usar_arm.control.vehicle_wire import ScannerInfo, VehicleInfo, pose_zup
from usar_arm.core.errors import InvalidInputError
from usar_arm.export.drive_bag import write_drive_bag

SCANNER = ScannerInfo("lms200", 0.1, 20.0, 0.0174, 3.1414,
                      pose_zup((0.208, 0.0, -0.2), (0.0, 0.0, 0.0)))  # the P3AT's GEO
VEHICLE = VehicleInfo("P3AT", "SkidSteered", 0.098, 0.36, 1.2999, "GndTruth", "Odometer",
                      "InsTest", SCANNER)


def _record() -> DriveRecord:
    t = np.arange(0.0, 2.01, 0.1)
    truth = PoseTrack(t, np.column_stack([1 + 0.1 * t, -2 + 0 * t, 0.5 + 0 * t]))
    odometry = PoseTrack(t, np.column_stack([0.1 * t, 0 * t, 0 * t]))
    scans = tuple(Scan(float(s), tuple(np.linspace(1, 3, 181)), 3.1414) for s in t[::2])
    commands = tuple(Command(float(s), 0.1, 0.0, 1.02, 1.02, False) for s in t)
    return DriveRecord(VEHICLE, truth, odometry, PoseTrack.of([]), scans, commands, 0.145,
                       True)


def _messages(bag: Path) -> dict[str, list[Any]]:
    store = get_typestore(Stores.ROS2_HUMBLE)
    out: dict[str, list[Any]] = {}
    with Reader(bag) as reader:
        for conn, _, raw in reader.messages():
            out.setdefault(conn.topic, []).append(store.deserialize_cdr(raw, conn.msgtype))
    return out


def test_frames_follow_rep_103_and_rep_105(tmp_path: Path) -> None:
    write_drive_bag(tmp_path / "bag", _record())
    msgs = _messages(tmp_path / "bag")
    static = {(tf.header.frame_id, tf.child_frame_id): tf.transform.translation
              for tf in msgs["/tf_static"][0].transforms}
    assert static[("base_footprint", "base_link")].z == pytest.approx(0.145)
    mount = static[("base_link", "lms200")]  # z down 0.2 above the chassis -> z up +0.2
    assert (mount.x, mount.y, mount.z) == pytest.approx((0.208, 0.0, 0.2))
    first = {(tf.header.frame_id, tf.child_frame_id): tf.transform
             for tf in msgs["/tf"][0].transforms}
    map_odom = first[("map", "odom")]  # the odom frame where truth and odometry agree
    assert (map_odom.translation.x, map_odom.translation.y) == pytest.approx((1.0, -2.0))
    assert 2 * math.atan2(map_odom.rotation.z, map_odom.rotation.w) == pytest.approx(0.5)
    assert msgs["/odom"][0].header.frame_id == "odom"
    assert msgs["/ground_truth"][0].header.frame_id == "map"
    assert msgs["/odom"][-1].twist.twist.linear.x == pytest.approx(0.1)


def test_scans_run_from_the_right_to_the_left(tmp_path: Path) -> None:
    write_drive_bag(tmp_path / "bag", _record())
    scan = _messages(tmp_path / "bag")["/scan"][0]
    assert scan.angle_min == pytest.approx(-3.1414 / 2) and scan.angle_max == pytest.approx(
        3.1414 / 2)
    assert scan.angle_increment == pytest.approx(3.1414 / 180)
    assert scan.ranges[0] == pytest.approx(1.0) and scan.ranges[-1] == pytest.approx(3.0)
    assert (scan.range_min, scan.range_max) == pytest.approx((0.1, 20.0))


def test_an_existing_bag_is_kept_unless_overwrite(tmp_path: Path) -> None:
    first = write_drive_bag(tmp_path / "bag", _record())
    with pytest.raises(InvalidInputError, match="exists already"):
        write_drive_bag(tmp_path / "bag", _record())
    assert first.topics["/cmd_vel"] == 21
    again = write_drive_bag(tmp_path / "bag", _record(), overwrite=True)
    assert again.topics == first.topics
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bag"]  # no staging left behind
