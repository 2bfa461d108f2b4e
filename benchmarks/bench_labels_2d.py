"""The label table of 2D label images against scikit-image's regionprops_table.

    python benchmarks/bench_labels_2d.py                     # 1024^2 with 1,000 cells, 4096^2 with 20,000
    python benchmarks/bench_labels_2d.py --sizes 512 --cells 100 --repeat 1 --commands 1 --json ''   # a look

Input (generated, cached in benchmarks/.cache/): a cell segmentation,
Voronoi cells of uniform random seeds (``int32``, numbered 1 .. N), with
2 % of the pixels set to 0 (holes in the cells, as segmentations leave).

In process, in this process, the tools alternated, best of ``--repeat``
after one untimed call each:

* ``isoflow.label_table(image, 8)``: every cell's row (pixels, area,
  perimeter, box, centroid, chi, b0, b1, planar classes, energy);
* ``skimage.measure.regionprops_table(image, properties=("label", "area",
  "euler_number"))``: pixel counts and the Euler number (at 8).

Whole commands (``--commands N`` pairs, alternated, medians): ``isoflow
info FILE.npy --labels --connectivity 8 --json`` against ``python -c``
running the same ``regionprops_table`` on ``np.load(FILE)``. Results go to
``benchmarks/results/labels_2d.json`` (``--json``) and a Markdown table on
stdout; the two tables' Euler numbers are checked equal first.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from bench_labels import cached_array, commands  # the same whole commands, with --connectivity 8
from timing import write_results

ROOT = Path(__file__).resolve().parent.parent


def cells(size: int, count: int, seed: int = 0) -> np.ndarray:
    """Voronoi cells of ``count`` random seeds on a size x size image, 2 % of the pixels 0."""
    from scipy import ndimage as ndi

    rng = np.random.default_rng(seed)
    seeds = np.zeros((size, size), np.int32)
    at = rng.choice(size * size, count, replace=False)
    seeds.reshape(-1)[at] = np.arange(1, count + 1, dtype=np.int32)
    _, (iy, ix) = ndi.distance_transform_edt(seeds == 0, return_indices=True)
    image = seeds[iy, ix]
    image[rng.random(image.shape) < 0.02] = 0
    return image


def cached(size: int, count: int) -> Path:
    return cached_array(f"cells-{size}-{count}", lambda: cells(size, count))


def in_process(image: np.ndarray, repeat: int) -> dict:
    """Best seconds of each tool, alternated, after one untimed call each."""
    from skimage.measure import regionprops_table

    import isoflow

    tools = {"isoflow": lambda: isoflow.label_table(image, 8),
             "skimage": lambda: regionprops_table(image, properties=("label", "area", "euler_number"))}
    first = {name: run() for name, run in tools.items()}
    assert np.array_equal(first["isoflow"]["euler_characteristic"], first["skimage"]["euler_number"])
    assert np.array_equal(first["isoflow"]["voxels"], first["skimage"]["area"])
    best = dict.fromkeys(tools, float("inf"))
    for _ in range(repeat):
        for name, run in tools.items():
            start = time.perf_counter()
            run()
            best[name] = min(best[name], time.perf_counter() - start)
    return {"isoflow_seconds": best["isoflow"], "skimage_seconds": best["skimage"],
            "ratio": best["skimage"] / best["isoflow"], "rows": len(first["isoflow"]["label"])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1024, 4096])
    ap.add_argument("--cells", type=int, nargs="+", default=[1000, 20000], help="one count per size")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--commands", type=int, default=3, help="pairs of whole commands per input (0: none)")
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "labels_2d.json"))
    args = ap.parse_args(argv)
    if len(args.cells) != len(args.sizes):
        ap.error("give one --cells count per --sizes entry")
    results = []
    lines = ["| image | cells | how | isoflow label_table (s) | regionprops_table (s) | regionprops / isoflow |",
             "|---|---|---|---|---|---|"]
    for size, count in zip(args.sizes, args.cells):
        path = cached(size, count)
        rec = {"size": size, "cells": count, "how": "in process", **in_process(np.load(path), args.repeat)}
        results.append(rec)
        if args.commands:
            results.append({"size": size, "cells": count, "how": "whole commands", "input":
                            str(path.relative_to(ROOT)), **commands(path, args.commands, ("--connectivity", "8"))})
        for r in results[-2 if args.commands else -1:]:
            lines.append(f"| {size}^2 | {count:,} | {r['how']} | {r['isoflow_seconds']:.3f} | "
                         f"{r['skimage_seconds']:.3f} | {r['ratio']:.2f}x |")
            print(lines[-1], file=sys.stderr)
    print("\n".join(lines))
    if args.json:
        write_results(args.json, "bench_labels_2d.py", argv, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
