"""Plain NumPy readers for the simplest mesh files: binary and ASCII STL,
and OBJ files of vertices and faces (PLY: :mod:`isoflow.mesh.ply`, on
this module's helpers).

Each reader returns exactly the vertices and faces that ``trimesh.load``
(``process=False``, ``force="mesh"``) gives for the file, or ``None`` for
anything it does not recognise as simple, and the caller then asks trimesh;
except a concave polygon whose fan from its first corner would leave it,
which trimesh fans and :func:`triangulate` cuts by ears (an OBJ file that
trimesh reads is given to it with those cuts: :func:`concave_faces_cut`).
Saying ``None`` is always safe; guessing never is, so every reader refuses
at the first line it has not seen before.  An OBJ face index that names no
vertex is refused outright (:func:`obj_index_error` names its line): no
reader reads that file.  Used by
:func:`isoflow.mesh.load.load_mesh` so that a command on a plain file does
not import trimesh (and the scipy modules it pulls in).
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from ..errors import IsoflowError, counted

Mesh = tuple[np.ndarray, np.ndarray]

_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attribute", "<u2")])
_OBJ_IGNORED = frozenset((b"#", b"vt", b"vn", b"o", b"g", b"s", b"mtllib"))
#: the bytes ``bytes.split()`` splits at
_SPACE = np.isin(np.arange(256), list(b" \t\n\r\x0b\x0c"))
#: the bytes of a face line's words and the spaces between them
_FACE_BYTES = np.isin(np.arange(256), list(b"0123456789-/ \t\n"))
#: the bytes of a text file's lines
_TEXT = bytes(range(32, 127)) + b"\t\n\r"
#: polygons whose fans :func:`_cut_by_ears` tests at a time
_CHUNK = 1 << 16


def read_simple(path: Path) -> Mesh | None:
    """Vertices (float64 (N, 3)) and faces (int64 (M, 3)) of a plain STL or
    OBJ file read as trimesh reads it, or ``None`` where trimesh should read it.
    An OBJ face index that names no vertex raises :class:`IsoflowError`
    naming its line (:func:`obj_index_error`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "t.obj"
    >>> _ = p.write_text("v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nv 0 0 1\\nf 1 2 3 4\\n")
    >>> v, f = read_simple(p)
    >>> f.tolist()
    [[0, 1, 2], [2, 3, 0]]
    """
    suffix = path.suffix.lower()
    if suffix not in (".stl", ".obj"):
        return None
    try:
        data = path.read_bytes()
    except OSError:
        return None  # trimesh's path says what is wrong with the file
    if suffix == ".stl":
        return read_stl(data)
    try:
        return read_obj(data)
    except BadFaceIndex:
        message = obj_index_error(path, data)
        if message is None:  # (the line scan and the vectorised check disagree: trimesh's path says it)
            return None
        raise IsoflowError(message) from None


def read_stl(data: bytes) -> Mesh | None:
    """A binary STL (80-byte header, count, 50-byte records; read as binary
    whenever the size says so, as trimesh does) or an ASCII STL of one solid
    (its "endsolid" line may be missing after a whole last facet): three
    corners per facet, none shared."""
    n = _binary_facets(data)
    if n is not None:
        if n == 0:
            return None
        rec = np.frombuffer(data, _STL_RECORD, n, 84)
        return _soup(rec["corners"].reshape(-1, 3).astype(np.float64))
    return _read_stl_ascii(data)


def _binary_facets(data: bytes) -> int | None:
    """The facets of a binary STL, where the file's size is its header,
    count and 50-byte records (as trimesh tells a binary STL); None for any
    other file."""
    if len(data) >= 84:
        n = int(np.frombuffer(data, "<u4", 1, 80)[0])
        if len(data) == 84 + 50 * n:
            return n
    return None


#: a ``solid NAME`` or ``endsolid NAME`` line of an ASCII STL: its keyword and the rest of the line
_SOLID_LINE = re.compile(rb"^[ \t]*(end)?solid(?=[ \t\r\n]|$)([^\r\n]*)", re.MULTILINE | re.IGNORECASE)


def stl_solids(data: bytes) -> list[tuple[str, Mesh]] | None:
    """The solids of an ASCII STL file, in the file's order: each one's
    name as its ``solid`` line gives it (``""`` where it gives none) and
    its triangles as :func:`read_stl` reads a file of that solid alone. A
    solid without a facet is left out, as trimesh leaves it out.

    Parameters
    ----------
    data : bytes
        The file's bytes.

    Returns
    -------
    list of (str, (ndarray, ndarray)) or None
        None for a binary STL, and where the file is not ``solid`` ...
        ``endsolid`` blocks alone or a solid's facets are not read as
        :func:`read_stl` reads them (trimesh's reading of the whole file
        is then the one to take).

    Examples
    --------
    >>> facet = b"facet normal 0 0 1\\nouter loop\\nvertex 0 0 0\\nvertex 1 0 0\\nvertex 0 1 0\\nendloop\\nendfacet\\n"
    >>> solids = stl_solids(b"solid lid\\n" + facet + b"endsolid lid\\nsolid\\n" + facet * 2 + b"endsolid\\n")
    >>> [(name, len(f)) for name, (v, f) in solids]
    [('lid', 1), ('', 2)]
    """
    if _binary_facets(data) is not None:
        return None  # binary, as read_stl reads it: a binary STL has no solid names
    lines = list(_SOLID_LINE.finditer(data))
    if not lines or [bool(m[1]) for m in lines] != [False, True] * ((len(lines) + 1) // 2):
        return None  # not solid, endsolid, solid, endsolid, ... (a solid left unended too)
    ends = [0] + [m.end() for m in lines[1::2]]
    if any(data[a:b].strip() for a, b in zip(ends, [m.start() for m in lines[::2]] + [len(data)])):
        return None  # text between the solids
    solids = []
    for start, end in zip(lines[::2], lines[1::2]):
        body = data[start.end():end.start()]
        if b"vertex" not in body.lower():
            continue
        mesh = _read_stl_ascii(b"solid\n" + body + b"\nendsolid\n")
        if mesh is None:
            return None
        solids.append((start[2].strip().decode("utf-8", "replace"), mesh))
    return solids


def stl_size_error(path, data: bytes) -> str | None:
    """Why a file that is no ASCII STL gave no triangles as a binary one:
    the line naming its size against the 84 bytes plus 50 per facet that
    its header counts (a file truncated, padded after its facets, or whose
    count a writer left wrong), or ``None`` where the size is right, the
    file holds no whole facet of numbers or it reads as ASCII.

    Examples
    --------
    >>> data = bytes(80) + (2).to_bytes(4, "little") + bytes(110)
    >>> print(stl_size_error("t.stl", data))
    t.stl: no triangles read: as a binary STL its header counts 2 facets (184 bytes), but the file has
    194 bytes (2 facets and 10 bytes after the header): truncated, padded, or its facet count is wrong
    """
    head = data[:1024]
    if len(data) < 84 or not head.translate(None, _TEXT):
        return None  # text (an ASCII STL among it), not a header and facets: the reader's own line
    n = int(np.frombuffer(data, "<u4", 1, 80)[0])
    whole, rest = divmod(len(data) - 84, 50)
    if len(data) == 84 + 50 * n or not whole:
        return None
    # facets that hold numbers, as a file of other bytes would not: a NaN,
    # an infinity or 1e30 among them says the file is no STL at all
    rec = np.frombuffer(data, _STL_RECORD, min(whole, 10_000), 84)
    values = np.concatenate((rec["normal"].ravel(), rec["corners"].ravel()))
    if not (np.abs(values) < 1e30).all():
        return None
    held = counted(whole, "facet") + (f" and {rest} bytes" if rest else "")
    return (f"{path}: no triangles read: as a binary STL its header counts {counted(n, 'facet')} "
            f"({84 + 50 * n} bytes), but the file has {len(data)} bytes ({held} after the header): "
            "truncated, padded, or its facet count is wrong")


def stl_text_error(path, data: bytes) -> str | None:
    """The one line naming the first fault of an ASCII STL file's facets:
    a ``vertex`` line whose word is not a number (a decimal comma) or that
    holds other than three, a loop of other than three vertices, or a file
    that ends inside a facet (cut short); ``None`` where there is none or
    the file is no ASCII STL.  trimesh says "cannot reshape array of size
    37 into shape (3)", or reads no triangle at all.

    Parameters
    ----------
    path : str or os.PathLike
        The STL file's name, for the message.
    data : bytes
        Its bytes: a text file of ``solid``, ``facet``, ``vertex`` ... lines.

    Returns
    -------
    str or None
        ``path:LINE: ...``, or ``path: ...`` for a file cut short.

    Examples
    --------
    >>> loop = b"facet normal 0 0 1\\nouter loop\\nvertex 0 0 0\\nvertex 1 0 0\\nvertex 0 1 0\\n"
    >>> stl_text_error("t.stl", b"solid t\\n" + loop + b"vertex 1 1 0\\nendloop\\nendfacet\\nendsolid t\\n")
    "t.stl:8: 'endloop': facet 1's loop has 4 vertices, where an STL facet has 3"
    >>> stl_text_error("t.stl", b"solid t\\n" + loop.replace(b"1 0 0", b"1,5 0 0"))
    "t.stl:5: 'vertex 1,5 0 0': '1,5' is not a coordinate (STL writes decimals with a point: 1.5)"
    >>> stl_text_error("t.stl", b"solid t\\n" + loop)
    't.stl: the file ends inside facet 1 (line 2, its last): cut short'
    """
    if not data.lstrip()[:5].lower() == b"solid" or data[:4096].translate(None, _TEXT):
        return None  # a binary STL whose header starts "solid": its size says what is wrong
    facet, corners, opened = 0, 0, None
    lines = data.splitlines()
    for lineno, line in enumerate(lines, 1):
        words = line.lower().split()
        head = words[0] if words else b""
        if head == b"facet":
            facet, corners, opened = facet + 1, 0, lineno
        elif head == b"vertex":
            bad = _bad_obj_word([b"v", *line.split()[1:]])
            if bad is not None:
                return f"{path}:{lineno}: {shown_line(line)!r}: {bad.replace('OBJ', 'STL')}"
            corners += 1
        elif head == b"endloop" and corners != 3:
            return (f"{path}:{lineno}: {shown_line(line)!r}: facet {facet}'s loop has "
                    f"{counted(corners, 'vertex', 'vertices')}, where an STL facet has 3")
        elif head == b"endfacet":
            opened = None
    if opened is not None:
        return f"{path}: the file ends inside facet {facet} (line {opened}, its last): cut short"
    return None


def _read_stl_ascii(data: bytes) -> Mesh | None:
    low = data.lower()
    # a solid whose last facet is whole but whose "endsolid" line is missing (a writer that left it
    # out, a file cut at a facet's end) is read: trimesh reads no triangles of it, pymeshlab all
    unended = low.count(b"endsolid") == 0 and low.rstrip().endswith(b"endfacet")
    if not low.lstrip().startswith(b"solid") or not unended and (
            low.count(b"endsolid") != 1 or low.rfind(b"vertex") > low.find(b"endsolid")):
        return None  # several solids (or none): trimesh's scene of them
    lines = [ln.split() for ln in low.splitlines()]
    corners = [w[1:] for w in lines if w[:1] == [b"vertex"]]
    if not corners or len(corners) != low.count(b"vertex") or len(corners) % 3:
        return None
    if any(len(c) != 3 for c in corners):
        return None
    v = numbers(b" ".join(b" ".join(c) for c in corners), np.float64, 3 * len(corners))
    return None if v is None else _soup(v.reshape(-1, 3))


def _soup(v: np.ndarray) -> Mesh:
    """Every three consecutive corners a triangle of their own."""
    return v, np.arange(len(v), dtype=np.int64).reshape(-1, 3)


def read_obj(data: bytes, *, ears: bool = True) -> Mesh | None:
    """An OBJ file of ``v`` and ``f`` lines (``vt``, ``vn``, ``#``, ``o``,
    ``g``, ``s``, ``mtllib`` and one material's ``usemtl`` lines ignored).

    Faces use the position indices only; a polygon is split as trimesh
    splits it (quads of a file of quads as two blocks, first triangles then
    second; other polygons as fans) unless its fan would leave it (a
    concave polygon: cut by ears, :func:`triangulate`; with ``ears``
    False fanned too, as trimesh fans it: then the faces are trimesh's
    every one); vertices no face uses are dropped.
    Negative indices are read only where every ``v`` line comes before every
    ``f`` line (there trimesh's count from the end and OBJ's count back from
    the face agree), and with ``/`` only where every index is negative.

    Raises :class:`BadFaceIndex` where a face's position index is 0 or
    beyond the vertices (either way): :func:`obj_index_error` names it."""
    if b"\\" in data or data.startswith(b"\xef\xbb\xbf"):
        return None  # line continuations and byte-order marks: trimesh's rules
    data = data.replace(b"\r\n", b"\n")
    if b"\r" in data:
        return None  # lines ended by CR alone: not lines to trimesh
    # the lines told apart by their first two bytes, on the file's bytes
    # as one array (no Python object per line)
    a = np.frombuffer(data, np.uint8)
    ends = np.flatnonzero(a == 10)
    starts = np.concatenate(([0], ends + 1))
    ends = np.append(ends, len(a))
    is_v, is_f = _heads(a, starts, ends, b"v "), _heads(a, starts, ends, b"f ")
    v_at, f_at = np.flatnonzero(is_v), np.flatnonzero(is_f)
    if not len(v_at) or not len(f_at):
        return None
    # the other lines, in order, and the first face line as "f" (the only
    # face line :func:`_only_ignored` needs: where faces begin)
    others = np.flatnonzero(~is_v & (~is_f | (np.arange(len(starts)) == f_at[0])))
    rest = [b"f" if is_f[i] else data[starts[i]:ends[i]] for i in others.tolist()]
    if not _only_ignored(rest):
        return None
    v_text = _tails(a, starts, ends, is_v)
    if not (words_per_line(v_text) == 3).all():
        return None  # four or six numbers a line: trimesh's w or colours
    v_text[v_text == 10] = 32  # the lines' numbers as one line
    v = numbers(v_text.tobytes(), np.float64, 3 * len(v_at))
    if v is None:
        return None
    v = v.reshape(-1, 3)
    first_line = data[starts[f_at[0]] + 2:ends[f_at[0]]]
    faces = _obj_faces(first_line, _tails(a, starts, ends, is_f), len(f_at), v if ears else None,
                       negatives_ok=v_at[-1] < f_at[0], vertices=len(v))
    if faces is None:
        return None
    used = np.zeros(len(v), dtype=bool)
    used[faces] = True
    inverse = np.cumsum(used) - 1  # the used vertices, in file order
    return v[used], inverse[faces]


def _heads(a: np.ndarray, starts: np.ndarray, ends: np.ndarray, head: bytes) -> np.ndarray:
    """Which lines (from ``starts`` to ``ends`` in the bytes ``a``) begin
    with the two bytes ``head``."""
    long = ends - starts >= 2
    if not long.any():
        return long
    first = a[np.where(long, starts, 0)]
    second = a[np.where(long, starts + 1, 0)]
    return long & (first == head[0]) & (second == head[1])


def _tails(a: np.ndarray, starts: np.ndarray, ends: np.ndarray, which: np.ndarray) -> np.ndarray:
    """The text after the first two bytes of the lines ``which`` (from
    ``starts`` to ``ends`` in the bytes ``a``, each but the last followed
    by a newline): ``b"\\n".join(tails)``, as a new array."""
    newline = np.ones(len(starts), np.int64)
    newline[-1] = 0
    # each line as three runs of bytes: its head, its tail and its newline,
    # the last two kept where the line is one of ``which``
    keep = np.repeat(np.stack([np.zeros(len(starts), bool), which, which], axis=1).ravel(),
                     np.stack([np.where(which, 2, ends - starts + newline), np.where(which, ends - starts - 2, 0),
                               np.where(which, newline, 0)], axis=1).ravel())
    text = a[keep]
    return text[:-1] if len(text) and text[-1] == 10 else text


def words_per_line(text: np.ndarray) -> np.ndarray:
    """The number of words ``bytes.split`` finds on each line of ``text``
    (bytes, lines ended by newlines; no carriage returns).

    Examples
    --------
    >>> words_per_line(np.frombuffer(b"3 0 1 2\\n\\n 4  0 1 2 3", np.uint8)).tolist()
    [4, 0, 5]
    """
    space = _SPACE[text]
    start = np.flatnonzero(~space & np.r_[True, space[:-1]])
    newline = np.flatnonzero(text == 10)
    return np.diff(np.r_[0, np.searchsorted(start, newline), len(start)])


def _only_ignored(lines: list[bytes]) -> bool:
    """Whether the lines other than ``v`` (each face line given as ``f``)
    are blank or ones the reader ignores, with at most one material, named
    before the first face (trimesh makes a mesh of each material, and of
    the faces before the first, and concatenates them in its own order)."""
    materials: set[bytes] = set()
    attributes: dict[bytes, list[list[bytes]]] = {b"vt": [], b"vn": []}
    first_material = first_face = len(lines)
    for i, line in enumerate(lines):
        if line == b"f":
            first_face = min(first_face, i)
            continue
        words = line.split()
        if not words:
            continue
        if line[:1].isspace():
            return False
        key = words[0]
        if key == b"usemtl" and len(words) == 2:
            materials.add(words[1])
            first_material = min(first_material, i)
        elif key in attributes:
            attributes[key].append(words[1:])
        elif key not in _OBJ_IGNORED and not key.startswith(b"#"):
            return False
    if materials and (len(materials) > 1 or first_material > first_face):
        return False
    return all(_table(rows) for rows in attributes.values())


def _table(rows: list[list[bytes]]) -> bool:
    """Whether ``vt`` or ``vn`` lines hold numbers, as many on each line
    (where they do not, trimesh's reader may fail, or clip them)."""
    if not rows:
        return True
    n = len(rows[0])
    return all(len(r) == n for r in rows) and numbers(b" ".join(w for r in rows for w in r), np.float64,
                                                       n * len(rows)) is not None


def numbers(text: bytes, dtype, count: int) -> np.ndarray | None:
    """``count`` numbers parsed as trimesh parses them (``np.fromstring``),
    or None where the text holds anything else.

    Examples
    --------
    >>> numbers(b"1 2.5e0\\n-3", np.float64, 3).tolist(), numbers(b"1 x", np.float64, 2)
    ([1.0, 2.5, -3.0], None)
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)  # text it cannot read to its end
            a = np.fromstring(text.decode("ascii"), dtype=dtype, sep=" ")
    except (UnicodeDecodeError, ValueError):
        return None
    return a if len(a) == count else None


def _obj_faces(first_line: bytes, text: np.ndarray, n_lines: int, v: np.ndarray | None, *,
               negatives_ok: bool, vertices: int) -> np.ndarray | None:
    """Triangles (position indices from 0) of the face lines, ``text``
    their text after ``f`` joined by newlines (bytes, a new array: changed
    here), ``first_line`` the first one's, over ``vertices`` positions
    ``v``, which tell a concave polygon to cut by ears (None: every polygon
    fanned); or ``None``."""
    nv = vertices
    first = first_line.split()[0]
    form = 2 if b"//" in first else 3 if first.count(b"/") == 2 else first.count(b"/")
    if form > 3:
        return None
    sizes = _face_sizes(text, form, n_lines)
    if sizes is None or sizes.min() < 3:
        return None
    per = (1, 2, 2, 3)[form]  # numbers per corner: i; i/j; i//k; i/j/k
    text[text == 47] = 32
    nums = numbers(text.tobytes(), np.int64, per * int(sizes.sum()))
    if nums is None:
        return None
    flat = nums[::per]
    if (flat == 0).any() or (flat > nv).any() or (flat < -nv).any():
        raise BadFaceIndex  # trimesh fails with an IndexError or reads 0 as vertex 1: the file is wrong
    negative = flat < 0
    if negative.any() and (not negatives_ok or (form != 0 and not negative.all())):
        return None  # trimesh sorts texture-split corners by raw index: negatives before the others
    return triangulate(np.where(flat > 0, flat - 1, flat + nv), sizes, v)


class BadFaceIndex(ValueError):
    """An OBJ face index that names no vertex (0, or beyond the vertices)."""


def obj_index_error(path, data: bytes) -> str | None:
    """The one line that names the first face of an OBJ file whose position
    index names no vertex, or ``None`` where every index names one.

    A positive index must be at most the file's number of ``v`` lines (as
    trimesh counts; OBJ's readers differ on vertices listed after the face),
    0 names none (OBJ counts from 1), and a negative one counts back from
    its line over the ``v`` lines above it.  The file is read line by line
    in Python (seconds for a million faces), so only once a reader has
    found a bad index, or suspects one (:func:`may_name_vertex_0`).

    Parameters
    ----------
    path : str or os.PathLike
        The file's name, as the line shows it.
    data : bytes
        The file's contents.

    Returns
    -------
    str or None
        ``path:LINE: face 'f ...' uses vertex index K, ...``.

    Examples
    --------
    >>> obj_index_error("t.obj", b"v 0 0 0\\nv 1 0 0\\nv 0 1 0\\n# x\\nf 1 2 4\\n")
    "t.obj:5: face 'f 1 2 4' uses vertex index 4, past the file's 3 vertices"
    """
    lines = data.removeprefix(b"\xef\xbb\xbf").splitlines()  # CR, LF or CRLF: an editor's lines
    total = sum(1 for ln in lines if ln.split()[:1] == [b"v"])
    seen = 0  # v lines above the current line: what a negative index counts back over
    for lineno, line in enumerate(lines, 1):
        words = line.split(b"#", 1)[0].split()
        if words[:1] == [b"v"]:
            seen += 1
        elif words[:1] == [b"f"]:
            for word in words[1:]:
                written = word.split(b"/", 1)[0]
                try:
                    k = int(written)
                except ValueError:
                    continue  # not a number: the reader's own message says so
                if 0 < k <= total or -seen <= k < 0:
                    continue
                shown = shown_line(line)
                if k > 0:
                    why = ("but the file has no vertices (no 'v x y z' line)" if not total else
                           "past the file's " + ("only vertex" if total == 1 else f"{total} vertices"))
                elif k < 0:
                    before = "1 vertex comes" if seen == 1 else f"{seen} vertices come"
                    why = f"before the first vertex ({before} before the face; -1 is the last of them)"
                else:
                    why = "but OBJ numbers vertices from 1 (-1 for the last)"
                return f"{path}:{lineno}: face {shown!r} uses vertex index {written.decode()}, {why}"
    return None


#: a number as an OBJ reader parses one (C's strtod, NumPy's fromstring)
_NUMBER = re.compile(rb"[+-]?((\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|inf(inity)?|nan)", re.IGNORECASE)
#: what each kind of OBJ line holds, by its first word: a number per word
_OBJ_NUMBERS = {b"v": "a coordinate", b"vt": "a texture coordinate", b"vn": "a normal's coordinate"}


def obj_number_error(path, data: bytes) -> str | None:
    """The one line that names the first ``v``, ``vt``, ``vn`` or ``f``
    line of an OBJ file holding a word that is not the number it must be
    (a decimal comma, a stray letter), or a ``v`` line with fewer than
    three coordinates, or ``None`` where there is none.  trimesh says only
    "string or file could not be read to its end due to unmatched data".

    Parameters
    ----------
    path : str or os.PathLike
        The file, as the line names it.
    data : bytes
        What the file holds.

    Returns
    -------
    str or None
        ``path:LINE: 'v 0,5 0 0': '0,5' is not a coordinate``, with a hint
        for a decimal comma.

    Examples
    --------
    >>> obj_number_error("t.obj", b"v 0 0 0\\nv 0,5 1 0\\nv 0 1 0\\nf 1 2 3\\n")
    "t.obj:2: 'v 0,5 1 0': '0,5' is not a coordinate (OBJ writes decimals with a point: 0.5)"
    >>> obj_number_error("t.obj", b"v 0 0\\n"), obj_number_error("t.obj", b"v 0 0 0\\nf 1/1 2//3 -1\\n")
    ("t.obj:1: 'v 0 0': 2 coordinates, where a vertex has 3 (x y z)", None)
    """
    for lineno, line in enumerate(data.removeprefix(b"\xef\xbb\xbf").splitlines(), 1):
        words = line.split(b"#", 1)[0].split()
        bad = _bad_obj_word(words)
        if bad is None:
            continue
        return f"{path}:{lineno}: {shown_line(line)!r}: {bad}"
    return None


def _bad_obj_word(words: list[bytes]) -> str | None:
    """What is wrong with an OBJ line's words, or None (a line of a kind
    that holds no numbers, or whose numbers are numbers)."""
    head = words[0] if words else b""
    if head == b"f":
        for word in words[1:]:
            parts = word.split(b"/")
            if not all(q.lstrip(b"-").isdigit() for q in parts[:1]) or not all(
                    q.lstrip(b"-").isdigit() or not q for q in parts[1:3]) or len(parts) > 3:
                return f"{word.decode(errors='replace')!r} is not a vertex index (i, i/t, i//n or i/t/n)"
        return None
    what = _OBJ_NUMBERS.get(head)
    if what is None:
        return None
    for word in words[1:]:
        if _NUMBER.fullmatch(word) is None:
            shown = word.decode(errors="replace")
            comma = _NUMBER.fullmatch(word.replace(b",", b".", 1)) is not None
            hint = f" (OBJ writes decimals with a point: {shown.replace(',', '.', 1)})" if comma else ""
            return f"{shown!r} is not {what}{hint}"
    if head == b"v" and len(words) < 4:
        return f"{len(words) - 1} coordinate{'s' if len(words) != 2 else ''}, where a vertex has 3 (x y z)"
    return None


def shown_line(line: bytes) -> str:
    """A file's line as a message quotes it: stripped, at most 60 characters.

    Examples
    --------
    >>> shown_line(b"  f 1 2 3 "), len(shown_line(b"f " + b"1 " * 40))
    ('f 1 2 3', 60)
    """
    shown = line.strip().decode(errors="replace")
    return shown if len(shown) <= 60 else shown[:57] + "..."


def may_name_vertex_0(data: bytes) -> bool:
    """Whether an ``f`` line of an OBJ file may hold a position index 0 (or
    -0): a word ``0`` or ``0/...`` on a line that starts ``f``.  trimesh
    reads it as the first vertex without a word.  Vectorised, for the files
    trimesh reads: about a second for 100 MB, where trimesh takes eight and
    a line-by-line search ten."""
    a = np.frombuffer(data, np.uint8)
    z = np.flatnonzero(a[1:] == 48) + 1  # a 0 not the file's first byte
    after = a[np.minimum(z + 1, len(a) - 1)]
    z = z[(z + 1 == len(a)) | (after == 47) | (after == 32) | (after == 9) | (after == 10) | (after == 13)]
    z = z - (a[z - 1] == 45)  # '-0' starts at its sign
    before = a[z - 1]
    z = z[(before == 32) | (before == 9)]
    newline = np.flatnonzero(a == 10)
    start = np.concatenate(([0], newline + 1))[np.searchsorted(newline, z)]
    second = a[np.minimum(start + 1, len(a) - 1)]
    return bool(((a[start] == 102) & ((second == 32) | (second == 9))).any())


def relative_indices_resolved(data: bytes) -> bytes | None:
    """An OBJ file's text with each relative (negative) index of its ``f``
    lines written as the index from 1 that it names, where a ``v``, ``vt``
    or ``vn`` line follows a face with one; None where none does.

    OBJ counts a relative index back from its face's line (-1: the last
    vertex above it), trimesh from the end of the file.  The two agree
    unless vertices follow the face, as in a file of several objects each
    written with relative indices, where trimesh's count gives every
    object the last one's vertices.  A position index before the first
    vertex is written 0, which the readers refuse (:func:`obj_index_error`
    names its line in the file as written).

    Examples
    --------
    >>> relative_indices_resolved(b"v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf -3 -2 -1\\nv 0 0 1\\nf -4 -2 -1 # c -1\\n")
    b'v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\nv 0 0 1\\nf 1 3 4 # c -1\\n'
    >>> relative_indices_resolved(b"v 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf -3 -2 -1\\n") is None
    True
    """
    a = np.frombuffer(data, np.uint8)
    # a sign after a space or tab, on a line that starts "f ": the first
    # relative index; vectorised, as most files have none
    sign = np.flatnonzero(a[1:] == 45) + 1
    sign = sign[(a[sign - 1] == 32) | (a[sign - 1] == 9)]
    newline = np.flatnonzero(a == 10)
    start = np.concatenate(([0], newline + 1))[np.searchsorted(newline, sign)]
    second = a[np.minimum(start + 1, len(a) - 1)]
    sign = sign[(a[start] == 102) & ((second == 32) | (second == 9))]
    if not len(sign) or data.find(b"\nv", int(sign[0])) < 0:
        return None  # no vertex after a relative index: trimesh's count is OBJ's
    seen = [0, 0, 0]  # v, vt and vn lines so far
    slot = {b"v": 0, b"vt": 1, b"vn": 2}
    lines = data.split(b"\n")
    for i, line in enumerate(lines):
        code, hash_, comment = line.partition(b"#")
        words = code.split()
        if words and words[0] in slot:
            seen[slot[words[0]]] += 1
        elif words[:1] == [b"f"] and b"-" in code:
            lines[i] = b" ".join([b"f"] + [_absolute(w, seen) for w in words[1:]]) + (
                b" " + hash_ + comment if hash_ else b"") + (b"\r" if line.endswith(b"\r") and not hash_ else b"")
    return b"\n".join(lines)


def concave_faces_cut(data: bytes) -> bytes | None:
    """An OBJ file's text with each face line whose polygon :func:`triangulate`
    cuts by ears (a concave polygon whose fan would cross its notch) written
    as those triangles, one ``f`` line each of the corners' words as written
    (texture and normal indices kept); None where no face line needs it.

    For the files trimesh reads (several materials, vertex colours, ...):
    trimesh fans every polygon. Relative indices are counted from the end of
    the file, as trimesh counts them (:func:`relative_indices_resolved`
    first, where the two counts differ); a file this cannot read (a face
    index that names no vertex, line continuations) is left as it is, for
    trimesh to read or name what is wrong.

    Examples
    --------
    >>> L = b"v 2 0 0\\nv 2 1 0\\nv 1 1 0\\nv 1 2 0\\nv 0 2 0\\nv 0 0 0\\nusemtl a\\n"
    >>> concave_faces_cut(L + b"f 1/1 2/1 3/1 4/1 5/1 6/1\\n").split(b"\\n")[7:]
    [b'f 3/1 4/1 5/1', b'f 3/1 5/1 6/1', b'f 1/1 2/1 3/1', b'f 6/1 1/1 3/1', b'']
    >>> concave_faces_cut(L + b"f 6 5 4 3 2 1\\n") is None  # from (0, 0) the fan stays in the L
    True
    """
    a = np.frombuffer(data, np.uint8)
    start = np.concatenate(([0], np.flatnonzero(a == 10) + 1))
    # a face of four corners or more, found without a Python line loop: most files have none
    head = np.r_[a, 0, 0][np.minimum(start[:, None] + [0, 1], len(a) + 1)]
    if b"\\" in data or not ((head[:, 0] == 102) & _SPACE[head[:, 1]] & (words_per_line(a) > 4)).any():
        return None
    lines = data.split(b"\n")
    positions, polygons = [], []
    for i, line in enumerate(lines):
        words = line.split(b"#", 1)[0].split()
        if words[:1] == [b"v"]:
            positions.append(words[1:4])
        elif words[:1] == [b"f"] and len(words) > 4:
            polygons.append((i, words[1:]))
    try:
        v = np.array(positions, dtype=np.float64).reshape(-1, 3)
        flat = np.array([int(w.split(b"/", 1)[0]) for _, words in polygons for w in words], dtype=np.int64)
    except ValueError:
        return None
    if not len(flat) or (flat == 0).any() or (np.abs(flat) > len(v)).any():
        return None
    flat = np.where(flat > 0, flat - 1, flat + len(v))
    sizes = np.array([len(words) for _, words in polygons], dtype=np.int64)
    # cut by places in ``flat``: which polygon, and which of its words, each corner is
    at = triangulate(np.arange(len(flat)), sizes, v[flat])
    first = np.cumsum(sizes) - sizes
    owner = np.searchsorted(first, at[:, 0], side="right") - 1
    changed = np.unique(owner[(at != triangulate(np.arange(len(flat)), sizes)).any(axis=1)])
    if not len(changed):
        return None
    order = np.argsort(owner, kind="stable")  # each polygon's triangles together, in the fan's order
    row = np.cumsum(sizes - 2) - (sizes - 2)
    for p in changed.tolist():
        i, words = polygons[p]
        end = b"\r" if lines[i].endswith(b"\r") else b""
        cut = at[order[row[p]:row[p] + sizes[p] - 2]] - first[p]
        lines[i] = b"\n".join(b"f " + b" ".join(words[c] for c in t) + end for t in cut.tolist())
    return b"\n".join(lines)


def _absolute(word: bytes, seen: list[int]) -> bytes:
    """A face word ``i``, ``i/j``, ``i//k`` or ``i/j/k`` with its relative
    indices counted back over the ``seen`` vertex, texture and normal lines
    (a position before the first written 0, which names none)."""
    parts = word.split(b"/")
    for n, part in enumerate(parts[:3]):
        if part.startswith(b"-") and part[1:].isdigit():
            k = seen[n] + 1 + int(part)
            parts[n] = str(k if k >= 1 or n else 0).encode()
    return b"/".join(parts)


def _face_sizes(a: np.ndarray, form: int, n_lines: int) -> np.ndarray | None:
    """The number of corners on each line of face words (bytes ``a``), or
    ``None`` unless every word has the first word's form: ``i`` (form 0),
    ``i/j`` (1), ``i//k`` (2) or ``i/j/k`` (3), each number ``-?[0-9]+``.

    Only the signs and slashes are looked at one by one (their neighbours
    say whether they sit in a number's place); a word whose signs and
    slashes all do ends in a digit."""
    if not _FACE_BYTES[a].all():
        return None
    padded = np.concatenate(([32], a, [32]))  # a space before and after
    space = padded <= 32  # (tab, newline and space: the only bytes below 33 left)
    start = np.flatnonzero(~space[1:-1] & space[:-2])
    double = form == 2
    minus, slash = np.flatnonzero(a == 45), np.flatnonzero(a == 47)
    for at, before, after in ((minus, b" \t\n/", b"0123456789"),
                              (slash, b"0123456789" + b"/" * double, b"0123456789-" + b"/" * double)):
        if len(at) and not (np.isin(padded[at], list(before)).all() and np.isin(padded[at + 2], list(after)).all()):
            return None
    # slashes sit inside words (a digit or slash either side): those between
    # one word's start and the next are that word's
    per_word = np.diff(np.r_[np.searchsorted(slash, start), len(slash)])
    if (per_word != (0, 1, 2, 2)[form]).any():
        return None
    if double and np.count_nonzero(padded[slash + 2] == 47) != len(start):
        return None
    newline = np.flatnonzero(a == 10)
    return np.bincount(np.searchsorted(newline, start), minlength=n_lines)


def triangulate(flat: np.ndarray, sizes: np.ndarray, vertices: np.ndarray | None = None) -> np.ndarray:
    """Triangles of polygons, each polygon's in its own orientation.

    Every polygon is first cut as trimesh cuts it: a file of quads only as
    all first halves, then all second halves; otherwise each polygon in
    turn as a fan from its first corner (a quad among others as (0, 1, 2),
    (2, 3, 0)). Given ``vertices``, a polygon whose fan leaves it (a
    concave polygon, an L or a U, whose first corner does not see every
    other corner) is cut by ear clipping in the plane of its Newell normal
    instead (:func:`_ear_cuts`), its triangles in the rows its fan had.

    Parameters
    ----------
    flat : numpy.ndarray
        The polygons' corners (vertex indices), one polygon after another.
    sizes : numpy.ndarray
        The number of corners of each polygon, each at least 3.
    vertices : numpy.ndarray, optional
        float64 (N, 3) positions of the vertices ``flat`` names; without
        them every polygon is fanned.

    Returns
    -------
    numpy.ndarray
        The triangles (M, 3), ``sizes - 2`` of them per polygon.

    Notes
    -----
    A polygon keeps its fan wherever every fan triangle turns the way of
    the polygon's Newell normal (convex polygons, and concave ones whose
    first corner sees all the others): there the fan covers the polygon
    once. So does a polygon of no area (a spike ``1 2 3 2``: two triangles
    that cancel in the winding number). A polygon off its plane by more
    than 1e-6 of its size and coordinates (non-planar, past rounding), or
    whose ear cut has a triangle turned against the polygon (self-crossing,
    a bow tie), keeps its fan as well, as trimesh cuts it: the fan's
    winding number is the polygon's.

    Examples
    --------
    >>> triangulate(np.arange(8), np.array([4, 4])).tolist()
    [[0, 1, 2], [4, 5, 6], [2, 3, 0], [6, 7, 4]]
    >>> triangulate(np.arange(7), np.array([3, 4])).tolist()
    [[0, 1, 2], [3, 4, 5], [5, 6, 3]]

    An L from a corner that does not see the far end of the L: its fan's
    second triangle (2, 0) (1, 1) (1, 2) would lie in the notch, turned
    against the L, so the L is cut by ears.

    >>> L = np.array([[2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0], [0, 0, 0]], float)
    >>> triangulate(np.arange(6), np.array([6]))[1].tolist()
    [0, 2, 3]
    >>> triangulate(np.arange(6), np.array([6]), L).tolist()
    [[2, 3, 4], [2, 4, 5], [0, 1, 2], [5, 0, 2]]
    """
    if (sizes == 3).all():
        return flat.reshape(-1, 3)
    at = _fan(np.arange(len(flat)), sizes)  # where in ``flat`` each corner of each triangle is
    if vertices is not None:
        _cut_by_ears(at, flat, sizes, vertices)
    return flat[at]


def _fan(flat: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """The polygons as trimesh cuts them (see :func:`triangulate`)."""
    k = int(sizes[0])
    if (sizes == 3).all():
        return flat.reshape(-1, 3)
    if (sizes == 4).all():
        q = flat.reshape(-1, 4)
        return np.vstack((q[:, [0, 1, 2]], q[:, [2, 3, 0]]))
    if (sizes == k).all():
        p = flat.reshape(-1, k)
        j = np.arange(1, k - 1)
        return np.stack((np.repeat(p[:, :1], k - 2, axis=1), p[:, j], p[:, j + 1]), axis=2).reshape(-1, 3)
    # polygons of several sizes, each in turn: triangle t of a polygon from
    # corner s is (s, s + t + 1, s + t + 2), but a quad's second is (2, 3, 0)
    start = np.cumsum(sizes) - sizes
    owner = np.repeat(np.arange(len(sizes)), sizes - 2)
    s = start[owner]
    t = np.arange(len(owner)) - np.repeat(np.cumsum(sizes - 2) - (sizes - 2), sizes - 2)
    at = np.stack((s, s + t + 1, s + t + 2), axis=1)
    second = (sizes[owner] == 4) & (t == 1)
    at[second] = s[second, None] + [2, 3, 0]
    return flat[at]


def _cut_by_ears(at: np.ndarray, flat: np.ndarray, sizes: np.ndarray, vertices: np.ndarray) -> None:
    """Replace, in ``at`` (the fan of :func:`_fan`, as places in ``flat``),
    the triangles of each planar polygon its fan leaves by its ear cut.

    The test is vectorised over the polygons of each size: the fan from the
    first corner covers a polygon once where every fan triangle's normal
    agrees with the polygon's Newell normal (the fan normals' sum), which
    holds for every convex polygon, so that most files never reach the cut."""
    start = np.cumsum(sizes) - sizes
    bad = []
    for k in np.unique(sizes[sizes > 3]).tolist():
        which = np.flatnonzero(sizes == k)
        corners = flat.reshape(-1, k) if len(which) == len(sizes) else flat[start[which, None] + np.arange(k)]
        for lo in range(0, len(which), _CHUNK):  # in chunks: a few arrays of (chunk, k) floats at a time
            bad.append(which[lo:lo + _CHUNK][_fan_turns_back(corners[lo:lo + _CHUNK], vertices)])
    cut = np.sort(np.concatenate(bad)) if bad else np.zeros(0, np.int64)
    if not len(cut):
        return
    # the rows of each polygon's triangles, polygon by polygon, in the fan's
    # order (a file of quads puts a quad's two halves far apart)
    owner = np.searchsorted(start, at[:, 0], side="right") - 1
    rows = np.flatnonzero(np.isin(owner, cut))
    rows = rows[np.argsort(owner[rows], kind="stable")]
    first_row = np.cumsum(sizes[cut] - 2) - (sizes[cut] - 2)
    for k in np.unique(sizes[cut]).tolist():
        these = np.flatnonzero(sizes[cut] == k)
        corners = flat[start[cut[these], None] + np.arange(k)]
        ears, ok = _ear_cuts(vertices[corners])
        mine = rows[first_row[these[ok], None] + np.arange(k - 2)]  # (polygon, its k - 2 rows)
        at[mine] = start[cut[these[ok]], None, None] + ears[ok]


def _fan_turns_back(corners: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Which polygons (rows of ``corners``, vertex indices) have a fan
    triangle turned against the polygon's Newell normal, past rounding.

    The Newell normal is the sum of the fan triangles' normals (taken from
    the first corner); a straight corner's triangle has no area, and a
    polygon of no area (a spike) no normal: neither counts as turned. The
    cross products are written out per coordinate: ``np.cross`` on
    (m, k, 3) arrays is the slowest step on a file of a million quads."""
    x, y, z = (vertices[:, d][corners] for d in range(3))
    x, y, z = x[:, 1:] - x[:, :1], y[:, 1:] - y[:, :1], z[:, 1:] - z[:, :1]
    nx = y[:, :-1] * z[:, 1:] - z[:, :-1] * y[:, 1:]
    ny = z[:, :-1] * x[:, 1:] - x[:, :-1] * z[:, 1:]
    nz = x[:, :-1] * y[:, 1:] - y[:, :-1] * x[:, 1:]
    sx, sy, sz = nx.sum(axis=1), ny.sum(axis=1), nz.sum(axis=1)
    along = nx * sx[:, None] + ny * sy[:, None] + nz * sz[:, None]
    return (along < -1e-12 * (sx * sx + sy * sy + sz * sz)[:, None]).any(axis=1)


