"""The shape report of volumes larger than memory: dask arrays and zarr stores.

:func:`analyze_chunked` returns exactly the dict of
``analyze(DigitalObject(np.asarray(array)), connectivity, surfaces)``
while holding only a few blocks at a time. The volume is read once, block
by block; each block is summed up on its own, in 3D by the vertex sweep of
the in-memory report (:mod:`isoflow.digital.blocks`), and hands on only
what crosses its faces and a few numbers per component on them:

* **The configuration histogram.** Vertex ``w`` sees the voxels ``w-1`` and
  ``w``. The block ``[a, b)`` counts the vertices ``a+1 .. b-1`` (and ``0``,
  ``b`` where it is the first, the last block); the seam between it and the
  next block counts the vertices ``b`` (:mod:`isoflow.digital.seams`). Each
  vertex is counted exactly once, no block is read twice or with a halo,
  and the 256 (16 in 2D) bins add up to the whole volume's histogram, from
  which chi, ``n``, ``a^T n`` and the energy follow
  (:func:`isoflow.digital.analysis.report_from_histogram`).
* **Components** (b0 and the enclosed background components). A block's
  components on its faces are nodes (``block << 32 | number``); the seams
  give the pairs of nodes that touch across a face, and the union-find
  over those edges (that of the sweep's pinches) gives ``b0 = nodes -
  merges``. The background on the volume's border is
  the outside, one node; the enclosed components are the others.
* **The closed surfaces.** The components of the boundary mesh's solid and
  of its complement form a tree whose edges are the surfaces
  (:func:`isoflow.digital.closed_surfaces.component_parents`). A block
  counts the surfaces of its components that touch no face and hands on
  the sums of those on its faces; the seams add what lies across the faces,
  and the tree over the joined components gives the others.
* **Doubled edges.** An edge is counted where both its ends are; a doubled
  spoke whose other end another block or seam counts is a loose end, and
  the edges whose two loose ends meet are doubled too.

Why not ``dask_image.ndmeasure.label``: it offsets every block's labels by
the counts of all earlier blocks and relabels the blocks after the global
merge, so every label block stays in memory until the merge is done: the
whole int32 label volume (32 GiB at 2048^3) for the border slices and the
component count. Counting needs only the faces, which is what this module
keeps; the tests check the two against each other.

Zarr input is read block by block inside each block's task, a block being
a chunk (or shard); a dask array is processed along its chunks. The blocks
go layer by layer along the first axis, or along the axis with the most
blocks where it has many more (each block's axes put in that order as it
is read), so peak memory is a few blocks per worker plus the faces of two
layers of blocks (and a few numbers per piece of a component on a face:
what the finished layers handed on settles into one record after each
layer, :mod:`isoflow.digital.settle`), never the volume or a label
volume. Blocks that would not fit in memory at the threads asked for are
refused before any is read.
"""

from __future__ import annotations

import dataclasses
import itertools
import os
import sys
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, check_callable, check_switch, given_text
from ..scale.arrays import NotBinary, binary, fill_value_named
from ..scale.chunks import (
    BlockTicks,
    SpatialAxes,
    argument_words,
    block_bounds,
    checked_block_shape,
    decoded_chunk_voxels,
    distributed_client,
    import_dask,
    is_zarr_array,
    layer_axes,
    never_written,
    smaller_blocks_help,
    unwritten_fill,
    zarr_blocks,
    zarr_volume,
)
from ..scale.chunks import compute as compute_tasks
from ..scale.compiled import thread_count, using
from .analysis import Place, placed, report_from_histogram
from .blocks import OUTSIDE, PENDING, SHIFT, summarize_block
from .closed_surfaces import subtree_sums, surface_counts, surfaces_from_counts
from .connectivity import resolve_connectivity
from .measures import BOX_AND_CENTROID, Extent, faces_per_axis, joined, unheld_dropped, world_measures
from .report import Report
from .seams import merge_block
from .settle import key_components, resolved_pieces, settle
from .surface import boundary_faces, pinch_lut
from .topology import euler_from_histogram


class _Grid(NamedTuple):
    """An array in blocks: the array (zarr or dask), whether it is zarr,
    per axis each block's [start, stop), and the number of blocks along
    each axis, these two in the order ``axes`` of the array's axes (the
    order the blocks are summed in: layers along ``axes[0]``)."""

    array: Any
    is_zarr: bool
    bounds: list
    numblocks: tuple
    axes: tuple

    def box(self, index) -> tuple:
        return tuple(self.bounds[axis][i] for axis, i in enumerate(index))

    def stored(self, index) -> tuple:
        """The block ``index`` (in the order ``axes``) in the array's order."""
        return tuple(index[i] for i in np.argsort(self.axes))


class _Job:
    """What a block's tasks are told: the block (``index`` in the grid
    ``numblocks``, its [start, stop) per axis ``box``), the volume's
    ``shape``, the connectivity, the name of the input, whether the surfaces
    are counted, and the order ``axes`` of the array's axes that these
    follow (the array's own where empty). One argument of a class of its
    own, which dask passes on as it is: it walks through every tuple, named
    tuple and dataclass among a task's arguments, twenty per block."""

    __slots__ = ("index", "box", "numblocks", "shape", "conn", "where", "surfaces", "axes")

    def __init__(self, index, box, numblocks, shape, conn: int, where: str, surfaces: bool, axes: tuple = ()):
        self.index, self.box, self.numblocks, self.shape = index, box, numblocks, shape
        self.conn, self.where, self.surfaces, self.axes = conn, where, surfaces, axes


# --------------------------------------------------------------------------
# the tasks (module-level functions so that process workers can run them)
# --------------------------------------------------------------------------


def _read_zarr_block(z, job: _Job) -> dict:
    """Read one block of a zarr array and summarise it.

    Reading inside the task (rather than through dask-array chunks) means a
    chunk is decoded where it is needed and dropped at once, whatever order
    the scheduler picks; blocks follow the chunk grid, so each chunk is
    decoded once.
    """
    box = _in_array_order(job.box, job.axes)
    try:
        data = np.asarray(z[tuple(slice(a, b) for a, b in box)])
    except Exception as exc:  # a damaged or missing chunk
        raise IsoflowError(f"{job.where}: cannot read the block at voxel {tuple(a for a, _ in box)} ({exc})") from None
    try:
        return _dask_block(data, job)
    except NotBinary as exc:
        raise fill_value_named(exc, getattr(z, "fill_value", None), z.dtype) from None


