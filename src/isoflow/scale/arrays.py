"""Where a volume lives: host NumPy, a CuPy array on a GPU, or any array-API array.

The array core (vertex configurations, their histogram, chi, the class vector
and the Betti numbers) is written against the Python array API standard, so a
CuPy volume is read on its GPU and never copied to the host: only the
256-entry histogram comes back. The few operations the standard lacks are
dispatched here, so the rest of the core names no library:

* counting codes: ``bincount`` where the library has it (NumPy, CuPy), the
  standard's ``unique_counts`` otherwise;
* connected components: ``scipy.ndimage.label`` on the host,
  ``cupyx.scipy.ndimage.label`` on a CuPy GPU; other libraries have no
  labelling, so their volume is copied to the host for that step alone.

Anything that is not an array-API array (lists, NumPy itself) is read with
``numpy.asarray``, a dask array block by block into one NumPy array
(:func:`read_anew`); host volumes must hold 0/1 values (:func:`binary`).
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import os
import sys
import uuid
from collections.abc import Mapping

import numpy as np

from ..errors import IsoflowError, counted, with_article
from .memory import sized


def namespace(x):
    """The array library of ``x``: ``numpy`` for host data, ``cupy`` for CuPy
    arrays, else the array's own ``__array_namespace__()``."""
    if isinstance(x, np.ndarray):
        return np
    if _is_cupy(x):
        import cupy

        # CuPy's main namespace has the standard's functions plus bincount;
        # its __array_namespace__ may be a narrower compatibility module.
        return cupy
    get = getattr(x, "__array_namespace__", None)
    return np if get is None else get()


def _is_cupy(x) -> bool:
    return type(x).__module__.partition(".")[0] in ("cupy", "cupyx")


def is_host(xp) -> bool:
    return xp is np


def refuse_object(array, where: str, then: str = "", reader: str = "isoflow.read_object") -> None:
    """Refuse a :class:`~isoflow.digital.lattice.DigitalObject`, a
    :class:`~isoflow.digital.label_table.LabelImage`, a triangle mesh (a
    ``trimesh.Trimesh`` or ``Scene``, a ``manifold3d.Manifold``) or a path
    where an array is taken: NumPy would make each a 0D array, refused for its
    shape or type rather than named (an object is known by its fields:
    this layer cannot import the classes). ``then``: what to do with
    the result to place it as the object is placed; ``reader``: the
    function that reads such a file."""
    if isinstance(array, (str, os.PathLike)):
        raise IsoflowError(f"{where}: {array} is a path, not an array; read it with {reader}")
    if all(hasattr(array, name) for name in ("volume", "pitch", "origin", "parity")):
        raise IsoflowError(f"{where}: a DigitalObject, not an array; pass its .volume" + (f" ({then})" if then else ""))
    if all(hasattr(array, name) for name in ("array", "spacing", "origin")):  # a LabelImage (read_labels)
        raise IsoflowError(f"{where}: a LabelImage, not a binary volume; pass one label's mask, "
                           "DigitalObject(image.array == N, pitch=image.spacing, origin=image.origin) "
                           "(label_table reports every label)")
    # a mesh in memory (a trimesh.Trimesh, a trimesh.Scene, a manifold3d.Manifold), known by its fields as
    # isoflow.mesh knows one: NumPy makes it a 0D array of type object, whose refusal names no mesh
    scene = all(hasattr(array, name) for name in ("graph", "geometry", "to_mesh"))
    if scene or (hasattr(array, "vertices") and hasattr(array, "faces")):
        # the voxeliser takes triangles; a QuadMesh is the surface of a volume, which is what to pass
        triangles = scene or np.shape(array.faces)[1:] == (3,)
        how = ("voxelise it first: isoflow.voxelize_mesh(mesh, resolution=N) (or voxelize_file(path) for its file)"
               if triangles else "pass the volume whose surface it is")
        raise IsoflowError(f"{where}: a mesh ({type(array).__name__}), not an array of voxels; {how}")
    if type(array).__name__ == "Manifold" and hasattr(array, "to_mesh"):
        raise IsoflowError(f"{where}: a manifold3d.Manifold, not an array of voxels; voxelise it first: "
                           "isoflow.from_manifold(manifold, pitch=P)")


