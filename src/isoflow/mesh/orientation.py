"""Repair of face orientation before a mesh is read by its winding number.

Faces joined across an edge that exactly two faces share, running it in
opposite directions, agree; the faces joined so make *patches*, each
consistently oriented. Two patches whose faces run a two-face edge the same
way meet at a *seam*, and turning one of them over resolves it: so each
group of patches joined by seams is turned to agree, the side with the
smaller area turned over (a cavity stays a cavity), as trimesh's
``repair.fix_winding`` propagates one face's orientation.

A seam is ambiguous, though: a face turned over inside a sheet, or what is
left of a non-manifold join (two solids touching along an edge, listed with
four faces there) whose other two faces are missing. Turned at every seam,
an open, non-manifold mesh can have whole correctly oriented pieces
inverted, and its winding number count solid where there is none. So a
seam is followed where it shows a turned face:

* on a closed component (every edge used an even number of times; faces
  joined across two-face edges and, round an edge of four faces or more,
  each to its neighbours by angle: :func:`ring_pairs`), every seam, as
  trimesh's ``fix_winding`` does;
* elsewhere a *smooth* seam, whose two faces turned to agree bend by less
  than 60 degrees (their given normals' dot product below -1/2): a face
  turned over in a tessellated sheet lies almost along its neighbours;
* and a *wide* seam: the seam edges between its two patches are at least
  half as long as the rim of the one with less area, the one that would be
  turned (a patch's rim: its edges not shared with another face of it, that
  is its seams, open boundary and non-manifold edges). A wall of an open
  low-poly box turned over is bounded by seams on three of its four sides;
  the remnant of a join in a cut mesh meets the other solid along the one
  former join edge, and most of its rim is the holes of the cut.

A closed shell oriented by most of its area, where its faces were turned
at random, may be wound as the shell round it, a cavity then read as
solid: rays tell (:func:`nested_shells`).
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..scale.graphs import components
from .load import repeated_faces

#: a seam is smooth where its faces' given unit normals have a dot product
#: below this: turned to agree, they bend by less than 60 degrees
SMOOTH_SEAM = -0.5

#: faces of each closed group that rays start from (:func:`nested_shells`),
#: its rounds, and the faces a round's rays may look at (per face, and more)
SHELL_RAYS = 4
SHELL_ROUNDS = 8
SHELL_WORK = 8, 1 << 16

#: a sharp seam is followed where the seam edges of the patch with less area
#: (with every patch) are at least this share of its rim
WIDE_SEAM = 0.5


def orient_faces(vertices: np.ndarray, faces: np.ndarray, first: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Faces turned over to agree with their neighbours across the seams
    that show a turned face, and how many were turned.

    Parameters
    ----------
    vertices : float ndarray (N, 3)
    faces : int ndarray (M, 3)
    first : int ndarray (M,), optional
        :func:`~isoflow.mesh.load.repeated_faces` of ``faces``, where the
        caller has it already; found here otherwise.

    Returns
    -------
    faces : int64 ndarray (M, 3)
        The faces, those turned over with their corners reversed.
    flipped : int
        How many faces were turned over.

    Examples
    --------
    A closed tetrahedron with one face turned inwards is turned back; two
    triangles at a right angle that run their shared edge the same way (as
    two touching solids' faces do), each with most of its rim open, are
    left as given:

    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> tet = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    >>> bad = tet.copy(); bad[0] = bad[0, ::-1]
    >>> fixed, n = orient_faces(v, bad)
    >>> n, bool(np.array_equal(fixed, tet))
    (1, True)
    >>> orient_faces(v, np.array([[0, 1, 2], [0, 1, 3]]))[1]
    0

    The same tetrahedron open, its face on ``x = 0`` missing, with its
    face on ``z = 0`` turned: two of that face's three sides are seams, and
    it is turned back:

    >>> fixed, n = orient_faces(v, bad[:3])
    >>> n, bool(np.array_equal(fixed, tet[:3]))
    (1, True)
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    # copies of a face (the same corners the same way round) add their
    # windings (a wall listed twice jumps w by 2): they are oriented as one
    # face, so that a copy is never turned against its twin to cancel it
    one, copy_of = single_copies(f, first)
    corners = np.asarray(vertices, dtype=np.float64)[one]
    label, seams, area, closed = followed_seams(corners, one)
    if len(seams) == 0:
        return f, 0
    turned, group = turned_patches(seams, area)
    turn = nested_shells(corners, turned[label], group[label], closed, np.asarray(vertices, dtype=np.float64), one)[copy_of]
    fixed = f.copy()
    fixed[turn] = fixed[turn][:, ::-1]
    return fixed, int(turn.sum())


def single_copies(faces: np.ndarray, first: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each face once: of faces on the same three corners the same way
    round (any rotation of them) the first in file order, and for every
    face the index of its copy among those kept
    (:func:`~isoflow.mesh.load.repeated_faces`).

    Parameters
    ----------
    faces : int ndarray (M, 3)
    first : int ndarray (M,), optional
        :func:`~isoflow.mesh.load.repeated_faces` of ``faces``, where the
        caller has it already; found here otherwise.

    Returns
    -------
    one : int64 ndarray (M', 3)
        The distinct faces, in file order.
    copy_of : int64 ndarray (M,)
        ``one[copy_of[i]]`` is face i (up to a rotation of its corners).

    Examples
    --------
    >>> one, copy_of = single_copies(np.array([[0, 1, 2], [1, 2, 0], [0, 2, 1]]))
    >>> one.tolist(), copy_of.tolist()
    ([[0, 1, 2], [0, 2, 1]], [0, 0, 1])
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    first = repeated_faces(f) if first is None else np.asarray(first, dtype=np.int64)
    keep = np.flatnonzero(first == np.arange(len(f)))
    rank = np.zeros(len(f), dtype=np.int64)
    rank[keep] = np.arange(len(keep))
    return f[keep], rank[first]


def edge_sides(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The faces' sides grouped by undirected edge.

    Returns
    -------
    side : int64 ndarray (H,)
        Each side's index in ``faces[:, [0, 1, 2]]`` order (face ``side // 3``,
        from its corner ``side % 3``); degenerate sides, ``a -> a``, left out.
    face : int64 ndarray (H,)
        The face of each side.
    uses : int64 ndarray (H,)
        How many sides share each side's edge.
    pairs : int64 ndarray (K, 2)
        The two sides (positions in ``side``) of each edge that exactly two
        sides share.
    agree : bool ndarray (K,)
        Whether the two run their edge in opposite directions.
    edge : int64 ndarray (H,)
        Each side's undirected edge, numbered from 0.
    """
    a, b = faces.reshape(-1), faces[:, [1, 2, 0]].reshape(-1)
    side = np.flatnonzero(a != b)
    a, b, face = a[side], b[side], side // 3
    n = int(faces.max()) + 1 if len(faces) else 1
    _, edge, count = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_inverse=True, return_counts=True)
    edge = edge.reshape(-1)
    order = np.argsort(edge, kind="stable")
    pairs = order[count[edge[order]] == 2].reshape(-1, 2)
    agree = (a[pairs[:, 0]] < b[pairs[:, 0]]) != (a[pairs[:, 1]] < b[pairs[:, 1]])
    return side, face, count[edge], pairs, agree, edge


