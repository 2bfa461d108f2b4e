"""Peak memory of the worker processes that run a store's blocks, against
what the memory check counts for them: a dask.distributed worker's, and
the processes scheduler's with the process that calls it.

    python benchmarks/bench_worker_memory.py                     # 1 and 2 threads, every case
    python benchmarks/bench_worker_memory.py --json benchmarks/results/worker_memory.json

Each case is a bool porous field (a smoothed random field, upsampled 4x)
stored in chunks of ``chunk``^3 and summed in blocks of the chunks, or of
``block_shape`` (smaller than the chunks), in fresh processes:

* ``distributed``: a LocalCluster of one worker process (``--threads``
  threads, a memory limit of 16 GB that refuses nothing; its nanny starts
  it with ``MALLOC_TRIM_THRESHOLD_`` set) runs ``surface`` of a store
  block by block (``write_surface_blocks``) and ``info``'s
  ``analyze_chunked``. Both are run first on a small store, so that the
  worker has loaded the compiled passes; then the worker's heap is
  trimmed, its peak resident memory reset (``/proc/self/clear_refs``),
  the work run, and the rise of ``VmHWM`` over the resident memory before
  it is the worker's peak. ``estimate`` is what
  ``isoflow.scale.memory.check_workers_fit`` is asked to fit in the
  worker's limit: a task's bytes times the worker's threads, beside what
  the worker holds (the largest of a run's checks: surface checks its
  counting and its writing pass).
* ``processes``: ``info`` on dask's processes scheduler (``--threads``
  worker processes, which dask spawns afresh for each layer of blocks),
  run first on a small store in the calling process. The peak is the
  rise of the calling process's ``VmHWM`` (reset as above) plus the
  threads times the largest worker process's own peak: its ``VmHWM`` less
  the file pages it maps (the libraries' code, shared with the calling
  process), read as it exits (the peaks of one layer's processes are
  added as if they came at once). ``estimate`` is what the check holds to
  the memory budget (``isoflow.digital.outofcore.store_memory``, the
  processes scheduler's terms).

* ``threads``: ``surface`` on this process's threads (dask's threaded
  scheduler, ``--threads`` threads) in a fresh process, the compiled passes
  loaded on a small store first, the heap trimmed and the peak reset as
  above; ``estimate`` is what ``isoflow.scale.memory.check_fits`` is asked
  to hold to the budget (the larger of the two passes' checks).

With ``--repeat N`` each case runs N times afresh and the row gives the
highest peak, with every run's in ``peaks_mib``: on this process's
threads the allocator keeps a varying share of what was freed (a 512^3
store's surface peaked at 312 to 428 MiB on one thread).

``ratio`` is the estimate over the peak (from 1.05 to 1.5 is the aim).
Linux only.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

#: (size, chunk, block_shape or None for the chunks) of surface's stores: blocks of 64^3, 128^3 and 256^3, as
#: large as the chunks and smaller
SURFACE_CASES = ((256, 64, None), (256, 128, None), (384, 128, None), (512, 256, None), (256, 128, (64, 64, 64)))
#: ... and of info's: blocks of 64^3, 128^3 and 256^3, as large as the chunks and smaller
INFO_CASES = ((256, 64, None), (256, 128, None), (512, 128, None), (512, 256, None), (256, 128, (64, 64, 64)),
              (512, 256, (128, 128, 128)))

#: written where the processes scheduler's workers import it: each worker
#: process notes its own peak as it exits (dask's worker initializer)
NOTE = """
import atexit, os

def note():
    def write():
        with open("/proc/self/status") as fh:
            got = {k: int(v.split()[0]) * 1024 for k, _, v in (line.partition(":") for line in fh)
                   if k in ("VmHWM", "RssFile", "RssShmem")}
        with open(os.environ["ISOFLOW_BENCH_PEAKS"], "a") as fh:
            fh.write(f"{got['VmHWM'] - got['RssFile'] - got['RssShmem']}\\n")
    atexit.register(write)
"""

PROCESSES = """
import ctypes, json, os, sys
import dask
from isoflow.digital import outofcore
from isoflow.digital.outofcore import analyze_zarr_volume
import peak_note

