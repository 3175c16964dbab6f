"""roboplan Scene set-up shared by the roboplan runners (runs in the roboplan venv)."""

from pathlib import Path

import numpy as np
from roboplan import core


def load(spec: dict) -> tuple["core.Scene", str, list[str], str]:
    """(scene, group name, the group's joint names, how collisions were filtered).

    SRDF: the problem's "srdf", else <urdf stem>.srdf beside the URDF (mplib's own rule), whose
    groups and disabled pairs importSrdf applies; with none, allowAdjacentLinkCollisions().
    Group: the problem's "group" (default "manipulator") if the SRDF defines it, else one
    built with addGroupFromChain(base_link, tip_link)."""
    scene = core.Scene("robot", core.loadUrdfSceneDescription(spec["urdf"]))
    srdf = spec.get("srdf") or Path(spec["urdf"]).with_suffix(".srdf")
    if Path(srdf).is_file():
        scene.importSrdf(Path(srdf).read_text())
        acm = f"srdf {srdf}"
    else:
        scene.allowAdjacentLinkCollisions()
        acm = "no srdf: adjacent links allowed to touch"
    group = spec.get("group", "manipulator")
    try:
        scene.getJointGroupInfo(group)
    except RuntimeError:  # not defined by the SRDF
        group = "chain"
        scene.addGroupFromChain(
            group, spec.get("base_link", "base_link"), spec.get("tip_link", "tool0")
        )
    return scene, group, list(scene.getJointGroupInfo(group).joint_names), acm


RGBA = np.array([0.5, 0.5, 0.5, 1.0])
MAX_OBSTACLES = 300
"""roboplan rebuilds its collision data on every added geometry: adding n obstacles one by one
costs ~n^3 (100 boxes 1.4 s, 300 boxes 35 s here; 1,000 would take ~20 min), so scenes with more
obstacles than this are refused (every problem of the scene fails with that reason)."""


class Obstacles:
    """The obstacles of one scene at a time in a roboplan Scene.

    Obstacles hang from the ``universe`` frame (where the URDF root base_link is): with
    base_link as parent frame, roboplan's setCollisions refuses any pair with base_link
    ("The index of collision objects must not be equal"), so an obstacle's ``allow`` list could
    not exempt base_link. Meshes: core.Mesh(file, scale). Obstacle-obstacle pairs are disabled
    (roboplan checks every geometry pair otherwise: 3x slower with 100 boxes)."""

    def __init__(self, scene, scenes: dict, on_change=None):
        self.scene = scene
        self.scenes = scenes
        self.present: list[str] = []
        self.on_change = on_change

    def enter(self, name: str) -> None:
        while self.present:
            self.scene.removeGeometry(self.present.pop())
        allowed = []
        if len(self.scenes[name]) > MAX_OBSTACLES:
            raise ValueError(
                f"not run: {len(self.scenes[name])} obstacles; roboplan adds geometry one by "
                f"one at ~n^3 cost (300 boxes took 35 s), limit {MAX_OBSTACLES}"
            )
        for i, ob in enumerate(self.scenes[name]):
            key = f"{name}/{ob.get('name', i)}"
            w, x, y, z = ob.get("quat_wxyz", [1, 0, 0, 0])
            T = np.eye(4)
            T[:3, :3] = _quat_matrix(w, x, y, z)
            T[:3, 3] = ob["xyz"]
            kind = ob["type"]
            if kind == "box":
                self.scene.addBoxGeometry(key, "universe", core.Box(*ob["size"]), T, RGBA)
            elif kind == "cylinder":
                self.scene.addCylinderGeometry(
                    key, "universe", core.Cylinder(ob["radius"], ob["length"]), T, RGBA
                )
            elif kind == "sphere":
                self.scene.addSphereGeometry(key, "universe", core.Sphere(ob["radius"]), T, RGBA)
            elif kind == "mesh":
                mesh = core.Mesh(ob["file"], np.full(3, float(ob.get("scale", 1.0))))
                self.scene.addMeshGeometry(key, "universe", mesh, T, RGBA)
            else:
                raise ValueError(f"unknown obstacle type {kind!r}")
            self.present.append(key)
            allowed += [(key, link) for link in ob.get("allow", [])]
        pairs = [(a, b) for i, a in enumerate(self.present) for b in self.present[i + 1 :]]
        pairs += allowed
        if pairs:
            self.scene.setCollisions(pairs, False)
        if self.on_change is not None:
            self.on_change(name)


def _quat_matrix(w, x, y, z):
    n = (w * w + x * x + y * y + z * z) ** 0.5
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
