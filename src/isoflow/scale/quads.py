"""The boundary quad mesh from bit rows (numba): vertices, faces and each
vertex's configuration and sheet, written straight into the mesh's arrays.

The mesh is the one :func:`isoflow.digital.surface.boundary_mesh` defines
(its tables come in as ``tables``: :func:`isoflow.digital.surface.row_tables`); this module
only knows lattice points, words and counts. A lattice vertex is on the
surface where its eight voxels are not all equal; on four bit rows (the
voxel rows around a row of vertices, :mod:`isoflow.scale.bitrows`) a few
word operations find those vertices 64 at a time, and only they are
visited. Each vertex gives its *items* in lattice order: one mesh vertex per
sheet, then two midpoints for each doubled lattice edge that leaves it
toward +x, +y, +z (that edge's two passes, the pair owning the midpoint told
apart by the side of the pair's voxel along the lower of the two axes
across the edge). Each face belongs to its lowest corner, so a vertex owns
at most three faces (one per normal axis, between octant 7 and octant
``7 - 2^axis``).

Two passes, each over slabs of vertex planes on the threads:

1. :func:`count_planes`: the items of every plane (split into the 27
   classes of a box, below), the faces each plane owns and their
   references to midpoints (the triangles they make);
2. :func:`fill_planes`: with each slab's first item and face known from the
   counts, a slab numbers its planes' items in lattice order, keeping the
   numbers, configurations and doubled edges of two planes at a time
   (plane ``p`` and ``p + 1``: a face's corners lie in both), and writes its
   vertices and faces into the mesh's arrays.

No array the size of the volume is made: the numbering is a running count,
not a cumulative sum over every lattice point.

A *box* restricts both passes to part of the lattice, for meshing a large
volume block by block: per axis ``(lo, hi, t0, t1)``, the lattice points
``lo .. hi`` are numbered, those in ``lo .. t1 - 1`` are the box's own
(their vertices and the faces whose lowest corner they are get written),
and each coordinate has a class ``(v > t0) + (v >= t1)``: 0 on a block's
lower seam, 1 inside, 2 on the upper seam (the neighbour's). Items are
numbered per class of their vertex (27 classes), each from its own start:
a block and its neighbours number the points of a seam alike. A whole
volume is one box with every point in class 1.
"""

from __future__ import annotations

import numpy as np

from .arrays import index_dtype
from .bitrows import config_at, trailing_zeros
from .jit import njit

#: the corners of a face with normal +e_a, counter-clockwise seen from
#: outside, as (d_j, d_k) of its window slot; the corner sits at
#: ``lowest corner + (1 - d_j) e_j + (1 - d_k) e_k``, (j, k) = (a+1, a+2) mod 3
CORNER_D = np.array([[1, 1], [0, 1], [0, 0], [1, 0]], np.int64)

#: the classes of a box's points (3 per axis)
CLASSES = 27


@njit(cache=True, nogil=True)
def _doubled(bits, nx, ny, nz, i, j, k, c, dspoke):
    """Bit a set: the lattice edge from (i, j, k) toward +e_a is doubled
    (a doubled spoke at both of its ends)."""
    m = 0
    for a in range(3):
        if dspoke[c, a, 1]:
            cn = config_at(bits, nx, ny, nz, i + (a == 0), j + (a == 1), k + (a == 2))
            if dspoke[cn, a, 0]:
                m |= 1 << a
    return m


@njit(cache=True, nogil=True, inline="always")
def _bits3(m):
    return (m & 1) + ((m >> 1) & 1) + ((m >> 2) & 1)


@njit(cache=True, nogil=True, inline="always")
def _cls(v, t0, t1):
    return (v > t0) + (v >= t1)


@njit(cache=True, nogil=True, inline="always")
def _row(x, y, nx, ny):
    """The bit row of voxel row (x, y); the clear last row outside."""
    if 0 <= x < nx and 0 <= y < ny:
        return x * ny + y
    return nx * ny


@njit(cache=True, nogil=True, inline="always")
def _vertex_rows(p, j, nx, ny):
    """The four voxel rows around vertex row (p, j), row dx + 2 dy being
    (p - 1 + dx, j - 1 + dy), and whether all four lie outside the array."""
    r0, r1 = _row(p - 1, j - 1, nx, ny), _row(p, j - 1, nx, ny)
    r2, r3 = _row(p - 1, j, nx, ny), _row(p, j, nx, ny)
    return r0, r1, r2, r3, r0 == r1 == r2 == r3


