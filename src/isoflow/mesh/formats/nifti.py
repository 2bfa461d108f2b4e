"""NIfTI-1 and NIfTI-2, ``.nii`` and ``.nii.gz`` (nibabel).

Axes: the data array's axes (i, j, k) are placed by the image's affine
(nibabel's ``img.affine``: the sform, else the qform), which maps a voxel's
*centre* index to world (scanner) coordinates, usually RAS+ millimetres.
isoflow turns the array so that axis 0 runs along world x, 1 along y, 2
along z, each with a positive step (:mod:`isoflow.mesh.formats.affine`:
flips and permutations are exact, a rotation or shear is kept as its axis-
aligned part with a warning). A fourth axis of length 1 is dropped; a 4D
image is read as 4D (``info`` only) with voxel size 1 along the fourth axis;
a 4D object written with another voxel size or origin along it is warned of.

Written as NIfTI-1 (uint8 0/1; a label image in its unsigned type) with a diagonal affine (the voxel sizes)
whose translation is voxel 0's centre, sform and qform code 1 (scanner).
NIfTI stores the affine in float32: pitch and origin are kept to float32
precision, and where that moves a voxel centre by more than
:data:`FLOAT32_SLACK` of a voxel (a model far from the origin: float32's
positions near 1e6 are 0.0625 apart) a warning says by how much and names
the formats that keep the placement. The length unit is the header's xyzt spatial unit
(``mm``, ``micron``, ``meter``; ``unknown`` is none). It is written so
where the unit is one of those three; NIfTI has no code for another (cm,
nm, inch, ...), which is written as ``unknown`` with a warning, the voxel
size and origin as they are (not converted to mm).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError, coordinates
from .affine import axis_aligned, centre_affine
from .registry import (
    RawVolume,
    check_shape,
    import_library,
    length_unit,
    note,
    placement,
    quiet_logs,
    reading,
    refuse_empty,
    stored_values,
    unit_not_kept,
)

#: NIfTI's xyzt spatial units (nibabel's names) of isoflow's spellings: the
#: format has codes for these three lengths only
XYZT_UNITS = {"m": "meter", "mm": "mm", "\u00b5m": "micron"}
#: voxels by which float32's rounding of the affine may move a voxel centre
#: unsaid: far below any voxel a reader would pick differently
FLOAT32_SLACK = 1e-3


def read(path: Path, dataset: str | None = None) -> RawVolume:
    nib = import_library("nibabel", "NIfTI")
    where = str(path)
    with reading(path, "NIfTI"), quiet_logs("nibabel.global"):
        img = _load(nib, path)
        if not isinstance(img, (nib.Nifti1Image, nib.Nifti2Image)):
            raise IsoflowError(f"{where}: not a NIfTI image ({type(img).__name__})")
        shape = img.shape
        check_shape(shape, img.get_data_dtype(), where)
        data = np.asanyarray(img.dataobj)  # the stored type (scaled to float only if the file says so)
        affine = np.asarray(img.affine, np.float64)
        unit = length_unit(img.header.get_xyzt_units()[0])  # 'mm', 'micron', 'meter' or 'unknown' (none)
    while data.ndim > 3 and data.shape[-1] == 1:
        data = data[..., 0]
    if data.ndim not in (2, 3, 4):
        raise IsoflowError(f"{where}: a volume must be 2D, 3D or 4D, this image has shape {tuple(data.shape)}")
    spatial = min(data.ndim, 3)  # the affine places the first three axes; time keeps step 1
    vol, pitch, origin = axis_aligned(data, affine[:3, :spatial], affine[:3, 3], where)
    if data.ndim == 4:
        pitch, origin = np.append(pitch, 1.0), np.append(origin, 0.0)
    return RawVolume(vol, pitch, origin, unit=unit)


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None) -> None:
    """Refuse an array with a side of length 0; warn of a fourth axis's
    placement, which the affine has no room for (read back as voxel size 1
    from 0), as every format says what of the placement it drops."""
    # a NIfTI dimension of 0 is written, but nibabel reads the file back as shape (0,)
    refuse_empty(path, obj.volume.shape, "NIfTI")
    if unit not in XYZT_UNITS:
        unit_not_kept(path, "NIfTI", unit, "the length units m, mm and \u00b5m only")
    float32_placement(path, obj)
    if obj.ndim != 4:
        return
    spacing, corner = placement(obj)
    if spacing[3] != 1 or corner[3] != 0:
        note(f"{path}: NIfTI places the first three axes only; the fourth axis's voxel size "
             f"{float(spacing[3]):.9g} and origin {float(corner[3]):.9g} are not written (read back as 1 and 0)")


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None) -> None:
    nib = import_library("nibabel", "NIfTI")
    spacing, corner = placement_3d(obj)
    steps, centre0 = centre_affine(spacing, corner)
    affine = np.eye(4)
    n = len(spacing)
    affine[:n, :n] = steps
    affine[:n, 3] = centre0
    values = stored_values(obj.volume)
    # the type named: nibabel refuses int64 and uint64 data unless it is (64-bit labels)
    img = nib.Nifti1Image(values, affine, dtype=values.dtype)
    img.set_sform(affine, code=1)
    img.set_qform(affine, code=1)
    img.header.set_xyzt_units(XYZT_UNITS.get(unit or "", "unknown"))
    # the file named exactly: nib.save takes "bob.Nii.gz" for "bob.nii.gz" and writes that other file,
    # leaving the named one (a temporary file renamed over the output) empty
    img.to_file_map(img.make_file_map({"image": str(path)}))


def _load(nib, path: Path):
    """The NIfTI image in the file ``path`` itself.

    Parameters
    ----------
    nib : module
        nibabel.
    path : Path
        The file.

    Returns
    -------
    nibabel.spatialimages.SpatialImage
        The image.
    """
    if nib.Nifti1Image.filespec_to_file_map(str(path))["image"].filename == str(path):
        return nib.load(path)
    # a suffix in mixed case ("bob.Nii.gz"): nib.load would open "bob.nii.gz", another file or none
    try:
        return nib.Nifti1Image.from_file_map(nib.Nifti1Image.make_file_map({"image": str(path)}))
    except nib.spatialimages.HeaderDataError:  # not NIfTI-1: a NIfTI-2 header, or no NIfTI at all
        return nib.Nifti2Image.from_file_map(nib.Nifti2Image.make_file_map({"image": str(path)}))


def float32_placement(path: Path, obj: DigitalObject) -> None:
    """Warn where the float32 affine moves a voxel centre of ``obj`` by more
    than :data:`FLOAT32_SLACK` voxels, as a format says what of the
    placement it drops."""
    spacing, corner = placement_3d(obj)
    moved, corner32 = float32_moved(spacing, corner, obj.volume.shape[:len(spacing)])
    if moved > FLOAT32_SLACK:
        note(f"{path}: NIfTI stores the voxel-to-world map as float32, which moves this volume's voxels by up to "
             f"{moved:.3g} voxels (voxel 0's lowest corner {coordinates(corner, 12)} is read back as "
             f"{coordinates(corner32, 12)}); .nrrd, .h5 and .npz keep the placement")


def float32_moved(spacing, corner, shape) -> tuple[float, np.ndarray]:
    """How far float32 storage of NIfTI's affine moves a voxel centre.

    Parameters
    ----------
    spacing : array_like
        Voxel size per axis.
    corner : array_like
        World position of voxel 0's lowest corner.
    shape : tuple of int
        The array's shape along the same axes.

    Returns
    -------
    moved : float
        The largest change of a voxel centre's coordinate, in voxels of its
        axis (the first and last voxels bound it: the map is affine).
    corner32 : ndarray
        Voxel 0's lowest corner as a reader of the file places it.

    Examples
    --------
    >>> moved, corner32 = float32_moved([0.04, 0.04, 0.04], [999998.7, 0, 0], (64, 64, 16))
    >>> round(moved, 2), round(float(corner32[0]), 2)
    (0.75, 999998.73)
    >>> float32_moved([0.5, 0.5, 0.5], [-100, 0, 0], (64, 64, 16))[0]
    0.0
    """
    steps, centre0 = centre_affine(spacing, corner)
    pitch = np.diag(steps)
    pitch32, centre32 = pitch.astype(np.float32).astype(np.float64), centre0.astype(np.float32).astype(np.float64)
    last = np.asarray(shape, np.float64) - 1
    moved = np.maximum(np.abs(centre32 - centre0), np.abs(centre32 + pitch32 * last - centre0 - pitch * last))
    return float((moved / pitch).max()), centre32 - pitch32 / 2


def placement_3d(obj: DigitalObject):
    """Voxel size and corner origin of the spatial axes (at most three)."""
    spacing, corner = placement(obj)
    if obj.ndim == 4:
        return spacing[:3], corner[:3]
    return spacing, corner
