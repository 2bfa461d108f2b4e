"""Reading volumes and point lists; writing volumes.

Every reader raises :class:`~isoflow.errors.IsoflowError` with the file name
and what is wrong; every writer refuses to replace an existing file unless
``force=True``.
"""

from __future__ import annotations

import dataclasses
import errno
import os
import re
import stat
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np
from numpy.typing import ArrayLike

from ..digital.label_table import LabelImage, as_labels, label_names
from ..digital.lattice import MAX_COORDINATE, DigitalObject
from ..digital.units import LENGTH_UNITS, length_unit, unit_given
from ..errors import IsoflowError, check_path, check_switch, choice_of, counted, given_text, missing, number_text, warn
from ..results import handed_over
from ..scale.arrays import NotBinary, as_array, binary, fill_value_named, refuse_object
from ..scale.chunks import never_written
from ..scale.memory import check_fits
from .formats.registry import (
    LabelVolume,
    RawVolume,
    check_label,
    check_time,
    format_for,
    no_such_label,
    one_time_point_labels,
    sniff_volume_format,
    split_dataset,
    volume_suffixes,
)
from .formats.text_encoding import utf16_order
from .outputs import atomic_path, check_output_path, refuse_directory_spelling, refuse_nameless

#: every volume suffix read_volume takes (see isoflow.mesh.formats.registry)
VOLUME_SUFFIXES = volume_suffixes()


#: what ``os.stat`` says of a path that is not there
NOT_THERE = (errno.ENOENT, errno.ENOTDIR)


def _check_readable(path: Path, directory_ok: bool = False) -> None:
    try:
        mode = path.stat().st_mode
    except OSError as exc:
        if exc.errno in NOT_THERE:
            raise missing(path) from None
        # a name too long, a directory on the way that may not be searched, a
        # loop of links: Path.exists raised the first two as a bare OSError
        raise IsoflowError(f"{path}: cannot be read ({exc.strerror})") from None
    if stat.S_ISDIR(mode):
        if not directory_ok:
            refuse_inside_store(path, path)
            raise IsoflowError(f"{path}: is a directory, not a volume or point list")
        return
    if not stat.S_ISREG(mode):
        # a device or FIFO would be read until memory runs out (/dev/zero)
        raise IsoflowError(f"{path}: not a regular file (a device, pipe or socket)")
    try:
        path.open("rb").close()
    except OSError as exc:
        # no read permission: np.load's error made it "an empty file", nibabel's "could not read"
        raise IsoflowError(f"{path}: cannot be read ({exc.strerror})") from None


def is_volume(path) -> bool:
    """Whether ``path`` (``FILE.h5:/dataset`` too) names a volume file by its suffix."""
    return format_for(split_dataset(path)[0]) is not None


def read_volume(path: str | os.PathLike, label: int | np.integer | float | None = None, *,
                time: int | np.integer | None = None) -> DigitalObject:
    """A 2D, 3D (or 4D) volume from any format of :mod:`isoflow.mesh.formats`,
    with its voxel size and origin where the format has them.

    ``path`` may name a dataset inside the file: ``FILE.h5:/group/volume``,
    ``IMAGE.zarr:1`` (an OME-Zarr resolution level). The volume must hold
    0/1 values, or 0 and one other value (a mask written 0/255); a label
    image is refused unless ``label`` selects one value (its voxels become
    the object). MagicaVoxel colours are not labels: any
    coloured voxel is in the object unless ``label`` picks one colour index.

    An ``.npz`` written by :func:`write_volume` carries ``volume`` plus its
    ``offset``, ``parity``, ``pitch`` and ``origin``; any other ``.npz`` must
    hold exactly one array (or one named ``volume``).

    Parameters
    ----------
    path : str or os.PathLike
        A file of any suffix of docs/formats.md, optionally ``:dataset``.
    label : int or float, optional
        The value whose voxels are the object, in a label image.
    time : int, optional
        One time point (0 the first) of a time series, a 4D volume read as
        (x, y, z, t): its 3D volume, with the voxel size and origin of x,
        y and z. A ``.zarr`` store reads only that time point's chunks, so
        a time-lapse larger than memory gives one; other formats read the
        whole series, then take the time point.

    Returns
    -------
    DigitalObject
        With the file's voxel size as ``pitch`` and its first voxel's place
        as ``origin``, in isoflow's (x, y, z) axis order, and their length
        unit as ``unit`` (None where the file says none, or names a unit
        isoflow does not know: :func:`read_volume_with_unit` gives that).

    Raises
    ------
    IsoflowError
        One line naming the file and the problem: missing, damaged, not
        binary, no such dataset or label, a library missing; a ``time``
        given for a volume that is not 4D, or beyond its time points.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> labels = np.zeros((4, 4, 4), np.uint8)
    >>> labels[1:3, 1:3, 1:3] = 7
    >>> np.save(folder / "labels.npy", labels)
    >>> read_volume(folder / "labels.npy", label=7).voxels
    8
    >>> series = np.stack([labels, np.where(labels, 0, 7)], axis=-1)  # (x, y, z, t): the cube, then the rest
    >>> np.save(folder / "series.npy", series)
    >>> frame = read_volume(folder / "series.npy", label=7, time=1)
    >>> frame.volume.shape, frame.voxels
    ((4, 4, 4), 56)
    """
    path = check_path(path, "path", "read_volume", "an array in memory: DigitalObject(array)")
    return read_volume_with_unit(path, label, time=time)[0]


def read_volume_with_unit(path: str | os.PathLike, label: int | np.integer | float | None = None, *,
                          time: int | np.integer | None = None) -> tuple[DigitalObject, str | None]:
    """:func:`read_volume`'s object and the length unit of its ``pitch`` and
    ``origin`` as the file says it, in one spelling per unit (``mm``,
    ``µm``, ``nm``, ``m``, ``cm``, ...: see docs/formats.md): NIfTI's xyzt
    units, NRRD's space units, ImageJ's or OME-XML's unit in a TIFF, HDF5's
    ``unit`` attribute or ``element_size_um``, OME-Zarr's axis units, an
    ``.npz``'s ``unit`` (what :func:`write_volume` writes with ``unit=``).

    Parameters
    ----------
    path : str or os.PathLike
        A volume file, optionally ``:dataset``, as :func:`read_volume` takes it.
    label : int or float, optional
        The value whose voxels are the object, in a label image.
    time : int, optional
        One time point of a time series (see :func:`read_volume`).

    Returns
    -------
    tuple of DigitalObject and str or None
        The object, and its unit (None where the file says none).

    Raises
    ------
    IsoflowError
        As :func:`read_volume`.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> import nibabel as nib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "cube.nii.gz"
    >>> img = nib.Nifti1Image(np.ones((2, 2, 2), np.uint8), np.diag([0.5, 0.5, 2.0, 1.0]))
    >>> img.header.set_xyzt_units("micron")
    >>> nib.save(img, path)
    >>> obj, unit = read_volume_with_unit(path)
    >>> obj.spacing.tolist(), unit
    ([0.5, 0.5, 2.0], '\u00b5m')
    """
    obj, unit, _ = read_volume_as_stored(path, label, time=time)
    return obj, unit


def read_volume_as_stored(path: str | os.PathLike, label: int | np.integer | float | None = None, *,
                          time: int | np.integer | None = None) -> tuple[DigitalObject, str | None, np.dtype]:
    """:func:`read_volume_with_unit`'s object and unit, and the type of the
    values the file holds: the object is boolean whatever they were (a
    uint8 mask, a float map of 0 and 1), and ``isoflow info --json`` says
    what it read.

    Parameters
    ----------
    path, label, time
        What :func:`read_volume_with_unit` takes.

    Returns
    -------
    tuple of DigitalObject, str or None, and numpy.dtype
        The object, its unit, and the values' type as read (a NIfTI's
        scaling applied where its header gives one).

    Raises
    ------
    IsoflowError
        What :func:`read_volume` raises.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "mask.npy"
    >>> np.save(path, np.ones((2, 2, 2), np.uint8))
    >>> obj, unit, dtype = read_volume_as_stored(path)
    >>> obj.volume.dtype.name, unit, dtype.name
    ('bool', None, 'uint8')
    """
    raw = _read_raw(path, time=time)
    if label is not None:  # a label image, read as read_labels reads it
        raw = _one_channel(raw, time)
    return as_object(raw, str(path), label), raw.unit, raw.array.dtype


def zarr_around(path: Path) -> Path | None:
    """The zarr store (a directory named ``*.zarr``) that holds ``path``,
    a group or array inside it (an OME-Zarr image's ``labels/cells``), or
    None.

    Parameters
    ----------
    path : pathlib.Path
        The path as given.

    Returns
    -------
    pathlib.Path or None
        The innermost store around it.

    Examples
    --------
    >>> str(zarr_around(Path("image.zarr/labels/cells"))), zarr_around(Path("scan.nii.gz"))
    ('image.zarr', None)
    """
    return next((p for p in path.parents if p.suffix.lower() == ".zarr"), None)


