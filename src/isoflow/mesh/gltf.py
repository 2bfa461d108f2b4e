"""Binary glTF 2.0 (GLB) of many triangle meshes at once, each its own
node: the file's JSON and binary chunks built from arrays concatenated
over the meshes, so that a scene of a hundred thousand labels costs a few
NumPy passes, not a hundred thousand meshes through a general exporter.

The layout is the one trimesh's exporter writes for a mesh with vertex
colours and custom vertex attributes (and reads back alike), but for the
indices' type: per mesh one primitive of triangles with ``indices``
(uint16 where the mesh has at most 65,535 vertices, else uint32; trimesh
writes uint32 always), ``POSITION`` (float32 VEC3, with its bounds as the
specification requires), ``COLOR_0`` (uint8 VEC4, normalised) and every
custom attribute under a name starting with ``_``, its rows padded with
zeros to a multiple of 4 bytes (the specification's alignment of vertex
attributes), float64 stored as float32; each mesh's ``extras`` may hold a
comment. Each kind of array of every mesh lies in one buffer view (a
vertex attribute's with its ``byteStride``), each mesh's part an accessor
at its offset there; the indices in two, one uint16 and one uint32, so
that no accessor's offset needs padding to its component size (the
specification does not say whether one view may mix them).
"""

from __future__ import annotations

import json
import struct

import numpy as np

#: glTF's component types of NumPy's kinds
COMPONENT = {np.dtype(np.int8): 5120, np.dtype(np.uint8): 5121, np.dtype(np.int16): 5122,
             np.dtype(np.uint16): 5123, np.dtype(np.uint32): 5125, np.dtype(np.float32): 5126}
#: glTF's names of vectors of n components
VECTOR = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
#: buffer view targets: vertex attributes and triangle indices
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963


