"""The generalised winding number (Jacobson et al. 2013) of voxel centres,
exactly and at about the cost of the closed scanline.

The generalised winding number of a triangle mesh M at a point p is
``w(p) = sum over triangles of Omega_t(p) / 4 pi`` (signed solid angles); a
voxel is in iff ``|w(centre)| > 1/2``.  On a closed, consistently oriented
mesh w is the integer winding number and the rule is the nonzero rule.

How it is computed (no approximation that can flip a voxel):

1. **Cap.** The boundary of M as an integer 1-chain (every edge with its net
   multiplicity, uses one way minus uses the other way) is a cycle.  The cone
   C from an apex over each of its connected pieces (one triangle
   ``(apex, b, a)`` per chain edge ``a -> b``) has boundary ``-boundary(M)``,
   so ``M + C`` is closed: its winding number W is an integer that the exact
   scanline (:mod:`isoflow.mesh.scanline`) computes at every centre, and
   ``w_M = W - w_C``.
2. **Rounding to an integer.** ``|W - w_C| > 1/2`` iff ``W != round(w_C)``
   (W is an integer; equality only at |w| = 1/2 exactly).  So only
   ``R = round(w_C)`` is needed, and R is 0 wherever ``|w_C| < 1/2``.
3. **Blocks with a bound.** ``w_C`` is harmonic off C, and its gradient is
   the Biot-Savart integral over the boundary chain, so on a ball of radius h
   around q that does not meet C, ``|w_C(p) - w_C(q)| <= h / 4 pi * sum_e
   len_e / (d_e - h)^2`` (d_e: distance from q to chain edge e).  Blocks of
   voxels are evaluated at their centre with this bound; a block whose
   interval ``w_C(q) +- bound`` holds no half-integer gets one R; the others
   (and blocks that meet C) are split in eight, down to single voxels,
   which get ``w_C`` exactly (the sum of the triangles' ``atan2`` terms is
   taken as the argument of a product of complex numbers, counting whole
   turns: one ``atan2`` per point).  A centre within ``1e-6`` pitch of the cap
   (where the scanline's tie rule and the sign of a solid angle could
   disagree), and one whose ``w_C`` is within ``1e-9`` of a half-integer
   (where rounding it decides nothing: on a planar part of M that lies in
   a plane of centres, ``w_C`` is exactly 1/2 inside the boundary, and
   ``|w_M| -> 1/2`` from both sides), gets ``w_M`` summed over M's own
   triangles instead, at the point the scanline's tie rule stands for
   (the centre moved by ``(eta, eps, -delta)``, ``0 < eps << eta << delta``,
   here 1e-9, 1e-7 and 1e-5 pitch): on a planar sheet ``|w_M|`` is then
   just under 1/2, so its centres are out, whichever way it faces.

Caps are cones over each boundary piece from its centroid, lifted by 1 % of
its size along its vector area and by 0.1 % along a fixed generic direction,
so that a planar hole lying in a plane of voxel centres does not put a whole
layer of centres on the cap; the boundary of a lone triangle (a soup) is
capped by the triangle itself, reversed.

Cost: the scanline's, plus (blocks evaluated) x (cap triangles + chain
edges).  Near a hole, w passes 1/2 on a soap-film-like sheet across it, and
there every voxel needs its exact value: a hole n voxels wide costs about
n^2 such voxels.
"""

from __future__ import annotations

import math

import numpy as np
from ..scale.jit import njit

from ..errors import IsoflowError

#: centres closer than this (in pitches) to the cap are summed over M itself
TIE_PITCHES = 1e-6
#: ... and those whose w_C is this close to a half-integer
TIE_WINDING = 1e-9
#: where they are summed: the centre moved as the scanline's tie rule moves
#: it, (x + eta, y + eps, z - delta) with 0 < eps << eta << delta (pitches)
TIE_STEP = np.array([1e-7, 1e-9, -1e-5])
#: blocks at the coarsest level are about this many per axis
TOP_BLOCKS = 16
_GENERIC = np.array([0.5773, 0.3141, 0.7537]) / np.linalg.norm([0.5773, 0.3141, 0.7537])


# ---------------------------------------------------------------------------
# caps
# ---------------------------------------------------------------------------

