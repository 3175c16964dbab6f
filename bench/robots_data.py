"""The files of the ``robots`` stage: example-robot-data's UR5 and Panda, and MotionBenchMaker's
problems as VAMP's repository carries them.

* example-robot-data 6.0.0 (PyPI wheel, ~540 MB) is downloaded once with ``pip download`` into
  :data:`CACHE` (ignored by git), and only ``robots/ur_description`` and
  ``robots/panda_description`` are unpacked from it; a cache that holds them is reused.
* Every solver (ours, the peers) and the judge read the same derived URDF per robot, written
  beside the cache: the original text with ``package://example-robot-data/`` replaced by the
  unpacked folder's absolute path (the peers do not all resolve ROS package URIs); for the
  Panda, its two finger joints made ``fixed``, each open at :data:`FINGER_POSITION` (the
  fingers are not planned; peers that refuse joints outside the planned group would otherwise
  not load it); for the UR5, a root link below ``base_link`` that stands it where MBM's UR5
  stands in the scene's frame (:data:`MBM_MOUNT`). Same meshes; the original SRDF, except the
  UR5's, which gets one missing pair (:data:`EXTRA_DISABLED`).
* Posed as MBM poses them: the scene's frame is the derived URDF's root (MBM's virtual joint is
  the identity in these files), and an object's primitive sits at the object's own ``pose``
  composed with its ``primitive_poses`` entry (MoveIt's CollisionObject: the shapes are given
  relative to the object's pose; only the UR5's ``table_pick`` objects carry a pose other than
  the identity, up to 2.4 m away).
* MotionBenchMaker problems: ``bench/data/vamp_mbm/<robot>_problems.tar.bz2``, the files
  ``resources/<robot>/problems.tar.bz2`` of github.com/KavrakiLab/vamp at commit
  :data:`VAMP_COMMIT` (Apache-2.0), copied byte for byte (this machine has no route to GitHub
  at run time). Each problem is a MoveIt planning scene (``sceneNNNN.yaml``: boxes and
  cylinders) and a request (``requestNNNN.yaml``: start state, joint goal). They are read here
  with PyYAML for the solvers (JSON obstacles); the judge reads the YAML text itself
  (``mesh_judge.py``).
"""

from __future__ import annotations

import hashlib
import math
import re
import subprocess
import sys
import tarfile
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

BENCH = Path(__file__).resolve().parent
CACHE = BENCH / ".cache" / "example-robot-data"
ERD_VERSION = "6.0.0"
ERD_PREFIX = "cmeel.prefix/share/example-robot-data/"
KEEP = ("robots/ur_description/", "robots/panda_description/")
VAMP_DIR = BENCH / "data" / "vamp_mbm"
VAMP_COMMIT = "f6de6a72e0725ba08e0829f0a34261a3f465aed7"
VAMP_SHA256 = {"panda": "4e1509e99c53da769ee6a338cf1173ecf601e4ec16f24081d3894ef358243b69",
               "ur5": "576c199b30a0150d176362207494e6f3e409eb74c55f5225e671a00decfcb5b0"}
SETS = ("table_pick", "table_under_pick", "box", "bookshelf_small", "bookshelf_tall",
        "bookshelf_thin", "cage")


@dataclass(frozen=True)
class RobotFiles:
    """One robot as every solver loads it."""

    key: str               # ur5 | panda
    urdf: Path             # the derived URDF (absolute mesh paths)
    srdf: Path             # the original SRDF
    group: str | None      # the SRDF group planned (None: the chain base_link -> tip)
    base: str
    tip: str
    joints: tuple[str, ...]
    urdf_relative: Path    # the same text with mesh paths relative to its folder (mplib)


EXTRA_DISABLED = {"ur5": (("wrist_3_link", "ee_link", "Adjacent"),)}
"""Pairs added to a robot's SRDF (every solver and the judge read the derived SRDF): the UR5's
``ee_link`` carries a small collision box fixed on ``wrist_3_link``, always touching it, and
example-robot-data's ``ur5.srdf`` does not disable the pair (MoveIt's setup assistant marks
such pairs Adjacent). Without it mplib finds every configuration in collision."""
FINGER_POSITION = 0.065
"""m: each of the Panda's fingers along its prismatic axis (y and -y), 0.13 m between them: the
finger joints of MBM's start states (0.065, 0.065) and of VAMP's Panda (robowflex's model with
its fingers fixed at y = +-0.065). Beyond example-robot-data's own finger limit (0.04 m), which
a fixed joint does not have."""
MBM_MOUNT = {"ur5": {"joint": "world_joint", "xyz": (0.0, 0.0, 0.9144),
                     "rpy": (0.0, 0.0, 1.57)}}
