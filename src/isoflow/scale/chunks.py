"""Volumes in blocks: dask and zarr, imported only when used.

What the out-of-core passes share and that knows nothing of digital
topology: the optional imports with the message that names the extra, a
dask compute that leaves no task running behind it, a zarr store's volume
array, and the block grid over an array (zarr chunks or shards grouped into
blocks big enough to be worth a task).
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import IsoflowError, missing

#: zarr chunks smaller than this (voxels) are grouped into larger blocks when
#: the grid would otherwise have more than MAX_BLOCKS blocks: per-task
#: overhead, not memory, is what small chunks cost
MIN_BLOCK = 1 << 21
MAX_BLOCKS = 512


def import_dask(array: bool = True):
    """``(dask, dask.array)``: dask is optional for isoflow; say how to get
    it when it is missing. Without ``array``, ``(dask, None)``: importing
    dask.array takes several times as long as dask, which zarr input does
    not need."""
    try:
        import dask

        if not array:
            return dask, None
        import dask.array as da
    except ImportError as exc:
        raise IsoflowError(
            f"out-of-core analysis needs dask: install isoflow[dask] (pip install 'isoflow[dask]'; {exc})"
        ) from None
    return dask, da


def compute(*tasks, scheduler=None, workers: int | None = None, **kwargs) -> tuple:
    """``dask.compute(*tasks)`` that leaves nothing running behind it.

    On dask's threaded scheduler (``scheduler`` None, ``"threads"`` or its
    function) the tasks run on a pool of ``workers`` threads of this call,
    shut down before it returns or raises: dask answers a failed task at
    once while the tasks already begun go on, in its pools kept for the
    process, reading the store and counting after the caller has the error
    (a Python caller goes on with other work beside them; a command's
    interrupt stops them through :data:`isoflow.scale.cancel.STOP`). Other
    schedulers (``"sync"``, a process pool, a distributed client's ``get``)
    are called as they are, ``workers`` as their ``num_workers``.

    Examples
    --------
    >>> from dask import delayed
    >>> compute(delayed(sum)([1, 2]), delayed(max)(3, 4), workers=2)
    (3, 4)
    """
    import_dask(array=False)  # where dask is missing: the message that names the extra
    import dask.system
    import dask.threaded

    if not _threaded(scheduler):
        extra = {} if workers is None else {"num_workers": workers}
        return dask.compute(*tasks, scheduler=scheduler, **extra, **kwargs)
    from concurrent.futures import ThreadPoolExecutor

    pool = ThreadPoolExecutor(workers or dask.system.CPU_COUNT, thread_name_prefix="isoflow-block")
    try:
        return dask.compute(*tasks, scheduler=dask.threaded.get, pool=pool, **kwargs)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def settle_zarr_io(timeout: float = 5.0) -> None:
    """Wait, at most ``timeout`` seconds, until zarr's I/O thread has no
    work in flight. A zarr call runs on that thread while the caller waits;
    an interrupt (Ctrl-C, a batch system's SIGTERM) ends the wait, not the
    work, which may then write into a store being removed and leave it
    behind. Called before a half-written store is removed; nothing where
    zarr is not loaded or its thread not started.

    Examples
    --------
    >>> settle_zarr_io()  # nothing in flight: returns at once
    """
    import asyncio

    sync = sys.modules.get("zarr.core.sync")
    loop = getattr(sync, "loop", [None])[0] if sync is not None else None
    if loop is None or loop.is_closed() or not loop.is_running():
        return

    async def the_others() -> None:
        me = asyncio.current_task()
        pending = [t for t in asyncio.all_tasks() if t is not me]
        if pending:
            await asyncio.wait(pending, timeout=timeout)

    try:
        asyncio.run_coroutine_threadsafe(the_others(), loop).result(timeout + 1.0)
    except Exception:  # (a loop closing meanwhile, a timeout: removing the store goes on as before)
        pass


def _threaded(scheduler) -> bool:
    """Whether ``scheduler`` is dask's threaded one: named so, or None where
    neither dask's configuration nor a distributed client (looked for only
    where dask.distributed is imported already) names another."""
    import dask.config
    import dask.threaded

    if scheduler is None:
        scheduler = dask.config.get("scheduler", None)
    if scheduler is None and "distributed" in sys.modules:
        try:
            sys.modules["distributed"].default_client()
            return False
        except ValueError:  # no client
            pass
    return scheduler is None or scheduler is dask.threaded.get or scheduler in ("threads", "threading")


def import_zarr():
    try:
        import zarr
    except ImportError as exc:
        raise IsoflowError(
            f"reading .zarr volumes needs zarr: install isoflow[dask] (pip install 'isoflow[dask]'; {exc})"
        ) from None
    return zarr


def is_zarr_array(array) -> bool:
    """A zarr array, recognised without importing zarr (it may be missing)."""
    if isinstance(array, SpatialAxes):
        return True
    return type(array).__module__.split(".")[0] == "zarr" and all(
        hasattr(array, name) for name in ("chunks", "shape", "dtype", "__getitem__")
    )


def block_bounds(chunks) -> list[list[tuple[int, int]]]:
    """Per axis, the [start, stop) of every block."""
    out = []
    for sizes in chunks:
        stops = np.cumsum(sizes)
        out.append([(int(b - s), int(b)) for s, b in zip(sizes, stops)])
    return out


def checked_block_shape(block_shape, shape) -> tuple[int, ...]:
    """``block_shape`` as integers >= 1, one per axis of ``shape``, or one
    line naming it (a dask array's rechunk divided by a zero, or raised
    dask's own error on a length that does not fit).

    Examples
    --------
    >>> checked_block_shape((2, 3.0), (5, 5))
    (2, 3)
    """
    try:
        block = tuple(int(b) for b in block_shape)
        whole = all(b == float(c) for b, c in zip(block, block_shape))
    except (TypeError, ValueError, OverflowError):
        block, whole = (), False
    if not whole or len(block) != len(shape) or any(b < 1 for b in block):
        raise IsoflowError(f"block_shape {block_shape!r} does not fit a {len(shape)}D array "
                           f"(one integer >= 1 per axis)")
    return block


def zarr_blocks(z, block_shape) -> tuple[tuple[int, ...], ...]:
    """Regular chunks of a zarr array: its shards (or chunks), grown by whole
    chunks to at least MIN_BLOCK voxels when they would make too many blocks."""
    shape = tuple(int(s) for s in z.shape)
    if block_shape is None:
        base = getattr(z, "shards", None) or z.chunks
        block = [max(1, min(int(c), s)) for c, s in zip(base, shape)]

        def count(b):
            return int(np.prod([-(-s // c) for s, c in zip(shape, b)]))

        while np.prod(block) < MIN_BLOCK and count(block) > MAX_BLOCKS:
            grow = [i for i in range(len(block)) if block[i] < shape[i]]
            if not grow:
                break
            i = min(grow, key=lambda j: block[j])
            block[i] = min(2 * block[i], shape[i])
    else:
        block = [min(b, s) for b, s in zip(checked_block_shape(block_shape, shape), shape)]
    return tuple(
        tuple([b] * (s // b) + ([s % b] if s % b else [])) for b, s in zip(block, shape)
    )



def open_zarr(path, level: str | None = None) -> object:
    """The volume array of a zarr store: the array at ``path``; in an
    OME-Zarr image (a group with NGFF ``multiscales``) its first resolution
    level, or ``level`` (a dataset path such as ``'1'``, or an index); in any
    other group the array named ``level``, else its array named ``volume``
    or its only array."""
    return open_zarr_node(path, level)[0]


def open_zarr_node(path, level: str | None = None) -> tuple:
    """``(array, multiscales entry or None, that level's dataset entry or
    None)`` of a zarr store, chosen as :func:`open_zarr` says."""
    zarr = import_zarr()
    path = Path(path)
    if not path.exists():
        raise missing(path)
    try:
        node = zarr.open(str(path), mode="r")
    except Exception as exc:  # zarr raises several types for what is not a store
        raise IsoflowError(
            f"{path}: not a zarr array or group ({exc.__class__.__name__}: {exc})"
        ) from None
    if not isinstance(node, zarr.Group):
        if level is not None:
            raise IsoflowError(f"{path}: a zarr array has no resolution level {level!r}")
        return node, None, None
    multiscale = ome_multiscales(node.attrs)
    if multiscale is not None:
        datasets = [d for d in multiscale.get("datasets") or [] if isinstance(d, dict)]
        paths = [str(d.get("path")) for d in datasets]
        if level is None and paths:
            i = 0
        elif level in paths:
            i = paths.index(level)
        elif level is not None and level.isdigit() and int(level) < len(paths):
            i = int(level)
        else:
            raise IsoflowError(f"{path}: no resolution level {level!r} in the OME-Zarr image (levels: {paths})")
        try:
            array = node[paths[i]]
        except Exception as exc:
            raise IsoflowError(f"{path}: OME-Zarr level {paths[i]!r} cannot be opened ({exc.__class__.__name__})") from None
        if isinstance(array, zarr.Group):
            raise IsoflowError(f"{path}: OME-Zarr level {paths[i]!r} is a group, not an array")
        return array, multiscale, datasets[i]
    arrays = dict(node.arrays())
    if level is not None:
        # a plain group: the name picks one of its arrays (a segmentation
        # beside its image), as FILE.h5:/dataset does
        if level not in arrays:
            raise IsoflowError(f"{path}: no array {level!r} in the zarr group (its arrays: {sorted(arrays)}; "
                               "it is no OME-Zarr image, whose levels the name would also pick)")
        node = arrays[level]
    elif "volume" in arrays:
        node = arrays["volume"]
    elif len(arrays) == 1:
        node = next(iter(arrays.values()))
    elif not arrays:
        raise IsoflowError(f"{path}: a zarr group without arrays")
    else:
        first = sorted(arrays)[0]
        raise IsoflowError(f"{path}: a zarr group with arrays {sorted(arrays)}; name one, {path}:{first}")
    return node, None, None


def axis_names(multiscale: dict, ndim: int, where: str) -> list[str]:
    """The level's axis names; NGFF 0.1-0.2 had none and meant (t, c, z, y, x)."""
    axes = multiscale.get("axes")
    if axes is None:
        names = list("tczyx"[-ndim:]) if ndim <= 5 else []
    else:
        names = [str(a.get("name")) if isinstance(a, dict) else str(a) for a in axes]
    if len(names) != ndim:
        raise IsoflowError(f"{where}: OME-Zarr axes {names} do not fit a {ndim}D array")
    return [n.lower() for n in names]


#: ``IMAGE.zarr:LEVEL`` (the path of a resolution level, or its index)
_LEVEL = re.compile(r"^(?P<store>.+?\.zarr)/?:(?P<level>[^:]*)$", re.IGNORECASE)


class SpatialAxes:
    """A zarr array without its axes of length 1 (an OME-Zarr image's
    channel and time point), read as the zarr array is: ``shape``,
    ``chunks``, ``shards``, ``dtype``, ``ndim`` and ``view[region]`` over the
    kept axes, in stored order. Plain attributes, so that it pickles for
    process workers."""

    def __init__(self, array, kept: list[int]):
        self.array, self.kept = array, list(kept)
        self.shape = tuple(int(array.shape[i]) for i in kept)
        self.chunks = tuple(int(array.chunks[i]) for i in kept)
        shards = getattr(array, "shards", None)
        self.shards = None if shards is None else tuple(int(shards[i]) for i in kept)
        self.dtype, self.ndim = array.dtype, len(kept)
        self.fill_value = getattr(array, "fill_value", None)
        self.store_path = getattr(array, "store_path", None)

    def __getitem__(self, region):
        region = region if isinstance(region, tuple) else (region,)
        full, given = [], iter(region)
        for i in range(self.array.ndim):
            full.append(next(given, slice(None)) if i in self.kept else 0)
        return np.asarray(self.array[tuple(full)])


def zarr_volume(path) -> tuple[Any, list[int]]:
    """The volume of a zarr store as the block-wise passes read it, and the
    order of its axes as (x, y, z).

    ``path`` is ``STORE.zarr`` or ``IMAGE.zarr:LEVEL``; a plain array's axes
    are (x, y, z) as stored; an OME-Zarr image's axes are named, and those
    of length 1 that are not x, y or z (a channel, a time point) are left
    out of the array returned (:class:`SpatialAxes`).

    Parameters
    ----------
    path : str or os.PathLike
        The store, with ``:LEVEL`` for a resolution level of an OME-Zarr
        image (its path or index).

    Returns
    -------
    tuple
        ``(array, order)``: a zarr array (or its view without the axes of
        length 1) in stored order, and for each of x, y, z present the
        index of its axis in that array.

    Raises
    ------
    IsoflowError
        A path that is no zarr store, no such level, or an axis other than
        x, y and z with more than one entry.

    Examples
    --------
    >>> import tempfile, zarr
    >>> d = Path(tempfile.mkdtemp()) / "image.zarr"
    >>> g = zarr.open_group(str(d), mode="w")
    >>> _ = g.create_array("0", shape=(1, 4, 5, 6), dtype="u1")
    >>> g.attrs["multiscales"] = [{"axes": ["c", "z", "y", "x"], "datasets": [{"path": "0"}]}]
    >>> array, order = zarr_volume(f"{d}:0")
    >>> array.shape, order
    ((4, 5, 6), [2, 1, 0])
    """
    text = str(path)
    m = _LEVEL.match(text)
    store, level = (text, None) if m is None or Path(text).exists() else (m["store"], m["level"] or None)
    array, multiscale, _ = open_zarr_node(store, level)
    if multiscale is None:
        return array, list(range(array.ndim))
    names = axis_names(multiscale, array.ndim, text)
    xyz = [names.index(a) for a in "xyz" if a in names]
    for i, name in enumerate(names):
        if i not in xyz and int(array.shape[i]) != 1:
            raise IsoflowError(f"{text}: axis {name!r} has {int(array.shape[i])} entries; the block-wise "
                               "report reads one 2D or 3D volume (isoflow info reads a time series in "
                               "memory; isoflow.read_volume(path, time=t) gives one time point)")
    if len(xyz) == array.ndim:
        return array, xyz
    return SpatialAxes(array, sorted(xyz)), [sorted(xyz).index(i) for i in xyz]


def ome_multiscales(attrs) -> dict | None:
    """The first ``multiscales`` entry of a group's attributes: at the top in
    OME-Zarr (NGFF) 0.4 and before, under ``ome`` in 0.5; None if absent."""
    attrs = dict(attrs)
    ome = attrs.get("ome")
    found = attrs.get("multiscales") or (ome.get("multiscales") if isinstance(ome, dict) else None)
    if isinstance(found, list) and found and isinstance(found[0], dict):
        return found[0]
    return None
