"""The shell of a triangle mesh: every voxel whose closed cube the surface
meets, decided exactly.

This is the conservative surface voxelisation of the literature (the voxels
a surface touches; 26-separating: no 26-path of background voxels crosses
the surface, Schwarz and Seidel 2010).  A voxel is in iff its closed cube
and some closed triangle of the mesh have a point in common, so the tie
rule is "touching counts": a face lying in a plane between two layers of
voxels marks both layers, an edge on a line where four voxels meet marks
all four, a vertex on a grid corner all eight.  The cubes are those of
:mod:`isoflow.mesh.grid`, their faces the planes ``origin + pitch * i`` as
floating-point numbers (two neighbours share one plane, so the cubes tile
the grid without gap or overlap).

Exactness
---------
A closed triangle and a closed box are disjoint iff one of thirteen axes
separates them (the separating axis theorem; Akenine-Moeller 2001): the
three box normals, the triangle's normal, and the nine products of a
triangle edge with a box axis.  The box normals are comparisons of
coordinates.  The triangle's normal separates iff the two box corners
furthest along it and against it lie strictly on one side of its plane, an
``orient3d`` sign; each of the nine others is the separation of the
triangle's and the box's projections on a coordinate plane by the line
through a projected edge, an ``orient2d`` sign at the corner of the
projected box nearest that line (its choice depends only on the signs of
the edge's coordinate differences, which floating point gets right).  Each
sign is first computed in floating point with Shewchuk's error bound
(1997) and, where that cannot decide, exactly, as a sum of non-overlapping
floating-point expansions; an edge parallel to an axis and a face parallel
to a coordinate plane are decided by exact comparisons.  So the shell is
exact for any floating-point input whose products do not underflow (the
voxeliser's scaled frame brings the mesh to about unit size).

Work
----
Each triangle visits the columns of its projection on the coordinate plane
most nearly parallel to it; in each column that its projection meets, only
the few voxels near its plane are tested (the plane rises by at most two
voxels across a column), or, for a sliver whose plane is ill-defined in
floating point, the voxels of its whole range in that column.  Work is
proportional to the area in voxels plus the triangles, not to the grid.
What a triangle shares between its columns is computed once: the chords of
its projection on the lines between columns (a row's lower line is the
last row's upper one), the plane's slopes, the corners in a row's strip.
A span's end is placed among the planes from its position alone where a
guard (the rounding of the planes and of the position, bounded) leaves no
plane within the margin.  The voxels a triangle's columns hold are gathered
as runs, their first cache lines fetched, and set together: the volume's
misses then overlap instead of waiting behind each column's arithmetic.

The helpers are numba functions of their own, not inlined into the loop by
numba (``inline="always"``): numba types every inlined copy again, which
made the shell's first compile, a user's first wait, about half as long
again, and the fill measured the same speed without it
(``benchmarks/bench_shell_ab.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ..scale.jit import njit
from ..scale.prefetch import prefetch_write

_EPS = 2.0**-53
#: Shewchuk's static bounds: |det| beyond them decides the sign
_CCW_BOUND = (3.0 + 16.0 * _EPS) * _EPS
_O3D_BOUND = (7.0 + 56.0 * _EPS) * _EPS
_SPLITTER = 134217729.0  # 2**27 + 1
#: a triangle whose plane is this ill-conditioned (|e1| |e2| / |n_w|) is a
#: sliver: its voxels per column are taken from its whole range
_SLIVER = 2.0**20
#: the heights of a triangle over a column, in floating point, are within
#: this many units of rounding (times the plane's condition and the
#: coordinates' size) of the true ones: a generous multiple of the few
#: roundings each takes, on a plane whose slope is at most 1
_SPAN_ERROR = 2.0**10


# ---------------------------------------------------------------------------
# exact arithmetic: floating-point expansions (Shewchuk 1997)
# ---------------------------------------------------------------------------

@njit(cache=True, nogil=True)
def _two_sum(a, b):
    x = a + b
    bv = x - a
    av = x - bv
    return x, (a - av) + (b - bv)


@njit(cache=True, nogil=True)
def _split(a):
    c = _SPLITTER * a
    hi = c - (c - a)
    return hi, a - hi


@njit(cache=True, nogil=True)
def _two_product(a, b):
    x = a * b
    ahi, alo = _split(a)
    bhi, blo = _split(b)
    err = x - ahi * bhi
    err -= alo * bhi
    err -= ahi * blo
    return x, alo * blo - err


@njit(cache=True, nogil=True)
def _grow(e, n, b):
    """Add ``b`` to the expansion ``e[:n]`` in place (Grow-Expansion, zeros
    dropped); returns its new length."""
    q = b
    m = 0
    for i in range(n):
        q, h = _two_sum(q, e[i])
        if h != 0.0:
            e[m] = h
            m += 1
    e[m] = q
    return m + 1


@njit(cache=True, nogil=True)
def _add_product(e, n, x, y, sign):
    """``e += sign * x * y`` for 2-component expansions x, y (exact)."""
    for i in range(2):
        for j in range(2):
            p, q = _two_product(x[i], y[j])
            n = _grow(e, n, sign * q)
            n = _grow(e, n, sign * p)
    return n


@njit(cache=True, nogil=True)
def _expansion_sign(e, n):
    for i in range(n - 1, -1, -1):
        if e[i] > 0.0:
            return 1
        if e[i] < 0.0:
            return -1
    return 0


@njit(cache=True, nogil=True)
def _diff(a, b, out):
    """``a - b`` exactly as a 2-component expansion (low part first)."""
    x = a - b
    bv = a - x
    av = x + bv
    out[0] = (a - av) + (bv - b)
    out[1] = x


@njit(cache=True, nogil=True)
def _orient2d_exact(au, av, bu, bv, cu, cv):
    """sign of (b - a) x (c - a), exactly."""
    d = np.empty((4, 2))
    _diff(bu, au, d[0])
    _diff(cv, av, d[1])
    _diff(bv, av, d[2])
    _diff(cu, au, d[3])
    e = np.empty(64)
    n = np.int64(1)  # not the literal 1: numba would compile the helpers once more for it
    e[0] = 0.0
    n = _add_product(e, n, d[0], d[1], 1.0)
    n = _add_product(e, n, d[2], d[3], -1.0)
    return _expansion_sign(e, n)


@njit(cache=True, nogil=True)
def orient2d(au, av, bu, bv, cu, cv):
    """Sign of ``(b - a) x (c - a)`` (+1: c left of a -> b), exact."""
    if au == bu:  # an edge parallel to an axis: a product of two exact signs
        return -_sgn(bv - av) * _sgn(cu - au)
    if av == bv:
        return _sgn(bu - au) * _sgn(cv - av)
    lhs = (bu - au) * (cv - av)
    rhs = (bv - av) * (cu - au)
    det = lhs - rhs
    bound = _CCW_BOUND * (abs(lhs) + abs(rhs))
    if det > bound:
        return 1
    if -det > bound:
        return -1
    return _orient2d_exact(au, av, bu, bv, cu, cv)


@njit(cache=True, nogil=True)
def _sgn(x):
    return 1 if x > 0 else (-1 if x < 0 else 0)


@njit(cache=True, nogil=True)
def _add_triple(e, n, a, b, c, sign):
    """``e += sign * a * b * c`` exactly (four floats)."""
    p, q = _two_product(a, b)
    r1, r2 = _two_product(p, c)
    r3, r4 = _two_product(q, c)
    n = _grow(e, n, sign * r4)
    n = _grow(e, n, sign * r3)
    n = _grow(e, n, sign * r2)
    return _grow(e, n, sign * r1)


@njit(cache=True, nogil=True)
def _side_exact(T, t, dx, dy, dz):
    """sign of ((b - a) x (c - a)) . (d - a) for triangle t = (a, b, c), exactly."""
    d = np.empty((9, 2))
    for k in range(3):
        _diff(T[t, 1, k], T[t, 0, k], d[k])
        _diff(T[t, 2, k], T[t, 0, k], d[3 + k])
    _diff(dx, T[t, 0, 0], d[6])
    _diff(dy, T[t, 0, 1], d[7])
    _diff(dz, T[t, 0, 2], d[8])
    e = np.empty(800)
    e[0] = 0.0
    n = np.int64(1)
    # u . (v x w) with u = b - a, v = c - a, w = d - a
    for (i, j, k, sg) in ((0, 4, 8, 1.0), (0, 5, 7, -1.0), (1, 5, 6, 1.0), (1, 3, 8, -1.0),
                          (2, 3, 7, 1.0), (2, 4, 6, -1.0)):
        for x in range(2):
            for y in range(2):
                for z in range(2):
                    n = _add_triple(e, n, d[i, x], d[j, y], d[k, z], sg)
    return _expansion_sign(e, n)


@njit(cache=True, nogil=True)
def side(T, t, dx, dy, dz):
    """Which side of triangle t's plane the point d lies on: the sign of
    ``((b - a) x (c - a)) . (d - a)`` (+1: the side its normal points to),
    exact."""
    ax, ay, az = T[t, 0, 0], T[t, 0, 1], T[t, 0, 2]
    for w in range(3):  # a face parallel to a coordinate plane: exact comparisons
        if T[t, 0, w] == T[t, 1, w] and T[t, 0, w] == T[t, 2, w]:
            u, v = (w + 1) % 3, (w + 2) % 3
            s = orient2d(T[t, 0, u], T[t, 0, v], T[t, 1, u], T[t, 1, v], T[t, 2, u], T[t, 2, v])
            dw = dx if w == 0 else (dy if w == 1 else dz)
            return s * _sgn(dw - T[t, 0, w])
    ux, uy, uz = T[t, 1, 0] - ax, T[t, 1, 1] - ay, T[t, 1, 2] - az
    vx, vy, vz = T[t, 2, 0] - ax, T[t, 2, 1] - ay, T[t, 2, 2] - az
    wx, wy, wz = dx - ax, dy - ay, dz - az
    m0, m1 = vy * wz, vz * wy
    m2, m3 = vz * wx, vx * wz
    m4, m5 = vx * wy, vy * wx
    det = ux * (m0 - m1) + uy * (m2 - m3) + uz * (m4 - m5)
    perm = abs(ux) * (abs(m0) + abs(m1)) + abs(uy) * (abs(m2) + abs(m3)) + abs(uz) * (abs(m4) + abs(m5))
    bound = _O3D_BOUND * perm
    if det > bound:
        return 1
    if -det > bound:
        return -1
    return _side_exact(T, t, dx, dy, dz)


# ---------------------------------------------------------------------------
# the separating axes
# ---------------------------------------------------------------------------

@njit(cache=True, nogil=True)
def _edge_sign(T, t, p, k, coef, bnd, cu, cv):
    """Sign of ``orient2d`` of edge k of triangle t, projected on the plane
    p (the coordinate plane (p+1, p+2)), at (cu, cv): the edge's affine
    function in floating point where its error bound decides, else exact."""
    val = coef[p, k, 0] * cu + coef[p, k, 1] * cv + coef[p, k, 2]
    if val > bnd[p, k]:
        return 1
    if val < -bnd[p, k]:
        return -1
    u, v = (p + 1) % 3, (p + 2) % 3
    k2 = (k + 1) % 3
    return orient2d(T[t, k, u], T[t, k, v], T[t, k2, u], T[t, k2, v], cu, cv)


@njit(cache=True, nogil=True)
def _projection_separated(T, t, p, S, coef, bnd, u0, u1, v0, v1):
    """Whether a line through an edge of triangle t, projected on the plane
    p, separates it from the rectangle [u0, u1] x [v0, v1].  ``S`` is the
    sign of the projection's orientation (0: a segment or a point, which
    any side of its line may hold).  The corners tested are those farthest
    along and against the edge's normal, chosen by the exact signs of its
    coefficients."""
    for k in range(3):
        A, B = coef[p, k, 0], coef[p, k, 1]
        if A == 0.0 and B == 0.0:  # the edge projects to a point
            continue
        if S >= 0 and _edge_sign(T, t, p, k, coef, bnd, u1 if A > 0 else u0, v1 if B > 0 else v0) < 0:
            return True  # every corner strictly outside this edge
        if S <= 0 and _edge_sign(T, t, p, k, coef, bnd, u0 if A > 0 else u1, v0 if B > 0 else v1) > 0:
            return True
    return False


@njit(cache=True, nogil=True)
def _plane_separated(T, t, s, plane, c0, c1):
    """Whether triangle t's plane has the box [c0, c1] strictly on one side
    (``s``: the exact signs of its normal's components, all 0 for a
    degenerate triangle, which has no plane; ``plane``: the normal in
    floating point, its offset and the error bound of n . c + d)."""
    if s[0] == 0 and s[1] == 0 and s[2] == 0:
        return False
    hx = c1[0] if s[0] > 0 else c0[0]
    hy = c1[1] if s[1] > 0 else c0[1]
    hz = c1[2] if s[2] > 0 else c0[2]
    val = plane[0] * hx + plane[1] * hy + plane[2] * hz + plane[3]
    if val < -plane[4] or (val <= plane[4] and side(T, t, hx, hy, hz) < 0):
        return True
    lx = c0[0] if s[0] > 0 else c1[0]
    ly = c0[1] if s[1] > 0 else c1[1]
    lz = c0[2] if s[2] > 0 else c1[2]
    val = plane[0] * lx + plane[1] * ly + plane[2] * lz + plane[3]
    return val > plane[4] or (val >= -plane[4] and side(T, t, lx, ly, lz) > 0)


@njit(cache=True, nogil=True)
def _cut(S, bound, far, near, au, av, bu, bv, fu, fv, nu, nv):
    """Whether the line through a projected edge a -> b separates the
    projection (orientation sign S) from a rectangle whose corners farthest
    along and against the edge's normal are (fu, fv) and (nu, nv), where
    the edge's affine function is ``far`` and ``near`` in floating point
    (error below ``bound``; exact where that cannot decide).  Scalars only:
    where a helper that takes arrays calls out, numba keeps its arrays'
    reference counting in the caller's loop."""
    if S >= 0:
        sg = 1 if far > bound else (-1 if far < -bound else orient2d(au, av, bu, bv, fu, fv))
        if sg < 0:
            return True  # every corner strictly outside this edge
    if S <= 0:
        sg = 1 if near > bound else (-1 if near < -bound else orient2d(au, av, bu, bv, nu, nv))
        if sg > 0:
            return True
    return False


