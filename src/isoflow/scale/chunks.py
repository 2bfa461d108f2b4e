"""Volumes in blocks: dask and zarr, imported only when used.

What the out-of-core passes share and that knows nothing of digital
topology: the optional imports with the message that names the extra, a
dask compute that leaves no task running behind it, a zarr store's volume
array (``STORE.zarr:LEVEL``, the name after the colon split off as for an
HDF5 dataset, and its named axes read as x, y, z), and the block grid over
an array (zarr chunks or shards grouped into blocks big enough to be worth
a task).
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import IsoflowError, given_text, missing, scalar_given, warn

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
    are called as they are, ``workers`` as their ``num_workers`` (an
    executor, ``concurrent.futures``, keeps its own).

    Examples
    --------
    >>> from dask import delayed
    >>> compute(delayed(sum)([1, 2]), delayed(max)(3, 4), workers=2)
    (3, 4)
    """
    import_dask(array=False)  # where dask is missing: the message that names the extra
    from concurrent.futures import Executor, ThreadPoolExecutor

    import dask.system
    import dask.threaded

    if not _threaded(scheduler):
        # dask gives an executor num_workers itself: a second one is a TypeError
        extra = {} if workers is None or isinstance(scheduler, Executor) else {"num_workers": workers}
        return dask.compute(*tasks, scheduler=scheduler, **extra, **kwargs)

    pool = ThreadPoolExecutor(workers or dask.system.CPU_COUNT, thread_name_prefix="isoflow-block")
    try:
        return dask.compute(*tasks, scheduler=dask.threaded.get, pool=pool, **kwargs)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


class BlockTicks:
    """``progress(done, total)`` as each task of the named functions ends.

    Local schedulers report each task (a dask callback, run on the calling
    thread); a ``dask.distributed`` cluster runs no such callback, so the
    caller also says :meth:`at` how many are done after each of its
    computes. Nothing is said twice, nor backwards.

    Examples
    --------
    >>> from dask import delayed
    >>> def square(x): return x * x
    >>> said = []
    >>> ticks = BlockTicks(lambda done, total: said.append((done, total)), 2, ("square",))
    >>> with ticks.callback():
    ...     compute(delayed(square, pure=False)(2), delayed(square, pure=False)(3), scheduler="sync")
    (4, 9)
    >>> ticks.at(2); said
    [(1, 2), (2, 2)]
    """

    def __init__(self, progress, total: int, functions: tuple[str, ...]) -> None:
        self.progress, self.total, self.done, self.told = progress, int(total), 0, 0
        self.prefixes = tuple(f"{name}-" for name in functions)  # dask.delayed's keys: the function's name, a dash

    def callback(self):
        """A context in which local schedulers report the tasks as they end."""
        import contextlib

        from dask.callbacks import Callback

        return Callback(posttask=self._posttask) if self.progress is not None else contextlib.nullcontext()

    def _posttask(self, key, result, dsk, state, worker_id) -> None:
        if str(key).startswith(self.prefixes):
            self.at(self.done + 1)

    def at(self, done: int) -> None:
        """Say ``done`` tasks (at most ``total``), if more than said."""
        self.done = max(self.done, min(int(done), self.total))
        if self.progress is not None and self.done > self.told:
            self.told = self.done
            self.progress(self.done, self.total)


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
    if scheduler is None and distributed_client(None) is not None:
        return False
    return scheduler is None or scheduler is dask.threaded.get or scheduler in ("threads", "threading")


def distributed_client(scheduler: Any) -> Any:
    """The ``dask.distributed`` client that runs the tasks given to
    ``dask.compute`` with ``scheduler``.

    Parameters
    ----------
    scheduler : object
        What ``dask.compute`` is given: a client, its ``get``, the name
        ``"distributed"``, or None for dask's configured scheduler (a
        client made the default names itself there).

    Returns
    -------
    distributed.Client or None
        The client itself, the client whose ``get`` it is, or the default
        client for the name, and for None where dask's configuration names
        no other scheduler (looked for only where dask.distributed is
        imported already: no client exists without it); None for any
        other scheduler, or where no client is found.

    Examples
    --------
    >>> distributed_client("threads") is None
    True
    """
    if scheduler is None and "dask" in sys.modules:  # "sync" configured runs here, a default client or not
        import dask.config

        scheduler = dask.config.get("scheduler", None)
    if hasattr(scheduler, "scheduler_info"):
        return scheduler
    owner = getattr(scheduler, "__self__", None)
    if hasattr(owner, "scheduler_info"):
        return owner
    named = scheduler is None or (isinstance(scheduler, str) and scheduler.lower() in ("distributed", "dask.distributed"))
    if not named or "distributed" not in sys.modules:
        return None
    try:
        return sys.modules["distributed"].default_client()
    except ValueError:  # no client
        return None


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


