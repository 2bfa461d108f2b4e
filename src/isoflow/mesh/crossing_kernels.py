"""Compiled pass of the crossing test: the rules of
:mod:`isoflow.mesh.crossings` on float64 with the error bounds of
:mod:`isoflow.mesh.predicates`, over the pairs of a grid's cubes.

Every sign is -1, 0 or 1 where the float64 evaluation is certified (the
bound, or a zero row or column), and :data:`UNDECIDED` otherwise; a pair
whose answer rests on an undecided sign is handed back undecided, and the
NumPy pass decides it in integers. Points that are small integers in one
unit (``n``, :attr:`isoflow.mesh.predicates.ExactPoints.small`) are
decided in int64 alone, exactly. So the compiled pass changes the time,
never the answer (the tests hold the two equal).
"""

from __future__ import annotations

import numpy as np

from ..scale.jit import njit
from .predicates import O2_BOUND, O3_BOUND

UNDECIDED = 2
_TINY = 2.0**-900


@njit(cache=True, nogil=True)
def _o3_int(n, a, b, c, d):
    """Exact orient3d on int64 points (all below 2**19: no overflow)."""
    adx, ady, adz = n[a, 0] - n[d, 0], n[a, 1] - n[d, 1], n[a, 2] - n[d, 2]
    bdx, bdy, bdz = n[b, 0] - n[d, 0], n[b, 1] - n[d, 1], n[b, 2] - n[d, 2]
    cdx, cdy, cdz = n[c, 0] - n[d, 0], n[c, 1] - n[d, 1], n[c, 2] - n[d, 2]
    det = adx * (bdy * cdz - bdz * cdy) + bdx * (cdy * adz - cdz * ady) + cdx * (ady * bdz - adz * bdy)
    return (det > 0) - (det < 0)


@njit(cache=True, nogil=True)
def _o2_int(n, a, b, c, k):
    i, j = (k + 1) % 3, (k + 2) % 3
    det = (n[a, i] - n[c, i]) * (n[b, j] - n[c, j]) - (n[a, j] - n[c, j]) * (n[b, i] - n[c, i])
    return (det > 0) - (det < 0)


@njit(cache=True, nogil=True)
def _o3(x, n, a, b, c, d):
    """Sign of orient3d: exact in int64 where the points are small integers
    (``n`` holds them; None where they are not), else certified float64,
    else UNDECIDED. A None ``n`` is a type of its own: numba compiles the
    kernels for it without the integer path, which, compiled in beside the
    float one, slows every call about three times."""
    if n is not None:
        return _o3_int(n, a, b, c, d)
    return _o3_float(x, a, b, c, d)


@njit(cache=True, nogil=True)
def _o2(x, n, a, b, c, k):
    """Sign of orient2d seen along axis ``k``, as :func:`_o3`."""
    if n is not None:
        return _o2_int(n, a, b, c, k)
    return _o2_float(x, a, b, c, k)


@njit(cache=True, nogil=True)
def _o3_float(x, a, b, c, d):
    adx, ady, adz = x[a, 0] - x[d, 0], x[a, 1] - x[d, 1], x[a, 2] - x[d, 2]
    bdx, bdy, bdz = x[b, 0] - x[d, 0], x[b, 1] - x[d, 1], x[b, 2] - x[d, 2]
    cdx, cdy, cdz = x[c, 0] - x[d, 0], x[c, 1] - x[d, 1], x[c, 2] - x[d, 2]
    if (adx == 0 and bdx == 0 and cdx == 0) or (ady == 0 and bdy == 0 and cdy == 0) or (
            adz == 0 and bdz == 0 and cdz == 0):
        return 0
    if (adx == 0 and ady == 0 and adz == 0) or (bdx == 0 and bdy == 0 and bdz == 0) or (
            cdx == 0 and cdy == 0 and cdz == 0):
        return 0
    bc1, bc2 = bdy * cdz, bdz * cdy
    ca1, ca2 = cdy * adz, cdz * ady
    ab1, ab2 = ady * bdz, adz * bdy
    det = adx * (bc1 - bc2) + bdx * (ca1 - ca2) + cdx * (ab1 - ab2)
    perm = ((abs(bc1) + abs(bc2)) * abs(adx) + (abs(ca1) + abs(ca2)) * abs(bdx)
            + (abs(ab1) + abs(ab2)) * abs(cdx))
    return _certified(det, perm, O3_BOUND)


