"""The cell as a planning Scene: the description's spawned objects as their classes' boxes (an
open container as floor and walls), what the simulator reports (GetSTA with the per-class
queries) turned back into the same scene, and the description's errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.core.cell import Sighting, load_cell
from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import FLIP_X, rpy_to_matrix, transform
from usar_arm.core.wc_classes import WC_CLASSES, find_class
from usar_arm.planning.cell_scene import (
    scene_from_sightings,
    sighting_scale,
    wc_object_pieces,
)
from usar_arm.planning.scene import Box
from usar_arm.planning.scene_file import load_scene

FLIP = transform(FLIP_X)


def _extent(pose: np.ndarray, size: tuple[float, float, float]) -> tuple[float, float, float]:
    """The world-axis bounding box size of a box, computed from its eight corners."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    corners = (pose[:3, :3] @ (signs * np.asarray(size) / 2).T).T
    e = corners.max(axis=0) - corners.min(axis=0)
    return (float(e[0]), float(e[1]), float(e[2]))


def test_the_table_scene_spawns_a_crate_and_an_open_bin() -> None:
    scene = load_scene("table")
    part = scene.object("part")
    assert isinstance(part.shape, Box) and part.shape.size == pytest.approx((0.12, 0.12, 0.10))
    assert part.pose[:3, 3] == pytest.approx((1.45, -0.45, 0.75))
    floor = scene.object("bin/floor")
    assert isinstance(floor.shape, Box) and floor.shape.size == pytest.approx((0.40, 0.30, 0.015))
    walls = [o for o in scene.objects if o.name.startswith("bin/wall")]
    assert len(walls) == 4
    inner = [o.pose[:3, 3] for o in walls]
    assert np.allclose(np.mean(inner, axis=0)[:2], (1.45, 0.50))  # around the bin's centre
    assert "bin" not in {o.name for o in scene.objects}  # an open container has no lid
    names = [o.name.split("/")[0] for o in scene.objects]  # the description's order
    assert list(dict.fromkeys(names)) == ["floor", "table_top", "leg_front_right",
                                          "leg_front_left", "leg_back_right", "leg_back_left",
                                          "part", "tower", "bin", "fixture"]


def test_a_container_is_a_floor_and_four_walls_that_fill_its_outline() -> None:
    cls = WC_CLASSES["WCKitTray"]
    pieces = wc_object_pieces("tray", cls, np.eye(4), (2.0, 1.0, 1.0))
    lo = np.min([o.pose[:3, 3] - np.asarray(o.shape.size) / 2 for o in pieces], axis=0)  # type: ignore[union-attr]
    hi = np.max([o.pose[:3, 3] + np.asarray(o.shape.size) / 2 for o in pieces], axis=0)  # type: ignore[union-attr]
    assert np.allclose(hi - lo, (1.0, 0.35, 0.05)) and np.allclose(lo + hi, 0.0)
    assert cls.scaled_mass((2.0, 1.0, 0.5)) == pytest.approx(5.0)


def test_scene_from_sightings_gives_the_descriptions_scene() -> None:
    cell = load_cell("table")
    sightings = []
    for p in cell.spawn:  # what GetSTA would say of the description's objects (z-down world)
        zdown = FLIP @ p.pose @ FLIP
        size = _extent(zdown, tuple(np.asarray(p.wc_class.size) * p.scale))  # type: ignore[arg-type]
        sightings.append(Sighting(p.name, p.wc_class, zdown, size))
    seen = scene_from_sightings(sightings, cell)
    described = load_scene("table")
    assert sorted(o.name for o in seen.objects) == sorted(o.name for o in described.objects)
    by_name = {o.name: o for o in described.objects}
    for a in seen.objects:  # (the scenery first, then the objects in GetSTA's order)
        b = by_name[a.name]
        assert np.allclose(a.pose, b.pose, atol=1e-9), a.name
        if isinstance(a.shape, Box):
            assert np.allclose(a.shape.size, b.shape.size), a.name  # type: ignore[union-attr]


def test_scene_from_sightings_in_a_robots_base_link() -> None:
    cls = find_class("WCCrate")
    assert cls is not None
    robot = transform(rpy_to_matrix((0.0, 0.0, np.pi / 2)), (4.0, 0.0, 0.0))  # z-down world
    ahead = transform(pos=(4.0, 1.0, -0.125))  # 1 m along the robot's x (world +y)
    scene = scene_from_sightings([Sighting("c", cls, ahead, cls.size)], robot_pose=robot)
    assert scene.object("c").pose[:3, 3] == pytest.approx((1.0, 0.0, 0.125))


@settings(max_examples=200, deadline=None)
@given(st.tuples(*[st.floats(-np.pi, np.pi)] * 3),
       st.tuples(*[st.floats(0.2, 3.0)] * 3))
def test_the_scale_is_recovered_from_gets_ta_size_and_rotation(rpy: tuple[float, ...],
                                                                scale: tuple[float, ...]) -> None:
    cls = WC_CLASSES["WCObjectBin"]
    pose = transform(rpy_to_matrix(rpy))
    size = _extent(pose, tuple(np.asarray(cls.size) * scale))  # type: ignore[arg-type]
    got = sighting_scale(Sighting("b", cls, pose, size))
    again = _extent(pose, tuple(np.asarray(cls.size) * got))  # type: ignore[arg-type]
    assert np.allclose(again, size, atol=1e-6)  # the same box outline, whatever the symmetry
    if abs(np.linalg.det(np.abs(pose[:3, :3]))) > 0.05:  # far from a 45-degree symmetry
        assert np.allclose(got, scale, rtol=1e-6, atol=1e-6)


def test_description_errors_name_the_line_and_the_field(tmp_path: Path) -> None:
    cases = {
        "objects:\n  - {name: p, class: WCNothing, xyz: [0, 0, 0]}\n": (2, "objects[0].class"),
        "objects:\n  - {name: p, class: WCCrate, xyz: [0, 0, 0], scale: [1, 0, 1]}\n":
            (2, "objects[0].scale"),
        "objects:\n  - {name: p, class: WCCrate, xyz: [0, 0, 0], permanent: maybe}\n":
            (2, "objects[0].permanent"),
        "objects:\n  - {name: p, class: WCCrate, xyz: [0, 0, 0], colour: red}\n":
            (2, "objects[0].colour"),
        "objects:\n  - {name: p, class: WCCrate, xyz: [0, 0, 0], box: [1, 1, 1]}\n":
            (2, "objects[0].box"),  # a class or a shape, not both
        "objects:\n  - {name: p, box: [1, 1, 1], xyz: [0, 0, 0], physics: None}\n":
            (2, "objects[0].physics"),  # a static object has no physics
        "objects:\n  - {name: p, class: WCCrate}\n": (2, "objects[0].xyz"),
    }
    for text, (line, field) in cases.items():
        path = tmp_path / "cell.yaml"
        path.write_text(text)
        with pytest.raises(FileFormatError) as info:
            load_scene(path)
        assert (info.value.line, info.value.field) == (line, field), (text, info.value)
        with pytest.raises(FileFormatError):
            load_cell(path)
    path = tmp_path / "both.yaml"
    path.write_text("objects:\n  - {name: p, box: [1, 1, 1], xyz: [0, 0, 0]}\n"
                    "  - {name: p, class: WCCrate, xyz: [0, 0, 0]}\n")
    with pytest.raises(FileFormatError, match="duplicate object name 'p'"):
        load_cell(path)
