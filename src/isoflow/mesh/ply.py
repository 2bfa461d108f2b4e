"""A plain NumPy reader of PLY meshes: the ``x``, ``y``, ``z`` of the
vertex element and the corner lists of the face element, ASCII or binary
of either byte order, read as ``trimesh.load(process=False)`` reads them,
so that a command on a PLY file does not import trimesh (and the scipy
modules it pulls in), which costs more than reading most files.

Every other property (normals, colours, texture coordinates per vertex or
per face, quality, flags) and every other element (edges, materials) is
stepped over, in the header's order, whatever its scalar and list types:
trimesh fails on some of those files (a binary file with texture
coordinates and faces of several sizes is "of unexpected length", per-face
texture lists of several sizes are a shape mismatch) that are valid PLY.
An element whose lists all have the first row's lengths is read as one
record type; lists of several lengths are walked row by row by a compiled
scan (:func:`_scan_binary`, :func:`_scan_words`). A file that does not
match its header (a body shorter than its counts, ASCII rows of other
lengths than their properties take, a face naming no vertex) is refused
in one :class:`~isoflow.errors.IsoflowError` line naming the file.

What the reader gives is trimesh's arrays exactly: each coordinate
rounded to its declared type, every vertex kept, a polygon split as
trimesh splits it (faces of one size as
:func:`~isoflow.mesh.readers.triangulate` does; faces of several sizes as
``trimesh.geometry.triangulate_quads`` orders them: the triangles, then
the quads' first halves and second halves, then the other polygons as
fans; faces of fewer than three corners dropped), except that a concave
polygon whose fan would leave it is cut by ears (see
:func:`~isoflow.mesh.readers.triangulate`), and that trimesh splits a
textured file's vertices at its texture seams, which the weld of
:func:`~isoflow.mesh.load.load_mesh` joins again. The reader says ``None``,
and trimesh reads the file, only for what is no mesh of this kind: no
``face`` element with a corner list, no ``x``, ``y``, ``z``, no faces, a
header out of the grammar. A file trimesh reads has its concave polygons
cut the same way after it (:func:`concave_polygons_cut`).
"""

from __future__ import annotations

import warnings
from typing import NamedTuple

import numpy as np

from ..errors import IsoflowError
from ..scale.compiled import read_only_view
from ..scale.jit import njit
from .readers import Mesh, triangulate, words_per_line

#: PLY's scalar types (both spellings, and the 64-bit and half types trimesh also reads), as NumPy's
TYPES = {"char": "i1", "uchar": "u1", "short": "i2", "ushort": "u2", "int": "i4", "uint": "u4", "float": "f4",
         "double": "f8", "int8": "i1", "uint8": "u1", "int16": "i2", "uint16": "u2", "int32": "i4",
         "uint32": "u4", "float32": "f4", "float64": "f8", "int64": "i8", "uint64": "u8", "float16": "f2"}
#: the face element's corner list, as exporters name it
CORNERS = ("vertex_indices", "vertex_index")


class Property(NamedTuple):
    """One property of an element: its name, its (item) type as NumPy's
    and, for a list, its count's type (``None`` for a scalar)."""

    name: str
    kind: str
    count_type: str | None


class Element(NamedTuple):
    """One element of the header: its name, its row count and properties."""

    name: str
    rows: int
    properties: list[Property]


