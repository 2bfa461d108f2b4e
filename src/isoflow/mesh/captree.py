"""A bounding-volume hierarchy over a cap's triangles, and the cap's
generalised winding number on a ball of voxel centres with a rigorous
bound: the far field of Barill et al. 2018 with a proven remainder.

The winding number of a set of triangles N at a point p is
``w_N(p) = 1/4pi * sum_t int_t (x - p) . n / |x - p|^3 dA``.  With every
triangle of N inside the ball ``|x - c| <= rho`` and ``r = c - p``,
``R = |r| > rho``, the integrand ``K(r + d) . n`` (``K(y) = y / |y|^3 =
-grad 1/|y|``, ``d = x - c``) is expanded in d (Barill et al. 2018, "Fast
winding numbers for soups and clouds", eq. 12-14; their order 0 and 1)::

    w_N(p) ~ 1/4pi * ( r . A / R^3  +  tr(Mo) / R^3 - 3 r . Mo r / R^5 )

with ``A = sum_t a_t`` (vector areas) and ``Mo = sum_t (g_t - c) a_t^T``
(``g_t`` the centroids: exact for flat triangles).  The remainder is the
tail of the Taylor series of ``-D(1/|y|)[n]`` about r.  Along any line,
``1/|r + s u|`` is Legendre's generating function, so
``|D^k (1/|y|)[u^k]| = k! |P_k| / R^(k+1) <= k! / R^(k+1)``, and by
Banach's theorem on symmetric multilinear forms (their norm is that of
their diagonal, in a real inner-product space) the same holds for mixed
directions.  The term of order k is therefore at most
``(k+1) rho^k / R^(k+2)`` per unit of area, and after order 1::

    |w_N(p) - expansion| <= S / (4 pi R^2) * x^2 (3 - 2x) / (1 - x)^2,
                                             x = rho / R,

with S the sum of the triangles' areas (no cancellation is assumed).

On a ball B of radius h around q that no triangle edge of the cap meets,
``w_C(p) - w_C(q)`` is the integer number of signed crossings of the
segment q-p with the cap plus a continuous part whose gradient is the
Biot-Savart field of the cap's boundary (the chain), at most
``1/4pi * sum_e len_e / dist(p, e)^2``; so ``h / 4pi * sum_e len_e /
(d_e - h)^2`` bounds it.  A triangle that meets B while none of its
edges does cuts B in two along its plane (the disc of B in that plane does
not meet the triangle's boundary, so it is all inside the triangle): its
crossing is the side of its plane (``w_t = -s/2 +`` continuous,
``s = sign((p - a) . n)``).  Such triangles are listed (*crossings*); any
other triangle that meets B makes the ball a *hit*.

Nodes are accepted (their expansion used) only when they are farther than
``rho / theta`` and do not meet B; a node's chain edges are bounded there
by ``L / (R - rho - h)^2`` (L their total length).  ``theta = 0`` opens
every node: the exact sum, whose ``atan2`` terms are added as the argument
of a product of complex numbers, counting whole turns (one ``atan2`` per
point).
"""

from __future__ import annotations

import math

import numpy as np

from ..scale.jit import njit

#: triangles per leaf
LEAF_SIZE = 8
#: at most this many triangles are near one ball (and as many crossing); more make it a hit
MAX_NEAR = 48
#: the gradient of w_C is this sign times the Biot-Savart integral over its boundary
GRAD_SIGN = -1.0
#: how a triangle near a ball is summed (:func:`evaluate`)
FAR, NEAR, CROSSING = 0, 1, 2
#: status of a ball (``evaluate``): no triangle meets it / it is hit
CLEAR, HIT = 0, 1


