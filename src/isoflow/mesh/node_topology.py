"""The topology of many disjoint triangle meshes at once: the nodes of a
scene as a reader gives them back, each closed or not, its Euler number
and its bodies, in one compiled pass over their triangles; and the volume
each encloses (:func:`node_volumes`).

The read-back of every surface file (:mod:`isoflow.mesh.readback`)
measures the mesh trimesh parsed from it, one node, or every label's node
of a ``surface --labels`` scene. trimesh's own figures (``is_watertight``,
``is_winding_consistent``, ``euler_number``, ``body_count``) sort every
edge of a mesh object built per node, most of a large file's read-back,
and of a scene of thousands of labels. Here every node is measured in
place, its edges grouped by their smaller vertex (a counting sort) and
told apart by a mark per vertex and direction (each edge looked at once,
not against every other edge of its vertex), with the same definitions:

* *closed*: every edge of the node lies in exactly two of its triangles,
  which run along it in opposite directions (trimesh's watertight and
  consistently wound): each directed edge ``a -> b`` occurs once, its
  reverse ``b -> a`` once, and no triangle repeats a vertex;
* *Euler number*: ``V - E + F``, its vertices counted where a triangle
  uses them and its edges once each (trimesh's ``euler_number``, over
  its ``edges_unique``); ``E = 3F / 2`` where it is closed;
* *bodies*: the components of the graph of its triangles' edges, over the
  vertices some triangle uses (trimesh's ``body_count`` less its unused
  vertices).
"""

from __future__ import annotations

import numpy as np

from ..scale.jit import njit
from ..scale.kernels import find


@njit(cache=True, nogil=True)
def _node(faces, v0, nv, f0, f1, start, keys, mark, parent, used):
    """``(closed, used vertices, bodies, edges)`` of one node: its
    triangles ``faces[f0:f1]`` on the vertices ``v0 .. v0 + nv - 1`` (-1s
    where a triangle names a vertex outside them). ``start``, ``keys``,
    ``parent`` and ``used``: scratch of the largest node's size; ``mark``:
    two per vertex of the largest node, none of them ``v0`` or more.

    Each edge ``a -> b`` is kept at its smaller vertex as ``2 max(a, b) +
    (a > b)``: the edges of a vertex that are one edge whichever way they
    run differ in the last bit alone. A mark per such key, the vertex's
    own number (``v0`` on: unique across the nodes of a call, so no mark
    is ever cleared), finds each key's repeats. The node is closed where
    no triangle repeats a vertex, no directed edge repeats (``3F`` keys
    apart) and every edge runs both ways (twice as many directed edges
    as edges)."""
    for v in range(nv + 1):
        start[v] = 0
    for v in range(nv):
        parent[v] = v
        used[v] = False
    for f in range(f0, f1):
        for c in range(3):
            a, b = faces[f, c] - v0, faces[f, (c + 1) % 3] - v0
            # both ends checked before either is an index: b is this face's next
            # corner, checked as a on the next turn, but indexes start first
            if a < 0 or a >= nv or b < 0 or b >= nv:
                return False, -1, -1, -1
            start[min(a, b) + 1] += 1
            used[a] = True
    for v in range(nv):
        start[v + 1] += start[v]
    # the keys of every vertex's edges, after its start (start[a] moves
    # past them while they are placed, and is moved back after)
    closed = f1 > f0
    for f in range(f0, f1):
        for c in range(3):
            a, b = faces[f, c] - v0, faces[f, (c + 1) % 3] - v0
            closed = closed and a != b
            low = min(a, b)
            keys[start[low]] = 2 * max(a, b) + (a > b)
            start[low] += 1
    for v in range(nv, 0, -1):
        start[v] = start[v - 1]
    start[0] = 0
    edges, directed = 0, 0
    for a in range(nv):
        here = v0 + a
        for e in range(start[a], start[a + 1]):
            k = keys[e]
            if mark[k] == here:  # this directed edge again
                closed = False
                continue
            mark[k] = here
            directed += 1
            if mark[k ^ 1] != here:  # an edge not seen the other way: a new one
                edges += 1
                ra, rb = find(parent, a), find(parent, k >> 1)
                if ra != rb:
                    parent[max(ra, rb)] = min(ra, rb)
    closed = closed and directed == 3 * (f1 - f0) and directed == 2 * edges
    vertices, bodies = 0, 0
    for v in range(nv):
        if used[v]:
            vertices += 1
            bodies += find(parent, v) == v
    return closed, vertices, bodies, edges


