"""The digital object: a binary volume placed on the lattice or its dual.

Definition 2 of the paper: a digital object is a finite complex of unit
cubes. Here it is a boolean array plus where that array sits:

* ``offset``: integer lattice position of voxel ``(0, 0, 0)``'s lowest corner;
* ``parity``: 0 on the lattice Z^n, 1 on the dual lattice Z^n + e/2 (eq. 5.1),
  which every step of the digital curvature flow switches;
* ``pitch`` and ``origin``: world coordinates, so that an object voxelised
  from a mesh exports back onto the mesh.

Array voxel ``v`` is the cube whose lowest corner has lattice coordinates
``offset + v + parity/2`` and world coordinates ``origin + pitch * (that)``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .errors import IsoflowError


@dataclass(frozen=True)
class DigitalObject:
    """A 2D or 3D binary volume with its place on the (dual) lattice.

    4D volumes are accepted for the topology report (section 6 of the paper);
    surfaces and the flow are 2D/3D only."""

    volume: np.ndarray
    offset: tuple[int, ...] = None  # type: ignore[assignment]
    parity: int = 0
    pitch: float = 1.0
    origin: np.ndarray = field(default=None)  # type: ignore[assignment]

    def __post_init__(self):
        vol = np.asarray(self.volume)
        if vol.dtype != np.bool_:
            vol = vol.astype(bool)
        if vol.ndim not in (2, 3, 4):
            raise IsoflowError(f"a digital object is 2D, 3D or 4D, got a {vol.ndim}D array")
        object.__setattr__(self, "volume", vol)
        offset = (0,) * vol.ndim if self.offset is None else tuple(int(o) for o in self.offset)
        if len(offset) != vol.ndim:
            raise IsoflowError(f"offset {offset} does not match a {vol.ndim}D volume")
        object.__setattr__(self, "offset", offset)
        origin = np.zeros(vol.ndim) if self.origin is None else np.asarray(self.origin, float)
        if origin.shape != (vol.ndim,):
            raise IsoflowError(f"origin {origin.tolist()} does not match a {vol.ndim}D volume")
        object.__setattr__(self, "origin", origin)
        if self.parity not in (0, 1):
            raise IsoflowError(f"parity must be 0 (lattice) or 1 (dual lattice), got {self.parity}")
        if not (np.isfinite(self.pitch) and self.pitch > 0):
            raise IsoflowError(f"pitch must be a positive number, got {self.pitch}")

    # ------------------------------------------------------------ builders
    @classmethod
    def from_voxels(cls, indices, **kw) -> "DigitalObject":
        """Object made of the voxels with the given integer indices (N, n)."""
        idx = _integer_points(indices, "voxel index")
        lo = idx.min(axis=0)
        vol = np.zeros(idx.max(axis=0) - lo + 1, dtype=bool)
        vol[tuple((idx - lo).T)] = True
        return cls(vol, offset=tuple(lo), **kw)

    @classmethod
    def from_points(cls, points, **kw) -> "DigitalObject":
        """The paper's point model (Definitions 1-2).

        A set of lattice points defines the object made of every unit cube
        (square in 2D) whose 2^n corners all belong to the set.
        """
        pts = _integer_points(points, "lattice point")
        lo = pts.min(axis=0)
        grid = np.zeros(pts.max(axis=0) - lo + 1, dtype=bool)
        grid[tuple((pts - lo).T)] = True
        n = grid.ndim
        shape = tuple(max(s - 1, 0) for s in grid.shape)
        vol = np.ones(shape, dtype=bool)
        for corner in np.ndindex(*(2,) * n):
            vol &= grid[tuple(slice(c, c + s) for c, s in zip(corner, shape))]
        return cls(vol, offset=tuple(lo), **kw)

    # ------------------------------------------------------------ geometry
    @property
    def ndim(self) -> int:
        return self.volume.ndim

    @property
    def voxels(self) -> int:
        return int(np.count_nonzero(self.volume))

    def lattice_coordinates(self, array_points: np.ndarray) -> np.ndarray:
        """Lattice coordinates of points given in array-corner units."""
        return np.asarray(array_points, float) + np.array(self.offset) + 0.5 * self.parity

    def world(self, array_points: np.ndarray) -> np.ndarray:
        """World coordinates of points given in array-corner units."""
        return self.origin + self.pitch * self.lattice_coordinates(array_points)

    def bbox(self) -> tuple[np.ndarray, np.ndarray] | None:
        """World [min corner, max corner] of the object's voxels; None if empty."""
        if not self.volume.any():
            return None
        lo, hi = _nonzero_bounds(self.volume)
        return self.world(lo), self.world(hi)

    def cropped(self) -> "DigitalObject":
        """The same object in the smallest array that holds it."""
        if not self.volume.any():
            return replace(self, volume=np.zeros((0,) * self.ndim, bool))
        lo, hi = _nonzero_bounds(self.volume)
        sl = tuple(slice(a, b) for a, b in zip(lo, hi))
        return replace(
            self,
            volume=self.volume[sl],
            offset=tuple(int(o + a) for o, a in zip(self.offset, lo)),
        )

    def __repr__(self) -> str:
        return (
            f"DigitalObject(shape={self.volume.shape}, voxels={self.voxels}, "
            f"offset={self.offset}, parity={self.parity}, pitch={self.pitch}, "
            f"origin={self.origin.tolist()})"
        )


def _nonzero_bounds(volume: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Smallest index and one past the largest index of True voxels, per axis."""
    lo, hi = [], []
    for axis in range(volume.ndim):
        others = tuple(a for a in range(volume.ndim) if a != axis)
        where = np.flatnonzero(volume.any(axis=others))
        lo.append(where[0])
        hi.append(where[-1] + 1)
    return np.array(lo), np.array(hi)


def _integer_points(points, what: str) -> np.ndarray:
    arr = np.asarray(points)
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] not in (2, 3):
        raise IsoflowError(f"expected a list of 2D or 3D {what}s, got shape {arr.shape}")
    if not np.issubdtype(arr.dtype, np.integer):
        if not np.all(np.isfinite(arr)) or not np.all(arr == np.round(arr)):
            raise IsoflowError(f"{what}s must be integers")
        arr = arr.astype(np.int64)
    return arr.astype(np.int64)
