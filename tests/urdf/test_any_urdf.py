"""Any arm's URDF: meshes found the way ROS tools find them, the planning group cut from the
tree (held joints, mimic joints, tips), and a one-line error (exit 13) for what has no serial
chain to plan."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_BAD_DESCRIPTION, FileFormatError, RobotStructureError
from usar_arm.core.shapes import Box, Capsule, Mesh, Sphere
from usar_arm.planning.robot import RobotOptions, robot_from_files
from usar_arm.urdf.description_reader import ReadOptions, read_urdf
from usar_arm.urdf.packages import PackagePaths

from .mesh_robot import PACKAGE, URDF, write_robot


@pytest.fixture
def toy(tmp_path: Path) -> tuple[Path, Path]:
    return write_robot(tmp_path)


def _moved(urdf: Path, tmp_path: Path) -> Path:
    """The URDF alone in another folder: its package is no longer among its ancestors."""
    alone = tmp_path / "elsewhere" / "toy.urdf"
    alone.parent.mkdir()
    alone.write_text(urdf.read_text())
    return alone


def test_meshes_are_found_through_the_urdfs_own_ancestors(toy: tuple[Path, Path]) -> None:
    tree = read_urdf(toy[0].read_text(), str(toy[0]))
    ring = tree.chain.link("base_link").collisions[0].shape
    assert isinstance(ring, Mesh) and ring.source.endswith("ring.stl")
    kinds = [type(c.shape) for c in tree.chain.link("link_2").collisions]
    assert kinds == [Mesh, Sphere]
    assert [type(c.shape) for c in tree.chain.link("link_3").collisions] == [Box, Capsule]


def test_a_mesh_scale_applies_per_axis(toy: tuple[Path, Path]) -> None:
    cup = read_urdf(toy[0].read_text(), str(toy[0])).chain.link("link_4").collisions[0].shape
    assert isinstance(cup, Mesh)
    assert np.abs(cup.vertices[:, :2]).max() == pytest.approx(0.9 * 0.05, rel=1e-6)


@pytest.mark.parametrize("how", ["explicit", "ros_package_path", "ament_prefix_path"])
def test_package_uris_resolve_as_ros_tools_resolve_them(toy: tuple[Path, Path], tmp_path: Path,
                                                        how: str) -> None:
    urdf = _moved(toy[0], tmp_path)
    ws = tmp_path / "ws"
    share = tmp_path / "install" / "share"
    share.mkdir(parents=True)
    (share / PACKAGE).symlink_to(ws / PACKAGE)
    paths = {"explicit": PackagePaths({PACKAGE: str(ws / PACKAGE)}, {}),
             "ros_package_path": PackagePaths({}, {"ROS_PACKAGE_PATH": str(ws)}),
             "ament_prefix_path": PackagePaths({}, {"AMENT_PREFIX_PATH": str(share.parent)})}
    tree = read_urdf(urdf.read_text(), str(urdf), ReadOptions(paths[how]))
    shape = tree.chain.link("base_link").collisions[0].shape
    assert isinstance(shape, Mesh) and Path(shape.source).name == "ring.stl"


def test_a_missing_mesh_names_the_link_and_the_uri(toy: tuple[Path, Path],
                                                   tmp_path: Path) -> None:
    urdf = _moved(toy[0], tmp_path)
    with pytest.raises(FileFormatError) as err:
        read_urdf(urdf.read_text(), str(urdf), ReadOptions(PackagePaths({}, {})))
    assert "link base_link" in str(err.value)
    assert f"package://{PACKAGE}/meshes/ring.stl" in str(err.value)


def test_the_convex_hull_is_the_users_choice(toy: tuple[Path, Path]) -> None:
    tree = read_urdf(toy[0].read_text(), str(toy[0]), ReadOptions(convex_hull=True))
    ring = tree.chain.link("base_link").collisions[0].shape
    assert isinstance(ring, Mesh) and ring.convex_hull
    assert not read_urdf(toy[0].read_text(), str(toy[0])).chain.link(
        "base_link").collisions[0].shape.convex_hull  # type: ignore[union-attr]


def test_the_srdf_group_is_planned_and_the_gripper_held(toy: tuple[Path, Path]) -> None:
    robot = robot_from_files(*toy)
    assert robot.chain.joint_names == ("joint_1", "joint_2", "joint_3", "joint_4")
    assert robot.chain.frames["tool0"] == "tool0"
    assert ("finger_l", "link_4") in robot.disabled
    # held at the middle of [0.01, 0.03] (0 is outside); the mimic finger follows
    q = np.zeros(4)
    left, right = (robot.kinematics.frame_pose(q, n)[:3, 3] for n in ("finger_l", "finger_r"))
    assert left[1] == pytest.approx(0.03 + 0.02) and right[1] == pytest.approx(-0.03 - 0.02)


def test_a_joint_list_group_and_a_tip(toy: tuple[Path, Path]) -> None:
    robot = robot_from_files(*toy, options=RobotOptions.of(group="wrist", tip="link_4"))
    assert robot.chain.joint_names == ("joint_3", "joint_4")
    assert robot.chain.frames["tool0"] == "link_4"
    pose = robot.kinematics.frame_pose(np.array([0.0, 0.05]), "tool0")
    assert pose[2, 3] == pytest.approx(0.05 + 0.2 + 0.3 + 0.24 + 0.05)


def test_a_link_list_group_plans_the_joints_that_move_its_links(toy: tuple[Path, Path]
                                                               ) -> None:
    robot = robot_from_files(*toy, options=RobotOptions.of(group="forearm"))
    assert robot.chain.joint_names == ("joint_3", "joint_4")
    with pytest.raises(RobotStructureError, match="group 'typo' names joints the URDF does "
                                                  "not have: joint_44"):
        robot_from_files(*toy, options=RobotOptions.of(group="typo"))


def test_base_and_tip_links_choose_the_chain(toy: tuple[Path, Path]) -> None:
    robot = robot_from_files(toy[0], options=RobotOptions.of(base="link_1", tip="link_3"))
    assert robot.chain.joint_names == ("joint_2", "joint_3")


def test_continuous_joints_plan_on_one_turn(toy: tuple[Path, Path]) -> None:
    robot = robot_from_files(*toy)
    lim = robot.chain.joint("joint_3").limits
    assert lim is not None and (lim.lower, lim.upper) == (-np.pi, np.pi)
    assert robot.kinematics.nq == 4


def _variant(tmp_path: Path, old: str, new: str) -> Path:
    text = URDF.format(pkg=PACKAGE, folder=tmp_path / "ws" / PACKAGE)
    assert old in text
    path = tmp_path / "ws" / PACKAGE / "urdf" / "variant.urdf"
    path.write_text(text.replace(old, new))
    return path


@pytest.mark.parametrize(("old", "new", "says"), [
    ('<joint name="joint_1" type="revolute">', '<joint name="joint_1" type="floating">',
     "a floating joint (joint_1)"),
    ('<joint name="tool0_joint" type="fixed">',
     '<joint name="loop" type="fixed"><parent link="link_1"/><child link="link_4"/></joint>'
     '<joint name="tool0_joint" type="fixed">', "a closed loop: link link_4"),
    ('<mimic joint="finger_l_joint" multiplier="1" offset="0"/>', "",
     "a branched robot without a planning group"),
])
def test_what_has_no_chain_to_plan_is_one_line_and_exit_13(
        toy: tuple[Path, Path], tmp_path: Path, old: str, new: str, says: str) -> None:
    urdf = _variant(tmp_path, old, new)
    with pytest.raises(RobotStructureError, match=re.escape(says)):
        robot_from_files(urdf)
    run = subprocess.run([sys.executable, "-m", "usar_arm", "ik", "--urdf", str(urdf), "--pose",
                          "0.1", "0", "0.5", "0", "0", "0"], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == EXIT_BAD_DESCRIPTION == 13
    errors = [line for line in run.stderr.splitlines() if "error" in line]
    assert len(errors) == 1 and says in errors[0] and "Traceback" not in run.stderr


def test_an_unknown_tip_or_group_is_exit_13_with_the_choices(
        toy: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["ik", "--urdf", str(toy[0]), "--tip-link", "nowhere", "--pose", "0.1", "0",
                 "0.5", "0", "0", "0"])
    err = capsys.readouterr().err
    assert code == 13 and "no link 'nowhere'" in err and "link_4" in err
    with pytest.raises(FileFormatError, match="no planning group 'legs'; groups: arm, wrist"):
        robot_from_files(*toy, options=RobotOptions.of(group="legs"))


def test_group_options_without_a_urdf_are_usage_errors() -> None:
    with pytest.raises(SystemExit) as stop:
        main(["ik", "--tip-link", "tool0", "--pose", "0.1", "0", "0.5", "0", "0", "0"])
    assert stop.value.code == 2


def test_ik_and_plan_on_a_mesh_arm_from_the_command_line(
        toy: tuple[Path, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """What a new user types: the gripper's finger joints are held, not asked for."""
    robot = robot_from_files(*toy)
    goal = np.array([0.4, -0.6, 0.8, 0.05])
    assert not robot.collision_world().in_collision(goal)
    x, y, z = robot.kinematics.frame_pose(goal, "tool0")[:3, 3]
    rot = robot.kinematics.frame_pose(goal, "tool0")[:3, :3]
    code = main(["ik", "--urdf", str(toy[0]), "--json", "--tolerance", "1e-6", "--pose",
                 str(x), str(y), str(z), *map(str, _rpy(rot))])
    assert code == 0
    solutions = json_out(capsys)["solutions"]
    assert any(np.allclose(robot.kinematics.frame_pose(np.array(q), "tool0"),
                           robot.kinematics.frame_pose(goal, "tool0"), atol=1e-5)
               for q in solutions)
    code = main(["plan", "--urdf", str(toy[0]), "--json", "--joints", *map(str, goal),
                 "--from-joints", "0", "0", "0", "0", "--out", str(tmp_path / "t.json")])
    assert code == 0 and json_out(capsys)["duration"] > 0
    planned = json.loads((tmp_path / "t.json").read_text())
    assert planned["joint_names"] == ["joint_1", "joint_2", "joint_3", "joint_4"]
    assert np.allclose(planned["q"][-1], goal)
    code = main(["render", "--urdf", str(toy[0]), "--out", str(tmp_path / "toy.png")])
    assert code == 0 and (tmp_path / "toy.png").stat().st_size > 10_000


def _rpy(rot: np.ndarray) -> tuple[float, float, float]:
    from usar_arm.core.spatial import matrix_to_rpy

    return matrix_to_rpy(rot)


def json_out(capsys: pytest.CaptureFixture[str]) -> dict:
    return json.loads(capsys.readouterr().out)


def test_the_library_takes_the_same_choices(toy: tuple[Path, Path], tmp_path: Path) -> None:
    from usar_arm import Arm

    arm = Arm.from_files(toy[0], toy[1], group="wrist", tip="link_4")
    assert tuple(arm.joint_names) == ("joint_3", "joint_4")
    assert arm.fk(np.zeros(2))[2, 3] == pytest.approx(0.05 + 0.2 + 0.3 + 0.24)
    urdf = _moved(toy[0], tmp_path)
    hull = Arm.from_files(urdf, package_paths={PACKAGE: str(toy[0].parents[1])},
                          convex_hull=True, base="base_link", tip="tool0")
    assert tuple(hull.joint_names) == ("joint_1", "joint_2", "joint_3", "joint_4")
