"""A sphere tree over a scene's obstacles, so that a link meets only the obstacles near it.

Built once per collision world (plain numpy); walked by the compiled checks in :mod:`.bounds`.
Each node holds a sphere (centre, radius, m) that contains the bounding spheres of all the
obstacles below it; a leaf holds at most :data:`LEAF_SIZE` obstacles. A link whose bounding
sphere is farther than a threshold from a node's sphere is farther than that from every obstacle
below it, so the whole subtree is cleared with one test, and its distance bound stands for all
of them. Scenes of fewer than :data:`MIN_OBSTACLES` obstacles get a single leaf that is never
pruned: a flat loop is as fast there.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from usar_arm.core.spatial import Array

IndexArray = np.ndarray[Any, np.dtype[np.int64]]

LEAF_SIZE = 4
"""Obstacles in a leaf at most."""
MIN_OBSTACLES = 4
"""Scenes with fewer obstacles are checked pair by pair."""
LEFT, RIGHT, START, END = range(4)
"""Columns of the tree's integer array: children (-1 for a leaf), then the leaf's range in the
obstacle order."""


def build(centres: Array, radii: Array) -> tuple[Array, IndexArray, IndexArray]:
    """The tree over obstacles with bounding spheres ``centres`` (S, 3), ``radii`` (S,) (m).

    Returns:
        ``spheres`` (M, 4): each node's centre and radius; ``nodes`` (M, 4) int: children and
        leaf ranges (columns LEFT, RIGHT, START, END); ``order`` (S,): obstacle indices in
        leaf order. A scene of fewer than :data:`MIN_OBSTACLES` obstacles gets one leaf whose
        radius is inf (so it is never pruned), an empty scene no node.
    """
    centres = np.asarray(centres, dtype=float).reshape(-1, 3)
    radii = np.asarray(radii, dtype=float).reshape(-1)
    count = len(radii)
    order = np.arange(count, dtype=np.int64)
    if count == 0:
        return np.zeros((0, 4)), np.zeros((0, 4), dtype=np.int64), order
    if count < MIN_OBSTACLES:  # one leaf that is never pruned: every pair is tested
        return (np.array([[0.0, 0.0, 0.0, np.inf]]),
                np.array([[-1, -1, 0, count]], dtype=np.int64), order)
    spheres: list[list[float]] = []
    nodes: list[list[int]] = []

    def node(start: int, end: int) -> int:
        members = order[start:end]
        lo = (centres[members] - radii[members, None]).min(axis=0)
        hi = (centres[members] + radii[members, None]).max(axis=0)
        centre = (lo + hi) / 2
        radius = float(np.max(np.linalg.norm(centres[members] - centre, axis=1)
                              + radii[members]))
        index = len(nodes)
        spheres.append([*centre.tolist(), radius * (1 + 1e-12) + 1e-12])
        nodes.append([-1, -1, start, end])
        if end - start > LEAF_SIZE:
            axis = int(np.argmax(hi - lo))
            order[start:end] = members[np.argsort(centres[members, axis], kind="stable")]
            middle = (start + end) // 2
            nodes[index][LEFT] = node(start, middle)
            nodes[index][RIGHT] = node(middle, end)
        return index

    node(0, count)
    return np.array(spheres), np.array(nodes, dtype=np.int64), order


def pair_table(rs: IndexArray, first: int, n_links: int, n_obstacles: int) -> IndexArray:
    """(L, S) int: the index of the checked pair (link, obstacle) among all pairs (the
    link-obstacle pairs ``rs`` start at ``first``), or -1 when the pair is not checked."""
    table = np.full((n_links, max(n_obstacles, 0)), -1, dtype=np.int64)
    for p, (link, obstacle) in enumerate(np.asarray(rs, dtype=np.int64).reshape(-1, 2)):
        table[link, obstacle] = first + p
    return table