class CapTree:
    """The cap's triangles sorted into a binary tree of balls.

    ``T`` (K, 3, 3) are the triangles in tree order, ``owner`` (K + 1,) the
    ranges of ``E`` (chain edges, (E, 2, 3)) that each triangle holds (one
    of its own edges: the bound on the variation needs each chain edge
    inside the ball of some node that holds it).  Nodes: ``lo, hi`` (range
    of triangles), ``child`` (first child, -1 for a leaf; the second is
    ``child + 1``), ``centre``, ``rho`` (every corner within it),
    ``A`` (vector area), ``Mo`` (first moment), ``S`` (area), ``L``
    (length of its chain edges).
    """

    def __init__(self, T: np.ndarray, E: np.ndarray, edge_owner: np.ndarray):
        T = np.ascontiguousarray(T, dtype=np.float64).reshape(-1, 3, 3)
        E = np.ascontiguousarray(E, dtype=np.float64).reshape(-1, 2, 3)
        k = len(T)
        if k:
            order, lo, hi, child = _build(T.mean(axis=1), LEAF_SIZE)
        else:  # a closed mesh: no compiled code to load
            order, lo, hi, child = (np.zeros(0, dtype=np.int64) for _ in range(4))
        rank = np.empty(k, dtype=np.int64)
        rank[order] = np.arange(k)
        self.T = np.ascontiguousarray(T[order])
        eo = rank[np.asarray(edge_owner, dtype=np.int64)]
        by = np.argsort(eo, kind="stable")
        self.E = np.ascontiguousarray(E[by])
        self.elen = np.linalg.norm(self.E[:, 1] - self.E[:, 0], axis=1)
        self.owner = np.searchsorted(eo[by], np.arange(k + 1)).astype(np.int64)
        self.nlen = np.linalg.norm(np.cross(self.T[:, 1] - self.T[:, 0], self.T[:, 2] - self.T[:, 0]), axis=1)
        self.lo, self.hi, self.child = lo, hi, child
        n = len(lo)
        self.centre = np.zeros((n, 3))
        self.rho = np.zeros(n)
        self.A = np.zeros((n, 3))
        self.Mo = np.zeros((n, 3, 3))
        self.S = np.zeros(n)
        self.L = np.zeros(n)
        if k:
            own_len = np.add.reduceat(np.append(self.elen, 0.0), self.owner[:-1]) * (np.diff(self.owner) > 0)
            _moments(self.T, own_len, lo, hi, child, self.centre, self.rho, self.A, self.Mo, self.S, self.L)

    def arrays(self) -> tuple:
        """What the compiled queries take, in their order."""
        return (self.T, self.nlen, self.E, self.elen, self.owner, self.lo, self.hi, self.child,
                self.centre, self.rho, self.A, self.Mo, self.S, self.L)


@njit(cache=True, nogil=True)
def _build(g, leaf):
    """Median splits of the centroids g along the longest side of their box;
    nodes are numbered so that children come after their parent."""
    k = g.shape[0]
    order = np.arange(k)
    cap = 2 * k + 1  # a leaf holds at least one triangle: at most 2k - 1 nodes
    lo = np.empty(cap, dtype=np.int64)
    hi = np.empty(cap, dtype=np.int64)
    child = np.full(cap, -1, dtype=np.int64)
    lo[0], hi[0] = 0, k
    n = 1
    stack = np.empty(128, dtype=np.int64)
    stack[0] = 0
    top = 1
    while top:
        top -= 1
        nd = stack[top]
        a, b = lo[nd], hi[nd]
        if b - a <= leaf:
            continue
        mn = np.full(3, np.inf)
        mx = np.full(3, -np.inf)
        for i in range(a, b):
            for d in range(3):
                mn[d] = min(mn[d], g[order[i], d])
                mx[d] = max(mx[d], g[order[i], d])
        ax = np.argmax(mx - mn)
        keys = np.empty(b - a)
        for i in range(a, b):
            keys[i - a] = g[order[i], ax]
        sub = order[a:b][np.argsort(keys, kind="mergesort")]
        for i in range(a, b):  # (element by element: a slice assigned an array compiles numba's message)
            order[i] = sub[i - a]
        m = (a + b) // 2
        child[nd] = n
        lo[n], hi[n], lo[n + 1], hi[n + 1] = a, m, m, b
        stack[top] = n
        stack[top + 1] = n + 1
        top += 2
        n += 2
    return order, lo[:n].copy(), hi[:n].copy(), child[:n].copy()


