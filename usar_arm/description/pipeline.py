"""From a learnt arm to validated robot description files (the ``usar-arm urdf`` pipeline).

discover (wire) -> WireArm -> frames (snap, z-up) -> KinematicChain -> URDF -> checks
(check_urdf, yourdfpy, Pinocchio, semantics) -> collision matrix (python-fcl) -> SRDF ->
joint_limits.yaml and discovery.json. Nothing is written until every check has passed.

This module never starts or imports the embedded simulator: talking to a server (embedded or
remote) and checking against the simulator's own model is :mod:`usar_arm.description.embedded`'s
job, so offline work (``Arm.from_files``, planning from files) stays free of MuJoCo and the TCP
server.
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from usar_arm.core.errors import InvalidInputError
from usar_arm.core.fileio import write_tree_atomic
from usar_arm.core.model import KinematicChain
from usar_arm.core.precision import with_precision
from usar_arm.core.spatial import invert, transform
from usar_arm.core.version import __version__
from usar_arm.discover.build import build_chain
from usar_arm.discover.frames import ArmFrames, Snap, accumulate, snap_tolerance_for, to_frame
from usar_arm.discover.interview import DiscoveryRecord
from usar_arm.discover.limits import home_state, load_limits_file, resolve
from usar_arm.discover.naming import Naming
from usar_arm.discover.tool_frames import EffectorFrame, effector_frames, zup_effector_frames
from usar_arm.discover.tool_links import effector_json, tool_links, with_tools
from usar_arm.discover.wire_arm import WireArm
from usar_arm.planning.acm import AcmResult, compute_acm
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.urdf.srdf import GroupState, joint_limits_yaml, srdf_text
from usar_arm.urdf.validation import validate
from usar_arm.urdf.writer import urdf_text

GENERATOR = 2
"""The version of what discovery writes from the same CONF/GEO lines and options; part of the
description cache's key, so a description cached by a generator that wrote something else is
made again (bump it when the geometry, the collision matrix or the files change)."""

log = logging.getLogger("usar_arm.description.pipeline")

FRAMES = ("z-up", "z-down")


@dataclass(frozen=True)
class DescribeOptions:
    """Options of a discovery (the parameters of the 2012 node, and the new ones).

    Attributes:
        robot: robot class, with or without package (``KR60`` means ``USARBot.KR60``).
        host: USARSim server; None starts the embedded simulator in-process.
        port: server port (3000, as UDK). start: start position (default: the first).
        naming: ``ros-i``, ``kuka-ros2`` or ``legacy-2012``. frame: ``z-up`` or ``z-down``.
        velocity_limits: path of a limits file (overrides table and server).
        wire_precision: number format of the embedded simulator (``udk`` or ``full``).
        acm_samples, acm_seed: collision-matrix sampling. timeout: s per server reply.
        actuator: which actuator to learn when the robot has several.
        accuracy_samples: configurations for the embedded ground-truth accuracy check.
    """

    robot: str = "KR60"
    host: str | None = None
    port: int = 3000
    start: str | None = None
    naming: str = "ros-i"
    frame: str = "z-up"
    velocity_limits: str | None = None
    wire_precision: str = "udk"
    acm_samples: int = 10_000
    acm_seed: int = 0
    timeout: float = 5.0
    actuator: str | None = None
    accuracy_samples: int = 1000

    def __post_init__(self) -> None:
        if self.frame not in FRAMES:
            raise InvalidInputError(f"--frame must be one of {', '.join(FRAMES)}, got "
                                    f"'{self.frame}'")
        Naming(self.naming, "x")  # validates the scheme name
        if self.acm_samples < 1:
            raise InvalidInputError(f"collision-matrix samples must be >= 1, got "
                                    f"{self.acm_samples}")

    @property
    def robot_class(self) -> str:
        """Package-qualified class name."""
        return self.robot if "." in self.robot else f"USARBot.{self.robot}"


@dataclass(frozen=True)
class Description:
    """A validated robot description and everything it was built from."""

    chain: KinematicChain
    urdf: str
    srdf: str
    joint_limits: str
    discovery: dict[str, Any]
    acm: AcmResult
    home: dict[str, float]
    limit_sources: tuple[tuple[str, str, str], ...]
    warnings: tuple[str, ...] = field(default_factory=tuple)

    def files(self) -> dict[str, str]:
        """File name -> content of the four outputs."""
        name = self.chain.name
        return {f"{name}.urdf": self.urdf, f"{name}.srdf": self.srdf,
                f"{name}.joint_limits.yaml": self.joint_limits,
                f"{name}.discovery.json":
                    json.dumps(with_precision(self.discovery), indent=2) + "\n"}


def describe_arm(record: DiscoveryRecord, options: DescribeOptions) -> Description:
    """Build and check the description of an arm already discovered."""
    arm = record.arm
    assert arm is not None
    naming = Naming(options.naming, arm.name)
    frames_down = accumulate(arm)
    frames = to_frame(frames_down, options.frame)
    override = None
    if options.velocity_limits:
        override = load_limits_file(options.velocity_limits, arm.dof,
                                    [naming.joint(k + 1) for k in range(arm.dof)])
    limits, warnings = resolve(arm, override)
    warnings = [*record.warnings, *warnings]
    sources = tuple(lim.sources for lim in limits)
    notes = _notes(record, arm, options, frames_down.snaps, sources)
    chain = build_chain(arm, frames, limits, naming, notes)
    effectors: tuple[EffectorFrame, ...] = ()
    snaps = frames_down.snaps
    if arm.effectors:
        chain, effectors, tool_snaps = _with_effectors(record, arm, chain, frames, frames_down,
                                                       naming, options.frame)
        snaps += tool_snaps
    urdf = urdf_text(chain)
    validate(chain, urdf)
    kinematics = KinematicModel(urdf, chain.joint_names)
    body_links = [naming.base if naming.legacy else naming.base_link]
    body_links += [naming.link(k + 1) for k in range(arm.dof)]
    for name in (n for n in body_links if not chain.link(n).elements):
        warnings.append(f"link {name} has no collision geometry (it is too short for a cylinder), "
                        "so collision checks cannot see it")
        log.warning("%s", warnings[-1])
    acm = compute_acm(chain, kinematics, options.acm_samples, options.acm_seed)
    home_q, home_source = home_state(arm, list(chain.lower()), list(chain.upper()))
    home = dict(zip(chain.joint_names, home_q, strict=True))
    acm_notes = [
        f"Generated by usar-arm {__version__} for {chain.name}; do not edit.",
        f"Disabled collisions computed as the MoveIt Setup Assistant does (Adjacent, Default, "
        f"Always >= 95 %, Never) with python-fcl over {acm.samples} random states, seed "
        f"{acm.seed}.",
        f"home: {home_source}."]
    srdf = srdf_text(chain, [GroupState("home", home)], acm.disabled, acm_notes)
    joint_limits = joint_limits_yaml(chain, sources)
    discovery = _discovery_json(record, arm, options, chain, snaps, acm, sources, warnings)
    discovery["effectors"] = [effector_json(f, chain) for f in effectors]
    return Description(chain, urdf, srdf, joint_limits, discovery, acm, home, sources,
                       tuple(warnings))


def _with_effectors(record: DiscoveryRecord, arm: WireArm, chain: KinematicChain,
                    frames: ArmFrames, frames_down: ArmFrames, naming: Naming, frame: str
                    ) -> tuple[KinematicChain, tuple[EffectorFrame, ...], tuple[Snap, ...]]:
    """The chain with the arm's effectors as links (:mod:`usar_arm.discover.tool_links`), their
    frames in the output convention, and the rotations snapped on the way."""
    joint_links = tuple(j.link for j in arm.joints)
    down, snaps = effector_frames(frames_down, arm.effectors, joint_links, arm.name,
                                  record.spawn_rotation, record.effector_joints,
                                  tuple(j.joint_type == "Prismatic" for j in arm.joints))
    placed = zup_effector_frames(down) if frame == "z-up" else down
    base = (naming.base, np.eye(4)) if naming.legacy else (naming.base_link,
                                                           invert(frames.mount))
    link_frames = {0: base, **{link: (naming.link(k + 1), transform(pos=frames.anchors[k]))
                               for k, link in enumerate(joint_links)}}
    return with_tools(chain, tool_links(placed, link_frames)), placed, snaps


def write_description(desc: Description, out_dir: str | Path) -> dict[str, Path]:
    """Write the four files into ``out_dir``, each atomically; returns kind -> path.

    The URDF is renamed into place last, so a URDF beside its SRDF, joint limits and discovery
    notes means they are all there: a run killed while writing never leaves a URDF whose SRDF
    (the disabled collision pairs) is missing. The description cache relies on this.
    """
    kinds = dict(zip(("urdf", "srdf", "joint_limits", "discovery"), desc.files().items(),
                     strict=True))
    order = ("srdf", "joint_limits", "discovery", "urdf")
    paths = write_tree_atomic(out_dir, dict(kinds[k] for k in order))
    written = dict(zip(order, paths, strict=True))
    return {k: written[k] for k in kinds}


# ------------------------------------------------------------------------------ reports


def _notes(record: DiscoveryRecord, arm: WireArm, options: DescribeOptions, snaps: tuple,
           sources: tuple[tuple[str, str, str], ...]) -> list[str]:
    where = "the embedded simulator" if options.host is None else f"{options.host}:{options.port}"
    notes = [
        f"Generated by usar-arm {__version__} from what a USARSim server ({where}) described "
        "over its TCP protocol; do not edit, regenerate with `usar-arm urdf`.",
        f"Robot {arm.robot_name} ({record.robot_class}), actuator {arm.name}, start "
        f"{record.start}; naming {options.naming}.",
        ("Frame: REP-103 z-up, converted from USARSim's z-down frame." if options.frame == "z-up"
         else "Frame: USARSim's z-down frame, as the 2012 usar_urdf node wrote it."),
        f"Wire resolution: GEO locations {arm.location_resolution:g} m, orientations "
        f"{arm.orientation_resolution:g} rad, Tip {arm.tip_resolution:g} m (0 = exact); "
        f"{len(snaps)} frame(s) snapped to canonical directions (see {arm.robot_name}."
        "discovery.json).",
        "No <inertial> elements: the USARSim wire carries no masses.",
        "tool0 is the flange turned +90 deg about y (its z axis points out of the flange), "
        "as in ROS-Industrial KUKA packages.",
    ]
    distinct = sorted({s for triple in sources for s in triple})
    notes.append("Velocity/acceleration/jerk limits: " + "; ".join(distinct) + ".")
    return notes


def _discovery_json(record: DiscoveryRecord, arm: WireArm, options: DescribeOptions,
                    chain: KinematicChain, snaps: tuple, acm: AcmResult,
                    sources: tuple[tuple[str, str, str], ...], warnings: list[str]
                    ) -> dict[str, Any]:
    n = arm.dof
    loc_bound = [math.sqrt(3) * arm.location_resolution * (k + 1) for k in range(n)]
    flange_bound = math.sqrt(3) * (arm.location_resolution * n + arm.tip_resolution / 2)
    joints = []
    for jt, src, wj in zip(chain.actuated_joints, sources, arm.joints, strict=True):
        lim = jt.limits
        assert lim is not None
        joints.append({
            "name": jt.name, "type": jt.type.value, "usarsim_link": wj.link,
            "parent_link": jt.parent, "child_link": jt.child,
            "origin_xyz_m": list(jt.origin.xyz), "origin_rpy_rad": list(jt.origin.rpy),
            "axis": list(jt.axis), "lower": lim.lower, "upper": lim.upper,
            "velocity": lim.velocity, "acceleration": lim.acceleration, "jerk": lim.jerk,
            "effort": lim.effort,
            "sources": {"velocity": src[0], "acceleration": src[1], "jerk": src[2]}})
    return {
        "generator": f"usar-arm {__version__}",
        "server": "embedded simulator" if options.host is None else
        f"{options.host}:{options.port}",
        "robot": {"class": record.robot_class, "name": arm.robot_name, "start": record.start,
                  "actuator": arm.name, "platform": arm.platform_type},
        "options": {"naming": options.naming, "frame": options.frame,
                    "velocity_limits_file": options.velocity_limits,
                    "wire_precision_of_embedded_simulator":
                        options.wire_precision if options.host is None else None},
        "exchanges": [{"request": e.request, "reply": e.reply} for e in record.exchanges
                      if not e.request.startswith("INIT")],
        "components": record.components,
        "chain": {"robot": chain.name, "frames": dict(chain.frames), "joints": joints,
                  "tip_m": list(arm.tip), "tip_sensor": arm.tip_sensor.name
                  if arm.tip_sensor else None},
        "precision": {
            "location_resolution_m": arm.location_resolution,
            "orientation_resolution_rad": arm.orientation_resolution,
            "tip_resolution_m": arm.tip_resolution,
            "snap_tolerance_rad": snap_tolerance_for(arm),
            "snapped": [{"what": s.what, "deviation_rad": s.deviation_rad} for s in snaps],
            "origin_error_bound_at_zero_pose_m": loc_bound,
            "flange_error_bound_at_zero_pose_m": flange_bound},
        "collision_matrix": {
            "samples": acm.samples, "seed": acm.seed,
            "disabled": {r: sum(1 for d in acm.disabled if d.reason == r)
                         for r in ("Adjacent", "Default", "Always", "Never")},
            "checked_pairs": [list(p) for p in acm.checked_pairs],
            "links_without_geometry": list(acm.links_without_geometry)},
        "warnings": list(warnings),
    }


