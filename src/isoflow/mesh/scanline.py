"""The exact scanline: the winding number of every voxel centre of a closed
triangle chain, by z-columns.

For each triangle and each voxel column ``(x_i, y_j)`` under it, the
triangle's contribution to the column is the 2-D winding number of the
column point around the triangle's xy-projection (+1 for a counter-clockwise
projection, i.e. normal z > 0; -1 for clockwise; 0 outside).  The 3-D
winding number of a point is the sum of these over the triangles the column
crosses *above* it (ray casting along +z); since a column's contributions
sum to zero, that is minus the sum over those *below* it.  So each
contribution is kept, negated, as a crossing at the first voxel of the
column whose centre lies strictly above it, and a running sum up the column
yields every centre's winding number.

Tie rule (why this exact formulation).  The 2-D winding number of the column
point around a triangle is itself computed by casting a ray along +x and
counting signed edge crossings, where each *edge* decides alone whether it
is crossed: with the edge written from its lower endpoint to its upper one
(a fixed order that depends only on the two endpoint coordinates, not on
which triangle asks), it is crossed iff ``y_lo <= y < y_hi`` and the point is
strictly left of it (``w = dx*(y - y_lo) - dy*(x - x_lo) > 0``, evaluated
with exactly these floating-point operations).  Two triangles that share an
edge therefore get bit-identical answers for it, and since in a closed,
consistently oriented chain every edge is traversed once in each direction,
the contributions of all triangles to a column sum to exactly zero, in
floating point, whatever the column hits: edges, vertices, vertical walls.
A column through a shared edge is counted by exactly one of its two
triangles (the half-open rules act as the symbolic perturbation
``(x + eta, y + eps)``, 0 < eps << eta); a column through a vertex by
exactly one triangle of its fan; a column on a silhouette fold by both (+1
and -1 at the same height, cancelling).  Evaluating the edge function per
triangle in the triangle's own vertex order would give the two neighbours
rounding errors of different sign, so a column exactly on the shared edge
could be counted twice or not at all, leaving a spurious line of voxels of
winding +-1 above it.  A centre exactly at a crossing height is not
"strictly above" it, which acts as moving the centre down by delta >> eta.
So a centre exactly on the surface behaves as the point
``(x + eta, y + eps, z - delta)``, and an axis-aligned box
``[x0, x1] x [y0, y1] x [z0, z1]`` holds exactly the centres with
``x0 <= x < x1, y0 <= y < y1, z0 < z <= z1``.

The work is split in compiled passes (numba, no Python per triangle or per
voxel): every (triangle, column) pair is tested and the crossings are kept
as a sparse list (column, first centre above, -+1); the list is grouped by
column; each column is swept once upward with a running sum, writing the
volume directly.  Memory is the boolean volume plus the crossings (a few
bytes each): no integer volume is held.  Any range of the first axis (a
*slab*) can be filled on its own, which is how volumes beyond memory are
written (:mod:`isoflow.mesh.slabs`) and how two threads share the work.
These are the arithmetic and the tie rule of the earlier numpy scanline,
operation for operation: its volumes are reproduced bit for bit.
"""

from __future__ import annotations

import numpy as np

from ..scale.cancel import STOP, Stopped, run_pieces
from ..scale.jit import njit


