"""Many labels' boundary meshes per call (isoflow.digital.label_meshes):
each label's part equals boundary_mesh of that label's box alone (the same
vertices with their configurations and sheets, the same faces with their
normals and edge midpoints, the same pinched count), on random label
images with face, edge and vertex contacts, nested labels, at 6 and 26,
meshed by NumPy and compiled, in batches of one box, a few, and all."""

import numpy as np
import pytest

from isoflow.digital import label_meshes as lm
from isoflow.digital.surface import boundary_mesh


def canonical(mesh):
    """The mesh as sets keyed by positions (order-free): each vertex's
    position, sheet and configuration; each face as its corners' and its
    edge midpoints' keys from its lowest corner on, with its normal."""
    key = [tuple(np.round(v, 6)) + (int(s),) for v, s in zip(mesh.vertices.tolist(), mesh.sheet.tolist())]
    vertices = sorted(zip(key, mesh.config.tolist()))
    faces = []
    for f, mid, n in zip(mesh.faces.tolist(), mesh.edge_midpoint.tolist(), mesh.face_normals.tolist()):
        corners = [key[i] for i in f]
        mids = [key[i] if i >= 0 else None for i in mid]
        r = corners.index(min(corners))
        faces.append((tuple(corners[r:] + corners[:r]), tuple(mids[r:] + mids[:r]), tuple(n)))
    return vertices, sorted(faces), mesh.pinched


def boxes(image):
    labels = np.unique(image)
    labels = labels[labels != 0]
    where = [np.argwhere(image == v) for v in labels]
    return labels, np.array([w.min(axis=0) for w in where]), np.array([w.max(axis=0) + 1 for w in where])


@pytest.mark.parametrize("method", ["numpy", "compiled"])
@pytest.mark.parametrize("conn", [6, 26])
def test_each_labels_part_is_its_boxs_mesh(rng, monkeypatch, method, conn):
    for trial, batch in enumerate([1, 300, 1 << 22]):
        monkeypatch.setattr(lm, "BATCH_VOXELS", batch)
        image = rng.choice([0, 1, 2, 3, 5], size=(11, 9, 10), p=[0.3, 0.2, 0.2, 0.2, 0.1]).astype(np.uint16)
        image[2:8, 2:7, 3:9] = 7  # a label holding another
        image[4:6, 4:5, 5:7] = 8
        labels, lo, hi = boxes(image)
        found = lm.label_meshes(image, labels, lo, hi, conn, method=method)
        assert len(found) == len(labels)
        midpoints = 0
        for label, a, b, (mesh, mask) in zip(labels, lo, hi, found):
            alone = image[a[0]:b[0], a[1]:b[1], a[2]:b[2]] == label
            np.testing.assert_array_equal(mask, alone)
            want = boundary_mesh(alone, conn, method="numpy")
            assert canonical(mesh) == canonical(want), (trial, label)
            assert mesh.euler_characteristic == want.euler_characteristic
            midpoints += want.midpoints
    assert midpoints > 0 or conn == 6  # the random images have doubled edges at 26


@pytest.mark.parametrize("dtype", ["u1", "i2", "u4", "i8", "u8", ">u2"])
def test_masks_of_every_integer_type_are_the_labels_voxels(rng, monkeypatch, dtype):
    """Each label's mask, as the batch's one compiled pass lays it (a
    big-endian image's too: values compared as unsigned integers of their
    width), is
    ``image[box] == label`` (of values near the type's top too, where a
    conversion would be off by one)."""
    monkeypatch.setattr(lm, "BATCH_VOXELS", 400)
    top = np.iinfo(np.dtype(dtype)).max
    values = np.array([0, 1, 2, top - 1, top], dtype=np.dtype(dtype).newbyteorder("="))
    image = values[rng.choice(5, size=(9, 8, 7), p=[0.3, 0.2, 0.2, 0.15, 0.15])].astype(dtype)
    labels, lo, hi = boxes(image)
    found = lm.label_meshes(image, labels, lo, hi, 26, method="compiled")
    for label, a, b, (mesh, mask) in zip(labels, lo, hi, found):
        np.testing.assert_array_equal(mask, image[a[0]:b[0], a[1]:b[1], a[2]:b[2]] == label)
        assert mesh.euler_characteristic == boundary_mesh(mask.copy(), 26, method="numpy").euler_characteristic


