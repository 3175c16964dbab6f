"""Read an SRDF: planning groups (chains, joint lists, links, subgroups), named states and the
disabled collision pairs."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

from usar_arm.core.errors import FileFormatError

Pair = tuple[str, str]


@dataclass(frozen=True)
class GroupSpec:
    """A planning group as the SRDF states it.

    Attributes:
        name: group name. chains: (base_link, tip_link) pairs. joints: joint names.
        links: link names. subgroups: names of groups it includes.
    """

    name: str
    chains: tuple[Pair, ...] = ()
    joints: tuple[str, ...] = ()
    links: tuple[str, ...] = ()
    subgroups: tuple[str, ...] = ()


@dataclass(frozen=True)
class Srdf:
    """What an SRDF says: groups in document order, disabled pairs (sorted link names), named
    states (name -> joint -> value, rad or m)."""

    groups: tuple[GroupSpec, ...] = ()
    disabled: set[Pair] = field(default_factory=set)
    states: dict[str, dict[str, float]] = field(default_factory=dict)

    def group(self, name: str, where: str) -> GroupSpec:
        """The group called ``name`` (FileFormatError lists the groups)."""
        for g in self.groups:
            if g.name == name:
                return g
        raise FileFormatError(where, f"no planning group '{name}'; groups: "
                              f"{', '.join(g.name for g in self.groups) or 'none'}")

    def group_joints(self, spec: GroupSpec, where: str
                     ) -> tuple[list[Pair], list[str], list[str]]:
        """The chains, joints and links of ``spec`` with its subgroups' (depth first)."""
        chains, joints, links = list(spec.chains), list(spec.joints), list(spec.links)
        for sub in spec.subgroups:
            c, j, lk = self.group_joints(self.group(sub, where), where)
            chains, joints, links = chains + c, joints + j, links + lk
        return chains, joints, links


def read_srdf(text: str, path: str = "<srdf>") -> Srdf:
    """The groups, disabled pairs and named states of SRDF text."""
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise FileFormatError(path, f"not valid XML: {exc}", line=exc.position[0]) from None
    groups = []
    for el in root.findall("group"):
        groups.append(GroupSpec(
            el.get("name", ""),
            tuple((c.get("base_link", ""), c.get("tip_link", "")) for c in el.findall("chain")),
            tuple(j.get("name", "") for j in el.findall("joint")),
            tuple(lk.get("name", "") for lk in el.findall("link")),
            tuple(g.get("name", "") for g in el.findall("group"))))
    disabled = set()
    for el in root.findall("disable_collisions"):
        a, b = el.get("link1", ""), el.get("link2", "")
        disabled.add((a, b) if a <= b else (b, a))
    states = {el.get("name", ""): {j.get("name", ""): float(j.get("value", "0"))
                                   for j in el.findall("joint")}
              for el in root.findall("group_state")}
    return Srdf(tuple(groups), disabled, states)


def parse_srdf(text: str, path: str = "<srdf>") -> tuple[set[Pair], dict[str, dict[str, float]]]:
    """Disabled collision pairs and named group states of an SRDF."""
    srdf = read_srdf(text, path)
    return srdf.disabled, srdf.states
