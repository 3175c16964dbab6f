"""RViz (Debian's, under Xvfb, software GL) with the shipped configurations shows the live
robots: its Displays panel says "Global Status: Ok" (read by Tesseract from the screenshot),
the KR60's orange links are drawn where the arm is (its link frames, by this test's own FK of
the joint state, projected through the configuration's orbit camera), and the P3AT stands at
the view's centre with its laser scan's points around it. The screenshots are what
tools/rviz_pictures.py writes into docs/images."""

from __future__ import annotations

import itertools
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from usar_arm.planning.kinematics import KinematicModel

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

import rviz_pictures  # noqa: E402

BACKGROUND = (40, 44, 52)  # the configurations' Background Color


def _status_text(png: Path, folder: Path) -> str:
    """Tesseract's reading of the Displays panel (the left 340 pixels, scaled up 2x)."""
    with Image.open(png) as image:
        panel = image.crop((0, 60, 340, 300))
        panel.resize((panel.width * 2, panel.height * 2)).save(folder / "panel.png")
    done = subprocess.run(["tesseract", str(folder / "panel.png"), "-", "--psm", "6"],
                          capture_output=True, text=True, timeout=60, check=True)
    return done.stdout


def _view_area(pixels: np.ndarray) -> tuple[int, int, int, int]:
    """(left, top, right, bottom) of the 3D view: the background colour's bounding box."""
    mask = np.all(np.abs(pixels.astype(int) - BACKGROUND) <= 3, axis=2)
    rows, cols = np.where(mask)
    return int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1


def _project(points: np.ndarray, view: dict[str, float], area: tuple[int, int, int, int]
             ) -> np.ndarray:
    """Pixels of world points (n, 3) through RViz's orbit camera (vertical field of view)."""
    focal = np.array([view["Focal Point"][k] for k in ("X", "Y", "Z")], float)
    yaw, pitch, distance = view["Yaw"], view["Pitch"], view["Distance"]
    eye = focal + distance * np.array([math.cos(yaw) * math.cos(pitch),
                                       math.sin(yaw) * math.cos(pitch), math.sin(pitch)])
    forward = (focal - eye) / np.linalg.norm(focal - eye)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    d = points - eye
    x, y, z = d @ right, d @ up, d @ forward
    left, top, r, bottom = area
    half_h = (bottom - top) / 2
    scale = half_h / math.tan(view["Field of View"] / 2)
    return np.stack([(left + r) / 2 + x / z * scale, (top + bottom) / 2 - y / z * scale], axis=1)


def _config_view(config: Path) -> dict[str, float]:
    return yaml.safe_load(config.read_text())["Visualization Manager"]["Views"]["Current"]


def _orange(pixels: np.ndarray) -> np.ndarray:
    """Where the KUKA orange links are (lit or shaded): red well above green above blue."""
    p = pixels.astype(int)
    r, g, b = p[..., 0], p[..., 1], p[..., 2]
    return (r > 90) & (r > g * 1.35) & (g > b * 1.3) & (r - b > 60)


@pytest.fixture(scope="module")
def pictures(tmp_path_factory: pytest.TempPathFactory, ros1_env: object
             ) -> dict[str, rviz_pictures.Picture]:
    folder = tmp_path_factory.mktemp("rviz")
    out = {}
    for robot in ("KR60", "P3AT"):
        (folder / robot).mkdir()
        out[robot] = rviz_pictures.render(robot, folder / f"{robot}.png", folder / robot)
    return out


@pytest.mark.parametrize("robot", ["KR60", "P3AT"])
def test_rviz_says_global_status_ok(pictures: dict[str, rviz_pictures.Picture], robot: str,
                                    tmp_path: Path) -> None:
    text = _status_text(pictures[robot].png, tmp_path)
    assert "Global Status: Ok" in text, text
    assert "RobotModel" in text, text
    with Image.open(pictures[robot].png) as image:
        names = np.array(image.convert("RGB"))[85:200, 44:200].astype(int)
    # a display in error has its name in red, in warning in orange (blue when Ok); rows of
    # 19 pixels from Global Options: Global Status, Grid, RobotModel, TF, LaserScan
    red = (names[..., 0] > 180) & (names[..., 1] < 90) & (names[..., 2] < 90)
    orange = (names[..., 0] > 200) & (names[..., 1] > 100) & (names[..., 1] < 170) & \
        (names[..., 2] < 60)
    assert red.sum() < 5, "no display in error (the P3AT's wheels have their transforms)"
    warned = {int(r) // 19 for r in np.where(orange)[0]}
    # the P3AT's TF display warns of the truth/ frames: a tree of its own, with no transform
    # to the fixed frame odom by design (docs/ros.md section 8); nothing else warns
    assert warned <= ({4} if robot == "P3AT" else set()), warned


def test_the_kr60_is_drawn_where_its_links_are(pictures: dict[str, rviz_pictures.Picture]
                                               ) -> None:
    picture = pictures["KR60"]
    with Image.open(picture.png) as image:
        pixels = np.array(image.convert("RGB"))
        info = dict(image.text)  # type: ignore[attr-defined]
    assert "urdf_sha256" in json.loads(info["usar-arm:inputs"]), info
    area = _view_area(pixels)
    model = KinematicModel(picture.urdf)
    q = np.array(picture.joints)
    frames = [model.frame_pose(q, f)[:3, 3] for f in ("link_1", "link_2", "link_3", "link_5")]
    # along each link between two frames (the links are cylinders between joint frames)
    samples = np.array([a + t * (b - a) for a, b in itertools.pairwise(frames)
                        for t in (0.3, 0.5, 0.7)])
    orange = _orange(pixels)
    hits = 0
    for u, v in _project(samples, _config_view(picture.config), area).round().astype(int):
        window = orange[max(0, v - 8):v + 9, max(0, u - 8):u + 9]
        hits += bool(window.any())
    assert hits == len(samples), f"{hits} of {len(samples)} link points drawn in orange"
    left, top, right, bottom = area
    outside = orange.copy()
    outside[top:bottom, left:right] = False
    assert outside.sum() < 50, "orange only inside the 3D view"


def test_the_p3at_stands_at_the_centre_with_its_scan(pictures: dict[str, rviz_pictures.Picture]
                                                    ) -> None:
    picture = pictures["P3AT"]
    with Image.open(picture.png) as image:
        pixels = np.array(image.convert("RGB")).astype(int)
    left, top, right, bottom = _view_area(pixels.astype(np.uint8))
    cu, cv = (left + right) // 2, (top + bottom) // 2
    centre = pixels[cv - 30:cv + 31, cu - 30:cu + 31]
    robot = np.any(np.abs(centre - BACKGROUND) > 25, axis=2) & \
        ~np.all(np.abs(centre - (160, 160, 164)) < 30, axis=2)
    assert robot.sum() > 300, "the robot is drawn at the view's centre (its base_link)"
    scan = (pixels[..., 0] > 200) & (pixels[..., 1] < 90) & (pixels[..., 2] < 90)
    assert scan[top:bottom, left:right].sum() > 200, "the scan's red points"
    _, cols = np.where(scan)
    assert np.ptp(cols) > (right - left) / 4, "spread around the robot, not one blob"