@njit(cache=True, nogil=True, inline="always")
def _carry_into(bits, w, r0, r1, r2, r3):
    """The top bits of the four rows' words before word w."""
    if w == 0:
        return np.uint64(0)
    return _surface_word(bits, w - 1, r0, r1, r2, r3, np.uint64(0))[9]


@njit(cache=True, nogil=True, inline="always")
def _word_range(lo, hi, w):
    """Bits of word w that are lattice points lo .. hi."""
    m = ~np.uint64(0)
    if w == lo >> 6:
        m &= ~np.uint64(0) << np.uint64(lo & 63)
    if w == hi >> 6 and (hi & 63) != 63:
        m &= (np.uint64(1) << np.uint64((hi & 63) + 1)) - np.uint64(1)
    return m


@njit(cache=True, nogil=True, inline="always")
def _surface_word(bits, w, r0, r1, r2, r3, carry):
    """The four rows' words, the same shifted by one voxel (bit k: voxel
    k - 1, from ``carry``: the previous words' top bits), and the vertices
    of the word whose eight voxels differ."""
    x0, x1, x2, x3 = bits[r0, w], bits[r1, w], bits[r2, w], bits[r3, w]
    one, top = np.uint64(1), np.uint64(63)
    p0 = (x0 << one) | (carry & one)
    p1 = (x1 << one) | ((carry >> one) & one)
    p2 = (x2 << one) | ((carry >> np.uint64(2)) & one)
    p3 = (x3 << one) | ((carry >> np.uint64(3)) & one)
    every = x0 & x1 & x2 & x3 & p0 & p1 & p2 & p3
    none = ~(x0 | x1 | x2 | x3 | p0 | p1 | p2 | p3)
    carry = (x0 >> top) | ((x1 >> top) << one) | ((x2 >> top) << np.uint64(2)) | ((x3 >> top) << np.uint64(3))
    return x0, x1, x2, x3, p0, p1, p2, p3, ~(every | none), carry


@njit(cache=True, nogil=True, inline="always")
def _config_bits(b, x0, x1, x2, x3, p0, p1, p2, p3):
    """Configuration of the vertex at bit b of a word (octant dx + 2 dy +
    4 dz: row dx + 2 dy, voxel k - 1 + dz)."""
    one = np.uint64(1)
    return np.int64(((p0 >> b) & one) | (((p1 >> b) & one) << one) | (((p2 >> b) & one) << np.uint64(2))
                    | (((p3 >> b) & one) << np.uint64(3)) | (((x0 >> b) & one) << np.uint64(4))
                    | (((x1 >> b) & one) << np.uint64(5)) | (((x2 >> b) & one) << np.uint64(6))
                    | (((x3 >> b) & one) << np.uint64(7)))


@njit(cache=True, nogil=True, inline="always")
def _owned(v, lo, t1):
    return lo <= v < t1


@njit(cache=True, nogil=True)
def _count_refs(box, i, j, k, dm):
    """Faces owned by the box (lowest corner in it) that reference a
    midpoint of the doubled edges ``dm`` leaving (i, j, k): each such edge
    has four faces, two with their lowest corner at (i, j, k) and one at
    each of (i, j, k) - e_n, n the two axes across the edge; each face
    references one of the edge's midpoints."""
    n = 0
    w = (i, j, k)
    for a in range(3):
        if not (dm >> a) & 1:
            continue
        for f in range(4):
            c0, c1, c2 = w[0], w[1], w[2]
            if f >= 2:
                n_ax = (a + f - 1) % 3  # f = 2, 3: the two axes across the edge
                if n_ax == 0:
                    c0 -= 1
                elif n_ax == 1:
                    c1 -= 1
                else:
                    c2 -= 1
            if (_owned(c0, box[0, 0], box[0, 3]) and _owned(c1, box[1, 0], box[1, 3])
                    and _owned(c2, box[2, 0], box[2, 3])):
                n += 1
    return n