def refuse_inside_store(file: Path, shown: str | os.PathLike) -> None:
    """One line for a path inside a zarr store (:func:`zarr_around`),
    with the name that reads it: ``STORE.zarr:labels/cells``.

    Parameters
    ----------
    file : pathlib.Path
        The path, without a ``:dataset``.
    shown : str or os.PathLike
        The input as the line names it.

    Raises
    ------
    IsoflowError
        Where ``file`` lies inside a ``.zarr`` directory.

    Examples
    --------
    >>> refuse_inside_store(Path("image.zarr/labels/cells"), "image.zarr/labels/cells")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: image.zarr/labels/cells: inside the zarr store image.zarr; name it as image.zarr:labels/cells
    """
    if (store := zarr_around(file)) is not None:
        raise IsoflowError(f"{shown}: inside the zarr store {store}; name it as {store}:{file.relative_to(store).as_posix()}")


def _read_raw(path: str | os.PathLike, mesh: str | None = None, time: int | np.integer | None = None) -> RawVolume:
    """What the format of ``path`` (``FILE:dataset`` too) reads, once the
    suffix, the file and the dataset named are checked: the one prologue of
    :func:`read_volume` and :func:`read_labels`.

    Parameters
    ----------
    path : str or os.PathLike
        A volume file, optionally ``:dataset``.
    mesh : str, optional
        What to say of a mesh file in place of "not a volume file" (a
        reader whose remedy for a mesh differs: the label reader's, which
        names a point list's too).
    time : int, optional
        The time point of a 4D volume to give, as 3D (see
        :func:`read_volume`).

    Returns
    -------
    RawVolume
        The array in isoflow's axis order and its placement, unchecked.

    Raises
    ------
    IsoflowError
        A suffix of no volume format, a missing or unreadable file, a
        dataset named where the format has none, a ``time`` that picks no
        time point, or the format's refusal.
    """
    file, dataset = split_dataset(path)
    fmt = format_for(file)
    if fmt is None:
        from .load import is_mesh_path

        if mesh is not None and is_mesh_path(file):
            raise IsoflowError(f"{path}: {mesh}")
        if mesh is not None and file.suffix.lower() in POINT_SUFFIXES:
            # (a label reader's: one object's points hold no labels)
            raise IsoflowError(f"{path}: a point list ({file.suffix} of x y z per line), one object, not a label "
                               f"image: `isoflow info {path}` without --labels reports it (isoflow.read_points)")
        if file.is_dir():  # the line `info DIR` gives, with --labels too: a directory is not "not a volume file"
            _check_readable(file)
        refuse_inside_store(file, path)
        raise IsoflowError(f"{path}: not a volume file (volumes end in {', '.join(VOLUME_SUFFIXES)})")
    _check_readable(file, directory_ok=fmt.module == "omezarr")
    check_dataset_read(path, fmt, dataset)
    if time is None:
        return fmt.load().read(file, dataset)
    if fmt.module == "omezarr":  # only that time point's chunks: a time-lapse store may not fit in memory
        return fmt.load().read(file, dataset, time=time)
    raw = fmt.load().read(file, dataset)
    return _time_point(raw, check_time(time, np.shape(raw.array), str(path)))


def _one_channel(raw: RawVolume, time: int | np.integer | None) -> RawVolume:
    """A label image's ``raw`` as 3D where its array is 4D with a last axis
    of one entry and no ``time`` was asked: a 3D segmentation saved with a
    channel axis (ilastik's HDF5 (z, y, x, 1), an .npy of shape
    (X, Y, Z, 1)) has one 3D image to read, as NIfTI's reader drops such
    an axis; ``raw`` itself otherwise. A mask with no label asked stays 4D:
    its 0/1 values may be a 4D object one voxel thick."""
    arr = np.asarray(raw.array)
    if time is None and arr.ndim == 4 and arr.shape[3] == 1:
        return _time_point(dataclasses.replace(raw, array=arr), 0)
    return raw


def _time_point(raw: RawVolume, time: int) -> RawVolume:
    """Time point ``time`` of a 4D ``raw`` volume, as 3D: its array's last
    axis and the placement's fourth entries dropped."""
    def spatial(value):  # a per-axis entry loses its fourth; one number for all axes stays
        return value if value is None or not np.ndim(value) else value[:3]

    return dataclasses.replace(raw, array=raw.array[..., time], pitch=spatial(raw.pitch), origin=spatial(raw.origin),
                               offset=spatial(raw.offset))


def check_dataset_read(path, fmt, dataset: str | None) -> None:
    """A dataset named in a path is one the format can read: a dataset of
    HDF5 and zarr, an array of an .npz."""
    if dataset is not None and not (fmt.datasets or fmt.read_datasets):
        raise IsoflowError(f"{path}: a dataset inside the file is named only for HDF5, zarr, .npz and a 3D Slicer "
                           ".seg.nrrd (a layer)")


def as_object(raw: RawVolume, where: str, label=None) -> DigitalObject:
    """The DigitalObject of what a format reader found: one label selected,
    or the 0/1 check (``binary``), and the metadata checked."""
    arr = np.asarray(raw.array)
    if arr.ndim not in (2, 3, 4):
        raise IsoflowError(f"{where}: a volume must be 2D, 3D or 4D, this array is {arr.ndim}D with shape {arr.shape}")
    said_of(raw, label)
    if arr.ndim == 4:
        raw = time_axis_placed(raw)
    if label is not None:
        vol = select_label(arr, label, where)
    elif raw.paint:
        vol = arr != 0
    else:
        arr = one_value_mask(arr)
        try:
            vol = binary(arr, where)
        except NotBinary as exc:
            # a label table takes 2D and 3D images: --labels is no way out in 4D
            raise with_label_options(scaling_named(fill_value_named(exc, raw.fill, arr.dtype), raw.scaling),
                                     every=arr.ndim != 4, ndim=arr.ndim) from None
    never_written(where, raw.unwritten, label)
    # a format stored (z, y, x) comes back turned, in Fortran order: the
    # kernels run about five times faster on C order than on that view
    vol = np.ascontiguousarray(vol)
    meta: dict[str, Any] = {"pitch": raw.pitch, "origin": raw.origin, "offset": raw.offset, "parity": raw.parity,
                            # a unit isoflow cannot write (free text of NRRD or ImageJ) is not carried:
                            # read_volume_with_unit gives it as the file says it
                            "unit": raw.unit if raw.unit in LENGTH_UNITS else None, "space": raw.space}
    try:  # DigitalObject checks the metadata fields; its errors get the file's name
        # the place first, whose refusal names no function (DigitalObject's names itself): the file's name goes before it
        DigitalObject.placement(vol.ndim, raw.pitch, raw.origin, raw.offset, raw.parity)
        # handed over read-only with the file's array under it: an object copies a volume someone else could still write
        return DigitalObject(handed_over(vol), **{k: v for k, v in meta.items() if v is not None})
    except IsoflowError as exc:
        raise exc.at(where) from None


def time_axis_placed(raw: RawVolume) -> RawVolume:
    """A 4D volume whose pitch, origin or offset gives its three axes in
    space alone (an ``.npz`` saved with the spacing of its scan) placed
    along its fourth, time, axis as a 4D NIfTI's is: steps of 1 from 0.

    Parameters
    ----------
    raw : RawVolume
        What a reader found, of a 4D array.

    Returns
    -------
    RawVolume
        ``raw``, its placement's entries of three given a fourth.

    Examples
    --------
    >>> raw = RawVolume(np.zeros((2, 3, 4, 5), np.uint8), pitch=[0.5, 0.5, 2.0], origin=[1, 2, 3])
    >>> placed = time_axis_placed(raw)
    >>> placed.pitch.tolist(), placed.origin.tolist(), placed.offset
    ([0.5, 0.5, 2.0, 1.0], [1.0, 2.0, 3.0, 0.0], None)
    """
    def timed(value, step):
        return np.append(np.asarray(value), step) if value is not None and np.ndim(value) == 1 and len(value) == 3 \
            else value

    return dataclasses.replace(raw, pitch=timed(raw.pitch, 1.0), origin=timed(raw.origin, 0.0),
                               offset=timed(raw.offset, 0))


