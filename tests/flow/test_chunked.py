"""The plain flow of a zarr store, block by block (isoflow.flow.chunked),
against the in-memory flow of the same volume: the same records, stop,
limit and topology changes (not located out of core: ``where`` is None),
and every state's store equal to the in-memory state, read back by zarr
and by isoflow.read_volume with its place in the world. On odd chunkings
of the input and odd slab thicknesses, at 6 and 26, with segments that
cross many slabs, edge and vertex contacts, shapes touching the border;
on a two-process dask LocalCluster; as the command `isoflow flow
IN.zarr --out DIR --volumes .zarr`, whose refusals are one line and whose
interruption leaves the previous run as it was."""

from __future__ import annotations

import csv
import json
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

zarr = pytest.importorskip("zarr")
pytest.importorskip("dask")

from isoflow import DigitalObject  # noqa: E402
from isoflow.cli import main  # noqa: E402
from isoflow.errors import IsoflowError  # noqa: E402
from isoflow.flow.chunked import flow_chunked, slab_thickness  # noqa: E402
from isoflow.flow.files import STAGE  # noqa: E402
from isoflow.flow.run import run_flow  # noqa: E402
from isoflow.mesh.outputs import TEMP_MARK  # noqa: E402
from isoflow.mesh.volumes import read_object, write_volume  # noqa: E402
from isoflow.scale.memory import default_budget  # noqa: E402


def crossing_volume(seed: int = 0) -> np.ndarray:
    """A ball, a bar along the first axis through every slab (long
    segments), noise (edge and vertex contacts), voxels on the border."""
    rng = np.random.default_rng(seed)
    x = np.indices((23, 19, 70)) - np.array([11, 9, 40])[:, None, None, None]
    v = (x**2).sum(0) <= 8**2
    v[:, 1:4, 2:5] = True  # touches both ends of the first axis
    v[3:9, 12:18, 60:70] |= rng.random((6, 6, 10)) < 0.6
    return v


def plain_store(path, v, chunks):
    zarr.open_array(str(path), mode="w", shape=v.shape, chunks=chunks, dtype=np.uint8)[...] = v


def in_memory(path, conn, **kw):
    r = run_flow(read_object(path), connectivity=conn, method="numpy", **kw)
    expected = r.to_dict()
    for change in expected["topology_changes"]:
        change["where"] = None
    return r, expected


def check_states(run, out, width=3):
    for step, state in enumerate(run.states):
        store = out / f"step_{step:0{width}d}.zarr"
        if not state.voxels:
            assert not store.exists()
            continue
        stored = zarr.open_group(str(store), mode="r")["0"][...]
        assert stored.shape == state.volume.shape and np.array_equal(stored != 0, state.volume)
        back = read_object(store)
        assert np.array_equal(back.volume, state.volume)
        assert np.allclose(back.world(np.zeros(3)), state.world(np.zeros(3)))
        assert np.allclose(back.spacing, state.spacing)


@pytest.mark.parametrize("conn,chunks,slab,steps", [(6, (5, 7, 11), 1, 8), (26, (5, 7, 11), 3, None),
                                                    (6, (23, 19, 70), 8, None), (26, (4, 19, 9), 5, None)])
def test_equals_the_in_memory_flow_on_odd_chunkings(tmp_path, conn, chunks, slab, steps):
    v = crossing_volume()
    plain_store(tmp_path / "in.zarr", v, chunks)
    mem, expected = in_memory(tmp_path / "in.zarr", conn, steps=steps)
    out = tmp_path / "run"
    out.mkdir()
    got = flow_chunked(tmp_path / "in.zarr", out, connectivity=conn, slab=slab, steps=steps)
    assert got.to_dict() == expected
    assert expected["topology_changes"]  # the bar and the ball part
    check_states(mem, out)


def test_placed_ome_zarr_input_and_its_stops(tmp_path):
    v = crossing_volume(1)
    obj = DigitalObject(v, pitch=(0.5, 0.5, 2.0), origin=(10.0, -3.0, 7.5))
    write_volume(obj, tmp_path / "in.zarr")
    for kw in ({"steps": 4}, {"until_topology_change": True}, {"max_steps": 2}):
        mem, expected = in_memory(tmp_path / "in.zarr", 6, **kw)
        out = tmp_path / f"run{len(list(tmp_path.iterdir()))}"
        out.mkdir()
        got = flow_chunked(tmp_path / "in.zarr", out, slab=6, **kw)
        assert got.to_dict() == expected
        check_states(mem, out)


def cluster_run(tmp_path, seed: int, conn: int, steps: int):
    """A crossing volume's store, its in-memory flow and the run's directory."""
    plain_store(tmp_path / "in.zarr", crossing_volume(seed), (6, 10, 16))
    mem, expected = in_memory(tmp_path / "in.zarr", conn, steps=steps)
    out = tmp_path / "run"
    out.mkdir()
    return mem, expected, out


def test_on_a_two_process_local_cluster(tmp_path):
    distributed = pytest.importorskip("distributed")
    mem, expected, out = cluster_run(tmp_path, 2, 26, 6)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        got = flow_chunked(tmp_path / "in.zarr", out, connectivity=26, slab=4, steps=6, scheduler=client.get)
    assert got.to_dict() == expected
    check_states(mem, out)


def test_a_default_client_runs_the_slabs_and_the_records_alike(tmp_path):
    """With scheduler=None and a dask.distributed default client, the slabs
    ran on local threads while each step's record ran on the cluster: both
    run on the cluster now (its task stream holds the slabs' tasks and the
    report's blocks), and the run equals the in-memory flow."""
    distributed = pytest.importorskip("distributed")
    from distributed.utils import key_split

    mem, expected, out = cluster_run(tmp_path, 3, 6, 2)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client, distributed.get_task_stream(client) as stream:
        got = flow_chunked(tmp_path / "in.zarr", out, slab=4, steps=2)
    ran = {key_split(t["key"]) for t in stream.data}
    assert {"slab_ends", "slab_keep", "read_zarr_block"} <= ran  # (key_split drops the leading underscore)
    assert got.to_dict() == expected
    check_states(mem, out)


