"""An HDF5 label image's table read a slab at a time, and a mask's report a
block at a time, against the same file read whole.

    python benchmarks/bench_hdf5_slabs.py                       # 256^3, 1,000 grains, 9 pairs
    python benchmarks/bench_hdf5_slabs.py --mask                # 256^3 porous mask, info a block at a time
    python benchmarks/bench_hdf5_slabs.py --size 128 --pairs 3 --json ''   # a quick look

Input: bench_labels.py's grain map (cached in benchmarks/.cache/), uint32,
written to HDF5 twice: chunked 64^3 with gzip (as h5py users and ilastik
write it) and contiguous. ``isoflow info FILE.h5:/seg --labels --json``
runs as whole processes, alternated: once as the machine has its memory
(the image fits: read whole), once with isoflow's memory budget held at 5
bytes a voxel (``isoflow.scale.memory.budget_held``, below the 6 that the
whole read needs: read a slab at a time, ``isoflow.mesh.formats.hdf5.LabelSlabs``).
The two tables are compared (they must be equal); medians of wall
seconds, their ratio, and each process's peak RSS (``ru_maxrss``).
With ``--mask`` the input is a porous mask instead (a smoothed random
field thresholded at 0, uint8 0/1), the command ``isoflow info
FILE.h5:/seg --json`` and the budget 2 bytes a voxel (the whole read
needs 3: read a block at a time, ``isoflow.mesh.formats.hdf5.analyze_dataset``).
No other tool reads an HDF5 image larger than memory into a report or a
table of topology; the figure is what reading by slabs or blocks costs
beside reading whole. Results: ``benchmarks/results/hdf5_slabs.json``
(``hdf5_blocks.json`` with ``--mask``) and a Markdown table on stdout.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from bench_labels import cached  # noqa: E402
from timing import write_results  # noqa: E402

#: the command, its memory budget held at argv[1] bytes (0: the machine's)
RUN = ("import sys; from isoflow.cli import main; from isoflow.scale.memory import budget_held\n"
       "budget = int(sys.argv[1])\n"
       "if budget:\n    with budget_held(budget):\n        sys.exit(main(sys.argv[2:]))\n"
       "sys.exit(main(sys.argv[2:]))")


def command(budget: int, path: Path, mask: bool = False) -> list[str]:
    """``isoflow info PATH:/seg --labels --json`` (of a ``mask``: without
    ``--labels``), the memory budget held at ``budget`` (0: the machine's)."""
    return [sys.executable, "-c", RUN, str(budget), "info", f"{path}:/seg", *([] if mask else ["--labels"]), "--json"]


def run(budget: int, path: Path, mask: bool = False) -> tuple[float, str]:
    """Wall seconds and stdout of one whole process."""
    start = time.perf_counter()
    done = subprocess.run(command(budget, path, mask), check=True, capture_output=True, text=True)
    return time.perf_counter() - start, done.stdout


def peak(budget: int, path: Path, mask: bool = False) -> int:
    """Peak RSS (bytes) of one whole process, run under a parent of its own
    (``ru_maxrss`` of the children is the largest of all of them)."""
    script = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, stdout=subprocess.DEVNULL); "
              "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024)")
    done = subprocess.run([sys.executable, "-c", script, *command(budget, path, mask)], check=True,
                          capture_output=True, text=True)
    return int(done.stdout)


def measure(path: Path, voxels: int, pairs: int, mask: bool = False) -> dict:
    """The two routes over ``pairs`` alternated pairs (after one of each, untimed)."""
    routes = {"whole": 0, "slabs": (2 if mask else 5) * voxels}
    tables = {key: json.loads(run(budget, path, mask)[1]) for key, budget in routes.items()}
    assert tables["whole"] == tables["slabs"], "the report read in parts differs from the whole one"
    times: dict[str, list[float]] = {"whole": [], "slabs": []}
    for _ in range(pairs):
        for key, budget in routes.items():
            times[key].append(run(budget, path, mask)[0])
    peaks = {key: peak(budget, path, mask) for key, budget in routes.items()}
    med = {k: statistics.median(v) for k, v in times.items()}
    return {"whole_seconds": med["whole"], "slab_seconds": med["slabs"], "slabs_over_whole": med["slabs"] / med["whole"],
            "whole_peak_mib": peaks["whole"] / 2**20, "slab_peak_mib": peaks["slabs"] / 2**20, "pairs": pairs,
            "tables_equal": True}


def main(argv=None) -> int:
    import h5py

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--labels", type=int, default=1000)
    ap.add_argument("--pairs", type=int, default=9)
    ap.add_argument("--mask", action="store_true", help="a porous mask's report instead of a label table")
    ap.add_argument("--json", default=None, help="default: results/hdf5_slabs.json (hdf5_blocks.json with --mask)")
    args = ap.parse_args(argv)
    if args.json is None:
        args.json = str(HERE / "results" / ("hdf5_blocks.json" if args.mask else "hdf5_slabs.json"))
    if args.mask:
        from scipy.ndimage import gaussian_filter

        field = gaussian_filter(np.random.default_rng(0).standard_normal((args.size,) * 3).astype(np.float32), 2)
        image = (field > 0).astype(np.uint8)
    else:
        image = np.load(cached(args.size, args.labels)).astype(np.uint32)
    results = []
    with tempfile.TemporaryDirectory() as folder:
        for layout, options in (("chunked 64^3, gzip", {"chunks": (64,) * 3, "compression": "gzip"}),
                                ("contiguous", {})):
            path = Path(folder) / "grains.h5"
            with h5py.File(path, "w") as f:
                f.create_dataset("seg", data=image, **options)
            found = measure(path, image.size, args.pairs, args.mask)
            results.append({"size": args.size, "labels": 1 if args.mask else args.labels, "layout": layout, **found})
    print("| layout | read whole (s) | in parts (s) | parts / whole | peak whole (MiB) | peak in parts (MiB) |")
    print("|---|---|---|---|---|---|")
    for r in results:
        what = "porous mask" if args.mask else f"{r['labels']} labels"
        print(f"| {r['size']}^3, {what}, {r['layout']} | {r['whole_seconds']:.2f} | "
              f"{r['slab_seconds']:.2f} | {r['slabs_over_whole']:.2f} | {r['whole_peak_mib']:.0f} | "
              f"{r['slab_peak_mib']:.0f} |")
    if args.json:
        write_results(args.json, "bench_hdf5_slabs.py", argv, results)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