def _dask_block(chunk, job: _Job) -> dict:
    """Summarise one chunk of a dask array (no halo needed, see blocks),
    its axes put in the order ``job.axes`` first."""
    if job.axes:
        # checked in the array's order, so that an error names the voxel as the array holds it
        chunk = binary(chunk, job.where, near=tuple(a for a, _ in _in_array_order(job.box, job.axes)), canonical=False)
        chunk = np.ascontiguousarray(np.transpose(chunk, job.axes))
    return summarize_block(chunk, job.index, job.numblocks, tuple(a for a, _ in job.box), job.shape, job.conn,
                           job.where, job.surfaces)


def _in_array_order(box, axes: tuple) -> tuple:
    """A block's [start, stop) per axis, given in the order ``axes`` of the
    array's axes (the array's own where empty), in the array's order."""
    return tuple(box[i] for i in np.argsort(axes)) if axes else tuple(box)


def _merge(job: _Job, *summaries) -> dict:
    """:func:`isoflow.digital.seams.merge_block` of a block and its upper
    neighbours' summaries."""
    return merge_block(job.index, job.numblocks, job.box, job.shape, job.conn, job.surfaces, *summaries)


# --------------------------------------------------------------------------
# the final step
# --------------------------------------------------------------------------


def _components(nodes: int, edges: list[np.ndarray]) -> int:
    """Components of a graph with ``nodes`` nodes given by its cross-block
    edges (2, E). Only nodes that appear in an edge need the union-find;
    every other node is a component by itself."""
    pairs = np.concatenate(edges, axis=1) if edges else np.zeros((2, 0), np.int64)
    keys, comp = key_components(pairs, np.zeros(0, np.int64))
    return int(nodes - len(keys) + (comp.max(initial=-1) + 1))


def _betti(ndim: int, conn: int, chi: int, merged) -> list[int]:
    """b0 and the enclosed background components from the blocks' nodes and
    the edges between them: the seams' joins, and the pinches, which join
    what the mesh's adjacencies split (object pieces under 26, background
    pieces under 6); the outside is one more background node."""
    joins = {kind: [e for m in merged for e in m["joins"][kind]] for kind in ("fg", "bg")}
    joins["fg" if conn == 26 else "bg"] += [p for m in merged for p in m["pinches"]]
    b0 = _components(sum(m["nodes"]["fg"] for m in merged), joins["fg"])
    enclosed = _components(sum(m["nodes"]["bg"] for m in merged) + 1, joins["bg"]) - 1
    if ndim == 2:
        # as in topology.betti_numbers: b1 counts the holes, chi = b0 - b1
        assert b0 - enclosed == chi, "2D: chi must equal components minus holes"
        return [b0, enclosed]
    return [b0, b0 + enclosed - chi, enclosed]


def _joined_surfaces(merged) -> tuple[np.ndarray, np.ndarray]:
    """Mesh vertices and faces of the surfaces between components that
    touch a block face: the tree of the joined components (each one's
    parent is that of its first piece), its sums the pieces' and the seams'
    gains, and the surfaces the signed sums over the subtrees (as in
    :func:`isoflow.digital.closed_surfaces.surface_tree`)."""
    pieces = resolved_pieces(merged)
    joins = [e for m in merged for kind in ("fg", "bg") for e in m["joins"][kind]]
    nodes, comp = key_components(np.concatenate(joins or [np.zeros((2, 0), np.int64)], axis=1),
                                 np.append(pieces["key"], OUTSIDE))
    count, root = int(comp.max()) + 1, comp[np.searchsorted(nodes, OUTSIDE)]
    mine = comp[np.searchsorted(nodes, pieces["key"])]
    total = np.zeros((count, 2), np.int64)
    np.add.at(total, mine, pieces["sums"])
    gains = np.concatenate([g for m in merged for g in m["gains"]] or [np.zeros((3, 0), np.int64)], axis=1)
    np.add.at(total, comp[np.searchsorted(nodes, gains[0])], gains[1:].T)
    first = np.lexsort((pieces["order"], mine))
    first = first[np.diff(mine[first], prepend=-1) != 0]
    parent = pieces["parent"][first]
    assert (parent != PENDING).all() and (parent >= 0).all(), "every component's first piece knows its parent"
    up = np.arange(count)
    up[mine[first]] = comp[np.searchsorted(nodes, parent)]
    up[root], total[root] = root, 0
    total = subtree_sums(up, root, total)
    obj = np.zeros(count, bool)
    obj[mine] = pieces["obj"]
    total[~obj] *= -1
    return surface_counts(total[np.arange(count) != root])


def _surfaces(conn: int, chi: int, hist: np.ndarray, merged) -> dict:
    """The report's surfaces, pinched vertices and doubled edges."""
    joined = _joined_surfaces(merged)
    inner = np.concatenate([s for m in merged for s in m["surfaces"]] or [np.zeros((0, 2), np.int64)])
    vertices, faces = np.concatenate([joined[0], inner[:, 0]]), np.concatenate([joined[1], inner[:, 1]])
    assert faces.sum() == boundary_faces(hist), "the surfaces' faces do not add up"
    found = surfaces_from_counts(vertices, 4 * faces)
    pinched = int(hist[pinch_lut(conn)].sum())
    assert found.columns()["euler_characteristic"].sum() == 2 * chi + 2 * pinched
    # a doubled edge whose ends two tasks count: its key twice among the loose ends
    _, seen = np.unique(np.concatenate([e for m in merged for e in m["loose"]]), return_counts=True)
    assert (seen <= 2).all(), "an edge has two ends"
    doubled = sum(m["doubled"] for m in merged) + int(np.count_nonzero(seen == 2))
    return {"surfaces": found, "pinched_vertices": pinched, "doubled_edges": doubled}


