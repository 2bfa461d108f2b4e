"""isoflow.scale.chunks: what waits for zarr's I/O thread."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest

zarr = pytest.importorskip("zarr")


def test_settle_zarr_io_waits_for_a_write_an_interrupt_left_running(tmp_path):
    """A zarr call's coroutine runs on zarr's thread; an interrupted caller
    stops waiting but the write goes on. settle_zarr_io returns only once it
    is done, so that a store removed after it stays removed."""
    import zarr.core.sync as zsync

    from isoflow.scale.chunks import settle_zarr_io

    zarr.create_array(str(tmp_path / "a.zarr"), shape=(4,), dtype=np.uint8)  # zarr's thread started
    late = tmp_path / "late.txt"

    async def write_late() -> None:  # a write still under way when the caller was interrupted
        await asyncio.sleep(0.3)
        late.write_text("written")

    asyncio.run_coroutine_threadsafe(write_late(), zsync.loop[0])
    assert not late.exists()
    settle_zarr_io()
    assert late.read_text() == "written"


@pytest.mark.parametrize("without_sync", [False, True])
def test_store_keys_and_shard_indexes_as_zarr_counts_them(tmp_path, monkeypatch, without_sync):
    """The keys a store holds and the written inner chunks of its shards,
    through zarr's own synchronous runner, and through a loop of their own
    where a zarr has no ``zarr.core.sync`` (not among its documented API):
    the chunks zarr itself lists as stored (``nchunks_initialized``) and
    the chunks written."""
    import sys

    from isoflow.scale.chunks import shard_indexes, store_keys

    plain = zarr.create_array(str(tmp_path / "p.zarr"), shape=(6, 4), chunks=(2, 4), dtype=np.uint8)
    plain[2:4] = 1
    sharded = zarr.create_array(str(tmp_path / "s.zarr"), shape=(8, 2), chunks=(2, 2), shards=(4, 2), dtype=np.uint8)
    sharded[2:4] = 1  # the first shard's second inner chunk
    if without_sync:
        monkeypatch.setitem(sys.modules, "zarr.core.sync", None)  # its import then fails
    keys = store_keys(plain)
    assert sorted(k for k in keys if k != "zarr.json") == ["c/1/0"]
    assert len(keys) - 1 == plain.nchunks_initialized
    (inner,) = shard_indexes(sharded, [(0, 0)], [2, 1])
    assert inner.ravel().tolist() == [False, True]