def status(key):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))

if __name__ == "__main__":
    path, small, block, threads = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    dask.config.set({"multiprocessing.initializer": peak_note.note})
    analyze_zarr_volume(small, 6, threads=threads, scheduler="processes")
    checked, asked = outofcore._tasks_that_fit, []

    def record(workers, threads, need, *args):
        asked.append(threads * need.block + need.faces + need.kept)
        return checked(workers, threads, need, *args)

    outofcore._tasks_that_fit = record
    open(os.environ["ISOFLOW_BENCH_PEAKS"], "w").close()
    ctypes.CDLL("libc.so.6").malloc_trim(0)
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")
    before = status("VmRSS")
    shape = None if block == 0 else (block,) * 3
    analyze_zarr_volume(path, 6, threads=threads, block_shape=shape, scheduler="processes")
    parent = status("VmHWM") - before
    with open(os.environ["ISOFLOW_BENCH_PEAKS"]) as fh:
        process = max(int(line) for line in fh)
    print(json.dumps({"parent": parent, "process": process, "estimate": asked[-1]}))
"""


#: ``surface`` on this process's threads (dask's threaded scheduler), in a fresh process: the compiled passes
#: loaded on a small store, the heap trimmed and the peak reset as on a worker; the check's estimate is what
#: ``isoflow.scale.memory.check_fits`` is asked to hold to the budget (the larger of the two passes')
THREADS = """
import ctypes, json, sys
import zarr
from isoflow.mesh.surface_blocks import write_surface_blocks
from isoflow.scale import memory

def status(key):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))

path, small, block, threads, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
write_surface_blocks(zarr.open_array(small, mode="r"), out, threads=threads, force=True)
asked = []
memory.check_fits = lambda need, *args, **kwargs: asked.append(need)
ctypes.CDLL("libc.so.6").malloc_trim(0)
with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")
before = status("VmRSS")
write_surface_blocks(zarr.open_array(path, mode="r"), out, threads=threads, force=True,
                     block_shape=None if block == 0 else (block,) * 3)
