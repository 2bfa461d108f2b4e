"""T-junctions: a vertex of one face lying inside another face's edge.

A CAD export tessellates each face of the model apart, so the two sides
of a model edge may be sampled at different points: one side's edge
``a -> b`` meets the other side's ``b -> p -> a``, and no edge of the mesh
has two faces there.  The mesh counts as open (boundary edges) although
the surface is closed as drawn.  :func:`split_t_junctions` splits each
such edge at the vertices lying on it, where that pairs every piece with
a piece of the other side, so the mesh's own genus (and manifold3d's and
pymeshlab's) can be counted, and the voxeliser reads the mesh as closed
(the exact scanline, no cap to close a boundary chain).  Only boundary
edges and their vertices are looked at; the geometry is unchanged (the new
corners lie on the edges, a face split along two or more edges gets a
vertex at its centroid), so the generalised winding number at every point
off the surface is too.  A face listed more than once the same way round
is looked at once and each copy cut as the first, so that a copy on a
crack closes it as the face alone does.  :func:`close_t_junctions` is the
split that ``isoflow genus`` and ``isoflow voxelize`` both make, at one
tolerance.
"""

from __future__ import annotations

import math

import numpy as np

from .load import repeated_faces

#: how far from an edge, as a share of the bounding box's diagonal, a vertex
#: lies on it for :func:`close_t_junctions`: above float32's rounding (a
#: CAD export's STL), far below any feature
T_JUNCTION_RTOL = 1e-6


