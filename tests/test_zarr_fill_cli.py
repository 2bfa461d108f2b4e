"""A zarr store's chunks never written are read as its fill value: where
that value makes them voxels (of the object, or of the label asked for),
every command says so in one warning line with zarr's own count, and says
nothing where every chunk is written or the fill value is 0."""

from __future__ import annotations

import contextlib
import io
import json
import subprocess
import sys
import warnings

import numpy as np
import pytest
import trimesh

from isoflow import analyze_zarr
from isoflow.cli import main

zarr = pytest.importorskip("zarr")


def isoflow(*args, code: str | None = None):
    """stdout, and the warning lines about chunks never written, of the
    command line ARGS (or of the Python ``code``), run in this process:
    the shell is not what is tested (one test runs its command in the
    shell too). Every warning is kept (``always``), so a line said twice
    is seen twice."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        if code:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                exec(code, {})
            lines = [f"{w.category.__name__}: {w.message}" for w in caught]
        else:
            assert main([*map(str, args)]) == 0, err.getvalue()
            lines = err.getvalue().splitlines()
    return out.getvalue(), [line for line in lines if "never written" in line]


def store(path, shape, fill, written):
    """A uint8 store of chunks of 2 along axis 0 whose first ``written``
    chunks hold 0 (1 where the fill value is 0); the others never
    written."""
    z = zarr.create_array(str(path), shape=shape, chunks=(2,) + shape[1:], dtype="u1", fill_value=fill)
    z[:2 * written] = 0 if fill else 1
    return z


def said(path, z, counted):
    missing = z.nchunks - z.nchunks_initialized
    return (f"{path}: {missing} of {z.nchunks} chunks were never written; zarr reads their voxels as the fill "
            f"value {z.fill_value}, so they count as {counted}")


def test_binary_store_of_fill_value_1_says_its_unwritten_chunks_are_voxels(tmp_path):
    z = store(tmp_path / "one.zarr", (8, 6, 6), 1, 2)
    assert (z.nchunks, z.nchunks_initialized) == (4, 2)
    p = subprocess.run([sys.executable, "-m", "isoflow", "info", str(tmp_path / "one.zarr"), "--json"],
                       capture_output=True, text=True)  # as a user's shell runs it
    assert p.returncode == 0, p.stderr
    out, notes = p.stdout, [line for line in p.stderr.splitlines() if "never written" in line]
    assert json.loads(out)["voxels"] == int(np.count_nonzero(z[...])) == 144
    assert notes == [f"isoflow info: warning: {said(tmp_path / 'one.zarr', z, 'voxels of the object')}"]
    out, notes = isoflow("surface", tmp_path / "one.zarr", "-o", tmp_path / "one.ply")
    assert notes == [f"isoflow surface: warning: {said(tmp_path / 'one.zarr', z, 'voxels of the object')}"]

    z[4:] = 0  # every chunk written
    assert z.nchunks_initialized == z.nchunks
    z[5, 2, 2] = 1
    assert isoflow("info", tmp_path / "one.zarr", "--json")[1] == []
    assert isoflow("surface", tmp_path / "one.zarr", "-o", tmp_path / "two.ply")[1] == []

    store(tmp_path / "zero.zarr", (8, 6, 6), 0, 1)
    assert isoflow("info", tmp_path / "zero.zarr", "--json")[1] == []
    assert isoflow("surface", tmp_path / "zero.zarr", "-o", tmp_path / "zero.ply")[1] == []


def test_label_of_a_store_that_is_its_fill_value_says_its_unwritten_chunks_count(tmp_path):
    path = tmp_path / "seg.zarr"
    z = store(path, (8, 4, 4), 2, 1)
    z[:2] = 1
    out, notes = isoflow("info", path, "--label", 2, "--json")
    assert json.loads(out)["voxels"] == int(np.count_nonzero(z[...] == 2)) == 96
    assert notes == [f"isoflow info: warning: {said(path, z, 'label 2')}"]
    out, notes = isoflow("surface", path, "--label", 2, "-o", tmp_path / "two.ply")
    assert notes == [f"isoflow surface: warning: {said(path, z, 'label 2')}"]
    # another label's count does not depend on the chunks never written
    assert isoflow("info", path, "--label", 1, "--json")[1] == []
    assert isoflow("surface", path, "--label", 1, "-o", tmp_path / "one.ply")[1] == []


@pytest.mark.parametrize(("dtype", "fill"), [("i8", 2**53 + 1), ("u8", 2**64 - 3)])
def test_a_fill_value_past_2_53_is_named_and_matched_exactly(tmp_path, dtype, fill):
    """A 64-bit fill value that no float64 holds (2**53 + 1 reads as
    2**53 through a float) is the label zarr itself reads: the warning
    names zarr's own value, and ``--label`` of that value is warned
    about, not its float neighbour."""
    path = tmp_path / "big.zarr"
    z = zarr.create_array(str(path), shape=(4, 4, 4), chunks=(2, 4, 4), dtype=dtype, fill_value=fill)
    z[:2] = 0
    z[0, 1:3, 1:3] = fill
    assert int(z.fill_value) == fill and float(fill) != fill
    out, notes = isoflow("info", path, "--labels", "--json")
    assert {r["label"]: r["voxels"] for r in json.loads(out)["labels"]} == {fill: int(np.count_nonzero(z[...] == fill))}
    assert notes == [f"isoflow info: warning: {said(path, z, f'label {fill}')}"]
    out, notes = isoflow("info", path, "--label", fill, "--json")
    assert json.loads(out)["voxels"] == 4 + 32
    assert notes == [f"isoflow info: warning: {said(path, z, f'label {fill}')}"]


def test_store_read_into_memory_says_its_unwritten_chunks_are_voxels(tmp_path):
    path = tmp_path / "flat.zarr"
    z = store(path, (8, 6), 1, 1)
    assert z.nchunks - z.nchunks_initialized == 3
    code = f"import isoflow; print(isoflow.read_volume({str(path)!r}).voxels)"
    out, notes = isoflow(code=code)
    assert int(out) == int(np.count_nonzero(z[...])) == 36
    assert len(notes) == 1 and notes[0].endswith(said(path, z, "voxels of the object"))
    out, notes = isoflow("flow", path, "--steps", 1, "--json")
    assert notes == [f"isoflow flow: warning: {said(path, z, 'voxels of the object')}"]
    out, notes = isoflow("info", path, "--labels", "--json")
    assert {r["label"]: r["voxels"] for r in json.loads(out)["labels"]} == {1: 36}
    assert notes == [f"isoflow info: warning: {said(path, z, 'label 1')}"]

    z[2:] = 0  # every chunk written
    z[3, 3] = 1
    assert isoflow(code=code) == ("1\n", [])
    assert isoflow("flow", path, "--steps", 1, "--json")[1] == []
    store(tmp_path / "zero.zarr", (8, 6), 0, 1)
    assert isoflow(code=f"import isoflow; print(isoflow.read_volume({str(tmp_path / 'zero.zarr')!r}).voxels)") == (
        "12\n", [])


def test_analyze_zarr_says_its_unwritten_chunks_are_voxels_once(tmp_path):
    from isoflow import IsoflowWarning, analyze_zarr

    z = store(tmp_path / "one.zarr", (8, 6, 6), 1, 1)
    assert z.nchunks - z.nchunks_initialized == 3
    with pytest.warns(IsoflowWarning) as caught:
        report = analyze_zarr(tmp_path / "one.zarr")
    assert report["voxels"] == int(np.count_nonzero(z[...])) == 6 * 6 * 6
    assert [str(w.message) for w in caught] == [said(tmp_path / "one.zarr", z, "voxels of the object")]
    assert caught[0].filename == __file__  # the caller's line, not isoflow's


def shard_holds(path, key, chunk_bytes, chunks_per_shard):
    """The inner chunks a shard file holds, from its size alone: zarr v3
    sharding stores the inner chunks' bytes (uncompressed here) and an
    index of 16 bytes per inner chunk and a 4-byte checksum."""
    size = (path / key).stat().st_size - (16 * chunks_per_shard + 4)
    assert size % chunk_bytes == 0
    return size // chunk_bytes


def test_sharded_store_counts_the_chunks_never_written_inside_a_written_shard(tmp_path):
    """A written shard may hold some of its inner chunks only (zarr leaves
    out the others, read as the fill value): those count as never written
    too, not the missing shards alone."""
    path = tmp_path / "sharded.zarr"
    z = zarr.create_array(str(path), shape=(8, 6, 6), chunks=(2, 6, 6), shards=(4, 6, 6), dtype="u1",
                          fill_value=1, compressors=None)
    z[:2] = 0  # the first shard's first chunk: three of the four chunks never written
    assert sorted(p.name for p in (path / "c").iterdir()) == ["0"]  # one shard of two stored
    assert shard_holds(path, "c/0/0/0", 2 * 6 * 6, 2) == 1
    assert z.nchunks - z.nchunks_initialized == 2  # zarr takes the stored shard's chunks as written
    out, notes = isoflow("info", path, "--json")
    assert json.loads(out)["voxels"] == int(np.count_nonzero(z[...])) == 3 * 2 * 6 * 6
    said = (f"{path}: 3 of 4 chunks were never written; zarr reads their voxels as the fill value 1, so they "
            "count as voxels of the object")
    assert notes == [f"isoflow info: warning: {said}"]
    assert isoflow("surface", path, "-o", tmp_path / "s.ply")[1] == [f"isoflow surface: warning: {said}"]
    out, notes = isoflow(code=f"import isoflow; print(isoflow.read_volume({str(path)!r}).voxels)")
    assert int(out) == 216 and len(notes) == 1 and notes[0].endswith(said)
    z[2:] = 0
    assert isoflow("info", path, "--json")[1] == []


def test_sharded_store_written_whole_whose_last_shard_reaches_past_it_says_nothing(tmp_path):
    """zarr's count of chunks written (stored shards times chunks per
    shard) takes in the chunks of the last shard that lie past the array:
    more than the array has, which read as -1 shards never written."""
    edge = tmp_path / "edge.zarr"  # 3 chunks in 2 shards, the second shard's second chunk past the array
    z = zarr.create_array(str(edge), shape=(6, 6, 6), chunks=(2, 6, 6), shards=(4, 6, 6), dtype="u1",
                          fill_value=1, compressors=None)
    z[:] = 0
    z[3, 3, 3] = 1
    assert (z.nchunks, z.nchunks_initialized) == (3, 4)
    assert isoflow("info", edge, "--json")[1] == []
    assert isoflow("surface", edge, "-o", tmp_path / "e.ply")[1] == []


def time_series(path, shards=None, ome=False):
    """A 4D store of fill value 1, chunks of 2 along z and 1 along t: time
    point 0 written whole but for a cube of 8 voxels of 1, 1 in its first
    chunk alone, 2 and 3 never written. A plain array (x, y, z, t), or
    (``ome``) an OME-Zarr image of axes t, c, z, y, x (c of length 1).
    Returns the array and a function of a time point giving its voxels."""
    if ome:
        g = zarr.open_group(str(path), mode="w")
        z = g.create_array("0", shape=(4, 1, 8, 6, 6), chunks=(1, 1, 2, 6, 6), dtype="u1", fill_value=1)
        g.attrs["multiscales"] = [{"axes": [{"name": "t", "type": "time"}, {"name": "c", "type": "channel"},
                                            "z", "y", "x"], "datasets": [{"path": "0"}]}]
        z[0] = 0
        z[0, 0, 2:4, 2:4, 2:4] = 1
        z[1, 0, :2] = 0
        return z, lambda time: z[time]
    z = zarr.create_array(str(path), shape=(6, 6, 8, 4), chunks=(6, 6, 2, 1), shards=shards, dtype="u1",
                          fill_value=1, compressors=None)
    z[..., 0] = 0
    z[2:4, 2:4, 2:4, 0] = 1
    z[:, :, :2, 1] = 0
    return z, lambda time: z[..., time]


@pytest.mark.parametrize(("shards", "ome"), [(None, False), ((6, 6, 4, 2), False), (None, True)])
def test_one_time_point_says_how_many_of_its_own_chunks_were_never_written(tmp_path, shards, ome):
    """``read_volume(STORE, time=T)`` and ``read_labels(STORE, time=T)``
    read that time point's chunks alone and count its chunks never
    written, told apart by the time axis's index in their keys (in the
    shard's index for a sharded store); a time point written whole says
    nothing."""
    path = tmp_path / "series.zarr"
    z, at = time_series(path, shards, ome)
    if shards is None:  # the time point's chunks are those whose key has T as the time axis's index
        chunks = path / "0" / "c" if ome else path / "c"
        keys = [p.relative_to(chunks).parts for p in chunks.rglob("*") if p.is_file()]
        assert sorted(k[0 if ome else 3] for k in keys) == ["0"] * 4 + ["1"]
    else:  # shard c/0/0/Z/0 holds time points 0 and 1; no shard of 2 and 3
        assert sorted(p.name for p in (path / "c/0/0/0").iterdir()) == ["0"]
        assert sorted(p.name for p in (path / "c/0/0/1").iterdir()) == ["0"]
        assert shard_holds(path, "c/0/0/0/0", 6 * 6 * 2, 4) == 2 + 1  # time point 0's two, 1's one
        assert shard_holds(path, "c/0/0/1/0", 6 * 6 * 2, 4) == 2  # time point 0's
    chunk = 6 * 6 * 2

    def read(time, labels=False):
        call = f"(isoflow.read_labels({str(path)!r}, time={time}).array == 1).sum()" if labels else \
            f"isoflow.read_volume({str(path)!r}, time={time}).voxels"
        return isoflow(code=f"import isoflow; print({call})")

    for time, missing in [(1, 3), (2, 4)]:  # the chunks left unwritten, read back as the fill value
        assert int(np.count_nonzero(at(time) == 1)) == missing * chunk
        said = (f"{path}: {missing} of 4 chunks were never written; zarr reads their voxels as the fill value 1, "
                "so they count as ")
        for labels, counted in [(False, "voxels of the object"), (True, "label 1")]:
            out, notes = read(time, labels)
            assert int(out) == missing * chunk
            assert len(notes) == 1 and notes[0].endswith(said + counted), notes
    assert int(np.count_nonzero(at(0))) == 8
    assert read(0) == ("8\n", [])


def test_a_block_of_one_label_is_offered_its_value_as_the_label(tmp_path, capsys):
    """A store of labels refused block by block, whose refusing block holds
    0 and one value alone (255), names that value as the label that
    selects it (as the block's), and --label 255 then counts its voxels.
    A block of two labels still says N."""
    labels = np.zeros((8, 6, 6), np.uint8)
    labels[1:3, 1:5, 1:5] = 255
    labels[5:7, 1:5, 1:5] = 7  # in the second block of chunks: the first holds 0 and 255 alone
    zarr.create_array(str(tmp_path / "m.zarr"), shape=labels.shape, chunks=(4, 6, 6), dtype="u1")[:] = labels
    for command in (["info"], ["surface", "-o", str(tmp_path / "m.ply")]):
        assert main([command[0], str(tmp_path / "m.zarr"), *command[1:]]) == 2
        err = capsys.readouterr().err
        assert "select one label with --label 255 (label=255; 255 is the one value other than 0 in that block)" in err
        assert "--label N" not in err, err
        assert not (tmp_path / "m.ply").exists()
    assert main(["info", str(tmp_path / "m.zarr"), "--label", "255", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["voxels"] == np.count_nonzero(labels == 255)
    two = (labels == 255) * np.uint8(2)
    two[2, 1, 1] = 3
    zarr.create_array(str(tmp_path / "two.zarr"), shape=two.shape, chunks=(4, 6, 6), dtype="u1")[:] = two
    assert main(["info", str(tmp_path / "two.zarr")]) == 2
    assert "select one label with --label N (label=N)" in capsys.readouterr().err


@pytest.mark.parametrize("value", [255, -1], ids=["uint8 0/255", "int16 0/-1"])
def test_a_store_of_0_and_one_value_is_its_mask_block_by_block(tmp_path, value):
    """A mask written 0/255 in a .zarr store, read block by block by
    ``info`` and ``surface``, is the mask of 255, as the same array in an
    .npy is (and as ``read_volume`` reads the store whole): it was refused
    block by block as "not a binary volume". The first block of chunks
    holds 0 alone, so the 255 is met in the pass. The report is
    scikit-image's Euler number and the voxel count of the mask, the
    surface trimesh's closed mesh of its volume; ``analyze_zarr`` gives
    the same."""
    from skimage.measure import euler_number

    dtype = np.uint8 if value == 255 else np.int16
    mask = np.zeros((12, 10, 9), bool)
    mask[5:11, 2:8, 2:7] = True
    mask[7, 4, 4] = False  # a cavity
    stored = (mask * value).astype(dtype)
    zarr.create_array(str(tmp_path / "m.zarr"), shape=stored.shape, chunks=(4, 5, 5), dtype=dtype)[:] = stored
    np.save(tmp_path / "m.npy", stored)
    want = {"voxels": int(np.count_nonzero(mask)), "euler_characteristic": int(euler_number(mask, connectivity=1))}
    reports = {}
    for name in ("m.zarr", "m.npy"):
        done = subprocess.run([sys.executable, "-m", "isoflow", "info", str(tmp_path / name), "--json"],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        report = json.loads(done.stdout)
        assert {k: report[k] for k in want} == want and report["betti"] == [1, 0, 1]
        reports[name] = {k: v for k, v in report.items() if k != "input"}
        out = tmp_path / f"{name}.stl"
        done = subprocess.run([sys.executable, "-m", "isoflow", "surface", str(tmp_path / name), "-o", str(out)],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        mesh = trimesh.load(out)
        assert mesh.is_watertight and mesh.euler_number == 4 and mesh.volume == pytest.approx(want["voxels"])
    assert reports["m.zarr"] == reports["m.npy"]
    assert analyze_zarr(tmp_path / "m.zarr").betti == [1, 0, 1]


def test_a_block_of_several_labels_is_refused_without_reading_the_store_again(tmp_path, monkeypatch):
    """A store of 0 and one other value is that value's mask: the readers
    block by block look for it once a block holds another value. Where
    that block holds several labels, the store is no mask whatever the
    other blocks hold, and is refused without a pass over it (a pass over
    a store of terabytes before a refusal)."""
    zarr = pytest.importorskip("zarr")
    from isoflow.mesh.formats import omezarr
    from isoflow.scale.arrays import NotBinary

    labels = np.zeros((6, 6, 6), np.uint8)
    labels[1, 1, 1], labels[2, 2, 2] = 5, 9
    zarr.create_array(str(tmp_path / "l.zarr"), data=labels, chunks=(3, 3, 3))
    store = omezarr.open_store(tmp_path / "l.zarr")
    monkeypatch.setattr(omezarr.StoreArray, "lazy", lambda self: pytest.fail("the store was read again"))
    assert omezarr.one_value_of_store(store, NotBinary("l.zarr: two labels", value=None)) is None
    monkeypatch.undo()
    looked = []
    monkeypatch.setattr(omezarr.StoreArray, "lazy", lambda self, lazy=omezarr.StoreArray.lazy: looked.append(1) or
                        lazy(self))
    with pytest.raises(NotBinary) as refused:  # the first block holds 5 and 9
        omezarr.analyze_zarr(tmp_path / "l.zarr")
    assert refused.value.value is None and not looked


def test_the_mask_search_stops_at_the_first_slab_holding_another_label():
    """Where the refused block holds 0 and one label v, the store is read
    for v alone (only_values), a slab of blocks at a time, stopping at the
    first slab that holds another label: a label image of one label per
    block (big grains) is refused after a few blocks, not a whole read."""
    dask_array = pytest.importorskip("dask.array")
    from isoflow.mesh.formats.omezarr import CHECKED_BLOCKS, only_values

    class Counted:
        """An array whose reads are counted, as a store's chunks are read."""

        def __init__(self, values):
            self.values, self.shape, self.dtype, self.ndim, self.reads = values, values.shape, values.dtype, 3, 0

        def __getitem__(self, key):
            self.reads += 1
            return self.values[key]

    grains = np.zeros((20, 8, 8), np.uint8)
    grains[:, :4, :4] = 5
    mask = Counted(grains.copy())
    assert only_values(dask_array.from_array(mask, chunks=(1, 2, 2), asarray=False), 5)
    assert mask.reads >= 20 * 4 * 4  # a mask: every block read (and a slice dask reads for its type)
    grains[1, 6, 6] = 9  # another label in the first slabs
    labels = Counted(grains)
    assert not only_values(dask_array.from_array(labels, chunks=(1, 2, 2), asarray=False), 5)
    assert labels.reads <= CHECKED_BLOCKS + 1 < 20 * 4 * 4
