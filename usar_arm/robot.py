"""A described arm, ready for IK, collision checking and planning, and where it comes from.

A :class:`Robot` is built from a fresh discovery (:func:`robot_from_record`, which caches the
generated description under a key made of the CONF/GEO lines it was built from, so a second run
against the same server skips the collision-matrix sampling), from files a user gives
(:func:`robot_from_files`), or from a :class:`~usar_arm.description.Description`.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from usar_arm.description import (
    GENERATOR,
    DescribeOptions,
    Description,
    describe_arm,
    write_description,
)
from usar_arm.discover.interview import DiscoveryRecord
from usar_arm.errors import FileFormatError
from usar_arm.fileio import write_tree_atomic
from usar_arm.model import KinematicChain
from usar_arm.planning.collision import CollisionWorld, Pair
from usar_arm.planning.ik import IKOptions, IKSolver
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.planning.scene import EMPTY, Scene
from usar_arm.planning.scene_file import validate_allow
from usar_arm.urdf.reader import apply_joint_limits_text, parse_srdf, parse_urdf
from usar_arm.version import __version__

log = logging.getLogger("usar_arm.robot")


@dataclass
class Robot:
    """An arm's description and the solvers built on it.

    Attributes:
        chain: the kinematic chain (limits with acceleration and jerk when known).
        urdf: its URDF text. disabled: the SRDF's disabled collision pairs.
        states: the SRDF's named states (``home``...), joint name -> value.
        actuator: the USARSim actuator that moves it (for ACT), when known.
        source: where the description came from (for messages).
    """

    chain: KinematicChain
    urdf: str
    disabled: set[Pair] = field(default_factory=set)
    states: dict[str, dict[str, float]] = field(default_factory=dict)
    actuator: str | None = None
    source: str = ""
    wire_links: tuple[int, ...] = ()
    """USARSim link number (1-based, as in ASTA) of each joint, in joint order."""
    tip_sensor: str | None = None
    """Name of the server's tip GroundTruth sensor (and of its URDF frame), when it has one."""
    files: dict[str, str] = field(default_factory=dict)
    """The description's files (name -> text: URDF, SRDF, joint limits, discovery notes)."""
    _kinematics: KinematicModel | None = None
    _ik: dict[tuple[str, IKOptions], IKSolver] = field(default_factory=dict)

    @property
    def kinematics(self) -> KinematicModel:
        """The Pinocchio model (built on first use)."""
        if self._kinematics is None:
            self._kinematics = KinematicModel(self.urdf, self.chain.joint_names)
        return self._kinematics

    def ik_solver(self, options: IKOptions | None = None, frame: str = "tool0") -> IKSolver:
        """An IK solver of ``frame`` (cached per options)."""
        key = (frame, options or IKOptions())
        if key not in self._ik:
            self._ik[key] = IKSolver(self.chain, self.kinematics, frame, key[1])
        return self._ik[key]

    def collision_world(self, scene: Scene = EMPTY, padding: float = 0.0) -> CollisionWorld:
        """A collision world of this arm in ``scene``."""
        validate_allow(scene, {lk.name for lk in self.chain.links})
        return CollisionWorld(self.chain, self.kinematics, self.disabled, scene, padding)

    def named_state(self, name: str) -> list[float]:
        """A named state (``home``) in joint order."""
        if name not in self.states:
            raise KeyError(f"no state '{name}'; states: {', '.join(self.states) or 'none'}")
        values = self.states[name]
        return [values[j] for j in self.chain.joint_names]


def robot_from_description(desc: Description, actuator: str | None = None) -> Robot:
    """A Robot from a freshly built description."""
    links, tip_sensor = _wire_facts(desc.discovery)
    return Robot(desc.chain, desc.urdf, desc.acm.pairs(), {"home": dict(desc.home)},
                 actuator or desc.discovery.get("robot", {}).get("actuator"),
                 f"discovery of {desc.chain.name}", links, tip_sensor, desc.files())


def _wire_facts(discovery: dict) -> tuple[tuple[int, ...], str | None]:
    chain = discovery.get("chain", {})
    links = tuple(int(j["usarsim_link"]) for j in chain.get("joints", []))
    return links, chain.get("tip_sensor")


