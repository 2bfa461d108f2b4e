"""The label table block by block (issue 25): equal to the whole image's
on random and nested label images cut into slabs of odd sizes, at 6 and 26,
and from zarr stores (plain, and OME-Zarr stored z, y, x) on the command
line."""

import importlib
import json
import re

import numpy as np
import pytest
from test_label_table import nested

from isoflow import label_table
from isoflow.cli import main
from isoflow.digital.label_blocks import label_table_blocks
from isoflow.errors import IsoflowError
from isoflow.scale.compiled import have_numba

pytestmark = pytest.mark.skipif(not have_numba(), reason="numba not installed")


def same_tables(a, b):
    assert list(a) == list(b)
    for key in a:
        if a[key].dtype == object:
            assert list(a[key]) == list(b[key]), key
        else:
            assert np.array_equal(a[key], b[key], equal_nan=True), key


def cuts(rng, n):
    """Random slab sizes adding up to n (ones included)."""
    out = []
    while n:
        out.append(int(rng.integers(1, n + 1)) if rng.random() < 0.6 else 1)
        n -= out[-1]
    return out


@pytest.mark.parametrize("conn", [6, 26])
def test_slabs_of_any_size_give_the_whole_images_table(rng, conn):
    for trial in range(40):
        shape = tuple(rng.integers(2, 11, 3))
        k = int(rng.integers(2, 6))
        p = rng.dirichlet(np.ones(k) * (0.3 if trial % 2 else 3.0))
        image = rng.choice(k, size=shape, p=p).astype(np.int16)
        same_tables(label_table_blocks(image, conn, layers=cuts(rng, shape[0])), label_table(image, conn))
    image = nested(rng)
    for layers in ([1] * 30, [7, 1, 13, 9], [29, 1]):
        same_tables(label_table_blocks(image, conn, layers=layers, pitch=(1, 2, 3), labels=[4, 1, 99]),
                    label_table(image, conn, pitch=(1, 2, 3), labels=[4, 1, 99]))


def test_pairs_renumbered_across_seams_as_each_pair_is_read(rng):
    from isoflow.scale.piece_graph import renumbered_pairs

    one = np.concatenate([[0], rng.integers(1, 40, 60)])  # 60 pieces made 39, many of them one
    a = rng.integers(1, 60, 500)
    b = rng.integers(a + 1, 61)  # the smaller piece first, as the vertex pass keys them
    keys = (a.astype(np.uint64) << np.uint64(32)) | b.astype(np.uint64)
    kind = rng.integers(0, 5, 500).astype(np.uint8)
    sums = rng.integers(0, 1 << 40, (500, 2)).astype(np.uint64)
    want = []  # pair by pair: the smaller new number first, its column of sums first; one piece touches nothing
    for p, q, k, (s0, s1) in zip(one[a].tolist(), one[b].tolist(), kind.tolist(), sums.tolist()):
        if p != q:
            want.append((min(p, q), max(p, q), k, [s0, s1] if p < q else [s1, s0]))
    out = np.zeros(600, np.uint64), np.zeros(600, np.uint8), np.zeros((600, 2), np.uint64)
    end = renumbered_pairs(one, keys, kind, sums, *out, 100)  # written after 100 entries already there
    got = [(int(k) >> 32, int(k) & 0xFFFFFFFF, c, x)
           for k, c, x in zip(out[0][100:end], out[1][100:end].tolist(), out[2][100:end].tolist())]
    assert got == want
    assert len(want) < 500 and not out[0][:100].any()


def test_a_joined_stream_lets_go_of_its_slabs_and_gives_the_whole_images_table(rng):
    from isoflow.digital.label_table import SlabStream, rows_of_pieces

    image = nested(rng)
    stream = SlabStream(image, 6, None, True)
    for x0, x1 in ((0, 7), (7, 8), (8, image.shape[0])):
        stream.slab(x0, x1)
    pieces, passed = stream.joined()
    assert not any(stream.parts.values())  # what the slabs found is held by the whole image's findings alone
    rows = rows_of_pieces(pieces, passed, image.dtype, 6, None)
    whole = label_table(image, 6)
    assert np.array_equal(rows["voxels"], whole["voxels"]) and np.array_equal(rows["b0"], whole["b0"])
    assert np.array_equal(rows["b2"], whole["b2"])