def test_a_box_larger_than_a_batch_is_meshed_alone(monkeypatch):
    monkeypatch.setattr(lm, "BATCH_VOXELS", 10)
    image = np.zeros((6, 5, 4), np.uint8)
    image[0:6, 0:5, 0:4] = 1
    image[2:4, 2:3, 1:3] = 2
    labels, lo, hi = boxes(image)
    (big, _), (small, _) = lm.label_meshes(image, labels, lo, hi)
    assert (big.euler_characteristic, small.euler_characteristic) == (4, 2)  # 1 is hollow: two spheres


@pytest.mark.parametrize("origin", [(1.0, -2.0, 0.5), (4e6 + 0.1, 0.0, -3e5)])
def test_batch_glb_parts_are_each_parts_own(rng, monkeypatch, origin):
    """The glTF parts computed once over a batch equal glb_part of each
    label's mesh and box (columns, triangles, and the node transform where
    float32 cannot hold the world positions: far from the origin)."""
    from isoflow.digital.lattice import DigitalObject
    from isoflow.mesh import export

    monkeypatch.setattr(lm, "BATCH_VOXELS", 2000)
    image = rng.choice([0, 1, 2, 3], size=(12, 8, 9), p=[0.4, 0.2, 0.2, 0.2]).astype(np.uint8)
    labels, lo, hi = boxes(image)
    pitch = (0.5, 1.25, 3.0)
    names = [f"label_{v}" for v in labels]
    frames = 0
    for conn in (6, 26):
        for batch in lm.label_batches(image, labels, lo, hi, conn):
            parts = export.batch_glb_parts(batch, names, lo, pitch, origin)
            assert parts.names == [names[t] for t in batch.rows]
            for s, t in enumerate(batch.rows):
                obj = DigitalObject(batch.masks[s], offset=tuple(int(v) for v in lo[t]), pitch=pitch, origin=origin)
                name, columns, triangles, frame = export.glb_part(names[t], batch.part(s), obj)
                v, f = slice(*parts.vfirst[s:s + 2]), slice(*parts.tfirst[s:s + 2])
                stored = np.column_stack([columns[k] for k in "xyz"]) if frame is None else frame[0]
                np.testing.assert_array_equal(parts.positions[v], np.asarray(stored, np.float32))
                srgb = np.column_stack([columns[k] for k in ("red", "green", "blue")])
                np.testing.assert_array_equal(parts.colors[v, :3], export.linear_bytes(srgb))  # glTF's COLOR_0 is linear
                assert parts.attributes.keys() == {f"_{k}" for k in columns} - {"_x", "_y", "_z", "_red", "_green",
                                                                                   "_blue"}
                for key, column in parts.attributes.items():
                    np.testing.assert_array_equal(column[v], columns[key[1:]], err_msg=key)
                    assert column.dtype == columns[key[1:]].dtype
                np.testing.assert_array_equal(parts.triangles[f], triangles)
                assert (frame is None) == (s not in parts.matrices)
                if frame is not None:
                    frames += 1
                    np.testing.assert_array_equal(parts.matrices[s], frame[1])
    assert frames > 0 or origin[0] < 1e6


def test_batches_take_the_compiled_mesh_on_their_voxels_together():
    """numba's start is paid once for all the batches: boxes each below the
    compiled mesh's threshold, but above it together, are meshed compiled
    (where one volume of their size would be), and so are all of them."""
    from isoflow.digital.surface import mesh_method
    from isoflow.scale.compiled import have_numba, least_voxels

    side = 40
    box = np.array([side - 1, side, side])  # with its empty layer, side^3 voxels
    count = least_voxels(surfaces=True) // side**3 + 1
    assert mesh_method(np.zeros((side, side, side), bool)) == "numpy"
    together = np.zeros((count * side, side, side), bool)
    want = mesh_method(together)
    assert want == ("compiled" if have_numba() else "numpy")
    assert lm.batches_method(np.tile(box, (count, 1))) == want
    assert lm.batches_method(np.tile(box, (count - 2, 1))) == "numpy"