class ScanGrid:
    """The per-triangle data of the scanline, computed once (O(triangles)).

    ``T`` is the (M, 3, 3) array of triangle corners in the scaled frame,
    ``origin``, ``pitch`` and ``shape`` the grid in that frame.  Everything a
    slab needs is here; a ScanGrid is small enough to ship to dask workers.
    ``start`` makes it the block of a larger grid whose voxel ``start`` is
    this one's voxel 0: its centres are that grid's, bit for bit
    (``origin + (start + i + 0.5) * pitch``, not rounded twice).
    """

    def __init__(self, T: np.ndarray, origin, pitch: float, shape, start=(0, 0, 0)):
        nx, ny, nz = (int(n) for n in shape)
        self.shape = (nx, ny, nz)
        sx, sy, sz = (int(s) for s in start)
        self.xc = origin[0] + (np.arange(sx, sx + nx) + 0.5) * pitch
        self.yc = origin[1] + (np.arange(sy, sy + ny) + 0.5) * pitch
        self.zc = origin[2] + (np.arange(sz, sz + nz) + 0.5) * pitch
        m = len(T)
        T = np.ascontiguousarray(T, dtype=np.float64)
        self.j0, self.j1, self.i0, self.i1 = (np.empty(m, dtype=np.int64) for _ in range(4))
        self.e_lox, self.e_loy, self.e_hiy, self.e_dx, self.e_dy = (np.empty((m, 3)) for _ in range(5))
        self.e_dir = np.empty((m, 3), dtype=np.int8)
        self.A = np.ascontiguousarray(T[:, 0, :])
        self.n = np.empty((m, 3))
        self.zmin, self.zmax = np.empty(m), np.empty(m)
        _set_up(T, self.xc, self.yc, self.j0, self.j1, self.i0, self.i1, self.e_lox, self.e_loy, self.e_hiy,
                self.e_dx, self.e_dy, self.e_dir, self.n, self.zmin, self.zmax)

    def pairs(self, xa: int = 0, xb: int | None = None) -> int:
        """Number of (triangle, column) pairs tested for the slab [xa, xb)."""
        xb = self.shape[0] if xb is None else xb
        w = np.maximum(np.minimum(self.i1, xb) - np.maximum(self.i0, xa), 0)
        return int((w * np.maximum(self.j1 - self.j0, 0)).sum())

    def crossings(self, xa: int, xb: int):
        """The crossings of the columns of slab [xa, xb), grouped by column.

        Returns ``(start, kz, val)``: the crossings of local column
        ``c = (i - xa) * ny + j`` are ``kz[start[c]:start[c+1]]`` (index of
        the first centre strictly above the crossing, nz if none) with values
        ``val`` (minus the triangle's 2-D winding number around the column).
        """
        nx, ny, nz = self.shape
        lo = np.maximum(self.i0, xa)
        hi = np.minimum(self.i1, xb)
        tri = np.nonzero((hi > lo) & (self.j1 > self.j0))[0]
        counts = np.zeros(len(tri) + 1, dtype=np.int64)
        args = (tri, lo, hi, self.j0, self.j1, self.xc, self.yc, self.e_lox, self.e_loy,
                self.e_hiy, self.e_dx, self.e_dy, self.e_dir, STOP)
        _count_hits(*args, counts)
        if STOP[0]:  # the counts are unfinished: no list to build from them
            raise Stopped
        offsets = np.cumsum(counts)
        offsets[1:] = offsets[:-1].copy()
        offsets[0] = 0
        total = int(counts.sum())
        col = np.empty(total, dtype=np.int64)
        kz = np.empty(total, dtype=np.int32)
        val = np.empty(total, dtype=np.int8)
        _write_hits(*args, offsets, self.zc, self.A, self.n, self.zmin, self.zmax, xa, ny,
                    col, kz, val)
        if STOP[0]:
            raise Stopped
        ncol = (xb - xa) * ny
        start = np.zeros(ncol + 1, dtype=np.int64)
        skz = np.empty(total, dtype=np.int32)
        sval = np.empty(total, dtype=np.int8)
        _group_by_column(col, kz, val, start, skz, sval)
        return start, skz, sval


# ---------------------------------------------------------------------------
# compiled passes
# ---------------------------------------------------------------------------

@njit(cache=True, nogil=True)
def first_at_least(a, x, strict):
    """``np.searchsorted(a, x, side="right" if strict else "left")``."""
    lo, hi = 0, len(a)
    while lo < hi:
        mid = (lo + hi) // 2
        if a[mid] < x or (strict and a[mid] == x):
            lo = mid + 1
        else:
            hi = mid
    return lo


