"""MagicaVoxel ``.vox`` (read and written here: a RIFF-like chunk file).

Axes: a model's ``SIZE`` is (x, y, z), z up, and each ``XYZI`` voxel has
its (x, y, z) and a colour index 1-255; voxel ``(x, y, z)`` of isoflow's
array is that voxel. Colours are paint, not labels: every coloured voxel is
in the object, or one colour index with ``--label``. A file with several
models (a scene) is refused: isoflow reads one model. MagicaVoxel has no
voxel size or origin (1 and 0 on reading; a warning when writing an object
that has others) and models of at most 256 voxels a side.

Written as version 150 with one model, every voxel colour index 1 (the
default palette's white), which MagicaVoxel and the other .vox readers open;
a label image's voxels get their label (1-255) as colour index.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .registry import RawVolume, note, placement_lost, reading

MAX_SIDE = 256
VERSION = 150
#: the bytes a chunk's content holds at least: SIZE three int32, XYZI its count
_LEAST = {b"SIZE": 12, b"XYZI": 4}


class ModelTooLarge(IsoflowError):
    """An object past MagicaVoxel's :data:`MAX_SIDE` voxels a side. Its
    message states the format's limit only: what to do differs by caller
    (``voxelize`` a coarser grid, ``flow`` its steps in another format), so
    each caller that has a remedy adds it.

    Examples
    --------
    >>> import numpy as np
    >>> try:
    ...     check(Path("big.vox"), DigitalObject(np.zeros((300, 2, 2), bool)))
    ... except ModelTooLarge as exc:
    ...     print(exc)
    big.vox: MagicaVoxel models are at most 256 voxels a side, this object is 300x2x2
    """


def _chunks(data: bytes, start: int, end: int, where: str):
    """(id, content bytes, children start, children end) of the chunks in data[start:end]."""
    pos = start
    while pos < end:
        if pos + 12 > end:
            raise IsoflowError(f"{where}: truncated .vox chunk header at byte {pos}")
        cid, n, m = data[pos:pos + 4], *struct.unpack_from("<ii", data, pos + 4)
        body = pos + 12
        if n < 0 or m < 0 or body + n + m > end:
            raise IsoflowError(f"{where}: .vox chunk {cid!r} at byte {pos} runs past the end of the file")
        yield cid, data[body:body + n], body + n, body + n + m
        pos = body + n + m


def read(path: Path, dataset: str | None = None) -> RawVolume:
    where = str(path)
    with reading(path, "MagicaVoxel"):
        data = path.read_bytes()
    if data[:4] != b"VOX " or len(data) < 20:
        raise IsoflowError(f"{where}: not a MagicaVoxel file (it does not start with 'VOX ')")
    main = next(_chunks(data, 8, len(data), where))
    if main[0] != b"MAIN":
        raise IsoflowError(f"{where}: .vox without a MAIN chunk (found {main[0]!r})")
    sizes, models = [], []
    for cid, content, _, _ in _chunks(data, main[2], main[3], where):
        if cid in _LEAST and len(content) < _LEAST[cid]:
            raise IsoflowError(f"{where}: .vox {cid.decode()} chunk of {len(content)} bytes "
                               f"(it holds at least {_LEAST[cid]})")
        if cid == b"SIZE":
            sizes.append(struct.unpack_from("<3i", content))
        elif cid == b"XYZI":
            (count,) = struct.unpack_from("<i", content)
            if count < 0 or 4 + 4 * count > len(content):
                raise IsoflowError(f"{where}: .vox XYZI chunk says {count} voxels in {len(content)} bytes")
            models.append(np.frombuffer(content, np.uint8, 4 * count, 4).reshape(count, 4))
    if not models or len(sizes) != len(models):
        raise IsoflowError(f"{where}: .vox has {len(sizes)} SIZE and {len(models)} XYZI chunks; expected one model")
    if len(models) > 1:
        raise IsoflowError(f"{where}: a scene of {len(models)} models; isoflow reads a .vox with one model "
                           "(export each model on its own)")
    size, xyzi = sizes[0], models[0]
    if min(size) < 0 or max(size) > MAX_SIDE:
        raise IsoflowError(f"{where}: .vox model size {size} (MagicaVoxel models are 0-{MAX_SIDE} a side)")
    vol = np.zeros(size, np.uint8)
    xyz = xyzi[:, :3].astype(np.int64)
    if len(xyz) and (xyz >= np.array(size)).any():
        raise IsoflowError(f"{where}: .vox voxel {xyz[(xyz >= np.array(size)).any(1)][0].tolist()} "
                           f"lies outside the model's size {size}")
    vol[tuple(xyz.T)] = xyzi[:, 3]
    return RawVolume(vol, paint=True)


def check(path: Path, obj: DigitalObject, dataset: str | None = None, unit: str | None = None,
          space: str | None = None) -> None:
    if obj.ndim != 3:
        raise IsoflowError(f"{path}: MagicaVoxel holds 3D models, this object is {obj.ndim}D")
    if max(obj.volume.shape, default=0) > MAX_SIDE:
        raise ModelTooLarge(f"{path}: MagicaVoxel models are at most {MAX_SIDE} voxels a side, this object is "
                            f"{'x'.join(map(str, obj.volume.shape))}")
    # only what reads back otherwise (voxel size 1 from 0): a pitch of 1 is kept, as a PNG's is
    lost = placement_lost(obj, unit, space)
    if lost:
        note(f"{path}: MagicaVoxel keeps no voxel size, origin or unit; {' and '.join(lost)} "
             f"{'are' if len(lost) > 1 else 'is'} not written (read back as voxel size 1, origin 0)")


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    xyzi = voxel_list(obj.volume)
    size = struct.pack("<3i", *obj.volume.shape)
    voxels = 4 + xyzi.nbytes  # the count, then (x, y, z, colour) a byte each
    children = _chunk(b"SIZE", size) + b"XYZI" + struct.pack("<iii", voxels, 0, len(xyzi))
    with open(path, "wb") as fh:
        fh.write(b"VOX " + struct.pack("<i", VERSION))
        fh.write(b"MAIN" + struct.pack("<ii", 0, len(children) + xyzi.nbytes) + children)
        fh.write(xyzi.reshape(-1))  # a view of the list: a copy into bytes would hold it twice


def voxel_list(volume: np.ndarray) -> np.ndarray:
    """The (x, y, z, colour index) bytes of an ``XYZI`` chunk: a row a
    voxel that is not 0, in C order (x slowest), its colour 1 in a boolean
    volume and its value in a label image (1 to 255: what the format keeps).

    Built a slab of constant x at a time into one uint8 array of the set
    voxels' count, so that a volume's list holds 4 bytes a set voxel beside
    one slab's indices, where ``np.argwhere`` of the whole volume would hold
    24 and a stack of them with the colours 32 more.

    Parameters
    ----------
    volume : numpy.ndarray
        A 3D array of at most 256 voxels a side (each coordinate a byte).

    Returns
    -------
    numpy.ndarray
        uint8 of shape (voxels set, 4).

    Examples
    --------
    >>> vol = np.zeros((2, 3, 4), np.uint8)
    >>> vol[1, 2, 3], vol[0, 1, 0] = 7, 200
    >>> voxel_list(vol).tolist()
    [[0, 1, 0, 200], [1, 2, 3, 7]]
    >>> voxel_list(vol > 0)[:, 3].tolist()
    [1, 1]
    """
    xyzi = np.empty((np.count_nonzero(volume), 4), np.uint8)
    xyzi[:, 3] = 1
    row = 0
    for x, slab in enumerate(volume):
        y, z = np.nonzero(slab)
        end = row + len(y)
        # coordinates below 256 (check refuses more) and colours of 1 to 255 are a byte each
        xyzi[row:end, 0], xyzi[row:end, 1], xyzi[row:end, 2] = x, y, z
        if volume.dtype != np.bool_:
            xyzi[row:end, 3] = slab[y, z]
        row = end
    return xyzi


def _chunk(cid: bytes, content: bytes) -> bytes:
    return cid + struct.pack("<ii", len(content), 0) + content
