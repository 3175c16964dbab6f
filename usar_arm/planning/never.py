"""Robot-robot pairs proven never in contact: links whose relative pose one revolute joint sets.

Two links whose paths from the root differ by a single actuated revolute joint (a tool link fixed
to the last link, against the link before that joint: the UR5's ``ee_link`` box and
``wrist_2_link``) move relative to each other by that joint alone. Their clearance, as a
function of the joint angle, changes no faster than the largest distance R (m) of a point of the
moving side from the joint's axis (a point at distance r moves r per radian). So the exact
clearance (python-fcl, the real shapes) at angles at most ``h`` apart across the joint's whole
range, each above R h / 2 plus a margin, proves that the two links never touch, whatever the
other joints do. Such a pair is a permanent guest of the exact checks otherwise (its bounding
cylinders overlap in every configuration); proven, it is not checked at all. The proof is not a
sampling guess: a pair whose clearance comes within the bound anywhere stays checked.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from usar_arm.core.model import KinematicChain
from usar_arm.core.spatial import Array
from usar_arm.planning.poe import PoeModel

STEP = 0.05
"""rad between the angles at which the clearance is measured."""
MARGIN = 1e-4
"""m kept beyond the bound (python-fcl's distances are exact to about 1e-6 m)."""

BodyPairs = list[tuple[int, int]]
Gap = Callable[[Array, BodyPairs], float]
"""Exact clearance (m) over body pairs at a configuration (the collision world's)."""


def _one_joint(chain: KinematicChain, a: str, b: str) -> tuple[int, str] | None:
    """(index among the actuated joints, the link on its child side) when the paths of ``a``
    and ``b`` from the root differ by exactly one actuated joint, a revolute one; else None."""
    pa, pb = chain.path_to(a), chain.path_to(b)
    names = [j.name for j in chain.actuated_joints]
    differ = [j for j in pa + pb if (j in pa) != (j in pb) and j.name in names]
    if len(differ) != 1 or differ[0].type.value not in ("revolute", "continuous"):
        return None
    joint = differ[0]
    return names.index(joint.name), (a if joint in pa else b)


def proven_never(chain: KinematicChain, links: Sequence[str], centre_of: Callable[[Array], Array],
                 reach: Array, pairs: Sequence[tuple[str, str]], gap: Gap) -> set[tuple[str, str]]:
    """The pairs of ``pairs`` (link names) proven never in contact (see the module).

    Args:
        chain: the robot. links: the link of each collision body. centre_of: the bodies'
            bounding-cylinder centres (B, 3) at a configuration (asked once, at zero). reach:
            per body, the radius of a ball about that centre holding the body (m). gap: the
            exact clearance over body pairs at a configuration.
    """
    poe: PoeModel | None = None
    lower, upper = chain.lower(), chain.upper()
    centres = centre_of(np.zeros(chain.dof))
    proven = set()
    for a, b in pairs:
        found = _one_joint(chain, a, b)
        if found is None:
            continue
        j, moving = found
        poe = poe or PoeModel(chain)
        axis, point = np.asarray(poe.axes[j], float), np.asarray(poe.points[j], float)
        q = np.zeros(chain.dof)
        mine = [k for k, name in enumerate(links) if name == moving]
        body_pairs = [(i, k) for i in range(len(links)) for k in range(len(links))
                      if i < k and {links[i], links[k]} == {a, b}]
        off = centres[mine] - point
        along = off @ axis
        radius = float(np.max(np.sqrt(np.maximum(np.sum(off * off, axis=1) - along ** 2, 0.0))
                              + reach[mine]))
        span = float(upper[j] - lower[j])
        count = max(2, math.ceil(span / STEP) + 1)
        step = span / (count - 1)
        need = radius * step / 2 + MARGIN
        clear = True
        for angle in np.linspace(lower[j], upper[j], count):
            q[j] = angle
            if gap(q, body_pairs) <= need:
                clear = False
                break
        if clear:
            proven.add((a, b))
    return proven