def nested_stores(tmp_path, rng, chunks, ome_chunks):
    """A nested label image as n.npy, as plain.zarr in ``chunks`` and as
    an OME-Zarr image stored z, y, x (ome.zarr) in ``ome_chunks``."""
    zarr = pytest.importorskip("zarr")
    from isoflow.mesh.formats.omezarr import multiscales

    image = nested(rng).astype(np.uint32)
    np.save(tmp_path / "n.npy", image)
    plain = zarr.create_array(str(tmp_path / "plain.zarr"), shape=image.shape, chunks=chunks, dtype=image.dtype)
    plain[...] = image
    group = zarr.open_group(str(tmp_path / "ome.zarr"), mode="w")
    group.attrs["multiscales"] = multiscales("n", [1.0, 1.0, 1.0], [0.0, 0.0, 0.0], stored="zyx")
    stored = image.transpose(2, 1, 0)
    level = group.create_array("0", shape=stored.shape, chunks=ome_chunks, dtype=stored.dtype)
    level[...] = stored


def info_rows(capsys, path, *options):
    assert main(["info", str(path), "--labels", "--json", *options]) == 0
    return json.loads(capsys.readouterr().out)["labels"]


@pytest.mark.parametrize("grouped", [True, False])
def test_info_labels_of_zarr_stores_read_block_by_block(tmp_path, capsys, rng, monkeypatch, grouped):
    # the layers of chunks read together (a small image: one slab), or a slab each (GROUP_VOXELS 1: every seam)
    from isoflow.digital import label_blocks

    if not grouped:
        monkeypatch.setattr(label_blocks, "GROUP_VOXELS", 1)
    nested_stores(tmp_path, rng, (7, 9, 17), (5, 9, 11))
    want = info_rows(capsys, tmp_path / "n.npy", "--connectivity", "26")
    assert info_rows(capsys, tmp_path / "plain.zarr", "--connectivity", "26") == want
    assert info_rows(capsys, tmp_path / "ome.zarr", "--connectivity", "26") == want


def test_thin_layers_of_chunks_are_read_a_few_at_a_time(tmp_path, capsys, rng, monkeypatch):
    """A store of thin chunks (a layer of them 2,048 voxels here) was read
    one layer of chunks a slab: a slab under a million voxels runs its
    passes on one thread and pays their set-up and a seam for each layer
    (at 256^3 in chunks 16 layers thick, twice the time of chunks of 64).
    Layers are read together up to GROUP_VOXELS (lowered here to three
    layers), each read within its layers of chunks (the slab before's last
    two voxel layers kept, not read again), and the rows are the in-memory
    table's, random labels touching by faces, edges and vertices, at 6 and
    26."""
    zarr = pytest.importorskip("zarr")
    from isoflow.digital import label_blocks
    from isoflow.mesh.formats.omezarr import LabelSlabs

    image = rng.integers(0, 4, (40, 32, 64)).astype(np.uint16)
    np.save(tmp_path / "r.npy", image)
    z = zarr.create_array(str(tmp_path / "r.zarr"), shape=image.shape, chunks=(2, 32, 64), dtype=image.dtype)
    z[...] = image
    monkeypatch.setattr(label_blocks, "GROUP_VOXELS", 3 * 2 * 32 * 64)
    reads = []
    read = LabelSlabs.__getitem__

    def recorded(self, region):
        reads.append((region.start, region.stop))
        return read(self, region)

    monkeypatch.setattr(LabelSlabs, "__getitem__", recorded)
    for conn in ("6", "26"):
        reads.clear()
        assert info_rows(capsys, tmp_path / "r.zarr", "--connectivity", conn) == info_rows(
            capsys, tmp_path / "r.npy", "--connectivity", conn)
        assert len(reads) == 7  # 20 layers of chunks, three at a time
        assert all(a % 2 == 0 and (b % 2 == 0 or b == 40) for a, b in reads), reads  # within layers of chunks
        assert sum(b - a for a, b in reads) == 40  # each voxel layer read once


