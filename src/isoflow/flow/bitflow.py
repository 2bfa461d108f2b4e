"""The digital curvature flow on bit rows: a state packed 64 voxels to a
word, one step as a few passes of word operations
(:mod:`isoflow.scale.flowbits`), and each state's record from one sweep of
the same rows (:func:`isoflow.digital.closed_surfaces.census_of_rows`).

The moves are those of :mod:`isoflow.flow.motion` (eqs. 5.15-5.18) and
:mod:`isoflow.flow.planar` (eq. 5.8), read from the same tables
(:func:`step_table`); the NumPy step there is the reference these passes
are tested against, state for state. A 2D object is packed as one layer of
a 3D volume: its rows along axis 0, its pixels along axis 1 in the words.
Its record comes from the sweep of that layer, which has the planar
object's components and holes (a 6- or 26-connected slab one voxel thick
is the 4- or 8-connected object), and its planar histogram is the slab's
lower vertex layer.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cache

import numpy as np

from ..digital.analysis import report_from_histogram
from ..digital.closed_surfaces import census_of_rows
from ..digital.lattice import DigitalObject
from ..results import handed_over
from ..scale import bitrows, flowbits
from .motion import motion_luts
from .planar import planar_motion_luts


@cache
def step_table(ndim: int, connectivity: int) -> np.ndarray:
    """Per configuration, what the bit passes need to know (the flags of
    :mod:`isoflow.scale.flowbits`): kept whatever its segments, a negative
    segment end, and the segment a vertex waits for.

    Parameters
    ----------
    ndim : int
        2 or 3.
    connectivity : int
        The object's connectivity in that dimension (4 or 8; 6 or 26).

    Returns
    -------
    numpy.ndarray
        int64, one entry per 3D configuration (256), read-only. A 2D image
        is stepped as the layer ``x = 0`` of a volume: its configurations
        are those of the vertex layer ``x = 1``, octants ``dx = 0`` only
        (pixel bit ``b`` is octant ``2 b``), the others are 0.

    Notes
    -----
    3D: a convex edge along axis ``a`` waits for its segment along ``a``
    (kept when both ends are negative: ``BOTH``), a flat vertex with normal
    ``a`` for its two in-face segments (kept when any end is negative:
    ``ANY``): the table of :func:`isoflow.flow.motion.motion_luts`, eqs.
    5.15-5.18. 2D: a flat vertex waits for its segment along the axis of
    its two pixels (eq. 5.8), axes 0 and 1 being y and z.

    Examples
    --------
    >>> from isoflow.scale.flowbits import KEEP
    >>> bool(step_table(3, 6)[255] & KEEP), bool(step_table(3, 6)[1] & KEEP)
    (True, False)
    """
    any_, both = (flowbits.ANY_X, flowbits.ANY_Y, flowbits.ANY_Z), (flowbits.BOTH_X, flowbits.BOTH_Y, flowbits.BOTH_Z)
    if ndim == 3:
        keep, negative, role = motion_luts(connectivity)
        # edges along x, y, z; flats with normal x, y, z: the other two axes
        roles = [*both, any_[1] | any_[2], any_[0] | any_[2], any_[0] | any_[1]]
    else:
        keep, negative, role = planar_motion_luts(connectivity)
        roles = [any_[1], any_[2]]  # a flat pixel's segment along axis 0 (y), axis 1 (z)
    flags = np.where(keep, flowbits.KEEP, 0) | np.where(negative, flowbits.NEGATIVE, 0)
    for r, flag in enumerate(roles, start=1):
        flags[role == r] |= flag
    table = np.zeros(256, np.int64)
    table[_as_layer(ndim)] = flags
    table.setflags(write=False)
    return table


def _as_layer(ndim: int) -> np.ndarray:
    """Each configuration's index in :func:`step_table`: itself in 3D; in
    2D the configuration of the vertex layer ``x = 1`` with the same pixels
    (pixel bit ``b`` is octant ``2 b``)."""
    if ndim == 3:
        return np.arange(256)
    return np.array([sum(1 << (2 * b) for b in range(4) if c >> b & 1) for c in range(16)])


def _layers(shape: tuple[int, ...]) -> tuple[int, int, int]:
    """The 3D shape the rows of a 2D or 3D volume are packed as."""
    return tuple(shape) if len(shape) == 3 else (1, *shape)


@dataclass(frozen=True)
class PackedObject:
    """A digital object as bit rows, between two steps of the flow.

    ``bits``, ``runs``, ``gaps``: the volume of ``shape``, cropped, as
    :func:`isoflow.scale.bitrows.pack` gives them (a 2D volume as one
    layer); ``place``: where it sits (offset, parity, pitch, origin; its
    own volume is empty). ``voxels``: the object's voxels."""

    bits: np.ndarray
    shape: tuple[int, ...]
    runs: np.ndarray
    gaps: np.ndarray
    place: DigitalObject
    voxels: int

    @classmethod
    def of(cls, obj: DigitalObject) -> PackedObject:
        """The cropped object ``obj`` as bit rows."""
        obj = DigitalObject.of(obj).cropped()
        vol = obj.volume
        bits, runs, gaps = bitrows.pack(vol.reshape(_layers(vol.shape)))
        place = replace(obj, volume=np.zeros((0,) * obj.ndim, bool))
        return cls(bits, vol.shape, runs, gaps, place, obj.voxels)

    @property
    def ndim(self) -> int:
        return len(self.shape)

    @property
    def parity(self) -> int:
        return self.place.parity

    def to_object(self) -> DigitalObject:
        """The state as a :class:`DigitalObject` (the volume unpacked)."""
        volume = flowbits.unpack(self.bits, _layers(self.shape)).reshape(self.shape)
        return replace(self.place, volume=handed_over(volume))  # unpacked for it alone: no copy

    def bbox_list(self) -> list | None:
        """World min corner then max corner, one flat list (as
        :func:`isoflow.analyze` gives a box), None when empty."""
        if not self.voxels:
            return None
        nd = self.ndim
        return self.place.world(np.zeros(nd)).tolist() + self.place.world(np.array(self.shape, float)).tolist()

    def same_shape(self, other: PackedObject) -> bool:
        """The same voxels in the same cropped array (placement aside)."""
        return self.shape == other.shape and np.array_equal(self.bits, other.bits)