def as_array(array, where: str = "volume") -> np.ndarray:
    """``numpy.asarray(array)``, nested sequences of uneven lengths refused
    in one line naming the argument: NumPy's own ``ValueError`` ("setting an
    array element with a sequence") names neither it nor the function.

    A dask array is read by :func:`read_anew` where it can be: each block
    is written into its place as it is computed, where ``numpy.asarray``
    holds every block and then their concatenation (twice the array's
    bytes at its peak).

    A masked array with masked elements is refused too: ``numpy.asarray``
    would read the values stored under the mask, which are missing data,
    as if they were valid. One with no masked element is read as its data.

    Parameters
    ----------
    array : array_like
        What the caller passed.
    where : str
        The argument's name, which the message starts with.

    Returns
    -------
    numpy.ndarray

    Raises
    ------
    IsoflowError
        For nested sequences of uneven lengths, for a masked array with
        masked elements, and for a mapping (:func:`refuse_mapping`).

    Examples
    --------
    >>> as_array([[1, 0], [0, 1]]).shape
    (2, 2)
    >>> try:
    ...     as_array([[1, 0], [1]], "volume")
    ... except IsoflowError as error:
    ...     print(str(error).split(" (")[0])
    volume: nested sequences of uneven lengths are no array
    >>> try:
    ...     as_array(np.ma.masked_equal([[1, 0], [0, 1]], 0), "volume")
    ... except IsoflowError as error:
    ...     print(str(error).split(";")[0])
    volume: a masked array with 2 masked elements
    >>> type(as_array(np.ma.array([[1, 0], [0, 1]], mask=False))).__name__
    'ndarray'
    """
    refuse_masked(array, where)
    refuse_mapping(array, where)
    read = read_anew(array, where)  # a dask array it reads is checked to fit there
    if read is not None:
        return read
    refuse_beyond_memory(array, where)
    if is_dask(array) and hasattr(array, "compute"):
        # one that read_anew leaves (its tasks run in other processes): computed as itself, where numpy.asarray
        # would give a masked block's data
        array = array.compute()
        masked = int(np.ma.count_masked(array)) if is_masked_array(array) else 0
        if masked:
            raise IsoflowError(masked_blocks(where, masked))
    try:
        return np.asarray(array)
    except ValueError as error:
        if "inhomogeneous" not in str(error):  # another failure of the object's own conversion: as it is
            raise
        raise IsoflowError(f"{where}: nested sequences of uneven lengths are no array ({error})") from None


def read_anew(array: object, where: str = "volume") -> np.ndarray | None:
    """A dask array computed into a NumPy array made for it here, which
    nothing else holds, so that a holder that must own its memory keeps it
    as it is (``numpy.asarray`` may give memory the caller still holds: an
    array that a dask task returns whole); None for anything else, and for
    a dask array of unknown chunk sizes or whose scheduler runs its tasks
    in other processes (which would write into copies of the array).

    Each block is written into its place once computed and then let go,
    a run of consecutive blocks a task (at most :data:`WRITE_TASKS`
    tasks): the peak is the array and the blocks in flight, where
    ``numpy.asarray`` holds every block and their concatenation.

    Parameters
    ----------
    array : object
        What the caller passed.
    where : str
        The argument's name, for the refusal of an array beyond memory
        (:func:`refuse_beyond_memory`).

    Returns
    -------
    numpy.ndarray or None
        A writeable array that owns its memory, of the dask array's shape
        and type.

    Examples
    --------
    >>> import dask.array as da
    >>> read = read_anew(da.ones((4, 4), dtype=bool, chunks=2))
    >>> read.dtype.name, int(read.sum()), read.flags.owndata, read_anew(np.ones(3)) is None
    ('bool', 16, True, True)
    """
    if not is_dask(array) or not hasattr(array, "store"):
        return None
    shape = tuple(array.shape)  # type: ignore[attr-defined]
    if any(not np.isfinite(s) for s in shape):
        return None
    import dask.local
    import dask.threaded
    from dask.base import get_scheduler

    scheduler = get_scheduler(collections=[array])
    if scheduler not in (dask.threaded.get, dask.local.get_sync):
        return None
    refuse_beyond_memory(array, where)
    read = np.empty(shape, dtype=array.dtype)  # type: ignore[attr-defined]
    _write_blocks(array, read, scheduler, where)
    return read


#: the most tasks that write a dask array's blocks into the array read
#: (:func:`read_anew`), each a run of consecutive blocks: dask's ``store``
#: schedules a task per block, which for thousands of small blocks costs
#: more than copying them, and ``numpy.asarray`` one task for all, which
#: holds every block until the last is computed
WRITE_TASKS = 64


