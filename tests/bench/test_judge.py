"""The benchmark's judge (bench/verify.py, bench/judge_reading.py): it imports nothing from
usar_arm, it sees contacts and gaps on hand-made cases whose answer is worked out here, it skips
the SRDF's disabled pairs and an obstacle's allowed links, it reads every scene from the scene's
YAML file itself (and finds there what the solvers are given as JSON), and it agrees with
usar-arm's own collision world on random KR60 configurations in every shipped scene."""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

import verify  # noqa: E402
from judge_reading import JudgedRobot, read_scene, read_scene_file  # noqa: E402

# A base cylinder (radius 0.1, length 0.4, centred 0.2 above the base) and an arm cylinder
# (radius 0.05, length 1.0) lying along the x axis of link_1, 0.5 above the base, centred
# 0.5 m out; link_1 turns about z.
URDF = """<robot name="probe">
  <link name="base_link"><collision><origin xyz="0 0 0.2"/>
    <geometry><cylinder radius="0.1" length="0.4"/></geometry></collision></link>
  <link name="link_1"><collision><origin xyz="0.5 0 0.5" rpy="0 1.5707963267948966 0"/>
    <geometry><cylinder radius="0.05" length="1.0"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link_1"/>
    <axis xyz="0 0 1"/><limit lower="-3.14" upper="3.14" effort="1" velocity="1"/></joint>
</robot>"""
SRDF_NONE = "<robot name='probe'/>"


def _box(x: float, y: float, z: float, size: tuple[float, float, float], **extra: object
         ) -> dict[str, object]:
    return {"name": "b", "type": "box", "xyz": [x, y, z], "quat_wxyz": [1, 0, 0, 0],
            "size": list(size), **extra}


def _judge(items: list[dict[str, object]], srdf: str = SRDF_NONE) -> verify.Judge:
    return verify.Judge(JudgedRobot.from_text(URDF, srdf), read_scene(items), ["j1"])


def test_the_judge_imports_nothing_from_usar_arm() -> None:
    for name in ("verify.py", "judge_reading.py"):
        tree = ast.parse((ROOT / "bench" / name).read_text())
        imported = [n.name for node in ast.walk(tree) if isinstance(node, ast.Import)
                    for n in node.names]
        imported += [node.module or "" for node in ast.walk(tree)
                     if isinstance(node, ast.ImportFrom)]
        assert not [m for m in imported if m.split(".")[0] == "usar_arm"], (name, imported)


@pytest.mark.parametrize(("gap", "hit"), [(0.001, False), (-0.001, True)])
def test_an_arm_link_above_a_box_by_a_millimetre_or_into_it(gap: float, hit: bool) -> None:
    # The arm cylinder's underside is at z = 0.5 - 0.05 = 0.45 along x in [0, 1] at q = 0; a
    # box 0.2 high whose top is at 0.45 - gap, under x = 0.8.
    top = 0.45 - gap
    judge = _judge([_box(0.8, 0.0, top - 0.1, (0.2, 0.2, 0.2))])
    assert bool(judge.colliding(np.array([[0.0]]))[0]) is hit
    # Turned a quarter turn about z, the arm points along y and misses the box by far.
    assert not judge.colliding(np.array([[np.pi / 2]]))[0]


def test_a_sphere_and_a_cylinder_obstacle_by_hand() -> None:
    # Arm axis along y at q = pi/2: points (0, 0..1, 0.5); a sphere of radius 0.1 at
    # (0, 0.5, 0.5 + 0.05 + 0.1 + d): apart for d > 0, touching for d < 0.
    for d, hit in ((0.002, False), (-0.002, True)):
        sphere = {"name": "s", "type": "sphere", "xyz": [0.0, 0.5, 0.65 + d], "radius": 0.1}
        assert bool(_judge([sphere]).colliding(np.array([[np.pi / 2]]))[0]) is hit
    # A vertical post of radius 0.05 at (0.3, 0): the base cylinder (r 0.1) is 0.15 away
    # from its axis -> touching exactly; move it 3 mm out -> apart (the arm passes above it).
    for x, hit in ((0.147, True), (0.153, False)):
        post = {"name": "p", "type": "cylinder", "xyz": [x, 0.0, 0.2], "radius": 0.05,
                "length": 0.3}
        assert bool(_judge([post]).colliding(np.array([[np.pi]]))[0]) is hit


