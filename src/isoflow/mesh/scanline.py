"""The exact scanline: the winding number of every voxel centre of a closed
mesh, by z-columns.

Ties are broken by a fixed rule (see :func:`scanline`): a centre exactly on the
surface behaves as the point ``(x + eta, y + eps, z - delta)`` with
``0 < eps << eta << delta`` infinitesimal, so an axis-aligned box
``[x0, x1] x [y0, y1] x [z0, z1]`` holds exactly the centres with
``x0 <= x < x1, y0 <= y < y1, z0 < z <= z1``.
"""

from __future__ import annotations

import numpy as np

# Number of (triangle, column) pairs handled at once by the scanline, and the
# bytes of temporaries each costs at most (int64 indices, float64 coordinates
# and edge values for the pairs of one chunk).
PAIR_CHUNK = 1 << 20
PAIR_BYTES = 200


def diff_dtype(m: int):
    """Smallest integer type for the difference array: a column's partial sums
    are bounded by the number of triangles."""
    return np.int8 if m < 127 else (np.int16 if m < 32767 else np.int32)


def scan_plan(v, f, origin, pitch, shape):
    """Voxel-centre coordinates and, per triangle, the columns to test.

    Rows: exactly the y_j with ymin <= y_j < ymax (only those can straddle an
    edge under the half-open rule of :func:`scanline`).  Columns: the
    triangle's x-range plus one spare column on each side; farther columns are
    robustly outside (left of the triangle both straddled edges are crossed
    and cancel, right of it neither is), so clipping the range changes no sum.
    Returns ``(xc, yc, zc, T, tri, i0, j0, width, cum)``: centres, corner
    coordinates, the triangles with work, their first column and row, row
    width, and the running total of (triangle, column) pairs.
    """
    nx, ny, nz = shape
    xc = origin[0] + (np.arange(nx) + 0.5) * pitch
    yc = origin[1] + (np.arange(ny) + 0.5) * pitch
    zc = origin[2] + (np.arange(nz) + 0.5) * pitch
    T = v[f]  # (M, 3, 3)
    x, y = T[:, :, 0], T[:, :, 1]
    j0 = np.searchsorted(yc, y.min(axis=1), side="left")
    j1 = np.searchsorted(yc, y.max(axis=1), side="left")
    i0 = np.maximum(np.searchsorted(xc, x.min(axis=1), side="left") - 1, 0)
    i1 = np.minimum(np.searchsorted(xc, x.max(axis=1), side="right") + 1, nx)
    width = np.maximum(i1 - i0, 0)
    count = np.maximum(j1 - j0, 0) * width
    tri = np.nonzero(count)[0]
    cum = np.concatenate([[0], np.cumsum(count[tri])]).astype(np.int64)
    return xc, yc, zc, T, tri, i0, j0, width, cum


