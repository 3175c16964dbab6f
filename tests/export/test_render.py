"""Pictures and replays: arm renders, trajectory plots and the viser HTML replay, on a real KR60
description, the built-in 'table' scene and a planned motion."""

from __future__ import annotations

import sys
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from usar_arm.control.motion import MotionPlan, plan_motion
from usar_arm.control.trajectory import MotionLimits, Trajectory
from usar_arm.core.errors import InvalidInputError
from usar_arm.export.plot import jerk_samples, plot_trajectory
from usar_arm.export.render import render_arm, tool_path
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.planning.scene import Scene
from usar_arm.planning.scene_file import load_scene

KR60_URDF = Path(__file__).resolve().parents[2] / "robots" / "generated" / "KR60.urdf"
HOME = np.zeros(6)
GOALS = [np.array([0.9, -0.3, 0.4, 0.0, 0.8, 0.0]), np.array([-0.6, -0.4, 0.3, 0.2, 0.6, 0.1])]


@dataclass(frozen=True)
class Samples:
    """What the executor measures (the shape of control.trajectory.ExecutedSamples)."""

    t: np.ndarray
    q: np.ndarray


@pytest.fixture(scope="module")
def robot() -> Robot:
    return robot_from_files(KR60_URDF)


@pytest.fixture(scope="module")
def table() -> Scene:
    return load_scene("table")


@pytest.fixture(scope="module")
def plan(robot: Robot, table: Scene) -> MotionPlan:
    world = robot.collision_world(table)
    assert not world.in_collision(HOME)
    goal = next(g for g in GOALS if not world.in_collision(g))
    return plan_motion(robot, world, HOME, goal=goal)


def _pixels(path: Path) -> np.ndarray:
    with Image.open(path) as img:
        return np.asarray(img.convert("RGB"), dtype=float)


# ------------------------------------------------------------------ render_arm, tool_path


def test_the_tool_path_follows_tool0_from_start_to_goal(robot: Robot, plan: MotionPlan) -> None:
    traj = plan.trajectory
    path = tool_path(robot.chain, traj, every=10)
    assert path.shape == (len(range(0, len(traj.t), 10)) + 1, 3)
    assert np.allclose(path[0], robot.chain.frame_pose("tool0", traj.q[0])[:3, 3])
    assert np.allclose(path[-1], robot.chain.frame_pose("tool0", traj.q[-1])[:3, 3])
    with pytest.raises(InvalidInputError, match="tool0"):
        tool_path(robot.chain, traj, frame="gripper")


def test_a_render_is_a_png_of_the_requested_size_and_not_blank(
        robot: Robot, table: Scene, plan: MotionPlan, tmp_path: Path) -> None:
    path = tool_path(robot.chain, plan.trajectory, every=20)
    out = render_arm(tmp_path / "pics" / "home.png", robot.chain, HOME, table, path,
                     size=(640, 480), title="KR60 at home")
    assert out == tmp_path / "pics" / "home.png" and out.exists()
    pixels = _pixels(out)
    assert pixels.shape == (480, 640, 3)
    assert pixels.std() > 20, "the picture is (nearly) blank"
    orange = (pixels[..., 0] > 180) & (pixels[..., 1] > 70) & (pixels[..., 1] < 150) \
        & (pixels[..., 2] < 90)
    assert orange.sum() > 500, "the links are not drawn in their KUKA orange"


def test_another_configuration_gives_another_picture(
        robot: Robot, table: Scene, plan: MotionPlan, tmp_path: Path) -> None:
    a = render_arm(tmp_path / "a.png", robot.chain, HOME, table, size=(400, 320))
    b = render_arm(tmp_path / "b.png", robot.chain, plan.goal, table, size=(400, 320),
                   ghosts=[HOME])
    assert _pixels(a).shape == _pixels(b).shape
    assert np.abs(_pixels(a) - _pixels(b)).mean() > 1.0


def test_render_rejects_a_configuration_of_the_wrong_length(robot: Robot,
                                                            tmp_path: Path) -> None:
    with pytest.raises(InvalidInputError, match="6 values"):
        render_arm(tmp_path / "x.png", robot.chain, np.zeros(5))
    assert not (tmp_path / "x.png").exists()


