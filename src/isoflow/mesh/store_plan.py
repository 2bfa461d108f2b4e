"""How a zarr store is written slab by slab, in numbers: its chunks, its
slabs and the memory writing it holds at once (:mod:`isoflow.mesh.slabs`
writes it; :mod:`isoflow.mesh.voxelize` asks whether a store would hold a
grid that memory does not, to say so when it refuses one).
"""

from __future__ import annotations

import numpy as np

from ..errors import IsoflowError, given_text, whole_given
from .fills import Fill

#: a slab (and so a zarr chunk's first side) holds at most this many voxels
SLAB_BYTES = 1 << 27
#: zarr chunk sides along the second and third axes
CHUNK_YZ = 256
#: slabs in flight with the default (threaded) scheduler
WORKERS = 2


def slab_chunks(shape, chunks=None) -> tuple[int, int, int]:
    """Zarr chunks of a store of ``shape``: ``chunks`` checked, or by
    default a slab (one chunk thick along the first axis) of at most
    SLAB_BYTES voxels (a power of two rows, at most 64)."""
    nx, ny, nz = shape
    if chunks is None:
        rows = max(1, min(64, SLAB_BYTES // max(1, ny * nz)))
        rows = 1 << (rows.bit_length() - 1)
        chunks = (min(rows, nx), min(CHUNK_YZ, ny), min(CHUNK_YZ, nz))
    return check_chunks(chunks)


def check_chunks(chunks: object) -> tuple[int, int, int]:
    """A store's chunks given as three sides, each a whole number of at
    least 1 (a whole float or a NumPy integer too), as three ints.

    Parameters
    ----------
    chunks : object
        What was given for the chunks.

    Returns
    -------
    tuple of int
        The three sides.

    Raises
    ------
    IsoflowError
        ``chunks must be three positive integers, got ...``: 2.5 is no
        side, ``"4"`` no number and ``4`` not three sides.

    Examples
    --------
    >>> check_chunks((4.0, np.int64(8), 16))
    (4, 8, 16)
    >>> check_chunks((0, 3, 3))
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: chunks must be three positive integers, got (0, 3, 3)
    """
    # a side given as a 0D array of a number is that number; a 0D array of chunks is one number, not three
    listed = isinstance(chunks, (tuple, list)) or (isinstance(chunks, np.ndarray) and chunks.ndim == 1)
    # each side a whole number >= 1 (a NumPy integer, a 0D array of one): 2.5 is no side, and "4" no number
    wholes = [whole_given(c) for c in chunks] if listed else []
    if len(wholes) != 3 or any(c is None or c < 1 for c in wholes):
        raise IsoflowError(f"chunks must be three positive integers, got {given_text(chunks)}")
    return wholes[0], wholes[1], wholes[2]  # type: ignore[return-value]  # ints, as just checked


def slab_layout(shape, chunks=None) -> tuple[tuple[int, int, int], list[tuple[int, int]]]:
    """Zarr chunks (:func:`slab_chunks`) and slabs: a slab is one chunk
    thick along the first axis."""
    chunks = slab_chunks(shape, chunks)
    return chunks, [(a, min(a + chunks[0], shape[0])) for a in range(0, shape[0], chunks[0])]


#: the scanline indexes a slab's columns (and a layer's) in fewer than this
MAX_COLUMNS = 2**40


def store_need(shape, chunks=None, fill: Fill = "winding", temp: int = 0, fixed: int = 0) -> int | None:
    """Bytes that writing a store of ``shape`` holds at once: :data:`WORKERS`
    slabs of ``chunks`` (default :func:`slab_chunks`) with ``temp`` bytes
    of temporaries each, ``fixed`` bytes and the voxel centres of the
    plan, or for ``fill="flood"`` the whole grid where that is more; None
    where the grid has too many columns for any store."""
    nx, ny, nz = (int(n) for n in shape)
    if max(nx * ny, ny * nz) >= MAX_COLUMNS:
        return None
    rows = slab_chunks(shape, chunks)[0]
    # the centres: a grid of few columns and very many rows is refused
    # before its plan allocates them
    need = WORKERS * (rows * ny * nz + temp) + fixed + 8 * (nx + ny + nz)
    return max(need, nx * ny * nz) if fill == "flood" else need


def in_store(solid, frame, shape, chunks, fill: Fill, budget: int):
    """Whether writing the grid of ``shape`` (in the scaled ``frame`` of
    :func:`~isoflow.mesh.grid.voxel_grid`) to a store fits in ``budget``
    bytes: :func:`store_need` with the slabs' temporaries and two copies of
    the triangles. Returns ``(fits, plan, bytes)``; where the slabs'
    volumes alone do not fit, no plan is made and the bytes are theirs
    (None: too many columns)."""
    need = store_need(shape, chunks, fill)
    if need is None or need > budget:
        return False, None, need
    rows = slab_chunks(shape, chunks)[0]
    plan = solid.prepare(frame, frame[2], frame[3], shape)
    need = store_need(shape, chunks, fill, temp=plan.slab_bytes(rows), fixed=2 * plan.Tm.nbytes)
    return need is not None and need <= budget, plan, need
