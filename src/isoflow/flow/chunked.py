"""The digital curvature flow beyond memory: every state a zarr store, every
step slabs of layers as dask tasks (the plain flow; eqs. 5.15-5.18).

A step's move at a vertex needs its configuration (two voxel layers) and
the ends of its segments, which may run far along any axis. A slab of
vertex layers ``i0 <= i < i1`` reads voxel layers ``i0 - 1 .. i1 - 1``
(:func:`isoflow.scale.flowbits.moves3_layers`) and holds every segment
along the second and third axes whole, as it spans them; a segment along
the first axis may leave it. Whether such a segment's end beyond the slab
is negative is what the slabs hand on, per vertex line ``(j, k)``:

1. every slab, given nothing, says what it hands on upward and downward
   and along which lines its cross-section changes (where it does not, it
   hands on what it is given): bit arrays of one face each;
2. a scan over the slabs composes them, so that each slab gets what the
   slabs below and above hand it;
3. every slab computes its moves with that, and writes its vertex layers
   to a scratch store; the bounding box of all of them is copied to the
   step's store (an OME-Zarr image, axes stored x, y, z).

The result equals the in-memory flow's states. The records come from the
block-wise report (:func:`isoflow.digital.outofcore.analyze_chunked`).
Topology changes are found (the Betti numbers of consecutive states) but
not located: the place is where the guard's sweeps over the whole surface
get stuck, and those sweeps go in one order over all of it, so ``where``
is None. For the same reason the guarded flow is not done block by block
(:func:`guard_refusal`).

Memory is a few slabs per worker (two bytes per voxel of a slab, and its
bit rows) and faces; the slabs are as thick as fits :data:`SLAB_VOXELS`,
and thin enough that each step's record can sum the step's store, chunked
as thick as they are. The input's chunks, each decoded whole, are checked
before any is read (:func:`check_chunks_fit`).
The tasks take paths, so they run on a ``dask.distributed`` cluster
(``scheduler=client.get``, or the default client where the scheduler is
None, for the slabs and the records alike) where the stores are on a
shared file system.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..digital.lattice import DigitalObject
from ..errors import IsoflowError, check_callable, check_switch, counted, some_of
from ..mesh.outputs import remove_entry
from ..scale.chunks import (
    compute,
    decoded_chunk_voxels,
    import_dask,
    import_zarr,
    never_written,
    store_name,
    unwritten_fill,
)
from ..scale.memory import check_fits, default_budget, sized
from .engines import ArrayFlow

#: voxels of one slab (a slab reads them as bytes and writes as many)
SLAB_VOXELS = 1 << 25
#: chunk sides of the step stores along the second and third axes
CHUNK_YZ = 256


@dataclass(frozen=True)
class StoredObject:
    """A state of the flow held in a zarr store: ``path`` (None when
    empty), its ``shape`` (x, y, z), ``place`` (offset, parity, pitch,
    origin; its own volume empty) and ``voxels``."""

    path: str | None
    shape: tuple[int, int, int]
    place: DigitalObject
    voxels: int

    @property
    def parity(self) -> int:
        return self.place.parity

    @property
    def ndim(self) -> int:
        return 3

    def array(self):
        """The state's zarr array (x, y, z; uint8 0/1)."""
        return import_zarr().open_group(self.path, mode="r")["0"]


def _layers(path: str, a: int, b: int, shape: tuple[int, int, int]) -> np.ndarray:
    """Voxel layers ``a <= x < b`` of the store's volume (``shape``), as
    bools; layers outside the volume are empty."""
    out = np.zeros((b - a, *shape[1:]), bool)
    lo, hi = max(a, 0), min(b, shape[0])
    if hi > lo:
        out[lo - a:hi - a] = import_zarr().open_group(path, mode="r")["0"][lo:hi] != 0
    return out


def _slab_moves(path: str, shape, i0: int, i1: int, table, before=None, after=None):
    """The moves of vertex layers ``i0 <= i < i1`` of the state in ``path``:
    :func:`isoflow.scale.flowbits.moves3_layers` of voxel layers ``i0 - 1
    .. i1 - 1`` (one thread: the slabs are the parallel work)."""
    from ..scale import bitrows, flowbits
    from ..scale.compiled import using

    vol = _layers(path, i0 - 1, i1, shape)
    with using(1):
        bits = bitrows.pack(vol)[0]
        return flowbits.moves3_layers(bits, vol.shape, table, 1, vol.shape[0], before, after, hand_on=True)


def _slab_ends(path: str, shape, i0: int, i1: int, table):
    """Pass 1: what the slab hands on with nothing given (``before``,
    ``after``) and where its cross-section changes."""
    return _slab_moves(path, shape, i0, i1, table)[1:]