@njit(cache=True, nogil=True)
def _nodes(faces, vfirst, ffirst, closed, vertices, bodies, edges):
    """:func:`_node` of every node ``t``: vertices ``vfirst[t] ..
    vfirst[t + 1] - 1``, triangles ``ffirst[t] .. ffirst[t + 1] - 1``."""
    n = len(vfirst) - 1
    most_v, most_f = 1, 1
    for t in range(n):
        most_v = max(most_v, vfirst[t + 1] - vfirst[t])
        most_f = max(most_f, ffirst[t + 1] - ffirst[t])
    start = np.empty(most_v + 1, np.int64)
    keys = np.empty(3 * most_f, np.int64)
    mark = np.full(2 * most_v, -1, np.int64)
    parent = np.empty(most_v, np.int64)
    used = np.empty(most_v, np.bool_)
    for t in range(n):
        closed[t], vertices[t], bodies[t], edges[t] = _node(faces, vfirst[t], vfirst[t + 1] - vfirst[t], ffirst[t],
                                                            ffirst[t + 1], start, keys, mark, parent, used)


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
        use), ``edges`` (distinct, whichever way they run), ``euler``
        (``vertices - edges + F``) and ``bodies``; a node whose triangles
        name a vertex not its own is not closed and has ``vertices``,
        ``edges`` and ``bodies`` -1.

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
    closed, vertices, bodies, edges = (np.zeros(n, np.bool_), np.zeros(n, np.int64), np.zeros(n, np.int64),
                                       np.zeros(n, np.int64))
    _nodes(faces, vfirst, ffirst, closed, vertices, bodies, edges)
    return {"closed": closed, "vertices": vertices, "edges": edges, "euler": vertices - edges + np.diff(ffirst),
            "bodies": bodies}


@njit(cache=True, nogil=True)
def _volumes(vertices, faces, vfirst, ffirst, units, out):
    """:func:`node_volumes` into ``out``."""
    for t in range(len(vfirst) - 1):
        v0, v1 = vfirst[t], vfirst[t + 1]
        u = units[t]
        # the mean of the positions in the unit, not in world units: near
        # float64's largest coordinates their world sum is inf (a power-of-two
        # unit, as the read-back's, divides exactly, so the differences are the same)
        mx, my, mz = 0.0, 0.0, 0.0
        for v in range(v0, v1):
            mx += vertices[v, 0] / u
            my += vertices[v, 1] / u
            mz += vertices[v, 2] / u
        n = max(v1 - v0, 1)
        mx, my, mz = mx / n, my / n, mz / n
        total = 0.0
        for f in range(ffirst[t], ffirst[t + 1]):
            a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
            if min(a, b, c) < v0 or max(a, b, c) >= v1:
                total = np.nan
                break
            ax, ay, az = vertices[a, 0] / u - mx, vertices[a, 1] / u - my, vertices[a, 2] / u - mz
            bx, by, bz = vertices[b, 0] / u - mx, vertices[b, 1] / u - my, vertices[b, 2] / u - mz
            cx, cy, cz = vertices[c, 0] / u - mx, vertices[c, 1] / u - my, vertices[c, 2] / u - mz
            total += ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        out[t] = total / 6.0


def node_volumes(vertices: np.ndarray, faces: np.ndarray, vfirst: np.ndarray, ffirst: np.ndarray,
                 units: np.ndarray | float = 1.0) -> np.ndarray:
    """The signed volume each node's triangles enclose (the divergence
    theorem: a sixth of the sum of ``a . (b x c)``), in its ``units`` cubed,
    about the mean of its vertices (far from the origin, triple products
    of world coordinates cancel to a few digits).

    Parameters
    ----------
    vertices : numpy.ndarray
        ``(V, 3)`` positions of every node's vertices, node after node.
    faces, vfirst, ffirst : numpy.ndarray
        As for :func:`node_topology` (the triangles on one numbering of
        all the vertices).
    units : numpy.ndarray or float
        Per node (or one for all), the length the volume is counted in.

    Returns
    -------
    numpy.ndarray
        Per node, its volume in ``units`` cubed: positive for a closed
        surface wound outward (counter-clockwise seen from outside); NaN
        for a node whose triangles name a vertex not its own.

    Examples
    --------
    A tetrahedron of volume 1/6, and a unit cube in units of 1/2:

    >>> import numpy as np
    >>> tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> import trimesh
    >>> cube = trimesh.creation.box()
    >>> vertices = np.concatenate([corners, cube.vertices])
    >>> faces = np.concatenate([tet, cube.faces + 4])
    >>> node_volumes(vertices, faces, [0, 4, 12], [0, 4, 16], [1.0, 0.5]).round(6).tolist()
    [0.166667, 8.0]
    """
    vfirst, ffirst = np.asarray(vfirst, np.int64), np.asarray(ffirst, np.int64)
    n = len(vfirst) - 1
    units = np.broadcast_to(np.asarray(units, np.float64), (n,)).copy()
    out = np.zeros(n, np.float64)
    _volumes(np.ascontiguousarray(vertices, np.float64).reshape(-1, 3),
             np.ascontiguousarray(faces, np.int64).reshape(-1, 3), vfirst, ffirst, units, out)
    return out