@njit(cache=True, nogil=True)
def _column_cut(T, t, u, v, w, S, coef, bnd, c0, c1):
    """:func:`_projection_separated` on the plane w for the column
    [c0[u], c1[u]] x [c0[v], c1[v]], its array reads here and its signs in
    :func:`_cut`."""
    for k in range(3):
        A, B = coef[w, k, 0], coef[w, k, 1]
        if A == 0.0 and B == 0.0:  # the edge projects to a point
            continue
        k2 = (k + 1) % 3
        fu, fv = (c1[u] if A > 0 else c0[u]), (c1[v] if B > 0 else c0[v])
        nu, nv = (c0[u] if A > 0 else c1[u]), (c0[v] if B > 0 else c1[v])
        if _cut(S, bnd[w, k], A * fu + B * fv + coef[w, k, 2], A * nu + B * nv + coef[w, k, 2],
                T[t, k, u], T[t, k, v], T[t, k2, u], T[t, k2, v], fu, fv, nu, nv):
            return True
    return False


@njit(cache=True, nogil=True)
def _separated(T, t, u, v, w, s, coef, bnd, plane, c0, c1):
    """Whether one of the thirteen axes separates triangle t from the box
    [c0, c1]: the box's own axes are the column and its voxel's extent."""
    return (_projection_separated(T, t, w, s[w], coef, bnd, c0[u], c1[u], c0[v], c1[v])
            or _projection_separated(T, t, u, s[u], coef, bnd, c0[v], c1[v], c0[w], c1[w])
            or _projection_separated(T, t, v, s[v], coef, bnd, c0[w], c1[w], c0[u], c1[u])
            or _plane_separated(T, t, s, plane, c0, c1))