@pytest.mark.parametrize("conn", [6, 26])
def test_slabs_across_any_axis_give_the_whole_images_table(rng, conn):
    # the boxes, centroids and areas (per axis, with a voxel of three sizes) come back in the image's order
    for axes in [(2, 0, 1), (1, 0, 2), (2, 1, 0), (0, 2, 1)] * 5:
        shape = tuple(rng.integers(2, 11, 3))
        image = rng.choice(int(rng.integers(2, 6)), size=shape).astype(np.int16)
        got = label_table_blocks(image, conn, layers=cuts(rng, shape[axes[0]]), axes=axes, pitch=(1, 2, 3))
        same_tables(got, label_table(image, conn, pitch=(1, 2, 3)))


def test_info_labels_of_stores_thin_along_z_reads_slabs_along_z(tmp_path, capsys, rng, monkeypatch):
    """Chunks thin along z (stored last, or first as OME-Zarr's z, y, x)
    are one layer of chunks along x: read in slabs along x, the first slab
    was the whole image. The slabs follow the chunks as the report block
    by block does, along z, each a layer of chunks and a voxel layer either
    side; the rows are the in-memory table's."""
    from isoflow.digital import label_blocks
    from isoflow.mesh.formats.omezarr import LabelSlabs

    monkeypatch.setattr(label_blocks, "GROUP_VOXELS", 1)  # a slab a layer of chunks, as the test reads them
    nested_stores(tmp_path, rng, (30, 18, 2), (2, 18, 30))
    reads = []
    read = LabelSlabs.__getitem__

    def recorded(self, region):
        out = read(self, region)
        reads.append(out.shape)  # in x, y, z order
        return out

    monkeypatch.setattr(LabelSlabs, "__getitem__", recorded)
    want = info_rows(capsys, tmp_path / "n.npy")
    for name in ("plain.zarr", "ome.zarr"):
        reads.clear()
        assert info_rows(capsys, tmp_path / name) == want
        assert len(reads) == 9 and all(shape[:2] == (30, 18) and shape[2] <= 4 for shape in reads)


@pytest.mark.parametrize("conn", [6, 26])
def test_a_pair_table_of_16_slots_drains_and_grows_to_the_same_table(rng, conn, monkeypatch):
    """The vertex pass writes out the pairs behind the sweep whenever its
    table fills, and grows it where a vertex row does not fit: from a table
    of 16 slots and a near cache of 4 (whose pairs are pushed out into the
    table all the time), on one thread and two, whole and in slabs (pieces
    numbered from a base), every row is still analyze's."""
    from isoflow.scale import pieces

    image = np.where(rng.random((20, 18, 17)) < 0.5, nested(rng, (20, 18, 17)),
                     rng.integers(0, 9, (20, 18, 17))).astype(np.int32)
    numpy = label_table(image, conn, method="numpy")
    drains, drain = [], pieces.PairSink.drain
    monkeypatch.setattr(pieces, "FIRST_SLOTS", 16)
    monkeypatch.setattr(pieces, "NEAR_SLOTS", 4)
    monkeypatch.setattr(pieces.PairSink, "drain", lambda self, *a, **k: drains.append(k) or drain(self, *a, **k))
    for threads in (1, 2):
        same_tables(label_table(image, conn, method="compiled", threads=threads), numpy)
    same_tables(label_table_blocks(image, conn, layers=cuts(rng, 20)), numpy)
    # the table filled again and again, and some vertex row did not fit in it
    assert len(drains) > 20 and any(k.get("grow") for k in drains)


