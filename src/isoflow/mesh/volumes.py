"""Reading volumes and point lists; writing volumes.

Every reader raises :class:`~isoflow.errors.IsoflowError` with the file name
and what is wrong; every writer refuses to replace an existing file unless
``force=True``.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from ..digital.lattice import MAX_COORDINATE, DigitalObject
from ..errors import IsoflowError
from ..scale.arrays import binary
from .outputs import atomic_write, check_output_path

VOLUME_SUFFIXES = (".npy", ".npz")
POINT_SUFFIXES = (".txt", ".xyz", ".pts", ".csv")


def _check_readable(path: Path) -> None:
    if not path.exists():
        raise IsoflowError(f"{path}: no such file")
    if path.is_dir():
        if path.suffix != ".zarr":
            raise IsoflowError(f"{path}: is a directory, not a volume or point list")
    elif not path.is_file():
        # a device or FIFO would be read until memory runs out (/dev/zero)
        raise IsoflowError(f"{path}: not a regular file (a device, pipe or socket)")


def read_volume(path: str | os.PathLike) -> DigitalObject:
    """A 2D or 3D volume from ``.npy`` or ``.npz``.

    An ``.npz`` written by :func:`write_volume` carries ``volume`` plus its
    ``offset``, ``parity``, ``pitch`` and ``origin``; any other ``.npz`` must
    hold exactly one array (or one named ``volume``).
    """
    path = Path(path)
    _check_readable(path)
    meta: dict = {}
    try:
        loaded = np.load(path, allow_pickle=False)
        # trust the content, not the name: an .npz may be called .npy or .NPZ
        if isinstance(loaded, np.lib.npyio.NpzFile):
            with loaded as z:
                names = list(z.files)
                if "volume" in names:
                    arr = z["volume"]
                    for key in ("offset", "parity", "pitch", "origin"):
                        if key in names:
                            meta[key] = z[key]
                elif len(names) == 1:
                    arr = z[names[0]]
                else:
                    raise IsoflowError(
                        f"{path}: holds arrays {names}; name the volume 'volume'"
                    )
        elif isinstance(loaded, np.ndarray):
            arr = loaded
        else:
            raise IsoflowError(f"{path}: not a numpy array or archive ({type(loaded).__name__})")
    except IsoflowError:
        raise
    except Exception as exc:  # numpy raises several types for a bad file
        raise IsoflowError(f"{path}: not a readable numpy file ({exc.__class__.__name__}: {exc})") from None
    if arr.ndim not in (2, 3, 4):
        raise IsoflowError(f"{path}: a volume must be 2D, 3D or 4D, this array is {arr.ndim}D with shape {arr.shape}")
    vol = binary(arr, str(path))
    try:  # DigitalObject checks the metadata fields; its errors get the file's name
        return DigitalObject(vol, **meta)
    except IsoflowError as exc:
        raise IsoflowError(f"{path}: {exc}") from None


_SPLIT = re.compile(r"[,\s]+")


def read_points(path: str | os.PathLike) -> np.ndarray:
    """Integer lattice points from a text file: ``x y z`` (or ``x y``) per
    line, ``#`` starts a comment, commas or blanks separate the numbers."""
    path = Path(path)
    _check_readable(path)
    try:
        # look at the head first: any file of unknown type lands here, and
        # a big binary one should not be read whole before being refused
        with open(path, "rb") as fh:
            head = fh.read(1024)
        if b"\0" in head:
            raise IsoflowError(
                f"{path}: binary data, not a text point list (x y z per line); "
                f"volumes are .npy/.npz"
            )
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise IsoflowError(f"{path}: cannot read as text ({exc})") from None
    rows, width = [], None
    for lineno, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        fields = [f for f in _SPLIT.split(line) if f]
        if width is None:
            width = len(fields)
            if width not in (2, 3):
                raise IsoflowError(f"{path}:{lineno}: expected 2 or 3 coordinates, got {len(fields)}")
        elif len(fields) != width:
            raise IsoflowError(f"{path}:{lineno}: expected {width} coordinates, got {len(fields)}")
        try:
            values = [float(f) for f in fields]
        except ValueError:
            raise IsoflowError(f"{path}:{lineno}: not a number in {line!r}") from None
        for f, v in zip(fields, values):
            if not np.isfinite(v) or v != round(v):
                raise IsoflowError(f"{path}:{lineno}: coordinate {f} is not an integer")
            if abs(v) > MAX_COORDINATE:  # 1e300 or int64 extremes overflow later
                raise IsoflowError(f"{path}:{lineno}: coordinate {f} is out of range (beyond +-{MAX_COORDINATE})")
        rows.append([int(round(v)) for v in values])
    if not rows:
        raise IsoflowError(f"{path}: no points")
    return np.array(rows, dtype=np.int64)


def read_object(path: str | os.PathLike, points_are: str = "corners") -> DigitalObject:
    """A digital object from a volume file or a point list.

    ``points_are='corners'`` reads a point list with the paper's point model
    (Definitions 1-2); ``'voxels'`` takes each point as a voxel index.
    """
    path = Path(path)
    if points_are not in ("corners", "voxels"):
        raise IsoflowError(f"points_are must be 'corners' or 'voxels', got {points_are!r}")
    if path.suffix.lower() in VOLUME_SUFFIXES:
        return read_volume(path)
    pts = read_points(path)
    try:
        if points_are == "voxels":
            return DigitalObject.from_voxels(pts)
        return DigitalObject.from_points(pts)
    except IsoflowError as exc:  # e.g. the grid beyond the memory budget: say which file
        raise IsoflowError(f"{path}: {exc}") from None



def write_volume(obj: DigitalObject, path: str | os.PathLike, force: bool = False) -> Path:
    """Save an object as ``.npz`` with its offset, parity, pitch and origin."""
    path = Path(path)
    check_output_path(path, force)
    with atomic_write(path) as fh:  # whole or not at all: never a truncated .npz
        np.savez_compressed(
            fh,
            volume=obj.volume,
            offset=np.array(obj.offset, np.int64),
            parity=np.int64(obj.parity),
            pitch=np.float64(obj.pitch),
            origin=obj.origin,
        )
    return path