def read_ply(data: bytes, where: str = "PLY file") -> Mesh | None:
    """Vertices (float64 (N, 3)) and faces (int64 (M, 3)) of a PLY mesh,
    or ``None`` where trimesh should read it.

    Parameters
    ----------
    data : bytes
        The file's bytes.
    where : str
        What an error line names first (the file's path).

    Returns
    -------
    tuple of numpy.ndarray, or None
        The vertices and the triangles of the face element's polygons
        (indices into the vertices); None for a file that is no PLY mesh
        of vertices and faces (trimesh's reading, or its error, stands).

    Raises
    ------
    IsoflowError
        A file that does not match its header: a body that ends before
        its rows do, ASCII rows of other lengths than their properties
        take, a list count that is no whole number, a face naming no
        vertex, a type PLY has not.

    Examples
    --------
    A quad (cut in two) beside texture coordinates, a normal and a colour
    per vertex, stepped over:

    >>> text = b"ply\\nformat ascii 1.0\\nelement vertex 4\\nproperty float x\\nproperty float y\\n" \\
    ...     b"property float z\\nproperty float u\\nproperty float v\\nproperty uchar red\\n" \\
    ...     b"element face 1\\nproperty list uchar int vertex_indices\\nproperty list uchar float texcoord\\n" \\
    ...     b"end_header\\n0 0 0 0 0 9\\n1 0 0 1 0 9\\n1 1 0 1 1 9\\n0 1 0.1 0 1 9\\n4 0 1 2 3 2 0.5 0.5\\n"
    >>> v, f = read_ply(text)
    >>> f.tolist(), v[3].tolist() == [0.0, 1.0, float(np.float32(0.1))]
    ([[0, 1, 2], [2, 3, 0]], True)
    >>> read_ply(text.replace(b"4 0 1 2 3", b"4 0 1 2 7"), "m.ply")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: m.ply: face 0 names vertex 7, but the file's vertices are numbered 0 to 3
    """
    head = _header(data, where)
    if head is None:
        return None
    form, body, elements = head
    if form == "ascii":
        xyz, corners, sizes = _ascii(data[body:], elements, where, data[:body].count(b"\n"))
    else:
        xyz, corners, sizes = _binary(data[body:], ">" if form == "binary_big_endian" else "<", elements, where)
    return _mesh(xyz, corners, sizes, where)


def header_elements(data: bytes, where: str = "PLY file") -> tuple[str, int, list[Element]] | None:
    """A PLY header's format, where the body begins and its elements (each
    with its row count and properties), whatever they hold; None for a
    header out of the grammar, IsoflowError for a type PLY has not.

    Examples
    --------
    >>> fmt, start, elements = header_elements(b"ply\\nformat ascii 1.0\\nelement vertex 2\\n"
    ...                                        b"property float x\\nend_header\\n0\\n1\\n")
    >>> fmt, [(e.name, e.rows) for e in elements]
    ('ascii', [('vertex', 2)])
    """
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
    elements: list[Element] = []
    for line in lines[1:]:
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "element" and len(w) == 3 and w[2].isdigit():
            elements.append(Element(w[1], int(w[2]), []))
        elif w[0] == "property" and elements and (len(w) == 3 or (len(w) == 5 and w[1] == "list")):
            elements[-1].properties.append(_property(w, where))
        else:
            return None
    return words[1], stop + 1, elements


def _header(data: bytes, where: str) -> tuple[str, int, list[Element]] | None:
    """The header's format, where the body begins and the elements; None
    for a header this reader leaves to trimesh (out of the grammar, or no
    mesh of vertices and faces), IsoflowError for a type PLY has not."""
    parsed = header_elements(data, where)
    if parsed is None:
        return None
    elements = parsed[2]
    names = [e.name for e in elements]
    if len(set(names)) != len(names) or "vertex" not in names or "face" not in names:
        return None
    vertex, face = elements[names.index("vertex")], elements[names.index("face")]
    scalars = [p.name for p in vertex.properties if p.count_type is None]
    lost = [c for c in "xyz" if c not in scalars]
    if lost:  # no reader places such vertices (trimesh's fails on a KeyError): say which coordinate is missing
        raise IsoflowError(f"{where}: the header's element 'vertex' has no property {', '.join(map(repr, lost))} "
                           f"(its properties: {', '.join(p.name for p in vertex.properties) or 'none'}), so its "
                           "vertices have no positions")
    corners = [p for p in face.properties if p.name in CORNERS and p.count_type is not None]
    if not {"x", "y", "z"} <= {p.name for p in vertex.properties if p.count_type is None} or len(corners) != 1 \
            or corners[0].kind[0] not in "iu" or face.rows == 0 \
            or any(len({p.name for p in e.properties}) != len(e.properties) for e in (vertex, face)):
        return None
    return parsed