# ---------------------------------------------------------------------------
# the shell
# ---------------------------------------------------------------------------

#: runs of voxels a triangle's columns hold, set together: the marking's
#: misses in the volume then overlap, away from the columns' arithmetic
_RUNS = 256


@njit(cache=True, nogil=True)
def _mark_runs(flat, run_at, run_len, m, step):
    """Set the voxels of runs ``0 .. m - 1`` of ``flat`` (run r: run_len[r]
    voxels from run_at[r], ``step`` apart); returns how many were not set
    yet (the shell's voxels are counted as they are found, not by reading
    the volume again)."""
    added = 0
    for r in range(m):
        at = run_at[r]
        for _ in range(run_len[r]):
            added += 1 - np.int64(flat[at])
            flat[at] = True
            at += step
    return added


@njit(cache=True, nogil=True)
def _planes_below(PL, a, n, x, strict, per_unit):
    """How many of the planes ``PL[a, :n + 1]`` are below x (at most x if
    not ``strict``): guessed from the even spacing (``per_unit`` planes per
    unit), then settled by comparing with the planes themselves (so exact
    however they round)."""
    if not x > PL[a, 0]:
        return 0 if (strict or not x == PL[a, 0]) else 1
    if not x < PL[a, n]:
        return n + 1 if (not strict or x > PL[a, n]) else n
    c = min(max(int((x - PL[a, 0]) * per_unit), 0), n)
    while c > 0 and not (PL[a, c - 1] < x or (not strict and PL[a, c - 1] == x)):
        c -= 1
    while c <= n and (PL[a, c] < x or (not strict and PL[a, c] == x)):
        c += 1
    return c