def scanline(shape, plan, progress):
    """Winding number of every voxel centre by a z-column scanline.

    For each triangle and each voxel column ``(x_i, y_j)`` under it, the
    triangle's contribution to the column is the 2-D winding number of the
    column point around the triangle's xy-projection (+1 for a counter-
    clockwise projection, i.e. normal z > 0; -1 for clockwise; 0 outside).
    The 3-D winding number of a point is the sum of these over the triangles
    the column crosses *above* it (ray casting along +z); since a column's
    contributions sum to zero, that is minus the sum over those *below* it.
    So each contribution is stored, negated, in a difference array at the
    first voxel of the column whose centre lies strictly above the crossing,
    and a cumulative sum along z yields every centre's winding number.

    Tie rule (why this exact formulation).  The 2-D winding number of the
    column point around a triangle is itself computed by casting a ray along
    +x and counting signed edge crossings, where each *edge* decides alone
    whether it is crossed: with the edge written from its lower endpoint to
    its upper one (a fixed order that depends only on the two endpoint
    coordinates, not on which triangle asks), it is crossed iff
    ``y_lo <= y < y_hi`` and the point is strictly left of it
    (``w = dx*(y - y_lo) - dy*(x - x_lo) > 0``, evaluated with exactly these
    floating-point operations).  Two triangles that share an edge therefore
    get bit-identical answers for it, and since in a closed, consistently
    oriented mesh every edge is traversed once in each direction, the
    contributions of all triangles to a column sum to exactly zero, in
    floating point, whatever the column hits: edges, vertices, vertical walls.
    A column through a shared edge is counted by exactly one of its two
    triangles (the half-open rules act as the symbolic perturbation
    ``(x + eta, y + eps)``, 0 < eps << eta); a column through a vertex by
    exactly one triangle of its fan; a column on a silhouette fold by both
    (+1 and -1 at the same height, cancelling).  Evaluating the edge function
    per triangle in the triangle's own vertex order would give the two
    neighbours rounding errors of different sign, so a column exactly on the
    shared edge could be counted twice or not at all, leaving a spurious
    line of voxels of winding +-1 above it.  A centre exactly at a crossing
    height is not "strictly above" it, which acts as moving the centre down by
    delta >> eta: a box [z0, z1] holds the centres with z0 < z <= z1.
    """
    nx, ny, nz = shape
    xc, yc, zc, T, tri, i0, j0, width, cum = plan
    total = int(cum[-1])
    dtype = diff_dtype(len(T))
    diff = np.zeros(nx * ny * (nz + 1), dtype=dtype)

    # per-triangle edge data, edge k from corner k to corner k+1, stored in
    # the fixed low-to-high (in y) order
    P = T[:, :, :2]
    Pn = P[:, [1, 2, 0], :]
    up = P[:, :, 1] < Pn[:, :, 1]
    lo = np.where(up[:, :, None], P, Pn)
    hi = np.where(up[:, :, None], Pn, P)
    e_lox, e_loy, e_hiy = lo[:, :, 0], lo[:, :, 1], hi[:, :, 1]
    e_dx = hi[:, :, 0] - lo[:, :, 0]
    e_dy = hi[:, :, 1] - lo[:, :, 1]
    e_dir = np.where(up, 1, -1).astype(np.int8)

    # plane of each triangle: z = A.z - (n.x (x - A.x) + n.y (y - A.y)) / n.z
    A = T[:, 0, :]
    n = np.cross(T[:, 1, :] - A, T[:, 2, :] - A)
    zmin, zmax = T[:, :, 2].min(axis=1), T[:, :, 2].max(axis=1)

    nchunks = max(1, -(-total // PAIR_CHUNK))
    for c in range(nchunks):
        s, e = c * PAIR_CHUNK, min(total, (c + 1) * PAIR_CHUNK)
        if e > s:
            gid = np.arange(s, e, dtype=np.int64)
            slot = np.searchsorted(cum, gid, side="right") - 1
            t = tri[slot]
            local = gid - cum[slot]
            w_t = width[t]
            i = i0[t] + local % w_t
            j = j0[t] + local // w_t
            px = xc[i]
            py = yc[j]
            wn = np.zeros(len(t), dtype=np.int8)
            for k in range(3):
                loy = e_loy[t, k]
                crossed = (loy <= py) & (py < e_hiy[t, k])
                w = e_dx[t, k] * (py - loy) - e_dy[t, k] * (px - e_lox[t, k])
                crossed &= w > 0
                wn += np.where(crossed, e_dir[t, k], np.int8(0)).astype(np.int8)
            hit = np.nonzero(wn)[0]
            if len(hit):
                t, i, j, px, py, wn = t[hit], i[hit], j[hit], px[hit], py[hit], wn[hit]
                with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                    z = A[t, 2] - (n[t, 0] * (px - A[t, 0]) + n[t, 1] * (py - A[t, 1])) / n[t, 2]
                # a (nearly) vertical triangle can be hit through rounding only;
                # its crossing lies somewhere on it: clamp to its z-range
                z = np.where(np.isfinite(z), z, 0.5 * (zmin[t] + zmax[t]))
                z = np.clip(z, zmin[t], zmax[t])
                kz = np.searchsorted(zc, z, side="right")  # first centre strictly above
                idx = (i * ny + j) * (nz + 1) + kz
                np.add.at(diff, idx, (-wn).astype(dtype))
        if progress is not None:
            progress(c + 1, nchunks + 1)
    diff = diff.reshape(nx, ny, nz + 1)
    np.cumsum(diff, axis=2, dtype=dtype, out=diff)
    vol = diff[:, :, :nz] != 0
    del diff
    if progress is not None:
        progress(nchunks + 1, nchunks + 1)
    return vol
