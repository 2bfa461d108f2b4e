"""An HDF5 volume larger than memory, or whose report would not fit beside
it: ``isoflow info`` (a mask, ``--label N``) reads it a block at a time
(``isoflow.mesh.formats.hdf5.analyze_dataset``), as a .zarr store's, where
it was refused ("needs about ... more than the budget"). The memory is
held small with ``budget_held``; the truth is the report of the same file
read whole, and scikit-image's Euler number, area and box of the array
h5py reads back, placed by the file's voxel size and offset."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import torus
from test_input_errors import fails

from isoflow.cli import main
from isoflow.scale.memory import budget_held

h5py = pytest.importorskip("h5py")

SIZE_ZYX = np.array([2.0, 1.0, 0.5])
OFFSET_ZYX = np.array([10.0, 0.0, -3.0])
#: scikit-image's connectivity for isoflow's
SKIMAGE = {6: 1, 26: 3}


def porous(shape=(47, 45, 43), seed=3) -> np.ndarray:
    """Noise of voxels touching each other by faces, edges and corners, with
    a torus (a tunnel across the chunks) cut out of a solid slab."""
    rng = np.random.default_rng(seed)
    v = rng.random(shape) < 0.4
    v[5:40, 5:40, 15:28] = True
    v[2:43, 2:43, 1:42] &= ~torus(16, 5, size=41)
    return v


def report(capsys, *args) -> dict:
    assert main([*map(str, args)]) == 0
    return json.loads(capsys.readouterr().out)


def write(path, data, layout: str) -> None:
    with h5py.File(path, "w") as f:
        chunks = {"contiguous": None, "odd chunks": (5, 7, 43), "funlib c^zyx": (1, 5, 7, 43),
                  "funlib c^zyx contiguous": None}[layout]
        ds = f.create_dataset("v", data=data[None] if layout.startswith("funlib") else data, chunks=chunks)
        ds.attrs["resolution"] = SIZE_ZYX
        ds.attrs["offset"] = OFFSET_ZYX
        if layout.startswith("funlib"):  # a channel of one first: a contiguous dataset's layers are along z
            ds.attrs["axis_names"] = ["c^", "z", "y", "x"]


@pytest.mark.parametrize("conn", [6, 26])
@pytest.mark.parametrize("layout, values", [("contiguous", 255), ("odd chunks", 1), ("funlib c^zyx", 1),
                                            ("funlib c^zyx contiguous", 1)])
def test_a_mask_too_large_to_read_whole_is_read_a_block_at_a_time(tmp_path, capsys, layout, values, conn):
    from skimage.measure import euler_number, regionprops

    stored = porous()
    path = tmp_path / "mask.h5"
    write(path, stored.astype(np.uint8) * values, layout)  # 255: a mask written 0/255, read as read_volume reads it
    whole = report(capsys, "info", path, "--json", "--connectivity", conn)
    with budget_held(stored.size * 2):  # the whole read needs 3 bytes a voxel
        blocks = report(capsys, "info", path, "--json", "--connectivity", conn)
    assert blocks == whole
    named = layout.startswith("funlib")  # x, y, z is the stored z, y, x reversed; otherwise read as stored
    image, size, offset = (stored.T, SIZE_ZYX[::-1], OFFSET_ZYX[::-1]) if named else (stored, SIZE_ZYX, OFFSET_ZYX)
    assert blocks["euler_characteristic"] == euler_number(image, connectivity=SKIMAGE[conn])
    (props,) = regionprops(image.astype(np.uint8))
    assert blocks["voxels"] == props.area and np.isclose(blocks["volume"], props.area * np.prod(size))
    box = np.concatenate([offset + np.array(props.bbox[:3]) * size, offset + np.array(props.bbox[3:]) * size])
    assert np.allclose(blocks["bbox"], box) and blocks["pitch"] == size.tolist()


@pytest.mark.parametrize("conn", [6, 26])
def test_a_volume_read_whole_whose_report_would_not_fit_is_read_again_a_block_at_a_time(tmp_path, capsys, conn):
    # the file fits (4 bytes a voxel) but the report of label 7, noise of half the voxels, does not beside it (12
    # bytes a run and a gap on the compiled path, more on NumPy's): the same image as .npy is refused, the HDF5
    # file is read again a block at a time, and its label's report is the one the whole read gives
    rng = np.random.default_rng(5)
    shape = (47, 45, 43)
    labels = np.where(rng.random(shape) < 0.5, 7, np.where(rng.random(shape) < 0.5, 3, 0)).astype(np.uint16)
    path = tmp_path / "seg.h5"
    write(path, labels, "odd chunks")
    np.save(tmp_path / "seg.npy", labels)
    whole = report(capsys, "info", path, "--label", "7", "--json", "--connectivity", conn)
    budget = labels.size * 5
    with budget_held(budget):
        fails(capsys, "info", tmp_path / "seg.npy", "--label", "7", words=("needs about", "more than the budget"))
        blocks = report(capsys, "info", path, "--label", "7", "--json", "--connectivity", conn)
        absent = fails(capsys, "info", path, "--label", "5", words=("seg.h5: no voxel has label 5",))
        mixed = fails(capsys, "info", path, words=("seg.h5: not a binary volume", "--labels"))
    assert blocks == whole
    assert "(values present: 0, 3, 7)" in absent and "--label N" in mixed
    from skimage.measure import euler_number

    assert blocks["euler_characteristic"] == euler_number(labels == 7, connectivity=SKIMAGE[conn])


@pytest.mark.parametrize("conn", [6, 26])
def test_the_surface_of_a_label_too_large_to_read_whole_is_written_a_block_at_a_time(tmp_path, capsys, conn):
    # label 7 of a porous field and label 3 beside it, stored as funlib writes it (c^, z, y, x; a voxel size and a
    # world offset): the surface written block by block under a budget the whole read exceeds (3 bytes a voxel)
    # is the one written from the whole read, face for face, and trimesh reads back its volume as the voxels' and
    # its box as the file places them, pymeshlab a closed two-manifold of the genus of info's closed surfaces;
    # a label no voxel has is named with the values present; a surface that needs the whole mesh in memory (OBJ)
    # is refused, naming the ways that read a block at a time
    import pymeshlab
    import trimesh
    from scipy.ndimage import gaussian_filter

    field = gaussian_filter(np.random.default_rng(0).standard_normal((128,) * 3).astype(np.float32), 1.5)
    labels = np.where(field > 0, 7, np.where(field < -0.3, 3, 0)).astype(np.uint8)
    path = tmp_path / "seg.h5"
    with h5py.File(path, "w") as f:
        ds = f.create_dataset("seg", data=labels[None], chunks=(1, 16, 16, 16))
        ds.attrs.update({"axis_names": ["c^", "z", "y", "x"], "resolution": SIZE_ZYX, "offset": OFFSET_ZYX})
    command = ["surface", str(path), "--label", "7", "--threads", "1", "--connectivity", str(conn)]
    assert main([*command, "-o", str(tmp_path / "whole.ply")]) == 0
    with budget_held(int(labels.size * 2.9)):
        assert main([*command, "-o", str(tmp_path / "blocks.ply")]) == 0
        fails(capsys, "surface", path, "--label", "5", "-o", tmp_path / "none.ply", "--threads", "1",
              words=("seg.h5: no voxel has label 5 (values present: 0, 3, 7)",))
        fails(capsys, "surface", path, "--label", "7", "-o", tmp_path / "m.obj",
              words=("seg.h5: a ", "'isoflow surface FILE.h5:/DATASET -o OUT.ply' (or .stl) read a 3D HDF5 volume"))
    whole, blocks = (trimesh.load(tmp_path / f"{name}.ply", process=False) for name in ("whole", "blocks"))
    assert len(blocks.faces) == len(whole.faces) and np.allclose(blocks.bounds, whole.bounds)
    assert np.isclose(blocks.volume, np.count_nonzero(labels == 7) * np.prod(SIZE_ZYX))
    zyx = np.argwhere(labels == 7)
    lo, hi = OFFSET_ZYX + zyx.min(0) * SIZE_ZYX, OFFSET_ZYX + (zyx.max(0) + 1) * SIZE_ZYX
    assert np.allclose(blocks.bounds, [lo[::-1], hi[::-1]])  # x, y, z: the stored z, y, x reversed
    assert not (tmp_path / "none.ply").exists() and not (tmp_path / "m.obj").exists()
    surfaces = report(capsys, "info", path, "--label", 7, "--json", "--connectivity", conn)["surfaces"]
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(tmp_path / "blocks.ply"))
    topo = ms.get_topological_measures()
    assert topo["is_mesh_two_manifold"] and topo["boundary_edges"] == 0
    assert topo["genus"] == sum(s["genus"] for s in surfaces)
