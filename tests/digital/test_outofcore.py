"""Out-of-core analysis: block-wise results equal the in-memory report exactly.

Every comparison is the whole ``analyze(...)`` dict (histogram classes, chi,
Betti numbers, energy, the closed surfaces and their genus, the pinched
vertices and doubled edges), on volumes split into odd-sized chunks so
that objects, tunnels, cavities, pinches and surfaces cross block faces,
edges and corners.
"""

import json
import os
import subprocess
import sys
import types

import numpy as np
import pytest
from conftest import ball, torus
from scipy.ndimage import gaussian_filter
from skimage.measure import euler_number

from isoflow import DigitalObject, IsoflowError, IsoflowWarning, analyze
from isoflow.cli import main

da = pytest.importorskip("dask.array")
zarr = pytest.importorskip("zarr")
from isoflow.digital import outofcore  # noqa: E402
from isoflow.digital.outofcore import analyze_chunked  # noqa: E402
from isoflow.digital.outofcore import analyze_zarr_volume as analyze_zarr  # noqa: E402
from isoflow.scale import arrays  # noqa: E402
from isoflow.scale import chunks as chunks_mod  # noqa: E402

CHUNKS3 = (7, 5, 9)
CHUNKS2 = (7, 5)


def reference(v, conn, surfaces=True):
    return analyze(DigitalObject(v), conn, surfaces=surfaces)


def check(v, conn, chunks=None):
    chunks = chunks or (CHUNKS3 if v.ndim == 3 else CHUNKS2)
    got = analyze_chunked(da.from_array(v, chunks=chunks), conn)
    want = reference(v, conn)
    assert got == want
    assert list(got) == list(want)  # same keys in the same order (JSON output)
    return got


def smooth(rng, shape, sigma=1.5, level=0.5):
    return gaussian_filter(rng.random(shape), sigma) > level


def hollow_ball(r_out, r_in, size=None):
    size = size or int(2 * r_out + 4)
    return ball(r_out, size) & ~ball(r_in, size)


# --------------------------------------------------------------------------
# equal to the in-memory report
# --------------------------------------------------------------------------


@pytest.mark.parametrize("conn", [6, 26])
def test_random_volumes_3d(rng, conn):
    for density in (0.2, 0.5, 0.8):
        shape = tuple(rng.integers(20, 33, 3))
        check(rng.random(shape) < density, conn)


@pytest.mark.parametrize("conn", [6, 26])
def test_smoothed_random_fields_3d(rng, conn):
    for level in (0.45, 0.5, 0.55):
        check(smooth(rng, (31, 26, 37), level=level), conn)


@pytest.mark.parametrize("conn", [6, 26])
def test_known_shapes_across_chunk_borders(conn):
    r = check(ball(11), conn)
    assert r["betti"] == [1, 0, 0]
    r = check(hollow_ball(12, 7), conn)  # the cavity spans several chunks
    assert r["betti"] == [1, 0, 1]
    r = check(torus(9, 3), conn)
    assert r["betti"] == [1, 1, 0] and r["euler_characteristic"] == 0
    # a torus off-centre, around another axis, and a ball inside a hollow ball
    t = torus(8, 2.5, size=30, axis=0, centre=(13, 16, 14))
    check(t, conn)
    nested = hollow_ball(13, 9, size=30) | ball(4, 30)
    r = check(nested, conn)
    assert r["betti"] == [2, 0, 1]


def test_a_box_whose_cavity_and_walls_cross_every_block():
    v = np.ones((29, 33, 31), dtype=bool)
    v[3:-3, 2:-4, 5:-2] = False  # one cavity through all interior blocks
    v[10:12, 10:20, 8:25] = True  # a plate floating inside it
    for conn in (6, 26):
        r = check(v, conn)
        assert r["betti"] == [2, 0, 1]


def test_diagonal_contacts_across_block_corners():
    """Voxels touching only by an edge or a corner, right at block corners:
    one component with 26-connectivity, several with 6."""
    v = np.zeros((21, 20, 27), dtype=bool)
    v[6, 4, 8] = v[7, 5, 9] = True  # corner contact across the (7, 5, 9) block corner
    v[13, 9, 3] = v[14, 10, 3] = True  # edge contact across two block faces
    v[0, 0, 0] = v[20, 19, 26] = True  # the array's own corners
    r6 = check(v, 6)
    r26 = check(v, 26)
    assert r6["betti"][0] == 6 and r26["betti"][0] == 4
    # and the background seen with 6 / 26 around a corner-thin shell
    check(hollow_ball(9, 6, size=24), 26)


@pytest.mark.parametrize("conn", [6, 26])
def test_pinches_tunnels_and_cavities_at_block_edges_and_corners(rng, conn):
    """Vertex contacts (pinches under 6 between background voxels, under
    26 between object voxels) and edge contacts right at block edges and
    corners, a torus whose hole is a block corner, a cavity whose wall is
    cut by three block faces; every field equal to the in-memory report."""
    v = np.zeros((21, 24, 27), dtype=bool)
    c = (7, 5, 9)  # a block corner: voxels 6|7, 4|5, 8|9
    v[6, 4, 8] = v[7, 5, 9] = True  # vertex contact across the corner
    v[6, 5, 8] = v[7, 4, 9] = True  # and the other diagonal: two contacts at one vertex
    v[6, 19, 8] = v[7, 20, 9] = True  # a pinch of the object under 26 at the corner (7, 20, 9)
    v[13, 9, 3] = v[14, 10, 3] = True  # edge contact across the block edge x = 14, y = 10
    v[13:15, 9:11, 17:19] = True  # a pinch of the background under 6 at the corner (14, 10, 18):
    v[13, 9, 17] = v[14, 10, 18] = False  # two opposite background voxels among six object ones
    v[:, 14:16, 17:19] = True  # a bar along x through three blocks
    v[2:5, 14, 17] = False  # (pierced: a vertex contact of its background)
    t = torus(5, 1.5, size=13, axis=2)
    v[c[0] - 6:c[0] + 7, c[1] - 6 + 10:c[1] + 7 + 10, 18:27] |= t[:, :, 2:11]
    shell = hollow_ball(5, 3, size=12)
    v[9:21, 8:20, 0:12] |= shell  # a cavity cut by the faces at x = 14, y = 10 and 15, z = 9
    r = check(v, conn)
    assert r["pinched_vertices"] >= 1 and r["betti"][1] >= 1 and r["betti"][2] >= 1
    for chunks in ((7, 5, 9), (1, 24, 27), (21, 1, 4), (3, 3, 3)):
        check(v, conn, chunks)


@pytest.mark.parametrize("conn", [6, 26])
def test_doubled_edges_across_every_face(rng, conn):
    """Chunks one voxel thick: every vertex is a seam's, every edge along
    that axis has its ends in two seams (loose ends that meet); random
    volumes with edge and vertex contacts."""
    for axis in range(3):
        v = rng.random((9, 10, 11)) < 0.5
        chunks = [5, 4, 6]
        chunks[axis] = 1
        r = check(v, conn, tuple(chunks))
        assert r["doubled_edges"] > 0


@pytest.mark.parametrize("conn", [4, 8])
def test_2d(rng, conn):
    for density in (0.3, 0.5, 0.7):
        check(rng.random(tuple(rng.integers(25, 41, 2))) < density, conn)
    check(smooth(rng, (37, 29)), conn)
    yy, xx = np.indices((33, 35))
    ring = ((yy - 16) ** 2 + (xx - 17) ** 2 <= 13**2) & ((yy - 16) ** 2 + (xx - 17) ** 2 > 6**2)
    r = check(ring, conn)
    assert r["betti"] == [1, 1]


