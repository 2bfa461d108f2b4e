"""Compiled kernels (numba) for the passes that dominate ``isoflow info``
on large volumes: the configuration histogram and component labelling.

Both stream over the volume without materialising a configuration array or
a label volume:

* :func:`histogram3d` keeps, along every row of the last axis, the 8-bit
  configuration of the current vertex and shifts in one nibble (the four
  voxels of the next layer) per step: four reads per vertex, one pass.
* :func:`join_runs` is a run-based union-find: runs of equal voxels along
  the last axis are the nodes, runs in neighbouring rows that touch (under
  6-, 18- or 26-adjacency, 4 or 8 in 2D) are joined. The background's runs
  are the gaps between the object's (:func:`gap_runs`), so the volume is read
  once for both; one extra node stands for the region outside the array.
  Memory is three int32 per run (about one byte per voxel on real data)
  instead of a 4-byte label per voxel, and the parents, flattened, are the
  labels that :mod:`isoflow.scale.sweep` reads.

Every pass splits the volume into slabs along the first axis, one per
thread (:mod:`isoflow.scale.compiled`); the union-find joins the seams
between slabs afterwards. They give the same numbers as
:func:`isoflow.digital.configurations.configurations` and scipy (the tests
check it). The numpy/scipy paths stay in use for small volumes, where
loading numba would cost more than it saves; compiled code is cached on
disk after the first run.
"""

from __future__ import annotations

import numpy as np

from .compiled import read_only_view, run, slabs, thread_count
from .memory import check_fits

#: bytes per run held by the union-find: start, end and parent (int32)
RUN_BYTES = 12

