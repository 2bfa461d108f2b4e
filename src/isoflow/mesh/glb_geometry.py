"""A binary glTF as trimesh's reader needs it for a read-back's figures:
each node's positions and triangles, without the accessors it does not
measure.

trimesh's glTF reader turns every accessor of the file into an array, some
20 microseconds each, before it looks at a mesh; isoflow's scenes hold 8
accessors a node (indices, positions, colours and five curvature
attributes), and a read-back measures two of them. :func:`geometry_parts`
gives trimesh's reader the file's JSON with the other accessors left out
(the binary chunk as it is), once each of them is checked to be one
trimesh's reader turns into an array without fail, so that the file still
reads back as unreadable where trimesh cannot read it whole. A file of any
other layout (materials, extensions, sparse accessors, URIs, several binary
chunks) is left as it is: trimesh reads all of it.

:func:`read_geometry` hands that JSON, as parsed, and the binary chunk to
the reader's own step from a parsed glTF to its meshes (the one trimesh's
``load_glb`` takes once it has parsed the file's JSON): written out again
as JSON for ``load_glb`` to parse, a scene of thousands of nodes would be
serialised and parsed a second time. Where trimesh has no such step (a
private function of its own) ``load_glb`` is given that JSON written out
as the file's, with the file's binary chunk.

The binary chunk of a file on disk is given to the reader as a view of
the file mapped into memory, not as bytes read: the reader takes each
buffer view as a slice of the chunk (a copy of bytes, none of a view)
and reads the positions and triangles out of it, so they are read from
the file's pages where they lie and the other attributes (most of the
chunk) are not read at all. Read as bytes, the chunk and the copy of
each of its views would be most of the memory a scene's read-back
touches. A buffer view whose ``byteStride`` is the row of every accessor
the reader is given on it (the positions', rows of three float32 packed
one after another) is given without it: its rows are the same bytes, the
glTF specification's tightly packed rows, which trimesh reads where they
lie instead of copying them row by row.
"""

from __future__ import annotations

import inspect
import io
import json
import mmap
import struct
from typing import BinaryIO

#: the GLB header (magic, version, length) with the JSON chunk's (length,
#: type), and a chunk's header
GLB_HEAD = struct.Struct("<4sIII4s")
CHUNK_HEAD = struct.Struct("<I4s")
#: bytes per component of each glTF component type trimesh's reader knows
COMPONENT_BYTES = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
#: components per element of each accessor type trimesh's reader knows
TYPE_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
#: the top-level keys of a file whose accessors can be left out: none of
#: them names an accessor but the meshes (a skin or an animation does)
PLAIN_KEYS = frozenset(("asset", "scene", "scenes", "nodes", "meshes", "accessors", "bufferViews", "buffers",
                        "extras"))
#: a primitive's keys trimesh's reader of triangles uses with nothing but
#: its accessors (a material reads the texture coordinates' accessor)
PLAIN_PRIMITIVE = frozenset(("attributes", "indices", "mode"))
#: glTF's triangles, the mode of a primitive that gives none
TRIANGLES = 4


