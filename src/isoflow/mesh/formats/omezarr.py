"""OME-Zarr (NGFF 0.1-0.5) and plain zarr stores (zarr-python).

An OME-Zarr image is a zarr group whose ``multiscales`` metadata lists its
resolution levels; ``IMAGE.zarr`` reads the first (full) level and
``IMAGE.zarr:1`` the level whose path is ``1`` (or the level of that index).
Axes are matched by name: x, y, z go to isoflow's axes 0, 1, 2, whatever
order the file stores them in (NGFF stores z, y, x); a channel axis must
have length 1, and a time axis too unless x, y and z are all there: a time
series of 3D volumes is read as (x, y, z, t), voxel size 1 along t, the 4D
volume ``info`` analyses (in memory, not block by block); ``time`` reads
the chunks of one time point alone, as 3D. The level's ``coordinateTransformations`` (scale, then
translation, then those of the whole image) place voxel *centres*, as napari
and ome-zarr-py take them: the voxel size is the scale and voxel 0's lowest
corner is the translation less half a voxel, in the length unit of the x,
y and z ``axes`` entries (NGFF 0.4 on; :func:`axis_unit`). A zarr store without
``multiscales`` is read as before: the array at the path, or a group's array
named ``volume`` or its only array (``STORE.zarr:NAME`` the array of that
name), axes as its zarr v3 ``dimension_names`` name them where they are x,
y, z in some order (z, y, x as xarray writes them;
:func:`~isoflow.scale.chunks.named_axes`), else as stored (axis 0 is x);
placed by its ``pitch`` and ``origin`` attributes (one entry per stored
axis; each where given), else by the voxel size and offset another tool
wrote (:func:`plain_placement`: gunpowder's ``resolution``, funlib's
``voxel_size``, ...).

``isoflow info`` reads a zarr store block by block (:func:`analyze_store`);
the other commands read the level into memory, refused up front when it
would not fit.

Written as NGFF 0.4 (zarr format 2, which the most viewers read): one level
``0`` of uint8 0/1 in (z, y, x) order, chunks of at most 128 a side, with
the scale and translation that put every voxel where it was, and a length
unit given as each axis's ``unit`` in its UDUNITS name (``micrometer``,
``millimeter``, ...). A label image's names are written as NGFF's
``image-label`` metadata, its ``properties`` a ``{"label-value": v,
"name": ...}`` per label, and read back from there (under ``ome`` in
0.5), of the image read or of a segmentation in its ``labels/`` group.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ...digital.lattice import DigitalObject
from ...digital.report import Report
from ...errors import IsoflowError, check_path, counted, some_of, warn
from ...scale.arrays import NotBinary
from ...scale.chunks import (
    axis_names,
    named_axes,
    never_written,
    open_zarr_node,
    spatial_axes,
    split_store,
    stored_order_said,
    unwritten_fill,
)
from .grid_attributes import attribute_grid
from .registry import (
    HOLD_4D,
    UDUNITS,
    RawVolume,
    axis_units,
    check_label,
    check_shape,
    check_time,
    import_library,
    no_such_label,
    one_line_name,
    one_time_point_labels,
    placement,
    reading,
    space_not_kept,
    split_dataset,
    stored_values,
    to_xyz,
    unit_not_kept,
)

CHUNK = 128
NGFF_VERSION = "0.4"


def placement_of(multiscale: dict, dataset: dict, ndim: int, where: str,
                 xyz: list[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(scale, translation) per stored axis: the level's transformations,
    then the image's; one line naming the level's scale where that of an
    axis of ``xyz`` (the stored indices of x, y and z) is no positive voxel
    size (the file's field, not isoflow's word for it, ``pitch``)."""
    scale, shift = np.ones(ndim), np.zeros(ndim)
    steps = list(dataset.get("coordinateTransformations") or []) + list(
        multiscale.get("coordinateTransformations") or [])
    for t in steps:
        kind = t.get("type") if isinstance(t, dict) else None
        if kind == "identity":
            continue
        values = t.get(kind) if kind in ("scale", "translation") else None
        try:
            values = np.asarray(values, np.float64)
        except (TypeError, ValueError):
            values = None
        if values is None or values.shape != (ndim,) or not np.isfinite(values).all():
            raise IsoflowError(f"{where}: OME-Zarr coordinate transformation {t} is not a scale or "
                               f"translation of {ndim} finite numbers (isoflow does not read "
                               "transformations by path)")
        if kind == "scale":
            scale, shift = scale * values, shift * values
        else:
            shift = shift + values
    for name, i in zip("xyz", xyz or []):
        if not scale[i] > 0:
            raise IsoflowError(f"{where}: OME-Zarr level {dataset.get('path')!r}: the scale of axis {name!r} is "
                               f"{scale[i]:g} (its coordinateTransformations, then the image's), not a positive "
                               "voxel size")
    return scale, shift


def axis_unit(multiscale: dict | None, xyz: list[int], where: str) -> tuple[np.ndarray, str | None]:
    """The length unit of an OME-Zarr image's x, y and z axes (the
    ``unit`` of each of their ``axes`` entries, NGFF 0.4 on: a UDUNITS name
    such as ``micrometer``), and the factor per axis that turns its
    scale and translation into that unit: x's, where they differ (a z in
    ``millimeter`` beside an x in ``micrometer``: times 1000;
    :func:`~isoflow.mesh.formats.registry.axis_units`); None and ones for
    a plain array and for axes without one.

    Examples
    --------
    >>> axes = [{"name": n, "type": "space", "unit": "micrometer"} for n in "zyx"]
    >>> axis_unit({"axes": [{"name": "t", "unit": "second"}] + axes}, [3, 2, 1], "a.zarr")
    (array([1., 1., 1.]), '\u00b5m')
    >>> axes[0]["unit"] = "millimeter"
    >>> axis_unit({"axes": axes}, [2, 1, 0], "a.zarr")
    (array([   1.,    1., 1000.]), '\u00b5m')
    """
    axes = None if multiscale is None else multiscale.get("axes")
    if not isinstance(axes, list):
        return np.ones(min(len(xyz), 3)), None
    units = [axes[i].get("unit") if i < len(axes) and isinstance(axes[i], dict) else None for i in xyz[:3]]
    return axis_units(units, where, "OME-Zarr axis units")