def packed_step(state: PackedObject, connectivity: int) -> PackedObject:
    """One step of the digital curvature flow (Definition 18) on bit rows.

    Parameters
    ----------
    state : PackedObject
        The object, 2D or 3D.
    connectivity : int
        The object's connectivity (4 or 8 in 2D; 6 or 26 in 3D).

    Returns
    -------
    PackedObject
        The next object on the other lattice, cropped: the same as
        :func:`isoflow.flow.motion.flow_step`.

    Notes
    -----
    Eqs. 5.15-5.18 in 3D, eq. 5.8 in 2D; the new voxels sit at the old
    lattice vertices (eq. 5.1).

    Examples
    --------
    >>> import numpy as np
    >>> box = PackedObject.of(np.ones((3, 4, 5), bool))
    >>> packed_step(box, 6).shape
    (2, 3, 4)
    """
    if not state.voxels:
        return replace(state, place=state.place.on_dual_lattice())
    return from_vertex_rows(state, vertex_rows(state, connectivity))


def vertex_rows(state: PackedObject, connectivity: int) -> np.ndarray:
    """The lattice vertices of a non-empty state that one step keeps.

    Parameters
    ----------
    state : PackedObject
        A non-empty state.
    connectivity : int
        The object's connectivity (4 or 8; 6 or 26).

    Returns
    -------
    numpy.ndarray
        The bit rows of the vertex grid
        (:func:`isoflow.scale.flowbits.moves3`; a 2D grid as one layer).

    Examples
    --------
    >>> import numpy as np
    >>> rows = vertex_rows(PackedObject.of(np.ones((3, 3, 3), bool)), 6)
    >>> int(np.bitwise_count(rows).sum())  # the box's inner vertices: a 2^3 box
    8
    """
    table = step_table(state.ndim, connectivity)
    moves = flowbits.moves3 if state.ndim == 3 else flowbits.moves2
    return moves(state.bits, state.shape, table)