def geometry_parts(fh: BinaryIO) -> tuple[dict, memoryview | bytes] | None:
    """A binary glTF (``fh``, at its start) as trimesh's reader is given it
    for a read-back: its JSON as :func:`geometry_tree` leaves it, and its
    binary chunk; None where the file is of another layout or an accessor
    left out is one trimesh's reader would fail on (``fh`` is then
    anywhere: seek to its start to read it whole).

    Parameters
    ----------
    fh : binary file
        The GLB, open for reading at its first byte.

    Returns
    -------
    tuple or None
        The JSON (a dict) and the binary chunk: a view of the file mapped
        into memory where ``fh`` is a file on disk, else its bytes.

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box()
    >>> box.visual.vertex_colors = [200, 20, 20, 255]
    >>> tree, chunk = geometry_parts(io.BytesIO(box.export(file_type="glb")))
    >>> len(tree["accessors"]), tree["meshes"][0]["primitives"][0]["attributes"]
    (2, {'POSITION': 0})
    >>> len(chunk) >= 8 * 12 + 12 * 3 * 4  # the box's positions and triangles lie in it
    True
    """
    head = fh.read(GLB_HEAD.size)
    if len(head) != GLB_HEAD.size:
        return None
    magic, version, length, json_length, kind = GLB_HEAD.unpack(head)
    if magic != b"glTF" or version != 2 or kind != b"JSON":
        return None
    try:
        tree = json.loads(fh.read(json_length))
    except (UnicodeDecodeError, ValueError):
        return None
    chunk = fh.read(CHUNK_HEAD.size)
    if len(chunk) != CHUNK_HEAD.size:
        return None
    bin_length, bin_kind = CHUNK_HEAD.unpack(chunk)
    # one binary chunk, the file's last: its length is all the views need
    if bin_kind != b"BIN\x00" or length != GLB_HEAD.size + json_length + CHUNK_HEAD.size + bin_length:
        return None
    kept = geometry_tree(tree, bin_length)
    if kept is None:
        return None
    data = _binary_chunk(fh, bin_length)
    return None if data is None else (kept, data)


#: the arguments of trimesh's step from a parsed glTF to its meshes
#: (``trimesh.exchange.gltf._read_buffers``, private) that
#: :func:`read_geometry` gives it, by name
READER_ARGUMENTS = frozenset(("header", "buffers", "mesh_kwargs", "resolver"))


def read_geometry(fh: BinaryIO) -> dict:
    """What trimesh's ``load_glb`` reads from the binary glTF ``fh`` (at
    its start) for a read-back: the nodes' graph and each mesh's
    ``vertices`` and ``faces``, of :func:`geometry_parts` where it gives
    them (the JSON handed over as parsed, see the module docs), else of
    the whole file.

    Parameters
    ----------
    fh : binary file
        The GLB, open for reading at its first byte; a file on disk is
        mapped into memory (see the module docs), a stream read.

    Returns
    -------
    dict
        ``load_glb``'s keyword arguments of a scene (``"geometry"``,
        ``"graph"``); trimesh's reader raises where it cannot read the
        file.

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box()
    >>> read = read_geometry(io.BytesIO(box.export(file_type="glb")))
    >>> [(len(g["vertices"]), len(g["faces"])) for g in read["geometry"].values()]
    [(8, 12)]
    """
    from trimesh.exchange import gltf

    parts = geometry_parts(fh)
    if parts is None:
        fh.seek(0)
        return gltf.load_glb(fh)
    tree, data = parts
    reader = getattr(gltf, "_read_buffers", None)
    if not _takes(reader, READER_ARGUMENTS):  # a trimesh without that step: the file, through load_glb
        return gltf.load_glb(_as_glb(tree, data))
    # as load_glb gives them: no options, the one binary chunk as its buffer
    return reader(header=tree, buffers=[data], mesh_kwargs={}, resolver=None)


def _as_glb(tree: dict, data: memoryview | bytes) -> io.RawIOBase:
    """A GLB file of the JSON ``tree`` and the binary chunk ``data`` (not
    copied: read, a view of it)."""
    text = json.dumps(tree, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)  # the chunk's padding, as the specification pads JSON
    size = GLB_HEAD.size + len(text) + CHUNK_HEAD.size + len(data)
    return _Joined(GLB_HEAD.pack(b"glTF", 2, size, len(text), b"JSON") + text + CHUNK_HEAD.pack(len(data), b"BIN\x00"),
                   data)


def _takes(function: object, names: frozenset) -> bool:
    """Whether ``function`` is a callable that takes all of ``names`` by name."""
    if not callable(function):
        return False
    try:
        parameters = inspect.signature(function).parameters
    except (TypeError, ValueError):
        return False
    return names <= {name for name, p in parameters.items()
                     if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}


def _binary_chunk(fh: BinaryIO, size: int) -> memoryview | bytes | None:
    """The ``size`` bytes of ``fh`` from where it is: a view of the file
    mapped into memory where it is a file on disk, else read; None where
    the file holds fewer."""
    at = fh.tell()
    try:
        data = memoryview(mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ))[at:at + size]
    except (AttributeError, OSError, ValueError):  # not a file on disk (a stream, an empty file): read it
        data = fh.read(size)
    return data if len(data) == size else None