@njit(cache=True, nogil=True)
def _moments(T, own_len, lo, hi, child, centre, rho, A, Mo, S, L):
    """Each node's ball (centre of its corners' box, radius to the farthest
    corner), vector area, first moment about its centre, area and chain
    length; children before parents."""
    for nd in range(lo.shape[0] - 1, -1, -1):
        mn = np.full(3, np.inf)
        mx = np.full(3, -np.inf)
        for t in range(lo[nd], hi[nd]):
            for c in range(3):
                for d in range(3):
                    mn[d] = min(mn[d], T[t, c, d])
                    mx[d] = max(mx[d], T[t, c, d])
        cx, cy, cz = 0.5 * (mn[0] + mx[0]), 0.5 * (mn[1] + mx[1]), 0.5 * (mn[2] + mx[2])
        centre[nd, 0], centre[nd, 1], centre[nd, 2] = cx, cy, cz
        r2 = 0.0
        for t in range(lo[nd], hi[nd]):
            for c in range(3):
                dx, dy, dz = T[t, c, 0] - cx, T[t, c, 1] - cy, T[t, c, 2] - cz
                r2 = max(r2, dx * dx + dy * dy + dz * dz)
        rho[nd] = math.sqrt(r2) * (1.0 + 1e-12)
        for t in range(lo[nd], hi[nd]):  # leaves and inner nodes alike: O(K log K) in all
            ux, uy, uz = T[t, 1, 0] - T[t, 0, 0], T[t, 1, 1] - T[t, 0, 1], T[t, 1, 2] - T[t, 0, 2]
            vx, vy, vz = T[t, 2, 0] - T[t, 0, 0], T[t, 2, 1] - T[t, 0, 1], T[t, 2, 2] - T[t, 0, 2]
            a = np.array([0.5 * (uy * vz - uz * vy), 0.5 * (uz * vx - ux * vz), 0.5 * (ux * vy - uy * vx)])
            gx = (T[t, 0, 0] + T[t, 1, 0] + T[t, 2, 0]) / 3.0 - cx
            gy = (T[t, 0, 1] + T[t, 1, 1] + T[t, 2, 1]) / 3.0 - cy
            gz = (T[t, 0, 2] + T[t, 1, 2] + T[t, 2, 2]) / 3.0 - cz
            for d in range(3):
                A[nd, d] += a[d]
                Mo[nd, 0, d] += gx * a[d]
                Mo[nd, 1, d] += gy * a[d]
                Mo[nd, 2, d] += gz * a[d]
            S[nd] += math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
            L[nd] += own_len[t]


@njit(cache=True, nogil=True, inline="always")
def far_field(centre, A, Mo, S, rho, nd, px, py, pz):
    """Order-1 expansion of node nd's ``4 pi w`` at p and its bound
    (module docstring); ``R > rho`` is the caller's to ensure."""
    rx, ry, rz = centre[nd, 0] - px, centre[nd, 1] - py, centre[nd, 2] - pz
    r2 = rx * rx + ry * ry + rz * rz
    R = math.sqrt(r2)
    r3 = r2 * R
    m = Mo[nd]
    rMr = (rx * (m[0, 0] * rx + m[0, 1] * ry + m[0, 2] * rz) + ry * (m[1, 0] * rx + m[1, 1] * ry + m[1, 2] * rz)
           + rz * (m[2, 0] * rx + m[2, 1] * ry + m[2, 2] * rz))
    val = (rx * A[nd, 0] + ry * A[nd, 1] + rz * A[nd, 2]) / r3 + (m[0, 0] + m[1, 1] + m[2, 2]) / r3 - 3.0 * rMr / (r3 * r2)
    x = rho[nd] / R
    bound = S[nd] / r2 * x * x * (3.0 - 2.0 * x) / ((1.0 - x) * (1.0 - x))
    return val, bound


@njit(cache=True, nogil=True, inline="always")
def _upper(x, y):
    """The argument of x + iy lies in (0, pi]."""
    return y > 0 or (y == 0 and x < 0)


