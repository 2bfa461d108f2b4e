"""Binary glTF 2.0 (GLB) of many triangle meshes at once, each its own
node: the file's JSON and binary chunks built from columns over the meshes
(:class:`SceneParts`, a set of them per batch of labels, the sets' arrays
written one after another, not joined), so that a scene of a hundred
thousand labels costs a few NumPy passes and a line of JSON text per mesh,
not a hundred thousand meshes through a general exporter.

The layout is the one trimesh's exporter writes for a mesh with vertex
colours and custom vertex attributes (and reads back alike), but for the
indices' type: per mesh one primitive of triangles with ``indices``
(uint16 where the mesh has at most 65,535 vertices, else uint32; trimesh
writes uint32 always), ``POSITION`` (float32 VEC3, with its bounds, which
the specification asks of it alone; no other accessor carries them),
``COLOR_0`` (uint8 VEC4, normalised) and every
custom attribute under a name starting with ``_``, its rows padded with
zeros to a multiple of 4 bytes (the specification's alignment of vertex
attributes), float64 stored as float32; each mesh's ``extras`` may hold a
comment, and a node's ``extras`` what its part's says (a label's name).
Each kind of array of every mesh lies in one buffer view (a
vertex attribute's with its ``byteStride``), each mesh's part an accessor
at its offset there; the indices in two, one uint16 and one uint32, so
that no accessor's offset needs padding to its component size (the
specification does not say whether one view may mix them).
"""

from __future__ import annotations

import json
import struct
from dataclasses import dataclass, field

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


@dataclass
class SceneParts:
    """Meshes of a glTF scene as columns over all of them: part ``s`` holds
    vertices ``vfirst[s]:vfirst[s + 1]`` and triangles ``tfirst[s]:tfirst[s
    + 1]`` (numbered within the part); each part becomes a mesh and a node.

    Examples
    --------
    >>> tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> two = SceneParts(names=["a", "b"], positions=np.vstack([np.eye(4, 3), np.eye(4, 3) + 2]),
    ...                  colors=np.full((8, 4), 255, np.uint8), attributes={"_k": np.arange(8)},
    ...                  vfirst=np.array([0, 4, 8]), triangles=np.vstack([tet, tet]), tfirst=np.array([0, 4, 8]))
    >>> two.counts().tolist(), two.sizes().tolist()
    ([4, 4], [4, 4])
    """

    names: list[str]
    positions: np.ndarray  # (n, 3), stored as float32
    colors: np.ndarray  # (n, 4) uint8
    attributes: dict[str, np.ndarray]  # name -> (n,) or (n, k), as padded_rows stores them
    vfirst: np.ndarray
    triangles: np.ndarray  # (m, 3)
    tfirst: np.ndarray
    matrices: dict[int, np.ndarray] = field(default_factory=dict)  # part -> its node's 4x4 transform
    extras: dict[int, dict] = field(default_factory=dict)  # part -> its node's extras (a label's name)

    def counts(self) -> np.ndarray:
        """Vertices of each part."""
        return np.diff(np.asarray(self.vfirst, np.int64))

    def sizes(self) -> np.ndarray:
        """Triangles of each part."""
        return np.diff(np.asarray(self.tfirst, np.int64))

    @classmethod
    def of_meshes(cls, meshes: list[dict]) -> SceneParts:
        """Meshes given one by one (``{"name", "positions", "triangles",
        "colors", "attributes", "matrix"}``) as one set of parts.

        Examples
        --------
        >>> tri = {"name": "t", "positions": np.eye(3), "triangles": np.array([[0, 1, 2]]),
        ...        "colors": np.zeros((3, 4), np.uint8), "attributes": {}, "matrix": None}
        >>> SceneParts.of_meshes([tri, tri]).vfirst.tolist()
        [0, 3, 6]
        """
        def joined(arrays: list, width: int) -> np.ndarray:
            return np.concatenate(arrays) if len(arrays) != 1 else np.asarray(arrays[0]).reshape(-1, width)

        names = [m["name"] for m in meshes]
        counts = [len(m["positions"]) for m in meshes]
        sizes = [len(m["triangles"]) for m in meshes]
        keys = list(meshes[0]["attributes"]) if meshes else []
        return cls(names=names, positions=joined([m["positions"] for m in meshes], 3) if meshes else np.zeros((0, 3)),
                   colors=joined([m["colors"] for m in meshes], 4) if meshes else np.zeros((0, 4), np.uint8),
                   attributes={k: np.concatenate([np.asarray(m["attributes"][k]) for m in meshes]) for k in keys},
                   vfirst=np.concatenate([[0], np.cumsum(counts, dtype=np.int64)]),
                   triangles=joined([m["triangles"] for m in meshes], 3) if meshes else np.zeros((0, 3), np.int64),
                   tfirst=np.concatenate([[0], np.cumsum(sizes, dtype=np.int64)]),
                   matrices={t: m["matrix"] for t, m in enumerate(meshes) if m.get("matrix") is not None})