#: what a store too large to read can do instead: the commands that read it block by block (the
#: default hint, to use a .zarr store, told it to be what it is)
STORE_HINT = ("crop it; a .zarr store is read block by block by 'isoflow info' (--labels too), "
              "'isoflow surface --label N -o OUT.ply' (or .stl) and 'isoflow flow --volumes .zarr'")


def read(path: Path, dataset: str | None = None, time: int | None = None) -> RawVolume:
    """The level (or plain array) as a RawVolume; ``time`` picks one time
    point of a 4D volume, and only that time point's chunks are read (a
    time-lapse store is often larger than memory)."""
    import_library("zarr", "OME-Zarr")
    where = str(path) if dataset is None else f"{path}:{dataset}"
    array, multiscale, level = open_zarr_node(path, dataset)
    names = None if multiscale is None else axis_names(multiscale, array.ndim, where)
    # a plain array's x, y, z: by its dimension_names where they name them, else as stored
    plain = (named_axes(array) or list(range(array.ndim))) if multiscale is None else None
    index: tuple = (Ellipsis,)
    shape = tuple(array.shape)
    at = None
    if time is not None:
        xyz = plain if names is None else spatial_axes(names, array.shape, where, time=True)[0]
        time = check_time(time, [array.shape[i] for i in xyz], where)
        # the time axis kept, of length 1, so that the axes stay as stored
        index = tuple(slice(int(time), int(time) + 1) if i == xyz[3] else slice(None) for i in range(array.ndim))
        shape = tuple(1 if i == xyz[3] else n for i, n in enumerate(shape))
        at = {xyz[3]: int(time)}
    # a time series is read whole by every command: only cropping helps
    check_shape(shape, array.dtype, where, hint=STORE_HINT if sum(n > 1 for n in shape) <= 3 else "crop it")
    with reading(where, "zarr"):
        data = np.asarray(array[index])
    # the label is chosen later (as_object): counted for any nonzero fill
    # value, over the chunks read (those of the time point)
    fill = getattr(array, "fill_value", None)
    blank = unwritten_fill(array, at=at)
    if multiscale is None:
        stored_order_said(array, where)
        data = data if time is None else data[..., 0]
        data = np.transpose(data, plain) if data.ndim == len(plain) else data
        pitch, origin, unit = plain_placement(array, plain, where)
        pitch, origin = (v if time is None or np.ndim(v) != 1 else v[:3] for v in (pitch, origin))
        return RawVolume(data, 1.0 if pitch is None else pitch, origin, fill=fill, unwritten=blank, unit=unit)
    xyz, _ = spatial_axes(names, data.shape, where, time=True)
    scale, shift = placement_of(multiscale, level, data.ndim, where, xyz)
    factors, unit = axis_unit(multiscale, xyz, where)
    pitch, origin = scale[xyz[:3]] * factors, (shift[xyz[:3]] - scale[xyz[:3]] / 2) * factors
    if len(xyz) == 4:  # time keeps step 1 from 0, as a 4D NIfTI's does: a lattice axis, not seconds
        pitch, origin = np.append(pitch, 1.0), np.append(origin, 0.0)
    return RawVolume(to_xyz(data, names, where), pitch, origin, fill=fill, unwritten=blank,
                     unit=unit, names=label_properties(array, where))


def label_properties(array, where: str | None = None) -> dict[int, str] | None:
    """The names of an OME-Zarr label image's labels: the ``name`` of each
    entry of its ``image-label`` ``properties`` (NGFF 0.4; under ``ome``
    in 0.5) with a whole ``label-value`` (``2`` or ``2.0``), from the group
    that holds the level ``array``, a line break in it escaped
    (:func:`~isoflow.mesh.formats.registry.one_line_name`); None where it
    names none.

    A name that is a JSON number (``"name": 7``) is kept as its text
    (``'7'``), as the name a viewer shows; an entry without a ``name`` (or
    with ``null``) leaves its label unnamed, and one for label 0, the
    background, is left out. An entry whose ``name`` is anything else
    (true, a list, an object), or whose ``label-value`` is no whole number
    (``"3"``, ``2.5``, missing), is left out with one
    :class:`~isoflow.errors.IsoflowWarning` naming each such entry and what
    it holds, rather than dropped without a word.

    Parameters
    ----------
    array : zarr.Array
        A level of the image, as :func:`~isoflow.scale.chunks.open_zarr_node` opens it.
    where : str, optional
        The image as the warning names it; the store's path by default.

    Returns
    -------
    dict of int to str, or None
        Label value to name.

    Examples
    --------
    >>> import tempfile, zarr
    >>> g = zarr.open_group(tempfile.mkdtemp() + "/l.zarr", mode="w")
    >>> level = g.create_array("0", shape=(2, 2, 2), dtype="u1")
    >>> g.attrs["image-label"] = {"properties": [{"label-value": 2, "name": "tumour"}, {"label-value": 1}]}
    >>> label_properties(level)
    {2: 'tumour'}
    >>> g.attrs["image-label"] = {"properties": [{"label-value": 1, "name": 7}, {"label-value": 2.0, "name": "spleen"}]}
    >>> label_properties(level)
    {1: '7', 2: 'spleen'}
    """
    zarr = import_library("zarr", "OME-Zarr")
    try:
        group = zarr.open_group(store=array.store, path=array.path.rpartition("/")[0], mode="r")
        attrs = dict(group.attrs)
    except Exception:  # (a store zarr opens no group of: the image reads without names)
        return None
    ome = attrs.get("ome")
    label = attrs.get("image-label") or (ome.get("image-label") if isinstance(ome, dict) else None)
    properties = label.get("properties") if isinstance(label, dict) else None
    found = {}
    skipped = []
    for n, entry in enumerate(properties if isinstance(properties, list) else [], 1):
        if not isinstance(entry, dict):
            skipped.append(f"entry {n} is {_json_text(entry)}, not an object")
            continue
        value, name = entry.get("label-value"), entry.get("name")
        if name is None:  # a label described (colour, class) but not named
            continue
        number = _number(value)
        # an integer as it is (a float would round labels past 2**53), a whole float as its integer
        label = (value if isinstance(value, int) and not isinstance(value, bool)
                 else int(number) if number is not None and number.is_integer() else None)
        if label == 0:  # the background, which no table row or file names
            continue
        if label is None:
            skipped.append(f"entry {n} (name {_json_text(name)}) has label-value {_json_text(value)}, not a whole "
                           "number")
        elif isinstance(name, str):
            found[label] = one_line_name(name)  # one line, as a table's row and write_labels take it
        elif _number(name) is not None:  # "name": 7, as a viewer shows it
            found[label] = json.dumps(name)
        else:
            skipped.append(f"label {label}'s name is {_json_text(name)}, not text")
    if skipped:
        shown = some_of(skipped, sep="; ")
        entries = counted(len(skipped), "image-label properties entry", "image-label properties entries")
        warn(f"{where or array.store}: {entries} not read as a label name: {shown}")
    return dict(sorted(found.items())) or None


