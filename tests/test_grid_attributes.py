"""The voxel size and place other tools write in an HDF5 dataset's or a
plain zarr array's attributes (``isoflow.mesh.formats.grid_attributes``).

A CREMI volume (``resolution`` 40 x 4 x 4 nm, ``offset`` in nm) was read
with voxels of 1 and its offset taken as a count of voxels: volumes and
areas in voxels and its box 40 and 4 times too far out, with exit 0. The
truth here is gunpowder's rule (world = offset + index x voxel size) on
the array h5py and zarr read back, and scikit-image's ``regionprops``
with that spacing for the volumes."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from in_process import isoflow_here
from test_input_errors import fails

import isoflow

h5py = pytest.importorskip("h5py")

RESOLUTION = np.array([40.0, 4.0, 4.0])  # CREMI's z, y, x in nm, read as stored: axis 0 is isoflow's x
OFFSET = np.array([1520.0, 8.0, 12.0])  # voxel 0's corner, in nm


def labels() -> np.ndarray:
    """Three labels touching by faces, edges and corners, one with a tunnel
    (chi 0), stored as CREMI stores neuron ids (uint64)."""
    a = np.zeros((6, 9, 10), np.uint64)
    a[1:5, 1:8, 1:9] = 7
    a[1:5, 3:6, 4:6] = 0  # a tunnel through 7 along x
    a[2:4, 3:6, 4:6] = 9  # 9 inside the tunnel, touching 7 by faces
    a[5, 8, 9] = 5  # 5 touches 7 by a corner
    a[5, 0, 0] = 5  # and is in two pieces
    return a


def expected(a: np.ndarray, label: int) -> dict:
    """Volume from scikit-image with the voxel size, box and centroid by
    gunpowder's rule on the array as stored."""
    from skimage.measure import regionprops_table

    area = dict(zip(*regionprops_table(a.astype(np.int64), spacing=tuple(RESOLUTION),
                                       properties=("label", "area")).values()))
    cells = np.argwhere(a == label)
    low, high = OFFSET + cells.min(0) * RESOLUTION, OFFSET + (cells.max(0) + 1) * RESOLUTION
    return {"volume": area[label], "bbox": np.concatenate([low, high]),
            "centroid": OFFSET + (cells + 0.5).mean(0) * RESOLUTION}


def cremi(path, a: np.ndarray, **attrs) -> str:
    """An HDF5 file laid out as CREMI's, the labels with ``attrs``."""
    with h5py.File(path, "w") as f:
        f.create_dataset("volumes/raw", data=np.zeros(a.shape, np.uint8)).attrs["resolution"] = RESOLUTION
        ds = f.create_dataset("volumes/labels/neuron_ids", data=a)
        for key, value in attrs.items():
            ds.attrs[key] = value
    return f"{path}:/volumes/labels/neuron_ids"


def row_of(table: dict, label: int) -> dict:
    return next(r for r in table["labels"] if r["label"] == label)


def test_a_cremi_volume_is_in_nanometres_at_its_offset(tmp_path):
    """``info --labels`` (the command, run as a user runs it) of a CREMI
    volume: every label's volume, box and centroid in the file's nm, and
    ``info --label`` and the surface ``trimesh`` reads back agree."""
    a = labels()
    given = cremi(tmp_path / "sample_A.hdf", a, resolution=RESOLUTION, offset=OFFSET)
    with h5py.File(tmp_path / "sample_A.hdf") as f:
        stored = f["volumes/labels/neuron_ids"][()]
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", given, "--labels", "--json"],
                          capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    table = json.loads(done.stdout)
    assert np.allclose(table["pitch"], RESOLUTION) and np.allclose(table["origin"], OFFSET)
    for label in (5, 7, 9):
        row, truth = row_of(table, label), expected(stored, label)
        assert np.isclose(row["volume"], truth["volume"]), label
        assert np.allclose([row[f"bbox-{i}"] for i in range(6)], truth["bbox"]), label
        assert np.allclose([row[f"centroid-{i}"] for i in range(3)], truth["centroid"]), label
    assert (row_of(table, 7)["euler_characteristic"], row_of(table, 5)["b0"]) == (0, 2)

    one = isoflow_here("info", given, "--label", "9", "--json")
    assert one.returncode == 0, one.stderr
    assert np.allclose(json.loads(one.stdout)["bbox"], expected(stored, 9)["bbox"])
    made = isoflow_here("surface", given, "--label", "9", "-o", tmp_path / "nine.ply")
    assert made.returncode == 0, made.stderr
    mesh = trimesh.load(tmp_path / "nine.ply", process=False)
    box = expected(stored, 9)["bbox"]
    assert np.allclose(mesh.bounds, [box[:3], box[3:]])
    assert np.isclose(mesh.volume, expected(stored, 9)["volume"])