def index_columns(sets: list[SceneParts]) -> tuple[list[list[np.ndarray]], np.ndarray]:
    """The triangle indices of every part of ``sets`` as glTF stores them:
    uint16 for a part of at most :data:`SHORT_VERTICES` vertices, uint32
    otherwise, each type a column of its own (a list of arrays, one per
    set, to lie one after another; a type no part takes is left out), and
    per part (numbered over the sets) its column and byte offset there.
    Kept apart, each column's offsets are multiples of its component size,
    as the specification requires of an accessor.

    Examples
    --------
    >>> tri = np.array([[0, 1, 2]])
    >>> parts = SceneParts(names=["s", "l"], positions=np.zeros((70003, 3)), colors=np.zeros((70003, 4), np.uint8),
    ...                    attributes={}, vfirst=np.array([0, 3, 70003]), triangles=np.vstack([tri, tri]),
    ...                    tfirst=np.array([0, 1, 2]))
    >>> data, where = index_columns([parts])
    >>> [d[0].dtype.name for d in data], where.tolist()
    (['uint16', 'uint32'], [[0, 0], [1, 0]])
    """
    counts = np.concatenate([s.counts() for s in sets]) if sets else np.zeros(0, np.int64)
    sizes = np.concatenate([s.sizes() for s in sets]) if sets else np.zeros(0, np.int64)
    small = counts <= SHORT_VERTICES
    data, where = [], np.zeros((len(counts), 2), np.int64)
    for dtype, chosen in ((np.dtype(np.uint16), small), (np.dtype(np.uint32), ~small)):
        picked = np.flatnonzero(chosen)
        if not len(picked):
            continue
        column, first = [], 0
        for s in sets:
            mine = chosen[first:first + len(s.names)]
            first += len(s.names)
            if mine.all():
                column.append(np.asarray(s.triangles).astype(dtype).reshape(-1))
            elif mine.any():
                column.append(np.asarray(s.triangles)[np.repeat(mine, s.sizes())].astype(dtype).reshape(-1))
        data.append(column)
        where[picked, 0] = len(data) - 1
        where[picked, 1] = np.concatenate([[0], np.cumsum(3 * sizes[picked])])[:-1] * dtype.itemsize
    return data, where


