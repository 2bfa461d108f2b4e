"""One step of the digital curvature flow on bit rows (numba).

The volume is held as rows of 64-voxel words along its last axis
(:mod:`isoflow.scale.bitrows`); the step writes the next object, on the
vertex grid (one more voxel per axis), in the same form. What a vertex does
is given by a table over its configurations (:data:`KEEP`, :data:`NEGATIVE`
and the segment roles below, made by :mod:`isoflow.flow.bitflow` from the
paper's tables); this module knows rows and runs, not curvature.

A vertex row ``(i, j)`` has the four voxel rows around it, ``(i - 1 + dx, j
- 1 + dy)``; read as a word ``U`` (voxel ``k`` at bit ``k``) and shifted by
one (``S``: voxel ``k - 1`` at bit ``k``) they are the eight octant planes
of the 64 vertices of a word: octant ``dx + 2 dy + 4 dz`` is ``S`` for
``dz = 0``, ``U`` for ``dz = 1``. So every interior vertex of a word is
found by one AND of the planes, and only boundary vertices are decoded one
by one (count trailing zeros), their configuration gathered from the
planes and looked up.

Segments (runs of one configuration along an axis, Definitions 12-13, 16)
are only asked for configurations that are the same on both sides of the
vertex along the segment's axis (a convex edge along its edge, a flat
vertex along its face): the run of such a vertex is the run of equal
*cross-sections* (the 2^(n-1) voxels at one position along the axis), and
its ends are the vertices where the cross-section changes.

* Along the packed axis the cross-section changes where any of the rows
  does (an *event*: ``S ^ U``); a segment is the stretch between two
  events, its ends those events.
* Across rows the change is a word comparison of the rows at ``t`` and at
  ``t - 1``; whether the segment through each vertex has a negative end
  before it (after it) is carried along the axis by one forward (backward)
  scan of words, 64 lines at a time.

Vertex rows are cut into slabs along the first axis, one per thread, as in
:mod:`isoflow.scale.sweep`; the scan across the first axis runs afterwards,
in slabs along the second.
"""

from __future__ import annotations

import numpy as np

from .bitrows import around, configuration, octant_planes, popcount, trailing_zeros, word
from .compiled import read_only_view, run, slabs, thread_count
from .jit import njit

#: bits of the table over configurations (:func:`isoflow.flow.bitflow.step_table`)
KEEP, NEGATIVE = 1, 2
#: the segments a vertex waits for, per axis: kept when one end (``ANY_*``:
#: a flat vertex's in-face axes) or both ends (``BOTH_*``: a convex edge's
#: axis) are negative; a 2D image is the layer ``x = 0`` of a 3D volume, its
#: axes 0 and 1 the axes y and z
ANY_X, BOTH_X, ANY_Y, BOTH_Y, ANY_Z, BOTH_Z = 4, 8, 16, 32, 64, 128

_U1, _U63 = np.uint64(1), np.uint64(63)


@njit(cache=True, nogil=True, inline="always")
def _bit(value, k):
    return (value >> np.uint64(k)) & _U1


@njit(cache=True, nogil=True)
def _fill(words, row, a, b):
    """Set bits ``a .. b`` (inclusive) of row ``row``."""
    wa, wb = a >> 6, b >> 6
    for w in range(wa, wb + 1):
        lo = a - 64 * w if w == wa else 0
        hi = b - 64 * w if w == wb else 63
        span = ~np.uint64(0) >> np.uint64(63 - (hi - lo))
        words[row, w] |= span << np.uint64(lo)


