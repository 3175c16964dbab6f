"""``usar-arm plan --attach`` and a batch problem's ``attach``, as a user runs them: the part
picked from the table scene, a body from a file, and the errors' exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from usar_arm.cli.main import main
from usar_arm.control.trajectory import load_with_executed
from usar_arm.core.errors import EXIT_IN_COLLISION, EXIT_INVALID_INPUT, EXIT_OK
from usar_arm.core.spatial import matrix_to_rpy
from usar_arm.planning.attach_file import parse_attach, read_attach
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import load_scene
from usar_arm.workspace.batch_file import parse_problems
from usar_arm.workspace.batch_job import BatchOptions, run_batch
from usar_arm.workspace.jobs import backend_for

from .attached_bodies import GRIPPER, KR60, TCP, kr60

GOAL = [2.732, 0.064, -2.081, -0.649, 0.726, 0.083]
"""A PTP goal from home whose straight path sweeps a carried 1.2 m bar through the table
scene (tests/planning/test_attached.py)."""
BAR = ('{"name": "bar", "link": "KR60gripper_tcp", "box": [1.2, 0.04, 0.04], '
       '"xyz": [0, 0, 0.05], "touch_links": ["KR60gripper"]}')


@pytest.fixture(scope="module")
def arm() -> Robot:
    return kr60()


def _tcp_down(arm: Robot, xyz: tuple[float, float, float]) -> np.ndarray:
    q = np.array(arm.home())
    k = arm.kinematics
    offset = np.linalg.inv(k.frame_pose(q, "tool0")) @ k.frame_pose(q, TCP)
    target = np.diag([1.0, -1.0, -1.0, 1.0])
    target[:3, 3] = xyz
    return target @ np.linalg.inv(offset)


def _pick(arm: Robot) -> np.ndarray:
    """The joints that put the suction point on the part's top."""
    return np.array(arm.ik_solver().solve(_tcp_down(arm, (1.45, -0.45, 0.80)),
                                          np.array(arm.home())).best.q)


def _held_part(arm: Robot) -> AttachedBody:
    """The table scene's part as the gripper holds it at the pick."""
    part = load_scene("table").object("part")
    grasp = np.linalg.inv(arm.kinematics.frame_pose(_pick(arm), TCP)) @ part.pose
    return AttachedBody("part", TCP, part.shape, grasp, (GRIPPER,))


def _bar() -> AttachedBody:
    return parse_attach(json.loads(BAR), "bar", Path(".")).body()


def _words(values: np.ndarray | list[float]) -> list[str]:
    return [repr(float(v)) for v in values]


def test_plan_attach_a_scene_object_and_lift_it(arm: Robot, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    up = _tcp_down(arm, (1.45, -0.45, 1.1))
    out = tmp_path / "lift.json"
    code = main(["plan", "--urdf", str(KR60), "--scene", "table", "--motion", "lin",
                 "--from-joints", *_words(_pick(arm)),
                 "--pose", *_words([*up[:3, 3], *matrix_to_rpy(up[:3, :3])]),
                 "--attach", "part", "--attach-link", TCP, "--touch-links", GRIPPER,
                 "--json", "--out", str(out), "-q"])
    assert code == EXIT_OK
    summary = json.loads(capsys.readouterr().out)
    assert summary["attached"] == [{"name": "part", "link": TCP}]
    trajectory, _ = load_with_executed(out)
    assert trajectory.info["attached"] == [{"name": "part", "link": TCP}]
    carried = arm.carrying([_held_part(arm)])
    last = carried.kinematics.frame_pose(trajectory.q[-1], "part")
    np.testing.assert_allclose(last[:3, 3], [1.45, -0.45, 1.05], atol=1e-5)
    world = carried.collision_world(load_scene("table"))
    lifted = [q for q in trajectory.q if carried.kinematics.frame_pose(q, "part")[2, 3] > 0.751]
    assert lifted and not any(world.contacts_brute_force(q) for q in lifted)


def test_plan_attach_a_body_file_goes_round(arm: Robot, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str]) -> None:
    body = tmp_path / "bar.json"
    body.write_text(BAR + "\n")
    out = tmp_path / "round.json"
    assert main(["plan", "--urdf", str(KR60), "--scene", "table", "--joints",
                 *_words(GOAL), "--attach", str(body), "--out", str(out), "-q"]) == EXIT_OK
    assert "carrying: bar on KR60gripper_tcp (may touch KR60gripper)" in capsys.readouterr().out
    trajectory, _ = load_with_executed(out)
    world = arm.carrying([read_attach(body).body()]).collision_world(load_scene("table"))
    assert not any(world.contacts_brute_force(q) for q in trajectory.q)
    assert world.in_collision_many(np.linspace(arm.home(), GOAL, 50)).any()


