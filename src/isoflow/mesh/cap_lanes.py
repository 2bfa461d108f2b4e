"""The block model of :func:`isoflow.mesh.captree.evaluate` for a cap of
few triangles, over all of them at once in SIMD lanes instead of through
the tree.

A soup's triangles are as large as the domain: no node of the cap's tree
is ever far from a block, every evaluation opens every leaf, and the tree
only adds its walk and the scalar arithmetic of one triangle (one chain
edge) at a time.  Here the same quantities are computed triangle by
triangle and edge by edge in lanes, with the same classification:

* triangles whose plane passes within ``reach`` of the block's centre q
  are measured in lanes (as :func:`~isoflow.mesh.captree.dist_triangle`
  and :func:`~isoflow.mesh.captree.near_kind` do): *near* ones are left for the
  caller to sum at each centre, *crossing* ones are listed;
* the far part's winding number at q is the sum of the other triangles'
  solid angles, and its gradient the Biot-Savart field of their chain
  edges plus the near triangles' cut edges
  (:func:`~isoflow.mesh.captree.cut_edges`), with the same bound on its
  derivative (:func:`~isoflow.mesh.captree.edge_terms`, written here with
  selects instead of branches).

No expansion is used, so there is no remainder (``err = var = 0``): the
model is that of :func:`~isoflow.mesh.captree.evaluate` with ``theta =
0``, its sums taken in another order (rounding far inside
:data:`~isoflow.mesh.block_lanes.TIE_WINDING`).
"""

from __future__ import annotations

import math

import numpy as np

from ..scale.jit import njit
from .captree import CLEAR, CROSSING, FAR, GRAD_SIGN, HIT, NEAR, CapTree, cut_edges
from .solid_angles import half_angle

#: caps of at most this many triangles are evaluated in lanes, larger ones through the tree
FLAT_MAX = 2048


def lanes_arrays(tree: CapTree) -> tuple:
    """The cap's triangles and chain edges laid out for lanes: ``C`` (9, K)
    the triangles' corners coordinate by coordinate, ``D`` (6, E) the chain
    edges' ends (as the cap's boundary runs: from the chain's head to its
    tail), ``eo`` (E,) the triangle holding each edge (in tree order)."""
    K = len(tree.T)
    C = np.ascontiguousarray(tree.T.reshape(K, 9).T)
    D = np.ascontiguousarray(tree.E[:, ::-1].reshape(-1, 6).T)
    eo = np.repeat(np.arange(K, dtype=np.int64), np.diff(tree.owner))
    return C, D, eo


@njit(cache=True, nogil=True, error_model="numpy")
def _angles(C, nlen, px, py, pz, ang, det):
    """Each triangle's ``atan2(det, den)`` at p and its ``det``, in lanes."""
    for t in range(C.shape[1]):
        ax, ay, az = C[0, t] - px, C[1, t] - py, C[2, t] - pz
        bx, by, bz = C[3, t] - px, C[4, t] - py, C[5, t] - pz
        cx, cy, cz = C[6, t] - px, C[7, t] - py, C[8, t] - pz
        ang[t], det[t] = half_angle(ax, ay, az, bx, by, bz, cx, cy, cz)


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _segment(ax, ay, az, bx, by, bz):
    """Distance from the origin to the segment a-b
    (:func:`~isoflow.mesh.captree.dist_segment` with selects for branches)."""
    ex, ey, ez = bx - ax, by - ay, bz - az
    wx, wy, wz = -ax, -ay, -az
    ee = ex * ex + ey * ey + ez * ez
    s = min(max((wx * ex + wy * ey + wz * ez) / (ee if ee != 0 else 1.0), 0.0), 1.0)
    s = s if ee != 0 else 0.0
    dx, dy, dz = wx - s * ex, wy - s * ey, wz - s * ez
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, nogil=True, error_model="numpy")
def _distances(C, px, py, pz, dtri, dedge):
    """Each triangle's distance from p (``dtri``,
    :func:`~isoflow.mesh.captree.dist_triangle`) and its edges' least
    distance (``dedge``), in lanes."""
    for t in range(C.shape[1]):
        ax, ay, az = C[0, t] - px, C[1, t] - py, C[2, t] - pz
        bx, by, bz = C[3, t] - px, C[4, t] - py, C[5, t] - pz
        cx, cy, cz = C[6, t] - px, C[7, t] - py, C[8, t] - pz
        d = min(_segment(ax, ay, az, bx, by, bz), _segment(bx, by, bz, cx, cy, cz), _segment(cx, cy, cz, ax, ay, az))
        ux, uy, uz = bx - ax, by - ay, bz - az
        vx, vy, vz = cx - ax, cy - ay, cz - az
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        nn = nx * nx + ny * ny + nz * nz
        wx, wy, wz = -ax, -ay, -az
        s0 = ((uy * wz - uz * wy) * nx + (uz * wx - ux * wz) * ny + (ux * wy - uy * wx) * nz)
        s1 = ((wy * vz - wz * vy) * nx + (wz * vx - wx * vz) * ny + (wx * vy - wy * vx) * nz)
        inside = nn > 0 and s0 >= 0 and s1 >= 0 and s0 + s1 <= nn
        plane = abs(wx * nx + wy * ny + wz * nz) / math.sqrt(nn if nn > 0 else 1.0)
        dedge[t] = d
        dtri[t] = plane if inside else d