def padded_rows(data: np.ndarray) -> np.ndarray:
    """A vertex attribute as glTF stores it: 2D, float64 as float32, 64-bit
    integers as 32-bit, each row zero-padded to a multiple of 4 bytes.

    Examples
    --------
    >>> padded_rows(np.array([3, -1], np.int8)).tolist()
    [[3, 0, 0, 0], [-1, 0, 0, 0]]
    >>> padded_rows(np.array([0.5])).dtype.str
    '<f4'
    """
    data = np.asarray(data)
    if data.dtype.itemsize == 8:
        data = data.astype(np.float32 if data.dtype.kind == "f" else np.int32 if data.dtype.kind == "i"
                           else np.uint32)
    data = data.reshape(len(data), -1)
    width = data.shape[1] * data.dtype.itemsize
    out = np.zeros((len(data), data.shape[1] + (-width % 4) // data.dtype.itemsize), data.dtype.newbyteorder("<"))
    out[:, :data.shape[1]] = data
    return out


#: the most vertices a mesh's uint16 indices can number: the specification
#: keeps each index type's largest value (65535) out of index data, as
#: graphics APIs read it as a primitive restart
SHORT_VERTICES = 65535


def index_columns(meshes: list[dict], counts: np.ndarray, sizes: np.ndarray) -> tuple[list, np.ndarray]:
    """The triangle indices of ``meshes`` (of ``counts`` vertices and
    ``sizes`` triangles) as glTF stores them: uint16 for a mesh of at most
    :data:`SHORT_VERTICES` vertices, uint32 otherwise, each type in a column
    of its own (a column that no mesh fills is left out), and per mesh its
    column and byte offset there. Kept apart, each column's offsets are
    multiples of its component size, as the specification requires of an
    accessor.

    Examples
    --------
    >>> tri = {"triangles": np.array([[0, 1, 2]])}
    >>> data, where = index_columns([tri, tri], np.array([3, 70000]), np.array([1, 1]))
    >>> [d.dtype.name for d in data], where.tolist()
    (['uint16', 'uint32'], [[0, 0], [1, 0]])
    """
    small = counts <= SHORT_VERTICES
    data, where = [], np.zeros((len(meshes), 2), np.int64)
    for dtype, chosen in ((np.dtype(np.uint16), small), (np.dtype(np.uint32), ~small)):
        picked = np.flatnonzero(chosen)
        if len(picked):
            data.append(np.concatenate([np.asarray(meshes[t]["triangles"]).astype(dtype).reshape(-1) for t in picked]))
            where[picked, 0] = len(data) - 1
            where[picked, 1] = np.concatenate([[0], np.cumsum(3 * sizes[picked])])[:-1] * dtype.itemsize
    return data, where


def vertex_columns(meshes: list[dict]) -> dict[str, np.ndarray]:
    """Each vertex attribute of every mesh of ``meshes`` concatenated, 2D,
    in its glTF type: ``POSITION`` float32, ``COLOR_0`` uint8 and the
    custom attributes as :func:`padded_rows` gives them.

    Examples
    --------
    >>> mesh = {"positions": np.zeros((2, 3)), "colors": np.zeros((2, 4), np.uint8),
    ...         "attributes": {"_k": np.arange(2)}}
    >>> {k: (v.dtype.name, v.shape) for k, v in vertex_columns([mesh, mesh]).items()}
    {'POSITION': ('float32', (4, 3)), 'COLOR_0': ('uint8', (4, 4)), '_k': ('int32', (4, 1))}
    """
    if not meshes:
        return {"POSITION": np.zeros((0, 3), np.float32), "COLOR_0": np.zeros((0, 4), np.uint8)}
    columns = {"POSITION": np.concatenate([np.asarray(m["positions"], np.float32) for m in meshes]).reshape(-1, 3),
               "COLOR_0": np.concatenate([np.asarray(m["colors"], np.uint8) for m in meshes]).reshape(-1, 4)}
    for name in meshes[0]["attributes"]:
        columns[name] = padded_rows(np.concatenate([np.asarray(m["attributes"][name]) for m in meshes]))
    return columns


def glb_chunks(meshes: list[dict], comment: str = "") -> list:
    """The GLB file of ``meshes`` as the pieces to write one after the
    other (bytes, and the arrays' own memory as memoryviews: the header, the
    JSON chunk, the binary chunk's header and its arrays): ``meshes`` holds each ``{"name", "positions" (n, 3),
    "triangles" (m, 3), "colors" (n, 4) uint8, "attributes": {name: (n,)
    or (n, k)}, "matrix": 4x4 or None}``, every mesh with the same
    attribute names and at least one triangle; a node each, in order.

    Examples
    --------
    >>> tet = {"name": "tet", "positions": np.eye(4, 3), "triangles": np.array([[0, 2, 1], [0, 1, 3],
    ...        [0, 3, 2], [1, 2, 3]]), "colors": np.full((4, 4), 255, np.uint8),
    ...        "attributes": {"_k": np.arange(4, dtype=np.int8)}, "matrix": None}
    >>> data = b"".join(glb_chunks([tet]))
    >>> data[:4], len(data) % 4
    (b'glTF', 0)
    """
    counts = np.array([len(m["positions"]) for m in meshes], np.int64)
    sizes = np.array([len(m["triangles"]) for m in meshes], np.int64)
    if len(meshes) and (not counts.all() or not sizes.all()):
        raise ValueError("every mesh of a glTF scene needs a triangle")
    first = np.concatenate([[0], np.cumsum(counts)])[:-1]
    index_data, index_of = index_columns(meshes, counts, sizes)
    columns = vertex_columns(meshes)
    views, chunks, offset = [], [], 0
    for data, target in [*((d, ELEMENT_ARRAY_BUFFER) for d in index_data), *((d, ARRAY_BUFFER) for d in columns.values())]:
        # the array's own bytes, little-endian, not a copy where they are so
        raw = np.ascontiguousarray(data, data.dtype.newbyteorder("<")).reshape(-1).data.cast("B")
        # every mesh's accessor shares the view, and the specification asks a
        # view shared by vertex attributes for its stride (and one of indices
        # for none)
        stride = {"byteStride": data.dtype.itemsize * data.shape[1]} if target == ARRAY_BUFFER else {}
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(raw), "target": target, **stride})
        chunks += [raw, b"\0" * (-len(raw) % 4)]
        offset += len(raw) + -len(raw) % 4
    # the accessors kind by kind: mesh t's of kind k is accessor k * n + t
    # (the indices are the first kind)
    n = len(meshes)
    accessors = [{"bufferView": v, "componentType": COMPONENT[index_data[v].dtype], "type": "SCALAR",
                  "byteOffset": o, "count": c} for (v, o), c in zip(index_of.tolist(), (3 * sizes).tolist())]
    for v, (key, data) in enumerate(columns.items(), len(index_data)):
        row = data.shape[1]
        head = {"bufferView": v, "componentType": COMPONENT[np.dtype(data.dtype.name)], "type": VECTOR[row],
                **({"normalized": True} if key == "COLOR_0" else {})}
        low, high = ((np.minimum.reduceat(data, first, axis=0).tolist(), np.maximum.reduceat(data, first, axis=0).tolist())
                     if len(data) else ([], []))
        accessors += [{**head, "byteOffset": o, "count": c, "min": a, "max": b}
                      for o, c, a, b in zip((first * row * data.dtype.itemsize).tolist(), counts.tolist(), low, high)]
    kinds = ["indices", *columns]
    extras = {"extras": {"isoflow": comment}} if comment else {}
    gltf_meshes = [{"name": mesh["name"], "primitives": [{
        "attributes": {key: k * n + t for k, key in enumerate(kinds) if key != "indices"},
        "indices": t, "mode": 4}], **extras} for t, mesh in enumerate(meshes)]
    nodes = []
    for t, mesh in enumerate(meshes):
        node = {"name": mesh["name"], "mesh": t}
        if mesh.get("matrix") is not None:
            node["matrix"] = np.asarray(mesh["matrix"], np.float64).T.reshape(-1).tolist()  # column-major
        nodes.append(node)
    tree = {"asset": {"version": "2.0", "generator": "isoflow"}, "scene": 0,
            "scenes": [{"nodes": list(range(len(nodes)))}], "nodes": nodes, "meshes": gltf_meshes,
            "accessors": accessors, "bufferViews": views, "buffers": [{"byteLength": offset}]}
    text = json.dumps(tree, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + offset
    return [struct.pack("<4sII", b"glTF", 2, total), struct.pack("<I4s", len(text), b"JSON"), text,
            struct.pack("<I4s", offset, b"BIN\0"), *chunks]