def scaling_named(exc: NotBinary, scaling: str | None) -> NotBinary:
    """``exc``, the refusal of a volume whose values were read through its
    header's scaling (``scaling``: :attr:`RawVolume.scaling`), saying so
    after its example value, as :func:`read_labels` says it: the value
    refused ("e.g. 0.5") is not what the file stores (1, under a
    ``scl_slope`` of 0.5), and the value alone would not say why.

    Parameters
    ----------
    exc : NotBinary
        The refusal (:func:`~isoflow.scale.arrays.binary`).
    scaling : str or None
        The scaling in words; None where the values are as stored.

    Returns
    -------
    NotBinary
        ``exc``, with the scaling named where there is one.

    Examples
    --------
    >>> e = NotBinary("s.nii: not a binary volume (1 voxel holds values other than 0 and 1, e.g. 0.5); threshold it")
    >>> str(scaling_named(e, "its header's scl_slope 0.5"))
    "s.nii: not a binary volume (1 voxel holds values other than 0 and 1, e.g. 0.5; the values are read through \
its header's scl_slope 0.5, not as stored); threshold it"
    """
    if scaling is None:
        return exc
    # the example's closing parenthesis: the last "); " (the file's name, which comes first, may hold one too)
    head, sep, tail = exc.bare.rpartition("); ")
    if not sep:
        return exc
    bare = f"{head}; the values are read through {scaling}, not as stored{sep}{tail}"
    return NotBinary(str(exc.args[0]).replace(exc.bare, bare, 1), bare, exc.every, exc.ndim, exc.kind, exc.value)


def said_of(raw: RawVolume, label: object = None) -> None:
    """The reader's warning that depends on the label selected, if any
    (``raw.said``): None for no label, and for a label table."""
    said = raw.said(label) if raw.said is not None else None
    if said:
        warn(said)


def one_value_mask(arr: np.ndarray) -> np.ndarray:
    """The mask of an array whose only nonzero value is one ``v`` other than
    1 (a mask written 0/255, as image tools write masks, or a label image
    of one label: ``--label v`` could mean nothing else); a uint8 0/1 array
    (as every format is written) as its bool view, without a copy; else
    the array as it is (for :func:`~isoflow.scale.arrays.binary` to check).

    Examples
    --------
    >>> one_value_mask(np.array([[0, 255], [255, 0]], np.uint8)).tolist()
    [[False, True], [True, False]]
    >>> one_value_mask(np.array([0, 3, 5])).tolist()  # two labels: not a mask
    [0, 3, 5]
    """
    if arr.dtype.kind not in "iuf" or not arr.size:
        return arr
    high = arr.max()
    if arr.dtype == np.uint8 and high <= 1:
        return arr.view(np.bool_)
    low = arr.min()
    value = high if high != 0 else low
    if value == 1 or value == 0 or not np.isfinite(value) or (low != 0 and high != 0 and low != high):
        return arr
    mask = arr == value
    return mask if np.count_nonzero(mask) + np.count_nonzero(arr == 0) == arr.size else arr


#: what the refusal of a label image where a mask is expected adds
EVERY_LABEL = "or give every label its row with --labels (isoflow.label_table(isoflow.read_labels(path)))"
#: the same for surface, whose --labels writes a surface per label, not a table
SURFACE_PER_LABEL = "or write a closed surface per label with --labels"


def with_label_options(exc: NotBinary, every: bool = True, *, surfaces: bool = False,
                       ndim: int | None = None) -> NotBinary:
    """The refusal of a label image where a mask is expected, with the
    options that select its labels: one (``--label N``) and, where the
    command takes it (``every``) and the image has a table (``exc.every``:
    2D and 3D), all (``--labels``): its table, or with ``surfaces`` (the
    surface command) a surface per label; on the condition that every
    voxel holds a whole number where ``exc.every`` is None (a float store
    refused at a block of whole values: the blocks not read may hold
    NaN or a fraction, which ``--labels`` refuses).  ``ndim``: the
    image's dimension, kept for the command (else ``exc.ndim``).

    Examples
    --------
    >>> str(with_label_options(NotBinary("v.npy: not a binary volume"), every=False))
    'v.npy: not a binary volume, or select one label with --label N (label=N)'
    >>> str(with_label_options(NotBinary("v.npy: not a binary volume"), surfaces=True))
    'v.npy: not a binary volume, or select one label with --label N (label=N), or write a closed surface per label with --labels'
    >>> str(with_label_options(NotBinary("v.zarr: not a binary volume", every=None), surfaces=True)).split("), ")[1]
    'or, if every voxel holds a whole number, write a closed surface per label with --labels'
    """
    ndim = exc.ndim if ndim is None else ndim
    table = exc.every if every else False
    if exc.kind == "fractions":  # a probability map: its threshold, which ``bare`` says, and no label
        return NotBinary(exc.bare, bare=exc.bare, every=False, ndim=ndim, kind=exc.kind, value=exc.value)
    offer = SURFACE_PER_LABEL if surfaces else EVERY_LABEL
    if table is None:  # (not known: said as a condition, not a promise)
        offer = offer.replace("or ", "or, if every voxel holds a whole number, ", 1)
    # many whole values are most often a grey image: its labels said as a condition
    one = ", or, if its values are labels, select one" if exc.kind == "grey" else ", or select one label"
    options = f"{one} with {label_option(exc.value)}" + (f", {offer}" if table is not False else "")
    return NotBinary(exc.bare + options, bare=exc.bare, every=table, ndim=ndim, kind=exc.kind, value=exc.value)


def label_option(value: object = None) -> str:
    """The option that selects one label, as a refusal offers it: with
    the value where the block read holds 0 and that value alone, a mask
    of it (a 0/255 mask read block by block), said to be the block's (a
    label image's other blocks hold other labels), else ``N``.

    Parameters
    ----------
    value : number, optional
        The one value other than 0 (:attr:`NotBinary.value`), or None.

    Returns
    -------
    str
        ``--label V (label=V...)``.

    Examples
    --------
    >>> label_option(np.uint8(255))
    '--label 255 (label=255; 255 is the one value other than 0 in that block)'
    >>> label_option(255.0).split(" (")[0], label_option()
    ('--label 255', '--label N (label=N)')
    """
    if value is None:
        return "--label N (label=N)"
    shown = number_text(value)
    return f"--label {shown} (label={shown}; {shown} is the one value other than 0 in that block)"


def read_labels(path: str | os.PathLike, *, time: int | np.integer | None = None) -> LabelImage:
    """A 3D or 2D label image from a file, with its voxel size and origin.

    Parameters
    ----------
    path : str or os.PathLike
        A file of any format :func:`read_volume` reads (a segmentation in
        NIfTI, NRRD, TIFF, HDF5, zarr, ...), optionally ``:dataset``.
    time : int, optional
        One time point of a time series of label images (4D, read as x, y,
        z, t), as :func:`read_volume` takes it. A file's last axis of one
        entry (ilastik's HDF5 ``(z, y, x, 1)``) is read as 3D without it.

    Returns
    -------
    LabelImage
        ``array``: the labels in isoflow's (x, y, z) order, as integers (a
        float array whose values are all whole numbers, as NIfTI scaling
        may give, becomes int64); ``spacing`` and ``origin`` as
        :func:`read_volume` gives them, and ``unit``, their length unit as
        the file says it (:func:`read_volume_with_unit`); ``space``, the
        anatomical frame of the world axes (``"RAS"`` for NIfTI and MGH, a
        NRRD's ``space``; None where the file says none); ``names``, label
        value to name, where the file records them (3D Slicer's segments in
        a NRRD, OME-Zarr's ``image-label`` properties, the ``label_names``
        that :func:`write_labels` writes into HDF5 and ``.npz``), else
        None. :func:`isoflow.label_table` takes it as it is, in the file's
        units.

    Raises
    ------
    IsoflowError
        One line naming the file: not a volume, not 2D or 3D (a time
        series without ``time``), values that are no labels, a ``time``
        that picks no time point.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from isoflow import label_table
    >>> labels = np.zeros((4, 4, 4), np.uint8)
    >>> labels[0], labels[2:] = 1, 2
    >>> path = write_labels(labels, pathlib.Path(tempfile.mkdtemp()) / "seg.nii.gz", pitch=(0.5, 0.5, 2.0))
    >>> image = read_labels(path)
    >>> image.spacing.tolist(), label_table(image)["volume"].tolist()
    ([0.5, 0.5, 2.0], [8.0, 16.0])
    """
    path = check_path(path, "path", "read_labels", "an array in memory: label_table(array)")
    # a mesh voxelises to one object; a label image of meshes is voxelize's
    raw = _read_raw(path, mesh="a mesh, not a label image; voxelize A.stl B.obj --resolution R -o LABELS.nii.gz "
                               "makes one of several meshes (isoflow.voxelize_meshes)", time=time)
    said_of(raw)
    raw = _one_channel(raw, time)
    arr = np.asarray(raw.array)
    if arr.ndim not in (2, 3):
        raise IsoflowError(f"{path}: a label image is read in 3D or 2D, this array is {arr.ndim}D with shape "
                           f"{arr.shape}" + (one_time_point_labels(path, arr.shape[-1]) if arr.ndim == 4 else ""))
    if arr.dtype.kind == "f":
        try:
            arr = as_labels(arr, fill=raw.fill)
        except IsoflowError as exc:
            if raw.scaling is not None:  # "holds 0.5" of a file that stores 1: the header made it so
                raise IsoflowError(f"{path}: {exc}; the values are read through {raw.scaling}, not as "
                                   "stored") from None
            raise exc.at(path) from None
    elif arr.dtype.kind not in "biu":
        raise IsoflowError(f"{path}: holds {arr.dtype} values, not labels")
    try:
        obj = DigitalObject.placement(arr.ndim, raw.pitch, raw.origin, raw.offset, raw.parity)
    except IsoflowError as exc:
        raise exc.at(path) from None
    never_written(str(path), raw.unwritten, table=True)
    return LabelImage(np.ascontiguousarray(arr), obj.spacing, obj.world(np.zeros((1, arr.ndim)))[0], raw.unit,
                      raw.names, space=raw.space)