try:  # numba is a dependency, but keep isoflow importable without it
    from .jit import njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    HAVE_NUMBA = False


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
    def find(parent, a):
        """The root of node a in a union-find's parent array (path halving).

        Indices are cast to unsigned: numba then skips the test for a
        negative index (counted from the end) on every step of the chain."""
        a = np.uint64(a)
        while np.uint64(parent[a]) != a:
            parent[a] = parent[np.uint64(parent[a])]
            a = np.uint64(parent[a])
        return np.int64(a)

    @njit(cache=True, nogil=True)
    def _join_rows(parent, start, end, a0, a1, b0, b1, slack):
        """Union runs of row A [a0, a1) with touching runs of row B [b0, b1).

        Runs touch when their intervals overlap (slack 0) or overlap once
        widened by one voxel (slack 1: diagonal neighbours)."""
        ia, ib = a0, b0
        while ia < a1 and ib < b1:
            if start[ia] < end[ib] + slack and start[ib] < end[ia] + slack:
                ra, rb = find(parent, ia), find(parent, ib)
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
    def _join_range(shape, offsets, start, end, slack, diagonal, parent, i0, i1, seam):
        """Join the runs of rows i0 <= i < i1 with their earlier neighbour
        rows: (i, j-1) and (i-1, j) with ``slack`` (0: face contact only,
        1: also edge contact across the row), and when ``diagonal >= 0`` the
        rows (i-1, j-1), (i-1, j+1) with slack ``diagonal`` (0: edge
        contact, 1: also vertex contact). 6-adjacency is (0, -1), 18 is
        (1, 0), 26 is (1, 1). Rows i0-1 are left out unless ``seam``, so that
        slabs can run at once on disjoint parts of ``parent``; ``seam`` joins
        only row i0 to row i0-1."""
        nx, ny, nz = shape
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
                    if diagonal >= 0:
                        if j >= 1:
                            r = (i - 1) * ny + j - 1
                            _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], diagonal)
                        if j + 1 < ny:
                            r = (i - 1) * ny + j + 1
                            _join_rows(parent, start, end, a0, a1, offsets[r], offsets[r + 1], diagonal)

    @njit(cache=True, nogil=True)
    def _join_outside(shape, offsets, start, end, parent, outside, planar):
        """Join every run on the array's border with the node ``outside``:
        the region outside the array is background and touches them all."""
        nx, ny, nz = shape
        for i in range(nx):
            for j in range(ny):
                a0, a1 = offsets[i * ny + j], offsets[i * ny + j + 1]
                if a0 == a1:
                    continue
                if j == 0 or j == ny - 1 or (not planar and (i == 0 or i == nx - 1)):
                    for r in range(a0, a1):
                        union(parent, r, outside)
                else:
                    # inside rows only their first and last runs can reach
                    # the ends of the row
                    if start[a0] == 0:
                        union(parent, a0, outside)
                    if end[a1 - 1] == nz:
                        union(parent, a1 - 1, outside)

    @njit(cache=True, nogil=True, inline="always")
    def union(parent, a, b):
        """Join the sets of nodes a and b: the larger root is hung in the
        other set (under a node of it, whose root is smaller), so that every
        root is the smallest node of its set and ``parent[x] <= x`` always.

        Rem's algorithm with splicing (Patwary, Blair and Manne, *Experiments
        on union-find algorithms for the disjoint-set data structure*, 2010):
        the two paths are climbed together, always from the node whose
        parent is larger, which is hung under the other's parent on the way
        (so parents only decrease). It stops as soon as both reach a common
        parent, which is most of the sweep's unions: half of them join
        nodes of one set already, and those rarely climb to the root. The
        sweep of a porous 512^3 field takes 3-4% less time than with two
        finds by path halving."""
        x, y = np.uint64(a), np.uint64(b)
        px, py = parent[x], parent[y]
        while px != py:
            if px < py:
                if np.uint64(py) == y:  # y is a root: hang it under px
                    parent[y] = px
                    return
                parent[y] = px
                y = np.uint64(py)
                py = parent[y]
            else:
                if np.uint64(px) == x:
                    parent[x] = py
                    return
                parent[x] = py
                x = np.uint64(px)
                px = parent[x]

    @njit(cache=True, nogil=True)
    def _join_pairs(parent, pairs):
        for p in range(len(pairs)):
            union(parent, pairs[p, 0], pairs[p, 1])

    @njit(cache=True, nogil=True)
    def _flatten(parent):
        """Point every node at its root. Unions always hang the larger root
        under the smaller, so ``parent[r] <= r`` and one pass in index order
        suffices. Returns the number of roots."""
        roots = 0
        for r in range(len(parent)):
            p = parent[r]
            if p == r:
                roots += 1
            else:
                parent[r] = parent[p]
        return roots

    @njit(cache=True, nogil=True)
    def _paint_gaps(v, goff, gstart, gend, parent, outside, r0, r1):
        """Set every gap of rows [r0, r1) whose component is not the one
        outside the array (rows in C order over the first two axes)."""
        ny = v.shape[1]
        for r in range(r0, r1):
            i, j = r // ny, r % ny
            for g in range(goff[r], goff[r + 1]):
                if parent[g] != outside:
                    v[i, j, gstart[g]:gend[g]] = 1

    @njit(cache=True, nogil=True)
    def _label_polygons(polygons, nv):
        """Vertex labels 0..n-1 of the connected components of a polygon
        mesh (rows of vertex ids, -1 for an empty slot), numbered in order
        of their smallest vertex."""
        parent = np.arange(nv).astype(polygons.dtype)
        for f in range(polygons.shape[0]):
            a = find(parent, polygons[f, 0])
            for t in range(1, polygons.shape[1]):
                if polygons[f, t] >= 0:
                    b = find(parent, polygons[f, t])
                    if a != b:
                        parent[b] = a
        label = np.full(nv, -1, dtype=np.int32)
        count = 0
        for i in range(nv):
            r = find(parent, i)
            if label[r] < 0:
                label[r] = count
                count += 1
            label[i] = label[r]
        return label, count


def label_polygons(polygons: np.ndarray, nv: int) -> tuple[np.ndarray, int]:
    """``(labels, count)``: connected components of a mesh's ``nv`` vertices
    joined by its polygons (same partition as scipy's ``connected_components``
    on the face graph; 4 bytes per vertex instead of a sparse matrix)."""
    # int32 below 2^31 vertices whichever type the mesh holds: one compile
    return _label_polygons(np.ascontiguousarray(polygons, dtype=np.int32 if nv < 1 << 31 else np.int64), nv)


