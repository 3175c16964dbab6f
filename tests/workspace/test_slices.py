"""The map's slice pictures: reach-xz and reach-xy through the base (y = 0, z = 0), a third at
shoulder height, and obstacle names that never overlap."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from usar_arm.cli import reach_cmd
from usar_arm.cli.main import main
from usar_arm.core.errors import EXIT_OK
from usar_arm.export import reach_plot
from usar_arm.planning.robot import Robot
from usar_arm.planning.scene_file import load_scene

REPO = Path(__file__).resolve().parents[2]
URDF = str(REPO / "robots" / "generated" / "KR60.urdf")


def test_the_layer_through_the_base_is_the_one_centred_on_z_0() -> None:
    origin = np.array([-2.9, -2.9, -2.4])  # voxel centres on multiples of 0.1 m
    layer, level = reach_plot.slice_layer((59, 59, 54), origin, 0.1, "xy", 0.0)
    assert layer == 24 and level == pytest.approx(0.0, abs=1e-12)
    assert reach_plot.slice_layer((59, 59, 54), origin, 0.1, "xz", 0.0)[0] == 29


def test_the_shoulder_is_the_first_horizontal_axis(kr60: Robot, fanuc: Robot) -> None:
    joint, height = reach_plot.shoulder(kr60.chain)
    assert joint == "joint_a2" and height == pytest.approx(0.796, abs=1e-3)
    joint, _ = reach_plot.shoulder(fanuc.chain)  # the rail and J1 (vertical) come first
    assert joint == fanuc.chain.joint_names[2]


def test_reach_draws_xy_and_xz_through_the_base_and_xy_at_the_shoulder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[tuple[str, float, str]] = []
    draw = reach_plot.reach_slice_png

    def recorded(index: Any, origin: Any, resolution: float, plane: str, chain: Any,
                 scene: Any = None, at: float = 0.0, title: str = "") -> bytes:
        calls.append((plane, at, title))
        return draw(index, origin, resolution, plane, chain, scene, at, title)

    monkeypatch.setattr(reach_cmd, "reach_slice_png", recorded)
    assert main(["reach", "--urdf", URDF, "--resolution", "0.3", "--orientations", "8",
                 "--workers", "0", "--out", str(tmp_path), "-q"]) == EXIT_OK
    assert [(plane, at) for plane, at, _ in calls] == [("xz", 0.0), ("xy", 0.0),
                                                      ("xy", pytest.approx(0.796, abs=1e-3))]
    assert "through the base" in calls[1][2] and "shoulder" in calls[2][2]
    for name in ("reach-xz.png", "reach-xy.png", "reach-xy-shoulder.png"):
        assert (tmp_path / name).read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("plane", ["xz", "xy"])
def test_the_table_scenes_names_do_not_overlap(plane: str) -> None:
    h, v, _ = reach_plot.PLANES[plane]
    fig = Figure(figsize=(7.5, 6.5), dpi=110)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    ax.set_xlim(-2.9, 3.0)
    ax.set_ylim(-2.9, 3.0)
    ax.set_aspect("equal")
    rings: dict[str, list[np.ndarray]] = {}
    for obj in load_scene("table").objects:  # an open container's pieces: one name, "bin"
        rings.setdefault(obj.name.split("/")[0], []).append(reach_plot.outline(obj, h, v))
    anchors = []
    for name, outlines in rings.items():
        points = np.vstack([o[:-1] for o in outlines])  # one piece: its ring's mean; more:
        middle = points.mean(axis=0) if len(outlines) == 1 else (  # their outline's middle
            points.min(axis=0) + points.max(axis=0)) / 2
        anchors.append((name, *map(float, middle)))
    left_out = reach_plot.place_labels(ax, anchors, "red")
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    boxes = [t.get_window_extent(renderer) for t in ax.texts]
    assert not left_out and len(boxes) <= len(anchors)
    assert not any(a.overlaps(b) for a, b in itertools.combinations(boxes, 2))
    labels = {t.get_text() for t in ax.texts}
    if plane == "xz":  # the legs front left and right are one behind the other
        assert "leg_front_left/right" in labels or "leg_front_right/left" in labels
    else:
        assert {"leg_front_left", "leg_back_right", "bin", "tower"} <= labels


def test_names_at_one_place_share_a_label() -> None:
    assert reach_plot.join_names(["leg_front_right", "leg_front_left"]) == \
        "leg_front_right/left"
    assert reach_plot.join_names(["pick_above", "pick"]) == "pick_above, pick"
    assert reach_plot.join_names(["bin"]) == "bin"