def select_label(array, label, where: str) -> np.ndarray:
    """The voxels of ``array`` equal to ``label``; an error listing the
    values present when there are none."""
    arr = np.asarray(array)
    label = check_label(label, arr.dtype, where)
    vol = arr == label
    if not vol.any():
        raise no_such_label(label, np.unique(arr), where, arr.ndim)
    return vol


#: numbers of a point list are separated by blanks, or by one comma with
#: blanks around it allowed ("0,,0" has an empty coordinate)
_SPLIT = re.compile(r"\s*,\s*|\s+")
#: a decimal number as people write coordinates: no "1_000", "0x10", "nan",
#: and ASCII digits only (float() takes Arabic-Indic and full-width ones)
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def read_points(path: str | os.PathLike) -> np.ndarray:
    """Integer lattice points from a text file: ``x y z`` (or ``x y``) per
    line, ``#`` starts a comment, blanks or commas separate the numbers. A
    first line of column names (``x,y,z``, as pandas' ``to_csv`` writes
    it) is skipped where the next line holds as many numbers; where its
    first name is empty or ``index`` (``,x,y,z``: ``to_csv`` with the
    frame's index; ``,0,1,2`` for a frame of an array), that first column
    is the index, not a coordinate.
    UTF-8 text, or UTF-16 where a byte-order mark opens it (Windows
    PowerShell's ``>``) or, without one, where every other byte is NUL
    beside ASCII text (LE or BE); a UTF-8 byte-order mark is skipped.

    numpy's compiled reader takes the file when it can; a file it refuses,
    or whose numbers are not all integers in range, is read again line by
    line, for the one-line error that names the line.

    Parameters
    ----------
    path : str or os.PathLike
        A text file of points.

    Returns
    -------
    numpy.ndarray
        int64 points, shape ``(N, 2)`` or ``(N, 3)``.

    Raises
    ------
    IsoflowError
        A file that is no point list: a mesh or a volume under its own
        suffix (named so, with the function that reads it), or a line that
        is not 2 or 3 integers (naming the line).

    Examples
    --------
    >>> from isoflow import data
    >>> read_points(data.example19()).shape  # the paper's 20 points of Example 19
    (20, 3)
    """
    path = check_path(path, "path", "read_points")
    path = Path(path)
    # a volume under a volume suffix is no point list: the reader below would
    # name its format and ask for the name it already has ("rename it
    # v.npy"), a .binvox's header line would be "no number", and a .zarr
    # store "a directory"; a missing one is said missing below
    if is_volume(path) and os.path.exists(path):
        raise IsoflowError(f"{path}: a volume file, not a list of lattice points; isoflow.read_volume(path) reads it")
    _check_readable(path)
    from .load import is_mesh_path, refuse_cad

    # a mesh is known by its suffix, as the command line knows it, and is no
    # point list: the point reader would blame its first line, or its bytes
    refuse_cad(path)
    if is_mesh_path(path):
        raise IsoflowError(f"{path}: a mesh file, not a volume or a list of lattice points; "
                           "isoflow.voxelize_file(path) voxelizes it")
    try:
        # look at the head first: any file of unknown type lands here, and
        # a big binary one should not be read whole before being refused
        with open(path, "rb") as fh:
            head = fh.read(1024)
        encoding = _text_encoding(head)
        if b"\0" in head and not encoding.startswith("utf-16"):  # (UTF-16 text is half NUL bytes)
            found = sniff_volume_format(path)
            if found is not None:  # a volume without its suffix (or under another one)
                raise IsoflowError(f"{path}: its content is {found[0]}, but volumes are read by their suffix: rename it "
                                   f"{path.stem if path.suffix else path.name}{found[1]}")
            raise IsoflowError(
                f"{path}: binary data, not a text point list (x y z per line); "
                f"volumes are read by their suffix: {', '.join(volume_suffixes())}"
            )
        # a point takes at least 4 bytes of text ("0 0" and a line end) and
        # 8 bytes a coordinate once read: 4 to 6 bytes per byte of text
        check_fits(6 * path.stat().st_size, f"reading the point list {path}",
                   hint="a volume file (.npy, .zarr) holds points far more compactly")
        try:
            header, index = _header_line(path, encoding)
            points = _read_points_fast(path, b"," in head, header, index, encoding)
            return points if points is not None else _read_points_by_line(path, header, index, encoding)
        except IsoflowError as exc:
            raise IsoflowError(not_points(path, str(exc))) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise IsoflowError(f"{path}: cannot read as text ({exc})") from None


#: Suffixes a text point list goes by (any file of no volume or mesh
#: suffix is read as one).
POINT_SUFFIXES = (".txt", ".csv", ".xyz", ".pts")


def not_points(path: str | os.PathLike, said: str) -> str:
    """The line for a text file that the point reader refused with
    ``said``: a mesh file without its suffix (or under another one) is
    named as such, with the name to give it, as a volume's content is;
    under a suffix no point list goes by, ``said`` gains what the file was
    read as. The point reader's own line for an OBJ named ``part``,
    ``part:3: not a number: 'v'``, reads as a typo in a point list.

    Parameters
    ----------
    path : str or os.PathLike
        The file read.
    said : str
        The point reader's line.

    Returns
    -------
    str
        The line to refuse the file with.

    Examples
    --------
    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "part"
    >>> _ = p.write_text("# a mesh\\nv 0 0 0\\nv 1 0 0\\nv 0 1 0\\nf 1 2 3\\n")
    >>> print(not_points(p, f"{p}:2: not a number: 'v'").replace(str(p.parent), "DIR"))
    DIR/part: its content is an OBJ file (lines 'v x y z' and 'f ...'), but meshes are read by their suffix: \
rename it part.obj
    >>> print(not_points("scene.vtp", "scene.vtp:1: not a number: '<?xml'"))
    scene.vtp:1: not a number: '<?xml' (read as a text point list, x y z per line: the suffix .vtp names no \
volume or mesh format)
    """
    from .sniff import FORMATS, SNIFF_BYTES, sniff_mesh_format

    path = Path(path)
    try:
        with open(path, "rb") as fh:
            kind = sniff_mesh_format(fh.read(SNIFF_BYTES), os.fstat(fh.fileno()).st_size)
    except OSError:
        kind = ""
    if kind:
        what, suffix = FORMATS[kind]
        return (f"{path}: its content is {what}, but meshes are read by their suffix: rename it "
                f"{path.stem if path.suffix else path.name}{suffix}")
    if path.suffix.lower() not in POINT_SUFFIXES:
        named = f"the suffix {path.suffix.lower()}" if path.suffix else "a name without a suffix"
        return f"{said} (read as a text point list, x y z per line: {named} names no volume or mesh format)"
    return said


def _text_encoding(head: bytes) -> str:
    """How a point list's text is encoded, from its first bytes: UTF-16
    where it opens with UTF-16's byte-order mark (what Windows PowerShell's
    ``>`` and Notepad's "Unicode" write); UTF-16 LE or BE without one
    (some Windows tools write none) where the text unambiguously is: every
    other byte NUL, the bytes between printable ASCII, tabs and line ends,
    a digit among them; else UTF-8, a byte-order mark (Windows editors)
    skipped. Anything else with a NUL byte stays binary."""
    encoding = utf16_order(head)
    if encoding == "utf-16":
        return encoding
    if encoding is not None:
        # a point list's UTF-16 without a mark is held to ASCII text: its bytes between are that text
        chars = head[0::2] if encoding == "utf-16-le" else head[1::2]
        if not chars.translate(None, _ASCII_TEXT) and any(48 <= c <= 57 for c in chars):
            return encoding
    return "utf-8-sig"


#: the bytes of ASCII text a point list may hold: printable, tab, line ends
_ASCII_TEXT = bytes(range(32, 127)) + b"\t\n\r"