def _slab_keep(path: str, shape, i0: int, i1: int, table, before, after, scratch: str):
    """Pass 3: the slab's vertex layers, written to ``scratch`` (the vertex
    grid); returns their bounding box in the grid (``lo``, ``hi``) or None."""
    from ..scale import flowbits

    keep = _slab_moves(path, shape, i0, i1, table, before, after)[0]
    grid = (i1 - i0 + 2, shape[1] + 1, shape[2] + 1)
    vol = flowbits.unpack(keep, grid)[1:-1]
    import_zarr().open_group(scratch, mode="r+")["0"][i0:i1] = vol.view(np.uint8)
    if not vol.any():
        return None
    nz = [np.flatnonzero(vol.any(axis=tuple(a for a in range(3) if a != axis))) for axis in range(3)]
    return [int(i0 + nz[0][0]), int(nz[1][0]), int(nz[2][0])], [int(i0 + nz[0][-1] + 1), int(nz[1][-1] + 1),
                                                                 int(nz[2][-1] + 1)]


def _hand_on(ends: list) -> tuple[list, list]:
    """Pass 2: what each slab is handed from below and from above, given
    each slab's ``(before, after, changed)`` with nothing handed to it."""
    zero = np.zeros_like(ends[0][0])
    below, above = [zero], [zero]
    for before, _, changed in ends[:-1]:
        below.append((changed & before) | (~changed & below[-1]))
    for _, after, changed in ends[:0:-1]:
        above.append((changed & after) | (~changed & above[-1]))
    return below, above[::-1]


def _create_store(path: Path, shape, chunks, place: DigitalObject, unit: str | None = None) -> None:
    """An empty OME-Zarr image (NGFF 0.4, one level ``0`` of uint8, axes
    stored x, y, z) placed as ``place``, in the length ``unit`` (isoflow's
    spelling, or None), for slabs to write into."""
    from ..mesh.formats.omezarr import multiscales

    root = import_zarr().open_group(str(path), mode="w", zarr_format=2)
    root.create_array("0", shape=tuple(shape), chunks=tuple(chunks), dtype=np.uint8, fill_value=0)
    corner = place.world(np.zeros(3))
    root.attrs["multiscales"] = multiscales(path.name, place.spacing, corner, stored="xyz", unit=unit)


