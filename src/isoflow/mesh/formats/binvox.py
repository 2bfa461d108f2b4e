"""binvox (Patrick Min's format, ShapeNet's voxels; trimesh reads and writes
it too). Read and written here: a text header and run-length bytes are a
few lines of numpy, and no library is needed.

Axes: the header's ``dim`` is (x, y, z); the data run with y fastest, then
z, then x (the spec's ``index = x * wxh + z * width + y``), and are turned
into isoflow's (x, y, z).

Placement, by the spec: voxel ``(i, j, k)``'s centre is
``translate + scale * ((i, j, k) + 0.5) / dim``, so the voxel size is
``scale / dim`` and voxel 0's lowest corner is ``translate``. (trimesh's own
reader takes ``scale / (dim - 1)`` and puts voxel centres on ``translate``:
its coordinates differ from the spec's by a fraction of a voxel; the voxels
are the same.) A grid with unequal ``dim`` (not in the spec) takes the
largest as the side of the scaled cube. binvox 2 files may hold values up
to 255: a label image, read with ``--label``.

Written as binvox 1 on a cubic grid (the spec wants equal ``dim``: the array
is padded with empty voxels at the high end of the shorter axes), with
``translate`` and ``scale`` giving every voxel its world place in full float
precision. One voxel size only: anisotropic objects are refused.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .registry import RawVolume, check_shape, placement, reading, unit_not_kept

MAX_HEADER_LINES = 32


def read(path: Path, dataset: str | None = None) -> RawVolume:
    where = str(path)
    with reading(path, "binvox"), open(path, "rb") as fh:
        first = fh.readline(64)
        if not first.startswith(b"#binvox"):
            raise IsoflowError(f"{where}: not a binvox file (it does not start with '#binvox')")
        header = {}
        for _ in range(MAX_HEADER_LINES):
            line = fh.readline(256).split(b"#", 1)[0].strip()
            if line == b"data":
                break
            if line:
                key, *values = line.decode("ascii").split()
                header[key.lower()] = values
        else:
            raise IsoflowError(f"{where}: binvox header without a 'data' line")
        try:
            dims = [int(v) for v in header["dim"]]
            translate = [float(v) for v in header.get("translate", ["0", "0", "0"])]
            scale = float(header.get("scale", ["1"])[0])
        except (KeyError, ValueError, IndexError):
            raise IsoflowError(f"{where}: binvox header needs 'dim X Y Z' (and numbers in translate, scale): "
                               f"{header}") from None
        if len(dims) != 3 or min(dims) < 0 or len(translate) != 3:
            raise IsoflowError(f"{where}: binvox header has dim {dims} and translate {translate}; "
                               "expected three sizes and three numbers")
        check_shape(dims, np.uint8, where)
        runs = np.frombuffer(fh.read(), dtype=np.uint8)
    values, counts = runs[0::2], runs[1::2]
    voxels = int(counts.sum(dtype=np.int64))
    if len(runs) % 2 or voxels != math.prod(dims):
        raise IsoflowError(f"{where}: binvox data hold {voxels} voxels in {len(runs)} bytes; "
                           f"dim {dims} needs {math.prod(dims)} (a truncated or damaged file)")
    flat = np.repeat(values, counts)
    vol = flat.reshape(dims[0], dims[2], dims[1]).transpose(0, 2, 1)
    side = max(dims) or 1
    if not (np.isfinite(scale) and scale > 0 and np.isfinite(translate).all()):
        raise IsoflowError(f"{where}: binvox scale {scale} and translate {translate} must be finite, scale > 0")
    return RawVolume(vol, scale / side, np.array(translate))


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None) -> None:
    if obj.ndim != 3:
        raise IsoflowError(f"{path}: binvox holds 3D voxels, this object is {obj.ndim}D")
    if np.ndim(obj.pitch):
        raise IsoflowError(f"{path}: binvox holds one voxel size and this object's pitch is "
                           f"{np.round(obj.pitch, 9).tolist()}; write .nii.gz, .nrrd or .h5 to keep it")
    unit_not_kept(path, "binvox", unit)


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None) -> None:
    spacing, corner = placement(obj)
    side = max(obj.volume.shape)
    # scale is the cube's side in world units; the reader divides it by the side, or by 1 for an empty cube (0
    # voxels a side), whose scale must still be the voxel size: a scale of 0 is refused as damaged on reading
    cube = np.zeros((side,) * 3, np.uint8)
    cube[tuple(slice(0, s) for s in obj.volume.shape)] = obj.volume
    header = (f"#binvox 1\ndim {side} {side} {side}\n"
              f"translate {' '.join(repr(float(c)) for c in corner)}\n"
              f"scale {float(spacing[0]) * max(side, 1)!r}\ndata\n")
    with open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(run_lengths(cube.transpose(0, 2, 1).ravel()).tobytes())


def run_lengths(flat: np.ndarray) -> np.ndarray:
    """binvox's (value, count) byte pairs of a flat uint8 array, runs longer
    than 255 split."""
    if flat.size == 0:
        return np.zeros(0, np.uint8)
    starts = np.concatenate([[0], np.flatnonzero(flat[1:] != flat[:-1]) + 1])
    lengths = np.diff(np.append(starts, flat.size))
    pieces = (lengths + 254) // 255
    counts = np.full(int(pieces.sum()), 255, np.int64)
    counts[np.cumsum(pieces) - 1] = lengths - 255 * (pieces - 1)
    out = np.empty(2 * len(counts), np.uint8)
    out[0::2] = np.repeat(flat[starts], pieces)
    out[1::2] = counts
    return out
