"""What crosses the face between two blocks of a volume (numba): the
census of a *seam*, the two voxel layers on either side of the face, for
the report block by block (:mod:`isoflow.digital.outofcore`).

A seam's voxels carry the node keys of their blocks' components (object
keys ``fg``, background keys ``bg``). Three passes over it:

* its vertices, those between the two layers that the seam counts (each
  vertex of the volume is counted by one block or one seam): the
  configuration histogram; every sheet of a configuration (tables from
  :func:`isoflow.scale.sweep.sheet_tables`) adds ``4 - q`` to the key of its
  voxel on the side that counts sheets, a pinch adds 8 to the key of the
  formula side around it and joins the keys of its two voxels, and a
  doubled spoke is a loose end whose other end is counted elsewhere;
* its cells, which the blocks' own sums leave out since they lie in two
  blocks: a pair of face neighbours of one kind across the face is a face
  counted twice (-2 faces); on the side whose Euler characteristic comes
  from the formula over runs, such a pair is an edge (-1), four voxels of a
  square across the face a square (+1), eight of a cube a cube (-1);
* the pairs of neighbouring voxels of one kind across the face, under
  either side's adjacency: the keys to join.

Per key the sums are added up in a small open-addressing hash table, since
a seam holds few pieces; every buffer that fills up is made larger and the
seam counted again.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from .jit import njit

_EMPTY = -1
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
    if key != _EMPTY:
        used += _add(table[0], table[1], table[2], key, dv, dq)
    return used


@njit(cache=True, nogil=True, inline="always")
def _nibble(vox, j, k):
    """Voxels (t, j - 1 + p, k) of the seam as bits t + 2 p (clear outside)."""
    _, n1, n2 = vox.shape
    c = 0
    if 0 <= k < n2:
        if j >= 1:
            c |= vox[0, j - 1, k] | (vox[1, j - 1, k] << 1)
        if j < n1:
            c |= (vox[0, j, k] << 2) | (vox[1, j, k] << 3)
    return c


@njit(cache=True, nogil=True, inline="always")
def _octant_key(vox, fg, bg, j, k, o, outside):
    """The key of octant ``o`` (t + 2 p + 4 q) of vertex (1, j, k) and its
    sign in the sums (+1 for the object, -1 for the background);
    ``outside`` beyond the seam."""
    t, y, z = o & 1, j - 1 + ((o >> 1) & 1), k - 1 + (o >> 2)
    if 0 <= y < vox.shape[1] and 0 <= z < vox.shape[2]:
        if vox[t, y, z]:
            return fg[t, y, z], 1
        return bg[t, y, z], -1
    return np.int64(outside), -1


@njit(cache=True, nogil=True)
def _vertices(vox, fg, bg, lo, hi, outside, tables, formula_obj, order, octant, table, hist, pairs, loose):
    """The vertices (1, j, k), lo <= (j, k) < hi, of a seam whose axis is
    first: histogram, sheets and pinches into the hash ``table`` (keys, 4
    chi, faces), pinch ``pairs``, loose ends (j, k, spoke bit). ``order``
    turns the seam's configuration code into the volume's, ``octant`` the
    volume's octants into the seam's. Returns the pinch pairs and loose
    ends found (also past the buffers) and whether the table filled up."""
    used = npairs = nloose = 0
    run, dv = _EMPTY, 0  # the key being added to, and what it gained so far
    for j in range(lo[0], hi[0]):
        before = _nibble(vox, j, lo[1] - 1)
        for k in range(lo[1], hi[1]):
            now = _nibble(vox, j, k)
            c = order[before | (now << 4)]
            before = now
            hist[c] += 1
            if c == 0 or c == 255:
                continue
            for s in range(tables.nsheet[c]):
                key, sign = _octant_key(vox, fg, bg, j, k, octant[tables.octant[c, s]], outside)
                if key != run:
                    used = _flush(table, run, dv, 0, used)
                    run, dv = key, 0
                dv += sign * tables.values[c, s]
            if tables.pinch[c, 0] >= 0:
                o = 0  # the six other octants: one component of the formula side
                while ((c >> o) & 1) != formula_obj:
                    o += 1
                key, sign = _octant_key(vox, fg, bg, j, k, octant[o], outside)
                used = _flush(table, key, 8 * sign, 0, used)
                a = _octant_key(vox, fg, bg, j, k, octant[tables.pinch[c, 0]], outside)[0]
                b = _octant_key(vox, fg, bg, j, k, octant[tables.pinch[c, 1]], outside)[0]
                if a != b:
                    if npairs < len(pairs):
                        pairs[npairs, 0], pairs[npairs, 1] = a, b
                    npairs += 1
            for d in range(6):
                if (tables.spokes[c] >> d) & 1:
                    if nloose < len(loose):
                        loose[nloose, 0], loose[nloose, 1], loose[nloose, 2] = j, k, d
                    nloose += 1
            if 2 * used > len(table[0]):
                return npairs, nloose, True
    used = _flush(table, run, dv, 0, used)
    return npairs, nloose, 2 * used > len(table[0])


@njit(cache=True, nogil=True, inline="always")
def _formula(vox, formula_obj, j, k):
    """Whether voxels (0, j, k) and (1, j, k) are both of the formula side
    (False outside the seam)."""
    return j < vox.shape[1] and k < vox.shape[2] and vox[0, j, k] == formula_obj and vox[1, j, k] == formula_obj


@njit(cache=True, nogil=True)
def _cells(vox, fg, bg, own, formula_obj, table):
    """The cells across the face of a seam whose axis is first, with their
    first voxel (0, j, k) the block's own (``own``: its extent along j and
    k; the seam reaches one voxel further where the next block along that
    axis takes part), into the hash ``table``: a pair of one kind is a face
    counted twice; on the formula side it is an edge, with the squares and
    the cube that follow it along j and k. Returns whether the table filled
    up."""
    used = 0
    run, dv, dq = _EMPTY, 0, 0
    for j in range(own[0]):
        for k in range(own[1]):
            if vox[0, j, k] != vox[1, j, k]:
                continue
            key, sign = (fg[0, j, k], 1) if vox[0, j, k] else (bg[0, j, k], -1)
            if key != run:
                used = _flush(table, run, dv, dq, used)
                run, dv, dq = key, 0, 0
            dq -= 2 * sign
            if vox[0, j, k] == formula_obj:
                along_j, along_k = _formula(vox, formula_obj, j + 1, k), _formula(vox, formula_obj, j, k + 1)
                cube = along_j and along_k and _formula(vox, formula_obj, j + 1, k + 1)
                dv += 8 * sign * (-1 + along_j + along_k - cube)
            if 2 * used > len(table[0]):
                return True
    used = _flush(table, run, dv, dq, used)
    return 2 * used > len(table[0])


@njit(cache=True, nogil=True)
def _joins(vox, fg, bg, steps_obj, steps_bg, edges):
    """The pairs of neighbouring voxels of one kind across the face of a
    seam whose axis is first, (0, j, k) and (1, j + a, k + b) for (a, b) in
    the object's ``steps`` or the background's: their keys where they
    differ (and 1 for the object, 0 for the background), less those just
    found in the same direction. Returns their number (also past the
    buffer)."""
    n = 0
    last = np.full((9, 2), _EMPTY, np.int64)
    _, n1, n2 = vox.shape
    for j in range(n1):
        for k in range(n2):
            kind = vox[0, j, k]
            steps = steps_obj if kind else steps_bg
            a = fg[0, j, k] if kind else bg[0, j, k]
            for d in range(len(steps)):
                y, z = j + steps[d, 0], k + steps[d, 1]
                if not (0 <= y < n1 and 0 <= z < n2) or vox[1, y, z] != kind:
                    continue
                b = fg[1, y, z] if kind else bg[1, y, z]
                if a == b or (a == last[d, 0] and b == last[d, 1]):
                    continue
                last[d, 0], last[d, 1] = a, b
                if n < len(edges):
                    edges[n, 0], edges[n, 1], edges[n, 2] = a, b, kind
                n += 1
    return n


def _steps(reach: int) -> np.ndarray:
    """The steps (a, b) along the seam's face from a voxel of layer 0 to its
    neighbours in layer 1 under an adjacency (``reach``: how many
    coordinates two neighbours may differ in: 1, 2, 3 for 6, 18, 26)."""
    return np.array([(a, b) for a in (-1, 0, 1) for b in (-1, 0, 1) if 1 + abs(a) + abs(b) <= reach], np.int64)


@lru_cache(maxsize=None)
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


def seam_census(vox: np.ndarray, fg: np.ndarray, bg: np.ndarray, lo, hi, axis: int, own, outside: int, tables,
                formula_obj: bool, reach: tuple[int, int]) -> dict:
    """The census of a seam (see the module docs).

    Parameters
    ----------
    vox : numpy.ndarray
        The seam's voxels (bool, 3D), two layers along ``axis``.
    fg, bg : numpy.ndarray
        Their node keys (int64): of the object voxels, of the background
        voxels (anything elsewhere).
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
        The object's and the background's adjacencies: how many coordinates
        two neighbours may differ in (1, 2, 3 for 6, 18, 26).

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
    >>> found = seam_census(vox, keys, keys + 1, (1, 0, 0), (2, 4, 4), 0, (1, 3, 3), -1,
    ...                     sheet_tables(sweep_tables(6), True), True, (1, 2))
    >>> int(found["hist"].sum()), sorted(set(map(tuple, found["edges"].tolist())))
    (16, [(10, 20, 1), (11, 21, 0)])
    >>> dict(zip(found["keys"].tolist(), zip(found["chi4"].tolist(), found["faces"].tolist())))[10]  # the edge, the face twice
    (-8, -2)
    """
    others = [m for m in range(3) if m != axis]
    vox, fg, bg = (np.ascontiguousarray(np.moveaxis(a, axis, 0)) for a in (vox.view(np.uint8), fg, bg))
    order, octant = _orders(axis)
    lo, hi, own = (np.array([x[m] for m in others], np.int64) for x in (lo, hi, own))
    capacity, room = 1 << 10, 1 << 8
    while True:
        table = (np.full(capacity, _EMPTY, np.int64), np.zeros(capacity, np.int64), np.zeros(capacity, np.int64))
        hist = np.zeros(256, np.int64)
        pairs, loose = np.empty((room, 2), np.int64), np.empty((room, 3), np.int64)
        npairs, nloose, full = _vertices(vox, fg, bg, lo, hi, outside, tables, formula_obj, order, octant, table, hist,
                                         pairs, loose)
        full = full or _cells(vox, fg, bg, own, formula_obj, table)
        if full:
            capacity *= 4
        elif max(npairs, nloose) > room:
            room = max(npairs, nloose)
        else:
            break
    steps = _steps(reach[0]), _steps(reach[1])
    edges = np.empty((max(64, vox.size // 64), 3), np.int64)
    nedges = _joins(vox, fg, bg, *steps, edges)
    if nedges > len(edges):
        edges = np.empty((nedges, 3), np.int64)
        _joins(vox, fg, bg, *steps, edges)
    ends = np.ones((nloose, 4), np.int64)  # (vertex in the volume's axis order, spoke bit)
    ends[:, others[0]], ends[:, others[1]], ends[:, 3] = loose[:nloose, 0], loose[:nloose, 1], loose[:nloose, 2]
    filled = table[0] != _EMPTY
    return {"hist": hist, "keys": table[0][filled], "chi4": table[1][filled], "faces": table[2][filled],
            "pairs": pairs[:npairs], "loose": ends, "edges": edges[:nedges]}