def _property(words: list[str], where: str) -> Property:
    """The property of a header line's words (``property TYPE NAME`` or
    ``property list COUNT ITEM NAME``); IsoflowError for a type PLY has
    not, or a list counted by floats."""
    types = words[1:2] if len(words) == 3 else words[2:4]
    for t in types:
        if t not in TYPES:
            raise IsoflowError(f"{where}: the header's line {' '.join(words)!r} names the type {t!r}, which PLY "
                               "has not (char, uchar, short, ushort, int, uint, float, double, or int8 ... float64)")
    if len(words) == 3:
        return Property(words[2], TYPES[words[1]], None)
    if TYPES[words[2]][0] not in "iu":
        raise IsoflowError(f"{where}: the header's line {' '.join(words)!r} counts a list by {words[2]!r}; "
                           "a list's count is an integer type")
    return Property(words[4], TYPES[words[3]], TYPES[words[2]])


def _wanted(element: Element) -> list[str]:
    """The properties read of an element: the vertices' coordinates, the
    faces' corner list, nothing of any other element."""
    if element.name == "vertex":
        return ["x", "y", "z"]
    if element.name == "face":
        return [p.name for p in element.properties if p.name in CORNERS and p.count_type is not None]
    return []


def _layout(element: Element, itemsizes: bool) -> tuple[np.ndarray, ...]:
    """An element's properties as the scans take them: whether each is a
    list, its (items') size, its count's size and signedness (bytes where
    ``itemsizes``, else one word each), and the column of the scan's
    ``places`` each wanted property is given (-1: not wanted)."""
    props = element.properties
    wanted = _wanted(element)
    lists = np.array([p.count_type is not None for p in props])
    sizes = np.array([np.dtype(p.kind).itemsize if itemsizes else 1 for p in props], np.int64)
    counts = np.array([np.dtype(p.count_type).itemsize if p.count_type and itemsizes else 1 for p in props], np.int64)
    signed = np.array([p.count_type is not None and p.count_type[0] == "i" for p in props])
    want = np.array([wanted.index(p.name) if p.name in wanted else -1 for p in props], np.int64)
    return lists, sizes, counts, signed, want