@njit(cache=True, nogil=True)
def _below_near(PL, a, n, x, m, strict, per_unit):
    """How many planes of axis a are below x - m and below x + m (at most,
    if not ``strict``): one search, then the planes within m of x."""
    c = _planes_below(PL, a, n, x, strict, per_unit)
    lo, hi = c, c
    while lo > 0 and (PL[a, lo - 1] > x - m or (strict and PL[a, lo - 1] == x - m)):
        lo -= 1
    while hi <= n and (PL[a, hi] < x + m or (not strict and PL[a, hi] == x + m)):
        hi += 1
    return lo, hi


@njit(cache=True, nogil=True)
def _near_count(PL, a, n, x, m, strict, per_unit):
    """:func:`_below_near`, found at once where no plane is within m of x
    (the common case: the planes on either side of the guess from the even
    spacing, ``per_unit`` planes per unit, are farther)."""
    c = int((x - PL[a, 0]) * per_unit)
    if 0 <= c < n and PL[a, c] < x - m and PL[a, c + 1] > x + m:
        return c + 1, c + 1
    return _below_near(PL, a, n, x, m, strict, per_unit)


@njit(cache=True, nogil=True)
def _place(x, x0, per_unit, n, guard):
    """How many of n + 1 evenly spaced planes (the first at x0,
    ``per_unit`` a unit) are below x - m and below x + m, both, where
    ``guard`` (:func:`_guard`) tells that no plane is within m of x; -1
    where that is not sure (then :func:`_near_count` compares)."""
    f = (x - x0) * per_unit
    c = int(f)
    if 0 <= c < n and guard < f - c < 1.0 - guard:  # f - c is exact (Sterbenz)
        return c + 1
    return -1


@njit(cache=True, nogil=True)
def _guard(m, scale, per_unit, n):
    """How far from a whole number x's place among n + 1 planes must be
    (in units of their spacing) for no plane to lie within m of x.  The
    planes ``origin + pitch * i`` are each rounded by at most 4 eps scale,
    ``per_unit`` (n over the planes' span) is 1 / pitch within 3 eps plus
    8 eps scale per unit, and x's place is rounded twice: together less
    than (m + 18 eps scale) per_unit + 3 eps n, doubled and more here."""
    return (m + 64.0 * _EPS * (scale + 1.0)) * per_unit + 64.0 * _EPS * n


@njit(cache=True, nogil=True)
def _range(PL, a, n, lo, hi, k_min, k_max, per_unit):
    """Voxels [k0, k1) of axis a (n voxels, planes ``PL[a]``, ``per_unit``
    planes per unit) whose closed extent meets [lo, hi], within
    [k_min, k_max)."""
    k0 = max(_planes_below(PL, a, n, lo, True, per_unit) - 1, k_min)
    k1 = min(_planes_below(PL, a, n, hi, False, per_unit), k_max)
    return k0, k1


