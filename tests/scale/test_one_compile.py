"""Each compiled pass is compiled once for what differs only incidentally
between its inputs: a read-only array beside a writeable one (a volume
from ``np.load(mmap_mode="r")``, a file's bytes), labels of every integer
width, int64 and uint64 columns, a table held in either order. numba
types each of these apart, and each type was a compile of its own: a
first wait of seconds for the user, the larger part of the suite's time.
Each test calls the pass with both kinds, checks what it gives against an
independent answer, and counts the pass' compiled signatures."""

import numpy as np
import pytest

from isoflow.scale.compiled import have_numba

pytestmark = pytest.mark.skipif(not have_numba(), reason="numba not installed")


def read_only(a):
    a = a.copy()
    a.flags.writeable = False
    return a


def only_read_only(dispatcher, argument=0):
    """Every compile of the pass took ``argument`` read-only: one kind,
    whatever the caller held (other tests in this process may have called
    the pass with other layouts, so the compiles are not counted)."""
    assert dispatcher.signatures and not any(sig[argument].mutable for sig in dispatcher.signatures), \
        dispatcher.signatures


def test_volumes_read_only_or_not_share_one_compile(rng, tmp_path):
    """The histogram, the runs and the bit rows of a volume loaded from
    disk (read-only, memory-mapped) and of one made in memory."""
    from isoflow.scale import bitrows, kernels

    volume = rng.random((6, 7, 9)) < 0.5
    np.save(tmp_path / "v.npy", volume)
    mapped = np.load(tmp_path / "v.npy", mmap_mode="r")
    assert not mapped.flags.writeable
    for v in (volume, mapped):
        # one configuration for each vertex of the grid, (n + 1) per axis
        assert kernels.histogram3d(v).sum() == 7 * 8 * 10
        offsets, start, end = kernels.object_runs(kernels.volume_view(v))
        # runs along the last axis: where a True follows a False (or the row's start)
        padded = np.pad(volume, ((0, 0), (0, 0), (1, 0)))
        assert offsets[-1] == np.count_nonzero(padded[:, :, 1:] & ~padded[:, :, :-1])
        assert (end - start).sum() == volume.sum()
        bits, runs, _ = bitrows.pack(v)
        assert runs[-1] == offsets[-1]
    for dispatcher in (kernels._hist_rows, kernels._count_runs_rows, kernels._fill_runs_rows, bitrows._pack_rows):
        only_read_only(dispatcher)


def test_a_read_only_table_of_moves_shares_one_compile():
    """The flow's moves with a table made in memory and a read-only one (a
    shared, cached table): an all-zero table keeps the interior vertices,
    the 2^3 of a 3^3 cube."""
    from isoflow.scale import bitrows, flowbits

    bits = bitrows.pack(np.ones((3, 3, 3), bool))[0]
    for table in (np.zeros(256, np.int64), read_only(np.zeros(256, np.int64))):
        rows = flowbits.moves3(bits, (3, 3, 3), table)
        assert int(np.bitwise_count(rows).sum()) == 8
    only_read_only(flowbits._moves_layers, 3)


def test_binary_ply_as_bytes_or_bytearray_shares_one_compile():
    """A binary PLY of a triangle and a quad (faces of different sizes:
    the scan, not one record type) read from bytes and from a bytearray:
    3 triangles, the quad cut in two."""
    from isoflow.mesh import ply

    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
              b"property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n")
    xyz = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]], "<f4").tobytes()
    faces = bytes([3]) + np.array([0, 1, 4], "<i4").tobytes() + bytes([4]) + np.array([0, 1, 2, 3], "<i4").tobytes()
    data = header + xyz + faces
    for body in (data, bytearray(data)):
        vertices, faces = ply.read_ply(body)
        assert vertices.shape == (5, 3) and len(faces) == 3
    only_read_only(ply._scan_binary)


