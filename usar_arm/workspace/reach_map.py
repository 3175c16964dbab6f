"""A reachability map: per voxel of a grid in base_link, how well tool0 reaches its cell.

Written as ``reach.npz`` (the arrays, no pickled objects) and read back by :meth:`ReachMap.load`.
Voxel (i, j, k) is centred at ``origin + (i, j, k) * resolution``.
"""

from __future__ import annotations

import io
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from usar_arm.core.errors import FileFormatError
from usar_arm.core.fileio import write_atomic
from usar_arm.core.spatial import Array

ARRAYS = ("index", "manipulability", "margin", "best_q", "best_orientation", "reachable",
          "origin", "resolution", "orientations", "joint_names", "edge")


@dataclass(frozen=True)
class ReachMap:
    """The map's arrays.

    Attributes:
        index: (nx, ny, nz) float32 in [0, 1]: the reachability index, the fraction of the
            orientations reached collision-free at the voxel's centre; for an edge voxel
            (``edge``), whose centre the arm reaches in none of them though it reaches some
            point of the cell, the fraction of the orientations nearest its witnesses' (a lower
            bound, 1 / m for one witness).
        manipulability: (nx, ny, nz) float32: the best Yoshikawa manipulability of those
            solutions (0 where the index is 0).
        margin: (nx, ny, nz) float32: the largest distance to the nearest joint limit among
            them (rad, or m for a prismatic joint; 0 where the index is 0).
        best_q: (nx, ny, nz, n) float64: the solution with the best manipulability (NaN where
            the index is 0): a witness anyone can check by FK and a collision judge (tool0 at
            the centre in orientation ``best_orientation``; for an edge voxel, tool0 inside
            the cell in an orientation nearer ``best_orientation`` than any other of the set).
        best_orientation: (nx, ny, nz) int32: its orientation's row (-1 where none).
        reachable: (nx, ny, nz, ceil(m / 8)) uint8: which orientations were reached, as bits
            (``numpy.unpackbits(..., axis=-1, count=m)``).
        origin: (3,) m, the centre of voxel (0, 0, 0). resolution: m.
        orientations: (m, 4) unit quaternions (w, x, y, z) of tool0 in base_link.
        joint_names: the joints of ``best_q``.
        edge: (nx, ny, nz) bool: the voxels marked by the edge search (:mod:`.edges`).
    """

    index: NDArray[np.float32]
    manipulability: NDArray[np.float32]
    margin: NDArray[np.float32]
    best_q: Array
    best_orientation: NDArray[np.int32]
    reachable: NDArray[np.uint8]
    origin: Array
    resolution: float
    orientations: Array
    joint_names: tuple[str, ...]
    edge: NDArray[np.bool_]

    @property
    def shape(self) -> tuple[int, int, int]:
        """(nx, ny, nz)."""
        return (int(self.index.shape[0]), int(self.index.shape[1]), int(self.index.shape[2]))

    def centre(self, i: int, j: int, k: int) -> Array:
        """Centre (m, base_link) of voxel (i, j, k)."""
        return np.asarray(self.origin + np.array([i, j, k]) * self.resolution)

    def voxel_of(self, points: Array) -> NDArray[np.int64]:
        """(N, 3) indices of the voxels holding points (N, 3) (may be outside the grid)."""
        pts = np.asarray(points, float).reshape(-1, 3)
        return np.floor((pts - self.origin) / self.resolution + 0.5).astype(np.int64)

    def lookup(self, points: Array) -> NDArray[np.float32]:
        """The index at points (N, 3), 0 outside the grid."""
        ijk = self.voxel_of(points)
        inside = np.all((ijk >= 0) & (ijk < np.array(self.shape)), axis=1)
        out = np.zeros(len(ijk), np.float32)
        if inside.any():
            i, j, k = ijk[inside].T
            out[inside] = self.index[i, j, k]
        return out

    def reached(self, i: int, j: int, k: int) -> NDArray[np.bool_]:
        """(m,) which orientations voxel (i, j, k) reaches."""
        bits = np.unpackbits(self.reachable[i, j, k], count=len(self.orientations))
        return bits.astype(bool)

    def to_bytes(self) -> bytes:
        """The map as an ``.npz`` file's bytes."""
        buffer = io.BytesIO()
        np.savez_compressed(
            buffer, index=self.index, manipulability=self.manipulability, margin=self.margin,
            best_q=self.best_q, best_orientation=self.best_orientation,
            reachable=self.reachable, origin=self.origin,
            resolution=np.float64(self.resolution), orientations=self.orientations,
            joint_names=np.array(self.joint_names), edge=self.edge,
            frame=np.array("base_link"))
        return buffer.getvalue()

    def save(self, path: str | Path) -> Path:
        """Write ``path`` atomically."""
        return write_atomic(path, self.to_bytes())

    @classmethod
    def load(cls, path: str | Path) -> ReachMap:
        """Read a map written by :meth:`save`.

        Raises:
            FileFormatError: not such a file (names the missing array).
        """
        try:
            with np.load(path, allow_pickle=False) as data:
                missing = [a for a in ARRAYS if a not in data.files]
                if missing:
                    raise FileFormatError(str(path), f"not a reachability map: no array "
                                                     f"{', '.join(missing)}")
                return cls(data["index"], data["manipulability"], data["margin"],
                           data["best_q"], data["best_orientation"], data["reachable"],
                           data["origin"], float(data["resolution"]), data["orientations"],
                           tuple(str(n) for n in data["joint_names"]),
                           data["edge"].astype(bool))
        except (OSError, ValueError) as exc:
            raise FileFormatError(str(path), f"cannot read a reachability map: {exc}") from None
