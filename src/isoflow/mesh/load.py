"""Reading triangle meshes, and the edge census that says whether they bound
a solid.

``load_mesh`` reads any format trimesh reads and welds vertices that differ
only by rounding noise; ``mesh_defects`` counts boundary, non-manifold and
inconsistently oriented edges from the vertex indices alone.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import IsoflowError, MeshNote, counted, given_text, missing, refuse_empty_path, warn
from ..scale.arrays import as_array, refuse_masked

#: Default relative tolerance (times the bounding-box diagonal) below which two
#: vertex positions are welded by :func:`load_mesh`.
MERGE_RTOL = 1e-10

#: File name endings read as meshes: every mesh and scene format trimesh
#: reads, and its archives (a test checks this against
#: ``trimesh.available_formats()``; ``.xyz`` is a point list here).
MESH_SUFFIXES = (".stl", ".stl_ascii", ".obj", ".ply", ".off", ".glb", ".gltf", ".3mf", ".dae", ".zae",
                 ".3dxml", ".xaml", ".zip", ".tar.gz", ".tar.bz2", ".bz2", ".step", ".stp")
#: CAD (boundary representation) formats: surfaces, no triangles until a CAD kernel tessellates them
CAD_SUFFIXES = (".step", ".stp", ".iges", ".igs", ".brep", ".sat", ".x_t", ".x_b", ".sldprt", ".sldasm", ".ipt",
                ".iam", ".catpart", ".catproduct", ".prt", ".f3d", ".3dm", ".jt")
#: of them, those trimesh tessellates where cascadio (OpenCASCADE) is installed (not in isoflow's extras)
CASCADIO_SUFFIXES = (".step", ".stp")
#: Formats whose reader needs an optional library: ``isoflow[formats]``.
FORMAT_NEEDS = {".3mf": ("lxml",), ".dae": ("collada",), ".zae": ("collada",),
                ".3dxml": ("lxml",), ".xaml": ("lxml",)}
_PACKAGE = {"lxml": "lxml", "collada": "pycollada"}


def is_mesh_path(path) -> bool:
    """Whether a file name ends in one of :data:`MESH_SUFFIXES` (any case)."""
    name = Path(os.fspath(path)).name.lower()
    return any(name.endswith(s) for s in MESH_SUFFIXES)


def check_format_libraries(path: Path) -> None:
    """One clear line naming the extra when a format's reader is missing."""
    import importlib.util

    suffix = path.suffix.lower()
    missing = [m for m in FORMAT_NEEDS.get(suffix, ()) if importlib.util.find_spec(m) is None]
    if missing:
        names = " and ".join(_PACKAGE[m] for m in missing)
        raise IsoflowError(
            f"{path}: reading {suffix.lstrip('.').upper()} files needs {names}: "
            "pip install 'isoflow[formats]'")


def refuse_cad(path) -> None:
    """One line for a CAD file (:data:`CAD_SUFFIXES`), which holds surfaces
    and no triangles: trimesh's reader of a STEP file raises
    "ModuleNotFoundError: No module named 'cascadio'", and the point-list
    reader "not a number: 'ISO-10303-21;'". A STEP file passes where
    cascadio is installed (trimesh then tessellates it).

    Parameters
    ----------
    path : str or os.PathLike
        An input, by its name.

    Raises
    ------
    IsoflowError
        A CAD file that cannot be read as a mesh here.

    Examples
    --------
    >>> refuse_cad("part.igs")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: part.igs: a CAD file (IGS: surfaces, not triangles); export it ... as STL, OBJ, PLY or GLB
    """
    import importlib.util

    suffix = Path(os.fspath(path)).suffix.lower()
    if suffix not in CAD_SUFFIXES:
        return
    if suffix in CASCADIO_SUFFIXES:
        if importlib.util.find_spec("cascadio") is not None:
            return
        how = " (or pip install cascadio, with which trimesh tessellates STEP files)"
    else:
        how = ""
    raise IsoflowError(f"{path}: a CAD file ({suffix.lstrip('.').upper()}: surfaces, not triangles); export it from "
                       f"the CAD tool as STL, OBJ, PLY or GLB{how}")


