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
from ...errors import IsoflowError, coordinates
from .registry import RawVolume, check_shape, placement, reading, space_not_kept, unit_not_kept

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


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    if obj.ndim != 3:
        raise IsoflowError(f"{path}: binvox holds 3D voxels, this object is {obj.ndim}D")
    if np.ndim(obj.pitch):
        raise IsoflowError(f"{path}: binvox holds one voxel size and this object's pitch is "
                           f"{coordinates(obj.spacing)}; write .nii.gz, .nrrd or .h5 to keep it")
    unit_not_kept(path, "binvox", unit)
    space_not_kept(path, "binvox", space)


def written_shape(shape: tuple[int, ...]) -> tuple[int, int, int]:
    """The grid a volume of ``shape`` is written in: a cube of its longest
    side (the spec wants equal ``dim``; the shorter axes are padded with
    empty voxels at their high end, so the origin and every voxel keep
    their place).

    Parameters
    ----------
    shape : tuple of int
        The volume's shape, (x, y, z).

    Returns
    -------
    tuple of int

    Examples
    --------
    >>> written_shape((4, 5, 6)), written_shape((0, 0, 0))
    ((6, 6, 6), (0, 0, 0))
    """
    side = max(shape)
    return side, side, side


#: the cube is run-length coded about this many voxels at a time
SLAB_VOXELS = 1 << 20


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    spacing, corner = placement(obj)
    side = written_shape(obj.volume.shape)[0]
    # scale is the cube's side in world units; the reader divides it by the side, or by 1 for an empty cube (0
    # voxels a side), whose scale must still be the voxel size: a scale of 0 is refused as damaged on reading
    header = (f"#binvox 1\ndim {side} {side} {side}\n"
              f"translate {' '.join(repr(float(c)) for c in corner)}\n"
              f"scale {float(spacing[0]) * max(side, 1)!r}\ndata\n")
    with open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        for values, lengths in cube_runs(obj.volume, side):
            fh.write(run_bytes(values, lengths).tobytes())


def cube_runs(vol: np.ndarray, side: int, voxels: int = SLAB_VOXELS):
    """The maximal runs ``(values, lengths)`` of ``vol`` padded with zeros to
    a cube of ``side``, in binvox's order, a slab of about ``voxels`` voxels
    at a time: neither the cube nor its runs are ever held whole (a flat
    plate's cube is many times its grid; a thin shell has a run every few
    voxels). The run still open at the end of a slab is carried into the
    next, so the runs are those of the whole cube.

    Examples
    --------
    >>> vol = np.zeros((2, 1, 1), bool); vol[1] = True
    >>> [(v.tolist(), n.tolist()) for v, n in cube_runs(vol, 2, voxels=1)]
    [([0], [4]), ([1], [1]), ([0], [3])]
    """
    nx, ny, nz = vol.shape
    rows = max(1, voxels // max(1, side * side))
    carry: tuple[int, int] | None = None  # the run open at the end of the slabs so far
    for a in range(0, nx, rows):
        b = min(a + rows, nx)
        slab = np.zeros((b - a, side, side), np.uint8)
        slab[:, :nz, :ny] = vol[a:b].transpose(0, 2, 1)
        values, lengths = runs_of(slab.ravel())
        if carry is not None and carry[0] == values[0]:
            lengths[0] += carry[1]
        elif carry is not None:
            yield np.array([carry[0]], np.uint8), np.array([carry[1]], np.int64)
        if len(values) > 1:
            yield values[:-1], lengths[:-1]
        carry = int(values[-1]), int(lengths[-1])
    rest = (side - nx) * side * side  # the rows of the cube beyond the grid: empty
    if carry is not None and carry[0] == 0:
        carry = 0, carry[1] + rest
    elif rest:
        if carry is not None:
            yield np.array([carry[0]], np.uint8), np.array([carry[1]], np.int64)
        carry = 0, rest
    if carry is not None:
        yield np.array([carry[0]], np.uint8), np.array([carry[1]], np.int64)


def runs_of(flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The maximal runs of a flat, non-empty uint8 array: their values and
    lengths.

    Examples
    --------
    >>> [r.tolist() for r in runs_of(np.array([0, 0, 1, 1, 1, 0], np.uint8))]
    [[0, 1, 0], [2, 3, 1]]
    """
    starts = np.concatenate([[0], np.flatnonzero(flat[1:] != flat[:-1]) + 1])
    return flat[starts], np.diff(np.append(starts, flat.size))


def run_bytes(values: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """binvox's (value, count) byte pairs of runs, those longer than 255
    split."""
    pieces = (lengths + 254) // 255
    counts = np.full(int(pieces.sum()), 255, np.int64)
    counts[np.cumsum(pieces) - 1] = lengths - 255 * (pieces - 1)
    out = np.empty(2 * len(counts), np.uint8)
    out[0::2] = np.repeat(values, pieces)
    out[1::2] = counts
    return out
