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
