"""The boundary mesh of a volume larger than memory, written block by block
into a binary PLY or STL (docs/surface.md).

The volume (a zarr array, a dask array, any array that slices) is cut into
blocks along its chunks. Each block is read with a halo (one voxel below,
two above: the configurations of its vertices and of the ends of the
lattice edges that leave them) and meshed from its bit rows by the
kernels of :mod:`isoflow.scale.quads`, restricted to the block's *box*: its
own lattice vertices (the block's voxels' lowest corners; the last block
along an axis also the far side) and the faces whose lowest corner they
are. Two passes, each one dask task per block:

1. **count**: each block's items (mesh vertices: sheets, then the midpoints
   of the doubled edges that leave a vertex toward +x, +y, +z) in the eight
   *parts* of its box (the vertices on its lower seams along each
   combination of axes, and inside), its faces and the triangles they make;
2. **write**: with every block's first vertex, first face and the starts
   of its parts known, a block numbers its items and writes its vertex and
   face records at their places in the file (``os.pwrite``). A face on a
   block's upper seam names the vertices of the neighbour's lower seam
   part, which the block numbers as the neighbour does (same points, same
   order, same start): seams are exact, nothing is joined afterwards.

The file is a temporary beside the output, renamed over it when every
block is written (:func:`isoflow.mesh.outputs.atomic_path`): an interrupted
run leaves any previous output as it was. Every task opens the file by
name, so a dask.distributed cluster runs the blocks on its workers where
they share the file system.

The mesh equals :func:`isoflow.digital.surface.boundary_mesh`'s up to the
order of vertices and faces, with the same per-vertex attributes.
Memory: a few blocks per worker; nothing grows with the volume but the
counts (a few numbers per block).
"""

from __future__ import annotations

import contextlib
import itertools
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np

from ..digital.lattice import DigitalObject
from ..digital.surface import QuadMesh, row_tables, triangle_rows
from ..errors import IsoflowError
from ..scale.arrays import NotBinary, as_array, binary, fill_value_named, index_dtype, refuse_object
from ..scale.chunkcache import ChunkReader
from ..scale.chunks import BlockTicks, argument_words, decoded_chunk_voxels, is_zarr_array, smaller_blocks_help
from ..scale.compiled import using
from .export import (
    STL_DTYPE,
    VERTEX_COMMENT,
    float32_holds,
    mesh_vertex_table,
    ply_header,
    shared_positions,
    space_tag,
    stl_header,
)

#: the suffixes whose files are written block by block
STREAM_SUFFIXES = (".ply", ".stl")

#: the class (of 27, see :mod:`isoflow.scale.quads`) of each of a box's
#: eight parts, part ``px + 2 py + 4 pz`` (0: on the lower seam, 1: inside)
PARTS = np.array([px + 3 * py + 9 * pz for pz in (0, 1) for py in (0, 1) for px in (0, 1)])

#: bytes of an STL header (its records: :data:`isoflow.mesh.export.STL_DTYPE`)
STL_HEADER = 84

#: peak bytes of a block's write task per item (mesh vertex): its float64
#: position, configuration and sheet (26), and a PLY's vertex table made
#: from them (world positions, columns, records: 67 at its peak), measured
#: with tracemalloc on the largest 128^3 block of a 256^3 porous field
#: (``benchmarks/bench_worker_memory.py``'s); the kernel's peak of that
#: task alone, and of the largest 256^3 block of a 512^3 field, is within
#: 2 % of these terms, so the slack around them is counted once per run
#: (:data:`RUN_BYTES`), not per item
BYTES_PER_ITEM = 93
#: ... per face (quad): its corners and midpoints (int32) and its normal
#: (35), and its PLY quad record (17), on the same block
BYTES_PER_FACE = 52
#: ... per triangle of a PLY of triangles: the int64 rows that
#: ``triangle_rows`` cuts and their records (48.5 on the same block)
BYTES_PER_TRIANGLE = 56
#: ... per triangle of an STL: each face's polygon size and the faces of
#: its size group (4.5 on the same block), beside one batch of records
#: (:data:`STL_BATCH_BYTES`); the STL's copies at contacts
#: (``shared_positions``, 56 per mesh vertex) fit in ``BYTES_PER_ITEM``
BYTES_PER_STL_TRIANGLE = 8
#: ... and one batch of :data:`STL_BATCH_FACES` faces of an STL: their
#: float64 corners, midpoints, world positions and records (2.2 MiB
#: measured on the same block and on a 64^3 block of the same field)
STL_BATCH_BYTES = 3 * 2**20
#: copies of a decoded chunk at the peak of a read through zarr: the
#: decoded buffer and the array zarr gives (a block's read spans up to 8
#: chunks, decoded one after another, each let go before the next: a
#: dask.distributed worker writing blocks of 64^3 from chunks of 128^3,
#: 2 MiB each, peaked at 6.5 to 8.1 MiB in all, its mesh and records
#: 4.2 of it)
DECODED_COPIES = 2
#: what a run holds beside its blocks at work, whatever their size: the
#: tasks' records and results, the layout's counts per block and the
#: allocator's pages around the largest task (a dask.distributed worker
#: writing blocks of 64^3 peaked 1.6 to 3.7 MiB above the task's own
#: terms, from chunks of 64^3 and of 128^3)
RUN_BYTES = 4 << 20