@njit(cache=True, nogil=True)
def dist_segment(ax, ay, az, bx, by, bz, px, py, pz):
    """Distance from p to the segment a-b."""
    ex, ey, ez = bx - ax, by - ay, bz - az
    wx, wy, wz = px - ax, py - ay, pz - az
    ee = ex * ex + ey * ey + ez * ez
    s = 0.0 if ee == 0 else min(max((wx * ex + wy * ey + wz * ez) / ee, 0.0), 1.0)
    dx, dy, dz = wx - s * ex, wy - s * ey, wz - s * ez
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, nogil=True)
def dist_triangle(T, t, px, py, pz):
    """Distance from p to triangle t: inside its prism, to its plane;
    otherwise to the nearest of its edges."""
    ax, ay, az = T[t, 0, 0], T[t, 0, 1], T[t, 0, 2]
    ux, uy, uz = T[t, 1, 0] - ax, T[t, 1, 1] - ay, T[t, 1, 2] - az
    vx, vy, vz = T[t, 2, 0] - ax, T[t, 2, 1] - ay, T[t, 2, 2] - az
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    nn = nx * nx + ny * ny + nz * nz
    wx, wy, wz = px - ax, py - ay, pz - az
    if nn > 0:
        # barycentric signs of p's projection: each edge's side within the plane
        s0 = ((uy * wz - uz * wy) * nx + (uz * wx - ux * wz) * ny + (ux * wy - uy * wx) * nz)
        s1 = ((wy * vz - wz * vy) * nx + (wz * vx - wx * vz) * ny + (wx * vy - wy * vx) * nz)
        if s0 >= 0 and s1 >= 0 and s0 + s1 <= nn:
            return abs(wx * nx + wy * ny + wz * nz) / math.sqrt(nn)
    d = dist_segment(ax, ay, az, T[t, 1, 0], T[t, 1, 1], T[t, 1, 2], px, py, pz)
    d = min(d, dist_segment(T[t, 1, 0], T[t, 1, 1], T[t, 1, 2], T[t, 2, 0], T[t, 2, 1], T[t, 2, 2], px, py, pz))
    return min(d, dist_segment(T[t, 2, 0], T[t, 2, 1], T[t, 2, 2], ax, ay, az, px, py, pz))


@njit(cache=True, nogil=True, inline="always")
def edge_terms(ax, ay, az, bx, by, bz, h):
    """An edge a -> b of the far part's boundary, given relative to the
    ball's centre p: its Biot-Savart integral ``int dl x (x - p) / |x -
    p|^3`` at p, and the bound ``2 int |x - x'|^-3 dl`` on that integral's
    derivative at any x' of the ball (with ``|x - x'| >= |x - p| (1 - h /
    d)``, d the edge's distance from p); NaN if d <= h (the caller splits).

    With u the edge's direction, s the coordinate along its line from the
    foot of p and delta the line's distance, ``I = int |x - p|^-3 dl =
    (sin phi_b - sin phi_a) / delta^2`` (``sin phi = s / r``), written
    without cancellation when both ends lie on one side of the foot as
    ``(s_b^2 - s_a^2) / (r_a r_b (s_b r_a + s_a r_b))``; the Biot-Savart
    integral is ``(u x a) I``."""
    ex, ey, ez = bx - ax, by - ay, bz - az
    length = math.sqrt(ex * ex + ey * ey + ez * ez)
    if length == 0:
        return 0.0, 0.0, 0.0, 0.0
    ux, uy, uz = ex / length, ey / length, ez / length
    sa = ax * ux + ay * uy + az * uz  # coordinates of a and b along u, from the foot
    sb = bx * ux + by * uy + bz * uz
    ra = math.sqrt(ax * ax + ay * ay + az * az)
    rb = math.sqrt(bx * bx + by * by + bz * bz)
    cx, cy, cz = uy * az - uz * ay, uz * ax - ux * az, ux * ay - uy * ax  # u x a: |u x a| = delta
    if sa <= 0 <= sb:  # the foot on the edge
        dd = cx * cx + cy * cy + cz * cz
        d = math.sqrt(dd)
        if d <= h:
            return 0.0, 0.0, 0.0, math.nan
        integral = (sb / rb - sa / ra) / dd
    else:
        d = min(ra, rb)
        if d <= h:
            return 0.0, 0.0, 0.0, math.nan
        integral = (sb - sa) * (sb + sa) / (ra * rb * (sb * ra + sa * rb))  # both signs of s alike
    f = d / (d - h)
    return cx * integral, cy * integral, cz * integral, 2.0 * integral * f * f * f