@njit(cache=True, nogil=True, inline="always")
def _packed_segments(keep, neg, row, events, edge, flat, nwords):
    """Along the packed axis: the stretches between events whose vertices
    wait for it (``edge``: kept when both ends are negative, ``flat``: when
    one is) are kept or left to the other axes."""
    prev, prev_neg = -1, np.uint64(0)
    for w in range(nwords):
        m = events[w]
        while m:
            k = trailing_zeros(m)
            m &= m - _U1
            e = 64 * w + np.int64(k)
            here = _bit(neg[row, w], k)
            s = prev + 1
            if prev >= 0 and e > s:
                sw, sk = s >> 6, s & 63
                if _bit(edge[sw], sk) & prev_neg & here:
                    _fill(keep, row, s, e - 1)
                elif _bit(flat[sw], sk) & (prev_neg | here):
                    _fill(keep, row, s, e - 1)
            prev, prev_neg = e, here


@njit(cache=True, nogil=True)
def _scan(keep, neg, pany, pboth, p0, pstride, v0, vstride, n, t0, t1, bits, a0, b0, rstride, ends, change,
          before, after, changed):
    """Across rows: keep the vertices of rows ``v0 + t vstride`` (``t0 <= t
    < t1``, of ``0 .. n``) that wait for a segment along this axis,
    ``pany`` (one negative end) and ``pboth`` (two), rows ``p0 + t
    pstride`` of those tables.

    The cross-section at ``t`` is voxel rows ``a0 + t rstride`` and ``b0 +
    t rstride`` (-1: none; ``t = n``: outside the array), both at voxels
    ``k - 1`` and ``k``; it changes at vertex ``t`` where they differ from
    those at ``t - 1``. A segment's end before a vertex is the last change
    at or before it, after it the first change after it: whether that end
    is negative is carried forward (``before``: in, for the rows before
    ``t0``; out, after ``t1 - 1``) and backward (``after``: in, for row ``t1
    - 1`` from the rows past it; out, for row ``t0 - 1``); ``changed`` gets
    every change seen. A whole axis is ``t0 = 0``, ``t1 = n + 1`` with
    nothing before or after; a slab of it hands these on to the next.
    ``ends``, ``change``: (n + 1, words) work arrays."""
    nwords = keep.shape[1]
    for t in range(t0, t1):
        prev = np.uint64(0)
        v = v0 + t * vstride
        for w in range(nwords):
            d = np.uint64(0)
            for r0 in (a0, b0):
                if r0 >= 0:
                    now = word(bits, r0 + t * rstride, w) if t < n else np.uint64(0)
                    old = word(bits, r0 + (t - 1) * rstride, w) if t > 0 else np.uint64(0)
                    d |= now ^ old
            dd = d | (d << _U1) | (prev >> _U63)
            prev = d
            change[t, w] = dd
            changed[w] |= dd
            before[w] = (dd & neg[v, w]) | (~dd & before[w])
            ends[t, w] = before[w]
    for t in range(t1 - 1, t0 - 1, -1):
        v = v0 + t * vstride
        p = p0 + t * pstride
        for w in range(nwords):
            a, b = pany[p, w], pboth[p, w]
            if a | b:
                ahead, behind = ends[t, w], after[w]
                keep[v, w] |= (a & (ahead | behind)) | (b & ahead & behind)
            dd = change[t, w]
            after[w] = (dd & neg[v, w]) | (~dd & after[w])