@njit(cache=True, nogil=True)
def _o2_float(x, a, b, c, k):
    i, j = (k + 1) % 3, (k + 2) % 3
    acx, acy = x[a, i] - x[c, i], x[a, j] - x[c, j]
    bcx, bcy = x[b, i] - x[c, i], x[b, j] - x[c, j]
    if (acx == 0 and acy == 0) or (bcx == 0 and bcy == 0) or (acx == 0 and bcx == 0) or (acy == 0 and bcy == 0):
        return 0
    left, right = acx * bcy, acy * bcx
    det = left - right
    return _certified(det, abs(left) + abs(right), O2_BOUND)


@njit(cache=True, nogil=True)
def _certified(det, permanent, relative):
    """The sign of ``det`` where the error bound ``relative * permanent``
    certifies it, else UNDECIDED (also where products may be subnormal or
    overflowed)."""
    if not (permanent > _TINY and permanent < np.inf):
        return UNDECIDED
    bound = relative * permanent
    if det > bound:
        return 1
    if -det > bound:
        return -1
    return UNDECIDED


@njit(cache=True, nogil=True)
def _either(r, s):
    """Or of two answers (0 no, 1 yes, UNDECIDED)."""
    if r == 1 or s == 1:
        return 1
    if r == UNDECIDED or s == UNDECIDED:
        return UNDECIDED
    return 0


@njit(cache=True, nogil=True)
def _between(x, r, s, p):
    """Whether ``p`` lies in the box of ``r`` and ``s`` (on their segment,
    for collinear points)."""
    for m in range(3):
        if x[p, m] < min(x[r, m], x[s, m]) or x[p, m] > max(x[r, m], x[s, m]):
            return False
    return True


@njit(cache=True, nogil=True)
def _segments_meet_2d(x, n, p, q, r, s, k):
    d1, d2, d3, d4 = _o2(x, n, r, s, p, k), _o2(x, n, r, s, q, k), _o2(x, n, p, q, r, k), _o2(x, n, p, q, s, k)
    if d1 == UNDECIDED or d2 == UNDECIDED or d3 == UNDECIDED or d4 == UNDECIDED:
        return UNDECIDED
    if d1 * d2 < 0 and d3 * d4 < 0:
        return 1
    if (d1 == 0 and _between(x, r, s, p)) or (d2 == 0 and _between(x, r, s, q)) or (
            d3 == 0 and _between(x, p, q, r)) or (d4 == 0 and _between(x, p, q, s)):
        return 1
    return 0


@njit(cache=True, nogil=True)
def _inside_2d(x, n, p, t0, t1, t2, k):
    return _one_side(_o2(x, n, t0, t1, p, k), _o2(x, n, t1, t2, p, k), _o2(x, n, t2, t0, p, k))


@njit(cache=True, nogil=True)
def _one_side(s1, s2, s3):
    """1 where three signs have no two opposite (a point in a triangle, a
    line through it), 0 where they do, UNDECIDED where one is."""
    if s1 == UNDECIDED or s2 == UNDECIDED or s3 == UNDECIDED:
        return UNDECIDED
    if (s1 > 0 or s2 > 0 or s3 > 0) and (s1 < 0 or s2 < 0 or s3 < 0):
        return 0
    return 1


@njit(cache=True, nogil=True)
def _segment_meets_triangle(x, n, p, q, t0, t1, t2, k, sp, sq):
    if sp == UNDECIDED or sq == UNDECIDED:
        return UNDECIDED
    if sp == sq and sp != 0:
        return 0
    if sp == 0 and sq == 0:
        r = _either(_inside_2d(x, n, p, t0, t1, t2, k), _inside_2d(x, n, q, t0, t1, t2, k))
        r = _either(r, _segments_meet_2d(x, n, p, q, t0, t1, k))
        r = _either(r, _segments_meet_2d(x, n, p, q, t1, t2, k))
        return _either(r, _segments_meet_2d(x, n, p, q, t2, t0, k))
    return _one_side(_o3(x, n, p, q, t0, t1), _o3(x, n, p, q, t1, t2), _o3(x, n, p, q, t2, t0))