def _number(value: object) -> float | None:
    """A JSON number as a float (not true or false), else None."""
    if isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value):
        return float(value)
    return None


def _json_text(value: object, width: int = 40) -> str:
    """A metadata value as a warning quotes it: its JSON, cut short."""
    text = json.dumps(value, ensure_ascii=False, default=str)
    return text if len(text) <= width else text[:width - 3] + "..."


@dataclasses.dataclass(frozen=True)
class StoreArray:
    """A zarr store's volume array as :func:`open_store` opens it: the
    array, the store as messages name it, the OME-Zarr ``multiscales`` entry
    and level (None for a plain array), and the indices of its x, y and z
    axes (a plain array's by its ``dimension_names`` where they name x, y
    and z, :func:`~isoflow.scale.chunks.named_axes`; else every axis, in
    stored order) and of its other axes (each of length 1).

    Examples
    --------
    >>> import tempfile, zarr
    >>> path = tempfile.mkdtemp() + "/v.zarr"
    >>> z = zarr.create_array(path, shape=(2, 3, 4), dtype="u1")
    >>> z.attrs.update(pitch=[0.5, 0.5, 2.0], origin=[0, 0, 1])
    >>> store = open_store(path)
    >>> store.xyz, [v.tolist() for v in store.placement()]
    ([0, 1, 2], [[0.5, 0.5, 2.0], [0.0, 0.0, 1.0]])
    """

    array: Any
    where: str
    multiscale: dict | None
    dataset: dict | None
    xyz: list[int]
    other: list[int]

    def guarded(self) -> Guarded:
        """The array read through :class:`Guarded` (a damaged chunk is one
        line naming the store)."""
        return Guarded(self.array, self.where)

    def lazy(self):
        """The array as a dask array along its chunks, read through
        :meth:`guarded`, without its other axes (stored order)."""
        from ...scale.chunks import import_dask

        _, da = import_dask()
        lazy = da.from_array(self.guarded(), chunks=self.array.chunks, asarray=True)
        return lazy[tuple(0 if i in self.other else slice(None) for i in range(self.array.ndim))]

    def placement(self) -> tuple[np.ndarray | None, np.ndarray | None]:
        """``(pitch, origin)`` in x, y, z order: the OME-Zarr level's scale
        and translation (voxel centres, so the origin is half a voxel
        lower), a plain array's by its attributes (:func:`plain_placement`;
        each None where they give none)."""
        if self.multiscale is None:
            return self.plain[0], self.plain[1]
        scale, shift = placement_of(self.multiscale, self.dataset, self.array.ndim, self.where, self.xyz)
        factors = self.units[0]
        if len(self.xyz) == 4:  # (a time axis: its step as it is)
            factors = np.append(factors, 1.0)
        return scale[self.xyz] * factors, (shift[self.xyz] - scale[self.xyz] / 2) * factors

    @functools.cached_property
    def plain(self) -> tuple[Any, Any, str | None]:
        """A plain array's :func:`plain_placement` (read, and any warning
        given, once)."""
        return plain_placement(self.array, self.xyz, self.where)

    def unit(self) -> str | None:
        """The length unit of the placement (:func:`axis_unit`)."""
        return self.units[1]

    @functools.cached_property
    def units(self) -> tuple[np.ndarray, str | None]:
        """:func:`axis_unit` of the store's axes (a plain array's unit: that
        of :func:`plain_placement`), read (and any warning given) once."""
        if self.multiscale is None:
            return np.ones(min(len(self.xyz), 3)), self.plain[2]
        return axis_unit(self.multiscale, self.xyz, self.where)


def stored_axes_value(value: Any, xyz: list[int], ndim: int | None = None) -> Any:
    """A plain zarr array's attribute of one entry per stored axis
    (``pitch``, ``origin``) in isoflow's order: the entries of the axes
    ``xyz`` (the stored indices of x, y and z, see :class:`StoreArray`); one
    number for every axis, or another count of entries (``ndim``, the
    stored axes, by default ``len(xyz)``), as it is (checked where used).

    Examples
    --------
    >>> stored_axes_value([2.0, 1.0, 0.5], [2, 1, 0]), stored_axes_value(0.5, [2, 1, 0])
    ([0.5, 1.0, 2.0], 0.5)
    >>> stored_axes_value(np.array([2.0, 1.0, 0.5, 1.0]), [0, 1, 2], 4)
    array([2. , 1. , 0.5])
    """
    if np.ndim(value) != 1 or len(value) != (len(xyz) if ndim is None else ndim):
        return value
    return value[xyz] if isinstance(value, np.ndarray) else [value[i] for i in xyz]


