"""The boundary mesh written block by block (``surface STORE.zarr``) is the
in-memory mesh: the same vertices with the same attributes and the same
faces, up to order, on odd chunkings with objects, tunnels, cavities, edge
and vertex contacts across block faces, edges and corners, at 6 and 26;
the files read back by trimesh and pymeshlab as the in-memory files do."""

import os
import sys
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import ball, torus

from isoflow import DigitalObject, boundary_mesh
from isoflow.cli import main
from isoflow.digital.surface import QuadMesh, triangle_rows
from isoflow.errors import IsoflowError
from isoflow.mesh import export, surface_blocks
from isoflow.mesh.streamed_readback import check_streamed, read_ply_header
from isoflow.mesh.surface_blocks import BlockGrid, block_plan, count_block, mesh_block, plan, write_surface_blocks
from isoflow.scale.chunks import block_bounds

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "digital"))
from test_surface_rows import canonical, contact_volume  # noqa: E402

zarr = pytest.importorskip("zarr")

CHUNKS = (5, 7, 6)


def seam_volume(rng) -> np.ndarray:
    """Random voxels and shapes cut by the blocks of CHUNKS, with vertex
    and edge contacts (of the object and of the background) planted on
    block corners, edges and faces."""
    v = rng.random((17, 20, 19)) < 0.15
    v[:, 2:19, 1:18] |= torus(6, 2, size=17, axis=1)  # a tunnel across blocks
    hollow = ball(6, 17) & ~ball(3, 17)  # a cavity spanning blocks
    v[:, 3:20, 2:19] |= hollow
    corners = [(5, 7, 6), (10, 14, 12), (5, 14, 6)]
    for x, y, z in corners:
        v[x - 1:x + 1, y - 1:y + 1, z - 1:z + 1] = False
        v[x - 1, y - 1, z - 1] = v[x, y, z] = True  # vertex contact on a block corner
    for x, y in ((5, 7), (10, 14)):
        v[x - 1:x + 1, y - 1:y + 1, 2:4] = False
        v[x - 1, y - 1, 2:4] = v[x, y, 2:4] = True  # edge contact along a block edge
    cube = np.ones((2, 2, 2), bool)
    cube[0, 1, 0] = cube[1, 0, 1] = False  # a background vertex contact on a block face
    v[4:6, 9:11, 11:13] = cube
    return v