@njit(cache=True, nogil=True)
def segment_crosses_triangle(x, p, q, t0, t1, t2):
    """Whether the segment ``p q`` crosses the triangle ``t0 t1 t2`` (point
    indices into ``x``) at one point of its inside, away from its edges
    and corners, with neither end on its plane: 1; 0 where the segment
    misses the closed triangle; :data:`UNDECIDED` where it touches it
    otherwise (through an edge or a corner, an end on it, in its plane)
    or a sign is not certified. A ray cast to count crossings takes 1
    and 0 as they are and gives up on the rest.

    Examples
    --------
    >>> x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, -1], [0.2, 0.2, 1], [1, 1, 1]], float)
    >>> int(segment_crosses_triangle(x, 3, 4, 0, 1, 2)), int(segment_crosses_triangle(x, 4, 5, 0, 1, 2))
    (1, 0)
    """
    s = segment_crossing_side(x, p, q, t0, t1, t2)
    return 1 if s == -1 else s


@njit(cache=True, nogil=True)
def segment_crossing_side(x, p, q, t0, t1, t2):
    """:func:`segment_crosses_triangle` with the way it crosses: 1 from
    the triangle's back to its front (the side its normal
    ``(t1 - t0) x (t2 - t0)`` points to), -1 from front to back; 0 and
    :data:`UNDECIDED` as there. Summed along a ray from a point to beyond
    a closed mesh, the signs are the point's winding number.

    Examples
    --------
    >>> x = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.2, 0.2, -1], [0.2, 0.2, 1]], float)
    >>> int(segment_crossing_side(x, 3, 4, 0, 1, 2)), int(segment_crossing_side(x, 4, 3, 0, 1, 2))
    (1, -1)
    """
    # the line through p and q misses the closed triangle where two of
    # these signs are opposite, and meets its inside where all three agree;
    # the line first, so that a triangle beside the line whose plane passes
    # near an end (one in the plane of the face the ray starts from) is no
    # question
    s1, s2, s3 = _o3(x, None, p, q, t0, t1), _o3(x, None, p, q, t1, t2), _o3(x, None, p, q, t2, t0)
    if ((s1 == 1 or s2 == 1 or s3 == 1) and (s1 == -1 or s2 == -1 or s3 == -1)):
        return 0
    if s1 == UNDECIDED or s2 == UNDECIDED or s3 == UNDECIDED:
        return UNDECIDED
    sp, sq = _o3(x, None, t0, t1, t2, p), _o3(x, None, t0, t1, t2, q)
    if sp == sq and sp != 0 and sp != UNDECIDED:
        return 0  # both ends on one side
    if sp == UNDECIDED or sq == UNDECIDED or sp == 0 or sq == 0 or s1 == 0 or s2 == 0 or s3 == 0:
        return UNDECIDED
    return -sq  # orient3d is negative for a point in front (on the normal's side)