def plain_placement(array: Any, xyz: list[int], where: str) -> tuple[Any, Any, str | None]:
    """A plain zarr array's ``pitch`` and ``origin`` in isoflow's order
    (each None where its attributes give none) and their length unit:
    isoflow's attributes ``pitch`` and ``origin`` (each an entry per stored
    axis, or one number), else the voxel size and offset another tool
    wrote (:func:`~isoflow.mesh.formats.grid_attributes.attribute_grid`:
    gunpowder's and daisy's ``resolution``, funlib's ``voxel_size``, ...).

    Parameters
    ----------
    array : zarr.Array
        The plain array (no ``multiscales`` above it).
    xyz : list of int
        The stored axes read, in isoflow's order (:class:`StoreArray`).
    where : str
        The store, as refusals name it.

    Returns
    -------
    tuple
        ``(pitch, origin, unit)``.

    Examples
    --------
    >>> import zarr
    >>> z = zarr.create_array({}, shape=(4, 5, 6), dtype="u1")
    >>> z.attrs.update(resolution=[40, 4, 4], offset=[80, 0, 0])
    >>> pitch, origin, unit = plain_placement(z, [0, 1, 2], "a.zarr")
    >>> pitch.tolist(), origin.tolist(), unit
    ([40.0, 4.0, 4.0], [80.0, 0.0, 0.0], None)
    """
    attrs = dict(getattr(array, "attrs", {}) or {})
    grid = attribute_grid(attrs, tuple(array.shape), xyz, where)
    try:
        if grid is not None:
            origin = grid.origin if grid.origin is not None or "origin" not in attrs else \
                stored_axes_value(np.asarray(attrs["origin"], np.float64), xyz, array.ndim)
            return grid.pitch, origin, grid.unit
        pitch, origin = (stored_axes_value(np.asarray(attrs[k], np.float64), xyz, array.ndim) if k in attrs else None
                         for k in ("pitch", "origin"))
    except (TypeError, ValueError):
        raise IsoflowError(f"{where}: the attributes pitch {attrs.get('pitch')!r} and origin "
                           f"{attrs.get('origin')!r} are not numbers") from None
    return pitch, origin, None


def open_store(path: str | os.PathLike, time: bool = False, channel: bool = False) -> StoreArray:
    """A zarr store's volume array with its axes matched by name, not
    read: what the block-by-block readers share.

    Parameters
    ----------
    path : str or os.PathLike
        The store; ``:LEVEL`` after it picks a resolution level of an
        OME-Zarr image (its path or index), ``:NAME`` an array of a group.
    time : bool
        An OME-Zarr time axis of several entries beside x, y and z is kept
        as a fourth entry of ``xyz``, as :func:`read` reads it (see
        :func:`~isoflow.scale.chunks.spatial_axes`); by default it is
        refused.
    channel : bool
        A plain array of shape (X, Y, Z, 1) is a 3D label image saved with
        a channel axis of one entry: its x, y, z axes are the first three,
        the last indexed at 0, as :func:`isoflow.read_labels` reads such a
        file (and ``read_volume`` with a ``label``). By default it is 4D.

    Returns
    -------
    StoreArray
        The array, its placement and its x, y, z and other axes.

    Raises
    ------
    IsoflowError
        Not a zarr store, no such level, or axes that
        :func:`~isoflow.scale.chunks.spatial_axes` refuses.

    Examples
    --------
    >>> import tempfile, zarr
    >>> d = Path(tempfile.mkdtemp()) / "image.zarr"
    >>> g = zarr.open_group(str(d), mode="w")
    >>> _ = g.create_array("0", shape=(1, 4, 5, 6), chunks=(1, 2, 5, 6), dtype="u1")
    >>> g.attrs["multiscales"] = [{"axes": ["c", "z", "y", "x"], "datasets": [{"path": "0"}]}]
    >>> store = open_store(f"{d}:0")
    >>> store.xyz, store.other, store.lazy().shape, store.lazy().chunks
    ([3, 2, 1], [0], (4, 5, 6), ((2, 2), (5,), (6,)))
    >>> _ = g.create_array("t", shape=(3, 4, 5, 6), dtype="u1")
    >>> g.attrs["multiscales"] = [{"axes": ["t", "z", "y", "x"], "datasets": [{"path": "t"}]}]
    >>> open_store(f"{d}:t", time=True).xyz
    [3, 2, 1, 0]
    >>> _ = zarr.open_array(str(d.parent / "x1.zarr"), mode="w", shape=(4, 5, 6, 1), dtype="u1")
    >>> open_store(d.parent / "x1.zarr").xyz, open_store(d.parent / "x1.zarr", channel=True).xyz
    ([0, 1, 2, 3], [0, 1, 2])
    """
    file, level = split_dataset(path)
    where = str(path)
    array, multiscale, dataset = open_zarr_node(file, level)
    if multiscale is None:
        named = named_axes(array)  # x, y, z by the array's dimension_names, where they name them
        if named is not None:
            return StoreArray(array, where, None, None, named, [])
        stored_order_said(array, where)
        if channel and array.ndim == 4 and array.shape[3] == 1:
            return StoreArray(array, where, None, None, [0, 1, 2], [3])
        return StoreArray(array, where, None, None, list(range(array.ndim)), [])
    xyz, other = spatial_axes(axis_names(multiscale, array.ndim, where), array.shape, where, time=time)
    return StoreArray(array, where, multiscale, dataset, xyz, other)


def stored_ndim(path, channel: bool = False) -> int:
    """The dimension of a zarr store's volume (``IMAGE.zarr:LEVEL`` too):
    its x, y and z axes in an OME-Zarr image (and a time axis of several
    entries beside them: 4), every axis of a plain array (``channel``: but
    a last axis of one entry, see :func:`open_store`)."""
    return len(stored_shape(path, channel))