def _header_line(path: Path, encoding: str = "utf-8-sig") -> tuple[int, bool]:
    """The number of the line that is a header of column names (``x,y,z``,
    as pandas' ``to_csv`` writes one), 0 where there is none: the first
    line that is neither blank nor a comment, where none of its fields is
    a number and the next such line is as many numbers (a file of words is
    still refused naming its first line); and whether its first column is
    an index (``to_csv`` writes the frame's index first, named ``""``, or
    ``index`` after ``reset_index``), which is no coordinate: then 2 or 3
    names follow it. Those names may be ``0, 1, 2``: the column names
    pandas gives a frame made from an array (``pd.DataFrame(points)``);
    after an index's name that line cannot be a point."""
    lines = []
    with open(path, encoding=encoding) as fh:
        for lineno, line in enumerate(fh, 1):
            line = line.split("#", 1)[0].strip()
            if line:
                lines.append((lineno, line))
                if len(lines) == 2:
                    break
    if len(lines) < 2:
        return 0, False
    (lineno, first), (_, second) = lines
    # a header's names are split at commas where it has them ("x (mm), y (mm), z (mm)"), else at blanks
    names = [f.strip() for f in first.split(",")] if "," in first else first.split()
    numbers = _SPLIT.split(second)
    index = "," in first and len(names) in (3, 4) and names[0].lower() in ("", "index")
    # ",0,1,2": an array's frame, its index written first (without the index, "0,1,2" is a point)
    numbered = index and names[1:] == [str(i) for i in range(len(names) - 1)]
    if (len(names) != len(numbers) or len(names) - index not in (2, 3)
            or (any(_NUMBER.fullmatch(f) for f in names) and not numbered)
            or not all(_NUMBER.fullmatch(f) for f in numbers)):
        return 0, False
    return lineno, index


def _read_points_fast(path: Path, commas: bool, header: int = 0, index: bool = False,
                      encoding: str = "utf-8-sig") -> np.ndarray | None:
    """The points by ``np.loadtxt`` (as integers, else as decimals that
    must be integers: "1e3", "2.0"), or None where the file needs the
    line-by-line reader: to be refused with its line, or for separators
    loadtxt does not take (blanks and commas mixed). loadtxt's own parser
    refuses empty fields and "1_000"; it takes "nan" and "inf", refused
    here. The lines up to ``header`` (:func:`_header_line`) are skipped,
    and the first column where it is an ``index``."""
    import warnings

    for dtype in (np.int64, np.float64):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # "empty input file": said by the line reader
                values = np.loadtxt(path, comments="#", delimiter="," if commas else None, ndmin=2, dtype=dtype,
                                    encoding=encoding, skiprows=header)
            break
        except (ValueError, UnicodeDecodeError):
            continue
    else:
        return None
    if index:  # (read with the rest: a line whose index is no number is the line reader's to name)
        values = values[:, 1:]
    if values.size == 0 or values.shape[1] not in (2, 3):
        return None
    if dtype is np.float64 and not (np.isfinite(values).all() and (values == np.round(values)).all()):
        return None
    if dtype is np.float64 and float64_may_round(path, encoding):
        return None  # whole as float64, but maybe not as written: the line reader decides on the text
    if (values > MAX_COORDINATE).any() or (values < -MAX_COORDINATE).any():  # (abs overflows at int64's least)
        return None
    return values.astype(np.int64, copy=False)


def _read_points_by_line(path: Path, header: int = 0, index: bool = False, encoding: str = "utf-8-sig") -> np.ndarray:
    """The points, read line by line as a stream (8 bytes a coordinate, as
    loadtxt); the first bad line is refused with its number. The lines up
    to ``header`` (:func:`_header_line`) are skipped, and the first number
    of each line where it is an ``index``."""
    from array import array

    coords, width = array("q"), None
    with open(path, encoding=encoding) as fh:  # a byte-order mark (Windows editors) is no coordinate
        for lineno, line in enumerate(fh, 1):
            if lineno <= header:
                continue
            point = _point(path, lineno, line, width, index)
            if point:
                width = len(point)
                coords.extend(point)
    if not coords or width is None:
        raise IsoflowError(f"{path}: no points")
    return np.frombuffer(coords, dtype=np.int64).reshape(-1, width).copy()


def _point(path: Path, lineno: int, line: str, width: int | None, index: bool = False) -> list[int]:
    """The coordinates on one line of a point list (none for a blank or
    comment line), or the error naming the line; ``width``: the number of
    coordinates of the lines before (None for the first point); ``index``:
    the line's first number is its row's index, no coordinate."""
    line = line.split("#", 1)[0].strip()
    if not line:
        return []
    fields = _SPLIT.split(line)
    for f in fields:
        if not _NUMBER.fullmatch(f):
            shown = f"empty coordinate in {line!r}" if not f else f"not a number: {f!r}"
            raise IsoflowError(f"{path}:{lineno}: {shown}")
    fields = fields[index:]
    if width is None and len(fields) not in (2, 3):
        raise IsoflowError(f"{path}:{lineno}: expected 2 or 3 coordinates, got {len(fields)}")
    if width is not None and len(fields) != width:
        raise IsoflowError(f"{path}:{lineno}: expected {width} coordinates, got {len(fields)}")
    point = []
    for f in fields:
        v = float(f)  # "1e999" is inf: out of range, before round() fails on it
        if abs(v) > MAX_COORDINATE:  # 1e300 or int64 extremes overflow later
            raise IsoflowError(f"{path}:{lineno}: coordinate {f} is out of range (beyond +-{MAX_COORDINATE})")
        # a long number, or one of a negative exponent, may be whole as float64 alone (float64_may_round)
        if v != round(v) or ((len(f) > EXACT_RUN or "e-" in f or "E-" in f) and not whole_text(f)):
            raise IsoflowError(f"{path}:{lineno}: coordinate {f} is not an integer")
        point.append(int(round(v)))
    return point


#: characters of a number's digits and point beyond which float64 may
#: round a fraction away: 15 significant digits always read back exactly
EXACT_RUN = 16


def float64_may_round(path: Path, encoding: str = "utf-8-sig") -> bool:
    """Whether a text file of decimals may hold a number that float64 reads
    as whole but is not as written: one with a negative exponent (``1e-400``
    is 0.0) or more than :data:`EXACT_RUN` digits and points in a row
    (``1.00000000000000000001`` is 1.0). A number of 15 significant digits
    or fewer that reads as a whole float64 is that whole number: its
    distance to any other whole number is above float64's rounding.

    Parameters
    ----------
    path : Path
        The text file.
    encoding : str
        Its encoding, as :func:`read_points` finds it.

    Returns
    -------
    bool

    Examples
    --------
    >>> import tempfile
    >>> folder = Path(tempfile.mkdtemp())
    >>> _ = (folder / "whole.txt").write_text("2.0 3.000 1.5e1\\n")
    >>> _ = (folder / "long.txt").write_text("1.00000000000000000001 0 0\\n")
    >>> float64_may_round(folder / "whole.txt"), float64_may_round(folder / "long.txt")
    (False, True)
    """
    data = path.read_text(encoding=encoding).encode() if encoding.startswith("utf-16") else path.read_bytes()
    if b"e-" in data or b"E-" in data:
        return True
    # digits and points as "1", the rest as "0": a run of EXACT_RUN + 1 ones is a number float64 may round
    return b"1" * (EXACT_RUN + 1) in data.translate(_DIGITS_AS_ONES)


#: :func:`float64_may_round`'s table of bytes: digits and the point to "1"
_DIGITS_AS_ONES = bytes(49 if chr(b) in "0123456789." else 48 for b in range(256))


def whole_text(number: str) -> bool:
    """Whether a decimal number, as written, is a whole number: exactly,
    digit by digit, where float64 keeps 15 to 17 significant digits and
    so reads ``1.00000000000000000001`` as 1.

    Parameters
    ----------
    number : str
        A decimal number (``2.0``, ``1.5e1``, ``-3``).

    Returns
    -------
    bool

    Examples
    --------
    >>> whole_text("1.5e1"), whole_text("2.000"), whole_text("1.00000000000000000001")
    (True, True, False)
    """
    from decimal import Decimal

    exact = Decimal(number)
    return exact == exact.to_integral_value()


#: how :func:`read_object` reads a point list: cube corners (the paper's point model) or voxel indices
PointsAre = Literal["corners", "voxels"]


