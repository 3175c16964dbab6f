"""What a description's ``<Robot>.discovery.json`` says about the arm on the wire, read in one
place: the actuator's name, the USARSim link of each joint, the tip sensor, the frame roles and
the step the server printed the Tip with. The file is written by
:mod:`usar_arm.description.pipeline` (docs/cli.md lists its keys); a description without one
(any other URDF) has none of these facts, and the defaults below stand for them.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from usar_arm.core.errors import FileFormatError


@dataclass(frozen=True)
class WireFacts:
    """The wire facts of a learnt arm.

    Attributes:
        actuator: the arm's name on the wire (ACT/ASTA), None when not learnt over the wire.
        links: the USARSim link (1-based) of each joint, in configuration order; empty when the
            file lists none (the joints are then links 1..n).
        tip_sensor: the name of its tip GroundTruth sensor, None without one.
        frames: frame roles (e.g. ``{"tool0": "tool0"}``) the description's chain adds.
        tip_resolution_m: the step (m) the server printed the Tip with (0: exact or unknown).
    """

    actuator: str | None = None
    links: tuple[int, ...] = ()
    tip_sensor: str | None = None
    frames: dict[str, str] = field(default_factory=dict)
    tip_resolution_m: float = 0.0


def wire_facts(discovery: Mapping[str, Any]) -> WireFacts:
    """The wire facts of a parsed discovery document (its JSON object)."""
    chain = discovery.get("chain", {})
    precision = discovery.get("precision", {})
    return WireFacts(
        actuator=discovery.get("robot", {}).get("actuator"),
        links=tuple(int(j["usarsim_link"]) for j in chain.get("joints", [])),
        tip_sensor=chain.get("tip_sensor"),
        frames=dict(chain.get("frames", {})),
        tip_resolution_m=float(precision.get("tip_resolution_m") or 0.0))


def discovery_document(files: Mapping[str, str], stem: str | None = None
                       ) -> dict[str, Any] | None:
    """The parsed ``<stem>.discovery.json`` of a description's files (name -> text); with no
    ``stem``, the one file of that suffix. None when there is none.

    Raises:
        FileFormatError: the file is not a JSON object (with the parser's reason).
    """
    names = [f"{stem}.discovery.json"] if stem else [
        n for n in files if n.endswith(".discovery.json")]
    name = next((n for n in names if n in files), None)
    if name is None:
        return None
    try:
        doc = json.loads(files[name])
    except json.JSONDecodeError as exc:
        raise FileFormatError(name, f"not JSON: {exc.msg}", line=exc.lineno) from None
    if not isinstance(doc, dict):
        raise FileFormatError(name, f"expected a JSON object, got {type(doc).__name__}")
    return doc