# ------------------------------------------------------------------ plot_trajectory


def test_jerk_samples_recover_a_known_constant_jerk_phase_by_phase() -> None:
    """A trajectory built by hand from piecewise-constant jerk (+2, then -3 rad/s^3 on one
    joint, 0 on the other): the plotted jerk is those numbers, at the interval midpoints."""
    t = np.arange(0.0, 2.0 + 1e-9, 0.01)
    jerk = np.where(t < 1.0, 2.0, -3.0)
    qdd = np.concatenate([[0.0], np.cumsum(jerk[:-1] * 0.01)])  # exact for a piecewise
    zeros = np.zeros_like(t)                                     # constant jerk per interval
    traj = Trajectory(("a", "b"), t, np.c_[zeros, zeros], np.c_[zeros, zeros],
                      np.c_[qdd, zeros], np.zeros((2, 2)),
                      MotionLimits(*(np.full(2, v) for v in (-1.0, 1.0, 1.0, 5.0, 4.0))))
    mid, got = jerk_samples(traj)
    assert np.allclose(mid, t[:-1] + 0.005)
    assert np.allclose(got[mid < 1.0, 0], 2.0) and np.allclose(got[mid > 1.0, 0], -3.0)
    assert np.all(got[:, 1] == 0.0)


def test_a_planned_trajectory_stays_within_its_jerk_limits(plan: MotionPlan) -> None:
    traj = plan.trajectory
    _, jerk = jerk_samples(traj)
    assert jerk.shape == (len(traj.t) - 1, len(traj.joint_names))
    assert np.all(np.abs(jerk) <= traj.limits.jerk * (1 + 1e-6))


def test_a_trajectory_plot_with_and_without_executed_samples(plan: MotionPlan,
                                                             tmp_path: Path) -> None:
    traj: Trajectory = plan.trajectory
    planned = plot_trajectory(tmp_path / "planned.png", traj, width=1000)
    t = np.arange(0.0, traj.duration, 0.004)
    q = np.array([traj.at(s)[0] for s in t]) + 0.002
    executed = plot_trajectory(tmp_path / "executed.png", traj, Samples(t, q), jerk=False,
                               width=1000)
    a, b = _pixels(planned), _pixels(executed)
    assert a.shape[1] == b.shape[1] == 1000 and a.std() > 10 and b.std() > 10
    assert a.shape[0] == b.shape[0] > 6 * 100, "one row per joint"
    with pytest.raises(InvalidInputError, match="one column per joint"):
        plot_trajectory(tmp_path / "bad.png", traj, Samples(t, q[:, :3]))


# ------------------------------------------------------------------ view (viser, optional)


def test_the_viewer_says_how_to_install_viser_when_it_is_missing(
        robot: Robot, plan: MotionPlan, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from usar_arm.export import view

    monkeypatch.setitem(sys.modules, "viser", None)
    with pytest.raises(InvalidInputError, match=r"usar-arm\[viz\]"):
        view.export_html(tmp_path / "r.html", robot.urdf, plan.trajectory)


def test_export_html_writes_a_self_contained_replay(robot: Robot, table: Scene,
                                                    plan: MotionPlan, tmp_path: Path) -> None:
    pytest.importorskip("viser")
    from usar_arm.export.view import export_html

    out = export_html(tmp_path / "replay.html", robot.urdf, plan.trajectory, table, fps=20)
    html = out.read_text()
    assert out.stat().st_size > 100_000
    assert "viser" in html.lower() and "__VISER_EMBED_DATA__" in html


def test_the_replay_server_serves_its_page_and_frees_its_port(robot: Robot, table: Scene,
                                                              plan: MotionPlan) -> None:
    pytest.importorskip("viser")
    from usar_arm.export.view import serve_replay

    with serve_replay(robot.urdf, plan.trajectory, table, port=0) as replay:
        with urllib.request.urlopen(replay.url, timeout=5) as page:
            assert page.status == 200 and b"<html" in page.read(2000).lower()
    with pytest.raises(OSError):
        urllib.request.urlopen(replay.url, timeout=2)
