"""Exact orientation signs of float64 points, filtered.

A crossing test that rounds sees two faces that meet at an edge cross, or
misses a crossing, and its answer then depends on the units and the
placement of the mesh. The signs here are those of the exact determinants
of the points as stored. A float64 evaluation decides wherever its error
bound certifies the sign (Shewchuk 1997, the bounds ``errboundA`` of
``orient2d`` and ``orient3d``); a determinant with a column that is exactly
zero (points on one axis-aligned plane, as in most CAD parts) is zero
without arithmetic; the rest is evaluated in integers, since every float64
is an integer times a power of two.

References
----------
J. R. Shewchuk, "Adaptive precision floating-point arithmetic and fast
robust geometric predicates", Discrete & Computational Geometry 18 (1997).
"""

from __future__ import annotations

import numpy as np

_EPS = 2.0**-53
#: relative error bound of the float64 ``orient3d`` (Shewchuk's o3derrboundA)
O3_BOUND = (7 + 56 * _EPS) * _EPS
#: relative error bound of the float64 ``orient2d`` (Shewchuk's ccwerrboundA)
O2_BOUND = (3 + 16 * _EPS) * _EPS
#: below this magnitude products may be subnormal, where the relative bound
#: does not hold: such determinants are evaluated exactly
_TINY = 2.0**-900