class EmptySurface(IsoflowError):
    """The volume holds no voxel of the object: there is no surface to
    write. A kind of its own, so that a caller that selected a label can
    say that no voxel has it (:func:`isoflow.mesh.formats.omezarr.label_absent`)."""


@dataclass(frozen=True)
class BlockGrid:
    """Blocks of a 3D volume of ``shape``: per axis the ``[start, stop)``
    of each (``bounds``)."""

    shape: tuple[int, int, int]
    bounds: tuple[tuple[tuple[int, int], ...], ...]

    @property
    def numblocks(self) -> tuple[int, ...]:
        return tuple(len(b) for b in self.bounds)

    def indices(self) -> list[tuple[int, ...]]:
        """Every block's index, in C order (the file's order)."""
        return list(itertools.product(*(range(n) for n in self.numblocks)))

    def box(self, index) -> tuple[tuple[slice, ...], np.ndarray, np.ndarray]:
        """The voxels a block reads (its own, one more below and two above,
        inside the array), its box in their lattice coordinates (per axis
        ``lo, hi, t0, t1`` as :mod:`isoflow.scale.quads` takes it) and the
        lattice coordinates of their first point."""
        slices, box, origin = [], np.zeros((3, 4), np.int64), np.zeros(3, np.int64)
        for axis, i in enumerate(index):
            (a, b), n = self.bounds[axis][i], self.shape[axis]
            last = i == len(self.bounds[axis]) - 1
            s0, s1 = max(a - 1, 0), min(b + 2, n)
            slices.append(slice(s0, s1))
            box[axis] = (a - s0, (n if last else b) - s0, a - s0, (n + 1 if last else b) - s0)
            origin[axis] = s0
        return tuple(slices), box, origin

    def own(self, index) -> tuple[slice, ...]:
        """The block's own voxels within what :meth:`box` reads."""
        return tuple(slice(a - max(a - 1, 0), b - max(a - 1, 0))
                     for (a, b) in (self.bounds[axis][i] for axis, i in enumerate(index)))


def _read_box(array, grid: BlockGrid, index, where: str) -> np.ndarray:
    """The voxels :meth:`BlockGrid.box` says block ``index`` reads, as a host
    bool array (a dask array is computed here, in the task, on its
    synchronous scheduler)."""
    slices, own = grid.box(index)[0], grid.own(index)
    near = [grid.bounds[axis][i][0] for axis, i in enumerate(index)]  # the block's first voxel
    part = array[slices]
    if hasattr(part, "compute"):
        part = part.compute(scheduler="sync")
    try:
        part = np.asarray(part)
        return binary(part, where, near=near)
    except NotBinary as exc:
        refusal = exc
    except IsoflowError:
        raise
    except Exception as exc:  # zarr and its codecs raise many types
        raise IsoflowError(f"{where}: cannot read the block at voxel {tuple(int(n) for n in near)} "
                           f"({type(exc).__name__}: {exc})") from None
    # the line counts the voxels of one block, its own or, where only the
    # margins read with them hold such values, the neighbour's that holds
    # the first, as info's blocks do
    voxels = part[own]
    if not ((voxels != 0) & (voxels != 1)).any():
        first = np.argwhere((part != 0) & (part != 1))[0] + [s.start for s in slices]
        index = tuple(next(i for i, (a, b) in enumerate(grid.bounds[axis]) if a <= c < b)
                      for axis, c in enumerate(first))
        near = [grid.bounds[axis][i][0] for axis, i in enumerate(index)]
        voxels = array[tuple(slice(*grid.bounds[axis][i]) for axis, i in enumerate(index))]
        voxels = np.asarray(voxels.compute(scheduler="sync") if hasattr(voxels, "compute") else voxels)
    try:
        binary(voxels, where, near=near)
    except NotBinary as exc:
        refusal = exc
    stored = getattr(array, "array", array)  # a _Source holds the reader
    raise fill_value_named(refusal, getattr(stored, "fill_value", None), part.dtype) from None


def count_block(array, grid: BlockGrid, index, connectivity: int, where: str) -> dict:
    """Pass 1 on one block (a dask task).

    Parameters
    ----------
    array : array-like
        The volume (x, y, z), sliced for the block and its halo.
    grid : BlockGrid
        The blocks.
    index : tuple of int
        The block.
    connectivity : {6, 26}
        The object's connectivity.
    where : str
        The input's name in messages.

    Returns
    -------
    dict
        ``parts``: the block's items (mesh vertices) in each of its eight
        parts, part ``px + 2 py + 4 pz`` (0: on its lower seam along that
        axis, 1: inside); ``faces``: the faces it owns; ``triangles``: two
        per face and one per midpoint a face names; ``voxels``: its own.

    Raises
    ------
    IsoflowError
        A block that cannot be read or is not binary.

    Examples
    --------
    >>> grid = BlockGrid((2, 2, 2), (((0, 1), (1, 2)), ((0, 2),), ((0, 2),)))
    >>> count_block(np.ones((2, 2, 2), bool), grid, (1, 0, 0), 6, "cube")["parts"].tolist()
    [1, 1, 2, 2, 2, 2, 3, 4]
    """
    from ..scale.bitrows import pack
    from ..scale.quads import count_planes

    _, box, origin = grid.box(index)
    vol = _read_box(array, grid, index, where)
    with using(1):
        bits = pack(vol)[0]
        # every plane of the box: the faces below the upper seam name the
        # midpoints of the edges that leave it
        items, faces, refs = count_planes(bits, vol.shape, box, int(box[0, 0]), int(box[0, 1] + 1),
                                          row_tables(connectivity))
    per_class = items.sum(axis=0)
    return {"parts": per_class[PARTS], "faces": int(faces.sum()), "triangles": int(2 * faces.sum() + refs.sum()),
            "voxels": int(np.count_nonzero(vol[grid.own(index)]))}


