"""A zarr array read block by block through a cache of decoded chunks.

A pass that reads each block with a halo (the boundary mesh reads one voxel
below and two above every block) touches the neighbouring chunks too, and
zarr decodes a whole chunk to give one layer of it: read directly, every
chunk would be decoded up to 27 times. :class:`ChunkReader` keeps the
chunks it decoded, the least recently used dropped past a byte limit, so
that blocks taken layer by layer along the first axis decode each chunk
once while the cache holds three layers of them.

It also presents the stored array in isoflow's (x, y, z) order (an
OME-Zarr image stores (z, y, x), and may have a time or channel axis of
length 1) and can select one label's voxels, so that a block read is one
call whatever the store's layout.

The cache lives in the reader: the threads of one process share it. A
reader sent to another process (a dask.distributed worker, dask's process
pool) keeps no chunk past the read that decoded it: each task there
unpickles a copy of its own, which no other task reads through, and the
worker holds every task's copy until its layer of blocks is done, so
copies that kept the chunks their block and halo touched (up to 27 each)
held that many chunks for every block of the layer, where the memory
check counts the one chunk a read decodes at a time.
"""

from __future__ import annotations

import itertools
import threading
from collections import OrderedDict

import numpy as np


class ChunkReader:
    """``reader[x0:x1, y0:y1, z0:z1]``: a host array of a region of a
    zarr-like array (``shape``, ``chunks``, ``dtype``, slicing), in x, y, z
    order.

    Parameters
    ----------
    array : zarr.Array or array-like with ``chunks``
        The stored array.
    order : sequence of int, optional
        The stored axis of x, y and z (default: the stored order).
    fixed : sequence of int, optional
        Stored axes of length 1 that are not spatial (read at index 0).
    label : number, optional
        Read ``array == label`` instead of the values.
    max_bytes : int
        The decoded chunks kept (default: 256 MiB); a copy unpickled in
        another process keeps none.

    Examples
    --------
    >>> a = np.arange(24).reshape(2, 3, 4)
    >>> class Stored:  # a zarr-like array: shape, chunks, dtype, slicing
    ...     shape, chunks, dtype = a.shape, (1, 2, 2), a.dtype
    ...     def __getitem__(self, key): return a[key]
    >>> r = ChunkReader(Stored(), order=(2, 1, 0))
    >>> r.shape, r[1:3, 0:2, 0:1].tolist()
    ((4, 3, 2), [[[1], [5]], [[2], [6]]])
    """

    def __init__(self, array, order=None, fixed=(), label=None, max_bytes: int = 256 << 20):
        self.array = array
        self.order = tuple(range(len(array.shape)) if order is None else order)
        self.fixed = tuple(fixed)
        self.label = label
        self.max_bytes = int(max_bytes)
        stored_chunks = tuple(int(c) for c in array.chunks)
        self.shape = tuple(int(array.shape[i]) for i in self.order)
        self.chunks = tuple(stored_chunks[i] for i in self.order)
        shards = getattr(array, "shards", None)
        self.shards = None if shards is None else tuple(int(shards[i]) for i in self.order)
        self.dtype = np.dtype(bool) if label is not None else np.dtype(array.dtype)
        # what zarr reads for a chunk never written, named where it is refused
        self.fill_value = None if label is not None else getattr(array, "fill_value", None)
        self.ndim = len(self.shape)
        self._stored_chunks = stored_chunks
        self._keeps = True
        self._reset()

    def _reset(self) -> None:
        self._cache: OrderedDict = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        for name in ("_cache", "_bytes", "_lock", "_keeps"):
            del state[name]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        # a copy unpickled in another process reads for one task only, and the worker holds it until the
        # layer is done: the chunks it kept would outlive the read that needed them
        self._keeps = False
        self._reset()

    def __getitem__(self, key) -> np.ndarray:
        bounds = [s.indices(n)[:2] for s, n in zip(key, self.shape)]
        out = np.empty([b - a for a, b in bounds], np.dtype(self.array.dtype))
        ranges = [range(a // c, -(-b // c)) for (a, b), c in zip(bounds, self.chunks)]
        for index in itertools.product(*ranges):
            chunk, start = self._chunk(index)
            lo = [max(a, s) for (a, _), s in zip(bounds, start)]
            hi = [min(b, s + n) for (_, b), s, n in zip(bounds, start, chunk.shape)]
            if all(h > low for low, h in zip(lo, hi)):
                out[tuple(slice(low - a, h - a) for low, h, (a, _) in zip(lo, hi, bounds))] = \
                    chunk[tuple(slice(low - s, h - s) for low, h, s in zip(lo, hi, start))]
            # a chunk that is not kept is let go before the next is decoded, not held beside its buffers
            del chunk
        return out if self.label is None else out == self.label

    def _chunk(self, index) -> tuple[np.ndarray, list[int]]:
        """Chunk ``index`` (in x, y, z order) decoded, in x, y, z order, and
        its first voxel."""
        start = [i * c for i, c in zip(index, self.chunks)]
        with self._lock:
            if index in self._cache:
                self._cache.move_to_end(index)
                return self._cache[index], start
        key = [0] * len(self.array.shape)
        for axis in self.fixed:
            key[axis] = 0
        for axis, s, c, n in zip(self.order, start, self.chunks, self.shape):
            key[axis] = slice(s, min(s + c, n))
        stored = np.asarray(self.array[tuple(key)])
        kept = [i for i in range(len(self.array.shape)) if i not in self.fixed]
        data = np.transpose(stored, [kept.index(i) for i in self.order])
        if not self._keeps:
            return data, start
        with self._lock:
            self._cache[index] = data
            self._bytes += data.nbytes
            while self._bytes > self.max_bytes and len(self._cache) > 1:
                _, old = self._cache.popitem(last=False)
                self._bytes -= old.nbytes
        return data, start