def geometry_tree(tree: object, bin_length: int) -> dict | None:
    """The JSON of :func:`geometry_parts`: ``tree`` (a GLB's, whose binary
    chunk holds ``bin_length`` bytes) with only the accessors of its
    triangle primitives' positions and indices, renumbered, and without
    the ``byteStride`` of a buffer view that is the row of each of those
    on it; None where it is of another layout or where an accessor left
    out is not one trimesh turns into an array without fail.

    Parameters
    ----------
    tree : object
        The parsed JSON chunk.
    bin_length : int
        The bytes of the binary chunk, which every buffer view must lie in.

    Returns
    -------
    dict or None
        The JSON to give trimesh's reader: the meshes' primitives with
        ``POSITION`` and ``indices`` alone, and those accessors.

    Examples
    --------
    >>> tree = {"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36}],
    ...         "bufferViews": [{"buffer": 0, "byteLength": 36, "byteStride": 12}],
    ...         "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 3},
    ...                       {"bufferView": 0, "componentType": 5121, "type": "VEC4", "count": 3}],
    ...         "meshes": [{"primitives": [{"attributes": {"COLOR_0": 1, "POSITION": 0}}]}]}
    >>> kept = geometry_tree(tree, 36)
    >>> kept["meshes"], kept["bufferViews"]
    ([{'primitives': [{'attributes': {'POSITION': 0}}]}], [{'buffer': 0, 'byteLength': 36}])
    >>> tree["accessors"][1]["byteOffset"] = 28  # 12 colour bytes from byte 28 of a 36-byte view
    >>> geometry_tree(tree, 36) is None
    True
    """
    if not isinstance(tree, dict) or not PLAIN_KEYS.issuperset(tree):
        return None
    buffers, views, accessors, meshes = (tree.get(k) for k in ("buffers", "bufferViews", "accessors", "meshes"))
    if not (_list_of_dicts(buffers) and len(buffers) == 1 and "uri" not in buffers[0]
            and _list_of_dicts(views) and _list_of_dicts(accessors) and _list_of_dicts(meshes)):
        return None
    sizes = [_view_size(view, bin_length) for view in views]
    if None in sizes:
        return None
    count = len(accessors)
    new: dict[int, int] = {}  # an accessor kept -> its place among those kept
    out_meshes = []
    # (one loop over every primitive, its checks written out: a scene's
    # thousands of primitives would otherwise pay a call per check)
    for mesh in meshes:
        primitives = mesh.get("primitives")
        if type(primitives) is not list or "extensions" in mesh:
            return None
        out = []
        for p in primitives:
            if type(p) is not dict or not PLAIN_PRIMITIVE.issuperset(p) or p.get("mode", TRIANGLES) != TRIANGLES:
                return None
            attributes = p.get("attributes")
            if type(attributes) is not dict or "POSITION" not in attributes:
                return None
            for at in attributes.values():
                if type(at) is not int or not 0 <= at < count:
                    return None
            kept = {"attributes": {"POSITION": new.setdefault(attributes["POSITION"], len(new))}}
            if "indices" in p:
                at = p["indices"]
                if type(at) is not int or not 0 <= at < count:
                    return None
                kept["indices"] = new.setdefault(at, len(new))
            if "mode" in p:
                kept["mode"] = p["mode"]
            out.append(kept)
        out_meshes.append({**mesh, "primitives": out})
    # every accessor left out must be one trimesh's reader turns into an
    # array without fail, as it would read it: its failure is the file's
    if not _all_readable([a for i, a in enumerate(accessors) if i not in new], views, sizes):
        return None
    given = [accessors[i] for i in sorted(new, key=new.__getitem__)]
    return {**tree, "meshes": out_meshes, "accessors": given, "bufferViews": _packed_views(given, views, sizes)}