def test_a_block_is_read_while_another_task_imports_numpy_ma(monkeypatch):
    # np.unique imports numpy.ma on its first use, inside a 2D block's task;
    # meanwhile another task checks its block for a mask and finds the module
    # in sys.modules before its MaskedArray is defined
    for name in ("numpy.ma", "numpy.ma.core"):
        monkeypatch.setitem(sys.modules, name, types.ModuleType(name))
    block = np.eye(5, dtype=np.uint8)
    assert not arrays.is_masked_array(block)
    got = arrays.binary(block, "block", near=(0, 0))
    assert got.dtype == bool and (got == (block == 1)).all()
    assert euler_number(got, connectivity=2) == 1  # one 8-connected diagonal: skimage's count of the same pixels


def test_irregular_and_thin_chunks(rng):
    v = smooth(rng, (24, 20, 18))
    for chunks in (((3, 10, 11), (7, 1, 12), (18,)), (1, 20, 6), (24, 20, 1), (5, 3, 4)):
        for conn in (6, 26):
            check(v, conn, chunks)
    img = rng.random((30, 25)) < 0.5
    for conn in (4, 8):
        check(img, conn, (1, 25))
        check(img, conn, ((5, 1, 24), (2, 23)))


def test_chunks_of_no_voxel_are_left_out(rng):
    """dask allows a chunk of length 0 along an axis (chunks=((0, 5, 5),
    ...)); its blocks hold no voxel and add nothing, where their sweep
    raised ZeroDivisionError."""
    v = rng.random((10, 9, 8)) < 0.5
    for chunks in (((0, 5, 5), (9,), (4, 0, 4)), ((3, 7, 0), (0, 9), (8, 0))):
        for conn, full in ((6, 1), (26, 3)):
            got = analyze_chunked(da.from_array(v, chunks=chunks), conn)
            assert got.euler_characteristic == euler_number(np.pad(v, 1), connectivity=full)
            assert got == reference(v, conn)


def test_trivial_volumes():
    for v in (np.zeros((9, 8, 10), bool), np.ones((9, 8, 10), bool), np.ones((1, 1, 1), bool)):
        for conn in (6, 26):
            check(v, conn, (4, 3, 5))
    check(np.ones((12, 9), bool), 8, (5, 4))


def test_numeric_0_1_dtypes(rng):
    v = smooth(rng, (22, 19, 25))
    for dtype in (np.uint8, np.int32, np.float32):
        got = analyze_chunked(da.from_array(v.astype(dtype), chunks=CHUNKS3), 26)
        assert got == reference(v, 26)


def test_block_counts_agree_with_dask_image(rng):
    """b0 against dask-image's chunked labelling (few blocks: it is slow)."""
    from dask_image.ndmeasure import label
    from scipy.ndimage import generate_binary_structure

    v = smooth(rng, (26, 22, 30), level=0.55)
    x = da.from_array(v, chunks=(13, 11, 15))
    for conn, full in ((6, 1), (26, 3)):
        r = analyze_chunked(x, conn)
        _, n = label(x, generate_binary_structure(3, full))
        assert r["betti"][0] == int(n.compute()) == reference(v, conn)["betti"][0]


def test_blocks_hand_on_faces_and_own_each_vertex_once(rng):
    """What a block hands on is faces and a few numbers per piece, never
    voxel-sized (the reason memory stays bounded), and the vertices split
    exactly between the blocks and the seams across their upper faces."""
    from isoflow.digital.blocks import summarize_block
    from isoflow.digital.configurations import configuration_histogram
    from isoflow.digital.seams import merge_block

    v = rng.random((40, 30, 20)) < 0.5
    s = summarize_block(v, (1, 1, 1), (3, 3, 3), (0, 0, 0), (120, 90, 60), 6, "test", True)
    assert sorted({a.shape for a in s["faces"].values()}) == [(30, 20), (40, 20), (40, 30)]
    assert len(s["faces"]) == 2 * 6  # the numbers and the object's voxels on 6 faces
    assert s["hist"].sum() == 39 * 29 * 19  # vertices a+1 .. b-1; those at b are the seams'
    assert len(s["pieces"][0]["key"]) < v.size // 20
    for conn in (6, 26):
        for surfaces in (False, True):
            parts = [(v[:17], (0, 0, 0), ((0, 17), (0, 30), (0, 20))), (v[17:], (1, 0, 0), ((17, 40), (0, 30), (0, 20)))]
            sums = [summarize_block(b, i, (2, 1, 1), (box[0][0], 0, 0), v.shape, conn, "test", surfaces)
                    for b, i, box in parts]
            total = merge_block((0, 0, 0), (2, 1, 1), parts[0][2], v.shape, conn, surfaces, *sums)["hist"]
            total += merge_block((1, 0, 0), (2, 1, 1), parts[1][2], v.shape, conn, surfaces, sums[1])["hist"]
            assert (total == configuration_histogram(v)).all()


def seam_oracle(vox, fg, bg, keep, axis, own, conn, outside):
    """What a seam's census must give, by NumPy: the histogram and loose
    ends of its counted vertices, per key the sheets (box_sheets, the small
    in-memory path), pinches and the cells across the face, and the pairs
    of keys that touch across it."""
    from isoflow.digital.closed_surfaces import MESH_ADJACENCY, box_sheets, sweep_tables
    from isoflow.digital.configurations import configurations

    formula = conn == 6  # the object's Euler characteristic comes from the runs under 6
    cfg = configurations(vox)
    found = box_sheets(vox, fg, bg, keep, conn, outside, cfg=cfg)
    gains = {}

    def add(key, chi4, faces):
        old = gains.get(int(key), (0, 0))
        gains[int(key)] = (old[0] + chi4, old[1] + faces)

    for o, b, vert, q in zip(found["obj"], found["bg"], found["vertices"], found["quarters"]):
        add(b if formula else o, (-1 if formula else 1) * (4 * int(vert) - int(q)), 0)
    padded = np.pad(vox, 1)
    keys = np.pad(np.where(vox, fg, bg), 1, constant_values=outside)
    nsheet, _, _, _, spokes, pinch = sweep_tables(conn)
    loose = set()
    for w in zip(*np.nonzero(np.ones(cfg[keep].shape, bool))):
        w = tuple(int(x) + k.start for x, k in zip(w, keep))
        c = int(cfg[w])
        loose |= {(*w, d) for d in range(6) if (spokes[c] >> d) & 1}
        if pinch[c, 0] >= 0:
            o = next(o for o in range(8) if bool((c >> o) & 1) == formula)
            add(keys[w[0] + (o & 1), w[1] + ((o >> 1) & 1), w[2] + (o >> 2)], 8 * (1 if formula else -1), 0)
    step = np.eye(3, dtype=int)[axis]
    for u in zip(*np.nonzero(np.ones(own, bool))):
        if u[axis] != 0 or vox[u] != vox[tuple(np.add(u, step))]:
            continue
        sign = 1 if vox[u] else -1
        chi = 0
        if bool(vox[u]) == formula:
            boxes = [step + np.eye(3, dtype=int)[m] for m in range(3) if m != axis] + [np.ones(3, int)]
            inside = [all(padded[tuple(np.add(u, d) + 1)] == formula for d in np.ndindex(*(b + 1))) for b in boxes]
            chi = 8 * (-1 + inside[0] + inside[1] - inside[2])
        add(keys[tuple(np.add(u, 1))], sign * chi, -2 * sign)
    joins = set()
    reach = {6: 1, 18: 2, 26: 3}
    for u in zip(*np.nonzero(np.ones(vox.shape, bool))):
        if u[axis] != 0:
            continue
        adj = MESH_ADJACENCY[conn][0 if vox[u] else 1]
        for d in np.ndindex(3, 3, 3):
            d = np.array(d) - 1
            d[axis] = 1
            v = tuple(np.add(u, d))
            if np.abs(d).sum() <= reach[adj] and all(0 <= x < n for x, n in zip(v, vox.shape)) and vox[v] == vox[u]:
                a, b = (fg[u], fg[v]) if vox[u] else (bg[u], bg[v])
                if a != b:
                    joins.add((int(a), int(b), int(vox[u])))
    hist = np.bincount(cfg[keep].ravel(), minlength=256)
    pairs = sorted(map(sorted, found["pairs"].tolist()))
    return hist, {k: g for k, g in gains.items() if g != (0, 0)}, pairs, loose, joins