def test_slabs_that_do_not_fit_are_refused_up_front():
    with pytest.raises(IsoflowError, match="slabs of 1 layer of 1000001 x 1000001 vertices .* crop the volume"):
        slab_thickness((10, 10**6, 10**6), None, 2)
    with pytest.raises(IsoflowError, match="slabs of 7 layers of 11 x 11 vertices .* give thinner slabs"):
        slab_thickness((10, 10, 10), 7, 10**17)


def test_slabs_are_thinned_to_fit_the_memory_budget(monkeypatch):
    """Where the default slabs (SLAB_VOXELS) would not fit the memory
    available, `isoflow flow STORE --volumes .zarr` was refused, telling a
    command-line user to pass `slab=`, which only Python takes; the slabs
    are now as thick as the budget holds, and only a slab of one layer
    that does not fit is refused, saying how many workers would fit (in
    the words of the command line and of Python), and they do."""
    from isoflow.scale import memory

    layer = 1024 * 1024  # the vertices of a layer of a (1023, 1023) plane
    per_layer = 2 * layer + 6 * layer // 8  # its bytes read and written, its bit rows and faces
    monkeypatch.setattr(memory, "default_budget", lambda: 12 * per_layer)
    thick = slab_thickness((100, 1023, 1023), None, 2)
    assert thick == 4 and 2 * (thick + 2) * per_layer <= memory.default_budget()  # two workers' slabs with a seam each
    # a cross-section whose step records are small beside its slabs' layers
    layer = 4001 * 4001
    per_layer = 2 * layer + 6 * layer // 8
    monkeypatch.setattr(memory, "default_budget", lambda: 5 * per_layer)
    with pytest.raises(IsoflowError, match=r"slabs of 1 layer .*; slabs of one layer fit 1 at a time "
                                           r"\(--threads 1, workers=1\)"):
        slab_thickness((10, 4000, 4000), None, 2)
    assert slab_thickness((10, 4000, 4000), None, 1) >= 1


def slab_refusals(monkeypatch, shape, workers, budgets):
    """The refusal of ``slab_thickness(shape, None, workers)`` under each
    memory budget (bytes) that refuses it, the budget still set while the
    caller looks at the message."""
    from isoflow.scale import memory

    for budget in np.asarray(budgets).astype(int):
        monkeypatch.setattr(memory, "default_budget", lambda b=budget: int(b))
        try:
            slab_thickness(shape, None, workers)
        except IsoflowError as err:
            yield str(err)


@pytest.mark.parametrize("shape", [(100, 1023, 1023), (10, 4000, 4000), (20, 200, 200)])
def test_the_workers_a_slab_refusal_names_flow(monkeypatch, shape):
    """A slab refusal named the workers whose slabs of one layer fit
    without asking whether each step's report of those slabs fits them
    too: on a 1023 x 1023 cross-section it said they fit 1 at a time, and
    one worker was then refused for the report. Under every budget, the
    workers a refusal names (`--threads N`, `workers=N`) are sized
    without a refusal, and a refusal naming none says what else to do: a
    cross-section to crop to, at one thread a wider one, which is sized
    without a refusal at one thread."""
    import re


    layer = (shape[1] + 1) * (shape[2] + 1)
    named = set()
    for message in slab_refusals(monkeypatch, shape, 4, np.geomspace(layer, 40 * layer, 60)):
        fit = re.search(r"\(--threads (\d+), workers=\1\)", message)
        if fit is None:
            alone = re.search(r", or (\d+) x \1 at --threads 1, workers=1$", message)
            if alone is not None:
                assert slab_thickness((shape[0], int(alone[1]), int(alone[1])), None, 1) >= 1, message
                message = message[:alone.start()]
            assert "crop the volume" in message and "workers=" not in message, message
            continue
        named.add(int(fit[1]))
        assert 1 <= int(fit[1]) < 4 and slab_thickness(shape, None, int(fit[1])) >= 1, message
    assert named  # some budget is refused naming fewer workers