def _binary(body: bytes, order: str, elements: list[Element], where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coordinates, corners and face sizes of a binary body, its
    elements read in the header's order up to the vertices and faces
    (bytes after them ignored)."""
    buf = read_only_view(np.frombuffer(body, np.uint8))  # bytes or a bytearray: one compile for both
    got: dict[str, dict] = {}
    at = 0
    for element in elements:
        if {"vertex", "face"} <= set(got):
            break  # nothing after them is read
        got[element.name], at = _binary_element(body, buf, at, element, order, where)
    return _assemble(got, elements, where)


def _binary_element(body: bytes, buf: np.ndarray, at: int, element: Element, order: str,
                    where: str) -> tuple[dict, int]:
    """The wanted properties of one element of a binary body from byte
    ``at`` (scalars as arrays, lists as (items, lengths)), and where the
    next element begins."""
    props, rows = element.properties, element.rows
    if rows == 0 or not props:  # (rows of no properties take no bytes)
        return {}, at
    first = _first_binary_row(body, at, props, order)
    if first is not None:  # each row as the first: one record type, if every count says so
        fields: list[tuple] = []
        for j, (p, k) in enumerate(zip(props, first)):
            fields += [(f"c{j}", order + p.count_type), (f"l{j}", order + p.kind, (k,))] if p.count_type else [
                (f"s{j}", order + p.kind)]
        kind = np.dtype(fields)
        if at + rows * kind.itemsize <= len(body):
            rec = np.frombuffer(body, kind, rows, at)
            if all((rec[f"c{j}"] == k).all() for j, (p, k) in enumerate(zip(props, first)) if p.count_type):
                out = {p.name: (rec[f"l{j}"].reshape(-1), np.full(rows, first[j], np.int64)) if p.count_type
                       else rec[f"s{j}"] for j, p in enumerate(props) if p.name in _wanted(element)}
                return out, at + rows * kind.itemsize
    lists, sizes, counts, signed, want = _layout(element, True)
    places = np.zeros((rows, max(1, int((want >= 0).sum()))), np.int64)
    lengths, status = np.zeros(rows, np.int64), np.zeros(3, np.int64)
    end = _scan_binary(buf, at, lists, sizes, counts, signed, order == ">", want, places, lengths, status)
    _refuse(status, element, where, "binary body")
    out = {}
    for j, p in enumerate(props):
        if want[j] >= 0:
            starts = places[:, want[j]]
            dtype = np.dtype(order + p.kind)
            if p.count_type:
                items = np.repeat(starts, lengths) + _within(lengths) * dtype.itemsize
                out[p.name] = (_take(buf, items, dtype), lengths)
            else:
                out[p.name] = _take(buf, starts, dtype)
    return out, int(end)


def _first_binary_row(body: bytes, at: int, props: list[Property], order: str) -> list[int] | None:
    """The lengths of the lists of a binary element's first row (0 for a
    scalar), or None where the body ends inside it or a count is
    negative (the scan says which)."""
    first = []
    for p in props:
        k = 0
        if p.count_type:
            c = np.dtype(order + p.count_type)
            if at + c.itemsize > len(body):
                return None
            k = int(np.frombuffer(body, c, 1, at)[0])
            if not 0 <= k <= len(body):
                return None
            at += c.itemsize
        at += np.dtype(p.kind).itemsize * (k if p.count_type else 1)
        first.append(k)
    return first


def _take(buf: np.ndarray, starts: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """The values of ``dtype`` whose bytes begin at ``starts`` in ``buf``."""
    cells = buf[starts[:, None] + np.arange(dtype.itemsize)]
    return cells.view(dtype).reshape(-1)


def _ascii(text: bytes, elements: list[Element], where: str, header_lines: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coordinates, corners and face sizes of an ASCII body: its
    numbers taken row after row as the header's elements say. Where the
    body has as many lines as rows, as writers write it (and as trimesh
    reads it: a row per line), a line of another length than its row's is
    refused, naming it (:func:`_line_off`)."""
    text = text.replace(b"\r\n", b"\n")
    if not text.isascii():
        raise IsoflowError(f"{where}: the ASCII body holds bytes that are not ASCII text")
    words = words_per_line(np.frombuffer(text, np.uint8))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)  # (older NumPy) text it cannot read to its end
            tokens = np.fromstring(text.decode("ascii"), dtype=np.float64, sep=" ")
    except ValueError:
        tokens = np.zeros(0)
    if len(tokens) != words.sum():
        lines = text.split(b"\n")
        line = next((i for i, t in enumerate(lines) if not _all_numbers(t)), None)
        if line is None:
            raise IsoflowError(f"{where}: a word that is not a number")
        word = next(w for w in lines[line].split() if not _all_numbers(w)).decode(errors="replace")
        comma = _all_numbers(word.replace(",", ".", 1).encode())
        hint = f" (PLY writes decimals with a point: {word.replace(',', '.', 1)})" if comma else ""
        raise IsoflowError(f"{where}: line {header_lines + line + 1}: {word!r} is not a number{hint}")
    lines = np.flatnonzero(words)
    rows = sum(e.rows for e in elements if e.properties)
    got: dict[str, dict] = {}
    at, error = 0, None
    try:
        for element in elements:
            got[element.name], at = _ascii_element(tokens, at, element, where)
        if at != len(tokens):
            raise IsoflowError(f"{where}: the header's rows take {at} numbers, but the body holds {len(tokens)} "
                               "(the header's counts do not match the data)")
    except IsoflowError as exc:
        error = exc
    if len(lines) == rows and (off := _line_off(tokens, words[lines], elements)) is not None:
        i, name, row, width = off  # a row per line: the first line that is not its row says more
        line = f"{where}: line {header_lines + int(lines[i]) + 1}"
        if width < 0:
            raise IsoflowError(f"{line}: row {row} of element '{name}' gives a list a count that is no whole number "
                               "from 0 up, or past the line") from None
        raise IsoflowError(f"{line} holds {int(words[lines[i]])} numbers, but row {row} of element '{name}' takes "
                           f"{width} (the header's properties or counts do not match the data)") from None
    if error is not None:
        raise error
    return _assemble(got, elements, where)