def close_t_junctions(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict | None]:
    """The mesh with its edges split at T-junctions where that closes them
    (:func:`split_t_junctions`), a vertex counting as on an edge within
    :data:`T_JUNCTION_RTOL` of the bounding box's diagonal.

    Parameters
    ----------
    vertices : ndarray, shape (N, 3)
        Positions (welded), in any unit.
    faces : ndarray, shape (M, 3)
        Triangles; a face listed twice keeps both copies, each split as the
        first.

    Returns
    -------
    vertices, faces : ndarray
        The split mesh: the vertices given, then a centroid per face split
        along two or more edges; or the arrays given where nothing closes.
    facts : dict or None
        As :func:`split_t_junctions`.

    Examples
    --------
    A box with one triangle split at the middle of an edge, the triangle
    across that edge left whole: trimesh calls it open; split there too,
    it is closed.

    >>> import trimesh
    >>> box = trimesh.creation.box()
    >>> v, f = box.vertices, box.faces
    >>> a, b, c = f[0]
    >>> v2 = np.vstack([v, (v[a] + v[b]) / 2])
    >>> f2 = np.vstack([f[1:], [[a, 8, c], [8, b, c]]])
    >>> _, f3, facts = close_t_junctions(v2, f2)
    >>> trimesh.Trimesh(v2, f2, process=False).is_watertight, trimesh.Trimesh(v2, f3, process=False).is_watertight
    (False, True)
    >>> facts
    {'points': 1, 'faces': 1, 'edges': 3}
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    v = np.asarray(vertices, dtype=np.float64)
    mask = np.zeros(len(v), dtype=bool)
    mask[f.ravel()] = True
    used = v[mask]
    if not len(used):
        return vertices, faces, None
    # in units of a power of two near the longest side, from the box's corner, as the weld measures:
    # the diagonal and the products along an edge neither overflow at 1e200 nor underflow at 1e-200
    lo = used.min(axis=0)
    e = math.frexp(float((used.max(axis=0) - lo).max()) or 1.0)[1]
    with np.errstate(over="ignore", invalid="ignore"):
        scaled = np.ldexp(v - lo, -e)
    diagonal = float(np.linalg.norm(np.ldexp(used.max(axis=0) - lo, -e)))
    v2, f2, facts = split_t_junctions(scaled, f, T_JUNCTION_RTOL * diagonal)
    if facts is None:
        return vertices, faces, None
    # the vertices given are kept bit for bit: only the centroids come back from the scaled frame
    return np.vstack([v, np.ldexp(v2[len(v):], e) + lo]), f2, facts


def split_t_junctions(vertices: np.ndarray, faces: np.ndarray, tolerance: float
                      ) -> tuple[np.ndarray, np.ndarray, dict | None]:
    """The mesh with its boundary edges split at the boundary vertices that
    lie on them, where every piece of such an edge then has a piece of
    another edge running the other way (the crack closes).

    Parameters
    ----------
    vertices : ndarray, shape (N, 3)
        Positions (welded).
    faces : ndarray, shape (M, 3)
        Triangles. A face listed again the same way round (the same three
        corners, :func:`~isoflow.mesh.load.repeated_faces`) is a copy: the
        split is found on the first and made on each copy alike.
    tolerance : float
        How far from an edge a vertex may lie and count as on it (the
        weld's distance).

    Returns
    -------
    vertices, faces : ndarray
        The split mesh (vertices appended: a centroid per face split along
        two or more edges), or the arrays given where nothing closes.
    facts : dict or None
        ``points`` (vertices that split an edge), ``faces`` (faces split,
        every copy counted) and ``edges`` (boundary edges of the faces
        given closed), or None.

    Examples
    --------
    A unit square of two triangles above one whose bottom edge has a vertex
    at its middle:

    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0, 0]], float)
    >>> f = np.array([[0, 1, 2], [1, 3, 2], [3, 0, 2]])
    >>> _, f2, facts = split_t_junctions(v, f, 1e-9)
    >>> facts, len(f2)
    ({'points': 1, 'faces': 1, 'edges': 3}, 4)

    The face across the split edge listed twice: its edge, used twice,
    is not open, yet both copies are split, alike, and the two open
    pieces close.

    >>> _, f3, facts = split_t_junctions(v, np.vstack([f, f[:1]]), 1e-9)
    >>> facts, f3.tolist()
    ({'points': 1, 'faces': 2, 'edges': 2}, [[1, 3, 2], [3, 0, 2], [0, 3, 2], [3, 1, 2], [0, 3, 2], [3, 1, 2]])
    """
    faces = np.asarray(faces, np.int64)
    # the split is found on each face once and made on every copy of it: a
    # copy on a crack uses the whole side's edge twice, which then looks
    # closed, and leaves the other side's pieces open
    first = repeated_faces(faces)
    once = first == np.arange(len(faces))
    unique = faces[once]
    slots = unique[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)  # edge j of face i is slot 3 i + j
    open_slots = _open_slots(slots)
    if not len(open_slots):
        return vertices, faces, None
    inserts = _points_on_edges(vertices, slots, open_slots, tolerance)
    inserts = _closing(slots, open_slots, inserts)
    if not inserts:
        return vertices, faces, None
    new_v, pieces = _split_faces(vertices, unique, inserts)
    # each face's first listing among the faces listed once; a copy is cut
    # into its first's pieces, so that the copies stay copies
    of = (np.cumsum(once) - 1)[first]
    split = np.isin(of, np.fromiter(pieces, dtype=np.int64, count=len(pieces)))
    cut = [pieces[int(i)] for i in of[split]]
    new_f = np.vstack([faces[~split], *cut])
    before = len(_open_slots(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)))
    after = len(_open_slots(new_f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)))
    points = len(np.unique(np.concatenate(list(inserts.values()))))
    return new_v, new_f, {"points": points, "faces": int(split.sum()), "edges": max(0, before - after)}


def _edge_keys(p: np.ndarray, q: np.ndarray, n: int) -> np.ndarray:
    """One integer per directed edge ``p -> q`` of vertices below ``n``."""
    return p * n + q


def _open_slots(slots: np.ndarray) -> np.ndarray:
    """The slots whose edge no other slot has, either way round: a key per
    undirected edge sorts far faster than the pairs as rows."""
    if not len(slots):
        return np.zeros(0, dtype=np.int64)
    keys = _edge_keys(slots.min(axis=1), slots.max(axis=1), int(slots.max()) + 1)
    _, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    return np.flatnonzero(counts[inverse.ravel()] == 1)


#: open edges times their corners up to which every pair is tried (a block
#: of edges at a time) to find the corners that lie on edges: above it a KD
#: tree picks the pairs, but importing scipy.spatial would be a large share
#: of a short command on a small open mesh or soup
ALL_PAIRS = 1 << 20
#: pairs tried at a time below :data:`ALL_PAIRS`
PAIR_BLOCK = 1 << 16


def _points_on_edges(v: np.ndarray, slots: np.ndarray, open_slots: np.ndarray, tol: float) -> dict:
    """Per open edge slot, the boundary vertices strictly inside it (within
    ``tol`` of the segment), in order from its first corner; never its own
    face's third corner (the face has no area: split there, it would be
    cut into a piece with a corner twice and a piece on its own edges,
    which closes the face on itself)."""
    ends = slots[open_slots]
    # edge j of a face is slot 3 i + j; its third corner ends edge j + 1
    apex = slots[3 * (open_slots // 3) + (open_slots % 3 + 1) % 3, 1]
    points = np.unique(ends)
    if len(ends) * len(points) <= ALL_PAIRS:
        step = max(1, PAIR_BLOCK // max(len(points), 1))
        found = [_on_edges(v, ends, apex, np.repeat(np.arange(lo, min(lo + step, len(ends))), len(points)),
                           np.tile(points, min(step, len(ends) - lo)), tol) for lo in range(0, len(ends), step)]
    else:
        found = [_on_edges(v, ends, apex, *_near_pairs(v, ends, points, tol), tol)]
    k = np.concatenate([f[0] for f in found]) if found else np.zeros(0, np.int64)
    c = np.concatenate([f[1] for f in found]) if found else np.zeros(0, np.int64)
    t = np.concatenate([f[2] for f in found]) if found else np.zeros(0)
    order = np.lexsort((t, k))  # by edge, then along it
    k, c = k[order], c[order]
    runs = np.flatnonzero(np.diff(k)) + 1
    return {int(open_slots[run[0]]): pts for run, pts in zip(np.split(k, runs), np.split(c, runs)) if len(run)}


def _near_pairs(v: np.ndarray, ends: np.ndarray, points: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The (edge, corner) pairs whose corner lies in the ball around the
    edge that holds every point within ``tol`` of it (a KD tree's query)."""
    from scipy.spatial import cKDTree

    a, b = v[ends[:, 0]], v[ends[:, 1]]
    middle, radius = (a + b) / 2, np.linalg.norm(b - a, axis=1) / 2 + tol
    tree = cKDTree(v[points])
    # most edges' balls hold their own two corners alone (a triangle soup:
    # every edge open): only the others are listed
    busy = np.flatnonzero(tree.query_ball_point(middle, radius, return_length=True) > 2)
    if not len(busy):
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    near = tree.query_ball_point(middle[busy], radius[busy])
    lengths = np.fromiter(map(len, near), dtype=np.int64, count=len(busy))
    return np.repeat(busy, lengths), points[np.concatenate([np.asarray(n, dtype=np.int64) for n in near])]