@njit(cache=True, nogil=True)
def _set_up(T, t, scale, s, n, coef, bnd, plane):
    """Triangle t's exact normal signs ``s``, its normal ``n`` in floating
    point, and the affine functions of its projected edges and of its
    plane with their error bounds (the coordinates are at most ``scale`` in
    magnitude; each bound is 16 times the rounding error of evaluating the
    function at such a point, which keeps every sign it decides exact)."""
    for p in range(3):
        u, v = (p + 1) % 3, (p + 2) % 3
        s[p] = orient2d(T[t, 0, u], T[t, 0, v], T[t, 1, u], T[t, 1, v], T[t, 2, u], T[t, 2, v])
        for k in range(3):
            k2 = (k + 1) % 3
            A = -(T[t, k2, v] - T[t, k, v])  # orient2d(a, b, c) = A cu + B cv + C
            B = T[t, k2, u] - T[t, k, u]
            coef[p, k, 0] = A
            coef[p, k, 1] = B
            coef[p, k, 2] = -(A * T[t, k, u] + B * T[t, k, v])
            bnd[p, k] = 16.0 * _EPS * (abs(A) + abs(B)) * 2.0 * scale
    ux, uy, uz = T[t, 1, 0] - T[t, 0, 0], T[t, 1, 1] - T[t, 0, 1], T[t, 1, 2] - T[t, 0, 2]
    vx, vy, vz = T[t, 2, 0] - T[t, 0, 0], T[t, 2, 1] - T[t, 0, 1], T[t, 2, 2] - T[t, 0, 2]
    n[0] = uy * vz - uz * vy
    n[1] = uz * vx - ux * vz
    n[2] = ux * vy - uy * vx
    plane[0], plane[1], plane[2] = n[0], n[1], n[2]
    plane[3] = -(n[0] * T[t, 0, 0] + n[1] * T[t, 0, 1] + n[2] * T[t, 0, 2])
    norms = math.sqrt((ux * ux + uy * uy + uz * uz) * (vx * vx + vy * vy + vz * vz))
    plane[4] = 16.0 * _EPS * (abs(n[0]) + abs(n[1]) + abs(n[2]) + 6.0 * norms) * 2.0 * scale
    return norms


@njit(cache=True, nogil=True)
def _plane_span(h0, ou, ov, su, sv, u0, u1, v0, v1):
    """Least and greatest height of the plane ``h0 + su (u - ou) + sv (v -
    ov)`` over the column [u0, u1] x [v0, v1], in floating point: at two of
    its corners."""
    h = h0 + su * (u0 - ou) + sv * (v0 - ov)
    du, dv = su * (u1 - u0), sv * (v1 - v0)
    return h + min(du, 0.0) + min(dv, 0.0), h + max(du, 0.0) + max(dv, 0.0)


@njit(cache=True, nogil=True)
def _side_span(lo, hi, side_lo, side_hi, base, slope, o, zl, zh):
    """``(zl, zh)`` widened by the heights of a triangle's plane at the ends
    of the chord [lo, hi] (the triangle along a side of a column) clipped to
    the side [side_lo, side_hi]; along the side, the plane's height at x is
    ``base + slope * (x - o)``."""
    a, b = max(lo, side_lo), min(hi, side_hi)
    if a <= b:
        za, zb = base + slope * (a - o), base + slope * (b - o)
        zl, zh = min(zl, za, zb), max(zh, za, zb)
    return zl, zh


@njit(cache=True, nogil=True)
def _inverse_slopes(T, t, u, v, out):
    """``out[k]``: how far u moves along edge k of triangle t (corner k to
    corner k + 1) per unit of v (0 where the edge keeps v)."""
    for k in range(3):
        k2 = (k + 1) % 3
        dv = T[t, k2, v] - T[t, k, v]
        out[k] = (T[t, k2, u] - T[t, k, u]) / dv if dv != 0.0 else 0.0


@njit(cache=True, nogil=True)
def _line_extent(T, t, u, v, c, slopes):
    """Where the line v = c meets triangle t projected on the axes (u, v):
    its least and greatest u, in floating point ((inf, -inf) if it misses);
    ``slopes`` are the edges' :func:`_inverse_slopes`."""
    lo, hi = np.inf, -np.inf
    for k in range(3):
        au, av = T[t, k, u], T[t, k, v]
        if av == c:
            lo, hi = min(lo, au), max(hi, au)
        bv = T[t, (k + 1) % 3, v]
        if (av < c < bv) or (bv < c < av):
            x = au + (c - av) * slopes[k]
            lo, hi = min(lo, x), max(hi, x)
    return lo, hi