def _all_numbers(line: bytes) -> bool:
    """Whether each word of a line reads as a float (the line for an error)."""
    try:
        [float(w) for w in line.split()]
    except ValueError:
        return False
    return True


def _line_off(tokens: np.ndarray, words: np.ndarray, elements: list[Element]) -> tuple[int, str, int, int] | None:
    """The first row, taken as beginning on its own line (the body's lines
    holding ``words`` numbers each, one a row), whose properties take
    another count of numbers than its line holds: the line's index, the
    element, the row and the numbers it takes; None where each fits."""
    starts = np.cumsum(words) - words
    a = 0
    for e in elements:
        if not e.properties:
            continue
        s = starts[a:a + e.rows]
        pos = s.astype(np.float64)
        for p in e.properties:
            if p.count_type is None:
                pos += 1
                continue
            inside = pos < len(tokens)
            k = np.where(inside, tokens[np.where(inside, pos, 0).astype(np.int64)], np.inf)
            pos += 1 + np.where((k >= 0) & (k == np.floor(k)), k, np.inf)  # (a count no length: no fit)
        off = np.flatnonzero(pos - s != words[a:a + e.rows])
        if len(off):
            width = pos[off[0]] - s[off[0]]
            return a + int(off[0]), e.name, int(off[0]), int(width) if np.isfinite(width) else -1
        a += e.rows
    return None


def _ascii_element(tokens: np.ndarray, at: int, element: Element, where: str) -> tuple[dict, int]:
    """The wanted properties of one element of an ASCII body from number
    ``at`` (scalars as arrays, lists as (items, lengths)), and where the
    next element begins."""
    props, rows = element.properties, element.rows
    if rows == 0 or not props:  # (rows of no properties take no numbers, nor lines)
        return {}, at
    wanted = _wanted(element)
    first = _first_ascii_row(tokens, at, props)
    width = sum(1 + k if p.count_type else 1 for p, k in zip(props, first or []))
    if first is not None and at + rows * width <= len(tokens):
        table = tokens[at:at + rows * width].reshape(rows, width)
        cols = np.cumsum([0] + [1 + k if p.count_type else 1 for p, k in zip(props, first)])[:-1]
        if all((table[:, c] == k).all() for p, k, c in zip(props, first, cols) if p.count_type):
            out = {p.name: (table[:, c + 1:c + 1 + k].reshape(-1), np.full(rows, k, np.int64)) if p.count_type
                   else table[:, c] for p, k, c in zip(props, first, cols) if p.name in wanted}
            return out, at + rows * width
    lists, _, _, _, want = _layout(element, False)
    places = np.zeros((rows, max(1, int((want >= 0).sum()))), np.int64)
    lengths, status = np.zeros(rows, np.int64), np.zeros(3, np.int64)
    end = _scan_words(tokens, at, lists, want, places, lengths, status)
    _refuse(status, element, where, "ASCII body")
    out = {}
    for j, p in enumerate(props):
        if want[j] >= 0:
            starts = places[:, want[j]]
            out[p.name] = (tokens[np.repeat(starts + 1, lengths) + _within(lengths)], lengths) if p.count_type \
                else tokens[starts]
    return out, int(end)


