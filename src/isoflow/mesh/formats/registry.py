"""Which module reads and writes which volume format, chosen by suffix.

Every format module has ``read(path, dataset) -> RawVolume`` and
``write(path, obj, dataset, name)``, and may have ``check(path, obj,
dataset)``: what the format cannot hold refused, and what it drops said,
before anything is written and naming the output as given (``write`` gets
a temporary path beside it, and ``name``, the output's file name, for
formats that store one). It imports its library
only inside those functions, so ``import isoflow`` stays cheap and a missing
library costs nothing until its suffix is used. :func:`isoflow.mesh.volumes.read_volume`
and :func:`~isoflow.mesh.volumes.write_volume` dispatch through
:func:`format_for`, so every command gets every format at once.

A reader returns the array in isoflow's axis order (axis 0 is x, 1 is y, 2
is z: what ``DigitalObject.world`` maps to world x, y, z), the voxel size per
axis and the world position of voxel ``(0, 0, 0)``'s lowest corner; each
module's docstring says how the format's own axes map to these.
"""

from __future__ import annotations

import contextlib
import importlib
import logging
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ...digital.frames import frame_text
from ...digital.lattice import DigitalObject
from ...digital.units import LENGTH_UNITS, length_unit, unit_factor
from ...errors import IsoflowError, coordinates, given_text, number_text, scalar_given, warn, whole_given, with_article
from ...scale.chunks import fourth_axis_name, spatial_axes, split_store

#: the extra that brings every format library (pip install 'isoflow[formats]')
EXTRA = "formats"


@dataclass(frozen=True)
class VolumeFormat:
    """A volume format: its name, suffixes, module and library."""

    name: str
    suffixes: tuple[str, ...]
    module: str  # under isoflow.mesh.formats
    library: str | None  # the pip package it needs beyond isoflow's own dependencies
    #: a path may name a dataset inside the file: FILE.h5:/group/volume
    datasets: bool = False
    #: ... when reading only (an .npz's arrays: it is written whole; a
    #: 3D Slicer .seg.nrrd's layers: FILE.seg.nrrd:1)
    read_datasets: bool = False
    #: the module the library installs, when it differs from the package name
    imports: str | None = None
    #: suffixes read but not written (a detached header needs a second file)
    read_only: tuple[str, ...] = ()
    #: written as a directory (a store), so ``-o NAME/`` names it
    directory: bool = False
    #: the largest label a label image written in it keeps (None: any unsigned integer)
    max_label: int | None = None
    #: the dimensions of the images it writes, where not both 2D and 3D
    ndims: tuple[int, ...] = (2, 3)
    #: bytes per voxel that its writer holds beside a mask of a byte per
    #: voxel, at most (its own copies, a library's, a compressed stream
    #: kept in memory; a writer that works through a buffer of fixed size
    #: holds none), so that a volume is let in only where it can also be
    #: written; benchmarks/bench_write_memory.py measures them
    write_bytes: float = 0
    #: ... beside a label image, per byte of its labels, where that differs
    #: (None: ``write_bytes``)
    label_bytes: float | None = None
    #: the suffixes of its files that keep label names (docs/labels.md)
    names_in: tuple[str, ...] = ()

    def load(self):
        """The format's module (its library is imported only when used)."""
        return importlib.import_module(f"{__package__}.{self.module}")

    def require(self):
        """The format's library, or one line naming the extra that brings it."""
        if self.library is not None:
            return import_library(self.imports or self.library, self.name, self.library)
        return None


FORMATS = (
    VolumeFormat("NumPy", (".npy", ".npz"), "npy", None, read_datasets=True, names_in=(".npz",)),
    # ImageJ: 8 or 16 bits; tifffile writes a z, y, x copy
    VolumeFormat("TIFF", (".tif", ".tiff"), "tiff", "tifffile", max_label=2**16 - 1, write_bytes=1.05),
    VolumeFormat("NIfTI", (".nii", ".nii.gz"), "nifti", "nibabel"),
    # FreeSurfer's volumes (aseg.mgz); labels in int32 at most; a mask's bytes are written as they are,
    # labels as a copy in MGH's signed types: uint16 above 32767 as int32, twice their bytes
    VolumeFormat("MGH", (".mgh", ".mgz"), "mgh", "nibabel", max_label=2**31 - 1, label_bytes=2),
    # a header and its image beside it, either named: Analyze 7.5, or a NIfTI pair
    VolumeFormat("Analyze", (".hdr", ".img"), "analyze", "nibabel", read_only=(".hdr", ".img")),
    # pynrrd copies the bytes in Fortran order (a byte a byte) and gzips that copy into the file a piece at a time
    VolumeFormat("NRRD", (".nrrd", ".nhdr"), "nrrd", "pynrrd", read_datasets=True, imports="nrrd",
                 read_only=(".nhdr",), write_bytes=1.3, names_in=(".nrrd",)),
    # the file is built in memory (HDF5's core driver) and copied out whole: its gzip stream is held two to
    # three times, as the image grows and as its copy; a random mask's bytes shrink to a sixth, random
    # labels' not at all
    # .hdf: CREMI's files (HDF5; HDF4 used the suffix too, and a refusal of such a file names it)
    VolumeFormat("HDF5", (".h5", ".hdf5", ".he5", ".hdf"), "hdf5", "h5py", datasets=True, write_bytes=0.6,
                 label_bytes=2.5, names_in=(".h5", ".hdf5", ".he5", ".hdf")),
    # a bit per voxel; run-length coded a slab at a time
    VolumeFormat("binvox", (".binvox",), "binvox", None, max_label=1, ndims=(3,)),
    # colour indices; its voxels are listed by their coordinates (at most 256 a side), built a slab at a time
    # into a byte each of x, y, z and colour (4 bytes a voxel set) beside one slab's indices
    VolumeFormat("MagicaVoxel", (".vox",), "magicavoxel", None, max_label=255, write_bytes=4.5, ndims=(3,)),
    # a z, y, x copy (a byte a byte), and the chunks zarr encodes at once (a few, of 128^3 voxels each)
    VolumeFormat("OME-Zarr", (".zarr", ".ome.zarr"), "omezarr", "zarr", datasets=True, directory=True,
                 write_bytes=1.6, names_in=(".zarr",)),
    # 2D masks and label images as many segmentations save them; Pillow comes with matplotlib
    # its 2D images only, in 8- or 16-bit grey; the array turned to rows and
    # its mask made 0/255 are copies, and Pillow holds one more
    VolumeFormat("PNG", (".png",), "png", None, imports="PIL", max_label=2**16 - 1, write_bytes=2, ndims=(2,)),
)


