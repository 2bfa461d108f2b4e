"""The label table (issue 25): every row equals ``analyze(image == label)``
on random label images whose labels touch by faces, edges and vertices,
nest inside each other and wrap around each other, at 6 and 26, on the
NumPy and compiled paths and on several threads; and scikit-image's
regionprops gives the same voxel counts, Euler numbers, boxes and
centroids."""

import re

import numpy as np
import pytest
from conftest import ball

from isoflow import analyze, label_table
from isoflow.digital.label_table import distinct, image_values
from isoflow.errors import IsoflowError
from isoflow.scale.compiled import have_numba

needs_numba = pytest.mark.skipif(not have_numba(), reason="numba not installed")
METHODS = ["numpy", pytest.param("compiled", marks=needs_numba)]


def row_report(table, r):
    """The row's part of analyze's report, in analyze's form."""
    return {
        "voxels": int(table["voxels"][r]),
        "euler_characteristic": int(table["euler_characteristic"][r]),
        "betti": [int(table["b0"][r]), int(table["b1"][r]), int(table["b2"][r])],
        "n": [int(table[f"n-{i}"][r]) for i in range(9)],
        "non_well_composed": int(table["non_well_composed"][r]),
        "energy": int(table["energy"][r]),
        "genera": list(table["genera"][r]),
        "surface_euler": int(table["surface_euler"][r]),
        "pinched_vertices": int(table["pinched_vertices"][r]),
        "doubled_edges": int(table["doubled_edges"][r]),
    }


def analyze_report(mask, conn):
    r = analyze(mask, conn)
    return {
        "voxels": r["voxels"], "euler_characteristic": r["euler_characteristic"], "betti": r["betti"],
        "n": r["n"], "non_well_composed": r["non_well_composed"], "energy": r["energy"],
        "genera": [s["genus"] for s in r["surfaces"]],
        "surface_euler": sum(s["euler_characteristic"] for s in r["surfaces"]),
        "pinched_vertices": r["pinched_vertices"], "doubled_edges": r["doubled_edges"],
    }


def assert_rows_equal_analyze(image, conn, **kw):
    table = label_table(image, conn, **kw)
    assert len(set(table.keys()) - {"genera"}) == len(table) - 1
    for r, label in enumerate(table["label"]):
        assert row_report(table, r) == analyze_report(image == label, conn), (label, conn, kw)
    return table


def nested(rng, shape=(30, 18, 17)):
    """Labels that nest and wrap: a hollow ball (1) around a hollow ball
    (2) around a ball (3), a torus (4) around a rod (5), in a noise of
    labels 6-8 and 0 with face, edge and vertex contacts."""
    image = rng.choice([0, 0, 6, 7, 8], size=shape).astype(np.int32)
    x = np.indices(shape).astype(float)
    r = np.sqrt(((x - np.array([8, 8.5, 8]).reshape(3, 1, 1, 1)) ** 2).sum(0))
    image[r <= 7.2] = 1
    image[r <= 5.2] = 2
    image[r <= 3.6] = 0
    image[r <= 2.2] = 3
    # a torus around axis 0 at x = 22, a rod of label 5 through it along axis 0
    rho = np.hypot(x[1] - 8.5, x[2] - 8)
    image[(rho - 5) ** 2 + (x[0] - 22) ** 2 <= 1.6**2] = 4
    image[17:29, 8:10, 7:9] = 5
    return image


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("conn", [6, 26])
def test_random_label_images_equal_analyze_per_label(rng, conn, method):
    seen = np.zeros(4, int)
    for trial in range(60):
        shape = tuple(rng.integers(2, 10, 3))
        k = rng.integers(2, 6)
        # one label dense half of the time, so that it encloses others
        p = rng.dirichlet(np.ones(k) * (0.3 if trial % 2 else 3.0))
        image = rng.choice(k, size=shape, p=p).astype(rng.choice([np.uint8, np.int16, np.uint64]))
        table = assert_rows_equal_analyze(image, conn, method=method, threads=1 + trial % 3)
        seen += [(table["b0"] > 1).any(), (table["b1"] > 0).any(), (table["b2"] > 0).any(),
                 (table["pinched_vertices"] > 0).any()]
    # several components, tunnels, cavities and pinches all occurred
    assert (seen > 2).all(), seen


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("conn", [6, 26])
def test_label_zero_asked_for_equals_analyze(rng, conn, method):
    """Asked for, the value 0 is a label like any other: its row is
    ``analyze(image == 0)``; the region outside the array is not part of it
    (a block with the outside, 0-voxels and other labels in it)."""
    for trial in range(12):
        image = rng.choice(4, size=tuple(rng.integers(2, 9, 3)), p=[0.4, 0.2, 0.2, 0.2]).astype(np.uint8)
        table = assert_rows_equal_analyze(image, conn, method=method, labels=[0, 2], threads=1 + trial % 2)
        assert table["label"].tolist() == [0, 2] and table["voxels"][0] == np.count_nonzero(image == 0)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("conn", [6, 26])
def test_nested_and_wrapped_labels_equal_analyze(rng, conn, method):
    image = nested(rng)
    table = assert_rows_equal_analyze(image, conn, method=method, threads=2)
    by_label = dict(zip(table["label"].tolist(), range(len(table["label"]))))
    # the hollow balls enclose (b2), the torus has its tunnel, the rod goes through it
    assert table["b2"][by_label[1]] >= 1 and table["b2"][by_label[2]] >= 1
    assert table["b1"][by_label[4]] >= 1