"""Where MBM's robot stands in the scene's frame, per robot that does not stand at its origin:
MBM's UR5 (robowflex's ``ur5_robotiq85``, the model VAMP compiles) hangs ``base_link`` from an
``offset_link`` root by a fixed ``offset_joint`` 0.9144 m up, turned 1.57 rad about z.
example-robot-data's UR5 hangs it from a ``world`` root by a fixed ``world_joint`` at the
identity: the derived URDF gives that joint MBM's origin, so the scene's frame is the root
every solver and the judge plan in."""
ROBOTS = {"ur5": dict(urdf="ur_description/urdf/ur5_robot.urdf",
                      srdf="ur_description/srdf/ur5.srdf", group=None, base="world",
                      tip="tool0",
                      joints=("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                              "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")),
          "panda": dict(urdf="panda_description/urdf/panda.urdf",
                        srdf="panda_description/srdf/panda.srdf", group="arm",
                        base="panda_link0", tip="panda_hand",
                        joints=tuple(f"panda_joint{i}" for i in range(1, 8)))}
FIXED_JOINTS = {"panda": {"panda_finger_joint1": (FINGER_POSITION, 0.0584),
                          "panda_finger_joint2": (-FINGER_POSITION, 0.0584)}}
"""Joint -> (y offset, z) of its fixed origin: the fingers held open as MotionBenchMaker's
problems hold them (:data:`FINGER_POSITION`); closed fingers would cut through the objects the
MBM goals grasp."""


def log(msg: str) -> None:
    print(f"[robots] {msg}", file=sys.stderr, flush=True)


def example_robot_data(cache: Path = CACHE) -> Path:
    """The unpacked ``share/example-robot-data`` folder (downloaded and unpacked once)."""
    share = cache / "share" / "example-robot-data"
    if all((share / k).is_dir() for k in KEEP):
        return share
    wheels = sorted(cache.glob(f"example_robot_data-{ERD_VERSION}-*.whl"))
    if not wheels:
        log(f"downloading example-robot-data=={ERD_VERSION} from PyPI into {cache} (~540 MB, "
            "once)")
        cache.mkdir(parents=True, exist_ok=True)
        subprocess.run([sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary",
                        ":all:", f"example-robot-data=={ERD_VERSION}", "-d", str(cache)],
                       check=True)
        wheels = sorted(cache.glob(f"example_robot_data-{ERD_VERSION}-*.whl"))
    with zipfile.ZipFile(wheels[0]) as z:
        for name in z.namelist():
            if name.startswith(ERD_PREFIX) and name[len(ERD_PREFIX):].startswith(KEEP):
                z.extract(name, cache / "unzip")
    (cache / "share").mkdir(exist_ok=True)
    (cache / "unzip" / ERD_PREFIX).rename(share)
    log(f"example-robot-data unpacked into {share}")
    return share


def robot_files(key: str, cache: Path = CACHE) -> RobotFiles:
    """The derived URDF of ``ur5`` or ``panda`` (written once) and the original SRDF."""
    share = example_robot_data(cache)
    r = ROBOTS[key]
    text = (share / "robots" / r["urdf"]).read_text(encoding="utf-8")
    text = text.replace("package://example-robot-data/", f"{share}/")
    if key in MBM_MOUNT:
        text = _mounted(text, **MBM_MOUNT[key])
    for joint, (dy, z) in FIXED_JOINTS.get(key, {}).items():
        text, n = re.subn(
            rf'(<joint\s+name="{joint}"\s+type=)"prismatic"(>\s*<parent[^>]*>\s*<child[^>]*>\s*)'
            r'<origin rpy="0 0 0" xyz="0 0 [0-9.]+"\s*/>',
            rf'\1"fixed"\2<origin rpy="0 0 0" xyz="0 {dy!r} {z!r}"/>', text)
        assert n == 1, f"{joint} not found as a prismatic joint"
    out = cache / "derived" / f"{key}.urdf"
    out.parent.mkdir(parents=True, exist_ok=True)
    if not out.is_file() or out.read_text(encoding="utf-8") != text:
        out.write_text(text, encoding="utf-8")
    # mplib joins every mesh path to the URDF's folder (an absolute path loses its leading
    # slash), so it reads a copy of the same text, beside the original URDF, whose mesh paths
    # are relative to that folder.
    original = share / "robots" / r["urdf"]
    relative = original.with_name(f"{key}.bench-relative.urdf")
    rel_text = text.replace(f"{original.parent.parent}/", "../")
    if not relative.is_file() or relative.read_text(encoding="utf-8") != rel_text:
        relative.write_text(rel_text, encoding="utf-8")
    srdf = share / "robots" / r["srdf"]
    if key in EXTRA_DISABLED:  # a derived SRDF: the original plus the missing pairs
        srdf_text = srdf.read_text(encoding="utf-8")
        lines = "".join(f'  <disable_collisions link1="{a}" link2="{b}" reason="{why}"/>\n'
                        for a, b, why in EXTRA_DISABLED[key])
        srdf_text = srdf_text.replace("</robot>", lines + "</robot>")
        srdf = cache / "derived" / f"{key}.srdf"
        if not srdf.is_file() or srdf.read_text(encoding="utf-8") != srdf_text:
            srdf.write_text(srdf_text, encoding="utf-8")
    return RobotFiles(key, out, srdf, r["group"], r["base"], r["tip"], r["joints"], relative)


def _mounted(text: str, joint: str, xyz: tuple[float, ...], rpy: tuple[float, ...]) -> str:
    """The URDF ``text`` with the origin of the fixed ``joint`` set to (``xyz`` m, ``rpy``
    rad)."""
    origin = f'<origin rpy="{" ".join(map(repr, rpy))}" xyz="{" ".join(map(repr, xyz))}"/>'
    text, n = re.subn(rf'(<joint\s+name="{joint}"\s+type="fixed">(?:(?!</joint>).)*?)'
                      r"<origin[^>]*/>", lambda m: m.group(1) + origin, text, flags=re.S)
    if n != 1:
        raise ValueError(f"no fixed joint {joint!r} with an <origin> to mount the robot by")
    return text


# ------------------------------------------------------------------------------ MBM problems
def vamp_archive(robot: str) -> Path:
    path = VAMP_DIR / f"{robot}_problems.tar.bz2"
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    if digest != VAMP_SHA256[robot]:
        raise ValueError(f"{path}: sha256 {digest}, expected {VAMP_SHA256[robot]}")
    return path


def mbm_texts(robot: str, sets: tuple[str, ...] = SETS, per_set: int = 100
              ) -> dict[str, tuple[str, str]]:
    """``<set>/<NNNN>`` -> (scene YAML text, request YAML text), the first ``per_set`` of each
    set, in number order."""
    out: dict[str, tuple[str, str]] = {}
    with tarfile.open(vamp_archive(robot), "r:bz2") as tar:
        files = {m.name: m for m in tar.getmembers() if m.isfile()}
        for s in sets:
            for n in range(1, per_set + 1):
                base = f"problems/{s}_{robot}/"
                scene, request = base + f"scene{n:04d}.yaml", base + f"request{n:04d}.yaml"
                if scene in files and request in files:
                    out[f"{s}/{n:04d}"] = tuple(  # type: ignore[assignment]
                        tar.extractfile(files[f]).read().decode("utf-8")  # type: ignore[union-attr]
                        for f in (scene, request))
    return out


def _quat_wxyz(xyzw: list[float]) -> list[float]:
    x, y, z, w = (float(v) for v in xyzw)
    n = math.sqrt(w * w + x * x + y * y + z * z)
    return [w / n, x / n, y / n, z / n]


def _quat_mul(a: list[float], b: list[float]) -> list[float]:
    """Hamilton product of two (w, x, y, z) quaternions."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return [aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw]


def _rotate(q: list[float], v: list[float]) -> list[float]:
    """``v`` rotated by the unit quaternion ``q`` (w, x, y, z)."""
    return _quat_mul(_quat_mul(q, [0.0, *v]), [q[0], -q[1], -q[2], -q[3]])[1:]


def _object_pose(obj: dict[str, Any]) -> tuple[list[float], list[float]]:
    """(xyz, quat_wxyz) of a collision object's own pose (identity without one)."""
    pose = obj.get("pose")
    if pose is None:
        return [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
    return [float(v) for v in pose["position"]], _quat_wxyz(pose["orientation"])


def scene_json(scene_text: str) -> list[dict[str, Any]]:
    """The obstacles of a MoveIt planning scene, in the problem files' JSON form, in the
    scene's frame (the derived URDF's root: MBM's virtual joint is the identity in these
    files): each primitive at its object's pose composed with its primitive pose."""
    doc = yaml.safe_load(scene_text)
    items = []
    for obj in doc["world"]["collision_objects"]:
        at, turn = _object_pose(obj)
        for k, (prim, pose) in enumerate(zip(obj.get("primitives", []),
                                             obj.get("primitive_poses", []), strict=True)):
            d = [float(v) for v in prim["dimensions"]]
            offset = _rotate(turn, [float(v) for v in pose["position"]])
            item: dict[str, Any] = {
                "name": f"{obj['id']}_{k}", "xyz": [a + o for a, o in zip(at, offset, strict=True)],
                "quat_wxyz": _quat_mul(turn, _quat_wxyz(pose["orientation"]))}
            if prim["type"] == "box":
                item.update(type="box", size=d[:3])
            elif prim["type"] == "cylinder":  # shape_msgs: [height, radius]
                item.update(type="cylinder", length=d[0], radius=d[1])
            elif prim["type"] == "sphere":
                item.update(type="sphere", radius=d[0])
            else:
                raise ValueError(f"unsupported primitive {prim['type']!r}")
            items.append(item)
    return items


def request_start_goal(request_text: str, joints: tuple[str, ...]
                       ) -> tuple[list[float], list[float]]:
    """(start, goal) in the order ``joints`` from a MoveIt motion plan request."""
    doc = yaml.safe_load(request_text)
    js = doc["start_state"]["joint_state"]
    start_of = dict(zip(js["name"], js["position"], strict=True))
    goal_of = {c["joint_name"]: c["position"]
               for c in doc["goal_constraints"][0]["joint_constraints"]}
    return ([float(start_of[j]) for j in joints], [float(goal_of[j]) for j in joints])
