"""A plain NumPy reader of PLY meshes: the vertex and face elements, ASCII
or binary of either byte order, read as ``trimesh.load(process=False)``
reads them, so that a command on a PLY file does not import trimesh (and
the scipy modules it pulls in), which costs more than reading most files.

As :mod:`isoflow.mesh.readers` does for STL and OBJ, the reader says
``None`` for anything it has not seen before and trimesh reads the file:
texture coordinates (trimesh splits vertices at UV seams), elements other
than ``vertex`` and ``face``, faces with properties beside their corner
list, anything out of the grammar. What it reads gives trimesh's arrays
exactly: each coordinate rounded to its declared type, every vertex kept,
a polygon split as trimesh splits it (faces of one size as
:func:`~isoflow.mesh.readers.triangulate` does; faces of several sizes
as ``trimesh.geometry.triangulate_quads`` orders them: the triangles, then
the quads' first halves and second halves, then the other polygons as
fans), except that a concave polygon whose fan would leave it is cut by
ears (see :func:`~isoflow.mesh.readers.triangulate`). A binary file whose
faces have several sizes, which trimesh cannot read ("PLY is unexpected
length"), is read the same way. A file trimesh reads has its concave
polygons cut the same way after it (:func:`concave_polygons_cut`).
"""

from __future__ import annotations

import numpy as np

from .readers import Mesh, numbers, triangulate, words_per_line

#: PLY's scalar types (both spellings), as NumPy's
TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4", "uint": "u4", "float": "f4",
         "double": "f8", "int8": "i1", "uint8": "u1", "int16": "i2", "uint16": "u2", "int32": "i4",
         "uint32": "u4", "float32": "f4", "float64": "f8", "int64": "i8", "uint64": "u8", "float16": "f2"}
#: vertex properties trimesh reads as texture coordinates (it then splits vertices at their seams)
TEXTURE = frozenset(("texture_u", "texture_v", "u", "v", "s", "t"))


def read_ply(data: bytes) -> Mesh | None:
    """Vertices (float64 (N, 3)) and faces (int64 (M, 3)) of a PLY file of
    vertices and faces, or ``None`` where trimesh should read it.

    Examples
    --------
    >>> text = b"ply\\nformat ascii 1.0\\nelement vertex 4\\nproperty float x\\nproperty float y\\n" \\
    ...     b"property float z\\nelement face 1\\nproperty list uchar int vertex_indices\\nend_header\\n" \\
    ...     b"0 0 0\\n1 0 0\\n1 1 0\\n0 1 0.1\\n4 0 1 2 3\\n"
    >>> v, f = read_ply(text)
    >>> f.tolist(), v[3].tolist() == [0.0, 1.0, float(np.float32(0.1))]
    ([[0, 1, 2], [2, 3, 0]], True)
    """
    head = _header(data)
    if head is None:
        return None
    form, body, vertex, nv, count, index, nf = head
    if form == "ascii":
        return _ascii(data[body:], vertex, nv, count, index, nf)
    order = "<" if form == "binary_little_endian" else ">"
    return _binary(data[body:], order, vertex, nv, count, index, nf)