@njit(cache=True, nogil=True)
def _pair(x, n, tri, axis, fa, fb):
    """0, 1 or UNDECIDED: whether faces ``fa`` and ``fb`` cross."""
    shared = 0
    ia = -1
    ib = -1
    for m in range(3):
        for w in range(3):
            if tri[fa, m] == tri[fb, w]:
                shared += 1
                ia, ib = m, w
    if shared == 3:
        return 0
    if shared == 2:  # the corners off the common edge
        for m in range(3):
            if tri[fa, m] != tri[fb, 0] and tri[fa, m] != tri[fb, 1] and tri[fa, m] != tri[fb, 2]:
                ia = m
            if tri[fb, m] != tri[fa, 0] and tri[fb, m] != tri[fa, 1] and tri[fb, m] != tri[fa, 2]:
                ib = m
        a, b = tri[fa, ia], tri[fb, ib]
        u, v = tri[fa, (ia + 1) % 3], tri[fa, (ia + 2) % 3]
        o = _o3(x, n, u, v, a, b)
        if o != 0:
            return UNDECIDED if o == UNDECIDED else 0
        s1, s2 = _o2(x, n, u, v, a, axis[fa]), _o2(x, n, u, v, b, axis[fa])
        if s1 == UNDECIDED or s2 == UNDECIDED:
            return UNDECIDED
        return 1 if s1 * s2 > 0 else 0
    A0, A1, A2 = tri[fa, 0], tri[fa, 1], tri[fa, 2]
    B0, B1, B2 = tri[fb, 0], tri[fb, 1], tri[fb, 2]
    if shared == 1:
        a1, a2 = tri[fa, (ia + 1) % 3], tri[fa, (ia + 2) % 3]
        b1, b2 = tri[fb, (ib + 1) % 3], tri[fb, (ib + 2) % 3]
        r = _segment_meets_triangle(x, n, a1, a2, B0, B1, B2, axis[fb], _o3(x, n, B0, B1, B2, a1), _o3(x, n, B0, B1, B2, a2))
        if r == 1:
            return 1
        return _either(r, _segment_meets_triangle(x, n, b1, b2, A0, A1, A2, axis[fa], _o3(x, n, A0, A1, A2, b1),
                                                  _o3(x, n, A0, A1, A2, b2)))
    sb0, sb1, sb2 = _o3(x, n, A0, A1, A2, B0), _o3(x, n, A0, A1, A2, B1), _o3(x, n, A0, A1, A2, B2)
    if (sb0 == 1 and sb1 == 1 and sb2 == 1) or (sb0 == -1 and sb1 == -1 and sb2 == -1):
        return 0
    sa0, sa1, sa2 = _o3(x, n, B0, B1, B2, A0), _o3(x, n, B0, B1, B2, A1), _o3(x, n, B0, B1, B2, A2)
    if (sa0 == 1 and sa1 == 1 and sa2 == 1) or (sa0 == -1 and sa1 == -1 and sa2 == -1):
        return 0
    r = _segment_meets_triangle(x, n, B0, B1, A0, A1, A2, axis[fa], sb0, sb1)
    r = _either(r, _segment_meets_triangle(x, n, B1, B2, A0, A1, A2, axis[fa], sb1, sb2))
    r = _either(r, _segment_meets_triangle(x, n, B2, B0, A0, A1, A2, axis[fa], sb2, sb0))
    r = _either(r, _segment_meets_triangle(x, n, A0, A1, B0, B1, B2, axis[fb], sa0, sa1))
    r = _either(r, _segment_meets_triangle(x, n, A1, A2, B0, B1, B2, axis[fb], sa1, sa2))
    return _either(r, _segment_meets_triangle(x, n, A2, A0, B0, B1, B2, axis[fb], sa2, sa0))


@njit(cache=True, nogil=True)
def cube_pairs(x, n, tri, axis, box, key, start, size, cl, lo, hi, dims, found, undecided):
    """Every pair of boxes that share a grid cube (``box`` sorted by
    ``key``, cubes from ``start`` with ``size`` entries), emitted by the
    cube of the lower corner of their common box where the boxes overlap,
    and decided: crossing pairs into ``found``, undecided ones into
    ``undecided`` (rows of face indices). Returns the two counts; a count
    beyond an array's length means it was too short (call again)."""
    nf = 0
    nu = 0
    for g in range(len(start)):
        s0 = start[g]
        for e1 in range(s0, s0 + size[g]):
            i = box[e1]
            for e2 in range(e1 + 1, s0 + size[g]):
                j = box[e2]
                r0, r1, r2 = max(cl[i, 0], cl[j, 0]), max(cl[i, 1], cl[j, 1]), max(cl[i, 2], cl[j, 2])
                if (r2 * dims[1] + r1) * dims[0] + r0 != key[e1]:
                    continue
                if (lo[i, 0] > hi[j, 0] or lo[j, 0] > hi[i, 0] or lo[i, 1] > hi[j, 1] or lo[j, 1] > hi[i, 1]
                        or lo[i, 2] > hi[j, 2] or lo[j, 2] > hi[i, 2]):
                    continue
                r = _pair(x, n, tri, axis, i, j)
                if r == 1:
                    if nf < len(found):
                        found[nf, 0], found[nf, 1] = min(i, j), max(i, j)
                    nf += 1
                elif r == UNDECIDED:
                    if nu < len(undecided):
                        undecided[nu, 0], undecided[nu, 1] = min(i, j), max(i, j)
                    nu += 1
    return nf, nu


