"""Vertex configurations: the 2^n cells around every lattice vertex.

Section 4 of the paper reads the curvature of a digital surface off the
3x3x3 neighbourhood of a boundary point. With voxels as unit cubes (Definition
1: a "digital 3-simplex" is the cube spanned by 8 lattice points), the same
information sits in the 2x2x2 block of voxels around each lattice vertex: the
vertex's *configuration*.

Conventions used everywhere in isoflow:

* voxel ``v`` (an index into the array) is the closed unit cube ``[v, v+1]``;
* lattice vertex ``w`` is the common corner of the cells ``w - 1 + d`` for
  ``d`` in ``{0,1}^n``, its *octants*;
* octant ``d`` is bit ``d_0 + 2 d_1 + 4 d_2`` of the configuration (axis 0 is
  the array's first axis);
* an array of shape ``S`` has vertices ``0 .. S`` on every axis (the volume is
  padded with one layer of background), so the configuration array has shape
  ``S + 1``.

Everything here is array in / array out; the lookup tables over all 256 (3D)
or 16 (2D) configurations are derived in :mod:`isoflow.digital.indices` from the
geometry of the window, never typed in.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, given_text, whole_given
from ..results import read_only
from ..scale import arrays
from ..scale.compiled import Method, use_compiled

#: the largest dimension of a window (4D already has 2^16 configurations)
MAX_DIM = 4
#: the dimensions whose configurations isoflow computes
DIMENSIONS = (1, 2, 3, 4)


def check_dimension(n: object, name: str = "dimension n") -> int:
    """The dimension of a window, an integer 1..4, or one line saying why
    not, naming it as its caller's parameter ``name``."""
    whole = whole_given(n)
    if whole is None:
        raise IsoflowError(f"{name} must be an integer 1..{MAX_DIM}, got {given_text(n)}")
    if not 1 <= whole <= MAX_DIM:
        raise IsoflowError(f"{name} must be 1..{MAX_DIM}, got {given_text(n)}")
    return whole


def octant_bit(d: Sequence[int]) -> int:
    """Bit index of octant ``d`` (a 0/1 tuple): ``d_0 + 2 d_1 + 4 d_2 + ...``.

    Examples
    --------
    >>> octant_bit((1, 0, 1))
    5
    """
    return sum(int(b) << i for i, b in enumerate(d))


@cache
def octants(n: int) -> np.ndarray:
    """Offsets ``d`` of the ``2^n`` cells of the window, row ``b`` = bit ``b``.

    Bit ``b`` is ``d_0 + 2 d_1 + 4 d_2 + 8 d_3``, i.e. ``d_i = (b >> i) & 1``:
    the one octant table of isoflow (read-only int8, shape ``(2^n, n)``).

    Examples
    --------
    >>> octants(2).tolist()
    [[0, 0], [1, 0], [0, 1], [1, 1]]
    """
    n = check_dimension(n)
    b = np.arange(1 << n)
    return read_only(((b[:, None] >> np.arange(n)) & 1).astype(np.int8))


def full_window(n: int) -> int:
    """The configuration whose every cell is in the object: ``2^(2^n) - 1``."""
    return (1 << (1 << n)) - 1


def half_mask(n: int, axis: int, side: int) -> int:
    """Bitmask of the window cells with ``d_axis == side`` (one half)."""
    d = octants(n)
    return int(sum(1 << b for b in range(1 << n) if d[b, axis] == side))


@cache
def window_faces(n: int) -> tuple[tuple[int, int], ...]:
    """The ``3^n`` faces of the lattice incident to a vertex, as (mask, k).

    A face incident to vertex ``w`` is ``w + prod_i F_i`` with ``F_i`` one of
    ``{0}``, ``[-1, 0]``, ``[0, 1]`` (``e_i = 0, -1, +1``); ``k`` is its
    dimension (the number of ``e_i != 0``). ``mask`` is the set of window
    cells that contain it: ``d_i = (e_i > 0)`` where ``e_i != 0``, ``d_i``
    free where ``e_i = 0``. The same masks are exactly the blocks of
    ``2^(n-k)`` face-adjacent cells of the window (the faces of the dual
    complex), which is why both Euler tables come from one list
    (:func:`isoflow.digital.indices.euler_lut`).

    Examples
    --------
    >>> window_faces(1)  # the edge to the left (cell 0), the vertex (both cells), the edge to the right
    ((1, 1), (3, 0), (2, 1))
    """
    n = check_dimension(n)
    d = octants(n)
    faces = []
    for e in itertools.product((-1, 0, 1), repeat=n):
        ok = np.ones(1 << n, dtype=bool)
        for i, ei in enumerate(e):
            if ei != 0:
                ok &= d[:, i] == (1 if ei > 0 else 0)
        mask = int(sum(1 << int(b) for b in np.flatnonzero(ok)))
        faces.append((mask, sum(1 for ei in e if ei != 0)))
    return tuple(faces)


