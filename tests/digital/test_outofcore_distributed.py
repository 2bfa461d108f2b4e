"""analyze_chunked on a real cluster engine: a dask.distributed LocalCluster
of two worker processes, one thread each, with the client's scheduler. Every
block task and merge is pickled to another process and its result pickled
back; the report must equal the in-memory one key for key.

One cluster for the module (starting one costs a few seconds); volumes
small, chunkings odd, so that objects, tunnels, cavities and edge/vertex
contacts cross block faces, edges and corners."""

import numpy as np
import pytest
from conftest import ball, torus

from isoflow import DigitalObject, IsoflowError, analyze, analyze_chunked

distributed = pytest.importorskip("distributed")
da = pytest.importorskip("dask.array")
zarr = pytest.importorskip("zarr")


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as c:
        yield c


def test_workers_are_two_processes(client):
    pids = client.run(lambda: __import__("os").getpid())
    assert len(pids) == 2 and len(set(pids.values())) == 2
    assert __import__("os").getpid() not in pids.values()


@pytest.mark.parametrize("conn", [6, 26])
def test_dask_array_on_process_workers(client, conn):
    rng = np.random.default_rng(20131122)
    v = rng.random((23, 19, 26)) < 0.45  # many edge and vertex contacts
    v[:12] |= torus(8, 3, size=26, axis=0)[:12, 3:22, :]  # a tunnel across blocks
    layers = []
    got = analyze_chunked(da.from_array(v, chunks=(7, 5, 9)), conn, scheduler=client.get,
                          progress=lambda done, total: layers.append((done, total)))
    want = analyze(DigitalObject(v), conn)
    assert got == want  # the closed surfaces, their genus, the doubled edges included
    assert want["doubled_edges"] > 0 and want["pinched_vertices"] > 0
    # a cluster runs no dask callback: one report per layer of blocks along axis 0 (4 layers of 4 x 3
    # blocks), each counting the blocks summed (a layer ahead) and merged, of twice the blocks in all
    assert layers == [(12 * (i + 1 + min(i + 2, 4)), 96) for i in range(4)]


@pytest.mark.parametrize("conn", [6, 26])
def test_zarr_store_on_process_workers(client, tmp_path, conn):
    v = ball(12, 30) & ~ball(7, 30)  # a cavity spanning blocks
    v |= torus(4, 1.5, size=30, centre=(14.5, 14.5, 14.5))  # a torus floating in the cavity
    z = zarr.open_array(str(tmp_path / "v.zarr"), mode="w", shape=v.shape, chunks=(11, 7, 13), dtype=bool)
    z[:] = v
    got = analyze_chunked(zarr.open_array(str(tmp_path / "v.zarr"), mode="r"), conn, scheduler=client.get)
    want = analyze(DigitalObject(v), conn)
    assert got == want
    assert got["betti"] == [2, 1, 1]


def test_a_bad_block_is_one_line_from_a_worker(client):
    v = np.zeros((20, 20, 20), np.uint8)
    v[15, 3, 3] = 2  # in a block that only a worker reads
    with pytest.raises(IsoflowError) as err:
        analyze_chunked(da.from_array(v, chunks=(7, 5, 9)), 6, scheduler=client.get)
    message = str(err.value)
    assert "\n" not in message and "not a binary volume" in message and "(14, 0, 0)" in message


@pytest.mark.parametrize("conn", [6, 26])
def test_surface_blocks_on_process_workers(client, tmp_path, conn):
    # the surface of a zarr store written block by block on two worker
    # processes into one file: the in-memory mesh's records and faces
    import trimesh

    from isoflow import boundary_mesh
    from isoflow.mesh.export import write_mesh_file
    from isoflow.mesh.streamed_readback import check_streamed
    from isoflow.mesh.surface_blocks import write_surface_blocks

    rng = np.random.default_rng(20131122)
    v = rng.random((23, 19, 26)) < 0.45  # many edge and vertex contacts
    v[:12] |= torus(8, 3, size=26, axis=0)[:12, 3:22, :]  # a tunnel across blocks
    z = zarr.open_array(str(tmp_path / "v.zarr"), mode="w", shape=v.shape, chunks=(7, 5, 9), dtype=bool)
    z[:] = v
    got = write_surface_blocks(zarr.open_array(str(tmp_path / "v.zarr"), mode="r"), tmp_path / "s.ply", conn,
                               scheduler=client.get)
    mesh = boundary_mesh(v, conn)
    want = write_mesh_file(tmp_path / "m.ply", mesh, DigitalObject(v))
    assert got["pinched"] == mesh.pinched and got["euler_characteristic"] == mesh.euler_characteristic
    assert check_streamed(got["path"], dict(got, centre=np.array(v.shape) / 2), DigitalObject(v))["agree"]

    def records(path):
        tm = trimesh.load(path, process=False)
        data = tm.metadata["_ply_raw"]["vertex"]["data"]
        rows = np.stack([data[n].astype(np.float64).ravel() for n in data.dtype.names], axis=1)
        faces = np.sort(rows[tm.faces].reshape(len(tm.faces), -1), axis=1)  # a face by its corners' records
        return np.unique(rows, axis=0, return_counts=True), np.unique(faces, axis=0, return_counts=True)

    (rows_got, n_got), (faces_got, m_got) = records(got["path"])
    (rows_want, n_want), (faces_want, m_want) = records(want["path"])
    assert np.array_equal(rows_got, rows_want) and np.array_equal(n_got, n_want)
    assert np.array_equal(faces_got, faces_want) and np.array_equal(m_got, m_want)