def test_a_gunpowder_zarr_is_placed_in_memory_and_block_by_block(tmp_path):
    """A plain zarr array with gunpowder's ``resolution`` and ``offset``:
    the label table read block by block (odd chunks) and in memory (a
    label selected) and the surface written block by block all place it
    as gunpowder does."""
    zarr = pytest.importorskip("zarr")
    pytest.importorskip("dask")
    a = labels()
    z = zarr.create_array(str(tmp_path / "seg.zarr"), data=a, chunks=(4, 5, 3))
    z.attrs.update(resolution=RESOLUTION.tolist(), offset=OFFSET.tolist())
    stored = zarr.open_array(str(tmp_path / "seg.zarr"), mode="r")[...]
    done = isoflow_here("info", tmp_path / "seg.zarr", "--labels", "--json")
    assert done.returncode == 0, done.stderr
    table = json.loads(done.stdout)
    for label in (5, 7, 9):
        row, truth = row_of(table, label), expected(stored, label)
        assert np.isclose(row["volume"], truth["volume"])
        assert np.allclose([row[f"bbox-{i}"] for i in range(6)], truth["bbox"])
    solid = isoflow.read_volume(tmp_path / "seg.zarr", label=7)
    assert np.allclose(solid.bbox(), expected(stored, 7)["bbox"].reshape(2, 3))
    made = isoflow_here("surface", tmp_path / "seg.zarr", "--label", "7", "-o", tmp_path / "seven.ply")
    assert made.returncode == 0, made.stderr
    box = expected(stored, 7)["bbox"]
    assert np.allclose(trimesh.load(tmp_path / "seven.ply", process=False).bounds, [box[:3], box[3:]])


def test_funlib_voxel_size_takes_its_units(tmp_path):
    """funlib.persistence's ``voxel_size`` with ``units``: the unit is
    reported, a z in µm beside y and x in nm converted to the first
    axis's unit, as an OME-TIFF's are."""
    a = labels()
    given = cremi(tmp_path / "f.h5", a, voxel_size=[0.04, 4.0, 4.0], offset=[1.52, 8.0, 12.0],
                  units=["um", "nm", "nm"])
    done = isoflow_here("info", given, "--label", "9", "--json")
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    assert got["unit"] == "\u00b5m"
    assert np.allclose(got["pitch"], RESOLUTION / 1000) and np.allclose(got["origin"], OFFSET / 1000)
    assert np.isclose(got["volume"], expected(a, 9)["volume"] / 1e9)


def test_a_plain_zarr_pitch_alone_places_every_reading_alike(tmp_path):
    """A plain zarr array with isoflow's ``pitch`` and no ``origin`` was
    read with voxels of 1 in memory (``info``) but with its pitch block
    by block (``info --labels``): one file, two sizes. Both read it."""
    zarr = pytest.importorskip("zarr")
    a = labels()
    z = zarr.create_array(str(tmp_path / "p.zarr"), data=a, chunks=(4, 5, 3))
    z.attrs.update(pitch=[2.0, 1.0, 1.5])
    mask = isoflow_here("info", tmp_path / "p.zarr", "--label", "9", "--json")
    table = isoflow_here("info", tmp_path / "p.zarr", "--labels", "9", "--json")
    assert mask.returncode == table.returncode == 0, mask.stderr + table.stderr
    count = int((a == 9).sum())
    assert np.isclose(json.loads(mask.stdout)["volume"], count * 3.0)
    assert np.isclose(row_of(json.loads(table.stdout), 9)["volume"], count * 3.0)