@njit(cache=True, nogil=True, _nrt=False)
def _plane(bits, nx, ny, nz, box, p, counters, idmap, cfgmap, dmmap, nsheet, dspoke, dflag, pinch, keep, write,
           vbase, origin, vertices, config, sheet, tally):
    """Number plane p's items in lattice order (``counters``: the next
    number of each class, advanced); with ``keep``, keep each surface
    vertex's first number, configuration and doubled edges in the plane's
    maps; with ``write``, write the box's own vertices. Adds the faces the
    box owns here and their references to midpoints to ``tally``. Returns
    the pinched vertices written."""
    pinched = 0
    s = p & 1
    cx = _cls(p, box[0, 2], box[0, 3])
    ly, lz = box[1, 0], box[2, 0]
    for j in range(box[1, 0], box[1, 1] + 1):
        cxy = cx + 3 * _cls(j, box[1, 2], box[1, 3])
        own_xy = cxy % 3 != 2 and cxy // 3 != 2
        r0, r1, r2, r3, outside = _vertex_rows(p, j, nx, ny)
        if outside:
            continue
        w0, w1 = box[2, 0] >> 6, box[2, 1] >> 6
        carry = _carry_into(bits, w0, r0, r1, r2, r3)
        for w in range(w0, w1 + 1):
            x0, x1, x2, x3, q0, q1, q2, q3, surf, carry = _surface_word(bits, w, r0, r1, r2, r3, carry)
            surf &= _word_range(box[2, 0], box[2, 1], w)
            while surf:
                b = trailing_zeros(surf)
                surf &= surf - np.uint64(1)
                k = w * 64 + np.int64(b)
                c = _config_bits(b, x0, x1, x2, x3, q0, q1, q2, q3)
                ck = _cls(k, box[2, 2], box[2, 3])
                cl = cxy + 9 * ck
                dm = _doubled(bits, nx, ny, nz, p, j, k, c, dspoke) if dflag[c] else 0
                first = counters[cl]
                counters[cl] = first + nsheet[c] + 2 * _bits3(dm)
                if keep:
                    idmap[s, j - ly, k - lz] = first
                    cfgmap[s, j - ly, k - lz] = c
                    dmmap[s, j - ly, k - lz] = dm
                if dm:
                    tally[1] += _count_refs(box, p, j, k, dm)
                if own_xy and ck != 2:
                    top = (c >> 7) & 1
                    tally[0] += (top != ((c >> 6) & 1)) + (top != ((c >> 5) & 1)) + (top != ((c >> 3) & 1))
                    if write:
                        _write_vertex(first - vbase, c, dm, nsheet[c], origin[0] + p, origin[1] + j, origin[2] + k,
                                      vertices, config, sheet)
                        pinched += pinch[c]
    return pinched


@njit(cache=True, nogil=True)
def _count_planes(bits, nx, ny, nz, box, p0, p1, nsheet, dspoke, dflag, pinch, items, tally):
    """Pass 1 over vertex planes p0 <= p < p1 (see :func:`count_planes`)."""
    maps = np.empty((2, 1, 1), np.int64)
    small = np.empty((2, 1, 1), np.uint8)
    vertices, config, sheet = np.empty((0, 3)), np.empty(0, np.uint8), np.empty(0, np.int8)
    origin = np.zeros(3, np.int64)
    for p in range(p0, p1):
        _plane(bits, nx, ny, nz, box, p, items[p - p0], maps, small, small, nsheet, dspoke, dflag, pinch, False,
               False, 0, origin, vertices, config, sheet, tally[p - p0])


