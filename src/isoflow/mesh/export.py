"""Writing the boundary mesh: PLY, OBJ, STL and GLB (docs/formats.md, "Surface files").

The writers take plain arrays (vertex columns, faces padded with -1) so that
any polygon mesh can be written; :func:`mesh_vertex_table` makes the columns
of a boundary quad mesh (:class:`isoflow.digital.surface.QuadMesh`) and
:func:`write_mesh_file` picks, per format, what the file holds so that every
reader opens it as the closed, oriented 2-manifold isoflow counts:

========================  =========================================  =======================================
format                    faces                                      per vertex
========================  =========================================  =======================================
PLY, binary (default)     quads; triangles for the whole file when   position, config, class, gamma, a, f,
                          the surface has doubled edges (trimesh's   red/green/blue
                          binary reader needs faces of one size)
PLY ``--ascii``, OBJ      quads, and polygons starting at a midpoint  PLY: as binary; OBJ: position
                          where an edge is doubled (readers fan them)
STL (binary)              triangles, no shared vertices              none (a normal per triangle)
GLB                       triangles, shared vertices                 position, COLOR_0 (linear), _config,
                                                                     _class, _gamma, _a, _f
========================  =========================================  =======================================

``triangulate`` writes triangles in every format. Every file goes through
:func:`isoflow.mesh.outputs.atomic_write`: written whole or not at all.

Positions are where the voxels are, to a millionth of a voxel, whatever the
units (a mesh in units of 1e-200, map coordinates of 4e6 with a pitch of
0.1): PLY stores them as float32 where that holds them so (the usual case:
smaller files) and as double otherwise; OBJ prints as many digits as they
need (9 at least); GLB, whose positions are float32 by its spec, then stores
them in voxel units with the voxel size and the origin as its node's
transform (float64 in the JSON), which trimesh applies when it makes one
mesh and pymeshlab keeps apart until ``apply_matrix_freeze``
(docs/formats.md, "Surface files"). Binary STL holds float32 only, and no
shared vertices (readers weld equal positions): it is written wherever
float32 keeps the surface's distinct positions distinct, so that the weld
gives back the same closed surface, and refused (nothing written) only
where float32 would merge some, with the numbers; :func:`~isoflow.mesh.float32.float32_effect`
says how far float32 moves the positions.

Positions are in the volume's own world frame (RAS for NIfTI, a NRRD's
``space``); where that frame is RAS or LPS the file's header says so as 3D
Slicer writes and reads it (:func:`space_tag`: ``SPACE=RAS`` in a PLY
comment, an OBJ comment, the STL header), since Slicer reads an untagged
mesh as LPS. GLB has no such convention.
"""

from __future__ import annotations

import contextlib
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..digital.float64 import beyond_axes_reasons, lost_axes_reasons, placement_words
from ..digital.lattice import DigitalObject
from ..errors import IsoflowError, check_switch, given_text, warn
from .float32 import float32_effect, float64_corners, float64_moved
from .outputs import atomic_write, check_output_path, output_set

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..digital.label_meshes import Batch
    from ..digital.surface import QuadMesh

#: a position is held exactly enough when it is off by at most this many voxels
POSITION_TOLERANCE = 1e-6

#: the surface formats ``isoflow surface`` writes, by suffix
SURFACE_SUFFIXES = (".ply", ".obj", ".stl", ".glb")

#: what a writer holds beyond a binary PLY's, which
#: :func:`isoflow.digital.surface.mesh_memory` counts (measured, rounded
#: up: docs/surface.md, "Memory: the check before meshing"): per face of
#: the mesh, an ASCII PLY's rows as float64 tables and an OBJ's lines; an
#: STL's records are made by trimesh, whose imports it loads
WRITE_BYTES_PER_FACE = {"ascii": 100, ".obj": 60}
WRITE_BYTES_STL = 72 << 20


def write_memory(faces: int, suffix: str, ascii: bool = False) -> int:
    """Estimated bytes that writing a mesh of ``faces`` faces as ``suffix``
    holds beyond a binary PLY's (what ``mesh_memory`` counts).

    Parameters
    ----------
    faces : int
        The mesh's faces (squares, before any triangulation).
    suffix : str
        The file's suffix.
    ascii : bool
        An ASCII PLY.

    Returns
    -------
    int

    Examples
    --------
    >>> write_memory(1000, ".ply"), write_memory(1000, ".ply", ascii=True), write_memory(1000, ".obj")
    (0, 100000, 60000)
    """
    suffix = suffix.lower()
    if suffix == ".stl":
        return WRITE_BYTES_STL
    key = "ascii" if ascii and suffix == ".ply" else suffix
    return faces * WRITE_BYTES_PER_FACE.get(key, 0)


def gamma_colours(gamma: np.ndarray, vertex_class: np.ndarray) -> np.ndarray:
    """RGB (uint8) of the vertex angle gamma (-4..4 eighths): blue for concave,
    white for flat, red for convex, linear in between; green marks vertices
    that are not well-composed, grey the midpoints of doubled edges."""
    palette = _gamma_palette()
    rgb = palette[np.clip(np.asarray(gamma, np.int64), -4, 4) + 4]  # a gather, not float math per vertex
    rgb[vertex_class == -1] = (20, 170, 60)
    rgb[vertex_class == -2] = (150, 150, 150)
    return rgb


def _gamma_palette() -> np.ndarray:
    """Colour of gamma = -4 .. 4: blue - white - red, linear in between."""
    t = np.arange(-4, 5) / 4.0
    white = np.array([255.0, 255.0, 255.0])
    red = np.array([200.0, 30.0, 30.0])
    blue = np.array([30.0, 60.0, 200.0])
    pos = np.clip(t, 0, 1)[:, None]
    neg = np.clip(-t, 0, 1)[:, None]
    return np.round(white * (1 - pos - neg) + red * pos + blue * neg).astype(np.uint8)


def float32_holds(xyz: np.ndarray, spacing) -> bool:
    """Whether float32 holds the positions ``xyz`` to
    :data:`POSITION_TOLERANCE` voxels (of size ``spacing`` per axis)."""
    return bool(float32_held(xyz, spacing).all())


