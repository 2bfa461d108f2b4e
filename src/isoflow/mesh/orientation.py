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

* on a closed manifold component (no boundary or non-manifold edge), every
  seam, as trimesh's ``fix_winding`` does;
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
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..scale.graphs import components
from .load import repeated_faces

#: a seam is smooth where its faces' given unit normals have a dot product
#: below this: turned to agree, they bend by less than 60 degrees
SMOOTH_SEAM = -0.5

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
    label, seams, area = followed_seams(np.asarray(vertices, dtype=np.float64)[one], one)
    if len(seams) == 0:
        return f, 0
    turn = turned_patches(seams, area)[label][copy_of]
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


def edge_sides(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
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
    return side, face, count[edge], pairs, agree


def followed_seams(corners: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each face's patch, the pairs of patches at the seams followed (every
    seam of a closed manifold component; on any other, the smooth seams and
    the wide ones; pairs of two different patches), and each patch's area
    (twice it, as the cross products give it).

    ``corners`` are the faces' corner positions, (M, 3, 3)."""
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    size = np.linalg.norm(normal, axis=1)
    normal /= np.where(size > 0, size, 1.0)[:, None]
    side, face, uses, pairs, agree = edge_sides(faces)
    corner = side % 3
    length = np.linalg.norm(corners[face, (corner + 1) % 3] - corners[face, corner], axis=1)
    m = len(faces)
    patches, label = components(m, face[pairs[agree, 0]], face[pairs[agree, 1]])
    area = np.bincount(label, weights=size, minlength=patches)
    seam = face[pairs[~agree]]
    count, comp = components(m, face[pairs[:, 0]], face[pairs[:, 1]])
    closed = np.bincount(comp[face[uses != 2]], minlength=count) == 0
    smooth = np.einsum("ij,ij->i", normal[seam[:, 0]], normal[seam[:, 1]]) < SMOOTH_SEAM
    rim = np.ones(len(side), dtype=bool)
    rim[pairs[agree]] = False  # an edge joining two faces of one patch is inside it
    rim_length = np.bincount(label[face[rim]], weights=length[rim], minlength=patches)
    wide = wide_seams(label[seam], length[pairs[~agree, 0]], rim_length, area)
    seams = label[seam[smooth | wide | closed[comp[seam[:, 0]]]]]
    return label, seams[seams[:, 0] != seams[:, 1]], area  # within one patch turning it changes nothing


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


def turned_patches(seams: np.ndarray, area: np.ndarray) -> np.ndarray:
    """Which patches to turn over: the patches joined by seams, each with
    the other side of its seams turned (breadth first, as trimesh's
    ``fix_winding``; the first side wins where the seams disagree), and in
    each group the side with less area turned."""
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
    return turned