@njit(cache=True, nogil=True)
def _moves_layers(bits, nx, ny, table, keep, neg, pany_x, pboth_x, waits_x, i0, i1, planar):
    """The moves of vertex rows ``(i, j)``, ``i0 <= i < i1``: ``keep`` gets
    the vertices kept by their configuration alone and by their segments
    along the packed axis and along the second axis; ``pany_x``,
    ``pboth_x`` (and ``waits_x[j]``) the vertices still waiting for their
    segments along the first axis, which :func:`_scan` settles afterwards.
    ``planar``: the volume is a 2D image as the layer ``x = 0`` (one voxel
    layer, vertex layer 1 asked), whose vertices have only the octants
    ``dx = 0``."""
    nwords = keep.shape[1]
    pany_y = np.zeros((ny + 1, nwords), np.uint64)
    pboth_y = np.zeros((ny + 1, nwords), np.uint64)
    ends = np.empty((ny + 1, nwords), np.uint64)
    change = np.empty((ny + 1, nwords), np.uint64)
    work = np.empty((3, nwords), np.uint64)
    events = np.empty(nwords, np.uint64)
    both_z = np.empty(nwords, np.uint64)
    any_z = np.empty(nwords, np.uint64)
    for i in range(i0, i1):
        waits_y = False
        for j in range(ny + 1):
            v = i * (ny + 1) + j
            rows = around(i, j, nx, ny)
            previous = (np.uint64(0), np.uint64(0), np.uint64(0), np.uint64(0))
            waits_z = np.uint64(0)
            for w in range(nwords):
                s0, s1, s2, s3, u0, u1, u2, u3 = octant_planes(bits, rows, w, previous)
                previous = (u0, u1, u2, u3)
                inside = s0 & s2 & u0 & u2 if planar else s0 & s1 & s2 & s3 & u0 & u1 & u2 & u3
                boundary = (s0 | s1 | s2 | s3 | u0 | u1 | u2 | u3) & ~inside
                kp, ng, ax, bx, ay, by, az, bz = _decode(boundary, s0, s1, s2, s3, u0, u1, u2, u3, table)
                keep[v, w] = inside | kp
                neg[v, w] = ng
                pany_x[v, w] = ax
                pboth_x[v, w] = bx
                pany_y[j, w] = ay
                pboth_y[j, w] = by
                events[w] = (s0 ^ u0) | (s1 ^ u1) | (s2 ^ u2) | (s3 ^ u3)
                both_z[w] = bz
                any_z[w] = az
                waits_z |= az | bz
                if ax | bx:
                    waits_x[j] = True
                if ay | by:
                    waits_y = True
            if waits_z:
                _packed_segments(keep, neg, v, events, both_z, any_z, nwords)
        if waits_y:
            work[:] = 0
            one = np.int64(1)  # the strides as variables, as the columns' call passes them: one compile
            _scan(keep, neg, pany_y, pboth_y, np.int64(0), one, i * (ny + 1), one, ny, np.int64(0), ny + 1, bits,
                  (i - 1) * ny if i >= 1 else -1, i * ny if i < nx else -1, one, ends, change, work[0], work[1],
                  work[2])


@njit(cache=True, nogil=True, inline="always")
def _decode(boundary, s0, s1, s2, s3, u0, u1, u2, u3, table):
    """The boundary vertices of a word, one by one: per flag of the table
    (:data:`KEEP`, :data:`NEGATIVE`, ``ANY_X`` .. ``BOTH_Z``), the word of
    those whose configuration has it."""
    f0 = f1 = f2 = f3 = f4 = f5 = f6 = f7 = np.uint64(0)
    m = boundary
    while m:
        k = trailing_zeros(m)
        m &= m - _U1
        f = np.uint64(table[configuration(s0, s1, s2, s3, u0, u1, u2, u3, k)])
        f0 |= (f & _U1) << k
        f1 |= ((f >> np.uint64(1)) & _U1) << k
        f2 |= ((f >> np.uint64(2)) & _U1) << k
        f3 |= ((f >> np.uint64(3)) & _U1) << k
        f4 |= ((f >> np.uint64(4)) & _U1) << k
        f5 |= ((f >> np.uint64(5)) & _U1) << k
        f6 |= ((f >> np.uint64(6)) & _U1) << k
        f7 |= ((f >> np.uint64(7)) & _U1) << k
    return f0, f1, f2, f3, f4, f5, f6, f7