def test_signed_bool_and_float_images_give_the_whole_images_table_in_slabs(rng):
    """Slabs of a signed image list negative labels first, as the whole
    image and analyze do (the pieces hold the bits, unsigned); a bool
    image is label 1 (label 2 absent); a float image of whole numbers is
    int64, and a NaN is named with its voxel in the whole image."""
    from isoflow.errors import IsoflowError

    image = nested(rng)
    signed = (image.astype(np.int64) - 4).astype(np.int8)
    signed[signed == 4] = -128
    numpy = label_table(signed, method="numpy")
    assert numpy["label"].tolist() == sorted(set(np.unique(signed).tolist()) - {0})
    same_tables(label_table_blocks(signed, layers=cuts(rng, 30)), numpy)
    same_tables(label_table_blocks(image > 4, layers=cuts(rng, 30), labels=[2, 1]),
                label_table(image > 4, method="numpy", labels=[2, 1]))
    same_tables(label_table_blocks(image.astype(np.float32), layers=cuts(rng, 30)),
                label_table(image.astype(np.int64), method="numpy"))
    broken = image.astype(np.float32)
    broken[23, 4, 5] = np.nan
    with pytest.raises(IsoflowError, match=r"voxel \(23, 4, 5\) holds nan"):
        label_table_blocks(broken, layers=[10, 10, 10])


def test_info_labels_of_a_float_store_names_it_and_counts_what_the_file_does(tmp_path, capsys, rng):
    zarr = pytest.importorskip("zarr")
    image = (nested(rng) - 4).astype(np.float32)  # NIfTI-style whole floats, negative ones too
    np.save(tmp_path / "n.npy", image.astype(np.int64))
    store = zarr.create_array(str(tmp_path / "f.zarr"), shape=image.shape, chunks=(7, 9, 17), dtype=image.dtype)
    store[...] = image

    def rows(path, spec="--labels"):
        assert main(["info", str(path), spec, "--json"]) == 0
        out = capsys.readouterr()
        return json.loads(out.out)["labels"], out.err

    assert rows(tmp_path / "f.zarr")[0] == rows(tmp_path / "n.npy")[0]
    asked, note = rows(tmp_path / "f.zarr", "--labels=-3,99")
    assert asked == rows(tmp_path / "n.npy", "--labels=-3")[0]
    assert "1 of the labels asked for does not occur (99)" in note
    store[3, 2, 1] = 0.5
    assert main(["info", str(tmp_path / "f.zarr"), "--labels"]) == 2
    err = capsys.readouterr().err
    assert "f.zarr: voxel (3, 2, 1) holds 0.5: not a whole number" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("chunks", [(30, 18, 2), (30, 2, 17)])
def test_a_value_that_is_no_label_in_slabs_across_x_is_named_at_its_voxel(tmp_path, capsys, rng, chunks):
    # slabs along z (or y) hold the voxels with their axes moved: the error names the voxel in x, y, z all the same
    zarr = pytest.importorskip("zarr")
    image = nested(rng).astype(np.float32)
    image[21, 13, 11] = np.nan
    store = zarr.create_array(str(tmp_path / "f.zarr"), shape=image.shape, chunks=chunks, dtype=image.dtype)
    store[...] = image
    assert main(["info", str(tmp_path / "f.zarr"), "--labels"]) == 2
    err = capsys.readouterr().err
    assert "f.zarr: voxel (21, 13, 11) holds nan: not a label" in err and len(err.splitlines()) == 1