def _finish(ndim: int, conn: int, shape, surfaces: bool, merged, place: tuple, axes: list[int]) -> dict:
    """Add up the blocks and build the report of an array of ``shape``,
    placed by ``place``, whose blocks were summed with its axes in the
    order ``axes``: the faces per axis and the voxels' extent are put back
    in the array's order, so that its world measures are computed as in
    memory, to the last bit."""
    hist = np.sum([m["hist"] for m in merged], axis=0)
    chi = euler_from_histogram(hist, ndim, conn)
    betti = _betti(ndim, conn, chi, merged)
    voxels = sum(m["voxels"] for m in merged)
    report = report_from_histogram(hist, ndim, conn, voxels=voxels, shape=shape, betti=betti, parity=0)
    order = np.argsort(axes)
    extent = joined([m["extent"] for m in merged])
    extent = None if extent is None else Extent(extent.lo[order], extent.hi[order], extent.sums[order])
    spacing, corner, unit = place
    report.update(world_measures(ndim, voxels, faces_per_axis(hist, ndim)[order], extent, spacing, corner, unit,
                                 tuple(int(n) for n in shape)))
    if surfaces and ndim == 3:
        report.update(_surfaces(conn, chi, hist, merged))
    return report


# --------------------------------------------------------------------------
# the graph
# --------------------------------------------------------------------------


def _checked(array, where: str | os.PathLike | None) -> tuple[tuple[int, ...], str]:
    """The shape of a dask or zarr array fit for the report, and the name
    of the input in messages; one-line errors for anything else."""
    is_zarr = is_zarr_array(array)
    if not is_zarr and not isinstance(array, import_dask()[1].Array):
        raise IsoflowError(f"analyze_chunked: array: a dask or zarr array is read block by block, not "
                           f"{type(array).__name__}; {_instead(array)}")
    if where is None:
        where = argument_words(array, "analyze_chunked")
    elif isinstance(where, os.PathLike):
        where = os.fsdecode(where)
    elif not isinstance(where, str):
        # a number or a list would be printed as the input's name in every later message
        raise IsoflowError(f"analyze_chunked: where names the input in messages, a str (or a path) or None; got "
                           f"{given_text(where)}")
    if any(np.isnan(s) for s in array.shape):
        raise IsoflowError(f"{where}: array shape {array.shape} is not known (call compute_chunk_sizes first)")
    shape = tuple(int(s) for s in array.shape)
    if len(shape) not in (2, 3):
        raise IsoflowError(f"{where}: a volume must be 2D or 3D, this array is {len(shape)}D with shape {shape}")
    dtype = np.dtype(array.dtype)
    if dtype.kind not in "biuf":
        raise IsoflowError(f"{where}: array of type {dtype} is not a binary {'image' if len(shape) == 2 else 'volume'}")
    return shape, where


def _instead(array) -> str:
    """What to call for an input that is not a chunked array: a store (its
    path, or the group an OME-Zarr image is, as ``voxelize_to_zarr`` writes
    it) was told to use the in-memory ``analyze``, which reads neither.

    Parameters
    ----------
    array : object
        What :func:`analyze_chunked` was given.

    Returns
    -------
    str
        The advice, for the end of the one-line error.

    Examples
    --------
    >>> _instead("scan.zarr")
    'isoflow.analyze_zarr(path) reads a zarr store (an OME-Zarr image: its first level)'
    """
    store = "isoflow.analyze_zarr(path) reads a zarr store (an OME-Zarr image: its first level)"
    if isinstance(array, (str, os.PathLike)):
        return store
    if type(array).__module__.split(".")[0] == "zarr" and hasattr(array, "arrays"):
        return f"{store}, or pass one of the group's arrays (group['0'])"
    if isinstance(array, np.memmap):  # on disk, perhaps beyond memory: not what analyze is for
        return "a memmap is read block by block as dask.array.from_array(volume, chunks=...); isoflow.analyze reads it whole"
    return "use isoflow.analyze for in-memory arrays"


def _grid(array, block_shape, where: str) -> _Grid:
    """The blocks: a zarr array's chunks (or shards, small ones grouped), a
    dask array's chunks, or ``block_shape``."""
    if is_zarr_array(array):
        chunks = zarr_blocks(array, block_shape)
    else:
        if block_shape is not None:
            array = array.rechunk(checked_block_shape(block_shape, array.shape))
        if any(np.isnan(c) for sizes in array.chunks for c in sizes):
            raise IsoflowError(f"{where}: chunk sizes are not known (call compute_chunk_sizes first)")
        if any(0 in sizes for sizes in array.chunks):  # a block of no voxel, which the sweep cannot take, adds nothing
            array = array.rechunk(tuple(tuple(c for c in sizes if c) for sizes in array.chunks))
        chunks = array.chunks
    if max(int(np.prod([max(c) for c in chunks])), 1) >= 1 << SHIFT:
        raise IsoflowError(f"{where}: blocks of {tuple(max(c) for c in chunks)} voxels are too large; use smaller chunks")
    axes = layer_axes(tuple(len(c) for c in chunks))
    return _Grid(array, is_zarr_array(array), block_bounds([chunks[i] for i in axes]),
                 tuple(len(chunks[i]) for i in axes), axes)


def _block_tasks(grid: _Grid, i: int, conn: int, where: str, surfaces: bool, shape) -> dict:
    """The summary tasks of the blocks of layer ``i`` along the grid's first axis."""
    dask, _ = import_dask(array=False)
    # the zarr array as one node of the graph: as an argument of every task
    # dask would walk through its fields (dataclasses) for each of them
    array = dask.delayed(grid.array, pure=False, traverse=False) if grid.is_zarr else None
    blocks: Any = None if grid.is_zarr else grid.array.to_delayed()
    tasks = {}
    for tail in itertools.product(*(range(n) for n in grid.numblocks[1:])):
        index = (i, *tail)
        job = _job(grid, index, shape, conn, where, surfaces)
        if grid.is_zarr:
            tasks[index] = dask.delayed(_read_zarr_block, pure=False)(array, job)
        else:
            tasks[index] = dask.delayed(_dask_block, pure=False)(blocks[grid.stored(index)], job)
    return tasks


