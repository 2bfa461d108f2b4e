"""The edge census of a triangle mesh in one compiled pass: every undirected
edge with how often it is used each way, the face components, and the
coincident faces of opposite orientation (double-sided faces).

The half-edges are bucketed by their lower vertex instead of sorting all
3M of them (``np.unique``), so the census is linear in the faces: it is
per-mesh set-up that every voxelisation pays, whatever the grid. The
counts are those of a sort (the tests compare with ``np.unique``); only
the order in which edges are listed differs (by the lower vertex, then as
the faces first use them).
"""

from __future__ import annotations

import numpy as np

from ..scale.jit import njit
from ..scale.kernels import find, union
from .crossing_kernels import segment_crossing_side
from .cube_grid import CubeGrid

#: Fibonacci hashing of a face's vertex set: the key times 2**64 / golden
#: ratio, top bits
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


@njit(cache=True, nogil=True)
def _slot_bits(n: int) -> int:
    """Bits of a table with at least twice ``n`` slots (load below 1/2)."""
    bits = 4
    while (1 << bits) < 2 * n:
        bits += 1
    return bits


@njit(cache=True, nogil=True)
def _edges(faces, n_vertices):
    """Distinct undirected edges ``lo < hi`` (grouped by ``lo``), the uses
    of each going lo -> hi (``fwd``) and hi -> lo (``bwd``), the first
    face using each, and each face's component root (the smallest face of
    its component: faces joined across any shared edge).

    The half-edges are bucketed by their lower vertex (a counting sort), and
    each bucket, a handful of edges, is searched for the upper one: memory is
    read in the order of the vertex indices, which meshes keep local."""
    m = faces.shape[0]
    n = max(n_vertices, 1)
    start = np.zeros(n + 1, dtype=np.int64)
    for t in range(m):
        for k in range(3):
            a, b = faces[t, k], faces[t, (k + 1) % 3]
            if a != b:
                start[min(a, b) + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    end = start[:-1].copy()  # each bucket's distinct edges so far: [start[v], end[v])
    hi = np.empty(start[n], dtype=np.int64)
    fwd = np.zeros(start[n], dtype=np.int64)
    bwd = np.zeros(start[n], dtype=np.int64)
    first = np.empty(start[n], dtype=np.int64)
    parent = np.arange(m)
    for t in range(m):
        for k in range(3):
            a, b = faces[t, k], faces[t, (k + 1) % 3]
            if a == b:
                continue
            low, h = (a, b) if a < b else (b, a)
            e = start[low]
            while e < end[low] and hi[e] != h:
                e += 1
            if e == end[low]:
                hi[e] = h
                first[e] = t
                end[low] += 1
            else:
                union(parent, t, first[e])
            if a < b:
                fwd[e] += 1
            else:
                bwd[e] += 1
    ne = 0
    for v in range(n):
        ne += end[v] - start[v]
    lo_out = np.empty(ne, dtype=np.int64)
    hi_out = np.empty(ne, dtype=np.int64)
    fwd_out = np.empty(ne, dtype=np.int64)
    bwd_out = np.empty(ne, dtype=np.int64)
    q = 0
    for v in range(n):
        for e in range(start[v], end[v]):
            lo_out[q], hi_out[q], fwd_out[q], bwd_out[q] = v, hi[e], fwd[e], bwd[e]
            q += 1
    first_out = np.empty(ne, dtype=np.int64)
    q = 0
    for v in range(n):
        for e in range(start[v], end[v]):
            first_out[q] = first[e]
            q += 1
    for t in range(m):
        parent[t] = find(parent, t)
    return lo_out, hi_out, fwd_out, bwd_out, first_out, parent


def edge_table(faces: np.ndarray, n_vertices: int):
    """:func:`census` with what it counts from: ``(lo, hi, fwd, bwd, first,
    root)``, ``first`` the first face using each edge and ``root`` each
    face's component (the smallest face index in it)."""
    f = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    return _edges(f, int(n_vertices))


def census(faces: np.ndarray, n_vertices: int):
    """The undirected edges of ``faces`` and how they are used.

    Parameters
    ----------
    faces : int64 ndarray (M, 3)
        Vertex indices in ``[0, n_vertices)``; a degenerate edge ``a -> a``
        is ignored.
    n_vertices : int

    Returns
    -------
    lo, hi : int64 ndarray (E,)
        The distinct edges, ``lo < hi``, by ``lo`` and then in the order
        the faces first use them.
    fwd, bwd : int64 ndarray (E,)
        How many faces run each edge lo -> hi and hi -> lo.
    components : int
        Face components: faces joined across shared edges.

    Examples
    --------
    >>> lo, hi, fwd, bwd, comps = census(np.array([[0, 1, 2], [0, 2, 3]]), 4)
    >>> lo.tolist(), hi.tolist(), (fwd - bwd).tolist(), comps
    ([0, 0, 0, 1, 2], [1, 2, 3, 2, 3], [1, 0, -1, 1, 1], 1)
    """
    lo, hi, fwd, bwd, _, root = edge_table(faces, n_vertices)
    components = int(np.count_nonzero(root == np.arange(len(root))))
    return lo, hi, fwd, bwd, components


@njit(cache=True, nogil=True)
def _opposite_pairs(faces, n_vertices):
    """For each face, the face it pairs with (same three vertices, opposite
    orientation), or -1; faces are paired in file order, the first face of
    each orientation with the first of the other."""
    m = faces.shape[0]
    bits = _slot_bits(m)
    size = 1 << bits
    shift = np.uint64(64 - bits)
    mask = size - 1
    n = np.uint64(max(n_vertices, 1))
    keys = np.full((size, 3), -1, dtype=np.int64)
    open_even = np.full(size, -1, dtype=np.int64)  # slot -> head of unpaired faces of each parity
    open_odd = np.full(size, -1, dtype=np.int64)
    nxt = np.full(m, -1, dtype=np.int64)  # next unpaired face of the same slot and parity
    tail_even = np.full(size, -1, dtype=np.int64)
    tail_odd = np.full(size, -1, dtype=np.int64)
    mate = np.full(m, -1, dtype=np.int64)
    for t in range(m):
        a, b, c = faces[t, 0], faces[t, 1], faces[t, 2]
        if a == b or b == c or c == a:
            continue
        # rotate the smallest index first: (x, y, z) and (x, z, y) are the
        # two orientations of one vertex set
        if b < a and b < c:
            a, b, c = b, c, a
        elif c < a and c < b:
            a, b, c = c, a, b
        even = b < c
        y, z = (b, c) if even else (c, b)
        h = ((np.uint64(a) * n + np.uint64(y)) * n + np.uint64(z)) * _GOLDEN
        s = np.int64(h >> shift)
        while keys[s, 0] != -1 and not (keys[s, 0] == a and keys[s, 1] == y and keys[s, 2] == z):
            s = (s + 1) & mask
        keys[s, 0], keys[s, 1], keys[s, 2] = a, y, z
        other = open_odd[s] if even else open_even[s]
        if other >= 0:  # pair with the oldest unpaired face of the other orientation
            mate[t] = other
            mate[other] = t
            if even:
                open_odd[s] = nxt[other]
                if open_odd[s] < 0:
                    tail_odd[s] = -1
            else:
                open_even[s] = nxt[other]
                if open_even[s] < 0:
                    tail_even[s] = -1
        elif even:
            if tail_even[s] >= 0:
                nxt[tail_even[s]] = t
            else:
                open_even[s] = t
            tail_even[s] = t
        else:
            if tail_odd[s] >= 0:
                nxt[tail_odd[s]] = t
            else:
                open_odd[s] = t
            tail_odd[s] = t
    return mate


def opposite_pairs(faces: np.ndarray, n_vertices: int) -> np.ndarray:
    """Coincident faces of opposite orientation (double-sided faces): the
    same three vertex indices, one face running them the other way round.

    Parameters
    ----------
    faces : int64 ndarray (M, 3)
    n_vertices : int

    Returns
    -------
    int64 ndarray (M,)
        For each face the index of the face it pairs with, or -1.  Each
        face pairs with at most one: faces of the same vertex set pair in
        file order, the first of one orientation with the first of the
        other (two copies one way and one the other make one pair and a
        face left over).

    Examples
    --------
    >>> opposite_pairs(np.array([[0, 1, 2], [1, 2, 3], [2, 1, 0], [1, 2, 0]]), 4).tolist()
    [2, -1, 0, -1]
    """
    f = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    return _opposite_pairs(f, int(n_vertices))


def one_face_per_pair(vertices: np.ndarray, faces: np.ndarray, mate: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Double-sided faces read as one face each: of each pair of coincident
    faces with opposite orientation (:func:`opposite_pairs`) the first in
    file order is kept and the other dropped, except in a wall between
    solids.

    A closed model drawn double-sided (every face also written reversed, as
    many modellers and exporters write furniture and game assets) has
    winding number 0 everywhere, the two layers cancelling; read with one
    face per pair it bounds the solid it draws.  Two closed solids that
    touch along coincident faces (boxes stacked face to face, voxel-art
    exports, a tetrahedral mesh's cells) also give pairs: there the pairs
    form a wall whose every free edge is an edge of the unpaired faces, or
    that lies inside the solid the unpaired faces bound (a wall parting a
    box whose sides are not split where it meets them), and the wall is
    dropped whole, both faces of each pair, leaving the union that the
    winding number gave anyway (one face of each pair would leave
    membranes inside it, and call the union double-sided).
    Pairs whose every free edge the unpaired faces use an odd number of
    times (once, on a manifold surface) are no wall but a patch of a
    surface drawn double-sided (a box with one side written both ways):
    the unpaired faces leave a hole there that one face of each pair
    closes, where a wall's edges are used by the solids on both sides.
    The faces left must use each edge an even number of times, which
    decides pairs that meet only pairs on an edge (two outer faces written
    both ways and the wall between their cubes), from those that other
    faces decide or that lie in a plane of the bounding box or another
    supporting plane (no solid beyond them: no wall).  Sets still
    undecided (in closed surfaces of pairs) are decided by rays where they
    can be: a wall has solid on both sides, so an even count of crossings
    from one side says no wall, odd counts from both sides a wall; those
    left are walls.
    A pair of zero-area faces (three corners on a line) draws nothing and
    is left as it is.

    Parameters
    ----------
    vertices : float ndarray (N, 3)
    faces : int64 ndarray (M, 3)
    mate : int64 ndarray (M,), optional
        :func:`opposite_pairs` of these faces, where the caller has it.

    Returns
    -------
    faces : int64 ndarray (M', 3)
        The faces in their order, less those dropped.
    pairs : int
        Pairs read as one face (walls not counted).

    Examples
    --------
    A triangle written twice, once each way, is one triangle:

    >>> f, n = one_face_per_pair(np.eye(3), np.array([[0, 1, 2], [0, 2, 1]]))
    >>> f.tolist(), n
    ([[0, 1, 2]], 1)
    """
    f = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    n_vertices = len(vertices)
    if mate is None:
        mate = opposite_pairs(f, n_vertices)
    paired = mate >= 0
    if not paired.any():
        return f, 0
    p = np.asarray(vertices, dtype=np.float64)[f]
    flat = ~np.any(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    paired &= ~flat
    if not paired.any():
        return f, 0
    first = paired & (np.arange(len(f)) < mate)
    lo, hi = p[~flat].min(axis=(0, 1)), p[~flat].max(axis=(0, 1))
    q = p[first]
    outer = np.any(np.all(q == lo, axis=1) | np.all(q == hi, axis=1), axis=1)  # in a plane of the bounding box
    outer |= _supporting(q, f[first], p[~flat].reshape(-1, 3), f[~flat].ravel())
    wall, patch, root = _walls(f[first], f[~paired & ~flat], n_vertices, outer, (q, p[~paired & ~flat]))
    if not (wall | patch).all():
        wall |= _inside_walls(p[first], p[~paired & ~flat], root, ~wall & ~patch)
    drop = paired.copy()
    kept = np.nonzero(first)[0][~wall]
    drop[kept] = False
    return f[~drop], int(len(kept))


def _walls(kept: np.ndarray, single: np.ndarray, n_vertices: int, outer: np.ndarray,
           corners: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which of the ``kept`` faces (one per pair) lie in a wall, which in a
    patch of a surface drawn double-sided, and each one's component.

    The components are the kept faces joined across edges that no unpaired
    face uses: on an edge of the unpaired faces a wall meets the solids'
    faces, and there it may meet pairs of the other kind too (an outer face
    of a cube written both ways, beside the wall to the next cube), which
    are told apart on their own.  A wall is a component with free edges
    (used once among its faces), every one of which an unpaired face also
    uses, not all of them an odd number of times; or a closed component (no
    free edge) every corner of which an unpaired face also uses: the walls
    all round a solid enclosed by others, where a closed model drawn
    double-sided meets no unpaired face, or a few of its corners.  A patch
    is a component whose every free edge the unpaired faces use an odd
    number of times: they have a hole there, which one face of each pair
    closes (some faces of a closed model written both ways), where a wall's
    free edges are used by the solids on both of its sides, an even number
    of times.  ``corners``: the coordinates of ``kept`` and ``single``
    (K, 3, 3), for the rays of :func:`_closed_by_parity`."""
    from ..scale.graphs import components

    m = len(kept)
    n = np.int64(max(n_vertices, 1))
    a, b = kept.ravel(), np.roll(kept, -1, axis=1).ravel()
    face = np.repeat(np.arange(m), 3)
    real = a != b
    a, b, face = a[real], b[real], face[real]
    key = np.minimum(a, b) * n + np.maximum(a, b)
    if len(single) == 0:
        none = np.zeros(len(key), dtype=bool)
        # with no unpaired face, a pair that the edges leave open is read as one face
        rays = None if corners is None else (*corners, np.ones(m, np.int8))
        kept_one = _closed_by_parity(m, key, face, none, none, outer, rays)
        return kept_one == 0, kept_one == 1, edge_table(kept, n_vertices)[5]
    slo, shi, sfwd, sbwd, _, _ = edge_table(single, n_vertices)
    order = np.argsort(slo * n + shi)
    skey, suses = (slo * n + shi)[order], (sfwd + sbwd)[order]
    at = np.minimum(np.searchsorted(skey, key), len(skey) - 1)
    covered = skey[at] == key
    odd = covered & (suses[at] % 2 == 1)
    o = np.argsort(key, kind="stable")
    join = (key[o][1:] == key[o][:-1]) & ~covered[o][1:]
    _, label = components(m, face[o][:-1][join], face[o][1:][join])
    root = np.unique(label, return_index=True)[1][label]  # each face's component: its smallest face
    # each component's free edges: those its own faces use once
    o = np.lexsort((root[face], key))
    k, c = key[o], root[face][o]
    begin = np.flatnonzero(np.r_[True, (k[1:] != k[:-1]) | (c[1:] != c[:-1])])
    free = begin[np.diff(np.r_[begin, len(k)]) == 1]
    comp = c[free]
    has_free = np.zeros(m, dtype=bool)
    has_free[comp] = True
    open_edge = np.zeros(m, dtype=bool)
    open_edge[comp[~covered[o][free]]] = True
    even_edge = np.zeros(m, dtype=bool)
    even_edge[comp[~odd[o][free]]] = True
    # a corner no unpaired face uses, per component of the kept faces
    reached = np.zeros(int(n_vertices), dtype=bool)
    reached[single.ravel()] = True
    bare = np.zeros(m, dtype=bool)
    bare[np.repeat(root, 3)[~reached[kept.ravel()]]] = True
    patch = has_free & ~even_edge
    wall, patch = ((has_free & ~open_edge & ~patch) | (~has_free & ~bare))[root], patch[root]
    rays = None if corners is None else (*corners, np.where(wall, 0, np.where(patch, 1, -1)).astype(np.int8))
    kept_one = _closed_by_parity(m, key, face, covered, odd, outer, rays)
    return np.where(kept_one < 0, wall, kept_one == 0), np.where(kept_one < 0, patch, kept_one == 1), root


def _supporting(q: np.ndarray, kept: np.ndarray, corners: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Which of the ``kept`` faces (corner coordinates ``q``) at the mesh's
    last corner in (x, y, z) order lie in a supporting plane of the mesh
    (every corner of a face on one side of it, or in it): no solid beyond
    them, no wall."""
    last = index[np.lexsort(corners.T[::-1])[-1]]
    out = np.zeros(len(kept), dtype=bool)
    for i in np.flatnonzero(np.any(kept == last, axis=1)):
        other = ~np.isin(index, kept[i])  # its own corners lie in it, whatever the rounding
        side = (corners[other] - q[i, 0]) @ np.cross(q[i, 1] - q[i, 0], q[i, 2] - q[i, 0])
        out[i] = bool(np.all(side >= 0) or np.all(side <= 0))
    return out


def _closed_by_parity(m: int, key: np.ndarray, face: np.ndarray, covered: np.ndarray, odd: np.ndarray,
                      outer: np.ndarray, rays: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Per kept face (one per pair), 1 where its pair is read as one face,
    0 where it is dropped as a wall, -1 where the edges leave it open.

    The pairs are taken in sheets, joined across edges that two of them
    use and no unpaired face.  The faces left must use each edge an even
    number of times (a closed surface): an edge used by the unpaired faces
    ``u`` times and by sheets ``s1 .. sk`` an odd number of times each
    gives ``u + x1 + .. + xk`` even, ``x`` 1 for a sheet kept.  An edge of
    one sheet alone decides it (the unpaired faces have a hole there, or
    meet a wall of two solids); an edge where outer pairs meet a wall and
    nothing else (two outer faces side by side, both written both ways,
    and the wall between their cubes) decides the last sheet once the
    others are known.  A sheet with an edge no other face uses (an open
    surface drawn double-sided), or told both ways, is left open (-1).
    A sheet with an ``outer`` face (in a plane of the mesh's bounding box,
    or in a supporting plane at its last corner: no solid beyond it) is no
    wall: kept, it decides the walls that meet it where no unpaired face
    is (a model all of whose faces are pairs).  Sheets that the edges
    leave undecided lie in closed surfaces of pairs; where ``rays`` are
    given (the kept faces' and the unpaired faces' coordinates, and what
    becomes of each kept face where the edges leave its sheet open: 0
    dropped, 1 kept, -1 not known), rays decide what they can
    (:func:`_told_by_rays`), and the edges then what follows, round after
    round.  Of those still undecided the
    first is taken for a wall and the rest follow, so the faces left still
    close."""
    from ..scale.graphs import components

    o = np.lexsort((face, key))
    k, fo, cov, od = key[o], face[o], covered[o], odd[o]
    start = np.flatnonzero(np.r_[True, k[1:] != k[:-1]])
    uses = np.diff(np.r_[start, len(k)])
    two = np.repeat(uses == 2, uses) & ~cov
    join = two[1:] & (k[1:] == k[:-1])
    _, sheet = components(m, fo[:-1][join], fo[1:][join])
    n_sheets = int(sheet.max()) + 1 if m else 0
    # each (edge, sheet) once, with the sheet's uses of it odd
    s = sheet[fo]
    o2 = np.lexsort((s, k))
    k2, s2, cov2, od2 = k[o2], s[o2], cov[o2], od[o2]
    begin = np.flatnonzero(np.r_[True, (k2[1:] != k2[:-1]) | (s2[1:] != s2[:-1])])
    free = begin[np.diff(np.r_[begin, len(k2)]) % 2 == 1]
    ek, es, ecov, eodd = k2[free], s2[free], cov2[free], od2[free]
    estart = np.flatnonzero(np.r_[len(ek) > 0, ek[1:] != ek[:-1]])
    esize = np.diff(np.r_[estart, len(ek)])
    # an edge that only one sheet uses, and no unpaired face: open
    bare_edge = (esize == 1) & ~ecov[estart]
    open_sheet = np.zeros(n_sheets, dtype=bool)
    open_sheet[es[estart[bare_edge]]] = True
    eq = ~bare_edge
    eqstart, eqsize = estart[eq], esize[eq]
    rhs = eodd[eqstart].astype(np.int8)
    on_box = np.zeros(n_sheets, dtype=bool)
    on_box[sheet[outer]] = True
    seed = np.where(on_box & ~open_sheet, 1, -1).astype(np.int8)
    equations = (np.r_[0, np.cumsum(eqsize)].astype(np.int64), es[np.repeat(eq, esize)].astype(np.int64), rhs, open_sheet)
    if rays is not None:
        value, guessed = _unit_parity(*equations, seed, False)
        scene = None
        for _ in range(RAY_ROUNDS):
            if not guessed.any():
                break
            scene = scene or _RayScene(rays[0], rays[1])
            told = _told_by_rays(scene, rays[2], sheet, value, guessed)
            if not (told >= 0).any():
                break
            seed = np.where(told >= 0, told, value).astype(np.int8)
            value, guessed = _unit_parity(*equations, seed, False)
    return _unit_parity(*equations, seed, True)[0][sheet]


#: rounds of rays (:func:`_told_by_rays`) and the edges' consequences, at
#: most: each round casts a few rays from every sheet still undecided
RAY_ROUNDS = 16
#: the most faces the rays of one round look at, per face of the mesh and
#: at least: past it the round's other rays tell nothing (those sheets keep
#: the rule without rays), so that a round costs about a pass over the
#: mesh (a model of 188k faces written cube by cube leaves 35k sheets of
#: walls to the rule, whose rays all stop at the next wall)
RAY_WORK = 8, 1 << 16
#: kept faces per undecided sheet that rays start from, spread over it
RAY_FACES = 2


class _RayScene:
    """What the rays of :func:`_told_by_rays` look at, round after round:
    the kept faces (one per pair) and then the unpaired faces, as corner
    coordinates (K, 3, 3), and the grid of cubes that holds them
    (:class:`~isoflow.mesh.cube_grid.CubeGrid`)."""

    def __init__(self, kept: np.ndarray, single: np.ndarray) -> None:
        self.tri = np.ascontiguousarray(np.concatenate([kept, single]), dtype=np.float64)
        self.grid = CubeGrid(self.tri.min(axis=1), self.tri.max(axis=1), compiled=True)


def _told_by_rays(scene: _RayScene, fate: np.ndarray, sheet: np.ndarray, value: np.ndarray,
                  todo: np.ndarray) -> np.ndarray:
    """Per sheet, 1 where rays show it is no wall (a patch, read as one
    face), 0 where they show a wall, -1 where they do not tell.

    A wall lies between solids: the faces left bound solid on both of its
    sides.  A patch is part of those faces, which change sides across it.
    From a point of a kept face of a ``todo`` sheet (a few faces of each)
    a ray along each axis the face is not parallel to, away from one side,
    counts its crossings with the faces decided so far: the unpaired
    faces, the pairs of decided sheets (``value``) read as one face (kept)
    or none (wall), and those of sheets the edges leave open as ``fate``
    says (per kept face: 1 kept, 0 dropped, -1 not known).  Where it
    crosses no face of an undecided sheet and touches no face at an edge,
    a corner or in its plane (exact signs, or certified float64:
    :func:`~isoflow.mesh.crossing_kernels.segment_crosses_triangle`), the
    count's parity is that of the faces left just off that side: odd
    inside their solid, even outside.  An even count on either side: no
    wall.  Odd on both sides: a wall.  A side told both ways (faces that
    do not close) tells nothing."""
    n_sheets = len(value)
    faces = np.flatnonzero(todo[sheet])
    if len(faces) == 0:
        return np.full(n_sheets, -1, np.int8)
    faces = spread_faces(faces, sheet[faces], RAY_FACES)[0]
    kept = scene.tri[:len(sheet)]
    normal = np.cross(kept[faces, 1] - kept[faces, 0], kept[faces, 2] - kept[faces, 0])
    start = face_points(kept[faces])
    face_of, axis = np.nonzero(normal != 0)
    face_of, axis = np.repeat(face_of, 2), np.repeat(axis, 2)
    direction = np.tile([1, -1], len(axis) // 2)
    side = np.sign(normal[face_of, axis]).astype(np.int64) * direction
    known = np.where(todo[sheet], -1, fate)  # an open sheet's pairs: as they will be read
    weight = np.ones(len(scene.tri), np.int8)
    weight[:len(sheet)] = np.where(value[sheet] >= 0, value[sheet], known)
    count, told = axis_rays(scene.tri, weight, start[face_of], axis, direction, faces[face_of], scene.grid,
                            RAY_WORK[0] * len(scene.tri) + RAY_WORK[1], False)
    parity = np.where(told, count % 2, -1)
    # per sheet, side (the one the kept face faces, the other) and parity: seen?
    ok = parity >= 0
    seen = np.zeros((4, n_sheets), bool)
    seen[(2 * (side[ok] < 0) + parity[ok]), sheet[faces[face_of[ok]]]] = True
    even_front, odd_front, even_back, odd_back = seen
    sure = todo & ~(even_front & odd_front) & ~(even_back & odd_back)  # no side seen both ways
    told = np.full(n_sheets, -1, np.int8)
    told[sure & (even_front | even_back)] = 1
    told[sure & odd_front & odd_back & ~even_front & ~even_back] = 0
    return told


def face_points(t: np.ndarray) -> np.ndarray:
    """A point inside each face (corners ``t``, (K, 3, 3)) that rays start
    from: away from its edges and from the line that splits a square into
    two triangles; on an axis-aligned face it lies on the face exactly
    (the normal's coordinate is a corner's).

    Examples
    --------
    >>> face_points(np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], float)).tolist()
    [[0.3141, 0.2113, 0.0]]
    """
    return t[:, 0] + 0.3141 * (t[:, 1] - t[:, 0]) + 0.2113 * (t[:, 2] - t[:, 0])


def axis_rays(tri: np.ndarray, weight: np.ndarray, start: np.ndarray, axis: np.ndarray, towards: np.ndarray,
              own: np.ndarray, grid: CubeGrid, work: int, signed: bool) -> tuple[np.ndarray, np.ndarray]:
    """:func:`ray_crossings` of rays from ``start`` along ``axis``, to the
    side ``towards`` (+1 or -1) says, to past the triangles' box; and which
    of them tell (neither stopped, nor ending short of the box: a mesh so
    far from the origin that the end rounds onto it touches a face).

    Parameters
    ----------
    tri : float64 ndarray (K, 3, 3)
        The triangles, C-contiguous.
    weight : int8 ndarray (K,)
        As :func:`ray_crossings` takes it.
    start : float ndarray (R, 3)
    axis, towards, own : ndarray (R,)
        Each ray's axis, direction and own triangle (left out).
    grid : CubeGrid
        The compiled grid of the triangles' boxes.
    work : int
        The triangles the rays may look at in all.
    signed : bool
        Count the crossings' signs (a winding number), not their number.

    Returns
    -------
    count : int64 ndarray (R,)
    told : bool ndarray (R,)

    Examples
    --------
    From inside a cube of two triangles a side, off the diagonals that
    split them, a ray along +x crosses one face, and the winding number
    there is 1.

    >>> import trimesh
    >>> box = trimesh.creation.box((2, 2, 2))
    >>> tri = np.ascontiguousarray(box.vertices[box.faces], dtype=np.float64)
    >>> grid = CubeGrid(tri.min(axis=1), tri.max(axis=1), compiled=True)
    >>> count, told = axis_rays(tri, np.ones(12, np.int8), np.array([[0, 0.3, 0.1]]), np.array([0]), np.array([1]),
    ...                         np.array([-1]), grid, 1000, True)
    >>> count.tolist(), told.tolist()
    ([1], [True])
    """
    lo, hi = grid.lo.min(axis=0), grid.hi.max(axis=0)  # the triangles' box, from their own boxes in the grid
    reach = float(np.max(hi - lo))
    rows = np.arange(len(axis))
    end = np.array(start, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        end[rows, axis] = np.where(towards > 0, hi[axis] + reach, lo[axis] - reach)
    beyond = np.where(towards > 0, end[rows, axis] > hi[axis], end[rows, axis] < lo[axis]) & np.isfinite(end).all(axis=1)
    count, stopped = ray_crossings(tri, weight, np.asarray(start, np.float64), end, np.asarray(axis, np.int64),
                                   np.asarray(own, np.int64), grid.origin, float(grid.cube), grid.dims.astype(np.int64),
                                   grid.start, grid.size, grid.key, grid.box, work, signed)
    return count, ~stopped & beyond


def spread_faces(faces: np.ndarray, group: np.ndarray, most: int) -> tuple[np.ndarray, np.ndarray]:
    """Up to ``most`` of ``faces`` of each group, spread over its faces in
    file order (neighbours in a file are often neighbours on the surface),
    and each one's group as a rank among the groups (in increasing order).

    Parameters
    ----------
    faces, group : int ndarray (K,)
        Faces and the group of each.
    most : int

    Returns
    -------
    chosen, rank : int64 ndarray (J,)

    Examples
    --------
    >>> chosen, rank = spread_faces(np.arange(7), np.array([5, 5, 5, 5, 2, 5, 5]), 2)
    >>> chosen.tolist(), rank.tolist()
    ([4, 0, 3], [0, 1, 1])
    """
    faces = np.asarray(faces, dtype=np.int64)
    order = np.argsort(group, kind="stable")
    faces, g = faces[order], np.asarray(group)[order]
    begin = np.flatnonzero(np.r_[True, g[1:] != g[:-1]]) if len(g) else np.zeros(0, np.int64)
    size = np.diff(np.r_[begin, len(g)])
    rays = np.minimum(size, most)
    rank = np.repeat(np.arange(len(begin)), rays)
    step = np.arange(len(rank)) - np.repeat(np.cumsum(rays) - rays, rays)
    return faces[begin[rank] + step * size[rank] // rays[rank]], rank


@njit(cache=True, nogil=True)
def ray_crossings(tri, weight, ray_from, ray_to, ray_axis, ray_own, origin, cube, dims, start, size, key, box, budget,
                  signed):
    """Each ray's crossings with the triangles of weight 1 (``signed``:
    their sum of :func:`~isoflow.mesh.crossing_kernels.segment_crossing_side`,
    the winding number of its start where they close), and whether it
    stopped: crossed or touched one of weight -1, or touched one of weight
    1 (weight 0: not there). Ray r runs from ``ray_from[r]`` to
    ``ray_to[r]`` along axis ``ray_axis[r]``, beside its own triangle
    ``ray_own[r]``; it walks the cubes of a
    :class:`~isoflow.mesh.cube_grid.CubeGrid` (the triangles of each cube
    from ``start``, ``size``) from its start and stops at the first
    triangle that stops it. Past ``budget`` triangles looked at, the rays
    left are stopped."""
    n_rays = len(ray_from)
    count = np.zeros(n_rays, np.int64)
    halted = np.zeros(n_rays, np.bool_)
    seen = np.full(len(weight), -1, np.int64)  # the last ray that looked at each triangle
    cubes = key[start]
    c = np.empty(3, np.int64)
    x = np.empty((5, 3))  # the triangle's corners, the ray's start and end
    work = 0
    for r in range(n_rays):
        if work > budget:
            halted[r] = True
            continue
        k = ray_axis[r]
        i, j = (k + 1) % 3, (k + 2) % 3
        step = 1 if ray_to[r, k] > ray_from[r, k] else -1
        for m in range(3):
            c[m] = min(dims[m] - 1, max(0, np.int64(np.floor((ray_from[r, m] - origin[m]) / cube))))
            x[3, m], x[4, m] = ray_from[r, m], ray_to[r, m]
        last = dims[k] - 1 if step > 0 else 0
        lo_k, hi_k = min(x[3, k], x[4, k]), max(x[3, k], x[4, k])
        pi, pj = x[3, i], x[3, j]
        stopped = False
        while True:
            here = (c[2] * dims[1] + c[1]) * dims[0] + c[0]
            g = np.searchsorted(cubes, here)
            if g < len(cubes) and cubes[g] == here:
                for e in range(start[g], start[g] + size[g]):
                    t = box[e]
                    work += 1
                    if seen[t] == r or weight[t] == 0 or t == ray_own[r]:
                        continue
                    seen[t] = r
                    if (max(tri[t, 0, i], tri[t, 1, i], tri[t, 2, i]) < pi or min(tri[t, 0, i], tri[t, 1, i], tri[t, 2, i]) > pi
                            or max(tri[t, 0, j], tri[t, 1, j], tri[t, 2, j]) < pj
                            or min(tri[t, 0, j], tri[t, 1, j], tri[t, 2, j]) > pj
                            or max(tri[t, 0, k], tri[t, 1, k], tri[t, 2, k]) < lo_k
                            or min(tri[t, 0, k], tri[t, 1, k], tri[t, 2, k]) > hi_k):
                        continue
                    for m in range(3):
                        for n in range(3):
                            x[m, n] = tri[t, m, n]
                    s = segment_crossing_side(x, 3, 4, 0, 1, 2)
                    if s == 0:
                        continue
                    if (s == 1 or s == -1) and weight[t] == 1:
                        count[r] += s if signed else 1
                    else:
                        stopped = True
                        break
            if stopped or c[k] == last:
                break
            c[k] += step
        halted[r] = stopped
    return count, halted


@njit(cache=True, nogil=True)
def _unit_parity(eq_start, eq_sheet, rhs, frozen, given, guess):
    # each equation: its sheets' values and rhs sum to an even number; a
    # sheet alone in one takes its value, a given value (an outer sheet,
    # kept; one that rays told) is taken, and then the last unknown sheet
    # of every equation takes its value (the first value kept); where every
    # equation left has two unknowns or more, with ``guess`` the first sheet
    # left is a wall and the rest follow from it. Returns the values and
    # the sheets left to guess (none with ``guess``)
    n = len(frozen)
    value = np.full(n, -1, np.int8)
    seed = given.copy()
    clash = frozen.copy()
    n_eq = len(eq_start) - 1
    for e in range(n_eq):
        if eq_start[e + 1] - eq_start[e] == 1:
            t = eq_sheet[eq_start[e]]
            if seed[t] >= 0 and seed[t] != rhs[e]:
                clash[t] = True
            seed[t] = rhs[e]
    count = np.zeros(n + 1, np.int64)
    for i in range(len(eq_sheet)):
        count[eq_sheet[i] + 1] += 1
    for t in range(n):
        count[t + 1] += count[t]
    sheet_eq = np.empty(len(eq_sheet), np.int64)
    fill = count[:-1].copy()
    for e in range(n_eq):
        for i in range(eq_start[e], eq_start[e + 1]):
            sheet_eq[fill[eq_sheet[i]]] = e
            fill[eq_sheet[i]] += 1
    unknown = np.zeros(n_eq, np.int64)
    parity = rhs.astype(np.int64)
    for e in range(n_eq):
        unknown[e] = eq_start[e + 1] - eq_start[e]
    stack = np.empty(n + n_eq + 1, np.int64)
    top = 0
    for t in range(n):
        if seed[t] >= 0 and not clash[t]:
            stack[top] = t
            top += 1
            value[t] = seed[t]
    nxt = 0
    while True:
        while top > 0:
            top -= 1
            t = stack[top]
            for j in range(count[t], count[t + 1]):
                e = sheet_eq[j]
                unknown[e] -= 1
                parity[e] ^= value[t]
                if unknown[e] == 1:
                    for i in range(eq_start[e], eq_start[e + 1]):
                        u = eq_sheet[i]
                        if value[u] < 0 and not clash[u]:
                            value[u] = parity[e]
                            stack[top] = u
                            top += 1
        while nxt < n and (value[nxt] >= 0 or clash[nxt] or count[nxt + 1] == count[nxt]):
            nxt += 1
        if nxt == n or not guess:
            return value, (value < 0) & ~clash & (count[1:] > count[:-1])
        value[nxt] = 0  # no edge tells it: a wall, dropped (the union)
        stack[top] = nxt
        top += 1


#: the most (point, triangle) solid angles that :func:`_inside_walls`
#: sums (about a second on one core); past it walls are found by their
#: edges alone, and the pairs inside the solid are read as one face each,
#: which leaves the same voxels (a membrane inside a solid keeps |w| >= 1/2)
INSIDE_WALL_TERMS = 1 << 27


def _inside_walls(kept: np.ndarray, single: np.ndarray, root: np.ndarray, candidate: np.ndarray) -> np.ndarray:
    """Which of the ``kept`` faces (one per pair, as corner coordinates,
    ``root`` their components) lie in a wall inside the solid that the
    unpaired faces ``single`` bound: the generalised winding number of the
    unpaired faces at the centroid of the largest face of each
    ``candidate`` component is beyond 1/2 (a wall whose rim meets the
    solid's faces away from their edges, which the edge test of
    :func:`_walls` cannot see).  The pairs' own windings cancel, so
    dropping both faces leaves the winding number as it is, where keeping
    one would put a membrane inside the solid, across which w jumps by 1."""
    from .solid_angles import winding_numbers

    out = np.zeros(len(kept), dtype=bool)
    if len(single) == 0 or not candidate.any():
        return out
    area = np.linalg.norm(np.cross(kept[:, 1] - kept[:, 0], kept[:, 2] - kept[:, 0]), axis=1)
    faces = np.flatnonzero(candidate)
    order = faces[np.lexsort((-area[faces], root[faces]))]
    largest = order[np.r_[True, root[order][1:] != root[order][:-1]]]
    points = kept[largest].mean(axis=1)
    # a point outside the unpaired faces' box is outside their solid
    within = np.all((points >= single.min(axis=(0, 1))) & (points <= single.max(axis=(0, 1))), axis=1)
    largest, points = largest[within], points[within]
    if len(largest) == 0 or len(largest) * len(single) > INSIDE_WALL_TERMS:
        return out
    w, _ = winding_numbers(points, single)
    # a centroid on an unpaired face (|w| = 1/2) says nothing of either side
    out[root[largest]] = np.abs(w) > 0.5 + 1e-9
    return out[root] & candidate


@njit(cache=True, nogil=True)
def _distinct_in_groups(start, values, n_values):
    # each group's values marked with the group's number as they are seen
    seen = np.full(n_values, -1, np.int64)
    out = np.zeros(len(start) - 1, np.int64)
    for g in range(len(start) - 1):
        for e in range(start[g], start[g + 1]):
            if seen[values[e]] != g:
                seen[values[e]] = g
                out[g] += 1
    return out


def distinct_counts(first: np.ndarray, n_first: int, second: np.ndarray, n_second: int) -> np.ndarray:
    """Per value ``0 .. n_first - 1`` of ``first``, how many distinct values
    of ``second`` (``0 .. n_second - 1``) occur beside it, in time linear
    in the items (no sort of them).

    Parameters
    ----------
    first, second : int ndarray (K,)
        The items' two values.
    n_first, n_second : int
        Bounds of the values.

    Returns
    -------
    int64 ndarray (n_first,)

    Examples
    --------
    >>> distinct_counts(np.array([0, 0, 2, 0]), 3, np.array([5, 5, 1, 4]), 6).tolist()
    [2, 0, 1]
    """
    from ..scale.piece_graph import grouped  # the counting sort

    start, values = grouped(first, int(n_first), np.asarray(second, np.int64))
    return _distinct_in_groups(start, values, max(int(n_second), 1))