def volume_suffixes(writable: bool = False) -> tuple[str, ...]:
    """Every volume suffix isoflow reads (or writes)."""
    return tuple(s for f in FORMATS for s in f.suffixes if not writable or s not in f.read_only)


#: the files in which ``FILE:NAME`` names a dataset, an array, a level or
#: a layer (of a 3D Slicer segmentation)
_CONTAINERS = ("h5", "hdf5", "he5", "hdf", "npz", "zarr", "nrrd", "nhdr")


def split_dataset(path) -> tuple[Path, str | None]:
    """``FILE.h5:/group/volume`` -> (FILE.h5, '/group/volume'); ``IMG.zarr:1``
    (or ``IMG.zarr/:1``) -> (IMG.zarr, '1'), a resolution level; ``ARCHIVE.npz:seg`` -> one of
    its arrays (read only); ``SEG.seg.nrrd:1`` -> a layer of a 3D Slicer
    segmentation (read only); any other path -> (path, None).

    Only after an HDF5, zarr, npz or NRRD suffix, so that ``C:\\data\\a.nii`` stays a path."""
    return split_store(path, _CONTAINERS)


def format_for(path, writing: bool = False) -> VolumeFormat | None:
    """The format of ``path`` by its suffix (longest match, any case); None
    for what is not a volume (a point list, a mesh), or, ``writing``, not a
    volume isoflow writes."""
    name = Path(path).name.lower()
    best = None
    for f in FORMATS:
        for s in f.suffixes:
            if writing and s in f.read_only:
                continue
            if name.endswith(s) and (best is None or len(s) > len(best[1])):
                best = (f, s)
    return None if best is None else best[0]


#: the first bytes of the volume formats that have a magic number, with
#: the format's name (as in FORMATS) and the suffix its reader takes
MAGIC = (
    (b"\x93NUMPY", "NumPy", ".npy"),
    (b"PK\x03\x04", "NumPy", ".npz"),
    (b"II*\x00", "TIFF", ".tif"),
    (b"MM\x00*", "TIFF", ".tif"),
    (b"II+\x00", "TIFF", ".tif"),
    (b"MM\x00+", "TIFF", ".tif"),
    (b"NRRD000", "NRRD", ".nrrd"),
    (b"\x89HDF\r\n\x1a\n", "HDF5", ".h5"),
    (b"#binvox", "binvox", ".binvox"),
    (b"VOX ", "MagicaVoxel", ".vox"),
    (b"\x89PNG\r\n\x1a\n", "PNG", ".png"),
)

#: HDF4's first bytes: a ``.hdf`` may hold HDF4 (HDF5's predecessor, of
#: satellite and older microscope data), which h5py does not read
HDF4 = b"\x0e\x03\x13\x01"


def sniff_volume_format(path) -> tuple[str, str] | None:
    """The volume format a file's first bytes say it holds, as ``(name,
    suffix)``, or None: a magic number of :data:`MAGIC`, NIfTI's ``n+1`` or
    ``n+2`` (a ``.nii.gz`` where that lies in a gzip stream), a FreeSurfer MGH
    header (an ``.mgz`` where that lies in a gzip stream).

    Parameters
    ----------
    path : str or os.PathLike
        The file; only its first bytes are read (of a gzip stream, its
        first bytes once inflated).

    Returns
    -------
    tuple of str, or None
        The format's name and the suffix its reader takes.

    Examples
    --------
    >>> import os, tempfile
    >>> with tempfile.TemporaryDirectory() as d:
    ...     _ = open(os.path.join(d, "scan.nii"), "wb").write(b"II*" + bytes(100))
    ...     sniff_volume_format(os.path.join(d, "scan.nii"))
    ('TIFF', '.tif')
    """
    import gzip
    import zlib

    try:
        with open(path, "rb") as fh:
            head = fh.read(352)
        if head.startswith(b"\x1f\x8b"):
            with gzip.open(path, "rb") as fh:
                inner = fh.read(352)
            return ("NIfTI", ".nii.gz") if _nifti(inner) else ("MGH", ".mgz") if _mgh(inner) else None
    # unreadable, a gzip stream cut short in its header, or damaged deflate
    # data (zlib's own error, no OSError): no content to name
    except (OSError, EOFError, zlib.error):
        return None
    if _nifti(head):
        return ("NIfTI", ".nii")
    found = next(((name, suffix) for magic, name, suffix in MAGIC if head.startswith(magic)), None)
    if found is None and _mgh(head):
        return ("MGH", ".mgh")
    if found == ("NumPy", ".npz") and not _npz(path):
        return None  # a zip archive of something else
    return found


