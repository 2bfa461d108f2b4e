"""Rows of equal values found by hashing (numba): each row's first equal
row, in one pass, for :func:`isoflow.mesh.load.distinct_rows` on large
arrays and :func:`isoflow.mesh.load.unsorted_rows` (a weld's positions,
where the distinct rows need no sort).

An STL stores every corner of every triangle, so its positions are six
copies, about, of each distinct one; sorting every row (``np.lexsort`` over
the columns) costs most of reading such a file back or welding it. An
open-addressing table keyed by the rows' bits finds each row's first copy
in time linear in the rows; only the distinct rows are then sorted.
Values compare as numbers: ``-0.0`` equals ``0.0`` (both hash as ``0.0``)
and NaN equals nothing, as in the sort.
"""

from __future__ import annotations

import numpy as np

from ..scale.jit import njit


@njit(cache=True, nogil=True)
def _first_equal(p, bits, table, first):
    """``first[i]``: the first row of ``p`` equal to row i (i itself where
    none before it is); ``bits``: ``p``'s rows as int64 (what is hashed),
    ``table``: -1s, a power of two longer than ``p``."""
    mask = np.uint64(len(table) - 1)
    n, k = p.shape
    for i in range(n):
        h = np.uint64(0x9E3779B97F4A7C15)
        for c in range(k):
            h = (h ^ np.uint64(bits[i, c])) * np.uint64(0xBF58476D1CE4E5B9)
            h ^= h >> np.uint64(31)
        s = h & mask
        while True:
            j = table[s]
            if j < 0:
                table[s] = i
                first[i] = i
                break
            same = True
            for c in range(k):
                if p[j, c] != p[i, c]:
                    same = False
                    break
            if same:
                first[i] = j
                break
            s = (s + np.uint64(1)) & mask


def first_equal(points: np.ndarray) -> np.ndarray:
    """Each row's first equal row (its own index where it is the first).

    Parameters
    ----------
    points : numpy.ndarray
        ``(N, K)`` numbers (converted to float64: exact for every float32
        and for integers below 2^53).

    Returns
    -------
    numpy.ndarray
        ``int64`` of N: ``first[i] <= i`` and ``points[first[i]]`` equals
        ``points[i]``; ``first[i] == i`` for the first row of each value.

    Examples
    --------
    >>> first_equal(np.array([[1.0, 2.0], [0.0, 5.0], [1.0, 2.0], [-0.0, 5.0]])).tolist()
    [0, 1, 0, 1]
    """
    # + 0.0 makes -0.0 0.0, so that the two zeros, equal, hash alike; added
    # in place, as a float32 table's (an STL's corners) float64 copy and
    # its sum would be two copies at once
    p = np.array(points, np.float64, order="C").reshape(len(points), -1)
    p += 0.0
    table = np.full(1 << max(int(2 * len(p)).bit_length(), 1), -1, np.int64)
    first = np.empty(len(p), np.int64)
    _first_equal(p, p.view(np.int64), table, first)
    return first
