"""Compiled kernels (numba) for the two passes that dominate ``isoflow info``
on large volumes: the configuration histogram and component counting.

Both stream over the volume without materialising a configuration array or
a label volume:

* :func:`histogram3d` keeps, along every row of the last axis, the 8-bit
  configuration of the current vertex and shifts in one nibble (the four
  voxels of the next layer) per step: four reads per vertex, one pass.
* :func:`count_components` is a run-based union-find: runs of equal voxels
  along the last axis are the nodes, runs in neighbouring rows that touch are
  joined. The background's runs are the gaps between the object's, so the
  volume is read once for both. Memory is three int32 per run (about one
  byte per voxel on real data) instead of a 4-byte label per voxel.

They give the same numbers as :func:`isoflow.digital.configurations.configurations`
and scipy (the tests check it). The numpy/scipy paths stay in use for small
volumes, where compiling would cost more than it saves; compiled code is
cached on disk after the first run.
"""

from __future__ import annotations

import numpy as np

try:  # numba is a dependency, but keep isoflow importable without it
    from numba import njit

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
                    # != 0: a bool array made by .view(bool) may hold other bytes
                    nib = (r00[k] != 0) | ((r10[k] != 0) << 1) | ((r01[k] != 0) << 2) | ((r11[k] != 0) << 3)
                    code = (code >> 4) | (nib << 4)
                    hist[code] += 1
                hist[code >> 4] += 1  # the last vertex of the row, k = nz

    @njit(cache=True, nogil=True)
    def _count_runs_rows(v, counts, i0, i1):
        """Number of runs of True in every row (i, j), i0 <= i < i1."""
        ny, nz = v.shape[1], v.shape[2]
        for i in range(i0, i1):
            for j in range(ny):
                row = v[i, j]
                c = 0
                prev = 0
                for k in range(nz):
                    cur = 1 if row[k] else 0
                    c += cur & (1 - prev)
                    prev = cur
                counts[i * ny + j + 1] = c

    @njit(cache=True, nogil=True)
    def _fill_runs_rows(v, offsets, start, end, i0, i1):
        """Starts and ends of the runs of True of rows i0 <= i < i1."""
        ny, nz = v.shape[1], v.shape[2]
        for i in range(i0, i1):
            for j in range(ny):
                r = offsets[i * ny + j]
                row = v[i, j]
                prev = 0
                for k in range(nz):
                    cur = row[k]
                    if cur and not prev:
                        start[r] = k
                    elif prev and not cur:
                        end[r] = k
                        r += 1
                    prev = cur
                if prev:
                    end[r] = nz

    @njit(cache=True, nogil=True)
    def _count_gaps_rows(offsets, start, end, nz, counts, r0, r1):
        """Number of background runs (gaps between object runs) per row."""
        for r in range(r0, r1):
            a, b = offsets[r], offsets[r + 1]
            if nz == 0:
                c = 0
            elif a == b:
                c = 1
            else:
                c = (b - a) + 1 - (1 if start[a] == 0 else 0) - (1 if end[b - 1] == nz else 0)
            counts[r + 1] = c

    @njit(cache=True, nogil=True)
    def _fill_gaps_rows(offsets, start, end, nz, goff, gstart, gend, r0, r1):
        for r in range(r0, r1):
            g = goff[r]
            prev = 0
            for q in range(offsets[r], offsets[r + 1]):
                if start[q] > prev:
                    gstart[g] = prev
                    gend[g] = start[q]
                    g += 1
                prev = end[q]
            if prev < nz:
                gstart[g] = prev
                gend[g] = nz

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
    def _join_range(shape, offsets, start, end, full, parent, i0, i1, seam):
        """Join the runs of rows i0 <= i < i1 with their earlier neighbour
        rows: (i, j-1) and (i-1, j), and with full connectivity (i-1, j-1),
        (i-1, j+1), all with slack 1 (diagonal contact). Rows i0-1 are left
        out unless ``seam``, so that two ranges can run at once on disjoint
        parts of ``parent``; ``seam`` joins only row i0 to row i0-1."""
        nx, ny, nz = shape
        slack = 1 if full else 0
        for i in range(i0, i1):
            for j in range(ny):
                a0, a1 = offsets[i * ny + j], offsets[i * ny + j + 1]
                if a0 == a1:
                    continue
                if j >= 1 and not seam:
                    r = i * ny + j - 1
                    _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], slack)
                if i >= 1 and (i > i0 or seam):
                    r = (i - 1) * ny + j
                    _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], slack)
                    if full:
                        if j >= 1:
                            r = (i - 1) * ny + j - 1
                            _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], 1)
                        if j + 1 < ny:
                            r = (i - 1) * ny + j + 1
                            _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], 1)

    @njit(cache=True, nogil=True)
    def _roots(shape, offsets, start, end, parent, border, planar):
        """Number of components; with ``border``, only those that do not
        touch the array's border. ``planar``: a 2D image with a dummy first
        axis, whose ends are not a border."""
        nx, ny, nz = shape
        n = len(start)
        touch = np.zeros(n, dtype=np.bool_)
        if border:
            for i in range(nx):
                for j in range(ny):
                    a0, a1 = offsets[i * ny + j], offsets[i * ny + j + 1]
                    if a0 == a1:
                        continue
                    if j == 0 or j == ny - 1 or (not planar and (i == 0 or i == nx - 1)):
                        for r in range(a0, a1):
                            touch[_find(parent, r)] = True
                    else:
                        # inside rows only their first and last runs can
                        # reach the ends of the row
                        if start[a0] == 0:
                            touch[_find(parent, a0)] = True
                        if end[a1 - 1] == nz:
                            touch[_find(parent, a1 - 1)] = True
        roots = 0
        for r in range(n):
            if parent[r] == r and not touch[r]:
                roots += 1
        return roots

    @njit(cache=True, nogil=True)
    def _label_polygons(polygons, nv):
        """Vertex labels 0..n-1 of the connected components of a polygon
        mesh (rows of vertex ids, -1 for an empty slot), numbered in order
        of their smallest vertex."""
        parent = np.arange(nv).astype(polygons.dtype)
        for f in range(polygons.shape[0]):
            a = _find(parent, polygons[f, 0])
            for t in range(1, polygons.shape[1]):
                if polygons[f, t] >= 0:
                    b = _find(parent, polygons[f, t])
                    if a != b:
                        parent[b] = a
        label = np.full(nv, -1, dtype=np.int32)
        count = 0
        for i in range(nv):
            r = _find(parent, i)
            if label[r] < 0:
                label[r] = count
                count += 1
            label[i] = label[r]
        return label, count