def _job(grid: _Grid, index, shape, conn: int, where: str, surfaces: bool) -> _Job:
    """The :class:`_Job` of block ``index`` (``shape``, the volume's, in the
    grid's order of axes); its ``axes`` empty where that is the array's."""
    axes = grid.axes if list(grid.axes) != sorted(grid.axes) else ()
    return _Job(index, grid.box(index), grid.numblocks, tuple(shape), conn, where, surfaces, axes)


def _uppers(index, numblocks) -> list[tuple[int, ...]]:
    """The block and its existing upper neighbours, ``index + d`` for ``d``
    in ``{0,1}^n`` (C order)."""
    return [tuple(i + di for i, di in zip(index, d)) for d in itertools.product((0, 1), repeat=len(index))
            if all(i + di < n for i, di, n in zip(index, d, numblocks))]


def _layers(grid: _Grid, conn: int, where: str, surfaces: bool, shape, compute, progress) -> list[dict]:
    """Layer by layer along axis 0: merging layer i needs the summaries of
    layers i and i+1 only, so at most two layers of faces are held,
    whatever order dask would pick for one big graph (it tends to read
    most blocks before merging any). Within a layer the blocks and merges
    run in parallel."""
    dask, _ = import_dask(array=False)
    per_layer = int(np.prod(grid.numblocks[1:], dtype=np.int64))
    # a store of one layer of blocks, or a layer of thousands (4096^3 in chunks of 256^3 has 256),
    # is long work that a count of layers would leave silent: each block summed and merged is told
    ticks = BlockTicks(progress, 2 * per_layer * grid.numblocks[0], ("_read_zarr_block", "_dask_block", "_merge"))
    merged = []
    with ticks.callback():
        first = _block_tasks(grid, 0, conn, where, surfaces, shape)
        current = dict(zip(first, compute(*first.values())))
        for i in range(grid.numblocks[0]):
            upper = _block_tasks(grid, i + 1, conn, where, surfaces, shape) if i + 1 < grid.numblocks[0] else {}
            # the summaries computed already as leaves of the graph (dask would
            # walk through every dict and array of them as arguments)
            both = {**{index: dask.delayed(s, pure=False, traverse=False) for index, s in current.items()}, **upper}
            tasks = [dask.delayed(_merge, pure=False)(_job(grid, index, shape, conn, where, surfaces),
                                                      *(both[u] for u in _uppers(index, grid.numblocks)))
                     for index in current]
            done = compute(*tasks, *upper.values())
            merged.extend(done[:len(tasks)])
            if upper:  # later records name only the next layer's keys: the rest settles into one record
                merged = [settle(merged, (i + 1) * per_layer, conn)]
            current = dict(zip(upper, done[len(tasks):]))
            ticks.at((i + 1 + min(i + 2, grid.numblocks[0])) * per_layer)
    return merged


def _tasks_at_once(threads: int, is_zarr: bool, scheduler) -> int:
    """The workers of a local scheduler: one per thread, two for the
    threaded scheduler where the blocks are read from zarr. A zarr block's
    task waits while zarr's own threads read and decompress its chunk; a
    second task per thread sweeps another block meanwhile, so the cores
    are not left idle. Worker processes are not doubled: each holds a
    Python of its own."""
    return threads * (2 if is_zarr and not _in_processes(scheduler) else 1)


def _in_processes(scheduler) -> bool:
    """Whether ``scheduler`` (as dask.compute takes it) is dask's processes
    scheduler, by its name or its function."""
    return scheduler in ("processes", "multiprocessing") or getattr(scheduler, "__module__", "") == "dask.multiprocessing"


#: bytes per voxel of a bool block at work: the block, zarr's decoded chunk it is copied from and the sweep's passes
#: (2.6 measured on a store of one block of 256^3 voxels of a porous field, 0.6 of it the passes)
BLOCK_BYTES = 3
#: ... and of a block of another type beside twice its stored values (zarr's and NumPy's): the masks of its values
#: other than 0 and 1, and its bool copy
CHECK_BYTES = 4
#: bytes per voxel of the faces of a layer of blocks: a summary keeps 3 (its faces' numbers and voxels) and the
#: merges of the seams take the rest while they run. The summaries of two layers are held between layers (here;
#: a dask.distributed worker holds one layer's while the client holds the rest), and the merges' part does not
#: double with them: 10 to 13 measured in all per voxel of a layer's faces on stores of 256^3 to 640^3 voxels in
#: blocks of 64^3 and 128^3, where the faces outweigh the blocks at work (benchmarks/bench_store_estimate.py)
FACE_BYTES = 14
#: blocks (or the larger chunks they are read from) that the C allocator keeps in its heaps once freed: glibc
#: serves buffers of up to 32 MiB from per-thread heaps after the first is freed and keeps the freed ones there,
#: one or two in each heap of the threads that decode chunks (zarr's) and sum blocks. 1.3 to 4 blocks of 256^3 were
#: kept on 2 CPUs (a store of 512^3 peaked at 107 to 127 MiB, 43 MiB with MALLOC_ARENA_MAX=1, 37 MiB with
#: MALLOC_TRIM_THRESHOLD_=65536, which dask.distributed's nanny sets for its workers: these hold none)
KEPT_BLOCKS = 4