def volume_view(volume: np.ndarray) -> np.ndarray:
    """A C-contiguous uint8 view of a 2D or 3D volume; 2D gets a dummy first axis."""
    v = np.ascontiguousarray(volume, dtype=bool)
    return (v.reshape((1,) + v.shape) if v.ndim == 2 else v).view(np.uint8)


def histogram3d(volume: np.ndarray) -> np.ndarray:
    """The 256 configuration counts of a 3D volume (same as
    ``np.bincount(configurations(volume).ravel(), minlength=256)``)."""
    v = read_only_view(volume_view(volume))  # one compile, whether or not the volume is writeable
    parts = slabs(v.shape[0] + 1, thread_count(v.size))
    hists = [np.zeros(256, np.int64) for _ in parts]  # one per thread
    run([(_hist_rows, v, a, b, h) for (a, b), h in zip(parts, hists)])
    return np.sum(hists, axis=0)


def object_runs(v: np.ndarray):
    """Runs of True along the last axis of a 3D uint8 array: row offsets
    (int64, one more than rows), starts and ends (int32); runs numbered row
    by row in C order."""
    v = read_only_view(v)  # one compile, whether or not the volume is writeable
    counts = np.zeros(v.shape[0] * v.shape[1] + 1, dtype=np.int64)
    parts = slabs(v.shape[0], thread_count(v.size))
    run([(_count_runs_rows, v, counts, a, b) for a, b in parts])
    offsets = np.cumsum(counts)
    nruns, rows = int(offsets[-1]), len(counts)
    # refuse up front what will not fit: the runs, their gaps (at most one
    # more per row), a parent for each and the row offsets of both
    check_fits(
        RUN_BYTES * (2 * nruns + rows) + 16 * rows,
        f"labelling the {nruns:,} runs of a {'x'.join(map(str, v.shape))} volume",
        hint="store it as .zarr and run isoflow info on that (block by block)",
    )
    start = np.empty(nruns, dtype=np.int32)
    end = np.empty(nruns, dtype=np.int32)
    run([(_fill_runs_rows, v, offsets, start, end, a, b) for a, b in parts])
    return offsets, start, end


def gap_runs(offsets, start, end, nz: int):
    """The background runs of every row: the gaps between the object's runs,
    so the volume is not read a second time."""
    nrows = len(offsets) - 1
    counts = np.zeros(nrows + 1, dtype=np.int64)
    parts = slabs(nrows, thread_count(nrows * nz))
    run([(_count_gaps_rows, offsets, start, end, nz, counts, a, b) for a, b in parts])
    goff = np.cumsum(counts)
    gstart = np.empty(goff[-1], dtype=np.int32)
    gend = np.empty(goff[-1], dtype=np.int32)
    run([(_fill_gaps_rows, offsets, start, end, nz, goff, gstart, gend, a, b) for a, b in parts])
    return goff, gstart, gend


#: adjacency -> (slack between neighbour rows, slack between diagonal rows
#: or -1 for none); see ``_join_range``. 4 and 8 are the planar ones.
ADJACENCY = {6: (0, -1), 18: (1, 0), 26: (1, 1), 4: (0, -1), 8: (1, -1)}