def label_polygons(polygons: np.ndarray, nv: int) -> tuple[np.ndarray, int]:
    """``(labels, count)``: connected components of a mesh's ``nv`` vertices
    joined by its polygons (same partition as scipy's ``connected_components``
    on the face graph; 4 bytes per vertex instead of a sparse matrix)."""
    return _label_polygons(np.ascontiguousarray(polygons), nv)


def _halves(n: int):
    mid = n // 2
    return [(a, b) for a, b in ((0, mid), (mid, n)) if b > a]


def _on_two_threads(calls) -> list:
    """Run compiled calls (which release the GIL) on two threads. Plain
    threads rather than numba's parallel=True: no OpenMP pool spinning
    next to them, and no slow parallel compile."""
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=2) as pool:
        futures = [pool.submit(fn, *args) for fn, *args in calls]
        return [f.result() for f in futures]


def _as3d(volume: np.ndarray) -> np.ndarray:
    v = np.ascontiguousarray(volume, dtype=bool)
    return v.reshape((1,) + v.shape) if v.ndim == 2 else v


def histogram3d(volume: np.ndarray) -> np.ndarray:
    """The 256 configuration counts of a 3D volume (same as
    ``np.bincount(configurations(volume).ravel(), minlength=256)``)."""
    v = np.ascontiguousarray(volume, dtype=bool).view(np.uint8)
    parts = [np.zeros(256, np.int64) for _ in range(2)]  # one per thread
    _on_two_threads([(_hist_rows, v, a, b, h) for (a, b), h in zip(_halves(v.shape[0] + 1), parts)])
    return parts[0] + parts[1]