def test_a_store_without_layers_gives_the_empty_images_table(tmp_path, capsys):
    """A store of shape (0, y, x) holds no voxel: label_table_blocks gives
    label_table's table of that empty image (a zero row per label asked
    for), and info --labels gives that table, with a warning that says it
    has no voxels, or refuses a choice none of whose labels can occur (was
    ValueError from min() of no layers)."""
    zarr = pytest.importorskip("zarr")
    empty = np.zeros((0, 4, 5), np.uint16)
    for layers in (None, []):  # (a table of no row: info --labels gives it, as of an .npy without voxels)
        same_tables(label_table_blocks(empty, layers=layers), label_table(empty))
    asked = label_table_blocks(empty, labels=[3], pitch=(1, 2, 3))
    same_tables(asked, label_table(empty, labels=[3], pitch=(1, 2, 3)))
    assert asked["voxels"].tolist() == [0] and np.isnan(asked["bbox-0"]).all()
    zarr.create_array(str(tmp_path / "e.zarr"), shape=(0, 4, 5), chunks=(2, 2, 2), dtype="uint16")
    no_voxels = f"{tmp_path / 'e.zarr'}: the image has no voxels (shape 0x4x5)"
    assert main(["info", str(tmp_path / "e.zarr"), "--labels", "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["labels"] == [] and err.splitlines() == [f"isoflow info: warning: {no_voxels}; the table has no row"]
    assert main(["info", str(tmp_path / "e.zarr"), "--labels=3"]) == 2
    err = capsys.readouterr().err
    assert err.splitlines() == [f"isoflow info: error: {tmp_path / 'e.zarr'}: none of the labels asked for occur (3): "
                                f"the image has no voxels (shape 0x4x5)"]


def test_info_labels_json_of_a_float_store_is_the_float_files(tmp_path, capsys, rng):
    """A float image is read as int64 labels in memory and from a store
    alike: --json of the store is --json of the same floats in a .npy,
    "dtype" included (the store said float32)."""
    zarr = pytest.importorskip("zarr")
    image = (nested(rng) - 4).astype(np.float32)
    np.save(tmp_path / "f.npy", image)
    store = zarr.create_array(str(tmp_path / "f.zarr"), shape=image.shape, chunks=(7, 9, 17), dtype=image.dtype)
    store[...] = image
    said = []
    for name in ("f.npy", "f.zarr"):
        assert main(["info", str(tmp_path / name), "--labels", "--json"]) == 0
        said.append(json.loads(capsys.readouterr().out))
    assert said[0]["dtype"] == said[1]["dtype"] == "int64"
    said[1]["input"] = said[0]["input"]
    assert said[1] == said[0]


def test_a_damaged_chunk_is_one_line_naming_the_store_once(tmp_path, capsys):
    """info --labels of a store with a damaged chunk: the store named once
    (it was 'd.zarr: d.zarr: ...') and the voxels read as ranges, not
    Python's slice objects."""
    zarr = pytest.importorskip("zarr")
    image = np.zeros((10, 8, 6), np.uint16)
    image[2:7, 1:5, 1:4] = 3
    zarr.create_array(str(tmp_path / "d.zarr"), data=image, chunks=(5, 4, 3), zarr_format=2)
    (tmp_path / "d.zarr" / "1.0.0").write_bytes(b"garbage")
    for extra in (["--labels"], ["--label", "3"]):
        assert main(["info", str(tmp_path / "d.zarr"), *extra]) == 2
        err = capsys.readouterr().err.splitlines()
        assert len(err) == 1 and err[0].count("d.zarr") == 1 and "cannot read a chunk in [" in err[0], err
        assert "slice(" not in err[0]


@pytest.mark.parametrize("conn", [6, 26])
def test_a_chunk_of_more_voxels_than_the_pieces_number_is_read_in_slabs_within_it(rng, conn, monkeypatch):
    """A zarr chunk of 256 layers of 4096 x 4096 voxels (4.3 G voxels, more
    than the 2^32 - 2 that a slab's pieces are numbered in) ended
    ``isoflow info STORE.zarr --labels`` in a ValueError traceback. Here the
    limit is lowered to 300 voxels so that one chunk of 20 layers of 10 x 10
    is over it: the table is read in slabs within it, every label's voxels,
    components and Euler characteristic those of scipy and scikit-image."""
    from scipy import ndimage
    from skimage.measure import euler_number

    from isoflow.scale import pieces

    image = rng.integers(0, 4, (20, 10, 10)).astype(np.uint16)
    monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 300)
    table = label_table_blocks(image, conn, layers=[20])
    structure = ndimage.generate_binary_structure(3, 1 if conn == 6 else 3)
    for row, value in enumerate(table["label"].tolist()):
        solid = image == value
        assert table["voxels"][row] == solid.sum()
        assert table["b0"][row] == ndimage.label(solid, structure)[1]
        assert table["euler_characteristic"][row] == euler_number(solid, 1 if conn == 6 else 3)


def test_a_label_image_whose_three_layers_exceed_the_numbering_is_refused_in_one_line(monkeypatch):
    from isoflow import IsoflowError
    from isoflow.scale import pieces

    monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 250)
    with pytest.raises(IsoflowError, match=r"layers across x hold 100 voxels each .* crop or split it along y and z"):
        label_table_blocks(np.ones((5, 10, 10), np.uint8), 6)