def test_command_counts_a_slab_of_one_layer_in_the_singular(tmp_path, capsys, monkeypatch):
    """The refusal of slabs that do not fit, as `isoflow flow STORE --volumes
    .zarr` prints it, says "1 layer", and several layers in the plural: a
    budget that holds no slab of one layer refuses the flow at once (no
    step written), and a slab thickness asked of Python beyond one that a
    worker holds is refused in the plural."""
    from isoflow.scale import memory

    plain_store(tmp_path / "in.zarr", crossing_volume(), (8, 8, 8))
    # the input's chunks of 8^3 fit (about 8 KiB two at a time), one slab of one layer does not (its
    # 18 x 69 vertices and their seams: 3 x 3415 bytes)
    monkeypatch.setattr(memory, "default_budget", lambda: 10_000)
    assert main(["flow", str(tmp_path / "in.zarr"), "--out", str(tmp_path / "run"), "--volumes", ".zarr"]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and "slabs of 1 layer of " in line and "1 layers" not in line, line
    assert not list((tmp_path / "run").glob("step_*"))
    with pytest.raises(IsoflowError, match="slabs of 3 layers of 11 x 11 vertices"):
        slab_thickness((10, 10, 10), 3, 10**17)


def test_a_workers_slab_thickness_is_counted_in_the_singular_and_plural(monkeypatch):
    """On a cluster the refusal of slabs too thick for a worker says the
    thickest that fits: "1 layer" for one, "N layers" for more, and the
    slab it names does fit the worker, one layer more does not."""
    import re

    from isoflow.scale import chunks

    limit = [0]

    class Cluster:  # what a client's scheduler_info() says of a worker of one thread
        def scheduler_info(self, n_workers=-1):
            return {"workers": {"tcp://w1": {"memory_limit": limit[0], "nthreads": 1}}}

    monkeypatch.setattr(chunks, "distributed_client", lambda scheduler: Cluster())
    shape, told = (40, 100, 100), {}
    # a worker's record holds 3 MiB whatever the slab (outofcore.WORKER_RUN_BYTES): the limits that fit
    # slabs of one layer span under 2 % above it, so the steps are finer than that
    for limit[0] in np.geomspace(1e4, 1e8, 1200).astype(int):
        try:
            slab_thickness(shape, 40, 1, scheduler=None)
            continue  # a worker this large holds the slab asked for
        except IsoflowError as err:
            named = re.search(r"slabs of (\d+) (layers?) fit \(slab=\1\)", str(err))
        if named:
            told.setdefault(int(named[1]) == 1, (int(limit[0]), int(named[1]), named[2]))
    assert set(told) == {True, False}, told
    for limit[0], fit, word in told.values():
        assert word == ("layer" if fit == 1 else "layers")
        assert slab_thickness(shape, fit, 1, scheduler=None) == fit
        with pytest.raises(IsoflowError, match="on a dask.distributed worker"):
            slab_thickness(shape, fit + 1, 1, scheduler=None)


def test_command_writes_the_states_as_stores(tmp_path, capsys):
    v = crossing_volume(3)
    write_volume(DigitalObject(v, pitch=0.25), tmp_path / "in.zarr")
    assert main(["flow", str(tmp_path / "in.zarr"), "--steps", "6", "--json"]) == 0
    expected = json.loads(capsys.readouterr().out)
    for change in expected["topology_changes"]:
        change["where"] = None
    out = tmp_path / "run"
    assert main(["flow", str(tmp_path / "in.zarr"), "--steps", "6", "--out", str(out), "--volumes", ".zarr",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == expected
    names = sorted(p.name for p in out.iterdir())
    assert names == ["flow.csv", "flow.png"] + [f"step_{s:03d}.zarr" for s in range(7)]
    rows = (out / "flow.csv").read_text().splitlines()
    assert len(rows) == len(expected["steps"]) + 1


@pytest.mark.parametrize("extra,message", [
    (["--guard"], "--guard is not done block by block"),
    (["--label", "1"], "--label is not read block by block"),
])
def test_command_refusals_are_one_line(tmp_path, capsys, extra, message):
    plain_store(tmp_path / "in.zarr", crossing_volume(), (8, 8, 8))
    assert main(["flow", str(tmp_path / "in.zarr"), "--out", str(tmp_path / "run"), "--volumes", ".zarr", *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "run").exists()


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_an_interrupted_command_leaves_the_previous_run(tmp_path):
    plain_store(tmp_path / "in.zarr", crossing_volume(), (8, 8, 8))
    out = tmp_path / "run"
    out.mkdir()
    (out / "flow.csv").write_text("the previous run\n")
    proc = subprocess.Popen([sys.executable, "-m", "isoflow.cli", "flow", str(tmp_path / "in.zarr"), "--out", str(out),
                             "--volumes", ".zarr", "--force"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)
    end = time.monotonic() + 120
    while not any(s.glob("step_002.zarr") for s in out.glob(f".{STAGE}{TEMP_MARK}*")):
        assert proc.poll() is None and time.monotonic() < end, proc.stderr.read()
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert "Traceback" not in err
    assert sorted(p.name for p in out.iterdir()) == ["flow.csv"]
    assert (out / "flow.csv").read_text() == "the previous run\n"


def test_command_text_says_changes_are_not_located(tmp_path, capsys):
    """The table of a store flowed block by block names its topology
    changes without a place; it printed "in None"."""
    v = crossing_volume(3)
    write_volume(DigitalObject(v), tmp_path / "in.zarr")
    assert main(["flow", str(tmp_path / "in.zarr"), "--steps", "6", "--out", str(tmp_path / "run"),
                 "--volumes", ".zarr", "-q"]) == 0
    changes = [line for line in capsys.readouterr().out.splitlines() if "topology change" in line]
    assert changes and all(line.endswith("not located (block by block)") for line in changes)
    assert not any("None" in line for line in changes)


def test_command_names_the_fill_value_of_chunks_never_written(tmp_path):
    """A store whose second chunk was never written reads it as the
    array's fill value, 2 here: the flow block by block refused it with
    "e.g. 2" alone, a value no voxel was written with; the line now says it
    is the fill value, and why zarr reads it, as ``info`` does."""
    store = tmp_path / "sparse.zarr"
    z = zarr.create_array(str(store), shape=(8, 8, 8), chunks=(4, 8, 8), dtype="u1", fill_value=2)
    z[:4] = crossing_volume()[:4, :8, :8]
    assert len(list(store.rglob("c/*/*/*"))) == 1  # one chunk of two written
    run = subprocess.run([sys.executable, "-m", "isoflow", "flow", str(store), "--out", str(tmp_path / "run"),
                          "--volumes", ".zarr"], capture_output=True, text=True, timeout=300)
    # (where numba's cache is cold a process may say so first, in a note line)
    err = [line for line in run.stderr.strip().splitlines() if not line.startswith("isoflow flow: note: ")]
    assert run.returncode == 2 and len(err) == 1, run.stderr
    assert err[0].startswith(f"isoflow flow: error: {store}: not a binary volume (256 voxels "), err  # 4 x 8 x 8
    assert "e.g. 2, the array's fill value, which zarr reads for a chunk never written" in err[0], err
    assert not (tmp_path / "run").exists()


def test_command_warns_that_chunks_never_written_count_as_the_object(tmp_path):
    """A store of fill value 1 whose chunks were never written reads them
    as voxels of the object: ``info`` of the store and the flow in memory
    said so in one warning line, the flow block by block (``--volumes
    .zarr``) said nothing and flowed them as written voxels. Its run is
    the run of the array zarr reads, and the warning is the same line."""
    store = tmp_path / "sparse.zarr"
    z = zarr.create_array(str(store), shape=(10, 10, 10), chunks=(4, 4, 4), dtype="u1", fill_value=1)
    z[:4, :4, :4] = 0  # one chunk of 27 written
    read = np.asarray(zarr.open_array(str(store), mode="r")[...]) != 0
    assert np.count_nonzero(read) == 1000 - 64
    lines = {}
    for name, extra in (("memory", []), ("blocks", ["--out", str(tmp_path / "run"), "--volumes", ".zarr"])):
        run = subprocess.run([sys.executable, "-m", "isoflow", "flow", str(store), "--json", "--steps", "1", *extra],
                             capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        assert [s["voxels"] for s in json.loads(run.stdout)["steps"]][0] == np.count_nonzero(read)
        # (where numba's cache is cold a process may say so first, in a note line)
        lines[name] = [line for line in run.stderr.splitlines() if "warning:" in line]
    assert len(lines["memory"]) == 1 and "26 of 27 chunks were never written" in lines["memory"][0], lines
    assert lines["blocks"] == lines["memory"], lines


def test_force_removes_a_linked_step_store_not_the_store_it_names(tmp_path):
    """``flow_chunked(..., force=True)`` into a directory whose
    ``step_004.zarr`` is a symbolic link to a store of the user's raised
    OSError ("Cannot call rmtree on a symbolic link"): the link goes as an
    earlier run's store does, the store it names is kept."""
    mine = tmp_path / "mine.zarr"
    plain_store(mine, crossing_volume()[:8, :8, :8], (4, 8, 8))
    kept = {str(f.relative_to(mine)): f.read_bytes() for f in sorted(mine.rglob("*")) if f.is_file()}
    out = tmp_path / "run"
    out.mkdir()
    (out / "step_004.zarr").symlink_to(mine)
    run = flow_chunked(mine, out, steps=1, force=True)
    assert [s["step"] for s in run.steps] == [0, 1]
    assert sorted(p.name for p in out.iterdir()) == ["step_000.zarr", "step_001.zarr"]
    assert {str(f.relative_to(mine)): f.read_bytes() for f in sorted(mine.rglob("*")) if f.is_file()} == kept


def test_force_removes_a_file_named_as_a_step_store(tmp_path, capsys):
    """A plain file named ``step_000.zarr`` in the directory:
    ``flow_chunked(..., force=True)`` ended in a NotADirectoryError
    traceback (rmtree of a file), and the command with ``--force`` refused
    the run ("could not put it in place (Not a directory)"). The file goes
    as an earlier run's store does; without force it is named."""
    v = np.zeros((5, 5, 5), bool)
    v[1:4, 1:4, 1:4] = True
    plain_store(tmp_path / "in.zarr", v, (2, 3, 5))
    for how in ("python", "command"):
        out = tmp_path / how
        out.mkdir()
        (out / "step_000.zarr").write_text("not a store\n")
        if how == "python":
            with pytest.raises(IsoflowError, match=r"earlier run \(step_000\.zarr\)"):
                flow_chunked(tmp_path / "in.zarr", out, steps=1)
            assert (out / "step_000.zarr").read_text() == "not a store\n"
            flow_chunked(tmp_path / "in.zarr", out, steps=1, force=True)
        else:
            assert main(["flow", str(tmp_path / "in.zarr"), "--out", str(out), "--volumes", ".zarr", "--steps", "1",
                         "--force", "-q"]) == 0, capsys.readouterr().err
        assert (out / "step_000.zarr").is_dir()
        # step 0 is the input, cropped: its voxels as numpy counts them
        assert np.count_nonzero(zarr.open_group(str(out / "step_000.zarr"), mode="r")["0"][...]) == v.sum()


def test_command_names_a_damaged_chunk_in_one_line(tmp_path, capsys):
    """A chunk that does not decode (zarr's codec raises) ended the flow
    block by block in a traceback, exit status 1; it is one line naming the
    store and the region of the chunk, exit status 2, as ``info`` and
    ``surface`` refuse it."""
    store = tmp_path / "damaged.zarr"
    plain_store(store, crossing_volume()[:8, :8, :8], (4, 8, 8))
    (store / "c" / "1" / "0" / "0").write_bytes(b"not a chunk")
    assert main(["flow", str(store), "--out", str(tmp_path / "run"), "--volumes", ".zarr"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"isoflow flow: error: {store}: cannot read a chunk in [4:8, 0:8, 0:8] ("), err
    assert not (tmp_path / "run").exists()


def test_command_on_a_label_image_names_the_way_to_one_label(tmp_path, capsys):
    """A label image flowed block by block was refused with "or select one
    label with --label N", an option that flow refuses ("--label is not
    read block by block"); the line now names the flow in memory, where
    --label flows the label's voxels."""
    v = crossing_volume()[:8, :8, :8].astype(np.uint8)
    v[1:3, 1:4, 1:6] = 2
    store = tmp_path / "labels.zarr"
    plain_store(store, v, (4, 8, 8))
    assert main(["flow", str(store), "--out", str(tmp_path / "run"), "--volumes", ".zarr"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"({np.count_nonzero(v[:4] == 2)} voxels in the block at voxel (0, 0, 0)" in err[0], err
    assert err[0].endswith("or select one label with --label N in the flow in memory (without --volumes .zarr), "
                           "or write its voxels as a store of their own"), err
    assert main(["flow", str(store), "--label", "2", "--steps", "0", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["steps"][0]["voxels"] == np.count_nonzero(v == 2) == 30


def test_command_flows_a_mask_of_one_value_block_by_block(tmp_path, capsys):
    """A 0/255 mask flowed block by block (``--volumes .zarr``) was refused
    as "not a binary volume", where the flow in memory and ``read_volume``
    read a store of 0 and 255 alone as its mask: it is now flowed block by
    block as that mask, step for step the flow of the 0/1 store of the same
    voxels (its first state all of them). A store of 255 and another label
    is still refused, naming the one value of the block that refused it as
    the --label of the flow in memory."""
    v = crossing_volume()[:8, :8, :8]
    plain_store(tmp_path / "mask.zarr", (v * 255).astype(np.uint8), (4, 8, 8))
    plain_store(tmp_path / "ones.zarr", v.astype(np.uint8), (4, 8, 8))
    flows = []
    for name in ("mask.zarr", "ones.zarr"):
        out = tmp_path / f"run_{name.split('.')[0]}"
        assert main(["flow", str(tmp_path / name), "--steps", "2", "--out", str(out), "--volumes", ".zarr"]) == 0, \
            capsys.readouterr().err
        capsys.readouterr()
        with open(out / "flow.csv", newline="") as fh:
            flows.append([int(row["voxels"]) for row in csv.DictReader(fh)])
    assert flows[0] == flows[1] and flows[0][0] == np.count_nonzero(v)
    labels = (v * 255).astype(np.uint8)
    labels[4:][v[4:]] = 7  # each block holds 0 and one label alone: 255, then 7 (refused by either)
    plain_store(tmp_path / "labels.zarr", labels, (4, 8, 8))
    assert main(["flow", str(tmp_path / "labels.zarr"), "--out", str(tmp_path / "run"), "--volumes", ".zarr"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(r"or select one label with --label (255|7) in the flow in memory", err[0]), err
    assert not (tmp_path / "run").exists()


def test_help_names_the_flow_block_by_block(capsys):
    """``flow --help`` said nothing of the flow of a store block by block:
    its --volumes and --out read as if every run wrote surfaces and
    shapes.png. It now names ``--volumes .zarr`` and what that run leaves
    out (docs/flow.md, "Beyond memory")."""
    with pytest.raises(SystemExit):
        main(["flow", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert ("a .zarr input with --volumes .zarr is flowed block by block, never read into memory (its --out gets no "
            "surfaces or shapes.png)") in text


@pytest.mark.parametrize("suffix", ["zarr", "ZARR"])
def test_the_suffix_without_its_dot_flows_block_by_block(tmp_path, capsys, suffix):
    """``--volumes zarr`` names the suffix ``.zarr`` (the dot may be left
    out, as for every suffix) but flowed the store in memory, writing the
    surfaces and shapes.png that the flow block by block leaves out; it now
    flows it block by block, as ``--volumes .zarr`` does."""
    plain_store(tmp_path / "in.zarr", crossing_volume(3), (8, 8, 8))
    out = tmp_path / "run"
    assert main(["flow", str(tmp_path / "in.zarr"), "--steps", "2", "--out", str(out), "--volumes", suffix, "-q"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["flow.csv", "flow.png"] + [f"step_{s:03d}.zarr" for s in range(3)]
    assert "volumes (step_*.zarr, read block by block)" in capsys.readouterr().out


def edge_touching_boxes() -> np.ndarray:
    """Two 4x4x4 boxes sharing an edge: two 6-components, which the third
    plain step merges into one."""
    v = np.zeros((12, 8, 8), bool)
    v[1:5, 1:5, 1:5] = True
    v[5:9, 5:7, 1:5] = True
    return v


def test_until_topology_change_leaves_no_store_of_the_step_not_taken(tmp_path):
    """The step that would change the Betti numbers is reported, not
    taken: no store of it is left beside the states taken (a step_002.zarr
    of one piece was left in the directory)."""
    from scipy import ndimage

    v = edge_touching_boxes()
    plain_store(tmp_path / "in.zarr", v, (5, 3, 4))
    out = tmp_path / "run"
    out.mkdir()
    got = flow_chunked(tmp_path / "in.zarr", out, until_topology_change=True, slab=2)
    assert got.stop_reason == "topology-change"
    stores = sorted(out.glob("step_*.zarr"))
    assert [p.name for p in stores] == [f"step_{s['step']:03d}.zarr" for s in got.steps]
    # scipy's 6-components of the input, and of every state left
    assert ndimage.label(v)[1] == 2
    assert [ndimage.label(zarr.open_group(str(p), mode="r")["0"][...] != 0)[1] for p in stores] == [2] * len(stores)


def test_command_names_the_store_of_a_connectivity_that_does_not_fit(tmp_path, capsys):
    """A 2D connectivity for a 3D store is refused in one line naming the
    store, as the in-memory flow names its file (the line named none)."""
    plain_store(tmp_path / "in.zarr", edge_touching_boxes(), (5, 3, 4))
    assert main(["flow", str(tmp_path / "in.zarr"), "--out", str(tmp_path / "run"), "--volumes", ".zarr",
                 "--connectivity", "4"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert err.startswith(f"isoflow flow: error: {tmp_path / 'in.zarr'}: connectivity 4 is not valid in 3D")
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("argument,value", [("progress", 5), ("steps", -1), ("steps", 1.5), ("steps", True),
                                            ("max_steps", -2), ("until_topology_change", "yes"),
                                            ("workers", 0), ("width", -1)])
def test_a_bad_argument_is_refused_before_any_store(tmp_path, argument, value):
    """Arguments run_flow refuses were taken, or failed late: steps=-1 ran
    no step, 1.5 two, True one, max_steps=-2 none, until_topology_change=
    "yes" stopped at a change; progress=5 failed after a step as "'int'
    object is not callable", workers=0 after the first store naming
    "threads", width=-1 as a format specifier. Each is refused up front,
    naming the argument, with nothing written; run_flow refuses those it
    shares."""
    plain_store(tmp_path / "in.zarr", edge_touching_boxes(), (5, 3, 4))
    out = tmp_path / "run"
    out.mkdir()
    with pytest.raises((IsoflowError, TypeError), match=argument):
        flow_chunked(tmp_path / "in.zarr", out, **{argument: value})
    assert list(out.iterdir()) == []
    if argument not in ("workers", "width"):
        with pytest.raises((IsoflowError, TypeError), match=argument):
            run_flow(read_object(tmp_path / "in.zarr"), **{argument: value})


def test_an_earlier_run_s_stores_are_refused_without_force(tmp_path):
    """A second run into the same directory wrote over the first one's
    first stores and left the rest: after a run of 3 steps, a run of 1
    left step_002.zarr of the other run beside its own. Now the earlier
    stores are refused (zarr reads them back unchanged) and force=True
    replaces all of them."""
    v = edge_touching_boxes()
    plain_store(tmp_path / "in.zarr", v, (5, 3, 4))
    out = tmp_path / "run"
    out.mkdir()
    flow_chunked(tmp_path / "in.zarr", out, steps=3)
    before = {p.name: zarr.open_group(str(p), mode="r")["0"][...] for p in out.glob("step_*.zarr")}
    assert sorted(before) == [f"step_{s:03d}.zarr" for s in range(4)]
    with pytest.raises(IsoflowError, match="earlier run"):
        flow_chunked(tmp_path / "in.zarr", out, steps=1)
    assert all(np.array_equal(zarr.open_group(str(out / n), mode="r")["0"][...], a) for n, a in before.items())
    flow_chunked(tmp_path / "in.zarr", out, steps=1, force=True)
    assert sorted(p.name for p in out.glob("step_*.zarr")) == ["step_000.zarr", "step_001.zarr"]
    # the input cropped to its bounding box: step 0 as scipy finds the object
    from scipy import ndimage

    box = ndimage.find_objects(v.astype(np.uint8))[0]
    assert np.array_equal(zarr.open_group(str(out / "step_000.zarr"), mode="r")["0"][...] != 0, v[box])


@pytest.fixture
def small_worker(request):
    """A default client of one worker of one thread whose memory limit
    (``request.param`` bytes) is far below this machine's memory (the
    worker's own monitor left out: in this process it would measure the
    whole test)."""
    import dask

    distributed = pytest.importorskip("distributed")
    from isoflow.scale.memory import default_budget

    if default_budget() < 1 << 30:
        pytest.skip("the slabs must fit this machine's memory, so that only the worker's limit bounds them")
    unmonitored = {f"distributed.worker.memory.{k}": False for k in ("target", "spill", "pause", "terminate")}
    with dask.config.set(unmonitored), \
            distributed.LocalCluster(n_workers=1, threads_per_worker=1, memory_limit=request.param, processes=False,
                                     dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        yield client


@pytest.mark.parametrize("small_worker", [5_000_000], indirect=True)
def test_slabs_beyond_a_workers_memory_limit_are_refused_up_front(tmp_path, small_worker):
    # one vertex layer of a 1500 x 1500 cross-section reads two voxel layers and writes one, 6.75 MB as bytes
    # alone, more than the worker's 5 MB though this machine holds it: refused in one line before any step's
    # store is written (the flow went ahead, holding the workers' memory to nothing)
    v = np.zeros((3, 1500, 1500), np.uint8)
    v[1, 0, 0] = v[1, -1, -1] = 1  # kept whole by the crop to the object's box
    plain_store(tmp_path / "in.zarr", v, (3, 500, 500))
    out = tmp_path / "run"
    out.mkdir()
    with pytest.raises(IsoflowError) as err:
        flow_chunked(tmp_path / "in.zarr", out, steps=2, scheduler=small_worker.get)
    message = str(err.value)
    assert "\n" not in message and f"memory limit of {5e6 / 2**20:.1f} MiB" in message
    assert "do not fit one at a time on a worker" in message
    assert not list(out.glob("step_*"))


@pytest.mark.parametrize("small_worker", [8_000_000], indirect=True)
def test_slabs_are_thinned_to_a_workers_memory_limit(tmp_path, small_worker):
    # slabs sized to this machine's memory (the whole 200^3 volume in one) would hold the worker's 8 MB twice
    # over with their bytes read and written alone (two per vertex of 202 layers of 201 x 201), and the
    # record's report refused the step's store, a chunk of that size, after it was written: they are sized to
    # the worker, and the run equals the in-memory flow
    v = np.zeros((200, 200, 200), np.uint8)
    v[:, 0, 0] = 1  # a bar along x, across every slab
    v[-1, -1, -1] = 1
    plain_store(tmp_path / "in.zarr", v, (20, 200, 200))  # chunks the worker reads (chunks of 50 layers do not fit)
    mem, expected = in_memory(tmp_path / "in.zarr", 6, steps=1)
    out = tmp_path / "run"
    out.mkdir()
    got = flow_chunked(tmp_path / "in.zarr", out, steps=1, scheduler=small_worker.get)
    assert got.to_dict() == expected
    check_states(mem, out)
    thick = zarr.open_group(str(out / "step_000.zarr"), mode="r")["0"].chunks[0]
    assert (min(thick, 201) + 2) * 2 * 201 * 201 <= 8_000_000



#: the memory budget before any test sets a smaller one
MACHINE_BUDGET = default_budget


def refused_under(tmp_path, monkeypatch, v, chunks, budget: int) -> tuple[str, object]:
    """The one-line refusal of flowing ``v`` stored in ``chunks`` under a
    memory budget of ``budget`` bytes, which names the input and leaves no
    step written; with the run's directory."""
    from isoflow.scale import memory

    plain_store(tmp_path / "in.zarr", v, chunks)
    monkeypatch.setattr(memory, "default_budget", lambda: budget)
    out = tmp_path / "run"
    out.mkdir()
    with pytest.raises(IsoflowError) as err:
        flow_chunked(tmp_path / "in.zarr", out, steps=1)
    message = str(err.value)
    assert "\n" not in message and message.startswith(str(tmp_path / "in.zarr")), message
    assert "step_" not in message and not list(out.glob("step_*"))
    return message, out


def flows_as_in_memory(path, v, chunks, out) -> None:
    """``v`` stored in ``chunks`` at ``path`` flows (a step) into ``out``
    as in memory, under the budget in force. The flow in memory it is
    compared with runs under the machine's budget: it is the reference,
    not what is tested, and NumPy's labelling of a step would not fit the
    small budgets these tests set (the test failed alone, and passed in
    the suite only where an earlier test had left the compiled passes
    chosen)."""
    from isoflow.scale import memory

    plain_store(path, v, chunks)
    small, memory.default_budget = memory.default_budget, MACHINE_BUDGET
    try:
        mem, expected = in_memory(path, 6, steps=1)
    finally:
        memory.default_budget = small
    assert flow_chunked(path, out, steps=1).to_dict() == expected
    check_states(mem, out)


def test_an_input_chunk_beyond_the_budget_is_refused_before_it_is_read(tmp_path, monkeypatch):
    """The memory check counted the slabs and the records, never the
    input's chunks, which the first pass decodes whole: a store of one
    chunk larger than the budget was read anyway (one past the memory
    ended as 'cannot read a chunk ... (MemoryError ...)'). It is refused
    in one line naming the chunks, before any step is written, and the
    chunks it says fit do: the same object so stored flows under that
    budget as in memory."""
    import re

    v = np.zeros((64, 64, 64), np.uint8)
    v[2:6, 2:6, 2:6] = 1  # a small object: its slabs and records fit where the chunk does not
    message, out = refused_under(tmp_path, monkeypatch, v, (64, 64, 64), 1_000_000)
    assert "chunks of 64 x 64 x 64 voxels" in message
    side = int(re.search(r"smaller chunks, of \d+ voxels or fewer \(e\.g\. (\d+) x \1 x \1\)", message)[1])
    assert 1 <= side < 64
    flows_as_in_memory(tmp_path / "fits.zarr", v, (side,) * 3, out)


def test_slabs_are_thinned_to_fit_each_step_s_report(monkeypatch, tmp_path):
    """The slabs were sized for the flow's step alone, and the step stores
    are chunked as thick as they are: each step's record, which sums a
    store in blocks of those chunks, was refused after step 0 was
    written, naming the hidden staging store. The slabs are now thin
    enough for the record too, and the run equals the in-memory flow."""
    from isoflow.scale import memory

    v = np.zeros((20, 200, 200), np.uint8)
    v[:, 0, 0] = 1  # a bar along x, across every slab
    v[-1, -1, -1] = 1
    monkeypatch.setattr(memory, "default_budget", lambda: 4_000_000)
    out = tmp_path / "run"
    out.mkdir()
    flows_as_in_memory(tmp_path / "in.zarr", v, (10, 100, 100), out)


def test_a_report_beyond_the_budget_is_refused_before_any_step(monkeypatch, tmp_path):
    """A cross-section whose report (the faces of a layer of blocks) does
    not fit the budget however thin the slabs: the run wrote step 0 and
    then failed naming the hidden staging store, advising smaller chunks
    of a store it wrote itself. It is refused up front naming the input,
    and the cross-section it says fits does: the object cropped to it
    flows under that budget as in memory."""
    import re

    v = np.zeros((20, 300, 300), np.uint8)
    v[:, 0, 0] = 1
    v[-1, -1, -1] = 1  # the object spans the whole cross-section
    message, out = refused_under(tmp_path, monkeypatch, v, (10, 100, 100), 4_000_000)
    assert "report of each step" in message
    ny, nz = map(int, re.search(r"crop the volume across x to (\d+) x (\d+) voxels or less", message).groups())
    assert ny < 300 and nz < 300
    w = v[:, :ny, :nz].copy()
    w[-1, -1, -1] = 1
    flows_as_in_memory(tmp_path / "fits.zarr", w, (10, 100, 100), out)


def test_a_narrow_cross_section_is_cropped_along_its_long_side(monkeypatch):
    """A cross-section of 40 x 3000 voxels whose report does not fit: the
    crop the refusal names was a square (S x S with S past the short
    side's 40, a crop no volume of this one has); it keeps the short side
    whole and narrows the long one, and a volume cropped to it is sized
    without a refusal."""
    import re


    shape = (20, 40, 3000)
    named = []
    for message in slab_refusals(monkeypatch, shape, 1, np.geomspace(1_000_000, 4_000_000, 12)):
        found = re.search(r"crop the volume across x to (\d+) x (\d+) voxels or less", message)
        if found is None:
            continue
        ny, nz = int(found[1]), int(found[2])
        assert ny == 40 and nz < 3000, message
        assert slab_thickness((20, ny, nz), None, 1) >= 1
        named.append(nz)
    assert named


def test_command_threads_flow_a_store_as_without(tmp_path, capsys):
    """``isoflow flow STORE --out DIR --volumes .zarr --threads 1`` (the
    slabs and records one at a time) gives the records, flow.csv and
    states the in-memory flow gives, as the run without --threads does;
    the command took no --threads."""
    v = crossing_volume(2)
    plain_store(tmp_path / "in.zarr", v, (5, 7, 11))
    mem, expected = in_memory(tmp_path / "in.zarr", 6, steps=5)
    runs = {}
    for name, extra in (("default", []), ("one", ["--threads", "1"])):
        out = tmp_path / name
        assert main(["flow", str(tmp_path / "in.zarr"), "--out", str(out), "--volumes", ".zarr", "--steps", "5",
                     "--json", *extra]) == 0, capsys.readouterr().err
        got = json.loads(capsys.readouterr().out)
        assert {k: got[k] for k in expected} == expected
        check_states(mem, out)
        runs[name] = (out / "flow.csv").read_text()
    assert runs["one"] == runs["default"]


@pytest.mark.parametrize("case", ["chunks", "report"])
def test_a_command_refusal_names_the_threads_that_flow(tmp_path, capsys, monkeypatch, case):
    """Where memory is short, `isoflow flow STORE --volumes .zarr` was
    refused with "they fit 1 at a time (flow_chunked(..., workers=1))",
    which the command line could not give. The refusal (of the input's
    chunks, of each step's report) names `--threads N` beside Python's
    `workers=N`, and the same command with `--threads N` under the same
    budget flows as in memory, as it does with the environment's
    ISOFLOW_THREADS=N for the default (it ran 2 at a time whatever that
    said)."""
    import re

    from isoflow.scale import memory

    if case == "chunks":  # a small object in one chunk of 64^3, which two threads decode at once
        v = np.zeros((64, 64, 64), np.uint8)
        v[2:6, 2:6, 2:6] = 1
        chunks, budget = (64, 64, 64), 2_000_000
    else:  # each step's report of a 17 x 68 cross-section, two blocks at a time
        v, chunks, budget = crossing_volume(), (8, 8, 8), 50_000
    plain_store(tmp_path / "in.zarr", v, chunks)
    mem, expected = in_memory(tmp_path / "in.zarr", 6, steps=2)
    monkeypatch.setattr(memory, "default_budget", lambda: budget)
    command = ["flow", str(tmp_path / "in.zarr"), "--out", str(tmp_path / "run"), "--volumes", ".zarr", "--steps", "2",
               "--json"]
    assert main(command) == 2
    err = capsys.readouterr().err.strip()
    fit = re.search(r"fits? (\d+) at a time \(--threads \1, workers=\1\)", err)
    assert "\n" not in err and fit is not None and "flow_chunked(" not in err, err
    assert not (tmp_path / "run").exists()
    monkeypatch.setenv("ISOFLOW_THREADS", fit[1])
    assert main([*command[:3], str(tmp_path / "run_env"), *command[4:]]) == 0, capsys.readouterr().err
    assert {k: v for k, v in json.loads(capsys.readouterr().out).items() if k in expected} == expected
    monkeypatch.delenv("ISOFLOW_THREADS")
    assert main([*command, "--threads", fit[1]]) == 0, capsys.readouterr().err
    got = json.loads(capsys.readouterr().out)
    assert {k: got[k] for k in expected} == expected
    monkeypatch.undo()  # the states read back into memory
    check_states(mem, tmp_path / "run")
    check_states(mem, tmp_path / "run_env")


@pytest.mark.parametrize("case", ["chunks", "report"])
def test_a_size_a_refusal_names_at_fewer_threads_flows(tmp_path, capsys, monkeypatch, case):
    """The chunks (`of N voxels or fewer`) and the cross-section (`crop
    the volume across x to S x S`) that a refusal named were sized for
    the threads asked (`--threads 4`) alone, though one thread holds
    larger ones. The line names those too, at `--threads 1`, and they
    are what it says: refused at four threads under the same budget, the
    same command at one thread flows to the in-memory flow's records."""
    import re

    from isoflow.scale import memory

    if case == "chunks":  # a small object in one chunk of 64^3
        v = np.zeros((64, 64, 64), np.uint8)
        v[2:6, 2:6, 2:6] = 1
        chunks, budget = (64, 64, 64), 1_000_000
        sizes = r"of \d+ voxels or fewer \(e\.g\. (\d+) x \1 x \1\), or \d+ or fewer at --threads 1, workers=1 " \
                r"\(e\.g\. (\d+) x \2 x \2\)"
    else:  # each step's report of a 300 x 300 cross-section
        v = np.zeros((20, 300, 300), np.uint8)
        v[:, 0, 0] = 1
        v[-1, -1, -1] = 1
        chunks, budget = (10, 100, 100), 3_000_000
        sizes = r"crop the volume across x to (\d+) x \1 voxels or less, or (\d+) x \2 at --threads 1, workers=1"
    plain_store(tmp_path / "in.zarr", v, chunks)
    monkeypatch.setattr(memory, "default_budget", lambda: budget)
    command = ["flow", "--volumes", ".zarr", "--steps", "1", "--json", "-q"]
    assert main([*command, str(tmp_path / "in.zarr"), "--out", str(tmp_path / "four"), "--threads", "4"]) == 2
    err = capsys.readouterr().err.strip()
    found = re.search(sizes, err)
    assert "\n" not in err and found is not None, err
    four, one = map(int, found.groups())
    assert one > four
    if case == "chunks":
        plain_store(tmp_path / "fits.zarr", v, (one,) * 3)
    else:
        fits = v[:, :one, :one].copy()
        fits[-1, -1, -1] = 1
        plain_store(tmp_path / "fits.zarr", fits, chunks)
    assert main([*command, str(tmp_path / "fits.zarr"), "--out", str(tmp_path / "refused"), "--threads", "4"]) == 2
    capsys.readouterr()
    assert main([*command, str(tmp_path / "fits.zarr"), "--out", str(tmp_path / "one"), "--threads", "1"]) == 0, \
        capsys.readouterr().err
    got = json.loads(capsys.readouterr().out)
    monkeypatch.undo()
    mem, expected = in_memory(tmp_path / "fits.zarr", 6, steps=1)
    assert {k: got[k] for k in expected} == expected
    check_states(mem, tmp_path / "one")


def test_the_threads_a_chunk_refusal_names_flow(tmp_path, capsys, monkeypatch):
    """The refusal of the input's chunks named the threads that decode
    them at a time within the budget, without asking whether the slabs and
    each step's report fit as many: on a 300 x 300 cross-section read in
    chunks of 4 layers it said "they fit 2 at a time", and `--threads 2`
    was then refused for the report. Under every budget, the threads a
    chunk refusal names run the same command to the in-memory flow's
    records, and the line that names none says what else to do."""
    import re

    from isoflow.scale import memory

    v = np.zeros((20, 300, 300), np.uint8)
    v[:, 0, 0] = 1
    v[-1, -1, -1] = 1  # the object spans the whole cross-section
    plain_store(tmp_path / "in.zarr", v, (4, 300, 300))
    mem, expected = in_memory(tmp_path / "in.zarr", 6, steps=1)
    command = ["flow", str(tmp_path / "in.zarr"), "--volumes", ".zarr", "--steps", "1", "--json", "-q"]
    named = set()
    for budget in (6_000_000, 7_800_000, 8_200_000, 8_500_000):
        monkeypatch.setattr(memory, "default_budget", lambda b=budget: b)
        assert main([*command, "--out", str(tmp_path / f"four{budget}"), "--threads", "4"]) == 2
        err = capsys.readouterr().err.strip()
        assert "\n" not in err, err
        fit = re.search(r"they fit (\d+) at a time \(--threads \1, workers=\1\)", err)
        if fit is None:  # the slabs or the report fit no count of threads: their refusal
            assert "workers=" not in err and "crop the volume across x" in err, err
            continue
        named.add(int(fit[1]))
        out = tmp_path / f"fit{budget}"
        assert main([*command, "--out", str(out), "--threads", fit[1]]) == 0, capsys.readouterr().err
        got = json.loads(capsys.readouterr().out)
        assert {k: got[k] for k in expected} == expected
    assert named  # some budget names fewer threads
    monkeypatch.undo()
    check_states(mem, out)


def test_no_command_refusal_names_what_only_python_takes(tmp_path, capsys, monkeypatch):
    """The command line sizes the slabs itself and takes no `slab=` or
    `workers=` alone: under every budget, a refusal of `isoflow flow STORE
    --volumes .zarr` names neither slab= nor flow_chunked(...), and any
    workers it names come with `--threads`."""
    from isoflow.scale import memory

    plain_store(tmp_path / "in.zarr", crossing_volume(), (8, 8, 8))
    refused = 0
    for budget in np.geomspace(4_000, 200_000, 10).astype(int):
        monkeypatch.setattr(memory, "default_budget", lambda b=budget: int(b))
        status = main(["flow", str(tmp_path / "in.zarr"), "--out", str(tmp_path / f"run{budget}"), "--volumes", ".zarr",
                       "--steps", "1", "-q"])
        err = capsys.readouterr().err
        if status:
            refused += 1
            assert status == 2 and len(err.strip().splitlines()) == 1, err
            assert "slab=" not in err and "flow_chunked(" not in err, err
            assert err.count("workers=") == err.count("--threads "), err
    assert 3 <= refused < 10, refused  # the sweep reaches the refusals, and the runs past them


@pytest.mark.parametrize("bad", ["0", "x", "-1", "1.5"])
def test_command_threads_must_be_a_positive_integer(tmp_path, capsys, bad):
    """`flow --threads` is refused as `info --threads` is: one line, exit
    status 2, before the store is read."""
    with pytest.raises(SystemExit) as refused:
        main(["flow", str(tmp_path / "missing.zarr"), "--out", str(tmp_path / "run"), "--volumes", ".zarr", "--threads",
              bad])
    assert refused.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    # said as argparse says the other counts: the value, not the help's name N for it
    said = f"must be 1 or more, got {bad}" if bad.lstrip("-").isdigit() else f"not a whole number of threads: '{bad}'"
    assert err == [f"isoflow flow: error: argument --threads: {said}"]
    assert not (tmp_path / "run").exists()