print(json.dumps({"peak": status("VmHWM") - before, "estimate": max(asked)}))
"""


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


def on_a_worker(what: str, store: str, block, threads: int, small: str, out: Path) -> dict:
    """The peak of a fresh dask.distributed worker running ``what`` of the
    store, and what the check counted for it."""
    import distributed
    import zarr

    from isoflow import analyze_chunked
    from isoflow.mesh.surface_blocks import write_surface_blocks
    from isoflow.scale import memory

    counted: list[int] = []
    checking = memory.check_workers_fit

    def record(client, per_task, what, hint="", held=0):
        counted.append(per_task * memory.worker_room(client)[1] + held)

    memory.check_workers_fit = record
    try:
        with distributed.LocalCluster(n_workers=1, processes=True, threads_per_worker=threads, memory_limit="16GB",
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            if what == "surface":
                write_surface_blocks(zarr.open_array(small, mode="r"), out / "small.ply", scheduler=client, force=True)
            else:
                analyze_chunked(zarr.open_array(small, mode="r"), 6, scheduler=client)
            counted.clear()
            (before,) = client.run(reset_peak).values()
            z = zarr.open_array(store, mode="r")
            if what == "surface":
                write_surface_blocks(z, out / "out.ply", scheduler=client, force=True, block_shape=block)
            else:
                analyze_chunked(z, 6, scheduler=client, block_shape=block)
            (after,) = client.run(status, "VmHWM").values()
    finally:
        memory.check_workers_fit = checking
    return {"peak": after - before, "estimate": max(counted)}


def on_threads(store: str, block, threads: int, small: str, tmp: Path) -> dict:
    """The peak of surface on this machine's threads in a fresh process, and
    what the check counted."""
    script = tmp / "threads.py"
    script.write_text(THREADS)
    side = 0 if block is None else block[0]
    p = subprocess.run([sys.executable, str(script), store, small, str(side), str(threads), str(tmp / "threads.ply")],
                       capture_output=True, text=True, check=True)
    return json.loads(p.stdout)


def on_processes(store: str, block, threads: int, small: str, tmp: Path) -> dict:
    """The peak of info on dask's processes scheduler in a fresh process
    (its own rise and its worker processes'), and what the check counted."""
    (tmp / "peak_note.py").write_text(NOTE)
    env = {**os.environ, "ISOFLOW_BENCH_PEAKS": str(tmp / "peaks.txt"),
           "PYTHONPATH": os.pathsep.join(p for p in (str(tmp), os.environ.get("PYTHONPATH", "")) if p)}
    script = tmp / "processes.py"
    script.write_text(PROCESSES)
    side = 0 if block is None else block[0]
    p = subprocess.run([sys.executable, str(script), store, small, str(side), str(threads)], capture_output=True,
                       text=True, check=True, env=env)
    got = json.loads(p.stdout)
    return {"peak": got["parent"] + threads * got["process"], "estimate": got["estimate"],
            "parent_mib": round(got["parent"] / 2**20, 1), "process_mib": round(got["process"] / 2**20, 1)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="threads of the worker, worker processes")
    ap.add_argument("--schedulers", nargs="+", default=["distributed", "processes", "threads"],
                    choices=["distributed", "processes", "threads"])
    ap.add_argument("--what", nargs="+", default=["surface", "info"], choices=["surface", "info"],
                    help="the work on a dask.distributed worker (the processes scheduler runs info, the threads "
                         "surface: bench_store_estimate.py measures info there)")
    ap.add_argument("--repeat", type=int, default=1,
                    help="fresh runs of each case; the row gives the highest peak (and each run's)")
    ap.add_argument("--json", type=Path, help="write the rows here")
    args = ap.parse_args(argv)
    if not sys.platform.startswith("linux"):
        ap.error("the peak is read from /proc/self/status (Linux)")
    import zarr

    tmp = Path(tempfile.mkdtemp(prefix="isoflow-worker-memory-"))
    stores = {}
    for n, chunk, _ in SURFACE_CASES + INFO_CASES:
        if (n, chunk) not in stores:
            stores[n, chunk] = str(tmp / f"porous-{n}-{chunk}.zarr")
            zarr.create_array(store=stores[n, chunk], shape=(n,) * 3, chunks=(chunk,) * 3, dtype=bool)[...] = porous(n)
    small = str(tmp / "small.zarr")
    zarr.create_array(store=small, shape=(40, 40, 40), chunks=(16, 16, 16), dtype=bool)[5:30, 5:30, 5:30] = True
    runs = [("distributed", what) for what in args.what if "distributed" in args.schedulers]
    runs += [("processes", "info")] if "processes" in args.schedulers and "info" in args.what else []
    runs += [("threads", "surface")] if "threads" in args.schedulers and "surface" in args.what else []
    rows = []
    for threads in args.threads:
        for scheduler, what in runs:
            for n, chunk, block in SURFACE_CASES if what == "surface" else INFO_CASES:
                runs_of = []
                for _ in range(args.repeat):
                    if scheduler == "distributed":
                        runs_of.append(on_a_worker(what, stores[n, chunk], block, threads, small, tmp))
                    elif scheduler == "threads":
                        runs_of.append(on_threads(stores[n, chunk], block, threads, small, tmp))
                    else:
                        runs_of.append(on_processes(stores[n, chunk], block, threads, small, tmp))
                # the check must cover the highest peak: the allocator's share differs between runs
                peaks = [g["peak"] for g in runs_of]
                got = dict(max(runs_of, key=lambda g: g["peak"]))
                peak, estimate = got.pop("peak"), got.pop("estimate")
                row = {"scheduler": scheduler, "what": what, "size": n, "chunks": chunk,
                       "blocks": list(block or (chunk,) * 3), "threads": threads, "peak_mib": round(peak / 2**20, 1),
                       "estimate_mib": round(estimate / 2**20, 1), "ratio": round(estimate / peak, 2), **got}
                if args.repeat > 1:
                    row["peaks_mib"] = [round(p / 2**20, 1) for p in peaks]
                print(json.dumps(row), flush=True)
                rows.append(row)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