def test_two_voxel_sizes_or_a_bad_one_are_refused_by_name(tmp_path, capsys):
    a = labels()
    given = cremi(tmp_path / "two.h5", a, resolution=RESOLUTION, element_size_um=[0.04, 0.004, 0.008])
    fails(capsys, "info", given, "--label", "7", words=("two.h5", "'resolution' [40.0, 4.0, 4.0]",
                                                         "'element_size_um' [0.04, 0.004, 0.008]", "keep one"))
    given = cremi(tmp_path / "same.h5", a, resolution=RESOLUTION, voxel_size=RESOLUTION)
    assert isoflow_here("info", given, "--label", "7").returncode == 0
    given = cremi(tmp_path / "neg.h5", a, resolution=[40.0, -4.0, 4.0])
    fails(capsys, "info", given, "--label", "7", words=("neg.h5", "attribute 'resolution' [40.0, -4.0, 4.0]",
                                                         "positive voxel sizes"))
    given = cremi(tmp_path / "off.h5", a, resolution=RESOLUTION, offset=[1.0, 2.0])
    fails(capsys, "info", given, "--label", "7", words=("off.h5", "attribute 'offset' [1.0, 2.0]", "3 numbers"))


def test_an_unread_voxel_size_is_said(tmp_path):
    """N5's ``pixelResolution`` is not read: the volume is in voxels, and
    a warning names the attribute rather than leaving it unsaid."""
    a = labels()
    given = cremi(tmp_path / "n5.h5", a, pixelResolution=json.dumps({"dimensions": [4, 4, 40], "unit": "nm"}))
    done = isoflow_here("info", given, "--label", "9", "--json")
    assert done.returncode == 0
    assert np.isclose(json.loads(done.stdout)["volume"], int((a == 9).sum()))
    assert done.stderr.strip().splitlines() == [
        f"isoflow info: warning: {given}: its attribute 'pixelResolution' is not read: voxels of 1 (isoflow reads the voxel "
        "size from pitch, element_size_um, resolution, voxel_size, spacing)"]


def test_a_cremi_hdf_file_is_hdf5_and_an_hdf4_one_is_named(tmp_path, capsys):
    """CREMI names its HDF5 files ``.hdf``, which isoflow did not take as a
    volume at all ("not a volume file"); HDF4 used the suffix too, and
    such a file gets one line saying what it holds and how to convert it."""
    a = labels()
    given = cremi(tmp_path / "sample_B.hdf", a, resolution=RESOLUTION)
    assert np.array_equal(isoflow.read_volume(given, label=9).volume, a == 9)
    (tmp_path / "modis.hdf").write_bytes(b"\x0e\x03\x13\x01" + bytes(200))  # HDF4's signature
    fails(capsys, "info", tmp_path / "modis.hdf", words=("modis.hdf", "its content is HDF4, not HDF5", "h4toh5"))


def test_a_time_series_takes_a_voxel_size_of_its_three_axes(tmp_path):
    """A 4D dataset (x, y, z, t) with ``resolution`` of its three axes in
    space: each time point is placed by them (as a NIfTI's time steps
    are), where the count of entries was refused."""
    a = np.stack([labels(), labels()], axis=-1)
    given = cremi(tmp_path / "t.h5", a, resolution=RESOLUTION, offset=OFFSET)
    one = isoflow.read_volume(given, label=9, time=1)
    assert np.allclose(one.spacing, RESOLUTION) and np.allclose(one.origin, OFFSET)
    assert np.isclose(one.volume.sum() * np.prod(one.spacing), expected(labels(), 9)["volume"])