@njit(cache=True, nogil=True, inline="always")
def _first_at_least_even(a, x, strict, per_unit):
    """:func:`first_at_least` of evenly spaced ``a`` (``per_unit`` entries
    per unit): guessed from the spacing, then settled by comparing with
    ``a`` itself (so exact however its entries round)."""
    n = len(a)
    if not x > a[0]:
        return 1 if strict and x == a[0] else 0
    if not x < a[n - 1]:
        return n if strict or x > a[n - 1] else n - 1
    c = min(max(int((x - a[0]) * per_unit) + 1, 1), n - 1)
    while c > 0 and not (a[c - 1] < x or (strict and a[c - 1] == x)):
        c -= 1
    while c < n and (a[c] < x or (strict and a[c] == x)):
        c += 1
    return c


@njit(cache=True, nogil=True)
def _set_up(T, xc, yc, j0, j1, i0, i1, e_lox, e_loy, e_hiy, e_dx, e_dy, e_dir, n, zmin, zmax):
    """The per-triangle data of :class:`ScanGrid`, one triangle at a time.

    Rows: exactly the y_j with ymin <= y_j < ymax (only those can straddle
    an edge under the half-open rule).  Columns: the triangle's x-range plus
    one spare column on each side; farther columns are robustly outside
    (left of the triangle both straddled edges are crossed and cancel, right
    of it neither is).  Edge k runs from corner k to corner k+1, stored
    low-to-high in y so that two triangles sharing an edge evaluate it bit
    for bit alike.  The plane of each triangle is
    ``z = A.z - (n.x (x - A.x) + n.y (y - A.y)) / n.z`` with ``n`` the cross
    product of its edges from corner 0, in NumPy's order of operations."""
    nx = len(xc)
    gx = (nx - 1) / (xc[nx - 1] - xc[0]) if nx > 1 else 0.0  # centres per unit: where a search starts
    gy = (len(yc) - 1) / (yc[len(yc) - 1] - yc[0]) if len(yc) > 1 else 0.0
    for t in range(T.shape[0]):
        xmin = min(T[t, 0, 0], T[t, 1, 0], T[t, 2, 0])
        xmax = max(T[t, 0, 0], T[t, 1, 0], T[t, 2, 0])
        ymin = min(T[t, 0, 1], T[t, 1, 1], T[t, 2, 1])
        ymax = max(T[t, 0, 1], T[t, 1, 1], T[t, 2, 1])
        j0[t] = _first_at_least_even(yc, ymin, False, gy)
        j1[t] = _first_at_least_even(yc, ymax, False, gy)
        i0[t] = max(_first_at_least_even(xc, xmin, False, gx) - 1, 0)
        i1[t] = min(_first_at_least_even(xc, xmax, True, gx) + 1, nx)
        for k in range(3):
            kn = (k + 1) % 3
            up = T[t, k, 1] < T[t, kn, 1]
            a, b = (k, kn) if up else (kn, k)
            e_lox[t, k] = T[t, a, 0]
            e_loy[t, k] = T[t, a, 1]
            e_hiy[t, k] = T[t, b, 1]
            e_dx[t, k] = T[t, b, 0] - T[t, a, 0]
            e_dy[t, k] = T[t, b, 1] - T[t, a, 1]
            e_dir[t, k] = 1 if up else -1
        a0, a1, a2 = T[t, 1, 0] - T[t, 0, 0], T[t, 1, 1] - T[t, 0, 1], T[t, 1, 2] - T[t, 0, 2]
        b0, b1, b2 = T[t, 2, 0] - T[t, 0, 0], T[t, 2, 1] - T[t, 0, 1], T[t, 2, 2] - T[t, 0, 2]
        n[t, 0] = a1 * b2 - a2 * b1
        n[t, 1] = a2 * b0 - a0 * b2
        n[t, 2] = a0 * b1 - a1 * b0
        zmin[t] = min(T[t, 0, 2], T[t, 1, 2], T[t, 2, 2])
        zmax[t] = max(T[t, 0, 2], T[t, 1, 2], T[t, 2, 2])