def thin_along_z(tmp_path):
    """A label store of chunks one voxel thick along z: layer_axes reads it in layers along z."""
    zarr = pytest.importorskip("zarr")
    from isoflow.scale.chunks import layer_axes

    image = np.zeros((6, 5, 40), np.uint8)
    image[1:4, 1:4, 2:30] = 3
    z = zarr.open_array(str(tmp_path / "labels.zarr"), mode="w", shape=image.shape, chunks=(6, 5, 1), dtype="u1")
    z[:] = image
    assert layer_axes((1, 1, 40))[0] == 2
    return tmp_path / "labels.zarr"


def test_a_slab_beyond_memory_names_the_axis_it_is_read_along(tmp_path, capsys, monkeypatch):
    # the store is read in slabs of layers along z (one chunk thick): the refusal of a slab names z, where the
    # layers go and thinner chunks would help, and the slab's shape in the image's order (x, y, z), not
    # "its first axis" of the store's axes turned for the reading
    from isoflow.scale import memory

    store = thin_along_z(tmp_path)
    monkeypatch.setattr(memory, "default_budget", lambda: 100)  # less than one slab of 6 x 5 voxels takes
    assert main(["info", str(store), "--labels"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "smaller chunks along z" in err[0] and "first axis" not in err[0], err
    assert "a slab of 6x5x2 voxels" in err[0], err  # one layer and the next one's, read with it


def test_layers_beyond_the_pieces_numbers_name_the_axes_across_them(tmp_path, capsys, monkeypatch):
    # read along z, a layer is x by y: too many voxels for the pieces' numbers, the image is to be split along
    # x and y (the store's last two axes are y and z)
    from isoflow.scale import pieces

    store = thin_along_z(tmp_path)
    monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 6 * 5 * 3 - 1)  # three layers of 6 x 5 do not fit
    assert main(["info", str(store), "--labels"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "layers across z hold 30 voxels" in err[0] and "along x and y" in err[0], err


def test_the_pieces_of_a_slab_beyond_memory_name_the_axis_it_is_read_along(tmp_path, capsys, monkeypatch):
    # the slab fits (two layers of 6 x 5 voxels, 120 bytes as read, and the two chunks of 6 x 5 x 1 that its
    # read decodes, 60) but the runs and pieces found in it do not: the layers they are counted in go along z,
    # which the refusal names
    from isoflow.scale import memory

    store = thin_along_z(tmp_path)
    monkeypatch.setattr(memory, "default_budget", lambda: 180)
    assert main(["info", str(store), "--labels"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(r"crop the image (along|across) z$", err[0]), err
    assert "first axis" not in err[0], err


class CountedChunks:
    """A zarr array whose reads (``array[a:b]``) count, per chunk along axis
    0, how often a read crossed it: each read decodes every chunk it
    crosses whole."""

    def __init__(self, array):
        self.array, self.shape, self.dtype, self.chunks = array, array.shape, array.dtype, array.chunks
        self.decoded = np.zeros(-(-array.shape[0] // array.chunks[0]), np.int64)

    def __getitem__(self, layers):
        step = self.chunks[0]
        self.decoded[layers.start // step:(layers.stop - 1) // step + 1] += 1
        return self.array[layers]


@pytest.mark.parametrize("chunks", [(20, 10, 10), (10, 10, 10)])
def test_a_layer_of_chunks_cut_into_thin_slabs_is_decoded_once(tmp_path, rng, chunks, monkeypatch):
    """A layer of chunks thicker than the slabs its pieces' numbers allow
    (a 4096^3 chunk: 17 slabs) was read slab by slab, each read decoding
    the whole chunk again. Here the numbering is lowered to 300 voxels, so
    that 10 x 10 layers go one a slab: each chunk is decoded for its own
    layer and once for each neighbouring layer's voxel layer, and the rows
    are the in-memory table's and scikit-image's voxels and boxes."""
    zarr = pytest.importorskip("zarr")
    from skimage.measure import regionprops

    from isoflow.scale import pieces

    image = rng.integers(0, 4, (20, 10, 10)).astype(np.uint16)
    z = zarr.create_array(str(tmp_path / "l.zarr"), shape=image.shape, chunks=chunks, dtype=image.dtype)
    z[...] = image
    want = label_table(image)
    monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 300)
    counted = CountedChunks(z)
    table = label_table_blocks(counted, layers=[chunks[0]] * (20 // chunks[0]))
    own = 1 if chunks[0] == 20 else 2  # its layer's read, and the neighbouring layer's voxel layer
    assert counted.decoded.tolist() == [own] * len(counted.decoded)
    same_tables(table, want)
    props = regionprops(image.astype(np.int64))
    assert table["voxels"].tolist() == [p.area for p in props]
    assert [tuple(table[f"bbox-{d}"][row] for d in range(6)) for row in range(len(props))] == [p.bbox for p in props]


@pytest.mark.parametrize("thick", [2, 5])
def test_each_layer_of_chunks_is_decoded_once(tmp_path, rng, thick):
    """A slab's read takes a voxel layer of each neighbouring slab beside
    its own, and each layer of chunks was decoded for its own slab and
    again for each neighbour's voxel layer (three times between two
    others). The slabs' boundaries sit one layer below the chunks' and a
    read begins with the two layers the slab before read last: each chunk
    is decoded once, and the rows are the in-memory table's (random labels
    touching by faces, edges and vertices, at both connectivities) and
    scikit-image's voxels and boxes."""
    zarr = pytest.importorskip("zarr")
    from skimage.measure import regionprops

    image = rng.integers(0, 4, (4 * thick, 9, 8)).astype(np.uint16)
    z = zarr.create_array(str(tmp_path / "l.zarr"), shape=image.shape, chunks=(thick, 9, 8), dtype=image.dtype)
    z[...] = image
    for conn in (6, 26):
        counted = CountedChunks(z)
        table = label_table_blocks(counted, conn, layers=[thick] * 4)
        assert counted.decoded.tolist() == [1, 1, 1, 1]
        same_tables(table, label_table(image, conn))
    props = regionprops(image.astype(np.int64))
    assert table["voxels"].tolist() == [p.area for p in props]
    assert [tuple(table[f"bbox-{d}"][row] for d in range(6)) for row in range(len(props))] == [p.bbox for p in props]


def test_a_chunk_beyond_the_budget_is_refused_naming_it_and_what_fits(tmp_path, capsys, monkeypatch):
    """A slab that fits the budget was read from a chunk that does not:
    the read decodes the chunk whole (20 x 10 x 10 voxels of 8 bytes here,
    read in slabs of three layers of 10 x 10), and the check counted the
    slab alone. The one line names the chunk and the largest that fits; a
    store in chunks of that size gives the in-memory table under the same
    budget, each label's voxels NumPy's count."""
    zarr = pytest.importorskip("zarr")
    from isoflow.scale import memory, pieces

    image = np.zeros((20, 10, 10), np.uint64)
    image[2:18, 2:8, 2:8] = 1
    image[5:15, 4:6, 4:6] = 2
    want = label_table(image)
    z = zarr.create_array(str(tmp_path / "one.zarr"), shape=image.shape, chunks=image.shape, dtype=image.dtype)
    z[...] = image
    monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 300)
    monkeypatch.setattr(memory, "default_budget", lambda: 8_000)  # a slab's 2,700 bytes, not the chunk's 16,000
    assert main(["info", str(tmp_path / "one.zarr"), "--labels"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "chunk of 20x10x10 voxels" in err[0] and "budget" in err[0], err
    found = re.search(r"chunks of at most ([\d,]+) voxels fit", err[0])
    assert found, err
    fit = int(found.group(1).replace(",", ""))
    assert 2_000 > fit >= 100  # below the chunk, at least a layer
    layers = fit // 100
    z = zarr.create_array(str(tmp_path / "fit.zarr"), shape=image.shape, chunks=(layers, 10, 10), dtype=image.dtype)
    z[...] = image
    # the pieces with what the passes after them take (tests/digital/test_label_table.py) are checked on
    # their own, and at this budget of a few KiB they would be refused too: here the chunks alone
    monkeypatch.setattr(importlib.import_module("isoflow.digital.label_table"), "later_bytes", lambda pieces, size: 0)
    got = label_table_blocks(z, layers=[layers] * (20 // layers) + ([20 % layers] if 20 % layers else []))
    same_tables(got, want)
    assert got["voxels"].tolist() == [np.count_nonzero(image == 1), np.count_nonzero(image == 2)]


@pytest.mark.parametrize("kind", ["dask", "numpy"])
@pytest.mark.parametrize("axes", [None, (2, 0, 1)])
def test_a_masked_voxel_read_block_by_block_is_refused_naming_it(kind, axes):
    """A dask array of masked blocks (``dask.array.ma``) or a masked NumPy
    array read block by block gave the table of the values stored under
    the mask, as if they were labels (``numpy.asarray`` drops the mask):
    the line names the masked voxel and the two remedies, and the array
    filled with 0 gives the table of the image with that voxel 0."""
    da = pytest.importorskip("dask.array")
    image = np.zeros((12, 10, 10), np.uint8)
    image[2:10, 2:8, 2:8] = 1
    mask = np.zeros(image.shape, bool)
    mask[5, 3, 7] = True
    if kind == "dask":
        array = da.ma.masked_array(da.from_array(image, chunks=(4, 10, 10)), mask=da.from_array(mask, chunks=(4, 10, 10)))
        filled = da.ma.filled(array, 0)
    else:
        array = np.ma.masked_array(image, mask=mask)
        filled = array.filled(0)
    layers = [4, 4, 4] if axes is None else [4, 6]
    with pytest.raises(IsoflowError, match=r"^label_table_blocks: array: voxel \(5, 3, 7\) is masked \(1 masked element "
                                           r"in voxel layers \d+-\d+\); pass .*filled.* or .*data"):
        label_table_blocks(array, layers=layers, axes=axes)
    same_tables(label_table_blocks(filled, layers=layers, axes=axes), label_table(np.where(mask, 0, image)))


def test_noise_read_slab_by_slab_is_refused_counting_the_pieces_of_the_slabs_before(monkeypatch):
    """Noise of 1,000 labels read in slabs: each slab's pieces fit, all of
    them and their graph do not. The refusal comes at the slab where they
    stop fitting, counts the pieces of the slabs before beside the slab's
    own, and says to crop along the axis read; with room for them all the
    table equals the one of the image in memory."""
    from isoflow.scale import memory

    vol = np.random.default_rng(5).integers(1, 1001, (24, 16, 16)).astype(np.uint16)
    monkeypatch.setattr(memory, "default_budget", lambda: 3 << 20)
    with pytest.raises(IsoflowError, match=r"^label_table_blocks: array: the label table of [\d,]+ pieces of a label "
                                           r"image \(beside [\d,]+ of the layers read before\) needs about .*; crop the "
                                           r"image along x; "):
        label_table_blocks(vol, layers=[8, 8, 8])
    monkeypatch.setattr(memory, "default_budget", lambda: 64 << 20)
    same_tables(label_table_blocks(vol, layers=[8, 8, 8]), label_table(vol))