@njit(cache=True, nogil=True)
def _scan_columns(bits, nx, ny, keep, neg, pany_x, pboth_x, waits_x, j0, j1, t0, t1, before, after, changed):
    """The segments along the first axis of the vertex columns ``j0 <= j <
    j1`` where something waits (``waits_x``), over vertex layers ``t0 <= t
    < t1`` (see :func:`_scan`; per column ``before``, ``after``,
    ``changed``)."""
    nwords = keep.shape[1]
    ends = np.empty((nx + 1, nwords), np.uint64)
    change = np.empty((nx + 1, nwords), np.uint64)
    for j in range(j0, j1):
        if waits_x[j]:
            _scan(keep, neg, pany_x, pboth_x, j, ny + 1, j, ny + 1, nx, t0, t1, bits,
                  j - 1 if j >= 1 else -1, j if j < ny else -1, ny, ends, change, before[j], after[j], changed[j])


def moves3(bits: np.ndarray, shape: tuple[int, int, int], table: np.ndarray) -> np.ndarray:
    """The vertices of a 3D volume's lattice that the step keeps, as bit rows.

    Parameters
    ----------
    bits : numpy.ndarray
        The volume as :func:`isoflow.scale.bitrows.pack` gives it.
    shape : tuple of int
        The volume's shape.
    table : numpy.ndarray
        Per configuration (256): :data:`KEEP`, :data:`NEGATIVE` and the
        segments a vertex waits for (``ANY_*``, ``BOTH_*``).

    Returns
    -------
    numpy.ndarray
        uint64 bit rows of the vertex grid (``shape`` plus one per axis),
        row ``(i, j)`` at ``i (ny + 1) + j``, ``(nz + 1) // 64 + 1`` words a
        row and one more row, clear.

    Notes
    -----
    The moves of eqs. 5.15-5.18 as the table gives them; the module
    docstring says how segments are found.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow.scale import bitrows
    >>> table = np.zeros(256, np.int64)  # keeps only the interior vertices
    >>> rows = moves3(bitrows.pack(np.ones((3, 3, 3), bool))[0], (3, 3, 3), table)
    >>> int(np.bitwise_count(rows).sum())  # the 2^3 inner vertices
    8
    """
    return moves3_layers(bits, shape, table, 0, shape[0] + 1)[0]


def moves3_layers(bits: np.ndarray, shape: tuple[int, int, int], table: np.ndarray, first: int, last: int,
                  before: np.ndarray | None = None, after: np.ndarray | None = None, *, hand_on: bool = False,
                  planar: bool = False):
    """:func:`moves3` for the vertex layers ``first <= i < last`` only: the
    volume's voxel layers ``first - 1 .. last - 1`` are all it reads, so a
    slab of a larger volume with one voxel layer below it (zeros outside
    the volume) gives its own vertex layers ``1 .. L - 1``. Segments along
    the first axis that go on past the slab take ``before``/``after``: per
    vertex line ``(j, k)`` (bit rows, ``(ny + 1, words)``), whether the
    segment's end before the slab (after it) is negative, as the slabs
    below (above) hand it on.

    ``hand_on``: scan every line along the first axis, for what the slab
    hands on, not only those where a vertex waits; ``planar``: the volume
    is a 2D image as the layer ``x = 0`` (:func:`moves2`).

    Returns ``(keep, before, after, changed)``: the vertex grid's bit rows
    (only the layers asked are set), what this slab hands on upward and
    downward (what a segment leaving the slab upward has behind it, and
    one leaving it downward ahead of it), and the lines along which the
    cross-section changes inside the slab (where it does not, the slab
    hands on what it was given)."""
    nx, ny, nz = shape
    nwords = (nz + 1) // 64 + 1
    rows = (nx + 1) * (ny + 1)
    keep = np.zeros((rows + 1, nwords), np.uint64)
    neg = np.zeros((rows, nwords), np.uint64)
    pany_x = np.zeros((rows, nwords), np.uint64)
    pboth_x = np.zeros((rows, nwords), np.uint64)
    table = read_only_view(np.ascontiguousarray(table, np.int64))  # one compile, a writeable table or not
    threads = thread_count((last - first) * (ny + 1) * (nz + 1))
    parts = [(first + a, first + b) for a, b in slabs(last - first, threads)]
    waits = np.zeros((len(parts), ny + 1), np.bool_)
    run([(_moves_layers, bits, nx, ny, table, keep, neg, pany_x, pboth_x, waits[t], a, b, planar)
         for t, (a, b) in enumerate(parts)])
    waits_x = waits.any(axis=0) | hand_on
    before = np.zeros((ny + 1, nwords), np.uint64) if before is None else before.copy()
    after = np.zeros((ny + 1, nwords), np.uint64) if after is None else after.copy()
    changed = np.zeros((ny + 1, nwords), np.uint64)
    run([(_scan_columns, bits, nx, ny, keep, neg, pany_x, pboth_x, waits_x, a, b, first, last, before, after, changed)
         for a, b in slabs(ny + 1, threads)])
    return keep, before, after, changed


