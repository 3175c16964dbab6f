"""The compiled broadphase (usar_arm.planning.bounds): never clears a pair in contact, never
proves a contact that python-fcl does not see, and places the links where Pinocchio does.

References here share no code with the kernel: segment distances from a dense scan, shapes from
python-fcl's own primitives, link poses from Pinocchio (through the collision world's
``contacts_brute_force`` / ``set_configuration`` path).
"""

from __future__ import annotations

import fcl
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from usar_arm.planning import bounds, bounds_walk, gaps
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Sphere
from usar_arm.planning.scene_file import BUILTIN, load_scene

CLEAR, CONTACT, UNDECIDED = bounds.CLEAR, bounds.CONTACT, bounds.UNDECIDED


def _scan_distance(p1: np.ndarray, d1: np.ndarray, p2: np.ndarray, d2: np.ndarray) -> float:
    """Segment distance by brute force: 2001 points on each segment, every pair."""
    s = np.linspace(0.0, 1.0, 2001)
    a = p1 + s[:, None] * d1
    b = p2 + s[:, None] * d2
    best = np.inf
    for chunk in np.array_split(a, 20):
        best = min(best, float(np.min(np.linalg.norm(chunk[:, None] - b[None], axis=2))))
    return best


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12))
def test_segment_distance_matches_a_dense_scan(v: list[float]) -> None:
    p1, d1, p2, d2 = (np.array(v[k:k + 3]) for k in range(0, 12, 3))
    got = bounds.segment_distance(p1, d1, p2, d2)
    scan = _scan_distance(p1, d1, p2, d2)
    step = (np.linalg.norm(d1) + np.linalg.norm(d2)) / 2000
    assert scan - step - 1e-12 <= got <= scan + 1e-12


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12), st.integers(0, 1))
def test_rows_distance_is_segment_distance_read_by_index(v: list[float], row: int) -> None:
    """The kernels' index-reading form gives the same float, to the bit."""
    p1, d1, p2, d2 = (np.array(v[k:k + 3]) for k in range(0, 12, 3))
    seg = np.zeros((4, 3, 3))  # rows (start, direction) at ``2 * row``; bodies 2 and 0
    seg[2 * row, 2], seg[2 * row + 1, 2], seg[2 * row, 0], seg[2 * row + 1, 0] = p1, d1, p2, d2
    assert gaps.rows_distance(seg, 2 * row, 2, 0) == bounds.segment_distance(p1, d1, p2, d2)


@pytest.mark.parametrize(("p1", "d1", "p2", "d2", "expected"), [
    ((0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 0, 0), 1.0),           # parallel, overlapping
    ((0, 0, 0), (1, 0, 0), (3, 2, 0), (1, 0, 0), np.hypot(2, 2)),  # parallel, apart
    ((0, 0, 0), (2, 0, 0), (1, -1, 0.5), (0, 2, 0), 0.5),        # crossing at a height
    ((0, 0, 0), (0, 0, 0), (0, 0, 3), (0, 0, 0), 3.0),           # two points
    ((1, 1, 1), (0, 0, 0), (0, 0, 0), (2, 0, 0), np.sqrt(2)),    # point and segment
])
def test_segment_distance_literal_cases(p1: tuple, d1: tuple, p2: tuple, d2: tuple,
                                        expected: float) -> None:
    got = bounds.segment_distance(*(np.array(x, float) for x in (p1, d1, p2, d2)))
    assert got == pytest.approx(expected, abs=1e-12)


def _pose(rotvec: np.ndarray, position: np.ndarray) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    t[:3, 3] = position
    return t


def _verdict(link_pose: np.ndarray, radius: float, half: float, kind: int,
             obstacle_pose: np.ndarray, size: np.ndarray) -> int:
    world = np.ascontiguousarray(link_pose[None, None, :3, :])
    verdicts = bounds.classify(world, np.array([radius]), np.array([half]),
                               np.zeros((0, 2), np.int64), np.array([[0, 0]], np.int64),
                               np.array([kind], np.int64),
                               np.ascontiguousarray(obstacle_pose[None, :3, :]),
                               np.asarray(size, float).reshape(1, 3), bounds.EPS,
                               bounds.MARGIN)
    return int(verdicts[0, 0])


def _fcl_hit(a: fcl.CollisionGeometry, ta: np.ndarray, b: fcl.CollisionGeometry,
             tb: np.ndarray) -> bool:
    oa = fcl.CollisionObject(a, fcl.Transform(ta[:3, :3], ta[:3, 3]))
    ob = fcl.CollisionObject(b, fcl.Transform(tb[:3, :3], tb[:3, 3]))
    return fcl.collide(oa, ob, fcl.CollisionRequest(), fcl.CollisionResult()) > 0