@njit(cache=True, nogil=True)
def _shell(T, tri, PL, nv, xa, xb, scale, out, stop):
    """Mark in ``out`` (rows [xa, xb) of the grid) the voxels that
    triangles ``tri`` meet; ``PL[a, :nv[a] + 1]`` are the planes between
    voxels along axis a, ``scale`` bounds the coordinates' magnitude.
    Returns how many voxels were not set yet; ends early when ``stop[0]``
    is set."""
    s = np.empty(3, dtype=np.int64)
    lo = np.empty(3, dtype=np.int64)
    hi = np.empty(3, dtype=np.int64)
    c0 = np.empty(3)
    c1 = np.empty(3)
    corner_u = np.empty(3)
    corner_w = np.empty(3)
    n = np.empty(3)
    coef = np.empty((3, 3, 3))
    bnd = np.empty((3, 3))
    plane = np.empty(5)
    g = np.empty(3)
    # the chords of the lines u = PL[u, i] (their least and greatest v) and
    # the plane's height where each line meets v = T[t, 0, v]: one triangle's
    cl = np.empty(PL.shape[1])
    ch = np.empty(PL.shape[1])
    cb = np.empty(PL.shape[1])
    du_dv = np.empty(3)  # the edges' inverse slopes, both ways
    dv_du = np.empty(3)
    flat = out.reshape(-1)
    stride = np.array([out.shape[1] * out.shape[2], out.shape[2], 1])
    run_at = np.empty(_RUNS, dtype=np.int64)
    run_len = np.empty(_RUNS, dtype=np.int64)
    m = np.int64(0)  # not the literal 0 (nor w below): numba would compile the callees once more for it
    for a in range(3):  # planes per unit along each axis: where a search starts
        g[a] = nv[a] / (PL[a, nv[a]] - PL[a, 0])
    added = 0
    for q in range(len(tri)):
        if stop[0]:
            break
        t = tri[q]
        empty = False
        for a in range(3):
            mn = min(T[t, 0, a], T[t, 1, a], T[t, 2, a])
            mx = max(T[t, 0, a], T[t, 1, a], T[t, 2, a])
            lo[a], hi[a] = _range(PL, a, nv[a], mn, mx, xa if a == 0 else 0, xb if a == 0 else nv[a], g[a])
            empty = empty or lo[a] >= hi[a]
        if empty:
            continue
        norms = _set_up(T, t, scale, s, n, coef, bnd, plane)
        w = np.int64(0)
        for a in range(1, 3):
            if abs(n[a]) > abs(n[w]):
                w = a
        u, v = (w + 1) % 3, (w + 2) % 3
        gu, gw = g[u], g[w]
        step = stride[w]
        cond = norms / abs(n[w]) if n[w] != 0 else np.inf
        sliver = not cond < _SLIVER
        margin = _SPAN_ERROR * _EPS * cond * (scale + 1.0)
        reach = _SPAN_ERROR * _EPS * (scale + 1.0)  # the rounding of a projection's extent
        h0, ou, ov = T[t, 0, w], T[t, 0, u], T[t, 0, v]
        pw0, guard = PL[w, 0], _guard(margin, scale, gw, nv[w])
        su = sv = 0.0
        _inverse_slopes(T, t, u, v, du_dv)
        if not sliver:  # the plane's slopes, and the u lines' chords (shared by the rows)
            su, sv = -n[u] / n[w], -n[v] / n[w]
            _inverse_slopes(T, t, v, u, dv_du)
            for i in range(lo[u], hi[u] + 1):
                cl[i], ch[i] = _line_extent(T, t, v, u, PL[u, i], dv_du)
                cb[i] = h0 + su * (PL[u, i] - ou)
        a1, b1 = _line_extent(T, t, u, v, PL[v, lo[v]], du_dv)  # the chord on the first row's lower line
        for iv in range(lo[v], hi[v]):
            c0[v], c1[v] = PL[v, iv], PL[v, iv + 1]
            row = iv * stride[v] - xa * stride[0]  # where the row's voxels 0 along u and w lie in flat
            # the corners in the strip, their u and w
            nc = 0
            for k in range(3):
                if c0[v] <= T[t, k, v] <= c1[v]:
                    corner_u[nc], corner_w[nc] = T[t, k, u], T[t, k, w]
                    nc += 1
            # The columns of this row that meet the projection are those
            # whose u-range meets its extent in the strip (a convex set's
            # shadow is an interval), and those strictly inside both of the
            # strip's lines' chords lie inside it whole; both extents are
            # rounded by less than reach, and only the columns within reach
            # of an end are tested.
            a0, b0 = a1, b1  # the last row's upper line
            a1, b1 = _line_extent(T, t, u, v, c1[v], du_dv)
            ul, uh = min(a0, a1), max(b0, b1)
            for k in range(nc):
                ul, uh = min(ul, corner_u[k]), max(uh, corner_u[k])
            if ul <= uh:  # the planes below ul -+ reach, and at most uh -+ reach
                below0, below1 = _near_count(PL, u, nv[u], ul, reach, True, gu)
                above0, above1 = _near_count(PL, u, nv[u], uh, reach, False, gu)
                iu0, met0 = max(below0 - 1, lo[u]), max(below1 - 1, lo[u])
                met1, iu1 = min(above0, hi[u]), min(above1, hi[u])
            else:  # rounding found nothing: every column of the box, tested
                iu0, iu1, met0, met1 = lo[u], hi[u], hi[u], lo[u]
            in0 = _planes_below(PL, u, nv[u], max(a0, a1) + reach, True, gu)
            in1 = _planes_below(PL, u, nv[u], min(b0, b1) - reach, False, gu) - 1
            b0v, b1v = h0 + sv * (c0[v] - ov), h0 + sv * (c1[v] - ov)  # the heights along v = c0[v], c1[v]
            for iu in range(iu0, iu1):
                u0, u1 = PL[u, iu], PL[u, iu + 1]
                c0[u], c1[u] = u0, u1
                if not met0 <= iu < met1 and _column_cut(T, t, u, v, w, s[w], coef, bnd, c0, c1):
                    continue
                k0, k1 = lo[w], hi[w]
                sure0, sure1 = k1, k0  # the voxels [sure0, sure1) are in without a test
                if not sliver:  # the span of heights over this column, rounded by less than margin
                    if in0 <= iu < in1:  # inside the projection: the plane over the column
                        zl, zh = _plane_span(h0, ou, ov, su, sv, u0, u1, c0[v], c1[v])
                    else:  # the heights at the corners of the polygon column and triangle share
                        zl, zh = np.inf, -np.inf
                        for k in range(nc):
                            if u0 <= corner_u[k] <= u1:
                                zl, zh = min(zl, corner_w[k]), max(zh, corner_w[k])
                        zl, zh = _side_span(a0, b0, u0, u1, b0v, su, ou, zl, zh)
                        zl, zh = _side_span(a1, b1, u0, u1, b1v, su, ou, zl, zh)
                        zl, zh = _side_span(cl[iu], ch[iu], c0[v], c1[v], cb[iu], sv, ov, zl, zh)
                        zl, zh = _side_span(cl[iu + 1], ch[iu + 1], c0[v], c1[v], cb[iu + 1], sv, ov, zl, zh)
                    if zl <= zh:
                        # in: every voxel whose extent meets [Zl, Zh], the
                        # true span (the polygon is connected, so it takes
                        # every height between); decided where the rounded
                        # span leaves no doubt, tested where a plane between
                        # voxels is within margin of one of its ends
                        below_lo = sure0 = _place(zl, pw0, gw, nv[w], guard)
                        if below_lo < 0:
                            below_lo, sure0 = _near_count(PL, w, nv[w], zl, margin, True, gw)
                        sure1 = above_hi = _place(zh, pw0, gw, nv[w], guard)
                        if sure1 < 0:
                            sure1, above_hi = _near_count(PL, w, nv[w], zh, margin, False, gw)
                        k0, k1 = max(below_lo - 1, lo[w]), min(above_hi, hi[w])
                        sure0, sure1 = max(sure0 - 1, lo[w]), min(sure1, hi[w])
                base = row + iu * stride[u]
                k = k0
                while k < k1:  # runs [k - n_run, k)
                    if k == sure0 and sure0 < sure1:  # the voxels in without a test: one run
                        k, n_run = sure1, sure1 - sure0
                    else:  # a voxel near an end of the span, tested
                        c0[w], c1[w] = PL[w, k], PL[w, k + 1]
                        k, n_run = k + 1, 1
                        if _separated(T, t, u, v, w, s, coef, bnd, plane, c0, c1):
                            continue
                    if m == _RUNS:
                        added += _mark_runs(flat, run_at, run_len, m, step)
                        m = np.int64(0)
                    run_at[m], run_len[m] = base + (k - n_run) * step, n_run
                    prefetch_write(flat, base + (k - n_run) * step)  # set with the triangle's other runs
                    m += 1
        added += _mark_runs(flat, run_at, run_len, m, step)
        m = np.int64(0)
    return added


