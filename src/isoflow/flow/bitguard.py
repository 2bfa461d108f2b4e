"""Topology control (:mod:`isoflow.flow.guard`) for states held as bit
rows (:mod:`isoflow.flow.bitflow`): the same guarded step, its flow step
realised by simple deformations in compiled code
(:mod:`isoflow.scale.fineblocks`) on the configuration bytes, one per
lattice vertex, which are the old object on the grid refined twice.

The rare ways on (blocks left stuck, a thinning step) unpack the state and
take the NumPy functions of :mod:`isoflow.flow.guard`, so the two
implementations differ only in how the common case is computed.
"""

from __future__ import annotations

import hashlib
from dataclasses import replace

import numpy as np

from ..digital.connectivity import is_face_connectivity
from ..scale import fineblocks, flowbits
from .bitflow import PackedObject, from_vertex_rows, vertex_rows, vertex_shape
from .guard import is_progress, resolve_stuck, thinning_step


def packed_key(state: PackedObject) -> bytes:
    """A digest of the state's shape up to translation and lattice (as
    :func:`isoflow.flow.guard.shape_key`, over the packed rows).

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow import DigitalObject
    >>> a, b = np.ones((2, 2, 2), bool), DigitalObject(np.ones((2, 2, 2), bool), offset=(5, 0, 0))
    >>> packed_key(PackedObject.of(a)) == packed_key(PackedObject.of(b))
    True
    """
    h = hashlib.sha1(repr(state.shape).encode())
    h.update(state.bits.tobytes())
    return h.digest()


def _vertex_mask(indices: np.ndarray, padded: tuple[int, ...], shape: tuple[int, ...]) -> np.ndarray:
    """Flat indices into a padded vertex grid (:func:`isoflow.scale.fineblocks.blocks`) as a boolean grid."""
    mask = np.zeros(shape, bool)
    mask[tuple(c - 1 for c in np.unravel_index(indices, padded))] = True
    return mask


def _toggle(rows: np.ndarray, indices: np.ndarray, padded: tuple[int, ...]) -> None:
    """Flip the bits of the vertices ``indices`` (padded flat) in a vertex grid's rows."""
    coords = [c - 1 for c in np.unravel_index(indices, padded)]
    row = coords[0] * (padded[1] - 2) + coords[1] if len(padded) == 3 else coords[0]
    k = coords[-1]
    np.bitwise_xor.at(rows, (row, k >> 6), np.left_shift(np.uint64(1), (k & 63).astype(np.uint64)))


def packed_stuck(state: PackedObject, conn: int) -> np.ndarray:
    """The vertices that the plain flow step of a packed state leaves
    stuck when it is carried out by simple deformations in the order that
    places a topology change: :func:`isoflow.flow.guard.realise_moves`
    with ``flip=False, by_class=True``, compiled.

    Returns
    -------
    numpy.ndarray
        bool, on the vertex grid (one larger than the state along each axis).

    Examples
    --------
    >>> import numpy as np
    >>> v = np.zeros((5, 5), bool)
    >>> v[0, 0] = True
    >>> v[2:, 2:] = True
    >>> np.argwhere(packed_stuck(PackedObject.of(v), 4)).tolist()  # a corner of the isolated pixel, which vanishes
    [[1, 1]]
    """
    cells, padded, pending, goal = fineblocks.blocks(state.bits, state.shape, vertex_rows(state, conn))
    stuck, _ = fineblocks.realise(cells, padded, pending, goal, is_face_connectivity(conn), flip=False, by_class=True)
    return _vertex_mask(stuck, padded, tuple(s + 1 for s in state.shape))


def packed_lattice_step(state: PackedObject, conn: int, betti: list[int]):
    """:func:`isoflow.flow.guard.lattice_step` of a packed state: the flow
    step by simple deformations (Theorem 21), else its stuck blocks
    resolved.

    Returns
    -------
    tuple or None
        ``(new state, kind, moves reversed)``, kind ``flow`` or
        ``partial``; None where no resolution keeps ``betti``.

    Examples
    --------
    >>> import numpy as np
    >>> new, kind, reversed_moves = packed_lattice_step(PackedObject.of(np.ones((3, 3, 3), bool)), 6, [1, 0, 0])
    >>> new.shape, kind, reversed_moves
    ((2, 2, 2), 'flow', 0)
    """
    keep = vertex_rows(state, conn)
    cells, padded, pending, goal = fineblocks.blocks(state.bits, state.shape, keep)
    stuck, flipped = fineblocks.realise(cells, padded, pending, goal, is_face_connectivity(conn),
                                        backward=state.parity == 1)  # as lattice_step: no drift to one side
    del cells
    if not len(stuck):
        _toggle(keep, flipped, padded)
        return from_vertex_rows(state, keep), "flow", len(flipped)
    grid = tuple(s + 1 for s in state.shape)
    plain = flowbits.unpack(keep, vertex_shape(state)).reshape(grid)
    done = plain ^ _vertex_mask(flipped, padded, grid)
    obj = state.to_object()
    got = resolve_stuck(obj, plain, done, _vertex_mask(stuck, padded, grid), conn, betti)
    if got is None:
        return None
    new, kind, n_reversed = got
    return PackedObject.of(new), kind, n_reversed


def packed_guarded_step(state: PackedObject, conn: int, betti: list[int], *, seen: set | None = None,
                        may_grow: bool = True) -> tuple[PackedObject, str, int]:
    """:func:`isoflow.flow.guard.guarded_step` of a packed state.

    Returns
    -------
    tuple
        ``(next state, kind, moves reversed)``, kind ``flow``, ``partial``,
        ``thinning`` or ``fixed-point`` (the state itself).

    Examples
    --------
    >>> import numpy as np
    >>> one = PackedObject.of(np.ones((1, 1, 1), bool))
    >>> packed_guarded_step(one, 6, [1, 0, 0])[1]  # a single voxel is a fixed point
    'fixed-point'
    """
    got = packed_lattice_step(state, conn, betti)
    if got is not None:
        new, kind, n_reversed = got
        if is_progress(new.voxels, state.voxels, lambda: packed_key(new), lambda: packed_key(state), seen, may_grow):
            return new, kind, n_reversed
    obj = state.to_object()
    thinned = thinning_step(obj.volume, conn)
    if thinned is not None:
        return PackedObject.of(replace(obj, volume=thinned)), "thinning", 0
    return state, "fixed-point", 0