def test_int64_and_uint64_columns_share_one_compile():
    """The digits of int64 and uint64 columns (as ``str`` writes them, the
    least int64 and the greatest uint64 too) and the rows joined from cells
    of a writeable and of a read-only buffer."""
    from isoflow.cli.table_text import cell_bytes, json_rows
    from isoflow.scale import text_rows

    for column in (np.array([-7, 0, 120, -(2**63)], np.int64), np.array([0, 7, 2**64 - 1], np.uint64),
                   np.array([3, -2], np.int16)):
        chars, lengths = cell_bytes(column, "", "", ("", ""))
        assert [bytes(row[len(row) - n:]).decode() for row, n in zip(chars, lengths)] == list(map(str, column.tolist()))
    assert all(str(sig[0].dtype) == "uint64" for sig in text_rows.integer_cells.signatures), \
        text_rows.integer_cells.signatures
    n = 3000  # past the rows Python writes
    table = {"label": np.arange(n, dtype=np.uint64)}
    assert "".join(json_rows(table)) == "[" + ", ".join(f'{{"label": {i}}}' for i in range(n)) + "]"
    cells = np.frombuffer(b" 1" b"23" b"x" b"y", np.uint8)  # a view of bytes, read-only
    out = np.zeros(32, np.uint8)
    size = text_rows.join_cells(cells, np.array([0, 4]), np.array([2, 1]), np.array([[1, 2], [1, 1]]),
                                np.frombuffer(b";a=,b=", np.uint8), np.array([3, 6]), out)
    assert bytes(out[:size]) == b";a=1,b=x;a=23,b=y"
    only_read_only(text_rows.join_cells)


def test_features_added_into_either_order_share_one_compile(rng):
    """Per-label sums of pieces' features into a table held in C order (a
    slab's pieces) and transposed (a label table's columns), against
    NumPy's ``add.at``."""
    from isoflow.scale import piece_graph

    of = rng.integers(0, 4, 30)
    counts, doubled = rng.integers(0, 9, 30), rng.integers(0, 9, 30)
    sums, features = rng.integers(0, 9, (30, 3)), rng.integers(0, 9, (30, 5))
    want = np.zeros((4, 5), np.int64)
    np.add.at(want, of, features)
    for out in (np.zeros((4, 5), np.int64), np.zeros((5, 4), np.int64).T):
        totals = [np.zeros(4, np.int64), np.zeros((4, 3), np.int64), out, np.zeros(4, np.int64)]
        piece_graph.add_by_label(of, counts, sums, features, doubled, *totals)
        assert np.array_equal(out, want)
        assert np.array_equal(totals[0], np.bincount(of, counts, 4))
    # the table as its memory: one dimension, whatever its order
    assert all(sig[7].ndim == 1 for sig in piece_graph._add_by_label.signatures), piece_graph._add_by_label.signatures


def test_masks_of_labels_of_one_width_share_one_compile(rng, monkeypatch):
    """Each label's mask in a batch of boxes for labels of 1, 2, 4 and 8
    bytes, signed or not, in either byte order: ``image[box] == label``,
    one compile for each width (they compare as unsigned integers of it,
    at a vector's speed; one compile for all, byte by byte, was slower)."""
    from isoflow.digital import label_meshes as lm
    from isoflow.scale import box_masks

    monkeypatch.setattr(lm, "BATCH_VOXELS", 400)
    codes = rng.choice(4, size=(6, 5, 7))
    for dtype in ("u1", "i2", ">u2", "u4", "i8", "u8"):
        image = (codes * 85).astype(dtype)  # 255 at the top: a uint8's greatest
        labels = np.unique(image)[1:]
        where = [np.argwhere(image == v) for v in labels]
        lo, hi = np.array([w.min(axis=0) for w in where]), np.array([w.max(axis=0) + 1 for w in where])
        for label, a, b, (_, mask) in zip(labels, lo, hi, lm.label_meshes(image, labels, lo, hi, 26, method="compiled")):
            np.testing.assert_array_equal(mask, image[a[0]:b[0], a[1]:b[1], a[2]:b[2]] == label)
    # unsigned, read-only: one compile for each width, whatever the sign and byte order
    assert {str(sig[0].dtype) for sig in box_masks.box_masks.signatures} == {"uint8", "uint16", "uint32", "uint64"}
    only_read_only(box_masks.box_masks)