def ring_pairs(corners: np.ndarray, faces: np.ndarray, side: np.ndarray, uses: np.ndarray, edge: np.ndarray) -> np.ndarray:
    """The sides of each edge that an even number of sides share, four or
    more, each paired with the next round the edge (in the order of the
    angles of their faces about it, the last with the first).

    A closed surface that bounds a solid without overlaps (the winding
    number 0 or 1 off it, as the boundary of a union of cubes that touch
    along edges) passes from solid to empty at each face round such an
    edge: neighbours round it run the edge in opposite directions.

    Parameters
    ----------
    corners : float ndarray (M, 3, 3)
        The faces' corner positions.
    faces : int ndarray (M, 3)
    side, uses, edge : int64 ndarray (H,)
        As :func:`edge_sides` gives them.

    Returns
    -------
    int64 ndarray (K, 2)
        Pairs of sides (positions in ``side``).

    Examples
    --------
    The cubes [0, 1]^3 and [1, 2] x [1, 2] x [0, 1] share the edge from
    (1, 1, 0) to (1, 1, 1), each by two faces there (a triangle of each,
    faces 0 and 1 the first cube's): round the edge come the second
    cube's faces, its solid between them, and then the first's.

    >>> v = np.array([[1, 1, 0], [1, 1, 1], [0, 1, 0], [1, 0, 0], [2, 1, 0], [1, 2, 0]], float)
    >>> f = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 0, 5]])
    >>> side, face, uses, _, _, edge = edge_sides(f)
    >>> face[ring_pairs(v[f], f, side, uses, edge)].tolist()
    [[3, 0], [0, 1], [1, 2], [2, 3]]
    """
    ring = np.flatnonzero((uses >= 4) & (uses % 2 == 0))
    if len(ring) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    ring = ring[np.argsort(edge[ring], kind="stable")]
    face, corner = side[ring] // 3, side[ring] % 3
    first = faces[face, corner] < faces[face, (corner + 1) % 3]
    lo = np.where(first, corner, (corner + 1) % 3)
    hi = np.where(first, (corner + 1) % 3, corner)
    p = corners[face, lo]
    d = corners[face, hi] - p
    u = corners[face, (corner + 2) % 3] - p
    u -= d * (np.einsum("ij,ij->i", u, d) / np.maximum(np.einsum("ij,ij->i", d, d), np.finfo(float).tiny))[:, None]
    # angles about the edge from its first face's plane, the same edge for each side
    start = np.flatnonzero(np.r_[True, edge[ring][1:] != edge[ring][:-1]])
    size = np.diff(np.r_[start, len(ring)])
    e1 = np.repeat(u[start], size, axis=0)
    angle = np.arctan2(np.einsum("ij,ij->i", np.cross(d, e1), u) / np.linalg.norm(d, axis=1), np.einsum("ij,ij->i", e1, u))
    ring = ring[np.lexsort((angle, edge[ring]))]
    nxt = np.arange(1, len(ring) + 1)
    nxt[start + size - 1] = start
    return np.stack([ring, ring[nxt]], axis=1)