def _write_blocks(array, read: np.ndarray, scheduler, where: str) -> None:
    """Compute the dask ``array`` into ``read`` by the thread-based
    ``scheduler``: each run of consecutive blocks is written into its
    place by a task that depends on those blocks alone, so a block is let
    go once written and no second array of the whole is held."""
    keys = list(_flat(array.__dask_keys__()))
    graph = dict(array.__dask_optimize__(array.__dask_graph__(), keys))
    bounds = [np.cumsum((0,) + tuple(c)).tolist() for c in array.chunks]
    places = [tuple(slice(b[i], b[i + 1]) for b, i in zip(bounds, index))
              for index in np.ndindex(*array.numblocks)]
    step = -(-len(keys) // WRITE_TASKS)
    # a name of its own: the graph's keys are the array's, never this one
    name = f"isoflow-write-{uuid.uuid4().hex}"
    writes = []
    for n, start in enumerate(range(0, len(keys), step)):
        run = slice(start, start + step)
        graph[(name, n)] = (functools.partial(_place, read, places[run], where), *keys[run])
        writes.append((name, n))
    scheduler(graph, writes)


def _place(read: np.ndarray, places: list[tuple[slice, ...]], where: str, *blocks) -> None:
    """A write task's work: its blocks, given in order, written into
    ``read`` at ``places``; a block with masked elements refused (a dask
    array of masked blocks, ``dask.array.ma``), as a masked NumPy array
    is (:func:`refuse_masked`): writing it would keep the values stored
    under its mask."""
    for place, block in zip(places, blocks):
        masked = int(np.ma.count_masked(block)) if is_masked_array(block) else 0
        if masked:
            raise IsoflowError(masked_blocks(where, masked, tuple(s.start for s in place)))
        read[place] = block


def masked_blocks(where: str, masked: int, corner: tuple[int, ...] | None = None) -> str:
    """The line that refuses a dask array of masked blocks with ``masked``
    masked elements (in the block at ``corner`` where known).

    Examples
    --------
    >>> masked_blocks("volume", 3, (4, 0, 0)).split(";")[0]
    'volume: a dask array of masked blocks, the block at (4, 0, 0) with 3 masked elements'
    >>> masked_blocks("volume", 1).split(";")[0]
    'volume: a dask array of masked blocks with 1 masked element'
    """
    at = "" if corner is None else f", the block at {corner}"
    return (f"{where}: a dask array of masked blocks{at} with {counted(masked, 'masked element')}; "
            + masked_remedy(True, "them"))


def masked_remedy(dask: bool, what: str = "the masked elements") -> str:
    """The two ways to read a masked array, or a dask array of masked
    blocks (``dask``), that the refusals of its masked elements give.

    Examples
    --------
    >>> masked_remedy(False)
    'pass a.filled(0) to read the masked elements as 0 (background), or a.data to use the values stored under the mask'
    """
    filled, data = ("dask.array.ma.filled(a, 0)", "dask.array.ma.getdata(a)") if dask else ("a.filled(0)", "a.data")
    return f"pass {filled} to read {what} as 0 (background), or {data} to use the values stored under the mask"


def is_dask(array: object) -> bool:
    """Whether ``array`` is one of dask's collections (told by its type's
    module, so that dask is not imported to ask).

    Examples
    --------
    >>> import dask.array as da
    >>> is_dask(da.zeros(3)), is_dask(np.zeros(3))
    (True, False)
    """
    return type(array).__module__.split(".")[0] == "dask"


def _flat(keys):
    """The keys of a dask array's nested lists (one level an axis), in
    order."""
    if isinstance(keys, list):
        return itertools.chain.from_iterable(_flat(k) for k in keys)
    return (keys,)


def refuse_beyond_memory(array: object, where: str = "volume") -> None:
    """Refuse, before it is read, a dask or zarr array whose voxels would
    not fit in memory (:func:`~isoflow.scale.memory.check_fits`): NumPy
    would read it whole, raising its MemoryError or making the machine
    swap, where the functions that read it block by block are meant.

    Parameters
    ----------
    array : object
        Anything; only an array of the dask or zarr library is looked at.
    where : str
        The argument's name, for the message.

    Raises
    ------
    IsoflowError
        Naming ``where``, the array's shape and type, the memory it needs
        and the functions that read it block by block.

    Examples
    --------
    >>> import dask.array as da
    >>> try:
    ...     refuse_beyond_memory(da.zeros((1 << 16,) * 3, dtype=np.uint8, chunks=256), "volume")
    ... except IsoflowError as error:
    ...     print(str(error).split(" needs")[0])
    volume: reading a 65536x65536x65536 dask array of uint8 into memory
    """
    from .memory import check_fits

    library = type(array).__module__.split(".")[0]
    if library not in ("dask", "zarr") or not hasattr(array, "shape") or not hasattr(array, "dtype"):
        return
    shape = tuple(array.shape)
    if any(not np.isfinite(s) for s in shape):  # a dask array of unknown chunk sizes: its size is not known
        return
    need = int(np.prod([int(s) for s in shape], dtype=object)) * np.dtype(array.dtype).itemsize
    check_fits(need, f"{where}: reading a {'x'.join(str(int(s)) for s in shape)} {library} array of "
               f"{np.dtype(array.dtype)} into memory",
               hint="isoflow.analyze_chunked reads a dask or zarr array block by block "
                    "(a label image in a zarr store: isoflow info STORE.zarr --labels)")


def refuse_mapping(array: object, where: str = "volume") -> None:
    """Refuse a mapping where an array is taken, naming it: NumPy makes an
    isoflow result (a Report, the LabelVoxelization of ``voxelize_meshes``)
    a 1D array of its keys, refused as "array of type <U14" or as 1D, and a
    dict a 0D array of type object. A result's field that holds an array
    (``labels``, ``volume``) is named as what to pass.

    Parameters
    ----------
    array : object
        Anything; only a :class:`collections.abc.Mapping` is refused.
    where : str
        The argument's name, for the message.

    Raises
    ------
    IsoflowError
        Naming ``where``, the mapping's type and the field to pass.

    Examples
    --------
    >>> refuse_mapping(np.zeros(3))
    >>> try:
    ...     refuse_mapping({"volume": np.ones((2, 2))}, "volume")
    ... except IsoflowError as error:
    ...     print(error)
    volume: a dict, not an array
    """
    if not isinstance(array, Mapping):
        return
    held = [k for k in array if isinstance(k, str) and isinstance(value := getattr(array, k, None), np.ndarray)
            and value.ndim >= 2]
    raise IsoflowError(f"{where}: {with_article(type(array).__name__)}, not an array"
                       + (f"; pass its .{held[0]}" if held else ""))


def is_masked_array(value: object) -> bool:
    """Whether ``value`` is a :class:`numpy.ma.MaskedArray`, without
    importing :mod:`numpy.ma`.

    ``np.ma`` is imported on its first use, a noticeable share of a light
    command's start (``isoflow info`` of a small ``.npy``); no masked array
    can exist before it is, so until then the answer is no. Nor while
    another thread is importing it (NumPy's ``np.unique`` does, in a
    block's task): the module is in :data:`sys.modules` before its
    ``MaskedArray`` is defined.

    Parameters
    ----------
    value : object
        Anything.

    Returns
    -------
    bool

    Examples
    --------
    >>> is_masked_array(np.zeros(3)), is_masked_array(np.ma.masked_equal([1, 0], 0))
    (False, True)
    """
    masked = getattr(sys.modules.get("numpy.ma.core"), "MaskedArray", None)
    return masked is not None and isinstance(value, masked)


def refuse_masked(array: object, where: str = "volume") -> None:
    """Refuse a masked array with masked elements in one line: its masked
    elements are missing data, and NumPy's conversions read whatever value
    is stored under the mask. One with no masked element (``nomask`` or an
    all-False mask) passes, as nothing is lost by reading its data.

    Parameters
    ----------
    array : object
        Anything; only a :class:`numpy.ma.MaskedArray` is looked at.
    where : str
        The argument's name, for the message.

    Raises
    ------
    IsoflowError
        Naming ``where``, the count of masked elements and what to pass.

    Examples
    --------
    >>> refuse_masked(np.ma.array([1, 0], mask=False))
    >>> try:
    ...     refuse_masked(np.ma.masked_equal([1, 0], 0), "labels")
    ... except IsoflowError as error:
    ...     print(str(error).split(";")[0])
    labels: a masked array with 1 masked element
    """
    if not is_masked_array(array):
        return
    masked = int(np.ma.count_masked(array))
    if masked:
        raise IsoflowError(f"{where}: a masked array with {counted(masked, 'masked element')}; {masked_remedy(False)}")


#: elements of a float volume looked at at a time for values other than 0
#: and 1: the look's two bool temporaries stay a small part of the volume
#: (the whole volume's would be two bytes a voxel, twice a uint8 volume)
CHECKED_AT_ONCE = 1 << 18


def holds_other_values(arr: np.ndarray) -> bool:
    """Whether a numeric array holds a value other than 0 and 1 (NaN
    too), looked for without a temporary array of the whole: an integer
    array by its least and greatest value, a float one a block of
    :data:`CHECKED_AT_ONCE` elements at a time.

    Parameters
    ----------
    arr : numpy.ndarray
        Integers or floats, of any shape and layout.

    Returns
    -------
    bool

    Examples
    --------
    >>> holds_other_values(np.array([[0, 1], [1, 0]], np.uint8)), holds_other_values(np.array([0, 2]))
    (False, True)
    >>> holds_other_values(np.array([0.0, np.nan])), holds_other_values(np.zeros((0, 3)))
    (True, False)
    """
    if not arr.size:
        return False
    if arr.dtype.kind in "iu":
        return bool(arr.max() > 1) or (arr.dtype.kind == "i" and bool(arr.min() < 0))
    if arr.ndim == 0:
        return not (arr == 0 or arr == 1)
    step = max(1, CHECKED_AT_ONCE // max(1, arr.size // arr.shape[0]))
    for start in range(0, arr.shape[0], step):
        part = arr[start:start + step]
        other = part != 0  # NaN is caught too: NaN != 0 and NaN != 1
        other &= part != 1
        if other.any():
            return True
    return False


def binary(array, where: str = "volume", near=None, canonical: bool = True, remedy: str | None = None,
           remedy_dims: tuple[int, ...] = (2, 3)) -> np.ndarray:
    """A host boolean volume from a 0/1 array, or a clear error saying why not.

    Other values (NaN, 2, -1, 255) are refused rather than read as True: a
    label image or a probability map needs a threshold the caller chooses.
    ``near``: the index of the block's first voxel, for errors found block by
    block (out-of-core input). ``canonical=False`` returns a bool array as it
    is, for a pass that reads every nonzero byte as set
    (:func:`isoflow.scale.bitrows.pack`), which spares it the pass over the
    volume that the check costs.

    ``where`` begins a refusal: a public function's name and its argument's
    (``run_flow: obj``), a file's name, or the argument alone. A label image
    in memory is offered :func:`~isoflow.digital.label_table.label_table`,
    which stands in for analyze and its kind only; ``remedy`` (the function
    called, ``{}`` where one label's mask goes: ``"run_flow({})"``,
    ``"write_surface({}, path)"``) offers instead that call of one label's
    mask, as a table of numbers is no flow, no surface and no histogram; an
    image of a dimension not in ``remedy_dims`` (those the function takes)
    is offered neither, as its next refusal would be of that.

    Examples
    --------
    >>> image = np.array([[0, 1], [2, 2]], np.uint8)
    >>> binary(image, "flow_step: obj", remedy="flow_step({})")
    Traceback (most recent call last):
    ...
    isoflow.scale.arrays.NotBinary: flow_step: obj: not a binary image (2 pixels hold values other than 0 and 1, \
e.g. 2); threshold it first, e.g. image > 0, or one label at a time, e.g. flow_step(image == 2)
    """
    refuse_object(array, where)
    arr = as_array(array, where)
    if arr.dtype == np.bool_ and not canonical:
        return arr
    if arr.dtype == np.bool_:
        # A bool array made by .view(bool) can hold bytes other than 0/1,
        # which numpy compares and cc3d labels as distinct values: make them
        # canonical (the max is one pass, and most arrays need no copy).
        if arr.size and arr.view(np.uint8).max() > 1:
            arr = arr.view(np.uint8) != 0
        return arr
    # a 2D image (a PNG or TIFF segmentation) is an image of pixels, as info
    # calls it, in the refusal and in its threshold example alike
    thing = "image" if arr.ndim == 2 else "volume"
    if arr.dtype.kind not in "iuf":
        raise IsoflowError(f"{where}: array of type {arr.dtype} is not a binary {thing}")
    if holds_other_values(arr):
        bad = (arr != 0) & (arr != 1)  # NaN is caught too: NaN != 0 and NaN != 1
        value, nbad = arr[bad].flat[0], int(bad.sum())
        # the count is of voxels (not of distinct values), and of this block
        # only where the volume is checked block by block
        cell = "pixel" if arr.ndim == 2 else "voxel"
        place = f" in the block at {cell} {tuple(int(o) for o in near)}" if near is not None else ""
        # a value that is no label (NaN, infinite, not whole) anywhere in
        # the array is refused by a label table too: --labels is not offered
        values = arr[bad]
        labels = arr.dtype.kind in "iu" or bool(np.all(np.isfinite(values) & (values == np.round(values))))
        kind = value_kind(values, labels)
        bare = (f"{where}: not a binary {thing} ({counted(nbad, cell)}{place} hold{'s' if nbad == 1 else ''} "
                "values other than 0 and 1, "
                f"e.g. {value}); threshold it first, e.g. {thing} {threshold_example(arr, kind)}")
        # integers in memory are most often a label image, which has a table
        # (a command adds its own options to ``bare`` instead)
        table = near is None and arr.dtype.kind in "iu" and arr.ndim in (2, 3) and kind == "labels"
        # a float block's whole values say nothing of the blocks not read,
        # which a label table reads too: whether it takes them is not known
        every = None if labels and near is not None and arr.dtype.kind == "f" else labels
        # a block of 0 and one other value (a 0/255 mask read block by block, or 0/0.5): the label that selects
        # it is that value (a whole array of one value is read as its mask by the file readers, never refused)
        one = (near is not None and bool(np.isfinite(value)) and bool(np.all(values == value))
               and not bool((arr == 1).any()))
        raise NotBinary(bare + (label_remedy(thing, value, remedy, remedy_dims, arr.ndim) if table else ""),
                        bare, every=every, ndim=arr.ndim if table else None, kind=kind, value=value if one else None)
    return arr.astype(bool)


def label_remedy(thing: str, label: object, remedy: str | None, dims: tuple[int, ...], ndim: int) -> str:
    """What a refusal of a label image in memory, where a mask is
    expected, offers after its threshold (:func:`binary`): every label's
    row of a table, or ``remedy`` of one label's mask, or nothing for an
    image of a dimension the function does not take.

    Examples
    --------
    >>> label_remedy("volume", 2, None, (2, 3), 3)
    ', or give every label its row with isoflow.label_table(volume)'
    >>> label_remedy("volume", 2, "write_surface({}, path)", (3,), 3), label_remedy("image", 2, "to_manifold({})", (3,), 2)
    (', or one label at a time, e.g. write_surface(volume == 2, path)', '')
    """
    if remedy is None:
        return f", or give every label its row with isoflow.label_table({thing})"
    return f", or one label at a time, e.g. {remedy.format(f'{thing} == {label}')}" if ndim in dims else ""


#: more distinct values other than 0 and 1 than this read as a grey image
#: (an 8-bit one holds up to 254) rather than a label image, whose labels
#: are a handful to some dozens (FreeSurfer's aseg about 40)
LABEL_HANDFUL = 64
#: values sampled to count them: the count decides a message, not a result
COUNTED_VALUES = 1 << 20


def value_kind(values: np.ndarray, whole: bool) -> str:
    """What the values other than 0 and 1 of a volume refused as a mask
    look like: ``labels`` (a handful of whole numbers, at most
    :data:`LABEL_HANDFUL`), ``grey`` (more whole numbers: an 8-bit grey
    image) or ``fractions`` (a value that is not a whole number: a
    probability map, a grey image in floats), so that the refusal offers
    the options that fit.

    Parameters
    ----------
    values : ndarray
        The values other than 0 and 1.
    whole : bool
        Whether every one is a finite whole number.

    Returns
    -------
    str

    Examples
    --------
    >>> value_kind(np.array([2, 3, 2]), True), value_kind(np.arange(2, 200), True), value_kind(np.array([0.5]), False)
    ('labels', 'grey', 'fractions')
    """
    if not whole:
        return "fractions"
    sample = values.ravel()[:: max(1, values.size // COUNTED_VALUES)]
    return "labels" if len(np.unique(sample)) <= LABEL_HANDFUL else "grey"


def threshold_example(arr: np.ndarray, kind: str) -> str:
    """The test a refusal suggests: ``> 0`` for labels (every label's
    voxels; ``!= 0`` where a label is negative, which ``> 0`` would leave
    out), else ``>`` half way through the values (a whole number for whole
    values), ``> 0.5`` for a probability map (values from 0 to 1).

    Parameters
    ----------
    arr : ndarray
        The volume refused.
    kind : str
        Its :func:`value_kind`.

    Returns
    -------
    str
        The comparison, operator and value.

    Examples
    --------
    >>> threshold_example(np.array([0, 2, 3]), "labels"), threshold_example(np.array([0.1, 0.9]), "fractions")
    ('> 0', '> 0.5')
    >>> threshold_example(np.array([0, 17, 255], np.uint8), "grey"), threshold_example(np.array([0, -1, -2]), "labels")
    ('> 127', '!= 0')
    """
    finite = arr[np.isfinite(arr)] if arr.dtype.kind == "f" else arr
    if kind == "labels" or not finite.size:
        return "!= 0" if finite.size and finite.min() < 0 else "> 0"
    low, high = float(finite.min()), float(finite.max())
    if kind == "grey":  # whole values: a whole threshold
        return f"> {int((low + high) // 2)}"
    return "> 0.5" if 0 <= low and high <= 1 else f"> {(low + high) / 2:.3g}"


#: what a zarr array's fill value is, said after a value that is it
FILL_READ = "the array's fill value, which zarr reads for a chunk never written"
#: the store that a value other than a label or 0 and 1 in chunks never written asks for
FILL_ZERO = "write the store with fill_value=0, which a chunk never written then reads as 0"


def fill_as(fill: object, dtype: object):
    """A zarr array's fill value as a value of ``dtype`` (the type a voxel
    was printed or compared in), or None where there is none or it has no
    such value.

    Parameters
    ----------
    fill : object
        The array's ``fill_value`` (None: not a zarr array).
    dtype : numpy dtype
        The voxels' type.

    Returns
    -------
    numpy scalar or None

    Examples
    --------
    >>> fill_as(float("nan"), np.float32), fill_as(None, np.uint8), fill_as("x", np.float64)
    (np.float32(nan), None, None)
    """
    if fill is None:
        return None
    try:
        with np.errstate(all="ignore"):
            return np.asarray(fill).astype(dtype)[()]
    except (TypeError, ValueError):
        return None


def fill_value_named(exc: NotBinary, fill: object, dtype: object) -> NotBinary:
    """``exc`` of a block read from a zarr array, saying so where its example
    value is the array's fill value: zarr reads every voxel of a chunk that
    was never written as the fill value, so a store written sparsely with a
    fill value other than 0 and 1 (NaN, 255) is refused for voxels nobody
    wrote, and the value alone would not say why. A fill value that is no
    label (NaN, infinite, not whole) is refused by a label table too, so
    the refusal offers a store written with ``fill_value=0`` instead of
    one (``every`` False: no ``--labels``). So is a block of whole values
    whose other blocks are not read (``every`` None) where the fill value
    is no label: the chunks never written, read as it, would be refused;
    the line names the fill value.

    Parameters
    ----------
    exc : NotBinary
        The refusal of the block (:func:`binary`).
    fill : number or None
        The array's ``fill_value``.
    dtype : numpy dtype
        The array's type, in which the value was printed.

    Returns
    -------
    NotBinary
        ``exc``, with the fill value named after the example where it is
        the example.

    Examples
    --------
    >>> e = NotBinary("s.zarr: not a binary volume (8 voxels hold values other than 0 and 1, e.g. nan); threshold")
    >>> named = fill_value_named(e, float("nan"), np.float32)
    >>> print(str(named).split("; ")[0])  # doctest: +ELLIPSIS
    s.zarr: not a binary volume (8 voxels hold ... e.g. nan, the array's fill value, which zarr reads for a chunk never written)
    >>> print(str(named).split("; ")[1])
    threshold, or write the store with fill_value=0, which a chunk never written then reads as 0
    >>> named.every  # a label table refuses NaN too: no --labels offered
    False
    >>> e = NotBinary("s.zarr: not a binary volume (8 voxels hold values other than 0 and 1, e.g. 2.0); threshold",
    ...               every=None)
    >>> other = fill_value_named(e, float("nan"), np.float32)  # a block of whole values, of a store filled with NaN
    >>> other.every, str(other).split("; ")[1]
    (False, "zarr reads a chunk never written as the array's fill value, nan, which is no label)")
    """
    value = fill_as(fill, dtype)
    if value is None:
        return exc
    example = f"e.g. {value})"
    label = bool(np.isfinite(value) and value == np.round(value)) if np.asarray(value).dtype.kind == "f" else True
    if example not in exc.bare:
        if label or exc.every is not None:
            return exc
        # a block of whole values, of a store whose chunks never written a
        # label table refuses: --labels is not offered, and the line says why
        told = f"; zarr reads a chunk never written as the array's fill value, {value}, which is no label); "
        unlabelled = exc.bare.replace("); ", told, 1)  # (the end of binary's example)
        return NotBinary(str(exc.args[0]).replace(exc.bare, unlabelled, 1), unlabelled, False, exc.ndim, exc.kind,
                         exc.value)
    named = f"{example[:-1]}, {FILL_READ})"
    bare = exc.bare.replace(example, named, 1)
    if label:
        return NotBinary(str(exc.args[0]).replace(exc.bare, bare, 1), bare, exc.every, exc.ndim, exc.kind, exc.value)
    # a label table refuses the value as it does here: a store with fill 0 is read either way
    unlabelled = bare + f", or {FILL_ZERO}"
    return NotBinary(str(exc.args[0]).replace(exc.bare, unlabelled, 1), unlabelled, False, exc.ndim, exc.kind,
                     exc.value)


class NotBinary(IsoflowError):
    """A volume of values other than 0 and 1 where a mask is expected (a
    label image, most often): a kind of its own, so that a command can add
    the options that select its labels, in memory or block by block, to
    ``bare`` (the message without them). ``every``: whether ``--labels``
    can take the image (a label table is 2D or 3D), so may be offered;
    None where that is not known (a float block of whole values, read
    before the blocks that may hold a value that is no label), so that it
    is offered on that condition;
    ``ndim``: the image's dimension where known (``surface --labels`` takes
    3D images only); ``kind``: what the values look like
    (:func:`value_kind`), so that a probability map is offered no label;
    ``value``: the one value other than 0 where the block read holds no
    other, a mask of it (0/255), which ``--label`` then names (``--label
    255``), else None."""

    def __init__(self, message: str, bare: str | None = None, every: bool | None = True, ndim: int | None = None,
                 kind: str = "labels", value: object = None):
        super().__init__(message)
        self.value = value
        self.bare = message if bare is None else bare
        self.every = every
        self.ndim = ndim
        self.kind = kind


def as_volume(volume, where: str = "volume", canonical: bool = True, dims: tuple[int, ...] = (2, 3, 4),
              remedy: str | None = None):
    """``(xp, boolean volume)`` of a 0/1 array of a dimension in ``dims``:
    host data checked by :func:`binary` (``canonical``, ``where`` and
    ``remedy``: see there), device arrays left where they are."""
    xp = namespace(volume)
    if is_host(xp):
        v = binary(volume, where, canonical=canonical, remedy=remedy, remedy_dims=dims)
    else:
        v = volume
        if v.dtype != xp.bool:
            if bool(xp.any((v != 0) & (v != 1))):
                raise IsoflowError(f"{where}: not a binary {'image' if v.ndim == 2 else 'volume'} (values other than 0 "
                                   "and 1)")
            v = xp.astype(v, xp.bool)
    if v.ndim not in dims:
        allowed = ", ".join(f"{d}D" for d in dims[:-1]) + f" or {dims[-1]}D"
        raise IsoflowError(f"{where}: a volume is {allowed}, got a {v.ndim}D array")
    return xp, v


def on_device(volume):
    """Context in which new arrays go to ``volume``'s device (CuPy allocates
    on the *current* GPU, which need not be the input's)."""
    return volume.device if _is_cupy(volume) else contextlib.nullcontext()


def zeros(xp, shape, dtype, like):
    """Zeros on the device of ``like``."""
    if is_host(xp) or _is_cupy(like):
        return xp.zeros(shape, dtype=dtype)
    return xp.zeros(shape, dtype=dtype, device=like.device)


def to_host(x) -> np.ndarray:
    """An explicit copy to host memory (never an implicit ``numpy.asarray``,
    which CuPy refuses)."""
    if isinstance(x, np.ndarray):
        return x
    if _is_cupy(x):
        return x.get()
    return np.from_dlpack(x)


def count_codes(xp, codes, size: int) -> np.ndarray:
    """How often each value ``0 .. size-1`` occurs in ``codes``, as a host
    int64 vector."""
    flat = xp.reshape(codes, (-1,))
    if hasattr(xp, "bincount"):
        return to_host(xp.bincount(flat, minlength=size)).astype(np.int64)
    values, counts = xp.unique_counts(flat)
    out = np.zeros(size, dtype=np.int64)
    out[to_host(values).astype(np.int64)] = to_host(counts)
    return out


def label_function(xp):
    """``label(volume, connectivity) -> (labels, count)`` for ``xp``'s
    arrays, or None where the library has no labelling."""
    from .labels import label, structure

    if is_host(xp):
        return label
    if xp.__name__ == "cupy":
        from cupyx.scipy.ndimage import label as cupy_label

        return lambda volume, connectivity: cupy_label(volume, structure(volume.ndim, connectivity))
    return None


#: bytes of GPU memory per voxel that ``analyze`` needs at most: the volume,
#: its complement and the int32 labels of one labelling, plus slack
GPU_BYTES_PER_VOXEL = 8


def to_gpu(volume: np.ndarray):
    """A host volume uploaded to the current CuPy GPU, after checking that
    CuPy works and that the analysis will fit in the GPU's free memory."""
    try:
        import cupy

        free, _total = cupy.cuda.runtime.memGetInfo()
    except Exception as exc:  # no CuPy, no driver, no device
        raise IsoflowError(
            f"--gpu needs CuPy and a CUDA GPU ({type(exc).__name__}: {exc}); "
            "install with: pip install 'isoflow[gpu]'"
        ) from None
    need = int(np.prod(volume.shape, dtype=np.int64)) * GPU_BYTES_PER_VOXEL
    if need > free:
        raise IsoflowError(
            f"a {'x'.join(map(str, volume.shape))} volume needs about {sized(need)} "
            f"of GPU memory and {sized(free)} is free; drop --gpu"
        )
    return cupy.asarray(volume)


def index_dtype(count: int) -> type:
    """The index type of a mesh with ``count`` vertices: int32 below 2^31
    (half the memory of int64, which large meshes need), else int64.

    Examples
    --------
    >>> index_dtype(8).__name__, index_dtype(2**31).__name__
    ('int32', 'int64')
    """
    return np.int32 if count < 2**31 else np.int64
