"""A learnt chain against the simulator's own model: forward kinematics of the chain and the
simulator's ground truth at seeded random configurations."""

from __future__ import annotations

from typing import Any

import numpy as np

from usar_arm.core.model import JointType, KinematicChain
from usar_arm.core.precision import with_precision
from usar_arm.core.spatial import FLIP_X, Array, invert, transform
from usar_arm.description.pipeline import DescribeOptions
from usar_arm.sim.robot_spec import ActuatorSpec, builtin_robots


def accuracy_report(chain: KinematicChain, act: ActuatorSpec, frame: str, samples: int,
                    seed: int = 0) -> dict[str, Any]:
    """Forward kinematics of ``chain`` against the simulator's ground truth at seeded random
    configurations: the largest joint-origin, joint-axis and flange errors (all configurations
    at once: numpy stacks)."""
    flip = FLIP_X if frame == "z-up" else np.eye(3)
    rng = np.random.default_rng(seed)
    lo = np.array([j.limit_low for j in act.joints])
    hi = np.array([j.limit_high for j in act.joints])
    q = np.vstack([np.zeros(len(lo)), rng.uniform(lo, hi, (samples, len(lo)))])
    truth, tip = _truth_frames(act, q)
    got, axes, flange_pose = _chain_frames(chain, q)
    origin = float(np.max(np.linalg.norm(got[:, :, :3, 3] - truth[:, :, :3, 3] @ flip.T,
                                         axis=2)))
    err = _angles(axes, truth[:, :, :3, 2] @ flip.T)
    flange = float(np.max(np.linalg.norm(flange_pose[:, :3, 3] - tip[:, :3, 3] @ flip.T,
                                         axis=1)))
    # With the precision discovery.json writes (the last bits of these maxima depend on which
    # SIMD kernel numpy picks for the matrix products), so the report in memory, the one
    # --json prints and the checked-in golden file agree.
    return with_precision({"reference": "the embedded simulator's own model (ground truth)",
                           "configurations": samples, "seed": seed,
                           "max_joint_origin_error_m": origin,
                           "max_joint_axis_error_rad": float(err.max()),
                           "max_joint_axis_error_at_zero_pose_rad": float(err[0].max()),
                           "max_flange_error_m": flange})


def _angles(a: Array, b: Array) -> Array:
    """Angles (rad) between the vectors of two (..., 3) stacks (atan2 form: accurate when
    tiny)."""
    norms = np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1)
    c = np.sum(a * b, axis=-1) / norms
    s = np.linalg.norm(np.cross(a, b), axis=-1) / norms
    return np.arctan2(s, c)


def _turn(axis: Array, q: Array, prismatic: bool) -> Array:
    """(N, 4, 4) motions about (along) ``axis`` by the values ``q`` (N,)."""
    out = np.tile(np.eye(4), (len(q), 1, 1))
    if prismatic:
        out[:, :3, 3] = q[:, None] * axis
        return out
    size = float(np.linalg.norm(axis))  # as exp_so3(axis * q): an angle of |axis| q
    axis, q = axis / size, q * size
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]],
                  [-axis[1], axis[0], 0.0]])
    s, c = np.sin(q)[:, None, None], np.cos(q)[:, None, None]
    out[:, :3, :3] = np.eye(3) + s * k + (1.0 - c) * (k @ k)
    return out


def _truth_frames(act: ActuatorSpec, q: Array) -> tuple[Array, Array]:
    """The simulator's joint frames (N, n, 4, 4; actuator frame, before each joint's motion)
    and Tip poses (N, 4, 4) at configurations ``q`` (N, n), as :mod:`usar_arm.sim.robot_spec`
    defines them."""
    n = len(q)
    zero = {act.body: np.eye(4)}
    poses = {act.body: np.tile(np.eye(4), (n, 1, 1))}
    frames = np.empty((n, len(act.joints), 4, 4))
    z = np.array([0.0, 0.0, 1.0])
    for k, jt in enumerate(act.joints):
        f0 = jt.frame()
        frames[:, k] = poses[jt.parent] @ (invert(zero[jt.parent]) @ f0)
        poses[jt.child] = frames[:, k] @ _turn(z, q[:, k], not jt.revolute)
        zero[jt.child] = f0
    last = act.joints[-1]
    tip = transform(pos=np.asarray(last.offset) + np.asarray(act.tip_offset))
    return frames, poses[last.child] @ (invert(last.frame()) @ tip)


def _chain_frames(chain: KinematicChain, q: Array) -> tuple[Array, Array, Array]:
    """The chain's actuated joint frames (N, n, 4, 4; root frame, before each joint's
    motion), their axes (N, n, 3) and the flange's poses (N, 4, 4) at ``q`` (N, n)."""
    n = len(q)
    col = {name: i for i, name in enumerate(chain.joint_names)}
    poses = {chain.root: np.tile(np.eye(4), (n, 1, 1))}
    frames = np.empty((n, chain.dof, 4, 4))
    axes = np.empty((n, chain.dof, 3))
    for jt in chain.joints:
        frame = poses[jt.parent] @ jt.origin.matrix()
        if jt.actuated:
            k = col[jt.name]
            axis = np.asarray(jt.axis, float)
            frames[:, k], axes[:, k] = frame, frame[:, :3, :3] @ axis
            frame = frame @ _turn(axis, q[:, k], jt.type is JointType.PRISMATIC)
        poses[jt.child] = frame
    return frames, axes, poses[chain.frames.get("flange", "flange")]


def urdf_accuracy(urdf: str, options: DescribeOptions, samples: int = 1000) -> dict[str, Any]:
    """:func:`accuracy_report` of a URDF (e.g. a calibrated one) of a built-in robot."""
    from usar_arm.urdf.description_reader import parse_urdf

    chain, _ = parse_urdf(urdf)
    spec = builtin_robots()[options.robot_class]
    act = next(a for a in spec.actuators if a.tip_sensor) if len(spec.actuators) > 1 \
        else spec.actuators[0]
    return accuracy_report(chain, act, options.frame, samples)