def slab_thickness(shape: tuple[int, int, int], slab: int | None, workers: int, scheduler: Any = "threads",
                   where: str | None = None) -> int:
    """Vertex layers per slab: ``slab``, or as many as fit
    :data:`SLAB_VOXELS` and the memory budget on ``workers`` at a time; on
    a ``dask.distributed`` cluster, as many as fit a worker's memory limit
    as many at a time as it has threads (the workers hold their own
    memory, which this machine's says nothing of). The step stores are
    chunked as thick as the slabs, and each step's record sums its store
    in blocks of those chunks: the slabs are thin enough for that too.

    Parameters
    ----------
    shape : tuple of int
        The state's volume (x, y, z); the slabs go along x.
    slab : int or None
        Vertex layers per slab, or None to size them.
    workers : int
        Slabs at a time on dask's local schedulers.
    scheduler : optional
        What the slabs' tasks are computed with (default: dask's threads
        here; a client or its ``get`` runs them on its workers, and None
        on dask's configured scheduler, a default client's too).
    where : str, optional
        The input, named where the records' report would not fit.

    Returns
    -------
    int

    Raises
    ------
    IsoflowError
        The workers' slabs, or the report of a step's store in chunks of
        their layers, would not fit in memory (up front), saying how many
        workers (``--threads N, workers=N``) slabs of one layer and their
        reports would fit, how thick a slab would fit a cluster's worker,
        what cross-section the report holds, or ``slab`` is not positive.

    Examples
    --------
    >>> slab_thickness((100, 1023, 1023), None, 2)
    32
    """
    from ..scale.chunks import distributed_client
    from ..scale.memory import check_workers_fit, default_budget, worker_room

    _, ny, nz = shape
    layer = (ny + 1) * (nz + 1)
    client = distributed_client(scheduler)
    per_layer = _layer_bytes(layer)
    if client is None:
        budget: int | None = default_budget()
    else:  # a slab per thread of a worker, in the worker's memory
        room = worker_room(client)
        # a worker also sums the blocks of the step's store for its record, a chunk of the slab's layers
        # each, beside a layer of those blocks' faces
        record_layer, held = _record_bytes(shape)
        budget, workers = (None if room is None else room[0] // room[1] - held), 1
        per_layer = max(per_layer, record_layer)
    if slab is None:
        # thinner slabs where the budget is short: the flow is the same, in more tasks
        thick = SLAB_VOXELS // layer if budget is None else budget // max(workers * per_layer, 1) - 2
        thick = max(1, min(SLAB_VOXELS // layer, thick))
        if client is None and budget is not None:  # thin enough for the records' report of the step's store
            thick = _thickest(thick, lambda t: _record_need(shape, t, workers, scheduler)[0] <= budget)
    else:
        thick = int(slab)
    if thick < 1:
        raise IsoflowError(f"slab must be a positive number of layers, got {slab}")
    what = f"the flow's slabs of {counted(thick, 'layer')} of {ny + 1} x {nz + 1} vertices"
    across = "its layers across x do not fit one at a time"
    if client is not None:
        fit = -1 if budget is None else budget // per_layer - 2  # the thickest slab a worker's thread holds
        hint = (f"slabs of {counted(fit, 'layer')} fit (slab={fit})" if fit >= 1 else
                f"{across} on a worker: crop the volume across them")
        check_workers_fit(client, (thick + 2) * per_layer, what, hint=f"{hint}, or give the workers more memory",
                          held=held)
        return thick
    need = workers * (thick + 2) * per_layer
    fit = budget // (3 * per_layer)  # the workers whose slabs of one layer fit
    if need > budget and fit >= 1 and (slab is None or thick == 1):
        # fewer workers are named only where each step's report of such slabs
        # fits them too: else following the hint meets the report's refusal
        fit = next((n for n in range(min(fit, workers), 0, -1) if _record_need(shape, 1, n, scheduler)[0] <= budget), 0)
        if not fit:  # not even one at a time: what the report needs (a narrower cross-section)
            _check_record_fits(shape, 1, 1, scheduler, budget, where)
    # slabs sized here (slab None, as the command line's always are) are as
    # thick as fit: only a slab asked for is too thick, and only Python asks
    hint = ("give thinner slabs (slab=)" if slab is not None and thick > 1 else
            f"slabs of one layer fit {fit} at a time ({_workers_words(fit)})" if fit >= 1 else
            f"{across}: crop the volume across them")
    check_fits(need, f"{what} ({workers} at a time)", hint=hint, budget=budget)
    _check_record_fits(shape, thick, workers, scheduler, budget, where, asked=slab is not None)
    return thick


def _slabs_fit(shape: tuple[int, int, int], slab: int | None, workers: int, scheduler: Any) -> bool:
    """Whether :func:`slab_thickness` sizes the slabs of a state of
    ``shape`` on ``workers`` without a refusal."""
    try:
        slab_thickness(shape, slab, workers, scheduler)
    except IsoflowError:
        return False
    return True


def _workers_words(n: int) -> str:
    """How a refusal names ``n`` slabs or chunks at a time that would fit,
    in the words of both of its callers, ``isoflow flow STORE --volumes
    .zarr --threads N`` and ``flow_chunked(..., workers=N)``, as the
    refusals of a label name ``--label N (label=N)``:

    >>> _workers_words(1)
    '--threads 1, workers=1'
    """
    return f"--threads {n}, workers={n}"


def _at_once(workers: int, scheduler: Any) -> int:
    """The tasks a local ``scheduler`` runs at a time: one on dask's
    synchronous scheduler, else ``workers``."""
    return 1 if scheduler in ("sync", "synchronous", "single-threaded") else workers


def _thickest(most: int, fits: Callable[[int], bool]) -> int:
    """A thickness from ``most`` down to 1 that ``fits``, within a
    sixteenth of the largest (1 where none does: its refusal names what
    would fit). Not a bisection: thinner chunks may be grouped into larger
    blocks (:func:`~isoflow.scale.chunks.zarr_blocks`), so a thinner slab
    may not fit where a thicker one does."""
    thick = most
    while thick > 1 and not fits(thick):
        thick -= max(1, thick // 16)
    return max(thick, 1)


def _record_need(shape: tuple[int, int, int], thick: int, workers: int, scheduler: Any) -> tuple[int, int, int, tuple]:
    """What the records' report holds on this machine summing a step's
    store of ``shape`` in chunks of ``thick`` layers (``CHUNK_YZ`` across),
    as :func:`isoflow.digital.outofcore.analyze_chunked` counts it before
    it reads a block: its blocks (the chunks, grouped where they are many
    and small) at ``workers`` threads, beside the faces of a layer of them
    and the blocks the allocator keeps. ``(need, per block, held, block
    sides in x, y, z)``."""
    from types import SimpleNamespace

    from ..digital.outofcore import store_memory
    from ..scale.chunks import layer_axes, zarr_blocks

    chunks = (thick, min(CHUNK_YZ, shape[1]), min(CHUNK_YZ, shape[2]))
    blocks = zarr_blocks(SimpleNamespace(shape=tuple(shape), chunks=chunks), None)
    axes = layer_axes(tuple(len(b) for b in blocks))
    local = "processes" if scheduler in ("processes", "multiprocessing") else "threads"
    need = store_memory(tuple(max(blocks[i]) for i in axes), tuple(len(blocks[i]) for i in axes), np.uint8,
                        int(np.prod(chunks)), local)
    threads = _at_once(workers, scheduler)
    held = need.faces + need.kept
    return threads * need.block + held, need.block, held, tuple(max(b) for b in blocks)


def _check_record_fits(shape: tuple[int, int, int], thick: int, workers: int, scheduler: Any, budget: int,
                       where: str | None, asked: bool = False) -> None:
    """Refuse, before any step's store is written, slabs of ``thick``
    layers whose step stores the records' report could not sum in memory
    (:func:`_record_need`), saying what would fit: thinner slabs where
    their thickness was ``asked`` (``slab=``, which the command line does
    not take: slabs it sizes are as thin as the report needs already),
    fewer workers, or a narrower cross-section (and the wider one that a
    single worker's report holds)."""
    need, block, held, sides = _record_need(shape, thick, workers, scheduler)
    if need <= budget:
        return
    _, ny, nz = shape
    thinner = _thickest(thick, lambda t: _record_need(shape, t, workers, scheduler)[0] <= budget)
    fit = max(budget - held, 0) // max(block, 1)
    if asked and _record_need(shape, thinner, workers, scheduler)[0] <= budget:
        hint = f"give thinner slabs (slab={thinner})"
    elif fit >= 1:
        hint = f"it fits {fit} at a time ({_workers_words(fit)})"
    else:
        def crop(s: int) -> tuple[int, int]:  # a square of side s, within the cross-section there is
            return min(s, ny), min(s, nz)

        def widest(n: int) -> int:  # the side of the square crop whose report fits n at a time, or 0
            side = _thickest(max(ny, nz), lambda s: _record_need((shape[0], *crop(s)), 1, n, scheduler)[0] <= budget)
            return side if _record_need((shape[0], *crop(side)), 1, n, scheduler)[0] <= budget else 0

        def words(s: int) -> str:  # a narrow cross-section is cropped along its long side alone
            return " x ".join(map(str, crop(s)))

        side, alone = widest(workers), widest(1) if _at_once(workers, scheduler) > 1 else 0
        # one thread holds a wider cross-section, which the line names (never the whole one: this
        # branch is where one block's report does not fit it)
        wider = alone > side and crop(alone) != crop(side)
        hint = (f"it holds the faces of a whole cross-section of {ny} x {nz} voxels: crop the volume across x"
                + (f" to {words(side)} voxels or less" if side else "")
                + (f"{', or' if side else ' to'} {words(alone)} at {_workers_words(1)}" if wider else ""))
    threads = _at_once(workers, scheduler)
    what = (f"{where + ': ' if where else ''}the report of each step (its store summed in blocks of "
            f"{' x '.join(map(str, sides))} voxels, {threads} at a time)")
    check_fits(need, what, hint=hint, budget=budget)


def _record_bytes(shape: tuple[int, int, int]) -> tuple[int, int]:
    """The memory a worker holds while the record's report sums the step's
    store in blocks of its chunks (``CHUNK_YZ`` across, a slab's layers
    along x), as :func:`isoflow.digital.outofcore.analyze_chunked` counts it
    on a cluster (:func:`~isoflow.digital.outofcore.store_memory`'s
    dask.distributed terms: a block at work beside one layer's faces): the
    part that grows with the chunk's layers, per layer, and the rest."""
    from ..digital.outofcore import store_memory

    cy, cz = min(CHUNK_YZ, shape[1]), min(CHUNK_YZ, shape[2])
    across = (-(-shape[1] // cy), -(-shape[2] // cz))

    def worker(layers: int) -> int:
        # the store's layers of blocks go along x, as many as its slabs
        need = store_memory((layers, cy, cz), (2, *across), np.uint8, scheduler="distributed")
        return need.block + need.faces

    # what the worker holds grows linearly with the chunk's layers: its slope and its value at none
    per_layer = worker(2) - worker(1)
    return per_layer, worker(1) - per_layer


def _layer_bytes(layer: int) -> int:
    """The memory of a slab's vertex layer of ``layer`` vertices: its bytes
    read and written, its bit rows (five arrays) and faces."""
    return 2 * layer + 6 * layer // 8


class ChunkedFlow(ArrayFlow):
    """States as zarr stores in ``directory`` (``step_NNN.zarr``, the step
    zero padded to ``width``), stepped by slabs of layers as dask tasks on
    ``scheduler``; the plain flow only."""

    def __init__(self, conn: int, directory, *, width: int = 3, slab: int | None = None, scheduler=None,
                 workers: int = 2):
        super().__init__(conn)
        self.directory, self.width, self.slab = Path(directory), width, slab
        self.scheduler, self.workers = scheduler, workers
        self.written: list[str] = []
        self.source_shape: tuple[int, ...] = ()
        self.unit: str | None = None  # the input's length unit, which every step's store keeps
        self.where: str | None = None  # the input, as refusals name it
        self._step = 0

    def _compute(self, *tasks):
        """The tasks computed on ``scheduler``: None is dask's configured
        scheduler or the default client where there is one, as the records'
        report takes it, else ``workers`` threads."""
        from ..scale.chunks import distributed_client

        local = self.scheduler in (None, "threads") and distributed_client(self.scheduler) is None
        return compute(*tasks, scheduler=self.scheduler, workers=self.workers if local else None)

    def _name(self) -> Path:
        name = f"step_{self._step:0{self.width}d}.zarr"
        self.written.append(name)
        return self.directory / name

    def start(self, source) -> StoredObject:
        """The input (a zarr store's volume, see :func:`source_volume`),
        cropped, as step 0's store."""
        from ..mesh.formats.omezarr import one_value_of_store, open_store
        from ..scale.arrays import NotBinary

        volume, place, fill = source_volume(source)
        store = open_store(source)
        self.unit, self.where = store.unit(), str(source)
        self.source_shape = tuple(int(s) for s in volume.shape)
        # its chunks are read whole, workers at a time, before any step's slabs or record is sized
        check_chunks_fit(volume, decoded_chunk_voxels(store.array), self.where, self.workers, self.scheduler,
                         self.slab)
        _, da = import_dask()

        def extents_of(checked):
            return self._compute(*(da.flatnonzero(checked.any(axis=tuple(a for a in range(3) if a != axis)))
                                   for axis in range(3)))

        checked = volume.map_blocks(_binary_block, dtype=bool, where=str(source), fill=fill)
        try:
            extents = extents_of(checked)
        except NotBinary as refused:
            # a store of 0 and one other value is that value's mask, as read_volume reads it
            value = one_value_of_store(store, refused)
            if value is None:
                raise
            checked = volume == value
            extents = extents_of(checked)
        if not len(extents[0]):
            raise IsoflowError(f"{source}: the object is empty, there is nothing to flow")
        # chunks never written of a fill value of 1 (or of the one value of a mask) are voxels of the
        # object: said as info of the store and the flow in memory say it, from the store's keys
        never_written(self.where, unwritten_fill(store.array))
        lo = [int(e[0]) for e in extents]
        hi = [int(e[-1]) + 1 for e in extents]
        place = replace(place, offset=tuple(lo))
        return self._store(checked[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]], place)

    def _store(self, box, place: DigitalObject) -> StoredObject:
        """A dask array written as the next step's store."""
        _, da = import_dask()
        shape = tuple(int(s) for s in box.shape)
        path = self._name()
        thick = slab_thickness(shape, self.slab, self.workers, self.scheduler, where=self.where)
        chunks = (thick, min(CHUNK_YZ, shape[1]), min(CHUNK_YZ, shape[2]))
        _create_store(path, shape, chunks, place, self.unit)
        target = import_zarr().open_group(str(path), mode="r+")["0"]
        voxels = box.astype(np.uint8).rechunk(chunks)
        count = voxels.sum(dtype=np.int64)
        _, total = self._compute(da.store(voxels, target, lock=False, compute=False), count)
        self._step += 1
        return StoredObject(str(path), shape, place, int(total))

    def record(self, state: StoredObject, step: int) -> dict:
        from ..digital.outofcore import analyze_chunked

        out = {"step": step, "voxels": state.voxels, "parity": state.parity, "betti": [0, 0, 0],
               "euler_characteristic": 0, "energy": 0, "bbox": None}
        if state.voxels:
            array = state.array()
            # the step's store named as the file it is (not the function called: the flow's own file)
            r = analyze_chunked(array, self.conn, surfaces=False, scheduler=self.scheduler, threads=self.workers,
                                where=store_name(array, str(state.path)))
            box = state.place.world(np.zeros(3)).tolist() + state.place.world(np.array(state.shape, float)).tolist()
            out.update(betti=list(map(int, r["betti"])), euler_characteristic=int(r["euler_characteristic"]),
                       energy=int(r["energy"]), bbox=box)
        return out

    def step(self, state: StoredObject) -> StoredObject:
        from dask import delayed

        from .bitflow import step_table

        _, da = import_dask()
        table = step_table(3, self.conn)
        shape = state.shape
        thick = slab_thickness(shape, self.slab, self.workers, self.scheduler, where=self.where)
        parts = [(a, min(a + thick, shape[0] + 1)) for a in range(0, shape[0] + 1, thick)]
        ends = self._compute(*(delayed(_slab_ends, pure=False)(state.path, shape, a, b, table) for a, b in parts))
        below, above = _hand_on(list(ends))
        scratch = self.directory / ".flow-scratch.zarr"
        grid = tuple(s + 1 for s in shape)
        _create_store(scratch, grid, (thick, min(CHUNK_YZ, grid[1]), min(CHUNK_YZ, grid[2])), state.place)
        try:
            boxes = [b for b in self._compute(*(
                delayed(_slab_keep, pure=False)(state.path, shape, a, b, table, below[s], above[s], str(scratch))
                for s, (a, b) in enumerate(parts))) if b is not None]
            place = state.place.on_dual_lattice()
            if not boxes:
                self._step += 1
                return StoredObject(None, (0, 0, 0), place, 0)
            lo = np.min([b[0] for b in boxes], axis=0)
            hi = np.max([b[1] for b in boxes], axis=0)
            place = replace(place, offset=tuple(int(o + a) for o, a in zip(place.offset, lo)))
            grid_array = da.from_zarr(import_zarr().open_group(str(scratch), mode="r")["0"])
            return self._store(grid_array[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]], place)
        finally:
            shutil.rmtree(scratch, ignore_errors=True)

    def change_region(self, state: StoredObject, betti: tuple[list, list] | None = None):
        return None  # not located out of core (module docstring)

    def discard(self, state: StoredObject) -> None:
        """Remove the store of a step not taken, so that the directory holds
        the states of the run's records only."""
        if state.path is not None:
            shutil.rmtree(state.path, ignore_errors=True)
            self.written.remove(Path(state.path).name)

    def same(self, a: StoredObject, b: StoredObject) -> bool:
        if a.shape != b.shape or a.voxels != b.voxels or not a.voxels:
            return False
        _, da = import_dask()
        return bool(self._compute((da.from_zarr(a.array()) == da.from_zarr(b.array())).all())[0])

    def to_object(self, state: StoredObject) -> StoredObject:
        return state  # never read into memory

    def is_cuboid(self, state: StoredObject) -> bool:
        return state.voxels == int(np.prod(state.shape))


def check_chunks_fit(volume: Any, chunk_voxels: int, where: str, workers: int, scheduler: Any = None,
                     slab: int | None = None) -> None:
    """Refuse, before any is read, an input whose chunks would not fit in
    memory read ``workers`` at a time (or on a ``dask.distributed``
    worker, its threads at a time): each is decoded whole and checked to
    be 0/1 (:func:`isoflow.digital.outofcore.store_memory` counts them as
    the report's blocks), saying how many would fit at a time, or how
    small the chunks would have to be (and how small at one at a time,
    where that holds larger ones). The workers it names are as many as
    the flow's slabs and each step's report of a volume of the input's
    shape fit too (:func:`slab_thickness`); where no count of them does,
    the refusal of those is raised instead.

    Parameters
    ----------
    volume : dask.array.Array
        The input as :func:`source_volume` reads it (x, y, z), along its
        chunks.
    chunk_voxels : int
        The voxels of the stored chunk a read decodes whole
        (:func:`~isoflow.scale.chunks.decoded_chunk_voxels`; larger than a
        chunk of ``volume`` where the store has other axes), or 0.
    where : str
        The input, for the message.
    workers : int
        Chunks read at a time on dask's local schedulers.
    scheduler : optional
        As :func:`slab_thickness` takes it.
    slab : int, optional
        The slabs' thickness asked for, as :func:`slab_thickness` takes it.

    Raises
    ------
    IsoflowError
        In one line, naming the chunks' shape and what would fit.

    Examples
    --------
    >>> import dask.array as da
    >>> check_chunks_fit(da.zeros((64, 64, 64), dtype=np.uint8, chunks=32), 0, "small.zarr", 2)
    >>> big = da.zeros((1 << 20, 1 << 20, 1 << 20), dtype=np.uint8, chunks=1 << 20)
    >>> check_chunks_fit(big, 0, "big.zarr", 2)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.DoesNotFit: big.zarr: reading its chunks of 1048576 x 1048576 x 1048576 voxels (uint8, 2 at a ...
    """
    from ..digital.outofcore import KEPT_BLOCKS, store_memory
    from ..scale.chunks import distributed_client
    from ..scale.memory import check_workers_fit, default_budget

    sides = tuple(max(int(c) for c in sizes) for sizes in volume.chunks)
    numblocks = tuple(len(sizes) for sizes in volume.chunks)
    voxels = max(int(np.prod(sides, dtype=np.int64)), chunk_voxels, 1)
    smaller = "write the store with smaller chunks"
    client = distributed_client(scheduler)
    if client is not None:
        need = store_memory(sides, numblocks, volume.dtype, chunk_voxels, "distributed")
        check_workers_fit(client, need.block, f"{where}: reading its chunks of {' x '.join(map(str, sides))} voxels "
                          f"({volume.dtype})", hint=f"{smaller}, or give the workers more memory")
        return
    need = store_memory(sides, numblocks, volume.dtype, chunk_voxels)
    threads = _at_once(workers, scheduler)
    budget = default_budget()
    fit = max(budget - need.kept, 0) // max(need.block, 1)
    if threads * need.block + need.kept > budget and fit >= 1:
        # fewer workers are named only where the steps' slabs and reports fit
        # them too, else following the hint meets their refusal; at one
        # worker that refusal is the one raised
        shape = tuple(int(s) for s in volume.shape)
        fit = next((n for n in range(min(fit, threads), 1, -1) if _slabs_fit(shape, slab, n, scheduler)), 1)
        if fit == 1:
            slab_thickness(shape, slab, 1, scheduler, where=where)
    if fit >= 1:
        hint = f"they fit {fit} at a time ({_workers_words(fit)}), or {smaller}"
    else:
        def largest(n: int) -> tuple[int, int]:  # the voxels of a chunk that fits n at a time, and a cube's side
            # per voxel: the chunks at work and the chunks the allocator keeps (KEPT_BLOCKS at most)
            most = int(budget // (n * need.block / voxels + KEPT_BLOCKS * np.dtype(volume.dtype).itemsize))
            side = int(round(most ** (1 / 3)))
            return most, side - (side ** 3 > most)

        (most, side), (alone, one) = largest(threads), largest(1)
        # one thread holds larger chunks, which the line names (never the ones there are: this branch
        # is where one of them does not fit)
        fewer = f"{alone} or fewer at {_workers_words(1)} (e.g. {one} x {one} x {one})"
        hint = (f"{smaller}, of {most} voxels or fewer (e.g. {side} x {side} x {side})"
                + (f", or {fewer}" if threads > 1 and one > side else "") if side >= 1 else
                f"{smaller}, of {fewer}" if one >= 1 else "make more memory available")
    check_fits(threads * need.block + need.kept, f"{where}: reading its chunks of {' x '.join(map(str, sides))} voxels "
               f"({volume.dtype}, {threads} at a time)", hint=hint, budget=budget)


def _binary_block(block: np.ndarray, where: str = "volume", fill=None, block_info=None) -> np.ndarray:
    """A block of the store as booleans; a value other than 0 and 1 that
    is the array's ``fill`` value is said to be it (zarr reads a chunk
    never written as the fill value)."""
    from ..scale.arrays import NotBinary, binary, fill_value_named

    near = None if block_info is None else tuple(lo for lo, _ in block_info[0]["array-location"])
    try:
        return binary(block, where, near=near)
    except NotBinary as exc:
        raise fill_value_named(exc, fill, block.dtype) from None


def source_volume(path: str | os.PathLike) -> tuple[Any, DigitalObject, Any]:
    """The volume of a zarr store (``IMAGE.zarr:LEVEL`` too) as a dask array
    in x, y, z order, its placement (a :class:`DigitalObject` with an empty
    volume), and the array's fill value (what zarr reads for a chunk never
    written; None where the array has none): what
    :func:`isoflow.read_volume` reads, lazily.

    Raises
    ------
    IsoflowError
        Not a zarr store, or not a 3D volume.

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> from isoflow.mesh.volumes import write_volume
    >>> path = tempfile.mkdtemp() + "/v.zarr"
    >>> _ = write_volume(DigitalObject(np.ones((2, 3, 4), bool), pitch=0.5), path)
    >>> volume, place, fill = source_volume(path)
    >>> volume.shape, place.spacing.tolist(), int(fill)
    ((2, 3, 4), [0.5, 0.5, 0.5], 0)
    """
    from ..mesh.formats.omezarr import open_store

    store = open_store(path)
    lazy = store.lazy()
    kept = [i for i in range(store.array.ndim) if i not in store.other]
    order = [kept.index(i) for i in store.xyz]
    if order != sorted(order):  # the kept axes in stored order (OME-Zarr's z, y, x), turned to x, y, z
        lazy = lazy.transpose(order)
    pitch, origin = store.placement()
    if lazy.ndim != 3:
        raise IsoflowError(f"{store.where}: the flow runs block by block on 3D volumes; this one is {lazy.ndim}D "
                           "(a 2D image is read into memory without --volumes .zarr)")
    place = DigitalObject(np.zeros((0, 0, 0), bool), pitch=1.0 if pitch is None else pitch, origin=origin)
    return lazy, place, getattr(store.array, "fill_value", None)


def guard_refusal(where: str, shape: tuple[int, ...]) -> str:
    """Why the guarded flow of a store is not done block by block, and what
    it would need in memory (one line).

    Examples
    --------
    >>> print(guard_refusal("big.zarr", (1024, 1024, 1024)).split(";")[0])  # doctest: +NORMALIZE_WHITESPACE
    big.zarr: --guard is not done block by block (a guarded step realises its moves cell by cell in one
    order over the whole surface)
    """
    need = 6 * int(np.prod(shape))  # the volume, its configuration bytes and the rows of a step
    return (f"{where}: --guard is not done block by block (a guarded step realises its moves cell by cell in one "
            f"order over the whole surface); in memory this {'x'.join(map(str, shape))} volume needs about "
            f"{sized(need)} of the {sized(default_budget())} available: flow it without --volumes .zarr, or without "
            "--guard")


def clear_earlier_run(directory: Path, force: bool) -> None:
    """Remove the ``step_*.zarr`` stores an earlier run left in
    ``directory`` where ``force``, else refuse them: a shorter run wrote
    over the first of them and left the rest, states of another run. A
    file or a symbolic link of such a name goes by itself (what a link
    leads to is kept).

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> (folder / "step_000.zarr").mkdir()
    >>> (folder / "step_000.zarr" / "zarr.json").write_text("{}")
    2
    >>> clear_earlier_run(folder, force=False)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: ...: holds the stores of an earlier run (step_000.zarr); ...
    >>> clear_earlier_run(folder, force=True); list(folder.iterdir())
    []
    """
    from .files import refuse_foreign_step

    earlier = sorted(directory.glob("step_*.zarr")) if directory.is_dir() else []
    for store in earlier:  # all checked before any goes: force replaces a run's stores, never a folder of the user's
        refuse_foreign_step(store)
    if earlier and not force:
        raise IsoflowError(f"{directory}: holds the stores of an earlier run "
                           f"({some_of([s.name for s in earlier], shown=1)}); give an empty directory, "
                           "or force=True to replace them")
    for store in earlier:  # a link (or a file) named as a step store goes as the store would; a link's target stays
        remove_entry(store)


def flow_chunked(source, directory, steps: int | None = None, connectivity: int = 6, *, max_steps: int | None = None,
                 until_topology_change: bool = False, slab: int | None = None, scheduler=None, workers: int = 2,
                 width: int = 3, progress=None, force: bool = False):
    """The plain flow of a zarr store's volume, block by block.

    Parameters
    ----------
    source : str or path
        A zarr store (``IMAGE.zarr`` or ``IMAGE.zarr:LEVEL``), 3D.
    directory : str or path
        An existing directory; every state is written into it as
        ``step_NNN.zarr`` (an OME-Zarr image, axes stored x, y, z, placed in
        the world), ``NNN`` zero padded to ``width``.
    steps, connectivity, max_steps, until_topology_change, progress
        As in :func:`isoflow.flow.run.run_flow` (``progress(step, state)``
        gets the stored state).
    slab : int, optional
        Vertex layers per task (default: :data:`SLAB_VOXELS` voxels).
    scheduler
        A dask scheduler, ``client.get`` of a ``dask.distributed`` client
        too; None (default): dask's configured scheduler, or the default
        client where there is one, else ``workers`` threads. The slabs and
        each step's record (:func:`isoflow.digital.outofcore.analyze_chunked`)
        run on it alike.
    workers : int
        Tasks in flight on the local schedulers (memory is sized for them;
        ``isoflow flow --threads N`` on the command line).
    force : bool
        Replace the ``step_*.zarr`` stores of an earlier run in
        ``directory`` (removed before this run starts); without it they
        are refused.

    Returns
    -------
    FlowResult
        As :func:`isoflow.flow.run.run_flow` returns it, without states and
        with ``where`` None in the topology changes.

    Raises
    ------
    IsoflowError
        A store that is not a 3D binary volume, an empty one, slabs that do
        not fit in memory, a directory holding an earlier run's stores
        without ``force``, a ``directory`` that is a file.

    Notes
    -----
    Eqs. 5.15-5.18; the segments along the first axis are joined across
    the slabs (module docstring).

    Examples
    --------
    >>> import tempfile, zarr, numpy as np
    >>> from pathlib import Path
    >>> folder = Path(tempfile.mkdtemp())
    >>> zarr.open_array(str(folder / "in.zarr"), mode="w", shape=(3, 3, 3), chunks=(2, 2, 2), dtype="u1")[...] = 1
    >>> r = flow_chunked(folder / "in.zarr", folder, slab=1)
    >>> [s["voxels"] for s in r.steps], sorted(p.name for p in folder.glob("step_*"))
    ([27, 8, 1, 0], ['step_000.zarr', 'step_001.zarr', 'step_002.zarr'])
    """
    from ..scale.compiled import thread_argument
    from .motion import flow_connectivity
    from .run import check_count, max_steps_for, run_engine

    conn = flow_connectivity(3, connectivity)
    # as run_flow refuses them, and before the input is cropped into the
    # first store: a bad one failed after it (progress, workers, width),
    # or ran another flow (steps=-1 none, 1.5 two steps, "no" stopped at a change)
    steps, max_steps = check_count("steps", steps), check_count("max_steps", max_steps)
    until_topology_change = check_switch(until_topology_change, "until_topology_change", "flow_chunked")
    check_callable(progress, "progress", "progress(step, state)")
    workers, width = thread_argument(workers, "workers"), thread_argument(width, "width")
    if Path(directory).exists() and not Path(directory).is_dir():  # before the input is read and cropped into it
        raise IsoflowError(f"{directory}: the directory for the step stores is not a directory")
    clear_earlier_run(Path(directory), check_switch(force, "force", "flow_chunked"))
    engine = ChunkedFlow(conn, directory, width=width, slab=slab, scheduler=scheduler, workers=workers)
    state = engine.start(source)
    cap = steps if steps is not None else max_steps_for(engine.source_shape) if max_steps is None else max_steps
    return run_engine(engine, state, cap=cap, capped="steps" if steps is not None else "max-steps",
                      until_topology_change=until_topology_change, progress=progress, unit=engine.unit)