def store_name(array: Any, default: str) -> str:
    """The name of a zarr array's store as a user gave its path: the
    directory of a local store (``z2.zarr``, ``IMAGE.zarr/0`` for a level),
    not zarr 3's URL of it (``file://z2.zarr``), which no shell or
    ``open`` takes; another store's URL (``memory://...``) as zarr gives
    it; ``default`` for an array of no store.

    Parameters
    ----------
    array : object
        A zarr array (or :class:`SpatialAxes` of one), or anything else.
    default : str
        The name where ``array`` has no ``store_path``.

    Returns
    -------
    str
        The name messages give the input.

    Examples
    --------
    >>> store_name(object(), "volume")
    'volume'
    """
    store_path = getattr(array, "store_path", None)
    if not store_path:
        return default
    root = getattr(getattr(store_path, "store", None), "root", None)  # a LocalStore's directory
    if root is None:
        return str(store_path)
    return os.path.join(os.fsdecode(root), store_path.path) if store_path.path else os.fsdecode(root)


def argument_words(array: Any, function: str, argument: str = "array") -> str:
    """How a refusal of a chunked ``array`` given to ``function`` begins
    where the caller names it not: the function, its argument, and the
    store's name where the array has one (:func:`store_name`).

    Parameters
    ----------
    array : object
        A dask or zarr array (or anything else).
    function : str
        The function called.
    argument : str
        The argument ``array`` was given for.

    Returns
    -------
    str

    Examples
    --------
    >>> argument_words(object(), "analyze_chunked")
    'analyze_chunked: array'
    """
    name = store_name(array, "")
    return f"{function}: {argument}" + (f" ({name})" if name else "")


def decoded_chunk_voxels(array: Any) -> int:
    """Voxels of the largest chunk that a read of any part of ``array``
    decodes whole: zarr decodes a whole chunk (an inner chunk of a shard)
    to give any part of it, and dask computes a whole chunk of its array;
    0 for an array in memory, read without decoding.

    Parameters
    ----------
    array : zarr.Array, dask.array.Array, a chunk reader or numpy.ndarray
        Anything with ``chunks`` (a tuple of ints, or dask's tuple of
        tuples); ``chunks`` None or absent: read as it is.

    Returns
    -------
    int

    Examples
    --------
    >>> import dask.array as da
    >>> decoded_chunk_voxels(da.zeros((10, 10), chunks=(4, 5))), decoded_chunk_voxels(np.zeros((10, 10)))
    (20, 0)
    """
    chunks = None if isinstance(array, np.ndarray) else getattr(array, "chunks", None)
    if not chunks:
        return 0
    return int(np.prod([max(c) if isinstance(c, tuple) else int(c) for c in chunks], dtype=np.int64))


def smaller_blocks_help(bounds: Any, array: Any) -> bool:
    """Whether blocks smaller than those of ``bounds`` would take less
    memory: not where the largest block is already smaller than the chunk
    a read of it decodes whole (:func:`decoded_chunk_voxels`), which a
    task holds whatever part of it the block takes; a refusal offers
    smaller blocks only where this is true.

    Parameters
    ----------
    bounds : sequence of sequences of (int, int)
        Per axis, each block's [start, stop).
    array : zarr.Array, dask.array.Array, a chunk reader or numpy.ndarray
        What the blocks are read from.

    Returns
    -------
    bool

    Examples
    --------
    >>> import dask.array as da
    >>> a = da.zeros((10, 10), chunks=(4, 5))  # chunks of 20 elements
    >>> smaller_blocks_help([[(0, 4), (4, 8)], [(0, 5), (5, 10)]], a)  # blocks of 20
    True
    >>> smaller_blocks_help([[(0, 2), (2, 4)], [(0, 5), (5, 10)]], a)  # blocks of 10
    False
    """
    voxels = int(np.prod([max(b - a for a, b in axis) for axis in bounds], dtype=np.int64))
    return voxels >= decoded_chunk_voxels(array)


#: the layers along another axis than the first, as a multiple of those
#: along the first, from which the blocks go in layers along that axis
LAYERS_APART = 8


