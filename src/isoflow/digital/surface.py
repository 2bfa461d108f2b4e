"""The boundary of a digital object as a closed quad mesh (docs/mathematics.md).

Faces are the unit squares between an object voxel and a background voxel,
oriented outward; vertices are lattice points. Where the object is not
well-composed, several *sheets* of the surface pass through one lattice point
(or one lattice edge), and the mesh gives each sheet its own vertex:

* around a lattice **edge** with four boundary faces (two voxels, or two
  background cells, meeting only along that edge), faces are paired inside
  each object voxel under 6-connectivity (the voxels stay apart) or across the
  edge under 26-connectivity (the voxels join);
* at a lattice **vertex**, the boundary faces are joined into sheets through
  the edges ("spokes") they share, with that same pairing rule; every sheet is
  a disc, so the mesh is a closed 2-manifold.

A vertex where only two opposite octants differ from the other six (a
*vertex contact*) can be split by a quad mesh but never joined. The split is
right for an object pair under 6-connectivity and for a background pair under
26; otherwise (object pair under 26, background pair under 6) the mesh splits
a point that the digital topology joins. isoflow always splits (so that the
mesh is a manifold that trimesh, MeshLab and manifold3d accept) and counts
those vertices as ``pinched``; the mesh's Euler characteristic is then
``V - E + F = 2 chi + 2 pinched``.

Everything is computed with lookup tables over the 256 configurations: no
loop over voxels or vertices.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError
from ..results import fields_repr, same_fields
from ..scale.arrays import as_array, binary, index_dtype, refuse_object
from ..scale.compiled import Method, use_compiled
from .configurations import configurations, octant_bit
from .connectivity import check_connectivity, resolve_connectivity
from .indices import OFF_SURFACE, a_lut, class_lut, code_lut, f_lut, gamma_lut, normal_lut

# --------------------------------------------------------------------------
# The 12 face slots of a vertex window and how they join into sheets
# --------------------------------------------------------------------------
# A boundary face through lattice vertex w has normal axis i and spans
# [w_j - 1 + d_j, w_j + d_j] x [w_k - 1 + d_k, w_k + d_k] along the two other
# axes (j, k) = (i+1, i+2) mod 3; its slot is 4 i + d_j + 2 d_k. It separates
# the octants with d_i = 0 and d_i = 1 and those (d_j, d_k).


def slot_octants(slot: int) -> tuple[int, int]:
    """The two octants (bits) that face slot ``slot`` separates, the one
    with ``d_i = 0`` first."""
    i, dj, dk = slot // 4, slot & 1, (slot >> 1) & 1
    j, k = (i + 1) % 3, (i + 2) % 3
    d = [0, 0, 0]
    d[j], d[k] = dj, dk
    lo = octant_bit(d)
    d[i] = 1
    return lo, octant_bit(d)


def _spoke_slots(axis: int, side: int) -> list[int]:
    """The four face slots containing the lattice edge from w along
    ``(-1)^(side+1) e_axis``: faces with another normal and d_axis = side."""
    out = []
    for slot in range(12):
        m = slot // 4
        if m == axis:
            continue
        d_axis = slot & 1 if axis == (m + 1) % 3 else (slot >> 1) & 1
        if d_axis == side:
            out.append(slot)
    return out


@cache
def sheet_lut(connectivity: int = 6) -> np.ndarray:
    """Sheet number (0..3) of every boundary face slot, -1 for no face.

    Shape (256, 12). Faces around a spoke are joined in pairs; with four
    boundary faces around one spoke (an edge contact) the pairs follow the
    connectivity: faces of the same object voxel under 6, faces of the same
    background cell under 26.
    """
    check_connectivity(3, connectivity)
    out = np.full((256, 12), -1, dtype=np.int8)
    slot_oct = [slot_octants(s) for s in range(12)]
    spokes = [_spoke_slots(ax, side) for ax in range(3) for side in (0, 1)]
    for c in range(256):
        bit = [(c >> b) & 1 for b in range(8)]
        boundary = [s for s in range(12) if bit[slot_oct[s][0]] != bit[slot_oct[s][1]]]
        parent = {s: s for s in boundary}

        def find(s, parent=parent):
            while parent[s] != s:
                s = parent[s]
            return s

        for spoke in spokes:
            faces = [s for s in spoke if s in parent]
            if len(faces) == 2:
                pairs = [faces]
            elif len(faces) == 4:
                keep = 1 if connectivity == 6 else 0  # share an object / background cell
                pairs = []
                for a in faces:
                    for b in faces:
                        shared = set(slot_oct[a]) & set(slot_oct[b])
                        if a < b and shared and bit[shared.pop()] == keep:
                            pairs.append([a, b])
            else:
                pairs = []
            for a, b in pairs:
                parent[find(a)] = find(b)
        roots: dict[int, int] = {}
        for s in boundary:
            out[c, s] = roots.setdefault(find(s), len(roots))
    return out


@cache
def pinch_lut(connectivity: int = 6) -> np.ndarray:
    """True at vertex contacts that the split mesh separates although the
    connectivity joins them: an opposite object pair under 26, an opposite
    background pair under 6."""
    out = np.zeros(256, dtype=bool)
    for o in range(8):
        pair = (1 << o) | (1 << (7 - o))
        if connectivity == 26:
            out[pair] = True
        else:
            out[255 ^ pair] = True
    return out


@cache
def doubled_spoke_lut(connectivity: int = 6) -> np.ndarray:
    """(256, 3, 2): the spoke (axis, side) carries four boundary faces whose
    two pairs belong to one sheet at this vertex.

    A lattice edge is passed twice by one mesh edge exactly when this holds at
    both of its ends; those edges get midpoints (see :class:`QuadMesh`).
    """
    sheets = sheet_lut(connectivity)
    out = np.zeros((256, 3, 2), dtype=bool)
    for axis in range(3):
        for side in (0, 1):
            slots = _spoke_slots(axis, side)
            ids = sheets[:, slots]
            four = (ids >= 0).all(axis=1)
            out[:, axis, side] = four & (ids == ids[:, :1]).all(axis=1)
    return out


# --------------------------------------------------------------------------
# The mesh
# --------------------------------------------------------------------------


@dataclass(eq=False, repr=False)
class QuadMesh:
    """A closed, outward-oriented quad mesh on lattice points.

    ``vertices`` are in the object's array-corner units (see
    :meth:`isoflow.digital.lattice.DigitalObject.world`); per-vertex arrays describe
    the lattice vertex each mesh vertex sits on.

    Where one surface sheet passes a lattice edge twice (an edge contact whose
    two pairs of faces belong to a single sheet at both ends), no choice of
    vertex copies separates the two copies of the edge. Each copy then gets a
    vertex at the edge's midpoint, listed in ``edge_midpoint``; those faces are
    pentagons (or more) with collinear corners. They are rare on voxelised
    shapes and frequent in random noise.

    Examples
    --------
    A single voxel: 8 vertices, 6 quads, a sphere (V - E + F = 2), each
    corner a convex corner (a = 1, eq. 4.10):

    >>> import numpy as np
    >>> m = boundary_mesh(np.ones((1, 1, 1), bool))
    >>> len(m.vertices), len(m.faces), m.euler_characteristic, m.a.tolist()
    (8, 6, 2, [1, 1, 1, 1, 1, 1, 1, 1])
    """

    vertices: np.ndarray  # (V, 3) float64, array-corner units
    faces: np.ndarray  # (F, 4) counter-clockwise seen from outside; int32 (int64 from 2^31 vertices on)
    edge_midpoint: np.ndarray  # (F, 4) as faces: vertex inserted on edge t -> t+1, or -1
    face_normals: np.ndarray  # (F, 3) int8, unit outward normals
    config: np.ndarray  # (V,) uint8 configuration byte (0 on midpoints)
    sheet: np.ndarray  # (V,) int8: which sheet of its lattice vertex (-1 on midpoints)
    connectivity: int
    pinched: int  # vertex contacts split against the connectivity

    __eq__ = same_fields  # the arrays by their elements: the generated __eq__ raised NumPy's ValueError
    __repr__ = fields_repr  # the arrays by their shape: the generated repr printed every vertex of a small mesh

    @property
    def midpoints(self) -> int:
        """How many vertices sit at the midpoint of a lattice edge one sheet
        passes twice (see the class's description; 0 on most shapes).

        Examples
        --------
        >>> boundary_mesh(np.ones((2, 2, 2), bool)).midpoints
        0
        """
        return int(np.count_nonzero(self.sheet < 0))

    @property
    def euler_characteristic(self) -> int:
        """``V - E + F``: every quad edge has two quads, and every midpoint
        adds one vertex and one edge, so ``E = 2F + midpoints``."""
        return len(self.vertices) - len(self.faces) - self.midpoints

    @property
    def vertex_class(self) -> np.ndarray:
        """Each vertex's class of eq. 4.9, an index into
        :data:`~isoflow.digital.indices.CLASS_LABELS` (``OFF_SURFACE`` on
        midpoints), as :attr:`Report.n <isoflow.Report>` counts them.

        Examples
        --------
        A 2x2x2 box: 8 convex corners (+,+,+), 12 edge vertices (+,0,0)
        and 6 face centres (0,0,empty):

        >>> from isoflow.digital.indices import CLASS_LABELS
        >>> m = boundary_mesh(np.ones((2, 2, 2), bool))
        >>> {CLASS_LABELS[c]: int(k) for c, k in zip(*np.unique(m.vertex_class, return_counts=True))}
        {'(0,0,∅)': 6, '(+,+,+)': 8, '(+,0,0)': 12}
        """
        return np.where(self.sheet >= 0, class_lut()[self.config], OFF_SURFACE)

    @property
    def gamma(self) -> np.ndarray:
        """The vertex angle gamma of each vertex (eq. 4.6, in eighths,
        :func:`~isoflow.digital.indices.gamma_lut`).

        Examples
        --------
        >>> m = boundary_mesh(np.ones((2, 2, 2), bool))
        >>> sorted(set(m.gamma.tolist()))  # flat face centres, convex edges and corners
        [0, 1, 2]
        """
        return gamma_lut()[self.config]

    @property
    def f(self) -> np.ndarray:
        """The vertex index f of each vertex (eq. 4.8 of Definition 9, :func:`~isoflow.digital.indices.f_lut`).

        Examples
        --------
        >>> m = boundary_mesh(np.ones((2, 2, 2), bool))
        >>> sorted(set(m.f.tolist()))
        [0, 1, 9]
        """
        return f_lut()[self.config]

    @property
    def code(self) -> np.ndarray:
        """Per-axis codes of eq. 4.3 (see :func:`isoflow.digital.indices.code_lut`)."""
        return code_lut()[self.config]

    @property
    def normal(self) -> np.ndarray:
        """Twice the vertex normal of Definition 14 (integer components)."""
        return normal_lut()[self.config]

    @property
    def a(self) -> np.ndarray:
        """Gauss-Bonnet weight of each lattice vertex (eq. 4.10), carried by
        its first sheet only, so that ``a.sum() == 8 chi`` on the mesh as on
        the lattice."""
        return np.where(self.sheet == 0, a_lut(self.connectivity)[self.config], 0)

    def polygons(self) -> np.ndarray:
        """Faces with their midpoints (docs/formats.md, "Surface files").

        Returns
        -------
        numpy.ndarray
            (F, 4) corner indices when no edge has a midpoint, else (F, 8)
            cyclic rows of corner, midpoint or -1, corner, ... (see
            :func:`polygon_rows`).

        Examples
        --------
        >>> boundary_mesh(np.ones((2, 2, 2), bool)).polygons().shape  # 24 quads, no doubled edge
        (24, 4)
        >>> pair = np.zeros((2, 2, 1), bool)
        >>> pair[0, 0], pair[1, 1] = True, True  # two cubes sharing an edge, joined under 26
        >>> boundary_mesh(pair, 26).polygons().shape  # the edge's midpoint in the faces along it
        (12, 8)
        """
        return polygon_rows(self.faces, self.edge_midpoint)

    def triangles(self) -> np.ndarray:
        """Triangles with the faces' orientation and no degenerate ones: two
        per plain quad, a fan from the first midpoint (see :meth:`polygons`)
        for a face with midpoints.

        Examples
        --------
        >>> boundary_mesh(np.ones((2, 2, 2), bool)).triangles().shape  # 24 quads
        (48, 3)
        """
        return triangle_rows(self.faces, self.edge_midpoint)[0]

    def components(self) -> list[dict]:
        """Closed surface components, largest first, each with its Euler
        characteristic and genus (``1 - chi/2``: every component is a closed
        orientable 2-manifold).

        Examples
        --------
        Two voxels that share one edge: at 6-connectivity the mesh splits
        the edge, two spheres:

        >>> v = np.zeros((2, 2, 1), bool); v[0, 0, 0] = v[1, 1, 0] = True
        >>> [c["genus"] for c in boundary_mesh(v, 6).components()], boundary_mesh(v, 6).euler_characteristic
        ([0, 0], 4)
        """
        nv = len(self.vertices)
        if nv == 0:
            return []
        n, label = _vertex_components(self.polygons(), nv)
        v_count = np.bincount(label, minlength=n)
        m_count = np.bincount(label[self.sheet < 0], minlength=n)
        f_count = np.bincount(label[self.faces[:, 0]], minlength=n)
        chi = v_count - f_count - m_count
        order = np.argsort(-f_count, kind="stable")
        return [
            {
                "faces": int(f_count[c]),
                "vertices": int(v_count[c]),
                "euler_characteristic": int(chi[c]),
                "genus": int(1 - chi[c] // 2),
            }
            for c in order
        ]


def polygon_rows(faces: np.ndarray, edge_midpoint: np.ndarray) -> np.ndarray:
    """Quads with the midpoints of their doubled edges as polygons.

    Parameters
    ----------
    faces : numpy.ndarray
        (F, 4) corner indices, counter-clockwise seen from outside.
    edge_midpoint : numpy.ndarray
        (F, 4): the vertex on edge t -> t + 1, or -1.

    Returns
    -------
    numpy.ndarray
        ``faces`` itself when no edge has a midpoint, else (F, 8) cyclic
        rows of corner, midpoint or -1, corner, ...; a row with a midpoint
        starts at its first midpoint. Readers (trimesh, MeshLab) triangulate
        a polygon by a fan from its first vertex; from a corner next to a
        midpoint that fan would draw the lattice edge the midpoint splits (a
        non-manifold edge) and a zero-area triangle along it. From the
        midpoint every fan triangle has area and every fan diagonal lies
        inside the face.

    Examples
    --------
    >>> polygon_rows(np.array([[0, 1, 2, 3]]), np.array([[-1, 4, -1, -1]])).tolist()
    [[4, 2, -1, 3, -1, 0, -1, 1]]
    """
    split = (edge_midpoint >= 0).any(axis=1)
    if not split.any():
        return faces
    seq = np.full((len(faces), 8), -1, dtype=np.int64)
    seq[:, 0::2] = faces
    seq[:, 1::2] = edge_midpoint
    rows = np.flatnonzero(split)
    first = np.argmax(edge_midpoint[rows] >= 0, axis=1) * 2 + 1
    seq[rows] = seq[rows[:, None], (first[:, None] + np.arange(8)) % 8]
    return seq


def triangle_rows(faces: np.ndarray, edge_midpoint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Triangles of quads with midpoints, and the face of each triangle.

    Parameters
    ----------
    faces, edge_midpoint : numpy.ndarray
        As in :func:`polygon_rows`.

    Returns
    -------
    triangles : numpy.ndarray
        (T, 3) with the faces' orientation and no degenerate ones: two per
        plain quad (in face order), then a fan from the first midpoint of
        each face with midpoints, grouped by polygon size.
    face : numpy.ndarray
        (T,) the face each triangle is part of.

    Examples
    --------
    >>> tris, face = triangle_rows(np.array([[0, 1, 2, 3]]), np.array([[-1, -1, -1, -1]]))
    >>> tris.tolist(), face.tolist()
    ([[0, 1, 2], [0, 2, 3]], [0, 0])
    """
    # the faces with a midpoint (few): one comparison over the flat array,
    # not a reduction along each short row
    split = np.unique(np.flatnonzero(np.ravel(edge_midpoint) >= 0) // 4)
    fans: list[tuple[np.ndarray, np.ndarray]] = []
    if len(split):
        seq = polygon_rows(faces[split], edge_midpoint[split])
        count = (seq >= 0).sum(axis=1)
        for size in np.unique(count):
            grp = seq[count == size]
            poly = grp[grp >= 0].reshape(len(grp), size)  # drop the -1 slots, keeping order
            fans += [(poly[:, [0, t, t + 1]], split[count == size]) for t in range(1, size - 1)]
    plain = len(faces) - len(split)
    # every array written once, in place: fresh pages cost more than the copies
    triangles = np.empty((2 * plain + sum(len(f) for f, _ in fans), 3), faces.dtype)
    face = np.empty(len(triangles), np.int64)
    kept = np.delete(np.arange(len(faces)), split)  # the plain quads' rows
    # (rows by index: a boolean row mask reads slower)
    quads = np.take(faces, kept, axis=0) if len(split) else faces
    # (0, 1, 2) and (0, 2, 3) of each quad ("clip": the columns are in range, and it writes unbuffered)
    np.take(quads, [0, 1, 2, 0, 2, 3], axis=1, out=triangles[:2 * plain].reshape(plain, 6), mode="clip")
    face[:2 * plain].reshape(plain, 2)[:] = kept[:, None]
    at = 2 * plain
    for tri, owner in fans:
        triangles[at:at + len(tri)], face[at:at + len(tri)] = tri, owner
        at += len(tri)
    return triangles, face


def _vertex_components(polygons: np.ndarray, nv: int) -> tuple[int, np.ndarray]:
    """Number of connected components and each vertex's component."""
    from ..scale import kernels

    if kernels.HAVE_NUMBA:
        label, n = kernels.label_polygons(polygons, nv)
        return n, label
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    width = polygons.shape[1]
    rows = np.repeat(polygons[:, 0], width - 1)
    cols = polygons[:, 1:].ravel()
    keep = cols >= 0
    graph = coo_matrix((np.ones(int(keep.sum()), np.int8), (rows[keep], cols[keep])), shape=(nv, nv))
    return connected_components(graph, directed=False)


# corner order of a +e_i face: (d_j, d_k), counter-clockwise seen from +e_i
_CORNER_D = ((1, 1), (0, 1), (0, 0), (1, 0))


#: Peak bytes of ``isoflow surface`` (mesh, components, PLY) above the
#: memory in use when it is checked: per lattice vertex of the volume by the
#: way the mesh is built (:func:`mesh_method`: the NumPy passes hold arrays
#: the size of the lattice, whose numbering is int64 from 2^28 voxels on,
#: the bit rows 1/8 byte a voxel) and per boundary face. Measured on balls,
#: tori and porous fields of 256^3 to 660^3 (docs/surface.md, "Memory: the
#: check before meshing"), rounded up. The read-back's imports are the
#: read-back's own estimate (:func:`isoflow.mesh.readback.readback_memory`),
#: checked when it comes: a budget too small for them skips the check alone.
MESH_BYTES_PER_VERTEX = {"numpy": 16, "compiled": 2}
MESH_BYTES_PER_VERTEX_INT64 = 24  # "numpy" from 2^28 lattice vertices on
MESH_BYTES_PER_FACE = 300


@cache
def face_slots() -> np.ndarray:
    """Boundary face slots (0..12) of each of the 256 configurations."""
    pairs = [slot_octants(s) for s in range(12)]
    codes = np.arange(256)
    return sum(((codes >> lo) & 1) != ((codes >> hi) & 1) for lo, hi in pairs).astype(np.int64)


def boundary_faces(hist: np.ndarray) -> int:
    """Number of boundary faces, from the configuration histogram alone:
    every face is seen in one slot of each of its four corners."""
    return int(np.asarray(hist, np.int64) @ face_slots()) // 4


def mesh_memory(hist: np.ndarray, method: Literal["numpy", "compiled"] = "numpy") -> int:
    """Estimated peak bytes of meshing the volume whose histogram is
    ``hist`` and writing the mesh (reading it back is estimated on its own,
    as a run with ``--no-check`` skips it).

    Parameters
    ----------
    hist : numpy.ndarray
        The volume's configuration histogram (256 counts, one per lattice
        vertex of the volume).
    method : {"numpy", "compiled"}
        How the mesh is built (:func:`mesh_method` of the volume); the
        NumPy passes' estimate is the larger one.

    Returns
    -------
    int

    Examples
    --------
    >>> from isoflow.digital.configurations import configuration_histogram
    >>> hist = configuration_histogram(np.ones((100, 100, 100), bool))
    >>> mesh_memory(hist, "compiled") < mesh_memory(hist, "numpy")
    True
    """
    if method not in MESH_BYTES_PER_VERTEX:
        raise IsoflowError(f"mesh_memory: method must be 'numpy' or 'compiled', got {method!r}")
    lattice = int(np.sum(hist))
    per_vertex = MESH_BYTES_PER_VERTEX[method]
    if method == "numpy" and lattice > 2**28:  # (the lattice outnumbers the voxels: this errs on the safe side)
        per_vertex = MESH_BYTES_PER_VERTEX_INT64
    return lattice * per_vertex + boundary_faces(hist) * MESH_BYTES_PER_FACE


def _empty_mesh(connectivity: int) -> QuadMesh:
    return QuadMesh(
        np.zeros((0, 3)), np.zeros((0, 4), index_dtype(0)), np.zeros((0, 4), index_dtype(0)),
        np.zeros((0, 3), np.int8), np.zeros(0, np.uint8), np.zeros(0, np.int8),
        connectivity, 0,
    )


def mesh_method(volume: np.ndarray, method: Method = "auto", record: bool = False) -> Literal["numpy", "compiled"]:
    """The way :func:`boundary_mesh` builds the mesh of ``volume``: from the
    bit rows (numba, :mod:`isoflow.scale.quads`) or with NumPy over the
    whole volume.

    Parameters
    ----------
    volume : numpy.ndarray
        The 3D volume to mesh.
    method : {"auto", "numpy", "compiled"}
        ``"auto"``: the bit rows where numba is installed and the volume has
        at least :func:`~isoflow.scale.compiled.least_voxels` voxels (with
        the surfaces: below that the NumPy mesh is done before numba has
        started; ``benchmarks/bench_mesh.py --small``), counting those that
        ``"auto"`` has already sent down the NumPy passes in this process
        (:func:`~isoflow.scale.compiled.use_compiled`), else NumPy.
    record : bool
        The mesh is built now: ``"auto"`` counts the volume in that tally.

    Returns
    -------
    {"numpy", "compiled"}

    Raises
    ------
    IsoflowError
        For another method, or ``"compiled"`` without numba.

    Examples
    --------
    >>> mesh_method(np.zeros((4, 4, 4), bool), "numpy"), mesh_method(np.zeros((4, 4, 4), bool), "compiled")
    ('numpy', 'compiled')
    """
    return "compiled" if use_compiled(volume, surfaces=True, method=method, record=record) else "numpy"


@cache
def row_tables(connectivity: int = 6) -> tuple[np.ndarray, ...]:
    """The tables of :mod:`isoflow.scale.quads` for one connectivity.

    Parameters
    ----------
    connectivity : {6, 26}
        The object's connectivity (it decides the pairing at edge contacts
        and which vertex contacts are pinched).

    Returns
    -------
    tuple of numpy.ndarray
        ``(nsheet, sheets, doubled_spoke, doubled_up, pinch)`` over the 256
        configurations: the number of sheets (int64), :func:`sheet_lut`
        (int64), :func:`doubled_spoke_lut`, whether a spoke toward +e_a is
        doubled (bool), :func:`pinch_lut` (int64).

    Examples
    --------
    >>> nsheet, sheets, dspoke, up, pinch = row_tables(6)
    >>> int(nsheet[0]), int(nsheet[1]), int(nsheet[0b10000001])
    (0, 1, 2)
    """
    sheets = sheet_lut(connectivity)
    dspoke = doubled_spoke_lut(connectivity)
    tables = ((sheets.max(axis=1) + 1).astype(np.int64), sheets.astype(np.int64), dspoke,
              np.asarray(dspoke[:, :, 1].any(axis=1)), pinch_lut(connectivity).astype(np.int64))
    for t in tables:
        t.setflags(write=False)
    return tables


def boundary_mesh(volume: ArrayLike, connectivity: int | np.integer | None = 6, method: Method = "auto") -> QuadMesh:
    """The closed quad mesh of a 3D object's boundary (docs/mathematics.md).

    Parameters
    ----------
    volume : array_like
        A 3D array of 0/1 values (bool or any numeric type), 1 for the
        object (any memory order).
    connectivity : {6, 26} or None
        The object's connectivity: faces meeting at an edge contact are
        paired inside each object voxel under 6, across the edge under 26;
        None is the paper's 6, as for :func:`isoflow.analyze`.
    method : {"auto", "numpy", "compiled"}
        How the mesh is built (see :func:`mesh_method`); every method gives
        the same mesh up to the order of its vertices and faces.

    Returns
    -------
    QuadMesh
        Vertices in array-corner units (voxel ``v`` spans ``[v, v + 1]``),
        ordered by lattice position and sheet (with ``"numpy"`` the
        midpoints of doubled edges come last, else after their edge's lower
        end).

    Raises
    ------
    IsoflowError
        (a ValueError) If the volume is not a 3D array of 0/1 values, or
        for a bad connectivity or method.

    Notes
    -----
    The mesh is a closed, oriented 2-manifold whose Euler characteristic
    is ``V - E + F = 2 chi + 2 pinched`` (section 4's chi, Theorems 10-11).

    Examples
    --------
    >>> mesh = boundary_mesh(np.ones((1, 1, 1), bool))
    >>> len(mesh.vertices), len(mesh.faces), mesh.euler_characteristic
    (8, 6, 2)
    """
    refuse_object(volume, "boundary_mesh: volume", then="the mesh is in array-corner units: obj.world(mesh.vertices) "
                  "puts its vertices where the object is")
    vol = as_array(volume, "boundary_mesh: volume")
    if vol.ndim != 3:  # an IsoflowError is the ValueError documented, as one line
        raise IsoflowError(f"boundary_mesh needs a 3D volume, got a {vol.ndim}D array")
    connectivity = resolve_connectivity(3, connectivity)  # as an int
    how = mesh_method(vol, method, record=True)
    # 2, 255 and NaN are refused as analyze refuses them, not meshed as
    # object; the bit rows read any nonzero byte of a bool array as set, so
    # only the NumPy faces need its bytes made 0/1
    # a label table is no mesh
    vol = binary(vol, "boundary_mesh: volume", canonical=how == "numpy", remedy="boundary_mesh({})", remedy_dims=(3,))
    if vol.size == 0:
        return _empty_mesh(connectivity)  # no voxel: no padded copy of the long axes
    if how == "compiled":
        return _mesh_from_rows(vol, connectivity)
    return _mesh_numpy(vol, connectivity)


def _mesh_from_rows(vol: np.ndarray, connectivity: int) -> QuadMesh:
    """The mesh from the bit rows, slab by slab on the threads
    (:func:`isoflow.scale.quads.mesh_rows`)."""
    from ..scale.quads import mesh_rows

    vertices, config, sheet, faces, midpoint, normals, pinched = mesh_rows(vol, row_tables(connectivity),
                                                                          connectivity)
    return QuadMesh(vertices, faces, midpoint, normals, config, sheet, connectivity, pinched)


def _mesh_numpy(vol: np.ndarray, connectivity: int) -> QuadMesh:
    """The mesh with NumPy over the whole volume: one configuration pass,
    a cumulative sum numbering the lattice vertices' sheets, three face
    passes, table look-ups."""
    cfg = configurations(vol)
    sheets = sheet_lut(connectivity)
    nsheet = (sheets.max(axis=1) + 1).astype(np.int32)[cfg.ravel()]
    # lattice vertex v with s sheets owns ids first[v] .. first[v] + s - 1
    first = np.cumsum(nsheet, dtype=np.int64 if vol.size > 2**28 else np.int32) - nsheet
    if not len(first) or int(first[-1] + nsheet[-1]) == 0:
        return _empty_mesh(connectivity)
    padded = np.pad(vol, 1)
    blocks = [_axis_faces(padded, cfg, first, i, sign, connectivity) for i in range(3) for sign in (1, -1)]
    blocks = [b for b in blocks if b is not None]
    faces = np.concatenate([b[0] for b in blocks])
    doubled = np.concatenate([b[1] for b in blocks])
    vertices, vconfig, sheet = _lattice_vertices(cfg, nsheet, first)
    pinched = int(np.count_nonzero(pinch_lut(connectivity)[vconfig] & (sheet == 0)))
    midpoint = np.full(faces.shape, -1, dtype=np.int64)
    if doubled.any():
        owners = np.concatenate([np.broadcast_to(b[3][:, None], b[0].shape) for b in blocks])
        vertices, vconfig, sheet = _add_midpoints(faces, doubled, owners, midpoint, vertices, vconfig, sheet)
    idx = index_dtype(len(vertices))
    return QuadMesh(vertices=vertices, faces=faces.astype(idx), edge_midpoint=midpoint.astype(idx),
                    face_normals=np.concatenate([b[2] for b in blocks]), config=vconfig, sheet=sheet,
                    connectivity=connectivity, pinched=pinched)


def _axis_faces(padded: np.ndarray, cfg: np.ndarray, first: np.ndarray, i: int, sign: int, connectivity: int):
    """The faces with normal ``sign * e_i``: their corner ids (outward
    order), which of their edges are doubled, their normals and the padded
    index of the voxel that owns them for edge pairing; None where there
    are none."""
    j, k = (i + 1) % 3, (i + 2) % 3
    lo = padded[tuple(slice(None, -1) if a == i else slice(1, -1) for a in range(3))]
    hi = padded[tuple(slice(1, None) if a == i else slice(1, -1) for a in range(3))]
    flat = np.flatnonzero(lo > hi if sign > 0 else hi > lo)  # faster than np.nonzero on 3D masks
    if len(flat) == 0:
        return None
    base = list(np.unravel_index(flat, lo.shape))
    cfg_flat = cfg.ravel()
    sheets = sheet_lut(connectivity)
    doubled_spoke = doubled_spoke_lut(connectivity)
    # Along i the index is the plane's lattice coordinate (the padded index
    # of the voxel below it); along j, k the face spans [q, q+1] with q the
    # unpadded voxel index.
    ids, cfgs = [], []
    for dj, dk in _CORNER_D:
        c: list[Any] = [0, 0, 0]
        c[i], c[j], c[k] = base[i], base[j] + (1 - dj), base[k] + (1 - dk)
        lin = np.ravel_multi_index(c, cfg.shape)
        cf = cfg_flat[lin]
        ids.append(first[lin] + sheets[cf, 4 * i + dj + 2 * dk])
        cfgs.append(cf)
    # Edge t -> t+1 runs along j or k; it is doubled when the spoke is
    # doubled at both ends (leaving corner t on side 1 when d goes 1 -> 0,
    # i.e. the coordinate grows).
    dbl = []
    for t in range(4):
        (dj0, dk0), (dj1, dk1) = _CORNER_D[t], _CORNER_D[(t + 1) % 4]
        axis = j if dj0 != dj1 else k
        side = 1 if (dj0 + dk0) > (dj1 + dk1) else 0
        dbl.append(doubled_spoke[cfgs[t], axis, side] & doubled_spoke[cfgs[(t + 1) % 4], axis, 1 - side])
    block, dblock = np.stack(ids, axis=1), np.stack(dbl, axis=1)
    if sign < 0:
        block, dblock = block[:, ::-1], dblock[:, [2, 1, 0, 3]]
    normals = np.zeros((len(block), 3), np.int8)
    normals[:, i] = sign
    # the voxel that owns the face for edge pairing: the object voxel under
    # 6-connectivity, the background voxel under 26 (padded linear index)
    own = [base[0] + 1, base[1] + 1, base[2] + 1]
    own[i] = base[i] + (1 if (sign > 0) == (connectivity == 26) else 0)
    return block.astype(np.int64), dblock, normals, np.ravel_multi_index(own, padded.shape)


def _lattice_vertices(cfg: np.ndarray, nsheet: np.ndarray, first: np.ndarray):
    """Positions, configurations and sheet numbers of the lattice vertices'
    sheets, in lattice order."""
    on = np.flatnonzero(nsheet)
    counts = nsheet[on]
    lin = np.repeat(on, counts)
    sheet = (np.arange(len(lin)) - np.repeat(first[on], counts)).astype(np.int8)
    vertices = np.stack(np.unravel_index(lin, cfg.shape), axis=1).astype(np.float64)
    return vertices, cfg.ravel()[lin], sheet


def _add_midpoints(faces, doubled, owners, midpoint, vertices, vconfig, sheet):
    """One midpoint per (doubled edge, owning voxel): the two faces of one
    pair share their owner, the two pairs have different owners. Fills
    ``midpoint`` and returns the vertex arrays with the midpoints after."""
    a, b = faces[doubled], np.roll(faces, -1, axis=1)[doubled]
    key = np.stack([np.minimum(a, b), np.maximum(a, b), owners[doubled]], axis=1)
    pairs, pair_id = np.unique(key, axis=0, return_inverse=True)
    midpoint[doubled] = len(vertices) + pair_id.ravel()
    mid_xyz = (vertices[pairs[:, 0]] + vertices[pairs[:, 1]]) / 2
    return (np.concatenate([vertices, mid_xyz]), np.concatenate([vconfig, np.zeros(len(pairs), np.uint8)]),
            np.concatenate([sheet, np.full(len(pairs), -1, np.int8)]))