def join_runs(runs_list, adjacencies, outside, planar: bool = False) -> list[tuple[np.ndarray, int]]:
    """Union-find over one or more run sets ``(shape, offsets, start, end)``:
    for each, the parent array, every node pointing at its root, and the
    number of components.

    Each run set is joined in slabs along the first axis at once (slabs
    touch disjoint parts of the parent array, so they need no lock), then
    along the seams between slabs; the compiled passes release the GIL. A
    run set with ``outside`` true gets one more node, the last, standing for
    the region outside the array, joined with every run on the border
    (``planar``: a 2D image with a dummy first axis, whose ends are not a
    border)."""
    calls, seams, parents = [], [], []
    threads = thread_count(max(int(np.prod(shape)) for shape, *_ in runs_list))
    for (shape, off, st, en), adjacency, out in zip(runs_list, adjacencies, outside):
        slack, diagonal = ADJACENCY[adjacency]
        parent = np.arange(len(st) + (1 if out else 0), dtype=np.int32)
        parents.append(parent)
        parts = slabs(shape[0], threads)
        calls += [(_join_range, shape, off, st, en, slack, diagonal, parent, a, b, False) for a, b in parts]
        seams.append([(shape, off, st, en, slack, diagonal, parent, a, a + 1, True) for a, _ in parts[1:]])
    run(calls)
    out_list = []
    for (shape, off, st, en), parent, out, seam in zip(runs_list, parents, outside, seams):
        for args in seam:
            _join_range(*args)
        if out:
            _join_outside(shape, off, st, en, parent, len(st), planar)
        out_list.append((parent, int(_flatten(parent))))
    return out_list


def join_pairs(parent: np.ndarray, pairs: np.ndarray) -> int:
    """Join the node pairs ``(n, 2)`` in a parent array (pinches found by the
    vertex sweep); returns the number of components after."""
    _join_pairs(parent, np.ascontiguousarray(pairs, dtype=np.int64))
    return int(_flatten(parent))


def count_components(volume: np.ndarray, connectivity: int) -> int:
    """Number of components of the True voxels (6/18/26 in 3D, 4/8 in 2D)."""
    v = volume_view(volume)
    runs = (v.shape, *object_runs(v))
    return join_runs([runs], [connectivity], [False], volume.ndim == 2)[0][1]


def count_enclosed(volume: np.ndarray, connectivity: int) -> int:
    """Background components (with ``connectivity``) not touching the border."""
    return count_object_and_enclosed(volume, None, connectivity)[1]


def count_object_and_enclosed(volume: np.ndarray, connectivity, background_connectivity: int) -> tuple[int, int]:
    """:func:`count_components` and :func:`count_enclosed` together: the
    object's runs are found once, the background's runs are their gaps, and
    all the slabs of both union-finds share the threads. The enclosed
    background components are all but the one holding the outside node.
    ``connectivity`` None skips the object's count (returned as None)."""
    v = volume_view(volume)
    off, st, en = object_runs(v)
    gaps = (v.shape, *gap_runs(off, st, en, v.shape[2]))
    sets, adj, out = [gaps], [background_connectivity], [True]
    if connectivity is not None:
        sets, adj, out = [(v.shape, off, st, en), gaps], [connectivity, background_connectivity], [False, True]
    joined = join_runs(sets, adj, out, volume.ndim == 2)
    b0 = joined[0][1] if connectivity is not None else None
    return b0, joined[-1][1] - 1


def fill_enclosed(volume: np.ndarray, inplace: bool = False) -> np.ndarray:
    """The volume with every background voxel that no 6-path of background
    voxels joins to the outside of the array set: the object's holes
    filled, as ``scipy.ndimage.binary_fill_holes`` fills them with its
    default structure (6-adjacency in 3D), without a label volume.

    Parameters
    ----------
    volume : bool ndarray (3D)
    inplace : bool
        Fill ``volume`` itself (C-contiguous) instead of a copy.

    Returns
    -------
    bool ndarray
        The filled volume.

    Examples
    --------
    >>> v = np.ones((3, 3, 3), dtype=bool); v[1, 1, 1] = False
    >>> int(fill_enclosed(v).sum())
    27
    """
    v = volume_view(volume)
    if not (inplace and np.shares_memory(v, volume)):
        v = v.copy()
    off, st, en = object_runs(v)
    goff, gst, gen = gap_runs(off, st, en, v.shape[2])
    ((parent, _),) = join_runs([(v.shape, goff, gst, gen)], [6], [True])
    rows = v.shape[0] * v.shape[1]
    parts = slabs(rows, thread_count(v.size))
    run([(_paint_gaps, v, goff, gst, gen, parent, parent[len(gst)], a, b) for a, b in parts])
    return v.view(bool).reshape(volume.shape)