def followed_seams(corners: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each face's patch, the pairs of patches at the seams followed (every
    seam of a closed component; on any other, the smooth seams and the wide
    ones; pairs of two different patches), each patch's area (twice it, as
    the cross products give it) and each face's closed component (-1: in
    none).

    A closed component is one whose edges are all used an even number of
    times: faces joined across two-face edges and, where some face of
    theirs lies in a component with a seam, across edges of four faces or
    more, each face with its neighbours round the edge
    (:func:`ring_pairs`).

    ``corners`` are the faces' corner positions, (M, 3, 3)."""
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    size = np.linalg.norm(normal, axis=1)
    normal /= np.where(size > 0, size, 1.0)[:, None]
    side, face, uses, pairs, agree, edge = edge_sides(faces)
    corner = side % 3
    length = np.linalg.norm(corners[face, (corner + 1) % 3] - corners[face, corner], axis=1)
    m = len(faces)
    ring = ring_pairs(corners, faces, side, uses, edge)
    if len(ring):
        # a component whose faces agree everywhere keeps the orientation it
        # is drawn with: two solids that overlap along an edge they share
        # step the winding number 0, 1, 2, 1 round it, not 0, 1, 0, 1
        sheets, sheet = components(m, face[pairs[:, 0]], face[pairs[:, 1]])
        seamed = np.bincount(sheet[face[pairs[~agree, 0]]], minlength=sheets) > 0
        ring = ring[seamed[sheet[face[ring[:, 0]]]] | seamed[sheet[face[ring[:, 1]]]]]
    joined = np.concatenate([pairs, ring])
    count, comp = components(m, face[joined[:, 0]], face[joined[:, 1]])
    closed = np.bincount(comp[face[uses % 2 == 1]], minlength=count) == 0
    ring = ring[closed[comp[face[ring[:, 0]]]]]
    up = faces.reshape(-1)[side] < faces[:, [1, 2, 0]].reshape(-1)[side]
    ring_agree = up[ring[:, 0]] != up[ring[:, 1]]
    together = np.concatenate([pairs[agree], ring[ring_agree]])
    patches, label = components(m, face[together[:, 0]], face[together[:, 1]])
    area = np.bincount(label, weights=size, minlength=patches)
    seam = face[pairs[~agree]]
    smooth = np.einsum("ij,ij->i", normal[seam[:, 0]], normal[seam[:, 1]]) < SMOOTH_SEAM
    rim = np.ones(len(side), dtype=bool)
    rim[together] = False  # an edge joining two faces of one patch is inside it
    rim_length = np.bincount(label[face[rim]], weights=length[rim], minlength=patches)
    wide = wide_seams(label[seam], length[pairs[~agree, 0]], rim_length, area)
    seams = label[np.concatenate([seam[smooth | wide | closed[comp[seam[:, 0]]]], face[ring[~ring_agree]]])]
    # within one patch turning it changes nothing
    return label, seams[seams[:, 0] != seams[:, 1]], area, np.where(closed[comp], comp, -1)