@njit(cache=True, nogil=True, inline="always")
def add_edge(acc, X, e, first, px, py, pz, h):
    """Add the terms of edge ``X[e, first] -> X[e, 1 - first]`` at p
    (:func:`edge_terms`) to ``acc = [gx, gy, gz, hess]``."""
    a, b = first, 1 - first
    gx, gy, gz, hs = edge_terms(X[e, a, 0] - px, X[e, a, 1] - py, X[e, a, 2] - pz,
                                X[e, b, 0] - px, X[e, b, 1] - py, X[e, b, 2] - pz, h)
    acc[0] += gx
    acc[1] += gy
    acc[2] += gz
    acc[3] += hs


@njit(cache=True, nogil=True, inline="always")
def _solid_angle_step(ax, ay, az, bx, by, bz, cx, cy, cz, zx, zy, turns):
    """Multiply the running product ``zx + i zy`` (``turns`` whole turns)
    by triangle (a, b, c)'s factor ``den + i det`` (van Oosterom & Strackee
    1983: its solid angle at the origin is ``2 atan2(det, den)``)."""
    det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
    la = math.sqrt(ax * ax + ay * ay + az * az)
    lb = math.sqrt(bx * bx + by * by + bz * bz)
    lc = math.sqrt(cx * cx + cy * cy + cz * cz)
    den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc
           + (bx * cx + by * cy + bz * cz) * la + (cx * ax + cy * ay + cz * az) * lb)
    nx = zx * den - zy * det
    ny = zx * det + zy * den
    if _upper(zx, zy) and _upper(den, det) and not _upper(nx, ny):
        turns += 1
    elif zy < 0 and det < 0 and _upper(nx, ny):
        turns -= 1
    m = max(abs(nx), abs(ny))
    if m > 0:  # 0 only for the origin on a corner (the callers exclude it)
        nx, ny = nx / m, ny / m
    return nx, ny, turns