def column_bounds(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The least and the greatest value of each column of ``points``: what
    ``points.min(axis=0)`` and ``points.max(axis=0)`` give.

    NumPy reduces a C-ordered ``(n, 3)`` array along its first axis three
    values at a time; a column at a time it takes its vector loop.

    Parameters
    ----------
    points : numpy.ndarray
        ``(n, k)`` numbers, ``n > 0``.

    Returns
    -------
    lo, hi : numpy.ndarray
        ``(k,)`` each, of the points' dtype (NaN where a column holds one).

    Examples
    --------
    >>> lo, hi = column_bounds(np.array([[0.0, 5.0, -1.0], [2.0, 3.0, -4.0]]))
    >>> lo.tolist(), hi.tolist()
    ([0.0, 3.0, -4.0], [2.0, 5.0, -1.0])
    """
    p = np.asarray(points)
    return (np.array([p[:, c].min() for c in range(p.shape[1])], dtype=p.dtype),
            np.array([p[:, c].max() for c in range(p.shape[1])], dtype=p.dtype))


def used_vertices(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The vertices the faces use, in their order (as ``v[np.unique(f)]``
    gives them, by a mask rather than a sort); ``v`` itself where every
    vertex is used.

    Parameters
    ----------
    v : numpy.ndarray
        ``(n, 3)`` vertices.
    f : numpy.ndarray
        Faces, indices into ``v``.

    Returns
    -------
    numpy.ndarray
        The rows of ``v`` that ``f`` names.

    Examples
    --------
    >>> used_vertices(np.array([[0.0, 0, 0], [9, 9, 9], [1, 0, 0], [0, 1, 0]]), np.array([[3, 0, 2]])).tolist()
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    mark = np.zeros(len(v), dtype=bool)
    mark[f.reshape(-1)] = True
    return v if mark.all() else v[mark]


def mesh_bbox(v: np.ndarray, f: np.ndarray, where: str):
    """Lower corner, upper corner and extent of the vertices the faces use;
    IsoflowError if the extent overflows to infinity."""
    lo, hi = column_bounds(used_vertices(v, f))
    with np.errstate(over="ignore"):
        ext = hi - lo
    if not np.all(np.isfinite(ext)):
        a = int(np.argmin(np.isfinite(ext)))
        raise IsoflowError(
            f"{where}: coordinates too large: the bounding box's {'xyz'[a]} extent "
            f"from {lo[a]:.6g} to {hi[a]:.6g} overflows the floating-point range "
            "(rescale the mesh)")
    return lo, hi, ext


# ---------------------------------------------------------------------------
# input checking
# ---------------------------------------------------------------------------

def check_mesh(vertices, faces, where: str = "mesh") -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles as float64 (N, 3) and int64 (M, 3) arrays
    (copies or views), or IsoflowError naming ``where`` and what is wrong:
    shapes, an empty mesh, non-integer faces, NaN or infinite coordinates,
    out-of-range indices."""
    refuse_masked(vertices, f"{where}: vertices")  # the faces are checked by as_array
    try:
        v = np.asarray(vertices)
    except (TypeError, ValueError) as exc:
        raise IsoflowError(f"{where}: vertices are not a numeric array ({exc})") from None
    if v.dtype.kind not in "biufc":
        # refused as the volume functions refuse them (isoflow.scale.arrays.binary): a cast to float64
        # would read Python objects or strings ("1e3") as numbers, whatever they hold
        raise IsoflowError(f"{where}: vertices: array of type {v.dtype} is not an array of coordinates")
    if v.dtype.kind == "c":  # a cast to float64 drops the imaginary part with NumPy's ComplexWarning alone
        raise IsoflowError(f"{where}: vertices must be real coordinates, got complex numbers ({v.dtype})")
    v = v.astype(np.float64, copy=False)
    if v.ndim != 2 or v.shape[1] != 3:
        raise IsoflowError(f"{where}: vertices must have shape (N, 3), got {v.shape}")
    f = as_array(faces, f"{where}: faces")
    if f.ndim != 2 or f.shape[1] != 3:
        raise IsoflowError(f"{where}: faces must have shape (M, 3) (triangles), got {f.shape}")
    if f.shape[0] == 0:
        raise IsoflowError(f"{where}: empty mesh (no faces)")
    if f.dtype.kind not in "iu":
        if f.dtype.kind == "f" and np.all(np.isfinite(f)) and np.all(f == np.round(f)):
            pass
        else:
            raise IsoflowError(f"{where}: faces must be integer vertex indices, got dtype {f.dtype}")
    bad = ~np.isfinite(v)
    if bad.any():
        nv = int(bad.any(axis=1).sum())
        # the position, not an index: a reader may number the vertices otherwise than the file lists them
        first = v[np.flatnonzero(bad.any(axis=1))[0]]
        raise IsoflowError(
            f"{where}: {nv} of {counted(len(v), 'vertex', 'vertices')} {'has' if nv == 1 else 'have'} NaN or "
            f"infinite coordinates ({counted(int(bad.sum()), 'value')}; {'the first ' if nv > 1 else ''}at "
            f"({', '.join(f'{x:.6g}' for x in first.tolist())}))")
    # checked in the faces' own type: int64 wraps a uint64 index from 2**63 on (and a float one
    # beyond int64) to a negative number, which the message then named instead of the index given
    lo, hi = int(f.min()), int(f.max())
    if lo < 0 or hi >= len(v):
        nbad = int(((f < 0) | (f >= len(v))).sum())
        worst = lo if lo < 0 else hi
        raise IsoflowError(
            f"{where}: {nbad} face indices out of range [0, {len(v)}) (e.g. {worst})")
    return v, f.astype(np.int64, copy=False)


# ---------------------------------------------------------------------------
# loading
# ---------------------------------------------------------------------------

def weld_groups(v: np.ndarray, f: np.ndarray, rtol: float = MERGE_RTOL, where: str = "mesh",
                stats: dict | None = None, among: np.ndarray | None = None, sort: bool = True) -> np.ndarray:
    """Each vertex's group in :func:`weld`: vertices closer than ``rtol``
    times the bounding box's diagonal (of the vertices ``f`` uses), in a
    chain, share one group number.

    Parameters
    ----------
    v : numpy.ndarray
        ``(n, 3)`` vertex positions.
    f : numpy.ndarray
        ``(m, 3)`` triangles (their vertices give the bounding box).
    rtol : float
        The distance, as a share of the diagonal.
    where : str
        The mesh's name in an error.
    stats : dict, optional
        Receives ``welded``, as :func:`weld` says.
    among : numpy.ndarray, optional
        The indices of the vertices to merge; the others are merged only
        with copies at the same position. All of them when not given.
    sort : bool
        Find the equal positions by sorting them (:func:`distinct_rows`),
        or, False, as :func:`unsorted_rows` finds them (by hashing, for a
        caller to whom the groups' numbers say nothing: the same groups,
        numbered otherwise).

    Returns
    -------
    numpy.ndarray
        ``(n,)`` int64 group numbers (equal positions always share one).

    Examples
    --------
    >>> v = np.array([[0, 0, 0], [1, 0, 0], [1 + 1e-9, 0, 0], [0, 1, 0]])
    >>> g = weld_groups(v, np.array([[0, 1, 3], [0, 2, 3]]), 1e-6)
    >>> bool(g[1] == g[2]), len(set(g.tolist()))
    (True, 3)
    """
    from ..scale.graphs import components  # numba: imported where a mesh is welded
    from .close_pairs import close_pairs

    lo, _, ext = mesh_bbox(v, f, where)  # refuses an extent that overflows
    longest = float(ext.max())
    uniq, inverse = distinct_rows(v) if sort else unsorted_rows(v)
    if rtol > 0 and longest > 0 and len(uniq) > 1:
        # Distances are taken relative to the bounding box's lower corner and
        # in units of a power of two near its longest side (so the tolerance
        # and squared distances neither overflow at 1e200 nor underflow at
        # 1e-200: the weld is scale-invariant).  Positions more than 2**40
        # boxes away (unused vertices only) are far beyond the tolerance
        # (< the diagonal): left out, they get no pairs.
        e = math.frexp(longest)[1]
        with np.errstate(over="ignore", invalid="ignore"):
            w = np.ldexp(uniq - lo, -e)
        tol = rtol * float(np.linalg.norm(np.ldexp(ext, -e)))
        near = np.nonzero(np.all(np.abs(w) <= 2.0**40, axis=1))[0]
        if among is not None:
            near = np.intersect1d(near, inverse[among])
        pairs = close_pairs(w[near], tol, cell=2.0**-20)  # cells far finer than any mesh's spacing
        if len(pairs):
            pairs = near[pairs]
            _, lab = components(len(uniq), pairs[:, 0], pairs[:, 1])
            if stats is not None:
                used = np.unique(inverse[f])
                stats["welded"] = int(len(used) - len(np.unique(lab[used])))
            inverse = lab[inverse]
    return inverse


def weld(v: np.ndarray, f: np.ndarray, rtol: float = MERGE_RTOL, where: str = "mesh",
         stats: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices closer than ``rtol * bbox diagonal``; drop collapsed faces.

    Rounding coordinates to a grid (trimesh's approach) misses pairs that
    straddle a rounding boundary, however close they are; the pairs within
    the distance (:func:`~isoflow.mesh.close_pairs.close_pairs`) plus
    connected components cannot.  Exact copies (an STL's corners) are found
    first, by hashing from :data:`WELD_HASHED_ROWS` rows on
    (:func:`unsorted_rows`).  Faces that lose a corner to the
    weld have zero area: they are removed, and vertices no face uses are
    dropped.  Output vertices keep the order of their first occurrence.
    ``stats`` receives ``welded``: the distinct positions of the faces'
    corners merged into others by the tolerance (not exact duplicates), and
    ``dropped_faces``: faces left with two equal corners (by the weld, or
    as read).
    """
    # the output is numbered by first use, whatever the groups' numbers
    inverse = weld_groups(v, f, rtol, where, stats, sort=False)
    f = inverse[f]
    keep = ~_repeats_a_corner(f)
    f = f[keep]
    if stats is not None:
        stats.setdefault("welded", 0)
        stats["dropped_faces"] = int(len(keep) - np.count_nonzero(keep))
    # compact + order by first use in the original vertex array; the
    # positions the faces use, marked in a bool array (no sort needed)
    positions = inverse.max() + 1
    mark = np.zeros(positions, dtype=bool)
    mark[f] = True
    groups = np.flatnonzero(mark)
    first = np.full(positions, len(v), dtype=np.int64)
    np.minimum.at(first, inverse, np.arange(len(v)))
    order = np.argsort(first[groups], kind="stable")
    remap = np.empty(inverse.max() + 1, dtype=np.int64)
    remap[groups[order]] = np.arange(len(groups))
    return v[first[groups[order]]].copy(), remap[f]


#: rows from which :func:`distinct_rows` finds the copies by hashing
#: (compiled) before it sorts; below, its sort alone answers before numba
#: would have started
HASHED_ROWS = 1 << 20
#: rows from which :func:`unsorted_rows` hashes: a weld runs numba's
#: compiled code anyway (its close pairs), and from here the hash and its
#: load from numba's cache take less than the sort
WELD_HASHED_ROWS = 1 << 14


def distinct_rows(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``points`` (equal values: ``-0.0`` is ``0.0``),
    in increasing order, and each row's number among them: what
    ``np.unique(points, axis=0, return_inverse=True)`` gives.

    ``np.unique`` sorts the rows as records, one comparison of a field
    after another; three stable sorts of plain columns (``np.lexsort``) are
    several times faster on a million rows.

    Parameters
    ----------
    points : ndarray, shape (N, K)
        Rows to compare (floats: NaN is unequal to anything).

    Returns
    -------
    distinct : ndarray, shape (D, K)
        The distinct rows, sorted by the first column, then the second, ...
    inverse : int64 ndarray, shape (N,)
        ``distinct[inverse]`` equals ``points``.

    Examples
    --------
    >>> d, i = distinct_rows(np.array([[1.0, 2.0], [0.0, 5.0], [1.0, 2.0]]))
    >>> d.tolist(), i.tolist()
    ([[0.0, 5.0], [1.0, 2.0]], [1, 0, 1])
    """
    p = np.asarray(points)
    if not len(p):
        return p.copy(), np.zeros(0, np.int64)
    # (compared as float64, which holds every such float and integer exactly)
    exact = (p.dtype.kind == "f" and p.dtype.itemsize <= 8) or (p.dtype.kind in "iu" and p.dtype.itemsize <= 4)
    if len(p) >= HASHED_ROWS and exact:
        # many rows (an STL's corners): each row's first copy by hashing, then
        # only the distinct rows sorted
        from .equal_rows import first_equal

        first = first_equal(p)
        (once,) = np.nonzero(first == np.arange(len(p)))
        distinct, at = _sorted_distinct(p[once])
        slot = np.empty(len(p), np.int64)
        slot[once] = at
        return distinct, slot[first]
    return _sorted_distinct(p)


def unsorted_rows(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``points`` and each row's number among them, as
    :func:`distinct_rows` gives them but in no stated order: from
    :data:`WELD_HASHED_ROWS` float rows on, each row's first copy found by
    hashing and the distinct rows in the order of their first row, with
    no sort (an STL's corners, six copies of each position, about); below,
    or for other numbers, :func:`distinct_rows`.

    Parameters
    ----------
    points : ndarray, shape (N, K)
        Rows to compare (floats: NaN is unequal to anything; ``-0.0`` is
        ``0.0``).

    Returns
    -------
    distinct : ndarray, shape (D, K)
        The distinct rows.
    inverse : int64 ndarray, shape (N,)
        ``distinct[inverse]`` equals ``points``.

    Examples
    --------
    >>> d, i = unsorted_rows(np.array([[1.0, 2.0], [0.0, 5.0], [1.0, 2.0]]))
    >>> bool(np.array_equal(d[i], [[1.0, 2.0], [0.0, 5.0], [1.0, 2.0]])), len(d)
    (True, 2)
    """
    p = np.asarray(points)
    if len(p) < WELD_HASHED_ROWS or p.dtype.kind != "f" or p.dtype.itemsize > 8:
        return distinct_rows(p)
    from .equal_rows import first_equal

    first = first_equal(p)
    (once,) = np.nonzero(first == np.arange(len(p)))
    slot = np.empty(len(p), np.int64)
    slot[once] = np.arange(len(once))
    return p[once], slot[first]


def _sorted_distinct(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`distinct_rows` of a non-empty array by sorting every row."""
    inverse = np.zeros(len(p), np.int64)
    order = np.lexsort(p.T[::-1])
    rows = p[order]
    new = np.r_[True, np.any(rows[1:] != rows[:-1], axis=1)]
    inverse[order] = np.cumsum(new) - 1
    return rows[new], inverse


def load_mesh(path, *, merge_rtol: float = MERGE_RTOL, stats: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Read a triangle mesh and weld vertices that coincide.

    Any format trimesh reads (STL, OBJ, PLY, OFF, GLB, ...) is accepted (OFF
    by :mod:`isoflow.mesh.off`, which takes polygons of any size; plain STL
    and OBJ files by :mod:`isoflow.mesh.readers`, to the same arrays as
    trimesh's, without importing it); the
    file is loaded with ``force="mesh"`` so multi-solid STLs and glTF scenes
    become one mesh (scene transforms applied).  trimesh splits an OBJ's
    vertices at UV / normal seams (``merge_tex``/``merge_norm`` are asked
    for, but an unprocessed load keeps the split), so every file goes
    through a positional weld with
    tolerance ``merge_rtol`` times the bounding-box diagonal: ASCII STLs such as
    ``featuretype.STL`` store shared corners that differ by 1e-16 and are only
    closed after that weld.  Faces collapsed by the weld (zero area) are
    dropped.

    Returns ``(vertices float64 (N, 3), faces int64 (M, 3))``. A dict passed
    as ``stats`` receives ``welded`` (positions merged into others by the
    tolerance) and ``dropped_faces`` (faces with two equal corners,
    dropped), so callers can say what the weld did.

    Raises :class:`IsoflowError` for a missing file, a file trimesh cannot
    read, a mesh without faces (naming the format a file holds where its
    suffix names another: :func:`misnamed_mesh`), NaN/inf coordinates,
    coordinates whose extent overflows, out-of-range faces and a
    ``merge_rtol`` outside [0, 1).
    """
    refuse_empty_path(path, "mesh path")
    p = Path(os.fspath(path))
    rtol = weld_tolerance(merge_rtol)
    refuse_volume(path)
    ext = p.suffix.lower().lstrip(".")
    with reading_mesh(p):  # a failed or empty read: one line, naming the format of a misnamed file
        vertices, faces = _read(p, ext)
        if faces.size == 0 or faces.ndim != 2:
            # trimesh returns an empty mesh rather than failing on many garbage files
            raise IsoflowError((_stl_size_line(p) if ext == "stl" else None) or _point_cloud_line(p, vertices)
                               or f"{p}: no triangles read (empty mesh, or not a valid {ext.upper() or 'mesh'} file)")
    vertices, faces = check_mesh(vertices, faces, where=str(p))
    welded, kept = weld(vertices, faces, rtol, where=str(p), stats=stats)
    if len(kept) == 0:
        raise IsoflowError(why_no_face(vertices, faces, rtol, str(p)))
    return welded, kept


def _point_cloud_line(path: Path, vertices: np.ndarray) -> str | None:
    """The line for a file that holds points and no face (a scan's point
    cloud saved as PLY, OBJ or GLB): what it holds, and that a surface is
    made from it elsewhere; None where it holds no point either."""
    points, lines = _faceless_held(path)
    n = len(np.asarray(vertices).reshape(-1, 3)) if np.size(vertices) else points
    if not n:
        return None
    return wireframe_line(path, n, lines) if lines else point_cloud_line(path, n)


def wireframe_line(where: str | os.PathLike, points: int, lines: int) -> str:
    """The line for a mesh input that holds ``points`` points joined by
    ``lines`` lines (an OBJ's ``l`` elements, a PLY's ``edge`` element: a
    model's wireframe or curves) and no face. Its lines bound no solid, and
    no surface is reconstructed from them as from a scan's point cloud: the
    model's faces are what to export, as for a glTF file of lines.

    Parameters
    ----------
    where : str or os.PathLike
        The file.
    points : int
        The points it holds.
    lines : int
        The lines joining them.

    Returns
    -------
    str

    Examples
    --------
    >>> print(wireframe_line("cage.obj", 8, 12))  # doctest: +ELLIPSIS
    cage.obj: no triangles read: it holds 8 points joined by 12 lines and no faces, a wireframe, not a surface: ...
    """
    return (f"{where}: no triangles read: it holds {counted(points, 'point')} joined by {counted(lines, 'line')} "
            "and no faces, a wireframe, not a surface: its lines bound no solid, and there is nothing to "
            "voxelise; export the model's faces (a mesh of triangles), not its edges or curves")


def _faceless_held(path: Path) -> tuple[int, int]:
    """The points and lines of a file whose reader gave no face: from a
    PLY's header (its ``vertex`` rows where it has no ``face`` rows, its
    ``edge`` rows), an OBJ's ``v`` lines (where it has no ``f`` line) and
    ``l`` lines, read once, as :func:`_faceless_counts` counts them; a
    glTF's point clouds (:func:`_points_held`) and no lines; (0, 0) for
    a file that cannot be read again (the plain "no triangles read" line
    is said then)."""
    kind = path.suffix.lower().lstrip(".")
    if kind not in ("ply", "obj"):
        return _points_held(path), 0
    try:
        with open(path, "rb") as fh:
            # a PLY's counts are in its header: a point cloud of millions of rows is not read again for them
            data = fh.read() if kind == "obj" else fh.read(PLY_HEADER_BYTES)
    except OSError:
        return 0, 0
    return _faceless_counts(data, kind, str(path))


def _lines_in(data: bytes, kind: str, where: str) -> int:
    """The lines of a file's bytes (an OBJ's ``l`` lines, the rows of a
    PLY's ``edge`` element), ``kind`` its format as trimesh names it
    (``obj``, ``ply``): an archive's member too; 0 otherwise."""
    try:
        if kind == "obj":
            # every OBJ trimesh reads is looked at for the note: a byte search
            # first, the line pattern only where a line may begin with l
            if not data.startswith(b"l") and b"\nl" not in data:
                return 0
            return len(re.findall(rb"^l\s", data, flags=re.M))
        if kind == "ply":
            from .ply import header_elements

            parsed = header_elements(data, where)
            return 0 if parsed is None else sum(e.rows for e in parsed[2] if e.name == "edge")
    except IsoflowError:
        return 0
    return 0


def point_cloud_line(where: str | os.PathLike, points: int) -> str:
    """The line for a mesh input that holds ``points`` points and no face.

    Parameters
    ----------
    where : str or os.PathLike
        The file, or an archive's member as ``ARCHIVE:MEMBER``.
    points : int
        The points it holds.

    Returns
    -------
    str

    Examples
    --------
    >>> point_cloud_line("scan.zip:scan.obj", 3)[:68]
    'scan.zip:scan.obj: no triangles read: it holds 3 points and no faces'
    """
    return (f"{where}: no triangles read: it holds {counted(points, 'point')} and no faces, a point cloud, not a "
            "surface; reconstruct a surface from it first (MeshLab's Screened Poisson, Open3D's "
            "create_from_point_cloud_poisson) and give that mesh")


def _points_held(path: Path) -> int:
    """The points of a glTF file whose reader gave no vertex for want of
    faces: its point clouds as trimesh reads its scene; 0 otherwise."""
    if path.suffix.lower() not in (".glb", ".gltf"):
        return 0
    try:
        import trimesh

        scene = trimesh.load(path, force="scene")
        return sum(len(g.vertices) for g in scene.geometry.values() if isinstance(g, trimesh.PointCloud))
    except Exception:  # (the plain "no triangles read" line is said then)
        return 0


def _faceless_counts(data: bytes, kind: str, where: str) -> tuple[int, int]:
    """The points and lines of a PLY's or an OBJ's bytes (``kind`` its
    format as trimesh names it; an archive's member too) that hold no
    face: a PLY's ``vertex`` and ``edge`` rows from one reading of its
    header, an OBJ's ``v`` and ``l`` lines; no points where it has faces
    (``face`` rows, ``f`` lines), (0, 0) for another kind or a header out
    of the grammar."""
    if kind == "ply":
        from .ply import header_elements

        try:
            parsed = header_elements(data, where)
        except IsoflowError:
            return 0, 0
        elements = [] if parsed is None else parsed[2]
        rows = {e.name: e.rows for e in elements}
        return (0 if rows.get("face") else rows.get("vertex", 0)), sum(e.rows for e in elements if e.name == "edge")
    if kind == "obj":
        points = 0 if re.search(rb"^f\s", data, flags=re.M) else len(re.findall(rb"^v\s", data, flags=re.M))
        return points, _lines_in(data, kind, where)
    return 0, 0


def why_no_face(vertices: np.ndarray, faces: np.ndarray, rtol: float, where: str, float32: bool | None = None) -> str:
    """The line for a mesh the weld left without a face (``faces``: as
    read): every face degenerate as read, or faces that had three corners
    until the weld's tolerance (``rtol`` times the bounding box's diagonal)
    merged them, because a face far from the rest stretches the box; or
    every corner at one position as read (a float32 file far from the
    origin, whose spacing there is coarser than the mesh). ``float32``:
    whether the coordinates were given as float32 (an array in memory);
    None for a file's, read as float64, where a position that float32
    holds exactly may have been one.

    Examples
    --------
    >>> v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1e300, 0, 0], [1e300, 1, 0], [1e300, 0, 1]], float)
    >>> why_no_face(v, np.array([[0, 1, 2], [3, 4, 5]]), 1e-10, "m.obj")[-103:]
    'to [1e+300, 1.0, 1.0], and so no face kept three corners (a face far from the others stretches the box)'
    >>> why_no_face(np.full((3, 3), 1e9), np.array([[0, 1, 2]]), 1e-10, "m.ply").split(" (")[1]
    'float32 coordinates are 64 apart there, coarser than a mesh smaller than that); no face has area'
    >>> why_no_face(np.zeros((3, 3)), np.array([[0, 1, 2]]), 1e-10, "mesh", float32=False)
    'mesh: empty mesh: every corner of every face lies at one position, [0.0, 0.0, 0.0]; no face has area'
    """
    if not np.count_nonzero(~_repeats_a_corner(faces)):
        return f"{where}: empty mesh (every face is degenerate)"
    used = used_vertices(vertices, faces)
    if not np.ptp(used, axis=0).any():
        # no box to stretch: the file holds one point, which a float32 file
        # far from the origin makes of any mesh smaller than its spacing there
        at = [float(f"{x:.6g}") for x in used[0]]
        spacing = float(np.spacing(np.float32(np.abs(used[0]).max())))
        # float32's spacing explains a collapse only where the corners may have been float32 and the spacing is
        # a normal number's: at the origin (1.4e-45 apart) the corners are the same point as given
        was32 = np.array_equal(used[0], used[0].astype(np.float32)) if float32 is None else float32
        far = np.abs(used[0]).max() >= np.finfo(np.float32).tiny
        coarse = (f" (float32 coordinates are {spacing:g} apart there, coarser than a mesh smaller than that)"
                  if was32 and far else "")
        return f"{where}: empty mesh: every corner of every face lies at one position, {at}{coarse}; no face has area"
    lo, hi = ([float(f"{x:.3g}") for x in p] for p in (used.min(axis=0), used.max(axis=0)))
    return (f"{where}: empty mesh: the weld makes one point of positions closer than {rtol:g} of the bounding "
            f"box's diagonal, the box runs from {lo} to {hi}, and so no face kept three corners (a face far from "
            "the others stretches the box)")



def _stl_size_line(p: Path) -> str | None:
    """The line for a binary STL whose size does not match its facet count
    (:func:`isoflow.mesh.readers.stl_size_error`), or for an ASCII STL
    whose facets are not three vertices of three numbers each, or that is
    cut short (:func:`isoflow.mesh.readers.stl_text_error`), or None."""
    from .readers import stl_size_error, stl_text_error

    try:
        data = p.read_bytes()
    except OSError:
        return None
    return stl_size_error(p, data) or stl_text_error(p, data)


def weld_tolerance(merge_rtol) -> float:
    """``merge_rtol`` as a float in [0, 1), or IsoflowError: 1 or more would
    weld every vertex of the mesh into one."""
    try:
        rtol = float(merge_rtol)
    except (TypeError, ValueError):
        rtol = math.nan
    if not 0 <= rtol < 1:
        raise IsoflowError(f"load_mesh: merge_rtol must be a number in [0, 1), got {given_text(merge_rtol)}")
    return rtol


#: a mesh given to a function that reads one: a file, a ``(vertices, faces)``
#: pair, or an object with ``vertices`` and ``faces`` (``trimesh.Trimesh``)
MeshInput = str | os.PathLike | tuple | Any


def mesh_input(mesh: MeshInput, *, merge_rtol: float = MERGE_RTOL,
               stats: dict | None = None) -> tuple[str, np.ndarray, np.ndarray]:
    """A mesh file read by :func:`load_mesh`, or a mesh in memory checked
    and welded the same way, with the name its messages give it.

    A mesh built in memory (trimesh splits vertices at UV seams as a file's
    reader does) gets the same weld as a file, so that its topology is the
    surface's, not the vertex list's.

    Parameters
    ----------
    mesh : str, os.PathLike, (vertices, faces) or object with ``vertices`` and ``faces``
        The mesh: a file of any format :func:`load_mesh` reads, or (N, 3)
        positions and (M, 3) vertex indices.
    merge_rtol : float
        Weld tolerance, times the bounding-box diagonal (:func:`load_mesh`).
    stats : dict, optional
        Receives what the weld did (:func:`weld`).

    Returns
    -------
    name : str
        The file's name, or ``"mesh"`` for a mesh in memory.
    vertices : numpy.ndarray
        float64 (N, 3).
    faces : numpy.ndarray
        int64 (M, 3).

    Examples
    --------
    >>> import trimesh
    >>> name, v, f = mesh_input(trimesh.creation.box())
    >>> name, v.shape, f.shape
    ('mesh', (8, 3), (12, 3))
    >>> mesh_input((v, f[:, :2]))
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: mesh: faces must have shape (M, 3) (triangles), got (12, 2)
    """
    if isinstance(mesh, (str, os.PathLike)):
        # the str the path stands for: str() of an os.DirEntry (os.scandir) is a repr
        return os.fsdecode(mesh), *load_mesh(mesh, merge_rtol=merge_rtol, stats=stats)
    vertices, faces = mesh_arrays(mesh, "mesh")
    v, f = check_mesh(vertices, faces, where="mesh")
    rtol = weld_tolerance(merge_rtol)
    welded, kept = weld(v, f, rtol, where="mesh", stats=stats)
    if len(kept) == 0:
        raise IsoflowError(why_no_face(v, f, rtol, "mesh", float32=np.asarray(vertices).dtype == np.float32))
    return "mesh", welded, kept


def is_scene(mesh: object) -> bool:
    """Whether ``mesh`` is a scene of meshes in memory (a ``trimesh.Scene``,
    as ``trimesh.load`` gives for a glTF file): nodes and their geometry."""
    return hasattr(mesh, "graph") and hasattr(mesh, "geometry") and hasattr(mesh, "to_mesh")


def is_manifold(mesh: object) -> bool:
    """Whether ``mesh`` is a ``manifold3d.Manifold``, known by its type's
    name and ``to_mesh`` (as :func:`isoflow.to_manifold` makes one), so
    that manifold3d is not imported to ask."""
    return type(mesh).__name__ == "Manifold" and hasattr(mesh, "to_mesh")


def mesh_arrays(mesh: object, where: str) -> tuple[Any, Any]:
    """The vertices and faces of a mesh in memory, as given (unchecked): a
    ``(vertices, faces)`` pair or an object with ``vertices`` and ``faces``
    (a ``trimesh.Trimesh``), or a ``trimesh.Scene``'s meshes as one, node
    transforms applied, as a scene file is read; IsoflowError naming
    ``where`` otherwise.

    Examples
    --------
    >>> mesh_arrays(([[0, 0, 0]], [[0, 0, 0]]), "mesh 1")
    ([[0, 0, 0]], [[0, 0, 0]])
    >>> mesh_arrays(3, "mesh 2")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: mesh 2: a mesh is a file, a (vertices, faces) pair, a trimesh.Trimesh or a trimesh.Scene, got int

    A ``manifold3d.Manifold`` is named, with what voxelises it and where
    its triangles are:

    >>> import manifold3d
    >>> mesh_arrays(manifold3d.Manifold.cube((1, 1, 1)), "mesh")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: mesh: a manifold3d.Manifold, not a triangle mesh: isoflow.from_manifold(manifold, ...
    """
    if is_scene(mesh):
        mesh = mesh.to_mesh()  # type: ignore[attr-defined]
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):
        return mesh.vertices, mesh.faces
    if isinstance(mesh, (tuple, list)) and len(mesh) == 2:
        return mesh[0], mesh[1]
    if is_manifold(mesh):  # "got Manifold" named neither isoflow's bridge nor the triangles it holds
        raise IsoflowError(f"{where}: a manifold3d.Manifold, not a triangle mesh: isoflow.from_manifold(manifold, "
                           "pitch=P) voxelises it; its triangles are m.vert_properties[:, :3] and m.tri_verts of "
                           "m = manifold.to_mesh()")
    raise IsoflowError(f"{where}: a mesh is a file, a (vertices, faces) pair, a trimesh.Trimesh or a trimesh.Scene, "
                       f"got {type(mesh).__name__}")


def refuse_volume(path) -> None:
    """One line for a volume file given where a mesh is read: trimesh would
    say ``file_type 'npy' not supported`` (or fail inside its binvox
    reader), and ``FILE.h5:/dataset`` would be "no such file or directory"
    while the file is there. A volume file that is not there is said to be
    missing, as every reader says it (a mesh's or a volume's)."""
    from .formats.registry import format_for, split_dataset

    file = split_dataset(path)[0]
    if not is_mesh_path(path) and format_for(file) is not None:
        if not file.exists():
            raise missing(file)
        raise IsoflowError(f"{path}: a volume file, not a triangle mesh; voxelize and genus read meshes "
                           "(isoflow info, surface and flow read volumes)")


def _read(p: Path, ext: str):
    """The vertices and faces of a mesh file as its reader gives them."""
    if ext == "off":  # trimesh's reader fails on polygons of 5+ corners (see isoflow.mesh.off)
        from .off import read_off

        check_mesh_file(p)
        return read_off(p)
    if (simple := _read_simple(p)) is not None:
        if ext == "ply" and simple[1].size:  # (an OBJ of l lines is never read here: trimesh reads it)
            _say_lines_left_out(p, ext)
        return simple
    try:
        if kind := next((k for s, k in ARCHIVE_TYPES.items() if p.name.lower().endswith(s)), None):
            # the merge below would leave a member of no triangle out
            if not sum(1 for _ in mesh_members(p, kind)) and (line := meshless_archive_line(p)) is not None:
                raise IsoflowError(line)  # a valid archive, which trimesh's empty mesh called "not a valid" one
        mesh = trimesh_load(p, "mesh")
    except IsoflowError:
        if ext == "obj":  # trimesh's IndexError on an index past the vertices, its ValueError on a word: the line
            _check_obj_indices(p, failed=True)
            _check_obj_numbers(p)
        if ext == "stl" and (line := _stl_size_line(p)) is not None:  # trimesh's "cannot reshape array"
            raise IsoflowError(line) from None
        raise
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces)
    if ext in ("obj", "ply") and faces.size:  # (of no face, the line refusing a wireframe says them)
        _say_lines_left_out(p, ext)
    if ext == "obj":
        # trimesh leaves out, without a word, a face whose indices name no
        # vertex: where none is left, the first such face is the line
        _check_obj_indices(p, failed=not faces.size)
        if vertices.ndim != 2 or vertices.shape[1] != 3:  # v lines of two numbers: name the first
            _check_obj_numbers(p)
    return vertices, faces


#: a PLY header is looked for in the file's first bytes up to this many
PLY_HEADER_BYTES = 1 << 20


def _say_lines_left_out(p: Path, ext: str) -> None:
    """Name in a :class:`~isoflow.errors.MeshNote` the lines of a mesh file
    read with faces (an OBJ's ``l`` lines, a PLY's ``edge`` element) that
    its reader leaves out without a word, as a glTF file's lines beside
    faces are named (:func:`_lines_left_out`). A PLY's header alone is
    read again, not its body."""
    try:
        with open(p, "rb") as fh:
            data = fh.read() if ext == "obj" else fh.read(PLY_HEADER_BYTES)
    except OSError:
        return
    if (note := _lines_left_out(p, ext, data)) is not None:
        warn(note, MeshNote)


def _lines_left_out(where: str | os.PathLike, kind: str, data: bytes) -> str | None:
    """The note on the lines of an OBJ's or a PLY's bytes (``kind`` as
    trimesh names the format) that a reader of its faces leaves out, in
    the words of a glTF file's
    (:func:`~isoflow.mesh.gltf_extensions.read_without`); None where it
    holds none."""
    lines = _lines_in(data, kind, str(where))
    if not lines:
        return None
    from .gltf_extensions import read_without

    what = f"its {counted(lines, 'line')} (OBJ l lines)" if kind == "obj" else \
        f"its {counted(lines, 'edge')} (the PLY edge element)"
    return read_without(where, what, lines)


def _read_simple(p: Path):
    """A plain STL, OBJ or PLY read with NumPy alone (no trimesh import), or None."""
    from .readers import read_simple

    check_mesh_file(p)
    if p.suffix.lower() != ".ply":
        return read_simple(p)
    from .ply import read_ply

    try:
        data = p.read_bytes()
    except OSError:
        return None  # trimesh's path says what is wrong with the file
    return read_ply(data, where=str(p))


def check_mesh_file(p: Path) -> None:
    """A mesh file that exists, is a regular file, and whose format's
    library is installed, or one line saying which is not."""
    if not p.exists():
        raise missing(p)
    if p.is_dir():  # (a directory given among meshes: `voxelize a.stl . -o out.nii.gz`)
        raise IsoflowError(f"{p}: is a directory, not a mesh file")
    if not p.is_file():
        raise IsoflowError(f"{p}: not a regular file")
    refuse_cad(p)
    if p.stat().st_size == 0:  # a download or copy that failed: trimesh's readers raise IndexError and the like
        raise IsoflowError(empty_file_line(p, p.name))
    refuse_zipped_store(p)
    refuse_empty_members(p)
    check_format_libraries(p)


def empty_file_line(where: str | os.PathLike, name: str) -> str:
    """The line for a mesh file of 0 bytes (``where``: the file, or an
    archive's member as ``ARCHIVE:MEMBER``; ``name``: the file's name,
    whose suffix names the format).

    Examples
    --------
    >>> empty_file_line("parts.zip:lid.stl", "lid.stl")
    'parts.zip:lid.stl: an empty file (0 bytes), not a readable STL file'
    """
    kind = Path(name).suffix.lstrip(".").upper() or "mesh"
    return f"{where}: an empty file (0 bytes), not a readable {kind} file"


#: the archives whose members trimesh reads as meshes, by their suffix, as trimesh names their type
ARCHIVE_TYPES = {".zip": "zip", ".tar.gz": "tar.gz", ".tar.bz2": "tar.bz2"}


def refuse_empty_members(p: Path) -> None:
    """Refuse an archive (:data:`ARCHIVE_TYPES`) that holds a mesh file of
    0 bytes, as that file given alone is refused: trimesh reads it as a
    scene of no geometry, and the archive's other meshes would be taken
    without a word on the one left out.

    Parameters
    ----------
    p : pathlib.Path
        A mesh input, by its name; only an archive is looked into.

    Raises
    ------
    IsoflowError
        One line naming the first empty mesh member, ``ARCHIVE:MEMBER``.

    Examples
    --------
    A tar archive of an empty readme (no mesh) and an empty STL (each
    ``TarInfo`` of size 0):

    >>> import tarfile, tempfile
    >>> p = Path(tempfile.mkdtemp()) / "parts.tar.gz"
    >>> with tarfile.open(p, "w:gz") as t:
    ...     t.addfile(tarfile.TarInfo("readme.txt")); t.addfile(tarfile.TarInfo("lid.stl"))
    >>> refuse_empty_members(p)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    isoflow.errors.IsoflowError: ...parts.tar.gz:lid.stl: an empty file (0 bytes), not a readable STL file
    """
    import tarfile
    import zipfile

    name = p.name.lower()
    if not any(name.endswith(s) for s in ARCHIVE_TYPES):
        return
    try:
        if name.endswith(".zip"):
            with zipfile.ZipFile(p) as z:
                sizes = [(i.filename, i.file_size) for i in z.infolist() if not i.is_dir()]
        else:
            with tarfile.open(p) as t:
                sizes = [(m.name, m.size) for m in t.getmembers() if m.isfile()]
    except (OSError, EOFError, zipfile.BadZipFile, tarfile.TarError):
        return  # trimesh's reader says what is wrong with the archive
    empty = [member for member, size in sizes if size == 0]
    if not empty:
        return
    from trimesh.exchange.load import mesh_formats
    from trimesh.util import split_extension

    formats = mesh_formats()
    # (an empty readme or material file is no mesh left out)
    meshes = [member for member in empty if split_extension(member).lower() in formats]
    if meshes:
        raise IsoflowError(empty_file_line(f"{p}:{meshes[0]}", meshes[0]))


def faceless_member_line(where: str, kind: str, scene: Any, data: bytes = b"") -> str | None:
    """The line for an archive's mesh member that holds no triangle, as
    that file given alone is refused: a wireframe's (an OBJ's ``l`` lines,
    a PLY's ``edge`` element, :func:`wireframe_line`), a point cloud's, or
    "no triangles read"; None where some geometry of it is a mesh with
    faces.

    Parameters
    ----------
    where : str
        The member as ``ARCHIVE:MEMBER``.
    kind : str
        Its format, as trimesh names it (``stl``, ``obj``).
    scene : trimesh.Scene
        The member as ``trimesh.load_scene`` reads it.
    data : bytes, optional
        The member's bytes, where its lines are counted (trimesh reads no
        OBJ ``l`` line, and a PLY's edges as a path); without them a
        wireframe is named by its points alone.

    Returns
    -------
    str or None

    Examples
    --------
    >>> import trimesh
    >>> faceless_member_line("parts.zip:lid.stl", "stl", trimesh.Scene())
    'parts.zip:lid.stl: no triangles read (empty mesh, or not a valid STL file)'
    >>> faceless_member_line("parts.zip:box.stl", "stl", trimesh.Scene(trimesh.creation.box())) is None
    True
    >>> cage = b"v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nl 1 2\\nl 2 3\\n"
    >>> print(faceless_member_line("parts.zip:cage.obj", "obj", trimesh.Scene(), cage))  # doctest: +ELLIPSIS
    parts.zip:cage.obj: no triangles read: it holds 3 points joined by 2 lines and no faces, a wireframe, ...
    """
    import trimesh

    geometry = list(scene.geometry.values())
    if any(isinstance(g, trimesh.Trimesh) and len(g.faces) for g in geometry):
        return None
    points, lines = _faceless_counts(data, kind, where)
    if lines and points:
        return wireframe_line(where, points, lines)
    points = sum(len(g.vertices) for g in geometry if isinstance(g, (trimesh.PointCloud, trimesh.Trimesh)))
    if points:
        return point_cloud_line(where, points)
    return f"{where}: no triangles read (empty mesh, or not a valid {kind.upper()} file)"


def meshless_archive_line(p: Path) -> str | None:
    """The line for an archive (:data:`ARCHIVE_TYPES`) that opens but holds
    no mesh file: what it holds, and that an archive inside it is not
    opened; None where it does not open (the reader's line says why).

    Parameters
    ----------
    p : pathlib.Path
        The archive.

    Returns
    -------
    str or None

    Examples
    --------
    >>> import tempfile, zipfile
    >>> p = Path(tempfile.mkdtemp()) / "parts.zip"
    >>> with zipfile.ZipFile(p, "w") as z:
    ...     z.writestr("readme.txt", "notes"); z.writestr("more.zip", b"")
    >>> print(meshless_archive_line(p))  # doctest: +ELLIPSIS
    /.../parts.zip: holds no mesh file (its files: more.zip, readme.txt); a mesh in an archive is read by its \
suffix (.stl, .obj, .ply, .off, .glb, ...); an archive inside it (more.zip) is not opened: unpack it and give its mesh
    """
    import tarfile
    import zipfile

    try:
        if p.name.lower().endswith(".zip"):
            with zipfile.ZipFile(p) as z:
                names = sorted(i.filename for i in z.infolist() if not i.is_dir())
        else:
            with tarfile.open(p) as t:
                names = sorted(m.name for m in t.getmembers() if m.isfile())
    except (OSError, EOFError, zipfile.BadZipFile, tarfile.TarError):
        return None
    if not names:
        return f"{p}: an archive of no file: it holds no mesh"
    shown = ", ".join(names[:5]) + (f", ... ({len(names)} files)" if len(names) > 5 else "")
    line = (f"{p}: holds no mesh file (its files: {shown}); a mesh in an archive is read by its suffix (.stl, .obj, "
            ".ply, .off, .glb, ...)")
    inner = [n for n in names if any(n.lower().endswith(s) for s in ARCHIVE_TYPES)]
    if inner:
        line += f"; an archive inside it ({', '.join(inner[:3])}) is not opened: unpack it and give its mesh"
    return line


def mesh_members(p: Path, kind: str, key: Callable[[str], Any] | None = None) -> Iterator[tuple[str, str, bytes, Any]]:
    """The mesh files of an archive, each read on its own: trimesh merges a
    whole archive's meshes into one, and a member of no triangle (a binary
    STL of a header and no facet, an OBJ of ``v`` lines alone) would be
    left out of it without a word; here it is refused, as that file given
    alone is.

    Parameters
    ----------
    p : pathlib.Path
        The archive.
    kind : str
        Its type, a value of :data:`ARCHIVE_TYPES` (``"zip"``).
    key : callable, optional
        The order of the member names (default: sorted as strings).

    Yields
    ------
    tuple
        ``(member, format, data, scene)``: the member's name, its format as
        trimesh names it (``"stl"``), its bytes, and ``trimesh.Scene``.

    Raises
    ------
    IsoflowError
        One line naming the first member of no triangle, ``ARCHIVE:MEMBER``
        (:func:`faceless_member_line`).

    Examples
    --------
    >>> import tempfile, zipfile
    >>> p = Path(tempfile.mkdtemp()) / "parts.zip"
    >>> with zipfile.ZipFile(p, "w") as z:
    ...     z.writestr("readme.txt", "notes"); z.writestr("points.obj", "v 0 0 0\\nv 1 0 0\\n")
    >>> list(mesh_members(p, "zip"))  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    isoflow.errors.IsoflowError: ...parts.zip:points.obj: no triangles read: it holds 2 points and no faces, ...
    """
    import trimesh
    from trimesh.exchange.load import mesh_formats

    from .gltf_extensions import faceless_note, json_of, unapplied_in

    with open(p, "rb") as f:
        archive = trimesh.util.decompress(f, file_type=kind)
    resolver = trimesh.resolvers.ZipResolver(archive)
    for member in sorted(archive, key=key):
        member_kind = trimesh.util.split_extension(member).lower()
        if member_kind not in mesh_formats():
            continue  # a texture, a material, metadata
        data = archive[member].read()
        if member_kind in ("gltf", "glb") and (tree := json_of(data, glb=member_kind == "glb")) is not None:
            if (refusal := unapplied_in(tree, f"{p}:{member}")) is not None:  # as for a file of its own
                raise IsoflowError(refusal)
            if (note := faceless_note(f"{p}:{member}", tree)) is not None:
                warn(note, MeshNote)
        scene = trimesh.load_scene(trimesh.util.wrap_as_stream(data), file_type=member_kind, resolver=resolver,
                                   process=False)
        if (line := faceless_member_line(f"{p}:{member}", member_kind, scene, data)) is not None:
            raise IsoflowError(line)
        if (note := _lines_left_out(f"{p}:{member}", member_kind, data)) is not None:  # lines beside its faces
            warn(note, MeshNote)
        yield member, member_kind, data, scene


#: the metadata files that make a directory a zarr store (v3, v2)
ZARR_METADATA = ("zarr.json", ".zarray", ".zgroup")


def refuse_zipped_store(p: Path) -> None:
    """Refuse a zip archive that holds a zarr store (``scan.zarr.zip``, as
    zarr's ``ZipStore`` writes it), which trimesh would open as a zip of
    meshes and report as "no triangles read".

    Parameters
    ----------
    p : pathlib.Path
        A mesh input, by its name; only a ``.zip`` is looked into.

    Raises
    ------
    IsoflowError
        A zip whose members include zarr metadata: one line saying to unzip
        it into a ``.zarr`` directory, which isoflow reads block by block.

    Examples
    --------
    >>> import tempfile, zipfile
    >>> p = Path(tempfile.mkdtemp()) / "scan.zarr.zip"
    >>> with zipfile.ZipFile(p, "w") as z:
    ...     z.writestr("zarr.json", "{}")
    >>> refuse_zipped_store(p)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    isoflow.errors.IsoflowError: ...scan.zarr.zip: a zipped zarr store; isoflow reads a zarr store as a directory: ...
    """
    import shlex
    import zipfile

    if p.suffix.lower() != ".zip":
        return
    try:
        with zipfile.ZipFile(p) as z:
            names = z.namelist()
    except (OSError, zipfile.BadZipFile):
        return  # trimesh's reader says what is wrong with the file
    if any(n.rstrip("/").rsplit("/", 1)[-1] in ZARR_METADATA for n in names):
        store = p.with_suffix("") if p.stem.lower().endswith(".zarr") else p.with_suffix(".zarr")
        raise IsoflowError(f"{p}: a zipped zarr store; isoflow reads a zarr store as a directory: unzip it "
                           f"(python -m zipfile -e {shlex.quote(str(p))} {shlex.quote(str(store))}) and give {store}")


@contextlib.contextmanager
def reading_mesh(p: Path):
    """Whatever a mesh reader raises on a bad file as one line naming it.

    Where the file's first bytes say it holds another format than its
    suffix names (an OBJ file saved as ``.stl``: read as an STL, it gives
    no triangles), the line says which and the name to give it instead
    (:func:`misnamed_mesh`); otherwise it is the reader's own.  The
    content is looked at only once a read has failed.
    """
    try:
        yield
    except IsoflowError:
        hint = misnamed_mesh(p)
        if hint is None:
            raise
        raise IsoflowError(hint) from None
    except MemoryError:  # the command's own "out of memory" line, not "cannot read as a mesh"
        raise
    except Exception as exc:  # trimesh raises anything from KeyError to struct.error
        msg = " ".join(str(exc).split())[:200] or "no detail"
        hint = misnamed_mesh(p)
        if hint is None and isinstance(exc, NotImplementedError) and "not supported" in msg:
            hint = not_a_mesh_format(p)
        raise IsoflowError(hint or f"{p}: cannot read as a mesh ({type(exc).__name__}: {msg})") from None


def not_a_mesh_format(p: Path) -> str:
    """The line for a file whose suffix names no format a mesh reader
    knows: trimesh says only ``file_type 'txt' not supported``, which
    leaves a user of ``genus example19.txt`` to guess that the point lists
    the other commands read are no mesh.

    Examples
    --------
    >>> print(not_a_mesh_format(Path("example19.txt")))  # doctest: +ELLIPSIS
    example19.txt: the suffix .txt names no mesh format (STL, OBJ, PLY, OFF, GLB, ...); voxelize and genus read \
triangle meshes (a text point list, x y z per line, is read by isoflow info, surface and flow)
    """
    kind = f"the suffix {p.suffix.lower()}" if p.suffix else "a name without a suffix"
    names = ", ".join(s.lstrip(".").upper() for s in MESH_SUFFIXES[:6] if s != ".stl_ascii")
    return (f"{p}: {kind} names no mesh format ({names}, ...); voxelize and genus read triangle meshes "
            "(a text point list, x y z per line, is read by isoflow info, surface and flow)")


def misnamed_mesh(p: Path) -> str | None:
    """The line for a mesh file that gave no triangles when its first
    bytes say it holds another format than its suffix names
    (:func:`isoflow.mesh.sniff.sniff_mesh_format`), or, where its suffix
    names a format whose files start with a magic word (PLY's ``ply``,
    GLB's ``glTF``), when they say no mesh format and lack that word (the
    reader's own error, such as trimesh's ``IndexError: list index out of
    range`` on a PLY file of text, says nothing of it); else ``None``.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "model.stl"
    >>> _ = p.write_text("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
    >>> print(misnamed_mesh(p).replace(str(p.parent), "DIR"))
    DIR/model.stl: no triangles read: its content is an OBJ file (lines 'v x y z' and 'f ...'), not STL; rename it model.obj
    >>> q = p.with_name("scan.ply")
    >>> _ = q.write_text("not a mesh")
    >>> print(misnamed_mesh(q).replace(str(p.parent), "DIR"))
    DIR/scan.ply: not a PLY file: it starts with b'not a me', not PLY's b'ply'
    """
    from .sniff import FORMATS, MAGIC_WORDS, SNIFF_BYTES, sniff_mesh_format

    try:
        if not p.is_file():  # (a FIFO would block the read)
            return None
        with open(p, "rb") as fh:
            size = os.fstat(fh.fileno()).st_size
            head = fh.read(SNIFF_BYTES)
    except OSError:
        return None
    kind = sniff_mesh_format(head, size)
    name = p.name
    written = next((s for s in MESH_SUFFIXES if name.lower().endswith(s)), p.suffix.lower())
    if not kind:
        magic = MAGIC_WORDS.get(written.lstrip("."))  # (.glb, .ply: the format is the suffix's name)
        if magic is None or not head or head.startswith(magic):  # (an empty file has its own line)
            return None
        fmt = written.lstrip(".").upper()
        return f"{p}: not a {fmt} file: it starts with {head[:8]!r}, not {fmt}'s {magic!r}"
    what, suffix = FORMATS[kind]
    if suffix == {".stl_ascii": ".stl"}.get(written, written):
        return None  # the format the suffix says: the reader's own line says what is wrong
    stem = name[:len(name) - len(written)]
    said = f", not {written.lstrip('.').upper()}" if written else ""
    return f"{p}: no triangles read: its content is {what}{said}; rename it {stem}{suffix}"


def trimesh_load(p: Path, force: str):
    """``trimesh.load`` of a checked file, unprocessed (the weld is
    isoflow's), ``force`` "mesh" (a scene's meshes as one, transforms
    applied) or "scene"; an OBJ's texture and normal seams are asked to be
    merged (the weld merges what trimesh leaves split); a PLY's concave
    polygons are cut by ears (:func:`_ply_polygons_cut`); a glTF file that
    uses a geometry extension trimesh does not apply is refused
    (:func:`~isoflow.mesh.gltf_extensions.gltf_refusal`), and its
    primitives of points or lines beside faces, which trimesh leaves out,
    are named in a :class:`~isoflow.errors.MeshNote`
    (:func:`~isoflow.mesh.gltf_extensions.faceless_note`)."""
    from .gltf_extensions import faceless_note, gltf_json, gltf_refusal

    check_mesh_file(p)
    tree = gltf_json(p) if p.suffix.lower() in (".gltf", ".glb") else None
    if (refusal := gltf_refusal(p, tree)) is not None:  # trimesh: another model, or its bare error
        raise IsoflowError(refusal)
    if tree is not None and (note := faceless_note(p, tree)) is not None:  # trimesh leaves them out without a word
        warn(note, MeshNote)
    import trimesh  # lazy: keeps `import isoflow` cheap

    kwargs: dict = {"process": False}
    source: Any = str(p)
    if p.suffix.lower() == ".obj":
        kwargs.update(merge_tex=True, merge_norm=True)
        if (text := _obj_rewritten(p)) is not None:
            # the file's own materials and textures still resolve beside it
            source = io.BytesIO(text)
            kwargs.update(file_type="obj", resolver=trimesh.resolvers.FilePathResolver(str(p)))
    with reading_mesh(p), warnings.catch_warnings():
        # NumPy's overflow warnings on inf or huge coordinates: the one
        # error line of check_mesh says what is wrong
        warnings.simplefilter("ignore", RuntimeWarning)
        loaded = trimesh.load(source, force=force, **kwargs)
    if p.suffix.lower() == ".ply":
        _ply_polygons_cut(loaded)
    return loaded


def _ply_polygons_cut(loaded: Any) -> None:
    """Re-cut, in place, the concave polygons trimesh fanned in a PLY file
    it read (a mesh, or a scene's meshes), as isoflow's own reader cuts
    them (:func:`isoflow.mesh.ply.concave_polygons_cut`, from the face
    lists trimesh keeps in ``metadata["_ply_raw"]``): a fan across an L's
    notch fills the notch and crosses the polygon's other triangles."""
    from .ply import concave_polygons_cut

    meshes = list(loaded.geometry.values()) if is_scene(loaded) else [loaded]
    for mesh in meshes:
        raw = getattr(mesh, "metadata", {}).get("_ply_raw")
        faces = getattr(mesh, "faces", None)
        if not isinstance(raw, dict) or not isinstance(raw.get("face"), dict) or faces is None:
            continue  # a point cloud, or a trimesh that keeps no face lists: its reading stands
        cut = concave_polygons_cut(faces, mesh.vertices, raw["face"].get("data"))
        if cut is not None:
            mesh.faces = cut


def _obj_rewritten(p: Path) -> bytes | None:
    """The OBJ file's text as trimesh should read it, or None where it
    reads the file as it is: its relative face indices written as the
    vertices they name (:func:`isoflow.mesh.readers.relative_indices_resolved`;
    a relative index before the first vertex is refused naming its line),
    then its concave polygons written as the triangles isoflow's readers
    cut them into (:func:`isoflow.mesh.readers.concave_faces_cut`: trimesh
    would fan them across their notches)."""
    from .readers import concave_faces_cut, may_name_vertex_0, obj_index_error, relative_indices_resolved

    try:
        data = p.read_bytes()
    except OSError:
        return None  # trimesh's path says what is wrong with the file
    text = relative_indices_resolved(data)
    if text is not None and may_name_vertex_0(text):  # written 0: no vertex (or a 0 in the file)
        message = obj_index_error(p, data)
        if message is not None:
            raise IsoflowError(message)
    cut = concave_faces_cut(data if text is None else text)
    return text if cut is None else cut


def _repeats_a_corner(faces: np.ndarray) -> np.ndarray:
    """Which triangles name one vertex twice (zero area, nothing to bound)."""
    return (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])


def _check_obj_indices(path: Path, failed: bool = False) -> None:
    """One line naming the OBJ face whose index names no vertex, where
    trimesh ``failed`` to read the file (an index past the vertices, either
    way) or read it with a face that may use index 0 (trimesh reads it as
    the first vertex without a word; :func:`isoflow.mesh.readers.may_name_vertex_0`
    is the cheap look before the line-by-line search)."""
    from .readers import may_name_vertex_0, obj_index_error

    data = path.read_bytes()
    if failed or may_name_vertex_0(data):
        message = obj_index_error(path, data)
        if message is not None:
            raise IsoflowError(message)


def _check_obj_numbers(path: Path) -> None:
    """One line naming the OBJ line whose word is not the number it must be
    (:func:`isoflow.mesh.readers.obj_number_error`), where there is one."""
    from .readers import obj_number_error

    message = obj_number_error(path, path.read_bytes())
    if message is not None:
        raise IsoflowError(message)


# ---------------------------------------------------------------------------
# combinatorial defects
# ---------------------------------------------------------------------------

def mesh_defects(vertices, faces) -> dict:
    """Count the combinatorial defects that make a mesh unfit to bound a solid.

    Purely combinatorial (vertex indices only, no coordinates are compared;
    weld coincident vertices first, e.g. with :func:`load_mesh`).  Returns::

        boundary_edges     edges used by exactly one face
        nonmanifold_edges  edges used by more than two faces
        inconsistent_edges edges used by two or more faces whose directions do
                           not balance (for a two-face edge: both faces run
                           a->b; orientation cannot be consistent there)
        inconsistent_nonmanifold_edges
                           those of them also non-manifold (more than two
                           faces), counted in both counts above
        components         face components, faces joined across shared edges
        edges              number of distinct undirected edges
        watertight         no boundary, non-manifold or inconsistent edge

    Degenerate edges (a face repeating a vertex) are ignored.

    A non-manifold edge whose uses balance (two faces a->b, two b->a: two
    cubes sharing an edge) still bounds a solid; the scanline of
    :func:`voxelize` is exact on it without a cap.
    """
    from .census import census

    v, f = check_mesh(vertices, faces, where="mesh_defects")
    return defect_counts(*census(f, len(v))[2:])


def repeated_faces(faces) -> np.ndarray:
    """For each face, the first face with the same three vertices the same
    way round: itself, or an earlier face it repeats.

    ``(1, 2, 3)``, ``(2, 3, 1)`` and ``(3, 1, 2)`` are one face listed
    three times; ``(1, 3, 2)`` is its other side (a double-sided face, see
    :func:`isoflow.mesh.census.opposite_pairs`), not a repeat.  A repeat
    adds nothing to the surface, yet it makes its three edges non-manifold
    and inconsistently oriented (each used twice one way).

    Parameters
    ----------
    faces : int ndarray (M, 3)

    Returns
    -------
    int64 ndarray (M,)
        ``first[i] == i`` for the first listing of each face; the repeats
        are ``first != np.arange(M)``.

    Examples
    --------
    >>> repeated_faces(np.array([[0, 1, 2], [1, 2, 3], [2, 0, 1], [0, 2, 1]])).tolist()
    [0, 1, 0, 3]
    """
    f = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(f) == 0:
        return np.zeros(0, dtype=np.int64)
    a, b, c = f.T
    # each face turned to start at its smallest vertex: one spelling per side
    at_a, at_b = (a <= b) & (a <= c), (b < a) & (b <= c)
    turned = (np.minimum(np.minimum(a, b), c), np.where(at_a, b, np.where(at_b, c, a)),
              np.where(at_a, c, np.where(at_b, a, b)))
    n = int(f.max()) + 1
    if n <= 2_000_000:  # n**3 < 2**63: one int64 key, sorted several times faster than rows
        key = (turned[0] * n + turned[1]) * n + turned[2]
        _, first, inverse = np.unique(key, return_index=True, return_inverse=True)
    else:
        _, first, inverse = np.unique(np.stack(turned, axis=1), axis=0, return_index=True, return_inverse=True)
    return first[inverse.reshape(-1)]  # (np.unique's return_index: each value's first occurrence)


def defect_counts(fwd: np.ndarray, bwd: np.ndarray, components: int) -> dict:
    """:func:`mesh_defects` from an edge census (the uses of each edge each
    way, :func:`isoflow.mesh.census.census`) and the number of components."""
    counts = fwd + bwd
    boundary = int((counts == 1).sum())
    nonmanifold = int((counts > 2).sum())
    unbalanced = fwd != bwd
    inconsistent = int(((counts >= 2) & unbalanced).sum())
    return {
        "boundary_edges": boundary,
        "nonmanifold_edges": nonmanifold,
        "inconsistent_edges": inconsistent,
        # a repeated face makes its edges both: a line naming the two counts says the overlap
        "inconsistent_nonmanifold_edges": int(((counts > 2) & unbalanced).sum()),
        "components": components,
        "edges": int(len(counts)),
        "watertight": boundary == 0 and nonmanifold == 0 and inconsistent == 0,
    }


def merge_coincident(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Faces re-indexed so that vertices with identical coordinates share one
    index (a triangle soup becomes a mesh whose edges can be counted).
    Coordinates are not changed; only the indices are."""
    _, first, inverse = np.unique(np.asarray(vertices), axis=0, return_index=True, return_inverse=True)
    return first[inverse.reshape(-1)][faces]  # each position's first vertex


def boundary_chain(faces: np.ndarray, n_vertices: int) -> tuple[np.ndarray, np.ndarray]:
    """The boundary of the faces as an integer 1-chain: directed edges
    ``a[e] -> b[e]``, each repeated by its net multiplicity (uses a -> b
    minus uses b -> a).  Empty iff every edge's uses balance (the mesh bounds
    a solid).  The chain is a cycle: every vertex has as many chain edges in
    as out."""
    from .census import census

    return chain_of(*census(np.asarray(faces, dtype=np.int64), n_vertices)[:4])


def chain_of(lo: np.ndarray, hi: np.ndarray, fwd: np.ndarray, bwd: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`boundary_chain` from an edge census (edges ``lo -> hi`` and
    their uses each way), by ``(lo, hi)``."""
    net = fwd - bwd
    sel = np.nonzero(net)[0]
    sel = sel[np.lexsort((hi[sel], lo[sel]))]  # by (lo, hi): the cap's triangles in a fixed order
    k = net[sel]
    src = np.where(k > 0, lo[sel], hi[sel])
    dst = np.where(k > 0, hi[sel], lo[sel])
    rep = np.abs(k)
    return np.repeat(src, rep), np.repeat(dst, rep)