def wide_seams(seams: np.ndarray, length: np.ndarray, rim: np.ndarray, area: np.ndarray) -> np.ndarray:
    """Whether each seam (a pair of patches, with its edge's length) is
    wide: the seam edges of the patch with less area, the one that would be
    turned, at least ``WIDE_SEAM`` of its rim length.

    Its seams with every patch count, not only those with the other patch
    of this seam: a face turned over inside an open box meets one patch
    flat and others at its sides, and each of those seams tells which way
    it faces (followed only where they were the one patch's, the patches
    beyond were left out and a box whose two halves have equal area kept
    half its faces turned). A join's remnant is still no wide seam: most of
    each side's rim is open.

    Examples
    --------
    Patch 0 (area 1, rim 3) meets patch 1 along one edge and patch 2 along
    the other two: bounded by seams, each of its seams is wide. Patch 3
    (area 5, rim 10) meets patch 4 along one edge of 1: not wide.

    >>> wide_seams(np.array([[0, 1], [0, 2], [0, 2], [3, 4]]), np.array([1.0, 1, 1, 1]),
    ...            np.array([3.0, 8, 8, 10, 10]), np.array([1.0, 4, 4, 5, 5])).tolist()
    [True, True, True, False]
    """
    lo, hi = seams.min(axis=1), seams.max(axis=1)
    turned = np.where(area[lo] <= area[hi], lo, hi)
    seamed = np.bincount(seams.reshape(-1), weights=np.repeat(length, 2), minlength=len(rim))
    return seamed[turned] >= WIDE_SEAM * rim[turned]


