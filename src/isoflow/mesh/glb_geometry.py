"""A binary glTF as trimesh's reader needs it for a read-back's figures:
each node's positions and triangles, without the accessors it does not
measure.

trimesh's glTF reader turns every accessor of the file into an array, some
20 microseconds each, before it looks at a mesh; isoflow's scenes hold 8
accessors a node (indices, positions, colours and five curvature
attributes), and a read-back measures two of them. :func:`geometry_glb`
gives trimesh the file with the other accessors left out of its JSON (the
binary chunk as it is), once each of them is checked to be one trimesh's
reader turns into an array without fail, so that the file still reads back
as unreadable where trimesh cannot read it whole. A file of any other
layout (materials, extensions, sparse accessors, URIs, several binary
chunks) is left as it is: trimesh reads all of it.

The binary chunk of a file on disk is given to the reader as a view of
the file mapped into memory, not as bytes read: the reader takes each
buffer view as a slice of the chunk (a copy of bytes, none of a view)
and copies only the positions out of it, so the triangles are read from
the file's pages where they lie and the other attributes (most of the
chunk) are not read at all. Read as bytes, the chunk and the copy of
each of its views would be most of the memory a scene's read-back
touches.
"""

from __future__ import annotations

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


def geometry_glb(fh: BinaryIO) -> io.RawIOBase | None:
    """A binary glTF (``fh``, at its start) with its accessors other than
    each triangle primitive's ``POSITION`` and ``indices`` left out, as a
    file for trimesh's ``load_glb``, which then reads the same nodes,
    positions and triangles from it; or None where the file is of another
    layout or an accessor left out is one trimesh's reader would fail on
    (``fh`` is then anywhere: seek to its start to read it whole).

    Parameters
    ----------
    fh : binary file
        The GLB, open for reading at its first byte.

    Returns
    -------
    binary file or None
        The new header and JSON chunk, then ``fh``'s binary chunk read on
        from where it is (not copied; a view of the file mapped into
        memory where ``fh`` is a file on disk): read it while ``fh`` is
        open.

    Examples
    --------
    >>> import trimesh
    >>> from trimesh.exchange.gltf import load_glb
    >>> box = trimesh.creation.box()
    >>> box.visual.vertex_colors = [200, 20, 20, 255]
    >>> data = io.BytesIO(box.export(file_type="glb"))
    >>> len(json.loads(data.getvalue()[20:20 + struct.unpack_from("<I", data.getvalue(), 12)[0]])["accessors"])
    3
    >>> read = load_glb(geometry_glb(data))
    >>> [(len(g["vertices"]), len(g["faces"]), "vertex_colors" in g) for g in read["geometry"].values()]
    [(8, 12, False)]
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
    text = json.dumps(kept, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)  # the chunk's padding, as the specification pads JSON
    new_head = GLB_HEAD.pack(b"glTF", 2, GLB_HEAD.size + len(text) + CHUNK_HEAD.size + bin_length, len(text), b"JSON")
    return _Joined(new_head + text + chunk, fh)


def geometry_tree(tree: object, bin_length: int) -> dict | None:
    """The JSON of :func:`geometry_glb`: ``tree`` (a GLB's, whose binary
    chunk holds ``bin_length`` bytes) with only the accessors of its
    triangle primitives' positions and indices, renumbered; None where it
    is of another layout or where an accessor left out is not one trimesh
    turns into an array without fail.

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
    ...         "bufferViews": [{"buffer": 0, "byteLength": 36}],
    ...         "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 3},
    ...                       {"bufferView": 0, "componentType": 5121, "type": "VEC4", "count": 3}],
    ...         "meshes": [{"primitives": [{"attributes": {"COLOR_0": 1, "POSITION": 0}}]}]}
    >>> geometry_tree(tree, 36)["meshes"]
    [{'primitives': [{'attributes': {'POSITION': 0}}]}]
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
    new: dict[int, int] = {}  # an accessor kept -> its place among those kept
    out_meshes = []
    for mesh in meshes:
        primitives = mesh.get("primitives")
        if not _list_of_dicts(primitives) or "extensions" in mesh:
            return None
        out = []
        for p in primitives:
            attributes = p.get("attributes")
            if (not PLAIN_PRIMITIVE.issuperset(p) or p.get("mode", TRIANGLES) != TRIANGLES
                    or not isinstance(attributes, dict) or "POSITION" not in attributes
                    or not all(_index(a, len(accessors)) for a in attributes.values())
                    or ("indices" in p and not _index(p["indices"], len(accessors)))):
                return None
            kept = {"attributes": {"POSITION": new.setdefault(attributes["POSITION"], len(new))}}
            if "indices" in p:
                kept["indices"] = new.setdefault(p["indices"], len(new))
            if "mode" in p:
                kept["mode"] = p["mode"]
            out.append(kept)
        out_meshes.append({**mesh, "primitives": out})
    # every accessor left out must be one trimesh's reader turns into an
    # array without fail, as it would read it: its failure is the file's
    if not all(_readable(a, views, sizes) for i, a in enumerate(accessors) if i not in new):
        return None
    return {**tree, "meshes": out_meshes, "accessors": [accessors[i] for i in sorted(new, key=new.__getitem__)]}