def vertex_columns(sets: list[SceneParts]) -> dict[str, list[np.ndarray]]:
    """Each vertex attribute of every part of ``sets`` in its glTF type,
    2D, as a list of arrays (one per set) to lie one after another:
    ``POSITION`` float32, ``COLOR_0`` uint8 and the custom attributes as
    :func:`padded_rows` gives them.

    Examples
    --------
    >>> tri = SceneParts(names=["t"], positions=np.zeros((3, 3)), colors=np.zeros((3, 4), np.uint8),
    ...                  attributes={"_k": np.arange(3)}, vfirst=np.array([0, 3]), triangles=np.array([[0, 1, 2]]),
    ...                  tfirst=np.array([0, 1]))
    >>> {k: [(v.dtype.name, v.shape) for v in c] for k, c in vertex_columns([tri, tri]).items()}
    {'POSITION': [('float32', (3, 3)), ('float32', (3, 3))], 'COLOR_0': [('uint8', (3, 4)), ('uint8', (3, 4))],
     '_k': [('int32', (3, 1)), ('int32', (3, 1))]}
    """
    columns = {"POSITION": [np.asarray(s.positions, np.float32).reshape(-1, 3) for s in sets],
               "COLOR_0": [np.asarray(s.colors, np.uint8).reshape(-1, 4) for s in sets]}
    for name in (sets[0].attributes if sets else {}):
        columns[name] = [padded_rows(s.attributes[name]) for s in sets]
    return columns


def _buffer_views(index_data: list, columns: dict) -> tuple[list, list, list, int]:
    """Each column a buffer view over its arrays laid one after another:
    the views, the chunks to write (the arrays' own little-endian bytes,
    not a copy where they are so, and the padding to 4 bytes), each view's
    element (dtype and row width) and the binary chunk's length."""
    views, chunks, elements, offset = [], [], [], 0
    for arrays, target in [*((d, ELEMENT_ARRAY_BUFFER) for d in index_data),
                           *((d, ARRAY_BUFFER) for d in columns.values())]:
        raws = [np.ascontiguousarray(a, a.dtype.newbyteorder("<")).reshape(-1).data.cast("B") for a in arrays]
        length = sum(len(r) for r in raws)
        dtype, row = arrays[0].dtype, (arrays[0].shape[1] if arrays[0].ndim == 2 else 1)
        # every part's accessor shares the view, and the specification asks a
        # view shared by vertex attributes for its stride (and one of indices
        # for none)
        stride = {"byteStride": dtype.itemsize * row} if target == ARRAY_BUFFER else {}
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": length, "target": target, **stride})
        chunks += [*raws, b"\0" * (-length % 4)]
        elements.append((np.dtype(dtype.name), row))
        offset += length + -length % 4
    return views, chunks, elements, offset