KINDS = {"box": bounds.BOX, "sphere": bounds.SPHERE, "cylinder": bounds.CAPSULE}


@settings(max_examples=400, deadline=None)
@given(kind=st.sampled_from(sorted(KINDS)),
       v=st.lists(st.floats(-1.0, 1.0), min_size=12, max_size=12),
       dims=st.lists(st.floats(0.01, 0.6), min_size=5, max_size=5))
def test_a_link_against_any_obstacle_agrees_with_fcl(kind: str, v: list[float],
                                                     dims: list[float]) -> None:
    link = _pose(np.array(v[0:3]) * 3, np.array(v[3:6]) * 0.8)
    other = _pose(np.array(v[6:9]) * 3, np.array(v[9:12]) * 0.8)
    radius, half = dims[0], dims[1]
    if kind == "box":
        size, shape = np.array(dims[2:5]), fcl.Box(*(2 * np.array(dims[2:5])))
    elif kind == "sphere":
        size, shape = np.array([dims[2], 0, 0]), fcl.Sphere(dims[2])
    else:
        size, shape = np.array([dims[2], dims[3], 0]), fcl.Cylinder(dims[2], 2 * dims[3])
    verdict = _verdict(link, radius, half, KINDS[kind], other, size)
    truth = _fcl_hit(fcl.Cylinder(radius, 2 * half), link, shape, other)
    if verdict == CLEAR:
        assert not truth, "a pair in contact was cleared"
    if verdict == CONTACT:
        assert truth, "a contact was proven that python-fcl does not see"


@pytest.mark.parametrize(("gap", "allowed"), [
    (1e-6, {CLEAR}),                # resting just above the box: provably apart
    (0.0, {UNDECIDED}),             # touching: the exact judge decides
    (-1e-6, {UNDECIDED}),           # a micron inside: within the proof margin, exact judge
    (-1e-3, {CONTACT}),             # a millimetre inside: proven
    (-0.5, {CONTACT}),              # the whole cylinder sunk into the box (nested)
])
def test_a_cylinder_standing_on_a_box(gap: float, allowed: set[int]) -> None:
    radius, half, box_half = 0.1, 0.3, np.array([1.0, 1.0, 0.5])
    link = _pose(np.zeros(3), np.array([0.2, -0.1, box_half[2] + half + gap]))
    assert _verdict(link, radius, half, bounds.BOX, np.eye(4), box_half) in allowed


def test_a_mesh_is_cleared_by_its_box_but_never_proven() -> None:
    """Even a cylinder deep inside a mesh's bounding box is left to FCL (a mesh is a surface)."""
    assert _verdict(np.eye(4), 0.05, 0.05, bounds.HULL, np.eye(4),
                    np.array([1.0, 1.0, 1.0])) == UNDECIDED
    far = _pose(np.zeros(3), np.array([5.0, 0.0, 0.0]))
    assert _verdict(far, 0.05, 0.05, bounds.HULL, np.eye(4), np.ones(3)) == CLEAR


def test_degenerate_shapes_are_never_cleared_while_touching() -> None:
    flat = _pose(np.zeros(3), np.array([0.0, 0.0, 0.5 - 1e-4]))  # a disc of height 0
    assert _verdict(flat, 0.2, 0.0, bounds.BOX, np.eye(4), np.full(3, 0.5)) != CLEAR
    tiny = np.array([1e-9, 0.0, 0.0])
    assert _verdict(_pose(np.zeros(3), np.array([0.0, 0.0, 0.5999])), 0.1, 0.1,
                    bounds.SPHERE, _pose(np.zeros(3), tiny), np.array([0.5, 0, 0])) != CLEAR


@pytest.mark.parametrize("robot", ["kr60", "fanuc"])
def test_link_poses_equal_pinocchio(robot: str, request: pytest.FixtureRequest) -> None:
    arm: Robot = request.getfixturevalue(robot)
    world = arm.collision_world()
    qs = np.random.default_rng(5).uniform(arm.chain.lower(), arm.chain.upper(),
                                          size=(200, arm.chain.dof))
    poses, _ = world.bounded_poses(qs)
    for q, got in zip(qs, poses, strict=True):
        world.set_configuration(q)
        assert np.allclose(got, world._world[:, :3, :], atol=1e-12)