def read_object(path: str | os.PathLike, points_are: PointsAre = "corners",
                label: int | np.integer | float | None = None) -> DigitalObject:
    """A digital object from a volume file (any format of :func:`read_volume`,
    ``label`` selecting one value of a label image) or a point list.

    ``points_are='corners'`` reads a point list with the paper's point model
    (Definitions 1-2): the object is every cube whose 2^n corners are all
    listed; ``'voxels'`` takes each point as a voxel index.

    Parameters
    ----------
    path : str or os.PathLike
        A volume of any format of :func:`read_volume`, or a point list.
    points_are : {"corners", "voxels"}
        How a point list is read; ``"voxels"`` is refused for a volume
        (nothing of a volume is read as points).
    label : int or float, optional
        The value whose voxels are the object, in a label image.

    Returns
    -------
    DigitalObject

    Raises
    ------
    IsoflowError
        One line naming the file and the problem.

    Examples
    --------
    Example 19 of the paper: 20 points, 4 cubes (a corner cube and its three
    face neighbours).

    >>> from isoflow import data
    >>> read_object(data.example19()).voxels, read_object(data.example19(), points_are="voxels").voxels
    (4, 20)
    """
    path = check_path(path, "path", "read_object", "an array in memory: DigitalObject(array)")
    chosen = choice_of(points_are, get_args(PointsAre))  # the annotation binds type checkers only
    if chosen is None:
        raise IsoflowError(f"points_are must be 'corners' or 'voxels', got {given_text(points_are)}")
    points_are = chosen  # type: ignore[assignment]  # one of PointsAre, as just checked
    if is_volume(path):
        if points_are != "corners":  # the default, kept for any path; "voxels" would be ignored
            raise IsoflowError(f"{path}: points_are={points_are!r} applies to point lists (x y z per line, .txt), "
                               "not to volume input")
        return read_volume(path, label=label)
    path = Path(path)
    refuse_inside_store(path, path)  # (a group or array of a store is no point list)
    if label is not None:
        raise IsoflowError(f"{path}: a label selects voxels of a volume, not of a point list")
    pts = read_points(path)
    try:
        obj = DigitalObject.from_voxels(pts) if points_are == "voxels" else DigitalObject.from_points(pts)
    except IsoflowError as exc:  # e.g. the grid beyond the memory budget: say which file
        raise exc.at(path) from None
    if not obj.voxels and points_are == "corners":  # points, and no cube: say why, as the command line does
        warn(f"{path}: {no_cube_reason(obj.ndim, 'points_are=' + repr('voxels'))}")
    return obj


#: how :func:`no_cube_reason` starts (the command line, which says it in its own words, filters the warning by it)
NO_CUBE = "no unit "


def no_cube_reason(ndim: int, option: str) -> str:
    """Why a point list read with the paper's point model gave no voxel,
    naming ``option``, the spelling (Python's or the command line's) of
    the way that reads each point as a voxel.

    Examples
    --------
    >>> no_cube_reason(2, "--points-are voxels")[:45]
    'no unit square has all 4 of its corners among'
    """
    cell = "square" if ndim == 2 else "cube"
    return (f"{NO_CUBE}{cell} has all {2 ** ndim} of its corners among the points (the paper's point model, "
            f"Definitions 1-2); {option} reads each point as a voxel")



def write_bytes_per_voxel(path: str | os.PathLike, labels: bool = False) -> float:
    """Bytes per voxel that writing a mask to ``path`` holds beside it, at
    most, by the format its suffix names: what
    :func:`~isoflow.mesh.voxelize.voxelize` takes as ``write_bytes``, so
    that a grid let in can also be written (0 for a suffix isoflow does
    not write, which :func:`check_volume_output` refuses).

    Parameters
    ----------
    path : str or os.PathLike
        The output; its suffix names the format (``FILE.h5:/dataset`` too).
    labels : bool
        Bytes per byte of a label image's labels instead, what
        :func:`~isoflow.mesh.label_voxels.voxelize_meshes` takes as
        ``write_bytes``: a format may store labels in a type of its own
        (MGH's signed ones), which a mask's bytes need not.

    Returns
    -------
    float
        The bytes, from 0 on.

    Examples
    --------
    >>> write_bytes_per_voxel("seg.nii.gz"), write_bytes_per_voxel("stack.tif") > 1
    (0.0, True)
    >>> write_bytes_per_voxel("aseg.mgz"), write_bytes_per_voxel("aseg.mgz", labels=True)
    (0.0, 2.0)
    """
    fmt = format_for(split_dataset(path)[0], writing=True)
    if fmt is None:
        return 0.0
    return float(fmt.write_bytes if not labels or fmt.label_bytes is None else fmt.label_bytes)


def check_volume_output(path: str | os.PathLike, force: bool = False, ndim: int | None = None) -> tuple[Path, str | None]:
    """The file (and dataset) a volume will be written to, checked before
    any work: a suffix isoflow writes, its library installed, the path free
    (or ``force``), and with ``ndim`` a format that holds images of that
    dimension (``voxelize -o seg.png`` is refused before the voxelisation,
    not after it). Returns ``(file, dataset)``.

    Examples
    --------
    >>> check_volume_output("nowhere/seg.png", ndim=3)
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: nowhere/seg.png: PNG holds 2D images, this volume is 3D; write .tif, .nii.gz, .nrrd, \
.h5 or .npz
    """
    check_switch(force, "force", str(path))
    file, dataset = split_dataset(path)
    # ".nii.gz" would write a hidden file of no name and "-" a file named "-": refused as surfaces refuse them
    refuse_nameless(file, (".nii.gz", *volume_suffixes(writable=True)), "volume")
    fmt = format_for(file, writing=True)
    if fmt is None and Path(file).is_dir():  # "-o out/": say it is a directory, not only which suffixes are written
        raise IsoflowError(f"{path}: is a directory; give a file name for the volume, ending in "
                           f"{', '.join(volume_suffixes(writable=True))}")
    if fmt is None:
        raise IsoflowError(f"{path}: volumes are written as {', '.join(volume_suffixes(writable=True))}")
    if ndim is not None and ndim not in fmt.ndims:
        raise IsoflowError(f"{path}: {fmt.name} holds {' and '.join(f'{n}D' for n in fmt.ndims)} images, this volume is "
                           f"{ndim}D; write .tif, .nii.gz, .nrrd, .h5 or .npz")
    if dataset is None and not fmt.directory:  # split_dataset's Path dropped a trailing slash: check the path given
        refuse_directory_spelling(path, "volume")
    if dataset is not None and not fmt.datasets:
        whole = {"NumPy": " (an .npz is written whole: volume, offset, parity, pitch and origin)",
                 "NRRD": " (a layer of a 3D Slicer .seg.nrrd is read, not written)"}.get(fmt.name, "")
        raise IsoflowError(f"{path}: a dataset inside the file is written only for HDF5 and zarr{whole}")
    fmt.require()  # a missing library fails before anything is written
    # a zarr store is a directory: its module checks (and with force clears) it
    module = fmt.load()
    if hasattr(module, "check_output"):
        module.check_output(file, force, dataset)
    else:
        check_output_path(file, force)
    return file, dataset


def check_volume_suffix(suffix: str, where: str = "--volumes") -> str:
    """A suffix volumes are written with (``.nii.gz``; the dot may be left
    out), its library installed: checked before any work. Returns it with
    its dot."""
    given = suffix
    suffix = suffix if suffix.startswith(".") else "." + suffix
    fmt = format_for("step" + suffix, writing=True)
    if fmt is None:
        # named as given: an empty one ('', an unset shell variable) read as "."
        raise IsoflowError(f"{where} {given or repr(given)}: volumes are written as "
                           f"{', '.join(volume_suffixes(writable=True))}")
    fmt.require()
    return suffix