def test_disabled_pairs_and_allowed_links_are_not_checked() -> None:
    # A box around the arm cylinder's middle, allowed to touch link_1: nothing to report; the
    # same box without the exemption: a contact.
    box = _box(0.5, 0.0, 0.5, (0.2, 0.2, 0.2), allow=["link_1"])
    assert not _judge([box]).colliding(np.array([[0.0]]))[0]
    box["allow"] = []
    assert _judge([box]).colliding(np.array([[0.0]]))[0]
    # A tall base that reaches the arm: a self contact, unless the SRDF disables the pair.
    tall = URDF.replace('origin xyz="0 0 0.2"', 'origin xyz="0 0 0.3"')
    tall = tall.replace('radius="0.1" length="0.4"', 'radius="0.1" length="0.6"')
    srdf = ("<robot name='probe'><disable_collisions link1='link_1' link2='base_link' "
            "reason='Adjacent'/></robot>")
    for text, hit in ((SRDF_NONE, True), (srdf, False)):
        judge = verify.Judge(JudgedRobot.from_text(tall, text), [], ["j1"])
        assert bool(judge.colliding(np.array([[0.0]]))[0]) is hit


@pytest.mark.parametrize("scene", ["table", "shelf", "cage"])
def test_the_judge_agrees_with_usar_arm_on_random_configurations(scene: str,
                                                                 tmp_path: Path) -> None:
    import scenes

    from usar_arm.planning.robot import robot_from_files

    urdf, srdf = ROOT / "robots/generated/KR60.urdf", ROOT / "robots/generated/KR60.srdf"
    robot = robot_from_files(urdf, srdf)
    sc = scenes.shipped(scene)
    spec = {"urdf": str(urdf), "srdf": str(srdf), "joint_names": list(robot.chain.joint_names),
            "scenes": {scene: scenes.to_json(sc, tmp_path)},
            "scene_files": {scene: str(scenes.shipped_file(scene))}}
    judge = verify.Judge.for_scene(spec, scene)
    world = robot.collision_world(sc)
    qs = np.random.default_rng(4).uniform(robot.chain.lower(), robot.chain.upper(), (300, 6))
    ours = world.in_collision_many(qs)
    theirs = judge.colliding(qs)
    assert (ours == theirs).all(), np.flatnonzero(ours != theirs)
    assert 0 < theirs.sum() < len(qs)


@pytest.mark.parametrize("scene", ["empty", "table", "shelf", "cage"])
def test_the_judge_reads_each_scene_file_itself_and_finds_what_the_solvers_are_given(
        scene: str, tmp_path: Path) -> None:
    import scenes  # writes the solvers' JSON with usar-arm's own scene parser

    mine = read_scene_file(scenes.shipped_file(scene))
    given = read_scene(scenes.to_json(scenes.shipped(scene), tmp_path))
    assert [o.name for o in mine] == [o.name for o in given] and (scene == "empty" or mine)
    for a, b in zip(mine, given, strict=True):
        assert (a.kind, a.allow, sorted(a.params)) == (b.kind, b.allow, sorted(b.params))
        np.testing.assert_allclose(a.pose, b.pose, rtol=0, atol=1e-12)
        for key, value in a.params.items():  # an STL stores float32 vertices
            np.testing.assert_allclose(value, b.params[key], rtol=0, atol=1e-6)


def test_the_boxes_scene_files_hold_the_boxes_the_solvers_get(tmp_path: Path) -> None:
    import scenes

    centres = np.random.default_rng(2).uniform(-2, 2, (5, 3))
    mine = read_scene_file(scenes.write_boxes_file(centres, 3, tmp_path))
    given = read_scene(scenes.to_json(scenes.boxes(centres, 3), tmp_path))
    assert [o.name for o in mine] == [o.name for o in given] == ["box_0", "box_1", "box_2"]
    for a, b in zip(mine, given, strict=True):
        assert a.params == b.params == {"size": [scenes.BOX_EDGE] * 3}
        np.testing.assert_array_equal(a.pose, b.pose)
    assert read_scene_file(scenes.write_boxes_file(centres, 0, tmp_path)) == []


def test_the_judge_of_a_problem_file_reads_the_scene_file_not_the_solvers_list(
        tmp_path: Path) -> None:
    # The solvers' list is empty; the YAML file holds the box under the arm: the judge sees it.
    (tmp_path / "probe.urdf").write_text(URDF)
    scene = tmp_path / "s.yaml"
    scene.write_text("name: s\nobjects:\n  - {name: b, box: [0.2, 0.2, 0.2], "
                     "xyz: [0.8, 0, 0.36], rpy: [0, 0, 0.3]}\n")
    spec = {"urdf": str(tmp_path / "probe.urdf"), "joint_names": ["j1"], "scenes": {"s": []},
            "scene_files": {"s": str(scene)}}
    assert verify.Judge.for_scene(spec, "s").colliding(np.array([[0.0]]))[0]
    assert not verify.Judge.for_scene({**spec, "scene_files": {}}, "s").colliding(
        np.array([[0.0]]))[0]


