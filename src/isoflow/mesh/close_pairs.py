"""The pairs of points at most a distance apart, by hashing cells.

The weld merges vertices closer than a tolerance far below the spacing of
any mesh's vertices, so nearly every point is alone in its cell of that
size; a hash table of the cells finds the pairs in one compiled pass over
the points, as scipy's ``cKDTree.query_pairs`` does, without importing
``scipy.spatial`` (a large share of a short command's start-up).
"""

from __future__ import annotations

import numpy as np

from ..scale.jit import njit


def close_pairs(points: np.ndarray, r: float, cell: float = 0.0) -> np.ndarray:
    """Every pair ``i < j`` of points with ``|p_i - p_j| <= r``.

    Parameters
    ----------
    points : numpy.ndarray
        ``(n, 3)`` finite float coordinates.
    r : float
        The distance, greater than 0.
    cell : float, optional
        Side of the cells (at least ``r``): a side near the points' spacing
        leaves most points alone in their cell and farther than ``r`` from
        its faces, so that they look in no other cell.

    Returns
    -------
    numpy.ndarray
        ``(k, 2)`` int64, each pair once with ``i < j``, in no stated order
        (scipy's ``cKDTree(points).query_pairs(r, output_type="ndarray")``
        as a set).

    Notes
    -----
    Points within ``r`` lie in the same or neighbouring cells of side
    ``cell >= r`` (made larger where the coordinates exceed ``2**60`` cells,
    so that cell numbers stay exact integers). Each point looks in its own
    cell and in those of the 13 cells after it in lexicographic order whose
    shared faces it is within ``r`` of, so each pair is found once.

    Examples
    --------
    >>> import numpy as np
    >>> p = np.array([[0.0, 0, 0], [0.05, 0, 0], [1, 1, 1], [1, 1, 1.2]])
    >>> close_pairs(p, 0.1).tolist()
    [[0, 1]]
    """
    p = np.ascontiguousarray(points, dtype=np.float64)
    if len(p) < 2:
        return np.zeros((0, 2), np.int64)
    largest = float(np.abs(p).max())
    side = max(r, cell, largest * 2.0**-60)
    number = np.floor(p / side).astype(np.int64)
    table, chain = _cells(number)
    # a point's distance to its cell's faces is rounded: a slack of a few
    # units in the last place of the coordinates only adds cells to look in
    reach = r + (largest + side) * 2.0**-48
    return _pairs(p, number, side, table, chain, r, reach)


@njit(cache=True, nogil=True)
def _slot(table, c0, c1, c2):
    """The slot of cell (c0, c1, c2) in the open-addressed table (rows: the
    cell's three numbers and its last point, -1 where empty), or the empty
    slot where it would go."""
    mask = table.shape[0] - 1
    h = (np.uint64(c0) * np.uint64(0x9E3779B97F4A7C15)) ^ (np.uint64(c1) * np.uint64(0xC2B2AE3D27D4EB4F)) \
        ^ (np.uint64(c2) * np.uint64(0x165667B19E3779F9))
    s = np.int64((h >> np.uint64(24)) & np.uint64(mask))
    while table[s, 3] >= 0:
        if table[s, 0] == c0 and table[s, 1] == c1 and table[s, 2] == c2:
            return s
        s = (s + 1) & mask
    return s


@njit(cache=True, nogil=True)
def _cells(cell):
    """The table of occupied cells (load at most 1/2) and, per point, the
    next point of its cell (-1 at the end)."""
    n = cell.shape[0]
    size = 16
    while size < 2 * n:
        size *= 2
    table = np.full((size, 4), -1, np.int64)
    chain = np.full(n, -1, np.int64)
    for i in range(n):
        s = _slot(table, cell[i, 0], cell[i, 1], cell[i, 2])
        # element by element: an array assigned to a slice makes numba
        # compile its shape-mismatch message (string formatting), seconds
        # of a first run's compile
        table[s, 0], table[s, 1], table[s, 2] = cell[i, 0], cell[i, 1], cell[i, 2]
        chain[i] = table[s, 3]
        table[s, 3] = i
    return table, chain


@njit(cache=True, nogil=True)
def _pairs(p, cell, side, table, chain, r, reach):
    """The pairs, each found from the point of the lower cell."""
    out = np.empty((16, 2), np.int64)
    k = 0
    r2 = r * r
    for i in range(p.shape[0]):
        # the neighbouring cells this point is within reach of, per axis
        low1 = p[i, 1] - cell[i, 1] * side <= reach
        low2 = p[i, 2] - cell[i, 2] * side <= reach
        high0 = (cell[i, 0] + 1) * side - p[i, 0] <= reach
        high1 = (cell[i, 1] + 1) * side - p[i, 1] <= reach
        high2 = (cell[i, 2] + 1) * side - p[i, 2] <= reach
        for d0 in range(0, 2):
            if d0 == 1 and not high0:
                continue
            for d1 in range(-1 if d0 else 0, 2):
                if (d1 == 1 and not high1) or (d1 == -1 and not low1):
                    continue
                for d2 in range(-1 if (d0 or d1) else 0, 2):
                    if (d2 == 1 and not high2) or (d2 == -1 and not low2):
                        continue
                    own = d0 == 0 and d1 == 0 and d2 == 0
                    j = table[_slot(table, cell[i, 0] + d0, cell[i, 1] + d1, cell[i, 2] + d2), 3]
                    while j >= 0:
                        if not own or j > i:
                            q = 0.0
                            for a in range(3):
                                q += (p[i, a] - p[j, a]) ** 2
                            if q <= r2:
                                if k == out.shape[0]:
                                    grown = np.empty((2 * k, 2), np.int64)
                                    for m in range(k):  # (element by element: see _cells)
                                        grown[m, 0], grown[m, 1] = out[m, 0], out[m, 1]
                                    out = grown
                                out[k, 0] = min(i, j)
                                out[k, 1] = max(i, j)
                                k += 1
                        j = chain[j]
    return out[:k].copy()