def cap_triangles(v: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cap over the boundary chain ``a[e] -> b[e]`` (edges repeated by
    multiplicity): corners (K, 3, 3) of its triangles, one cone per
    connected piece, and the chain's edges (E, 2, 3) (the cap's boundary,
    for the bound on its variation).

    A piece that is the boundary of one lone triangle (a soup) is capped by
    that triangle reversed (the cone from one of its corners, less its two
    flat triangles): one cap triangle instead of three."""
    if len(a) == 0:
        return np.zeros((0, 3, 3)), np.zeros((0, 2, 3))
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    used, inv = np.unique(np.concatenate([a, b]), return_inverse=True)
    ia, ib = inv[: len(a)], inv[len(a):]
    n = len(used)
    g = coo_matrix((np.ones(len(a)), (ia, ib)), shape=(n, n))
    ncomp, lab = connected_components(g, directed=False)
    pts = v[used]
    cnt = np.bincount(lab, minlength=ncomp).astype(np.float64)
    centroid = np.stack([np.bincount(lab, weights=pts[:, d], minlength=ncomp) for d in range(3)], 1) / cnt[:, None]
    lo = np.full((ncomp, 3), np.inf)
    hi = np.full((ncomp, 3), -np.inf)
    np.minimum.at(lo, lab, pts)
    np.maximum.at(hi, lab, pts)
    size = np.linalg.norm(hi - lo, axis=1)
    ce = lab[ia]
    area = 0.5 * np.cross(pts[ia] - centroid[ce], pts[ib] - centroid[ce])
    normal = np.stack([np.bincount(ce, weights=area[:, d], minlength=ncomp) for d in range(3)], 1)
    nlen = np.linalg.norm(normal, axis=1)
    flat = nlen <= 1e-12 * size**2
    unit = np.where(flat[:, None], _GENERIC, normal / np.where(flat, 1.0, nlen)[:, None])
    apex = centroid + size[:, None] * (0.01 * unit + 0.001 * _GENERIC)
    # a lone triangle's boundary (three edges, three vertices): apex on a corner
    ecount = np.bincount(ce, minlength=ncomp)
    lone = (ecount == 3) & (cnt == 3)
    first = np.full(ncomp, -1, dtype=np.int64)
    first[ce[::-1]] = ia[::-1]  # some vertex of each piece
    apex[lone] = pts[first[lone]]
    T = np.empty((len(a), 3, 3))
    T[:, 0] = apex[ce]
    T[:, 1] = v[b]
    T[:, 2] = v[a]
    flat = lone[ce] & ((ia == first[ce]) | (ib == first[ce]))  # cap triangles with two equal corners
    E = np.stack([v[a], v[b]], axis=1)
    return T[~flat], E


# ---------------------------------------------------------------------------
# compiled geometry
# ---------------------------------------------------------------------------

@njit(cache=True, nogil=True, inline="always")
def _solid_angle(T, t, px, py, pz):
    """Signed solid angle of triangle t at p (van Oosterom & Strackee 1983)."""
    ax, ay, az = T[t, 0, 0] - px, T[t, 0, 1] - py, T[t, 0, 2] - pz
    bx, by, bz = T[t, 1, 0] - px, T[t, 1, 1] - py, T[t, 1, 2] - pz
    cx, cy, cz = T[t, 2, 0] - px, T[t, 2, 1] - py, T[t, 2, 2] - pz
    la = math.sqrt(ax * ax + ay * ay + az * az)
    lb = math.sqrt(bx * bx + by * by + bz * bz)
    lc = math.sqrt(cx * cx + cy * cy + cz * cz)
    det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
    den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc
           + (bx * cx + by * cy + bz * cz) * la + (cx * ax + cy * ay + cz * az) * lb)
    return 2.0 * math.atan2(det, den)


@njit(cache=True, nogil=True, inline="always")
def _dot(ax, ay, az, bx, by, bz):
    return ax * bx + ay * by + az * bz


@njit(cache=True, nogil=True)
def _dist2_triangle(T, t, px, py, pz):
    """Squared distance from p to triangle t (Ericson, Real-Time Collision
    Detection, 5.1.5)."""
    ax, ay, az = T[t, 0, 0], T[t, 0, 1], T[t, 0, 2]
    abx, aby, abz = T[t, 1, 0] - ax, T[t, 1, 1] - ay, T[t, 1, 2] - az
    acx, acy, acz = T[t, 2, 0] - ax, T[t, 2, 1] - ay, T[t, 2, 2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = _dot(abx, aby, abz, apx, apy, apz)
    d2 = _dot(acx, acy, acz, apx, apy, apz)
    if d1 <= 0 and d2 <= 0:
        qx, qy, qz = ax, ay, az
    else:
        bpx, bpy, bpz = px - T[t, 1, 0], py - T[t, 1, 1], pz - T[t, 1, 2]
        d3 = _dot(abx, aby, abz, bpx, bpy, bpz)
        d4 = _dot(acx, acy, acz, bpx, bpy, bpz)
        cpx, cpy, cpz = px - T[t, 2, 0], py - T[t, 2, 1], pz - T[t, 2, 2]
        d5 = _dot(abx, aby, abz, cpx, cpy, cpz)
        d6 = _dot(acx, acy, acz, cpx, cpy, cpz)
        vc = d1 * d4 - d3 * d2
        vb = d5 * d2 - d1 * d6
        va = d3 * d6 - d5 * d4
        if d3 >= 0 and d4 <= d3:
            qx, qy, qz = T[t, 1, 0], T[t, 1, 1], T[t, 1, 2]
        elif d6 >= 0 and d5 <= d6:
            qx, qy, qz = T[t, 2, 0], T[t, 2, 1], T[t, 2, 2]
        elif vc <= 0 and d1 >= 0 and d3 <= 0:
            s = d1 / (d1 - d3)
            qx, qy, qz = ax + s * abx, ay + s * aby, az + s * abz
        elif vb <= 0 and d2 >= 0 and d6 <= 0:
            s = d2 / (d2 - d6)
            qx, qy, qz = ax + s * acx, ay + s * acy, az + s * acz
        elif va <= 0 and (d4 - d3) >= 0 and (d5 - d6) >= 0:
            s = (d4 - d3) / ((d4 - d3) + (d5 - d6))
            qx = T[t, 1, 0] + s * (T[t, 2, 0] - T[t, 1, 0])
            qy = T[t, 1, 1] + s * (T[t, 2, 1] - T[t, 1, 1])
            qz = T[t, 1, 2] + s * (T[t, 2, 2] - T[t, 1, 2])
        else:
            den = va + vb + vc
            if den == 0:  # degenerate triangle: all three regions failed
                qx, qy, qz = ax, ay, az
            else:
                s, u = vb / den, vc / den
                qx, qy, qz = ax + abx * s + acx * u, ay + aby * s + acy * u, az + abz * s + acz * u
    dx, dy, dz = px - qx, py - qy, pz - qz
    return dx * dx + dy * dy + dz * dz


@njit(cache=True, nogil=True)
def _dist_segment(E, e, px, py, pz):
    """Distance from p to the segment E[e, 0] - E[e, 1]."""
    bx, by, bz = E[e, 0, 0], E[e, 0, 1], E[e, 0, 2]
    ex, ey, ez = E[e, 1, 0] - bx, E[e, 1, 1] - by, E[e, 1, 2] - bz
    wx, wy, wz = px - bx, py - by, pz - bz
    ee = ex * ex + ey * ey + ez * ez
    s = 0.0 if ee == 0 else min(max((wx * ex + wy * ey + wz * ez) / ee, 0.0), 1.0)
    dx, dy, dz = wx - s * ex, wy - s * ey, wz - s * ez
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, nogil=True)
def _eval_blocks(blocks, origin, pitch, Tc, nlen, E, elen, tol, status, rvals):
    """Evaluate round(w_C) on blocks ``[i0, i1) x [j0, j1) x [k0, k1)``.

    status 0: ``rvals`` holds R for the whole block; 1: split it; 2: a single
    centre within ``tol`` of the cap, or whose w_C is a half-integer within
    :data:`TIE_WINDING` (sum over the mesh instead).  One pass
    over the cap's triangles: the solid angle, the distance to the
    triangle's plane (``|det| / |n|``, a lower bound of the distance to the
    triangle, which is computed only when the plane is near), and a lower
    bound of the distance to its chain edge for the bound on the variation.
    """
    inv4pi = 1.0 / (4.0 * math.pi)
    for q in range(blocks.shape[0]):
        i0, i1, j0, j1, k0, k1 = blocks[q, 0], blocks[q, 1], blocks[q, 2], blocks[q, 3], blocks[q, 4], blocks[q, 5]
        px = origin[0] + pitch * (0.5 * (i0 + i1))
        py = origin[1] + pitch * (0.5 * (j0 + j1))
        pz = origin[2] + pitch * (0.5 * (k0 + k1))
        di, dj, dk = i1 - i0 - 1, j1 - j0 - 1, k1 - k0 - 1
        h = 0.5 * pitch * math.sqrt(di * di + dj * dj + dk * dk)
        reach = h if h > 0 else tol
        zx, zy, turns = 1.0, 0.0, 0
        var = 0.0
        hit = False
        for t in range(Tc.shape[0]):
            ax, ay, az = Tc[t, 0, 0] - px, Tc[t, 0, 1] - py, Tc[t, 0, 2] - pz
            bx, by, bz = Tc[t, 1, 0] - px, Tc[t, 1, 1] - py, Tc[t, 1, 2] - pz
            cx, cy, cz = Tc[t, 2, 0] - px, Tc[t, 2, 1] - py, Tc[t, 2, 2] - pz
            det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
            if abs(det) <= reach * nlen[t]:  # the plane is near: is the triangle?
                if _dist2_triangle(Tc, t, px, py, pz) <= reach * reach:
                    hit = True
                    break
            la = math.sqrt(ax * ax + ay * ay + az * az)
            lb = math.sqrt(bx * bx + by * by + bz * bz)
            lc = math.sqrt(cx * cx + cy * cy + cz * cz)
            den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc
                   + (bx * cx + by * cy + bz * cz) * la + (cx * ax + cy * ay + cz * az) * lb)
            # sum of atan2(det, den) as the argument of a product of complex
            # numbers, counting the turns: one atan2 per block, not per triangle
            nx = zx * den - zy * det
            ny = zx * det + zy * den
            if _upper(zx, zy) and _upper(den, det) and not _upper(nx, ny):
                turns += 1
            elif zy < 0 and det < 0 and _upper(nx, ny):
                turns -= 1
            m = max(abs(nx), abs(ny))
            if m > 0:  # 0 only for a centre on a corner: within tol, not used
                zx, zy = nx / m, ny / m
        w = 2.0 * (math.atan2(zy, zx) + 2.0 * math.pi * turns)  # the sum of 2 atan2(det, den)
        if h > 0 and not hit:
            for e in range(E.shape[0]):
                ax, ay, az = E[e, 0, 0] - px, E[e, 0, 1] - py, E[e, 0, 2] - pz
                bx, by, bz = E[e, 1, 0] - px, E[e, 1, 1] - py, E[e, 1, 2] - pz
                # distance to the edge >= (|a| + |b| - |b - a|) / 2
                la = math.sqrt(ax * ax + ay * ay + az * az)
                lb = math.sqrt(bx * bx + by * by + bz * bz)
                d = 0.5 * (la + lb - elen[e]) - h
                if d <= 0:
                    d = _dist_segment(E, e, px, py, pz) - h
                var += elen[e] / (d * d)
        if hit:
            status[q] = 2 if h == 0 else 1
            continue
        w *= inv4pi
        var *= h * inv4pi
        lo = math.floor(w - var + 0.5)
        if h == 0 and abs(w - math.floor(w) - 0.5) <= TIE_WINDING:
            status[q] = 2  # a half-integer: its rounding would be the noise's
        elif lo == math.floor(w + var + 0.5):
            status[q] = 0
            rvals[q] = int(lo)
        else:  # a single centre never splits (a NaN would loop forever)
            status[q] = 1 if h > 0 else 2


@njit(cache=True, nogil=True, inline="always")
def _upper(x, y):
    """The argument of x + iy lies in (0, pi]."""
    return y > 0 or (y == 0 and x < 0)


@njit(cache=True, nogil=True)
def _gwn_points(P, T, out):
    """Generalised winding number of points P over triangles T (brute force)."""
    inv4pi = 1.0 / (4.0 * math.pi)
    for p in range(P.shape[0]):
        w = 0.0
        for t in range(T.shape[0]):
            w += _solid_angle(T, t, P[p, 0], P[p, 1], P[p, 2])
        out[p] = w * inv4pi


def gwn(points, triangles) -> np.ndarray:
    """Generalised winding number of ``points`` (n, 3) over ``triangles``
    (m, 3, 3), summed triangle by triangle (O(n m))."""
    P = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    T = np.ascontiguousarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    out = np.empty(len(P))
    _gwn_points(P, T, out)
    return out


# ---------------------------------------------------------------------------
# the rule R = round(w_C) on a box of the grid
# ---------------------------------------------------------------------------

FORCE_IN, FORCE_OUT = 127, -128


def _split(blocks: np.ndarray) -> np.ndarray:
    """Each block cut in two at the middle of every axis longer than one."""
    out = [blocks]
    for a in range(3):
        lo, hi = out[-1][:, 2 * a], out[-1][:, 2 * a + 1]
        mid = (lo + hi) // 2
        cut = hi - lo > 1
        left = out[-1].copy()
        left[cut, 2 * a + 1] = mid[cut]
        right = out[-1][cut].copy()
        right[:, 2 * a] = mid[cut]
        out.append(np.concatenate([left, right]))
    return out[-1]


def winding_rule(Tc, E, Tm, origin, pitch, box, threads: int = 1):
    """``R = round(w_C)`` for every centre of ``box = (i0, i1, j0, j1, k0, k1)``
    where it is not 0, as ``(array, (i0, j0, k0))`` (int8, with the codes
    FORCE_IN / FORCE_OUT where the centre is so close to the cap that the
    mesh's own winding number decided), or None where R is 0 everywhere.

    ``Tc`` are the cap's triangles, ``E`` its boundary edges (E, 2, 3), ``Tm``
    the mesh's triangles (for the ties), all in the frame of ``origin`` and
    ``pitch``.
    """
    if len(E) == 0:
        return None
    Tc = np.ascontiguousarray(Tc, dtype=np.float64)
    E = np.ascontiguousarray(E, dtype=np.float64)
    origin = np.asarray(origin, dtype=np.float64)
    elen = np.linalg.norm(E[:, 1] - E[:, 0], axis=1)
    nlen = np.linalg.norm(np.cross(Tc[:, 1] - Tc[:, 0], Tc[:, 2] - Tc[:, 0]), axis=1)
    tol = TIE_PITCHES * pitch
    i0, i1, j0, j1, k0, k1 = (int(x) for x in box)
    ext = max(i1 - i0, j1 - j0, k1 - k0)
    s = 1 << max(0, math.ceil(math.log2(max(1, ext / TOP_BLOCKS))))
    edges = [np.append(np.arange(lo, hi, s), hi) for lo, hi in ((i0, i1), (j0, j1), (k0, k1))]
    gi, gj, gk = np.meshgrid(np.arange(len(edges[0]) - 1), np.arange(len(edges[1]) - 1),
                             np.arange(len(edges[2]) - 1), indexing="ij")
    gi, gj, gk = gi.ravel(), gj.ravel(), gk.ravel()
    blocks = np.stack([edges[0][gi], edges[0][gi + 1], edges[1][gj], edges[1][gj + 1],
                       edges[2][gk], edges[2][gk + 1]], axis=1).astype(np.int64)
    done_b, done_r, ties = [], [], []
    while len(blocks):
        status = np.empty(len(blocks), dtype=np.int8)
        rvals = np.zeros(len(blocks), dtype=np.int64)
        _run_split(_eval_blocks, blocks, origin, pitch, Tc, nlen, E, elen, tol, status, rvals, threads)
        keep = (status == 0) & (rvals != 0)
        done_b.append(blocks[keep])
        done_r.append(rvals[keep])
        ties.append(blocks[status == 2])
        blocks = _split(blocks[status == 1])
    done_b = np.concatenate(done_b)
    done_r = np.concatenate(done_r)
    ties = np.concatenate(ties)
    if len(ties):
        P = origin + pitch * (ties[:, [0, 2, 4]] + 0.5 + TIE_STEP)
        w = gwn(P, Tm)
        done_b = np.concatenate([done_b, ties])
        done_r = np.concatenate([done_r, np.where(np.abs(w) > 0.5, FORCE_IN, FORCE_OUT)])
    if len(done_b) == 0:
        return None
    normal = (done_r != FORCE_IN) & (done_r != FORCE_OUT)
    if normal.any() and np.abs(done_r[normal]).max() > 126:
        raise IsoflowError("voxelize: the cap's winding number exceeds 126 (more than 126 "
                           "overlapping layers of boundary): not supported")
    lo = done_b[:, [0, 2, 4]].min(axis=0)
    hi = done_b[:, [1, 3, 5]].max(axis=0)
    rule = np.zeros(tuple(hi - lo), dtype=np.int8)
    b = done_b - np.repeat(lo, 2)
    _paint(rule, b, done_r.astype(np.int8))
    return rule, tuple(int(x) for x in lo)


@njit(cache=True, nogil=True)
def _paint(rule, blocks, vals):
    for q in range(blocks.shape[0]):
        rule[blocks[q, 0]:blocks[q, 1], blocks[q, 2]:blocks[q, 3], blocks[q, 4]:blocks[q, 5]] = vals[q]


def _run_split(kernel, blocks, origin, pitch, Tc, nlen, E, elen, tol, status, rvals, threads):
    """The kernel over the blocks, in two halves on two threads if asked."""
    n = len(blocks)
    if threads <= 1 or n < 64:
        kernel(blocks, origin, pitch, Tc, nlen, E, elen, tol, status, rvals)
        return
    from .scanline import two_threads

    h = n // 2
    futs = [two_threads().submit(kernel, blocks[a:b], origin, pitch, Tc, nlen, E, elen, tol, status[a:b], rvals[a:b])
            for a, b in ((0, h), (h, n))]
    for fu in futs:
        fu.result()
