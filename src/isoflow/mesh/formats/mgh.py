"""FreeSurfer MGH, ``.mgh`` and ``.mgz`` (gzip-compressed) (nibabel).

The volumes FreeSurfer writes: ``aseg.mgz`` and ``aparc+aseg.mgz`` (label
images), ``brainmask.mgz``, ``T1.mgz``. nibabel reads them as ``MGHImage``.

Axes: the header's direction cosines, voxel sizes and centre (``Mdc``,
``delta``, ``Pxyz_c``) make the vox2ras affine (nibabel's ``img.affine``),
which maps a voxel's *centre* index to RAS millimetres, as NIfTI's does
(the volume's ``space`` is ``"RAS"``):
isoflow turns and places the array by it exactly as a NIfTI image's
(:func:`isoflow.mesh.formats.nifti.placed_by_affine`: flips and
permutations exact, a rotation kept as its axis-aligned part with a
warning). A file whose ``goodRASFlag`` is 0 has no valid direction cosines:
nibabel then gives FreeSurfer's default (coronal, voxel size 1), and so
does isoflow. The length unit is mm, which the format has by definition. The
data type is as stored (uint8, int16, int32, float32; uint16 from
FreeSurfer 7.3 on), in the machine's byte order (MGH stores big-endian).
A file of several frames is read as 4D (``info`` only), voxel size 1
along the frames, as NIfTI's; one frame is 3D.

Written as ``.mgz`` or ``.mgh`` (uint8 0/1; a label image in the smallest
of uint8, int16 and int32 that holds it, the types every FreeSurfer
version reads) with a diagonal affine into RAS (the axes of a volume in
another frame, an LPS NRRD's, negated where they point the other way, as
NIfTI's writer does); MGH stores its header in float32,
and stores the volume's centre, not its first voxel. The centre is
written measured with the float32 voxel size, and read back from the
stored numbers in float64 (:func:`mgh_affine`; nibabel's ``img.affine``
is built in float32 arithmetic), so an origin comes back exactly where
the centre's coordinates are float32 numbers, and otherwise within
float32 rounding of them (a warning says where that moves a voxel by
more than NIfTI's ``FLOAT32_SLACK``). It holds 3D
and 4D volumes only, labels up to 2**31 - 1, in mm: a unit other than mm
is not written (a warning says so; the numbers are kept, read back as
mm), and a volume without one (a voxelised STL's, a bare array's) is
read back in mm, which a warning says as it is written: the reader
cannot tell the millimetres the file was given from those it assumed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .nifti import diagonal_affine, float32_placement, fourth_axis_dropped, placed_by_affine
from .registry import (
    RawVolume,
    check_shape,
    import_library,
    note,
    quiet_logs,
    reading,
    refuse_empty,
    stored_values,
    unit_not_kept,
)

#: the types FreeSurfer has read since its first releases, smallest first
WRITTEN_TYPES = (np.uint8, np.int16, np.int32)


def read(path: Path, dataset: str | None = None) -> RawVolume:
    nib = import_library("nibabel", "MGH")
    where = str(path)
    with reading(path, "MGH"), quiet_logs("nibabel.global"):
        # the file opened here and closed here: nibabel's own opening of an
        # .mgh (from_file_map, nib.load) leaves it open (ResourceWarning)
        with nib.openers.ImageOpener(str(path), "rb") as fileobj:
            img = nib.MGHImage.from_file_map({"image": nib.FileHolder(fileobj=fileobj)})
            check_shape(img.shape, img.get_data_dtype(), where)
            data = np.asanyarray(img.dataobj)
            hdr = img.header
            affine = mgh_affine(hdr["Mdc"], hdr["delta"], hdr["Pxyz_c"], hdr["dims"][:3])
    # big-endian in the file: the kernels take the machine's order
    data = data.astype(data.dtype.newbyteorder("="), copy=False)
    return placed_by_affine(data, affine, where, "mm", "RAS")


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    """Refuse what MGH cannot hold (a 2D object, a side of length 0; labels
    beyond int32 are refused by the format's ``max_label``); warn of a unit
    other than mm, of none (read back as mm), of voxels that float32
    moves, and of a fourth axis's placement, which it does not keep."""
    if obj.ndim not in (3, 4):
        raise IsoflowError(f"{path}: MGH holds 3D volumes (and 4D frames), this object is {obj.ndim}D; "
                           "write .nii.gz, .nrrd or .npz")
    refuse_empty(path, obj.volume.shape, "MGH")
    if unit is None:
        # every reader (isoflow, nibabel, FreeSurfer) takes MGH's numbers as mm: a unit the volume had not
        note(f"{path}: the volume has no length unit and MGH's is mm by definition: its voxel size and origin "
             "are written as given and read back as mm")
    elif unit != "mm":
        unit_not_kept(path, "MGH", unit, "millimetres only (read back as mm)")
    float32_placement(path, obj, "MGH", centred=True)
    fourth_axis_dropped(path, obj, "MGH")


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    nib = import_library("nibabel", "MGH")
    img = nib.MGHImage(mgh_values(stored_values(obj.volume)), diagonal_affine(obj, space))
    # the file named exactly: nibabel gzips by the name's suffix, which a temporary name keeps
    img.to_file_map(img.make_file_map({"image": str(path)}))


def mgh_affine(mdc, delta, centre, dims) -> np.ndarray:
    """The 4x4 voxel-to-world map (RAS mm) that an MGH header's float32
    fields mean, computed in float64 from them.

    nibabel's ``img.affine`` builds the same map in float32 arithmetic,
    which adds rounding the file does not hold (an origin of 0 read back as
    3.7e-09); here only the stored numbers' own rounding remains.

    Parameters
    ----------
    mdc : array_like
        The direction cosines ``Mdc`` (3x3, one row per voxel axis).
    delta : array_like
        The voxel sizes.
    centre : array_like
        ``Pxyz_c`` (FreeSurfer's ``c_ras``): the world position of voxel
        index ``dims / 2``.
    dims : array_like
        The volume's first three dimensions.

    Returns
    -------
    numpy.ndarray
        The affine mapping a voxel's centre index to world coordinates.

    Examples
    --------
    >>> mgh_affine(np.eye(3), np.float32([0.1, 0.1, 0.1]), np.float32([0.6, 0, 0]), [11, 2, 2])[0].tolist()
    [0.10000000149011612, 0.0, 0.0, 0.050000015646219254]
    """
    steps = np.asarray(mdc, np.float64).T * np.asarray(delta, np.float64)
    affine = np.eye(4)
    affine[:3, :3] = steps
    affine[:3, 3] = np.asarray(centre, np.float64) - steps @ (np.asarray(dims, np.float64) / 2)
    return affine


def mgh_values(values: np.ndarray) -> np.ndarray:
    """A mask or a label image in the smallest type of
    :data:`WRITTEN_TYPES` that holds its values (0/1 bytes stay bytes).

    Examples
    --------
    >>> mgh_values(np.array([0, 300], np.uint16)).dtype.name, mgh_values(np.array([0, 3], np.uint64)).dtype.name
    ('int16', 'uint8')
    """
    top = int(values.max(initial=0))
    kind = next(t for t in WRITTEN_TYPES if np.iinfo(t).max >= top)
    return values.astype(kind, copy=False)
