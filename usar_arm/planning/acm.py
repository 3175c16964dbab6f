"""The disabled-collision matrix, computed as the MoveIt Setup Assistant does.

Source: moveit2 ``moveit_setup_srdf_plugins/src/compute_default_collisions.cpp``:

0. candidates: every pair of links with collision geometry, alphabetically;
1. **Adjacent**: pairs joined in the link graph once geometry-less links are removed (their
   neighbours joined to each other);
2. **Default**: pairs in contact at the default state (each joint at 0, or mid-range when 0 is
   outside its limits);
3. **Always**: batches of 200 random states; pairs in contact in more than 95 % of a batch, until a
   batch finds none;
4. **Never**: pairs still enabled that are never in contact over N seeded random states.

Contacts come from python-fcl through :class:`~usar_arm.planning.collision.CollisionWorld`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from usar_arm.core.model import KinematicChain
from usar_arm.planning.collision import CollisionWorld, Pair, pair
from usar_arm.planning.kinematics import KinematicModel
from usar_arm.urdf.srdf import DisabledPair

ALWAYS_BATCH = 200
ALWAYS_FRACTION = 0.95
CHUNK = 1000
"""States checked per batched call while looking for pairs that ever touch."""


@dataclass(frozen=True)
class AcmResult:
    """The disabled pairs with their reasons, and how they were computed."""

    disabled: tuple[DisabledPair, ...]
    samples: int
    seed: int
    checked_pairs: tuple[Pair, ...]
    links_without_geometry: tuple[str, ...]

    def pairs(self) -> set[Pair]:
        """The disabled pairs (canonical order)."""
        return {pair(d.link1, d.link2) for d in self.disabled}

def adjacent_pairs(chain: KinematicChain) -> set[Pair]:
    """Pairs of links with geometry joined in the link graph after removing geometry-less links."""
    with_geometry = {lk.name for lk in chain.links if lk.elements}
    graph: dict[str, set[str]] = {lk.name: set() for lk in chain.links}
    for j in chain.joints:
        graph[j.parent].add(j.child)
        graph[j.child].add(j.parent)
    changed = True
    while changed:
        changed = False
        for name in list(graph):
            if name in with_geometry:
                continue
            neighbours = graph.pop(name)
            for a in neighbours:
                graph[a].discard(name)
                for b in neighbours:
                    if a != b:
                        graph[a].add(b)
            changed = True
            break
    return {pair(a, b) for a, nbrs in graph.items() for b in nbrs}


def default_state(chain: KinematicChain) -> np.ndarray:
    """Each joint at 0, or mid-range when 0 is outside its limits."""
    lo, hi = chain.lower(), chain.upper()
    return np.where((lo <= 0) & (0 <= hi), 0.0, (lo + hi) / 2)


def compute_acm(chain: KinematicChain, kinematics: KinematicModel, samples: int = 10_000,
                seed: int = 0) -> AcmResult:
    """Adjacent / Default / Always / Never pairs over ``samples`` states drawn with ``seed``."""
    world = CollisionWorld(chain, kinematics)
    links = sorted(world.link_names)
    candidates = [pair(a, b) for i, a in enumerate(links) for b in links[i + 1:]]
    reasons: dict[Pair, str] = {}
    for p in sorted(adjacent_pairs(chain) & set(candidates)):
        reasons[p] = "Adjacent"
    for p in world.contacts(default_state(chain)):
        reasons.setdefault(p, "Default")
    rng = np.random.default_rng(seed)
    lo, hi = chain.lower(), chain.upper()
    while True:
        counts: dict[Pair, int] = {}
        for found in world.contacts_many(rng.uniform(lo, hi, size=(ALWAYS_BATCH, len(lo)))):
            for p in found:
                if p not in reasons:
                    counts[p] = counts.get(p, 0) + 1
        always = [p for p, c in counts.items() if c > ALWAYS_FRACTION * ALWAYS_BATCH]
        if not always:
            break
        for p in always:
            reasons[p] = "Always"
    seen: set[Pair] = set()
    enabled = [p for p in candidates if p not in reasons]
    world.set_disabled(reasons)  # only the still-enabled pairs need checking now
    states = rng.uniform(lo, hi, size=(samples, len(lo)))
    for start in range(0, samples, CHUNK):  # stop early once every enabled pair was seen
        for found in world.contacts_many(states[start:start + CHUNK]):
            seen.update(found)
        if len(seen) == len(enabled):
            break
    for p in enabled:
        if p not in seen:
            reasons[p] = "Never"
    disabled = tuple(DisabledPair(a, b, reasons[(a, b)]) for a, b in sorted(reasons))
    no_geometry = tuple(lk.name for lk in chain.links if not lk.elements)
    return AcmResult(disabled, samples, seed, tuple(p for p in candidates if p not in reasons),
                     no_geometry)
