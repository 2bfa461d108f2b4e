"""The label table of scattered labels (noise) against scikit-image's regionprops_table.

    python benchmarks/bench_scattered_labels.py                    # 64^3, 96^3 and 128^3, 1,000 labels
    python benchmarks/bench_scattered_labels.py --sizes 48 --repeat 1 --json ''   # a look
    python benchmarks/bench_scattered_labels.py --ndim 2 --sizes 2048 --labels 10 --repeat 3 \
        --json benchmarks/results/scattered_labels_2d.json                    # 2D noise of a few labels
    python benchmarks/bench_scattered_labels.py --sizes 128 --labels 3 4 10 30 --repeat 3 \
        --json benchmarks/results/scattered_labels_few.json                   # noise of a few labels

Input (generated): ``np.random.default_rng(1).integers(0, labels, (n,)*3,
dtype=np.uint32)`` (``(n,)*2`` with ``--ndim 2``, at 4-connectivity
there), every voxel a label drawn at random: each label is
thousands of pieces spread over the whole image, its box the image's, the
worst case of the label table's walks around a label (the grain maps of
``bench_labels.py`` are the usual case); with a few labels, a noisy
segmentation (``--labels 3``: three phases of a third of the voxels each,
which percolate).

In process, the tools alternated, best of ``--repeat`` after one untimed
call each: ``isoflow.label_table(image, 6)`` (every label's row, Betti
numbers and surfaces) against ``regionprops_table(image, properties=
("label", "area", "euler_number"))``; the Euler numbers are checked equal
(at 6-connectivity, scikit-image's ``connectivity=1``) and the seconds and
the call's peak memory beyond what the process held before it
(``ru_maxrss`` after, less the resident memory before: bytes per voxel;
true where the call's peak passes every earlier one) written
to ``benchmarks/results/scattered_labels.json`` (``--json``) and a
Markdown table on stdout (give the sizes smallest first).
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np
from timing import write_results

ROOT = Path(__file__).resolve().parent.parent


def peak_bytes() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def resident_bytes() -> int:
    """The process's resident memory now (Linux)."""
    return int(Path("/proc/self/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def main(argv=None) -> int:
    from skimage.measure import euler_number, regionprops_table

    import isoflow

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 96, 128])
    ap.add_argument("--labels", type=int, nargs="+", default=[1000], help="values drawn (0 among them), each in turn")
    ap.add_argument("--ndim", type=int, choices=(2, 3), default=3)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "scattered_labels.json"))
    args = ap.parse_args(argv)
    lines = ["| image | labels | isoflow label_table (s) | regionprops_table (s) | isoflow peak growth (B/voxel) |",
             "|---|---|---|---|---|"]
    results = []
    conn = 6 if args.ndim == 3 else 4  # scikit-image's connectivity=1 either way
    # numba's passes loaded (a small scattered image takes the compiled ones)
    isoflow.label_table(np.random.default_rng(0).integers(0, 50, (24,) * args.ndim, dtype=np.uint32), conn)
    for n, drawn in [(n, drawn) for drawn in args.labels for n in args.sizes]:
        image = np.random.default_rng(1).integers(0, drawn, (n,) * args.ndim, dtype=np.uint32)
        before = resident_bytes()
        table = isoflow.label_table(image, conn)
        grown = peak_bytes() - before
        first = int(table["label"][0])
        assert table["euler_characteristic"][0] == euler_number(image == first, connectivity=1)
        tools = {"isoflow": lambda x=image: isoflow.label_table(x, conn),
                 "skimage": lambda x=image: regionprops_table(x, properties=("label", "area", "euler_number"))}
        best = dict.fromkeys(tools, float("inf"))
        for _ in range(args.repeat):
            for name, run in tools.items():
                start = time.perf_counter()
                run()
                best[name] = min(best[name], time.perf_counter() - start)
        rec = {"size": n, "ndim": args.ndim, "labels": len(table["label"]), "isoflow_seconds": best["isoflow"],
               "skimage_seconds": best["skimage"], "isoflow_peak_growth_bytes_per_voxel": grown / image.size}
        results.append(rec)
        lines.append(f"| {n}^{args.ndim} | {rec['labels']:,} | {best['isoflow']:.2f} | {best['skimage']:.2f} | "
                     f"{rec['isoflow_peak_growth_bytes_per_voxel']:.0f} |")
        print(lines[-1], file=sys.stderr)
    print("\n".join(lines))
    if args.json:
        write_results(args.json, "bench_scattered_labels.py", argv, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