@dataclass(frozen=True)
class Layout:
    """Where every block's vertices and faces go: per block (by index) the
    first item of each of its parts, its items, its quads, and its first
    face record (a quad, or a triangle where ``kind`` says so)."""

    grid: BlockGrid
    part_start: dict  # index -> (8,) int64
    items: dict  # index -> int
    quads: dict  # index -> int
    face_start: dict  # index -> int
    vertices: int
    faces: int  # face records: quads, or triangles
    kind: Literal["quads", "triangles"]
    voxels: int

    def counters(self, index) -> np.ndarray:
        """The first number of each of the 27 classes of the block's box: a
        class on an upper seam (2) is the lower seam part of the neighbour
        along that axis (-1 where there is none)."""
        out = np.full(27, -1, np.int64)
        for cl in range(27):
            c = (cl % 3, (cl // 3) % 3, cl // 9)
            owner = tuple(i + (ci == 2) for i, ci in zip(index, c))
            if owner in self.part_start:
                part = sum((ci if ci < 2 else 0) << axis for axis, ci in enumerate(c))
                out[cl] = self.part_start[owner][part]
        return out


@dataclass(frozen=True)
class BlockPlan:
    """What one block's write task needs of the layout."""

    index: tuple[int, ...]
    counters: np.ndarray  # (27,) the first number of each class of its box
    first: int  # its first item
    items: int
    quads: int
    face_start: int  # its first face record
    kind: Literal["quads", "triangles"]
    vertices: int  # of the whole mesh


def block_plan(layout: Layout, index) -> BlockPlan:
    """The part of ``layout`` that block ``index`` writes by.

    Parameters
    ----------
    layout : Layout
        The file's layout (:func:`plan`).
    index : tuple of int
        The block.

    Returns
    -------
    BlockPlan
    """
    return BlockPlan(tuple(index), layout.counters(index), int(layout.part_start[index][0]), layout.items[index],
                     layout.quads[index], layout.face_start[index], layout.kind, layout.vertices)


def plan(grid: BlockGrid, counts: dict, triangles: bool) -> Layout:
    """The layout of the file from every block's counts, blocks in C order.

    Parameters
    ----------
    grid : BlockGrid
        The blocks.
    counts : dict
        Block index -> :func:`count_block`'s result.
    triangles : bool
        The faces are written as triangles (STL, or a PLY whose faces are
        not all quads).

    Returns
    -------
    Layout

    Examples
    --------
    >>> grid = BlockGrid((2, 2, 2), (((0, 1), (1, 2)), ((0, 2),), ((0, 2),)))
    >>> counts = {i: count_block(np.ones((2, 2, 2), bool), grid, i, 6, "cube") for i in grid.indices()}
    >>> layout = plan(grid, counts, False)
    >>> layout.vertices, layout.faces, layout.part_start[(1, 0, 0)].tolist()
    (26, 24, [9, 10, 11, 13, 15, 17, 19, 22])
    """
    part_start, items, quads, face_start = {}, {}, {}, {}
    nitems = nfaces = 0
    for index in grid.indices():
        c = counts[index]
        part_start[index] = nitems + np.concatenate([[0], np.cumsum(c["parts"])[:-1]]).astype(np.int64)
        items[index], quads[index], face_start[index] = int(np.sum(c["parts"])), c["faces"], nfaces
        nitems += items[index]
        nfaces += c["triangles"] if triangles else c["faces"]
    voxels = sum(c["voxels"] for c in counts.values())
    return Layout(grid, part_start, items, quads, face_start, nitems, nfaces,
                  "triangles" if triangles else "quads", voxels)


def mesh_block(array, grid: BlockGrid, block: BlockPlan, connectivity: int, where: str) -> QuadMesh:
    """Pass 2 on one block, in memory: its own vertices and the faces it
    owns, numbered as in the whole file.

    Parameters
    ----------
    array, grid, connectivity, where
        As in :func:`count_block`.
    block : BlockPlan
        Where the block's items and faces go (:func:`block_plan`).

    Returns
    -------
    QuadMesh
        Vertex ``v`` of the file at row ``v - block.first``; the faces name
        the file's vertices (the block's own and its upper neighbours'
        seams'). ``pinched``: the block's own.
    """
    from ..scale.bitrows import pack
    from ..scale.quads import fill_planes

    _, box, origin = grid.box(block.index)
    vol = _read_box(array, grid, block.index, where)
    idx = index_dtype(block.vertices)
    n, f = block.items, block.quads
    out = (np.empty((n, 3)), np.empty(n, np.uint8), np.empty(n, np.int8), np.empty((f, 4), idx),
           np.empty((f, 4), idx), np.empty((f, 3), np.int8))
    with using(1):
        bits = pack(vol)[0]
        pinched = fill_planes(bits, vol.shape, box, int(box[0, 0]), int(min(box[0, 3], box[0, 1] + 1)),
                              block.counters, block.first, 0, row_tables(connectivity), connectivity, origin, out)
    vertices, config, sheet, faces, midpoint, normals = out
    return QuadMesh(vertices, faces, midpoint, normals, config, sheet, connectivity, pinched)


@dataclass(frozen=True)
class Target:
    """The file the blocks write into: its (temporary) path, format, the
    world frame and type of the positions, and where its sections start."""

    path: str
    suffix: Literal[".ply", ".stl"]
    frame: DigitalObject
    position: type
    vertex_offset: int  # bytes before the first vertex record (PLY)
    face_offset: int  # bytes before the first face record
    header: bytes = b""


def _vertex_dtype(position) -> np.dtype:
    """A PLY vertex record of :func:`isoflow.mesh.export.mesh_vertex_table`'s
    columns, positions of type ``position``."""
    empty = QuadMesh(np.zeros((0, 3)), np.zeros((0, 4), np.int32), np.zeros((0, 4), np.int32),
                     np.zeros((0, 3), np.int8), np.zeros(0, np.uint8), np.zeros(0, np.int8), 6, 0)
    table = mesh_vertex_table(empty, DigitalObject.placement(3), position)
    return np.dtype([(k, v.dtype.newbyteorder("<")) for k, v in table.items()])


def _face_dtype(kind: Literal["quads", "triangles"]) -> np.dtype:
    """A PLY face record: the corner count (uchar), then int indices."""
    return np.dtype([("n", "u1"), ("i", "<i4", (4 if kind == "quads" else 3,))])


def _pwrite(fd: int, data: np.ndarray, offset: int) -> None:
    view = memoryview(np.ascontiguousarray(data)).cast("B")
    while len(view):
        n = os.pwrite(fd, view, offset)
        view, offset = view[n:], offset + n


def write_block(array, grid: BlockGrid, block: BlockPlan, target: Target, connectivity: int, where: str) -> dict:
    """Pass 2 on one block, written into the target file (a dask task).

    Parameters
    ----------
    array, grid, block, connectivity, where
        As in :func:`mesh_block`.
    target : Target
        The file: its vertex records are written at their numbers, its face
        records from the block's first face on.

    Returns
    -------
    dict
        ``pinched``: the block's pinched vertices; ``shared``: in an STL,
        its positions that carry more than one of its vertices
        (:func:`isoflow.mesh.export.shared_positions`), 0 in a PLY.
    """
    mesh = mesh_block(array, grid, block, connectivity, where)
    shared = 0
    if target.suffix == ".stl":
        # every copy at a contact is the block's own (the block that counts its lattice vertex or edge), so the
        # blocks' counts add up to the mesh's: the copies that an STL reader welds
        shared = shared_positions(mesh)
        records = []
    else:
        vertices = mesh_vertex_table(mesh, target.frame, target.position)
        vrec = np.empty(len(mesh.vertices), _vertex_dtype(target.position))
        for name in vrec.dtype.names:
            vrec[name] = vertices[name]
        fdt = _face_dtype(block.kind)
        faces = mesh.faces if block.kind == "quads" else triangle_rows(mesh.faces, mesh.edge_midpoint)[0]
        frec = np.empty(len(faces), fdt)
        frec["n"], frec["i"] = fdt["i"].shape[0], faces
        records = [(target.vertex_offset + block.first * vrec.dtype.itemsize, vrec),
                   (target.face_offset + block.face_start * fdt.itemsize, frec)]
    fd = os.open(target.path, os.O_WRONLY)
    try:
        if target.suffix == ".stl":
            _write_stl_records(fd, mesh, block.first, target.frame, STL_HEADER + block.face_start * STL_DTYPE.itemsize)
        for offset, rec in records:
            _pwrite(fd, rec, offset)
    finally:
        os.close(fd)
    return {"pinched": mesh.pinched, "shared": shared}


#: corner offsets of a face with normal +e_a from its lowest corner, in
#: its outward order (``isoflow.scale.quads.CORNER_D``: (1 - d_j) e_j + (1 - d_k) e_k)
def _corner_offsets() -> np.ndarray:
    out = np.zeros((3, 4, 3))
    for a in range(3):
        j, k = (a + 1) % 3, (a + 2) % 3
        for t, (dj, dk) in enumerate(((1, 1), (0, 1), (0, 0), (1, 0))):
            out[a, t, j], out[a, t, k] = 1 - dj, 1 - dk
    return out


def _stl_records(mesh: QuadMesh, faces: np.ndarray, first: int, frame: DigitalObject) -> np.ndarray:
    """The STL triangles of some of a block's faces (``faces``: their
    numbers in the block), as :func:`triangle_rows` cuts them. A face's
    positions come from its lowest corner, which is the block's own vertex
    (its first corner, or its last where the normal is negative and the
    corners run the other way)."""
    normals = mesh.face_normals[faces]
    plus = normals.sum(axis=1) > 0
    low = mesh.vertices[np.where(plus, mesh.faces[faces, 0], mesh.faces[faces, 3]) - first]
    axis = np.abs(normals).argmax(axis=1)
    order = np.where(plus[:, None], np.arange(4), np.arange(3, -1, -1))
    corners = low[:, None, :] + _corner_offsets()[axis[:, None], order]
    mids = (corners + np.roll(corners, -1, axis=1)) / 2
    n = len(faces)
    codes = np.arange(4 * n).reshape(n, 4)
    mid_codes = np.where(mesh.edge_midpoint[faces] >= 0, 4 * n + codes, -1)
    tris, face = triangle_rows(codes, mid_codes)
    xyz = frame.world(np.concatenate([corners.reshape(-1, 3), mids.reshape(-1, 3)]))
    rec = np.zeros(len(tris), STL_DTYPE)
    rec["normal"] = normals[face]
    rec["v"] = xyz[tris]
    return rec


#: faces whose STL records a block's write makes at a time: their float64
#: corners, midpoints and world positions and their records take about
#: 1.1 KiB a face, so a batch holds a few MiB whatever the block's size
STL_BATCH_FACES = 2048


def _write_stl_records(fd: int, mesh: QuadMesh, first: int, frame: DigitalObject, offset: int) -> None:
    """Write a block's STL triangles from byte ``offset`` on, a batch of
    faces at a time, in the order :func:`triangle_rows` gives the whole
    block: two per plain quad in face order, then the faces with midpoints
    grouped by polygon size, each group's fans triangle by triangle (the
    first triangle of every face of the group, then the second, ...). A
    batch's records are those of :func:`_stl_records` on the whole block,
    made with the same arithmetic per face, so the bytes do not depend on
    the batch size."""
    size = 4 + (mesh.edge_midpoint >= 0).sum(axis=1, dtype=np.int8)  # at most 8 corners
    row = 0  # the block's triangles before the group
    for polygon in np.unique(np.concatenate([[4], size])):
        group = np.flatnonzero(size == polygon)
        fans = polygon - 2  # triangles per face
        for start in range(0, len(group), STL_BATCH_FACES):
            rec = _stl_records(mesh, group[start:start + STL_BATCH_FACES], first, frame)
            if polygon == 4:  # a plain quad's two triangles are next to each other
                _pwrite(fd, rec, offset + (row + 2 * start) * STL_DTYPE.itemsize)
                continue
            k = len(rec) // fans
            for t in range(fans):
                _pwrite(fd, rec[t * k:(t + 1) * k], offset + (row + t * len(group) + start) * STL_DTYPE.itemsize)
        row += fans * len(group)


class _Source:
    """The volume handed to the block tasks: a holder, so that dask passes
    a dask array to them as it is instead of computing it first."""

    def __init__(self, array):
        self.array = array

    def __getitem__(self, key):
        return self.array[key]


def block_grid(array, block_shape=None) -> BlockGrid:
    """The blocks of a volume.

    Parameters
    ----------
    array : zarr.Array, ChunkReader, dask.array.Array or array-like
        A zarr array is cut along its shards or chunks, grouped when tiny
        (:func:`isoflow.scale.chunks.zarr_blocks`); a dask array along its
        chunks; any other array into one block.
    block_shape : tuple of int, optional
        Blocks of this shape instead.

    Returns
    -------
    BlockGrid

    Examples
    --------
    >>> block_grid(np.zeros((5, 4, 3)), (2, 4, 3)).bounds[0]
    ((0, 2), (2, 4), (4, 5))
    """
    from ..scale.chunks import block_bounds, zarr_blocks

    shape = tuple(int(s) for s in array.shape)
    if is_zarr_array(array) or isinstance(array, ChunkReader):
        chunks = zarr_blocks(array, block_shape)
    elif block_shape is None and hasattr(array, "chunks") and hasattr(array, "compute"):
        chunks = array.chunks
    else:
        block = shape if block_shape is None else tuple(min(int(b), s) for b, s in zip(block_shape, shape))
        chunks = tuple(tuple([b] * (s // b) + ([s % b] if s % b else [])) for b, s in zip(block, shape))
    return BlockGrid(shape, tuple(tuple(b) for b in block_bounds(chunks)))


def _position_type(shape, frame: DigitalObject) -> type:
    """float32 where it holds every lattice point and edge midpoint of the
    volume to :data:`isoflow.mesh.export.POSITION_TOLERANCE` voxels (as
    :func:`isoflow.mesh.export.mesh_vertex_table` asks of a mesh's own
    vertices), else float64."""
    for axis, n in enumerate(shape):
        points = np.zeros((2 * n + 1, 3))
        points[:, axis] = np.arange(2 * n + 1) / 2
        if not float32_holds(frame.world(points)[:, axis], frame.spacing[axis]):
            return np.float64
    return np.float32


def _by_layers(grid: BlockGrid, task, scheduler, workers: int, ticks, before: int) -> dict:
    """``task(index)`` (a dask.delayed call) for every block, computed one
    layer of blocks along the first axis at a time; ``ticks`` (a
    :class:`~isoflow.scale.chunks.BlockTicks` of both passes) told of each
    block, ``before`` blocks done before this pass. A store of one layer
    of blocks, or of thousands to a layer, is long work that a count of
    layers would leave silent."""
    from ..scale.chunks import compute

    out = {}
    with ticks.callback():
        for i in range(grid.numblocks[0]):
            indices = [ix for ix in grid.indices() if ix[0] == i]
            (done,) = compute([task(ix) for ix in indices], scheduler=scheduler, workers=workers)
            out.update(zip(indices, done))
            ticks.at(before + len(out))
    return out


def write_surface_blocks(array, path, connectivity: int | None = None, *, frame: DigitalObject | None = None,
                         block_shape=None, scheduler=None, threads: int | None = None, progress=None,
                         force: bool = False, where: str | None = None, comments: tuple[str, ...] = (),
                         triangulate: bool = False) -> dict:
    """Write the boundary mesh of a 3D volume block by block (binary PLY or
    STL), never holding more than a few blocks per worker.

    Parameters
    ----------
    array : zarr.Array, dask.array.Array or array-like
        The 3D volume (x, y, z), 0/1 or bool; read block by block, each block
        with a halo (see the module docs).
    path : str or os.PathLike
        The output, ``.ply`` or ``.stl``.
    connectivity : {6, 26}, optional
        The object's connectivity (default 6).
    frame : DigitalObject, optional
        Gives the voxel size and the origin of the world positions (its
        volume is not read), and their anatomical frame, which the header
        records where it is RAS or LPS (:func:`~isoflow.mesh.export.space_tag`);
        default: unit voxels at the origin, no frame.
    block_shape : tuple of int, optional
        Blocks of this shape instead of the array's chunks.
    scheduler : optional
        Passed to ``dask.compute`` (a ``dask.distributed`` client's ``get``
        runs the blocks on its workers, which must share the file system).
    threads : int, optional
        Workers of dask's local schedulers (default: the CPUs).
    progress : callable, optional
        ``progress(done, total)`` as each block of the two passes is done
        (``total``: twice the blocks; on a ``dask.distributed`` cluster,
        which runs no dask callback, after each layer of blocks).
    force : bool
        Replace an existing output.
    where : str, optional
        The input's name in messages; default: the function and its
        argument, ``write_surface_blocks: array``, with a zarr store's
        name.
    comments : tuple of str
        PLY header comments; by default ``isoflow write_surface_blocks,
        N-connectivity`` and the per-vertex columns, as :func:`write_surface`
        records them (``isoflow genus`` reads the file at that connectivity;
        an STL's header records it always).
    triangulate : bool
        Triangles in a PLY too (an STL always holds triangles; a PLY holds
        them anyway where a face has midpoints, as binary PLY readers need
        faces of one size).

    Returns
    -------
    dict
        ``path``, ``vertices``, ``faces`` (records: quads, or triangles as
        ``kind`` says), ``quads``, ``midpoints``, ``pinched``, ``voxels``,
        ``euler_characteristic`` (``V - E + F`` of the quad mesh), ``bytes``,
        and ``shared``: in an STL, the positions of more than one vertex
        (the copies at contacts, which readers weld), 0 in a PLY.

    Raises
    ------
    IsoflowError
        Another suffix (naming those that stream), a non-binary or empty
        volume, work or a file that would not fit (saying what would), an
        output that exists without ``force``.

    Notes
    -----
    The mesh is :func:`isoflow.digital.surface.boundary_mesh`'s (docs/mathematics.md,
    the boundary mesh: ``V - E + F = 2 chi + 2 pinched``), up to the order of its
    vertices and faces, with the same per-vertex attributes.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "cube.ply"
    >>> r = write_surface_blocks(np.ones((2, 2, 2), bool), out, block_shape=(1, 2, 2), scheduler="sync")
    >>> r["vertices"], r["faces"], r["euler_characteristic"]
    (26, 24, 2)
    """
    from ..digital.connectivity import resolve_connectivity
    from ..scale.compiled import thread_count

    where = where or argument_words(array, "write_surface_blocks")
    out = _checked_output(path, force)
    # a path (the store's, as the command takes it), an object or a mesh: AttributeError 'str' object has no
    # attribute 'shape'
    refuse_object(array, where, then="and frame=obj for its placement",
                  reader='zarr.open_array(path, mode="r"), or an OME-Zarr image\'s level: zarr.open_group(path, '
                         'mode="r")["0"]')
    if not hasattr(array, "shape"):  # nested lists: array-like
        array = as_array(array, where)
    if len(array.shape) != 3:
        raise IsoflowError(f"{where}: surface needs a 3D volume, this one has shape {tuple(array.shape)}")
    conn = resolve_connectivity(3, connectivity)
    # the record genus reads the connectivity from, as write_surface's file and the STL's header have it
    comments = comments or (f"isoflow write_surface_blocks, {conn}-connectivity", VERTEX_COMMENT)
    if 0 in array.shape:  # no blocks to lay out: the in-memory refusal, before the grid is sized
        raise EmptySurface(f"{where}: the object is empty (shape {tuple(array.shape)}), there is no surface to write")
    frame = frame or DigitalObject.placement(3)
    array, grid, cache = _reader(array, block_shape)
    with using(threads):
        workers = thread_count()
    read = _read_bytes(array, grid)
    blocks_help = smaller_blocks_help(grid.bounds, array)
    _check_memory(where, workers, read, "counting", cache, scheduler, blocks_help)
    source = _Source(array)
    ticks = BlockTicks(progress, 2 * len(grid.indices()), ("count_block", "write_block"))
    counts = _by_layers(grid, lambda i: _delayed(count_block)(source, grid, i, conn, where), scheduler, workers,
                        ticks, 0)
    triangles = triangulate or out.suffix.lower() == ".stl" or any(
        c["triangles"] != 2 * c["faces"] for c in counts.values())
    layout = plan(grid, counts, triangles)
    if layout.voxels == 0:
        raise EmptySurface(f"{where}: the object is empty, there is no surface to write")
    per_task = max(_write_bytes(read, layout, counts[i]["triangles"], i, out.suffix.lower()) for i in grid.indices())
    _check_memory(where, workers, per_task, "writing", cache, scheduler, blocks_help)
    target, size = _prepared(out, layout, frame, comments, conn, where)
    with _filling(out, target, size) as target:
        written = _by_layers(grid, lambda i: _delayed(write_block)(source, grid, block_plan(layout, i), target, conn,
                                                                   where), scheduler, workers, ticks,
                             len(counts))
    quads = sum(layout.quads.values())
    midpoints = sum(c["triangles"] - 2 * c["faces"] for c in counts.values()) // 2
    return {"path": out, "vertices": layout.vertices, "faces": layout.faces, "kind": layout.kind, "quads": quads,
            "midpoints": midpoints, "pinched": sum(w["pinched"] for w in written.values()), "voxels": layout.voxels,
            "euler_characteristic": layout.vertices - quads - midpoints, "bytes": size,
            "shared": sum(w["shared"] for w in written.values())}


def _checked_output(path, force: bool) -> Path:
    """The output, refused in one line naming the suffixes that stream."""
    from .outputs import check_output_path

    suffix = Path(path).suffix.lower()
    if suffix not in STREAM_SUFFIXES:
        raise IsoflowError(f"{path}: a surface larger than memory is written block by block as binary PLY or STL "
                           f"only ({', '.join(STREAM_SUFFIXES)}), not {suffix or 'this'}")
    return check_output_path(path, force, suffixes=STREAM_SUFFIXES, what="surface")


def _reader(array, block_shape) -> tuple:
    """The array the blocks read (a zarr array through a chunk cache), its
    blocks and the cache's bytes."""
    if is_zarr_array(array):
        array = ChunkReader(array)
    grid = block_grid(array, block_shape)
    cache = 0
    if isinstance(array, ChunkReader):
        # a layer's blocks read the last chunk layer of the one below and the
        # first of the one above: each chunk decoded once
        array.max_bytes = cache = _cache_bytes(grid, array.chunks, np.dtype(array.array.dtype).itemsize)
    return array, grid, cache


def _prepared(out: Path, layout: Layout, frame: DigitalObject, comments, conn: int, where: str) -> tuple:
    """The file's target (a temporary path to come) and size, refused up
    front where the format or the disk cannot hold it."""
    suffix = out.suffix.lower()
    position = _checked_position(out, suffix, layout, layout.grid, frame)
    header = _header(suffix, layout, position, comments, conn, where, frame.space)
    size = _file_size(suffix, layout, position, len(header))
    _check_disk(out, size)
    faces_at = len(header) + (layout.vertices * _vertex_dtype(position).itemsize if suffix == ".ply" else 0)
    return Target("", suffix, frame, position, len(header), faces_at, header), size


@contextlib.contextmanager
def _filling(out: Path, target: Target, size: int):
    """A temporary file beside ``out`` of the final size with its header,
    for the blocks to write into; renamed over ``out`` when they are done
    (:func:`isoflow.mesh.outputs.atomic_path`: an error or an interruption
    removes it and leaves ``out`` as it was)."""
    from .outputs import atomic_path

    with atomic_path(out) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(target.header)
            fh.truncate(size)
        yield replace(target, path=str(tmp))


def _delayed(fn):
    from ..scale.chunks import import_dask

    return import_dask()[0].delayed(fn, pure=False)


def _largest_read(grid: BlockGrid) -> int:
    """Voxels of the largest block with its halo."""
    return int(np.prod([max(b - a for a, b in bounds) + 3 for bounds in grid.bounds]))


def _read_bytes(array, grid: BlockGrid) -> int:
    """Peak bytes of one task's read of the largest block with its halo:
    the voxels read, their bool copy and the decoded chunk they are copied
    from (:data:`DECODED_COPIES` times), counted whole where it is larger
    than what the block reads (zarr decodes a whole chunk to give any part
    of it, as dask computes a whole chunk of its array, and the task holds
    it before the shared chunk cache can drop it)."""
    voxels = _largest_read(grid)
    itemsize = np.dtype(array.dtype).itemsize
    return voxels * (itemsize + 2) + max(voxels, DECODED_COPIES * decoded_chunk_voxels(array)) * itemsize


def _write_bytes(read: int, layout: Layout, triangles: int, index, suffix: str) -> int:
    """Peak bytes of block ``index``'s write task: the larger of its read
    and its mesh with its records (``triangles``: the block's, written
    where the layout writes triangles; an STL's cost the most). The two
    do not add up: the decoded chunks are let go before the mesh is made,
    and the voxels and bit rows it is made from (under 1.2 bytes a voxel)
    before its records, so the mesh is held beside less than the read."""
    if suffix == ".stl":
        records = triangles * BYTES_PER_STL_TRIANGLE + STL_BATCH_BYTES
    else:
        records = triangles * BYTES_PER_TRIANGLE if layout.kind == "triangles" else 0
    return max(read, layout.items[index] * BYTES_PER_ITEM + layout.quads[index] * BYTES_PER_FACE + records)


def _check_memory(where: str, workers: int, per_task: int, what: str, cache: int = 0, scheduler=None,
                  blocks_help: bool = True) -> None:
    """Refuse, before the pass, blocks that would not fit ``workers`` at a
    time (beside the chunk cache), saying how many would; on a
    ``dask.distributed`` cluster, blocks that would not fit a worker's
    memory limit as many at a time as it has threads. ``blocks_help``:
    whether smaller blocks would take less memory
    (:func:`~isoflow.scale.chunks.smaller_blocks_help`), else the refusal
    offers smaller chunks and more memory alone."""
    from ..scale.chunks import distributed_client
    from ..scale.memory import check_fits, check_workers_fit, default_budget

    # a task holds the chunk its block decodes whole, however small the block:
    # smaller blocks are offered only where they are not smaller than the chunks
    smaller = ("write the store with smaller chunks (or pass smaller blocks)" if blocks_help else
               "write the store with smaller chunks (a chunk is decoded whole, however small the blocks)")
    client = distributed_client(scheduler)
    if client is not None:
        # a task's copy of the chunk reader keeps no chunk past its read:
        # per_task counts the chunk it decodes, whole where it is larger
        # than the block
        check_workers_fit(client, per_task, f"{where}: {what} the surface's blocks",
                          hint=f"{smaller}, or give the workers more memory", held=RUN_BYTES)
        return
    # the cache is counted at its limit, which a volume smaller than the limit does not fill: this process's
    # allocator keeps chunks and records freed before in its heaps (not trimmed, unlike a dask.distributed
    # worker's), and the peak of one store varies between runs by as much as the unfilled part
    fit = (default_budget() - cache - RUN_BYTES) // max(per_task, 1)
    hint = (f"run {fit} at a time (--threads {fit})" if fit >= 1 else
            smaller if blocks_help else f"{smaller}, or make more memory available")
    check_fits(workers * per_task + cache + RUN_BYTES, f"{where}: {what} the surface's blocks ({workers} at a time)",
               hint=hint)


def _cache_bytes(grid: BlockGrid, chunks, itemsize: int) -> int:
    """Decoded chunks of a layer of blocks along the first axis with the
    chunk layers either side (what its blocks read), and of the next layer
    of blocks, which starts while the last blocks of this one run."""
    thick = 2 * max(b - a for a, b in grid.bounds[0]) + 2 * chunks[0]
    return int(thick * grid.shape[1] * grid.shape[2] * itemsize)


def _checked_position(out: Path, suffix: str, layout: Layout, grid: BlockGrid, frame: DigitalObject) -> type:
    """The position type of the file, refusing what the format cannot hold."""
    position = _position_type(grid.shape, frame)
    if suffix == ".stl":
        if position is not np.float32:
            raise IsoflowError(f"{out}: binary STL holds float32 positions, which would move this surface's "
                               "vertices off the voxel grid (units far from 1, or far from the origin); write .ply")
        if layout.faces >= 2**32:
            raise IsoflowError(f"{out}: binary STL counts at most 2^32 - 1 triangles, this surface has "
                               f"{layout.faces:,}; crop the volume")
    elif layout.vertices >= 2**31:
        raise IsoflowError(f"{out}: PLY faces index their vertices with int32, this surface has "
                           f"{layout.vertices:,} vertices; write .stl (no shared vertices) or crop the volume")
    return position


def _header(suffix: str, layout: Layout, position, comments: tuple[str, ...], conn: int, where: str,
            space: str | None) -> bytes:
    if suffix == ".stl":
        text = stl_header(f"isoflow surface of {Path(where).name}, {conn}-connectivity", space).encode("ascii")
        return text.ljust(80, b" ") + np.uint32(layout.faces).tobytes()
    vdt = _vertex_dtype(position)
    tag = space_tag(space)
    return ply_header({k: vdt[k] for k in vdt.names}, layout.vertices, layout.faces,
                      (*comments, f"faces: {layout.kind}", *((tag,) if tag else ())))


def _file_size(suffix: str, layout: Layout, position, header: int) -> int:
    if suffix == ".stl":
        return header + layout.faces * STL_DTYPE.itemsize
    return header + layout.vertices * _vertex_dtype(position).itemsize + layout.faces * _face_dtype(layout.kind).itemsize


def _check_disk(out: Path, size: int) -> None:
    """Refuse a file larger than the free space beside the output."""
    import shutil

    from ..scale.memory import sized

    free = shutil.disk_usage(out.parent).free
    if size > free:
        raise IsoflowError(f"{out}: the surface file needs {sized(size)} on disk, {sized(free)} is free there")
