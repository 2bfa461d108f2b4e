"""HDF5, ``FILE.h5:/path/to/dataset`` (h5py).

Axes: the dataset's axes as stored (C order), axis 0 being x, as for
``.npy``. Without a dataset path the file must hold one dataset, one
named ``volume``, or one of 2 to 4 axes beside datasets of fewer (a name,
a voxel size); otherwise the error lists the datasets to choose from
(a dataset an external link names among them). A dataset whose axes
vigra's ``axistags`` attribute names (ilastik's exports) is read by them
(:func:`tagged_axes`), as is one whose axes funlib.persistence's
``axis_names`` names (:func:`axes_by_name`): a channel axis of one entry
dropped, of several refused, and the spatial axes turned to the x, y, z
the names give (ilastik and funlib store z, y, x).

Metadata: isoflow writes the attributes ``pitch`` (one number, or one per
axis), ``origin``, ``offset`` and ``parity`` on the dataset and reads them
back, so a round trip is exact. Files from other tools: the voxel size
in their word (:mod:`~isoflow.mesh.formats.grid_attributes`: ilastik's and
Fiji's ``element_size_um`` in µm, CREMI's and gunpowder's ``resolution``
with ``offset`` in world units, funlib's ``voxel_size``, ``spacing``) is
read when ``pitch`` is absent. The length unit: isoflow's attribute
``unit`` (a string) where present, else the one the voxel size's
attribute says (µm for ``element_size_um``). ``.hdf`` (CREMI's suffix)
is read as HDF5. A unit given is written
as ``unit``; and, where it is µm, ``element_size_um`` too (the pitch per
dataset axis), for Fiji and ilastik. An anatomical frame known (a volume
read from NIfTI, MGH or a NRRD with a space) is isoflow's attribute
``space`` (``"LPS"``), read back with it. A label image's names are the
attribute ``label_names``, JSON text of an object of label value to name
(``{"1": "a.stl", "2": "b.obj"}``).

Written as uint8 0/1, gzip-compressed and chunked. ``FILE.h5`` names the
file: a new one (``--force`` replaces it). ``FILE.h5:/group/name`` names one
dataset: written into an existing HDF5 file beside its other datasets, which
are kept (``--force`` only where that dataset is there already; HDF5 does not
give back a replaced dataset's space, ``h5repack`` does). The file is built
in memory (compressed) and written out whole, so a write that fails midway
(a full disk) is one error line; a dataset added to an existing file holds
that file in memory too, twice (read whole, and its image written out):
counted in the memory check before any work, and again with the dataset
before the write, the refusal naming ``h5copy``, which copies a dataset
written to a file of its own into the large one without reading it.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...digital.frames import space_given
from ...digital.lattice import DigitalObject
from ...digital.report import Report
from ...errors import IsoflowError
from ...scale.chunks import axis_names_given
from .grid_attributes import READ, VOXEL_SIZES, attribute_grid, size_named
from .registry import (
    READ_HINT,
    RawVolume,
    check_label,
    check_shape,
    import_library,
    names_from_json,
    names_json,
    no_such_label,
    note,
    reading,
    split_dataset,
    stored_values,
    unit_field,
)

DEFAULT_DATASET = "volume"
#: copies of an existing file that adding a dataset to it holds: the file
#: read whole by HDF5's core driver and the image of it written out
FILE_COPIES = 2
#: bytes per voxel of the dataset added beside them, at most: its uint8
#: values and their gzip stream in both copies (1.5 measured on a random
#: mask, which compresses least)
DATASET_BYTES = 2


def read(path: Path, dataset: str | None = None) -> RawVolume:
    h5py = import_library("h5py", "HDF5")
    where = str(path) if dataset is None else f"{path}:{dataset}"
    with reading(path, "HDF5"), h5py.File(path, "r") as f:
        found = _opened(f, h5py, path, dataset, where)
        check_shape(found.shape, found.dtype, where, hint=HINT)
        ds = f[found.name]
        array = ds[found.index] if found.index else ds[()]
    # the axes read are in stored order: turned to the order the tags give them (x, y, z, t)
    array = np.transpose(array, [sorted(found.kept).index(i) for i in found.kept])
    return RawVolume(np.asarray(array), *found.placement, unit=found.unit, space=found.space, names=found.names)


#: what a dataset too large to read whole can do instead
HINT = (f"{READ_HINT}; 'isoflow info FILE.h5:/DATASET' (--label N, --labels too) and 'isoflow surface "
        "FILE.h5:/DATASET -o OUT.ply' (or .stl) read a 3D HDF5 volume a block at a time")


def fits_whole(path: str | os.PathLike) -> bool:
    """Whether ``FILE.h5`` (or ``FILE.h5:/DATASET``) is read whole for its
    label table: it fits in memory as :func:`read` reads it, or it is not
    3D (a 2D image and a time series are read whole, and refused there
    where they do not fit); else its table is read a slab at a time
    (:class:`LabelSlabs`).

    Parameters
    ----------
    path : str or os.PathLike
        The file, with its dataset where named.

    Returns
    -------
    bool

    Examples
    --------
    >>> import tempfile, h5py
    >>> from isoflow.scale.memory import budget_held
    >>> path = Path(tempfile.mkdtemp()) / "seg.h5"
    >>> with h5py.File(path, "w") as f:
    ...     _ = f.create_dataset("seg", shape=(100, 100, 100), dtype=np.uint32)
    >>> fits_whole(path)
    True
    >>> with budget_held(10**6):
    ...     fits_whole(path)
    False
    """
    from ...scale.memory import DoesNotFit

    shape, dtype = _spatial(path)
    if len(shape) != 3:
        return True
    try:
        check_shape(shape, dtype, str(path))
    except DoesNotFit:
        return False
    return True


def is_3d(path: str | os.PathLike) -> bool:
    """Whether ``FILE.h5`` (or ``FILE.h5:/DATASET``) holds a 3D volume
    (its axes as :func:`read` takes them), which :func:`analyze_dataset`
    reads a block at a time.

    Examples
    --------
    >>> import tempfile, h5py
    >>> path = Path(tempfile.mkdtemp()) / "seg.h5"
    >>> with h5py.File(path, "w") as f:
    ...     _ = f.create_dataset("seg", shape=(1, 5, 6, 7), dtype=np.uint8).attrs["axis_names"] = ["c^", "z", "y", "x"]
    >>> is_3d(path)
    True
    """
    return len(_spatial(path)[0]) == 3


def _spatial(path: str | os.PathLike) -> tuple[list[int], np.dtype]:
    """The shape of the dataset as :func:`read` takes its axes, and its
    type, from its metadata alone."""
    file, dataset = split_dataset(path)
    h5py = import_library("h5py", "HDF5")
    with reading(file, "HDF5"), h5py.File(file, "r") as f:
        ds = f[_choose(f, h5py, file, dataset)]
        stored = tuple(int(n) for n in ds.shape)
        _, kept = named_axes(ds.attrs, stored, str(path))
        return [stored[i] for i in kept], ds.dtype


@dataclass(frozen=True)
class _Dataset:
    """An HDF5 dataset as isoflow reads it, before its values: its path in
    the file, how to read it (``index``, ``kept``: :func:`axes_by_name`),
    its shape in isoflow's order and type, stored shape and chunks, its
    placement (``pitch, origin, offset, parity``), unit, frame and label
    names."""

    name: str
    index: tuple
    kept: list[int]
    shape: tuple[int, ...]
    dtype: np.dtype
    stored: tuple[int, ...]
    chunks: tuple[int, ...] | None
    placement: tuple
    unit: str | None
    space: str | None
    names: dict[int, str] | None


def _opened(f, h5py, path: Path, dataset: str | None, where: str) -> _Dataset:
    """The dataset ``read`` reads in the open file ``f``: chosen, its axes
    by name, placed by its attributes (isoflow's, else another tool's:
    :func:`~isoflow.mesh.formats.grid_attributes.attribute_grid`)."""
    chosen = _choose(f, h5py, path, dataset)
    ds = f[chosen]
    attrs = dict(ds.attrs)
    stored = tuple(int(n) for n in ds.shape)
    index, kept = named_axes(attrs, stored, where)
    # beside a volume placed by no attribute, a dataset that holds a voxel size is not read as its own
    if "pitch" not in attrs and not any(name in attrs for name in VOXEL_SIZES):
        beside = size_named((n for n in _datasets(f, h5py)[0] if n != chosen.strip("/")), attributes=False)
        if beside:
            note(f"{where}: {'the dataset' if len(beside) == 1 else 'the datasets'} "
                 f"{', '.join('/' + n for n in beside)} beside it {'is' if len(beside) == 1 else 'are'} not read: "
                 f"voxels of 1 (isoflow reads the voxel size from the dataset's attributes {READ})")
    # another tool's voxel size (ilastik's element_size_um, CREMI's resolution, ...), per stored axis
    grid = attribute_grid(attrs, stored, kept, where)
    if grid is None:  # isoflow's own attributes, or none
        pitch, origin, offset, unit = attrs.get("pitch", 1.0), attrs.get("origin"), attrs.get("offset"), None
    else:
        pitch, unit = grid.pitch, grid.unit
        origin = attrs.get("origin") if grid.origin is None else grid.origin
        offset = attrs.get("offset") if grid.lattice_offset else None
    if "unit" in attrs:
        unit = unit_field(attrs["unit"], f"{where}: attribute 'unit'")
    names = names_from_json(attrs["label_names"], where, "attribute 'label_names'") if "label_names" in attrs else None
    space = space_given(str(attrs["space"]), f"{where}: attribute 'space'") if "space" in attrs else None
    return _Dataset(chosen, index, kept, tuple(stored[i] for i in kept), ds.dtype, stored,
                    None if ds.chunks is None else tuple(int(c) for c in ds.chunks),
                    (pitch, origin, offset, attrs.get("parity", 0)), unit, space, names)


class LabelSlabs:
    """An HDF5 dataset's 3D label image read a slab at a time (h5py reads
    any block of a dataset), as :class:`~isoflow.mesh.formats.omezarr.LabelSlabs`
    reads a zarr store's, for a label table of an image that would not fit
    in memory whole: ``shape`` and ``dtype`` in isoflow's (x, y, z) order,
    ``slabs[x, y, z]`` the region of a slice per axis (one line naming the
    file where a read fails); ``axes``, the order of x, y, z in which it
    is read, along the axis of the most chunks (the stored first axis of
    a contiguous dataset, whose layers lie one after another), and
    ``layers`` its chunks' layers along ``axes[0]``; ``pitch`` and
    ``origin`` (voxel (0, 0, 0)'s lowest corner in world units), ``unit``,
    ``space`` (its anatomical frame, where it records one), ``names`` (its
    labels' names, where it records them) and ``where``.

    Examples
    --------
    >>> import tempfile, h5py
    >>> path = Path(tempfile.mkdtemp()) / "seg.h5"
    >>> with h5py.File(path, "w") as f:
    ...     ds = f.create_dataset("seg", data=np.arange(60, dtype=np.uint16).reshape(3, 4, 5), chunks=(3, 2, 5))
    ...     ds.attrs.update({"axis_names": ["z", "y", "x"], "resolution": [40.0, 4.0, 4.0]})
    >>> slabs = LabelSlabs(path)
    >>> slabs.shape, slabs.axes, slabs.layers, slabs.pitch.tolist()
    ((5, 4, 3), (0, 1, 2), [5], [4.0, 4.0, 40.0])
    >>> slabs[0:2, 0, 0].tolist() == [0, 1]
    True
    """

    fill_value = None  # (HDF5 reads a chunk never written as the dataset's fill value, 0 unless set)

    def __init__(self, path: str | os.PathLike) -> None:
        from ...scale.chunks import layer_axes

        self.path, dataset = split_dataset(path)
        self.where = str(path)
        h5py = import_library("h5py", "HDF5")
        with reading(self.path, "HDF5"), h5py.File(self.path, "r") as f:
            self.found = _opened(f, h5py, self.path, dataset, self.where)
        found = self.found
        if len(found.kept) != 3:
            raise IsoflowError(f"{self.where}: a label table read a slab at a time needs a 3D volume, this dataset "
                               f"is {len(found.kept)}D with shape {found.shape}")
        try:
            place = DigitalObject.placement(3, *found.placement)
        except IsoflowError as exc:
            raise exc.at(self.where) from None
        self.place = dataclasses.replace(place, space=found.space)
        self.pitch, self.origin = place.spacing, place.world(np.zeros((1, 3)))[0]
        self.unit, self.space, self.names = found.unit, found.space, found.names
        self.shape, self.dtype, self.ndim = found.shape, found.dtype, 3
        # a contiguous dataset's layers along its stored first axis in space (after a channel's) lie one after
        # another: one chunk per layer
        sides = found.chunks or tuple(1 if i == min(found.kept) else n for i, n in enumerate(found.stored))
        self.chunks = tuple(int(sides[i]) for i in found.kept)
        self.axes = layer_axes(tuple(-(-n // c) for n, c in zip(self.shape, self.chunks)))
        along, side = self.shape[self.axes[0]], self.chunks[self.axes[0]]
        self.layers = [side] * (along // side) + ([along % side] if along % side else [])

    def __getitem__(self, region: object) -> np.ndarray:
        parts = region if isinstance(region, tuple) else (region,)
        index = list(self.found.index) or [slice(None)] * len(self.found.stored)
        for n, axis in enumerate(self.found.kept):
            index[axis] = parts[n] if n < len(parts) else slice(None)
        h5py = import_library("h5py", "HDF5")
        with reading(self.path, "HDF5"), h5py.File(self.path, "r") as f:
            data = f[self.found.name][tuple(index)]
        kept = [a for a, i in enumerate(index) if not isinstance(i, (int, np.integer))]
        return np.transpose(data, [kept.index(a) for a in self.found.kept if a in kept])

    def reader(self, label: object = None):
        """The volume as ``surface`` reads a store's a block at a time
        (:class:`~isoflow.scale.chunkcache.ChunkReader`: decoded chunks
        kept while they are needed), of the voxels equal to ``label``
        where given (checked as :func:`read` checks it)."""
        from ...scale.chunkcache import ChunkReader

        return ChunkReader(self, label=None if label is None else check_label(label, self.dtype, self.where))

    def absent(self, label: object) -> IsoflowError:
        """The error for a ``label`` no voxel has, listing the values
        present (read in a pass over the dataset), as :func:`read`'s
        refuses it."""
        from ...scale.chunks import import_dask

        _, da = import_dask()
        return no_such_label(label, np.unique(da.unique(self.lazy()).compute()), self.where)

    def lazy(self):
        """The image as a dask array in x, y, z order, a block of whole
        chunks (grown where they would make too many blocks:
        :func:`~isoflow.scale.chunks.zarr_blocks`; of a contiguous dataset,
        a slab of about :data:`~isoflow.scale.chunks.MIN_BLOCK` voxels of
        its layers, one read) read as each is needed."""
        from ...scale.chunks import import_dask, zarr_blocks

        _, da = import_dask()
        if self.found.chunks is None:
            # a block's sides: dask cuts the image into regular blocks of them, the last shorter
            layered = self.found.kept.index(min(self.found.kept))
            blocks = tuple(self._slab_layers(layered) if axis == layered else n for axis, n in enumerate(self.shape))
        else:
            blocks = zarr_blocks(self, None)
        return da.from_array(self, chunks=blocks, asarray=True, name=False)

    def _slab_layers(self, layered: int) -> int:
        """The layers of a contiguous dataset a block takes: about
        :data:`~isoflow.scale.chunks.MIN_BLOCK` voxels (a block of one
        layer is read and summed at a cost of its own, thousands of times
        over), halved while the blocks summed at a time would not fit in
        memory (:func:`~isoflow.digital.outofcore.store_memory`)."""
        from ...digital.outofcore import store_memory
        from ...scale.chunks import MIN_BLOCK
        from ...scale.compiled import thread_count
        from ...scale.memory import default_budget

        along = self.shape[layered]
        rest = [n for axis, n in enumerate(self.shape) if axis != layered]
        side = max(1, min(MIN_BLOCK // max(int(np.prod(rest)), 1), along))
        while side > 1:
            need = store_memory((side, *rest), (-(-along // side), 1, 1), self.dtype)
            if thread_count() * need.block + need.faces + need.kept <= default_budget():
                break
            side //= 2
        return side


def analyze_dataset(path: str | os.PathLike | LabelSlabs, connectivity: int | None = None, label: object = None,
                    progress: Callable[[int, int], object] | None = None, *, surfaces: bool = True,
                    threads: int | None = None) -> Report:
    """``isoflow info``'s report of an HDF5 dataset's 3D volume a block at a
    time (:class:`LabelSlabs`, :func:`isoflow.digital.outofcore.analyze_chunked`),
    for a volume that would not fit in memory whole: the report of the
    same file read whole, placed as :func:`read` places it.

    Parameters
    ----------
    path : str, os.PathLike or LabelSlabs
        ``FILE.h5`` or ``FILE.h5:/DATASET``, or its dataset opened (its
        metadata read, and any warning about it said, once).
    connectivity : int, optional
        6 or 26 (default 6).
    label : number, optional
        The value of the object's voxels in a label image; without it the
        dataset holds 0 and 1 (or 0 and one other value, a mask written
        0/255: that value's voxels).
    progress : callable, optional
        ``progress(done, total)``, as each block is summed and merged.
    surfaces, threads
        As :func:`~isoflow.digital.outofcore.analyze_chunked` takes them.

    Returns
    -------
    Report

    Raises
    ------
    IsoflowError
        A dataset that is not 3D, a label image without ``label``, a
        ``label`` that no voxel has (naming the values present).

    Examples
    --------
    >>> import tempfile, h5py
    >>> v = np.zeros((9, 8, 7), np.uint8); v[1:8, 1:7, 1:6] = 1; v[3:6, 3:5, :] = 0  # a tunnel along z
    >>> path = Path(tempfile.mkdtemp()) / "m.h5"
    >>> with h5py.File(path, "w") as f:
    ...     _ = f.create_dataset("mask", data=v, chunks=(4, 3, 7))
    >>> r = analyze_dataset(path, 6)
    >>> r["betti"], r["voxels"] == int(v.sum())
    ([1, 1, 0], True)
    """
    from ...digital.outofcore import analyze_in_xyz
    from ...scale.arrays import NotBinary
    from .omezarr import one_value_of_store

    slabs = path if isinstance(path, LabelSlabs) else LabelSlabs(path)
    lazy = slabs.lazy()
    options = {"where": slabs.where, "progress": progress, "surfaces": surfaces, "threads": threads,
               "pitch": slabs.pitch, "origin": slabs.origin, "unit": slabs.unit}
    if label is None:
        try:
            report = analyze_in_xyz(lazy, [0, 1, 2], connectivity, **options)
        except NotBinary as refused:
            # a dataset of 0 and one other value is that value's mask, as read reads it
            label = one_value_of_store(slabs, refused)
            if label is None:
                raise
    if label is not None:
        label = check_label(label, slabs.dtype, slabs.where)
        report = analyze_in_xyz(lazy == label, [0, 1, 2], connectivity, **options)
        if report.voxels == 0:
            raise slabs.absent(label)
    return dataclasses.replace(report, parity=slabs.place.parity)


def named_axes(attrs: Mapping, stored: tuple[int, ...], where: str) -> tuple[tuple, list[int]]:
    """How to read a dataset by its axes' names: ilastik's ``axistags``
    (:func:`tagged_axes`), else funlib's ``axis_names``
    (:func:`~isoflow.scale.chunks.axis_names_given`), else as stored
    (:func:`axes_by_name`'s ``index`` and ``kept``).

    Examples
    --------
    >>> named_axes({"axis_names": ["z", "y", "x"]}, (4, 5, 6), "a.h5")[1]
    [2, 1, 0]
    """
    if "axistags" in attrs:
        return tagged_axes(attrs["axistags"], stored, where)
    return axes_by_name(axis_names_given(attrs.get("axis_names"), len(stored)), stored, where, "axis_names")


def tagged_axes(tags: object, shape: tuple[int, ...], where: str) -> tuple[tuple, list[int]]:
    """How to read a dataset whose ``axistags`` attribute (vigra's JSON, as
    ilastik writes its exports, ``exported_data`` of z, y, x, c) names its
    axes: a channel axis ``c`` of one entry (or a time axis ``t``) is
    dropped, as an OME-Zarr image's and a TIFF's are; one of several
    entries is refused, as theirs are, rather than read as a fourth
    spatial or time axis; a time axis of several entries beside three
    other axes becomes the last (isoflow's x, y, z, t), and beside fewer is
    refused. The spatial axes are read in the order the tags name them:
    ilastik's z, y, x as isoflow's x, y, z (axis 0 is x), as a TIFF's and
    an OME-Zarr image's are, so that the voxel sizes, the bounding box and
    a surface are those of the image ilastik and Fiji show, not its mirror
    image with x and z swapped. Axes the tags name otherwise (a key other
    than x, y, z, c and t, a spatial key twice) stay as stored, as does
    every axis of a dataset without such an attribute (or one that does
    not fit the shape).

    Parameters
    ----------
    tags : object
        The attribute as h5py gives it (str or bytes), or None.
    shape : tuple of int
        The dataset's shape.
    where : str
        The dataset, as refusals name it.

    Returns
    -------
    index : tuple
        What to read the dataset by (``()``: the whole as stored).
    kept : list of int
        The stored axes read, in the order isoflow's axes take them (x,
        y, z, then t).

    Examples
    --------
    >>> tags = '{"axes": [{"key": "z"}, {"key": "y"}, {"key": "x"}, {"key": "c"}]}'
    >>> tagged_axes(tags, (8, 7, 6, 1), "a.h5")
    ((slice(None, None, None), slice(None, None, None), slice(None, None, None), 0), [2, 1, 0])
    >>> tagged_axes(None, (8, 7, 6, 1), "a.h5")
    ((), [0, 1, 2, 3])
    """
    import json

    try:
        axes = json.loads(tags.decode() if isinstance(tags, bytes) else str(tags))["axes"]
        keys = [str(a["key"]).lower() for a in axes]
    except (TypeError, ValueError, KeyError, AttributeError, UnicodeDecodeError):
        keys = None
    return axes_by_name(None if tags is None else keys, shape, where, "axistags")


def axes_by_name(keys: list[str] | None, shape: tuple[int, ...], where: str,
                 field: str) -> tuple[tuple, list[int]]:
    """How to read a dataset whose axes ``keys`` names (vigra's
    ``axistags``' keys, funlib's ``axis_names``): as :func:`tagged_axes`
    says, ``field`` the attribute as refusals name it.

    Parameters
    ----------
    keys : list of str or None
        One lower-case name per stored axis (``x``, ``y``, ``z``, ``c``,
        ``t``, or others), or None for none.
    shape : tuple of int
        The dataset's shape.
    where : str
        The dataset, as refusals name it.
    field : str
        The attribute that gave the names.

    Returns
    -------
    index : tuple
        What to read the dataset by (``()``: the whole as stored).
    kept : list of int
        The stored axes read, in isoflow's order.

    Examples
    --------
    >>> axes_by_name(["c", "z", "y", "x"], (1, 8, 7, 6), "a.h5", "axis_names")
    ((0, slice(None, None, None), slice(None, None, None), slice(None, None, None)), [3, 2, 1])
    """
    if keys is None or len(keys) != len(shape):
        return (), list(range(len(shape)))
    stated = f"({field} {''.join(keys) if all(len(k) == 1 for k in keys) else ', '.join(keys)}, " \
             f"shape {tuple(int(n) for n in shape)})"
    for key, n in zip(keys, shape):
        if key == "c" and n > 1:
            raise IsoflowError(f"{where}: axis 'c' has {n} entries {stated}; isoflow reads one volume: save one "
                               "channel")
    kept = [i for i, (key, n) in enumerate(zip(keys, shape)) if key not in ("c", "t") or n > 1]
    times = [i for i in kept if keys[i] == "t"]
    if times and len(kept) != 4:
        raise IsoflowError(f"{where}: axis 't' has {shape[times[0]]} entries {stated}; isoflow reads one "
                           "volume: save one time point (a time series is read as 4D only of 3D volumes)")
    index = tuple(slice(None) if i in kept else 0 for i in range(len(shape)))
    named = [keys[i] for i in kept]
    if set(named) <= set("xyzt") and len(set(named)) == len(named):
        kept = sorted(kept, key=lambda i: "xyzt".index(keys[i]))
    else:  # axes the tags do not name as x, y, z: as stored, a time axis last
        kept = [i for i in kept if i not in times] + times
    return index, kept


def _choose(f, h5py, path, dataset) -> str:
    """The dataset's name: the one given, or the file's only one, or 'volume'."""
    names, dangling = _datasets(f, h5py)
    if dataset is not None:
        if dataset not in f:
            raise IsoflowError(f"{path}: no dataset {dataset!r} (datasets: {_listed(names)})")
        if not isinstance(f[dataset], h5py.Dataset):
            raise IsoflowError(f"{path}: {dataset!r} is a group, not a dataset (datasets: {_listed(names)})")
        return dataset
    if DEFAULT_DATASET in names:
        return DEFAULT_DATASET
    if len(names) == 1:
        return names[0]
    if not names:
        broken = "".join(f"; its external link /{n} names {t}, which cannot be opened" for n, t in dangling[:3])
        raise IsoflowError(f"{path}: holds no dataset{broken}")
    # beside a scalar or a list (a name, a voxel size) one array of 2 to 4
    # axes is the file's volume
    arrays = [n for n in names if 2 <= len(f[n].shape) <= 4]
    if len(arrays) == 1:
        return arrays[0]
    raise IsoflowError(f"{path}: holds datasets {_listed(names)}; name one, e.g. {path}:/{(arrays or names)[0]}")


def _datasets(f, h5py) -> tuple[list[str], list[tuple[str, str]]]:
    """The names of the file's datasets, those an external link names
    (``f["v"] = h5py.ExternalLink("big.h5", "/v")``, as a file that
    gathers others' volumes holds them) too, which HDF5's visit of the
    file's own objects leaves out; and each external link that cannot be
    opened, with the file and path it names."""
    names: list[str] = []
    groups = [("", f)]

    def seen(name, node):
        if isinstance(node, h5py.Dataset):
            names.append(name)
        elif isinstance(node, h5py.Group):
            groups.append((name + "/", node))

    f.visititems(seen)
    dangling = []
    for prefix, group in groups:
        for key in group:
            link = group.get(key, getlink=True)
            if not isinstance(link, h5py.ExternalLink):
                continue
            try:
                node = group.get(key)
            except (KeyError, OSError, ValueError):
                node = None
            if isinstance(node, h5py.Dataset):
                names.append(prefix + key)
            elif node is None:
                dangling.append((prefix + key, f"{link.filename}:{link.path}"))
    return sorted(names), dangling


def _listed(names: list[str]) -> str:
    shown = ", ".join("/" + n for n in names[:10])
    return (shown + f", ... ({len(names)} in all)" if len(names) > 10 else shown) or "none"


def _name(dataset: str | None) -> str:
    return (dataset or DEFAULT_DATASET).strip("/") or DEFAULT_DATASET


def _kept(path: Path, dataset: str | None) -> bool:
    """Whether writing ``path:dataset`` keeps the file's other datasets: a
    dataset is named and the file is there as HDF5 (anything else at the
    path is a file that ``--force`` replaces)."""
    if dataset is None or not path.is_file():
        return False
    h5py = import_library("h5py", "HDF5")
    try:
        return bool(h5py.is_hdf5(path))
    except OSError:  # unreadable: the write itself says why
        return False


def check_output(path: str | Path, force: bool = False, dataset: str | None = None) -> Path:
    """The output ``FILE.h5`` (a new file, or ``force``) or ``FILE.h5:/name``
    (a dataset added to an existing HDF5 file, or replaced with ``force``),
    checked before any work."""
    from ..outputs import check_output_path, check_writable_dir

    path = Path(path)
    if not _kept(path, dataset):
        return check_output_path(path, force)
    h5py = import_library("h5py", "HDF5")
    name = _name(dataset)
    with reading(path, "HDF5"), h5py.File(path, "r") as f:
        node = f.get(name)
        if node is not None and not isinstance(node, h5py.Dataset):
            raise IsoflowError(f"{path}: /{name} is a group of the file, not a dataset; not replaced")
        if node is not None and not force:
            raise IsoflowError.worded(
                f"{path}: holds /{name} already; pass force=True to replace it (the file's other datasets are kept)",
                f"{path}: holds /{name} already; pass --force to replace it (the file's other datasets are kept)")
        parts = name.split("/")
        for i in range(1, len(parts)):  # every group on the way must be a group, not a dataset
            above = "/".join(parts[:i])
            if isinstance(f.get(above), h5py.Dataset):
                raise IsoflowError(f"{path}: /{above} is a dataset, so /{name} cannot be made inside it")
    check_writable_dir(path.parent, f"the HDF5 file {path.name}")
    _check_held(path, name, 0)
    return path


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    """Refuse, before the file is copied, a dataset added to an existing
    file whose copies in memory, with the dataset's, would not fit."""
    if _kept(path, dataset):
        _check_held(path, _name(dataset), DATASET_BYTES * int(np.asarray(obj.volume).size))


def _check_held(path: Path, name: str, extra: int) -> None:
    """Refuse adding ``/name`` to the existing file ``path`` where its
    copies in memory and ``extra`` bytes (the dataset's) exceed the
    budget, naming the way that holds only the dataset: a file of its own,
    copied in by ``h5copy``."""
    from ...scale.memory import check_fits, sized

    size = path.stat().st_size
    check_fits(FILE_COPIES * size + extra, f"{path}: adding /{name} holds this file of {sized(size)} in memory twice",
               hint=f"write /{name} to a file of its own (NEW.h5:/{name}), which holds only the dataset, and copy it "
                    f"in with h5copy -i NEW.h5 -o {path} -s /{name} -d /{name}")


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          into: Path | None = None, unit: str | None = None, space: str | None = None) -> None:
    """Write ``obj`` as the dataset; ``into``: the existing file whose other
    datasets the written file keeps (``path`` is then a copy of it)."""
    h5py = import_library("h5py", "HDF5")
    keep = into is not None and _kept(into, dataset)
    if keep:
        assert into is not None
        shutil.copyfile(into, path)
    name = _name(dataset)
    # built in memory (the core driver, nothing written back) and written out by Python, so that a
    # failing write (a full disk) is one OSError: HDF5's own write fails in several lines and can crash
    with h5py.File(path, "r+" if keep else "w", driver="core", backing_store=False) as f:
        if name in f:
            del f[name]
        ds = f.create_dataset(name, data=stored_values(obj.volume), compression="gzip",
                              chunks=True if obj.volume.size else None)
        ds.attrs["pitch"] = np.asarray(obj.pitch, np.float64)
        ds.attrs["origin"] = obj.origin
        ds.attrs["offset"] = np.array(obj.offset, np.int64)
        ds.attrs["parity"] = np.int64(obj.parity)
        if unit is not None:
            ds.attrs["unit"] = unit
        if space is not None:  # isoflow's own attribute, as unit: no HDF5 convention names a frame
            ds.attrs["space"] = space
        if unit == "\u00b5m":
            ds.attrs["element_size_um"] = obj.spacing
        names = getattr(obj, "names", None)  # a label image's
        if names:
            ds.attrs["label_names"] = names_json(names)
        f.flush()
        image = f.id.get_file_image()
    with open(path, "wb") as fh:
        fh.write(image)