#: copies of a chunk larger than the block that a block's read holds at its peak: zarr's decoded chunk and
#: its decompression buffer (a 256^3 store in 128^3 chunks summed in 64^3 blocks on 2 threads peaked at 21.0 MiB
#: where one copy counted 20.0)
DECODED_COPIES = 2
#: bytes per voxel of the faces between the blocks of a layer that a dask.distributed worker holds: a block's
#: summary carries about 3 per voxel of its faces that touch another block (nothing for a face on the volume's
#: border, which needs no seam), and the worker holds the summaries of the layer its merges take, those of the
#: next layer it makes and the records the merges give, with the merges' own arrays while they run: 3 to 7
#: measured per voxel of these faces beside the blocks at work and WORKER_RUN_BYTES, 10 counted so that every
#: store of benchmarks/bench_worker_memory.py is estimated at 1.08 to 1.40 times its peak. The threads' term
#: (FACE_BYTES a voxel of every face of a layer: two layers' summaries beside the merges) is twice a worker's peak
WORKER_FACE_BYTES = 10
#: what a dask.distributed worker holds over a run whatever the size of its blocks and faces: its records of
#: the run's tasks and results, and the reader's buffers (a worker summing a 256^3 store in blocks of 64^3 rose
#: 1.5 to 2.5 MiB above its blocks and faces from run to run)
WORKER_RUN_BYTES = 3 << 20
#: the memory of a worker process of dask's processes scheduler beside its blocks: dask starts a fresh Python
#: for each layer's tasks, which imports NumPy, zarr, dask, numba and isoflow and loads the compiled passes
#: from numba's cache (the libraries' code is shared with this process; 64 MiB of its own measured in a process
#: that only merged, 80 to 93 MiB in those that read blocks of 64^3 and 128^3, benchmarks/bench_worker_memory.py)
PROCESS_BYTES = 90 << 20
#: blocks (or the larger chunks they are read from) that a worker process's allocator keeps once freed: it reads
#: one layer's blocks at most, and kept 1 to 3 of 256^3 (its peak varied by up to 37 MiB between runs of one
#: store); one beside PROCESS_BYTES and the faces its merges take covers the higher peaks too
PROCESS_KEPT_BLOCKS = 1

#: where the blocks are summed: this process's threads, dask's worker processes, dask.distributed's workers
SCHEDULERS = ("threads", "processes", "distributed")


class StoreMemory(NamedTuple):
    """What summing an array in blocks holds, in bytes: ``block``, one
    block's task at work (on a worker process, all that the process holds
    beside its share of the faces); ``faces``, the faces of the layers of
    blocks held between the layers for the merges; ``kept``, the blocks
    freed before that the C allocator keeps in its heaps in this
    process."""

    block: int
    faces: int
    kept: int