def _list_of_dicts(value: object) -> bool:
    return isinstance(value, list) and all(isinstance(v, dict) for v in value)


def _whole(value: object) -> bool:
    """A JSON whole number (not a float or a boolean, which trimesh's
    reader may take otherwise)."""
    return type(value) is int


def _index(value: object, count: int) -> bool:
    """An index into a list of ``count`` (not one from its end)."""
    return _whole(value) and 0 <= value < count


def _view_size(view: dict, bin_length: int) -> int | None:
    """The bytes of a buffer view of the one binary chunk, or None where it
    does not lie within the chunk or has a stride that is no step."""
    offset, size = view.get("byteOffset", 0), view.get("byteLength")
    stride = view.get("byteStride", 1)
    if not (view.get("buffer") == 0 and _whole(view.get("buffer")) and _whole(offset) and _whole(size)
            and _whole(stride) and offset >= 0 and size >= 0 and stride > 0 and offset + size <= bin_length):
        return None
    return size


def _readable(accessor: dict, views: list, sizes: list) -> bool:
    """Whether trimesh's glTF reader turns the accessor into an array
    without fail: a known component type and type, at least one element,
    every byte it reads within its buffer view (with the view's stride
    where it has one), no sparse part."""
    count, width = accessor.get("count"), TYPE_COMPONENTS.get(accessor.get("type"))
    itemsize, at = COMPONENT_BYTES.get(accessor.get("componentType")), accessor.get("bufferView")
    offset = accessor.get("byteOffset", 0)
    if (width is None or itemsize is None or not _whole(accessor.get("componentType")) or "sparse" in accessor
            or not (_whole(count) and count > 0 and _index(at, len(views)) and _whole(offset) and offset >= 0)):
        return False
    row = width * itemsize
    stride = views[at].get("byteStride", row)  # (trimesh reads rows apart by the view's stride)
    return offset + (count - 1) * stride + row <= sizes[at]


class _Joined(io.RawIOBase):
    """The bytes ``head``, then ``rest`` read on from where it is: as
    views of ``rest`` mapped into memory where it is a file on disk (see
    the module docs), else as bytes read from it."""

    def __init__(self, head: bytes, rest: BinaryIO):
        super().__init__()
        self._head, self._rest, self._at = head, rest, 0
        self._mapped: memoryview | None = None
        try:
            whole = mmap.mmap(rest.fileno(), 0, access=mmap.ACCESS_READ)
        except (AttributeError, OSError, ValueError):  # not a file on disk (a stream, an empty file): read it
            return
        self._mapped, self._from = memoryview(whole), rest.tell()

    def readable(self) -> bool:
        return True

    def read(self, size: int = -1) -> bytes | memoryview:
        part = self._head[self._at:] if size < 0 else self._head[self._at:self._at + size]
        if size < 0 or len(part) < size:
            more = -1 if size < 0 else size - len(part)
            if self._mapped is None:
                part += self._rest.read(more)
            else:
                at = self._from + self._at + len(part) - len(self._head)
                rest = self._mapped[at:] if more < 0 else self._mapped[at:at + more]
                # a read within the chunk (the reader's) is its view alone, not copied
                part = rest if not part else part + rest.tobytes()
        self._at += len(part)
        return part

    def tell(self) -> int:
        return self._at
