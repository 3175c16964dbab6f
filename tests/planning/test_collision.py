"""The collision world: exact against brute force, scenes, padding, distances."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pytest

from usar_arm.core.errors import FileFormatError
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Box, Mesh
from usar_arm.planning.scene_file import BUILTIN, load_scene

SCENES = list(BUILTIN)


@pytest.mark.slow
@pytest.mark.parametrize("scene", SCENES)
def test_broadphase_agrees_with_brute_force_on_20000_configurations(kr60: Robot,
                                                                    scene: str) -> None:
    world = kr60.collision_world(load_scene(scene))
    rng = np.random.default_rng(2024 + SCENES.index(scene))
    qs = rng.uniform(kr60.chain.lower(), kr60.chain.upper(), size=(20_000, 6))
    batch = world.in_collision_many(qs)
    contacts = world.contacts_many(qs)
    colliding = 0
    for q, hit, found in zip(qs, batch, contacts, strict=True):
        truth = world.contacts_brute_force(q)
        assert found == truth, f"at {q.tolist()}: broadphase {found}, brute force {truth}"
        assert bool(hit) == bool(truth)
        colliding += bool(truth)
    assert 0 < colliding < len(qs)  # both outcomes are exercised
    for q in qs[:2000]:  # the single-configuration path too
        assert world.contacts(q) == world.contacts_brute_force(q)
        assert world.in_collision(q) == bool(world.contacts_brute_force(q))


def test_the_second_arm_in_the_cage_agrees_with_brute_force(fanuc: Robot) -> None:
    world = fanuc.collision_world(load_scene("cage"))
    qs = np.random.default_rng(8).uniform(fanuc.chain.lower(), fanuc.chain.upper(),
                                          size=(2000, 7))
    for q, found in zip(qs, world.contacts_many(qs), strict=True):
        assert found == world.contacts_brute_force(q)


def test_every_scene_leaves_the_home_pose_free(kr60: Robot) -> None:
    home = np.array(kr60.named_state("home"))
    for scene in SCENES:
        world = kr60.collision_world(load_scene(scene))
        assert not world.in_collision(home), (scene, world.contacts(home))
        assert world.distance(home) > 0.0


def test_disabled_pairs_are_never_reported(kr60: Robot) -> None:
    world = kr60.collision_world()
    qs = np.random.default_rng(3).uniform(kr60.chain.lower(), kr60.chain.upper(),
                                          size=(3000, 6))
    for pairs in world.contacts_many(qs):
        assert not set(pairs) & kr60.disabled


def test_padding_only_adds_contacts(kr60: Robot) -> None:
    scene = load_scene("table")
    plain, padded = kr60.collision_world(scene), kr60.collision_world(scene, padding=0.05)
    qs = np.random.default_rng(4).uniform(kr60.chain.lower(), kr60.chain.upper(),
                                          size=(2000, 6))
    a, b = plain.in_collision_many(qs), padded.in_collision_many(qs)
    assert np.all(b[a]) and b.sum() > a.sum()


def test_distance_is_the_clearance_and_agrees_with_contacts(kr60: Robot) -> None:
    world = kr60.collision_world(load_scene("shelf"))
    qs = np.random.default_rng(6).uniform(kr60.chain.lower(), kr60.chain.upper(),
                                          size=(300, 6))
    for q in qs:
        d = world.distance(q)
        if world.in_collision(q):
            assert d <= 1e-9
        else:
            assert d > 0.0
            padded = kr60.collision_world(world.scene, padding=d * 1.05 + 1e-6)
            assert padded.in_collision(q)  # a pad a little larger than the clearance touches


def test_scene_files_name_the_line_and_the_field(tmp_path: Path) -> None:
    cases = {
        "objects:\n  - name: a\n    box: [1, 2]\n    xyz: [0, 0, 0]\n": (3, "objects[0].box"),
        "objects:\n  - name: a\n    sphere: {radius: -1}\n    xyz: [0, 0, 0]\n":
            (3, "objects[0].sphere.radius"),
        "objects:\n  - name: a\n    box: [1, 1, 1]\n    colour: red\n    xyz: [0, 0, 0]\n":
            (4, "objects[0].colour"),
        "objects:\n  - name: a\n    box: [1, 1, 1]\n    xyz: [0, 0]\n": (4, "objects[0].xyz"),
        "objects:\n  - name: a\n    box: [1, 1, 1]\n    sphere: {radius: 1}\n    xyz: [0,0,0]\n":
            (2, "objects[0]"),
        "objects:\n  - {name: a, box: [1, 1, 1], xyz: [0, 0, 0]}\n"
        "  - {name: a, box: [1, 1, 1], xyz: [0, 0, 0]}\n": (3, "objects[1].name"),
        "objects:\n  - name: m\n    mesh: {file: nothere.stl}\n    xyz: [0, 0, 0]\n":
            (3, "objects[0].mesh.file"),
        "objects: [\n": (2, None),
    }
    for text, (line, field) in cases.items():
        path = tmp_path / "scene.yaml"
        path.write_text(text)
        with pytest.raises(FileFormatError) as info:
            load_scene(path)
        assert info.value.line == line, (text, info.value)
        assert info.value.field == field, (text, info.value)
        assert str(path) in str(info.value)


def test_shipped_scenes_load_with_every_shape_kind() -> None:
    table = load_scene("table")
    assert isinstance(table.object("fixture").shape, Mesh)
    assert isinstance(table.object("table_top").shape, Box)
    assert {o.name for o in load_scene("cage").objects} >= {"post_30", "beam_30"}
    assert load_scene("empty").objects == ()
    with pytest.raises(FileFormatError) as info:
        load_scene("kitchen")
    assert "table" in str(info.value)


def test_unknown_links_in_allow_are_rejected(kr60: Robot, tmp_path: Path) -> None:
    path = tmp_path / "s.yaml"
    path.write_text("objects:\n  - {name: f, box: [1, 1, 1], xyz: [0, 0, -2], allow: [link_9]}\n")
    with pytest.raises(FileFormatError) as info:
        kr60.collision_world(load_scene(path))
    assert "link_9" in str(info.value) and "link_6" in str(info.value)


@pytest.mark.parametrize("robot_name", ["kr60", "fanuc"])
def test_a_thin_plate_through_any_joint_touches_the_arm(robot_name: str,
                                                        request: pytest.FixtureRequest) -> None:
    """No gap at the joints: a 5 mm plate (0.4 m square, any orientation) centred on a joint's
    origin, or on the tip, collides with the arm, at random configurations (a rail carriage's
    joint on the mount excepted: nothing passes between a mount and the carriage standing on
    it). With one trimmed cylinder per link a 5 cm floor slab passed through the KR60's elbow;
    each link's thin core spans its joints. The joints are placed by yourdfpy's forward
    kinematics of the URDF text, the contacts are python-fcl's brute force."""
    import yourdfpy

    from usar_arm.planning.scene import Scene, SceneObject

    robot: Robot = request.getfixturevalue(robot_name)
    urdf = yourdfpy.URDF.load(io.StringIO(robot.urdf))
    moving = [j for j in robot.chain.joints if j.type.value != "fixed"]
    on_mount = moving[0].type.value == "prismatic" and not any(moving[0].origin.xyz)
    rng = np.random.default_rng(7)
    hits = 0
    for q in rng.uniform(robot.chain.lower(), robot.chain.upper(), size=(12, len(moving))):
        urdf.update_cfg(dict(zip([j.name for j in moving], q, strict=True)))
        points = [urdf.get_transform(j.child)[:3, 3] for j in moving]
        points.append(urdf.get_transform(robot.chain.frames["flange"])[:3, 3])
        for k, p in enumerate(points):
            if k == 0 and on_mount:
                continue
            axis = rng.normal(size=3)
            axis /= np.linalg.norm(axis)
            angle = rng.uniform(0, np.pi)
            kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                           [-axis[1], axis[0], 0]])
            pose = np.eye(4)
            pose[:3, :3] = np.eye(3) + np.sin(angle) * kx + (1 - np.cos(angle)) * kx @ kx
            pose[:3, 3] = p
            plate = SceneObject("plate", Box((0.4, 0.4, 0.005)), pose)
            world = robot.collision_world(Scene("plate", (plate,)))
            assert world.contacts_brute_force(q), (
                f"a plate through point {k} ({p.round(3).tolist()}) at q={q.round(3).tolist()} "
                "touches no link: the arm has a gap there")
            hits += 1
    assert hits == 12 * (len(moving) + 1 - on_mount)