@njit(cache=True, nogil=True)
def _area(T):
    total = 0.0
    for t in range(len(T)):
        ux, uy, uz = T[t, 1, 0] - T[t, 0, 0], T[t, 1, 1] - T[t, 0, 1], T[t, 1, 2] - T[t, 0, 2]
        vx, vy, vz = T[t, 2, 0] - T[t, 0, 0], T[t, 2, 1] - T[t, 0, 1], T[t, 2, 2] - T[t, 0, 2]
        total += math.sqrt((uy * vz - uz * vy) ** 2 + (uz * vx - ux * vz) ** 2 + (ux * vy - uy * vx) ** 2)
    return 0.5 * total


def surface_area(T: np.ndarray) -> float:
    """The total area of the triangles ``T`` (M, 3, 3), in one compiled
    pass (it decides, for every winding voxelisation, whether the thin
    note's shell is counted).

    Examples
    --------
    >>> surface_area(np.array([[[0, 0, 0], [2, 0, 0], [0, 1, 0]]], dtype=float))
    1.0
    """
    return float(_area(np.ascontiguousarray(T, dtype=np.float64)))


def grid_planes(origin, pitch: float, shape, start=(0, 0, 0)) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The planes between voxels along each axis, ``origin + pitch * i`` for
    i = start .. start + n (the cubes' faces, as floating-point numbers; a
    block of a larger grid gets that grid's planes)."""
    return tuple(np.asarray(origin[a] + pitch * np.arange(start[a], start[a] + shape[a] + 1), dtype=np.float64)
                 for a in range(3))


def fill_shell(T: np.ndarray, planes, xa: int, xb: int, out=None, threads: int = 1) -> np.ndarray:
    """The shell of the triangles ``T`` (M, 3, 3) on rows ``[xa, xb)`` of
    the grid whose planes between voxels are ``planes`` (:func:`grid_planes`).

    Parameters
    ----------
    T : float64 ndarray (M, 3, 3)
        Triangle corners, in the frame of the planes (any triangles:
        degenerate, overlapping, in any orientation).
    planes : three float64 ndarrays
        ``planes[a][i]`` is the lower face of voxel i along axis a.
    xa, xb : int
        The rows of the first axis to fill.
    out : bool ndarray (xb - xa, ny, nz), optional
        Filled in place (voxels are only set, never cleared).
    threads : int
        1 or 2 (the rows split in two halves filled at once; compiled code
        runs without the GIL).

    Returns
    -------
    bool ndarray (xb - xa, ny, nz)
        True where the voxel's closed cube meets a triangle.

    Raises
    ------
    Stopped
        When :data:`isoflow.scale.cancel.STOP` was set (a signal) before
        the shell was complete.

    Examples
    --------
    A triangle in the plane z = 1 between two layers of a 2 x 2 x 2 grid
    meets the closed cubes of both layers:

    >>> planes = grid_planes(np.zeros(3), 1.0, (2, 2, 2))
    >>> T = np.array([[[0.2, 0.2, 1.0], [0.8, 0.2, 1.0], [0.2, 0.8, 1.0]]])
    >>> fill_shell(T, planes, 0, 2)[:, :, :].sum(axis=(0, 1)).tolist()
    [1, 1]
    """
    if out is None:
        out = np.zeros((xb - xa,) + tuple(len(p) - 1 for p in planes[1:]), dtype=bool)
    ShellGrid(T, planes).fill(xa, xb, out, threads=threads)
    return out


@njit(cache=True, nogil=True)
def _spatial_order(T, bits):
    """The triangles in Morton (Z-curve) order of their centres on a grid of
    ``2**bits`` cells a side (a counting sort): neighbours follow each
    other, so the voxels they share are still in cache when the next one
    marks them (a voxel near an edge is reached from each triangle around
    it).
    Returns the order, each triangle's least and greatest first coordinate,
    and the largest magnitude of a coordinate."""
    m = len(T)
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    xmin, xmax = np.empty(m), np.empty(m)
    scale = 0.0
    for t in range(m):
        xmin[t] = min(T[t, 0, 0], T[t, 1, 0], T[t, 2, 0])
        xmax[t] = max(T[t, 0, 0], T[t, 1, 0], T[t, 2, 0])
        for a in range(3):
            c = (T[t, 0, a] + T[t, 1, a] + T[t, 2, a]) / 3.0
            lo[a], hi[a] = min(lo[a], c), max(hi[a], c)
            for k in range(3):
                scale = max(scale, abs(T[t, k, a]))
    span = max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2])
    f = ((1 << bits) - 1) / span if span > 0 else 0.0
    code = np.zeros(m, dtype=np.int64)
    for t in range(m):
        for a in range(3):
            q = int(((T[t, 0, a] + T[t, 1, a] + T[t, 2, a]) / 3.0 - lo[a]) * f)
            for b in range(bits):
                code[t] |= ((q >> b) & 1) << (3 * b + a)
    start = np.zeros((1 << (3 * bits)) + 1, dtype=np.int64)
    for t in range(m):
        start[code[t] + 1] += 1
    for c in range(1 << (3 * bits)):
        start[c + 1] += start[c]
    order = np.empty(m, dtype=np.int64)
    for t in range(m):
        order[start[code[t]]] = t
        start[code[t]] += 1
    return order, xmin[order], xmax[order], scale


