"""NIfTI-1 and NIfTI-2, ``.nii`` and ``.nii.gz`` (nibabel).

Axes: the data array's axes (i, j, k) are placed by the image's affine
(nibabel's ``img.affine``: the sform, else the qform), which maps a voxel's
*centre* index to world (scanner) coordinates, usually RAS+ millimetres;
an image with neither (both codes 0) by the standard's method 1 (the
voxel sizes alone, voxel 0 centred at 0: :func:`method_1_affine`; a
negative ``pixdim`` mirrors its axis, :func:`stored_pixdim`), with a
warning.
Both present (codes above 0) and placing the voxels apart: the sform,
with a warning of how far the qform is from it (:func:`forms_disagree`).
isoflow turns the array so that axis 0 runs along world x, 1 along y, 2
along z, each with a positive step (:mod:`isoflow.mesh.formats.affine`:
flips and permutations are exact, a rotation or shear is kept as its axis-
aligned part with a warning). A fourth axis of length 1 is dropped; a 4D
image is read as 4D (``info`` only) with voxel size 1 along the fourth axis;
a 4D object written with another voxel size or origin along it is warned of.

Written as NIfTI-1 (uint8 0/1; a label image in its unsigned type) with a diagonal affine (the voxel sizes)
whose translation is voxel 0's centre, sform and qform code 1 (scanner). The
world read is RAS (the volume's ``space``; none for method 1); a volume in
another frame (an LPS NRRD's) is written with the rows of its world axes
that point the other way negated (:func:`diagonal_affine`), so every voxel
keeps its anatomical place.
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

import dataclasses
from pathlib import Path

import numpy as np

from ...digital.frames import grid_in_frame
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
#: the longest side NIfTI-1 holds: its header's dim[] is int16
MAX_SIDE = 32767


def read(path: Path, dataset: str | None = None) -> RawVolume:
    nib = import_library("nibabel", "NIfTI")
    where = str(path)
    with reading(path, "NIfTI"), quiet_logs("nibabel.global"):
        img = _load(nib, path)
        if not isinstance(img, (nib.Nifti1Image, nib.Nifti2Image)):
            raise IsoflowError(f"{where}: not a NIfTI image ({type(img).__name__})")
        return image_volume(img, where)


def image_volume(img, where: str) -> RawVolume:
    """The volume of a NIfTI image nibabel opened (a single file or a
    ``.hdr``/``.img`` pair): its data as stored, placed by its affine, in
    its xyzt spatial unit.

    Parameters
    ----------
    img : nibabel.Nifti1Pair or nibabel.Nifti2Pair
        The image (``Nifti1Image`` is one).
    where : str
        The file, as refusals name it.

    Returns
    -------
    RawVolume
        As :func:`placed_by_affine` gives it.

    Examples
    --------
    >>> import nibabel
    >>> img = nibabel.Nifti1Image(np.ones((2, 2, 2), np.uint8), np.diag([0.5, 0.5, 2, 1]))
    >>> img.header.set_xyzt_units("mm")
    >>> raw = image_volume(img, "a.nii")
    >>> raw.pitch.tolist(), raw.origin.tolist(), raw.unit, raw.space
    ([0.5, 0.5, 2.0], [-0.25, -0.25, -1.0], 'mm', 'RAS')
    """
    check_shape(img.shape, img.get_data_dtype(), where)
    data = np.asanyarray(img.dataobj)  # the stored type (scaled to float only if the file says so)
    zero_scaled(img.dataobj, where)
    affine = np.asarray(img.affine, np.float64)
    # the standard's world of an sform or qform is RAS; method 1's voxel grid has no anatomical frame
    space: str | None = "RAS"
    if int(img.header["qform_code"]) == 0 and int(img.header["sform_code"]) == 0:
        steps = stored_pixdim(img)
        affine, space = method_1_affine(steps), None
        mirrored = [f"pixdim[{i}] {steps[i - 1]:g}" for i in range(1, len(steps) + 1) if steps[i - 1] < 0]
        said = f"; {', '.join(mirrored)} negative: that axis runs mirrored (nibabel takes its magnitude)" if mirrored else ""
        # a size of 0 is no size: read as 1 (nibabel, nifti1_io), which the user must hear of, not find in the mesh
        stored = file_pixdim(img)
        zero = [f"pixdim[{i}]" for i in range(1, len(steps) + 1) if stored[i - 1] == 0]
        said += f"; {', '.join(zero)} 0, no voxel size: read as 1, as nibabel and nifti1_io do" if zero else ""
        note(f"{where}: no qform or sform (both codes 0): placed by the NIfTI standard's method 1, voxel (i, j, k) "
             f"at (i dx, j dy, k dz), not by nibabel's fallback affine (x mirrored, centred on 0){said}")
    unit = length_unit(img.header.get_xyzt_units()[0])  # 'mm', 'micron', 'meter' or 'unknown' (none)
    if int(img.header["sform_code"]) > 0 and not np.abs(affine[:3, :3]).max(axis=0).all():
        affine = sform_without_size(img.header, where)
    else:
        forms_disagree(img.header, img.shape, where, unit)
    return dataclasses.replace(placed_by_affine(data, affine, where, unit, space), scaling=scaling_read(img.dataobj))


def scaling_read(dataobj) -> str | None:
    """The header's scaling the values are read through, in words that
    name its fields, or None where they are read as stored: a label image
    stored 1, 3 under ``scl_slope`` 0.5 is read as 0.5, 1.5, which a
    refusal of 0.5 must trace to the header, not to the stored labels.

    Parameters
    ----------
    dataobj : nibabel.arrayproxy.ArrayProxy or numpy.ndarray
        The image's ``dataobj``: its ``slope`` and ``inter`` are the
        scaling nibabel applies (an array in memory has none).

    Returns
    -------
    str or None
        ``"its header's scl_slope 0.5 and scl_inter 0 (value = 0.5 x
        stored + 0, as the NIfTI standard, nibabel and ITK read it)"``, or
        None for a slope of 1 and an intercept of 0.

    Examples
    --------
    >>> import nibabel
    >>> img = nibabel.Nifti1Image(np.ones((2, 2, 2), np.int16), np.eye(4))
    >>> img.header.set_slope_inter(0.5, 0)
    >>> scaling_read(nibabel.Nifti1Image.from_bytes(img.to_bytes()).dataobj)
    "its header's scl_slope 0.5 and scl_inter 0 (value = 0.5 x stored + 0, as the NIfTI standard, nibabel and ITK \
read it)"
    >>> scaling_read(np.zeros(2)) is None
    True
    """
    slope, inter = float(getattr(dataobj, "slope", 1.0)), float(getattr(dataobj, "inter", 0.0))
    if slope == 1 and inter == 0:
        return None
    return (f"its header's scl_slope {slope:g} and scl_inter {inter:g} (value = {slope:g} x stored "
            f"{'-' if inter < 0 else '+'} {abs(inter):g}, as the NIfTI standard, nibabel and ITK read it)")


def zero_scaled(dataobj, where: str) -> float:
    """Warn where a NIfTI header's scaling reads a stored 0 as another
    value (``scl_inter`` not 0, with a ``scl_slope`` that the standard
    applies: neither 0 nor NaN). The values read are ``scl_slope *
    stored + scl_inter``, as the standard, nibabel and ITK read them; a
    mask stored 0/1 under ``scl_inter`` 1 is read as 1/2 (refused as no
    mask), under ``scl_inter`` -1 as -1/0, whose object is then the
    voxels stored 0. The file's values are not changed, but the voxels
    stored as background are said to be read as something else.

    Parameters
    ----------
    dataobj : nibabel.arrayproxy.ArrayProxy or numpy.ndarray
        The image's ``dataobj``: its ``slope`` and ``inter`` are the
        scaling nibabel applies (an array in memory has none).
    where : str
        The file, named in the warning.

    Returns
    -------
    float
        The value a stored 0 is read as (0 where it stays 0).

    Examples
    --------
    >>> zero_scaled(np.zeros((2, 2, 2)), "a.nii")  # an array in memory: no scaling
    0.0
    """
    slope, inter = float(getattr(dataobj, "slope", 1.0)), float(getattr(dataobj, "inter", 0.0))
    if inter == 0 or not np.isfinite(inter):
        return 0.0
    note(f"{where}: {scaling_read(dataobj)} reads a stored 0 as {inter:g}: the voxels stored 0 are not background; a "
         f"mask stored 0/1 is read as {inter:g}/{slope + inter:g}")
    return inter


def sform_without_size(header, where: str) -> np.ndarray:
    """The qform's voxel-to-world map of a header whose sform (code above
    0) gives an axis no voxel size (its ``srow_x``, ``srow_y``,
    ``srow_z`` all 0 in that column, an sform of zeros as some writers
    leave it), said in a warning; refused where the qform's code is 0.

    nibabel takes such an sform and places every voxel at one point; ITK
    reads the qform where the sform is no rotation and voxel size, and so
    does isoflow, naming the fields.

    Parameters
    ----------
    header : nibabel.Nifti1Header
        The image's header.
    where : str
        The file, named in the warning or the refusal.

    Returns
    -------
    numpy.ndarray
        The qform's 4x4 map, float64.

    Raises
    ------
    IsoflowError
        Where ``qform_code`` is 0: the file has no placement to read.

    Examples
    --------
    >>> import nibabel
    >>> header = nibabel.Nifti1Header()
    >>> header.set_sform(np.zeros((4, 4)), code=2)
    >>> sform_without_size(header, "a.nii")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: a.nii: its sform (sform_code 2, ...) gives axes 0, 1, 2 no voxel size (srow_x, ...
    """
    sform = header.get_sform().astype(np.float64)
    flat = [i for i in range(3) if not np.abs(sform[:3, i]).any()]
    rows = ", ".join(f"srow_{a} {sform[i].tolist()}" for i, a in enumerate("xyz"))
    axes = f"{'axis' if len(flat) == 1 else 'axes'} {', '.join(map(str, flat))}"
    said = (f"its sform (sform_code {int(header['sform_code'])}, {rows}) gives {axes} no "
            f"voxel size (srow_x, srow_y and srow_z 0 in {'that column' if len(flat) == 1 else 'those columns'})")
    if int(header["qform_code"]) <= 0:
        raise IsoflowError(f"{where}: {said}, and its qform_code is 0: no placement to read (nibabel takes the sform "
                           "and places every voxel at one point); set sform_code 0 to place it by pixdim")
    note(f"{where}: {said}: placed by its qform (qform_code {int(header['qform_code'])}), as ITK reads it (nibabel "
         "takes the sform and places every voxel at one point)")
    return header.get_qform().astype(np.float64)


def forms_disagree(header, shape, where: str, unit: str | None) -> float:
    """Warn where a NIfTI header holds both a valid sform and a valid qform
    (codes above 0) that place its voxels apart: isoflow, as nibabel and
    FSL, takes the sform, but a reader that prefers the qform (ITK's, as
    3D Slicer and ITK-SNAP use, for some such files) shows the image
    elsewhere, and the file alone cannot tell which is meant.

    Parameters
    ----------
    header : nibabel.Nifti1Header
        The image's header (``Nifti2Header`` too).
    shape : tuple of int
        The image's shape; its first three axes are placed.
    where : str
        The file, named in the warning.
    unit : str or None
        The length unit of the world coordinates, named in the warning.

    Returns
    -------
    float
        How far apart the two place a voxel centre, at most (0 where
        either code is 0).

    Examples
    --------
    >>> import nibabel
    >>> img = nibabel.Nifti1Image(np.ones((2, 2, 2), np.uint8), np.eye(4))
    >>> img.set_qform(np.eye(4), code=1)
    >>> forms_disagree(img.header, img.shape, "a.nii", "mm")
    0.0
    """
    if int(header["sform_code"]) <= 0 or int(header["qform_code"]) <= 0:
        return 0.0
    sform, qform = header.get_sform().astype(np.float64), header.get_qform().astype(np.float64)
    last = np.maximum(np.asarray((tuple(shape) + (1, 1, 1))[:3], np.float64) - 1, 0)
    # the affine maps are apart at most at the box's corners
    box = np.array([[x, y, z, 1.0] for x in (0, last[0]) for y in (0, last[1]) for z in (0, last[2])])
    apart = float(np.linalg.norm(box @ (sform - qform).T, axis=1).max())
    voxel = float(np.linalg.norm(sform[:3, :3], axis=0).min())
    if not np.isfinite(apart) or apart <= FLOAT32_SLACK * voxel:
        return apart
    s_code, q_code = (header.get_value_label(k) for k in ("sform_code", "qform_code"))
    note(f"{where}: its sform (code '{s_code}') and qform (code '{q_code}') place the voxels up to {apart:.6g} "
         f"{unit or 'units'} apart; isoflow takes the sform, as nibabel and FSL do (a reader that prefers the "
         "qform shows the image elsewhere)")
    return apart


def stored_pixdim(img) -> np.ndarray:
    """The voxel sizes ``pixdim[1]``, ``pixdim[2]``, ``pixdim[3]`` of a
    NIfTI image with their signs as the file stores them. nibabel's header
    check turns a negative one into its magnitude as it loads the file,
    but the standard's method 1 (:func:`method_1_affine`) places voxel i
    at i pixdim[1], as the reference library nifti1_io reads it: a
    negative size mirrors its axis. The header is read again from the
    file, unchecked; an image held in memory keeps its header as set.

    Parameters
    ----------
    img : nibabel.Nifti1Pair or nibabel.Nifti2Pair
        The image (``Nifti1Image`` is one).

    Returns
    -------
    numpy.ndarray
        float64, one size per spatial axis (up to 3): nibabel's zooms (a
        size of 0 read as 1), negated where the file's is negative.

    Examples
    --------
    >>> import nibabel
    >>> img = nibabel.Nifti1Image(np.ones((2, 2, 2), np.uint8), np.diag([2.0, 1.5, 1, 1]))
    >>> img.header["pixdim"][1] = -2.0
    >>> stored_pixdim(img).tolist()
    [-2.0, 1.5, 1.0]
    """
    steps = np.asarray(img.header.get_zooms(), np.float64)[:3]
    stored = file_pixdim(img)[:len(steps)]
    return np.where((stored < 0) & (steps > 0), -steps, steps)


def file_pixdim(img) -> np.ndarray:
    """``pixdim[1]``, ``pixdim[2]``, ``pixdim[3]`` as the file's header
    bytes hold them, unchecked: nibabel's header check has made a negative
    one its magnitude and a 0 one 1 (:func:`stored_pixdim`). An image held
    in memory, or a file unreadable now, gives its header as set.

    Parameters
    ----------
    img : nibabel.Nifti1Pair or nibabel.Nifti2Pair
        The image.

    Returns
    -------
    numpy.ndarray
        float64, the three sizes.

    Examples
    --------
    >>> import nibabel
    >>> img = nibabel.Nifti1Image(np.ones((2, 2, 2), np.uint8), np.diag([2.0, 1.5, 1, 1]))
    >>> img.header["pixdim"][2] = 0.0
    >>> file_pixdim(img).tolist()
    [2.0, 0.0, 1.0]
    """
    header = raw = img.header
    holder = img.file_map.get("header", img.file_map.get("image"))  # a .nii holds its header in "image"
    if holder is not None and (holder.filename is not None or holder.fileobj is not None):
        try:
            with holder.get_prepare_fileobj(mode="rb") as fh:
                raw = type(header).from_fileobj(fh, check=False)
        except (OSError, ValueError):  # the file as loaded above: unreadable now, its checked header stands
            raw = header
    return np.asarray(raw["pixdim"], np.float64)[1:4]


def method_1_affine(zooms) -> np.ndarray:
    """The affine of a NIfTI image whose qform and sform codes are both 0:
    the standard's "method 1" (nifti1.h), voxel (i, j, k) centred at
    (i pixdim[1], j pixdim[2], k pixdim[3]), unturned, as the reference C
    library (nifti1_io) reads it. nibabel gives such an image the Analyze
    convention instead, x mirrored and the volume centred on 0, which the
    file does not say.

    Examples
    --------
    >>> method_1_affine((2.0, 3.0, 4.0)).tolist()
    [[2.0, 0.0, 0.0, 0.0], [0.0, 3.0, 0.0, 0.0], [0.0, 0.0, 4.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
    """
    steps = np.asarray(zooms, np.float64)[:3]
    affine = np.eye(4)
    affine[:len(steps), :len(steps)] = np.diag(steps)
    return affine


def placed_by_affine(data: np.ndarray, affine: np.ndarray, where: str, unit: str | None,
                     space: str | None = None) -> RawVolume:
    """The volume of an image placed by a 4x4 voxel-to-world ``affine`` (of
    voxel centres, as NIfTI's and FreeSurfer MGH's), on isoflow's grid.

    Parameters
    ----------
    data : numpy.ndarray
        The image's array as stored, (i, j, k) or (i, j, k, t); trailing
        axes of length 1 are dropped.
    affine : numpy.ndarray
        The 4x4 map of voxel centre indices to world coordinates.
    where : str
        The file, as refusals name it.
    unit : str or None
        The length unit of the world coordinates.
    space : str, optional
        Their anatomical frame (``"RAS"`` for NIfTI's and MGH's), None
        for none.

    Returns
    -------
    RawVolume
        The array turned to (x, y, z) with positive steps
        (:func:`~isoflow.mesh.formats.affine.axis_aligned`), a fourth axis
        with voxel size 1 from 0.

    Examples
    --------
    >>> raw = placed_by_affine(np.zeros((2, 3, 4, 1)), np.diag([-2.0, 1, 1, 1]), "a.nii", "mm")
    >>> raw.array.shape, raw.pitch.tolist(), raw.origin.tolist()
    ((2, 3, 4), [2.0, 1.0, 1.0], [-3.0, -0.5, -0.5])
    """
    while data.ndim > 3 and data.shape[-1] == 1:
        data = data[..., 0]
    if data.ndim not in (2, 3, 4):
        raise IsoflowError(f"{where}: a volume must be 2D, 3D or 4D, this image has shape {tuple(data.shape)}")
    spatial = min(data.ndim, 3)  # the affine places the first three axes; time keeps step 1
    vol, pitch, origin = axis_aligned(data, affine[:3, :spatial], affine[:3, 3], where)
    if data.ndim == 4:
        pitch, origin = np.append(pitch, 1.0), np.append(origin, 0.0)
    return RawVolume(vol, pitch, origin, unit=unit, space=space)


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    """Refuse an array with a side of length 0 or past NIfTI-1's 32767
    voxels; warn of a fourth axis's
    placement, which the affine has no room for (read back as voxel size 1
    from 0), as every format says what of the placement it drops."""
    # a NIfTI dimension of 0 is written, but nibabel reads the file back as shape (0,)
    refuse_empty(path, obj.volume.shape, "NIfTI")
    if max(obj.volume.shape, default=0) > MAX_SIDE:
        # here, before the write: nibabel's HeaderDataError would come only after the work, as a traceback
        raise IsoflowError(f"{path}: NIfTI-1 holds at most {MAX_SIDE} voxels a side (its dim[] is int16), this "
                           f"image is {'x'.join(map(str, obj.volume.shape))}; write .nrrd, .h5, .zarr or .npz")
    if unit not in XYZT_UNITS:
        unit_not_kept(path, "NIfTI", unit, "the length units m, mm and \u00b5m only")
    float32_placement(path, obj)
    fourth_axis_dropped(path, obj, "NIfTI")


def fourth_axis_dropped(path: Path, obj: DigitalObject, fmt: str) -> None:
    """Warn that a 4D object's voxel size and origin along its fourth axis,
    which a format placed by a 4x4 affine has no room for, are read back as
    1 and 0 (nothing where they are those).

    Parameters
    ----------
    path : Path
        The file to be written, named in the warning.
    obj : DigitalObject
        The object.
    fmt : str
        The format's name.

    Examples
    --------
    >>> fourth_axis_dropped(Path("a.nii"), DigitalObject(np.ones((2, 2, 2, 3), bool)), "NIfTI")  # nothing to say
    """
    if obj.ndim != 4:
        return
    spacing, corner = placement(obj)
    if spacing[3] != 1 or corner[3] != 0:
        note(f"{path}: {fmt} places the first three axes only; the fourth axis's voxel size "
             f"{float(spacing[3]):.9g} and origin {float(corner[3]):.9g} are not written (read back as 1 and 0)")


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    nib = import_library("nibabel", "NIfTI")
    affine = diagonal_affine(obj, space)
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


def diagonal_affine(obj: DigitalObject, space: str | None = None) -> np.ndarray:
    """The 4x4 voxel-to-world map of ``obj``'s spatial axes into RAS: its
    voxel sizes on the diagonal, voxel 0's centre as the translation (what
    NIfTI and FreeSurfer MGH store), each row of a world axis that
    ``space`` points the other way (L for R, P for A, I for S) negated, so
    that every voxel keeps its anatomical place. The voxel sizes are the
    float32 ones the file keeps, and the translation is measured with
    them: a reader subtracts those sizes from the stored float32 position,
    so an origin that float32 holds (0, small integers and halves) reads
    back exactly.

    Parameters
    ----------
    obj : DigitalObject
        The object (or a placed label image).
    space : str, optional
        The anatomical frame of its world coordinates
        (:func:`~isoflow.digital.frames.space_given`); None: written as
        they are.

    Returns
    -------
    numpy.ndarray
        The 4x4 affine.

    Examples
    --------
    >>> diagonal_affine(DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5)).tolist()[0]
    [0.5, 0.0, 0.0, 0.25]

    A voxel 10 mm to the patient's left in LPS is at x = -10 in RAS:

    >>> diagonal_affine(DigitalObject(np.ones((1, 1, 1), bool), origin=(9.5, 0, 0)), "LPS").tolist()[0]
    [-1.0, 0.0, 0.0, -10.0]
    >>> bool(diagonal_affine(DigitalObject(np.ones((2, 2, 2), bool), pitch=0.1))[0, 3] == np.float32(0.1) / 2)
    True
    """
    spacing, corner = placement_3d(obj)
    steps, centre0 = centre_affine(np.asarray(spacing, np.float64).astype(np.float32), corner)
    if space is not None:
        steps, centre0 = grid_in_frame(steps, centre0, space)
    affine = np.eye(4)
    n = len(spacing)
    affine[:n, :n] = steps.T  # (diagonal: an affine's row is a world axis, a column an array axis)
    affine[:n, 3] = centre0
    return affine


def float32_placement(path: Path, obj: DigitalObject, fmt: str = "NIfTI", centred: bool = False) -> None:
    """Warn where the float32 affine moves a voxel centre of ``obj`` by more
    than :data:`FLOAT32_SLACK` voxels, as a format says what of the
    placement it drops; ``centred``: the format stores the volume's centre
    (FreeSurfer MGH's ``Pxyz_c``), not voxel 0's (NIfTI's). A placement
    that float32 cannot hold at all (a voxel size that rounds to 0, a
    coordinate past float32's largest) is refused: the file would be
    written, and read back by no one (nibabel's affine of 0 or inf)."""
    spacing, corner = placement_3d(obj)
    shape = obj.volume.shape[:len(spacing)]
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        moved, corner32 = float32_moved(spacing, corner, shape, np.asarray(shape) / 2 if centred else 0)
        size32 = np.asarray(spacing, np.float64).astype(np.float32)
    if not (np.all(size32 > 0) and np.all(np.isfinite(size32)) and np.all(np.isfinite(corner32)) and np.isfinite(moved)):
        _past_float32(path, fmt, spacing, corner)
    if moved > FLOAT32_SLACK:
        note(f"{path}: {fmt} stores the voxel-to-world map as float32, which moves this volume's voxels by up to "
             f"{moved:.3g} voxels (voxel 0's lowest corner {coordinates(corner, 12)} is read back as "
             f"{coordinates(corner32, 12)}); .nrrd, .h5 and .npz keep the placement")


def _past_float32(path: Path, fmt: str, spacing, corner) -> None:
    raise IsoflowError(f"{path}: {fmt} stores the voxel-to-world map as float32 (no number past about 3.4e+38, no size "
                       f"below about 1.4e-45), which cannot hold voxel size {coordinates(spacing, 12)} with voxel 0's "
                       f"lowest corner {coordinates(corner, 12)}; write .nrrd, .h5 or .npz, which keep the placement")


def float32_moved(spacing, corner, shape, anchor=0) -> tuple[float, np.ndarray]:
    """How far float32 storage of NIfTI's (or MGH's) affine moves a voxel centre.

    Parameters
    ----------
    spacing : array_like
        Voxel size per axis.
    corner : array_like
        World position of voxel 0's lowest corner.
    shape : tuple of int
        The array's shape along the same axes.
    anchor : float or array_like
        The voxel index whose world position the file stores beside the
        voxel sizes: 0 (NIfTI's translation, voxel 0's centre), or half the
        shape (MGH's ``Pxyz_c``, the volume's centre).

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
    >>> float32_moved([0.5, 0.5, 0.5], [-100, 0, 0], (64, 64, 16), anchor=np.array([32, 32, 8]))[0]
    0.0
    """
    steps, centre0 = centre_affine(spacing, corner)
    pitch = np.diag(steps)
    pitch32 = pitch.astype(np.float32).astype(np.float64)
    # the stored position is measured with the stored voxel sizes (diagonal_affine),
    # and read back from them in float64 (mgh_affine)
    stored32 = (corner + pitch32 / 2 + pitch32 * anchor).astype(np.float32).astype(np.float64)
    centre32 = stored32 - pitch32 * anchor
    last = np.asarray(shape, np.float64) - 1
    moved = np.maximum(np.abs(centre32 - centre0), np.abs(centre32 + pitch32 * last - centre0 - pitch * last))
    return float((moved / pitch).max()), centre32 - pitch32 / 2


def placement_3d(obj: DigitalObject):
    """Voxel size and corner origin of the spatial axes (at most three)."""
    spacing, corner = placement(obj)
    if obj.ndim == 4:
        return spacing[:3], corner[:3]
    return spacing, corner
