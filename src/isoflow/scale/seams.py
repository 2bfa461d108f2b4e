"""What crosses the face between two blocks of a volume (numba): the
census of a *seam*, the two voxel layers on either side of the face, for
the report block by block (:mod:`isoflow.digital.outofcore`).

A seam's voxels carry the node keys of their blocks' components (of the
object's or the background's, as the voxel is). Two passes over it:

* its vertices, those between the two layers that the seam counts (each
  vertex of the volume is counted by one block or one seam): the
  configuration histogram; every sheet of a configuration (tables from
  :func:`isoflow.scale.sweep.sheet_tables`) adds ``4 - q`` to the key of its
  voxel on the side that counts sheets, a pinch adds 8 to the key of the
  formula side around it and joins the keys of its two voxels, and a
  doubled spoke is a loose end whose other end is counted elsewhere;
* its voxels on one side of the face: the cells that the blocks' own sums
  leave out since they lie in two blocks (a pair of face neighbours of one
  kind across the face is a face counted twice, -2 faces; on the side
  whose Euler characteristic comes from the formula over runs, such a pair
  is an edge, -1, four voxels of a square across the face a square, +1,
  eight of a cube a cube, -1), and the pairs of neighbouring voxels of one
  kind across the face under either side's adjacency: the keys to join.

Per key the sums are added up in a small open-addressing hash table, since
a seam holds few pieces; every buffer that fills up is made larger and the
seam counted again.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .jit import njit

_EMPTY = -1
_BEYOND = 2  # a padded seam's voxels beyond the seam: of neither kind
_GOLDEN = -7046029254386353131  # 0x9E3779B97F4A7C15 as int64: Fibonacci hashing


@njit(cache=True, nogil=True, inline="always")
def _slot(key, mask):
    h = key * _GOLDEN
    return (h ^ (h >> 29)) & mask


@njit(cache=True, nogil=True)
def _add(keys, vs, qs, key, dv, dq):
    """Add (dv, dq) to ``key``'s entry of the table; returns 1 for a new
    key. The table never grows here; the caller sizes it."""
    mask = len(keys) - 1
    s = _slot(key, mask)
    while keys[s] != _EMPTY and keys[s] != key:
        s = (s + 1) & mask
    if keys[s] == key:
        vs[s] += dv
        qs[s] += dq
        return 0
    keys[s], vs[s], qs[s] = key, dv, dq
    return 1


@njit(cache=True, nogil=True, inline="always")
def _flush(table, key, dv, dq, used):
    """Add a run's sums to the table (nothing for no key); returns the
    entries used."""
    if key != _EMPTY:  # as int64 at every call site (some pass constants): _add compiles once
        used += _add(table[0], table[1], table[2], np.int64(key), np.int64(dv), np.int64(dq))
    return used


@njit(cache=True, nogil=True, inline="always")
def _nibble(vox, j, k):
    """Voxels (t, j - 1 + p, k) of the padded seam as bits t + 2 p (clear
    beyond the seam)."""
    return (vox[0, j - 1, k] & 1) | ((vox[1, j - 1, k] & 1) << 1) | ((vox[0, j, k] & 1) << 2) | ((vox[1, j, k] & 1) << 3)


@njit(cache=True, nogil=True, inline="always")
def _octant_key(vox, keys, j, k, o):
    """The key of octant ``o`` (t + 2 p + 4 q) of vertex (1, j, k) of the
    padded seam and its sign in the sums (+1 for the object, -1 for the
    background and beyond the seam)."""
    t, y, z = o & 1, j - 1 + ((o >> 1) & 1), k - 1 + (o >> 2)
    return keys[t, y, z], 2 * np.int64(vox[t, y, z] & 1) - 1


@njit(cache=True, nogil=True)
def _vertices(vox, keys, lo, hi, tables, formula_obj, order, octant, table, hist, pairs, loose):
    """The vertices (1, j, k), lo <= (j, k) < hi, of a seam whose axis is
    first (``vox`` and ``keys`` padded, :func:`_padded`, so that the
    vertex sees the padded voxels (j .. j + 1, k .. k + 1)): histogram,
    sheets and pinches into the hash ``table`` (keys, 4 chi, faces), pinch
    ``pairs``, loose ends (j, k, spoke bit). ``order``
    turns the seam's configuration code into the volume's, ``octant`` the
    volume's octants into the seam's. Returns the pinch pairs and loose
    ends found (also past the buffers) and whether the table filled up."""
    used = npairs = nloose = 0
    run, dv = _EMPTY, 0  # the key being added to, and what it gained so far
    for j in range(lo[0] + 1, hi[0] + 1):
        before = _nibble(vox, j, lo[1])
        for k in range(lo[1] + 1, hi[1] + 1):
            now = _nibble(vox, j, k)
            c = order[before | (now << 4)]
            before = now
            hist[c] += 1
            if c == 0 or c == 255:
                continue
            for s in range(tables.nsheet[c]):
                key, sign = _octant_key(vox, keys, j, k, octant[tables.octant[c, s]])
                if key != run:
                    used = _flush(table, run, dv, 0, used)
                    run, dv = key, 0
                dv += sign * tables.values[c, s]
            if tables.pinch[c, 0] >= 0:
                o = 0  # the six other octants: one component of the formula side
                while ((c >> o) & 1) != formula_obj:
                    o += 1
                key, sign = _octant_key(vox, keys, j, k, octant[o])
                used = _flush(table, key, 8 * sign, 0, used)
                a = _octant_key(vox, keys, j, k, octant[tables.pinch[c, 0]])[0]
                b = _octant_key(vox, keys, j, k, octant[tables.pinch[c, 1]])[0]
                if a != b:
                    if npairs < len(pairs):
                        pairs[npairs, 0], pairs[npairs, 1] = a, b
                    npairs += 1
            for d in range(6):
                if (tables.spokes[c] >> d) & 1:
                    if nloose < len(loose):
                        loose[nloose, 0], loose[nloose, 1], loose[nloose, 2] = j - 1, k - 1, d
                    nloose += 1
            if 2 * used > len(table[0]):
                return npairs, nloose, True
    used = _flush(table, run, dv, 0, used)
    return npairs, nloose, 2 * used > len(table[0])


@njit(cache=True, nogil=True, inline="always")
def _formula(vox, formula_obj, j, k):
    """1 where voxels (0, j, k) and (1, j, k) of the padded seam are both
    of the formula side, else 0 (also beyond the seam)."""
    return np.int64(vox[0, j, k] == formula_obj) & np.int64(vox[1, j, k] == formula_obj)


@njit(cache=True, nogil=True, inline="always")
def _cell_gain(vox, formula_obj, j, k):
    """What the cells across the face with their first voxel (0, j, k)
    take from its component's sums (4 chi, faces; the voxel pairs with
    (1, j, k), of one kind): a face counted twice, and on the formula side
    an edge, with the squares and the cube that follow it along j and k.
    Without branches: the voxels' kinds follow no pattern a branch
    predictor could learn."""
    sign = 2 * np.int64(vox[0, j, k]) - 1
    along_j, along_k = _formula(vox, formula_obj, j + 1, k), _formula(vox, formula_obj, j, k + 1)
    cube = along_j & along_k & _formula(vox, formula_obj, j + 1, k + 1)
    edge = np.int64(vox[0, j, k] == formula_obj)
    return 8 * sign * edge * (-1 + along_j + along_k - cube), -2 * sign


@njit(cache=True, nogil=True)
def _across(vox, keys, own, formula_obj, steps_obj, steps_bg, table, edges):
    """One pass over the voxels (0, j, k) of a seam whose axis is first
    (``vox`` and ``keys`` padded, :func:`_padded`, so no neighbour is out
    of bounds; below the seam's own coordinates): the cells across the face whose first voxel is the block's own
    (``own``: its extent along j and k; the seam reaches one voxel further
    where the next block along that axis takes part) into the hash
    ``table``, and the pairs of neighbouring voxels of one kind across the
    face, (0, j, k) and (1, j + a, k + b) for (a, b) in the object's
    ``steps`` or the background's, as ``edges``: their keys where they
    differ (and 1 for the object, 0 for the background), less those just
    found in the same direction. A diagonal pair (18-adjacency: along an
    edge) is left out where (1, j, k) or (0, j + a, k + b) is of its kind:
    the two are joined through that voxel, by faces, whose pairs this seam
    or the blocks' own labels or another seam join. Returns the edges found
    (also past the buffer) and whether the table filled up."""
    used = n = 0
    run, dv, dq = _EMPTY, 0, 0
    last = np.full((9, 2), _EMPTY, np.int64)
    _, n1, n2 = vox.shape
    for j in range(1, n1 - 1):
        for k in range(1, n2 - 1):
            kind, a = vox[0, j, k], keys[0, j, k]
            straight = vox[1, j, k] == kind
            if straight and j <= own[0] and k <= own[1]:
                if a != run:
                    used = _flush(table, run, dv, dq, used)
                    run, dv, dq = a, 0, 0
                chi, faces = _cell_gain(vox, formula_obj, j, k)
                dv, dq = dv + chi, dq + faces
                if 2 * used > len(table[0]):
                    return n, True
            steps = steps_obj if kind else steps_bg
            if straight:  # the step (0, 0), the middle one; the diagonals join through it
                d, b = len(steps) // 2, keys[1, j, k]
                if a != b and not (a == last[d, 0] and b == last[d, 1]):
                    last[d, 0], last[d, 1] = a, b
                    if n < len(edges):
                        edges[n, 0], edges[n, 1], edges[n, 2] = a, b, kind
                    n += 1
                continue
            for d in range(len(steps)):
                y, z = j + steps[d, 0], k + steps[d, 1]
                if vox[1, y, z] != kind or vox[0, y, z] == kind:
                    continue  # no pair, or joined through a voxel face-adjacent to both
                b = keys[1, y, z]
                if a == b or (a == last[d, 0] and b == last[d, 1]):
                    continue
                last[d, 0], last[d, 1] = a, b
                if n < len(edges):
                    edges[n, 0], edges[n, 1], edges[n, 2] = a, b, kind
                n += 1
    used = _flush(table, run, dv, dq, used)
    return n, 2 * used > len(table[0])


@cache
def _steps(reach: int) -> np.ndarray:
    """The steps (a, b) along the seam's face from a voxel of layer 0 to its
    neighbours in layer 1 under an adjacency (``reach``: how many
    coordinates two neighbours may differ in: 1 or 2 for 6 or 18, the
    boundary mesh's adjacencies)."""
    assert reach <= 2, "a diagonal is joined through a face-adjacent voxel: not so under 26"
    # the step (0, 0) is the middle one (_across looks it up there)
    return np.array([(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1) if 1 + abs(a) + abs(b) <= reach], np.int64)


@cache
def _orders(axis: int) -> tuple[np.ndarray, np.ndarray]:
    """For a seam turned so that ``axis`` comes first: the volume's
    configuration code of each of the seam's, and the seam's octant of each
    of the volume's."""
    others = [m for m in range(3) if m != axis]
    octant = np.zeros(8, np.int64)
    for o in range(8):  # the volume's octant: bit m is the offset along axis m
        t, p, q = (o >> axis) & 1, (o >> others[0]) & 1, (o >> others[1]) & 1
        octant[o] = t | (p << 1) | (q << 2)
    order = np.zeros(256, np.int64)
    for c in range(256):
        order[sum(1 << int(octant[o]) for o in range(8) if (c >> o) & 1)] = c
    return order, octant


def _padded(vox: np.ndarray, keys: np.ndarray, outside: int) -> tuple[np.ndarray, np.ndarray]:
    """The seam (axis first) with one more voxel on either side along j and
    k, of neither kind (:data:`_BEYOND`, clear in the vertices'
    configurations) and of the ``outside`` key: the volume beyond the seam
    as the vertices on its rim see it, with no bounds to check."""
    _, n1, n2 = vox.shape
    padded = np.full((2, n1 + 2, n2 + 2), _BEYOND, np.uint8), np.full((2, n1 + 2, n2 + 2), outside, np.int64)
    for whole, part in zip(padded, (vox, keys)):
        whole[:, 1:-1, 1:-1] = part
    return padded


def seam_census(vox: np.ndarray, keys: np.ndarray, lo, hi, axis: int, own, outside: int, tables, formula_obj: bool,
                reach: tuple[int, int]) -> dict:
    """The census of a seam (see the module docs).

    Parameters
    ----------
    vox : numpy.ndarray
        The seam's voxels (bool, 3D), two layers along ``axis``.
    keys : numpy.ndarray
        Their node keys (int64), of their object or background components.
    lo, hi : sequence of int
        The box of vertices the seam counts (vertex ``w`` between voxels
        ``w - 1`` and ``w``; along ``axis`` the one vertex 1).
    axis : int
        The axis across the face.
    own : sequence of int
        The extent of the block's own voxels along each axis (the seam may
        reach one voxel further).
    outside : int
        The key of the voxels beyond the seam (the volume's outside).
    tables : Tables
        Those of :func:`isoflow.scale.sweep.sheet_tables`.
    formula_obj : bool
        Whether the object's Euler characteristic comes from its cells.
    reach : tuple of int
        The object's and the background's adjacencies, those of the
        boundary mesh: how many coordinates two neighbours may differ in (1
        or 2 for 6 or 18).

    Returns
    -------
    dict
        ``hist``; ``keys``, ``chi4`` and ``faces``: per key, signed (+ for
        the object, - for the background), what its surfaces gain, 4 chi and
        faces; the pinch ``pairs`` (keys); the ``loose`` ends (vertex, spoke
        bit); the ``edges`` (keys to join, and 1 for the object's, 0 for the
        background's).

    Examples
    --------
    >>> from isoflow.digital.closed_surfaces import sweep_tables
    >>> from isoflow.scale.sweep import sheet_tables
    >>> vox = np.zeros((2, 3, 3), bool); vox[:, 1, 1] = True  # a bar across the face
    >>> keys = np.array([10, 20]).repeat(9).reshape(2, 3, 3)
    >>> keys = np.where(vox, keys, keys + 1)
    >>> found = seam_census(vox, keys, (1, 0, 0), (2, 4, 4), 0, (1, 3, 3), -1, sheet_tables(sweep_tables(6), True),
    ...                     True, (1, 2))
    >>> int(found["hist"].sum()), sorted(set(map(tuple, found["edges"].tolist())))
    (16, [(10, 20, 1), (11, 21, 0)])
    >>> dict(zip(found["keys"].tolist(), zip(found["chi4"].tolist(), found["faces"].tolist())))[10]  # the edge, the face twice
    (-8, -2)
    """
    others = [m for m in range(3) if m != axis]
    vox, keys = np.moveaxis(vox.view(np.uint8), axis, 0), np.moveaxis(keys, axis, 0)
    order, octant = _orders(axis)
    lo, hi, own = (np.array([x[m] for m in others], np.int64) for x in (lo, hi, own))
    steps = _steps(reach[0]), _steps(reach[1])
    padded = _padded(vox, keys, outside)
    capacity, room, joins = 1 << 10, 1 << 8, max(64, vox.size // 4)
    while True:
        table = (np.full(capacity, _EMPTY, np.int64), np.zeros(capacity, np.int64), np.zeros(capacity, np.int64))
        hist = np.zeros(256, np.int64)
        pairs, loose = np.empty((room, 2), np.int64), np.empty((room, 3), np.int64)
        edges = np.empty((joins, 3), np.int64)
        npairs, nloose, full = _vertices(*padded, lo, hi, tables, formula_obj, order, octant, table, hist, pairs,
                                         loose)
        nedges, full_too = (0, True) if full else _across(*padded, own, formula_obj, *steps, table, edges)
        if full or full_too:
            capacity *= 4
        elif max(npairs, nloose) > room or nedges > joins:
            room, joins = max(room, npairs, nloose), max(joins, nedges)
        else:
            break
    ends = np.ones((nloose, 4), np.int64)  # (vertex in the volume's axis order, spoke bit)
    ends[:, others[0]], ends[:, others[1]], ends[:, 3] = loose[:nloose, 0], loose[:nloose, 1], loose[:nloose, 2]
    filled = table[0] != _EMPTY
    return {"hist": hist, "keys": table[0][filled], "chi4": table[1][filled], "faces": table[2][filled],
            "pairs": pairs[:npairs], "loose": ends, "edges": edges[:nedges]}