def layer_pairs(vox, keys, axis):
    """Pairs of keys of face neighbours of one kind inside each layer of a
    seam."""
    pairs = set()
    for m in range(3):
        if m == axis:
            continue
        a, b = [slice(None)] * 3, [slice(None)] * 3
        a[m], b[m] = slice(0, -1), slice(1, None)
        same = vox[tuple(a)] == vox[tuple(b)]
        pairs |= {(int(x), int(y), 0) for x, y in zip(keys[tuple(a)][same], keys[tuple(b)][same])}
    return pairs


def same_partition(left, right):
    """Whether two sets of (key, key, kind) pairs join the keys alike."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    nodes = sorted({k for p in left | right for k in p[:2]})
    at = {k: i for i, k in enumerate(nodes)}

    def labels(pairs):
        rows = np.array([[at[a], at[b]] for a, b, _ in pairs]).reshape(-1, 2)
        graph = coo_matrix((np.ones(len(rows)), (rows[:, 0], rows[:, 1])), shape=(len(nodes),) * 2)
        return connected_components(graph, directed=False)[1]

    x, y = labels(left), labels(right)
    return len(set(zip(x, y))) == len(set(x)) == len(set(y))


@pytest.mark.parametrize("conn", [6, 26])
def test_seam_census_against_numpy(rng, conn):
    """The compiled census of a seam (seen across each axis, with its
    vertices and cells cut as the merge cuts them) equals the NumPy oracle
    above on random seams with edge and vertex contacts."""
    from isoflow.digital.closed_surfaces import MESH_ADJACENCY, sweep_tables
    from isoflow.scale.seams import seam_census
    from isoflow.scale.sweep import sheet_tables

    outside = 1 << 62
    for axis in range(3):
        for density in (0.3, 0.5, 0.7):
            shape = [9, 11, 13]
            shape[axis] = 2
            vox = rng.random(shape) < density
            # keys beyond 32 bits, a few voxels of a layer each (in rows
            # along the last axis)
            keys = np.arange(vox.size).reshape(shape) // 3 + (np.indices(shape)[axis] << 40)
            fg, bg = np.where(vox, keys, 0), np.where(vox, 0, keys + (1 << 20))
            lo, hi = [1, 0, 1], [9, 12, 13]
            lo[axis], hi[axis] = 1, 2
            own = [n - 1 for n in shape]
            keep = tuple(slice(a, b) for a, b in zip(lo, hi))
            got = seam_census(vox, np.where(vox, fg, bg), lo, hi, axis, own, outside,
                              sheet_tables(sweep_tables(conn), conn == 6), conn == 6,
                              tuple({6: 1, 18: 2}[a] for a in MESH_ADJACENCY[conn]))
            hist, gains, pairs, loose, joins = seam_oracle(vox, fg, bg, keep, axis, own, conn, outside)
            assert (got["hist"] == hist).all()
            mine = {int(k): (int(c), int(f)) for k, c, f in zip(got["keys"], got["chi4"], got["faces"])}
            assert {k: g for k, g in mine.items() if g != (0, 0)} == gains and len(gains) > 5
            assert sorted(map(sorted, got["pairs"].tolist())) == pairs
            assert {tuple(map(int, e)) for e in got["loose"]} == loose
            # every pair found touches; with the pairs of face neighbours of
            # one kind inside each layer (which the blocks' labels or other
            # seams join), they join the keys as all the touching pairs do
            edges = {tuple(map(int, e)) for e in got["edges"]}
            assert edges <= joins and len(joins) > 5
            inside = layer_pairs(vox, np.where(vox, fg, bg), axis)
            assert same_partition(edges | inside, joins | inside)


# --------------------------------------------------------------------------
# zarr
# --------------------------------------------------------------------------


def write_zarr(path, v, chunks, dtype=None, zarr_format=3, group=None):
    data = v.astype(dtype or v.dtype)
    if group is None:
        z = zarr.create_array(store=str(path), shape=v.shape, chunks=chunks, dtype=data.dtype,
                              zarr_format=zarr_format)
    else:
        g = zarr.open_group(str(path), mode="w", zarr_format=zarr_format)
        z = g.create_array(group, shape=v.shape, chunks=chunks, dtype=data.dtype)
    z[...] = data
    return path


def test_zarr_v3_and_v2_and_groups(tmp_path, rng):
    v = smooth(rng, (23, 27, 19))
    want6, want26 = reference(v, 6), reference(v, 26)
    p3 = write_zarr(tmp_path / "v3.zarr", v, CHUNKS3)
    assert analyze_zarr(p3, 6) == want6
    assert analyze_zarr(p3, 26) == want26
    p2 = write_zarr(tmp_path / "v2.zarr", v, CHUNKS3, dtype=np.uint8, zarr_format=2)
    assert analyze_zarr(p2) == want6  # default connectivity 6
    pg = write_zarr(tmp_path / "group.zarr", v, (8, 9, 10), group="volume")
    zarr.open_group(str(pg), mode="a").create_array("mask_other", shape=(2, 2), dtype=bool)
    assert analyze_zarr(pg, 26) == want26
    ps = write_zarr(tmp_path / "single.zarr", v, (12, 12, 12), group="anything")
    assert analyze_zarr(ps, 6) == want6
    img = rng.random((31, 22)) < 0.5
    p2d = write_zarr(tmp_path / "img.zarr", img, (6, 7))
    assert analyze_zarr(p2d, 8) == reference(img, 8)


def test_zarr_blocks_follow_the_chunks(tmp_path):
    z = zarr.create_array(store=str(tmp_path / "big.zarr"), shape=(1000, 1000, 1000), chunks=(16, 16, 16), dtype=bool)
    chunks = chunks_mod.zarr_blocks(z, None)  # metadata only: nothing is written or read
    block = [c[0] for c in chunks]
    assert all(b % 16 == 0 for b in block) and np.prod(block) >= chunks_mod.MIN_BLOCK
    assert np.prod([len(c) for c in chunks]) <= chunks_mod.MAX_BLOCKS
    assert [sum(c) for c in chunks] == [1000] * 3
    small = zarr.create_array(store=str(tmp_path / "small.zarr"), shape=(30, 30, 30), chunks=CHUNKS3, dtype=bool)
    assert [c[0] for c in chunks_mod.zarr_blocks(small, None)] == list(CHUNKS3)
    assert [c[0] for c in chunks_mod.zarr_blocks(small, (10, 30, 4))] == [10, 30, 4]


@pytest.mark.parametrize("scheduler", ["sync", "threads"])
@pytest.mark.parametrize("chunks", [(7, 13, 5), (30, 13, 5)])
def test_progress_is_reported_per_block_not_per_layer(tmp_path, rng, scheduler, chunks):
    """A store of one layer of blocks along its first axis (or a layer of
    hundreds, 4096^3 in chunks of 256^3) said nothing until the layer was
    done: progress came once per layer. Every block summed and merged is
    reported now: twice zarr's count of the store's chunks in all, one
    step at a time, and the report still scikit-image's chi."""
    from skimage.measure import euler_number

    v = rng.random((30, 40, 25)) < 0.4
    z = zarr.create_array(store=str(tmp_path / "p.zarr"), shape=v.shape, chunks=chunks, dtype=bool)
    z[...] = v
    calls = []
    got = analyze_zarr(str(tmp_path / "p.zarr"), 26, scheduler=scheduler,
                       progress=lambda done, total: calls.append((done, total)))
    total = 2 * z.nchunks
    assert calls == [(k, total) for k in range(1, total + 1)]
    assert got["euler_characteristic"] == euler_number(v, 3)