def face_neighbours(sets: np.ndarray, n: int, axis: int) -> np.ndarray:
    """The face neighbours across ``axis`` of sets of window cells (bitmasks)."""
    step = 1 << axis  # bit distance between d and d xor e_axis
    return ((sets & half_mask(n, axis, 0)) << step) | ((sets & half_mask(n, axis, 1)) >> step)


def face_connected(sets: np.ndarray, n: int) -> np.ndarray:
    """Whether each non-empty set of window cells (a bitmask) is connected
    under the face adjacency of the cells; breadth-first growth from the
    lowest cell, vectorised over all sets.

    Examples
    --------
    >>> face_connected(np.array([0b0011, 0b1001]), 2).tolist()  # a domino; a diagonal pair
    [True, False]
    """
    sets = np.asarray(sets, dtype=np.int64)
    reach = sets & -sets  # lowest set bit
    while True:
        grown = reach.copy()
        for axis in range(n):
            grown |= face_neighbours(reach, n, axis)
        grown &= sets
        if np.array_equal(grown, reach):
            return reach == sets
        reach = grown


def configurations(volume: ArrayLike) -> np.ndarray:
    """The configuration of every lattice vertex of a binary image (section 4).

    Vertex ``w`` is the common corner of the ``2^n`` cells ``w - 1 + d``,
    ``d`` in ``{0,1}^n``; cell ``d`` is bit ``d_0 + 2 d_1 + 4 d_2 + 8 d_3``
    of the vertex's configuration (:func:`octants`). The image is padded
    with one layer of background, so every boundary vertex is counted.

    Parameters
    ----------
    volume : array_like of bool or 0/1, 1 to 4 dimensions
        A NumPy array, or a CuPy (or other array-API) array, whose
        configurations are then computed on its device.

    Returns
    -------
    numpy.ndarray
        uint8 (uint16 in 4D), of shape ``volume.shape + 1`` on every axis,
        in the input's array library.

    Raises
    ------
    IsoflowError
        When the volume is not binary or not 1D to 4D.

    Notes
    -----
    One pass per axis: pairs of cells along axis 0 (bits 0-1), pairs of
    pairs along axis 1 (bits 0-3), and so on, which is cheaper than or-ing
    the ``2^n`` shifted copies.

    Examples
    --------
    A single voxel is the convex corner (one octant, eq. 4.6) of each of its
    eight corners:

    >>> import numpy as np
    >>> c = configurations(np.ones((1, 1, 1), bool))
    >>> c.shape, sorted(int(v) for v in c.ravel())
    ((2, 2, 2), [1, 2, 4, 8, 16, 32, 64, 128])
    """
    # a label table holds no configurations
    xp, v = arrays.as_volume(volume, "configurations: volume", dims=DIMENSIONS, remedy="configurations({})")
    # 8 octant bits up to 3D, 16 in 4D
    dtype = xp.uint8 if v.ndim <= 3 else xp.uint16
    # The one layer of background padding, written with the standard's
    # zeros + slice assignment (``pad`` is not in the array API).
    code = arrays.zeros(xp, tuple(s + 2 for s in v.shape), dtype, like=v)
    code[(slice(1, -1),) * v.ndim] = xp.astype(v, dtype)
    for axis in range(v.ndim):
        lo = [slice(None)] * v.ndim
        hi = [slice(None)] * v.ndim
        lo[axis] = slice(None, -1)
        hi[axis] = slice(1, None)
        code = code[tuple(lo)] | (code[tuple(hi)] << (1 << axis))
    return code


def configurations_at(volume: np.ndarray, vertices: ArrayLike) -> np.ndarray:
    """The configurations of :func:`configurations` at some lattice vertices
    only, read from their ``2^n`` cells (no array of every vertex's).

    Parameters
    ----------
    volume : bool ndarray
        The binary image, n-dimensional.
    vertices : array_like of int, shape (K, n)
        Lattice vertices, ``0 <= w <= volume.shape`` (cells outside the
        image are background, as :func:`configurations` pads them).

    Returns
    -------
    numpy.ndarray
        int64, shape (K,): ``configurations(volume)[tuple(vertices.T)]``.

    Examples
    --------
    >>> import numpy as np
    >>> configurations_at(np.ones((1, 1, 1), bool), [[0, 0, 0], [1, 1, 1], [1, 0, 1]]).tolist()
    [128, 1, 4]
    """
    v = np.asarray(volume, dtype=bool)
    w = np.asarray(vertices, dtype=np.int64).reshape(-1, v.ndim)
    shape = np.asarray(v.shape)
    code = np.zeros(len(w), dtype=np.int64)
    for bit, d in enumerate(octants(v.ndim)):
        cell = w - 1 + d
        inside = np.all((cell >= 0) & (cell < shape), axis=1)
        code[inside] |= v[tuple(cell[inside].T)].astype(np.int64) << bit
    return code