def robot_from_files(urdf: str | Path, srdf: str | Path | None = None,
                     joint_limits: str | Path | None = None) -> Robot:
    """A Robot from a URDF (and SRDF, joint_limits.yaml; found beside the URDF when not given,
    as ``<Robot>.srdf`` and ``<Robot>.joint_limits.yaml``, with ``<Robot>.discovery.json``)."""
    path = Path(urdf)
    try:
        text = path.read_text()
    except OSError as exc:
        raise FileFormatError(str(path), f"cannot read: {exc.strerror or exc}") from None
    stem = path.name.removesuffix(".urdf")
    srdf_path = Path(srdf) if srdf else path.with_name(f"{stem}.srdf")
    if srdf and not srdf_path.exists():
        raise FileFormatError(str(srdf_path), "no such SRDF file")
    limits_path = Path(joint_limits) if joint_limits else path.with_name(
        f"{stem}.joint_limits.yaml")
    info = path.with_name(f"{stem}.discovery.json")
    roles = {f"{stem}.srdf": srdf_path, f"{stem}.joint_limits.yaml": limits_path,
             f"{stem}.discovery.json": info}
    files = {path.name: text, **{name: p.read_text() for name, p in roles.items()
                                 if p.exists()}}
    return robot_from_texts(files, path.name, str(path))


def robot_from_texts(files: dict[str, str], urdf_name: str | None = None,
                     source: str = "") -> Robot:
    """A Robot from a description's files given as text (name -> text): ``X.urdf`` and, when
    present, ``X.srdf``, ``X.joint_limits.yaml`` and ``X.discovery.json``. What a worker
    process builds its arm from (the files travel by value; the solvers do not pickle)."""
    if urdf_name is None:
        names = [n for n in files if n.endswith(".urdf")]
        if len(names) != 1:
            raise FileFormatError(source or "<description>",
                                  f"expected one .urdf file, got {names or 'none'}")
        urdf_name = names[0]
    stem = urdf_name.removesuffix(".urdf")
    where = source or urdf_name
    text = files[urdf_name]
    chain, notes = parse_urdf(text, where)
    for note in notes:
        log.warning("%s: %s", where, note)
    disabled: set[Pair] = set()
    states: dict[str, dict[str, float]] = {}
    if f"{stem}.srdf" in files:
        disabled, states = parse_srdf(files[f"{stem}.srdf"], f"{stem}.srdf")
    if f"{stem}.joint_limits.yaml" in files:
        chain = apply_joint_limits_text(chain, files[f"{stem}.joint_limits.yaml"],
                                        f"{stem}.joint_limits.yaml")
    actuator, links, tip_sensor = None, tuple(range(1, chain.dof + 1)), None
    if f"{stem}.discovery.json" in files:
        doc = json.loads(files[f"{stem}.discovery.json"])
        roles = doc.get("chain", {}).get("frames", {})
        chain = KinematicChain(chain.name, chain.links, chain.joints,
                               {**chain.frames, **roles}, chain.notes)
        actuator = doc.get("robot", {}).get("actuator")
        links, tip_sensor = _wire_facts(doc)
    return Robot(chain, text, disabled, states, actuator, where, links, tip_sensor,
                 dict(files))