def grid_of(shape, chunks) -> BlockGrid:
    sizes = tuple(tuple([c] * (s // c) + ([s % c] if s % c else [])) for c, s in zip(chunks, shape))
    return BlockGrid(tuple(shape), tuple(tuple(b) for b in block_bounds(sizes)))


def blocks_mesh(v, conn, chunks) -> QuadMesh:
    """The blocks' meshes side by side: vertex rows are the file's numbers."""
    grid = grid_of(v.shape, chunks)
    counts = {i: count_block(v, grid, i, conn, "v") for i in grid.indices()}
    layout = plan(grid, counts, False)
    meshes = [mesh_block(v, grid, block_plan(layout, i), conn, "v") for i in grid.indices()]
    cat = lambda name: np.concatenate([getattr(m, name) for m in meshes])  # noqa: E731
    return QuadMesh(cat("vertices"), cat("faces"), cat("edge_midpoint"), cat("face_normals"), cat("config"),
                    cat("sheet"), conn, sum(m.pinched for m in meshes))


@pytest.mark.parametrize("conn", [6, 26])
def test_blocks_number_their_seams_alike(rng, conn):
    # every block's vertices and faces together are the in-memory mesh,
    # numbered without gaps: the seams' vertices are the same numbers
    cases = [(seam_volume(rng), CHUNKS)]
    cases += [(contact_volume(rng, int(rng.integers(3, 12))), tuple(rng.integers(1, 7, 3))) for _ in range(8)]
    seen_pinch = seen_midpoint = 0
    for v, chunks in cases:
        got, want = blocks_mesh(v, conn, chunks), boundary_mesh(v, conn, method="numpy")
        assert got.pinched == want.pinched
        assert canonical(got) == canonical(want)
        seen_pinch += got.pinched > 0
        seen_midpoint += got.midpoints > 0
    assert seen_pinch and seen_midpoint


def store(tmp_path, v, chunks=CHUNKS) -> Path:
    path = tmp_path / "v.zarr"
    z = zarr.open_array(str(path), mode="w", shape=v.shape, chunks=chunks, dtype=bool)
    z[:] = v
    return path


def faces_as_records(path) -> tuple[list, list]:
    """A PLY's vertex records (every column) and its faces as the tuples of
    their corners' records, starting at the least, as multisets."""
    tm = trimesh.load(path, process=False)
    data = tm.metadata["_ply_raw"]["vertex"]["data"]
    rec = [tuple(float(data[name][i].item()) for name in data.dtype.names) for i in range(len(data))]
    faces = []
    for f in tm.faces.tolist():
        seq = [rec[i] for i in f]
        start = min(range(len(seq)), key=lambda t: seq[t])
        faces.append(tuple(seq[start:] + seq[:start]))
    return sorted(rec), sorted(faces)


@pytest.mark.parametrize("conn", [6, 26])
def test_written_files_equal_the_in_memory_files(tmp_path, rng, conn):
    import pymeshlab

    v = seam_volume(rng)
    obj = DigitalObject(v, pitch=0.5, origin=(10.0, 0.0, -1.0))
    frame = DigitalObject(np.zeros((1, 1, 1), bool), pitch=0.5, origin=(10.0, 0.0, -1.0))
    array = zarr.open_array(str(store(tmp_path, v)), mode="r")
    mesh = boundary_mesh(v, conn)
    assert mesh.pinched and (conn == 6 or mesh.midpoints)
    for suffix in (".ply", ".stl"):
        got = write_surface_blocks(array, tmp_path / f"blocks{suffix}", conn, frame=frame)
        want = export.write_mesh_file(tmp_path / f"memory{suffix}", mesh, obj)
        assert got["faces"] == want["face_count"] and got["kind"] == want["faces"].replace("polygons", "quads")
        assert got["vertices"] == len(mesh.vertices) and got["pinched"] == mesh.pinched
        assert got["euler_characteristic"] == mesh.euler_characteristic
        check = check_streamed(got["path"], dict(got, centre=np.array(v.shape) / 2), frame)
        assert check["agree"], check["problem"]
        if suffix == ".ply":
            assert faces_as_records(got["path"]) == faces_as_records(want["path"])
            ms = pymeshlab.MeshSet()
            ms.load_new_mesh(str(got["path"]))
            topo = ms.get_topological_measures()
            assert topo["is_mesh_two_manifold"] and topo["boundary_edges"] == 0
            assert topo["genus"] == sum(c["genus"] for c in mesh.components())
        else:
            a, b = (trimesh.load(p, process=False) for p in (got["path"], want["path"]))
            key = lambda m: sorted(map(tuple, np.round(m.vertices[m.faces], 6).reshape(len(m.faces), -1).tolist()))  # noqa: E731
            assert key(a) == key(b)


@pytest.mark.parametrize("conn", [6, 26])
def test_the_files_record_their_connectivity_for_genus(tmp_path, conn):
    """surface.md gives write_surface_blocks(...) from Python; its PLY had
    no record of who wrote it at which connectivity (the STL's header had
    one, and the command passes its own comments), so ``isoflow genus`` read
    a 26-connected PLY at 6, as another program's file. Both files now
    record it, and genus, run as a user runs it, reads each at it."""
    import json
    import subprocess

    v = torus(6, 2, size=17, axis=1)
    array = zarr.open_array(str(store(tmp_path, v)), mode="r")
    for suffix in (".ply", ".stl"):
        path = write_surface_blocks(array, tmp_path / f"s{suffix}", conn)["path"]
        run = subprocess.run([sys.executable, "-m", "isoflow", "genus", str(path), "--resolution", "16", "32",
                              "--no-step", "--json", "-q"], capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        assert {row["connectivity"] for row in json.loads(run.stdout)["digital"]} == {conn}, suffix
    header = (tmp_path / "s.ply").read_bytes().split(b"end_header")[0].decode()
    assert f"comment isoflow write_surface_blocks, {conn}-connectivity" in header.splitlines()
    assert f"comment {export.VERTEX_COMMENT}" in header.splitlines()


def test_dask_array_and_block_shapes(tmp_path, rng):
    da = pytest.importorskip("dask.array")
    v = seam_volume(rng)
    want = boundary_mesh(v, 26)
    for array, shape in ((da.from_array(v, chunks=(4, 9, 5)), None), (v, (3, 20, 7)), (v, None)):
        got = write_surface_blocks(array, tmp_path / "d.ply", 26, block_shape=shape, force=True,
                                   scheduler="threads", threads=2)
        assert (got["vertices"], got["euler_characteristic"], got["pinched"]) == (
            len(want.vertices), want.euler_characteristic, want.pinched)
        check = check_streamed(got["path"], dict(got, centre=np.array(v.shape) / 2), DigitalObject(v))
        assert check["agree"], check["problem"]


@pytest.mark.parametrize("chunks", [(5, 7, 6), (17, 7, 6)])
def test_progress_is_reported_per_block_of_both_passes(tmp_path, rng, chunks):
    """``surface STORE.zarr`` of one layer of blocks along the first axis
    (or of a layer of hundreds) showed no progress until a layer was done.
    Each block of the counting and the writing pass is reported now: twice
    zarr's count of the store's chunks in all, one at a time; the file is
    trimesh's closed mesh of the voxels' volume."""
    v = seam_volume(rng)
    z = zarr.create_array(store=str(tmp_path / "p.zarr"), shape=v.shape, chunks=chunks, dtype=bool)
    z[...] = v
    calls = []
    write_surface_blocks(z, tmp_path / "p.ply", 6, scheduler="threads", threads=2,
                         progress=lambda done, total: calls.append((done, total)))
    total = 2 * z.nchunks
    assert calls == [(k, total) for k in range(1, total + 1)]
    mesh = trimesh.load(tmp_path / "p.ply", process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(v.sum())


def test_the_check_sees_a_broken_file(tmp_path, rng):
    v = seam_volume(rng)
    got = write_surface_blocks(v, tmp_path / "b.ply", 6, block_shape=CHUNKS)
    expected = dict(got, centre=np.array(v.shape) / 2)
    head, vdt, nv, nf = read_ply_header(got["path"])
    data = bytearray(got["path"].read_bytes())
    k = 4 if got["kind"] == "quads" else 3
    at = head + nv * vdt.itemsize + 1  # the first face's indices, reversed
    data[at:at + 4 * k] = np.frombuffer(bytes(data[at:at + 4 * k]), "<i4")[::-1].tobytes()
    flipped = tmp_path / "flipped.ply"
    flipped.write_bytes(bytes(data))
    assert "not consistently wound" in check_streamed(flipped, expected, DigitalObject(v))["problem"]
    cut = tmp_path / "cut.ply"
    cut.write_bytes(bytes(data[:-(1 + 4 * k)]))
    assert not check_streamed(cut, expected, DigitalObject(v))["agree"]
    data[at:at + 4] = np.int32(nv).tobytes()  # an index past the last vertex
    flipped.write_bytes(bytes(data))
    assert "index out of range" in check_streamed(flipped, expected, DigitalObject(v))["problem"]


def test_command_writes_and_checks(tmp_path, rng, capsys):
    v = seam_volume(rng)
    path = store(tmp_path, v)
    out = tmp_path / "s.ply"
    assert main(["surface", str(path), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    mesh = boundary_mesh(v, 6)
    assert f"{len(mesh.vertices)} vertices" in printed and f"V-E+F = {mesh.euler_characteristic}" in printed
    assert "read back in chunks" in printed and "as isoflow counts" in printed
    tm = trimesh.load(out, process=False)
    assert tm.is_watertight and tm.volume == pytest.approx(v.sum())
    np.save(tmp_path / "v.npy", v)  # the in-memory command's file holds the same records
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "m.ply")]) == 0
    assert faces_as_records(out) == faces_as_records(tmp_path / "m.ply")


@pytest.mark.parametrize("argv, asked", [
    (["-o", "{tmp}/s.obj"], ".obj"),
    (["-o", "{tmp}/s.ply", "--png", "{tmp}/s.png"], "--png"),
    (["-o", "{tmp}/s.ply", "--ascii"], "--ascii"),
])
def test_what_does_not_stream_is_meshed_in_memory_or_refused(tmp_path, capsys, monkeypatch, argv, asked):
    from isoflow.scale import memory

    path = store(tmp_path, np.ones((3, 3, 3), bool))
    argv = ["surface", str(path), *[a.format(tmp=tmp_path) for a in argv]]
    assert main(argv) == 0  # a store that fits: read whole, as any volume
    assert "written block by block" not in capsys.readouterr().out
    for p in tmp_path.glob("s.*"):
        p.unlink()
    monkeypatch.setattr(memory, "default_budget", lambda: 50)  # a store larger than memory
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{asked} needs the whole surface in memory" in err[0] and "(.ply, .stl)" in err[0]
    assert not list(tmp_path.glob("s.*"))


def test_empty_store_and_existing_output(tmp_path, capsys):
    path = store(tmp_path, np.zeros((4, 5, 6), bool))
    assert main(["surface", str(path), "-o", str(tmp_path / "e.ply")]) == 2
    assert "the object is empty" in capsys.readouterr().err
    full = store(tmp_path, np.ones((4, 5, 6), bool))
    (tmp_path / "x.ply").write_text("old")
    assert main(["surface", str(full), "-o", str(tmp_path / "x.ply")]) == 2
    assert "exists" in capsys.readouterr().err and (tmp_path / "x.ply").read_text() == "old"


def test_store_without_voxels_is_refused_in_one_line(tmp_path, capsys):
    # a zero-length axis: no blocks at all (was a ValueError from sizing the chunk cache)
    path = store(tmp_path, np.zeros((0, 5, 6), bool))
    assert main(["surface", str(path), "-o", str(tmp_path / "e.ply")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the object is empty (shape (0, 5, 6))" in err[0]
    assert not list(tmp_path.glob("e.*"))


def test_interrupted_run_leaves_the_previous_output(tmp_path, rng, monkeypatch):
    v = seam_volume(rng)
    out = tmp_path / "s.ply"
    out.write_text("previous")
    real, calls = surface_blocks.write_block, []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 5:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(surface_blocks, "write_block", interrupted)
    with pytest.raises(KeyboardInterrupt, match="unchanged"):
        write_surface_blocks(v, out, 6, block_shape=CHUNKS, force=True, scheduler="sync")
    assert out.read_text() == "previous" and sorted(p.name for p in tmp_path.iterdir()) == ["s.ply"]


def test_work_that_does_not_fit_is_refused_up_front(tmp_path, rng, monkeypatch):
    from isoflow.scale import memory

    v = seam_volume(rng)
    # beside the run's own records (a fixed amount), room for a few blocks but not 4
    monkeypatch.setattr(memory, "default_budget", lambda: surface_blocks.RUN_BYTES + 150_000)
    with pytest.raises(IsoflowError, match=r"\(4 at a time\).*; run [123] at a time \(--threads [123]\)"):
        write_surface_blocks(v, tmp_path / "s.ply", 6, block_shape=CHUNKS, threads=4)
    monkeypatch.setattr(memory, "default_budget", lambda: 1_000)
    with pytest.raises(IsoflowError, match="smaller chunks"):
        write_surface_blocks(v, tmp_path / "s.ply", 6, block_shape=CHUNKS, threads=1)
    assert not list(tmp_path.iterdir())


def test_blocks_smaller_than_the_chunks_are_not_told_to_shrink(tmp_path, rng, monkeypatch):
    """A task holds the chunk its block reads decoded whole: below a budget
    smaller than one chunk's stored bytes (as NumPy counts them) no block
    shape fits, so the refusal of blocks already smaller than the chunks
    offers smaller chunks and more memory, not smaller blocks; blocks as
    large as the chunks are still offered smaller ones."""
    from isoflow.scale import chunks, memory

    v = seam_volume(rng).astype(np.uint8)
    store = zarr.create_array(str(tmp_path / "one.zarr"), shape=v.shape, chunks=v.shape, dtype=np.uint8)
    store[...] = v
    monkeypatch.setattr(memory, "default_budget", lambda: v.nbytes // 2)
    for block_shape in (CHUNKS, (1, 1, 1)):
        with pytest.raises(IsoflowError, match="surface's blocks") as exc:
            write_surface_blocks(store, tmp_path / "s.ply", 6, block_shape=block_shape, threads=1)
        said = str(exc.value)
        assert "; write the store with smaller chunks" in said and "more memory" in said, said
        assert "smaller blocks" not in said, said
    with pytest.raises(IsoflowError, match=r"write the store with smaller chunks \(or pass smaller blocks\)"):
        write_surface_blocks(store, tmp_path / "s.ply", 6, threads=1)

    class Cluster:  # what a client's scheduler_info() says of a worker of one thread, as small as the budget
        def scheduler_info(self, n_workers=-1):
            return {"workers": {"tcp://w1": {"memory_limit": v.nbytes // 2, "nthreads": 1}}}

    monkeypatch.setattr(chunks, "distributed_client", lambda scheduler: Cluster())
    with pytest.raises(IsoflowError, match="on a dask.distributed worker") as exc:
        write_surface_blocks(store, tmp_path / "s.ply", 6, block_shape=CHUNKS)
    said = str(exc.value)
    assert "smaller chunks" in said and "give the workers more memory" in said and "smaller blocks" not in said, said
    assert not (tmp_path / "s.ply").exists()


def test_ome_zarr_in_zyx_order_with_its_placement(tmp_path, rng, capsys):
    # isoflow's OME-Zarr stores (z, y, x) with a scale and a translation:
    # the streamed file's records (world positions) equal those of the
    # in-memory file of the same object
    from isoflow.mesh.volumes import write_volume

    v = seam_volume(rng)
    obj = DigitalObject(v, pitch=(0.5, 0.25, 2.0), origin=(10.0, 0.0, -1.0))
    path = write_volume(obj, tmp_path / "img.zarr")
    assert main(["surface", str(path), "-o", str(tmp_path / "s.ply")]) == 0
    assert "written block by block" in capsys.readouterr().out
    want = export.write_mesh_file(tmp_path / "m.ply", boundary_mesh(v, 6), obj)
    assert faces_as_records(tmp_path / "s.ply") == faces_as_records(want["path"])


def test_label_image_store(tmp_path, rng):
    labels = rng.integers(0, 3, (9, 11, 10)).astype(np.uint8) * 3  # 0, 3, 6
    path = tmp_path / "labels.zarr"
    z = zarr.open_array(str(path), mode="w", shape=labels.shape, chunks=(4, 5, 3), dtype=np.uint8)
    z[:] = labels
    assert main(["surface", str(path), "-o", str(tmp_path / "s.ply"), "--label", "3", "--connectivity", "26"]) == 0
    want = export.write_mesh_file(tmp_path / "m.ply", boundary_mesh(labels == 3, 26), DigitalObject(labels == 3))
    assert faces_as_records(tmp_path / "s.ply") == faces_as_records(want["path"])


def test_a_label_no_voxel_has_is_named_with_the_values_present(tmp_path, capsys):
    # as in memory and as `info STORE.zarr --label N`; it said "the object
    # is empty, there is no surface to write"
    labels = np.zeros((6, 7, 8), np.uint16)
    labels[1:3, 1:4, 2:5], labels[4, 5, 6] = 2, 7
    path = tmp_path / "labels.zarr"
    z = zarr.open_array(str(path), mode="w", shape=labels.shape, chunks=(4, 5, 3), dtype=np.uint16)
    z[:] = labels
    assert main(["surface", str(path), "-o", str(tmp_path / "s.ply"), "--label", "3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"isoflow surface: error: {path}: no voxel has label 3 (values present: 0, 2, 7)"]
    assert not list(tmp_path.glob("s.*"))


def test_other_suffixes_are_refused_naming_those_that_stream(tmp_path):
    for name in ("s.obj", "s.glb", "s"):
        with pytest.raises(IsoflowError, match=r"binary PLY or STL only \(\.ply, \.stl\)"):
            write_surface_blocks(np.ones((2, 2, 2), bool), tmp_path / name)
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("conn", [6, 26])
def test_an_stl_written_block_by_block_warns_of_the_weld(tmp_path, rng, capsys, conn):
    """A store's STL holds the split copies at edge and vertex contacts as
    the in-memory STL does, and readers weld them alike, but only the
    in-memory command said so: both now warn, counting the positions that
    trimesh reads more than one vertex at in the PLY of the same store."""
    v = seam_volume(rng)
    path = store(tmp_path, v)
    assert main(["surface", str(path), "-o", str(tmp_path / "s.ply"), "--connectivity", str(conn), "-q"]) == 0
    _, copies = np.unique(trimesh.load(tmp_path / "s.ply", process=False).vertices, axis=0, return_counts=True)
    welded = int(np.count_nonzero(copies > 1))
    capsys.readouterr()
    assert main(["surface", str(path), "-o", str(tmp_path / "s.stl"), "--connectivity", str(conn), "-q"]) == 0
    assert welded > 0 and capsys.readouterr().err.splitlines() == [
        f"isoflow surface: warning: {tmp_path / 's.stl'}: STL keeps no shared vertices, so readers weld the split "
        f"copies at {welded} edge/vertex contacts into non-manifold points; PLY, OBJ or GLB keep them apart"]


def test_a_label_store_beyond_memory_is_told_what_reads_it_block_by_block(tmp_path, capsys, monkeypatch):
    """`surface STORE.zarr --labels` reads the store whole; where it did
    not fit, the line said "use a .zarr store with 'isoflow info'" of a
    .zarr store. It now names the commands that read a store block by
    block, and the one it names for a surface, `--label N -o OUT.ply`,
    writes that label's surface within the same budget, a block at a time
    (its volume as trimesh reads it, NumPy's count of the label's voxels)."""
    from isoflow.scale import memory

    x = np.indices((60, 60, 60)) - 30
    lab = np.where((x ** 2).sum(0) <= 12 ** 2, 2, 1).astype(np.uint8)
    lab[:6] = 0
    path = tmp_path / "labels.zarr"
    zarr.open_array(str(path), mode="w", shape=lab.shape, chunks=(15, 15, 15), dtype=np.uint8)[:] = lab
    monkeypatch.setattr(memory, "default_budget", lambda: lab.size * 2)  # less than the volume and its copies
    # the run's own records (a fixed few MiB) outweigh a volume this small: left out, so that the budget
    # weighs the volume's copies in memory against its blocks
    monkeypatch.setattr(surface_blocks, "RUN_BYTES", 0)
    assert main(["surface", str(path), "--labels", "-o", str(tmp_path / "all.glb"), "-q"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and "use a .zarr store" not in err[0]
    assert "is read block by block by 'isoflow info' (--labels too), 'isoflow surface --label N -o OUT.ply'" in err[0]
    assert main(["surface", str(path), "--label", "2", "-o", str(tmp_path / "two.ply"), "-q", "--threads", "1"]) == 0
    assert trimesh.load(tmp_path / "two.ply", process=False).volume == pytest.approx(np.count_nonzero(lab == 2))


def _estimate(message: str) -> float:
    """The bytes a refusal says the work needs (as ``sized`` writes them)."""
    import re

    number, unit = re.search(r"needs about ([0-9.]+) (bytes|KiB|MiB|GiB)", message).groups()
    return float(number) * {"bytes": 1, "KiB": 2**10, "MiB": 2**20, "GiB": 2**30}[unit]


def test_a_chunk_larger_than_the_blocks_is_counted_whole(tmp_path, monkeypatch):
    """zarr decodes a whole chunk to give any part of it: blocks of 4^3 read
    from chunks of 4 x 256 x 256 (256 KiB) have each of the tasks at a time
    hold one such chunk, here and on a dask.distributed worker alike. The
    estimate grows by those chunks against chunks of 4 x 8 x 8 (which the
    blocks with their halo hold whole anyway), and where the blocks are the
    chunks it is the same whatever the chunks inside the blocks."""
    from isoflow.scale import memory

    monkeypatch.setattr(memory, "default_budget", lambda: 1_000)
    # the run's own records (a fixed few MiB, whatever the chunks) left out: the refusals compare the chunks
    monkeypatch.setattr(surface_blocks, "RUN_BYTES", 0)
    chunk = 4 * 256 * 256  # bytes of a bool chunk

    def refusal(chunks, block_shape, scheduler=None):
        name = "x".join(map(str, chunks))
        z = zarr.create_array(store=str(tmp_path / f"{name}.zarr"), shape=(8, 256, 256), chunks=chunks, dtype=bool,
                              overwrite=True)
        z[2:6, 100:150, 100:150] = True
        with pytest.raises(IsoflowError) as err:
            write_surface_blocks(z, tmp_path / "s.ply", 6, block_shape=block_shape, threads=2, scheduler=scheduler)
        return _estimate(str(err.value))

    small, large = refusal((4, 8, 8), (4, 4, 4)), refusal((4, 256, 256), (4, 4, 4))
    # the chunk cache is the same (it follows the chunks along the first axis only)
    assert large - small >= 0.95 * 2 * chunk

    class Cluster:  # a cluster's client as write_surface_blocks sees it: its workers' limits and threads
        def scheduler_info(self, n_workers=-1):
            return {"workers": {"tcp://w1": {"memory_limit": 1_000, "nthreads": 2}}}

    assert refusal((4, 256, 256), (4, 4, 4), Cluster()) >= 2 * chunk > 100 * refusal((4, 8, 8), (4, 4, 4), Cluster())
    # blocks that hold their chunks: nothing decoded beyond what the blocks read
    assert refusal((4, 8, 8), (4, 8, 8)) == refusal((4, 4, 4), (4, 8, 8))
    assert not (tmp_path / "s.ply").exists()


def _whole_block_stl(fd, mesh, first, frame, offset):
    """The STL records of a block made all at once (the writer before its
    batches): the bytes the batched writer must give back."""
    corner_offsets = np.zeros((3, 4, 3))
    for a in range(3):
        j, k = (a + 1) % 3, (a + 2) % 3
        for t, (dj, dk) in enumerate(((1, 1), (0, 1), (0, 0), (1, 0))):
            corner_offsets[a, t, j], corner_offsets[a, t, k] = 1 - dj, 1 - dk
    faces, normals = mesh.faces, mesh.face_normals
    plus = normals.sum(axis=1) > 0
    low = mesh.vertices[np.where(plus, faces[:, 0], faces[:, 3]) - first]
    axis = np.abs(normals).argmax(axis=1)
    order = np.where(plus[:, None], np.arange(4), np.arange(3, -1, -1))
    corners = low[:, None, :] + corner_offsets[axis[:, None], order]
    mids = (corners + np.roll(corners, -1, axis=1)) / 2
    n = len(faces)
    codes = np.arange(4 * n).reshape(n, 4)
    tris, face = triangle_rows(codes, np.where(mesh.edge_midpoint >= 0, 4 * n + codes, -1))
    xyz = frame.world(np.concatenate([corners.reshape(-1, 3), mids.reshape(-1, 3)]))
    rec = np.zeros(len(tris), surface_blocks.STL_DTYPE)
    rec["normal"] = normals[face]
    rec["v"] = xyz[tris]
    assert os.pwrite(fd, rec.tobytes(), offset) == rec.nbytes


@pytest.mark.parametrize("conn", [6, 26])
@pytest.mark.parametrize("chunks", [CHUNKS, (17, 3, 19), (4, 20, 5)])
def test_an_stl_written_in_batches_of_faces_is_the_whole_blocks_file(tmp_path, rng, monkeypatch, conn, chunks):
    """A block's STL records are made a batch of faces at a time, byte for
    byte those made of the whole block at once, on random voxels with
    edge and vertex contacts across odd chunkings, in batches of a few
    faces and of the default size; trimesh reads every triangle, and they
    enclose the volume of the voxels (their signed volume)."""
    v = seam_volume(rng)
    frame = DigitalObject(np.zeros((1, 1, 1), bool), pitch=(0.5, 0.25, 0.75), origin=(10.0, 0.5, -1.0))
    array = zarr.open_array(str(store(tmp_path, v, chunks)), mode="r")
    written = {}
    for batch in (5, surface_blocks.STL_BATCH_FACES, None):
        with monkeypatch.context() as m:
            if batch is None:
                m.setattr(surface_blocks, "_write_stl_records", _whole_block_stl)
            else:
                m.setattr(surface_blocks, "STL_BATCH_FACES", batch)
            got = write_surface_blocks(array, tmp_path / f"{batch}.stl", conn, frame=frame)
        written[batch] = Path(got["path"]).read_bytes()
    assert written[5] == written[None] and written[surface_blocks.STL_BATCH_FACES] == written[None]
    tm = trimesh.load(tmp_path / "5.stl", process=False)
    assert len(tm.faces) == got["faces"] == len(boundary_mesh(v, conn).triangles())
    assert tm.volume == pytest.approx(v.sum() * 0.5 * 0.25 * 0.75, rel=1e-9)


def test_an_stl_block_holds_little_beside_its_mesh(tmp_path, monkeypatch):
    """Writing a block's STL made the float64 corners, midpoints and world
    positions of every face of the block at once: 481 bytes per triangle
    beside the block's mesh (tracemalloc, which numpy reports its buffers
    to), where a PLY holds about 56. A batch of faces at a time holds a
    small part of that on a porous field's largest 64^3 block."""
    import tracemalloc

    from scipy.ndimage import gaussian_filter

    field = gaussian_filter(np.random.default_rng(0).standard_normal((32, 32, 32)), 2) > 0
    v = np.repeat(np.repeat(np.repeat(field, 4, 0), 4, 1), 4, 2)
    array = zarr.open_array(str(store(tmp_path, v, (64, 64, 64))), mode="r")
    got = []
    mesh_of, write = surface_blocks.mesh_block, surface_blocks.write_block

    def meshed(*args):
        mesh = mesh_of(*args)
        got.append([mesh, tracemalloc.get_traced_memory()[0]])
        tracemalloc.reset_peak()
        return mesh

    def measured(*args):
        tracemalloc.start()
        try:
            out = write(*args)
            got[-1].append(tracemalloc.get_traced_memory()[1])
        finally:
            tracemalloc.stop()
        return out

    monkeypatch.setattr(surface_blocks, "mesh_block", meshed)
    monkeypatch.setattr(surface_blocks, "write_block", measured)
    write_surface_blocks(array, tmp_path / "p.stl", 6, scheduler="synchronous")
    mesh, held, peak = max(got, key=lambda g: len(g[0].faces))
    triangles = len(triangle_rows(mesh.faces, mesh.edge_midpoint)[0])
    assert triangles > 50_000 and (peak - held) / triangles < 481 / 4


def test_a_path_or_an_object_given_for_the_array_says_what_to_pass(tmp_path):
    # a store's path (as the command takes it) ended in AttributeError: 'str' object has no attribute 'shape'
    vol = np.zeros((4, 4, 4), bool)
    vol[1:3, 1:3, 1:3] = True
    zarr.open_array(tmp_path / "v.zarr", mode="w", shape=vol.shape, dtype=bool)[:] = vol
    with pytest.raises(IsoflowError, match=r"v\.zarr is a path, not an array; read it with zarr\.open_array"):
        write_surface_blocks(str(tmp_path / "v.zarr"), tmp_path / "a.ply", scheduler="sync")
    with pytest.raises(IsoflowError, match=r"a DigitalObject, not an array; pass its \.volume \(and frame=obj"):
        write_surface_blocks(DigitalObject(vol), tmp_path / "b.ply", scheduler="sync")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["v.zarr"]
    # nested lists are array-like: the 2x2x2 cube, 26 corners and 24 quads, as trimesh reads them
    write_surface_blocks(vol.tolist(), tmp_path / "c.ply", scheduler="sync")
    m = trimesh.load(tmp_path / "c.ply", process=False)
    assert (len(m.vertices), len(m.faces), bool(m.is_watertight), float(m.volume)) == (26, 48, True, 8.0)


def test_a_zarr_array_given_in_python_is_named_by_its_path_not_zarr_s_url(tmp_path, monkeypatch):
    """write_surface_blocks and analyze_chunked of a zarr array opened from
    a path (no ``where``) named it ``file://z2.zarr``, zarr 3's URL of the
    store, which no shell takes: the path, as zarr was given it (a level
    of an OME-Zarr image: IMAGE.zarr/0)."""
    from isoflow.digital.outofcore import analyze_chunked

    monkeypatch.chdir(tmp_path)
    volume = np.zeros((8, 8, 8), np.uint8)
    volume[2:6, 2:6, 2:6] = 1
    volume[3, 3, 3] = 7  # not binary: the refusal names the input
    zarr.open_array("z2.zarr", mode="w", shape=volume.shape, chunks=(4, 4, 4), dtype="u1")[...] = volume
    zarr.open_group("img.zarr", mode="w").create_array("0", shape=volume.shape, chunks=(4, 4, 4), dtype="u1")[...] = volume
    for opened, name in ((zarr.open_array("z2.zarr", mode="r"), "z2.zarr"),
                         (zarr.open_group("img.zarr", mode="r")["0"], os.path.join("img.zarr", "0"))):
        for run, given in ((write_surface_blocks, ("s.ply",)), (analyze_chunked, ())):
            with pytest.raises(IsoflowError) as info:
                run(opened, *given)
            # the function called and its argument first, as every refusal of the Python API
            assert str(info.value).startswith(f"{run.__name__}: array ({name}): not a binary volume"), str(info.value)
    assert not Path("s.ply").exists()