def float32_held(xyz: np.ndarray, spacing, stored: np.ndarray | None = None) -> np.ndarray:
    """Per coordinate of ``xyz``, whether float32 holds it to
    :data:`POSITION_TOLERANCE` voxels (of size ``spacing`` per axis);
    ``stored``: the float32 cast of ``xyz`` where the caller has made it
    (the one a file keeps), else it is made here."""
    xyz = np.asarray(xyz, np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        error = np.abs((xyz.astype(np.float32) if stored is None else stored).astype(np.float64) - xyz)
    return np.asarray(error <= POSITION_TOLERANCE * np.asarray(spacing, np.float64))


def stl_refusal(path, effect: dict, spacing) -> str:
    """Why a binary STL cannot hold the surface, with the numbers."""
    if not effect["finite"]:
        return (f"{path}: binary STL holds float32 positions, and this surface's coordinates (up to "
                f"{effect['largest']:.3g}) exceed float32's range ({float(np.finfo(np.float32).max):.3g}); "
                "write .ply, .obj or .glb, which keep them")
    return (f"{path}: binary STL holds float32 positions, which would merge {effect['merged']} of this "
            f"surface's {effect['positions']} distinct corner positions into others (voxel size "
            f"{float(np.min(spacing)):.3g}, coordinates up to {effect['largest']:.3g}, where float32 positions "
            f"are {effect['step']:.3g} apart); write .ply, .obj or .glb, which keep them")


def check_float64_corners(where, origin, spacing, shape, collapses: str = "every surface file") -> dict:
    """Refuse, before anything is written, a surface of a grid placed
    where float64 itself cannot keep its voxel corners apart (a voxel size
    of 1 at an origin of 1e43): every format holds world positions in
    float64 at most, so the surface would collapse onto fewer corners in
    every file, its faces without area and its volume lost; and a grid
    whose corners pass float64's largest value (voxels of 1e306 from
    1.75e308), which every file would hold as inf.

    Parameters
    ----------
    where : str or os.PathLike
        The input (or the file), as the line names it.
    origin, spacing, shape
        The grid's placement and voxels per axis, as
        :func:`~isoflow.mesh.float32.float64_corners` takes them.
    collapses : str
        What would collapse there, as the line names it (a 2D flow's
        files have no surface).

    Returns
    -------
    dict
        :func:`~isoflow.mesh.float32.float64_corners` of the grid, with its
        ``origin`` and ``spacing``, for :func:`float64_move_note` where the
        corners are kept apart.

    Raises
    ------
    IsoflowError
        One line naming the origin, the voxel size and, for every axis
        float64 cannot keep apart, float64's spacing at that axis'
        coordinates (``np.spacing``), or for every axis past float64's
        largest value, its farthest corner.

    Examples
    --------
    >>> check_float64_corners("far.npz", (1e43, 0, 0), (1.0, 1.0, 1.0), (2, 2, 2))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: far.npz: the voxel corners are not distinct in float64 at this placement (origin
    (1e+43, 0, 0), voxel size (1, 1, 1)): near 1e+43 float64 values are 1.24e+27 apart (np.spacing), ...
    >>> check_float64_corners("near.npz", (0, 0, 0), (1.0, 1.0, 1.0), (2, 2, 2))["merged"]
    False
    """
    beyond = beyond_axes_reasons(origin, spacing, shape)
    if beyond:  # float64 makes those corners inf: no format holds them
        raise IsoflowError(
            f"{where}: the voxel corners are past float64 at this placement ({placement_words(origin, spacing)}): "
            f"{beyond}; so {collapses} would hold inf there; place the object nearer the origin (subtract its "
            "origin)")
    corners = {**float64_corners(origin, spacing, shape), "origin": origin, "spacing": spacing}
    if corners["merged"]:
        raise IsoflowError(
            f"{where}: the voxel corners are not distinct in float64 at this placement "
            f"({placement_words(origin, spacing)}): {lost_axes_reasons(origin, spacing, shape)}; so {collapses} "
            "would collapse; place the object nearer the origin (subtract its origin)")
    return corners


def float64_move_note(where, corners: dict, moved: str | None = None) -> str | None:
    """How far float64 itself moves the corners of a surface placed far
    from the origin against its voxel size (``corners``:
    :func:`check_float64_corners`), or None where
    :func:`~isoflow.mesh.float32.float64_moved` finds it too small to say.
    ``moved``: what the move shifts, where that is not a surface file's
    positions (the world coordinates a command prints).

    Examples
    --------
    >>> corners = check_float64_corners("s.ply", (1e6, 0, 0), (1e-9,) * 3, (2, 2, 2))
    >>> print(float64_move_note("s.ply", corners))  # doctest: +ELLIPSIS
    s.ply: float64 holds the voxel corners of this placement (origin (1e+06, 0, 0), voxel size (1e-09, 1e-09, 1e-09))
    only to its spacing near 1e+06, 1.16e-10 (np.spacing): every format's positions move by up to 0.12 voxels ...
    >>> float64_move_note("s.ply", check_float64_corners("s.ply", (0, 0, 0), (1.0,) * 3, (2, 2, 2))) is None
    True
    >>> print(float64_move_note("far.npz", corners, "the boxes printed"))  # doctest: +ELLIPSIS
    far.npz: float64 holds ... (np.spacing): the boxes printed move by up to 0.12 voxels along axis 0; place ...
    """
    if not float64_moved(corners):
        return None
    by = f"by up to {corners['moved_voxels']:.2g} voxels along axis {corners['axis']}"
    said = (f"every format's positions move {by}, and the read-back compares the volume within that" if moved is None
            else f"{moved} move {by}")
    return (f"{where}: float64 holds the voxel corners of this placement "
            f"({placement_words(corners['origin'], corners['spacing'])}) only to its spacing near "
            f"{corners['near']:.3g}, {corners['step']:.3g} (np.spacing): {said}; place the object nearer the origin "
            "(subtract its origin) to keep them")


def mesh_vertex_table(mesh, obj: DigitalObject, position=None) -> dict[str, np.ndarray]:
    """Per-vertex columns written to PLY: position (world; float32 where it
    holds them, see the module docs, or the type ``position``), curvature
    data."""
    xyz = obj.world(mesh.vertices)
    if position is None:
        position = np.float32 if float32_holds(xyz, obj.spacing) else np.float64
    return vertex_columns(mesh, xyz, position)


def vertex_columns(mesh, xyz: np.ndarray, position) -> dict[str, np.ndarray]:
    """The columns of :func:`mesh_vertex_table` from the vertices' world
    positions ``xyz``, stored as ``position``."""
    return {"x": xyz[:, 0].astype(position), "y": xyz[:, 1].astype(position), "z": xyz[:, 2].astype(position),
            **curvature_columns(mesh)}


def curvature_columns(mesh) -> dict[str, np.ndarray]:
    """The per-vertex columns of :func:`mesh_vertex_table` after the
    position: configuration, class, gamma, a, f and the colour of gamma
    (:func:`gamma_colours`)."""
    cls = mesh.vertex_class
    rgb = gamma_colours(mesh.gamma, cls)
    return {
        "config": mesh.config.astype(np.uint8),
        "class": cls.astype(np.int8),
        "gamma": mesh.gamma.astype(np.int8),
        "a": mesh.a.astype(np.int8),
        "f": mesh.f.astype(np.int8),
        "red": rgb[:, 0],
        "green": rgb[:, 1],
        "blue": rgb[:, 2],
    }


_PLY_TYPES = {"f4": "float", "u1": "uchar", "i1": "char", "i4": "int", "f8": "double"}


def _size_groups(faces: np.ndarray):
    """Faces padded with -1, grouped by their number of vertices."""
    faces = np.asarray(faces, dtype=np.int64)
    if faces.size and faces.min() >= 0:  # no padding (triangles, quads): one group, as it is, not copied
        yield faces.shape[1], faces
        return
    sizes = (faces >= 0).sum(axis=1) if faces.size else np.zeros(0, np.int64)
    for size in np.unique(sizes):
        rows = faces[sizes == size]
        # -1 slots can sit between vertices (a missing midpoint): drop them
        # keeping the cyclic order. A boolean mask reads row by row, and
        # every row of the group keeps exactly `size` slots.
        yield int(size), rows[rows >= 0].reshape(len(rows), size)


def write_ply(
    path: str | os.PathLike,
    columns: dict[str, np.ndarray],
    faces: np.ndarray,
    *,
    ascii: bool = False,
    force: bool = False,
    comments: tuple[str, ...] = (),
    sync: bool = True,
) -> Path:
    """Write a PLY with per-vertex scalar columns and polygon faces.

    ``faces`` is (F, K) with -1 padding for faces with fewer than K vertices;
    faces are written grouped by size, each in its row's cyclic order.
    Binary little-endian by default; a binary PLY takes faces of one size
    only (trimesh's binary reader cannot read a mixed list), so mixed sizes
    raise ``ValueError``: triangulate them first. ``sync``: see
    :func:`isoflow.mesh.outputs.atomic_path`.
    """
    path = check_output_path(path, force)
    names = list(columns)
    n = len(columns[names[0]])
    groups = list(_size_groups(faces))
    if not ascii and len(groups) > 1:
        raise ValueError(f"{path}: a binary PLY needs faces of one size, got sizes {[k for k, _ in groups]}")
    header = ply_header({k: columns[k].dtype for k in names}, n, sum(len(g) for _, g in groups), comments, ascii)
    with atomic_write(path, sync=sync) as fh:
        fh.write(header)
        if ascii:
            fmt = " ".join(f"%.{_digits(columns[k])}g" if columns[k].dtype.kind == "f" else "%d" for k in names)
            if n:
                table = np.column_stack([columns[k].astype(np.float64) for k in names])
                write_rows(fh, table, fmt + "\n", binary=True)
            for size, rows in groups:
                write_rows(fh, np.column_stack([np.full(len(rows), size), rows]), " ".join(["%d"] * (size + 1)) + "\n",
                           binary=True)
        else:
            vrec = np.empty(n, dtype=[(k, columns[k].dtype.newbyteorder("<")) for k in names])
            for k in names:
                vrec[k] = columns[k]
            fh.write(vrec.tobytes())
            for size, rows in groups:
                rec = np.empty(len(rows), dtype=[("n", "u1"), ("i", "<i4", (size,))])
                rec["n"] = size
                rec["i"] = rows
                fh.write(rec.tobytes())
    return path


def ply_header(dtypes: dict, vertices: int, faces: int, comments: tuple[str, ...] = (), ascii: bool = False) -> bytes:
    """The header of a PLY with per-vertex scalar columns of the given
    types and a face list (uchar count, int indices)."""
    header = ["ply", f"format {'ascii' if ascii else 'binary_little_endian'} 1.0"]
    # a PLY header is ASCII, a line each: an input named "grün.npy" (or with a line break) in a comment
    # raised UnicodeEncodeError, a traceback, so its other characters are written as escapes
    header += ["comment " + " ".join(c.split()).encode("ascii", "backslashreplace").decode("ascii") for c in comments]
    header.append(f"element vertex {vertices}")
    header += [f"property {_PLY_TYPES[np.dtype(t).str[1:]]} {k}" for k, t in dtypes.items()]
    header += [f"element face {faces}", "property list uchar int vertex_indices", "end_header"]
    return ("\n".join(header) + "\n").encode("ascii")


def _digits(values: np.ndarray, step: float | None = None) -> int:
    """Significant digits that print ``values`` to a step of ``step`` (the
    smallest voxel size times :data:`POSITION_TOLERANCE`; None: the values'
    own precision, 9 for float32 and 17 for double): 9 at least, 17 at most."""
    values = np.asarray(values)
    if step is None:
        return 9 if values.dtype == np.float32 else 17
    largest = float(np.max(np.abs(values))) if values.size else 0.0
    if not largest > step > 0 or not np.isfinite(largest):
        return 9
    return int(np.clip(np.ceil(np.log10(largest / step)) + 1, 9, 17))


def write_obj(
    path: str | os.PathLike,
    vertices: np.ndarray,
    faces: np.ndarray,
    *,
    force: bool = False,
    comments: tuple[str, ...] = (),
    sync: bool = True,
    spacing=None,
) -> Path:
    """Write an OBJ with polygon faces (quads stay quads); ``faces`` as in
    :func:`write_ply`, each row in its cyclic order. ``spacing``: the voxel
    size, so that positions are printed with the digits that keep them to
    :data:`POSITION_TOLERANCE` voxels (17, round-trip, without it)."""
    path = check_output_path(path, force)
    step = None if spacing is None else POSITION_TOLERANCE * float(np.min(spacing))
    d = _digits(vertices, step)
    with atomic_write(path, "w", sync=sync) as fh:
        for c in comments:
            # a comment is one line: an input named with a line break left its rest a line of no OBJ keyword
            fh.write(f"# {' '.join(c.split())}\n")
        write_rows(fh, np.asarray(vertices, np.float64).reshape(-1, 3), f"v %.{d}g %.{d}g %.{d}g\n")
        for size, rows in _size_groups(faces):
            write_rows(fh, rows + 1, "f" + " %d" * size + "\n")
    return path


#: rows of a text table formatted at once by :func:`write_rows`
ROWS_AT_ONCE = 1 << 16


def write_rows(fh, rows: np.ndarray, line: str, *, binary: bool = False) -> None:
    r"""Write the rows of a 2D table as text, each by ``line`` (its ``%``
    fields, one per column, and the newline at its end), byte for byte as
    ``np.savetxt(fh, rows, fmt=line[:-1])`` writes them. :data:`ROWS_AT_ONCE`
    rows are one ``%`` of the line repeated over their values: savetxt
    formats and writes a row at a time, a Python call for each.

    Parameters
    ----------
    fh : file
        Open for writing: text, or ``binary`` (written as ASCII).
    rows : numpy.ndarray
        (N, K), K the fields of ``line``.
    line : str
        The format of one row, ending in a newline.
    binary : bool
        Whether ``fh`` takes bytes.

    Examples
    --------
    >>> import io
    >>> out = io.StringIO()
    >>> write_rows(out, np.array([[1, 2, 3], [4, 5, 6]]), "f %d %d %d\n")
    >>> out.getvalue()
    'f 1 2 3\nf 4 5 6\n'
    """
    for at in range(0, len(rows), ROWS_AT_ONCE):
        part = rows[at:at + ROWS_AT_ONCE]
        text = (line * len(part)) % tuple(part.ravel().tolist())
        fh.write(text.encode("ascii") if binary else text)


def write_stl(path: str | os.PathLike, vertices: np.ndarray, triangles: np.ndarray, *, force: bool = False,
              sync: bool = True, header: str = "") -> Path:
    """Write a binary STL: one record per triangle with its normal and three
    corner positions; STL keeps no shared vertices.

    The records are those of trimesh's exporter (``trimesh.exchange.stl``),
    made :data:`STL_BATCH_TRIANGLES` triangles at a time; the 80-byte
    header holds ``header`` (ASCII, cut at 80 bytes, padded with spaces;
    zero bytes where it is empty, as trimesh writes it).

    Parameters
    ----------
    path : str or os.PathLike
        The file, written atomically.
    vertices : numpy.ndarray
        (V, 3) positions.
    triangles : numpy.ndarray
        (T, 3) vertex rows.
    force : bool
        Replace an existing file.
    sync : bool
        ``fsync`` the file before it is renamed into place.
    header : str
        What the header says: ``isoflow surface`` writes what it wrote and
        at which connectivity, which ``isoflow genus`` reads back.

    Returns
    -------
    pathlib.Path
        The file.

    Examples
    --------
    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp()) / "t.stl"
    >>> write_stl(out, np.eye(3), np.array([[0, 1, 2]]), header="a triangle").stat().st_size
    134
    >>> out.read_bytes()[:12]
    b'a triangle  '
    """
    import trimesh

    path = check_output_path(path, force)
    vertices = np.asarray(vertices, np.float64)
    with atomic_write(path, sync=sync) as fh:
        # trimesh's exporter makes the float64 corners, normals and records of every triangle it is given at
        # once; its header (80 zero bytes and the count) and its records are written here a batch at a time,
        # each record by trimesh's arithmetic (its face normals: zero where a triangle has none)
        # a header starting "solid" would read as ASCII STL to some readers
        text = header.encode("ascii", "replace")[:80].ljust(80, b" ") if header and not header.startswith("solid") \
            else bytes(80)
        fh.write(text + np.array(len(triangles), "<u4").tobytes())
        for start in range(0, len(triangles), STL_BATCH_TRIANGLES):
            corners = vertices[triangles[start:start + STL_BATCH_TRIANGLES]]
            with np.errstate(over="ignore"):  # said below, in one line
                normals, valid = trimesh.triangles.normals(corners)
                rec = np.zeros(len(corners), STL_DTYPE)
                rec["normal"][valid] = normals
                rec["v"] = corners
            fh.write(rec.tobytes())
    return path


#: triangles whose records :func:`write_stl` makes at a time: their
#: float64 corners, cross products and normals and their records hold
#: about 300 bytes each, so a batch holds a few MiB
STL_BATCH_TRIANGLES = 8192
#: a binary STL triangle record
STL_DTYPE = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def write_glb(
    path: str | os.PathLike,
    columns: dict[str, np.ndarray],
    triangles: np.ndarray,
    *,
    force: bool = False,
    comment: str = "",
    sync: bool = True,
    frame=None,
    name: str | None = None,
) -> Path:
    """Write a binary glTF (:mod:`isoflow.mesh.gltf`): triangles on shared
    vertices, the ``red/green/blue`` columns as the vertex colours
    (``COLOR_0``, linear: :func:`linear_bytes`) and the other columns but
    the position as custom vertex attributes (``_config``, ``_class``,
    ...). ``frame``: ``(positions,
    transform)``, positions in the file's float32 with the 4x4 transform
    that puts them in place as the node's matrix (where float32 cannot
    hold the world positions; see the module docs). ``name`` names the
    node and its mesh, which Blender and viewers' scene trees show as the
    object's name (None: the file's stem)."""
    name = Path(path).stem if name is None else name
    return write_glb_scene(path, [(name, columns, triangles, frame)], force=force, comment=comment, sync=sync)


def write_glb_scene(path: str | os.PathLike, parts: list, *, force: bool = False, comment: str = "",
                    sync: bool = True) -> Path:
    """Write several meshes into one binary glTF, each its own node:
    ``parts`` holds ``(name, columns, triangles, frame)`` as
    :func:`write_glb` takes them (a name of None: ``geometry_<i>``), in
    the layout of :mod:`isoflow.mesh.gltf`."""
    from .gltf import SceneParts

    meshes = []
    for t, (name, columns, triangles, frame) in enumerate(parts):
        xyz = np.column_stack([columns["x"], columns["y"], columns["z"]])
        meshes.append({"name": f"geometry_{t}" if name is None else name,
                       "positions": xyz if frame is None else frame[0], "triangles": triangles,
                       "colors": _rgba(columns), "attributes": _glb_attributes(columns),
                       "matrix": None if frame is None else frame[1]})
    return write_glb_sets(path, [SceneParts.of_meshes(meshes)], force=force, comment=comment, sync=sync)


def write_glb_sets(path: str | os.PathLike, sets: list, order: np.ndarray | None = None, *, force: bool = False,
                   comment: str = "", sync: bool = True) -> Path:
    """Write the parts of ``sets`` (:class:`isoflow.mesh.gltf.SceneParts`,
    as :func:`batch_glb_parts` gives them) into one binary glTF, a node
    each, node ``t`` showing part ``order[t]`` of all the sets' parts in
    turn (:func:`isoflow.mesh.gltf.scene_chunks`)."""
    from .gltf import scene_chunks

    path = check_output_path(path, force)
    chunks = scene_chunks(sets, order, comment)
    with atomic_write(path, sync=sync) as fh:
        for chunk in chunks:
            fh.write(chunk)
    return path


def linear_bytes(srgb: ArrayLike) -> np.ndarray:
    """sRGB colour bytes (as PLY holds them and its readers show them) as
    the linear bytes of glTF's ``COLOR_0``, which the specification makes
    a linear multiplier and which Blender's importer and web viewers turn
    back to sRGB for display (IEC 61966-2-1's curve; 8 bits lose up to 2
    of 255 in the darkest channels once turned back).

    Parameters
    ----------
    srgb : array_like of uint8
        Colour channels, any shape.

    Returns
    -------
    numpy.ndarray
        uint8, the same shape.

    Examples
    --------
    >>> linear_bytes(np.array([0, 30, 128, 200, 255], np.uint8)).tolist()
    [0, 3, 55, 147, 255]
    """
    return _LINEAR[np.asarray(srgb, np.uint8)]  # a gather, not float math per vertex


def _linear_table() -> np.ndarray:
    """The linear byte of each sRGB byte (IEC 61966-2-1)."""
    c = np.arange(256) / 255.0
    linear = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    return np.round(255.0 * linear).astype(np.uint8)


_LINEAR = _linear_table()


def _rgba(columns: dict) -> np.ndarray:
    """The vertex colours of ``columns`` as glTF's ``COLOR_0`` (linear,
    :func:`linear_bytes`; opaque)."""
    rgb = linear_bytes(np.column_stack([columns["red"], columns["green"], columns["blue"]]))
    return np.column_stack([rgb, np.full(len(rgb), 255, np.uint8)])


def _glb_attributes(columns: dict) -> dict:
    """The columns a glTF keeps as custom vertex attributes: all but the
    position and the colour, each under ``_`` and its name."""
    return {f"_{k}": v for k, v in columns.items() if k not in ("x", "y", "z", "red", "green", "blue")}


def float32_transform_problem(spacing: ArrayLike, shape: tuple, origin: ArrayLike) -> str | None:
    """What of a grid of ``shape`` voxels of size ``spacing`` from
    ``origin`` a GLB node's transform (:func:`grid_transform`) cannot hold
    in float32 (None where it can hold all of it). trimesh reads the
    transform in float64, but Blender's matrices, web viewers' and the
    Khronos validator's are float32 (the validator finds a matrix past
    float32 not decomposable to translation, rotation and scale): a voxel
    size that float32 makes 0 or infinite, or a corner past its range,
    leaves the node nowhere there.

    Parameters
    ----------
    spacing, shape, origin : array_like
        The voxel size per axis, the grid's shape and its lowest corner.

    Returns
    -------
    str or None
        The value beyond float32's range in words, or None.

    Examples
    --------
    >>> float32_transform_problem((0.1,) * 3, (4, 4, 4), (4e6, 0.0, 0.0)) is None
    True
    >>> float32_transform_problem((1e150,) * 3, (4, 4, 4), (0.0,) * 3)
    'a voxel size of 1e+150 is beyond float32 (magnitudes 1.4e-45 to 3.4e+38)'
    """
    spacing = np.broadcast_to(np.asarray(spacing, np.float64), (3,))
    corners = np.asarray(origin, np.float64) + np.array([np.zeros(3), spacing * np.asarray(shape)])
    with np.errstate(over="ignore", under="ignore"):
        size32, corners32 = spacing.astype(np.float32), corners.astype(np.float32)
    lost_size, lost_corner = ~np.isfinite(size32) | (size32 == 0), ~np.isfinite(corners32)
    if not lost_size.any() and not lost_corner.any():
        return None
    what = (f"a voxel size of {spacing[lost_size][0]:.3g}" if lost_size.any() else
            f"a corner at {corners[lost_corner][0]:.3g}")
    return (f"{what} is beyond float32 (magnitudes {float(np.finfo(np.float32).smallest_subnormal):.2g} to "
            f"{float(np.finfo(np.float32).max):.2g})")


def glb_part(name: str, mesh, obj: DigitalObject) -> tuple:
    """One boundary mesh as a part of :func:`write_glb_scene`: triangles
    in world coordinates, with the curvature columns (in voxel units under
    the node's transform where float32 cannot hold the world positions)."""
    table, frame = glb_columns(mesh, obj)
    return name, table, mesh.triangles(), frame


def glb_columns(mesh, obj: DigitalObject) -> tuple[dict[str, np.ndarray], tuple | None]:
    """A mesh's vertex columns for a glTF and its frame: None where float32
    holds the world positions, else :func:`grid_frame` (positions in voxel
    units under the node's transform)."""
    table = mesh_vertex_table(mesh, obj)
    return table, None if table["x"].dtype == np.float32 else grid_frame(mesh, obj)


def batch_glb_parts(batch: Batch, names: list[str], offsets: np.ndarray, spacing, origin,
                    label_names: list[str] | None = None):
    """The glTF parts (:class:`isoflow.mesh.gltf.SceneParts`) of every box
    of a batch of :func:`isoflow.digital.label_meshes.label_batches`
    (``names`` and ``offsets``, the boxes' first voxels, per label index),
    in the batch's order: for each part what :func:`glb_part` gives for it
    and its box, computed once over the batch. A part whose world
    positions float32 cannot hold stores voxel units under its node's
    transform (:func:`grid_frame`). ``label_names``, per label index, go
    into the nodes' ``extras`` as ``name`` (none where empty)."""
    from ..digital.surface import triangle_rows
    from .gltf import SceneParts

    mesh = batch.joined()
    parts = len(batch.rows)
    spacing, origin = np.asarray(spacing, np.float64), np.asarray(origin, np.float64)
    corner = np.asarray(offsets, np.float64)[batch.rows]
    of_vertex = np.repeat(np.arange(parts), np.diff(batch.vfirst))
    xyz = origin + spacing * (np.asarray(mesh.vertices, float) + corner[of_vertex])  # as DigitalObject.world
    # a part past float32's range casts to inf here, and is framed below:
    # its positions replaced by voxel units, not a NumPy warning on the terminal
    with np.errstate(over="ignore"):
        positions = xyz.astype(np.float32)
    held = float32_held(xyz, spacing, positions).all(axis=1)
    holds = np.logical_and.reduceat(held, batch.vfirst[:-1]) if len(xyz) else np.ones(parts, bool)
    table = curvature_columns(mesh)
    framed = np.flatnonzero(~holds)
    if len(framed):
        in_frame = ~holds[of_vertex]
        positions[in_frame] = mesh.vertices[in_frame]
    triangles, face = triangle_rows(mesh.faces, mesh.edge_midpoint)
    of_face = np.repeat(np.arange(parts), np.diff(batch.ffirst))[face]
    if len(of_face) and not (of_face[1:] >= of_face[:-1]).all():  # the fans of faces with midpoints come last
        order = np.argsort(of_face, kind="stable")  # a part's triangles in the order of its own triangle_rows
        triangles, of_face = triangles[order], of_face[order]
    return SceneParts(names=[names[t] for t in batch.rows], positions=positions, colors=_rgba(table),
                      attributes=_glb_attributes(table), vfirst=np.asarray(batch.vfirst, np.int64),
                      triangles=triangles, tfirst=np.searchsorted(of_face, np.arange(parts + 1)),
                      matrices={int(s): grid_transform(spacing, origin + spacing * corner[s]) for s in framed},
                      extras={s: {"name": label_names[t]} for s, t in enumerate(batch.rows)
                              if label_names is not None and label_names[t]})


def surface_faces(mesh, suffix: str, *, ascii: bool = False, triangulate: bool = False) -> tuple[str, np.ndarray]:
    """What a surface file of this suffix holds: ``("quads" | "polygons" |
    "triangles", faces)`` (see the table in this module's docstring)."""
    if triangulate or suffix in (".stl", ".glb") or (suffix == ".ply" and not ascii and mesh.midpoints):
        return "triangles", mesh.triangles()
    return ("polygons" if mesh.midpoints else "quads"), mesh.polygons()


def write_mesh_file(
    path: str | os.PathLike,
    mesh,
    obj: DigitalObject,
    *,
    ascii: bool = False,
    triangulate: bool = False,
    force: bool = False,
    comments: tuple[str, ...] = (),
    sync: bool = True,
    name: str | None = None,
) -> dict:
    """Write a boundary mesh in the format its suffix names (PLY, OBJ, STL,
    GLB), in world coordinates; ``name`` names a GLB's node (None: the
    file's stem, :func:`write_glb`). Returns what was written: ``path``,
    ``faces`` (the kind) and ``face_count``; for STL also ``moved`` and
    ``moved_voxels``, how far float32 moved the positions
    (:func:`~isoflow.mesh.float32.float32_effect`). Raises IsoflowError, writing nothing, for an
    STL in which float32 would merge distinct positions. ``sync=False`` leaves the
    ``fsync`` to the caller (:func:`isoflow.mesh.outputs.sync_file`);
    :func:`write_surface` is the public call."""
    path = check_output_path(path, force, suffixes=SURFACE_SUFFIXES, what="surface")
    suffix = path.suffix.lower()
    kind, faces = surface_faces(mesh, suffix, ascii=ascii, triangulate=triangulate)
    comments = (*comments, f"faces: {kind}")
    tag = space_tag(obj.space)
    tagged = (*comments, tag) if tag else comments  # the frame where 3D Slicer reads it (STL: in its header)
    if suffix == ".ply":
        write_ply(path, mesh_vertex_table(mesh, obj), faces, ascii=ascii, force=force, comments=tagged, sync=sync)
    elif suffix == ".obj":
        # an OBJ holds positions alone: no comment names the PLY's columns in it
        write_obj(path, obj.world(mesh.vertices), faces, force=force, sync=sync, spacing=obj.spacing,
                  comments=tuple(c for c in tagged if c != VERTEX_COMMENT))
    elif suffix == ".stl":
        xyz = obj.world(mesh.vertices)
        effect = float32_effect(xyz, obj.spacing)
        if effect["merged"] != 0:  # a reader's weld would not give the surface back: nothing written
            raise IsoflowError(stl_refusal(path, effect, obj.spacing))
        write_stl(path, xyz, faces, force=force, sync=sync, header=stl_header(comments[0], obj.space))
        return {"path": path, "faces": kind, "face_count": len(faces), "moved": effect["moved"],
                "moved_voxels": effect["moved_voxels"]}
    else:
        table, frame = glb_columns(mesh, obj)
        # glTF has no frame tag that 3D Slicer reads: the comment is isoflow's, untagged
        write_glb(path, table, faces, force=force, comment="; ".join(comments), sync=sync, frame=frame, name=name)
        beyond = float32_transform_problem(obj.spacing, obj.volume.shape, obj.world(np.zeros((1, 3)))[0])
        return {"path": path, "faces": kind, "face_count": len(faces), "framed": frame is not None,
                "beyond": beyond}
    return {"path": path, "faces": kind, "face_count": len(faces)}


#: the anatomical frames 3D Slicer reads from a mesh file's header (its
#: ``vtkMRMLModelStorageNode``); a mesh without one it reads as LPS
SLICER_SPACES = ("RAS", "LPS")


def space_tag(space: str | None) -> str | None:
    """The text that tells 3D Slicer a mesh file's frame: ``SPACE=RAS`` or
    ``SPACE=LPS``, as Slicer writes it, found anywhere in an STL's header,
    a PLY comment or an OBJ's leading comments. Slicer reads a file without
    it as LPS, so a surface of a NIfTI (RAS) without it opens mirrored in
    x and y.

    Parameters
    ----------
    space : str or None
        The object's anatomical frame (:attr:`DigitalObject.space`).

    Returns
    -------
    str or None
        The tag; None for no frame or one Slicer has no tag for (``"LAS"``).

    Examples
    --------
    >>> space_tag("RAS"), space_tag("LPS"), space_tag("LAS"), space_tag(None)
    ('SPACE=RAS', 'SPACE=LPS', None, None)
    """
    return f"SPACE={space}" if space in SLICER_SPACES else None


def stl_header(text: str, space: str | None = None) -> str:
    """A binary STL's 80-byte header text: ``text`` with the frame's
    :func:`space_tag` after it, ``text`` cut short where both do not fit
    (the tag is what a reader acts on; no reader makes anything else of
    the header). Where ``text`` records a connectivity (``..., 26-connectivity``),
    the cut is made before it, in the name, marked ``...``: ``isoflow genus``
    reads the file at the connectivity the header records.

    Parameters
    ----------
    text : str
        What the header says (ASCII; other characters are written as ``?``).
    space : str or None
        The object's anatomical frame.

    Returns
    -------
    str
        At most 80 ASCII characters.

    Examples
    --------
    >>> stl_header("isoflow surface of s.nii.gz, 6-connectivity", "RAS")
    'isoflow surface of s.nii.gz, 6-connectivity SPACE=RAS'
    >>> len(stl_header("x" * 100, "LPS")), stl_header("x" * 100, "LPS")[-10:]
    (80, ' SPACE=LPS')
    >>> stl_header("a triangle", "LAS")
    'a triangle'
    >>> stl_header(f"isoflow surface of {'n' * 80}.npy, 26-connectivity", "RAS")[-38:]
    'nnnnnnnn..., 26-connectivity SPACE=RAS'
    """
    text = text.encode("ascii", "replace").decode("ascii")
    tag = space_tag(space)
    room = 80 if tag is None else 80 - len(tag) - 1
    if len(text) > room:
        kept = CONNECTIVITY_RECORD.search(text)
        head = room - 3 - (len(text) - kept.start()) if kept else 0
        text = f"{text[:head]}...{text[kept.start():]}" if head > 0 else text[:room]
    if tag is None:
        return text
    return f"{text} {tag}" if text else tag


#: where a header records the connectivity the mesh was made at (what the
#: name before it may be cut to keep, :func:`stl_header`)
CONNECTIVITY_RECORD = re.compile(r", (?:6|26)-connectivity\b")


#: an STL's float32 positions are said to move the surface when they move a
#: corner by more than this many voxels (below it, nothing a user can see)
STL_NOTE_VOXELS = 1e-3

#: the header comment of PLY and OBJ that says what the per-vertex columns are
VERTEX_COMMENT = ("per-vertex: config byte, class (gamma+4; -1 not well-composed; -2 edge midpoint), "
                  "gamma (eighths, eq. 4.6), a (eq. 4.10), f (eq. 4.8)")


def stl_move_note(out: str | os.PathLike, written: dict) -> str:
    """How far an STL's float32 positions moved the surface."""
    return (f"{out}: STL stores float32 positions, which move the corners by up to {written['moved']:.3g} "
            f"({written['moved_voxels']:.2g} voxels); .ply, .obj and .glb keep them exactly")


def glb_transform_note(where: str | os.PathLike, framed: int = 1, of: int = 1, kind: str = "node",
                       beyond: str | None = None, instead: str = ".ply or .obj") -> str:
    """Where a GLB's positions read as voxel units: ``framed`` of the
    ``of`` nodes of a scene (or of the ``of`` files of a directory,
    ``kind="file"``) store them under the node's transform
    (:func:`grid_frame`), which MeshLab keeps apart from the vertices
    (docs/formats.md, "Surface files").

    Parameters
    ----------
    where : str or os.PathLike
        The file, or the directory of a file per label.
    framed, of : int
        The nodes (files) with a transform, of how many.
    kind : {"node", "file"}
        What ``of`` counts.
    beyond : str, optional
        What of the transform float32 cannot hold
        (:func:`float32_transform_problem`): the note then says which
        readers cannot place the file, and to write ``instead``.
    instead : str
        What keeps the positions for those readers.

    Returns
    -------
    str
        The note in one line.

    Examples
    --------
    >>> note = glb_transform_note("far.glb")
    >>> note.split(",")[0]
    'far.glb: float32 cannot hold its world positions to a millionth of a voxel'
    >>> "Apply to all visible Layers" in glb_transform_note("seg.glb", 3, 4)
    True
    """
    if of == 1:
        head = "float32 cannot hold its world positions to a millionth of a voxel, so the GLB stores"
    else:
        which = f"all {of}" if framed == of else f"{framed} of the {of}"
        head = f"float32 cannot hold the world positions of {which} {kind}s to a millionth of a voxel, so they store"
    every = kind == "node" and of > 1  # MeshLab freezes the current layer alone unless told otherwise
    return (f"{where}: {head} voxel units with the voxel size and origin as {'each' if of > 1 else 'its'} node's "
            f"transform: trimesh (force=\"mesh\") {'applies' if beyond else 'and Blender apply'} it; MeshLab keeps it "
            "apart (its measures and saved files in voxel units) until Filters > Normals, Curvatures and "
            "Orientation > Matrix: Freeze "
            f"Current Matrix{' with Apply to all visible Layers' if every else ''} "
            f"(pymeshlab: apply_matrix_freeze{'(alllayers=True)' if every else ''})"
            + (f"; Blender, web viewers and the Khronos validator hold the transform in float32, and {beyond}: "
               f"for them write {instead}, which keep the positions" if beyond else ""))


def stl_weld_note(out: Path, welded: int) -> str:
    """What a reader's weld of an STL does to the split copies at contacts."""
    return (f"{out}: STL keeps no shared vertices, so readers weld the split copies at {welded} edge/vertex "
            "contacts into non-manifold points; PLY, OBJ or GLB keep them apart")


def write_surface(
    obj: DigitalObject | ArrayLike,
    path: str | os.PathLike,
    connectivity: int | np.integer | None = None,
    *,
    mesh: QuadMesh | None = None,
    ascii: bool = False,
    triangulate: bool = False,
    force: bool = False,
    check: bool = True,
) -> Path:
    """Write the boundary mesh of a 3D object as the file ``isoflow surface``
    writes: PLY, OBJ, STL or GLB by the suffix, in world coordinates, and
    read it back, as the command does.

    The file holds the closed, outward-oriented boundary (docs/formats.md,
    "Surface files"): binary PLY with the per-vertex curvature columns
    ``config``, ``class``, ``gamma``, ``a``, ``f`` and colours; OBJ with
    positions; binary STL (triangles, no shared vertices); GLB (triangles,
    ``COLOR_0`` and the attributes ``_config`` ... ``_f``, in one node
    named after the file, less its suffix). It is written
    beside the target and renamed when complete, so an interrupted write
    leaves any previous file as it was.

    Parameters
    ----------
    obj : DigitalObject or array_like
        The object, placed by its pitch and origin (a bare 3D binary array
        is taken at the origin with voxels of size 1).
    path : str or os.PathLike
        The file: ``.ply``, ``.obj``, ``.stl`` or ``.glb`` (any case).
    connectivity : {6, 26}, optional
        The object's connectivity (6 if None; with ``mesh``, the mesh's).
    mesh : QuadMesh, optional
        ``boundary_mesh(obj.volume, connectivity)`` where it is already
        built, so that it is not built again; refused where it does not fit
        the object's array, has another connectivity, or is not this
        object's boundary (its face count, or the configuration of a vertex,
        differs from the object's).
    ascii : bool
        ASCII PLY instead of binary (``.ply`` only).
    triangulate : bool
        Triangles in every format (two per plain quad).
    force : bool
        Replace an existing file (True or False only: ``"no"`` is refused).
    check : bool
        Read the file back with trimesh before it replaces ``path``, as
        ``isoflow surface`` does (without ``--no-check``): its
        watertightness, Euler number, genus and volume must be isoflow's
        (the volume alone for an STL whose weld joins split copies). A
        read-back that would not fit in memory is skipped with a warning.

    Returns
    -------
    pathlib.Path
        The file written, which trimesh, pymeshlab and MeshLab open.

    Raises
    ------
    IsoflowError
        Before anything is written: an existing file without ``force``, a
        suffix other than the four, ``ascii`` with another format, an
        object that is not 3D or is empty, a mesh of another object or
        connectivity, a binary STL whose float32 positions would merge
        distinct corners (the message says by how much), an object placed
        where float64 itself cannot keep its voxel corners apart (a voxel
        size of 1 at 1e43: the line names float64's spacing there). With
        ``check``, a
        file that trimesh reads back otherwise, naming it and what differs:
        nothing is replaced.

    Warns
    -----
    IsoflowWarning
        An STL whose float32 positions move a corner by more than a
        thousandth of a voxel, or whose readers weld the split copies at
        edge and vertex contacts into non-manifold points; a file of any
        format whose corners float64 moves by more than a thousandth of a
        voxel (a voxel size of 1e-9 at 1e6); a read-back skipped for
        memory.

    See Also
    --------
    boundary_mesh : the mesh in memory, in array-corner units.
    write_volume : the object itself as a volume file.

    Examples
    --------
    A box of 2 x 3 x 4 voxels of 0.5 placed at (1, 2, 3), read back by
    trimesh: 54 corners, 52 quads (104 triangles), closed, volume 24 / 8:

    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> import trimesh
    >>> from isoflow import DigitalObject
    >>> obj = DigitalObject(np.ones((2, 3, 4), bool), pitch=0.5, origin=(1.0, 2.0, 3.0))
    >>> path = write_surface(obj, pathlib.Path(tempfile.mkdtemp()) / "box.ply")
    >>> m = trimesh.load(path, process=False)
    >>> len(m.vertices), len(m.faces), bool(m.is_watertight), float(m.volume), m.bounds.tolist()
    (54, 104, True, 3.0, [[1.0, 2.0, 3.0], [2.0, 3.5, 5.0]])

    The curvature columns: the ``a`` of the corners sums to 8 chi (the
    digital Gauss-Bonnet theorem; a box's chi is 1):

    >>> int(m.metadata["_ply_raw"]["vertex"]["data"]["a"].sum())
    8
    """
    from ..digital.connectivity import resolve_connectivity
    from ..digital.surface import boundary_mesh

    path = check_output_path(path, force, suffixes=SURFACE_SUFFIXES, what="surface")
    suffix = path.suffix.lower()
    ascii, triangulate = check_switch(ascii, "ascii", str(path)), check_switch(triangulate, "triangulate", str(path))
    check = check_switch(check, "check", str(path))
    if ascii and suffix != ".ply":
        raise IsoflowError(f"{path}: ascii=True applies to .ply output only")
    # the dimension before the values: "threshold it" is no remedy for a 2D label image
    if getattr(obj, "ndim", 3) == 3:
        # a label table is no surface
        obj = DigitalObject.of(obj, "write_surface", remedy="write_surface({}, path)", remedy_dims=(3,))
    if not isinstance(obj, DigitalObject) or obj.ndim != 3:
        # named by the function, as to_manifold, boundary_mesh and closed_surfaces name theirs: the file is not at fault
        raise IsoflowError(f"write_surface needs a 3D object, got {getattr(obj, 'ndim', 0)}D")
    if mesh is None:
        if obj.voxels == 0:
            raise IsoflowError(f"{path}: the object is empty, there is no surface to write")
        mesh = boundary_mesh(obj.volume, resolve_connectivity(3, connectivity))
    else:
        check_mesh_fits(path, mesh, obj, connectivity)
    corners = check_float64_corners(path, obj.origin, obj.spacing, obj.volume.shape)
    comments = (f"isoflow write_surface, {mesh.connectivity}-connectivity", VERTEX_COMMENT)
    welded = shared_positions(mesh) if suffix == ".stl" else 0
    # the file is put in place only once it reads back as isoflow counts it
    with output_set(path) if check else contextlib.nullcontext():
        written = write_mesh_file(path, mesh, obj, ascii=ascii, triangulate=triangulate, force=force,
                                  comments=comments)
        if check:
            read_back(path, mesh, obj, welded)
    if suffix == ".stl":
        if written["moved_voxels"] > STL_NOTE_VOXELS:
            warn(stl_move_note(path, written))
        if welded:
            warn(stl_weld_note(path, welded))
    moved = float64_move_note(path, corners)
    if moved:
        warn(moved)
    return path


def read_back(path: Path, mesh: QuadMesh, obj: DigitalObject, welded: int) -> None:
    """The file just written read back by trimesh
    (:func:`~isoflow.mesh.readback.check_surface_file`), refused in one line
    where it disagrees with isoflow's counts; the volume alone where an
    STL's weld joins ``welded`` split copies, as ``isoflow surface`` does."""
    from .readback import check_surface_file

    found = check_surface_file(path, mesh, obj, topology=not welded, components=mesh.components())
    if found.get("skipped"):
        warn(f"{path}: not read back ({found['skipped']})")
    elif not found["agree"]:
        raise IsoflowError(found["problem"])


def check_mesh_fits(path: Path, mesh: QuadMesh, obj: DigitalObject, connectivity: int | None) -> None:
    """Refuse, in one line, a mesh given to :func:`write_surface` that is not
    a boundary mesh of the object's array: another type, another
    connectivity, no faces, vertices outside the array's box, or the
    boundary of another object (another face count, or a corner whose
    configuration is not the object's there)."""
    from ..digital.configurations import configuration_histogram, configurations_at
    from ..digital.surface import QuadMesh, boundary_faces

    if not isinstance(mesh, QuadMesh):
        raise IsoflowError(f"{path}: mesh= takes the QuadMesh of boundary_mesh(obj.volume), got "
                           f"{type(mesh).__name__}")
    if connectivity is not None and connectivity != mesh.connectivity:
        raise IsoflowError(f"{path}: the mesh is {mesh.connectivity}-connected, connectivity={given_text(connectivity)} "
                           "was asked")
    if len(mesh.faces) == 0:
        raise IsoflowError(f"{path}: the mesh is empty, there is no surface to write")
    shape = np.asarray(obj.volume.shape)
    if np.any(mesh.vertices.min(axis=0) < 0) or np.any(mesh.vertices.max(axis=0) > shape):
        raise IsoflowError(f"{path}: the mesh reaches {mesh.vertices.max(axis=0).tolist()}, outside the object's "
                           f"array of shape {shape.tolist()} (array-corner units): pass the object it was built "
                           "from")
    # a mesh of another object inside the same box: the object's face count
    # (from its configuration histogram, without meshing it) and the
    # configuration at each of the mesh's corners. Equal, every face of the
    # mesh is a face of the object's boundary, and there are as many.
    faces = boundary_faces(configuration_histogram(obj.volume))
    if len(mesh.faces) != faces:
        raise IsoflowError(f"{path}: the mesh has {len(mesh.faces):,} faces, the object's boundary {faces:,}: "
                           "pass the mesh of this object")
    corner = mesh.sheet >= 0  # the midpoints of doubled edges are no lattice vertices
    at = np.asarray(mesh.vertices[corner], np.int64)
    differ = np.flatnonzero(configurations_at(obj.volume, at) != mesh.config[corner])
    if len(differ):
        w = at[differ[0]]
        raise IsoflowError(f"{path}: the mesh's corner {w.tolist()} (array-corner units) has configuration "
                           f"{int(mesh.config[corner][differ[0]])}, the object's there is "
                           f"{int(configurations_at(obj.volume, w[None])[0])} ({len(differ):,} corners differ): "
                           "pass the mesh of this object")


def grid_frame(mesh, obj: DigitalObject) -> tuple[np.ndarray, np.ndarray]:
    """The mesh's vertices in array-corner units (multiples of 1/2: exact
    in float32) and the 4x4 affine map that :meth:`DigitalObject.world`
    applies to them (a diagonal of voxel sizes, a translation)."""
    return np.asarray(mesh.vertices, np.float64), grid_transform(obj.spacing, obj.world(np.zeros((1, 3)))[0])


def grid_transform(spacing, corner) -> np.ndarray:
    """The 4x4 affine map from array-corner units to the world: a diagonal
    of voxel sizes ``spacing``, a translation to the array corner's world
    position ``corner``."""
    transform = np.eye(4)
    transform[:3, :3] = np.diag(spacing)
    transform[:3, 3] = corner
    return transform


def shared_positions(mesh) -> int:
    """Positions that carry more than one mesh vertex: the split copies at
    edge and vertex contacts and the two midpoints of a doubled edge. A
    format without shared vertices (STL) cannot keep them apart: readers
    weld them by position."""
    if len(mesh.vertices) == 0:
        return 0
    # lattice points and edge midpoints are multiples of 1/2: exact keys,
    # one integer each where their box's cells can be numbered in int64
    # (a sort of numbers, not of rows)
    keys = np.round(2 * mesh.vertices).astype(np.int64)
    lo = keys.min(axis=0)
    span = keys.max(axis=0) - lo + 1
    if float(np.prod(span.astype(np.float64))) >= 2.0**62:
        _, counts = np.unique(keys, axis=0, return_counts=True)
        return int(np.count_nonzero(counts > 1))
    flat = np.sort(np.ravel_multi_index(tuple((keys - lo).T), tuple(int(n) for n in span)))
    again = flat[1:] == flat[:-1]
    # a position held twice or more: where a run of equal keys starts repeating
    return int(np.count_nonzero(again & np.concatenate([[True], ~again[:-1]])))
