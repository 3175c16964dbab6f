"""The benchmark's scenes: the four shipped ones (``robots/scenes``) and ``boxes_N``, N boxes of
:data:`BOX_EDGE` m (the first N of the same 1,000), their JSON form in the problem files (what
the solvers read) and their YAML files (what the judge reads: ``scene_files``; the boxes scenes
are written as YAML here, straight from their centres).

Frame base_link, metres, radians.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import common
import numpy as np

from usar_arm.core.spatial import Array, matrix_from_quat, quat_from_matrix
from usar_arm.planning.scene import Box, CylinderShape, Mesh, Scene, SceneObject, Sphere
from usar_arm.planning.scene_file import load_scene

BOX_COUNTS = (1, 10, 100, 1000)
BOX_EDGE = 0.1
"""m: edge of every box of the ``boxes_N`` scenes."""
BOX_MARGIN = 0.03
"""m: the boxes keep this far from the arm's link capsules along the witness paths (more than
a link moves between two witness configurations 0.01 rad apart)."""


def shipped_file(name: str) -> Path:
    """The YAML file of a shipped scene (empty, table, shelf or cage)."""
    return common.ROOT / "robots" / "scenes" / f"{name}.yaml"


def shipped(name: str) -> Scene:
    """empty, table, shelf or cage (from ``robots/scenes``)."""
    return load_scene(shipped_file(name))


def write_boxes_file(centres: Array, n: int, folder: Path) -> Path:
    """``folder/boxes_N.yaml``: the scene of the first ``n`` boxes in the scene-file format
    (edges of :data:`BOX_EDGE` m, centres in base_link), written from the centres alone."""
    lines = [f"name: boxes_{n}", "objects:" if n else "objects: []"]
    lines += [f"  - {{name: box_{k}, box: [{BOX_EDGE!r}, {BOX_EDGE!r}, {BOX_EDGE!r}], "
              f"xyz: [{float(c[0])!r}, {float(c[1])!r}, {float(c[2])!r}]}}"
              for k, c in enumerate(centres[:n])]
    path = folder / f"boxes_{n}.yaml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def box_centres(count: int, capsules: tuple[Array, Array, Array], seed: int) -> Array:
    """Centres (count, 3) of boxes in a shell around the arm (0.6-2.4 m from the base axis,
    0.05-2.6 m high), drawn in order from ``default_rng(seed)``, each kept only when it is clear
    of every capsule (segment ends a, b (M, 3) and radii r (M,))."""
    from scipy.spatial import cKDTree

    a, b, r = capsules
    ab = b - a
    length2 = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-12)
    reach = r + BOX_EDGE * np.sqrt(3) / 2 + BOX_MARGIN
    tree = cKDTree((a + b) / 2)
    bound = float(np.max(np.sqrt(length2)) / 2 + np.max(reach))
    rng = np.random.default_rng(seed)
    kept: list[Array] = []
    while len(kept) < count:
        rad, ang, z = rng.uniform(0.6, 2.4), rng.uniform(-np.pi, np.pi), rng.uniform(0.05, 2.6)
        c = np.array([rad * np.cos(ang), rad * np.sin(ang), z])
        near = np.array(tree.query_ball_point(c, bound), dtype=int)
        if len(near):
            t = np.clip(np.einsum("ij,ij->i", c - a[near], ab[near]) / length2[near], 0.0, 1.0)
            gap = np.linalg.norm(a[near] + t[:, None] * ab[near] - c, axis=1) - reach[near]
            if np.any(gap <= 0.0):
                continue
        kept.append(c)
    return np.array(kept)


def boxes(centres: Array, n: int) -> Scene:
    """The scene of the first ``n`` boxes."""
    objects = []
    for k, c in enumerate(centres[:n]):
        pose = np.eye(4)
        pose[:3, 3] = c
        objects.append(SceneObject(f"box_{k}", Box((BOX_EDGE, BOX_EDGE, BOX_EDGE)), pose))
    return Scene(f"boxes_{n}", tuple(objects))


def to_json(sc: Scene, out: Path) -> list[dict[str, Any]]:
    """Obstacles for the problem files: box/cylinder/sphere/mesh with a pose (xyz, quat_wxyz)
    and the links each may touch (``allow``). Meshes are written as STL under ``out/meshes``."""
    items = []
    for o in sc.objects:
        d: dict[str, Any] = {"name": o.name, "xyz": o.pose[:3, 3].tolist(),
                             "quat_wxyz": quat_from_matrix(o.pose[:3, :3]).tolist()}
        s = o.shape
        if isinstance(s, Box):
            d.update(type="box", size=list(s.size))
        elif isinstance(s, CylinderShape):
            d.update(type="cylinder", radius=s.radius, length=s.length)
        elif isinstance(s, Sphere):
            d.update(type="sphere", radius=s.radius)
        elif isinstance(s, Mesh):
            import trimesh

            path = out / "meshes" / f"{sc.name}_{o.name}.stl"
            path.parent.mkdir(parents=True, exist_ok=True)
            trimesh.Trimesh(s.vertices, s.faces, process=False).export(str(path))
            d.update(type="mesh", file=str(path.resolve()), scale=1.0)
        if o.allow:
            d["allow"] = list(o.allow)
        items.append(d)
    return items


def from_json(name: str, items: list[dict[str, Any]]) -> Scene:
    """The Scene a problem file describes (the inverse of :func:`to_json`): our solvers and the
    judge build their obstacles from the same file as the peers."""
    objects = []
    for d in items:
        pose = np.eye(4)
        pose[:3, :3] = matrix_from_quat(d.get("quat_wxyz", [1.0, 0.0, 0.0, 0.0]))
        pose[:3, 3] = d["xyz"]
        kind = d["type"]
        shape: Any
        if kind == "box":
            shape = Box(tuple(d["size"]))
        elif kind == "cylinder":
            shape = CylinderShape(d["radius"], d["length"])
        elif kind == "sphere":
            shape = Sphere(d["radius"])
        elif kind == "mesh":
            import trimesh

            mesh = trimesh.load(d["file"], force="mesh")
            shape = Mesh(np.asarray(mesh.vertices, float) * d.get("scale", 1.0),
                         np.asarray(mesh.faces, np.int64), d["file"])
        else:
            raise ValueError(f"unknown obstacle type {kind!r} in scene {name!r}")
        objects.append(SceneObject(d["name"], shape, pose, tuple(d.get("allow", ()))))
    return Scene(name, tuple(objects))
