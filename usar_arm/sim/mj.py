"""The one module that imports ``mujoco``: the part of its vocabulary the simulator uses.

The simulator's world is built and stepped through these names only (geom, joint and object
kinds, a fresh spec, compiling, stepping, name lookups, rays, the contact list, equality
constraints), so that MuJoCo is loaded by one module and only when a simulator starts.
Specs, bodies, models and data are MuJoCo's own objects (``MjSpec``, ``MjsBody``, ``MjModel``,
``MjData``), passed through untouched; their methods (``add_body``, ``add_geom``...) are used by
:mod:`.physics` and the modules that build parts of the world.
"""

from __future__ import annotations

from typing import Any, TypeAlias

import mujoco
import numpy as np
from numpy.typing import NDArray

from usar_arm.core.spatial import Array

Spec: TypeAlias = mujoco.MjSpec
Body: TypeAlias = mujoco.MjsBody
Model: TypeAlias = mujoco.MjModel
Data: TypeAlias = mujoco.MjData

BOX = mujoco.mjtGeom.mjGEOM_BOX
SPHERE = mujoco.mjtGeom.mjGEOM_SPHERE
CAPSULE = mujoco.mjtGeom.mjGEOM_CAPSULE
CYLINDER = mujoco.mjtGeom.mjGEOM_CYLINDER
PLANE = mujoco.mjtGeom.mjGEOM_PLANE
MESH = mujoco.mjtGeom.mjGEOM_MESH
HINGE = mujoco.mjtJoint.mjJNT_HINGE
SLIDE = mujoco.mjtJoint.mjJNT_SLIDE
FREE = mujoco.mjtJoint.mjJNT_FREE
TRN_JOINT = mujoco.mjtTrn.mjTRN_JOINT
WELD = mujoco.mjtEq.mjEQ_WELD

MASS_GROUP = 3
"""The geom group of the geoms that only carry mass (they touch nothing, and rays that stand for
UDK's traces pass through them)."""
_RAY_GROUPS = np.array([1, 1, 1, 0, 1, 1], dtype=np.uint8)

_KINDS = {"body": mujoco.mjtObj.mjOBJ_BODY, "joint": mujoco.mjtObj.mjOBJ_JOINT,
          "actuator": mujoco.mjtObj.mjOBJ_ACTUATOR, "site": mujoco.mjtObj.mjOBJ_SITE,
          "geom": mujoco.mjtObj.mjOBJ_GEOM, "equality": mujoco.mjtObj.mjOBJ_EQUALITY}


def new_spec(timestep: float, gravity: float) -> Spec:
    """An empty spec: radians, ``timestep`` (s), gravity (m/s²) along +z (the z-down world),
    the implicit-fast integrator, and contacts between a body and its parent *not* filtered
    (MuJoCo's ``filterparent`` would also drop those of an arm's first moving link with
    anything welded to the world; the builders exclude the real neighbours explicitly)."""
    spec = mujoco.MjSpec()
    spec.compiler.degree = False
    spec.option.timestep = timestep
    spec.option.gravity = [0.0, 0.0, gravity]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.disableflags = (int(spec.option.disableflags)
                                | int(mujoco.mjtDisableBit.mjDSBL_FILTERPARENT))
    spec.modelname = "usar_arm_world"
    return spec


def new_data(model: Model) -> Data:
    """Fresh simulation state of ``model``."""
    return mujoco.MjData(model)


def name_id(model: Model, kind: str, name: str) -> int:
    """The id of the ``kind`` (body, joint, actuator, site, geom, equality) called ``name``,
    -1 when there is none."""
    return int(mujoco.mj_name2id(model, _KINDS[kind], name))


def id_name(model: Model, kind: str, index: int) -> str:
    """The name of the ``kind`` with id ``index`` ("" when unnamed)."""
    return mujoco.mj_id2name(model, _KINDS[kind], index) or ""


def step(model: Model, data: Data, n: int = 1) -> None:
    """``n`` physics steps."""
    mujoco.mj_step(model, data, nstep=n)