def moves2(bits: np.ndarray, shape: tuple[int, int], table: np.ndarray) -> np.ndarray:
    """:func:`moves3` for a 2D volume (eq. 5.8).

    Parameters
    ----------
    bits : numpy.ndarray
        The image's rows along axis 0, packed as one layer of a 3D volume.
    shape : tuple of int
        The image's shape.
    table : numpy.ndarray
        Per 3D configuration (256) of the layer ``x = 1`` of vertices of the
        image as the layer ``x = 0`` of voxels (octants ``dx = 0`` only:
        pixel ``(d0, d1)`` is octant ``2 d0 + 4 d1``): :data:`KEEP`,
        :data:`NEGATIVE`, ``ANY_Y`` (a segment along axis 0), ``ANY_Z``
        (along axis 1).

    Returns
    -------
    numpy.ndarray
        The vertex grid's bit rows, one per vertex row and one more, clear.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow.scale import bitrows
    >>> table = np.zeros(256, np.int64); table[1 | 4 | 16 | 64] = KEEP  # all four pixels
    >>> rows = moves2(bitrows.pack(np.ones((1, 3, 4), bool))[0], (3, 4), table)
    >>> int(np.bitwise_count(rows).sum())
    6
    """
    nx, ny = shape
    keep = moves3_layers(bits, (1, nx, ny), table, 1, 2, planar=True)[0]
    return keep[nx + 1:]  # the vertex layer x = 1, whose octants dx = 0 are the image, and the clear row


@njit(cache=True, nogil=True)
def _bounds(words, nx, ny):
    """Smallest and one past the largest row index along the first two
    axes holding a set bit, and every row or-ed together."""
    lo_i, hi_i, lo_j, hi_j = nx, 0, ny, 0
    union = np.zeros(words.shape[1], np.uint64)
    for i in range(nx):
        for j in range(ny):
            r = i * ny + j
            seen = np.uint64(0)
            for w in range(words.shape[1]):
                seen |= words[r, w]
                union[w] |= words[r, w]
            if seen:
                lo_i, hi_i = min(lo_i, i), max(hi_i, i + 1)
                lo_j, hi_j = min(lo_j, j), max(hi_j, j + 1)
    return lo_i, hi_i, lo_j, hi_j, union