@njit(cache=True, nogil=True)
def face_axes(x, n, tri, axis, undecided):
    """:func:`isoflow.mesh.crossings.projection_axis` per triangle, into
    ``axis``, where its three orient2d signs are certified
    (:func:`_o2`); ``undecided[t]`` set where one is not (the NumPy pass
    decides those). The normal's components are taken with NumPy's
    ``np.cross`` operations in its order, so the axis is the one it picks."""
    for t in range(len(tri)):
        a, b, c = tri[t, 0], tri[t, 1], tri[t, 2]
        s0, s1, s2 = _o2(x, n, a, b, c, 0), _o2(x, n, a, b, c, 1), _o2(x, n, a, b, c, 2)
        if s0 == UNDECIDED or s1 == UNDECIDED or s2 == UNDECIDED:
            undecided[t] = True
            continue
        if s0 == 0 and s1 == 0 and s2 == 0:
            axis[t] = -1
            continue
        u0, u1, u2 = x[b, 0] - x[a, 0], x[b, 1] - x[a, 1], x[b, 2] - x[a, 2]
        w0, w1, w2 = x[c, 0] - x[a, 0], x[c, 1] - x[a, 1], x[c, 2] - x[a, 2]
        best = 0
        top = -2.0
        for k in range(3):
            if k == 0:
                m, s = abs(u1 * w2 - u2 * w1), s0
            elif k == 1:
                m, s = abs(u2 * w0 - u0 * w2), s1
            else:
                m, s = abs(u0 * w1 - u1 * w0), s2
            if s == 0:
                m = -1.0
            else:
                if np.isnan(m):
                    m = 0.0
                elif np.isinf(m):
                    m = 1.0
                m = m + 1e-300
            if m > top:  # the first of equal ones, as argmax
                best, top = k, m
        axis[t] = best


@njit(cache=True, nogil=True)
def cube_entries(cl, ch, dims, box, key):
    """Each box's cubes (from its lowest ``cl`` to its highest ``ch``, x
    fastest) into ``box`` (the box's number) and ``key`` (the cube's, as
    :meth:`isoflow.mesh.cube_grid.CubeGrid.cube_key`), box after box."""
    e = 0
    for i in range(len(cl)):
        for z in range(cl[i, 2], ch[i, 2] + 1):
            for y in range(cl[i, 1], ch[i, 1] + 1):
                row = (z * dims[1] + y) * dims[0]
                for xx in range(cl[i, 0], ch[i, 0] + 1):
                    box[e] = i
                    key[e] = row + xx
                    e += 1


@njit(cache=True, nogil=True)
def sort_by_key(key, box, bits):
    """``key`` and ``box`` reordered by ``key`` (non-negative, below
    ``2**bits``), stably: a radix sort of 16-bit digits. Returns the two
    sorted arrays (new ones, or the arguments)."""
    n = len(key)
    k2 = np.empty_like(key)
    b2 = np.empty_like(box)
    count = np.empty(1 << 16, np.int64)
    shift = 0
    while shift < bits:
        count[:] = 0
        for e in range(n):
            count[(key[e] >> shift) & 0xFFFF] += 1
        total = 0
        for d in range(1 << 16):
            c = count[d]
            count[d] = total
            total += c
        for e in range(n):
            d = (key[e] >> shift) & 0xFFFF
            k2[count[d]] = key[e]
            b2[count[d]] = box[e]
            count[d] += 1
        key, k2 = k2, key
        box, b2 = b2, box
        shift += 16
    return key, box


@njit(cache=True, nogil=True)
def runs(key):
    """Where each run of equal values of the sorted ``key`` starts, and its
    length."""
    n = len(key)
    m = 0
    for e in range(n):
        if e == 0 or key[e] != key[e - 1]:
            m += 1
    start = np.empty(m, np.int64)
    size = np.empty(m, np.int64)
    g = -1
    for e in range(n):
        if e == 0 or key[e] != key[e - 1]:
            g += 1
            start[g] = e
            size[g] = 0
        size[g] += 1
    return start, size