def _header(data: bytes):
    """The header's facts: format, where the body begins, the vertex
    properties ``[(name, type)]`` and count, the face list's count and
    index types and the face count; None for a header this reader leaves
    to trimesh."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return None
    stop = data.find(b"\n", end)
    try:
        lines = data[:end].decode("ascii").splitlines()[1:]
    except UnicodeDecodeError:
        return None
    if stop < 0 or data[end:stop].strip() != b"end_header" or not lines:
        return None
    words = lines[0].split()
    if len(words) != 3 or words[0] != "format" or words[2] != "1.0" or words[1] not in (
            "ascii", "binary_little_endian", "binary_big_endian"):
        return None
    elements: list[tuple[str, int, list[list[str]]]] = []
    for line in lines[1:]:
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "element" and len(w) == 3 and w[2].isdigit():
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property" and elements and len(w) in (3, 5):
            elements[-1][2].append(w[1:])
        else:
            return None
    if [e[0] for e in elements] != ["vertex", "face"]:
        return None
    (_, nv, vprops), (_, nf, fprops) = elements
    names = [p[-1] for p in vprops]
    if any(len(p) != 2 or p[0] not in TYPES for p in vprops) or not {"x", "y", "z"} <= set(names) \
            or TEXTURE & set(names) or len(set(names)) != len(names):
        return None
    if len(fprops) != 1 or len(fprops[0]) != 4 or fprops[0][0] != "list" or \
            fprops[0][3] not in ("vertex_indices", "vertex_index"):
        return None
    count, index = fprops[0][1:3]
    if count not in TYPES or index not in TYPES or TYPES[index][0] not in "iu" or TYPES[count][0] not in "iu" \
            or nv == 0 or nf == 0:
        return None
    return words[1], stop + 1, [(p[1], TYPES[p[0]]) for p in vprops], nv, TYPES[count], TYPES[index], nf


def _ascii(text: bytes, vertex: list, nv: int, count: str, index: str, nf: int) -> Mesh | None:
    """The body of an ASCII file: ``nv`` vertex lines, then ``nf`` face
    lines (trimesh reads a row per line; blank lines at the end only)."""
    text = text.replace(b"\r\n", b"\n").rstrip()
    if not text.isascii() or any(c in text for c in b"\r\x0b\x0c\x1c\x1d\x1e"):
        return None  # lines that str.splitlines, trimesh's, would split differently
    a = np.frombuffer(text, np.uint8)
    ends = np.flatnonzero(a == 10)
    if len(ends) != nv + nf - 1:
        return None
    words = words_per_line(a)
    cols = len(vertex)
    if (words[:nv] != cols).any() or (words[nv:] < 4).any():
        return None
    v = numbers(text[:ends[nv - 1]], np.float64, cols * nv)
    flat = numbers(text[ends[nv - 1]:], np.float64, int(words[nv:].sum()))
    if v is None or flat is None:
        return None
    sizes = words[nv:] - 1
    first = np.cumsum(words[nv:]) - words[nv:]
    if not ((flat[first] == sizes).all() and (np.abs(flat) < 2.0**62).all()):
        return None  # counts that are not the lines' lengths, indices that are no integers
    names = [n for n, _ in vertex]
    v = v.reshape(nv, cols)
    # trimesh casts each column to its declared type (a float's text to
    # float32; past its range to inf, which check_mesh names)
    with np.errstate(over="ignore", invalid="ignore"):
        xyz = np.stack([v[:, names.index(c)].astype(dict(vertex)[c]) for c in "xyz"], axis=1)
    return _mesh(xyz, np.delete(flat, first).astype(index), sizes, nv)


def _binary(body: bytes, order: str, vertex: list, nv: int, count: str, index: str, nf: int) -> Mesh | None:
    """The body of a binary file: the vertex records, then each face's
    corner count and corners (trailing bytes ignored)."""
    kind = np.dtype([(n, order + t) for n, t in vertex])
    c, i = np.dtype(order + count), np.dtype(order + index)
    faces = body[kind.itemsize * nv:]
    if len(body) < kind.itemsize * nv + c.itemsize:
        return None
    rec = np.frombuffer(body, kind, nv)
    v = np.stack([rec[n] for n in "xyz"], axis=1)
    k = int(np.frombuffer(faces, c, 1)[0])
    if 0 < k and (c.itemsize + k * i.itemsize) * nf <= len(faces):
        table = np.frombuffer(faces, np.dtype([("n", c), ("corners", i, (k,))]), nf)
        if (table["n"] == k).all():  # faces of one size: one record type
            return _mesh(v, table["corners"].reshape(-1), np.full(nf, k), nv)
    sizes, starts, at = np.zeros(nf, np.int64), np.zeros(nf, np.int64), 0
    for f in range(nf):  # faces of several sizes: each count says where the next face begins
        if at + c.itemsize > len(faces):
            return None
        n = int(np.frombuffer(faces, c, 1, at)[0])
        if not 0 <= n <= len(faces):  # (a 64-bit count past int64 would not even fit the array)
            return None
        sizes[f], starts[f] = n, at + c.itemsize
        at = starts[f] + sizes[f] * i.itemsize
    if at > len(faces):
        return None
    byte = np.repeat(starts, sizes) + _within(sizes) * i.itemsize
    cells = np.frombuffer(faces, np.uint8)[byte[:, None] + np.arange(i.itemsize)]
    return _mesh(v, cells.copy().view(i).reshape(-1), sizes, nv)


def _mesh(v: np.ndarray, corners: np.ndarray, sizes: np.ndarray, nv: int) -> Mesh | None:
    """float64 vertices and the polygons as trimesh splits them; None for
    a polygon of fewer than three corners or an index past the vertices
    (trimesh's error, or its reading, says what is wrong)."""
    corners = corners.astype(np.int64)
    if (sizes < 3).any() or (corners < 0).any() or (corners >= nv).any():
        return None
    v = v.astype(np.float64)
    return v, _split(corners, sizes, v)


def _split(corners: np.ndarray, sizes: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
    """The polygons' triangles (int64 (M, 3)) in the order trimesh gives
    them: faces of one size as :func:`~isoflow.mesh.readers.triangulate`
    does, faces of several sizes as ``trimesh.geometry.triangulate_quads``
    orders them (the triangles, the quads as two blocks of halves, the
    other polygons as fans); given the vertices ``v``, a concave polygon
    whose fan would leave it is cut by ears."""
    if (sizes == sizes[0]).all():
        return triangulate(corners, sizes, v).astype(np.int64)
    first = np.cumsum(sizes) - sizes
    parts = []
    for which in (sizes == 3, sizes == 4, sizes > 4):
        if which.any():
            parts.append(triangulate(corners[np.repeat(first[which], sizes[which]) + _within(sizes[which])],
                                     sizes[which], v))
    return np.concatenate(parts).astype(np.int64)


def concave_polygons_cut(faces: np.ndarray, vertices: np.ndarray, face_data: object) -> np.ndarray | None:
    """The triangles of a PLY file that trimesh read, with each concave
    polygon whose fan would leave it cut by ears, as :func:`read_ply` cuts
    it; None where trimesh's triangles need no change.

    trimesh fans every polygon of the files it reads (texture coordinates,
    other elements, faces with more properties: where :func:`read_ply`
    says None), and a fan across an L's notch fills the notch. The
    polygons are the face lists trimesh keeps (``face_data``: its
    ``metadata["_ply_raw"]["face"]["data"]``). Its vertices may not be the
    file's (it splits them at texture seams), so each polygon's corners are
    taken from trimesh's own triangles, whose order (:func:`_split`) says
    which polygon corner each of their corners is; where that order is not
    trimesh's (another trimesh), the triangles are left as read.

    Parameters
    ----------
    faces : numpy.ndarray
        trimesh's triangles (M, 3), indices into ``vertices``.
    vertices : numpy.ndarray
        trimesh's vertices (N, 3).
    face_data : object
        The face element's data as trimesh's PLY reader keeps it: a dict
        of the corner lists (a 2D array, or an object array of lists) or
        a structured array of fixed-size lists.

    Returns
    -------
    numpy.ndarray or None
        int64 (M, 3): the triangles in trimesh's rows, concave polygons cut
        by ears; None where none is.

    Examples
    --------
    An L (fanned by trimesh from its corner (2, 0): its second triangle
    lies in the notch) with vertices split at a seam: corner 5 is vertex 6.

    >>> L = np.array([[2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0], [0, 0, 0], [0, 0, 0]], float)
    >>> fan = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 6]])
    >>> concave_polygons_cut(fan, L, {"vertex_indices": np.array([[0, 1, 2, 3, 4, 5]])}).tolist()
    [[2, 3, 4], [2, 4, 6], [0, 1, 2], [6, 0, 2]]
    """
    lists = _face_lists(face_data)
    faces = np.asarray(faces)
    if lists is None or not len(faces):
        return None
    flat, sizes = lists
    if (sizes < 3).any() or (sizes == 3).all():
        return None
    places = _split(np.arange(len(flat)), sizes)  # where in ``flat`` each corner of trimesh's triangles is
    if places.shape != faces.shape:
        return None
    corner = np.zeros(len(flat), np.int64)
    corner[places] = faces
    if not (corner[places] == faces).all():
        return None  # trimesh split the polygons otherwise: its reading stands
    cut = _split(corner, sizes, np.asarray(vertices, np.float64))
    return None if np.array_equal(cut, faces) else cut


def _face_lists(face_data: object) -> tuple[np.ndarray, np.ndarray] | None:
    """The corners (one polygon after another) and sizes of the face
    lists trimesh's PLY reader keeps, or None for a form it has not."""
    lists = None
    if isinstance(face_data, dict):
        lists = next((face_data[n] for n in ("vertex_indices", "vertex_index") if n in face_data), None)
    elif isinstance(face_data, np.ndarray) and face_data.dtype.names:
        name = next((n for n in ("vertex_indices", "vertex_index") if n in face_data.dtype.names), None)
        if name is not None and face_data.dtype[name].names and "f1" in face_data.dtype[name].names:
            lists = face_data[name]["f1"]  # binary lists of one size: (count, corners) records
    if not isinstance(lists, np.ndarray) or not len(lists):
        return None
    if lists.dtype != object and lists.ndim == 2 and lists.dtype.kind in "iu":
        return lists.reshape(-1).astype(np.int64), np.full(len(lists), lists.shape[1], np.int64)
    if lists.dtype != object or lists.ndim != 1:
        return None
    rows = [np.asarray(r).reshape(-1) for r in lists]
    if any(r.dtype.kind not in "iu" for r in rows):
        return None
    return np.concatenate(rows).astype(np.int64), np.array([len(r) for r in rows], np.int64)


def _within(sizes: np.ndarray) -> np.ndarray:
    """0 .. size - 1 for each size, concatenated."""
    return np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)