def store_memory(block: tuple[int, ...], numblocks: tuple[int, ...], dtype: Any, chunk_voxels: int = 0,
                 scheduler: str = "threads") -> StoreMemory:
    """The memory that :func:`analyze_chunked` counts for an array summed in
    blocks on ``scheduler``'s workers, ``threads * block + faces + kept``
    in all (:class:`StoreMemory`).

    On threads: what one block's task holds at work (:data:`BLOCK_BYTES`
    a voxel of a bool block, twice the stored bytes and
    :data:`CHECK_BYTES` for another type, and the chunk it is read from,
    :data:`DECODED_COPIES` times, where that chunk is larger), the faces
    of a layer of blocks (:data:`FACE_BYTES` a face voxel), and the
    blocks freed before that the allocator keeps (:data:`KEPT_BLOCKS`,
    as many as were read before the last). On worker processes (dask's
    processes scheduler) each holds a Python of its own
    (:data:`PROCESS_BYTES`) beside a block at work, the blocks its
    allocator keeps (:data:`PROCESS_KEPT_BLOCKS`) and the faces its merges
    take, while this process holds the faces. On a dask.distributed
    worker (whose allocator keeps no freed block) a task holds the chunk
    it decodes beside the block it copies out of it (and, for a type
    other than bool, :data:`CHECK_BYTES` a voxel), and the worker the
    faces between the blocks of a layer (:data:`WORKER_FACE_BYTES` a
    voxel) and :data:`WORKER_RUN_BYTES`.

    Parameters
    ----------
    block : tuple of int
        The sides of the largest block, the layers' axis first.
    numblocks : tuple of int
        The blocks along each axis in the same order: layers of blocks go
        along the first.
    dtype : numpy dtype or its name
        The stored values.
    chunk_voxels : int
        The voxels of the chunk zarr decodes to give a block
        (:func:`~isoflow.scale.chunks.decoded_chunk_voxels`), counted where
        it is larger than the block; 0 where the blocks are the chunks.
    scheduler : str
        Where the blocks are summed: ``"threads"`` (or one at a time) in
        this process, ``"processes"`` on dask's worker processes,
        ``"distributed"`` on a dask.distributed worker.

    Returns
    -------
    StoreMemory
        ``(block, faces, kept)``. The check here holds ``threads * block +
        faces + kept`` to the memory budget (``threads`` worker processes
        for ``"processes"``); on a dask.distributed cluster, ``threads *
        block + faces + kept`` with a worker's threads to its memory limit.

    Raises
    ------
    IsoflowError
        A ``scheduler`` other than these three.

    Examples
    --------
    >>> store_memory((64, 64, 64), (4, 4, 4), bool)  # a 256^3 store of bools in chunks of 64^3
    StoreMemory(block=786432, faces=5505024, kept=1048576)
    >>> store_memory((4, 4, 4), (2, 64, 64), "uint8", chunk_voxels=4 * 256 * 256).block  # 4^3 blocks of larger chunks
    524608
    >>> store_memory((128, 128, 128), (2, 2, 2), bool, scheduler="distributed")  # 256^3 in chunks of 128^3
    StoreMemory(block=4194304, faces=5111808, kept=0)
    """
    if scheduler not in SCHEDULERS:
        raise IsoflowError(f"store_memory: scheduler must be one of {', '.join(SCHEDULERS)}, got {given_text(scheduler)}")
    voxels = int(np.prod(block, dtype=np.int64))
    dtype = np.dtype(dtype)
    sides = [int(s) for s in block]
    areas = [int(np.prod(sides[:i] + sides[i + 1:], dtype=np.int64)) for i in range(len(sides))]
    layer = int(np.prod(numblocks[1:], dtype=np.int64))
    if scheduler == "distributed":
        # the read is a task's largest moment: the chunk decoded beside the block copied out of it (32.5 MiB
        # measured for a 256^3 block of bools); the sweep's passes come after the decoded chunk is let go
        at_work = (max(voxels, chunk_voxels) + voxels) * dtype.itemsize + (0 if dtype.kind == "b" else CHECK_BYTES * voxels)
        # the faces between blocks of the layer whose blocks have the most: both of their faces along the
        # layers' axis where there are layers on either side
        inner = sum(area * (min(n - 1, 2) * layer if axis == 0 else 2 * (n - 1) * layer // n)
                    for axis, (area, n) in enumerate(zip(areas, (int(n) for n in numblocks))))
        return StoreMemory(at_work, WORKER_FACE_BYTES * inner + WORKER_RUN_BYTES, 0)
    beyond = (DECODED_COPIES * chunk_voxels - voxels) * dtype.itemsize if chunk_voxels > voxels else 0
    at_work = voxels * (BLOCK_BYTES if dtype.kind == "b" else 2 * dtype.itemsize + CHECK_BYTES) + beyond
    faces = FACE_BYTES * 2 * sum(areas) * layer
    read_before = int(np.prod(numblocks, dtype=np.int64)) - 1
    if scheduler == "processes":
        # each worker process reads and sweeps its blocks, keeps freed ones in its own heaps and runs merges
        # on the summaries pickled to it; this process holds the layers' summaries between the layers
        kept = min(PROCESS_KEPT_BLOCKS, read_before) * max(voxels, chunk_voxels) * dtype.itemsize
        return StoreMemory(PROCESS_BYTES + at_work + kept + faces, faces, 0)
    return StoreMemory(at_work, faces, min(KEPT_BLOCKS, read_before) * max(voxels, chunk_voxels) * dtype.itemsize)


def _grid_memory(grid: _Grid, dtype, scheduler) -> StoreMemory:
    """:func:`store_memory` of ``grid``'s largest block (every block of
    the grid counted as large, every face of it) on the workers of
    ``scheduler`` (as dask.compute takes it)."""
    sides = tuple(max(b - a for a, b in bounds) for bounds in grid.bounds)
    on = "distributed" if distributed_client(scheduler) is not None else "processes" if _in_processes(scheduler) else "threads"
    return store_memory(sides, grid.numblocks, dtype, decoded_chunk_voxels(grid.array), on)


def _tasks_that_fit(workers: int, threads: int, need: StoreMemory, where: str, scheduler, is_zarr: bool,
                    blocks_help: bool) -> int:
    """The blocks summed at a time on this machine: ``workers``, or as many
    as the memory budget holds beside the layers' faces and the blocks the
    allocator keeps (``need``, :func:`store_memory`) where that is fewer
    but at least ``threads`` (a zarr store's second task per thread is
    left out first: it only spares the cores a wait). Blocks that would
    not fit ``threads`` at a time are refused up front, before any is
    read, saying how many would, where the blocks are summed here; one at
    a time on the synchronous scheduler. On a ``dask.distributed`` cluster
    (its client, its ``get``, or the default client) the workers hold
    their own memory: a block times a worker's threads, beside a layer's
    faces, is held to the workers' memory limit instead. On dask's worker
    processes ``need.block`` is a whole worker process, counted once for
    each. ``blocks_help``: whether smaller blocks would take less
    memory (:func:`~isoflow.scale.chunks.smaller_blocks_help`), else the
    refusal offers smaller chunks and more memory alone."""
    from dask.base import named_schedulers

    from ..scale.memory import check_fits, check_workers_fit, default_budget

    smaller = "write the store with smaller chunks" if is_zarr else "rechunk it"
    if not blocks_help:  # the chunk each block decodes is held whole, however small the block
        smaller += " (a chunk is decoded whole, however small the blocks)"
    client = distributed_client(scheduler)
    if client is not None:
        # the client holds the layers' summaries between layers (compute gathers them); a worker holds
        # those its merges take and give while they run (store_memory's worker terms)
        blocks = ", pass smaller blocks (block_shape)," if blocks_help else ","
        check_workers_fit(client, need.block, f"{where}: summing its blocks",
                          hint=f"{smaller}{blocks} or give the workers more memory", held=need.faces + need.kept)
        return workers
    if isinstance(scheduler, str):  # a name, as _scheduler leaves it once dask.distributed is imported
        scheduler = named_schedulers.get(scheduler.lower(), scheduler)
    if scheduler is not None and scheduler not in named_schedulers.values():
        return workers
    if scheduler is named_schedulers["sync"]:  # one task at a time, whatever the threads
        threads = workers = 1
    per_block, held = need.block, need.faces + need.kept
    budget = default_budget()
    fit = max(budget - held, 0) // max(per_block, 1)
    if fit >= workers:
        return workers
    room = ", or pass smaller blocks (block_shape)" if blocks_help else ", or make more memory available"
    hint = f"sum {fit} at a time (threads={fit}, isoflow info --threads {fit})" if fit >= 1 else smaller + room
    check_fits(threads * per_block + held, f"{where}: summing its blocks ({threads} at a time)", hint=hint,
               budget=budget)
    return int(fit)


def _fitted(array, block_shape, where: str, scheduler, threads) -> tuple[_Grid, Any, int]:
    """The blocks of ``array``, the scheduler and the blocks summed at a
    time (:func:`_tasks_that_fit`): blocks that would not fit in memory
    are refused here, before any chunk is read."""
    dask, _ = import_dask(array=False)
    grid = _grid(array, block_shape, where)
    scheduler = _scheduler(dask, scheduler)
    with using(threads):
        workers = _tasks_at_once(thread_count(), grid.is_zarr, scheduler)
        workers = _tasks_that_fit(workers, thread_count(), _grid_memory(grid, array.dtype, scheduler), where, scheduler,
                                  grid.is_zarr, smaller_blocks_help(grid.bounds, grid.array))
    return grid, scheduler, workers


def _scheduler(dask, scheduler):
    """The scheduler's function where it is named (or dask's configured one,
    by default threads), found without importing dask.distributed as dask
    does for a name, to look for a client: that import takes longer than
    the report of a small volume, and with distributed not imported no
    client exists."""
    from concurrent.futures import Executor

    from dask.base import named_schedulers

    # refused here, naming the argument: dask's ValueError ("Unexpected
    # scheduler: 5", "Expected one of [...]") named neither it nor isoflow;
    # what dask.compute takes passes (a name, a get function, a client, an executor)
    known = isinstance(scheduler, str) and scheduler.lower() in {*named_schedulers, "distributed", "dask.distributed"}
    if not (scheduler is None or known or callable(scheduler) or hasattr(scheduler, "get")
            or isinstance(scheduler, Executor)):
        raise IsoflowError(f"scheduler must be a dask scheduler's name ({', '.join(sorted(named_schedulers))}, "
                           f"distributed), a get function, a client or executor, or None, got {given_text(scheduler)}")
    if "distributed" in sys.modules or not (scheduler is None or isinstance(scheduler, str)):
        return scheduler
    name = scheduler or dask.config.get("scheduler", None) or "threads"
    return named_schedulers.get(name.lower(), scheduler) if isinstance(name, str) else name


# --------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------


def analyze_chunked(
    array: Any,
    connectivity: int | np.integer | None = None,
    *,
    block_shape: tuple[int | np.integer, ...] | None = None,
    scheduler: Callable | None = None,
    where: str | os.PathLike | None = None,
    progress: Callable[[int, int], object] | None = None,
    surfaces: bool = True,
    threads: int | np.integer | None = None,
    pitch: float | ArrayLike | None = None,
    origin: ArrayLike | None = None,
    unit: str | None = None,
) -> Report:
    """The report of :func:`isoflow.digital.analysis.analyze`, computed block
    by block.

    Parameters
    ----------
    array : dask.array.Array or zarr.Array
        A 2D or 3D array of bools or 0/1 numbers. A dask array is processed
        along its own chunks; a zarr array along its chunks (or shards;
        tiny chunks are grouped).
    connectivity : int, optional
        6 or 26 (4 or 8 in 2D); default 6 (4).
    block_shape : tuple of int, optional
        The blocks instead (a dask array is rechunked to it).
    scheduler : optional
        Passed to ``dask.compute``: default dask's configured one, threads;
        ``"processes"`` runs blocks in worker processes (only from code
        under ``if __name__ == "__main__":``; the memory check counts a
        Python of its own for each, :data:`PROCESS_BYTES`); a
        ``dask.distributed`` client's ``get`` runs them on its workers, a
        ``concurrent.futures`` executor on its own. Anything else is
        refused naming it.
    where : str or os.PathLike, optional
        The input's name in error messages (a path is taken as its text;
        anything else is refused); default: the function and its
        argument, ``analyze_chunked: array``, with a zarr store's name
        (``analyze_chunked: array (seg.zarr)``).
    progress : callable, optional
        ``progress(done, total)``, called as each block is summed and
        merged (``total`` twice the blocks; on a ``dask.distributed``
        cluster after each layer of blocks).
    surfaces : bool
        Count the closed surfaces, pinched vertices and doubled edges (3D).
    threads : int, optional
        Threads of the local scheduler (default
        :func:`isoflow.scale.compiled.thread_count`); each block's passes
        run on one thread and release the GIL. Blocks read from zarr run
        two tasks per thread, one of them mostly waiting for its chunk.
    pitch, origin, unit : optional
        The voxel size, the world position of voxel 0's lowest corner and
        their length unit, along the array's axes, as
        :func:`~isoflow.digital.analysis.analyze` takes them.

    Returns
    -------
    dict
        ``analyze(np.asarray(array), connectivity, surfaces, pitch=pitch,
        origin=origin, unit=unit)``, key for key.

    Raises
    ------
    IsoflowError
        Anything but a 2D or 3D dask or zarr array of 0 and 1 (named with
        ``where`` and the block's first voxel), blocks of 2^32 voxels,
        blocks that would not fit in memory at ``threads`` at a time on a
        local scheduler (saying how many would). An array with no voxels
        (a zero-length axis) has the empty report, as with ``analyze``.

    Notes
    -----
    Memory is a few blocks per worker plus the faces of two layers of
    blocks; the voxels are read once (see the module docs and
    ``docs/outofcore.md``).

    Examples
    --------
    >>> import dask.array as da
    >>> from isoflow import analyze
    >>> v = np.zeros((12, 10, 11), bool); v[2:10, 2:8, 2:9] = True; v[5:7, 4:6, :] = False  # a tunnel
    >>> r = analyze_chunked(da.from_array(v, chunks=(5, 4, 6)), 6)
    >>> r["betti"], r == analyze(v, 6)
    ([1, 1, 0], True)
    """
    check_callable(progress, "progress", "progress(done, total)")
    surfaces = check_switch(surfaces, "surfaces", "analyze_chunked")
    import_dask(array=False)
    shape, where = _checked(array, where)
    conn = resolve_connectivity(len(shape), connectivity)
    place = placed(None, len(shape), Place(pitch, origin, unit), "analyze_chunked")
    if 0 in shape:  # no block to read: the report of the empty array, as analyze gives it
        from .analysis import analyze

        return analyze(np.zeros(shape, bool), conn, surfaces=surfaces, pitch=place[0], origin=place[1], unit=place[2])
    grid, scheduler, workers = _fitted(array, block_shape, where, scheduler, threads)

    def compute(*tasks):
        return compute_tasks(*tasks, scheduler=scheduler, workers=workers, traverse=False)

    axes = list(grid.axes)
    try:
        merged = _layers(grid, conn, where, surfaces, [shape[i] for i in axes], compute, progress)
    except IsoflowError as exc:
        # a process worker's error comes back with its traceback in str();
        # keep the one-line message (and a label image's kind: the command
        # names the options that select labels, and which of them can)
        message = str(exc.args[0]) if exc.args else str(exc)
        if isinstance(exc, NotBinary):
            raise NotBinary(message, exc.bare, exc.every, exc.ndim, exc.kind, exc.value) from None
        raise IsoflowError(message) from None
    return Report.from_dict(_finish(len(shape), conn, list(shape), surfaces, merged, place, axes))


def analyze_in_xyz(array: Any, order: list[int], connectivity: int | None = None, *, pitch=None, origin=None,
                   unit: str | None = None, **options: Any) -> Report:
    """:func:`analyze_chunked` of an array whose x, y, z axes are its axes
    ``order`` (an OME-Zarr image stores z, y, x), with its ``pitch`` and
    ``origin`` in x, y, z order: the report's shape, box and centroid in
    x, y, z order too (the rest does not depend on the order).

    Examples
    --------
    >>> import dask.array as da
    >>> v = np.zeros((4, 3, 2), bool); v[3, 0, 1] = True  # stored (z, y, x): x = 1, y = 0, z = 3
    >>> r = analyze_in_xyz(da.from_array(v), [2, 1, 0], pitch=(1, 1, 2))
    >>> r.shape, r.bbox, r.centroid
    ([2, 3, 4], [1.0, 0.0, 6.0, 2.0, 1.0, 8.0], [1.5, 0.5, 7.0])
    """
    # (a store read by its path: the function called is analyze_zarr)
    spacing, corner, unit = placed(None, len(order), Place(pitch, origin, unit), "analyze_zarr")
    stored = np.argsort(order)  # stored axis i is axis stored[i] of x, y, z
    # placed at 0 and moved to the corner below, in x, y, z order: the sum
    # world_measures takes (corner + spacing * index), and a far
    # placement's warning then names the axes as the user gives them
    report = analyze_chunked(array, connectivity, pitch=spacing[stored], origin=np.zeros(len(order)), unit=unit,
                             **options)
    report = dataclasses.replace(report, shape=[int(report.shape[i]) for i in order])
    if report.bbox is None or report.centroid is None:  # an empty object's, or none in this dimension
        return report
    lo, hi, mid = (np.array([values[i] for i in order]) for values in
                   (report.bbox[:len(order)], report.bbox[len(order):], report.centroid))
    bbox, centroid = unheld_dropped([(corner + lo).tolist() + (corner + hi).tolist(), (corner + mid).tolist()],
                                    BOX_AND_CENTROID, corner, spacing, tuple(report.shape))
    return dataclasses.replace(report, bbox=bbox, centroid=centroid)


def analyze_zarr_volume(path: str | os.PathLike, connectivity: int | None = None, *,
                        block_shape: tuple[int, ...] | None = None, scheduler: Callable | None = None,
                        surfaces: bool = True, threads: int | None = None,
                        progress: Callable[[int, int], object] | None = None, pitch: float | ArrayLike | None = None,
                        origin: ArrayLike | None = None, unit: str | None = None) -> Report:
    """:func:`analyze_chunked` on the volume of a zarr store (v2 or v3),
    placed by the ``pitch``, ``origin`` and ``unit`` given alone:
    :func:`isoflow.analyze_zarr` places it where the store says it is.

    Parameters
    ----------
    path : str or pathlib.Path
        A zarr array, or a group with an array named ``volume`` or only one
        array; an OME-Zarr image (its first level, or ``IMAGE.zarr:LEVEL``
        by the level's path or index), whose channel and time axes of
        length 1 are left out.
    connectivity, block_shape, scheduler, surfaces, threads, progress
        As in :func:`analyze_chunked`.
    pitch, origin, unit : optional
        The voxel size, the world position of voxel 0's lowest corner and
        their unit, in (x, y, z) order, for the world measures (default
        unit voxels at 0: :func:`isoflow.analyze_zarr` and ``isoflow info``
        pass the store's own, which :func:`isoflow.read_volume` reads).

    Returns
    -------
    dict
        The report, as :func:`isoflow.digital.analysis.analyze` gives it,
        ``shape``, ``bbox`` and ``centroid`` in (x, y, z) order (an
        OME-Zarr image stores z, y, x).

    Raises
    ------
    IsoflowError
        A path that is no zarr store, a group without one volume, an
        OME-Zarr axis other than x, y, z with several entries, or the
        errors of :func:`analyze_chunked`, with the path.

    Warns
    -----
    IsoflowWarning
        Chunks never written whose fill value is nonzero: zarr reads them
        as the fill value, so their voxels count as the object's.

    Notes
    -----
    Before the full pass, the blocks are checked against the memory budget,
    then the dtype and the first block's values, so that a non-binary
    volume fails at once with the path in the message (every block is
    checked again as it is read).

    Examples
    --------
    >>> import tempfile, zarr
    >>> v = np.zeros((8, 8, 8), bool); v[1:7, 1:7, 1:7] = True; v[3:5, 3:5, 3:5] = False  # a cavity
    >>> with tempfile.TemporaryDirectory() as d:
    ...     z = zarr.create_array(store=d + "/v.zarr", shape=v.shape, chunks=(3, 5, 4), dtype=bool)
    ...     z[...] = v
    ...     analyze_zarr_volume(d + "/v.zarr")["betti"]
    [1, 0, 1]
    """
    z, order = zarr_volume(path)
    where = str(path)
    if z.ndim not in (2, 3):
        raise IsoflowError(f"{where}: a volume must be 2D or 3D, this array is {z.ndim}D with shape {tuple(z.shape)}")
    dtype = np.dtype(z.dtype)
    if dtype.kind not in "biuf":
        raise IsoflowError(f"{where}: array of type {dtype} is not a binary {'image' if z.ndim == 2 else 'volume'}")
    if dtype.kind != "b" and 0 not in z.shape:
        # the memory check first: the first chunk, decoded whole, may be what does not fit
        _fitted(z, block_shape, where, scheduler, threads)
        try:
            first = np.asarray(z[tuple(slice(0, int(c)) for c in z.chunks)])
        except Exception as exc:  # a damaged or missing chunk, as _read_zarr_block says
            raise IsoflowError(f"{where}: cannot read the block at voxel {(0,) * z.ndim} ({exc})") from None
        try:
            binary(first, where, near=(0,) * z.ndim)
        except NotBinary as exc:
            raise fill_value_named(exc, getattr(z, "fill_value", None), z.dtype) from None
    report = analyze_in_xyz(z, order, connectivity, block_shape=block_shape, scheduler=scheduler, where=where,
                            surfaces=surfaces, threads=threads, progress=progress, pitch=pitch, origin=origin,
                            unit=unit)
    never_written(where, unwritten_fill(z.array if isinstance(z, SpatialAxes) else z))
    return report
