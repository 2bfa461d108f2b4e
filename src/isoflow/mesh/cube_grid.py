"""A grid of cubes that holds closed boxes (a mesh's faces' boxes): the
pairs of boxes that overlap, for the crossing test
(:mod:`isoflow.mesh.crossings`), and the boxes a ray along an axis passes
by, cube after cube, for the rays that decide sheets of double-sided
faces (:mod:`isoflow.mesh.census`)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

#: candidate pairs handled at once (memory: about 200 bytes each)
CHUNK_PAIRS = 1 << 21


class CubeGrid:
    """Closed boxes ``[lo, hi]`` hashed into a grid of cubes about the size
    of a typical box: ``box`` (box numbers) sorted by ``key`` (their cubes),
    the cubes' ``start`` and ``size`` in it, each box's lowest cube ``cl``.
    A pair of overlapping boxes belongs to the one cube that holds the lower
    corner of their common box, so no pair is seen twice.  A point ``x``
    lies in cube ``floor((x - origin) / cube)``, as the boxes' corners."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray, compiled: bool = False) -> None:
        self.lo, self.hi = lo, hi
        cl, ch, self.origin, self.cube = _grid_cells(lo, hi)
        if compiled:
            self._compiled(cl, ch)
            return
        span = ch - cl + 1
        count = np.prod(span, axis=1)
        box = np.repeat(np.arange(len(lo)), count)
        local = np.arange(len(box)) - np.repeat(np.cumsum(count) - count, count)
        sx, sy = span[box, 0], span[box, 1]
        cell = cl[box] + np.stack([local % sx, (local // sx) % sy, local // (sx * sy)], axis=1)
        self.dims = ch.max(axis=0) + 1
        key = self.cube_key(cell)
        order = np.argsort(key, kind="stable")
        self.box, self.key, self.cl = box[order], key[order], cl
        self.start = np.flatnonzero(np.r_[True, self.key[1:] != self.key[:-1]])
        self.size = np.diff(np.r_[self.start, len(self.key)])

    def _compiled(self, cl: np.ndarray, ch: np.ndarray) -> None:
        """The same arrays from the compiled kernels: the cubes listed box
        by box and sorted by a radix sort (stable, as the NumPy pass)."""
        from .crossing_kernels import cube_entries, runs, sort_by_key

        self.cl = cl
        self.dims = ch.max(axis=0) + 1
        span = ch - cl + 1
        total = int((span[:, 0] * span[:, 1] * span[:, 2]).sum())
        box = np.empty(total, np.int64)
        key = np.empty(total, np.int64)
        cube_entries(cl, ch, self.dims, box, key)
        self.key, self.box = sort_by_key(key, box, int(np.prod(self.dims) - 1).bit_length())
        self.start, self.size = runs(self.key)

    def cube_key(self, cell: np.ndarray) -> np.ndarray:
        """One integer per cube (x fastest)."""
        return (cell[:, 2] * self.dims[1] + cell[:, 1]) * self.dims[0] + cell[:, 0]

    def pairs(self) -> Iterator[np.ndarray]:
        """Pairs ``(i, j)``, ``i < j``, of the boxes that overlap, in chunks."""
        after = np.repeat(self.start + self.size, self.size) - np.arange(len(self.key)) - 1
        lo, hi = self.lo, self.hi
        for first, second in _index_pairs(after):
            i, j = self.box[first], self.box[second]
            mine = self.cube_key(np.maximum(self.cl[i], self.cl[j])) == self.key[first]
            meet = np.all((lo[i] <= hi[j]) & (lo[j] <= hi[i]), axis=1)
            keep = mine & meet
            yield np.stack([np.minimum(i, j)[keep], np.maximum(i, j)[keep]], axis=1)


def _grid_cells(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """The lowest and highest grid cube of each box, for a cube size that
    puts each box in a few cubes on average (doubled until it does), and
    the grid's origin and cube size."""
    origin = lo.min(axis=0)
    extent = float(np.max(hi.max(axis=0) - origin))
    if not extent > 0:
        zero = np.zeros(lo.shape, np.int64)
        return zero, zero, origin, np.inf
    d = hi - lo
    size = max(float(np.median(np.maximum(np.maximum(d[:, 0], d[:, 1]), d[:, 2]))), extent / 2**20)
    while True:
        cl = np.floor((lo - origin) / size).astype(np.int64)
        ch = np.floor((hi - origin) / size).astype(np.int64)
        span = ch - cl + 1
        if (span[:, 0] * span[:, 1] * span[:, 2]).sum() <= 8 * len(lo) + 1024 or size >= extent:
            return cl, ch, origin, size
        size *= 2


def _index_pairs(after: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """``(first, second)`` index arrays: each entry ``k`` with each of the
    ``after[k]`` entries that follow it, at most :data:`CHUNK_PAIRS` a chunk."""
    ends = np.cumsum(after)
    lo = 0
    while lo < len(after):
        hi = int(np.searchsorted(ends, ends[lo - 1] + CHUNK_PAIRS if lo else CHUNK_PAIRS, side="right"))
        hi = max(hi, lo + 1)
        n = after[lo:hi]
        first = np.repeat(np.arange(lo, hi), n)
        offset = np.arange(len(first)) - np.repeat(np.cumsum(n) - n, n)
        yield first, first + 1 + offset
        lo = hi