@njit(cache=True, nogil=True)
def _winding_2d(t, px, py, e_lox, e_loy, e_hiy, e_dx, e_dy, e_dir):
    """2-D winding number of the column point around triangle t's projection:
    signed crossings of the ray along +x, each edge deciding alone (exactly
    these floating-point operations, so shared edges agree bit for bit)."""
    wn = 0
    for k in range(3):
        loy = e_loy[t, k]
        if loy <= py and py < e_hiy[t, k]:
            w = e_dx[t, k] * (py - loy) - e_dy[t, k] * (px - e_lox[t, k])
            if w > 0:
                wn += e_dir[t, k]
    return wn


@njit(cache=True, nogil=True)
def _count_hits(tri, lo, hi, j0, j1, xc, yc, e_lox, e_loy, e_hiy, e_dx, e_dy, e_dir, stop, counts):
    for q in range(len(tri)):
        if stop[0]:
            return
        t = tri[q]
        c = 0
        for i in range(lo[t], hi[t]):
            px = xc[i]
            for j in range(j0[t], j1[t]):
                if _winding_2d(t, px, yc[j], e_lox, e_loy, e_hiy, e_dx, e_dy, e_dir) != 0:
                    c += 1
        counts[q] = c


@njit(cache=True, nogil=True, error_model="numpy")
def _write_hits(tri, lo, hi, j0, j1, xc, yc, e_lox, e_loy, e_hiy, e_dx, e_dy, e_dir, stop, offsets,
                zc, A, n, zmin, zmax, xa, ny, col, kz, val):
    for q in range(len(tri)):
        if stop[0]:
            return
        t = tri[q]
        o = offsets[q]
        for i in range(lo[t], hi[t]):
            px = xc[i]
            for j in range(j0[t], j1[t]):
                py = yc[j]
                wn = _winding_2d(t, px, py, e_lox, e_loy, e_hiy, e_dx, e_dy, e_dir)
                if wn != 0:
                    z = A[t, 2] - (n[t, 0] * (px - A[t, 0]) + n[t, 1] * (py - A[t, 1])) / n[t, 2]
                    # a (nearly) vertical triangle can be hit through rounding
                    # only; its crossing lies somewhere on it: clamp to its z-range
                    if not np.isfinite(z):
                        z = 0.5 * (zmin[t] + zmax[t])
                    z = min(max(z, zmin[t]), zmax[t])
                    col[o] = (i - xa) * ny + j
                    kz[o] = np.searchsorted(zc, z, side="right")  # first centre strictly above
                    val[o] = -wn
                    o += 1


@njit(cache=True, nogil=True)
def _group_by_column(col, kz, val, start, skz, sval):
    """Counting sort of the crossings by column; within a column by kz."""
    ncol = len(start) - 1
    for e in range(len(col)):
        start[col[e] + 1] += 1
    for c in range(ncol):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    for e in range(len(col)):
        c = col[e]
        skz[fill[c]] = kz[e]
        sval[fill[c]] = val[e]
        fill[c] += 1
    for c in range(ncol):  # insertion sort: a column has a handful of crossings
        for a in range(start[c] + 1, start[c + 1]):
            k, v = skz[a], sval[a]
            b = a - 1
            while b >= start[c] and skz[b] > k:
                skz[b + 1] = skz[b]
                sval[b + 1] = sval[b]
                b -= 1
            skz[b + 1] = k
            sval[b + 1] = v