def _packed_views(given: list[dict], views: list[dict], sizes: list[int]) -> list[dict]:
    """``views`` without the ``byteStride`` of those whose stride is the
    row of every accessor ``given`` on them, where each of those reads
    within its view (read with the stride or without, the same bytes)."""
    strides = [view.get("byteStride") for view in views]
    rows: dict[int, set] = {}  # a view with a stride -> the rows of the accessors on it, None for one it fails on
    for a in given:
        at = a.get("bufferView")
        if type(at) is not int or not 0 <= at < len(views):
            return views  # (a view named otherwise than by its place, or none: each left as it is)
        if strides[at] is not None:
            rows.setdefault(at, set()).add(_row(a, strides, sizes))
    return [{k: v for k, v in view.items() if k != "byteStride"}
            if strides[at] is not None and rows.get(at) == {strides[at]} else view
            for at, view in enumerate(views)]


def _list_of_dicts(value: object) -> bool:
    return isinstance(value, list) and all(isinstance(v, dict) for v in value)


def _view_size(view: dict, bin_length: int) -> int | None:
    """The bytes of a buffer view of the one binary chunk, or None where it
    does not lie within the chunk or has a stride that is no step."""
    offset, size = view.get("byteOffset", 0), view.get("byteLength")
    stride = view.get("byteStride", 1)
    if not (view.get("buffer") == 0 and type(view.get("buffer")) is int and type(offset) is int
            and type(size) is int and type(stride) is int and offset >= 0 and size >= 0 and stride > 0
            and offset + size <= bin_length):
        return None
    return size


def _all_readable(accessors: list[dict], views: list[dict], sizes: list[int]) -> bool:
    """Whether trimesh's glTF reader turns each of the accessors into an
    array without fail (:func:`_row`), their buffer views ``views`` of
    ``sizes`` bytes."""
    strides = [view.get("byteStride") for view in views]
    for a in accessors:
        if _row(a, strides, sizes) is None:
            return False
    return True


def _row(accessor: dict, strides: list, sizes: list[int]) -> int | None:
    """The bytes of a row of the accessor where trimesh's glTF reader
    turns it into an array without fail, else None: a known component type
    and type, at least one element, every byte it reads within its buffer
    view (of ``sizes`` bytes; rows ``strides`` apart where the view has a
    stride), no sparse part. JSON's whole numbers alone pass (not a float
    or a boolean, which trimesh's reader may take otherwise), and a buffer
    view by its place (not from the end)."""
    # (its checks written out: a scene's tens of thousands of accessors
    # would otherwise pay a call per check)
    count, at, offset = accessor.get("count"), accessor.get("bufferView"), accessor.get("byteOffset", 0)
    component, kind = accessor.get("componentType"), accessor.get("type")
    if (type(count) is not int or type(at) is not int or type(offset) is not int or type(component) is not int
            or type(kind) is not str or "sparse" in accessor or count <= 0 or offset < 0 or not 0 <= at < len(sizes)):
        return None
    width, itemsize = TYPE_COMPONENTS.get(kind), COMPONENT_BYTES.get(component)
    if width is None or itemsize is None:
        return None
    row = width * itemsize
    # (trimesh reads rows apart by the view's stride)
    return row if offset + (count - 1) * (strides[at] or row) + row <= sizes[at] else None


class _Joined(io.RawIOBase):
    """The bytes ``head``, then ``data`` (bytes or a view of a mapped
    file): a read within ``data`` is a view of it, not copied (see the
    module docs)."""

    def __init__(self, head: bytes, data: memoryview | bytes):
        super().__init__()
        self._head, self._data, self._at = head, memoryview(data), 0

    def readable(self) -> bool:
        return True

    def read(self, size: int = -1) -> bytes | memoryview:
        known = len(self._head)
        end = known + len(self._data) if size < 0 else self._at + size
        head = self._head[self._at:end] if self._at < known else b""
        rest = self._data[max(self._at - known, 0):max(end - known, 0)]
        part = head + rest.tobytes() if head and len(rest) else head or rest
        self._at += len(part)
        return part

    def tell(self) -> int:
        return self._at
