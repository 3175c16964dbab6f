"""Balls inside a closed mesh (:mod:`usar_arm.planning.inner_balls`) lie inside it, as trimesh
measures (its own ray tests and closest points; not its signed distance, whose sign is wrong
inside the overlapping shells of the UR5's meshes), and prove contacts python-fcl agrees with: a
solid obstacle that one of them reaches into and that reaches out of the mesh is crossed by
its surface; an obstacle wholly inside a mesh is not (FCL sees the surface only)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from usar_arm.core.shapes import Box
from usar_arm.planning import exact
from usar_arm.planning.collision import CollisionWorld
from usar_arm.planning.inner_balls import LEAST, axis_balls, closed, surface_distance
from usar_arm.planning.robot import robot_from_files
from usar_arm.planning.scene import Scene, SceneObject

from ..urdf.mesh_robot import write_robot


def _check_inside(mesh: trimesh.Trimesh, balls: np.ndarray) -> None:
    """Each ball's centre is inside ``mesh`` (trimesh's ray test) and its radius its distance to
    the surface (trimesh's closest points)."""
    if len(balls):
        assert mesh.contains(balls[:, :3]).all()
        _, distance, _ = trimesh.proximity.closest_point(mesh, balls[:, :3])
        assert np.all(distance >= balls[:, 3])
        np.testing.assert_allclose(balls[:, 3], distance, atol=1e-5)  # and as large as allowed


def test_a_box_gets_balls_along_its_axis_as_deep_as_its_walls_allow() -> None:
    box = trimesh.creation.box(extents=(0.06, 0.08, 0.3))
    balls = axis_balls(box.vertices, box.faces, 0.15)
    assert len(balls) >= 25
    _check_inside(box, balls)
    assert balls[:, 3].max() == pytest.approx(0.03, abs=1e-5)  # the nearer wall


def test_a_ring_has_no_ball_on_the_axis_through_its_hole() -> None:
    ring = trimesh.creation.annulus(r_min=0.03, r_max=0.06, height=0.08)
    assert closed(ring.faces)
    assert len(axis_balls(ring.vertices, ring.faces, 0.04)) == 0


def test_overlapping_shells_give_balls_only_where_one_shell_holds_the_centre() -> None:
    """Two closed boxes overlapping between z = -5 and 5 cm, one mesh (as the UR5's links):
    a centre in both is crossed twice by every ray, so it gets no ball (no proof there, and no
    wrong one)."""
    low = trimesh.creation.box(extents=(0.06, 0.06, 0.2))
    low.apply_translation((0.0, 0.0, -0.05))
    high = low.copy()
    high.apply_translation((0.0, 0.0, 0.1))
    both = trimesh.Trimesh(np.vstack([low.vertices, high.vertices]),
                           np.vstack([low.faces, high.faces + len(low.vertices)]), process=False)
    assert closed(both.faces)
    balls = axis_balls(both.vertices, both.faces, 0.15)
    z = balls[:, 2]
    assert len(balls) >= 15 and not np.any((z > -0.05) & (z < 0.05))
    for shell in (low, high):  # each ball is inside one shell, off its surface
        mine = balls[shell.contains(balls[:, :3])]
        _, distance, _ = trimesh.proximity.closest_point(shell, mine[:, :3])
        assert np.all(distance >= mine[:, 3])
    assert len(balls) == sum(shell.contains(balls[:, :3]).sum() for shell in (low, high))


def test_an_open_mesh_gets_no_balls() -> None:
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.3))
    assert closed(box.faces)
    assert not closed(box.faces[1:])
    assert len(axis_balls(box.vertices, box.faces[1:], 0.15)) == 0


@pytest.mark.filterwarnings("ignore:invalid value encountered in divide")  # (flat hulls)
@pytest.mark.filterwarnings("ignore:divide by zero encountered")  # (flat hulls, likewise)
@settings(max_examples=60, deadline=None)
@given(points=arrays(np.float64, st.tuples(st.integers(8, 40), st.just(3)),
                     elements=st.floats(-0.1, 0.1, allow_nan=False)),
       lift=st.floats(-0.02, 0.02))
def test_balls_inside_random_convex_meshes_are_inside(points: np.ndarray, lift: float) -> None:
    hull = trimesh.convex.convex_hull(points + np.array([0.0, 0.0, lift]))
    balls = axis_balls(hull.vertices, hull.faces, 0.1)
    assert np.all(balls[:, 3] >= LEAST)
    _check_inside(hull, balls)


