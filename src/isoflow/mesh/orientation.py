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
an open, non-manifold mesh had whole correctly oriented pieces inverted,
and its winding number counted solid where there was none. So a seam is
followed only where it is evidence of a turned face: on a closed manifold
component (no boundary or non-manifold edge) every seam, as before; on any
other component only a *smooth* seam, whose two faces turned to agree bend
by less than 60 degrees (their given normals' dot product below -1/2). The
solids of a non-manifold join meet at an angle, as touching boxes at a
right angle; a face turned over in a tessellated sheet lies almost along
its neighbours.
"""

from __future__ import annotations

from collections import deque

import numpy as np

from ..scale.graphs import components

#: a seam is smooth where its faces' given unit normals have a dot product
#: below this: turned to agree, they bend by less than 60 degrees
SMOOTH_SEAM = -0.5


def orient_faces(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, int]:
    """Faces turned over to agree with their neighbours across the seams
    that show a turned face, and how many were turned.

    Parameters
    ----------
    vertices : float ndarray (N, 3)
    faces : int ndarray (M, 3)

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
    two touching solids' faces do) are left as given:

    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> tet = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    >>> bad = tet.copy(); bad[0] = bad[0, ::-1]
    >>> fixed, n = orient_faces(v, bad)
    >>> n, bool(np.array_equal(fixed, tet))
    (1, True)
    >>> orient_faces(v, np.array([[0, 1, 2], [0, 1, 3]]))[1]
    0
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    corner = np.asarray(vertices, dtype=np.float64)[f]
    normal = np.cross(corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0])
    area = np.linalg.norm(normal, axis=1)
    label, seams = followed_seams(f, normal / np.where(area > 0, area, 1.0)[:, None])
    if len(seams) == 0:
        return f, 0
    turn = turned_patches(seams, np.bincount(label, weights=area, minlength=int(label.max()) + 1))[label]
    fixed = f.copy()
    fixed[turn] = fixed[turn][:, ::-1]
    return fixed, int(turn.sum())


def edge_sides(faces: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The faces' sides grouped by undirected edge.

    Returns
    -------
    face : int64 ndarray (H,)
        The face of each side (degenerate sides, ``a -> a``, left out).
    uses : int64 ndarray (H,)
        How many sides share each side's edge.
    pairs : int64 ndarray (K, 2)
        The two sides of each edge that exactly two sides share.
    agree : bool ndarray (K,)
        Whether the two run their edge in opposite directions.
    """
    a, b = faces.reshape(-1), faces[:, [1, 2, 0]].reshape(-1)
    face = np.repeat(np.arange(len(faces)), 3)
    keep = a != b
    a, b, face = a[keep], b[keep], face[keep]
    n = int(faces.max()) + 1 if len(faces) else 1
    _, edge, count = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_inverse=True, return_counts=True)
    edge = edge.reshape(-1)
    order = np.argsort(edge, kind="stable")
    pairs = order[count[edge[order]] == 2].reshape(-1, 2)
    agree = (a[pairs[:, 0]] < b[pairs[:, 0]]) != (a[pairs[:, 1]] < b[pairs[:, 1]])
    return face, count[edge], pairs, agree


def followed_seams(faces: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each face's patch, and the pairs of patches at the seams followed:
    every seam of a closed manifold component, the smooth seams of any
    other (pairs of two different patches)."""
    face, uses, pairs, agree = edge_sides(faces)
    m = len(faces)
    _, label = components(m, face[pairs[agree, 0]], face[pairs[agree, 1]])
    seam = face[pairs[~agree]]
    count, comp = components(m, face[pairs[:, 0]], face[pairs[:, 1]])
    closed = np.bincount(comp[face[uses != 2]], minlength=count) == 0
    smooth = np.einsum("ij,ij->i", normals[seam[:, 0]], normals[seam[:, 1]]) < SMOOTH_SEAM
    seams = label[seam[smooth | closed[comp[seam[:, 0]]]]]
    return label, seams[seams[:, 0] != seams[:, 1]]  # within one patch turning it changes nothing


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