def stored_shape(path: str | os.PathLike, channel: bool = False) -> tuple[int, ...]:
    """The shape of a zarr store's volume as :func:`read` gives it, from
    the metadata alone (the volume is not read).

    Parameters
    ----------
    path : str or os.PathLike
        ``STORE.zarr`` or ``IMAGE.zarr:LEVEL``.
    channel : bool
        A plain array's last axis of one entry is no axis of the volume
        (a label image's channel, :func:`open_store`).

    Returns
    -------
    tuple of int
        (x, y, z) in an OME-Zarr image, (x, y, z, t) for a time series of
        3D volumes; in a plain array (x, y, z) where its dimension_names
        name them, else every axis as stored.

    Examples
    --------
    >>> import tempfile, numpy as np, zarr
    >>> path = Path(tempfile.mkdtemp()) / "plain.zarr"
    >>> _ = zarr.open_array(str(path), mode="w", shape=(5, 4, 3, 2), dtype="u1")
    >>> stored_shape(path)
    (5, 4, 3, 2)
    """
    import_library("zarr", "OME-Zarr")
    store = open_store(path, time=True, channel=channel)
    return tuple(int(store.array.shape[i]) for i in store.xyz)


def store_place(store: StoreArray, path: str | os.PathLike) -> dict[str, Any]:
    """The ``pitch``, ``origin`` and ``unit`` that place the store's volume
    as :func:`read` places it (None for a plain array without them),
    checked up front and named as ``info`` names the placement it prints."""
    pitch, origin = store.placement()
    if pitch is None and origin is None:
        return {"pitch": None, "origin": None, "unit": store.unit()}
    try:
        at = DigitalObject.placement(len(store.xyz), pitch=pitch, origin=origin)
    except IsoflowError as exc:
        raise exc.at(path) from None
    return {"pitch": at.spacing, "origin": at.origin, "unit": store.unit()}


def analyze_zarr(path: str | os.PathLike, connectivity: int | np.integer | None = None, *,
                 block_shape: tuple[int | np.integer, ...] | None = None, scheduler: Callable | None = None,
                 surfaces: bool = True, threads: int | np.integer | None = None,
                 progress: Callable[[int, int], object] | None = None, pitch: float | ArrayLike | None = None,
                 origin: ArrayLike | None = None, unit: str | None = None) -> Report:
    """The report of a zarr store's volume, read block by block and placed
    where the store says it is: what ``isoflow info STORE --json`` prints.

    Parameters
    ----------
    path : str or os.PathLike
        A zarr array, a group with an array named ``volume`` or only one
        array, or an OME-Zarr image (its first level, or
        ``IMAGE.zarr:LEVEL`` by the level's path or index).
    connectivity, block_shape, scheduler, surfaces, threads, progress
        As in :func:`isoflow.analyze_chunked`.
    pitch, origin, unit : optional
        The voxel size, the world position of voxel 0's lowest corner and
        their length unit, in (x, y, z) order; each given replaces the
        store's own, which :func:`isoflow.read_volume` reads too (an
        OME-Zarr level's scale, translation and axis unit; the ``pitch``
        and ``origin`` attributes of a plain array; else unit voxels at 0).

    Returns
    -------
    Report
        As :func:`isoflow.analyze` gives it for the volume that
        :func:`isoflow.read_volume` reads, ``shape``, ``bbox`` and
        ``centroid`` in (x, y, z) order (an OME-Zarr image stores z, y, x).

    Raises
    ------
    IsoflowError
        A path that is no zarr store, a placement that is no voxel size or
        position, or the errors of
        :func:`isoflow.digital.outofcore.analyze_zarr_volume`, with the path.

    Examples
    --------
    A store of 0.5 mm voxels, as :func:`isoflow.write_volume` writes it:

    >>> import tempfile
    >>> import numpy as np
    >>> import isoflow
    >>> obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5, unit="mm")
    >>> with tempfile.TemporaryDirectory() as d:
    ...     _ = isoflow.write_volume(obj, d + "/cube.zarr")
    ...     report = isoflow.analyze_zarr(d + "/cube.zarr")
    >>> report.volume, report.surface_area, report.unit
    (1.0, 6.0, 'mm')
    """
    path = check_path(path, "path", "analyze_zarr", "an array in memory: analyze(array), or a dask array: analyze_chunked(array)")
    from ...digital.outofcore import analyze_zarr_volume
    from ..volumes import refuse_inside_store

    file = split_store(path)[0]
    if not file.name.lower().endswith(".zarr"):
        # a level or array by its folder (IMG.zarr/0) opens without the image's scale and unit, which
        # would give its measures in voxels; read_volume and info refuse it too, naming IMG.zarr:0
        refuse_inside_store(file, path)
    import_library("zarr", "OME-Zarr")
    store = open_store(path)
    own = store_place(store, path)
    given = {"pitch": pitch, "origin": origin, "unit": unit}
    place = {k: own[k] if v is None else v for k, v in given.items()}
    options = {"block_shape": block_shape, "scheduler": scheduler, "surfaces": surfaces, "threads": threads,
               "progress": progress}
    try:
        return analyze_zarr_volume(path, connectivity, **options, **place)  # type: ignore[arg-type]
    except NotBinary as refused:
        # a store of 0 and one other value is that value's mask, as read_volume reads it
        value = one_value_of_store(store, refused)
        if value is None:
            raise
    return analyze_value(store, value, connectivity, place, **options)