def _nearest_by_projection(x: np.ndarray, triangles: np.ndarray) -> float:
    """The distance from ``x`` to the nearest triangle, written here: the foot of the
    perpendicular on each triangle's plane when its barycentric coordinates are in the triangle,
    and the nearest point of each of its three edges."""
    best = np.inf
    for a, b, c in triangles:
        n = np.cross(b - a, c - a)
        foot = x - np.dot(x - a, n) / np.dot(n, n) * n
        gram = np.array([[np.dot(b - a, b - a), np.dot(b - a, c - a)],
                         [np.dot(b - a, c - a), np.dot(c - a, c - a)]])
        v, w = np.linalg.solve(gram, [np.dot(foot - a, b - a), np.dot(foot - a, c - a)])
        if v >= 0 and w >= 0 and v + w <= 1:
            best = min(best, float(np.linalg.norm(x - foot)))
        for s, e in ((a, b), (b, c), (c, a)):
            t = np.clip(np.dot(x - s, e - s) / np.dot(e - s, e - s), 0.0, 1.0)
            best = min(best, float(np.linalg.norm(x - s - t * (e - s))))
    return best


@settings(max_examples=60, deadline=None)
@given(points=arrays(np.float64, st.tuples(st.integers(1, 30), st.just(3)),
                     elements=st.floats(-0.3, 0.3, allow_nan=False)))
@example(points=np.full((1, 3), 2.0 ** -24))  # trimesh's closest_point was 1.04e-8 m off here
def test_surface_distance_is_the_distance_to_the_nearest_triangle(points: np.ndarray) -> None:
    """Against a judge written here (trimesh's closest_point is not one: near the centre of
    this ellipsoid it picked a triangle 1.04e-8 m farther than the nearest)."""
    mesh = trimesh.creation.icosphere(subdivisions=1, radius=0.1)
    mesh.apply_scale((1.0, 0.6, 1.4))
    truth = [_nearest_by_projection(x, mesh.triangles) for x in points]
    np.testing.assert_allclose(surface_distance(points, mesh.triangles), truth, rtol=0,
                               atol=1e-12)


def _rod_world(tmp_path: Path, obstacle: SceneObject) -> tuple[CollisionWorld, np.ndarray]:
    """The test arm (its link_2 is a closed box mesh, 5 x 5 x 30 cm, from 25 to 55 cm up at
    zero joints) with one obstacle."""
    urdf, srdf = write_robot(tmp_path)
    robot = robot_from_files(urdf, srdf)
    return robot.collision_world(Scene("one", (obstacle,))), np.zeros(robot.chain.dof)


def _pose(z: float) -> np.ndarray:
    m = np.eye(4)
    m[2, 3] = z
    return m


def test_a_plate_across_a_closed_mesh_is_in_contact_without_asking_fcl(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    world, q = _rod_world(tmp_path, SceneObject("plate", Box((0.3, 0.3, 0.01)), _pose(0.40)))
    assert world.contacts_brute_force(q) == [("link_2", "plate")]
    calls: list[object] = []
    collide = exact.ExactJudge._collide

    def counted(self: exact.ExactJudge, a: object, b: object) -> bool:
        calls.append(b)
        return collide(self, a, b)

    monkeypatch.setattr(exact.ExactJudge, "_collide", counted)
    assert world.in_collision(q)
    assert calls == []


def test_a_box_wholly_inside_a_closed_mesh_is_not_in_contact(tmp_path: Path) -> None:
    # 5 mm inside the walls: too near them for the balls around the surface to clear the pair
    world, q = _rod_world(tmp_path, SceneObject("pebble", Box((0.04, 0.04, 0.04)), _pose(0.40)))
    assert world.contacts_brute_force(q) == []  # FCL: the surface does not touch it
    assert not world.in_collision(q)
    assert world.contacts(q) == []


def test_a_high_poly_mesh_is_taken_in_blocks_with_the_same_balls(
        monkeypatch: pytest.MonkeyPatch) -> None:
    from usar_arm.planning import inner_balls

    cylinder = trimesh.creation.cylinder(radius=0.05, height=0.3, sections=64)
    whole = axis_balls(cylinder.vertices, cylinder.faces, 0.15)
    monkeypatch.setattr(inner_balls, "PAIRS", 1000)  # blocks of 32 triangles here
    np.testing.assert_array_equal(axis_balls(cylinder.vertices, cylinder.faces, 0.15), whole)
    assert len(whole) > 20