class ShellGrid:
    """The triangles and the planes of a shell, set up once (O(triangles))
    for every slab that is filled from them; small and picklable, so dask
    can ship it to workers.

    ``T`` (M, 3, 3) are the triangles in the frame of ``planes``
    (:func:`grid_planes`), any triangles (degenerate, overlapping, in any
    orientation).
    """

    def __init__(self, T: np.ndarray, planes):
        T = np.ascontiguousarray(T, dtype=np.float64).reshape(-1, 3, 3)
        order, self.xmin, self.xmax, scale = _spatial_order(T, 5)
        self.T = T[order]
        self.nv = np.array([len(p) - 1 for p in planes], dtype=np.int64)
        self.x0 = np.asarray(planes[0], dtype=np.float64)
        self.PL = np.full((3, self.nv.max() + 1), np.nan)
        for a in range(3):
            self.PL[a, :self.nv[a] + 1] = planes[a]
        self.scale = float(max(scale, *(np.abs(p[[0, -1]]).max() for p in planes)))

    def fill(self, xa: int, xb: int, out: np.ndarray, threads: int = 1) -> int:
        """Set in ``out`` (bool (xb - xa, ny, nz)) the voxels of rows
        [xa, xb) that the triangles meet; returns how many were not set
        before (the shell's voxels, where ``out`` was all False).  With
        ``threads=2`` the rows are split in two halves filled at once; a
        signal (:data:`~isoflow.scale.cancel.STOP`) ends the work and
        raises :class:`~isoflow.scale.cancel.Stopped`."""
        from ..scale.cancel import STOP, Stopped, run_pieces

        if len(self.T) == 0 or xb <= xa:
            return 0
        if not out.flags.c_contiguous:  # the pass sets voxels by their place in the C-ordered volume
            work = np.ascontiguousarray(out)
            added = self.fill(xa, xb, work, threads=threads)
            out[...] = work
            return added
        mid = (xa + xb) // 2
        parts = [(xa, xb)] if threads <= 1 or xb - xa < 2 else [(xa, mid), (mid, xb)]
        added = [0] * len(parts)

        def run(i: int) -> None:  # each part its own rows: the threads never write the same memory
            a, b = parts[i]
            tri = np.nonzero((self.xmax >= self.x0[a]) & (self.xmin <= self.x0[b]))[0]  # the triangles that reach it
            added[i] = _shell(self.T, tri, self.PL, self.nv, a, b, self.scale, out[a - xa:b - xa], STOP)

        run_pieces(run, len(parts), threads=len(parts))  # off the main thread: a signal ends it
        if STOP[0]:
            raise Stopped
        return sum(added)