@njit(cache=True, nogil=True)
def _crop_rows(words, ny, lo_i, lo_j, lo_k, sy, out, nruns, ngaps, sz, r0, r1):
    """Rows ``r0 <= r < r1`` of the cropped volume: row ``(x, y)`` is row
    ``(lo_i + x, lo_j + y)`` of ``words`` from bit ``lo_k`` on; with the
    number of runs and gaps of each, as :func:`isoflow.scale.bitrows.pack`
    counts them."""
    q, s = lo_k >> 6, np.uint64(lo_k & 63)
    back = np.uint64(64) - s
    have = words.shape[1]
    for r in range(r0, r1):
        src = (lo_i + r // sy) * ny + lo_j + r % sy
        carry = np.uint64(0)
        runs = 0
        for w in range(out.shape[1]):
            word = words[src, w + q] if w + q < have else np.uint64(0)
            if s:
                word >>= s
                if w + q + 1 < have:
                    word |= words[src, w + q + 1] << back
            out[r, w] = word
            runs += popcount(word & ~((word << _U1) | carry))
            carry = word >> _U63
        nruns[r + 1] = runs
        first = out[r, 0] & _U1
        last = (out[r, (sz - 1) >> 6] >> np.uint64((sz - 1) & 63)) & _U1
        ngaps[r + 1] = runs + 1 - np.int64(first) - np.int64(last)


def crop(words: np.ndarray, shape: tuple[int, int, int]):
    """The smallest box holding the set bits of a volume given as bit rows.

    Parameters
    ----------
    words : numpy.ndarray
        Bit rows of a 3D volume (:func:`moves3`, or :func:`moves2` read as
        one layer), one clear row past the last.
    shape : tuple of int
        That volume's shape.

    Returns
    -------
    tuple
        ``(bits, shape, lo, run_offsets, gap_offsets)``: the box as
        :func:`isoflow.scale.bitrows.pack` would pack it (the runs and gaps
        of its rows counted), its shape and its lowest corner in the input's
        indices; an empty volume gives shape ``(0, 0, 0)``.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow.scale import bitrows
    >>> v = np.zeros((4, 4, 70), bool); v[1:3, 2, 65:67] = True
    >>> crop(bitrows.pack(v)[0], v.shape)[1:3]
    ((2, 1, 2), (1, 2, 65))
    """
    nx, ny, nz = shape
    lo_i, hi_i, lo_j, hi_j, union = _bounds(words, nx, ny)
    if hi_i == 0:
        empty = np.zeros((1, 1), np.uint64)
        return empty, (0, 0, 0), (0, 0, 0), np.zeros(2, np.int64), np.zeros(2, np.int64)
    set_words = np.flatnonzero(union)
    first, last = int(set_words[0]), int(set_words[-1])
    lo_k = 64 * first + (int(union[first]) & -int(union[first])).bit_length() - 1
    hi_k = 64 * last + int(union[last]).bit_length()
    sx, sy, sz = hi_i - lo_i, hi_j - lo_j, hi_k - lo_k
    out = np.empty((sx * sy + 1, sz // 64 + 1), np.uint64)
    out[-1] = 0
    nruns = np.zeros(sx * sy + 2, np.int64)
    ngaps = np.zeros(sx * sy + 2, np.int64)
    parts = slabs(sx * sy, thread_count(sx * sy * sz))
    run([(_crop_rows, words, ny, lo_i, lo_j, lo_k, sy, out, nruns, ngaps, sz, a, b) for a, b in parts])
    return out, (sx, sy, sz), (lo_i, lo_j, lo_k), np.cumsum(nruns), np.cumsum(ngaps)


def unpack(bits: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """The boolean volume of bit rows.

    Parameters
    ----------
    bits : numpy.ndarray
        uint64 rows, the last axis packed (voxel ``k`` at bit ``k % 64`` of
        word ``k // 64``), at least ``prod(shape[:-1])`` of them.
    shape : tuple of int
        The volume's shape.

    Returns
    -------
    numpy.ndarray
        A bool array of ``shape``.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow.scale import bitrows
    >>> v = np.random.default_rng(0).random((3, 2, 70)) < 0.5
    >>> bool(np.array_equal(unpack(bitrows.pack(v)[0], v.shape), v))
    True
    """
    rows = int(np.prod(shape[:-1]))
    if rows == 0 or shape[-1] == 0:
        return np.zeros(shape, bool)
    as_bytes = np.ascontiguousarray(bits[:rows], dtype="<u8").view(np.uint8)
    return np.unpackbits(as_bytes, axis=1, count=shape[-1], bitorder="little").view(bool).reshape(shape)