def _npz(path) -> bool:
    """Whether a zip archive holds ``.npy`` files alone, as an ``.npz`` does."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as z:
            names = z.namelist()
    except (OSError, zipfile.BadZipFile):
        return False
    return bool(names) and all(n.endswith(".npy") for n in names)


def _nifti(head: bytes) -> bool:
    """Whether a file's first bytes are a NIfTI-1 or NIfTI-2 header."""
    return head[344:348] == b"n+1\x00" or head[4:8] == b"n+2\x00"


def _mgh(head: bytes) -> bool:
    """Whether a file's first bytes are a FreeSurfer MGH header: version 1,
    four sizes from 1 on and a type FreeSurfer writes (uchar, int, float,
    short, ushort), big-endian, as nibabel's ``MGHHeader`` reads them."""
    import struct

    if len(head) < 24:
        return False
    version, *dims, kind = struct.unpack(">6i", head[:24])
    return version == 1 and min(dims) >= 1 and kind in (0, 1, 3, 4, 10)


def content_hint(path, what: str) -> str:
    """What to add to a refusal of ``path`` as a ``what`` file where its
    content is another volume format: ``; its content is TIFF, not NIfTI:
    rename it scan.tif``, or is NIfTI or MGH compressed where the name says
    uncompressed or the other way round (nibabel goes by the name);
    nothing otherwise."""
    found = sniff_volume_format(path)
    name = Path(path).name
    if found is None:
        return _hdf4_hint(path) if what == "HDF5" else ""
    if found[0] == what:
        packed = found[1] in (".nii.gz", ".mgz")
        if what not in ("NIfTI", "MGH") or packed == name.lower().endswith((".gz", ".mgz")):
            return ""
        content = f"{'gzip-compressed' if packed else 'uncompressed'} {what}"
    else:
        content = f"{found[0]}, not {what}"
    fmt = format_for(name)
    stem = name
    if fmt is not None:  # the suffix the name has, as format_for matched it
        stem = name[: -max(len(s) for s in fmt.suffixes if name.lower().endswith(s))]
    return f"; its content is {content}: rename it {stem}{found[1]}"


def _hdf4_hint(path) -> str:
    """What to add to a refusal of an HDF4 file read as HDF5: how to
    convert it; nothing for any other content."""
    try:
        with open(path, "rb") as fh:
            hdf4 = fh.read(len(HDF4)) == HDF4
    except OSError:
        return ""
    return "; its content is HDF4, not HDF5: convert it with the HDF Group's h4toh5" if hdf4 else ""


