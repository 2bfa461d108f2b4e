"""Voxelising beyond memory: the volume written slab by slab into a chunked
OME-Zarr image, as dask tasks.

The store is an OME-Zarr image (NGFF 0.4, zarr format 2: one level ``0``
of uint8 0/1 with named axes and the scale and translation that place
every voxel), which the OME-Zarr readers open by axis name. Unlike
:func:`isoflow.write_volume`'s (z, y, x), its axes are stored (x, y, z), as
NGFF allows (it recommends z, y, x): a slab is a range of the first axis
(the scanline fills x-ranges of z-columns), a whole number of zarr chunks
thick and spanning the other two axes, so that no two tasks write the same
chunk, and ``isoflow info`` reads the store in layers of thin blocks along
that same axis, holding the faces of two layers only. Stored (z, y, x), a
slab would be a range of the last axis and those layers 8 times thicker.
Every task gets the :class:`~isoflow.mesh.voxelize.VoxelPlan` (O(triangles):
the mesh, its cap and the grid) and fills its slab exactly as the in-memory
voxeliser fills the same rows (same crossings, same rule), so the store
equals :func:`~isoflow.mesh.voxelize.voxelize`'s volume voxel for voxel.
Memory is bounded by a slab per worker plus the mesh.  The tasks are plain
``dask.delayed`` calls, so the same code runs on a ``dask.distributed``
cluster (``scheduler=client``) when the store is on a shared file system.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping
from contextlib import nullcontext
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, overload

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, check_callable, check_path, check_switch
from ..results import Result
from ..scale import memory
from ..scale.chunks import compute, import_dask, import_zarr
from .fills import Fill, Voxelization, look_up
from .formats.omezarr import multiscales
from .grid import GridTooLarge, check_grid_request, finest_fit, fmt_count, grid_words
from .load import load_mesh, mesh_arrays
from .mesh_units import declared_unit
from .outputs import atomic_path, check_writable_dir, refuse_nameless, remove_abandoned
from .store_plan import WORKERS, check_chunks, in_store, slab_chunks, slab_layout, store_need


def check_store_path(path, force: bool) -> Path:
    """A ``.zarr`` output checked before any work: an existing store is
    replaced only with ``force``, and only if it is a zarr store (never an
    arbitrary directory)."""
    check_switch(force, "force", str(path))
    refuse_nameless(path, (".zarr", ".ome.zarr"), "volume")  # ".ome.zarr" is a hidden name, no store's suffix
    path = Path(path)
    if path.suffix.lower() != ".zarr":
        raise IsoflowError(f"{path}: a zarr store must end in .zarr")
    remove_abandoned(path)  # a store a killed command left aside is put back: then it exists, as it did
    if path.exists():
        if not force:
            raise IsoflowError.worded(f"{path}: exists; pass force=True to overwrite",
                                      f"{path}: exists; pass --force to overwrite")
        marks = ("zarr.json", ".zarray", ".zgroup")
        if not path.is_dir() or not (any((path / m).exists() for m in marks) or not any(path.iterdir())):
            raise IsoflowError(f"{path}: exists and is not a zarr store; not replacing it")
    if not path.parent.exists():  # a file in its place is named as one by check_writable_dir
        raise IsoflowError(f"{path.parent}: no such directory (for the output {path.name})")
    check_writable_dir(path.parent, f"the zarr store {path.name}")
    return path


def _slab_task(plan, store: str, xa: int, xb: int, points=None):
    """Fill rows [xa, xb) and write them to the store's level; the slab's
    counts, and whether each of ``points`` (K, 3), voxels of the slab
    (:func:`~isoflow.mesh.fills.sampled_points`), is in."""
    zarr = import_zarr()
    stats = np.zeros(4, dtype=np.int64)
    vol = plan.fill(xa, xb, stats=stats, threads=1)
    z = zarr.open_group(store, mode="r+")["0"]
    z[xa:xb] = vol.view(np.uint8)
    found = look_up(vol, points, (xa, 0, 0)) if points is not None else None
    return int(np.count_nonzero(vol)), stats, found


def slab_points(plan, slabs):
    """The winding rule's sampled points (:meth:`VoxelPlan.sampled_points`)
    split by slab, so that each slab looks up its own as it is filled (the
    grid is never held, nor read back): ``(points, area, parts)``, ``parts``
    the indices into the flattened points of each slab's, or None where no
    sampled face has area."""
    sampled = plan.sampled_points()
    if sampled is None:
        return None
    idx, area = sampled
    flat = idx.reshape(-1, 3)
    inside = np.all((flat >= 0) & (flat < np.array(plan.shape)), axis=1)
    parts = [np.flatnonzero(inside & (flat[:, 0] >= a) & (flat[:, 0] < b)) for a, b in slabs]
    return flat, area, parts


@dataclass(frozen=True, eq=False, repr=False)
class ZarrStore(Result):
    """The store :func:`voxelize_to_zarr` wrote, in a few numbers.

    Reads as a mapping too (``z["voxels"]``, ``dict(z)``), as the results of
    isoflow's other functions do; :meth:`to_dict` is the same fields as JSON
    takes them (origin a list).

    Attributes
    ----------
    shape : tuple of int
        Level ``0``'s shape, (nx, ny, nz).
    chunks : tuple of int
        Level ``0``'s chunks.
    voxels : int
        Voxels in.
    pitch : float
    origin : float64 ndarray (3,)
        Lower corner of voxel (0, 0, 0).
    """

    shape: tuple[int, int, int]
    chunks: tuple[int, int, int]
    voxels: int
    pitch: float
    origin: np.ndarray

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> ZarrStore:
        """The store's summary of :meth:`to_dict`'s JSON: the shape and the
        chunks tuples, the origin an array again.

        Examples
        --------
        >>> import json
        >>> z = ZarrStore((2, 3, 4), (1, 3, 4), 5, 0.5, np.zeros(3))
        >>> back = ZarrStore.from_dict(json.loads(json.dumps(z.to_dict())))
        >>> back == z, back.shape, back.origin.tolist()
        (True, (2, 3, 4), [0.0, 0.0, 0.0])
        """
        given = dict(values)
        for key in ("shape", "chunks"):
            if key in given:
                given[key] = tuple(int(n) for n in given[key])
        if "origin" in given:
            given["origin"] = np.asarray(given["origin"], dtype=np.float64)
        return super().from_dict(given)


#: what :func:`voxelize_to_zarr` voxelises: a mesh file, (vertices, faces), or an object with both (a trimesh.Trimesh)
MeshSource = str | os.PathLike | tuple[ArrayLike, ArrayLike] | Any
#: ``progress(done, total)``
Progress = Callable[[int, int], object]


@overload
def voxelize_to_zarr(source: MeshSource, path: str | os.PathLike, *, pitch: float | None = None,
                     resolution: int | np.integer | None = None, fill: Fill = "winding", strict: bool = False,
                     force: bool = False, chunks: tuple[int | np.integer, int | np.integer, int | np.integer] | None = None,
                     scheduler: Callable | None = None,
                     max_bytes: int | np.integer | None = None, progress: Progress | None = None,
                     details: Literal[False] = False) -> ZarrStore: ...


@overload
def voxelize_to_zarr(source: MeshSource, path: str | os.PathLike, *, pitch: float | None = None,
                     resolution: int | np.integer | None = None, fill: Fill = "winding", strict: bool = False,
                     force: bool = False, chunks: tuple[int | np.integer, int | np.integer, int | np.integer] | None = None,
                     scheduler: Callable | None = None,
                     max_bytes: int | np.integer | None = None, progress: Progress | None = None,
                     details: Literal[True]) -> tuple[ZarrStore, Voxelization]: ...


def voxelize_to_zarr(source: MeshSource, path: str | os.PathLike, *, pitch: float | None = None,
                     resolution: int | np.integer | None = None, fill: Fill = "winding", strict: bool = False,
                     force: bool = False, chunks: tuple[int | np.integer, int | np.integer, int | np.integer] | None = None,
                     scheduler: Callable | None = None,
                     max_bytes: int | np.integer | None = None, progress: Progress | None = None,
                     details: bool = False) -> ZarrStore | tuple[ZarrStore, Voxelization]:
    """Voxelise a mesh into a chunked zarr array at ``path`` without holding
    the volume.

    The winding rule and the shell are filled slab by slab, as dask tasks;
    a flood fill needs the whole grid's shell at once, so it is refused
    where that does not fit in memory. The store is an OME-Zarr image (see
    the module docs; read it back with :func:`isoflow.read_volume`, or
    ``isoflow info STORE.zarr`` block by block).

    Parameters
    ----------
    source : str, os.PathLike, (vertices, faces) or object with ``vertices`` and ``faces``
        A mesh file, or the mesh's arrays (a ``trimesh.Trimesh``), taken as
        :func:`~isoflow.mesh.voxelize.voxelize` takes them.
    path : str or os.PathLike
        The store to write (a directory ``NAME.zarr``).
    pitch, resolution, fill, strict
        As :func:`~isoflow.mesh.voxelize.voxelize`.
    force : bool
        Replace an existing store.
    chunks : tuple of int, optional
        Level ``0``'s chunks; default slabs of at most 128 MiB by 256 x 256.
    scheduler : callable, optional
        Any dask scheduler (default: two threads).
    max_bytes : int, optional
        The memory budget the slabs must fit in.
    progress : callable, optional
        ``progress(done, total)``, called per slab (local schedulers); one
        with a ``rule`` method too
        (:class:`~isoflow.mesh.voxelize.RuleProgress`) is told, before the
        slabs, whether the winding rule sums solid angles.
    details : bool
        Also return the :class:`~isoflow.mesh.fills.Voxelization` (its
        volume None); without it, its note is issued as a
        :class:`~isoflow.errors.MeshNote` warning.

    Returns
    -------
    ZarrStore or (ZarrStore, Voxelization)
        The store's ``shape``, ``chunks``, ``voxels``, ``pitch`` and
        ``origin``, as attributes and as keys (:class:`ZarrStore`).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from isoflow import data, read_volume
    >>> store = pathlib.Path(tempfile.mkdtemp()) / "torus.zarr"
    >>> z = voxelize_to_zarr(data.torus(), store, resolution=24)
    >>> back = read_volume(store)
    >>> z.voxels == back.voxels, z["shape"] == back.volume.shape, z.origin.tolist() == back.origin.tolist()
    (True, True, True)
    >>> sorted(z.to_dict())
    ['chunks', 'origin', 'pitch', 'shape', 'voxels']
    """
    from .fills import check_fill, check_strict
    from .voxelize import Solid, plan_voxels, say_note, tell_rule, voxelization

    fill, strict = check_fill(fill, "voxelize_to_zarr"), check_strict(strict, "voxelize_to_zarr")
    # details="yes" would return the pair, as True does: refused, as voxelize_mesh refuses it
    details = check_switch(details, "details", "voxelize_to_zarr")
    check_grid_request(pitch, resolution, "voxelize_to_zarr")  # before the mesh is read, whose name the errors below carry
    check_callable(progress, "progress", "progress(done, total)")
    path = check_path(path, "path", "voxelize_to_zarr")
    if chunks is not None:
        try:
            chunks = check_chunks(chunks)
        except IsoflowError as exc:  # before the mesh is read, whose name the errors below carry
            raise exc.at("voxelize_to_zarr") from None
    path = check_store_path(path, force)
    where = os.fsdecode(source) if isinstance(source, (str, os.PathLike)) else "mesh"
    # a file names itself in its errors
    v, f = load_mesh(source) if isinstance(source, (str, os.PathLike)) else mesh_arrays(source, where)
    try:
        v, f, shape, what, frame, origin, pitch = plan_voxels(v, f, pitch=pitch, resolution=resolution)
        budget = memory.budget_of(max_bytes)
        solid = None

        def made() -> Solid:  # the mesh made ready once, for the grid asked and for those a refusal tries
            nonlocal solid
            if solid is None:
                solid = Solid(v, f, strict=strict, fill=fill)
            return solid

        # the columns and the slabs' volumes before any work (the slabs'
        # list is not made for a grid of more rows than memory holds)
        if (need := store_need(shape, chunks, fill)) is None or need > budget:
            raise store_refusal(v, f, what, shape, chunks, fill, budget, made, need)
        fits, plan, need = in_store(made(), frame, shape, chunks, fill, budget)
        if not fits:
            raise store_refusal(v, f, what, shape, chunks, fill, budget, made, need, temporaries=True)
        chunks, slabs = slab_layout(shape, chunks)
    except IsoflowError as exc:  # a refused grid keeps its kind and its command-line words
        raise exc.called("voxelize_to_zarr", "voxelize").at(where) from None
    import_dask()  # where dask is missing: the message that names the extra
    tell_rule(progress, plan.solid_angles)
    zarr = import_zarr()
    from dask import delayed
    from dask.callbacks import Callback

    # whole or not at all: the store is written beside the target and
    # renamed over it when complete (an interrupt, an error or a --strict
    # refusal leave the previous store as it was)
    with atomic_path(path, directory=True) as tmp:
        root = zarr.open_group(str(tmp), mode="w", zarr_format=2)
        root.create_array("0", shape=shape, chunks=chunks, dtype=np.uint8, fill_value=0)
        # the axes in the unit the mesh file declares, as voxelize_file's object has it
        unit = declared_unit(source) if isinstance(source, (str, os.PathLike)) else None
        root.attrs.update({"multiscales": multiscales(path.name, [float(pitch)] * 3, origin, stored="xyz", unit=unit),
                           "source": where,
                           "rule": RULES[fill]})
        plan_d = delayed(plan, pure=True)
        # the share of the area that bounds nothing (the thin-solid note),
        # looked up by each slab in the voxels it fills
        sampled = slab_points(plan, slabs) if fill == "winding" else None
        tasks = [delayed(_slab_task, pure=False)(plan_d, str(tmp), a, b,
                                                 sampled[0][sampled[2][n]] if sampled is not None else None,
                                                 dask_key_name=("voxelize-slab", n))
                 for n, (a, b) in enumerate(slabs)]
        done = [0]

        def posttask(key, result, dsk, state, worker_id):
            if isinstance(key, tuple) and key and key[0] == "voxelize-slab":
                done[0] += 1
                progress(done[0], len(slabs))

        with Callback(posttask=posttask) if progress is not None else nullcontext():
            workers = WORKERS if scheduler in (None, "threads") else None  # others: their own count
            results = compute(*tasks, scheduler=scheduler or "threads", workers=workers)
        voxels = shell = sum(r[0] for r in results)
        stats = np.sum([r[1] for r in results], axis=0)
        found = None
        if sampled is not None:
            flat, _, parts = sampled
            each = np.zeros(len(flat), dtype=bool)
            for part, r in zip(parts, results):
                each[part] = r[2]
            found = each.reshape(3, -1)
        if fill == "flood":
            voxels = flood_store(root["0"], slabs)
        try:  # refused: nothing replaces the previous store
            made().check_layers(stats)
            result = voxelization(made(), plan, None, voxels, origin, pitch, stats, shell_before=shell, found=found)
        except IsoflowError as exc:
            raise exc.at(where) from None
    nx, ny, nz = (int(n) for n in shape)
    cx, cy, cz = (int(n) for n in chunks)
    store = ZarrStore((nx, ny, nz), (cx, cy, cz), int(voxels), float(pitch), np.asarray(origin, dtype=np.float64))
    if details:
        return store, result
    say_note(result.note)
    return store


def store_refusal(v, f, what: str, shape, chunks, fill: Fill, budget: int, made, need: int | None,
                  temporaries: bool = False) -> GridTooLarge:
    """The refusal of a store of ``shape`` (``need`` bytes, None: too many
    columns), naming the finest grid of the mesh that a store holds."""
    fit = finest_fit(v, f, what, shape, lambda s, fr: in_store(made(), fr, s, chunks, fill, budget)[0])
    rows, ny, nz = slab_chunks(shape, chunks)[0], shape[1], shape[2]
    hints = ("", "")
    if need is None:
        needs, beyond = grid_words(shape), "more columns than a zarr store's slabs can index (2**40)"
    elif fill == "flood" and math.prod(shape) > budget:  # its enclosed voxels need the whole grid's shell at once
        needs, beyond = f"{grid_words(shape, math.prod(shape))} in memory at once to flood it", ""
        hints = ('fill="shell" and fill="winding" go slab by slab', "--fill shell and --fill winding go slab by slab")
    else:
        needs = (f"{WORKERS} slabs of {rows} x {ny} x {nz} voxels in memory at once (about {fmt_count(need)} bytes"
                 + (" with their temporaries)" if temporaries else ")"))
        beyond = ""
        if rows > 1:  # thinner slabs: an option of the Python API only
            hints = ("smaller chunks= along the first axis make thinner slabs", "")
    return GridTooLarge(what, needs, budget, shape=tuple(shape), beyond=beyond, fit=fit, sought=True, hints=hints)


#: what the store's "rule" attribute says of each fill
RULES = {"winding": "generalised winding number |w| > 1/2 (nonzero on closed meshes)",
         "shell": "shell: every voxel whose closed cube the surface meets",
         "flood": "flood: the shell and every voxel it encloses (6-connected outside)"}


def flood_store(array, slabs) -> int:
    """Add to the shell written in ``array`` the voxels it encloses (read
    whole, filled in memory, written back slab by slab); the voxels in."""
    from ..scale.kernels import fill_enclosed

    vol = fill_enclosed(np.asarray(array[:], dtype=bool), inplace=True)
    for a, b in slabs:
        array[a:b] = vol[a:b].view(np.uint8)
    return int(np.count_nonzero(vol))