def count_planes(bits: np.ndarray, shape: tuple[int, int, int], box: np.ndarray, p0: int, p1: int,
                 tables: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pass 1 over the box's vertex planes ``p0 <= p < p1``.

    Parameters
    ----------
    bits : numpy.ndarray
        The volume's bit rows (:func:`isoflow.scale.bitrows.pack`).
    shape : tuple of int
        The volume's shape.
    box : numpy.ndarray
        (3, 4) int64: per axis ``lo, hi, t0, t1`` (see the module docs;
        :func:`whole_box` for a whole volume).
    p0, p1 : int
        The vertex planes (first axis) to count.
    tables : tuple of numpy.ndarray
        :func:`isoflow.digital.surface.row_tables`.

    Returns
    -------
    items : numpy.ndarray
        (p1 - p0, 27) int64: each plane's items (mesh vertices) per class.
    faces : numpy.ndarray
        (p1 - p0,) the faces the box owns in each plane.
    refs : numpy.ndarray
        (p1 - p0,) the references of those faces to midpoints: a face with
        m midpoints is ``2 + m`` triangles.

    Examples
    --------
    >>> from isoflow.scale.bitrows import pack
    >>> from isoflow.digital.surface import row_tables
    >>> cube = np.ones((1, 1, 1), bool)
    >>> items, faces, refs = count_planes(pack(cube)[0], (1, 1, 1), whole_box((1, 1, 1)), 0, 2, row_tables(6))
    >>> items[:, 13].tolist(), faces.tolist(), refs.tolist()  # the +x face's lowest corner is on plane 1
    ([4, 4], [5, 1], [0, 0])
    """
    nsheet, _, dspoke, dflag, pinch = tables
    n = max(p1 - p0, 0)
    items = np.zeros((n, CLASSES), np.int64)
    tally = np.zeros((n, 2), np.int64)
    nx, ny, nz = shape
    _count_planes(bits, nx, ny, nz, box, p0, p1, nsheet, dspoke, dflag, pinch, items, tally)
    return items, tally[:, 0], tally[:, 1]


@njit(cache=True, nogil=True, inline="always")
def _write_vertex(at, c, dm, ns, x, y, z, vertices, config, sheet):
    """A lattice vertex's sheets, then its doubled edges' midpoints."""
    for t in range(ns):
        vertices[at + t, 0], vertices[at + t, 1], vertices[at + t, 2] = x, y, z
        config[at + t] = c
        sheet[at + t] = t
    at += ns
    for a in range(3):
        if (dm >> a) & 1:
            for _ in range(2):
                vertices[at, 0] = x + 0.5 * (a == 0)
                vertices[at, 1] = y + 0.5 * (a == 1)
                vertices[at, 2] = z + 0.5 * (a == 2)
                config[at] = 0
                sheet[at] = -1
                at += 1


@njit(cache=True, nogil=True, _nrt=False)
def _emit_faces(bits, nx, ny, nz, box, p, f, idmap, cfgmap, dmmap, nsheet, sheets, lower_owner, cd, corner, faces,
                midpoint, normals):
    """Write the faces whose lowest corner is one of plane p's own
    vertices, from face number f on; returns the next number.
    ``lower_owner``: the voxel a face's pair of an edge contact is told by
    is the lower one (object voxel under 6, background under 26) for a
    face with normal +e_a; ``corner``: scratch (4, 5)."""
    ly, lz = box[1, 0], box[2, 0]
    for j in range(box[1, 0], box[1, 3]):
        r0, r1, r2, r3, outside = _vertex_rows(p, j, nx, ny)
        if outside:
            continue
        last = box[2, 3] - 1
        w0, w1 = box[2, 0] >> 6, last >> 6
        carry = _carry_into(bits, w0, r0, r1, r2, r3)
        for w in range(w0, w1 + 1):
            x0, x1, x2, x3, q0, q1, q2, q3, surf, carry = _surface_word(bits, w, r0, r1, r2, r3, carry)
            own = ((x2 ^ x3) | (x1 ^ x3) | (x3 ^ q3)) & _word_range(box[2, 0], last, w)
            while own:
                b = trailing_zeros(own)
                own &= own - np.uint64(1)
                k = w * 64 + np.int64(b)
                c = _config_bits(b, x0, x1, x2, x3, q0, q1, q2, q3)
                top = (c >> 7) & 1
                for a in range(3):
                    below = (c >> (7 - (1 << a))) & 1
                    if below != top:
                        f = _face(p, j, k, a, below == 1, f, ly, lz, idmap, cfgmap, dmmap, nsheet, sheets,
                                  lower_owner, cd, corner, faces, midpoint, normals)
    return f


@njit(cache=True, nogil=True, _nrt=False, inline="always")
def _face(p, j, k, a, plus, f, ly, lz, idmap, cfgmap, dmmap, nsheet, sheets, lower_owner, cd, corner, faces,
          midpoint, normals):
    """Face f: normal axis a (+e_a when ``plus``), lowest corner (p, j, k).
    ``corner[t]``: its corners' first number, configuration, doubled
    edges, number, midpoint of edge t -> t + 1."""
    ja, ka = (a + 1) % 3, (a + 2) % 3
    doubled = 0
    for t in range(4):
        dj, dk = cd[t, 0], cd[t, 1]
        x = p + (1 - dj) * (ja == 0) + (1 - dk) * (ka == 0)
        y = j + (1 - dj) * (ja == 1) + (1 - dk) * (ka == 1)
        z = k + (1 - dj) * (ja == 2) + (1 - dk) * (ka == 2)
        s, yy, zz = x & 1, y - ly, z - lz
        cc = np.int64(cfgmap[s, yy, zz])
        corner[t, 0] = idmap[s, yy, zz]
        corner[t, 1] = cc
        corner[t, 2] = dmmap[s, yy, zz]
        corner[t, 3] = corner[t, 0] + sheets[cc, 4 * a + dj + 2 * dk]
        corner[t, 4] = -1
        doubled |= corner[t, 2]
    if doubled:  # an edge of the face may be doubled: its lower end says so
        for t in range(4):
            u = (t + 1) % 4
            dj0, dk0, dj1, dk1 = cd[t, 0], cd[t, 1], cd[u, 0], cd[u, 1]
            e, m, dm_ = (ja, ka, dk0) if dj0 != dj1 else (ka, ja, dj0)
            low = t if dj0 + dk0 > dj1 + dk1 else u  # the coordinate grows from t when d goes 1 -> 0
            if (corner[low, 2] >> e) & 1:
                # the pair's voxel along the lower axis across the edge:
                # below (0) or above (1) it; the two pairs' are diagonal
                bit = (0 if plus == lower_owner else 1) if a < m else dm_
                corner[t, 4] = (corner[low, 0] + nsheet[corner[low, 1]]
                                + 2 * _bits3(corner[low, 2] & ((1 << e) - 1)) + bit)
    if plus:
        for t in range(4):
            faces[f, t] = corner[t, 3]
            midpoint[f, t] = corner[t, 4]
    else:
        for t in range(4):
            faces[f, t] = corner[3 - t, 3]
        midpoint[f, 0], midpoint[f, 1], midpoint[f, 2], midpoint[f, 3] = (corner[2, 4], corner[1, 4], corner[0, 4],
                                                                          corner[3, 4])
    normals[f, 0] = normals[f, 1] = normals[f, 2] = 0
    normals[f, a] = 1 if plus else -1
    return f + 1


@njit(cache=True, nogil=True)
def _fill_planes(bits, nx, ny, nz, box, p0, p1, counters, vbase, fbase, nsheet, sheets, dspoke, dflag, pinch,
                 lower_owner, origin, vertices, config, sheet, faces, midpoint, normals):
    """Pass 2 over the box's own vertex planes p0 <= p < p1 (see
    :func:`fill_planes`). Returns the pinched vertices written."""
    nj, nk = box[1, 1] - box[1, 0] + 1, box[2, 1] - box[2, 0] + 1
    idmap = np.empty((2, nj, nk), np.int64)
    cfgmap = np.empty((2, nj, nk), np.uint8)
    dmmap = np.empty((2, nj, nk), np.uint8)
    corner = np.empty((4, 5), np.int64)
    tally = np.zeros(2, np.int64)
    cd = CORNER_D
    # write as a runtime flag, as in the loop below: numba compiles _plane once for both calls
    pinched = _plane(bits, nx, ny, nz, box, p0, counters, idmap, cfgmap, dmmap, nsheet, dspoke, dflag, pinch, True,
                     np.bool_(True), vbase, origin, vertices, config, sheet, tally)
    f = fbase
    for p in range(p0, p1):
        if p + 1 <= box[0, 1]:
            pinched += _plane(bits, nx, ny, nz, box, p + 1, counters, idmap, cfgmap, dmmap, nsheet, dspoke, dflag,
                              pinch, True, p + 1 < p1, vbase, origin, vertices, config, sheet, tally)
        f = _emit_faces(bits, nx, ny, nz, box, p, f, idmap, cfgmap, dmmap, nsheet, sheets, lower_owner, cd, corner,
                        faces, midpoint, normals)
    return pinched


def fill_planes(bits: np.ndarray, shape: tuple[int, int, int], box: np.ndarray, p0: int, p1: int,
                counters: np.ndarray, vbase: int, fbase: int, tables: tuple, connectivity: int, origin,
                out: tuple) -> int:
    """Pass 2 over the box's own vertex planes ``p0 <= p < p1``: number
    their items and write the box's own vertices and faces.

    Parameters
    ----------
    bits, shape, box, tables
        As in :func:`count_planes`.
    p0, p1 : int
        The vertex planes to write (own planes of the box).
    counters : numpy.ndarray
        (27,) int64: the number of the first item of each class at plane
        ``p0`` (advanced in place).
    vbase : int
        Item ``n`` is written at row ``n - vbase`` of the vertex arrays.
    fbase : int
        The row of the first face written.
    connectivity : {6, 26}
        Which voxel of an edge contact a pair of faces belongs to (for the
        midpoints of doubled edges).
    origin : sequence of int
        The lattice coordinates of the bit rows' point (0, 0, 0).
    out : tuple of numpy.ndarray
        ``(vertices, config, sheet, faces, edge_midpoint, face_normals)``
        as :class:`isoflow.digital.surface.QuadMesh` holds them.

    Returns
    -------
    int
        The pinched vertices written (sheet 0 of a configuration in the
        tables' pinch table).

    Examples
    --------
    >>> from isoflow.scale.bitrows import pack
    >>> from isoflow.digital.surface import row_tables
    >>> out = (np.empty((8, 3)), np.empty(8, np.uint8), np.empty(8, np.int8), np.empty((6, 4), np.int32),
    ...        np.empty((6, 4), np.int32), np.empty((6, 3), np.int8))
    >>> counters = np.zeros(27, np.int64)
    >>> fill_planes(pack(np.ones((1, 1, 1), bool))[0], (1, 1, 1), whole_box((1, 1, 1)), 0, 2, counters, 0, 0,
    ...             row_tables(6), 6, (0, 0, 0), out)
    0
    >>> out[3][0].tolist(), out[5][0].tolist()  # the -x face, its corners seen from outside
    ([1, 3, 2, 0], [-1, 0, 0])
    """
    nsheet, sheets, dspoke, dflag, pinch = tables
    nx, ny, nz = shape
    return int(_fill_planes(bits, nx, ny, nz, box, p0, p1, counters, vbase, fbase, nsheet, sheets, dspoke, dflag,
                            pinch, connectivity == 6, np.asarray(origin, np.int64), *out))


def whole_box(shape: tuple[int, int, int]) -> np.ndarray:
    """The box of a whole volume: every lattice point numbered and own, in
    class 1.

    Parameters
    ----------
    shape : tuple of int
        The volume's shape.

    Returns
    -------
    numpy.ndarray
        (3, 4) int64, per axis ``lo, hi, t0, t1`` (see the module docs).

    Examples
    --------
    >>> whole_box((2, 3, 4)).tolist()
    [[0, 2, -1, 3], [0, 3, -1, 4], [0, 4, -1, 5]]
    """
    return np.array([[0, n, -1, n + 1] for n in shape], np.int64)


def mesh_rows(volume: np.ndarray, tables: tuple, connectivity: int) -> tuple:
    """The boundary mesh of a 3D volume from its bit rows, on the threads.

    Parameters
    ----------
    volume : numpy.ndarray
        3D, nonzero for the object (any memory order).
    tables : tuple of numpy.ndarray
        :func:`isoflow.digital.surface.row_tables` of ``connectivity``.
    connectivity : {6, 26}
        The object's connectivity.

    Returns
    -------
    tuple
        ``(vertices, config, sheet, faces, edge_midpoint, face_normals,
        pinched)`` as :class:`isoflow.digital.surface.QuadMesh` holds them
        (vertices float64 in array-corner units, faces and midpoints in
        :func:`isoflow.scale.arrays.index_dtype`), vertices numbered in
        lattice order with each lattice vertex's midpoints after its sheets.

    Examples
    --------
    >>> from isoflow.digital.surface import row_tables
    >>> vertices, config, sheet, faces, midpoint, normals, pinched = mesh_rows(np.ones((1, 1, 2), bool),
    ...                                                                        row_tables(6), 6)
    >>> len(vertices), len(faces), pinched
    (12, 10, 0)
    """
    from .bitrows import pack
    from .compiled import run, slabs, thread_count

    bits = pack(volume)[0]
    shape = tuple(int(n) for n in volume.shape)
    box = whole_box(shape)
    parts = slabs(shape[0] + 1, thread_count(int(np.prod(shape))))
    counted = run([(count_planes, bits, shape, box, a, b, tables) for a, b in parts])
    items = np.array([c[0][:, 13].sum() for c in counted], np.int64)
    nfaces = np.array([c[1].sum() for c in counted], np.int64)
    nv, nf = int(items.sum()), int(nfaces.sum())
    idx = index_dtype(nv)
    out = (np.empty((nv, 3)), np.empty(nv, np.uint8), np.empty(nv, np.int8), np.empty((nf, 4), idx),
           np.empty((nf, 4), idx), np.empty((nf, 3), np.int8))
    vstart = np.concatenate([[0], np.cumsum(items)[:-1]])
    fstart = np.concatenate([[0], np.cumsum(nfaces)[:-1]])
    calls = []
    for (a, b), v0, f0 in zip(parts, vstart, fstart):
        counters = np.zeros(CLASSES, np.int64)
        counters[13] = v0
        calls.append((fill_planes, bits, shape, box, a, b, counters, 0, int(f0), tables, connectivity, (0, 0, 0), out))
    pinched = sum(run(calls))
    return (*out, pinched)