def _first_ascii_row(tokens: np.ndarray, at: int, props: list[Property]) -> list[int] | None:
    """The lengths of the lists of an ASCII element's first row (0 for a
    scalar), or None where the body ends inside it or a count is no whole
    number from 0 up (the scan says which)."""
    first = []
    for p in props:
        k = tokens[at] if p.count_type and at < len(tokens) else 0.0
        if p.count_type and not (at < len(tokens) and 0 <= k <= len(tokens) and k == int(k)):
            return None
        first.append(int(k))
        at += 1 + int(k) if p.count_type else 1
    return first


def _refuse(status: np.ndarray, element: Element, where: str, body: str) -> None:
    """The line for what a scan found wrong (``status``: what, the row,
    the property), if anything."""
    what, row, prop = (int(s) for s in status)
    if what == 1:
        raise IsoflowError(f"{where}: the {body} ends inside row {row} of element '{element.name}' "
                           f"(of {element.rows}): the file is cut short, or the header's counts do not match the data")
    if what == 2:
        raise IsoflowError(f"{where}: row {row} of element '{element.name}' gives its list "
                           f"'{element.properties[prop].name}' a count that is no whole number from 0 up")


def _assemble(got: dict[str, dict], elements: list[Element], where: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The vertices' coordinates (float64 (N, 3), each rounded to its
    declared type first, as trimesh casts them), the faces' corners (one
    polygon after another, int64) and their sizes."""
    vertex = next(e for e in elements if e.name == "vertex")
    kinds = {p.name: p.kind for p in vertex.properties}
    with np.errstate(over="ignore", invalid="ignore"):  # past a float32's range: inf, which check_mesh names
        xyz = np.stack([np.asarray(got["vertex"].get(c, ())).astype(kinds[c]).astype(np.float64) for c in "xyz"],
                       axis=1)
    face = next(e for e in elements if e.name == "face")
    corner = next(p for p in face.properties if p.name in _wanted(face))
    flat, sizes = got["face"][corner.name]
    if flat.dtype.kind == "f":  # an ASCII body: the text's numbers cast to the declared type, as trimesh does
        far = ~(np.abs(flat) < 2.0**62)
        if far.any():  # no vertex, and past what a cast keeps
            i = int(np.argmax(far))
            raise IsoflowError(f"{where}: face {_face_of(i, sizes)} names vertex {flat[i]!r}, which is no vertex's "
                               "number")
        with np.errstate(over="ignore", invalid="ignore"):
            flat = flat.astype(corner.kind)
    return xyz, flat.astype(np.int64), sizes.astype(np.int64)


@njit(cache=True, nogil=True)
def _scan_binary(buf, at, lists, sizes, counts, signed, big, want, places, lengths, status):
    """Walk the rows of a binary element whose lists have several lengths
    from byte ``at`` of ``buf``: where each wanted property begins
    (``places[row, want[p]]``; a list's items, after its count), the
    wanted list's lengths; the byte after the last row. ``status`` is left 0, or says (1: the body ends, 2: a negative
    count), the row and the property.

    Examples
    --------
    Two rows of a uchar count and int16 items, big-endian: [7], [8, 9].

    >>> buf = np.frombuffer(bytes([1, 0, 7, 2, 0, 8, 0, 9]), np.uint8)  # read-only, as the reader hands it
    >>> places, lengths, status = np.zeros((2, 1), np.int64), np.zeros(2, np.int64), np.zeros(3, np.int64)
    >>> one = np.ones(1, np.bool_)
    >>> _scan_binary(buf, 0, one, np.array([2]), np.array([1]), ~one, True, np.array([0]), places, lengths, status)
    8
    >>> places[:, 0].tolist(), lengths.tolist(), status.tolist()
    ([1, 4], [1, 2], [0, 0, 0])
    """
    n = len(buf)
    for r in range(len(lengths)):
        for p in range(len(lists)):
            if not lists[p]:
                if at + sizes[p] > n:
                    status[0], status[1], status[2] = 1, r, p
                    return at
                if want[p] >= 0:
                    places[r, want[p]] = at
                at += sizes[p]
                continue
            c = counts[p]
            if at + c > n:
                status[0], status[1], status[2] = 1, r, p
                return at
            k = np.uint64(0)
            for b in range(c):  # the count's bytes, least significant first
                k |= np.uint64(buf[at + (c - 1 - b if big else b)]) << np.uint64(8 * b)
            if signed[p] and k >= np.uint64(1) << np.uint64(8 * c - 1):
                status[0], status[1], status[2] = 2, r, p
                return at
            if k > np.uint64(n):
                status[0], status[1], status[2] = 1, r, p
                return at
            items = np.int64(k)
            if at + c + items * sizes[p] > n:
                status[0], status[1], status[2] = 1, r, p
                return at
            if want[p] >= 0:
                places[r, want[p]] = at + c
                lengths[r] = items
            at += c + items * sizes[p]
    return at


@njit(cache=True, nogil=True)
def _scan_words(tokens, at, lists, want, places, lengths, status):
    """:func:`_scan_binary` for an ASCII body's numbers (``tokens``):
    each scalar one number, each list its count and as many numbers;
    ``places`` of a list is its count's (2 in ``status``: a count that is
    no whole number from 0 up).

    Examples
    --------
    >>> places, lengths, status = np.zeros((2, 1), np.int64), np.zeros(2, np.int64), np.zeros(3, np.int64)
    >>> _scan_words(np.array([1.0, 7, 2, 8, 9]), 0, np.ones(1, np.bool_), np.array([0]), places, lengths, status)
    5
    >>> places[:, 0].tolist(), lengths.tolist()
    ([0, 2], [1, 2])
    """
    n = len(tokens)
    for r in range(len(lengths)):
        for p in range(len(lists)):
            if at >= n:
                status[0], status[1], status[2] = 1, r, p
                return at
            if want[p] >= 0:
                places[r, want[p]] = at
            if not lists[p]:
                at += 1
                continue
            k = tokens[at]
            if not (k >= 0 and k <= n and k == np.floor(k)):
                status[0], status[1], status[2] = 2, r, p
                return at
            items = np.int64(k)
            if at + 1 + items > n:
                status[0], status[1], status[2] = 1, r, p
                return at
            if want[p] >= 0:
                lengths[r] = items
            at += 1 + items
    return at


def _mesh(xyz: np.ndarray, corners: np.ndarray, sizes: np.ndarray, where: str) -> Mesh:
    """The vertices and the polygons as trimesh splits them (faces of
    fewer than three corners dropped, as trimesh drops them); IsoflowError
    for a corner that names no vertex."""
    nv = len(xyz)
    bad = (corners < 0) | (corners >= nv)
    if bad.any():
        i = int(np.argmax(bad))
        face = _face_of(i, sizes)
        numbered = f"numbered 0 to {nv - 1}" if nv else "none (the vertex element is empty)"
        raise IsoflowError(f"{where}: face {face} names vertex {int(corners[i])}, but the file's vertices are {numbered}")
    keep = sizes >= 3
    if not keep.all():
        corners, sizes = corners[np.repeat(keep, sizes)], sizes[keep]
    if not len(sizes):
        return xyz, np.zeros((0, 3), np.int64)
    return xyz, _split(corners, sizes, xyz)


def _face_of(i: int, sizes: np.ndarray) -> int:
    """The face (from 0) whose corners hold corner ``i`` of the faces'
    corners, one face after another."""
    return int(np.searchsorted(np.cumsum(sizes), i, side="right"))


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
