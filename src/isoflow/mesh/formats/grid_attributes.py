"""A volume's voxel size and place in the attributes other tools write on
an HDF5 dataset or a plain zarr array.

isoflow writes ``pitch`` and ``origin`` (HDF5: with ``offset`` and
``parity`` too) and reads them back exactly; those files are read by
their own reader's rule. A dataset written by another tool says its voxel
size in that tool's word, one entry per stored axis (or one for all):

=================== ==================================== ================ ==========================
attribute           written by                           unit             ``offset`` beside it
=================== ==================================== ================ ==========================
``element_size_um`` ilastik, Fiji's HDF5 plug-in         µm               isoflow's (lattice steps)
``resolution``      CREMI, gunpowder, daisy (Funke lab)  none said        world units (voxel 0's corner)
``voxel_size``      funlib.persistence                   its ``units``    world units (voxel 0's corner)
``spacing``         scikit-image, SimpleITK, MONAI users none said        isoflow's (lattice steps)
=================== ==================================== ================ ==========================

CREMI's, gunpowder's and funlib's ``offset`` is where voxel 0's lowest
corner lies in world units (nm in CREMI), not a count of voxels: read as a
count it would put a CREMI volume 40 or 4 times too far along each axis.
Two of these attributes that differ are refused (one line naming both);
a dataset with none of them but one whose name says voxel size
(``pixelResolution``, ``transform``, ...) is read with voxels of 1 and a
warning naming it, not in silence.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ...errors import IsoflowError, coordinates
from .registry import axis_units, note

#: the voxel size's attribute in each tool's word, in the order read, with
#: the length unit it says (None: none) and whether an ``offset`` beside it
#: is in world units (True) or isoflow's lattice steps (False)
VOXEL_SIZES: dict[str, tuple[str | None, bool]] = {
    "element_size_um": ("\u00b5m", False),
    "resolution": (None, True),
    "voxel_size": (None, True),
    "spacing": (None, False),
}

#: words in an attribute's name (lower case, without ``_`` and ``-``)
#: that say it holds a voxel size or a placement isoflow does not read
#: (N5's ``pixelResolution``, COSEM's ``transform``, ``element_size_nm``):
#: named in a warning where no voxel size is read. Not ``scale``, which
#: netCDF's ``scale_factor`` (of the values) holds
SIZE_WORDS = ("resolution", "voxelsize", "voxelspacing", "spacing", "pixelsize", "elementsize", "transform", "affine")


#: the attributes read as the voxel size, as warnings list them
READ = ", ".join(("pitch", *VOXEL_SIZES))


def size_named(names: Iterable[object], attributes: bool = True) -> list[str]:
    """The names among ``names`` that say they hold a voxel size or a
    placement (:data:`SIZE_WORDS`) but are not read as one: a dataset's
    attributes other than those of :data:`VOXEL_SIZES` (``attributes``),
    or any of a file's datasets (no dataset is read as a voxel size).

    Examples
    --------
    >>> size_named(["axistags", "pixelResolution", "resolution", "transform", "scale_factor", "voxel_size_nm"])
    ['pixelResolution', 'transform', 'voxel_size_nm']
    >>> size_named(["data/image", "spacing"], attributes=False)
    ['spacing']
    """
    read = {"pitch", *VOXEL_SIZES} if attributes else set()
    return [str(n) for n in names if str(n) not in read
            and any(w in str(n).lower().replace("_", "").replace("-", "") for w in SIZE_WORDS)]


@dataclass(frozen=True)
class AttributeGrid:
    """Where another tool's attributes put a volume: ``pitch`` (one number,
    or one per axis read, in isoflow's order), ``origin`` (voxel 0's lowest
    corner in world units, or None where they give none), ``unit`` (their
    length unit, or None) and ``lattice_offset`` (whether an ``offset``
    attribute beside them is isoflow's count of voxels, for the reader
    to take; False where it was read here, in world units, as ``origin``)."""

    pitch: float | np.ndarray
    origin: np.ndarray | None
    unit: str | None
    lattice_offset: bool


def attribute_grid(attrs: Mapping[str, Any], shape: Sequence[int], axes: Sequence[int],
                   where: str) -> AttributeGrid | None:
    """The voxel size and place another tool wrote in a dataset's
    attributes (the module's table), or None where isoflow's own ``pitch``
    is there (its reader takes it) or no voxel size is (a warning where an
    attribute's name says one is, unread).

    Parameters
    ----------
    attrs : mapping
        The dataset's attributes (h5py's or zarr's ``attrs``, as a dict).
    shape : sequence of int
        The dataset's shape as stored.
    axes : sequence of int
        The stored axes read, in isoflow's order (x, y, z, then t): a
        value of one entry per stored axis is taken at these; one of an
        entry per axis read (a channel axis dropped) is in stored order.
    where : str
        The dataset, as refusals and warnings name it.

    Returns
    -------
    AttributeGrid or None

    Examples
    --------
    A CREMI volume, stored z, y, x with voxels of 40 x 4 x 4 nm and its
    corner at 1520 nm along z, read as stored (axis 0 is x):

    >>> grid = attribute_grid({"resolution": [40.0, 4.0, 4.0], "offset": [1520.0, 0.0, 0.0]},
    ...                       (125, 1250, 1250), [0, 1, 2], "sample_A.hdf:/volumes/labels/neuron_ids")
    >>> grid.pitch.tolist(), grid.origin.tolist(), grid.lattice_offset
    ([40.0, 4.0, 4.0], [1520.0, 0.0, 0.0], False)
    >>> attribute_grid({"resolution": [40, 4, 4], "voxel_size": [40, 4, 8]}, (5, 6, 7), [0, 1, 2], "v.h5")
    Traceback (most recent call last):
        ...
    isoflow.errors.IsoflowError: v.h5: holds both 'resolution' [40, 4, 4] and 'voxel_size' [40, 4, 8], two voxel sizes: keep one
    >>> attribute_grid({"pitch": 0.5, "resolution": [40, 4, 4]}, (5, 6, 7), [0, 1, 2], "a.h5:/v") is None
    True
    """
    if "pitch" in attrs:
        return None
    named = tuple(name for name in VOXEL_SIZES if name in attrs)
    if not named:
        unread = size_named(attrs)
        if unread:
            note(f"{where}: {'its attribute' if len(unread) == 1 else 'its attributes'} "
                 f"{', '.join(repr(k) for k in unread)} {'is' if len(unread) == 1 else 'are'} not read: voxels "
                 f"of 1 (isoflow reads the voxel size from {READ})")
        return None
    sizes = [_sizes(attrs[name], shape, axes, where, name) for name in named]
    for name, size in zip(named[1:], sizes[1:]):
        if not np.array_equal(np.broadcast_to(size, len(axes)), np.broadcast_to(sizes[0], len(axes))):
            raise IsoflowError(f"{where}: holds both {named[0]!r} {_shown(attrs[named[0]])} and {name!r} "
                               f"{_shown(attrs[name])}, two voxel sizes: keep one")
    pitch = sizes[0]
    unit = next((VOXEL_SIZES[name][0] for name in named if VOXEL_SIZES[name][0]), None)
    world = any(VOXEL_SIZES[name][1] for name in named)
    origin = None
    if world and "offset" in attrs:
        origin = _values(attrs["offset"], shape, axes, where, "offset")
        if "origin" in attrs:
            raise IsoflowError(f"{where}: holds both 'origin' {_shown(attrs['origin'])} and 'offset' "
                               f"{coordinates(origin)} (voxel 0's corner in world units beside {named[0]!r}), two "
                               "places: keep one")
    if "voxel_size" in named and "units" in attrs:  # funlib.persistence: one unit per axis
        units = _per_axis(attrs["units"], shape, axes, time="")
        spatial = min(len(axes), 3)
        if np.ndim(units) != 1 or len(units) < spatial:
            raise IsoflowError(f"{where}: attribute 'units' {_shown(attrs['units'])} is not {spatial} length units, "
                               "one per axis (or one for all)")
        factors, unit = axis_units(list(units)[:spatial], where, "attribute 'units'")
        factors = np.append(factors, 1.0) if len(axes) == 4 else factors
        pitch = pitch * factors
        origin = None if origin is None else origin * factors
    if np.ndim(pitch) == 1 and np.all(pitch == pitch[0]):
        pitch = float(pitch[0])
    return AttributeGrid(pitch, origin, unit, not world)


def _per_axis(value: Any, shape: Sequence[int], axes: Sequence[int], time: Any = None) -> Any:
    """``value`` of one entry per stored axis (or per axis read, in stored
    order) in isoflow's order of ``axes``; of a time series (four axes
    read, the last time), one per axis in space, ``time`` added for the
    time axis; anything else as it is."""
    if isinstance(value, (str, bytes)) or np.ndim(value) != 1:
        return [value] * len(axes) if isinstance(value, (str, bytes)) else value
    entries = list(value)
    if len(entries) == len(shape):
        return [entries[i] for i in axes]
    if len(entries) == len(axes):  # per axis read, in stored order
        return [entries[i] for i in np.argsort(np.argsort(axes))]
    if len(axes) == 4 and len(entries) == 3 and time is not None:  # x, y, z of a time series, in stored order
        return [entries[i] for i in np.argsort(np.argsort(axes[:3]))] + [time]
    return value


def _values(value: Any, shape: Sequence[int], axes: Sequence[int], where: str, name: str,
            time: float = 0.0) -> np.ndarray:
    """One finite number per axis read (one for all broadcast; ``time``
    for a time axis its value leaves out), from the attribute ``name``, or
    one line naming it."""
    try:
        values = np.asarray(_per_axis(value, shape, axes, time), np.float64)
    except (TypeError, ValueError):
        values = None
    if values is None or values.shape not in ((), (len(axes),)) or not np.isfinite(values).all():
        raise IsoflowError(f"{where}: attribute {name!r} {_shown(value)} is not {len(axes)} numbers, one per axis "
                           "(or one for all)")
    return np.broadcast_to(values, len(axes)).copy()


def _sizes(value: Any, shape: Sequence[int], axes: Sequence[int], where: str, name: str) -> np.ndarray:
    """The voxel sizes the attribute ``name`` holds, or one line naming it
    (not isoflow's word for it, 'pitch')."""
    try:
        sizes = _values(value, shape, axes, where, name, time=1.0)  # a time axis: steps of 1, as NIfTI's
    except IsoflowError:
        sizes = None
    if sizes is None or not (sizes > 0).all():
        raise IsoflowError(f"{where}: attribute {name!r} {_shown(value)} is not {len(axes)} positive voxel sizes, one "
                           "per axis (or one for all)")
    return sizes


def _shown(value: Any) -> str:
    """An attribute's value as a refusal shows it (h5py's arrays as lists)."""
    return repr(value.tolist() if isinstance(value, np.ndarray) else value)
