"""HDF5, ``FILE.h5:/path/to/dataset`` (h5py).

Axes: the dataset's axes as stored (C order), axis 0 being x, as for
``.npy``. Without a dataset path the file must hold one dataset, or one
named ``volume``; otherwise the error lists the datasets to choose from.

Metadata: isoflow writes the attributes ``pitch`` (one number, or one per
axis), ``origin``, ``offset`` and ``parity`` on the dataset and reads them
back, so a round trip is exact. Files from other tools: their
``element_size_um`` attribute (ilastik and Fiji's HDF5 plug-in, one size per
dataset axis) is read as the voxel size when ``pitch`` is absent.

Written as uint8 0/1, gzip-compressed and chunked, into a new file
(``--force`` replaces the whole file, not one dataset of it).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .registry import RawVolume, check_shape, import_library, reading, stored_values

DEFAULT_DATASET = "volume"


def read(path: Path, dataset: str | None = None) -> RawVolume:
    h5py = import_library("h5py", "HDF5")
    where = str(path) if dataset is None else f"{path}:{dataset}"
    with reading(path, "HDF5"), h5py.File(path, "r") as f:
        ds = f[_choose(f, h5py, path, dataset)]
        check_shape(ds.shape, ds.dtype, where)
        array = ds[()]
        attrs = dict(ds.attrs)
    pitch = attrs.get("pitch", attrs.get("element_size_um", 1.0))
    offset = attrs.get("offset")
    return RawVolume(np.asarray(array), pitch, attrs.get("origin"), offset, attrs.get("parity", 0))


def _choose(f, h5py, path, dataset) -> str:
    """The dataset's name: the one given, or the file's only one, or 'volume'."""
    names: list[str] = []
    f.visititems(lambda name, node: names.append(name) if isinstance(node, h5py.Dataset) else None)
    if dataset is not None:
        if dataset not in f:
            raise IsoflowError(f"{path}: no dataset {dataset!r} (datasets: {_listed(names)})")
        if not isinstance(f[dataset], h5py.Dataset):
            raise IsoflowError(f"{path}: {dataset!r} is a group, not a dataset (datasets: {_listed(names)})")
        return dataset
    if DEFAULT_DATASET in names:
        return DEFAULT_DATASET
    if len(names) == 1:
        return names[0]
    if not names:
        raise IsoflowError(f"{path}: holds no dataset")
    raise IsoflowError(f"{path}: holds datasets {_listed(names)}; name one, e.g. {path}:/{names[0]}")


def _listed(names: list[str]) -> str:
    shown = ", ".join("/" + n for n in names[:10])
    return (shown + f", ... ({len(names)} in all)" if len(names) > 10 else shown) or "none"


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None) -> None:
    h5py = import_library("h5py", "HDF5")
    name = (dataset or DEFAULT_DATASET).strip("/") or DEFAULT_DATASET
    with h5py.File(path, "w") as f:
        ds = f.create_dataset(name, data=stored_values(obj.volume), compression="gzip",
                              chunks=True if obj.volume.size else None)
        ds.attrs["pitch"] = np.asarray(obj.pitch, np.float64)
        ds.attrs["origin"] = obj.origin
        ds.attrs["offset"] = np.array(obj.offset, np.int64)
        ds.attrs["parity"] = np.int64(obj.parity)
