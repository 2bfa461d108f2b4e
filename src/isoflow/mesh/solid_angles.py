"""The generalised winding number of many points over many triangles,
summed exactly, one triangle at a time over all the points, so that the
compiler runs the points in SIMD lanes.

Triangle t's solid angle at p is ``2 atan2(det, den)`` (van Oosterom and
Strackee 1983) with ``a, b, c`` its corners less p, ``det = a . (b x c)``
and ``den = |a||b||c| + (a.b)|c| + (b.c)|a| + (c.a)|b|``; the winding
number is the sum over the triangles over ``4 pi`` (Jacobson et al. 2013,
eq. 4).  Every operation here is one the vector units have (square roots,
one division, a polynomial): the arc tangent is written out rather than
called from the C library, which no compiler vectorises.

The arc tangent: with ``u = min(|y|, |x|) / max(|y|, |x|)``, and
``u' = (u - 1) / (u + 1)`` (``atan u = pi / 4 + atan u'``) where ``u >
tan(pi / 8)``, the argument lies in ``[-tan(pi / 8), tan(pi / 8)]``, where
``atan u = u + u P(u^2)`` with :data:`ATAN_P` a degree-10 polynomial (a
Chebyshev fit of ``atan(u) / u - 1`` in ``u^2``), whose error against
arbitrary-precision arithmetic is below ``3e-16`` on that range; the
result is within ``1e-15`` of ``math.atan2`` (the tests check it on a
million arguments, every sign and octant); a sum of K triangles is therefore within ``K * 1e-15`` of
the true winding number, far inside the margin
(:data:`isoflow.mesh.winding.TIE_WINDING`, 1e-9) within which a centre
is decided by the tie rule instead of by rounding.
"""

from __future__ import annotations

import math

import numpy as np

from ..scale.jit import njit

#: atan(u) = u + u * P(u^2) on |u| <= tan(pi / 8), P's coefficients from the constant term up
ATAN_P = (0.0, -0.3333333333335038, 0.20000000001828097, -0.14285714365982155, 0.11111112468117139,
          -0.0909090087068788, 0.07691575394345418, -0.06653191845658303, 0.057516532653616295,
          -0.04520721320186245, 0.023149341945521564)
_P1, _P2, _P3, _P4, _P5, _P6, _P7, _P8, _P9, _P10 = ATAN_P[1:]
_TAN_PI_8 = math.tan(math.pi / 8)
_PI = math.pi


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def atan2_lanes(y: float, x: float) -> float:
    """``atan2(y, x)`` without a call or a branch (selects only), within
    1e-15 (module docstring); NaN at ``x = y = 0``."""
    ax, ay = abs(x), abs(y)
    big, small = max(ax, ay), min(ax, ay)
    past = small > _TAN_PI_8 * big
    u = (small - big if past else small) / (small + big if past else big)
    z = u * u
    p = _P10
    p = p * z + _P9
    p = p * z + _P8
    p = p * z + _P7
    p = p * z + _P6
    p = p * z + _P5
    p = p * z + _P4
    p = p * z + _P3
    p = p * z + _P2
    p = p * z + _P1
    a = u + u * (z * p)
    a = a + 0.25 * _PI if past else a
    a = 0.5 * _PI - a if ay > ax else a
    a = _PI - a if x < 0 else a
    return -a if y < 0 else a


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def half_angle(ax, ay, az, bx, by, bz, cx, cy, cz):
    """Half the solid angle of the triangle whose corners less p are
    ``a, b, c``, ``atan2(det, den)``, and ``det`` (module docstring)."""
    la = math.sqrt(ax * ax + ay * ay + az * az)
    lb = math.sqrt(bx * bx + by * by + bz * bz)
    lc = math.sqrt(cx * cx + cy * cy + cz * cz)
    det = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
    den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc
           + (bx * cx + by * cy + bz * cz) * la + (cx * ax + cy * ay + cz * az) * lb)
    return atan2_lanes(det, den), det


@njit(cache=True, nogil=True, error_model="numpy")
def winding_lanes(T, nlen, X, Y, Z, n, tol, w, gap):
    """``w[i]``: the winding number at ``(X[i], Y[i], Z[i])``, ``i < n``,
    over the triangles ``T`` (K, 3, 3); ``gap[i]``: the least ``|det| -
    tol * nlen`` over the triangles (``nlen`` their normals' lengths), at
    most 0 where a triangle's plane passes within ``tol`` of the point
    (where the caller checks for a tie).  Triangles in the outer loop,
    points in the inner one: the inner loop runs in SIMD lanes."""
    for i in range(n):
        w[i] = 0.0
        gap[i] = np.inf
    for t in range(T.shape[0]):
        ax0, ay0, az0 = T[t, 0, 0], T[t, 0, 1], T[t, 0, 2]
        bx0, by0, bz0 = T[t, 1, 0], T[t, 1, 1], T[t, 1, 2]
        cx0, cy0, cz0 = T[t, 2, 0], T[t, 2, 1], T[t, 2, 2]
        margin = tol * nlen[t]
        for i in range(n):
            ax, ay, az = ax0 - X[i], ay0 - Y[i], az0 - Z[i]
            bx, by, bz = bx0 - X[i], by0 - Y[i], bz0 - Z[i]
            cx, cy, cz = cx0 - X[i], cy0 - Y[i], cz0 - Z[i]
            half, det = half_angle(ax, ay, az, bx, by, bz, cx, cy, cz)
            w[i] += half
            gap[i] = min(gap[i], abs(det) - margin)
    inv = 1.0 / (2.0 * _PI)
    for i in range(n):
        w[i] *= inv


def winding_numbers(points: np.ndarray, triangles: np.ndarray, tol: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The generalised winding number of each point over the triangles,
    summed exactly (to within ``K * 1e-15`` for K triangles).

    Parameters
    ----------
    points : (n, 3) float array
    triangles : (K, 3, 3) float array
    tol : float
        Distance from a triangle's plane below which a point is flagged.

    Returns
    -------
    w : (n,) float array
        ``sum_t Omega_t(p) / 4 pi`` (Jacobson et al. 2013, eq. 4).
    flagged : (n,) bool array
        Points within ``tol`` of some triangle's plane (where ``w`` may
        be that of either side, or NaN on a corner).

    Examples
    --------
    The unit cube's surface winds once around its centre and not at all
    around a point outside it:

    >>> import trimesh
    >>> box = trimesh.creation.box()
    >>> w, _ = winding_numbers(np.array([[0.0, 0, 0], [2, 0, 0]]), box.vertices[box.faces])
    >>> np.round(w, 12).tolist()
    [1.0, 0.0]
    """
    P = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    T = np.ascontiguousarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    nlen = np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    n = len(P)
    w, gap = np.empty(n), np.empty(n)
    X, Y, Z = (np.ascontiguousarray(P[:, d]) for d in range(3))
    winding_lanes(T, nlen, X, Y, Z, n, float(tol), w, gap)
    return w, gap <= 0
