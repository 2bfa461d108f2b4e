"""T-junctions: a vertex of one face lying inside another face's edge.

A CAD export tessellates each face of the model apart, so the two sides
of a model edge may be sampled at different points: one side's edge
``a -> b`` meets the other side's ``b -> p -> a``, and no edge of the mesh
has two faces there.  The mesh counts as open (boundary edges) although
the surface is closed as drawn.  :func:`split_t_junctions` splits each
such edge at the vertices lying on it, where that pairs every piece with
a piece of the other side, so the mesh's own genus (and manifold3d's and
pymeshlab's) can be counted.  Only boundary edges and their vertices are
looked at; the geometry is unchanged (the new corners lie on the edges,
a face split along two or more edges gets a vertex at its centroid).
"""

from __future__ import annotations

import numpy as np


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
        Triangles.
    tolerance : float
        How far from an edge a vertex may lie and count as on it (the
        weld's distance).

    Returns
    -------
    vertices, faces : ndarray
        The split mesh (vertices appended: a centroid per face split along
        two or more edges), or the arrays given where nothing closes.
    facts : dict or None
        ``points`` (vertices that split an edge), ``faces`` (faces split)
        and ``edges`` (boundary edges closed), or None.

    Examples
    --------
    A unit square of two triangles above one whose bottom edge has a vertex
    at its middle:

    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0, 0]], float)
    >>> f = np.array([[0, 1, 2], [1, 3, 2], [3, 0, 2]])
    >>> _, f2, facts = split_t_junctions(v, f, 1e-9)
    >>> facts, len(f2)
    ({'points': 1, 'faces': 1, 'edges': 3}, 4)
    """
    faces = np.asarray(faces, np.int64)
    slots = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)  # edge j of face i is slot 3 i + j
    _, inverse, counts = np.unique(np.sort(slots, axis=1), axis=0, return_inverse=True, return_counts=True)
    open_slots = np.flatnonzero(counts[inverse.ravel()] == 1)
    if not len(open_slots):
        return vertices, faces, None
    inserts = _points_on_edges(vertices, slots, open_slots, tolerance)
    inserts = _closing(slots, open_slots, inserts)
    if not inserts:
        return vertices, faces, None
    new_v, new_f, split = _split_faces(vertices, faces, inserts)
    before = len(open_slots)
    _, inverse, counts = np.unique(np.sort(new_f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0,
                                   return_inverse=True, return_counts=True)
    after = int(np.count_nonzero(counts[inverse.ravel()] == 1))
    points = len(np.unique(np.concatenate(list(inserts.values()))))
    return new_v, new_f, {"points": points, "faces": split, "edges": before - after}


def _points_on_edges(v: np.ndarray, slots: np.ndarray, open_slots: np.ndarray, tol: float) -> dict:
    """Per open edge slot, the boundary vertices strictly inside it (within
    ``tol`` of the segment), in order from its first corner."""
    from scipy.spatial import cKDTree

    ends = slots[open_slots]
    points = np.unique(ends)
    a, b = v[ends[:, 0]], v[ends[:, 1]]
    near = cKDTree(v[points]).query_ball_point((a + b) / 2, np.linalg.norm(b - a, axis=1) / 2 + tol)
    found = {}
    for k, candidates in enumerate(near):
        if len(candidates) <= 2:  # its own two corners
            continue
        c = points[np.asarray(candidates)]
        c = c[(c != ends[k, 0]) & (c != ends[k, 1])]
        d = b[k] - a[k]
        t = (v[c] - a[k]) @ d / (d @ d)
        off = np.linalg.norm(a[k] + t[:, None] * d - v[c], axis=1)
        on = (t > 0) & (t < 1) & (off <= tol)
        if on.any():
            found[int(open_slots[k])] = c[on][np.argsort(t[on])]
    return found


def _closing(slots: np.ndarray, open_slots: np.ndarray, inserts: dict) -> dict:
    """The inserts of the edges whose every piece, once split, has a piece
    of an open edge running the other way."""
    pieces = {}
    for s in open_slots.tolist():
        chain = [slots[s, 0], *inserts.get(s, ()), slots[s, 1]]
        pieces[s] = list(zip(chain[:-1], chain[1:]))
    directed = {(int(p), int(q)) for run in pieces.values() for p, q in run}
    return {s: pts for s, pts in inserts.items() if all((int(q), int(p)) in directed for p, q in pieces[s])}


def _split_faces(v: np.ndarray, faces: np.ndarray, inserts: dict) -> tuple[np.ndarray, np.ndarray, int]:
    """Each face with inserted corners cut into triangles of its own
    orientation: a fan from the opposite corner where one edge is split,
    else from a new vertex at its centroid."""
    by_face: dict[int, dict[int, np.ndarray]] = {}
    for s, pts in inserts.items():
        by_face.setdefault(s // 3, {})[s % 3] = pts
    keep = np.ones(len(faces), dtype=bool)
    new_faces, new_points = [], []
    for i, edges in by_face.items():
        keep[i] = False
        corners = faces[i]
        if len(edges) == 1:
            (j, pts), = edges.items()
            path = [corners[j], *pts, corners[(j + 1) % 3]]
            new_faces += [(p, q, corners[(j + 2) % 3]) for p, q in zip(path[:-1], path[1:])]
            continue
        ring = [c for j in range(3) for c in (corners[j], *edges.get(j, ()))]
        centre = len(v) + len(new_points)
        new_points.append(v[corners].mean(axis=0))
        new_faces += [(p, q, centre) for p, q in zip(ring, ring[1:] + ring[:1])]
    out_v = np.vstack([v, np.asarray(new_points).reshape(-1, 3)])
    out_f = np.vstack([faces[keep], np.asarray(new_faces, np.int64).reshape(-1, 3)])
    return out_v, out_f, len(by_face)