@njit(cache=True, nogil=True, error_model="numpy", fastmath={"reassoc"})
def _far_sum(ang, keep):
    """The sum of the kept triangles' angles."""
    s = 0.0
    for t in range(ang.shape[0]):
        s += ang[t] if keep[t] else 0.0
    return s


@njit(cache=True, nogil=True, error_model="numpy", fastmath={"reassoc"})
def _edge_sums(D, eo, keep, px, py, pz, h):
    """The Biot-Savart field at p of the chain edges that kept triangles
    hold, and the bound on its derivative over the ball of radius h
    (:func:`isoflow.mesh.captree.edge_terms`, branch-free: NaN where a
    kept edge comes within h)."""
    gx = gy = gz = hs = 0.0
    for e in range(D.shape[1]):
        ax, ay, az = D[0, e] - px, D[1, e] - py, D[2, e] - pz
        bx, by, bz = D[3, e] - px, D[4, e] - py, D[5, e] - pz
        ex, ey, ez = bx - ax, by - ay, bz - az
        length = math.sqrt(ex * ex + ey * ey + ez * ez)
        inv = 1.0 / length if length > 0 else 0.0
        ux, uy, uz = ex * inv, ey * inv, ez * inv
        sa = ax * ux + ay * uy + az * uz
        sb = bx * ux + by * uy + bz * uz
        ra = math.sqrt(ax * ax + ay * ay + az * az)
        rb = math.sqrt(bx * bx + by * by + bz * bz)
        cx, cy, cz = uy * az - uz * ay, uz * ax - ux * az, ux * ay - uy * ax
        dd = cx * cx + cy * cy + cz * cz
        foot = sa <= 0 and sb >= 0
        d = math.sqrt(dd) if foot else min(ra, rb)
        integral = (sb / rb - sa / ra) / dd if foot else (sb - sa) * (sb + sa) / (ra * rb * (sb * ra + sa * rb))
        f = d / (d - h)
        bound = 2.0 * integral * f * f * f if d > h else math.nan
        use = keep[eo[e]] and length > 0
        gx += cx * integral if use else 0.0
        gy += cy * integral if use else 0.0
        gz += cz * integral if use else 0.0
        hs += bound if use else 0.0
    return gx, gy, gz, hs


@njit(cache=True, nogil=True)
def evaluate_lanes(px, py, pz, h, reach, tol, T, nlen, E, owner, C, D, eo, near, cross, edges, grad, ang, det,
                   keep, dtri, dedge):
    """:func:`isoflow.mesh.captree.evaluate` with every node opened (no
    expansion), in lanes: ``(w, err, var, hess, status, nnear, ncross)``
    with ``err = var = 0``, ``grad`` written into the argument (four
    entries, the fourth scratch).  ``ang``, ``det``, ``keep``, ``dtri`` and
    ``dedge`` are scratch of one entry per triangle."""
    K = C.shape[1]
    _angles(C, nlen, px, py, pz, ang, det)
    _distances(C, px, py, pz, dtri, dedge)
    nnear = np.int64(0)  # not the literal 0: numba would compile cut_edges once more for it
    ncross = np.int64(0)
    for t in range(K):
        keep[t] = True
        d = dtri[t]
        if d > reach:
            continue
        if h == 0:
            return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
        # as isoflow.mesh.captree.near_kind
        kind = NEAR if abs(det[t]) <= tol * nlen[t] or dedge[t] <= reach else (CROSSING if d <= h else FAR)
        if kind == NEAR:
            if nnear == near.shape[0]:
                return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
            near[nnear] = t
            nnear += 1
            keep[t] = False
        elif kind == CROSSING:
            if ncross == cross.shape[0]:
                return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
            cross[ncross] = t
            ncross += 1
    far = _far_sum(ang, keep)
    grad[:] = 0.0
    if h > 0:
        grad[0], grad[1], grad[2], grad[3] = _edge_sums(D, eo, keep, px, py, pz, h)
        if nnear:
            cut_edges(px, py, pz, h, T, E, owner, near, nnear, edges, grad)
    hess = grad[3]
    if not hess < math.inf or not abs(far) < math.inf:  # an edge of the far part within h, or p on a corner
        return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
    inv4pi = 1.0 / (4.0 * math.pi)
    for d in range(3):
        grad[d] *= GRAD_SIGN * inv4pi
    return far / (2.0 * math.pi), 0.0, 0.0, hess * inv4pi, CLEAR, nnear, ncross