def _random_scene(rng: np.random.Generator, count: int) -> Scene:
    objects = []
    for k in range(count):
        pose = _pose(rng.normal(size=3), rng.uniform([-1.8, -1.8, -0.2], [1.8, 1.8, 2.2]))
        kind = k % 4
        if kind == 0:
            shape: object = Box(tuple(rng.uniform(0.05, 0.8, 3)))
        elif kind == 1:
            shape = CylinderShape(float(rng.uniform(0.03, 0.4)), float(rng.uniform(0.05, 1.0)))
        elif kind == 2:
            shape = Sphere(float(rng.uniform(0.03, 0.4)))
        else:  # a tetrahedron
            v = rng.uniform(-0.3, 0.3, (4, 3))
            shape = Mesh(v, np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]))
        objects.append(SceneObject(f"o{k}", shape, pose))  # type: ignore[arg-type]
    return Scene("random", tuple(objects))


def _agree(world: object, qs: np.ndarray) -> tuple[int, int]:
    """Compare the fast paths with brute force; returns (configurations, colliding)."""
    fast = world.contacts_many(qs)  # type: ignore[attr-defined]
    flags = world.in_collision_many(qs)  # type: ignore[attr-defined]
    colliding = 0
    for q, found, flag in zip(qs, fast, flags, strict=True):
        truth = world.contacts_brute_force(q)  # type: ignore[attr-defined]
        assert found == truth, f"at {q.tolist()}: fast {found}, brute force {truth}"
        assert bool(flag) == bool(truth)
        colliding += bool(truth)
    return len(qs), colliding


@pytest.mark.parametrize("scene", list(BUILTIN))
def test_the_world_agrees_with_brute_force_in_each_shipped_scene(kr60: Robot,
                                                                 scene: str) -> None:
    world = kr60.collision_world(load_scene(scene))
    qs = np.random.default_rng(11).uniform(kr60.chain.lower(), kr60.chain.upper(), (1500, 6))
    _, colliding = _agree(world, qs)
    assert colliding > 0 or scene == "empty"
    for q in qs[:300]:
        assert world.in_collision(q) == bool(world.contacts_brute_force(q))


def test_the_world_agrees_with_brute_force_in_random_scenes(kr60: Robot) -> None:
    rng = np.random.default_rng(12)
    for _ in range(6):
        world = kr60.collision_world(_random_scene(rng, 12), padding=float(rng.uniform(0, 0.05)))
        _agree(world, rng.uniform(kr60.chain.lower(), kr60.chain.upper(), (400, 6)))


@pytest.mark.parametrize("scene", list(BUILTIN))
def test_a_segment_walk_answers_as_checking_every_configuration(kr60: Robot,
                                                                 scene: str) -> None:
    """segment_free skips configurations the clearance proves free; its answer must equal
    brute-force FCL on every one of the segment's configurations."""
    world = kr60.collision_world(load_scene(scene))
    rng = np.random.default_rng(21)
    lo, hi = kr60.chain.lower(), kr60.chain.upper()
    outcomes = set()
    for _ in range(120):
        a = rng.uniform(lo, hi)
        b = np.clip(a + rng.normal(0.0, 0.4, 6), lo, hi)
        steps = int(rng.integers(1, 300))
        qs = a + (b - a) * (np.arange(steps + 1) / steps)[:, None]
        truth = not any(world.contacts_brute_force(q) for q in qs)
        assert world.segment_free(a, b, steps) == truth, (a.tolist(), b.tolist(), steps)
        outcomes.add(truth)
    assert outcomes == {True, False} or scene == "empty"