@needs_numba
def test_the_passes_are_compiled_once_for_every_integer_width(rng):
    """Label images come as uint8, int16, uint32, int64, in either byte
    order: the labelling and the vertex pass read the values as bytes, so
    that one compiled pass serves every width (a compile of its own per
    width was a first wait of seconds per width for the user). Two threads,
    so that the slabs' seams are joined too."""
    from isoflow.scale import pieces

    image = rng.choice(5, size=(7, 6, 8), p=[0.4, 0.15, 0.15, 0.15, 0.15])
    for dtype in (np.uint8, np.dtype(">i2"), np.uint32, np.int64):
        assert_rows_equal_analyze(image.astype(dtype), 26, method="compiled", threads=2)
    for name in ("_vertex_rows", "_slab_runs", "_join_seam", "_number_runs", "_count_roots"):
        assert len(getattr(pieces, name).signatures) == 1, (name, getattr(pieces, name).signatures)
    # called from compiled passes only: compiled with them, none loaded from numba's cache
    for name in ("_change_bits", "_equal_bits", "_join_rows", "_join_row", "_into"):
        assert len(getattr(pieces, name).signatures) <= 1, (name, getattr(pieces, name).signatures)


@needs_numba
def test_labels_that_differ_only_in_a_high_byte_stay_apart(rng):
    """The labelling compares values byte by byte: labels whose low bytes
    agree (k << 8 (width - 1)) are cut and joined as their codes k are, on
    rows long enough for the compares of whole words (70 voxels) and busy
    enough for the joins from bits. The table of a relabelled image is the
    table of the codes, relabelled."""
    codes = rng.integers(0, 4, (5, 6, 70)).astype(np.uint8)
    codes[:, :3, 30:] = 3  # long runs beside the busy rows
    want = label_table(codes, 26, method="compiled", threads=2)
    for dtype in (np.dtype("<u2"), np.dtype(">i4"), np.dtype("<u8")):
        shift = 8 * (dtype.itemsize - 1) - (dtype.kind == "i")
        got = label_table(codes.astype(dtype) << shift, 26, method="compiled", threads=2)
        assert np.array_equal(got["label"], want["label"].astype(np.int64) << shift), dtype
        for key in want:
            if key != "label":
                assert np.array_equal(got[key], want[key], equal_nan=want[key].dtype.kind == "f"), (dtype, key)


@needs_numba
def test_many_pieces_grow_the_pair_table_and_threads_agree(rng):
    """A noise of 6 labels on 36^3 has tens of thousands of pieces: the pair
    table fills many times; 1 and 3 threads give the same table."""
    image = rng.integers(0, 6, (36, 30, 33)).astype(np.uint16)
    one = label_table(image, 26, method="compiled", threads=1)
    three = label_table(image, 26, method="compiled", threads=3)
    for key in one:
        assert np.array_equal(one[key], three[key]), key
    numpy = label_table(image, 26, method="numpy")
    for key in one:
        assert np.array_equal(one[key], numpy[key], equal_nan=key.startswith(("bbox", "centroid"))) or \
            np.allclose(one[key], numpy[key]), key



@needs_numba
@pytest.mark.parametrize("slabs", [False, True])
def test_the_graph_of_pieces_lets_each_block_of_pairs_go_before_it_returns(rng, monkeypatch, slabs):
    """The pairs of pieces are handed to the graph of pieces (the vertex
    pass' blocks, or the slabs' pairs joined into one), which empties the
    list and lets every block go while it places them: none is alive once
    the graph is made (the pairs and the whole graph are not held at
    once). A vertex pass block's keys, kind and sums lie in one set of
    pages, given back together (keys and kind apart would stay in the C
    allocator's heaps). The table is the NumPy path's."""
    import weakref

    from isoflow.scale import piece_graph, pieces

    monkeypatch.setattr(pieces, "ENTRY_BLOCK", 256)  # tens of blocks from a small image
    if slabs:
        monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 600)  # slabs of 3 layers
    made, seen = piece_graph.entries_graph, []

    def watched(entries, n, none, ticks=None):
        assert slabs or all(keys.base is kind.base is sums.base for keys, kind, sums in entries)
        refs = [weakref.ref(a.base) for block in entries for a in block]
        graph = made(entries, n, none, ticks)
        seen.append((len(entries), sum(ref() is not None for ref in refs), len(refs)))
        return graph

    monkeypatch.setattr(piece_graph, "entries_graph", watched)
    image = rng.integers(0, 40, (14, 13, 12)).astype(np.uint16)
    table = label_table(image, 26, method="compiled", threads=2)
    assert len(seen) == 1 and seen[0][:2] == (0, 0) and seen[0][2] >= (3 if slabs else 12), seen
    numpy = label_table(image, 26, method="numpy")
    for key in numpy:
        assert np.array_equal(table[key], numpy[key]) or np.allclose(table[key], numpy[key]), key

def cells(rng, shape=(26, 22, 24), count=400):
    """A cell segmentation's form: hundreds of tiny labels (one to a few
    voxels, some touching each other by faces, edges or vertices, some on
    the border) in one background label 1 that touches every one of them,
    with holes of 0 in it."""
    image = np.ones(shape, np.uint32)
    image[rng.random(shape) < 0.05] = 0
    for label, corner in enumerate(rng.integers(0, np.array(shape) - 1, (count, 3)), start=2):
        size = rng.integers(1, 3, 3)
        image[tuple(slice(c, c + s) for c, s in zip(corner, size))] = label
    return image


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("conn", [6, 26])
def test_many_tiny_labels_in_one_background_equal_analyze(rng, conn, method):
    """The background's piece and the outside touch hundreds of pieces each
    (more than a piece's home in the pair table holds)."""
    image = cells(rng)
    table = assert_rows_equal_analyze(image, conn, method=method, threads=2)
    # the background has a cavity or a tunnel round most cells
    assert len(table["label"]) > 300 and table["b1"][0] + table["b2"][0] > 100