def one_value_of_store(store: StoreArray, refused: NotBinary) -> object | None:
    """The value ``v`` of a store whose only value other than 0 is one
    ``v`` other than 1 (a mask written 0/255), found from the block a
    reader refused and a pass over the store (:func:`only_values`); None
    where it holds another value too (a label image).

    :func:`isoflow.read_volume` reads such an array as the mask of ``v``
    (:func:`~isoflow.mesh.volumes.one_value_mask`), and so do the readers
    of a store block by block, which call this once a block holds a value
    other than 0 and 1: the blocks alone cannot tell a mask written 0/255
    from a label image whose other labels lie in blocks not read yet.

    Parameters
    ----------
    store : StoreArray
        The store, as :func:`open_store` opens it (or an HDF5 dataset's
        :class:`~isoflow.mesh.formats.hdf5.LabelSlabs`: what is read is
        its ``lazy()`` array).
    refused : NotBinary
        The refusal of the block read: where that block holds more than one
        value other than 0 (its ``value`` is None) the store is no mask and
        is not read again; where it holds one, only that value is looked
        for.

    Returns
    -------
    number or None
        ``v``, a NumPy scalar of the array's type, or None.

    Examples
    --------
    >>> import tempfile, zarr
    >>> path = Path(tempfile.mkdtemp()) / "m.zarr"
    >>> z = zarr.create_array(str(path), shape=(4, 4, 4), chunks=(2, 2, 2), dtype="u1")
    >>> z[1:3, 1:3, 1:3] = 255
    >>> one_value_of_store(open_store(path), NotBinary("m.zarr: not a binary volume", value=255))
    np.uint8(255)
    >>> z[0, 0, 0] = 7
    >>> one_value_of_store(open_store(path), NotBinary("m.zarr: not a binary volume", value=255)) is None
    True
    """
    if refused.value is None:  # (the block read holds several labels: no store read)
        return None
    lazy = store.lazy()
    if lazy.dtype.kind not in "iuf" or not lazy.size:
        return None
    value = np.asarray(refused.value, lazy.dtype)[()]
    if value == 1 or value == 0 or not np.isfinite(value):
        return None
    return value if only_values(lazy, value) else None


#: blocks of a store checked at once by :func:`only_values` before it
#: decides whether to read on
CHECKED_BLOCKS = 64


