"""Attached-body files: what is written reads back to the same body (a property over shapes,
poses and names), a scene object is named without a shape, and every error names the file,
the line and the field."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from usar_arm.core.errors import FileFormatError
from usar_arm.core.spatial import transform_from_xyz_rpy
from usar_arm.core.yamlio import loads_yaml
from usar_arm.planning.attach_file import attach_text, parse_attach, read_attach
from usar_arm.planning.attached import AttachedBody
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Sphere

SCENES = Path(__file__).resolve().parents[2] / "usar_arm" / "data" / "scenes"
size = st.floats(0.001, 5.0)
names = st.text(st.sampled_from("abcxyz_/-0123:# "), min_size=1, max_size=12)
shapes = st.one_of(st.tuples(size, size, size).map(Box),
                   st.builds(CylinderShape, size, size), st.builds(Sphere, size))
angles = st.floats(-3.0, 3.0)


@settings(max_examples=150, deadline=None)
@given(name=names, link=names, shape=shapes, xyz=st.tuples(*[st.floats(-2, 2)] * 3),
       rpy=st.tuples(st.floats(-3.1, 3.1), st.floats(-1.5, 1.5), st.floats(-3.1, 3.1)),
       touch=st.lists(names, max_size=3))
def test_a_written_body_reads_back_the_same(name: str, link: str, shape: Box, xyz: tuple,
                                            rpy: tuple, touch: list[str]) -> None:
    body = AttachedBody(name, link, shape, transform_from_xyz_rpy(xyz, rpy), tuple(touch))
    back = parse_attach(loads_yaml(attach_text(body), "b.yaml"), "b.yaml", Path("."))
    assert (back.name, back.link, back.touch_links, back.shape) == (
        name, link, tuple(touch), shape)
    assert back.pose is not None
    np.testing.assert_allclose(back.pose, body.pose, atol=1e-12)


def test_json_files_meshes_and_scene_objects(tmp_path: Path) -> None:
    (tmp_path / "bar.json").write_text(
        '{"name": "bar", "link": "KR60gripper_tcp", "box": [1.2, 0.04, 0.04],\n'
        ' "xyz": [0, 0, 0.05], "touch_links": ["KR60gripper"]}\n')
    bar = read_attach(tmp_path / "bar.json").body()
    assert bar.shape == Box((1.2, 0.04, 0.04)) and bar.pose[2, 3] == 0.05
    (tmp_path / "cone.yaml").write_text(
        f"name: cone\nmesh: {{file: {SCENES / 'meshes' / 'fixture.stl'}, scale: 0.5}}\n"
        "xyz: [0, 0, 0.1]\n")
    cone = read_attach(tmp_path / "cone.yaml")
    assert isinstance(cone.shape, Mesh) and cone.link is None and cone.body().link == "tool0"
    part = parse_attach({"name": "part", "link": "KR60gripper_tcp"}, "x", tmp_path)
    assert part.shape is None and part.pose is None


@pytest.mark.parametrize(("text", "line", "field"), [
    ("name: a\nbox: [1, 2]\nxyz: [0, 0, 0]\n", 2, "a.box"),
    ("name: a\nsphere: {radius: -1}\nxyz: [0, 0, 0]\n", 2, "a.sphere.radius"),
    ("name: a\nbox: [1, 1, 1]\ncolour: red\nxyz: [0, 0, 0]\n", 3, "colour"),
    ("name: a\nbox: [1, 1, 1]\n", 1, "a.xyz"),
    ("name: a\nxyz: [0, 0, 0]\n", 2, "xyz"),
    ("box: [1, 1, 1]\nxyz: [0, 0, 0]\n", 1, "name"),
    ("name: a\ntouch_links: base_link\n", 2, "touch_links"),
    ("name: a\nmesh: {file: nothere.stl}\nxyz: [0, 0, 0]\n", 2, "a.mesh.file"),
])
def test_errors_name_the_line_and_the_field(tmp_path: Path, text: str, line: int,
                                            field: str) -> None:
    path = tmp_path / "body.yaml"
    path.write_text(text)
    with pytest.raises(FileFormatError) as info:
        read_attach(path)
    assert (info.value.line, info.value.field) == (line, field), info.value
    assert str(path) in str(info.value)