def layer_axes(numblocks: tuple[int, ...]) -> tuple[int, ...]:
    """The order of the axes in which an array's blocks are read, a layer
    of blocks at a time along the first of them.

    Parameters
    ----------
    numblocks : tuple of int
        The blocks along each axis of the array.

    Returns
    -------
    tuple of int
        The array's axes as they are, or first the axis along which the
        blocks are the most (the earliest of them) where they are
        :data:`LAYERS_APART` times as many as along the first axis, then
        the others as they are.

    Notes
    -----
    A pass over layers of blocks holds what lies across a layer (the
    faces of two layers of blocks of the report, a slab of the label
    table), so the more layers, the less of the volume is held: chunks of
    (N, N, 4) are one layer along the first axis, its faces half the
    volume's voxels, and N / 4 layers along the last. A block read across
    its stored order is copied into the new one, which costs a fifth of
    its sum: where the layers differ less, their faces are few beside the
    blocks at work.

    Examples
    --------
    >>> layer_axes((1, 1, 128)), layer_axes((2, 2, 4))
    ((2, 0, 1), (0, 1, 2))
    """
    first = int(np.argmax(numblocks))
    if numblocks[first] < LAYERS_APART * numblocks[0]:
        return tuple(range(len(numblocks)))
    return (first, *(i for i in range(len(numblocks)) if i != first))


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
        given = [scalar_given(c) for c in block_shape]  # a 0D array of a number is that number
        block = tuple(int(c) for c in given)
        # numbers only: int() and float() read "2" and True as 2 and 1 too
        whole = all(isinstance(c, (int, float, np.integer, np.floating)) and not isinstance(c, (bool, np.bool_))
                    and b == float(c) for b, c in zip(block, given))
    except (TypeError, ValueError, OverflowError):
        block, whole = (), False
    if not whole or len(block) != len(shape) or any(b < 1 for b in block):
        raise IsoflowError(f"block_shape {given_text(block_shape)} does not fit a {len(shape)}D array "
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
    None)`` of a zarr store, chosen as :func:`open_zarr` says; a name that
    is the path of a group inside it (an OME-Zarr image's segmentation,
    ``labels/cells``, an image of its own) picks that group's volume, and
    what follows the group in the name (``labels/cells/1``) its level."""
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
    return _volume_of_node(zarr, node, path, level)


def inner_group(zarr, node, level: str | None) -> tuple[str, str | None] | None:
    """The longest leading part of ``level`` that is a group inside the
    zarr group ``node``, and the rest of ``level`` (None where nothing is
    left); None where no part of it is a group.

    Parameters
    ----------
    zarr : module
        The zarr package.
    node : zarr.Group
        The store's root group.
    level : str or None
        The name after the store's colon.

    Returns
    -------
    tuple of (str, str or None), or None
        ``(group path, rest)``.

    Examples
    --------
    >>> import tempfile, zarr
    >>> g = zarr.open_group(tempfile.mkdtemp() + "/image.zarr", mode="w")
    >>> _ = g.create_array("labels/cells/0", shape=(2, 2, 2), dtype="u1")
    >>> inner_group(zarr, g, "labels/cells/0"), inner_group(zarr, g, "labels/cells"), inner_group(zarr, g, "0")
    (('labels/cells', '0'), ('labels/cells', None), None)
    """
    parts = [] if level is None else [p for p in level.split("/") if p]
    for cut in range(len(parts), 0, -1):
        try:
            inner = node["/".join(parts[:cut])]
        except (KeyError, ValueError):  # (zarr's KeyError, or its refusal of an odd name)
            continue
        if isinstance(inner, zarr.Group):
            return "/".join(parts[:cut]), "/".join(parts[cut:]) or None
    return None


def _volume_of_node(zarr, node, path: Path, level: str | None, inside: bool = False) -> tuple:
    """:func:`open_zarr_node` of the opened store ``node`` (``inside``: a
    group inside the store, ``path`` naming it as ``STORE.zarr:GROUP``)."""
    if isinstance(node, zarr.Group) and (inner := inner_group(zarr, node, level)) is not None:
        if level not in _level_names(node):  # (a level's own path is the level)
            named = Path(f"{path}{'/' if inside else ':'}{inner[0]}")
            return _volume_of_node(zarr, node[inner[0]], named, inner[1], inside=True)
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
            raise IsoflowError(f"{path}: no resolution level {level!r} in the OME-Zarr image (levels: {paths}"
                               f"{segmentations_named(node, path, inside)})")
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
            groups = sorted(name for name, _ in node.groups())
            if groups and not arrays:  # an OME-Zarr image's labels/ group: its segmentations are groups
                raise IsoflowError(f"{path}: no array or group {level!r} in the zarr group (its groups: {groups}; "
                                   f"name one, {path}{'/' if inside else ':'}{groups[0]})")
            raise IsoflowError(f"{path}: no array {level!r} in the zarr group (its arrays: {sorted(arrays)}; "
                               "it is no OME-Zarr image, whose levels the name would also pick)")
        node = arrays[level]
    elif "volume" in arrays:
        node = arrays["volume"]
    elif len(arrays) == 1:
        node = next(iter(arrays.values()))
    elif not arrays:
        groups = sorted(name for name, _ in node.groups())
        # an OME-Zarr image's labels/ group holds an image per segmentation
        pick = f" (its groups: {groups}; name one, {path}{'/' if inside else ':'}{groups[0]})" if groups else ""
        raise IsoflowError(f"{path}: a zarr group without arrays{pick}")
    else:
        first = sorted(arrays)[0]
        raise IsoflowError(f"{path}: a zarr group with arrays {sorted(arrays)}; name one, {path}:{first}")
    return node, None, None


def segmentations_named(node, path, inside: bool) -> str:
    """The end of the refusal of a name that is no level of the OME-Zarr
    image ``node``: its segmentations (the groups of its ``labels/``
    group, NGFF's image-label), each as the name that reads it, which a
    name given without ``labels/`` (``image.zarr:cells``) meant; nothing
    where it has none.

    Parameters
    ----------
    node : zarr.Group
        The image's group.
    path : str or Path
        The image as the refusal names it (``image.zarr``, or
        ``store.zarr:inner`` for an image inside a store).
    inside : bool
        Whether the image is a group inside the store (its names follow a
        ``/``, not the store's ``:``).

    Returns
    -------
    str
        ``"; its segmentations: image.zarr:labels/cells"``, or ``""``.

    Examples
    --------
    >>> import tempfile, zarr
    >>> g = zarr.open_group(tempfile.mkdtemp() + "/image.zarr", mode="w")
    >>> _ = g.create_array("labels/cells/0", shape=(2, 2, 2), dtype="u1")
    >>> segmentations_named(g, "image.zarr", False), segmentations_named(g["labels/cells"], "x", True)
    ('; its segmentations: image.zarr:labels/cells', '')
    """
    try:
        labels = node["labels"]
        names = sorted(name for name, _ in labels.groups())
    except (KeyError, ValueError, AttributeError):  # no labels/ group, or an array of that name
        return ""
    shown = ", ".join(f"{path}{'/' if inside else ':'}labels/{name}" for name in names[:5])
    return f"; its segmentations: {shown}{', ...' if len(names) > 5 else ''}" if names else ""


def _level_names(node) -> list[str]:
    """The dataset paths of an OME-Zarr image's levels (none for another group)."""
    multiscale = ome_multiscales(node.attrs)
    return [str(d.get("path")) for d in (multiscale or {}).get("datasets") or [] if isinstance(d, dict)]


def axis_names(multiscale: dict, ndim: int, where: str) -> list[str]:
    """The level's axis names; NGFF 0.1-0.2 had none and meant (t, c, z, y, x).

    An axis whose ``type`` (NGFF 0.4 on) is ``"time"`` or ``"channel"`` is
    named ``t`` or ``c`` whatever its name: NGFF lets a time axis be named
    "time", and read by its name it was taken for channels.

    Examples
    --------
    >>> axis_names({"axes": [{"name": "time", "type": "time"}, "z", "y", "x"]}, 4, "a.zarr")
    ['t', 'z', 'y', 'x']
    """
    axes = multiscale.get("axes")
    if axes is None:
        names = list("tczyx"[-ndim:]) if ndim <= 5 else []
    else:
        kinds = {"time": "t", "channel": "c"}
        names = [kinds.get(str(a.get("type")).lower(), str(a.get("name"))) if isinstance(a, dict) else str(a)
                 for a in axes]
    if len(names) != ndim:
        raise IsoflowError(f"{where}: OME-Zarr axes {names} do not fit a {ndim}D array")
    return [n.lower() for n in names]


def spatial_axes(names, shape, where: str, time: bool = False) -> tuple[list[int], list[int]]:
    """Given the format's axis names (letters), the indices of x, y and z
    (those present, in that order) and of the other axes, which must have
    length 1 (a time point or channel among several is refused).

    Parameters
    ----------
    names : sequence of str
        The stored axes' names, one letter each (``"tczyx"``).
    shape : sequence of int
        The stored array's shape.
    where : str
        The file, as an error names it.
    time : bool
        Keep a time axis ``t`` of several entries beside x, y and z as a
        fourth axis, after z: a time series of 3D volumes is the 4D volume
        ``info`` analyses, as a 4D NIfTI is (a series of 2D images is still
        refused: read as 3D, its time would pass for z).

    Returns
    -------
    tuple of list of int
        The indices of x, y, z (and t) in that order, and of the others.

    Raises
    ------
    IsoflowError
        Axes that name x, y or z twice, hold fewer than two of them, or a
        channel or time axis of several entries that is not kept.

    Examples
    --------
    >>> spatial_axes("tczyx", (3, 1, 4, 5, 6), "series.zarr", time=True)
    ([4, 3, 2, 0], [1])
    """
    names = [n.lower() for n in names]
    spatial = [n for n in names if n in ("x", "y", "z")]
    if len(set(spatial)) != len(spatial):
        raise IsoflowError(f"{where}: axes {''.join(names)} name a spatial axis twice")
    xyz = [names.index(a) for a in "xyz" if a in names]
    if len(xyz) < 2:
        raise IsoflowError(f"{where}: axes {''.join(names)} hold fewer than two of x, y, z")
    other = [i for i in range(len(names)) if i not in xyz]
    series = [i for i in other if names[i] == "t" and shape[i] > 1]
    if time and len(xyz) == 3 and len(series) == 1:
        xyz, other = xyz + series, [i for i in other if i not in series]
    for i in other:
        if shape[i] != 1:
            if names[i] != "t":
                remedy = "save one channel"
            elif len(xyz) == 3:  # a series of 3D volumes: refused only where the reader wants one volume
                remedy = "save one time point (only isoflow info's report takes a time series of 3D volumes, as 4D)"
            else:
                remedy = "save one time point (a time series is read as 4D only of 3D volumes)"
            raise IsoflowError(
                f"{where}: axis '{names[i]}' has {shape[i]} entries (axes {''.join(names)}, shape "
                f"{tuple(shape)}); isoflow reads one volume: {remedy}"
            )
    return xyz, other


def fourth_axis_name(path: str | os.PathLike) -> str | None:
    """The name the metadata gives the 4th axis of a zarr store's volume
    read as (x, y, z, t): an OME-Zarr image's (``"t"``, the time axis kept
    beside x, y and z), a plain array's last dimension name where zarr's
    ``dimension_names`` are x, y, z and one more; None where the store
    names none, or cannot be opened (the words of a message: no error of
    their own).

    Parameters
    ----------
    path : str or os.PathLike
        ``STORE.zarr`` or ``IMAGE.zarr:LEVEL``.

    Returns
    -------
    str or None
        The name, lower case.

    Examples
    --------
    >>> import tempfile, zarr
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = zarr.create_array(str(folder / "c.zarr"), shape=(4, 5, 6, 3), dtype="u1", dimension_names=list("xyzc"))
    >>> _ = zarr.create_array(str(folder / "u.zarr"), shape=(4, 5, 6, 3), dtype="u1")
    >>> fourth_axis_name(folder / "c.zarr"), fourth_axis_name(folder / "u.zarr")
    ('c', None)
    """
    try:
        array, multiscale, _ = open_zarr_node(*split_store(path))
        if multiscale is not None:
            names = axis_names(multiscale, array.ndim, str(path))
            xyz = spatial_axes(names, array.shape, str(path), time=True)[0]
            return names[xyz[3]] if len(xyz) == 4 else None
        names = _dimension_names(array)
    except Exception:  # zarr raises many types; the words fall back to "time points or channels"
        return None
    return names[3] if names[:3] == ["x", "y", "z"] and len(names) == 4 else None


def _dimension_names(array: Any) -> list[str]:
    """A zarr v3 array's ``dimension_names``, lower case (a missing one
    ``'none'``), else the ``axis_names`` attribute funlib.persistence
    writes (zarr v2 too; :func:`axis_names_given`); none for an array
    without either."""
    return _names_field(array)[1]


def _names_field(array: Any) -> tuple[str, list[str]]:
    """The field that names a plain zarr array's axes and its names (see
    :func:`_dimension_names`)."""
    names = getattr(getattr(array, "metadata", None), "dimension_names", None)
    if names:
        return "dimension_names", [str(n).lower() for n in names]
    given = axis_names_given(dict(getattr(array, "attrs", {}) or {}).get("axis_names"), array.ndim)
    return ("axis_names", given) if given else ("dimension_names", [])


def axis_names_given(value: Any, ndim: int) -> list[str] | None:
    """The axes' names that funlib.persistence writes as the attribute
    ``axis_names`` of an HDF5 dataset or a zarr array (``["z", "y",
    "x"]``; a name ending in ``^``, its mark of an axis not in space, is a
    channel, ``c``), lower case; None where the attribute is absent or is
    not one name per axis.

    Parameters
    ----------
    value : object
        The attribute (a list of strings, h5py's array of them or of bytes),
        or None.
    ndim : int
        The array's axes.

    Returns
    -------
    list of str or None

    Examples
    --------
    >>> axis_names_given(["c^", "Z", "y", "x"], 4)
    ['c', 'z', 'y', 'x']
    >>> axis_names_given(["z", "y"], 3) is None
    True
    """
    if value is None or isinstance(value, (str, bytes)) or np.ndim(value) != 1 or len(value) != ndim:
        return None
    names = [(n.decode("utf-8", "replace") if isinstance(n, bytes) else str(n)).strip().lower() for n in value]
    return ["c" if n.endswith("^") else n for n in names]


def named_axes(array: Any) -> list[int] | None:
    """The stored axes of x, y and z (x and y in 2D) of a plain zarr v3
    array whose ``dimension_names`` name them (or a zarr array whose
    ``axis_names`` attribute does, as funlib.persistence writes it), in
    any order and any case (z, y, x as xarray, tensorstore and funlib
    write them): such an array is read
    by its names, as an OME-Zarr image is by its axes. None where the
    names are anything else (none, a channel or time axis among them, a
    name twice), and the array is read as stored.

    Parameters
    ----------
    array : zarr.Array
        The plain array (no ``multiscales`` above it).

    Returns
    -------
    list of int or None
        For x, y (and z), the index of its stored axis.

    Examples
    --------
    >>> import zarr
    >>> named_axes(zarr.create_array({}, shape=(4, 5, 6), dtype="u1", dimension_names=["Z", "y", "x"]))
    [2, 1, 0]
    >>> named_axes(zarr.create_array({}, shape=(4, 5, 6, 1), dtype="u1", dimension_names=list("zyxc"))) is None
    True
    """
    names = _dimension_names(array)
    spatial = list("xyz"[:array.ndim])
    if array.ndim not in (2, 3) or sorted(names) != spatial:
        return None
    return [names.index(a) for a in spatial]


def stored_order_said(array, where: str) -> str | None:
    """Warn where a plain zarr array's ``dimension_names`` (zarr v3) name
    spatial axes that isoflow reads as stored, axis 0 as x, 1 as y, 2 as z
    (docs/formats.md): names that are x, y, z in some order are read by
    name (:func:`named_axes`), but among others (z, y, x, c) they are not,
    and an array named so is read with its z as x, the mirror image of the
    volume its names describe (coordinates and a surface with x and z
    swapped; counts and topology are the same). An OME-Zarr image's axes
    are read by name.

    Parameters
    ----------
    array : zarr.Array
        The plain array (no ``multiscales`` above it).
    where : str
        The store, named in the warning.

    Returns
    -------
    str or None
        The warning given, or None where the names agree, are read by
        name, or there are none.

    Examples
    --------
    >>> import tempfile, zarr
    >>> folder = Path(tempfile.mkdtemp())
    >>> a = zarr.create_array(str(folder / "a.zarr"), shape=(4, 5, 6), dtype="u1", dimension_names=list("zyx"))
    >>> stored_order_said(a, "a.zarr") is None
    True
    """
    if named_axes(array) is not None:
        return None
    field, names = _names_field(array)
    spatial = ("x", "y", "z")
    if len(names) != array.ndim or not any(n in spatial and n != a for n, a in zip(names, "xyzt")):
        return None
    read_as = ", ".join(f"{n} as {a}" for n, a in zip(names, "xyzt") if n != a and n in spatial)
    text = (f"{where}: its {field} are {', '.join(names)}, and a plain zarr array is read by them only "
            f"where they are x, y, z in some order; this one is read as stored (axis 0 as x, 1 as y, 2 as z): "
            f"{read_as}, the mirror image of the volume the names describe (its coordinates and surface with those "
            f"axes swapped; counts and topology unchanged); save it with {field} x, y, z, or as OME-Zarr, "
            "whose axes are read by name")
    warn(text)
    return text


def split_store(path: str | os.PathLike, suffixes: tuple[str, ...] = ("zarr",)) -> tuple[Path, str | None]:
    """The file or store a path names and the name after its colon:
    ``IMAGE.zarr:1`` -> (IMAGE.zarr, '1'), a resolution level or an array of
    a group; with ``suffixes`` ("h5", "npz", ...) a dataset or array inside
    such a file too (``FILE.h5:/group/volume``); any other path -> (path,
    None).

    Only after one of ``suffixes`` (any case), so that ``C:\\data\\a.nii``
    stays a path; the first such suffix followed by the colon ends the file.
    A zarr store is a directory, so its name may end in the "/" that a
    shell's completion adds, before the colon: ``IMAGE.zarr/:1``. An empty
    name is None.

    Parameters
    ----------
    path : str or os.PathLike
        The path as given.
    suffixes : tuple of str
        The suffixes (without the dot) of the files that hold named arrays.

    Returns
    -------
    tuple
        ``(file, name)``: the file's path and the name, or None.

    Examples
    --------
    >>> file, name = split_store("image.zarr/:1")
    >>> str(file), name
    ('image.zarr', '1')
    >>> split_store("v.h5:/a", ("h5", "zarr"))[1], split_store("v.h5:/a")[1]
    ('/a', None)
    """
    text = str(path)
    pattern = "|".join(re.escape(s) for s in suffixes)
    m = re.match(rf"^(?P<file>.+?\.(?:{pattern}))/?:(?P<name>.*)$", text, re.IGNORECASE)
    if m is None:
        return Path(text), None
    return Path(m["file"]), (m["name"] or None)


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
    are (x, y, z) as stored, or as its ``dimension_names`` name them
    (:func:`named_axes`); an OME-Zarr image's axes are named, and those
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
        A path that is no zarr store, no such level, or axes that
        :func:`spatial_axes` refuses (x, y or z named twice, fewer than two
        of them, another axis with more than one entry).

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
    store, level = (Path(text), None) if Path(text).exists() else split_store(text)
    array, multiscale, _ = open_zarr_node(store, level)
    if multiscale is None:
        return array, named_axes(array) or list(range(array.ndim))
    xyz, _ = spatial_axes(axis_names(multiscale, array.ndim, text), array.shape, text)
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


def declared_labels(path) -> list[str]:
    """The segmentations an OME-Zarr image declares in its ``labels/``
    group (NGFF's image-label: its ``labels`` attribute, under ``ome`` in
    0.5), each an image of its own read as ``IMAGE.zarr:labels/NAME``;
    none for any other store, a level or array named after its colon, or
    what zarr does not open.

    Parameters
    ----------
    path : str or os.PathLike
        The store as given.

    Returns
    -------
    list of str
        The names, as the image lists them.

    Examples
    --------
    >>> import tempfile, zarr
    >>> d = tempfile.mkdtemp() + "/image.zarr"
    >>> g = zarr.open_group(d, mode="w")
    >>> g.require_group("labels").attrs["labels"] = ["cells", "nuclei"]
    >>> declared_labels(d), declared_labels(d + ":0")
    (['cells', 'nuclei'], [])
    """
    file, name = split_store(path)
    if name is not None:
        return []
    try:
        group = import_zarr().open_group(str(file), mode="r")["labels"]
        attrs = dict(group.attrs)
    except Exception:  # no group, no labels/ in it, or no store: nothing declared
        return []
    ome = attrs.get("ome")
    names = attrs.get("labels") or (ome.get("labels") if isinstance(ome, dict) else None)
    return [str(n) for n in names] if isinstance(names, list) else []


def fill_label(array) -> int | None:
    """The fill value of a zarr array (what zarr reads for a chunk never
    written) as the label it passes for.

    Parameters
    ----------
    array : zarr.Array
        The array whose ``fill_value`` is read (any object with one).

    Returns
    -------
    int or None
        The fill value as a whole number, else None (no fill value, or one
        that is no label, such as NaN).

    Examples
    --------
    >>> import tempfile, zarr
    >>> z = zarr.create_array(tempfile.mkdtemp() + "/v.zarr", shape=(4,), dtype="f4", fill_value=2.0)
    >>> fill_label(z), fill_label(zarr.create_array({}, shape=(4,), dtype="f4", fill_value=float("nan")))
    (2, None)
    >>> fill_label(zarr.create_array({}, shape=(4,), dtype="u8", fill_value=2**64 - 3))
    18446744073709551613
    >>> fill_label(zarr.create_array({}, shape=(4,), dtype="c16", fill_value=2 + 3j)) is None  # no label
    True
    """
    fill = getattr(array, "fill_value", None)
    if isinstance(fill, (bool, int, np.bool_, np.integer)):
        # exact: a float holds whole numbers only up to 2**53, so a uint64 or
        # int64 fill value beyond would name a neighbouring label
        return int(fill)
    if isinstance(fill, (complex, np.complexfloating)):
        # a complex store holds no labels (it is refused as such); float() would read 2+3j as label 2
        return None
    try:
        value = float(fill)
    except (TypeError, ValueError):
        return None
    return int(value) if np.isfinite(value) and value.is_integer() else None


#: an inner chunk of a shard that was never written has this offset and
#: length in the shard's index (the zarr v3 sharding codec)
EMPTY_INNER = 2**64 - 1


def unwritten(array, at: dict[int, int] | None = None) -> tuple[int, int]:
    """How many of a zarr array's chunks are not in its store (never
    written, or left out because they held nothing but the fill value):
    ``(missing, total)``. ``at`` maps an axis to one index along it (a time
    point): only the chunks holding that index are counted.

    The store's keys are listed and no chunk is read. In a sharded array
    the chunks are the shards' inner chunks, each told written or not by
    its shard's index (read from the end or start of the shard, as the
    sharding codec places it): zarr's own count (``nchunks_initialized``)
    takes every chunk of a written shard as written. A shard whose index
    cannot be read, or is coded other than as the sharding codec's plain
    bytes and checksum, counts as zarr counts it.

    Parameters
    ----------
    array : zarr.Array
        The stored array.
    at : dict, optional
        ``{axis: index}``: count only the chunks that hold that index.

    Returns
    -------
    tuple
        ``(missing, total)``.

    Examples
    --------
    >>> import tempfile, zarr
    >>> z = zarr.create_array(tempfile.mkdtemp() + "/v.zarr", shape=(6, 4), chunks=(2, 4), dtype="u1", fill_value=2)
    >>> z[:2] = 1
    >>> unwritten(z), unwritten(z, at={0: 3})
    ((2, 3), (1, 1))
    >>> s = zarr.create_array(tempfile.mkdtemp() + "/s.zarr", shape=(8, 4), chunks=(2, 4), shards=(4, 4),
    ...                       dtype="u1", fill_value=2)
    >>> s[:2] = 1  # one of the first shard's two chunks
    >>> unwritten(s), s.nchunks - s.nchunks_initialized
    ((3, 4), 2)
    """
    import itertools

    at = at or {}
    chunks = [int(c) for c in array.chunks]
    grid = [-(-int(n) // c) for n, c in zip(array.shape, chunks)]
    # the chunk indices counted along each axis
    spans = [range(at[i] // c, at[i] // c + 1) if i in at else range(g) for i, (c, g) in enumerate(zip(chunks, grid))]
    total = int(np.prod([len(s) for s in spans]))
    if not total:
        return 0, 0
    shards = getattr(array, "shards", None)
    per = [s // c for s, c in zip(shards, chunks)] if shards else [1] * len(chunks)
    stored = set(store_keys(array))
    found = [coords for coords in itertools.product(*(range(s.start // p, (s.stop - 1) // p + 1)
                                                      for s, p in zip(spans, per)))
             if array.metadata.encode_chunk_key(coords) in stored]
    if not shards:
        return total - len(found), total
    written = 0
    for coords, index in zip(found, shard_indexes(array, found, per)):
        inside = tuple(slice(max(s.start - c * p, 0), min(s.stop - c * p, p)) for s, c, p in zip(spans, coords, per))
        written += int(np.count_nonzero(index[inside])) if index is not None else int(
            np.prod([t.stop - t.start for t in inside]))
    return total - written, total


def store_keys(array) -> list[str]:
    """The keys of a zarr array's store under the array, relative to it
    (``c/0/1``, ``zarr.json``): what is stored, nothing read.

    Examples
    --------
    >>> import zarr
    >>> z = zarr.create_array({}, shape=(4, 2), chunks=(2, 2), dtype="u1")
    >>> z[2:] = 1
    >>> sorted(store_keys(z))
    ['c/1/0', 'zarr.json']
    """
    prefix = array.store_path.path
    prefix = prefix + "/" if prefix else ""

    async def listed() -> list[str]:
        return [k[len(prefix):] async for k in array.store_path.store.list_prefix(prefix)]

    return run_zarr(listed())


def run_zarr(coroutine):
    """Run a coroutine on a zarr store to its end and return its result:
    zarr's stores are asynchronous, and zarr's own synchronous calls run
    them on its I/O loop (``zarr.core.sync.sync``), which this takes where
    it is; a zarr without it (the module is not among zarr's documented
    API) runs the coroutine on a loop of its own, in a thread, so that a
    caller inside a running loop is not blocked by it.

    Examples
    --------
    >>> async def three():
    ...     return 3
    >>> run_zarr(three())
    3
    """
    try:
        from zarr.core.sync import sync
    except ImportError:
        import asyncio
        from concurrent.futures import ThreadPoolExecutor

        with ThreadPoolExecutor(1) as pool:
            return pool.submit(asyncio.run, coroutine).result()
    return sync(coroutine)


def shard_indexes(array, shards: list[tuple[int, ...]], per: list[int]) -> list[np.ndarray | None]:
    """Which inner chunks of each stored shard (its grid coordinates) hold
    data, from the shard's index alone: a boolean array of ``per`` (inner
    chunks per shard along each axis). None for a shard whose index is not
    read: a codec before the sharding codec, index codecs other than the
    plain bytes (and a checksum), or an index that does not come back.

    Examples
    --------
    >>> import zarr
    >>> z = zarr.create_array({}, shape=(8, 2), chunks=(2, 2), shards=(4, 2), dtype="u1")
    >>> z[2:4] = 1  # the first shard's second chunk
    >>> [m.ravel().tolist() for m in shard_indexes(z, [(0, 0)], [2, 1])]
    [[False, True]]
    """
    import asyncio

    from zarr.abc.store import RangeByteRequest, SuffixByteRequest
    from zarr.buffer import default_buffer_prototype
    from zarr.codecs import BytesCodec, Crc32cCodec, ShardingCodec

    codecs = list(getattr(array.metadata, "codecs", ()))
    sharding = codecs[0] if codecs else None
    index_codecs = list(getattr(sharding, "index_codecs", ()))
    if (not isinstance(sharding, ShardingCodec) or not index_codecs or not isinstance(index_codecs[0], BytesCodec)
            or any(not isinstance(c, Crc32cCodec) for c in index_codecs[1:])):
        return [None] * len(shards)
    n = int(np.prod(per))
    size = 16 * n + 4 * (len(index_codecs) - 1)
    order = ">" if getattr(index_codecs[0].endian, "value", "little") == "big" else "<"
    at_start = getattr(sharding.index_location, "value", sharding.index_location) == "start"
    request = RangeByteRequest(0, size) if at_start else SuffixByteRequest(size)

    async def one(coords: tuple[int, ...], gate: asyncio.Semaphore) -> np.ndarray | None:
        async with gate:
            try:
                got = await (array.store_path / array.metadata.encode_chunk_key(coords)).get(
                    prototype=default_buffer_prototype(), byte_range=request)
            except Exception:  # (counted as zarr counts it; reading the chunks says what is wrong)
                return None
        raw = None if got is None else got.to_bytes()
        if raw is None or len(raw) != size:
            return None
        table = np.frombuffer(raw[:16 * n], dtype=f"{order}u8").reshape(*per, 2)
        return table[..., 0] != EMPTY_INNER

    async def every() -> list[np.ndarray | None]:
        # a few shards at a time: an index is small, the files may be many
        gate = asyncio.Semaphore(64)
        return list(await asyncio.gather(*(one(c, gate) for c in shards)))

    return run_zarr(every()) if shards else []


def unwritten_fill(array, label: object = None, at: dict[int, int] | None = None) -> tuple[int, int, int] | None:
    """``(fill, missing, total)`` of a zarr array (:func:`fill_label` and
    :func:`unwritten`, ``at`` as there), as :func:`never_written` takes
    it; None where no chunk would pass for a voxel: a fill value of 0 or
    no label, one other than ``label`` when given, or every chunk
    written. The store's keys are listed only where they would matter.

    Examples
    --------
    >>> import zarr
    >>> z = zarr.create_array({}, shape=(6, 4), chunks=(2, 4), dtype="u1", fill_value=1)
    >>> z[:2] = 0
    >>> unwritten_fill(z), unwritten_fill(z, label=3), unwritten_fill(z, at={0: 1})
    ((1, 2, 3), None, None)
    """
    fill = fill_label(array)
    if not fill or (label is not None and label != fill):
        return None
    missing, total = unwritten(array, at)
    return (fill, missing, total) if missing else None


def never_written(where: str, unwritten: tuple[int, int, int] | None, label: object = None, *,
                  table: bool = False) -> None:
    """The one warning that a zarr store's chunks never written are read
    as a nonzero fill value and so count as voxels: of the object (a
    binary volume), of ``label`` where it is the fill value, or of the
    label the fill value is (``table``, a label table).

    Parameters
    ----------
    where : str
        The store, as messages name it.
    unwritten : tuple or None
        ``(fill, missing, total)``: the fill value as a label, the chunks
        not in the store (of a sharded array: its inner chunks) and all of
        them (of the time point read); None says nothing.
    label : number, optional
        The label selected; nothing is said unless it is the fill value.
    table : bool
        Every label is counted (``--labels``).

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     never_written("v.zarr", (1, 3, 4))
    ...     never_written("v.zarr", (2, 3, 4), label=5)  # another label: its count is right
    >>> [str(w.message).split("; ")[1] for w in caught]
    ['zarr reads their voxels as the fill value 1, so they count as voxels of the object']
    """
    if unwritten is None:
        return
    fill, missing, total = unwritten
    if not fill or not missing or (label is not None and label != fill):
        return
    counted = f"label {fill}" if table or label is not None else "voxels of the object"
    warn(f"{where}: {missing} of {total} chunks were never written; zarr reads their voxels as the fill value {fill}, "
         f"so they count as {counted}")