def test_cli_info_on_zarr(tmp_path, capsys):
    v = torus(9, 3) | ball(3, torus(9, 3).shape[0])
    path = write_zarr(tmp_path / "t.zarr", v, CHUNKS3)
    np.save(tmp_path / "t.npy", v)
    assert main(["info", str(path), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert main(["info", str(tmp_path / "t.npy"), "--json"]) == 0
    want = json.loads(capsys.readouterr().out)
    assert got.pop("input").endswith("t.zarr") and want.pop("input").endswith("t.npy")
    assert got == want and got["betti"] == [2, 1, 0]
    # random volumes with edge and vertex contacts, at both connectivities:
    # the command's JSON equals that of the .npy, doubled edges included
    rng = np.random.default_rng(27)
    v = rng.random((19, 23, 17)) < 0.5
    write_zarr(tmp_path / "r.zarr", v, CHUNKS3)
    np.save(tmp_path / "r.npy", v)
    for conn in ("6", "26"):
        reports = []
        for name in ("r.zarr", "r.npy"):
            assert main(["info", str(tmp_path / name), "--json", "--connectivity", conn]) == 0
            reports.append(json.loads(capsys.readouterr().out))
            reports[-1].pop("input")
        assert reports[0] == reports[1] and reports[0]["doubled_edges"] > 0 and reports[0]["pinched_vertices"] > 0
    # and as the command, in a process of its own
    p = subprocess.run([sys.executable, "-m", "isoflow", "info", str(tmp_path / "r.zarr"), "--json",
                        "--connectivity", "26"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    command = json.loads(p.stdout)
    command.pop("input")
    assert command == reports[0]
    assert sorted(s["genus"] for s in got["surfaces"]) == [0, 1]  # the ball, the torus
    assert main(["info", str(path), "--connectivity", "26"]) == 0
    out = capsys.readouterr().out
    assert "2 components, 1 tunnel" in out and "#0: genus 1" in out
    assert main(["info", str(path), "--json", "--no-surfaces"]) == 0
    assert "surfaces" not in json.loads(capsys.readouterr().out)


# --------------------------------------------------------------------------
# errors
# --------------------------------------------------------------------------


def test_bad_arrays_raise_isoflow_error(rng):
    with pytest.raises(IsoflowError, match="not a binary volume"):
        v = rng.integers(0, 3, (12, 13, 14))
        analyze_chunked(da.from_array(v, chunks=CHUNKS3))
    with pytest.raises(IsoflowError, match="not a binary volume"):
        v = np.zeros((12, 13, 14), np.float32)
        v[11, 12, 13] = np.nan  # in the last block only
        analyze_chunked(da.from_array(v, chunks=CHUNKS3))
    with pytest.raises(IsoflowError, match="2D or 3D"):
        analyze_chunked(da.zeros((4, 4, 4, 4), chunks=2))
    with pytest.raises(IsoflowError, match="connectivity 8"):
        analyze_chunked(da.zeros((4, 4, 4), chunks=2, dtype=bool), 8)
    # no voxels: the empty object's report, as in memory (it was refused)
    assert analyze_chunked(da.zeros((0, 4, 5), chunks=2, dtype=bool)) == analyze(np.zeros((0, 4, 5), bool))
    with pytest.raises(IsoflowError, match="dask or zarr array"):
        analyze_chunked(np.zeros((4, 4, 4), bool))
    with pytest.raises(IsoflowError, match="not a binary image"):
        analyze_chunked(da.from_array(np.array([["a", "b"], ["c", "d"]]), chunks=1))


def test_a_memmap_given_to_analyze_chunked_is_pointed_to_dask(tmp_path):
    # a volume on disk beyond memory, as np.memmap maps a raw file, was
    # told "use isoflow.analyze for in-memory arrays": it is not in memory,
    # and the advice given now reads it block by block
    from skimage.measure import euler_number

    v = torus(6, 2)
    mapped = np.memmap(tmp_path / "torus.raw", dtype=np.uint8, mode="w+", shape=v.shape)
    mapped[...] = v
    mapped.flush()
    mapped = np.memmap(tmp_path / "torus.raw", dtype=np.uint8, mode="r", shape=v.shape)
    with pytest.raises(IsoflowError) as info:
        analyze_chunked(mapped, 6)
    assert "in-memory" not in str(info.value) and "dask.array.from_array(volume, chunks=" in str(info.value)
    report = analyze_chunked(da.from_array(mapped, chunks=(5, 7, 3)), 6)
    assert report.betti == [1, 1, 0] and report.euler_characteristic == euler_number(np.pad(v, 1), connectivity=1)


def test_a_store_given_to_analyze_chunked_is_pointed_to_analyze_zarr(tmp_path):
    # the OME-Zarr group voxelize_to_zarr and write_volume write, or its
    # path, was told "use isoflow.analyze for in-memory arrays", which
    # reads neither; the advice given now works
    from skimage.measure import euler_number

    from isoflow import write_volume

    v = torus(6, 2)
    path = write_volume(DigitalObject(v), tmp_path / "torus.zarr")
    for given in (str(path), path, zarr.open(str(path), mode="r")):
        with pytest.raises(IsoflowError) as info:
            analyze_chunked(given, 6)
        assert "isoflow.analyze_zarr(path) reads a zarr store" in str(info.value)
        assert "in-memory" not in str(info.value) and "\n" not in str(info.value)
    assert "group['0']" in str(info.value)
    report = analyze_zarr(path, 6)
    assert report.betti == [1, 1, 0] and report.euler_characteristic == euler_number(np.pad(v, 1), connectivity=1)
    with pytest.raises(IsoflowError, match="use isoflow.analyze for in-memory arrays"):
        analyze_chunked(v)


def test_bad_zarr_inputs_raise_with_the_path(tmp_path, rng):
    with pytest.raises(IsoflowError, match="missing.zarr: no such file"):
        analyze_zarr(tmp_path / "missing.zarr")
    (tmp_path / "plain.zarr").mkdir()
    with pytest.raises(IsoflowError, match="plain.zarr: not a zarr array or group"):
        analyze_zarr(tmp_path / "plain.zarr")
    g = zarr.open_group(str(tmp_path / "two.zarr"), mode="w")
    g.create_array("a", shape=(3, 3, 3), dtype=bool)
    g.create_array("b", shape=(3, 3, 3), dtype=bool)
    with pytest.raises(IsoflowError, match=r"two.zarr: a zarr group with arrays \['a', 'b'\]"):
        analyze_zarr(tmp_path / "two.zarr")
    write_zarr(tmp_path / "values.zarr", rng.integers(0, 5, (10, 10, 10)), (5, 5, 5), dtype=np.int16)
    with pytest.raises(IsoflowError, match="values.zarr: not a binary volume"):
        analyze_zarr(tmp_path / "values.zarr")
    write_zarr(tmp_path / "line.zarr", np.zeros(10, bool), (5,))
    with pytest.raises(IsoflowError, match="line.zarr: a volume must be 2D or 3D"):
        analyze_zarr(tmp_path / "line.zarr")


def test_cli_errors_are_one_line_with_the_path(tmp_path, capsys):
    bad = np.zeros((10, 10, 10), np.uint8)
    bad[9, 9, 9], bad[8, 8, 8] = 7, 3  # not in the first chunk: found while streaming (two labels: no mask)
    write_zarr(tmp_path / "bad.zarr", bad, (4, 4, 4))
    # the error found while streaming, as the command in a process of its own
    p = subprocess.run([sys.executable, "-m", "isoflow.cli", "info", str(tmp_path / "bad.zarr")],
                       capture_output=True, text=True)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "bad.zarr" in lines[0] and "not a binary volume" in lines[0], p.stderr
    # a store that is not there, as main prints it in this process
    assert main(["info", str(tmp_path / "nothere.zarr")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "nothere.zarr" in lines[0] and "no such file" in lines[0], lines


def test_missing_dask_says_what_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "dask", None)
    monkeypatch.setitem(sys.modules, "dask.array", None)
    with pytest.raises(IsoflowError, match=r"isoflow\[dask\]"):
        analyze_chunked(object())
    monkeypatch.setitem(sys.modules, "zarr", None)
    with pytest.raises(IsoflowError, match=r"isoflow\[dask\]"):
        outofcore.zarr_volume(".")


def test_a_failed_block_leaves_no_block_running_behind_the_error():
    """The error comes back when the blocks already begun have ended: work
    left running on dask's threads would go on reading the store and would
    restore the warnings state it found (numba's compiler enters
    ``warnings.catch_warnings`` on its thread) in the middle of what the
    caller does next."""
    import threading
    import time

    running = []
    lock = threading.Lock()

    def block(x, block_info=None):
        with lock:
            running.append(1)
        try:
            if block_info[0]["chunk-location"] == (0, 0, 0):
                raise IsoflowError("v.zarr: cannot read block (0, 0, 0)")
            time.sleep(0.3)
            return x
        finally:
            with lock:
                running.pop()

    v = da.from_array(np.ones((8, 8, 8), bool), chunks=4).map_blocks(block, dtype=bool)
    with pytest.raises(IsoflowError, match="cannot read block"):
        analyze_chunked(v, 6, block_shape=(4, 4, 4), threads=2)
    assert running == []


def test_info_of_a_store_without_voxels_is_the_files(tmp_path, capsys):
    # `info ZERO.zarr` refused ("the array has no voxels") where `info
    # zero.npy` of the same array answers with the empty report
    np.save(tmp_path / "zero.npy", np.zeros((0, 4, 5), bool))
    zarr.create_array(str(tmp_path / "zero.zarr"), shape=(0, 4, 5), chunks=(2, 2, 2), dtype="uint8", zarr_format=2)
    reports = []
    for name in ("zero.npy", "zero.zarr"):
        assert main(["info", str(tmp_path / name), "--json"]) == 0
        reports.append({k: v for k, v in json.loads(capsys.readouterr().out).items() if k != "input"})
    assert [r.pop("dtype") for r in reports] == ["bool", "uint8"]  # what each file holds
    assert reports[0] == reports[1] and reports[1]["voxels"] == 0 and reports[1]["betti"] == [0, 0, 0]


@pytest.mark.parametrize("axes", ["zyx", "tczyx", "cyxz"])
def test_analyze_zarr_of_an_ome_zarr_image_equals_the_in_memory_report(tmp_path, axes):
    """An OME-Zarr image by its path (and ``:LEVEL``): the report of the
    volume in (x, y, z) order, its channel and time axes of length 1 left
    out, as ``isoflow info`` gives it; the shape is not the stored order's."""
    from skimage.measure import euler_number

    v = (gaussian_filter(np.random.default_rng(7).random((13, 11, 9)), 1.0) > 0.5).astype(np.uint8)
    group = zarr.open_group(str(tmp_path / "image.zarr"), mode="w", zarr_format=2)
    datasets = []
    for level, step in (("0", 1), ("1", 2)):
        data = v[::step, ::step, ::step]
        stored = np.transpose(data, ["xyz".index(a) for a in axes if a in "xyz"])
        stored = stored.reshape([1 if a in "tc" else stored.shape[[b for b in axes if b in "xyz"].index(a)]
                                 for a in axes])
        group.create_array(level, data=stored, chunks=tuple(1 if a in "tc" else 4 for a in axes))
        datasets.append({"path": level})
    group.attrs["multiscales"] = [{"version": "0.4", "axes": list(axes), "datasets": datasets}]
    for path, data in ((tmp_path / "image.zarr", v), (f"{tmp_path / 'image.zarr'}:1", v[::2, ::2, ::2])):
        for conn in (6, 26):
            report = analyze_zarr(path, conn)
            assert report == analyze(data, conn)
            assert report["shape"] == list(data.shape)
            assert report["euler_characteristic"] == euler_number(np.pad(data, 1), 3 if conn == 26 else 1)


@pytest.mark.parametrize("fmt", [2, 3])
def test_chunks_never_written_are_read_as_the_fill_value(tmp_path, capsys, fmt):
    """zarr leaves out the chunks that hold nothing but the fill value, and
    reads them as it: with fill value 1 the report is that of the volume in
    memory; with 2 (or NaN) the refusal named "e.g. 2" only, a value no
    voxel was written with, and now says it is the array's fill value, in
    ``info`` and ``surface`` alike."""
    from scipy.ndimage import label

    v = (gaussian_filter(np.random.default_rng(3).random((17, 13, 11)), 1.0) > 0.5).astype(np.uint8)
    v[:10, :8, :] = 1  # whole chunks of ones, never written with fill value 1
    ones = zarr.create_array(str(tmp_path / "ones.zarr"), shape=v.shape, chunks=(5, 4, 11), dtype="u1",
                             fill_value=1, zarr_format=fmt)
    ones[...] = v
    assert len(list((tmp_path / "ones.zarr").rglob("*"))) < 40  # some chunks are not there
    with pytest.warns(IsoflowWarning, match="chunks were never written"):
        report = analyze_zarr(tmp_path / "ones.zarr", 6)
    assert report == analyze(v, 6) and report["betti"][0] == label(v)[1]
    for fill, dtype, shown in ((2, "u1", "2"), (float("nan"), "f4", "nan")):
        path = tmp_path / f"fill-{shown}.zarr"
        z = zarr.create_array(str(path), shape=v.shape, chunks=(5, 4, 11), dtype=dtype, fill_value=fill,
                              zarr_format=fmt)
        z[10:] = v[10:]  # the first chunks never written
        with pytest.raises(IsoflowError, match=rf"e\.g\. {shown}, the array's fill value, which zarr reads"):
            analyze_zarr(path)
        for command in (["info", str(path)], ["surface", str(path), "-o", str(tmp_path / "s.ply")]):
            assert main(command) == 2
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and f"e.g. {shown}, the array's fill value" in err[0], err


@pytest.mark.parametrize("kind", ["dask", "zarr"])
def test_thin_chunks_are_summed_a_layer_at_a_time(tmp_path, kind):
    """Chunks of (N, N, 1) are one layer of blocks along the first axis:
    summed along it, the whole volume's faces would be held at once. The
    blocks go in layers along the axis where they are the most, so no
    compute holds more than the two layers of one block each that the docs
    promise; the report is the in-memory one, whose chi and b0 are those of
    scikit-image and scipy."""
    from dask.local import get_sync
    from scipy.ndimage import label
    from skimage.measure import euler_number

    v = np.random.default_rng(4).random((9, 8, 10)) < 0.4
    if kind == "zarr":
        array = zarr.create_array(store=str(tmp_path / "thin.zarr"), shape=v.shape, chunks=(9, 8, 1), dtype=bool)
        array[...] = v
    else:
        array = da.from_array(v, chunks=(9, 8, 1))
    summed = []

    def counting(dsk, keys, **kwargs):  # the blocks summed in each compute: the tasks asked for by name
        summed.append(sum(str(k).startswith(("_dask_block", "_read_zarr_block")) for k in np.ravel(keys)))
        return get_sync(dsk, keys, **kwargs)

    got = analyze_chunked(array, 26, scheduler=counting)
    assert max(summed) <= 2 and sum(summed) == v.shape[2]
    assert got == reference(v, 26)
    assert got.euler_characteristic == euler_number(np.pad(v, 1), connectivity=3)
    assert got.betti[0] == label(v, np.ones((3, 3, 3)))[1]


@pytest.mark.parametrize("conn", [6, 26])
@pytest.mark.parametrize("chunks", [(3, 41, 29), (37, 41, 3), (5, 41, 4)])
def test_thin_chunks_hold_one_layer_of_faces(monkeypatch, conn, chunks):
    """Thin blocks have nearly all their components on their faces: kept
    for every block, their records grew with the volume's faces. After each
    layer of blocks the records settle into one that holds no more open
    keys and pieces than the voxels of one face of a layer; the report is
    the in-memory one, whose chi and b0 are those of scikit-image and
    scipy, with the same surfaces and doubled edges."""
    from scipy.ndimage import generate_binary_structure, label
    from skimage.measure import euler_number

    v = smooth(np.random.default_rng(29), (37, 41, 29), sigma=1.2)  # odd sizes: no chunking divides them
    held = []
    settle = outofcore.settle

    def settling(records, open_from, conn):
        out = settle(records, open_from, conn)
        held.append((sum(len(p["key"]) for p in out["pieces"]), sum(j.shape[1] for j in out["joins"]["fg"]) +
                     sum(j.shape[1] for j in out["joins"]["bg"])))
        return out

    monkeypatch.setattr(outofcore, "settle", settling)
    got = analyze_chunked(da.from_array(v, chunks=chunks), conn)
    assert got == reference(v, conn)
    assert got.euler_characteristic == euler_number(np.pad(v, 1), connectivity=1 if conn == 6 else 3)
    assert got.betti[0] == label(v, generate_binary_structure(3, 1 if conn == 6 else 3))[1]
    numblocks = [-(-n // c) for n, c in zip(v.shape, chunks)]
    along = int(np.argmax(numblocks))  # the layers go along the axis of the most blocks
    face = v.size // v.shape[along]
    assert len(held) == numblocks[along] - 1 >= 6  # one settled record per layer of blocks but the last
    assert max(pieces for pieces, _ in held) <= face and max(edges for _, edges in held) <= 2 * face


def test_blocks_beyond_the_memory_budget_are_refused_up_front(tmp_path, monkeypatch):
    """A store of one chunk larger than memory was read and swept on every
    thread until the system killed the process: blocks that would not fit
    the budget (the memory available) at the threads asked for are
    refused before any is read, in one line saying how many would fit, or
    that smaller chunks (a dask array: rechunked) are needed; where the
    threads fit without zarr's second task per thread, they run, and the
    report is the in-memory one (its chi that of scikit-image)."""
    from skimage.measure import euler_number

    from isoflow.scale import memory

    v = np.random.default_rng(2).random((40, 40, 40)) < 0.3
    path = str(tmp_path / "one.zarr")
    zarr.create_array(store=path, shape=v.shape, chunks=v.shape, dtype=np.uint8)[...] = v
    per_block = v.size * (2 + outofcore.CHECK_BYTES)  # the stored byte twice, the masks and the bool copy
    held = outofcore.FACE_BYTES * 6 * 40 * 40  # one block's six faces, held as its layer's summary
    want, told = reference(v, 6), []
    for budget, words in ((per_block // 2, "write the store with smaller chunks"),
                          (per_block + held + 1, "sum 1 at a time")):
        monkeypatch.setattr(memory, "default_budget", lambda budget=budget: budget)
        with pytest.raises(IsoflowError, match=f"^{path}: summing its blocks \\(2 at a time\\) .*; {words}") as exc:
            analyze_zarr(path, 6, threads=2, progress=lambda done, total: told.append(done))
        assert "\n" not in str(exc.value) and told == []
    assert analyze_zarr(path, 6, threads=2, scheduler="sync") == want  # one block at a time fits
    monkeypatch.setattr(memory, "default_budget", lambda: per_block // 2)
    with pytest.raises(IsoflowError, match="^analyze_chunked: array: summing its blocks .*; rechunk it, or pass smaller blocks"):
        analyze_chunked(da.from_array(v.astype(np.uint8), chunks=v.shape), 6, threads=2)
    monkeypatch.setattr(memory, "default_budget", lambda: 2 * per_block + held)
    got = analyze_zarr(path, 6, threads=2)
    assert got == want and got.euler_characteristic == euler_number(np.pad(v, 1), connectivity=1)


def test_a_store_that_does_not_fit_is_refused_before_its_first_chunk_is_read(tmp_path, monkeypatch):
    """A store of numbers (not bools) has its first chunk checked for 0
    and 1 before the pass; that chunk, decoded whole, may be what does not
    fit. The memory check comes first: a first chunk that cannot be read
    (here a damaged one) is not reached where the blocks are refused."""
    from isoflow.scale import memory

    v = np.zeros((40, 40, 40), np.uint8)
    v[5:30, 5:30, 5:30] = 1
    path = tmp_path / "one.zarr"
    zarr.create_array(store=str(path), shape=v.shape, chunks=v.shape, dtype=np.uint8, zarr_format=2)[...] = v
    (path / "0.0.0").write_bytes(b"not a chunk")
    monkeypatch.setattr(memory, "default_budget", lambda: v.nbytes // 2)
    with pytest.raises(IsoflowError, match=f"^{path}: summing its blocks \\(1 at a time\\) needs about") as exc:
        analyze_zarr(str(path), 6, threads=1)
    assert "\n" not in str(exc.value) and "cannot read" not in str(exc.value)


def test_a_dask_or_zarr_array_beyond_memory_is_refused_by_the_in_memory_functions(tmp_path, monkeypatch):
    """isoflow.analyze and isoflow.label_table read a dask or zarr array
    whole (NumPy's asarray); one beyond memory raised NumPy's MemoryError
    with a traceback, or made the machine swap. It is refused in one line
    naming analyze_chunked, which reads it block by block to the same
    report (chi: scikit-image's)."""
    import isoflow
    from isoflow.scale import memory

    v = (np.random.default_rng(4).random((20, 20, 20)) < 0.4).astype(np.uint8)
    z = zarr.create_array(store=str(tmp_path / "v.zarr"), shape=v.shape, chunks=(7, 7, 7), dtype=np.uint8)
    z[...] = v
    for array in (da.from_array(v, chunks=(7, 7, 7)), z):
        monkeypatch.setattr(memory, "default_budget", lambda: v.nbytes // 2)
        for call, where in ((analyze, "analyze: obj"), (isoflow.label_table, "label_table: image")):
            with pytest.raises(IsoflowError, match=f"^{where}: reading a 20x20x20 (dask|zarr) array of uint8 into "
                                                   "memory needs about .*; isoflow.analyze_chunked reads") as exc:
                call(array, 6)
            assert "\n" not in str(exc.value)
        monkeypatch.setattr(memory, "default_budget", lambda: 1 << 30)
        got = analyze_chunked(array, 6, threads=1)
        assert got.euler_characteristic == euler_number(np.pad(v, 1), connectivity=1)
        assert analyze(array, 6) == got


def test_blocks_smaller_than_the_chunks_are_not_told_to_shrink(tmp_path, monkeypatch):
    """Each block holds the chunk it reads decoded whole: below a budget
    smaller than one chunk's stored bytes (as NumPy counts them) no block
    shape fits, so a refusal of blocks already smaller than the chunks
    offers smaller chunks and more memory, not smaller blocks; blocks as
    large as the chunks are still offered smaller ones."""
    from isoflow.scale import memory

    v = np.random.default_rng(3).random((40, 40, 40)) < 0.3
    path = str(tmp_path / "one.zarr")
    zarr.create_array(store=path, shape=v.shape, chunks=v.shape, dtype=np.uint8)[...] = v
    monkeypatch.setattr(memory, "default_budget", lambda: v.astype(np.uint8).nbytes // 2)
    for block_shape in ((10, 40, 40), (1, 40, 40)):
        with pytest.raises(IsoflowError, match=f"^{path}: summing its blocks ") as exc:
            analyze_zarr(path, 6, threads=1, block_shape=block_shape)
        said = str(exc.value)
        assert "; write the store with smaller chunks" in said and "more memory" in said, said
        assert "smaller blocks" not in said and "block_shape" not in said, said
    with pytest.raises(IsoflowError, match="write the store with smaller chunks, or pass smaller blocks"):
        analyze_zarr(path, 6, threads=1)

    class Cluster:  # what a client's scheduler_info() says of a worker of one thread, as small as the budget
        def scheduler_info(self, n_workers=-1):
            return {"workers": {"tcp://w1": {"memory_limit": v.nbytes // 2, "nthreads": 1}}}

    monkeypatch.setattr(outofcore, "distributed_client", lambda scheduler: Cluster())
    with pytest.raises(IsoflowError, match="on a dask.distributed worker") as exc:
        analyze_zarr(path, 6, block_shape=(10, 40, 40))
    said = str(exc.value)
    assert "smaller chunks" in said and "give the workers more memory" in said and "smaller blocks" not in said, said


#: what a script that reads the kernel's peak runs first: ``status(key)`` of
#: /proc/self/status in bytes, ``small`` a small store to load the compiled
#: passes on, and ``reset()``, which gives back the heap and resets the peak
PEAK_PRELUDE = """
import contextlib, ctypes, io, json, re, sys, tempfile
import numpy as np, zarr

def status(key):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))

def reset():
    # the heap that numba's compile freed (a cold cache) given back, else the
    # pass reuses it unseen and the peak reads low
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/clear_refs", "w") as fh:  # the peak from here on (ru_maxrss keeps the imports' peak)
        fh.write("5")
    return status("VmRSS")

small = tempfile.mkdtemp() + "/small.zarr"  # the compiled passes loaded on it before the peak is taken
zarr.create_array(store=small, shape=(40, 40, 40), chunks=(16, 16, 16), dtype=bool)[5:30, 5:30, 5:30] = True
"""

MEASURED_PEAK = PEAK_PRELUDE + """
from isoflow import IsoflowError
from isoflow.digital.outofcore import analyze_zarr_volume
from isoflow.scale import memory

analyze_zarr_volume(small, 6, scheduler="sync")
before = reset()
analyze_zarr_volume(sys.argv[1], 6, scheduler="sync")
peak = status("VmHWM") - before
memory.default_budget = lambda: 1
try:
    analyze_zarr_volume(sys.argv[1], 6, scheduler="sync")
except IsoflowError as exc:
    need = float(re.search(r"needs about ([0-9.]+) MiB", str(exc)).group(1)) * 2**20
print(json.dumps({"peak": peak, "estimate": need}))
"""


def porous_store(tmp_path, chunk: int, size: int = 384, seed: int = 0) -> tuple[str, np.ndarray]:
    """A porous field of ``size``^3 voxels (a smoothed random field,
    upsampled 4x) stored as bools in chunks of ``chunk``^3: its path and
    volume. Skips where the kernel's peak cannot be reset, which the tests
    that take it read."""
    if not os.access("/proc/self/clear_refs", os.W_OK):
        pytest.skip("the kernel's peak cannot be reset here")
    field = gaussian_filter(np.random.default_rng(seed).standard_normal((size // 4,) * 3).astype(np.float32), 2)
    v = np.repeat(np.repeat(np.repeat(field > 0, 4, 0), 4, 1), 4, 2)
    path = str(tmp_path / "porous.zarr")
    zarr.create_array(store=path, shape=v.shape, chunks=(chunk,) * 3, dtype=bool)[...] = v
    return path, v


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the peak is read from /proc/self/status")
def test_the_estimate_of_a_store_covers_the_measured_peak(tmp_path):
    """A store's up-front estimate counted each block at work twice and
    nothing of the faces held for the next layer: a 384^3 store in chunks
    of 128^3 was estimated at 4 MiB and took 20 MiB as the kernel measures
    it, so a budget the estimate passed let the run die of memory. The
    estimate counts zarr's decoded chunk, the sweep's passes, the freed
    blocks the allocator keeps and the layers' faces: at least the peak
    the kernel measures (VmHWM over the resident memory before the run),
    and not a blanket overestimate. The kernel's peak of the same run
    reads 21 MB alone and 9 to 15 MB within the cold-cache suite (the
    memory numba's compile left in the process is reused unseen), so the
    estimate (27.1 MB) is held within 3.5 times the reading."""
    path, _ = porous_store(tmp_path, 128)
    p = subprocess.run([sys.executable, "-c", MEASURED_PEAK, path], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    got = json.loads(p.stdout)
    assert 0.95 * got["peak"] <= got["estimate"] <= 3.5 * got["peak"], got


INFO_UNDER_A_LIMIT = PEAK_PRELUDE + """
from isoflow.cli import main
from isoflow.scale import memory

with contextlib.redirect_stdout(io.StringIO()):
    main(["info", small, "--json", "--threads", "1"])
if sys.argv[2] != "none":  # the memory available as the budget sees it (90 % of MemAvailable, no option sets it)
    memory.default_budget = lambda: int(sys.argv[2])
before = reset()
out, err = io.StringIO(), io.StringIO()
with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
    code = main(["info", sys.argv[1], "--json", "--threads", "1"])
print(json.dumps({"code": code, "peak": status("VmHWM") - before, "report": out.getvalue(), "error": err.getvalue()}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the peak is read from /proc/self/status")
def test_info_of_a_store_runs_under_a_memory_limit_just_above_its_peak(tmp_path):
    """``info`` of a store counted 12 bytes a voxel of the faces of two
    layers of blocks, where the two layers' summaries and the merges take
    10 to 13 a voxel of one layer's faces: a 384^3 store in chunks of 64^3,
    whose faces outweigh its blocks at work, was refused under a budget
    of 1.5 to 1.75 times its peak (the estimate, 21.2 MiB, was up to twice
    the peak the kernel measures). It runs there now, as the command would on a machine with
    that much memory available (the budget is what the system says is
    available: a fresh process for each run, as the user's command), its
    peak within the budget and its chi that of scikit-image."""
    from skimage.measure import euler_number

    path, v = porous_store(tmp_path, 64)

    def info(budget):
        p = subprocess.run([sys.executable, "-c", INFO_UNDER_A_LIMIT, path, str(budget)], capture_output=True,
                           text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)

    free = info("none")
    assert free["code"] == 0, free["error"]
    # 1.75: the most the estimate is of a measured peak over the stores of
    # benchmarks/bench_store_estimate.py (the peak of one run reads 10-21 MiB
    # here by the state of the process; main's estimate was 21.2 MiB)
    limit = int(1.75 * free["peak"])
    got = info(limit)
    assert got["code"] == 0, got["error"]  # main: "summing its blocks (1 at a time) needs about 21.2 MiB"
    assert got["peak"] <= limit
    # scikit-image's chi of the field before it was upsampled: each of its
    # voxels became a 4^3 block, the same union of cubes scaled by 4, whose
    # chi is the same; on the 384^3 volume it takes most of the test's time
    coarse = v[::4, ::4, ::4]
    assert np.array_equal(np.repeat(np.repeat(np.repeat(coarse, 4, 0), 4, 1), 4, 2), v)
    assert json.loads(got["report"])["euler_characteristic"] == euler_number(np.pad(coarse, 1), connectivity=1)


PROCESSES_PEAK = PEAK_PRELUDE + """
import resource
from isoflow import IsoflowError
from isoflow.digital.outofcore import analyze_zarr_volume
from isoflow.scale import memory

analyze_zarr_volume(small, 6, scheduler="sync")  # the compiled passes in numba's cache, which the workers load
before = reset()
report = analyze_zarr_volume(sys.argv[1], 6, scheduler="processes", threads=1)
parent = status("VmHWM") - before
# a worker process's own peak: its resident peak less the libraries' pages it shares with this process
worker = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024 - status("RssFile")
memory.default_budget = lambda: 1
try:
    analyze_zarr_volume(sys.argv[1], 6, scheduler="processes", threads=1)
except IsoflowError as exc:
    need = float(re.search(r"needs about ([0-9.]+) MiB", str(exc)).group(1)) * 2**20
print(json.dumps({"parent": parent, "worker": worker, "estimate": need, "voxels": report.voxels}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the peak is read from /proc/self/status")
def test_the_estimate_on_worker_processes_counts_each_ones_python(tmp_path):
    """On dask's processes scheduler each worker process is a fresh Python
    that imports NumPy, zarr, dask, numba and isoflow before it sums a
    block: 80 MiB and more of its own, which the check left out (a 128^3
    store in chunks of 64^3 was estimated at 3.1 MiB), so a budget the
    estimate passed could not hold the run. What the check counts covers
    the calling process's rise (VmHWM over its resident memory before the
    run) and the worker process's own peak (its resident peak less the
    libraries' file pages, which it shares), and the report's voxels are
    NumPy's count."""
    path, v = porous_store(tmp_path, 64, size=128, seed=1)
    p = subprocess.run([sys.executable, "-c", PROCESSES_PEAK, path], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    got = json.loads(p.stdout)
    assert got["voxels"] == np.count_nonzero(v)
    assert got["estimate"] >= got["parent"] + got["worker"], got


def test_a_2d_block_is_counted_by_its_extent_sums(monkeypatch):
    """A 2D block's voxels come from the sums that give its extent, not
    from a count of every voxel of its own; the report's voxels, box and
    centroid are NumPy's."""
    v = np.random.default_rng(6).random((23, 17)) < 0.4
    counting = np.count_nonzero
    counted = []

    def recorded(a, *args, **kwargs):
        counted.append(np.shape(a))
        return counting(a, *args, **kwargs)

    monkeypatch.setattr(np, "count_nonzero", recorded)
    got = analyze_chunked(da.from_array(v, chunks=(7, 5)), 8, scheduler="sync")
    monkeypatch.undo()
    assert not [s for s in counted if len(s) == 2 and s[0] * s[1] > 1]  # no block counted apart
    at = np.argwhere(v)
    assert got.voxels == v.sum() and got.bbox == [*at.min(0).astype(float), *(at.max(0) + 1).astype(float)]
    assert got.centroid == pytest.approx(at.mean(0) + 0.5)
    assert got == reference(v, 8)


def test_a_chunk_larger_than_the_blocks_is_counted_in_the_estimate(tmp_path, monkeypatch):
    """zarr decodes a whole chunk to give any part of it: blocks of 4^3
    summed from chunks of 4 x 256 x 256 (256 KiB of bools) hold such a
    chunk each, which the estimate counted at the block's size. With a
    budget of nothing the refusal says what the work needs: it grows by
    at least a chunk against chunks of 4 x 8 x 8 (the same blocks), and
    where the blocks hold their chunks it is the same whatever the chunks
    inside them (chunks of 4^3 or 4 x 8 x 8 in blocks of 4 x 8 x 8)."""
    import re

    from isoflow.scale import memory

    monkeypatch.setattr(memory, "default_budget", lambda: 1_000)
    chunk = 4 * 256 * 256

    def needs(chunks, block_shape):
        z = zarr.create_array(store=str(tmp_path / ("x".join(map(str, chunks)) + ".zarr")), shape=(8, 256, 256),
                              chunks=chunks, dtype=bool, overwrite=True)
        z[2:6, 100:150, 100:150] = True
        with pytest.raises(IsoflowError, match="summing its blocks") as err:  # refused before any block is read
            analyze_chunked(z, 6, block_shape=block_shape, threads=1, scheduler="sync")
        number, unit = re.search(r"needs about ([0-9.]+) (bytes|KiB|MiB|GiB)", str(err.value)).groups()
        return float(number) * {"bytes": 1, "KiB": 2**10, "MiB": 2**20, "GiB": 2**30}[unit]

    assert needs((4, 256, 256), (4, 4, 4)) - needs((4, 8, 8), (4, 4, 4)) >= 0.95 * chunk
    assert needs((4, 4, 4), (4, 8, 8)) == needs((4, 8, 8), (4, 8, 8))


def test_a_scheduler_named_is_held_to_the_memory_budget_with_distributed_imported(tmp_path, monkeypatch):
    """Once dask.distributed is imported (a notebook with a cluster made
    earlier), a scheduler given by name ("sync", "threads") reached the
    memory check as a string, which it took for an unknown scheduler and
    let pass: blocks that do not fit ran. They are refused as without it."""
    pytest.importorskip("distributed")
    import distributed  # noqa: F401

    from isoflow.scale import memory

    monkeypatch.setattr(memory, "default_budget", lambda: 1_000)
    z = zarr.create_array(store=str(tmp_path / "v.zarr"), shape=(16, 16, 16), chunks=(8, 8, 8), dtype=bool)
    z[2:12, 3:9, 4:14] = True
    for name in ("sync", "threads", "THREADS"):
        with pytest.raises(IsoflowError, match="summing its blocks"):  # refused before any block is read
            analyze_chunked(z, 6, scheduler=name)


def test_a_2d_array_of_another_type_is_called_an_image(tmp_path):
    """A 2D store or dask array of strings is refused as an image, as a 2D
    array in memory is (3D: a volume)."""
    import dask.array as da

    for shape, word in (((4, 5), "image"), ((4, 5, 2), "volume")):
        with pytest.raises(IsoflowError, match=f"array of type <U1 is not a binary {word}$"):
            analyze_chunked(da.from_array(np.full(shape, "a")), 6 if len(shape) == 3 else 4)