def import_library(module: str, fmt: str, package: str | None = None):
    """``module`` imported, or one line naming the extra that brings it."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise IsoflowError(
            f"{fmt} files need {package or module}: pip install 'isoflow[{EXTRA}]' ({exc})"
        ) from None


@contextlib.contextmanager
def reading(path, what: str):
    """Turn whatever a library raises on a damaged or foreign file into one
    IsoflowError line naming the file and the format."""
    try:
        yield
    except (IsoflowError, MemoryError):
        raise
    except Exception as exc:  # libraries raise many types for a bad file
        if os.path.isfile(path) and os.path.getsize(path) == 0:
            # what a library says of no bytes at all rarely names it (pynrrd: "StopIteration")
            raise IsoflowError(f"{path}: an empty file (0 bytes), not a readable {what} file") from None
        detail = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        kind = exc.__class__.__name__
        if kind == "error":  # zlib's (damaged deflate data) and the like: "error" alone says nothing
            kind = f"{exc.__class__.__module__}.{kind}"
        raise IsoflowError(
            f"{path}: not a readable {what} file ({kind}{': ' + detail if detail else ''})"
            + content_hint(path, what)
        ) from None


@contextlib.contextmanager
def quiet_logs(logger: str):
    """Silence a library's logger while it reads a file: what it logs about
    a damaged file (nibabel prints its checks on stderr, tifffile logs
    before raising) is said by the one error line, or is no concern of the
    user's when the file reads. Yields the list of the messages it logged
    at level ERROR or above: tifffile logs a page it cannot reach (a file
    cut short) and reads on, so a reader can refuse what it read."""
    log = logging.getLogger(logger)
    errors: list[str] = []
    keep = _KeepErrors(errors)
    saved = log.handlers[:], log.propagate, log.disabled
    log.handlers, log.propagate, log.disabled = [keep], False, False
    try:
        yield errors
    finally:
        log.handlers, log.propagate, log.disabled = saved


class _KeepErrors(logging.Handler):
    """A handler that keeps the messages of error records and prints nothing."""

    def __init__(self, errors: list[str]) -> None:
        super().__init__(logging.ERROR)
        self.errors = errors

    def emit(self, record: logging.LogRecord) -> None:
        try:
            self.errors.append(record.getMessage())
        except Exception:  # arguments that do not fit the message: the message itself
            self.errors.append(str(record.msg))


@dataclass
class RawVolume:
    """What a reader found: the array in isoflow's (x, y, z) order and where
    it sits. ``paint``: the values are colours, not labels, so any nonzero
    voxel is in the object unless one value is selected (MagicaVoxel).
    ``fill``: a zarr array's fill value, which it reads for a chunk never
    written (a refusal of that value says so); None for other formats.
    ``unwritten``: ``(fill, missing, total)`` where that fill value
    is a nonzero whole number and chunks were never written (see
    :func:`~isoflow.scale.chunks.never_written`); None otherwise.
    ``said``: a warning that depends on the label selected (a TIFF
    MinIsWhite's), called with it (None where none is, or for a label
    table) and said where it gives a line; None where there is none."""

    array: np.ndarray
    pitch: float | np.ndarray = 1.0
    origin: np.ndarray | None = None
    offset: tuple[int, ...] | None = None
    parity: int = 0
    paint: bool = False
    fill: object = None
    unwritten: tuple[int, int, int] | None = None
    #: the length unit of ``pitch`` and ``origin`` as the file says it, in
    #: one spelling (:func:`length_unit`); None where the file says none
    unit: str | None = None
    #: the anatomical frame of the world axes (``"RAS"``, ``"LPS"``, ...:
    #: :func:`~isoflow.digital.frames.space_given`); None where the file says none
    space: str | None = None
    said: Callable[[object], str | None] | None = None
    #: what each label is, label value to name, where the file records it
    names: dict[int, str] | None = None
    #: the header's scaling the values were read through, as a refusal of
    #: a value names it (NIfTI's ``scl_slope 0.5 and scl_inter 0``); None
    #: where the values are as stored
    scaling: str | None = None


def axis_units(units, where: str, what: str) -> tuple[np.ndarray, str | None]:
    """The one length unit of several axes (:func:`length_unit` of each),
    and per axis the factor that turns its lengths into that unit: 1 where
    they agree; where they differ and each is a length unit isoflow knows
    (a z in mm beside an x and y in µm), the first axis's unit, the others
    converted to it (the z's voxel size and origin times 1000), as an
    OME-TIFF's PhysicalSizeZ is converted to PhysicalSizeXUnit, so that
    volumes, areas and the surface's shape are in one unit; otherwise
    (a unit isoflow does not know, or some axes without one) no unit,
    said in a warning, and factors of 1: one voxel size and origin cannot
    be in two units.

    Parameters
    ----------
    units : sequence
        The unit of each axis as the file gives it (None where it gives none).
    where : str
        The file, as the warning names it.
    what : str
        The field, as the warning names it (``"NRRD 'space units'"``).

    Returns
    -------
    factors : numpy.ndarray
        One per axis.
    unit : str or None

    Examples
    --------
    >>> axis_units(["mm", "millimeter", "Millimetre"], "a.nrrd", "NRRD space units")
    (array([1., 1., 1.]), 'mm')
    >>> axis_units(["micrometer", "micrometer", "millimeter"], "a.zarr", "OME-Zarr axis units")
    (array([   1.,    1., 1000.]), '\u00b5m')
    >>> axis_units([None, None], "a.nrrd", "NRRD space units")
    (array([1., 1.]), None)
    """
    spelled = [length_unit(u) for u in units]
    factors = np.ones(len(spelled))
    if len(set(spelled)) <= 1:
        return factors, spelled[0] if spelled else None
    if all(u in LENGTH_UNITS for u in spelled):
        return np.array([unit_factor(u, spelled[0]) for u in spelled]), spelled[0]
    note(f"{where}: the {what} differ by axis ({', '.join(str(u) for u in units)}); no unit is reported")
    return factors, None


def unit_field(value: object, where: str) -> str | None:
    """The length unit a file's ``unit`` field holds (:func:`length_unit`
    of its text: a string, bytes, or a NumPy array of one), or None, said
    in a warning, where the field holds no text (a number, several
    strings): the volume is read, with no unit, rather than with the
    value's repr printed as its unit.

    Parameters
    ----------
    value : object
        The field as the format's reader gives it.
    where : str
        The file and field, as the warning names them (``"a.npz: array 'unit'"``).

    Returns
    -------
    str or None

    Examples
    --------
    >>> unit_field(np.array("micron"), "a.npz: array 'unit'"), unit_field(b"mm", "a.h5: attribute 'unit'")
    ('\u00b5m', 'mm')
    """
    text = value.item() if isinstance(value, np.ndarray) and value.ndim == 0 else value
    if isinstance(text, (str, bytes)):
        return length_unit(text)
    note(f"{where} is {given_text(value)}, not the text of a length unit; no unit is reported")
    return None


#: OME-Zarr's axis units (NGFF 0.4: UDUNITS-2 names) of isoflow's spellings
UDUNITS = {"m": "meter", "cm": "centimeter", "mm": "millimeter", "\u00b5m": "micrometer", "nm": "nanometer",
           "pm": "picometer", "\u00c5": "angstrom", "km": "kilometer", "in": "inch", "ft": "foot", "yd": "yard",
           "mi": "mile"}


def ascii_unit(unit: str) -> str:
    """``unit`` in ASCII, for a header of free text (ImageJ's description,
    NRRD's): ``um`` for \u00b5m, as ImageJ writes it, ``angstrom`` for
    \u00c5, any other letter beyond ASCII as ImageJ escapes it
    (``\\u00XX``), which :func:`length_unit` reads back.

    Examples
    --------
    >>> ascii_unit("\u00b5m"), ascii_unit("mm"), length_unit(ascii_unit("\u00c5"))
    ('um', 'mm', '\u00c5')
    """
    unit = {"\u00b5m": "um", "\u00c5": "angstrom"}.get(unit, unit)
    return "".join(c if ord(c) < 128 else f"\\u{ord(c):04X}" for c in unit)


def unit_not_kept(path, fmt: str, unit: str | None, keeps: str = "no length unit") -> None:
    """Warn that the format of ``path`` does not keep ``unit`` (nothing for
    None), as a format says what of the placement it drops."""
    if unit is not None:
        note(f"{path}: {fmt} keeps {keeps}; the unit {unit} of the voxel size and origin is not written")


def space_not_kept(path, fmt: str, space: str | None) -> None:
    """Warn that the format of ``path`` has no place for the anatomical
    frame ``space`` (nothing for None), as a format says what of the
    placement it drops: a reader of the file cannot tell left from right.

    Examples
    --------
    >>> space_not_kept("a.h5", "HDF5", None)  # nothing to say
    """
    if space is not None:
        note(f"{path}: {fmt} keeps no anatomical frame; {frame_text(space)} is not written (.nii.gz, .mgz, "
             ".nrrd, .npz and .h5 keep it)")


@dataclass(frozen=True)
class LabelVolume:
    """A label image placed in the world, as the writers take it in place
    of a :class:`DigitalObject`: unsigned integers in (x, y, z) order, voxel
    ``v`` at ``origin + spacing * v`` (no lattice offset, parity 0);
    ``names``, label value to name, for the formats that keep them."""

    volume: np.ndarray
    pitch: float | np.ndarray
    origin: np.ndarray
    offset: tuple[int, ...] = (0, 0, 0)
    parity: int = 0
    names: Mapping[int, str] | None = None

    @property
    def ndim(self) -> int:
        return self.volume.ndim

    @property
    def spacing(self) -> np.ndarray:
        return np.broadcast_to(np.asarray(self.pitch, np.float64), (self.ndim,)).copy()

    def world(self, array_points) -> np.ndarray:
        return self.origin + self.spacing * np.asarray(array_points, np.float64)


def stored_values(volume: np.ndarray) -> np.ndarray:
    """What a format stores: a mask as 0/1 bytes, labels as they are. A
    mask's bytes are 0 and 1 already: they are viewed as uint8, not copied,
    so that writing a volume near the memory budget needs no second one.

    Examples
    --------
    >>> mask = np.array([True, False])
    >>> stored_values(mask).tolist(), np.shares_memory(stored_values(mask), mask)
    ([1, 0], True)
    """
    return volume.view(np.uint8) if volume.dtype == np.bool_ else volume


def placement(obj: DigitalObject) -> tuple[np.ndarray, np.ndarray]:
    """(voxel size per axis, world position of array voxel 0's lowest
    corner) of ``obj``: what formats without a lattice offset or parity
    store, so that every voxel lands where it was."""
    return obj.spacing, obj.world(np.zeros(obj.ndim))


def placement_lost(obj: DigitalObject, unit: str | None = None, space: str | None = None) -> list[str]:
    """What of ``obj``'s placement a format that keeps none (PNG,
    MagicaVoxel: read back as voxel size 1 from 0) drops, each as a
    warning names it: a pitch other than 1, an origin other than 0, the
    unit, the anatomical frame. Empty where the file reads back as placed.

    Parameters
    ----------
    obj : DigitalObject
        The object to be written.
    unit : str or None
        The length unit of its pitch and origin.
    space : str or None
        Its anatomical frame.

    Returns
    -------
    list of str
        ``["pitch [0.5, 0.5]", "origin [1, 2]", "unit mm", ...]``, in that
        order, each where it is lost.

    Examples
    --------
    >>> placement_lost(DigitalObject(np.ones((2, 2, 2), bool), origin=(1.0, 2.0, 3.0)))
    ['origin [1, 2, 3]']
    >>> placement_lost(DigitalObject(np.ones((2, 2), bool), pitch=0.5), unit="mm")
    ['pitch [0.5, 0.5]', 'unit mm']
    """
    spacing, corner = placement(obj)
    return ([f"pitch {coordinates(spacing)}"] if (spacing != 1).any() else []) + (
        [f"origin {coordinates(corner, step=spacing)}"] if corner.any() else []) + (
        [f"unit {unit}"] if unit is not None else []) + (
        [frame_text(space)] if space is not None else [])


#: where a refusal of a 4D object by a format of 2D and 3D images sends it: the formats that write 4D
HOLD_4D = "write .nii.gz, .nrrd, .h5 or .npz, which hold 4D"


def refuse_empty(path: Path, shape: tuple[int, ...], fmt: str) -> None:
    """Refuse, before writing, an array with a side of length 0 (the last
    state of a flow that vanished, a crop of nothing), which ``fmt`` has no
    way to store: its writer failed inside its library, or wrote a file that
    reads back as some other shape.

    Parameters
    ----------
    path : pathlib.Path
        The file to be written, named in the message.
    shape : tuple of int
        The array's shape.
    fmt : str
        The format's name, as the message gives it.

    Raises
    ------
    IsoflowError
        If a side of ``shape`` is 0, naming the formats that keep it.

    Examples
    --------
    >>> refuse_empty(Path("x.tif"), (2, 3, 4), "TIFF")  # nothing to refuse
    >>> try:
    ...     refuse_empty(Path("x.tif"), (0, 3, 4), "TIFF")
    ... except IsoflowError as error:
    ...     print(str(error).split(";")[0])
    x.tif: TIFF holds no array with a side of length 0, this one is 0x3x4
    """
    if 0 in shape:
        raise IsoflowError(f"{path}: {fmt} holds no array with a side of length 0, this one is "
                           f"{'x'.join(map(str, shape))}; write .npz, .npy, .h5, .nrrd or .zarr")


#: what a volume too large to read can do instead (:func:`check_shape`)
READ_HINT = "crop it, or use a .zarr store with 'isoflow info' (read block by block)"


def colours_refused(where: str, kind: str, save_as: str) -> IsoflowError:
    """The refusal of an image whose colour channels differ (grey stored as
    colour, whose channels are equal, is read as that grey), for every
    format that stores colour.

    Examples
    --------
    >>> str(colours_refused("a.png", "RGB", "a grey PNG"))
    'a.png: holds colours, not labels or a mask (its RGB channels differ); save it as a grey PNG'
    """
    return IsoflowError(f"{where}: holds colours, not labels or a mask (its {kind} channels differ); save it as "
                        f"{save_as}")


def check_alpha(grey: np.ndarray, alpha: np.ndarray, where: str, field: str, command: str) -> None:
    """Refuse grey whose alpha channel says which pixels are shown otherwise
    than the grey does.

    The grey is the image where the alpha adds nothing to it: one opacity
    everywhere (a mask saved as RGBA or LA, opaque), or transparent
    exactly where the grey is 0 (a mask whose background is cut out).
    Anywhere else the alpha holds what a viewer shows (black ink on a
    transparent sheet, as image editors export a painted layer, is a
    grey of 0 everywhere): reading the grey alone would count what is
    not drawn, or nothing at all, without a word.

    Parameters
    ----------
    grey, alpha : numpy.ndarray
        The grey values and their alpha, of one shape.
    where : str
        The file, as messages name it.
    field : str
        What holds the alpha, as the file says it (``PNG mode LA``).
    command : str
        The shell command that saves the alpha as a grey image.

    Examples
    --------
    >>> mask = np.array([[0, 255], [255, 0]], np.uint8)
    >>> check_alpha(mask, np.full_like(mask, 255), "m.png", "PNG mode LA", "...")
    >>> check_alpha(mask, mask, "m.png", "PNG mode LA", "...")
    >>> check_alpha(np.zeros_like(mask), mask, "m.png", "PNG mode LA", "...")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: m.png: its alpha channel (PNG mode LA) and its grey differ in which pixels are \