def kinematics(model: Model, data: Data) -> None:
    """Frames (positions and orientations of bodies, geoms and sites) of the current state."""
    mujoco.mj_kinematics(model, data)


def forward(model: Model, data: Data) -> None:
    """Everything that follows from the current state (frames, contacts, forces)."""
    mujoco.mj_forward(model, data)


def multi_ray(model: Model, data: Data, origin: Array, directions: Array, exclude_body: int,
              max_range: float) -> tuple[Array, NDArray[np.int32]]:
    """Distances (m) and geom ids of the first hits of rays from ``origin`` along unit
    ``directions`` (n x 3), ignoring the body ``exclude_body``; geom -1 for no hit."""
    n = len(directions)
    dist = np.empty(n)
    geom = np.empty(n, dtype=np.int32)
    mujoco.mj_multiRay(model, data, np.asarray(origin, dtype=float),
                       np.ascontiguousarray(directions, dtype=float).reshape(-1), None, True,
                       exclude_body, geom, dist, None, n, max_range)
    return dist, geom


def ray(model: Model, data: Data, origin: Array, direction: Array, exclude_body: int
        ) -> tuple[float, int]:
    """Distance (m, -1 for no hit) along a unit ``direction`` from ``origin`` to the first geom
    (static ones included, mass-only ones not: :data:`MASS_GROUP`) not of body
    ``exclude_body``, and that geom's id (-1)."""
    geom = np.array([-1], dtype=np.int32)
    dist = mujoco.mj_ray(model, data, np.asarray(origin, dtype=float),
                         np.asarray(direction, dtype=float), _RAY_GROUPS, 1, exclude_body, geom)
    return float(dist), int(geom[0])


def contacts(data: Data) -> tuple[NDArray[np.int32], Array]:
    """The current contacts: geom id pairs (n x 2) and signed distances (m, negative when the
    geoms overlap), as views of MuJoCo's arrays (copy before keeping them)."""
    n = int(data.ncon)
    if n == 0:
        return np.zeros((0, 2), dtype=np.int32), np.zeros(0)
    con = data.contact
    return con.geom[:n], con.dist[:n]


Follower = tuple[Array, Array, Array, Array]
"""Views of one kinematic body's position and orientation and of one site's (rows of
``MjData``'s arrays, valid until the data is replaced)."""


def follower(data: Data, mocap: int, site: int) -> Follower:
    """The views :func:`follow` moves mocap body ``mocap`` to site ``site`` with."""
    return (data.mocap_pos[mocap], data.mocap_quat[mocap], data.site_xpos[site],
            data.site_xmat[site])


def follow(followers: list[Follower]) -> None:
    """Put each kinematic (mocap) body where its site is (a few microseconds each: no
    indexing, only copies between views)."""
    for pos, quat, site_pos, site_mat in followers:
        pos[:] = site_pos
        mujoco.mju_mat2Quat(quat, site_mat)


def add_weld(spec: Spec, name: str, body1: str, body2: str, solref: tuple[float, float],
             active: bool) -> Any:
    """A weld equality constraint holding ``body2``'s pose in ``body1``'s frame (its relative
    pose is set at run time: :func:`set_weld_pose`)."""
    eq = spec.add_equality(name=name, type=WELD, name1=body1, name2=body2,
                           objtype=mujoco.mjtObj.mjOBJ_BODY)
    eq.active = active
    eq.solref = list(solref)
    return eq


def set_weld_pose(model: Model, eq: int, body1: int, body2: int, rel_pos: Array,
                  rel_quat: Array) -> None:
    """Re-aim weld ``eq`` at bodies ``body1``, ``body2`` (ids), holding ``body2`` at
    ``rel_pos`` (m), ``rel_quat`` (w, x, y, z) in ``body1``'s frame."""
    model.eq_obj1id[eq] = body1
    model.eq_obj2id[eq] = body2
    data = model.eq_data[eq]
    data[:] = 0.0
    data[3:6] = rel_pos
    data[6:10] = rel_quat
    data[10] = 1.0  # torquescale: rotation held as firmly as position