def check_volume_holds(path: str | os.PathLike, obj: DigitalObject | LabelVolume) -> None:
    """Refuse now, in one line, what the format of ``path`` could not hold
    of ``obj`` (a 2D object as binvox, a pitch per axis as MagicaVoxel),
    for work that writes such files later (the flow's step volumes); what
    a format would only drop is said when the file is written.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow import DigitalObject
    >>> check_volume_holds("run/step_000.binvox", DigitalObject(np.ones((3, 3), bool)))
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: run/step_000.binvox: binvox holds 3D voxels, this object is 2D
    """
    import warnings

    file, dataset = split_dataset(path)  # FILE.h5:/cells.vox is HDF5, whatever its dataset's name
    fmt = format_for(file, writing=True)
    module = None if fmt is None else fmt.load()
    if module is not None and hasattr(module, "check"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            module.check(file, obj, dataset)


def write_volume(obj: DigitalObject | ArrayLike, path: str | os.PathLike, force: bool = False, *,
                 unit: str | None = None) -> Path:
    """Save an object in the format its suffix names (``FILE.h5:/dataset``:
    a dataset of an HDF5 file, new or existing, whose other datasets are
    kept), with its voxel size and origin, and their length ``unit``, where
    the format has room for them; a warning says what a format cannot keep.
    Refuses an existing file (or dataset) unless ``force``. Returns the
    file's path.

    ``.npz`` keeps everything (offset and parity too); the other formats keep the world position of every voxel (see
    the table of docs/formats.md). An object's ``space`` (its anatomical
    frame, ``"LPS"`` as a 3D Slicer NRRD's) is written in the format's own:
    NIfTI and MGH in RAS, the world axes that point the other way negated;
    NRRD as its ``space`` field; ``.npz`` and HDF5 as isoflow's ``space``
    beside ``unit``; a warning names it where the format has no place for
    one.
    The file is written beside the target and renamed when complete, so an
    interrupted write leaves any previous file as it was.

    Parameters
    ----------
    obj : DigitalObject
        The object (a bare binary array is taken at the origin; an array
        of 0 and one other value, 0/255 or 0/-1, as that value's mask, as
        :func:`read_volume` reads such an array from a file).
    path : str or os.PathLike
        The file; its suffix names the format (``FILE.h5:/dataset`` too).
    force : bool
        Replace an existing file (``FILE.h5:/dataset``: only that dataset).
    unit : str, optional
        The length unit of the object's pitch and origin, in any spelling
        :func:`~isoflow.digital.units.length_unit` reads
        (``"mm"``, ``"micron"``, ``"micrometer"``, ...), as
        :func:`read_volume_with_unit` gives it; written in the format's own
        spelling where it has one (docs/formats.md, "Length unit"), else
        said in a warning. None: the object's ``unit`` (as
        :func:`read_volume` sets it from its file; none if it has none).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    IsoflowError
        An existing file without ``force``, a suffix isoflow does not write,
        a library missing, an unwritable place, a ``unit`` that is no length
        unit.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> import numpy as np
    >>> from isoflow import DigitalObject
    >>> obj = DigitalObject(np.ones((2, 3, 4), bool), pitch=0.5, origin=(1.0, 2.0, 3.0))
    >>> path = write_volume(obj, pathlib.Path(tempfile.mkdtemp()) / "box.npz")
    >>> back = read_volume(path)
    >>> back.voxels, float(back.pitch), back.origin.tolist()
    (24, 0.5, [1.0, 2.0, 3.0])

    With its length unit, which a NIfTI file keeps in its header:

    >>> path = write_volume(obj, pathlib.Path(tempfile.mkdtemp()) / "box.nii.gz", unit="millimeter")
    >>> read_volume(path).unit
    'mm'

    The object read keeps it, and writes it again:

    >>> read_volume(write_volume(read_volume(path), pathlib.Path(tempfile.mkdtemp()) / "box.nrrd")).unit
    'mm'
    """
    path = check_path(path, "path", "write_volume",
                      hint="the object comes first: write_volume(obj, path)" if isinstance(obj, (str, os.PathLike)) else "")
    try:
        obj = DigitalObject.of(obj, "write_volume")
    except NotBinary as exc:
        # an array of 0 and one other value (0/255, 0/-1, 0/0.5) is that value's mask, as the file readers
        # read the same array: what they read as a mask is written as one, and reads back as the same mask
        mask = one_value_mask(obj) if isinstance(obj, np.ndarray) else obj
        if mask is not obj:
            return write_volume(mask, path, force, unit=unit)
        if exc.kind != "labels" or not exc.every or isinstance(obj, DigitalObject) or np.ndim(obj) not in (2, 3):
            raise
        # a label image (2D or 3D, as write_labels takes it) is written as one by write_labels: a table is no file
        raise NotBinary(f"{exc.bare}, or write its labels with isoflow.write_labels(labels, path)", exc.bare,
                        every=exc.every, ndim=exc.ndim, kind=exc.kind, value=exc.value) from None
    return write_placed(obj, path, force, unit=obj.unit if unit is None else unit_given(unit, "write_volume"),
                        space=obj.space)


def write_placed(obj: DigitalObject | LabelVolume, path: str | os.PathLike, force: bool = False,
                 unit: str | None = None, space: str | None = None) -> Path:
    """:func:`write_volume` of a digital object or a placed label image,
    ``unit`` in isoflow's spelling (:func:`~isoflow.digital.units.length_unit`),
    ``space`` the anatomical frame of its world axes
    (:func:`~isoflow.digital.frames.space_given`), which the format's writer
    turns into its own frame or says it does not keep."""
    file, dataset = check_volume_output(path, force)
    fmt = format_for(file, writing=True)
    assert fmt is not None, "check_volume_output refuses a suffix that no format writes"
    module = fmt.load()
    import warnings

    # refusals come before the write; what the format drops is said once the
    # file is written: of a write that failed it would be a second line
    # about a file that is not there
    with warnings.catch_warnings(record=True) as dropped:
        warnings.simplefilter("always")
        if hasattr(module, "check"):
            module.check(file, obj, dataset, unit=unit, space=space)
    # whole or not at all: written beside the target, renamed when complete
    with atomic_path(file, directory=file.suffix.lower() == ".zarr") as tmp:
        if fmt.datasets and dataset is not None:  # FILE.h5:/name: the file's other datasets are kept
            module.write(tmp, obj, dataset, name=file.name, into=file, unit=unit, space=space)
        else:
            module.write(tmp, obj, dataset, name=file.name, unit=unit, space=space)
    for w in dropped:
        warn(str(w.message), w.category)
    return file


def check_label_output(path: str | os.PathLike, count: int, force: bool = False) -> tuple[Path, str | None]:
    """:func:`check_volume_output` for a label image of labels 1 .. ``count``:
    also refused, before any work, where the format keeps fewer labels
    (binvox a bit per voxel, MagicaVoxel 255 colours, ImageJ TIFF 16 bits)."""
    file, dataset = check_volume_output(path, force)
    refuse_label_count(path, count)
    return file, dataset


def refuse_label_count(path: str | os.PathLike, count: int) -> None:
    """Refuse, in one line, a label image of labels 1 .. ``count`` where
    the format of ``path`` keeps fewer labels (binvox a bit per voxel,
    MagicaVoxel 255 colours, ImageJ TIFF 16 bits): the part of
    :func:`check_label_output` left once the path itself is checked
    (:func:`check_volume_output`, before the labels are counted).

    Parameters
    ----------
    path : str or os.PathLike
        The output; its suffix names the format.
    count : int
        The largest label.

    Raises
    ------
    IsoflowError
        Where the format keeps fewer labels.

    Examples
    --------
    >>> refuse_label_count("cells.vox", 12)
    >>> refuse_label_count("cells.binvox", 2)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: cells.binvox: binvox keeps one label (a bit per voxel), this image's labels go up to 2; ...
    """
    fmt = format_for(split_dataset(path)[0], writing=True)
    if fmt is not None and fmt.max_label is not None and count > fmt.max_label:
        keeps = "one label (a bit per voxel)" if fmt.max_label == 1 else f"labels up to {fmt.max_label}"
        raise IsoflowError(f"{path}: {fmt.name} keeps {keeps}, this image's labels go up to {count}; write "
                           ".nii.gz, .nrrd, .h5 or .npz")


def write_labels(labels: ArrayLike | LabelImage, path: str | os.PathLike, *, pitch: float | ArrayLike | None = None,
                 origin: ArrayLike | None = None, force: bool = False, unit: str | None = None,
                 names: Mapping[int, str] | Sequence[str] | None = None) -> Path:
    """Save a label image in the format its suffix names, in its own integer type
    (a signed one as the unsigned type of its width).

    A bool image is written as uint8 labels 0 and 1, a float image of whole
    numbers (as NIfTI's scaling gives) in the smallest unsigned type that
    holds its labels: the images :func:`isoflow.label_table` takes.

    Parameters
    ----------
    labels : array_like
        Integers from 0 on in (x, y, z) order, or (x, y) for a 2D image (a
        cell segmentation, a section's grain map: the formats that hold 2D,
        not binvox or MagicaVoxel; PNG holds 2D only); 0 is the
        background; or a bool image, or a float image of whole numbers
        from 0 on. Not 4D:
        :func:`read_labels` would not read it back. Or a
        :class:`~isoflow.LabelImage`, as :func:`read_labels` gives it, with
        its voxel size, origin, length unit and anatomical frame (written
        as :func:`write_volume` writes an object's ``space``).
    path : str or PathLike
        The file; its suffix names the format (NIfTI, NRRD, HDF5, TIFF,
        OME-Zarr, ``.npz``, ...).
    pitch : float or array_like, optional
        The voxel size, one value or one per axis, kept where the format
        has room for it (if None: a LabelImage's spacing, else 1).
    origin : array_like, optional
        The lower corner of voxel (0, 0, 0) in world units (if None: a
        LabelImage's origin, else zero),
        kept where the format has room for it: not in ``.npy`` or
        MagicaVoxel, which a warning says (docs/labels.md lists what each
        format keeps).
    force : bool
        Overwrite an existing file.
    unit : str, optional
        The length unit of the voxel size and origin, in any spelling
        :func:`~isoflow.digital.units.length_unit` reads (if None:
        a LabelImage's ``unit``, else none); one given replaces a
        LabelImage's, as ``pitch`` and ``origin`` do. Written where the
        format has room for it (docs/formats.md, "Length unit"), else said
        in a warning.
    names : mapping of int to str, or sequence of str, optional
        What each label is: label value to name, or the names of labels 1,
        2, ... in order (if None: a LabelImage's ``names``; an empty
        mapping means no names, a LabelImage's too). Written where
        the format has a place for them: a NRRD as 3D Slicer's segments
        (``Segment{k}_Name``, ``Segment{k}_LabelValue``, ...), OME-Zarr as
        the ``image-label`` ``properties``, HDF5 as the dataset's
        attribute ``label_names`` and ``.npz`` as the array
        ``label_names`` (both JSON: label to name); the other formats have
        none, which a warning says.

    Returns
    -------
    Path
        The file written; :func:`read_labels` reads it back, with its names.

    Raises
    ------
    IsoflowError
        For an existing file without ``force``, an array that is not 2D or
        3D integers, bools or floats, a negative label, a float that is no
        whole number (NaN, 1.5: its voxel named), a 2D image for a format
        of 3D only (binvox, MagicaVoxel), a 3D image for PNG (2D only), a
        format that keeps fewer labels than the image has
        (:func:`check_label_output`), a ``unit`` that is no length unit, a
        name that is no string of one line or a label named that is no
        integer from 1 on (read_labels names a signed image's negative
        labels; this writes none).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> labels = np.zeros((3, 2, 2), np.uint8)
    >>> labels[0], labels[2] = 1, 2
    >>> path = write_labels(labels, pathlib.Path(tempfile.mkdtemp()) / "labels.npz", pitch=0.5, origin=(1, 2, 3))
    >>> back = read_labels(path)
    >>> np.array_equal(back.array, labels), back.spacing.tolist(), back.origin.tolist()
    (True, [0.5, 0.5, 0.5], [1.0, 2.0, 3.0])

    A 2D label image, placed by two numbers:

    >>> cells = np.array([[1, 1, 0], [0, 2, 2]], np.uint16)
    >>> back = read_labels(write_labels(cells, pathlib.Path(tempfile.mkdtemp()) / "cells.nii.gz", pitch=(0.5, 0.25)))
    >>> np.array_equal(back.array, cells), back.spacing.tolist()
    (True, [0.5, 0.25])

    A label image read from one file, written to another with its place:

    >>> again = read_labels(write_labels(back, pathlib.Path(tempfile.mkdtemp()) / "cells.nrrd"))
    >>> np.array_equal(again.array, cells), again.spacing.tolist()
    (True, [0.5, 0.25])

    With a length unit, which the next write of the image read back keeps:

    >>> first = read_labels(write_labels(cells, pathlib.Path(tempfile.mkdtemp()) / "cells.tif", unit="micron"))
    >>> first.unit, read_labels(write_labels(first, pathlib.Path(tempfile.mkdtemp()) / "cells.nrrd")).unit
    ('\u00b5m', '\u00b5m')

    With the names of its labels, which the file keeps:

    >>> named = write_labels(cells, pathlib.Path(tempfile.mkdtemp()) / "cells.nrrd", names=["nucleus", "cytoplasm"])
    >>> read_labels(named).names
    {1: 'nucleus', 2: 'cytoplasm'}
    """
    path = check_path(path, "path", "write_labels",
                      hint="the labels come first: write_labels(labels, path)" if isinstance(labels, (str, os.PathLike)) else "")
    unit = unit_given(unit, "write_labels")
    names = label_names(names, "write_labels: names")
    if isinstance(labels, LabelImage):  # its place and names, unless given, as label_table takes it
        pitch = labels.spacing if pitch is None else pitch
        origin = labels.origin if origin is None else origin
        # a unit read from a file is kept as the file spelled it where isoflow knows no other spelling
        unit = length_unit(labels.unit) if unit is None else unit
        names = labels.names if names is None else names
        # the frame goes with the place it is of: a pitch and origin given replace the image's, not its frame
        space = labels.space
        labels = labels.array
    else:
        space = None
    pitch = 1.0 if pitch is None else pitch
    # an object, a mesh or a path: NumPy would make each a 0D array, refused for its shape, not named
    where = "write_labels: labels"
    refuse_object(labels, where, reader="isoflow.read_labels",
                  then="and its place, pitch=obj.spacing, origin=obj.origin; or write_volume(obj, path) writes it")
    arr = as_array(labels, where)
    if arr.ndim == 4:
        # read_labels and label_table take 2D and 3D only: a file this wrote should read back
        raise IsoflowError(f"{where}: a label image is written in 2D or 3D, as read_labels reads it back; this one "
                           "is 4D (np.save keeps it, and read_volume(path, label=N) reads one label of it as 4D)")
    if arr.ndim not in (2, 3) or arr.dtype.kind not in "biuf":
        raise IsoflowError(f"{where}: a label image is a 3D or 2D array of integers (or bools, or floats of whole "
                           f"numbers), got {arr.ndim}D {arr.dtype}")
    arr = _unsigned_labels(arr, where)
    if names and min(names) < 0:
        # read_labels names a signed image's negative labels; a file written here holds none of them
        raise IsoflowError(f"write_labels: names: a label name is given for {min(names)}, and write_labels writes "
                           "labels from 0 on (a negative label is refused)")
    # the pitch and origin checked as every object's are, before the file
    # is written: the format stores whatever it is given
    place = DigitalObject.placement(arr.ndim, pitch=pitch, origin=origin, function="write_labels")
    # a 2D image is refused as 2D by the formats that hold 3D only, before its labels are counted against theirs
    check_volume_holds(path, LabelVolume(arr, place.pitch, place.origin, offset=(0,) * arr.ndim))
    file = check_label_output(path, int(arr.max(initial=0)), force)[0]
    fmt = format_for(file, writing=True)
    if fmt is not None and fmt.max_label is not None and arr.dtype.itemsize > np.min_scalar_type(fmt.max_label).itemsize:
        # a format of few labels stores them in its own type (ImageJ TIFF: 8 or
        # 16 bits, whatever the array's); they fit, as just checked
        arr = arr.astype(np.min_scalar_type(fmt.max_label))
    written = write_placed(LabelVolume(arr, place.pitch, place.origin, offset=(0,) * arr.ndim, names=names or None), path,
                           force, unit=unit, space=space)
    if names and not keeps_names(file):
        # said once the file is there, as what a format drops of the placement is
        warn(f"{path}: {names_not_kept(path, len(names))}")
    return written


def keeps_names(path: str | os.PathLike) -> bool:
    """Whether the label image file ``path`` (its suffix) has a place for
    label names (docs/labels.md, "Label files").

    Examples
    --------
    >>> keeps_names("seg.nrrd"), keeps_names("seg.h5:/labels"), keeps_names("seg.nii.gz"), keeps_names("seg.npy")
    (True, True, False, False)
    """
    file = split_dataset(path)[0]
    fmt = format_for(file, writing=True)
    return fmt is not None and file.name.lower().endswith(fmt.names_in)


def names_not_kept(path: str | os.PathLike, count: int) -> str:
    """What is said of the file ``path`` where names of ``count`` labels
    are given and its format has no place for them (:func:`keeps_names`).

    Examples
    --------
    >>> names_not_kept("seg.nii.gz", 2)
    'NIfTI has no place for label names; the names of 2 labels are not written (.nrrd, .h5, .zarr and .npz keep them)'
    """
    fmt = format_for(split_dataset(path)[0], writing=True)
    return (f"{fmt.name if fmt is not None else 'this format'} has no place for label names; the names of "
            f"{counted(count, 'label')} are not written (.nrrd, .h5, .zarr and .npz keep them)")


def _unsigned_labels(arr: np.ndarray, where: str) -> np.ndarray:
    """The labels of an image of integers, bools or floats as unsigned
    integers, as :func:`write_labels` writes them; a value that is no label
    (negative, NaN, not whole) is refused naming its voxel after ``where``
    (the function and its argument)."""
    labels = arr
    if arr.dtype.kind in "bf":
        try:  # as label_table takes them: a bool image as uint8 0 and 1, whole floats as int64
            labels = as_labels(arr)
        except IsoflowError as exc:
            raise exc.at(where) from None
    if labels.dtype.kind == "i":
        # signed labels (an int16 or int32 NIfTI read back, scipy.ndimage.label's and scikit-image's
        # label's output): written as the unsigned type of their width, whose bits are the same for
        # labels from 0 on (a view, no copy)
        if labels.size and labels.min() < 0:
            at = np.unravel_index(int(np.argmin(labels)), labels.shape)
            raise IsoflowError(f"{where}: a label image holds labels from 0 on, this one holds {arr[at].item()!r} at "
                               f"{'pixel' if arr.ndim == 2 else 'voxel'} ({', '.join(str(int(i)) for i in at)})")
        labels = labels.view(labels.dtype.str.replace("i", "u"))
    if arr.dtype.kind == "f":
        # a float image has no integer type of its own, and label_table's int64 would make every file
        # 8 bytes a voxel: the smallest type that holds its labels
        labels = labels.astype(np.min_scalar_type(int(labels.max(initial=0))), copy=False)
    return labels