@njit(cache=True, nogil=True)
def _sweep(vol, start, kz, val, r0, r1, rule, rbox, stats, stop):
    """Fill local rows r0 <= i < r1 of ``vol`` (slab-local first index).

    Each column is swept upward with the running winding number W (the sum
    of the values of the crossings below each centre).  A voxel is in iff
    ``W != R`` where R is 0, or ``rule[...]`` inside the box
    ``rbox = (i0, i1, j0, j1, k0, k1)`` (slab-local).  Codes 127 / -128 in
    ``rule`` force a voxel in / out.  ``stats`` counts voxels with
    ``|W - R| >= 2``, with ``W - R`` positive and negative, and those forced
    in (so the last three add up to the voxels in).  ``vol`` must
    be all False: only voxels inside are written (pages of a fresh
    ``np.zeros`` array that stay outside are never touched).
    """
    ny, nz = vol.shape[1], vol.shape[2]
    bi0, bi1, bj0, bj1, bk0, bk1 = rbox[0], rbox[1], rbox[2], rbox[3], rbox[4], rbox[5]
    over = 0
    pos_n = 0
    neg_n = 0
    forced = 0
    for i in range(r0, r1):
        if stop[0]:
            break
        for j in range(ny):
            c = i * ny + j
            a, b = start[c], start[c + 1]
            ruled = bi0 <= i and i < bi1 and bj0 <= j and j < bj1
            s = 0
            pos = 0
            for e in range(a, b + 1):
                top = nz if e == b else min(kz[e], nz)
                if top > pos:
                    if ruled and pos < bk1 and top > bk0:
                        for k in range(pos, top):
                            r = 0
                            if bk0 <= k and k < bk1:
                                r = rule[i - bi0, j - bj0, k - bk0]
                            if r == 127:
                                vol[i, j, k] = True
                                forced += 1
                            elif r != -128:
                                d = s - r
                                if d != 0:
                                    vol[i, j, k] = True
                                if d >= 2 or d <= -2:
                                    over += 1
                                if d > 0:
                                    pos_n += 1
                                elif d < 0:
                                    neg_n += 1
                    elif s != 0:  # the volume is zero: only runs inside are written
                        vol[i, j, pos:top] = True
                        n = top - pos
                        if s >= 2 or s <= -2:
                            over += n
                        if s > 0:
                            pos_n += n
                        else:
                            neg_n += n
                    pos = top
                if e < b:
                    s += val[e]
    stats[0] += over
    stats[1] += pos_n
    stats[2] += neg_n
    stats[3] += forced


# ---------------------------------------------------------------------------
# entry point
# ---------------------------------------------------------------------------

def fill_slab(grid: ScanGrid, xa: int, xb: int, rule=None, out=None, stats=None, threads: int = 1):
    """The volume of slab [xa, xb) of ``grid``: voxel in iff ``W != R``.

    ``rule`` is None (R = 0: the nonzero rule of a closed chain) or
    ``(array, (i0, j0, k0))``: R on a box of the grid, in grid coordinates
    (see :func:`_sweep` for the codes).  ``out`` is an optional boolean
    array of shape (xb - xa, ny, nz), all False, to fill.  ``stats`` (int64 (4,)) is
    incremented with the counts of :func:`_sweep`.  With ``threads=2`` the
    slab is split in two halves filled at once (compiled code runs without
    the GIL).
    """
    nx, ny, nz = grid.shape
    if out is None:
        out = np.zeros((xb - xa, ny, nz), dtype=bool)
    if stats is None:
        stats = np.zeros(4, dtype=np.int64)
    if rule is None:
        rarr, rbox = np.zeros((1, 1, 1), dtype=np.int8), np.zeros(6, dtype=np.int64)
    else:
        rarr, (ri, rj, rk) = rule
        # the rule box in slab-local coordinates (may be empty or clipped)
        rbox = np.array([ri - xa, ri - xa + rarr.shape[0], rj, rj + rarr.shape[1],
                         rk, rk + rarr.shape[2]], dtype=np.int64)
    halves = [(xa, xb)] if threads <= 1 or xb - xa < 2 else [(xa, (xa + xb) // 2), ((xa + xb) // 2, xb)]

    def run(a, b):
        start, kz, val = grid.crossings(a, b)
        st = np.zeros(4, dtype=np.int64)
        shift = np.array([a - xa, a - xa, 0, 0, 0, 0], dtype=np.int64)  # to this half's rows
        _sweep(out[a - xa:b - xa], start, kz, val, 0, b - a, rarr, rbox - shift, st, STOP)
        parts[(a, b)] = st

    parts: dict = {}
    run_pieces(lambda n: run(*halves[n]), len(halves), threads=threads)
    for st in parts.values():
        stats += st
    return out