def scene_chunks(sets: list[SceneParts], order: np.ndarray | None = None, comment: str = "") -> list:
    """The GLB file of every part of ``sets`` as the pieces to write one
    after the other (bytes, and the arrays' own memory as memoryviews: the
    header, the JSON chunk, the binary chunk's header and its arrays),
    node ``t`` showing part ``order[t]`` (parts numbered over the sets in
    turn; all of them in that order where None). Each part needs a
    triangle; every set has the same attribute names.

    Examples
    --------
    >>> tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> one = SceneParts(names=["tet"], positions=np.eye(4, 3), colors=np.full((4, 4), 255, np.uint8),
    ...                  attributes={}, vfirst=np.array([0, 4]), triangles=tet, tfirst=np.array([0, 4]))
    >>> data = b"".join(scene_chunks([one, one], order=np.array([1, 0])))
    >>> data[:4], len(data) % 4
    (b'glTF', 0)
    """
    sets = [s for s in sets if len(s.names)]
    counts = np.concatenate([s.counts() for s in sets]) if sets else np.zeros(0, np.int64)
    sizes = np.concatenate([s.sizes() for s in sets]) if sets else np.zeros(0, np.int64)
    if not counts.all() or not sizes.all():
        raise ValueError("every mesh of a glTF scene needs a triangle")
    n = len(counts)
    order = np.arange(n) if order is None else np.asarray(order, np.int64)
    index_data, index_of = index_columns(sets)
    columns = vertex_columns(sets)
    views, chunks, elements, length = _buffer_views(index_data, columns)
    first = np.concatenate([[0], np.cumsum(counts)])[:-1]
    kinds = ["indices", *columns]
    accessors = [_index_accessors(index_of[order], 3 * sizes[order], [e[0] for e in elements[:len(index_data)]])]
    for v, key in enumerate(columns, len(index_data)):
        dtype, row = elements[v]
        head = {"bufferView": v, "componentType": COMPONENT[dtype], "type": VECTOR[row],
                **({"normalized": True} if key == "COLOR_0" else {})}
        bounds = None
        if key == "POSITION":  # the specification asks POSITION's bounds alone
            low = np.concatenate([np.minimum.reduceat(p, s.vfirst[:-1], axis=0) for p, s in zip(columns[key], sets)])
            high = np.concatenate([np.maximum.reduceat(p, s.vfirst[:-1], axis=0) for p, s in zip(columns[key], sets)])
            bounds = low[order].tolist(), high[order].tolist()
        accessors.append(_vertex_accessors(head, (first * row * dtype.itemsize)[order], counts[order], bounds))
    names = [json.dumps(name) for s in sets for name in s.names]
    matrices, node_extras = {}, {}
    for base, s in zip(np.concatenate([[0], np.cumsum([len(s.names) for s in sets])]).tolist(), sets):
        matrices.update({base + p: m for p, m in s.matrices.items()})
        node_extras.update({base + p: e for p, e in s.extras.items()})
    extras = f',"extras":{json.dumps({"isoflow": comment}, separators=(",", ":"))}' if comment else ""
    meshes, nodes = [], []
    for t, p in enumerate(order.tolist()):
        attributes = ",".join(f'"{key}":{k * n + t}' for k, key in enumerate(kinds) if key != "indices")
        meshes.append(f'{{"name":{names[p]},"primitives":[{{"attributes":{{{attributes}}},"indices":{t},"mode":4}}]'
                      f'{extras}}}')
        matrix = matrices.get(p)
        node = f',"matrix":{json.dumps(np.asarray(matrix, np.float64).T.reshape(-1).tolist())}' if matrix is not None else ""
        if p in node_extras:
            node += f',"extras":{json.dumps(node_extras[p], separators=(",", ":"))}'
        nodes.append(f'{{"name":{names[p]},"mesh":{t}{node}}}')
    head = json.dumps({"asset": {"version": "2.0", "generator": "isoflow"}, "scene": 0,
                       "scenes": [{"nodes": list(range(n))}]}, separators=(",", ":"))
    tail = json.dumps({"bufferViews": views, "buffers": [{"byteLength": length}]}, separators=(",", ":"))
    text = (f'{head[:-1]},"nodes":[{",".join(nodes)}],"meshes":[{",".join(meshes)}],'
            f'"accessors":[{",".join(a for a in accessors if a)}],{tail[1:]}').encode()
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + length
    return [struct.pack("<4sII", b"glTF", 2, total), struct.pack("<I4s", len(text), b"JSON"), text,
            struct.pack("<I4s", length, b"BIN\0"), *chunks]


def _index_accessors(index_of: np.ndarray, count: np.ndarray, dtypes: list) -> str:
    """The JSON of the index accessors, one per node: its view, offset and
    count (``index_of`` and ``count`` in node order)."""
    types = [COMPONENT[d] for d in dtypes]
    return ",".join(f'{{"bufferView":{v},"componentType":{types[v]},"type":"SCALAR","byteOffset":{o},"count":{c}}}'
                    for (v, o), c in zip(index_of.tolist(), count.tolist()))


def _vertex_accessors(head: dict, offsets: np.ndarray, counts: np.ndarray, bounds: tuple | None) -> str:
    """The JSON of one vertex attribute's accessors, one per node: ``head``
    (view, type) with each node's offset and count, and ``bounds`` (each
    node's min and max) where given."""
    start = json.dumps(head, separators=(",", ":"))[:-1]
    if bounds is None:
        return ",".join(f'{start},"byteOffset":{o},"count":{c}}}' for o, c in zip(offsets.tolist(), counts.tolist()))
    return ",".join(f'{start},"byteOffset":{o},"count":{c},"min":{json.dumps(a)},"max":{json.dumps(b)}}}'
                    for o, c, a, b in zip(offsets.tolist(), counts.tolist(), *bounds))
