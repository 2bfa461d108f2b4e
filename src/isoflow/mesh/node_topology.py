"""The topology of many disjoint triangle meshes at once: the nodes of a
scene as a reader gives them back, each closed or not, its Euler number
and its bodies, in one compiled pass over their triangles.

The read-back of ``surface --labels -o OUT.glb`` measures every label's
node of the file as trimesh parsed it. trimesh's own figures
(``is_watertight``, ``is_winding_consistent``, ``body_count``) sort the
edges of a mesh object built per node; a scene of thousands of labels
then spends most of its read-back building those objects. Here every node
is measured in place, its edges grouped by their first vertex (a counting
sort: a closed surface's vertices have a few edges each), with the same
definitions:

* *closed*: every edge of the node lies in exactly two of its triangles,
  which run along it in opposite directions (trimesh's watertight and
  consistently wound): each directed edge ``a -> b`` occurs once, its
  reverse ``b -> a`` once, and no triangle repeats a vertex;
* *Euler number* of a closed node: ``V - E + F`` with ``E = 3F / 2``, its
  vertices counted where a triangle uses them;
* *bodies*: the components of the graph of its triangles' edges, over the
  vertices some triangle uses (trimesh's ``body_count`` less its unused
  vertices).
"""

from __future__ import annotations

import numpy as np

from ..scale.jit import njit


@njit(cache=True, nogil=True, inline="always")
def _root(parent, v):
    """The root of v in the union-find, halving the path on the way."""
    while parent[v] != v:
        parent[v] = parent[parent[v]]
        v = parent[v]
    return v


@njit(cache=True, nogil=True)
def _node(faces, v0, nv, f0, f1, start, heads, parent, used):
    """``(closed, used vertices, bodies)`` of one node: its triangles
    ``faces[f0:f1]`` on the vertices ``v0 .. v0 + nv - 1`` (-1s where a
    triangle names a vertex outside them). ``start``, ``heads``, ``parent``
    and ``used``: scratch of the largest node's size."""
    for v in range(nv + 1):
        start[v] = 0
    for v in range(nv):
        parent[v] = v
        used[v] = False
    for f in range(f0, f1):
        for c in range(3):
            a = faces[f, c] - v0
            if a < 0 or a >= nv:
                return False, -1, -1
            start[a + 1] += 1
            used[a] = True
    for v in range(nv):
        start[v + 1] += start[v]
    # the heads of every vertex's edges, after its start (start[a] moves
    # past them while they are placed, and is moved back after)
    closed = f1 > f0
    for f in range(f0, f1):
        for c in range(3):
            a, b = faces[f, c] - v0, faces[f, (c + 1) % 3] - v0
            closed = closed and a != b
            heads[start[a]] = b
            start[a] += 1
            ra, rb = _root(parent, a), _root(parent, b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
    for v in range(nv, 0, -1):
        start[v] = start[v - 1]
    start[0] = 0
    for a in range(nv):
        if not closed:
            break
        for e in range(start[a], start[a + 1]):
            b = heads[e]
            once, back = 0, 0
            for g in range(start[a], start[a + 1]):
                once += heads[g] == b
            for g in range(start[b], start[b + 1]):
                back += heads[g] == a
            if once != 1 or back != 1:
                closed = False
                break
    vertices, bodies = 0, 0
    for v in range(nv):
        if used[v]:
            vertices += 1
            bodies += _root(parent, v) == v
    return closed, vertices, bodies


@njit(cache=True, nogil=True)
def _nodes(faces, vfirst, ffirst, closed, vertices, bodies):
    """:func:`_node` of every node ``t``: vertices ``vfirst[t] ..
    vfirst[t + 1] - 1``, triangles ``ffirst[t] .. ffirst[t + 1] - 1``."""
    n = len(vfirst) - 1
    most_v, most_f = 1, 1
    for t in range(n):
        most_v = max(most_v, vfirst[t + 1] - vfirst[t])
        most_f = max(most_f, ffirst[t + 1] - ffirst[t])
    start = np.empty(most_v + 1, np.int64)
    heads = np.empty(3 * most_f, np.int64)
    parent = np.empty(most_v, np.int64)
    used = np.empty(most_v, np.bool_)
    for t in range(n):
        closed[t], vertices[t], bodies[t] = _node(faces, vfirst[t], vfirst[t + 1] - vfirst[t], ffirst[t],
                                                  ffirst[t + 1], start, heads, parent, used)


def node_topology(faces: np.ndarray, vfirst: np.ndarray, ffirst: np.ndarray) -> dict[str, np.ndarray]:
    """Closedness, Euler number and bodies of disjoint triangle meshes
    (see the module docs).

    Parameters
    ----------
    faces : numpy.ndarray
        ``(F, 3)`` integer triangles of every node, node after node, on
        one numbering of all their vertices.
    vfirst, ffirst : numpy.ndarray
        ``n + 1`` integers each: node ``t`` has the vertices ``vfirst[t] ..
        vfirst[t + 1] - 1`` and the triangles ``faces[ffirst[t]:ffirst[t +
        1]]``.

    Returns
    -------
    dict of numpy.ndarray
        Per node: ``closed`` (bool), ``vertices`` (those its triangles
        use), ``euler`` (``vertices - F / 2``, meaningful where closed) and
        ``bodies``; a node whose triangles name a vertex not its own is not
        closed and has ``vertices`` and ``bodies`` -1.

    Examples
    --------
    A tetrahedron, the same with one triangle turned over, and an octahedron:

    >>> import numpy as np
    >>> tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> octa = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
    ...                  [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    >>> flipped = tet.copy()
    >>> flipped[0] = [0, 1, 2]
    >>> faces = np.concatenate([tet, flipped + 4, octa + 8])
    >>> found = node_topology(faces, np.array([0, 4, 8, 14]), np.array([0, 4, 8, 16]))
    >>> found["closed"].tolist(), found["euler"].tolist(), found["bodies"].tolist()
    ([True, False, True], [2, 2, 2], [1, 1, 1])
    """
    faces = np.ascontiguousarray(faces, np.int64).reshape(-1, 3)
    vfirst, ffirst = np.asarray(vfirst, np.int64), np.asarray(ffirst, np.int64)
    n = len(vfirst) - 1
    closed, vertices, bodies = np.zeros(n, np.bool_), np.zeros(n, np.int64), np.zeros(n, np.int64)
    _nodes(faces, vfirst, ffirst, closed, vertices, bodies)
    return {"closed": closed, "vertices": vertices, "euler": vertices - np.diff(ffirst) // 2, "bodies": bodies}