def _ear_cuts(corner: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ear cuts of polygons of one size: corner numbers (m, k - 2, 3),
    each triangle turned as its polygon, and which of the ``m`` polygons
    (``corner``: positions (m, k, 3)) have one: not a polygon off its plane
    (by more than 1e-6 of its size and coordinates: rounding), of no area,
    or one whose cut has a triangle turned against it (self-crossing).

    Each polygon is laid flat in the plane of its Newell normal, in axes
    that see it counter-clockwise, and cut by ``manifold3d.triangulate``
    (imported here: only a file with such a polygon pays for it), one call
    per polygon: a call takes polygons as the outlines and holes of one."""
    m, k = corner.shape[:2]
    q = corner - corner[:, :1]
    newell = np.cross(q[:, 1:-1], q[:, 2:]).sum(axis=1)
    length = np.linalg.norm(newell, axis=1)
    size = np.abs(q).max(axis=(1, 2))
    normal = newell / np.where(length > 0, length, 1.0)[:, None]
    height = np.einsum("mkj,mj->mk", q, normal)
    ok = (length > 0) & (np.ptp(height, axis=1) <= 1e-6 * (size + np.abs(corner).max(axis=(1, 2))))
    # axes in the plane: u toward the corner farthest from the first, w = normal x u
    u = q[np.arange(m), np.argmax(np.einsum("mkj,mkj->mk", q, q), axis=1)]
    u -= np.einsum("mj,mj->m", u, normal)[:, None] * normal
    u /= np.where(ok, np.linalg.norm(u, axis=1), 1.0)[:, None]
    w = np.cross(normal, u)
    scale = np.where(ok, size, 1.0)[:, None]
    xy = np.stack((np.einsum("mkj,mj->mk", q, u) / scale, np.einsum("mkj,mj->mk", q, w) / scale), axis=2)
    from manifold3d import triangulate as cut

    ears = np.zeros((m, k - 2, 3), dtype=np.int64)
    for i in np.flatnonzero(ok).tolist():
        e = np.asarray(cut([xy[i]]), dtype=np.int64).reshape(-1, 3)
        if len(e) == k - 2:
            ears[i] = e
        else:
            ok[i] = False
    a, b, c = (xy[np.arange(m)[:, None], ears[:, :, j]] for j in range(3))
    turn = (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
    # the polygon's doubled area in the flat axes is length / size**2
    ok &= ~(turn < -1e-12 * (length / scale[:, 0] ** 2)[:, None]).any(axis=1)
    return ears, ok
