"""Which entries of a reduced state q are which node's displacement: the one way to find a node in q."""
from __future__ import annotations

import dataclasses
from typing import Sequence

import numpy as np


def _rotation_z(angle: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations about e_z by ``angle`` (rad)."""
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(np.shape(angle) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 1, 0], R[..., 1, 1], R[..., 2, 2] = c, -s, s, c, 1.0
    return R


@dataclasses.dataclass(frozen=True)
class NodeMap:
    """Which entries of the reduced state q are which physical node's displacement: the nodes a reduced model keeps
    (blade-tip contact nodes, one set per sector of a disk).

    Each node's displacement is q[q_index[k]] in its sector's frame; sector s's frame is the first sector's turned
    by s * sector_angle about e_z (a single blade: one sector, angle 0). Nothing else may assume where a node sits
    in q.

    Attributes:
        names: node names, unique within a sector; a blade's tip nodes are 'LE', 'tip1', ..., 'TE' from LE to TE.
        sector: (n,) sector of each node.
        coordinates: (n, 3) rest position in the node's sector frame (m).
        q_index: (n, 3) entries of q with the node's x, y, z displacement (sector frame).
        sector_angle: angle between consecutive sector frames (rad); 0 for a single blade.
        frame_angle: the blade frame's angle about e_z in its sector's frame (rad): the plane through the axis and
            the blade's centre of mass (``fem.Sector.blade_frame_angle``), whose radial direction is the contact
            normal 'x' (the paper's e_x of the blade frame), whatever the blade's angular position in its file.
    """

    names: tuple
    sector: np.ndarray
    coordinates: np.ndarray
    q_index: np.ndarray
    sector_angle: float = 0.0
    frame_angle: float = 0.0

    def __post_init__(self):
        n = len(self.names)
        sector = np.asarray(self.sector, dtype=np.int64).reshape(-1)
        coordinates = np.asarray(self.coordinates, float).reshape(-1, 3)
        q_index = np.asarray(self.q_index, dtype=np.int64).reshape(-1, 3)
        if not (sector.size == len(coordinates) == len(q_index) == n):
            raise ValueError(f"node map: {n} names, {sector.size} sectors, {len(coordinates)} coordinates and "
                             f"{len(q_index)} index rows must agree")
        if len(set(zip(self.names, sector.tolist()))) != n:
            raise ValueError("node map: node names must be unique within a sector")
        if q_index.size and (q_index.min() < 0 or len(np.unique(q_index)) != q_index.size):
            raise ValueError("node map: q indices must be distinct and >= 0")
        object.__setattr__(self, "names", tuple(str(x) for x in self.names))
        object.__setattr__(self, "sector", sector)
        object.__setattr__(self, "coordinates", coordinates)
        object.__setattr__(self, "q_index", q_index)
        if not (isinstance(self.frame_angle, (int, float, np.floating)) and abs(self.frame_angle) <= np.pi):
            raise ValueError(f"node map: frame_angle must be an angle in [-pi, pi] rad, got {self.frame_angle!r}")
        object.__setattr__(self, "frame_angle", float(self.frame_angle))

    @classmethod
    def for_nodes(cls, coordinates: np.ndarray, q_index: np.ndarray, names: Sequence[str] | None = None,
                  frame_angle: float = 0.0) -> "NodeMap":
        """One sector's nodes; default names 'LE', 'tip1', ..., 'TE' (the nodes must then be ordered LE -> TE)."""
        coordinates = np.asarray(coordinates, float).reshape(-1, 3)
        n = len(coordinates)
        if names is None:
            names = ["LE"] + [f"tip{k}" for k in range(1, n - 1)] + (["TE"] if n > 1 else [])
        return cls(tuple(names), np.zeros(n, np.int64), coordinates, q_index, frame_angle=frame_angle)

    def __len__(self) -> int:
        return len(self.names)

    @property
    def n_sectors(self) -> int:
        return int(self.sector.max()) + 1 if len(self) else 0

    @property
    def labels(self) -> tuple:
        """'<sector>:<name>' of every node, e.g. '0:LE'."""
        return tuple(f"{s}:{n}" for s, n in zip(self.sector.tolist(), self.names))

    @property
    def boundary_rows(self) -> np.ndarray:
        """All entries of q that hold node displacements (n * 3,), node by node."""
        return self.q_index.ravel()

    @property
    def angles(self) -> np.ndarray:
        """(n,) angle of each node's sector frame (rad)."""
        return self.sector * self.sector_angle

    def global_coordinates(self) -> np.ndarray:
        """(n, 3) rest positions in the frame of sector 0."""
        return np.einsum("nij,nj->ni", _rotation_z(self.angles), self.coordinates)

    def row(self, name: str = "LE", sector: int = 0) -> int:
        """Row of the node ``name`` of ``sector``; ValueError naming the nodes there if absent."""
        for k, (n, s) in enumerate(zip(self.names, self.sector.tolist())):
            if n == name and s == sector:
                return k
        if not 0 <= sector < max(self.n_sectors, 1):
            raise ValueError(f"sector must be in [0, {self.n_sectors - 1}], got {sector}")
        raise ValueError(f"no node {name!r} in sector {sector}; it has "
                         f"{[n for n, s in zip(self.names, self.sector.tolist()) if s == sector]}")

    def label_row(self, label: str) -> int:
        """Row of a node given as '<sector>:<name>' (see ``labels``)."""
        sector, _, name = str(label).partition(":")
        if not name or not sector.isdigit():
            raise ValueError(f"node label must read '<sector>:<name>', e.g. '0:LE', got {label!r}")
        return self.row(name, int(sector))

    def arrays(self, prefix: str = "nodes_") -> dict:
        """The map as named arrays (for .npz files); ``from_arrays`` reads them back."""
        return {prefix + "names": np.array(self.names, dtype=str), prefix + "sector": self.sector,
                prefix + "coordinates": self.coordinates, prefix + "q_index": self.q_index,
                prefix + "sector_angle": np.float64(self.sector_angle),
                prefix + "frame_angle": np.float64(self.frame_angle)}

    @classmethod
    def from_arrays(cls, arrays: dict, prefix: str = "nodes_") -> "NodeMap":
        """The map of ``arrays``; a file written before the blade frame was kept has the file's own x (angle 0)."""
        frame = float(arrays[prefix + "frame_angle"]) if prefix + "frame_angle" in arrays else 0.0
        return cls(tuple(str(x) for x in arrays[prefix + "names"]), arrays[prefix + "sector"],
                   arrays[prefix + "coordinates"], arrays[prefix + "q_index"], float(arrays[prefix + "sector_angle"]),
                   frame)