def test_the_default_clients_worker_limit_holds_the_blocks():
    # the blocks are summed on the default client's worker, whose memory limit (200 MB) is what they must fit,
    # not this machine's memory: a block of 2^27 voxels (about 256 MiB to sum) is refused up front, naming the
    # worker's limit; a volume of small blocks runs there
    import dask

    from isoflow.scale.memory import default_budget

    if default_budget() < 1 << 30:
        pytest.skip("the big block must fit this machine's memory, so that only the worker's limit refuses it")
    # the worker's own memory monitor left out: with processes=False it measures this whole test process
    unmonitored = {f"distributed.worker.memory.{k}": False for k in ("target", "spill", "pause", "terminate")}
    with dask.config.set(unmonitored), \
            distributed.LocalCluster(n_workers=1, threads_per_worker=1, memory_limit="200MB", processes=False,
                                     dashboard_address=None) as cluster, distributed.Client(cluster):
        with pytest.raises(IsoflowError) as err:
            analyze_chunked(da.zeros((512, 512, 512), bool, chunks=512), 6)
        message = str(err.value)
        assert "\n" not in message and f"memory limit of {200e6 / 2**20:.1f} MiB" in message
        v = ball(12, 30)
        got = analyze_chunked(da.from_array(v, chunks=(11, 7, 13)), 6)
    assert got["betti"] == [1, 0, 0] and got["voxels"] == np.count_nonzero(v)


def test_the_surface_blocks_are_held_to_the_workers_memory_limit(tmp_path):
    # the surface of a store written block by block on a default client's worker whose memory limit (50 MB) is
    # smaller than counting one block of 256^3 voxels takes (its voxels and halo as read, at least a byte each twice,
    # 2^25 bytes alone) though this machine holds it: refused up front, in one line naming the worker's limit, and
    # no file written; a store of small blocks is written there
    import dask

    from isoflow.mesh.surface_blocks import write_surface_blocks
    from isoflow.scale.memory import default_budget

    if default_budget() < 1 << 30:
        pytest.skip("the big block must fit this machine's memory, so that only the worker's limit refuses it")
    big = zarr.open_array(str(tmp_path / "big.zarr"), mode="w", shape=(256, 256, 256), chunks=256, dtype=bool)
    big[100:150, 100:150, 100:150] = True
    v = ball(12, 30)
    small = zarr.open_array(str(tmp_path / "small.zarr"), mode="w", shape=v.shape, chunks=(11, 7, 13), dtype=bool)
    small[:] = v
    unmonitored = {f"distributed.worker.memory.{k}": False for k in ("target", "spill", "pause", "terminate")}
    with dask.config.set(unmonitored), \
            distributed.LocalCluster(n_workers=1, threads_per_worker=1, memory_limit="50MB", processes=False,
                                     dashboard_address=None) as cluster, distributed.Client(cluster):
        with pytest.raises(IsoflowError) as err:
            write_surface_blocks(zarr.open_array(str(tmp_path / "big.zarr"), mode="r"), tmp_path / "big.ply")
        got = write_surface_blocks(zarr.open_array(str(tmp_path / "small.zarr"), mode="r"), tmp_path / "small.ply")
    message = str(err.value)
    assert "\n" not in message and f"memory limit of {50e6 / 2**20:.1f} MiB" in message
    assert "smaller chunks" in message  # what would fit: not even one block at a time does
    assert not (tmp_path / "big.ply").exists() and not list(tmp_path.glob(".big*"))
    assert got["voxels"] == np.count_nonzero(v) and got["euler_characteristic"] == 2  # a ball's surface, a sphere