def vertex_shape(state: PackedObject) -> tuple[int, int, int]:
    """The 3D shape the vertex grid's rows are packed as (a 2D grid as one
    layer).

    Examples
    --------
    >>> import numpy as np
    >>> vertex_shape(PackedObject.of(np.ones((2, 3), bool)))
    (1, 3, 4)
    """
    return _layers(tuple(s + 1 for s in state.shape))


def from_vertex_rows(state: PackedObject, rows: np.ndarray) -> PackedObject:
    """The object on the other lattice (eq. 5.1) whose voxels are the
    vertices set in ``rows`` (the vertex grid of ``state``, as
    :func:`vertex_rows` gives it), cropped.

    Examples
    --------
    >>> import numpy as np
    >>> box = PackedObject.of(np.ones((3, 3, 3), bool))
    >>> new = from_vertex_rows(box, vertex_rows(box, 6))
    >>> new.shape, new.place.offset, new.parity
    ((2, 2, 2), (0, 0, 0), 1)
    """
    nd = state.ndim
    bits, shape, lo, runs, gaps = flowbits.crop(rows, vertex_shape(state))
    place = state.place.on_dual_lattice()
    lo = lo[3 - nd:]
    if shape[0]:
        shape = shape[3 - nd:]
        place = replace(place, offset=tuple(o + int(a) for o, a in zip(place.offset, lo)))
    else:  # the object vanished: offset zeros, as DigitalObject.cropped gives every empty object
        shape = (0,) * nd
        place = replace(place, offset=(0,) * nd)
    return PackedObject(bits, shape, runs, gaps, place, int(np.bitwise_count(bits).sum()))


#: 2D configuration -> the 3D configuration of the slab's lower vertex
#: layer with the same pixels (2D octant bit b is 3D octant 2 b + 1)
_SLAB = np.array([sum(1 << (2 * b + 1) for b in range(4) if c >> b & 1) for c in range(16)])


def packed_record(state: PackedObject, step: int, connectivity: int) -> dict:
    """A state's figures, as :func:`isoflow.flow.engines.step_record` gives
    them for the unpacked state: step, voxels, parity, Betti numbers, chi,
    energy (eq. 5.22) and bbox, from one sweep of its rows.

    Examples
    --------
    >>> import numpy as np
    >>> r = packed_record(PackedObject.of(np.ones((2, 2, 2), bool)), 0, 6)
    >>> r["voxels"], r["betti"], r["euler_characteristic"], r["bbox"]
    (8, [1, 0, 0], 1, [0.0, 0.0, 0.0, 2.0, 2.0, 2.0])
    """
    nd = state.ndim
    if not state.voxels:
        hist, betti = None, [0] * nd
    else:
        conn3 = connectivity if nd == 3 else {4: 6, 8: 26}[connectivity]
        census = census_of_rows(state.bits, _layers(state.shape), state.runs, state.gaps, conn3, surfaces=False)
        hist = census["hist"]
        b0, enclosed = census["betti_counts"]
        if nd == 2:
            hist = hist[_SLAB]
            hist[0] = (state.shape[0] + 1) * (state.shape[1] + 1) - hist[1:].sum()
    if hist is None:
        chi, energy = 0, 0
    else:
        report = report_from_histogram(hist, nd, connectivity, voxels=state.voxels, shape=state.shape, betti=[])
        chi, energy = report["euler_characteristic"], report["energy"]
        betti = [b0, b0 + enclosed - chi, enclosed] if nd == 3 else [b0, b0 - chi]
    return {
        "step": step,
        "voxels": state.voxels,
        "parity": state.parity,
        "betti": betti,
        "euler_characteristic": int(chi),
        "energy": int(energy),
        "bbox": state.bbox_list(),
    }
