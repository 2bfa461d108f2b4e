"""Analyze 7.5 and NIfTI pairs, ``.hdr`` with ``.img`` (nibabel); read only.

Either file of the pair may be named; nibabel finds the other beside it.
A pair whose header is NIfTI's (``ni1``, ``ni2``) is read as a NIfTI image,
placed by its affine in its xyzt unit (:mod:`isoflow.mesh.formats.nifti`).

Analyze 7.5 stores the voxel sizes (``pixdim``), which nibabel reads as
written (a size of 0 as 1, which the warning names, and a negative one
as its magnitude, as its header check fixes them), but no orientation and no origin: nibabel's
affine for it is a convention (x mirrored, radiological, and the volume
centred on 0), not the file's, and an image written with any other
affine reads back so. isoflow reads the array as stored, axis 0 as x, 1 as
y, 2 as z, with those voxel sizes and voxel 0's corner at 0, and a warning
says that the placement is not the file's. The length unit is the header's
``vox_units`` where that names one (``mm``), else none. SPM's origin field
and ``.mat`` file are not read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.units import length_unit
from .nifti import file_pixdim, image_volume, method_1_affine, placed_by_affine
from .registry import RawVolume, check_shape, import_library, note, quiet_logs, reading


def read(path: Path, dataset: str | None = None) -> RawVolume:
    nib = import_library("nibabel", "Analyze")
    where = str(path)
    with reading(path, "Analyze"), quiet_logs("nibabel.global"):
        img = nib.load(path)
        if isinstance(img, (nib.Nifti1Pair, nib.Nifti2Pair)):  # a NIfTI header: its affine is the file's
            return image_volume(img, where)
        check_shape(img.shape, img.get_data_dtype(), where)
        data = np.asanyarray(img.dataobj)
        zooms = np.asarray(img.header.get_zooms(), np.float64)
        stored = file_pixdim(img)
        unit = length_unit(bytes(img.header["vox_units"]).decode("latin-1").strip("\x00 "))
    # the array as stored, voxel 0's centre half a voxel from 0: Analyze has no field that turns or places it
    affine = method_1_affine(zooms)
    n = min(len(zooms), 3)
    affine[:n, 3] = zooms[:n] / 2
    raw = placed_by_affine(data, affine, where, unit)
    # a size of 0 is none: nibabel reads it as 1, which the line names, as a NIfTI's
    zero = [f"pixdim[{i}]" for i in range(1, n + 1) if stored[i - 1] == 0]
    note(f"{where}: Analyze 7.5 stores voxel sizes but no orientation or origin; read as stored (axis 0 as x) "
         "from 0, not as nibabel's assumed affine places it (x mirrored, centred)"
         + (f"; {', '.join(zero)} 0, no voxel size: read as 1, as nibabel does" if zero else ""))
    return raw