@pytest.mark.parametrize("method", METHODS)
def test_regionprops_gives_the_same_counts_boxes_centroids_and_euler_numbers(rng, method):
    from skimage.measure import regionprops

    image = nested(rng)
    table = label_table(image, 26, method=method)  # scikit-image's 3D Euler number is 26-connected
    props = {p.label: p for p in regionprops(image)}
    assert sorted(props) == table["label"].tolist()
    for r, label in enumerate(table["label"]):
        p = props[label]
        assert table["voxels"][r] == p.area
        assert table["euler_characteristic"][r] == p.euler_number
        assert [table[f"bbox-{d}"][r] for d in range(6)] == list(p.bbox)
        # a voxel v spans [v, v + 1]: its centre is scikit-image's v + 0.5
        assert np.allclose([table[f"centroid-{d}"][r] - 0.5 for d in range(3)], p.centroid)
    # not at 6 (the default): the noise labels' edge and vertex contacts join at 26 alone (docs/labels.md)
    six = label_table(image, 6, method=method)["euler_characteristic"]
    assert six.tolist() != [props[v].euler_number for v in table["label"].tolist()]


def test_world_units_follow_the_pitch_per_axis_and_the_origin():
    image = np.zeros((6, 7, 8), np.uint8)
    image[1:4, 2:4, 3:7] = 9  # 3 x 2 x 4 voxels
    t = label_table(image, pitch=(0.5, 2.0, 3.0), origin=(10, 20, 30))
    assert t["volume"][0] == pytest.approx(24 * 0.5 * 2 * 3)
    # faces: 2 x (2*4) across axis 0 of area 6, 2 x (3*4) across axis 1 of area 1.5, 2 x (3*2) across 2 of area 1
    assert t["surface_area"][0] == pytest.approx(16 * 6 + 24 * 1.5 + 12 * 1.0)
    assert [t[f"bbox-{d}"][0] for d in range(6)] == [10.5, 24, 39, 12, 28, 51]
    assert [t[f"centroid-{d}"][0] for d in range(3)] == pytest.approx([11.25, 26, 45])


def test_labels_asked_for_in_order_with_absent_ones_as_empty_masks(rng):
    image = nested(rng).astype(np.int64) * 1000 - 3000  # negative labels, wide values
    table = label_table(image, labels=[-2000, 12345, -3000])
    assert table["label"].tolist() == [-2000, 12345, -3000]
    assert table["voxels"][1] == 0 and np.isnan(table["bbox-0"][1]) and table["genera"][1] == ()
    empty = analyze_report(np.zeros((3, 3, 3), bool), 6)
    assert row_report(table, 1) == empty
    for r in (0, 2):
        assert row_report(table, r) == analyze_report(image == table["label"][r], 6)


def test_labels_from_any_iterable_in_its_order(rng):
    """labels= is typed Iterable[int]: a generator, dict keys or a range
    give the rows a list gives, in their order (a generator was refused as
    "label <generator ...> is not a value the labels of this image hold"),
    in 3D, in 2D and block by block."""
    from isoflow.digital.label_blocks import label_table_blocks

    image = nested(rng)
    asked = [int(v) for v in np.unique(image)[::-1] if v][:3] + [250]
    counts = [int(np.count_nonzero(image == v)) for v in asked]
    for kind in (lambda: (v for v in asked), lambda: dict.fromkeys(asked).keys(), lambda: iter(asked)):
        assert label_table(image, labels=kind())["voxels"].tolist() == counts
        assert label_table(image, labels=kind())["label"].tolist() == asked
        assert label_table_blocks(image, labels=kind(), layers=[10, 20])["voxels"].tolist() == counts
        assert label_table(image[5], labels=kind())["voxels"].tolist() == [int(np.count_nonzero(image[5] == v))
                                                                           for v in asked]
    assert label_table(image, labels=range(1, 4))["label"].tolist() == [1, 2, 3]


def test_without_surfaces_the_surface_columns_are_left_out(rng):
    image = nested(rng)
    full, short = label_table(image), label_table(image, surfaces=False)
    assert set(full) - set(short) == {"surfaces", "genera", "surface_euler", "pinched_vertices", "doubled_edges"}
    for key in short:
        assert np.array_equal(short[key], full[key], equal_nan=True), key


@pytest.mark.parametrize("dtype", [np.int8, np.int16, np.int64, np.uint8, np.uint16, np.uint64])
def test_distinct_labels_equal_numpys_unique(rng, dtype):
    """The labels' distinct values and each one's index among them, from a
    table over their range where it is short, are NumPy's unique, as are an
    image's values read a step at a time into that table: also
    where the range spans the type's ends (a difference the type cannot
    hold) and where it is too sparse for a table."""
    info = np.iinfo(dtype)
    ends = [info.min, info.max, info.min + 2, info.max - 1, info.min, info.max - 1]
    cases = [rng.integers(info.min, info.max, size, dtype=dtype, endpoint=True) for size in (0, 7, 70_000)]
    cases += [np.array(ends[:2] * 3, dtype), np.array(ends[2:], dtype), rng.integers(0, 9, 500).astype(dtype)]
    cases += [np.array([info.min, info.min + 3, info.min], dtype), np.array([info.max, info.max - 3], dtype)]
    for values in cases:
        want, got = np.unique(values, return_inverse=True), distinct(values)
        assert got[0].dtype == values.dtype and got[0].tolist() == want[0].tolist(), values[:4]
        assert got[1].tolist() == want[1].tolist(), values[:4]
        # an image's values, read in steps into the same table (None where too sparse for one)
        seen = image_values(values.reshape(1, 1, -1))
        short = len(values) == 0 or int(values.max()) - int(values.min()) <= 4 * len(values) + 1024
        assert (seen is not None) == short and (seen is None or seen.tolist() == want[0].tolist()), values[:4]


def test_pandas_takes_the_columns_as_they_are(rng):
    pd = pytest.importorskip("pandas")
    table = label_table(nested(rng))
    frame = pd.DataFrame(table)
    assert len(frame) == len(table["label"]) and list(frame.columns) == list(table)


@pytest.mark.parametrize("method", METHODS)
def test_bool_image_is_label_1(method):
    image = ball(4.0, 12) & ~ball(2.0, 12)
    table = label_table(image, method=method)
    assert table["label"].tolist() == [1] and table["label"].dtype == np.uint8
    assert row_report(table, 0) == analyze_report(image, 6)
    # label 2 is not True: a bool image holds none of it, so its row is empty
    for image_nd in (image, image[6]):
        asked = label_table(image_nd, labels=[2, 1], method=method)
        assert asked["label"].tolist() == [2, 1]
        assert asked["voxels"].tolist() == [0, np.count_nonzero(image_nd)]


