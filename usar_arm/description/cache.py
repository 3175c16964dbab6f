"""The description cache: a learnt arm's description kept under a key made of the CONF/GEO
lines it was built from and the options (so a second run against the same server skips the
collision-matrix sampling), with the calibrated descriptions of the same arm beside it."""

from __future__ import annotations

import hashlib
import json
import logging
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from usar_arm.core.errors import FileFormatError
from usar_arm.core.fileio import write_tree_atomic
from usar_arm.core.version import __version__
from usar_arm.description.pipeline import (
    GENERATOR,
    DescribeOptions,
    Description,
    describe_arm,
    write_description,
)
from usar_arm.discover.interview import DiscoveryRecord
from usar_arm.planning.robot import Robot, robot_from_files
from usar_arm.urdf.discovery_file import wire_facts

log = logging.getLogger("usar_arm.description.cache")


def robot_from_description(desc: Description, actuator: str | None = None) -> Robot:
    """A Robot from a freshly built description."""
    facts = wire_facts(desc.discovery)
    return Robot(desc.chain, desc.urdf, desc.acm.pairs(), {"home": dict(desc.home)},
                 actuator or facts.actuator, f"discovery of {desc.chain.name}", facts.links,
                 facts.tip_sensor, desc.files())


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