@pytest.mark.slow
def test_a_million_configurations_agree_with_brute_force(kr60: Robot, fanuc: Robot) -> None:
    """1,000,000 configurations: the four shipped scenes and random box/cylinder/sphere/mesh
    scenes, KR60 and the Fanuc on its rail; every verdict equal to FCL on every pair."""
    rng = np.random.default_rng(2026)
    total = colliding = 0
    worlds = [kr60.collision_world(load_scene(s)) for s in BUILTIN]
    worlds += [kr60.collision_world(_random_scene(rng, 20)) for _ in range(8)]
    worlds += [fanuc.collision_world(load_scene("cage")), fanuc.collision_world(
        _random_scene(rng, 20))]
    per_world = 1_000_000 // len(worlds) + 1
    for world in worlds:
        chain = world.chain
        for _ in range(-(-per_world // 5000)):
            qs = rng.uniform(chain.lower(), chain.upper(), (5000, chain.dof))
            n, c = _agree(world, qs)
            total, colliding = total + n, colliding + c
    print(f"{total} configurations, {colliding} in contact, 0 disagreements")
    assert total >= 1_000_000


@pytest.mark.parametrize("scene", ["table", "cage", "boxes"])
def test_a_learnt_links_bodies_are_one_group_that_changes_no_verdict(kr60: Robot,
                                                                     scene: str) -> None:
    """A learnt link is a body cylinder and its core along one axis: the kernel tests the
    capsule around both first, for every link pair and obstacle. That may only save work: the
    verdicts, and where a walk first meets a contact, are those of testing every body alone."""
    world = kr60.collision_world(_random_scene(np.random.default_rng(9), 40) if scene == "boxes"
                                 else load_scene(scene))
    packed = world.verdicts.packed  # (the kernel's own arrays, as the world hands them over)
    links = packed.links
    owners, count = np.unique(links[:, bounds.OWNER], return_counts=True)
    paired = np.isin(links[:, bounds.OWNER], owners[count > 1])
    assert paired.sum() >= 12, "the six learnt links are a body and a core each"
    assert (links[paired, bounds.GROUP] >= 0).all(), "every learnt body is in its link's group"
    assert (links[~paired, bounds.GROUP] == -1).all(), "a one-body link (the tool) is alone"
    assert len(set(links[paired, bounds.GROUP])) == len(owners[count > 1])
    alone = packed._replace(links=links.copy())
    alone.links[:, bounds.GROUP] = -1
    alone.links[:, bounds.NEXT] = -1
    qs = np.random.default_rng(5).uniform(kr60.chain.lower(), kr60.chain.upper(), (3000, 6))
    grouped_verdicts = bounds.check(qs, packed, bounds.EPS, bounds.MARGIN)[1]
    alone_verdicts = bounds.check(qs, alone, bounds.EPS, bounds.MARGIN)[1]
    assert (grouped_verdicts == alone_verdicts).all()
    assert (grouped_verdicts != CLEAR).any()
    levers = np.ascontiguousarray(world._compiled.link_levers())
    decide = world._any_contact

    hits = 0
    for a, b in zip(qs[:150], qs[150:300], strict=True):
        grouped = bounds_walk.segment_free(a, b, 200, levers, packed, bounds.EPS, bounds.MARGIN,
                                           decide)
        single = bounds_walk.segment_free(a, b, 200, levers, alone, bounds.EPS,
                                          bounds.MARGIN, decide)
        assert grouped[0] == single[0], (a.tolist(), b.tolist())
        hits += not grouped[0]
    assert hits > 0


def test_a_links_bodies_must_share_their_obstacles_to_be_cleared_together() -> None:
    """The scene kernel clears a group's bodies against an obstacle at once, which is right
    only when every body of the link is checked against it (pairs are disabled link by link)."""
    from usar_arm.planning.verdicts import _group_chains
    group = np.array([1, 1, -1, 4, 4, 4])
    rs = np.array([[0, 0], [1, 0], [2, 0], [3, 0], [4, 0], [5, 0]])
    assert _group_chains(group, rs).tolist() == [-1, 0, -1, 5, 3, -1]  # group body first
    with pytest.raises(ValueError, match=r"bodies \[1, 0\] of one link"):
        _group_chains(group, rs[1:])


def test_only_bodies_along_one_axis_and_within_its_length_are_grouped() -> None:
    from usar_arm.planning.verdicts import link_groups

    def at(z: float, tilt: float = 0.0) -> np.ndarray:
        pose = np.eye(4)
        pose[:3, :3] = Rotation.from_euler("x", tilt).as_matrix()
        pose[2, 3] = z
        return pose

    radius, half = np.array([0.1, 0.01, 0.05, 0.05]), np.array([0.3, 0.5, 0.2, 0.2])
    owner, group, group_radius = link_groups(["a", "a", "b", "b"], radius, half,
                                             np.array([at(0.0), at(0.0), at(0.0), at(0.1)]))
    assert owner.tolist() == [0, 0, 1, 1]
    assert group.tolist() == [1, 1, -1, -1]  # b's second body reaches past the first's end
    assert group_radius[0] == group_radius[1] == pytest.approx(0.1)
    _, tilted, _ = link_groups(["a", "a"], radius[:2], half[:2],
                               np.array([at(0.0), at(0.0, 0.2)]))
    assert tilted.tolist() == [-1, -1]
