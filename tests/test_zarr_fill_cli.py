"""A zarr store's chunks never written are read as its fill value: where
that value makes them voxels (of the object, or of the label asked for),
every command says so in one warning line with zarr's own count, and says
nothing where every chunk is written or the fill value is 0."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

zarr = pytest.importorskip("zarr")


def isoflow(*args, code: str | None = None):
    """stdout, and the warning lines about chunks never written, of
    ``python -m isoflow ARGS`` (or of ``python -c CODE``)."""
    command = [sys.executable, "-c", code] if code else [sys.executable, "-m", "isoflow", *map(str, args)]
    p = subprocess.run(command, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    return p.stdout, [line for line in p.stderr.splitlines() if "never written" in line]


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
    out, notes = isoflow("info", tmp_path / "one.zarr", "--json")
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