def turned_patches(seams: np.ndarray, area: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which patches to turn over, and each patch's group (-1: none): the
    patches joined by seams, each with the other side of its seams turned
    (breadth first, as trimesh's ``fix_winding``; the first side wins
    where the seams disagree), and in each group the side with less area
    turned."""
    count = len(area)
    ends = np.concatenate([seams, seams[:, ::-1]])
    ends = ends[np.argsort(ends[:, 0], kind="stable")]
    start = np.searchsorted(ends[:, 0], np.arange(count + 1)).tolist()
    other = ends[:, 1].tolist()
    side = np.full(count, -1, dtype=np.int64)
    group = np.full(count, -1, dtype=np.int64)
    groups = 0
    for seed in np.unique(seams).tolist():
        if side[seed] >= 0:
            continue
        side[seed], group[seed] = 0, groups
        queue = deque([seed])
        while queue:
            p = queue.popleft()
            for q in other[start[p]:start[p + 1]]:
                if side[q] < 0:
                    side[q], group[q] = 1 - side[p], groups
                    queue.append(q)
        groups += 1
    joined = group >= 0
    g, s, w = group[joined], side[joined], area[joined]
    one = np.bincount(g, weights=w * s, minlength=groups) <= np.bincount(g, weights=w, minlength=groups) / 2
    turned = np.zeros(count, dtype=bool)
    turned[joined] = np.where(one[g], s == 1, s == 0)
    return turned, group


def nested_shells(corners: np.ndarray, turn: np.ndarray, group: np.ndarray, closed: np.ndarray,
                  vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """``turn`` (per face) with whole closed shells turned over where they
    lie in the solid that the rest bounds as a cavity would, but wound as
    the solid round them.

    A group of patches on a closed component is oriented by most of its
    area; where its faces were turned at random, that says nothing, and a
    shell inside another (a cavity), wound the same way as it, doubles
    the winding number inside it (2: solid) where the cavity is empty. So
    from a point inside a few faces of each such group, a ray along an
    axis, to the side the face faces, sums the signed crossings
    (:func:`~isoflow.mesh.census.ray_crossings`) with the faces of the
    closed components as oriented now: the winding number just in front of
    the face. A surface that bounds a solid without overlaps has 0 in
    front of each face and 1 behind it (-1 and 0 where it is inverted).
    Where every ray of a group that touches no edge, corner or plane of a
    face finds another number, and no face of the group crosses or touches
    a face outside it (:func:`~isoflow.mesh.crossings.crossing_pairs`:
    overlapping solids' shells are left as they are), the group is turned
    over; round after round, as turning a shell changes the numbers inside
    it (at most ``SHELL_ROUNDS``).

    Parameters
    ----------
    corners : float ndarray (M, 3, 3)
        The faces' corners, as given.
    turn : bool ndarray (M,)
        Faces turned over so far.
    group : int64 ndarray (M,)
        Each face's group of patches joined by seams (-1: none).
    closed : int64 ndarray (M,)
        Each face's closed component (-1: none); with fewer than two, no
        shell lies in another.
    vertices : float ndarray (N, 3)
    faces : int ndarray (M, 3)

    Returns
    -------
    bool ndarray (M,)

    Examples
    --------
    Two cubes, one in the other, both wound outwards, each a group: the
    inner one is turned, a cavity.

    >>> import trimesh
    >>> a, b = trimesh.creation.box((3, 3, 3)), trimesh.creation.box((1, 1, 1))
    >>> v = np.concatenate([a.vertices, b.vertices]); f = np.concatenate([a.faces, b.faces + 8])
    >>> group = np.repeat([0, 1], 12)
    >>> nested_shells(v[f], np.zeros(24, bool), group, group, v, f)[[0, 12]].tolist()
    [False, True]
    """
    shell = (group >= 0) & (closed >= 0)
    if not shell.any() or len(np.unique(closed[closed >= 0])) < 2:
        return turn
    from .census import axis_rays, face_points, spread_faces
    from .crossings import crossing_pairs
    from .cube_grid import CubeGrid

    turn = turn.copy()
    inside = np.flatnonzero(closed >= 0)
    c = corners[inside]
    grid = CubeGrid(c.min(axis=1), c.max(axis=1), compiled=True)
    faces_of = np.flatnonzero(shell[inside])
    own, which = spread_faces(faces_of, group[inside][faces_of], SHELL_RAYS)
    names = np.unique(group[inside][faces_of])  # the groups, as ranked in ``which``
    t = c[own]
    normal = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    axis = np.argmax(np.abs(normal), axis=1)
    keep = normal[np.arange(len(own)), axis] != 0  # a face without area starts no ray
    own, axis, which, t, normal = own[keep], axis[keep], which[keep], t[keep], normal[keep]
    start = face_points(t)
    ahead = np.sign(normal[np.arange(len(own)), axis])  # as given: a turned face faces the other way
    crossing = None
    weight = np.ones(len(inside), np.int8)
    for _ in range(SHELL_ROUNDS):
        flip = turn[inside]
        tri = np.ascontiguousarray(np.where(flip[:, None, None], c[:, ::-1], c))
        towards = np.where(flip[own], -ahead, ahead)
        count, told = axis_rays(tri, weight, start, axis, towards, own, grid, SHELL_WORK[0] * len(tri) + SHELL_WORK[1],
                                True)
        fine = (count == 0) | (count == -1)
        n = len(names)
        seen = np.bincount(which[told], minlength=n) > 0
        bad = seen & (np.bincount(which[told & fine], minlength=n) == 0)
        if not bad.any():
            break
        if crossing is None:
            pairs = crossing_pairs(vertices, faces[inside])
            apart = group[inside][pairs[:, 0]] != group[inside][pairs[:, 1]]
            crossing = np.unique(group[inside][pairs[apart]])
        bad &= ~np.isin(names, crossing)
        if not bad.any():
            break
        turn[np.isin(group, names[bad])] ^= True
    return turn