@pytest.mark.parametrize(("extra", "message"), [
    (["--attach-link", TCP], "need --attach OBJECT"),
    (["--attach", "part"], "needs --scene"),
    (["--attach", "part", "--scene", "table", "--attach-link", "hand"], "no link 'hand'"),
    (["--attach", "cup", "--scene", "table"], "no object of that name in scene 'table'"),
])
def test_plan_attach_errors_say_what_was_wrong(extra: list[str], message: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    got = main(["plan", "--urdf", str(KR60), "--joints", *_words(GOAL), *extra, "-q"])
    err = capsys.readouterr().err
    assert got == EXIT_INVALID_INPUT and message in err, err


def test_plan_attach_in_collision_is_refused_naming_the_pair(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    body = tmp_path / "deep.yaml"
    body.write_text("name: block\nlink: KR60gripper_tcp\nbox: [0.2, 0.2, 0.2]\nxyz: [0, 0, 0.05]\n")
    code = main(["plan", "--urdf", str(KR60), "--joints", *_words(GOAL), "--attach",
                 str(body), "-q"])
    assert code == EXIT_IN_COLLISION
    assert "block–KR60gripper" in capsys.readouterr().err


def test_batch_problems_attach_objects(arm: Robot) -> None:
    pick = _pick(arm).tolist()
    up = _tcp_down(arm, (1.45, -0.45, 1.1))
    lines = [
        {"id": "lift", "scene": "table", "attach": {"name": "part", "link": TCP,
                                                    "touch_links": [GRIPPER]},
         "plan": {"start": pick, "pose": up.tolist(), "motion": "lin"}},
        {"id": "round", "scene": "table", "attach": [json.loads(BAR)],
         "plan": {"start": arm.home(), "goal": GOAL}},
        {"id": "ik", "attach": json.loads(BAR), "ik": {"pose": up.tolist()}},
        {"id": "noseed", "scene": "table", "attach": {"name": "part"}, "ik": {"pose": [1] * 6}},
        {"id": "badlink", "scene": "table", "attach": {"name": "part", "link": "hand"},
         "plan": {"start": pick, "goal": GOAL}},
        {"id": "badbox", "attach": {"name": "b", "box": [1, 2], "xyz": [0, 0, 0]},
         "plan": {"start": pick, "goal": GOAL}},
    ]
    problems, bad = parse_problems("".join(json.dumps(x) + "\n" for x in lines))
    assert [b.id for b in bad] == ["noseed", "badbox"]
    assert "seed" in bad[0].message and "attach.box" in bad[1].message
    out, _ = run_batch(arm, problems, bad, BatchOptions(), backend_for(0))
    docs = {d["id"]: d for d in map(json.loads, out)}
    assert docs["lift"]["ok"] and docs["lift"]["attached"] == [{"name": "part", "link": TCP}]
    assert docs["round"]["ok"] and docs["ik"]["ok"], (docs["round"], docs["ik"])
    assert docs["badlink"]["error"]["type"] == "AttachError"
    assert "no link 'hand'" in docs["badlink"]["error"]["message"]
    world = arm.carrying([_bar()]).collision_world(load_scene("table"))
    assert not world.in_collision_many(np.array(docs["round"]["waypoints"])).any()
    assert problems[1].content() != parse_problems(json.dumps(
        {**lines[1], "attach": []}) + "\n")[0][0].content()  # (the job's key sees it)
