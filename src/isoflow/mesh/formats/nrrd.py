"""NRRD, ``.nrrd`` and detached ``.nhdr`` headers (pynrrd).

Axes: the file's axes in its own order, fastest first (pynrrd's
``index_order='F'``: axis 0 is the fastest), placed by ``space directions``
(one world vector per axis) and ``space origin`` (the centre of the first
sample), as NIfTI's affine is (:mod:`isoflow.mesh.formats.affine`: turned to
isoflow's x, y, z with positive steps; a rotation is kept as its axis-aligned
part with a warning). World coordinates are the file's ``space`` (3D Slicer
writes LPS). Axes without a direction (``none``: a vector or list axis) must
have length 1. A file with ``spacings`` instead of a space keeps them as the
voxel sizes, origin 0.

Written with ``space dimension``, diagonal ``space directions`` (the voxel
sizes), ``space origin`` (voxel 0's centre), uint8 0/1, gzip encoding;
float64 in the text header, so pitch and origin are kept exactly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .affine import axis_aligned, centre_affine
from .registry import RawVolume, check_shape, import_library, placement, reading


def read(path: Path, dataset: str | None = None) -> RawVolume:
    nrrd = import_library("nrrd", "NRRD", "pynrrd")
    where = str(path)
    with reading(path, "NRRD"):
        header = nrrd.read_header(str(path))
        sizes = [int(s) for s in header["sizes"]]
        check_shape(sizes, np.uint8, where)
        data, header = nrrd.read(str(path), index_order="F")
    directions = header.get("space directions")
    if directions is not None:
        directions = np.asarray(directions, np.float64)
        placed = [i for i in range(data.ndim) if np.isfinite(directions[i]).all()]
        others = [i for i in range(data.ndim) if i not in placed]
        for i in others:
            if data.shape[i] != 1:
                raise IsoflowError(
                    f"{where}: axis {i} has no space direction and {data.shape[i]} entries "
                    f"(shape {data.shape}); isoflow reads one scalar volume"
                )
        data = np.transpose(data, placed + others).reshape([data.shape[i] for i in placed])
        origin = np.asarray(header.get("space origin", np.zeros(directions.shape[1])), np.float64)
        if not np.isfinite(origin).all():
            origin = np.zeros(directions.shape[1])
        vol, pitch, corner = axis_aligned(data, directions[placed].T, origin, where)
        return RawVolume(vol, pitch, corner)
    spacings = header.get("spacings")
    pitch = 1.0
    if spacings is not None:
        spacings = np.asarray(spacings, np.float64)
        if np.isfinite(spacings).all():
            pitch = np.abs(spacings)
    return RawVolume(data, pitch)


def write(path: Path, obj: DigitalObject, dataset: str | None = None) -> None:
    nrrd = import_library("nrrd", "NRRD", "pynrrd")
    spacing, corner = placement(obj)
    steps, centre0 = centre_affine(spacing, corner)
    header = {
        "space dimension": obj.ndim,
        "space directions": steps,  # row i: the world step of axis i (diagonal)
        "space origin": centre0,
        "kinds": ["domain"] * obj.ndim,
        "encoding": "gzip",
    }
    nrrd.write(str(path), obj.volume.astype(np.uint8), header, index_order="F")