@njit(cache=True, nogil=True)
def evaluate(px, py, pz, h, reach, theta, tol, T, nlen, E, elen, owner, lo, hi, child, centre, rho, A, Mo, S,
             L, stack, near, cross, edges, grad):
    """The cap's winding number on the ball of radius h around p, as a
    first-order model of its *far* part plus what the caller sums at each
    point: ``w_C(x) = w + grad . (x - p) + w_near(x) + jumps(x) + e`` with
    ``|e| <= err + var + hess h^2 / 2`` on the ball.

    *Near* triangles (``near[:nnear]``) have an edge within ``reach >= h``
    of p: the caller sums their winding numbers at each point.  *Crossing*
    triangles (``cross[:ncross]``) cut the ball with no edge within reach:
    the disc of the ball in their plane lies inside them, so each adds its
    jump ``(s(p) - s(x)) / 2`` (s the side of its plane) at x.  Every
    other triangle, and the continuous part of the crossing ones, is the
    far part.  Its boundary edges all lie farther than ``reach`` from p
    (each belongs to a far or a crossing triangle), so it is smooth on
    the ball; the boundary is the cap's (the chain reversed) less the near
    triangles' boundaries: the chain edges that far triangles hold, plus
    what remains of the near triangles' edges and the chain edges they hold
    after opposite copies cancel (``edges`` is scratch for them).

    Returns ``(w, err, var, hess, status, nnear, ncross)``: ``w`` the far
    part at p up to ``err`` (the far nodes' remainder), ``grad`` (written
    into the argument) the Biot-Savart field at p of the far part's boundary
    edges that are summed exactly, ``var`` the bound on the variation over
    the ball of the far nodes, ``hess`` the bound on the derivative of
    ``grad``'s field over the ball (``grad`` has four entries: the fourth
    is scratch), and status :data:`CLEAR`, or
    :data:`HIT` where more triangles are near or crossing than the scratch
    holds, or where p lies within ``tol`` of a crossing triangle's plane,
    or (``h = 0``: the ball is the point) where any triangle is within
    ``reach``.  ``stack`` is scratch (64 entries are enough for any
    :class:`CapTree`).
    """
    zx, zy, turns = 1.0, 0.0, 0
    far = 0.0
    err = 0.0
    var = 0.0
    nnear = np.int64(0)  # not the literal 0: numba would compile cut_edges once more for it
    ncross = np.int64(0)
    grad[:] = 0.0
    if lo.shape[0] == 0 or hi[0] == 0:
        return 0.0, 0.0, 0.0, 0.0, CLEAR, 0, 0
    if h == 0 and theta == 0:  # the exact sum at a point: every triangle, in order
        for t in range(T.shape[0]):
            ax, ay, az = T[t, 0, 0] - px, T[t, 0, 1] - py, T[t, 0, 2] - pz
            bx, by, bz = T[t, 1, 0] - px, T[t, 1, 1] - py, T[t, 1, 2] - pz
            cx, cy, cz = T[t, 2, 0] - px, T[t, 2, 1] - py, T[t, 2, 2] - pz
            det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
            if abs(det) <= reach * nlen[t] and dist_triangle(T, t, px, py, pz) <= reach:
                return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
            zx, zy, turns = _solid_angle_step(ax, ay, az, bx, by, bz, cx, cy, cz, zx, zy, turns)
        return (math.atan2(zy, zx) + 2.0 * math.pi * turns) / (2.0 * math.pi), 0.0, 0.0, 0.0, CLEAR, 0, 0
    stack[0] = 0
    top = 1
    while top:
        top -= 1
        nd = stack[top]
        dx, dy, dz = centre[nd, 0] - px, centre[nd, 1] - py, centre[nd, 2] - pz
        R = math.sqrt(dx * dx + dy * dy + dz * dz)
        apart = R > (rho[nd] + reach) * (1.0 + 1e-9)  # every triangle of the node is far
        if apart and theta > 0 and rho[nd] <= theta * R:
            val, bound = far_field(centre, A, Mo, S, rho, nd, px, py, pz)
            far += val
            err += bound
            if h > 0:
                gap = R - rho[nd] - h
                var += L[nd] / (gap * gap)
            continue
        if child[nd] >= 0:
            stack[top] = child[nd]
            stack[top + 1] = child[nd] + 1
            top += 2
            continue
        for t in range(lo[nd], hi[nd]):
            ax, ay, az = T[t, 0, 0] - px, T[t, 0, 1] - py, T[t, 0, 2] - pz
            bx, by, bz = T[t, 1, 0] - px, T[t, 1, 1] - py, T[t, 1, 2] - pz
            cx, cy, cz = T[t, 2, 0] - px, T[t, 2, 1] - py, T[t, 2, 2] - pz
            if not apart:
                det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
                if abs(det) <= reach * nlen[t]:
                    d = dist_triangle(T, t, px, py, pz)
                    if d <= reach:
                        if h == 0:
                            return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
                        kind = near_kind(T, t, px, py, pz, d, h, reach, abs(det) <= tol * nlen[t])
                        if kind == NEAR:
                            if nnear == near.shape[0]:
                                return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
                            near[nnear] = t
                            nnear += 1
                            continue
                        if kind == CROSSING:
                            if ncross == cross.shape[0]:
                                return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
                            cross[ncross] = t
                            ncross += 1
            zx, zy, turns = _solid_angle_step(ax, ay, az, bx, by, bz, cx, cy, cz, zx, zy, turns)
            if h > 0:
                for e in range(owner[t], owner[t + 1]):
                    add_edge(grad, E, e, 1, px, py, pz, h)  # the cap's boundary runs against the chain
    if h > 0 and nnear:
        cut_edges(px, py, pz, h, T, E, owner, near, nnear, edges, grad)
    hess = grad[3]
    if not hess < math.inf:  # NaN: an edge of the far part within h (rounding); let the caller split
        return 0.0, 0.0, 0.0, 0.0, HIT, 0, 0
    inv4pi = 1.0 / (4.0 * math.pi)
    w = (2.0 * (math.atan2(zy, zx) + 2.0 * math.pi * turns) + far) * inv4pi
    for d in range(3):
        grad[d] *= GRAD_SIGN * inv4pi
    return w, err * inv4pi, var * h * inv4pi, hess * inv4pi, CLEAR, nnear, ncross