def _on_edges(v: np.ndarray, ends: np.ndarray, apex: np.ndarray, k: np.ndarray, c: np.ndarray, tol: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Of the pairs of edge ``k`` and corner ``c``, those whose corner lies
    strictly inside the edge within ``tol`` (not one of its own corners nor
    ``apex[k]``, the third corner of its face): the edges, the corners and
    where along the edge (0 to 1)."""
    other = (c != ends[k, 0]) & (c != ends[k, 1]) & (c != apex[k])
    k, c = k[other], c[other]
    a = v[ends[k, 0]]
    d = v[ends[k, 1]] - a
    with np.errstate(invalid="ignore", divide="ignore"):  # (a zero-length edge holds no point inside)
        t = np.einsum("ij,ij->i", v[c] - a, d) / np.einsum("ij,ij->i", d, d)
    off = np.linalg.norm(a + t[:, None] * d - v[c], axis=1)
    # a corner within tol of an end of the edge is a copy of that end the weld left apart (positions rounded
    # apart by less than this tolerance), not a point inside the edge: split there, a face would get a sliver
    # of no width whose edges pair with nothing drawn
    length = np.sqrt(np.einsum("ij,ij->i", d, d))
    on = (t * length > tol) & ((1 - t) * length > tol) & (off <= tol)
    return k[on], c[on], t[on]


def _closing(slots: np.ndarray, open_slots: np.ndarray, inserts: dict) -> dict:
    """The inserts of the edges whose every piece, once split, has a piece
    of an open edge running the other way."""
    if not inserts:
        return {}
    n = int(slots.max()) + 1
    whole = np.setdiff1d(open_slots, np.fromiter(inserts, dtype=np.int64, count=len(inserts)))
    directed = set(_edge_keys(slots[whole, 0], slots[whole, 1], n).tolist())
    pieces = {}
    for s, pts in inserts.items():
        chain = [int(slots[s, 0]), *pts.tolist(), int(slots[s, 1])]
        pieces[s] = list(zip(chain[:-1], chain[1:]))
        directed.update(p * n + q for p, q in pieces[s])
    return {s: pts for s, pts in inserts.items() if all(q * n + p in directed for p, q in pieces[s])}


def _split_faces(v: np.ndarray, faces: np.ndarray, inserts: dict) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """The vertices with a centroid per face split along two or more edges,
    and the triangles each face with inserted corners is cut into, of its
    own orientation: a fan from the opposite corner where one edge is
    split, else from its centroid."""
    by_face: dict[int, dict[int, np.ndarray]] = {}
    for s, pts in inserts.items():
        by_face.setdefault(s // 3, {})[s % 3] = pts
    pieces, new_points = {}, []
    for i, edges in by_face.items():
        corners = faces[i]
        if len(edges) == 1:
            (j, pts), = edges.items()
            path = [corners[j], *pts, corners[(j + 1) % 3]]
            pieces[i] = np.array([(p, q, corners[(j + 2) % 3]) for p, q in zip(path[:-1], path[1:])], np.int64)
            continue
        ring = [c for j in range(3) for c in (corners[j], *edges.get(j, ()))]
        centre = len(v) + len(new_points)
        new_points.append(v[corners].mean(axis=0))
        pieces[i] = np.array([(p, q, centre) for p, q in zip(ring, ring[1:] + ring[:1])], np.int64)
    return np.vstack([v, np.asarray(new_points).reshape(-1, 3)]), pieces