empty (alpha 0, grey 0) at 2 of 4 pixels: a viewer shows another image than the grey; save the alpha as the mask \
and give that (or save the grey alone): ...
    """
    if alpha.size == 0 or ((alpha == alpha.flat[0]).all() and alpha.flat[0] != 0):
        return
    differ = int(np.count_nonzero((alpha != 0) != (grey != 0)))
    if differ:
        raise IsoflowError(f"{where}: its alpha channel ({field}) and its grey differ in which pixels are empty "
                           f"(alpha 0, grey 0) at {differ} of {alpha.size} pixels: a viewer shows another image than "
                           f"the grey; save the alpha as the mask and give that (or save the grey alone): {command}")


def check_shape(shape, dtype, where: str, hint: str = READ_HINT) -> None:
    """Refuse, before reading, an array that will not fit in memory (the
    file's array plus the boolean volume), the line ending in ``hint``:
    what to do instead."""
    import math

    from ...scale.memory import check_fits

    voxels = math.prod(int(s) for s in shape)
    planar = len(shape) == 2
    if planar and hint == READ_HINT:  # a 2D image is read whole, from a .zarr store too: cropping is what helps
        hint = "crop it"
    check_fits(
        voxels * (np.dtype(dtype).itemsize + 2),  # the file's array, the boolean volume, its C-ordered copy
        f"{where}: a {'x'.join(map(str, shape))} {'image' if planar else 'volume'} of {np.dtype(dtype)}",
        hint=hint,
    )


def check_time(time, shape, where: str) -> int:
    """``time`` as the int of the time point it picks of a volume of
    ``shape`` (isoflow's order: x, y, z, t for a time series); refused
    where the volume is not 4D, or ``time`` is not an integer (Python's,
    NumPy's or a 0D array of one) from 0 to the count less 1.

    Examples
    --------
    >>> check_time(2, (8, 8, 8, 3), "cells.ome.zarr"), check_time(np.array(2), (8, 8, 8, 3), "cells.ome.zarr")
    (2, 2)
    >>> try:
    ...     check_time(3, (8, 8, 8, 3), "cells.ome.zarr")
    ... except IsoflowError as error:
    ...     print(error)
    cells.ome.zarr: time=3 is no time point of this time series of 3 (0 to 2)
    """
    if len(shape) != 4:
        raise IsoflowError(f"{where}: time={given_text(time)} picks a time point of a 4D volume (x, y, z, t), this one is "
                           f"{len(shape)}D with shape {'x'.join(map(str, shape))}: it has no time points")
    count = int(shape[3])
    whole = whole_given(time)
    if whole is None or not 0 <= whole < count:
        raise IsoflowError(f"{where}: time={given_text(time)} is no time point of this time series of {count} "
                           f"(0 to {count - 1})")
    return whole


def fourth_axis_words(path: str | os.PathLike, count: int | None = None) -> tuple[str, str]:
    """What the 4th axis of a 4D volume read as (x, y, z, t) holds, as a
    refusal says it, and what one entry of it is called: a time series
    where the file names the axis ``t`` (an OME-Zarr image's time axis, a
    zarr array's dimension name, a TIFF's ``T``) or its format reserves
    that axis for time (a NIfTI's or an Analyze header's ``dim[4]``),
    channels where it names it ``c``, else "time points or channels" (a
    .npy does not say which).

    Parameters
    ----------
    path : str or os.PathLike
        The file, as given.
    count : int, optional
        The entries along the axis, where the words give them.

    Returns
    -------
    tuple of str
        The words, and one entry's name (``"time point"``, ``"channel"``,
        ``"entry"``).

    Examples
    --------
    >>> fourth_axis_words("cells.npy", 3)
    ('a 4th axis of 3 entries, time points or channels', 'entry')
    >>> fourth_axis_words("cells.ome.tif", 3)
    ("a time series of 3 time points along its 4th axis 't'", 'time point')
    >>> fourth_axis_words("bold.nii.gz", 3)
    ("a time series of 3 time points along its 4th axis, NIfTI's dim[4]", 'time point')
    >>> fourth_axis_words("cells.npy")
    ('a 4th axis of time points or channels', 'entry')
    """
    suffix = split_store(path)[0].suffix.lower()
    # a TIFF is read as 4D only where its axes (OME-XML's, ImageJ's) hold a T
    # of several entries beside Z, Y, X (:func:`to_xyz`): a time series
    name = fourth_axis_name(path) if suffix == ".zarr" else "t" if suffix in (".tif", ".tiff") else None
    entries = "" if count is None else f"{count} "
    if name == "t":
        return f"a time series of {entries}time points along its 4th axis 't'", "time point"
    fmt = format_for(path)
    if fmt is not None and fmt.name in ("NIfTI", "Analyze"):
        # both headers reserve dim[4] for time (other values, a vector's, go
        # in dim[5], a 5D image the readers refuse): a time series
        return f"a time series of {entries}time points along its 4th axis, {fmt.name}'s dim[4]", "time point"
    if name == "c":
        return f"{entries}channels along its 4th axis 'c'", "channel"
    if count is None:
        return "a 4th axis of time points or channels", "entry"
    return f"a 4th axis of {count} entries, time points or channels", "entry"


def one_time_point_labels(path: str | os.PathLike, count: int | None = None) -> str:
    """The end of the refusal of a 4D label image (read as x, y, z, t; its
    4th axis what :func:`fourth_axis_words` says, of ``count`` entries):
    how to take one entry of it, in Python and as a 3D file that every
    command reads.

    Examples
    --------
    >>> print(one_time_point_labels("cells.zarr", 5))  # doctest: +NORMALIZE_WHITESPACE
     (a 4th axis of 5 entries, time points or channels, read as x, y, z, t): read one entry with read_labels(path,
     time=0), or save it as 3D and give that: python -c 'import isoflow;
     isoflow.write_labels(isoflow.read_labels("cells.zarr", time=0), "t0.npz")'
    """
    import json
    import shlex

    what, entry = fourth_axis_words(path, count)
    code = f'import isoflow; isoflow.write_labels(isoflow.read_labels({json.dumps(str(path))}, time=0), "t0.npz")'
    return (f" ({what}, read as x, y, z, t): read one {entry} with read_labels(path, "
            f"time=0), or save it as 3D and give that: python -c {shlex.quote(code)}")


def check_label(label, dtype, where: str) -> int | float:
    """A label selects voxels of an array of numbers by one finite number:
    returned as the array compares it exactly, a whole number as a Python
    int for an integer array (a float 2.0**63 compared with a uint64 array
    as a float, which also matched 2**63 + 1 and its neighbours); a whole
    number a float array cannot hold is refused, as no voxel can have it."""
    if np.dtype(dtype).kind not in "biuf":
        raise IsoflowError(f"{where}: array of type {dtype} holds no labels")
    label = scalar_given(label)  # a 0D array of a number (np.load of a saved label) is that number
    if not np.isscalar(label) or isinstance(label, (str, bytes)):
        raise IsoflowError(f"{where}: label must be a number, got {given_text(label)}")
    if isinstance(label, (bool, np.bool_)):  # True equals 1: it would pick label 1 unasked
        raise IsoflowError(f"{where}: label must be a number, not True or False, got {given_text(label)}")
    dtype = np.dtype(dtype)
    try:
        value = float(label)
    except OverflowError:  # an int beyond every float
        value = np.inf if label > 0 else -np.inf
    if not np.isfinite(value) and not isinstance(label, (int, np.integer)):  # "--label 1e400" is inf: a number
        raise IsoflowError(f"{where}: label must be a finite number, got {given_text(label)}")
    whole = not np.isfinite(value) or value.is_integer()  # (an int beyond every float is whole)
    if dtype.kind in "iu" and whole:
        info = np.iinfo(dtype)
        if not info.min <= int(label) <= info.max:
            raise IsoflowError(f"{where}: label {number_text(label)} is beyond the values {with_article(dtype)} array holds "
                               f"({info.min} to {info.max})")
    elif not np.isfinite(value):
        raise IsoflowError(f"{where}: label {number_text(label)} is beyond the values {with_article(dtype)} array holds")
    elif whole and dtype.kind == "f":
        # NumPy compares a float array with the label rounded to the array's
        # type: 16777217 picked the voxels of 16777216 in a float32 image
        with np.errstate(over="ignore"):
            held = dtype.type(label)
        if not np.isfinite(held):
            raise IsoflowError(f"{where}: label {number_text(label)} is beyond the values {with_article(dtype)} array holds")
        if int(held) != int(label):
            raise IsoflowError(f"{where}: no voxel has label {number_text(label)}: {with_article(dtype)} array "
                               f"cannot hold it (the nearest value it holds is {int(held)})")
    return int(label) if dtype.kind in "iu" and whole else label


def no_such_label(label, values, where: str, ndim: int = 3) -> IsoflowError:
    """The error for a label no voxel has, listing the ``values`` present
    (none in an array without voxels); the cells of an ``ndim`` 2 image are
    pixels, as ``isoflow info`` calls them."""
    cell = "pixel" if ndim == 2 else "voxel"
    if not len(values):
        return IsoflowError(f"{where}: no {cell} has label {number_text(label)}: the array has no {cell}s")
    shown = ", ".join(number_text(v) for v in values[:20]) + (", ..." if len(values) > 20 else "")
    return IsoflowError(f"{where}: no {cell} has label {number_text(label)} (values present: {shown})")


def names_json(names: Mapping[int, str]) -> str:
    """Label names as the JSON text that HDF5's attribute and an ``.npz``'s
    array ``label_names`` hold: an object of label value (as text) to name.

    Examples
    --------
    >>> names_json({1: "a.stl", 2: "b.obj"})
    '{"1": "a.stl", "2": "b.obj"}'
    """
    import json

    return json.dumps({str(k): v for k, v in names.items()}, ensure_ascii=False)


def one_line_name(name: str) -> str:
    r"""A label's name read from a file, as one line: a line break in it
    (which JSON and NGFF's ``properties`` hold, and a name given to
    :func:`isoflow.write_labels` may not) as its escape, ``\n`` or ``\r``,
    so that the image is read and written again with its names, and a
    table's row stays one line.

    Parameters
    ----------
    name : str
        The name as the file holds it.

    Returns
    -------
    str
        ``name``, each line break escaped.

    Examples
    --------
    >>> one_line_name("liver"), one_line_name("left\nlobe")
    ('liver', 'left\\nlobe')
    """
    return name.replace("\r", "\\r").replace("\n", "\\n")


def names_from_json(text, where: str, field: str) -> dict[int, str] | None:
    """Label names from :func:`names_json`'s text (bytes or a NumPy string
    too); text that is no such object is said in one warning and left out,
    as the image reads without it. A line break in a name is read as its
    escape (:func:`one_line_name`).

    Examples
    --------
    >>> names_from_json('{"2": "b.obj", "1": "a.stl"}', "l.h5", "label_names")
    {1: 'a.stl', 2: 'b.obj'}
    """
    import json

    try:
        text = text.decode("utf-8") if isinstance(text, bytes) else str(text)
        found = {int(k): v for k, v in json.loads(text).items()}
        if all(isinstance(v, str) and k >= 1 for k, v in found.items()):
            return {k: one_line_name(v) for k, v in sorted(found.items())} or None
    except (ValueError, AttributeError, TypeError):
        pass
    note(f"{where}: {field} {str(text)[:80]!r} is no JSON object of label to name; the labels are read without names")
    return None


def note(message: str) -> None:
    """A one-line warning (metadata a format cannot keep, an affine's
    rotation dropped); the command line prints it as ``warning: ...``."""
    warn(message)


def to_xyz(array: np.ndarray, names, where: str) -> np.ndarray:
    """``array`` with axes named ``names`` (e.g. 'tczyx') as isoflow's (x, y,
    z), or (x, y, z, t) for a time series of 3D volumes (see
    :func:`spatial_axes`)."""
    xyz, other = spatial_axes(names, array.shape, where, time=True)
    return np.transpose(array, xyz + other).reshape([array.shape[i] for i in xyz])
