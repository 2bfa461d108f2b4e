"""Compiled kernels (numba) for the two passes that dominate ``isoflow info``
on large volumes: the configuration histogram and component counting.

Both stream over the volume without materialising a configuration array or
a label volume:

* :func:`histogram3d` keeps, along every row of the last axis, the 8-bit
  configuration of the current vertex and shifts in one nibble (the four
  voxels of the next layer) per step: four reads per vertex, one pass.
* :func:`count_components` is a run-based union-find: runs of equal voxels
  along the last axis are the nodes, runs in neighbouring rows that touch are
  joined. Memory is three int32 per run (about one byte per voxel on real
  data) instead of a 4-byte label per voxel.

They give the same numbers as :func:`isoflow.configurations.configurations`
and cc3d (the tests check it). The numpy/cc3d paths stay in use for small
volumes, where compiling would cost more than it saves; compiled code is
cached on disk after the first run.
"""

from __future__ import annotations

import numpy as np

try:  # numba is a dependency, but keep isoflow importable without it
    from numba import njit, prange

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    HAVE_NUMBA = False

#: volumes with at least this many voxels (128^3) use the compiled kernels
MIN_VOXELS = 2_000_000


if HAVE_NUMBA:

    @njit(cache=True, nogil=True)
    def _hist_rows(v, i0, i1, hist):
        """Configurations of vertices with first index in [i0, i1)."""
        nx, ny, nz = v.shape
        zero = np.zeros(nz, dtype=np.uint8)
        for i in range(i0, i1):
            for j in range(ny + 1):
                # the four rows of voxels around the vertex row (i, j):
                # octant (dx, dy) is voxel row (i-1+dx, j-1+dy)
                r00 = v[i - 1, j - 1] if i >= 1 and j >= 1 else zero
                r10 = v[i, j - 1] if i < nx and j >= 1 else zero
                r01 = v[i - 1, j] if i >= 1 and j < ny else zero
                r11 = v[i, j] if i < nx and j < ny else zero
                code = 0
                for k in range(nz):
                    nib = r00[k] | (r10[k] << 1) | (r01[k] << 2) | (r11[k] << 3)
                    code = (code >> 4) | (nib << 4)
                    hist[code] += 1
                hist[code >> 4] += 1  # the last vertex of the row, k = nz

    @njit(cache=True, parallel=True)
    def _hist_parallel(v, nchunks):
        nx = v.shape[0]
        out = np.zeros((nchunks, 256), dtype=np.int64)
        for c in prange(nchunks):
            i0 = (nx + 1) * c // nchunks
            i1 = (nx + 1) * (c + 1) // nchunks
            _hist_rows(v, i0, i1, out[c])
        return out.sum(axis=0)

    @njit(cache=True, nogil=True)
    def _runs(v, value):
        """Runs of ``value`` along the last axis: row offsets, starts, ends."""
        nx, ny, nz = v.shape
        count = 0
        for i in range(nx):
            for j in range(ny):
                prev = False
                for k in range(nz):
                    cur = v[i, j, k] == value
                    if cur and not prev:
                        count += 1
                    prev = cur
        offsets = np.zeros(nx * ny + 1, dtype=np.int64)
        start = np.empty(count, dtype=np.int32)
        end = np.empty(count, dtype=np.int32)
        n = 0
        for i in range(nx):
            for j in range(ny):
                prev = False
                for k in range(nz):
                    cur = v[i, j, k] == value
                    if cur and not prev:
                        start[n] = k
                    if prev and not cur:
                        end[n] = k
                        n += 1
                    prev = cur
                if prev:
                    end[n] = nz
                    n += 1
                offsets[i * ny + j + 1] = n
        return offsets, start, end

    @njit(cache=True, nogil=True, inline="always")
    def _find(parent, a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    @njit(cache=True, nogil=True)
    def _join_rows(parent, start, end, a0, a1, b0, b1, slack):
        """Union runs of row A [a0, a1) with touching runs of row B [b0, b1).

        Runs touch when their intervals overlap (slack 0) or overlap once
        widened by one voxel (slack 1: diagonal neighbours)."""
        ia, ib = a0, b0
        while ia < a1 and ib < b1:
            if start[ia] < end[ib] + slack and start[ib] < end[ia] + slack:
                ra, rb = _find(parent, ia), _find(parent, ib)
                if ra != rb:
                    if ra < rb:
                        parent[rb] = ra
                    else:
                        parent[ra] = rb
            # advance the run that ends first
            if end[ia] < end[ib]:
                ia += 1
            else:
                ib += 1

    @njit(cache=True, nogil=True)
    def _count(v, value, full, border, planar):
        """Components of voxels equal to ``value``; with ``border``, only
        those that do not touch the array's border. ``planar``: ``v`` is a
        2D image with a dummy first axis, whose ends are not a border."""
        nx, ny, nz = v.shape
        offsets, start, end = _runs(v, value)
        n = len(start)
        parent = np.arange(n).astype(np.int32)
        slack = 1 if full else 0
        for i in range(nx):
            for j in range(ny):
                a0, a1 = offsets[i * ny + j], offsets[i * ny + j + 1]
                if a0 == a1:
                    continue
                # previous rows: (i, j-1) and (i-1, j) always; with full
                # connectivity also (i-1, j-1) and (i-1, j+1), and all rows
                # touch diagonally (slack 1).
                if j >= 1:
                    r = i * ny + j - 1
                    _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], slack)
                if i >= 1:
                    r = (i - 1) * ny + j
                    _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], slack)
                    if full:
                        if j >= 1:
                            r = (i - 1) * ny + j - 1
                            _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], 1)
                        if j + 1 < ny:
                            r = (i - 1) * ny + j + 1
                            _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], 1)
        if not border:
            roots = 0
            for r in range(n):
                if parent[r] == r:
                    roots += 1
            return roots
        touch = np.zeros(n, dtype=np.bool_)
        for i in range(nx):
            for j in range(ny):
                edge_row = j == 0 or j == ny - 1 or (not planar and (i == 0 or i == nx - 1))
                for r in range(offsets[i * ny + j], offsets[i * ny + j + 1]):
                    if edge_row or start[r] == 0 or end[r] == nz:
                        touch[_find(parent, r)] = True
        inner = 0
        for r in range(n):
            if parent[r] == r and not touch[r]:
                inner += 1
        return inner