@pytest.mark.parametrize("method", METHODS)
def test_signed_labels_come_in_increasing_order(rng, method):
    for dtype in (np.int8, np.int64):
        info = np.iinfo(dtype)
        values = np.array([0, info.min, -5, -1, 3, info.max], dtype)
        image = values[rng.integers(0, len(values), (60, 50, 45))]  # above the compiled pass's size
        table = label_table(image, method=method)
        assert table["label"].tolist() == sorted(set(values.tolist()) - {0})
        for r in range(len(table["label"])):
            assert table["voxels"][r] == np.count_nonzero(image == table["label"][r])


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("shape", [(60, 50, 45), (40, 30)])
def test_a_big_endian_image_gives_the_native_images_table(rng, method, shape):
    """NRRD, HDF5 and ``>i4`` arrays are big-endian: the table, column
    types included, is the native image's, so no column is big-endian."""
    from skimage.measure import regionprops

    image = rng.integers(0, 5, shape).astype(np.int32) * 1000003
    big = image.astype(">i4")
    native, table = label_table(image, method=method), label_table(big, method=method)
    assert table.keys() == native.keys()
    for key, column in table.items():
        assert column.dtype == native[key].dtype and column.dtype.isnative, key
        assert column.tolist() == native[key].tolist(), key
    props = regionprops(image)
    assert table["label"].tolist() == [p.label for p in props]
    assert table["voxels"].tolist() == [p.area for p in props]
    assert label_table(big, labels=[3000009, 1000003])["label"].dtype == np.int32


@pytest.mark.parametrize("method", METHODS)
def test_a_float_image_of_whole_numbers_is_read_as_int64(rng, method):
    image = nested(rng)
    want = label_table(image.astype(np.int64), method=method)
    for dtype in (np.float16, np.float32, np.float64):
        got = label_table(image.astype(dtype), method=method)
        assert got["label"].dtype == np.int64
        for key in want:
            same = (list(want[key]) == list(got[key]) if want[key].dtype == object
                    else np.array_equal(want[key], got[key], equal_nan=True))
            assert same, key
    planar = label_table(image[10].astype(np.float32))
    assert planar["label"].tolist() == np.unique(image[10])[1:].tolist()
    lowest = np.zeros((3, 3, 3))
    lowest[1, 1, 1] = -(2.0**63)  # int64's least value, exact in float64
    assert label_table(lowest)["label"].tolist() == [np.iinfo(np.int64).min]


@pytest.mark.parametrize("value, dtype, words", [
    (np.nan, np.float32, r"voxel \(1, 2, 0\) holds nan: not a label"),
    (-np.inf, np.float16, r"voxel \(1, 2, 0\) holds -inf: not a label"),
    (2.5, np.float64, r"voxel \(1, 2, 0\) holds 2.5: not a whole number"),
    (2.0**70, np.float32, r"holds 1.1805916207174113e\+21: beyond the int64 labels"),
    (2.0**63, np.float64, "beyond the int64 labels"),
])
def test_a_float_value_that_is_no_label_is_named_with_its_voxel(value, dtype, words):
    import warnings

    image = np.zeros((3, 4, 5), dtype)
    with np.errstate(over="ignore"):
        image[1, 2, 0] = value
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # float16 compared with 2**63 warned of an overflow
        with pytest.raises(IsoflowError, match=words):
            label_table(image)


@pytest.mark.parametrize("bad, words", [
    (np.zeros((2, 2, 2, 2), np.uint8), "3D or 2D label image, got a 4D"),  # (2D: tests/digital/test_planar_labels.py)
    (np.zeros((4, 4, 4), np.complex64), "integers, not complex64"),
])
def test_bad_images_are_one_line(bad, words):
    with pytest.raises(IsoflowError, match=words):
        label_table(bad)


def test_bad_choices_are_one_line():
    image = np.zeros((3, 3, 3), np.uint8)
    with pytest.raises(IsoflowError, match="asked twice: 2"):
        label_table(image, labels=[2, 1, 2])
    with pytest.raises(IsoflowError, match=r"not a value the labels of this image hold: they are uint8 \(0 to 255\)"):
        label_table(image, labels=[300])
    with pytest.raises(IsoflowError, match="method"):
        label_table(image, method="fast")
    with pytest.raises(IsoflowError, match="connectivity 18"):
        label_table(image, 18)
    # the text "6" is no connectivity; the message quotes it rather than
    # refuse 6 while offering it ("connectivity 6 is not valid in 3D (use 6 or 26)")
    for text, dims in (("6", 3), ("4", 2)):
        with pytest.raises(IsoflowError, match=f"^connectivity '{text}' is not valid in {dims}D"):
            label_table(image if dims == 3 else image[0], text)


def test_auto_takes_the_compiled_pass_from_the_start_it_pays():
    """The rule of ``method="auto"``: with numba imported, the compiled
    pass from LABEL_PASS_VOXELS on; without, the NumPy pass while its work
    (a share per label and the labels' boxes) stays below numba's start."""
    from isoflow.digital.label_table import LABEL_PASS_VOXELS, NUMBA_START_WORK, compiled_sooner, numpy_work

    assert compiled_sooner(LABEL_PASS_VOXELS, numba_loaded=True)
    assert not compiled_sooner(LABEL_PASS_VOXELS - 1, numba_loaded=True)
    few = 100
    boxes = NUMBA_START_WORK - numpy_work(few, 0)
    assert not compiled_sooner(2 * LABEL_PASS_VOXELS, False, few, boxes - 1)
    assert compiled_sooner(2 * LABEL_PASS_VOXELS, False, few, boxes)
    assert numpy_work(few + 1, boxes) > numpy_work(few, boxes)
    with pytest.raises(IsoflowError, match="box_voxels"):
        compiled_sooner(64**3, False)