@njit(cache=True, nogil=True)
def _holds_own_boundary(T, E, owner, t):
    """Whether the chain edges that cap triangle t holds are its own three
    edges, each reversed (a face of a soup, held by its cap reversed): then
    they cancel its boundary in :func:`cut_edges`."""
    if owner[t + 1] - owner[t] != 3:
        return False
    for k in range(3):
        k1 = (k + 1) % 3
        found = False
        for e in range(owner[t], owner[t + 1]):
            if (E[e, 0, 0] == T[t, k1, 0] and E[e, 0, 1] == T[t, k1, 1] and E[e, 0, 2] == T[t, k1, 2]
                    and E[e, 1, 0] == T[t, k, 0] and E[e, 1, 1] == T[t, k, 1] and E[e, 1, 2] == T[t, k, 2]):
                found = True
        if not found:
            return False
    return True


@njit(cache=True, nogil=True)
def near_kind(T, t, px, py, pz, d, h, reach, on_plane):
    """A triangle within ``reach`` of p (at distance d): :data:`NEAR` if an
    edge is within reach (or p is on its plane), :data:`CROSSING` if it
    meets the ball of radius h, else :data:`FAR`."""
    if on_plane:
        return NEAR
    for k in range(3):
        k1 = (k + 1) % 3
        if dist_segment(T[t, k, 0], T[t, k, 1], T[t, k, 2], T[t, k1, 0], T[t, k1, 1], T[t, k1, 2],
                        px, py, pz) <= reach:
            return NEAR
    return CROSSING if d <= h else FAR


@njit(cache=True, nogil=True)
def cut_edges(px, py, pz, h, T, E, owner, near, nnear, edges, acc):
    """The far part's boundary edges that come from the near triangles:
    the chain edges they hold (reversed, as in the cap's boundary) minus
    their own boundaries, opposite copies cancelled (equal coordinates:
    every edge is built from the same vertex positions).  Returns their
    Biot-Savart sum and derivative bound, as :func:`_edge_terms`."""
    n = 0
    for q in range(nnear):
        t = near[q]
        if _holds_own_boundary(T, E, owner, t):  # its six edges cancel among themselves
            continue
        if n + owner[t + 1] - owner[t] + 3 > edges.shape[0]:
            acc[3] = math.nan  # more than the scratch holds: the caller splits
            return
        for e in range(owner[t], owner[t + 1]):
            for d in range(3):
                edges[n, 0, d] = E[e, 1, d]
                edges[n, 1, d] = E[e, 0, d]
            n += 1
        for k in range(3):  # minus the triangle's boundary: its edges reversed
            k1 = (k + 1) % 3
            for d in range(3):
                edges[n, 0, d] = T[t, k1, d]
                edges[n, 1, d] = T[t, k, d]
            n += 1
    alive = np.ones(n, dtype=np.bool_)
    for a in range(n):
        if not alive[a]:
            continue
        for b in range(a + 1, n):
            if alive[b] and _same(edges, a, 0, b, 1) and _same(edges, a, 1, b, 0):
                alive[a] = False
                alive[b] = False
                break
    for a in range(n):
        if alive[a]:
            add_edge(acc, edges, a, 0, px, py, pz, h)


@njit(cache=True, nogil=True, inline="always")
def _same(edges, a, i, b, j):
    return (edges[a, i, 0] == edges[b, j, 0] and edges[a, i, 1] == edges[b, j, 1]
            and edges[a, i, 2] == edges[b, j, 2])