def _as3d(volume: np.ndarray) -> np.ndarray:
    v = np.ascontiguousarray(volume, dtype=bool)
    return v.reshape((1,) + v.shape) if v.ndim == 2 else v


def histogram3d(volume: np.ndarray) -> np.ndarray:
    """The 256 configuration counts of a 3D volume (same as
    ``np.bincount(configurations(volume).ravel(), minlength=256)``)."""
    v = np.ascontiguousarray(volume, dtype=bool).view(np.uint8)
    return _hist_parallel(v, 8)


def count_components(volume: np.ndarray, connectivity: int) -> int:
    """Number of components of the True voxels (6/26 in 3D, 4/8 in 2D)."""
    full = connectivity in (26, 8)
    return int(_count(_as3d(volume), True, full, False, volume.ndim == 2))


def count_enclosed(volume: np.ndarray, connectivity: int) -> int:
    """Background components (with ``connectivity``) not touching the border."""
    full = connectivity in (26, 8)
    return int(_count(_as3d(volume), False, full, True, volume.ndim == 2))


def count_object_and_enclosed(volume: np.ndarray, connectivity: int, background_connectivity: int) -> tuple[int, int]:
    """:func:`count_components` and :func:`count_enclosed` at once, on two
    threads: the kernels release the GIL and each is a single-core pass, so
    on a 2-core machine the Betti numbers cost the slower of the two."""
    from concurrent.futures import ThreadPoolExecutor

    v = _as3d(volume)
    planar = volume.ndim == 2
    with ThreadPoolExecutor(max_workers=2) as pool:
        b0 = pool.submit(_count, v, True, connectivity in (26, 8), False, planar)
        enclosed = pool.submit(_count, v, False, background_connectivity in (26, 8), True, planar)
        return int(b0.result()), int(enclosed.result())