def only_values(lazy, value) -> bool:
    """Whether every voxel of the dask array ``lazy`` is 0 or ``value``,
    read a slab of blocks at a time (about :data:`CHECKED_BLOCKS`), and no
    further than the first slab holding another value: a label image whose
    blocks each hold one label shows a second label within a few blocks,
    where one reduction over the store would read all of it.

    Examples
    --------
    >>> import dask.array as da
    >>> mask = np.zeros((6, 4, 4), np.uint8)
    >>> mask[1:5, 1:3, 1:3] = 255
    >>> only_values(da.from_array(mask, chunks=2), 255), only_values(da.from_array(mask * 0 + 7, chunks=2), 255)
    (True, False)
    """
    per_block = ((lazy == 0) | (lazy == value)).map_blocks(
        lambda block: np.array(block.all()).reshape((1,) * block.ndim), chunks=(1,) * lazy.ndim, dtype=bool)
    across = max(1, int(np.prod(per_block.shape[1:])))
    step = max(1, CHECKED_BLOCKS // across)
    return all(bool(per_block[at:at + step].all().compute()) for at in range(0, per_block.shape[0], step))


def analyze_value(store: StoreArray, value, connectivity: int | None, place: dict, **options: Any) -> Report:
    """The report of the voxels of ``store`` equal to ``value`` (a label,
    or the one value of a mask written 0/255), block by block, placed by
    ``place`` (:func:`store_place`); ``options`` as
    :func:`~isoflow.digital.outofcore.analyze_in_xyz` takes them.

    Examples
    --------
    Label 5 of two, a ring around label 3:

    >>> import tempfile, zarr
    >>> labels = np.full((5, 5, 1), 5, np.uint16)
    >>> labels[2, 2, 0] = 3
    >>> folder = Path(tempfile.mkdtemp())
    >>> zarr.create_array(str(folder / "l.zarr"), data=labels, chunks=(3, 3, 1))[...].max()
    np.uint16(5)
    >>> store = open_store(folder / "l.zarr")
    >>> analyze_value(store, 5, 6, store_place(store, folder))["betti"]
    [1, 1, 0]
    """
    from ...digital.outofcore import analyze_in_xyz

    # the lazy array drops the other axes: the x, y, z ones, in stored order, are left
    order = [int(i) for i in np.argsort(np.argsort(store.xyz))]
    return analyze_in_xyz(store.lazy() == value, order, connectivity, where=store.where, **options, **place)


def analyze_store(path, connectivity: int | None = None, label=None, progress=None, *,
                  surfaces: bool = True, threads: int | None = None) -> dict:
    """``isoflow info``'s report of a zarr store (``IMAGE.zarr:LEVEL`` too),
    block by block (:func:`isoflow.digital.outofcore.analyze_chunked`), with
    ``shape`` in isoflow's (x, y, z) order. ``label`` selects one value;
    ``progress(done, total)`` is called as each block is summed and merged;
    ``surfaces`` and ``threads`` as in :func:`~isoflow.digital.outofcore.analyze_chunked`.
    A ``label`` that no voxel has is refused, as :func:`isoflow.read_volume`
    refuses it (the values present are then read in a second pass). The
    world measures are placed as :func:`read` places the volume."""
    from ...digital.outofcore import analyze_zarr_volume

    import_library("zarr", "OME-Zarr")
    store = open_store(path, channel=label is not None)  # a label image: (X, Y, Z, 1) is 3D
    place = store_place(store, path)
    if label is None:
        try:
            return analyze_zarr_volume(path, connectivity, progress=progress, surfaces=surfaces, threads=threads,
                                       **place)
        except NotBinary as refused:
            # a store of 0 and one other value is that value's mask, as read_volume reads it
            label = one_value_of_store(store, refused)
            if label is None:
                raise
    label = check_label(label, store.array.dtype, store.where)
    report = analyze_value(store, label, connectivity, place, progress=progress, surfaces=surfaces, threads=threads)
    if report["voxels"] == 0:
        raise label_absent(path, label)
    never_written(store.where, unwritten_fill(store.array, label), label)
    return report


def label_absent(path, label) -> IsoflowError:
    """The error for a ``label`` that no voxel of the store ``path`` has,
    listing the values present (read in a pass over the store, once the
    label's object came out empty), as :func:`isoflow.read_volume` refuses
    it in memory."""
    from ...scale.chunks import import_dask

    _, da = import_dask()
    store = open_store(path, channel=True)
    return no_such_label(label, np.unique(da.unique(store.lazy()).compute()), store.where, len(store.xyz))


def store_volume(path, label=None) -> tuple:
    """A zarr store's 3D volume without reading it: ``(reader, pitch,
    origin)``, the reader giving blocks in isoflow's (x, y, z) order
    (:class:`isoflow.scale.chunkcache.ChunkReader`), of ``label``'s voxels
    when given, placed as :func:`read` places them.

    Parameters
    ----------
    path : str or os.PathLike
        ``STORE.zarr`` or ``IMAGE.zarr:LEVEL``.
    label : number, optional
        The value of the object's voxels in a label image.

    Returns
    -------
    tuple
        ``(reader, pitch, origin)``; ``pitch`` and ``origin`` None for a
        plain array without them.

    Raises
    ------
    IsoflowError
        A store that is not a 3D volume, a bad label or placement.
    """
    from ...scale.chunkcache import ChunkReader

    import_library("zarr", "OME-Zarr")
    store = open_store(path, channel=label is not None)  # a label image: (X, Y, Z, 1) is 3D
    if len(store.xyz) != 3:
        raise IsoflowError(f"{store.where}: surface needs a 3D volume, this store holds {len(store.xyz)}D")
    pitch, origin = store.placement()
    if label is not None:
        label = check_label(label, store.array.dtype, store.where)
    return ChunkReader(store.guarded(), store.xyz, store.other, label), pitch, origin


class Guarded:
    """A zarr array whose reads raise one IsoflowError line naming the
    store and the region read (a damaged chunk), for
    ``dask.array.from_array``.

    Parameters
    ----------
    array : zarr.Array
        The stored array, read as it is (``shape``, ``dtype``, ``chunks``,
        ``shards`` and ``fill_value`` are its own).
    where : str
        The store as the error names it (``IMAGE.zarr:LEVEL``).

    Examples
    --------
    >>> import tempfile, zarr
    >>> path = Path(tempfile.mkdtemp()) / "v.zarr"
    >>> z = zarr.create_array(str(path), shape=(4, 4), chunks=(2, 4), dtype="u1")
    >>> z[...] = 1
    >>> _ = (path / "c" / "1" / "0").write_bytes(b"not a chunk")
    >>> int(Guarded(z, "v.zarr")[:2].sum())
    8
    >>> try:
    ...     Guarded(z, "v.zarr")[2:4, 0:4]
    ... except IsoflowError as error:
    ...     print(str(error).split(" (")[0])
    v.zarr: cannot read a chunk in [2:4, 0:4]
    """

    def __init__(self, array, where: str) -> None:
        self.array, self.where = array, where
        self.shape, self.dtype, self.ndim = array.shape, array.dtype, array.ndim
        self.chunks, self.shards = array.chunks, getattr(array, "shards", None)
        self.fill_value = getattr(array, "fill_value", None)

    def __getitem__(self, key) -> np.ndarray:
        try:
            return np.asarray(self.array[key])
        except Exception as exc:  # zarr and its codecs raise many types
            raise IsoflowError(f"{self.where}: cannot read a chunk in {_index_text(key)} "
                               f"({exc.__class__.__name__}: {exc})") from None


def _index_text(key) -> str:
    """A read's index as the stored array's voxel ranges, ``[0:6, :, :]``
    (not Python's ``(slice(0, 6, None), ...)``)."""
    def one(k) -> str:
        if not isinstance(k, slice):
            return str(k)
        return f"{'' if k.start is None else k.start}:{'' if k.stop is None else k.stop}"

    return "[" + ", ".join(one(k) for k in (key if isinstance(key, tuple) else (key,))) + "]"


def check_output(path, force: bool = False, dataset: str | None = None) -> Path:
    """An output zarr store (a directory), checked before any work: refused
    when it exists, unless ``force`` and it is a zarr store (which
    :func:`write` replaces)."""
    from ..outputs import check_writable_dir, refuse_unusable_output, remove_abandoned

    path = Path(path)
    remove_abandoned(path)  # a store a killed command left aside is put back: then it exists, as it did
    refuse_unusable_output(path)  # --force would unlink a device or pipe and put a store in its place
    if not path.parent.exists():  # a file in its place is named as one by check_writable_dir
        raise IsoflowError(f"{path.parent}: no such directory (for the output {path.name})")
    check_writable_dir(path.parent, f"the zarr store {path.name}")
    if path.exists() or path.is_symlink():
        if not force:
            raise IsoflowError.worded(f"{path}: exists; pass force=True to overwrite",
                                      f"{path}: exists; pass --force to overwrite")
        is_store = any((path / m).exists() for m in (".zgroup", ".zarray", "zarr.json"))
        if path.is_dir() and not path.is_symlink() and not is_store:
            raise IsoflowError(f"{path}: a directory that is not a zarr store; not replaced")
    return path


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    if dataset is not None:
        raise IsoflowError(f"{path}:{dataset}: a level is named to read an OME-Zarr image; write to {path}")
    if obj.ndim not in (2, 3):
        raise IsoflowError(f"{path}: OME-Zarr images here are 2D or 3D, this object is {obj.ndim}D; {HOLD_4D}")
    if unit is not None and unit not in UDUNITS:
        unit_not_kept(path, "OME-Zarr", unit, "the UDUNITS length units of NGFF only")
    space_not_kept(path, "OME-Zarr", space)


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    zarr = import_library("zarr", "OME-Zarr")
    spacing, corner = placement(obj)
    data = stored_values(np.ascontiguousarray(obj.volume.T))  # (x, y, z) -> (z, y, x)
    if path.is_dir() and not path.is_symlink():  # checked by check_output: an old store, --force given
        shutil.rmtree(path)
    elif path.exists() or path.is_symlink():
        path.unlink()
    root = zarr.open_group(str(path), mode="w", zarr_format=2)
    root.create_array("0", data=data, chunks=tuple(max(1, min(s, CHUNK)) for s in data.shape))
    root.attrs["multiscales"] = multiscales(name or path.name, spacing, corner, unit=unit)
    names = getattr(obj, "names", None)  # a label image's
    if names:
        root.attrs["image-label"] = {"version": NGFF_VERSION,
                                     "properties": [{"label-value": v, "name": n} for v, n in names.items()]}


def multiscales(name: str, spacing, corner, stored: str = "zyx", unit: str | None = None) -> list[dict]:
    """NGFF 0.4 ``multiscales`` of one level ``0`` for a grid of voxel size
    ``spacing`` whose voxel 0 has its lowest corner at ``corner`` (both in
    isoflow's x, y, z order): the scale and the translation of voxel 0's
    centre, as NGFF places voxels, listed in the ``stored`` order of the
    axes (``"zyx"``, NGFF's usual order, ``"yx"`` in 2D, or ``"xyz"``: the
    spec asks that axes be named and space last, and only recommends z, y,
    x); ``unit`` (isoflow's spelling) as each axis's UDUNITS ``unit`` where
    NGFF has a name for it."""
    spacing, corner = np.asarray(spacing, np.float64), np.asarray(corner, np.float64)
    centre = corner + spacing / 2
    stored = stored[-len(spacing):] if stored == "zyx" else stored
    order = ["xyz".index(a) for a in stored]
    return [{
        "version": NGFF_VERSION,
        "name": name,
        "axes": [{"name": a, "type": "space", **({"unit": UDUNITS[unit]} if unit in UDUNITS else {})} for a in stored],
        "datasets": [{"path": "0", "coordinateTransformations": [
            {"type": "scale", "scale": spacing[order].tolist()},
            {"type": "translation", "translation": centre[order].tolist()},
        ]}],
    }]


class LabelSlabs:
    """A zarr store's 3D label image read in slabs, whatever the stored
    axis order: ``shape`` and ``dtype`` in isoflow's (x, y, z) order,
    ``slabs[a:b]`` the x layers a .. b - 1 as a NumPy array, or
    ``slabs[x, y, z]`` the region of a slice per axis (a damaged chunk is
    one line); ``axes``, the order of x, y, z in which it is read a layer
    of chunks at a time (:func:`~isoflow.scale.chunks.layer_axes`: along
    the axis of the most chunks where they are thin across it, as the
    report block by block reads a volume) and ``layers`` the chunks along
    ``axes[0]``; ``pitch`` and ``origin`` (voxel (0, 0, 0)'s lowest
    corner), ``unit`` their length unit (:func:`axis_unit`), ``fill_value``
    the array's (what zarr reads for a chunk never written), ``chunks``
    its chunks' sides in (x, y, z) order; ``names``
    those of its labels where it records them (:func:`label_properties`);
    ``space`` None, as for every zarr store (no anatomical frame)."""

    space = None

    def __init__(self, path):
        from ...scale.chunks import layer_axes, zarr_blocks

        import_library("zarr", "OME-Zarr")
        store = open_store(path, time=True)
        array, self.where = store.array, store.where
        pitch, origin = store.placement()
        pitch = 1.0 if pitch is None else pitch
        xyz, other = store.xyz, store.other
        if store.multiscale is None and array.ndim == 4 and array.shape[3] == 1:
            # a 3D label image saved with a last axis of one entry (an array
            # of shape (X, Y, Z, 1)) is read as 3D, as read_labels reads a
            # file's: that axis is indexed at 0, and the placement's fourth
            # entries (where the attributes give four) dropped
            xyz, other = [0, 1, 2], [3]
            pitch, origin = (v[:3] if np.ndim(v) == 1 and len(v) == 4 else v for v in (pitch, origin))
        elif store.multiscale is None and array.ndim not in (2, 3):
            # as a file's: no label table is 4D, whether read whole or by blocks
            raise IsoflowError(f"{self.where}: a label image is read in 3D or 2D, this array is {array.ndim}D "
                               f"with shape {tuple(array.shape)}"
                               + (one_time_point_labels(self.where, int(array.shape[-1])) if array.ndim == 4 else ""))
        if store.multiscale is None and len(xyz) != 3:
            raise IsoflowError(f"{self.where}: a label table of a .zarr store (read block by block) needs a 3D "
                               f"volume, this array is {array.ndim}D" + ("; a 2D table reads the image whole "
                                                                        "(label_table)" if array.ndim == 2 else ""))
        self.xyz, self.other = xyz, other
        if len(self.xyz) == 4:
            shape = tuple(int(array.shape[i]) for i in self.xyz)
            raise IsoflowError(f"{self.where}: a label image is read in 3D or 2D, this array is 4D with shape "
                               f"{shape}" + one_time_point_labels(self.where, shape[-1]))
        if len(self.xyz) != 3:
            names = None if store.multiscale is None else axis_names(store.multiscale, array.ndim, self.where)
            raise IsoflowError(f"{self.where}: a label table of a .zarr store (read block by block) needs a 3D "
                               f"volume, this image has axes {names}" + ("; a 2D table reads the image whole "
                                                                        "(label_table)" if len(self.xyz) == 2 else ""))
        self.array, self.guarded = array, Guarded(array, self.where)
        self.shape = tuple(int(array.shape[i]) for i in self.xyz)
        self.dtype = array.dtype
        # the chunks (a shard's inner chunks) in (x, y, z) order: a read decodes each it crosses whole
        self.chunks = tuple(int(array.chunks[i]) for i in self.xyz)
        self.fill_value = getattr(array, "fill_value", None)  # what zarr reads for a chunk never written
        blocks = zarr_blocks(array, None)
        self.axes = layer_axes(tuple(len(blocks[i]) for i in self.xyz))
        self.layers = list(blocks[self.xyz[self.axes[0]]])
        self.pitch, self.origin, self.unit = pitch, origin, store.unit()
        #: label value to name, where the image's ``image-label`` names them (:func:`label_properties`)
        self.names = None if store.multiscale is None else label_properties(array, self.where)
        never_written(self.where, unwritten_fill(array), table=True)

    def __getitem__(self, region):
        parts = region if isinstance(region, tuple) else (region,)
        index = [0] * len(self.array.shape)
        for n, axis in enumerate(self.xyz):
            index[axis] = parts[n] if n < len(parts) else slice(None)
        data = np.asarray(self.guarded[tuple(index)])
        kept = [a for a in range(len(self.array.shape)) if a not in self.other]
        return np.transpose(data, [kept.index(a) for a in self.xyz])