@njit(cache=True, nogil=True)
def near_sum(T, nlen, near, nnear, cross, ncross, qx, qy, qz, px, py, pz, tol):
    """The winding number at p of the triangles ``near[:nnear]`` plus the
    jumps of ``cross[:ncross]`` between q and p (see :func:`evaluate`), and
    whether p lies within ``tol`` of one of them."""
    jumps = 0
    for c in range(ncross):
        t = cross[c]
        ux, uy, uz = T[t, 1, 0] - T[t, 0, 0], T[t, 1, 1] - T[t, 0, 1], T[t, 1, 2] - T[t, 0, 2]
        vx, vy, vz = T[t, 2, 0] - T[t, 0, 0], T[t, 2, 1] - T[t, 0, 1], T[t, 2, 2] - T[t, 0, 2]
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        sp = (px - T[t, 0, 0]) * nx + (py - T[t, 0, 1]) * ny + (pz - T[t, 0, 2]) * nz
        sq = (qx - T[t, 0, 0]) * nx + (qy - T[t, 0, 1]) * ny + (qz - T[t, 0, 2]) * nz
        if abs(sp) <= tol * nlen[t]:
            return 0.0, True
        if (sp > 0) != (sq > 0):  # w_t = -s / 2 + a continuous part
            jumps += 1 if sq > 0 else -1
    zx, zy, turns = 1.0, 0.0, 0
    for q in range(nnear):
        t = near[q]
        ax, ay, az = T[t, 0, 0] - px, T[t, 0, 1] - py, T[t, 0, 2] - pz
        bx, by, bz = T[t, 1, 0] - px, T[t, 1, 1] - py, T[t, 1, 2] - pz
        cx, cy, cz = T[t, 2, 0] - px, T[t, 2, 1] - py, T[t, 2, 2] - pz
        det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        if abs(det) <= tol * nlen[t] and dist_triangle(T, t, px, py, pz) <= tol:
            return 0.0, True
        zx, zy, turns = _solid_angle_step(ax, ay, az, bx, by, bz, cx, cy, cz, zx, zy, turns)
    return jumps + (math.atan2(zy, zx) + 2.0 * math.pi * turns) / (2.0 * math.pi), False


@njit(cache=True, nogil=True)
def near_range(T, near, nnear, px, py, pz, h):
    """The near triangles' winding number at p and a bound on its variation
    over the ball of radius h around p (``h / 4pi sum_edges len / (d -
    h)^2``, their gradient being the Biot-Savart field of their edges), or
    ``ok = False`` where one of them meets the ball (the sum jumps there).
    Lets a block near a cap's edge be decided as a whole when it is far
    from the 1/2 level set."""
    zx, zy, turns = 1.0, 0.0, 0
    var = 0.0
    for q in range(nnear):
        t = near[q]
        if dist_triangle(T, t, px, py, pz) <= h:
            return 0.0, 0.0, False
        for k in range(3):
            k1 = (k + 1) % 3
            d = dist_segment(T[t, k, 0], T[t, k, 1], T[t, k, 2], T[t, k1, 0], T[t, k1, 1], T[t, k1, 2], px, py, pz) - h
            ex, ey, ez = T[t, k1, 0] - T[t, k, 0], T[t, k1, 1] - T[t, k, 1], T[t, k1, 2] - T[t, k, 2]
            var += math.sqrt(ex * ex + ey * ey + ez * ez) / (d * d)
        zx, zy, turns = _solid_angle_step(T[t, 0, 0] - px, T[t, 0, 1] - py, T[t, 0, 2] - pz, T[t, 1, 0] - px,
                                          T[t, 1, 1] - py, T[t, 1, 2] - pz, T[t, 2, 0] - px, T[t, 2, 1] - py,
                                          T[t, 2, 2] - pz, zx, zy, turns)
    w = (math.atan2(zy, zx) + 2.0 * math.pi * turns) / (2.0 * math.pi)
    return w, var * h / (4.0 * math.pi), True