def contacts(rng, size, labels):
    """Random labels on 2^3 blocks, so that neighbours touch by faces,
    edges and vertices; every label's voxels compact (a block of its
    own grid cell) where ``labels`` is a cube."""
    side = round(labels ** (1 / 3))
    coarse = rng.integers(0, labels + 1, (size // 2,) * 3)
    cell = np.arange(size // 2) * side // (size // 2)
    grid = (cell[:, None, None] * side + cell[None, :, None]) * side + cell[None, None, :] + 1
    return np.kron(np.where(coarse % 3 == 0, 0, grid), np.ones((2, 2, 2), np.int64)).astype(np.uint16)


@needs_numba
@pytest.mark.parametrize("labels", [8, 27, 1000])
@pytest.mark.parametrize("conn", [6, 26])
def test_both_passes_give_one_table_near_the_threshold(rng, labels, conn):
    """Either side of LABEL_PASS_VOXELS (a 62^3 and a 64^3 image), on few
    compact labels and on many, the NumPy and compiled tables are equal,
    and scikit-image's counts and Euler numbers (26) agree with both."""
    from skimage.measure import regionprops

    for size in (62, 64):
        image = contacts(rng, size, labels)
        numpy, compiled = (label_table(image, conn, method=m) for m in ("numpy", "compiled"))
        assert numpy.keys() == compiled.keys()
        for key in numpy:
            assert np.array_equal(numpy[key], compiled[key], equal_nan=key.startswith(("bbox", "centroid"))), key
        props = {p.label: p for p in regionprops(image)}
        assert numpy["label"].tolist() == sorted(props)
        assert numpy["voxels"].tolist() == [props[v].area for v in sorted(props)]
        if conn == 26:
            assert numpy["euler_characteristic"].tolist() == [props[v].euler_number for v in sorted(props)]


@needs_numba
@pytest.mark.parametrize(("labels", "offset", "numba_started"), [(27, 0, False), (1000, 0, True), (27, 2 * 64**3, True)])
def test_a_fresh_process_starts_numba_only_for_many_labels(tmp_path, rng, labels, offset, numba_started):
    """``isoflow info LABELS --labels`` on a 64^3 image of few compact
    labels answers without importing numba (its start would take longer
    than the NumPy pass), and gives the table the compiled pass gives;
    on many labels it takes the compiled pass, and on labels beyond the
    voxel count (whose count would hold an entry per value, 8 bytes a
    voxel and more) too."""
    import json
    import os
    import subprocess
    import sys

    image = contacts(rng, 64, labels).astype(np.uint32)
    image[image > 0] += offset
    path = tmp_path / "labels.npy"
    np.save(path, image)
    script = ("import runpy, sys; sys.argv = ['isoflow', 'info', sys.argv[1], '--labels', '--json']\n"
              "try:\n    runpy.run_module('isoflow', run_name='__main__')\n"
              "finally:\n    print('numba' in sys.modules, file=sys.stderr)")
    run = subprocess.run([sys.executable, "-c", script, str(path)], capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert run.stderr.strip().splitlines()[-1] == str(numba_started), run.stderr
    rows = json.loads(run.stdout)["labels"]
    compiled = label_table(image, 6, method="compiled")
    for key in ("label", "voxels", "euler_characteristic", "b0", "b1", "b2", "energy", "surfaces", "surface_euler",
                *(f"n-{i}" for i in range(9))):
        assert [row[key] for row in rows] == compiled[key].tolist(), key


@needs_numba
@pytest.mark.parametrize("conn", [6, 26])
def test_an_image_in_memory_of_more_voxels_than_the_pieces_number_is_read_in_slabs(rng, conn, monkeypatch):
    """An image in memory of more than 2^32 - 2 voxels (1,626^3 and up)
    ended ``label_table`` in a ValueError ("use slabs"), and ``isoflow info
    --labels`` in an internal error, where memory would have held the
    work. Here the limit is lowered to 1,200 voxels, so that the nesting,
    wrapping and touching labels of a 30 x 18 x 17 image are read in slabs
    of two layers: every label's voxels, box, components, cavities and
    Euler characteristic those of scikit-image and scipy."""
    from scipy import ndimage
    from skimage.measure import euler_number, regionprops

    from isoflow.scale import pieces

    image = nested(rng)
    monkeypatch.setattr(pieces, "MAX_PIECE_VOXELS", 1200)
    table = label_table(image, conn, method="compiled")
    props = {p.label: p for p in regionprops(image)}
    assert table["label"].tolist() == sorted(props)
    obj = ndimage.generate_binary_structure(3, 1 if conn == 6 else 3)
    other = ndimage.generate_binary_structure(3, 3 if conn == 6 else 1)
    for row, value in enumerate(table["label"].tolist()):
        solid = image == value
        assert table["voxels"][row] == props[value].area
        assert [table[f"bbox-{d}"][row] for d in range(6)] == list(props[value].bbox)
        assert table["euler_characteristic"][row] == euler_number(solid, 1 if conn == 6 else 3)
        assert table["b0"][row] == ndimage.label(solid, obj)[1]
        holes, n = ndimage.label(np.pad(~solid, 1, constant_values=True), other)
        assert table["b2"][row] == n - 1  # the complement's components but the one outside


@needs_numba
def test_pieces_beyond_the_budget_are_refused_naming_the_layers_that_fit(monkeypatch):
    """The compiled pass refused an image of noise whose pieces' statistics
    would not fit the budget without a word of what would: the line names
    the pieces (scipy's count of every value's 6-connected components)
    and the voxel layers whose passes fit, and the image cropped to them
    gives its table under the same budget, each label's voxels NumPy's."""
    from scipy import ndimage

    from isoflow.scale import memory
    from isoflow.scale.pieces import PIECE_BYTES

    vol = np.random.default_rng(3).integers(1, 7, (40, 40, 40)).astype(np.uint8)
    n = sum(ndimage.label(vol == value)[1] for value in range(1, 7))
    monkeypatch.setattr(memory, "default_budget", lambda: PIECE_BYTES * (n + 1) // 2)
    with pytest.raises(IsoflowError, match=f"^the label table of {n:,} pieces of a label image needs about ") as exc:
        label_table(vol, method="compiled")
    found = re.search(r"; about (\d+) of the 40 voxel layers fit: crop the image along its first axis;", str(exc.value))
    assert found and "\n" not in str(exc.value), str(exc.value)
    fit = int(found.group(1))
    table = label_table(vol[:fit], method="compiled")
    assert 1 <= fit < 40 and list(table["voxels"]) == np.bincount(vol[:fit].reshape(-1))[1:].tolist()


@needs_numba
def test_noise_of_many_labels_is_refused_before_its_graph_and_a_grain_map_is_not(monkeypatch):
    """Noise of 1,000 labels has a piece for nearly every voxel, and the
    passes after the pieces (features, pairs, the graph) take hundreds of
    bytes a piece: beyond the budget, the table is refused as soon as the
    pieces are counted (scipy's count of every value's 6-connected
    components), before the vertex pass, naming the voxel layers that fit;
    the crop to them gives its table under the same budget. A map of 64
    blocks of the same size is not refused under it."""
    from scipy import ndimage

    from isoflow.digital import label_table as module
    from isoflow.scale import memory, pieces

    vol = np.random.default_rng(5).integers(1, 1001, (32, 24, 24)).astype(np.uint16)
    n = sum(ndimage.label(vol == value)[1] for value in np.unique(vol))
    budget = (pieces.PIECE_BYTES * (n + 1) + module.later_bytes(n + 1, vol.size / (n + 1))) * 2 // 3
    monkeypatch.setattr(memory, "default_budget", lambda: budget)
    reached = []
    monkeypatch.setattr(pieces, "vertex_pass", lambda *a, **k: reached.append(1))
    with pytest.raises(IsoflowError, match=f"^the label table of {n:,} pieces of a label image needs about ") as exc:
        label_table(vol, method="compiled")
    assert not reached
    fit = int(re.search(r"; about (\d+) of the 32 voxel layers fit: crop the image along its first axis;",
                        str(exc.value)).group(1))
    monkeypatch.undo()
    monkeypatch.setattr(memory, "default_budget", lambda: budget)
    table = label_table(vol[:fit], method="compiled")
    assert 1 <= fit < 32 and table["voxels"].tolist() == np.bincount(vol[:fit].reshape(-1))[1:].tolist()
    blocks = (np.indices(vol.shape) // np.array([8, 6, 6]).reshape(3, 1, 1, 1))
    grains = (blocks[0] * 16 + blocks[1] * 4 + blocks[2] + 1).astype(np.uint16)
    assert label_table(grains, method="compiled")["b0"].tolist() == [1] * 64


@needs_numba
def test_a_table_whose_pieces_would_not_fit_is_made_label_by_label(monkeypatch):
    """Noise of three labels (a noisy segmentation of three phases) has
    a piece for every third voxel, and the one pass' pieces and graph
    take hundreds of bytes a voxel where each label's own ``analyze``
    takes tens: under a budget between the two, ``"auto"`` gives the
    table label by label (each row ``analyze`` of its label, as the
    NumPy path's), where ``"compiled"`` is refused; under a budget that
    neither fits, the refusal is the one pass', naming what would fit."""
    from isoflow.scale import memory

    image = np.random.default_rng(0).integers(0, 4, (64, 64, 64)).astype(np.uint8)
    monkeypatch.setattr(memory, "default_budget", lambda: 20 << 20)
    table = assert_rows_equal_analyze(image, 6)
    assert table["label"].tolist() == [1, 2, 3]
    with pytest.raises(IsoflowError, match=r"^the label table of [\d,]+ pieces of a label image needs about "):
        label_table(image, method="compiled")
    # below the label-by-label pass' masks (a mask and its bit rows: 1.1 bytes a voxel) and its sort (9)
    monkeypatch.setattr(memory, "default_budget", lambda: 256 << 10)
    with pytest.raises(IsoflowError, match=r"^the (label table of [\d,]+ pieces|runs of \d+ layers) of a label image "
                                           r".* voxel layers fit: crop the image"):
        label_table(image)


@needs_numba
def test_auto_takes_the_label_by_label_pass_where_the_pieces_are_many_for_the_values(monkeypatch):
    """Noise of three labels has a piece for every third voxel, three
    noisy phases (a third each, which percolate) one for every seventh,
    and a smooth segmentation of three labels with one voxel in a hundred
    changed one for every hundred and fifty: each is more than
    ``FRAGMENTED`` pieces a voxel for each of its four values, so "auto"
    makes the table label by label (the sooner there: every block of the
    one pass holds several pieces), the same table as the one pass'; the
    first two said so by slabs of a few layers, before the whole image's
    pieces were counted (``SAMPLE_LAYERS``). Noise of 1,000
    labels, a map of 64 blocks and the smooth segmentation unchanged keep
    the one pass."""
    from isoflow.digital import label_by_label
    from isoflow.digital import label_table as module
    from isoflow.scale import pieces

    called = []
    by_label, by_masks = module.box_rows, label_by_label._mask_rows
    monkeypatch.setattr(module, "box_rows", lambda *a, **k: called.append("box_rows") or by_label(*a, **k))
    monkeypatch.setattr(label_by_label, "_mask_rows", lambda *a, **k: called.append("masks") or by_masks(*a, **k))
    rng = np.random.default_rng(2)
    noise = rng.integers(0, 4, (64, 64, 64)).astype(np.uint8)
    phases = rng.integers(0, 3, (64, 64, 64)).astype(np.uint8)
    smooth = (np.indices(noise.shape)[0] // 22 + 1).astype(np.uint8)  # three slabs
    salted = smooth.copy()
    salt = rng.random(smooth.shape) < 0.01
    salted[salt] = rng.integers(0, 4, int(salt.sum()))
    many = rng.integers(0, 1001, (64, 64, 64)).astype(np.uint16)
    blocks = np.indices(noise.shape) // 16
    grains = (blocks[0] * 16 + blocks[1] * 4 + blocks[2] + 1).astype(np.uint8)
    counted = []
    piece_runs = pieces.piece_runs
    monkeypatch.setattr(pieces, "piece_runs", lambda v, *a, **k: counted.append(v.size) or piece_runs(v, *a, **k))
    for image, sampled in ((noise, True), (phases, True), (salted, False)):
        one_pass = label_table(image, method="compiled")
        assert not called
        counted.clear()
        table = label_table(image)
        assert called[:1] == ["box_rows"]  # (by masks where they pay for the compiled census: the next test)
        # three slabs of two layers said so, or the whole image's pieces (a slab of that smooth image said not)
        assert counted[0] == 2 * 64 * 64 and (image.size not in counted) == sampled
        assert all(np.array_equal(table[k], one_pass[k]) if table[k].dtype != object
                   else table[k].tolist() == one_pass[k].tolist() for k in table)
        called.clear()
    label_table(many), label_table(grains), label_table(smooth)
    assert not called


@needs_numba
@pytest.mark.parametrize("connectivity", [6, 26])
def test_a_noisy_segmentation_label_by_label_equals_analyze_in_a_fresh_process(monkeypatch, connectivity):
    """Where the masks of a noisy segmentation pay for loading the
    compiled census (as in a fresh process, whose tally is empty), each
    label's row comes from the census of its mask: rows equal to
    ``analyze`` of each label at both connectivities, a label asked for
    that is not in the image a row of no voxel, and label 0's row with
    ``background``; where they would not pay, each label's box goes
    through ``analyze`` after one sort."""
    from isoflow.digital import closed_surfaces, label_by_label
    from isoflow.scale import compiled

    monkeypatch.setattr(closed_surfaces, "census_loaded", lambda: False)
    monkeypatch.setattr(label_by_label, "census_loaded", lambda: False)
    compiled.reset_tally()
    masks = []
    by_masks = label_by_label._mask_rows
    monkeypatch.setattr(label_by_label, "_mask_rows", lambda *a, **k: masks.append(1) or by_masks(*a, **k))
    image = np.random.default_rng(7).integers(0, 4, (66, 64, 65)).astype(np.int16)
    image[image == 2] = -2  # a negative label, sorted before 0
    monkeypatch.setattr(compiled, "MIN_VOXELS", 200_000)  # the census from 400,000 voxels: two masks
    table = assert_rows_equal_analyze(image, connectivity, labels=[3, 5, -2, 1])
    assert masks and table["label"].tolist() == [3, 5, -2, 1] and table["voxels"][1] == 0
    everything = assert_rows_equal_analyze(image, connectivity, background=True)
    assert everything["label"].tolist() == [-2, 0, 1, 3]
    masks.clear()
    monkeypatch.setattr(compiled, "MIN_VOXELS", 2_000_000)  # three masks of 274,560 voxels do not pay
    compiled.reset_tally()
    again = label_table(image, connectivity)
    assert not masks and again["euler_characteristic"].tolist() == table["euler_characteristic"][[2, 3, 0]].tolist()


@needs_numba
def test_the_label_by_label_sort_weighs_its_boxes_as_a_loop_s_volumes(monkeypatch):
    """The sort's pass, taken after the pieces were counted (numba in the
    process: where the one pass would not fit), weighs its boxes as a
    loop's volumes: NumPy's census while they add up to less than the
    size that pays for loading the compiled one, the compiled census from
    there (noise of ten labels at 128^3 made every box of the whole image
    by NumPy's census, three times as slow). Taken for the whole image
    (few labels, small), every box stays NumPy's."""
    from isoflow.digital import analysis, closed_surfaces
    from isoflow.digital.label_by_label import box_rows
    from isoflow.scale import compiled

    monkeypatch.setattr(compiled, "MIN_VOXELS", 200_000)  # the census from 400,000 voxels: two boxes of 66^3
    monkeypatch.setattr(closed_surfaces, "census_loaded", lambda: False)  # as in a fresh process
    methods = []
    analyze = analysis.analyze
    monkeypatch.setattr(analysis, "analyze", lambda *a, **k: methods.append(k["method"]) or analyze(*a, **k))
    image = np.random.default_rng(4).integers(0, 4, (64, 64, 64)).astype(np.uint8)  # 3 labels and 0
    compiled.reset_tally()
    found = box_rows(image, 26, None, True, weighed=True)
    assert methods == ["numpy", "compiled", "compiled"]
    assert found["label"].tolist() == [1, 2, 3]
    for row, label in enumerate(found["label"].tolist()):
        report = analyze(image == label, 26)
        assert found["features"][row][0] == 8 * report["euler_characteristic"]
        assert [found["b0"][row], found["b2"][row]] == [report["betti"][0], report["betti"][2]]
    methods.clear()
    compiled.reset_tally()
    label_table(image[:6, :6, :6], 26)  # NumPy's pass for the whole image: numba need not load
    assert methods and set(methods) == {"numpy"}


@pytest.mark.parametrize("label", [1.5, True, np.True_, np.float64(1.5), np.float32(1.5)])
def test_a_label_asked_for_as_a_float_or_a_bool_is_refused(label):
    """``labels=[True]`` was taken as label 1, and ``1.5`` cut to it: a
    choice of labels is whole numbers, and the refusal names the value
    (a whole float, ``1.0``, is label 1: tests/test_integer_arguments.py)."""
    image = np.zeros((4, 4, 4), np.uint8)
    image[1:3, 1:3, 1:3] = 1
    shown = repr(label.item() if isinstance(label, np.generic) else label)  # a NumPy scalar as the value it holds
    with pytest.raises(ValueError, match=re.escape(f"label {shown} is not an integer")):
        label_table(image, labels=[label])
    # an integer of NumPy's is one
    assert label_table(image, labels=[np.int64(1)])["voxels"].tolist() == [np.count_nonzero(image == 1)]


@pytest.mark.parametrize("pitch", [(1, 1, np.inf), (1, 1, np.nan), np.inf, (1, -np.inf, 1)])
def test_a_pitch_that_is_not_finite_is_said_to_be_one(pitch):
    """``pitch=(1, 1, inf)`` was refused as "must be 3 numbers, one per
    axis", which three numbers are: the line says the voxel size must be
    finite and positive, naming the value."""
    assert not np.isfinite(pitch).all() and np.size(pitch) in (1, 3)
    with pytest.raises(IsoflowError) as info:
        label_table(np.ones((2, 2, 2), np.uint8), pitch=pitch)
    said = str(info.value)
    assert "'pitch' must be finite and positive" in said and "one per axis, got" not in said.split("(")[0]
    assert said.endswith("got " + ("inf" if np.ndim(pitch) == 0 else
                                   "[" + ", ".join(f"{x:g}" for x in np.asarray(pitch, float)) + "]"))


@needs_numba
@pytest.mark.parametrize("conn", [6, 26])
def test_labels_of_hundreds_of_surfaces_of_many_sizes_equal_analyze(rng, conn):
    """Noise of a few labels (at 26 sparse enough not to percolate): each
    label has a hundred surfaces or more, of many sizes and genera, which
    the table orders as analyze does, most faces first, then chi."""
    image = rng.integers(0, 3 if conn == 6 else 12, (18, 17, 16)).astype(np.uint8)
    table = assert_rows_equal_analyze(image, conn, method="compiled")
    assert (table["surfaces"] > 100).all() and len({g for row in table["genera"] for g in row}) >= 2


@needs_numba
@pytest.mark.parametrize("conn", [6, 26])
def test_components_of_one_label_nested_in_each_others_cavities_equal_analyze(rng, conn, monkeypatch):
    """A hollow ball of label 1 in a shell of label 2 drilled through, in a
    shell of label 1, in a scatter of label 3: the space between the two
    parts of label 1 lies around one (its parent) and inside the other (its
    child), which the graph walks tell apart per component against its own
    box; every row equals ``analyze`` of its label."""
    n = 31
    r = np.sqrt(((np.indices((n,) * 3) - (n - 1) / 2) ** 2).sum(0))
    image = np.choose((r // 3).astype(int) % 4, [1, 0, 2, 0]).astype(np.uint8)
    image[(r >= 15) | (r < 1)] = 0
    image[:15, 14:17, 14:17][image[:15, 14:17, 14:17] == 2] = 0  # the tunnel through label 2
    image[(image == 0) & (r < 15) & (rng.random(image.shape) < 0.1)] = 3
    table = assert_rows_equal_analyze(image, conn, method="compiled")
    assert table["b0"][:2].tolist() == [2, 1] and table["b2"][:2].tolist() == [2, 0]
    # the walks' int32 stamps start again on cleared stamps where they would wrap: here at every walk
    from isoflow.scale import piece_graph

    monkeypatch.setattr(piece_graph, "MOST_WALKS", 1)
    again = label_table(image, conn, method="compiled", threads=1)
    assert all(np.array_equal(again[k], table[k]) if table[k].dtype != object else again[k].tolist() == table[k].tolist()
               for k in table)


@needs_numba
@pytest.mark.parametrize("conn", [6, 26])
def test_the_graph_of_pieces_placed_on_threads_in_runs_of_pairs_equals_analyze(rng, conn, monkeypatch):
    """The graph of pieces is counted and placed from runs of the vertex
    pass' pairs, a run per thread (a run of one pair here, so that every
    block of pairs is cut): each row still equals ``analyze`` of its label,
    on labels touching by faces, edges and vertices, nested and wrapped."""
    from isoflow.scale import piece_graph

    monkeypatch.setattr(piece_graph, "PAIRS_PER_THREAD", 1)
    for trial in range(8):
        image = nested(rng) if trial == 0 else rng.choice(5, size=tuple(rng.integers(3, 11, 3)),
                                                           p=[0.4, 0.15, 0.15, 0.15, 0.15]).astype(np.uint16)
        assert_rows_equal_analyze(image, conn, method="compiled", threads=2 + trial % 2)


@pytest.mark.parametrize("how", ["numpy", "compiled", "blocks", "2d"])
def test_background_adds_label_0s_row_to_every_labels_in_one_pass(rng, how):
    # every label and the background from one pass (info --labels 0-100000): the rows of labels=[0, ...]
    from skimage.measure import euler_number

    from isoflow.digital.label_blocks import label_table_blocks

    if how == "compiled" and not have_numba():
        pytest.skip("numba not installed")
    image = rng.choice([0, 2, 5, -3], size=(9, 8, 7) if how != "2d" else (15, 13)).astype(np.int16)
    if how == "blocks":
        table = label_table_blocks(image, layers=[4, 5], background=True)
        asked = label_table_blocks(image, labels=[-3, 0, 2, 5])
    else:
        method = "auto" if how == "2d" else how
        table = label_table(image, background=True, method=method)
        asked = label_table(image, labels=[-3, 0, 2, 5], method=method)
    assert table["label"].tolist() == [-3, 0, 2, 5]
    for column in table:
        np.testing.assert_array_equal(table[column], asked[column], err_msg=column)
    zero = table["label"].tolist().index(0)
    assert table["voxels"][zero] == np.count_nonzero(image == 0)
    assert table["euler_characteristic"][zero] == euler_number(image == 0, connectivity=1)
    # an image with no voxel of 0 has no background row; a choice of labels asks for 0 itself
    assert 0 not in label_table(image + 10, background=True)["label"].tolist()
    with pytest.raises(IsoflowError, match="with labels, ask for 0"):
        label_table(image, labels=[2], background=True)