def empty_histogram(shape: Sequence[int]) -> np.ndarray:
    """The configuration histogram of an all-background volume of ``shape``.

    Every vertex of the padded grid, ``prod(s + 1)`` of them, sees
    configuration 0; the volume need not exist, so an empty one (an axis
    of length 0) is answered without a pass.

    Parameters
    ----------
    shape : sequence of int
        The volume's shape, 1 to 4 axes.

    Returns
    -------
    numpy.ndarray
        ``2^(2^n)`` int64 counts, all in configuration 0.

    Examples
    --------
    >>> h = empty_histogram((0, 3, 4))
    >>> int(h[0]), int(h[1:].sum()), len(h)
    (20, 0, 256)
    """
    hist = np.zeros(1 << (1 << len(shape)), dtype=np.int64)
    hist[0] = math.prod(int(s) + 1 for s in shape)
    return hist


def configuration_histogram(volume: ArrayLike, slab: int | np.integer | None = None, method: Method = "auto") -> np.ndarray:
    """How many vertices have each configuration: the counts behind eq. 4.9.

    Parameters
    ----------
    volume : array_like of bool or 0/1, 1 to 4 dimensions
        As for :func:`configurations`.
    slab : int, optional
        Rows of axis 0 taken at a time where the work goes slab by slab
        (default: about 8M voxels), so that memory stays a few bytes per
        slab voxel whatever the volume.
    method : {"auto", "numpy", "compiled"}
        The streaming compiled kernel (3D host volumes), the NumPy passes, or
        ``"auto"``: by the volume's size together with the voxels that
        ``"auto"`` has already sent down the NumPy passes in this process
        (:func:`~isoflow.scale.compiled.use_compiled`).

    Returns
    -------
    numpy.ndarray
        ``2^(2^n)`` host int64 counts (256 in 3D), indexed by configuration.

    Notes
    -----
    Large 3D host volumes go through the streaming kernel of
    :mod:`isoflow.scale.kernels`; otherwise (4D, device arrays) slab by slab
    along axis 0, the slabs overlapping by one voxel layer so that every
    vertex is counted once. Every table of the paper is a function of the
    configuration, so this histogram gives chi (Theorems 10-11), the class
    vector ``n`` (eq. 4.9) and the energy (eq. 5.22).

    Examples
    --------
    >>> import numpy as np
    >>> h = configuration_histogram(np.ones((2, 2, 2), bool))
    >>> int(h.sum()), int(h[255])  # 27 vertices, one of them inside
    (27, 1)
    """
    # checked before any pass: the NumPy passes step through the volume by
    # it, and the compiled kernel, which takes no slab, would not look at it
    if slab is not None:
        whole = whole_given(slab)
        if whole is None or whole < 1:
            raise IsoflowError(f"slab must be an integer >= 1, got {given_text(slab)}")
        slab = whole
    # a label table holds no histogram
    xp, v = arrays.as_volume(volume, "configuration_histogram: volume", dims=DIMENSIONS,
                             remedy="configuration_histogram({})")
    size = 1 << (1 << v.ndim)
    if v.size == 0:
        # no voxel: no padded copy of a volume that may be empty along one
        # axis only, and long along the others
        return empty_histogram(v.shape)
    if use_compiled(v, method=method, record=v.ndim == 3) and v.ndim == 3:
        from ..scale.kernels import histogram3d

        return histogram3d(v)
    if slab is None:
        row = math.prod(v.shape[1:])
        slab = max(1, (1 << 23) // max(row, 1))
    hist = np.zeros(size, dtype=np.int64)
    n0 = v.shape[0]
    with arrays.on_device(v):
        for start in range(0, max(n0, 1), slab):
            stop = min(start + slab, n0)
            # Vertices start..stop-1 (plus the last one n0 on the final slab)
            # need voxels start-1..stop-1; take them and drop the duplicated
            # vertex row.
            lo = max(start - 1, 0)
            part = configurations(v[lo:stop, ...])
            # part's vertex rows are lo .. stop; keep rows start .. stop-1,
            # and row n0 on the last slab.
            first = start - lo
            last = part.shape[0] if stop == n0 else part.shape[0] - 1
            hist += arrays.count_codes(xp, part[first:last, ...], size)
    return hist
