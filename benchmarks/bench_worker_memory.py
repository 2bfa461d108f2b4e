"""Peak memory of a dask.distributed worker running a store's blocks, against
what the memory check counts for the worker.

    python benchmarks/bench_worker_memory.py                     # 1 and 2 threads, 256^3 and 384^3
    python benchmarks/bench_worker_memory.py --threads 1 --json benchmarks/results/worker_memory.json

A LocalCluster of one worker process (``--threads`` threads, a memory limit
of 16 GB that refuses nothing) runs ``surface`` of a store block by block
(``write_surface_blocks``) and ``info``'s ``analyze_chunked`` on bool
porous fields (a smoothed random field, upsampled 4x) in chunks of 64^3
and 128^3, with blocks equal to the chunks and blocks of 64^3 in chunks
of 128^3. Both are run first on a small store, so that the worker has
loaded the compiled passes; then the worker's heap is trimmed, its peak
resident memory reset (``/proc/self/clear_refs``), the work run, and the
rise of ``VmHWM`` over the resident memory before it is the worker's
peak. ``estimate`` is what ``isoflow.scale.memory.check_workers_fit`` is
asked to fit in the worker's limit: a task's bytes times the worker's
threads, beside what the worker holds (the largest of a run's checks:
surface checks its counting and its writing pass). ``ratio`` is the
estimate over the peak (from 0.95 to 2 is the aim). Linux only.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

#: (size, chunk, block_shape or None for the chunks)
CASES = ((256, 64, None), (256, 128, None), (256, 128, (64, 64, 64)), (384, 128, None))


def porous(n: int, seed: int = 0) -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    field = gaussian_filter(np.random.default_rng(seed).standard_normal((n // 4,) * 3).astype(np.float32), 2)
    return np.repeat(np.repeat(np.repeat(field > 0, 4, 0), 4, 1), 4, 2)


def status(key: str) -> int:
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))


def reset_peak() -> int:
    """On the worker: its heap trimmed, its peak reset; its resident memory."""
    import ctypes
    import gc

    gc.collect()
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")
    return status("VmRSS")


def measure(threads: int, stores: dict, small: str, out: Path) -> list[dict]:
    import distributed
    import zarr

    from isoflow import analyze_chunked
    from isoflow.mesh.surface_blocks import write_surface_blocks
    from isoflow.scale import memory

    counted: list[int] = []

    def record(client, per_task, what, hint="", held=0):
        counted.append(per_task * memory.worker_room(client)[1] + held)

    memory.check_workers_fit = record
    rows = []
    with distributed.LocalCluster(n_workers=1, processes=True, threads_per_worker=threads, memory_limit="16GB",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        write_surface_blocks(zarr.open_array(small, mode="r"), out / "small.ply", scheduler=client, force=True)
        analyze_chunked(zarr.open_array(small, mode="r"), 6, scheduler=client)
        for n, chunk, block in CASES:
            for what in ("surface", "info"):
                counted.clear()
                (before,) = client.run(reset_peak).values()
                z = zarr.open_array(stores[n, chunk], mode="r")
                if what == "surface":
                    write_surface_blocks(z, out / "out.ply", scheduler=client, force=True, block_shape=block)
                else:
                    analyze_chunked(z, 6, scheduler=client, block_shape=block)
                (after,) = client.run(status, "VmHWM").values()
                peak, estimate = after - before, max(counted)
                row = {"what": what, "size": n, "chunks": chunk, "blocks": list(block or (chunk,) * 3),
                       "threads": threads, "peak_mib": round(peak / 2**20, 1),
                       "estimate_mib": round(estimate / 2**20, 1), "ratio": round(estimate / peak, 2)}
                print(json.dumps(row), flush=True)
                rows.append(row)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="threads of the worker")
    ap.add_argument("--json", type=Path, help="write the rows here")
    args = ap.parse_args(argv)
    if not sys.platform.startswith("linux"):
        ap.error("the peak is read from /proc/self/status (Linux)")
    import zarr

    tmp = Path(tempfile.mkdtemp(prefix="isoflow-worker-memory-"))
    stores = {}
    for n, chunk, _ in CASES:
        if (n, chunk) not in stores:
            stores[n, chunk] = str(tmp / f"porous-{n}-{chunk}.zarr")
            zarr.create_array(store=stores[n, chunk], shape=(n,) * 3, chunks=(chunk,) * 3, dtype=bool)[...] = porous(n)
    small = str(tmp / "small.zarr")
    zarr.create_array(store=small, shape=(40, 40, 40), chunks=(16, 16, 16), dtype=bool)[5:30, 5:30, 5:30] = True
    rows = [row for threads in args.threads for row in measure(threads, stores, small, tmp)]
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