class ExactPoints:
    """Points whose orientation signs are exact.

    Parameters
    ----------
    points : array_like, shape (N, 3)
        Coordinates, read as float64.

    Examples
    --------
    >>> import numpy as np
    >>> p = ExactPoints([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.1, 0.2, 1e-300]])
    >>> p.orient3d(np.array([0]), np.array([1]), np.array([2]), np.array([3])).tolist()
    [-1]
    """

    def __init__(self, points) -> None:
        p = np.asarray(points, np.float64)
        top = float(np.max(np.abs(p))) if p.size else 0.0
        e = int(np.frexp(top)[1]) if top > 0 and np.isfinite(top) else 0
        with np.errstate(under="ignore"):
            scaled = np.ldexp(p, -e)
        # a power of two changes no sign; where it would lose bits to
        # underflow the float filter runs on the points as given
        self.xyz = scaled if np.array_equal(np.ldexp(scaled, e), p) else p
        mant, expo = np.frexp(p)
        m = np.ldexp(mant, 53).astype(np.int64)  # exact: 53 bits
        shift = expo.astype(np.int64) - 53
        nonzero = m != 0
        # drop each mantissa's trailing zero bits, so that the common unit
        # is the lowest bit any coordinate sets
        zeros = np.zeros_like(m)
        zeros[nonzero] = np.log2((m & -m)[nonzero].astype(np.float64)).astype(np.int64)
        self._mant = m >> zeros
        shift = shift + zeros
        self._shift = shift - (int(shift[nonzero].min()) if nonzero.any() else 0)
        self.small = self._small_ints()

    def _small_ints(self) -> np.ndarray | None:
        """The points as int64 in the unit of :meth:`ints` where every
        coordinate is below 2**19 there (a voxel surface's corners, a part
        on a coarse grid): then every orientation determinant is exact in
        int64 (differences below 2**20, six products of three below 2**60).
        None otherwise."""
        if not self._mant.size:
            return None
        m = np.abs(self._mant)
        bits = np.where(m > 0, np.floor(np.log2(np.maximum(m, 1))).astype(np.int64) + 1 + self._shift, 0)
        if int(bits.max()) > 19:
            return None
        return np.left_shift(self._mant, np.maximum(self._shift, 0))

    def ints(self, index: np.ndarray) -> np.ndarray:
        """The points ``index`` as Python integers (object array, (K, 3)),
        all in one unit: a power of two below every coordinate's last bit."""
        m = self._mant[index].astype(object)
        s = np.maximum(self._shift[index], 0).astype(object)
        return np.left_shift(m, s)

    def orient3d(self, a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Sign (-1, 0, 1) of ``det[a - d, b - d, c - d]`` for index arrays:
        0 where the four points lie on one plane."""
        x = self.xyz
        ad, bd, cd = x[a] - x[d], x[b] - x[d], x[c] - x[d]
        with np.errstate(over="ignore", invalid="ignore", under="ignore"):
            det, permanent = _det3(ad, bd, cd, np)
            sure = np.isfinite(permanent) & (np.abs(det) > O3_BOUND * permanent) & (permanent > _TINY)
        sign = np.sign(det).astype(np.int8)
        flat = _zero_column(ad, bd, cd)
        sign[flat] = 0
        todo = np.flatnonzero(~sure & ~flat)
        if len(todo):
            da = self.ints(d[todo])
            exact, _ = _det3(self.ints(a[todo]) - da, self.ints(b[todo]) - da, self.ints(c[todo]) - da, None)
            sign[todo] = _sign_of(exact)
        return sign

    def orient2d(self, a: np.ndarray, b: np.ndarray, c: np.ndarray, axis: np.ndarray) -> np.ndarray:
        """Sign of the ``axis`` component of ``(b - a) x (c - a)``: the
        orientation of ``a, b, c`` seen along that axis (0 where they are
        collinear in that view)."""
        axis = np.broadcast_to(np.asarray(axis, np.int64), np.shape(a))
        i, j = (axis + 1) % 3, (axis + 2) % 3
        x = self.xyz
        ac = np.stack([x[a, i] - x[c, i], x[a, j] - x[c, j]], axis=1)
        bc = np.stack([x[b, i] - x[c, i], x[b, j] - x[c, j]], axis=1)
        with np.errstate(over="ignore", invalid="ignore", under="ignore"):
            left, right = ac[:, 0] * bc[:, 1], ac[:, 1] * bc[:, 0]
            det = left - right
            permanent = np.abs(left) + np.abs(right)
            sure = np.isfinite(permanent) & (np.abs(det) > O2_BOUND * permanent) & (permanent > _TINY)
        sign = np.sign(det).astype(np.int8)
        flat = np.all(ac == 0, axis=1) | np.all(bc == 0, axis=1) | ((ac[:, 0] == 0) & (bc[:, 0] == 0)) | (
            (ac[:, 1] == 0) & (bc[:, 1] == 0))
        sign[flat] = 0
        todo = np.flatnonzero(~sure & ~flat)
        if len(todo):
            rows = np.arange(len(todo))
            ii, jj = i[todo], j[todo]
            pa, pb, pc = self.ints(a[todo]), self.ints(b[todo]), self.ints(c[todo])
            exact = ((pa[rows, ii] - pc[rows, ii]) * (pb[rows, jj] - pc[rows, jj])
                     - (pa[rows, jj] - pc[rows, jj]) * (pb[rows, ii] - pc[rows, ii]))
            sign[todo] = _sign_of(exact)
        return sign


def _det3(ad, bd, cd, xp) -> tuple:
    """Shewchuk's ``orient3d`` expansion of ``det[ad, bd, cd]`` (rows) and,
    with ``xp`` NumPy, its permanent (the error bound's scale)."""
    adx, ady, adz = ad[:, 0], ad[:, 1], ad[:, 2]
    bdx, bdy, bdz = bd[:, 0], bd[:, 1], bd[:, 2]
    cdx, cdy, cdz = cd[:, 0], cd[:, 1], cd[:, 2]
    bc1, bc2 = bdy * cdz, bdz * cdy
    ca1, ca2 = cdy * adz, cdz * ady
    ab1, ab2 = ady * bdz, adz * bdy
    det = adx * (bc1 - bc2) + bdx * (ca1 - ca2) + cdx * (ab1 - ab2)
    if xp is None:
        return det, None
    permanent = ((xp.abs(bc1) + xp.abs(bc2)) * xp.abs(adx) + (xp.abs(ca1) + xp.abs(ca2)) * xp.abs(bdx)
                 + (xp.abs(ab1) + xp.abs(ab2)) * xp.abs(cdx))
    return det, permanent


def _zero_column(ad: np.ndarray, bd: np.ndarray, cd: np.ndarray) -> np.ndarray:
    """Where the 3x3 matrix has a row or a column of exact zeros (a point
    repeated, or four points on a plane x, y or z = const): determinant 0."""
    zero_col = np.any((ad == 0) & (bd == 0) & (cd == 0), axis=1)
    zero_row = np.all(ad == 0, axis=1) | np.all(bd == 0, axis=1) | np.all(cd == 0, axis=1)
    return zero_col | zero_row


def _sign_of(values: np.ndarray) -> np.ndarray:
    """Signs of an object array of Python integers, as int8."""
    return ((values > 0).astype(np.int8) - (values < 0).astype(np.int8))