def bar_zyx() -> np.ndarray:
    """A bar along stored axis 0, which funlib's names call z."""
    zyx = np.zeros((9, 4, 5), np.uint8)
    zyx[1:8, 1:3, 2:4] = 1
    return zyx


def named_truth(zyx: np.ndarray, size_zyx, offset_zyx) -> np.ndarray:
    """The bar's box by its names: the array transposed to x, y, z, placed
    by the sizes and offset of those axes."""
    cells = np.argwhere(zyx.T)
    size, offset = np.asarray(size_zyx, float)[::-1], np.asarray(offset_zyx, float)[::-1]
    return np.concatenate([offset + cells.min(0) * size, offset + (cells.max(0) + 1) * size])


def test_funlib_axis_names_place_a_zarr_array_by_name(tmp_path):
    """funlib.persistence writes ``axis_names`` z, y, x beside
    ``voxel_size`` and ``offset`` (all in that order). The array was read
    as stored, its z as x: the box and surface the mirror image of the
    volume the names describe. It is read by its names, in memory and
    block by block (odd chunks), as zarr v3's ``dimension_names`` are."""
    zarr = pytest.importorskip("zarr")
    pytest.importorskip("dask")
    zyx = bar_zyx()
    z = zarr.create_array(str(tmp_path / "f.zarr"), data=zyx, chunks=(4, 3, 2))
    z.attrs.update(axis_names=["z", "y", "x"], voxel_size=[40, 4, 4], offset=[80, 8, 12], units=["nm", "nm", "nm"])
    box = named_truth(zyx, [40, 4, 4], [80, 8, 12])
    assert box[5] - box[2] == 7 * 40  # the bar runs along z
    mask = isoflow_here("info", tmp_path / "f.zarr", "--json")
    table = isoflow_here("info", tmp_path / "f.zarr", "--labels", "--json")
    assert mask.returncode == table.returncode == 0, mask.stderr + table.stderr
    assert mask.stderr == table.stderr == ""
    got = json.loads(mask.stdout)
    assert got["unit"] == "nm" and got["shape"] == [5, 4, 9] and np.allclose(got["bbox"], box)
    assert np.allclose([row_of(json.loads(table.stdout), 1)[f"bbox-{i}"] for i in range(6)], box)
    made = isoflow_here("surface", tmp_path / "f.zarr", "-o", tmp_path / "bar.ply")
    assert made.returncode == 0, made.stderr
    assert np.allclose(trimesh.load(tmp_path / "bar.ply", process=False).bounds, box.reshape(2, 3))


def test_funlib_axis_names_place_an_hdf5_dataset_by_name(tmp_path, capsys):
    """The same in HDF5, with funlib's channel axis of one entry (``c^``)
    first and a voxel size of the three axes in space: the channel is
    dropped, as ilastik's ``c`` is; one of several entries is refused by
    name."""
    zyx = bar_zyx()
    with h5py.File(tmp_path / "f.h5", "w") as f:
        ds = f.create_dataset("pred", data=zyx[None])
        ds.attrs.update({"axis_names": ["c^", "z", "y", "x"], "voxel_size": [40, 4, 4], "offset": [80, 8, 12]})
        many = f.create_dataset("many", data=np.stack([zyx, zyx]))
        many.attrs.update({"axis_names": ["c^", "z", "y", "x"], "voxel_size": [40, 4, 4]})
    done = isoflow_here("info", f"{tmp_path / 'f.h5'}:/pred", "--json")
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    assert got["shape"] == [5, 4, 9] and np.allclose(got["bbox"], named_truth(zyx, [40, 4, 4], [80, 8, 12]))
    fails(capsys, "info", f"{tmp_path / 'f.h5'}:/many", words=("f.h5:/many: axis 'c' has 2 entries",
                                                                 "(axis_names czyx, shape (2, 9, 4, 5))"))