FIXTURE = ROOT / "usar_arm" / "data" / "scenes" / "meshes" / "fixture.stl"
CARRIED = {  # the judge's items (type and sizes, grasp in the link frame), as a problem file
    "box": {"type": "box", "size": [0.5, 0.12, 0.1]},
    "cylinder": {"type": "cylinder", "radius": 0.06, "length": 0.6},
    "sphere": {"type": "sphere", "radius": 0.15},
    "mesh": {"type": "mesh", "file": str(FIXTURE), "scale": 1.5},
}


@pytest.mark.parametrize("kind", sorted(CARRIED))
def test_the_judge_carries_attached_bodies_as_usar_arm_does(kind: str, tmp_path: Path) -> None:
    """A body under the KR60's gripper (box, cylinder, sphere or mesh, tilted): the judge,
    given its shape, link, grasp and touch links, finds the contacts usar-arm's carrying arm
    finds on random configurations in the table scene, the body's own included."""
    import scenes

    from usar_arm.core.spatial import quat_from_matrix, transform_from_xyz_rpy
    from usar_arm.planning.attach_file import parse_attach
    from usar_arm.planning.robot import robot_from_files

    urdf, srdf = ROOT / "robots/generated/KR60.urdf", ROOT / "robots/generated/KR60.srdf"
    robot = robot_from_files(urdf, srdf)
    grasp = transform_from_xyz_rpy((0.0, 0.05, 0.2), (0.3, 0.2, 0.1))
    item = {"name": "part", **CARRIED[kind], "xyz": grasp[:3, 3].tolist(),
            "quat_wxyz": quat_from_matrix(grasp[:3, :3]).tolist(),
            "link": "KR60gripper_tcp", "touch_links": ["KR60gripper"]}
    shape = ({"mesh": {"file": str(FIXTURE), "scale": 1.5}} if kind == "mesh" else
             {"box": CARRIED["box"]["size"]} if kind == "box" else
             {kind: {k: v for k, v in CARRIED[kind].items() if k != "type"}})
    body = parse_attach({"name": "part", "link": "KR60gripper_tcp", **shape,
                         "xyz": grasp[:3, 3].tolist(), "touch_links": ["KR60gripper"]},
                        "part", tmp_path).body()
    body = type(body)(body.name, body.link, body.shape, grasp, body.touch_links)
    carrying = robot.carrying([body])
    sc = scenes.shipped("table")
    spec = {"urdf": str(urdf), "srdf": str(srdf), "joint_names": list(robot.chain.joint_names),
            "scenes": {"table": scenes.to_json(sc, tmp_path)},
            "scene_files": {"table": str(scenes.shipped_file("table"))}, "attached": [item]}
    judge = verify.Judge.for_scene(spec, "table")
    bare = verify.Judge.for_scene({**spec, "attached": []}, "table")
    world = carrying.collision_world(sc)
    qs = np.random.default_rng(5).uniform(robot.chain.lower(), robot.chain.upper(), (400, 6))
    ours, theirs = world.in_collision_many(qs), judge.colliding(qs)
    assert (ours == theirs).all(), np.flatnonzero(ours != theirs)
    only_body = theirs & ~bare.colliding(qs)
    assert only_body.sum() > 10  # (configurations where the carried body alone collides)


def test_the_carry_stage_gives_the_solver_and_the_judge_the_same_part() -> None:
    """bench/carry.py's part as usar-arm builds it (``body_of``) and as the judge reads it
    (``read_attached``) sit at the same pose on the KR60 at random configurations."""
    import carry
    from judge_reading import read_attached

    from usar_arm.planning.robot import robot_from_files

    urdf, srdf = ROOT / "robots/generated/KR60.urdf", ROOT / "robots/generated/KR60.srdf"
    robot = robot_from_files(urdf, srdf).carrying([carry.body_of(carry.PART)])
    (part,) = read_attached([carry.PART])
    kin = verify.Kinematics(JudgedRobot.from_files(urdf, srdf), list(robot.chain.joint_names))
    for q in np.random.default_rng(6).uniform(robot.chain.lower(), robot.chain.upper(), (20, 6)):
        kin.update(q)
        np.testing.assert_allclose(robot.kinematics.frame_pose(q, "part"),
                                   kin.frame(part.link) @ part.body.pose, atol=1e-12)
    assert part.body.params["size"] == [0.12, 0.12, 0.10] and part.touch_links == {"KR60gripper"}
