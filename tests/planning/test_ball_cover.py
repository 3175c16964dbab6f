"""The balls around a mesh's surface (planning/ball_cover.py) and the compiled verdicts' second
look with them (planning/bounds_balls.py): every point of every triangle is in a leaf and every
leaf in its group; a ball gap is never more than python-fcl's distance; the balls only ever
turn an undecided pair into a cleared one, and they do on the test arm. And a walk's body
pairs close only by the joints between them (a turn of the first joint alone moves no body
against another)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from usar_arm.planning import bounds, bounds_balls
from usar_arm.planning.ball_cover import cover, split_triangles
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.planning.scene import Box, Scene, SceneObject, Sphere

from ..urdf.mesh_robot import write_robot

coordinate = st.floats(-0.3, 0.3, allow_nan=False, width=64)


def _area(tris: np.ndarray) -> float:
    return float(np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]),
                                axis=1).sum() / 2)


@settings(max_examples=60, deadline=None)
@given(vertices=arrays(np.float64, st.tuples(st.integers(3, 12), st.just(3)),
                       elements=coordinate),
       seed=st.integers(0, 2**16), leaf=st.floats(0.01, 0.2))
def test_every_point_of_every_triangle_is_in_a_leaf_and_every_leaf_in_its_group(
        vertices: np.ndarray, seed: int, leaf: float) -> None:
    rng = np.random.default_rng(seed)
    faces = rng.integers(0, len(vertices), (8, 3))
    balls = cover(vertices, faces, leaf, 4 * leaf)
    tris = vertices[faces]
    w = rng.dirichlet(np.ones(3), (len(tris), 40))  # points on each triangle, corners too
    points = np.concatenate([np.einsum("tkc,tcd->tkd", w, tris).reshape(-1, 3),
                             tris.reshape(-1, 3)])
    inside = np.linalg.norm(points[:, None] - balls.leaves[None, :, :3], axis=2) \
        <= balls.leaves[None, :, 3] + 1e-12
    assert inside.any(axis=1).all()
    ends = balls.groups[:, 4:6].astype(int)
    assert ends[0, 0] == 0 and ends[-1, 1] == len(balls.leaves)
    assert (ends[1:, 0] == ends[:-1, 1]).all() and (ends[:, 1] > ends[:, 0]).all()
    for g, (lo, hi) in zip(balls.groups, ends, strict=True):
        reach = np.linalg.norm(balls.leaves[lo:hi, :3] - g[:3], axis=1) + balls.leaves[lo:hi, 3]
        assert (reach <= g[3]).all()


@settings(max_examples=60, deadline=None)
@given(tris=arrays(np.float64, st.tuples(st.integers(1, 6), st.just(3), st.just(3)),
                   elements=coordinate), longest=st.floats(0.005, 0.5))
def test_split_triangles_keep_the_surface_with_short_edges(tris: np.ndarray,
                                                           longest: float) -> None:
    pieces = split_triangles(tris, longest)
    edges = np.linalg.norm(pieces[:, [1, 2, 0]] - pieces, axis=2)
    assert (edges <= longest).all()
    assert _area(pieces) == pytest.approx(_area(tris), rel=1e-9, abs=1e-15)


def test_a_mesh_without_triangles_is_refused() -> None:
    with pytest.raises(ValueError, match="without triangles"):
        cover(np.zeros((3, 3)), np.zeros((0, 3), dtype=np.int64))


@pytest.fixture(scope="module")
def toy(tmp_path_factory: pytest.TempPathFactory) -> Robot:
    urdf, srdf = write_robot(tmp_path_factory.mktemp("toy"))
    return robot_from_files(urdf, srdf)


def _scene() -> Scene:
    pose = np.eye(4)
    pose[:3, 3] = (0.25, 0.1, 0.45)
    table = np.eye(4)
    table[2, 3] = -0.02
    return Scene("test", (SceneObject("table", Box((1.0, 1.0, 0.04)), table, ("base_link",)),
                          SceneObject("ball", Sphere(0.08), pose)))


def test_a_ball_gap_is_never_more_than_fcls_distance(toy: Robot) -> None:
    """Over random configurations of the test arm, for every checked pair with a mesh body:
    the balls' gap is at most python-fcl's distance of the shapes (and at most ``eps`` when
    they touch)."""
    world = toy.collision_world(_scene())
    packed = world.verdicts.packed  # (the kernel's own arrays, as the world hands them over)
    links, kind, obstacles, axes, groups, leaves = (packed.links, packed.kind, packed.obstacles,
                                                    packed.axes, packed.groups, packed.leaves)
    rr, rs = world._rr, world._rs
    meshes = [k for k in range(len(links)) if bounds_balls.has_balls(links, k)]
    assert meshes, "the test arm has mesh bodies"
    rng = np.random.default_rng(4)
    compared = 0
    for q in rng.uniform(toy.chain.lower(), toy.chain.upper(), (1000, toy.chain.dof)):
        poses = bounds.check(q[None], packed, bounds.EPS, bounds.MARGIN)[0][0]
        seg = np.empty((6, len(links), 3))
        bounds.axis_segments(poses, links, seg)
        wg, wl, placed = bounds.ball_scratch(links, groups, leaves)
        for k in meshes:
            bounds_balls.place(poses, links, groups, leaves, k, wg, wl, placed)
        for p, (i, j) in enumerate(rr):
            if i not in meshes and j not in meshes:
                continue
            a, b = (i, j) if i in meshes else (j, i)
            gap = bounds_balls.pair_gap(a, b, seg, poses, links, groups, leaves, wg, wl, placed,
                                        bounds.EPS)
            truth = world._exact.distance(poses, rr[p:p + 1], rs[:0])
            assert gap <= max(truth, bounds.EPS) + 1e-12, (q.tolist(), p)
            compared += 1
        for p, (i, s) in enumerate(rs):
            if i not in meshes:
                continue
            gap = bounds_balls.obstacle_gap(i, int(kind[s]), obstacles[s], axes[s], poses,
                                            links, groups, leaves, wg, wl, placed, bounds.EPS)
            truth = world._exact.distance(poses, rr[:0], rs[p:p + 1])
            assert gap <= max(truth, bounds.EPS) + 1e-12, (q.tolist(), p)
            compared += 1
    assert compared > 500


def test_the_balls_only_clear_pairs_the_cylinders_left_undecided(toy: Robot) -> None:
    """The same verdicts with and without the balls, except undecided pairs the balls clear:
    there are such pairs on the test arm, and none of them is in contact."""
    world = toy.collision_world(_scene())
    packed = world.verdicts.packed
    bare = packed._replace(links=packed.links.copy())
    bare.links[:, bounds.COVER_FROM] = bare.links[:, bounds.COVER_TO] = 0
    qs = np.random.default_rng(8).uniform(toy.chain.lower(), toy.chain.upper(),
                                          (2000, toy.chain.dof))
    poses, with_balls, _ = bounds.check(qs, packed, bounds.EPS, bounds.MARGIN)
    _, without, _ = bounds.check(qs, bare, bounds.EPS, bounds.MARGIN)
    changed = with_balls != without
    assert (without[changed] == bounds.UNDECIDED).all()
    assert (with_balls[changed] == bounds.CLEAR).all()
    assert changed.sum() > 50
    n_rr = len(world._rr)
    for n, p in zip(*np.nonzero(changed), strict=True):  # python-fcl on that pair of bodies
        static, i, j = (False, *world._rr[p]) if p < n_rr else (True, *world._rs[p - n_rr])
        assert not world._exact.every_pair(poses[n], [(static, int(i), int(j))])


def test_turning_the_first_joint_alone_moves_no_body_against_another(kr60: Robot) -> None:
    """In the empty scene, a segment that turns joint 1 alone cannot bring two bodies together
    (both turn with it), so the walk settles the body pairs without stepping along it; the
    answer is still that of checking every configuration."""
    world = kr60.collision_world()
    compiled = world._compiled
    a = np.array([0.0, -1.2, 1.9, 0.3, 1.4, 0.0])
    assert not world.in_collision(a)
    b = a.copy()
    b[0] += 2.0
    steps = 400
    evaluated = compiled.segment_free(a, b, steps, world._any_contact)[1]
    qs = np.linspace(a, b, steps + 1)
    assert world.segment_free(a, b, steps) == (not any(world.contacts_brute_force(q)
                                                       for q in qs))
    assert evaluated < steps / 20


def test_a_folding_mesh_arm_walk_answers_as_checking_every_configuration(toy: Robot) -> None:
    """Segments that fold the test arm onto itself (its later joints only, empty scene): the
    body pairs close by those joints alone, and no contact is missed between the checked
    configurations."""
    world = toy.collision_world(Scene("empty", ()))
    rng = np.random.default_rng(12)
    lo, hi = toy.chain.lower(), toy.chain.upper()
    blocked = 0
    for _ in range(120):
        a = rng.uniform(lo, hi)
        b = a.copy()
        b[1:] = np.clip(a[1:] + rng.normal(0.0, 0.8, len(a) - 1), lo[1:], hi[1:])
        steps = int(rng.integers(2, 150))
        qs = a + (b - a) * (np.arange(steps + 1) / steps)[:, None]
        truth = not any(world.contacts_brute_force(q) for q in qs)
        blocked += not truth
        assert world.segment_free(a, b, steps) == truth, (a.tolist(), b.tolist(), steps)
    assert 10 < blocked < 110
