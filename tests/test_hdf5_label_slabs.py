"""An HDF5 label image that would not fit in memory whole: ``info
--labels`` reads it a slab at a time (``isoflow.mesh.formats.hdf5.LabelSlabs``),
as a .zarr store's, where it was refused ("needs about ... more than the
budget"). The memory is held small with ``budget_held``; the truth is the
table of the same file read whole (which ``label_table`` equals
``analyze`` label by label) and scikit-image's ``regionprops`` of the
array h5py reads back, placed by the file's voxel size and offset."""

from __future__ import annotations

import json

import numpy as np
import pytest

from isoflow.cli import main
from isoflow.scale.memory import budget_held

h5py = pytest.importorskip("h5py")

SIZE_ZYX = np.array([2.0, 1.0, 0.5])
OFFSET_ZYX = np.array([10.0, 0.0, -3.0])


def grains(shape=(93, 95, 91), seed=1) -> np.ndarray:
    """Cubes of 16 voxels, 40 labels among them (each in several pieces,
    touching each other by faces, edges and corners), cut to odd sides."""
    rng = np.random.default_rng(seed)
    cubes = np.kron(rng.integers(0, 40, (6, 6, 6)), np.ones((16, 16, 16), int)).astype(np.uint32)
    return cubes[tuple(slice(0, n) for n in shape)]


def table(capsys, *args) -> dict:
    assert main([*map(str, args)]) == 0
    out = capsys.readouterr()
    return json.loads(out.out)


@pytest.mark.parametrize("conn", [6, 26])
@pytest.mark.parametrize("layout", ["contiguous", "odd chunks", "funlib c^zyx", "funlib c^zyx contiguous"])
def test_a_label_image_too_large_to_read_whole_is_read_in_slabs(tmp_path, capsys, layout, conn):
    stored = grains()
    path = tmp_path / "seg.h5"
    with h5py.File(path, "w") as f:
        data = stored[None] if layout.startswith("funlib") else stored
        # a contiguous dataset with a channel of one first is layered along z
        chunks = {"contiguous": None, "odd chunks": (5, 7, 91), "funlib c^zyx": (1, 9, 95, 13),
                  "funlib c^zyx contiguous": None}[layout]
        ds = f.create_dataset("seg", data=data, chunks=chunks)
        ds.attrs["resolution"] = SIZE_ZYX
        ds.attrs["offset"] = OFFSET_ZYX
        if layout.startswith("funlib"):
            ds.attrs["axis_names"] = ["c^", "z", "y", "x"]
    whole = table(capsys, "info", path, "--labels", "--json", "--connectivity", conn)
    with budget_held(stored.size * 5):  # the whole read needs 6 bytes a voxel
        one = table(capsys, "info", path, "--label", "1", "--json", "--connectivity", conn)  # a block at a time
        slabs = table(capsys, "info", path, "--labels", "--json", "--connectivity", conn)
    assert slabs == whole
    (row,) = [r for r in slabs["labels"] if r["label"] == 1]
    assert [one[k] for k in ("voxels", "volume", "euler_characteristic")] == [row[k] for k in ("voxels", "volume",
                                                                                               "euler_characteristic")]
    assert one["betti"] == [row["b0"], row["b1"], row["b2"]] and one["bbox"] == [row[f"bbox-{i}"] for i in range(6)]

    from skimage.measure import regionprops

    # funlib's names turn the axes: x, y, z is the stored z, y, x reversed; otherwise read as stored
    named = layout.startswith("funlib")
    image, size, offset = (stored.T, SIZE_ZYX[::-1], OFFSET_ZYX[::-1]) if named else (stored, SIZE_ZYX, OFFSET_ZYX)
    rows = {r["label"]: r for r in slabs["labels"]}
    props = regionprops(image.astype(np.int64))
    assert sorted(rows) == [p.label for p in props]
    for p in props:
        row = rows[p.label]
        assert np.isclose(row["volume"], p.area * np.prod(size))
        box = np.concatenate([offset + np.array(p.bbox[:3]) * size, offset + np.array(p.bbox[3:]) * size])
        assert np.allclose([row[f"bbox-{i}"] for i in range(6)], box)
