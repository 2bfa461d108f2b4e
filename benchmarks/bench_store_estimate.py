"""Peak memory of ``info`` of a zarr store on this machine's threads, against
the estimate its memory check holds to the budget.

    python benchmarks/bench_store_estimate.py                           # every case, 1 and 2 threads
    python benchmarks/bench_store_estimate.py --json benchmarks/results/store_estimate.json

Each case is a porous bool field (a smoothed random field, upsampled 4x)
stored in chunks of ``chunk``^3 and summed in blocks of ``block``^3 (the
chunks where they are equal) on ``threads`` threads of dask's threaded
scheduler, in a fresh process: the compiled passes are loaded on a small
store first, the heap is trimmed (``malloc_trim``), the kernel's peak reset
(``/proc/self/clear_refs``), the store summed, and the rise of ``VmHWM``
over the resident memory before it is the peak. ``estimate`` is what the
check holds to the budget (``isoflow.digital.outofcore.store_memory``):
``blocks_mib`` the ``threads`` blocks at work and the blocks the allocator
keeps, ``faces_mib`` the layers' faces. The blocks summed at a time are
those a budget of the estimate lets run (``threads``; zarr's second task
per thread is left out first). ``ratio`` is the estimate over the peak:
at least 1 is what the check needs. Linux only; the allocator's share
depends on it (glibc's, run as it is, or with ``MALLOC_TRIM_THRESHOLD_``
in the environment, as dask.distributed's nanny runs its workers).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

#: (size, chunk, block): the volume's side, its chunks' and its blocks'
CASES = ((256, 64, 64), (384, 64, 64), (640, 64, 64), (256, 128, 128), (384, 128, 128), (640, 128, 128),
         (384, 64, 128), (512, 256, 256), (512, 128, 256), (768, 128, 256), (256, 128, 64), (512, 256, 128))

MEASURE = """
import ctypes, json, sys, tempfile
import zarr
from isoflow.digital import outofcore
from isoflow.digital.outofcore import analyze_zarr_volume

def status(key):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))

path, block, threads = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
small = tempfile.mkdtemp() + "/small.zarr"
zarr.create_array(store=small, shape=(40, 40, 40), chunks=(16, 16, 16), dtype=bool)[5:30, 5:30, 5:30] = True
analyze_zarr_volume(small, 6, threads=threads)
checked = outofcore._tasks_that_fit
asked = []

def record(workers, threads, need, *args):
    asked.append((threads * need.block + need.kept, need.faces))
    # as many at a time as a budget of the estimate lets run (zarr's second task per thread left out)
    return min(checked(workers, threads, need, *args), threads)

outofcore._tasks_that_fit = record
ctypes.CDLL("libc.so.6").malloc_trim(0)
with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")
before = status("VmRSS")
analyze_zarr_volume(path, 6, threads=threads, block_shape=(block,) * 3)
peak = status("VmHWM") - before
blocks, faces = asked[-1]
print(json.dumps({"peak": peak, "blocks": blocks, "faces": faces}))
"""


def porous(n: int, seed: int = 0):
    import numpy as np
    from scipy.ndimage import gaussian_filter

    field = gaussian_filter(np.random.default_rng(seed).standard_normal((n // 4,) * 3).astype(np.float32), 2)
    return np.repeat(np.repeat(np.repeat(field > 0, 4, 0), 4, 1), 4, 2)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2], help="threads of the scheduler")
    ap.add_argument("--cases", nargs="+", help="SIZE:CHUNK:BLOCK (default: every case)")
    ap.add_argument("--json", type=Path, help="write the rows here")
    args = ap.parse_args(argv)
    if not sys.platform.startswith("linux"):
        ap.error("the peak is read from /proc/self/status (Linux)")
    import zarr

    cases = [tuple(map(int, c.split(":"))) for c in args.cases] if args.cases else CASES
    tmp = Path(tempfile.mkdtemp(prefix="isoflow-store-estimate-"))
    rows = []
    for n, chunk, block in cases:
        path = tmp / f"porous-{n}-{chunk}.zarr"
        if not path.exists():
            zarr.create_array(store=str(path), shape=(n,) * 3, chunks=(chunk,) * 3, dtype=bool)[...] = porous(n)
        for threads in args.threads:
            p = subprocess.run([sys.executable, "-c", MEASURE, str(path), str(block), str(threads)],
                               capture_output=True, text=True, check=True)
            got = json.loads(p.stdout)
            estimate = got["blocks"] + got["faces"]
            row = {"size": n, "chunks": chunk, "blocks": block, "threads": threads,
                   "peak_mib": round(got["peak"] / 2**20, 1), "estimate_mib": round(estimate / 2**20, 1),
                   "blocks_mib": round(got["blocks"] / 2**20, 1), "faces_mib": round(got["faces"] / 2**20, 1),
                   "ratio": round(estimate / got["peak"], 2)}
            print(json.dumps(row), flush=True)
            rows.append(row)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