def _object_runs(v: np.ndarray):
    """Runs of True along the last axis of a 3D uint8 array: row offsets,
    starts, ends; runs numbered row by row in C order."""
    counts = np.zeros(v.shape[0] * v.shape[1] + 1, dtype=np.int64)
    halves = _halves(v.shape[0])
    _on_two_threads([(_count_runs_rows, v, counts, a, b) for a, b in halves])
    offsets = np.cumsum(counts)
    start = np.empty(offsets[-1], dtype=np.int32)
    end = np.empty(offsets[-1], dtype=np.int32)
    _on_two_threads([(_fill_runs_rows, v, offsets, start, end, a, b) for a, b in halves])
    return offsets, start, end


def _gap_runs(offsets, start, end, nz: int):
    """The background runs of every row: the gaps between the object's runs,
    so the volume is not read a second time."""
    nrows = len(offsets) - 1
    counts = np.zeros(nrows + 1, dtype=np.int64)
    halves = _halves(nrows)
    _on_two_threads([(_count_gaps_rows, offsets, start, end, nz, counts, a, b) for a, b in halves])
    goff = np.cumsum(counts)
    gstart = np.empty(goff[-1], dtype=np.int32)
    gend = np.empty(goff[-1], dtype=np.int32)
    _on_two_threads([(_fill_gaps_rows, offsets, start, end, nz, goff, gstart, gend, a, b) for a, b in halves])
    return goff, gstart, gend
def _runs_of(volume: np.ndarray, value: bool):
    v = _as3d(volume).view(np.uint8)
    offsets, start, end = _object_runs(v)
    if value:
        return v.shape, offsets, start, end
    return (v.shape,) + tuple(_gap_runs(offsets, start, end, v.shape[2]))


def _count_runs(runs_list, fulls, borders, planar: bool) -> list[int]:
    """Union-find over one or more run sets, on two threads.

    Each run set is joined in two halves along the first axis at once (the
    halves touch disjoint parts of the parent array), then along the seam
    between them; the compiled passes release the GIL."""
    from concurrent.futures import ThreadPoolExecutor

    jobs = []
    with ThreadPoolExecutor(max_workers=2) as pool:
        for (shape, off, st, en), full in zip(runs_list, fulls):
            parent = np.arange(len(st), dtype=np.int32)
            mid = shape[0] // 2
            parts = [pool.submit(_join_range, shape, off, st, en, full, parent, a, b, False)
                     for a, b in ((0, mid), (mid, shape[0])) if b > a]
            jobs.append((parent, parts, mid))
        out = []
        for ((shape, off, st, en), full, border), (parent, parts, mid) in zip(zip(runs_list, fulls, borders), jobs):
            for f in parts:
                f.result()
            if 0 < mid < shape[0]:
                _join_range(shape, off, st, en, full, parent, mid, mid + 1, True)
            out.append(int(_roots(shape, off, st, en, parent, border, planar)))
    return out


def count_components(volume: np.ndarray, connectivity: int) -> int:
    """Number of components of the True voxels (6/26 in 3D, 4/8 in 2D)."""
    runs = _runs_of(volume, True)
    return _count_runs([runs], [connectivity in (26, 8)], [False], volume.ndim == 2)[0]


def count_enclosed(volume: np.ndarray, connectivity: int) -> int:
    """Background components (with ``connectivity``) not touching the border."""
    runs = _runs_of(volume, False)
    return _count_runs([runs], [connectivity in (26, 8)], [True], volume.ndim == 2)[0]


def count_object_and_enclosed(volume: np.ndarray, connectivity: int, background_connectivity: int) -> tuple[int, int]:
    """:func:`count_components` and :func:`count_enclosed` together: the
    object's runs are found once, the background's runs are their gaps, and
    all four half union-finds share the two cores."""
    shape, off, st, en = _runs_of(volume, True)
    gaps = (shape,) + tuple(_gap_runs(off, st, en, shape[2]))
    b0, enclosed = _count_runs(
        [(shape, off, st, en), gaps],
        [connectivity in (26, 8), background_connectivity in (26, 8)],
        [False, True],
        volume.ndim == 2,
    )
    return b0, enclosed