def cache_dir() -> Path:
    """Where generated descriptions are cached (``$USAR_ARM_CACHE``, else
    ``$XDG_CACHE_HOME/usar-arm`` or ``~/.cache/usar-arm``)."""
    if os.environ.get("USAR_ARM_CACHE"):
        return Path(os.environ["USAR_ARM_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "usar-arm" / "descriptions"


def description_key(record: DiscoveryRecord, options: DescribeOptions) -> str:
    """A key made of everything a description depends on: the CONF/GEO lines and the options."""
    limits = Path(options.velocity_limits).read_text() if options.velocity_limits else ""
    material = json.dumps({"version": __version__, "generator": GENERATOR,
                           "class": record.robot_class,
                           "lines": record.reply_lines(), "naming": options.naming,
                           "frame": options.frame, "limits": limits,
                           "acm": [options.acm_samples, options.acm_seed]}, sort_keys=True)
    return hashlib.sha256(material.encode()).hexdigest()[:20]


CALIBRATED = "calibrated"
"""Prefix of the sub-folders of a cache entry that hold calibrated descriptions of the same
CONF/GEO: ``calibrated-<key>``, the key made of the calibration's settings."""
MADE = "made.json"
"""The file of a cached calibration that says when and from how many readings it was made;
written before the URDF, whose presence means the folder is complete."""


def cache_folder(record: DiscoveryRecord, options: DescribeOptions,
                 cache: Path | None = None) -> Path:
    """The cache entry of a discovery: the as-learnt description, and the calibrated ones in
    its ``calibrated-<key>`` sub-folders (:func:`calibrated_folder`)."""
    return (cache or cache_dir()) / description_key(record, options)


def calibrated_folder(entry: Path, settings: Mapping[str, Any]) -> Path:
    """Where the calibration of a cache entry's arm made with ``settings`` (everything the
    calibration depends on besides the CONF/GEO lines: poses, seed, scene, fit options; JSON
    values) is cached."""
    material = json.dumps({"version": __version__, "settings": settings}, sort_keys=True)
    return entry / f"{CALIBRATED}-{hashlib.sha256(material.encode()).hexdigest()[:16]}"


@dataclass(frozen=True)
class CachedCalibration:
    """A calibrated description from the cache: its files (name -> text: URDF, SRDF, joint
    limits, discovery.json and the tour's readings), when it was made (ISO 8601) and from how
    many readings."""

    folder: Path
    files: dict[str, str]
    made: str
    readings: int


def store_calibrated(folder: Path, files: Mapping[str, str], urdf_name: str, made: str,
                     readings: int, settings: Mapping[str, Any]) -> None:
    """Cache a calibrated description's ``files`` in ``folder`` (atomically; the URDF renamed
    into place last, after :data:`MADE`)."""
    info = json.dumps({"made": made, "readings": readings, "settings": settings}, indent=2,
                      sort_keys=True) + "\n"
    ordered = {**{k: v for k, v in files.items() if k != urdf_name}, MADE: info,
               urdf_name: files[urdf_name]}
    write_tree_atomic(folder, ordered)


def load_calibrated(folder: Path, robot_name: str) -> CachedCalibration | None:
    """The calibrated description cached in ``folder`` (None when there is none, or a broken
    one: logged and ignored)."""
    urdf = folder / f"{robot_name}.urdf"
    if not urdf.is_file():
        return None
    try:
        info = json.loads((folder / MADE).read_text())
        files = {p.name: p.read_text() for p in sorted(folder.iterdir())
                 if p.is_file() and p.name.startswith(f"{robot_name}.")}
        return CachedCalibration(folder, files, str(info["made"]), int(info["readings"]))
    except (OSError, ValueError, KeyError, TypeError) as exc:
        log.warning("ignoring a broken cached calibration %s: %s", folder, exc)
        return None


def latest_calibrated(entry: Path, robot_name: str) -> Path | None:
    """The cache entry's most recently made calibrated description (any settings), or None."""
    made = []
    for folder in entry.glob(f"{CALIBRATED}-*"):
        cached = load_calibrated(folder, robot_name)
        if cached is not None:
            made.append((cached.made, folder.name, folder))
    return max(made)[2] if made else None


def robot_from_record(record: DiscoveryRecord, options: DescribeOptions,
                      cache: Path | None = None, calibrated: bool = True) -> Robot:
    """The Robot a discovery describes, from the cache when the same CONF/GEO were described
    before (calibrated, when that arm was calibrated and ``calibrated``: the latest
    calibration), else built (and cached)."""
    assert record.arm is not None
    folder = cache_folder(record, options, cache)
    latest = latest_calibrated(folder, record.arm.robot_name) if calibrated else None
    tried = ([latest] if latest is not None else []) + [folder]
    for where in tried:
        urdf = where / f"{record.arm.robot_name}.urdf"
        if not urdf.exists():
            continue
        try:
            robot = robot_from_files(urdf)
            log.info("description of %s from the cache (%s)", record.arm.robot_name, where)
            return robot
        except (FileFormatError, ValueError, KeyError) as exc:
            log.warning("ignoring a broken cache entry %s: %s", where, exc)
    desc = describe_arm(record, options)
    try:
        write_description(desc, folder)
    except OSError as exc:
        log.warning("cannot cache the description in %s: %s", folder, exc)
    return robot_from_description(desc, record.arm.name)
