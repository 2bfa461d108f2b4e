"""Which triangles of a mesh meet other than at the corners they share.

Two faces *cross* when their closed triangles have a point in common that
their shared corners do not explain (libigl's ``remesh_self_intersections``
rules, whose CGAL predicates are exact):

* faces with no common corner cross when the triangles meet at all
  (touching counts);
* faces with one common corner cross when the edge of either opposite that
  corner meets the other face;
* faces with a common edge cross when they lie in one plane on the same
  side of that edge (they overlap); otherwise they meet only along it;
* faces with the same three corners (a duplicate, or the two sides of a
  double-sided face) are not tested, nor faces whose corners are collinear
  (no area, nothing to cross);
* where zero-area faces close a T-junction (an edge split by a vertex on
  one side, whole on the other, a sliver ``p, q, m`` with ``m`` on ``p-q``
  between them, as CAD exports write), an edge of one face lying on an
  edge of the other, both edges of such slivers, is a common edge: the
  faces cross only when coplanar on one side of it.

Of the crossing pairs, :func:`touching_pairs` tells those that only touch
(neither surface passes through the other there: solids stacked face to
face), which :func:`isoflow.mesh.genus.verify_genus` does not count as a
self-intersection.

Corners are common when they are at the same position. Every decision is
the sign of an exact determinant of the float64 coordinates as stored
(:mod:`isoflow.mesh.predicates`), so the answer depends on no unit,
placement or tolerance: moving or scaling the mesh cannot create or remove
a crossing.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from ..scale.compiled import have_numba
from .cube_grid import CubeGrid
from .load import distinct_rows
from .predicates import ExactPoints

#: from this many faces on, ``method="auto"`` takes the compiled pass
COMPILED_FACES = 2000


def crossing_pairs(vertices: np.ndarray, faces: np.ndarray,
                   method: Literal["auto", "numpy", "compiled"] = "auto") -> np.ndarray:
    """Pairs of faces that cross, by the rules of this module's docstring.

    Parameters
    ----------
    vertices : ndarray, shape (N, 3)
        Positions (float64; any units, any placement).
    faces : ndarray, shape (M, 3)
        Vertex indices of each triangle.
    method : {"auto", "numpy", "compiled"}
        ``"compiled"`` decides the pairs whose float64 signs are certified
        with numba and the rest in NumPy with integers; ``"numpy"`` decides
        all in NumPy; ``"auto"`` compiles from :data:`COMPILED_FACES` faces
        on, where numba is installed. The answer is the same.

    Returns
    -------
    ndarray, shape (K, 2), int64
        Face index pairs ``(i, j)`` with ``i < j``, sorted.

    Examples
    --------
    Two triangles through each other, and one apart:

    >>> import numpy as np
    >>> v = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0],
    ...               [0.5, 0.5, -1], [0.5, 0.5, 1], [1.5, 1.5, 0],
    ...               [5, 5, 5], [6, 5, 5], [5, 6, 5]], float)
    >>> crossing_pairs(v, np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8]])).tolist()
    [[0, 1]]
    """
    return find_crossings(vertices, faces, method).pairs


@dataclass(frozen=True)
class Crossings:
    """What :func:`find_crossings` found: the crossing ``pairs`` (as
    :func:`crossing_pairs`), the faces of ``zero_area`` (collinear
    corners, not tested), the pairs that meet ``along_slivers`` (at a
    T-junction zero-area faces close: no crossing) and, per pair, whether
    the two faces only ``touch`` (:func:`touching_pairs`: they meet, but
    neither surface passes through the other there)."""

    pairs: np.ndarray
    zero_area: int
    along_slivers: int
    touch: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))


def find_crossings(vertices: np.ndarray, faces: np.ndarray,
                   method: Literal["auto", "numpy", "compiled"] = "auto") -> Crossings:
    """:func:`crossing_pairs`, with the zero-area faces it left out and the
    pairs they explain (see the module's rules)."""
    v = np.asarray(vertices, np.float64)
    f = np.asarray(faces, np.int64)
    points, position = distinct_rows(v)
    exact = ExactPoints(points)
    tri = position.reshape(-1)[f]
    compiled = method == "compiled" or (method == "auto" and len(f) >= COMPILED_FACES and have_numba())
    axis = (_compiled_axis if compiled else projection_axis)(exact, tri) if len(f) else np.zeros(0, np.int64)
    tested = np.flatnonzero(axis >= 0)  # collinear corners: nothing to cross
    zero_area = len(f) - len(tested)
    if len(tested) < 2:
        return Crossings(np.zeros((0, 2), np.int64), zero_area, 0)
    tri, axis = tri[tested], axis[tested]
    corners = exact.xyz[tri]
    grid = CubeGrid(corners.min(axis=1), corners.max(axis=1), compiled=compiled)
    if compiled:
        found = _compiled_pairs(exact, tri, axis, grid)
    else:
        found = [pairs[_cross(exact, tri, axis, pairs)] for pairs in grid.pairs()]
    out = tested[np.concatenate(found)] if found else np.zeros((0, 2), np.int64)
    along = np.zeros(len(out), bool)
    if len(out) and zero_area:
        whole = position.reshape(-1)[f]
        flat = np.ones(len(f), bool)
        flat[tested] = False
        along = sliver_joined(exact, whole, whole[flat], out)
        out = out[~along]
    out = out[np.lexsort((out[:, 1], out[:, 0]))]
    return Crossings(out, zero_area, int(np.count_nonzero(along)), touching_pairs(exact, position.reshape(-1)[f], out))


def touching_pairs(exact: ExactPoints, tri: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Per pair of faces that meet (:func:`crossing_pairs`), whether they
    only touch: neither surface passes through the other there, as where two
    solids are stacked face to face or side by side.

    The pairs that count as crossings above (touching counts, as libigl's
    and CGAL's tests have it) are of four kinds, and three of them can
    touch:

    * coplanar faces whose insides do not overlap (they meet along their
      edges: a face of one box and the coplanar side of the box stacked on
      it, or a tessellation that is not edge to edge);
    * coplanar faces that overlap facing opposite ways: two sheets back to
      back, the two sides of a wall between solids drawn in different
      triangles (the same triangles each way round are double-sided faces,
      never tested); overlapping the same way they are two layers of one
      side, a crossing;
    * faces not in one plane where one lies on one side of the other's
      plane (it meets that plane at an edge or a corner): a face that rests
      on the other;
    * faces that each pass through the other's plane, which cross.

    A surface that passes through a face exactly along an edge or a corner
    of its own rests on the face from both sides (its faces on either side
    of that edge), so a face touched from both of its sides (the side a
    face rests on; an opposite coplanar face counts as resting on the side
    its normal points to, where the other solid lies) is crossed, and each
    of its touching pairs counts as a crossing. This is a test per face, not
    per point: a face that two other bodies touch from its two sides is
    taken as crossed too, the safe answer.

    Parameters
    ----------
    exact : ExactPoints
        The distinct positions.
    tri : ndarray (M, 3)
        Each face's corners as position numbers.
    pairs : ndarray (K, 2)
        Pairs of faces that meet.

    Returns
    -------
    ndarray (K,), bool

    Examples
    --------
    A face of one box under a face of the box on it, facing the other way
    and cut along the other diagonal; and a face standing on it:

    >>> p = ExactPoints([[0, 0, 0], [2, 0, 0], [2, 2, 0], [0, 2, 0], [1, 1, 0], [1, 1, 1], [1, 1, -1]])
    >>> touching_pairs(p, np.array([[0, 1, 2], [0, 3, 1], [4, 1, 5]]), np.array([[0, 1], [0, 2]])).tolist()
    [True, True]

    A face through it along its own edge (resting on both sides) crosses:

    >>> touching_pairs(p, np.array([[0, 1, 2], [4, 1, 5], [1, 4, 6]]), np.array([[0, 1], [0, 2]])).tolist()
    [False, False]
    """
    if not len(pairs):
        return np.zeros(0, bool)
    A, B = tri[pairs[:, 0]], tri[pairs[:, 1]]
    # sides are signed towards each face's normal: orient3d is negative on the side the normal points to
    side_b = -np.stack([exact.orient3d(A[:, 0], A[:, 1], A[:, 2], B[:, k]) for k in range(3)], axis=1)
    side_a = -np.stack([exact.orient3d(B[:, 0], B[:, 1], B[:, 2], A[:, k]) for k in range(3)], axis=1)
    coplanar = ~side_b.any(axis=1)
    touch = np.zeros(len(pairs), bool)
    # the side of each face that the other rests on (0: none said)
    rests_a, rests_b = np.zeros(len(pairs), np.int64), np.zeros(len(pairs), np.int64)
    k = np.flatnonzero(coplanar)
    if len(k):
        axis = projection_axis(exact, A[k])
        apart = _insides_apart_2d(exact, A[k], B[k], axis)
        turn = exact.orient2d(A[k, 0], A[k, 1], A[k, 2], axis) * exact.orient2d(B[k, 0], B[k, 1], B[k, 2], axis)
        back_to_back = ~apart & (turn < 0)
        touch[k] = apart | back_to_back
        rests_a[k[back_to_back]] = rests_b[k[back_to_back]] = 1
    k = np.flatnonzero(~coplanar)
    if len(k):
        b_one = np.all(side_b[k] >= 0, axis=1) | np.all(side_b[k] <= 0, axis=1)
        a_one = np.all(side_a[k] >= 0, axis=1) | np.all(side_a[k] <= 0, axis=1)
        touch[k] = b_one | a_one
        rests_a[k] = np.where(b_one, np.sign(side_b[k].sum(axis=1)), 0)
        rests_b[k] = np.where(a_one, np.sign(side_a[k].sum(axis=1)), 0)
    # faces touched from both sides are crossed
    face = np.concatenate([pairs[:, 0], pairs[:, 1]])
    rests = np.concatenate([rests_a, rests_b])
    said = rests != 0
    up = np.unique(face[said & (rests > 0)])
    down = np.unique(face[said & (rests < 0)])
    crossed = np.intersect1d(up, down)
    return touch & ~np.isin(pairs, crossed).any(axis=1)


def _insides_apart_2d(exact: ExactPoints, A: np.ndarray, B: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Whether coplanar triangles ``A`` and ``B`` (corners as position
    numbers), seen along ``axis``, have no inside point in common: a line
    through an edge of one has the other on its far side, touching allowed
    (two convex polygons whose insides are apart are parted by the line of
    one of their edges)."""
    apart = np.zeros(len(A), bool)
    for S, T in ((A, B), (B, A)):
        for e in range(3):
            p, q, r = S[:, e], S[:, (e + 1) % 3], S[:, (e + 2) % 3]
            own = exact.orient2d(p, q, r, axis)
            far = np.stack([exact.orient2d(p, q, T[:, j], axis) * own <= 0 for j in range(3)], axis=1)
            apart |= far.all(axis=1)
    return apart


def sliver_joined(exact: ExactPoints, tri: np.ndarray, slivers: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Per pair of faces found to meet, whether zero-area faces explain
    it: an edge of one lies on an edge of the other (collinear, within
    it), both edges of ``slivers`` (faces of collinear corners), and the
    faces meet only along it (the shorter edge's face has its third corner
    off the other's plane, or on the other side of the line). ``tri``:
    corners as position numbers."""
    n = np.int64(len(exact.xyz))

    def edge_keys(t: np.ndarray) -> np.ndarray:  # (K, 3) edge keys, edge e from corner e to e + 1
        a, b = t, np.roll(t, -1, axis=1)
        return np.minimum(a, b).astype(np.int64) * n + np.maximum(a, b)

    on_sliver = np.isin(edge_keys(tri[pairs.reshape(-1)]), np.unique(edge_keys(slivers))).reshape(-1, 2, 3)
    out = np.zeros(len(pairs), bool)
    for r in np.flatnonzero(on_sliver[:, 0].any(axis=1) & on_sliver[:, 1].any(axis=1)).tolist():
        for long, short in ((0, 1), (1, 0)):
            F, G = tri[pairs[r, long]], tri[pairs[r, short]]
            for e in np.flatnonzero(on_sliver[r, long]).tolist():
                for g in np.flatnonzero(on_sliver[r, short]).tolist():
                    out[r] |= _meets_only_along(exact, F, e, G, g)
    return out


def _meets_only_along(exact: ExactPoints, F: np.ndarray, e: int, G: np.ndarray, g: int) -> bool:
    """Whether G's edge g lies on F's edge e (not the same edge) and the
    two faces meet only along it."""
    p, q, c = F[e], F[(e + 1) % 3], F[(e + 2) % 3]
    a, b, k = G[g], G[(g + 1) % 3], G[(g + 2) % 3]
    if {int(a), int(b)} == {int(p), int(q)}:
        return False
    x = exact.xyz
    lo, hi = np.minimum(x[p], x[q]), np.maximum(x[p], x[q])
    for m in (a, b):
        line = exact.orient2d(np.array([p] * 3), np.array([q] * 3), np.array([m] * 3), np.arange(3))
        if line.any() or (x[m] < lo).any() or (x[m] > hi).any():
            return False
    if exact.orient3d(np.array([p]), np.array([q]), np.array([c]), np.array([k]))[0] != 0:
        return True
    axis = projection_axis(exact, F[None])[0]
    view = exact.orient2d(np.array([p, p]), np.array([q, q]), np.array([c, k]), np.array([axis, axis]))
    return bool(view[0] * view[1] < 0)


def _compiled_pairs(exact: ExactPoints, tri: np.ndarray, axis: np.ndarray, grid: CubeGrid) -> list:
    """The crossing pairs: decided by the compiled pass where its float64
    signs are certified, the others here, in integers."""
    from .crossing_kernels import cube_pairs

    small = exact.small  # (None: no integer path compiled in)
    found = np.zeros((1024, 2), np.int64)
    undecided = np.zeros((1 << 16, 2), np.int64)
    while True:
        nf, nu = cube_pairs(exact.xyz, small, tri, axis, grid.box, grid.key, grid.start, grid.size, grid.cl,
                            grid.lo, grid.hi, grid.dims, found, undecided)
        if nf <= len(found) and nu <= len(undecided):
            break
        found = np.zeros((max(nf, len(found)), 2), np.int64)
        undecided = np.zeros((max(nu, len(undecided)), 2), np.int64)
    rest = undecided[:nu]
    return [found[:nf], rest[_cross(exact, tri, axis, rest)]]


def _compiled_axis(exact: ExactPoints, tri: np.ndarray) -> np.ndarray:
    """:func:`projection_axis`, compiled where the float64 signs are
    certified, the rest by it."""
    from .crossing_kernels import face_axes

    axis = np.zeros(len(tri), np.int64)
    undecided = np.zeros(len(tri), bool)
    face_axes(exact.xyz, exact.small, tri, axis, undecided)
    rest = np.flatnonzero(undecided)
    if len(rest):
        axis[rest] = projection_axis(exact, tri[rest])
    return axis


def projection_axis(exact: ExactPoints, tri: np.ndarray) -> np.ndarray:
    """Per triangle, the axis along which it is seen with its largest
    extent (a component of its normal that is exactly non-zero), or -1 where
    its corners are collinear."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    signs = np.stack([exact.orient2d(a, b, c, np.full(len(tri), k)) for k in range(3)], axis=1)
    x = exact.xyz
    with np.errstate(over="ignore", invalid="ignore"):
        normal = np.abs(np.cross(x[b] - x[a], x[c] - x[a]))
    normal = np.where(signs != 0, np.nan_to_num(normal, nan=0.0, posinf=1.0) + 1e-300, -1.0)
    axis = np.argmax(normal, axis=1)
    axis[~np.any(signs != 0, axis=1)] = -1
    return axis


def _cross(exact: ExactPoints, tri: np.ndarray, axis: np.ndarray, pairs: np.ndarray) -> np.ndarray:
    """Which face pairs cross, by the number of corners they share."""
    A, B = tri[pairs[:, 0]], tri[pairs[:, 1]]
    same = A[:, :, None] == B[:, None, :]
    shared = same.sum(axis=(1, 2))
    out = np.zeros(len(pairs), dtype=bool)
    for n, rule in ((2, _edge_rule), (1, _corner_rule), (0, _apart_rule)):
        rows = np.flatnonzero(shared == n)
        if len(rows):
            out[rows] = rule(exact, A[rows], B[rows], same[rows], axis[pairs[rows, 0]], axis[pairs[rows, 1]])
    return out


def _edge_rule(exact, A, B, same, axis_a, axis_b) -> np.ndarray:
    """Faces on a common edge cross when coplanar on one side of it."""
    ia = np.argmin(same.any(axis=2), axis=1)  # A's corner off the common edge
    ib = np.argmin(same.any(axis=1), axis=1)
    rows = np.arange(len(A))
    a, b = A[rows, ia], B[rows, ib]
    u, v = A[rows, (ia + 1) % 3], A[rows, (ia + 2) % 3]
    out = exact.orient3d(u, v, a, b) == 0
    k = np.flatnonzero(out)
    side = exact.orient2d(u[k], v[k], a[k], axis_a[k]) * exact.orient2d(u[k], v[k], b[k], axis_a[k])
    out[k] = side > 0
    return out


def _corner_rule(exact, A, B, same, axis_a, axis_b) -> np.ndarray:
    """Faces on a common corner cross when the edge of either opposite that
    corner meets the other face."""
    ia = np.argmax(same.any(axis=2), axis=1)
    ib = np.argmax(same.any(axis=1), axis=1)
    rows = np.arange(len(A))
    out = segment_meets_triangle(exact, A[rows, (ia + 1) % 3], A[rows, (ia + 2) % 3], B, axis_b)
    rest = np.flatnonzero(~out)
    out[rest] = segment_meets_triangle(exact, B[rest, (ib[rest] + 1) % 3], B[rest, (ib[rest] + 2) % 3],
                                       A[rest], axis_a[rest])
    return out


def _apart_rule(exact, A, B, same, axis_a, axis_b) -> np.ndarray:
    """Faces with no common corner cross when they meet: then an edge of one
    meets the other (their common part is convex, with its ends on edges)."""
    side_b = np.stack([exact.orient3d(A[:, 0], A[:, 1], A[:, 2], B[:, k]) for k in range(3)], axis=1)
    side_a = np.stack([exact.orient3d(B[:, 0], B[:, 1], B[:, 2], A[:, k]) for k in range(3)], axis=1)
    apart = (np.all(side_b > 0, axis=1) | np.all(side_b < 0, axis=1)
             | np.all(side_a > 0, axis=1) | np.all(side_a < 0, axis=1))
    out = np.zeros(len(A), dtype=bool)
    for (S, T, sides, axis_t) in ((B, A, side_b, axis_a), (A, B, side_a, axis_b)):
        for k in range(3):
            rows = np.flatnonzero(~apart & ~out)
            if not len(rows):
                return out
            p, q = (k, (k + 1) % 3)
            out[rows] = segment_meets_triangle(exact, S[rows, p], S[rows, q], T[rows], axis_t[rows],
                                               sides[rows, p], sides[rows, q])
    return out


def segment_meets_triangle(exact: ExactPoints, p: np.ndarray, q: np.ndarray, tri: np.ndarray, axis: np.ndarray,
                           side_p: np.ndarray | None = None, side_q: np.ndarray | None = None) -> np.ndarray:
    """Whether each closed segment ``p q`` meets its closed triangle ``tri``
    (point indices; ``axis`` from :func:`projection_axis`; ``side_p``,
    ``side_q``: the orientations of ``p`` and ``q`` against the triangle's
    plane, where known)."""
    t0, t1, t2 = tri[:, 0], tri[:, 1], tri[:, 2]
    sp = exact.orient3d(t0, t1, t2, p) if side_p is None else side_p
    sq = exact.orient3d(t0, t1, t2, q) if side_q is None else side_q
    out = np.zeros(len(p), dtype=bool)
    meets_plane = ~((sp == sq) & (sp != 0))
    planar = meets_plane & (sp == 0) & (sq == 0)
    k = np.flatnonzero(meets_plane & ~planar)  # one point on the plane: inside the triangle?
    if len(k):
        w = np.stack([exact.orient3d(p[k], q[k], a[k], b[k]) for a, b in ((t0, t1), (t1, t2), (t2, t0))], axis=1)
        out[k] = ~(np.any(w > 0, axis=1) & np.any(w < 0, axis=1))
    k = np.flatnonzero(planar)
    if len(k):
        out[k] = _segment_meets_triangle_2d(exact, p[k], q[k], tri[k], axis[k])
    return out


def _segment_meets_triangle_2d(exact, p, q, tri, axis) -> np.ndarray:
    """Segment and triangle in one plane, seen along ``axis``: an end inside
    the triangle, or the segment meets an edge."""
    out = _inside(exact, p, tri, axis) | _inside(exact, q, tri, axis)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        k = np.flatnonzero(~out)
        if not len(k):
            break
        out[k] = _segments_meet_2d(exact, p[k], q[k], tri[k, a], tri[k, b], axis[k])
    return out


def _inside(exact, x, tri, axis) -> np.ndarray:
    """Whether point ``x`` lies in the closed triangle seen along ``axis``."""
    s = np.stack([exact.orient2d(tri[:, a], tri[:, b], x, axis) for a, b in ((0, 1), (1, 2), (2, 0))], axis=1)
    return ~(np.any(s > 0, axis=1) & np.any(s < 0, axis=1))


def _segments_meet_2d(exact, p, q, r, s, axis) -> np.ndarray:
    """Whether closed segments ``p q`` and ``r s`` meet, seen along ``axis``."""
    d1, d2 = exact.orient2d(r, s, p, axis), exact.orient2d(r, s, q, axis)
    d3, d4 = exact.orient2d(p, q, r, axis), exact.orient2d(p, q, s, axis)
    out = (d1 * d2 < 0) & (d3 * d4 < 0)
    x = exact.xyz
    for d, x0, x1, y in ((d1, r, s, p), (d2, r, s, q), (d3, p, q, r), (d4, p, q, s)):
        on = d == 0
        lo, hi = np.minimum(x[x0], x[x1]), np.maximum(x[x0], x[x1])
        out |= on & np.all((lo <= x[y]) & (x[y] <= hi), axis=1)
    return out
