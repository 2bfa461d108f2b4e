"""The label table's two passes on noisy segmentations: where "auto" takes
the label-by-label pass (``label_table.FRAGMENTED``).

    python benchmarks/bench_noisy_segmentations.py                 # 128^3, 3, 8 and 30 labels
    python benchmarks/bench_noisy_segmentations.py --size 64 --labels 3 --repeat 1 --json ''   # a look

Input (generated, seed 0): a smooth segmentation of ``L`` labels (and 0),
each voxel the value of its nearest of ``2 L`` seeds of random values
(Voronoi blobs), with a share ``q`` of its voxels drawn again at random
among the ``L + 1`` values (salt noise; ``q = 1``: noise).

In process, warm, best of ``--repeat``: the one pass
(``label_table(image, 6, method="compiled")``: the pieces, one vertex
pass, the graph of pieces) against the label-by-label pass of a noisy
segmentation (``label_by_label.box_rows`` given the image's values: each
label's mask through the compiled census), both from the image, the
second without counting the pieces (what "auto" decides it on). Printed
per image: its values, its pieces a voxel (6-connected pieces of one
value, ``scale.pieces.piece_runs``), the shares of its 2x2x2 blocks that
hold more than one value, and both times; written to
``benchmarks/results/noisy_segmentations.json`` (``--json``) and as a
Markdown table on stdout. The rule: the label-by-label pass from
``FRAGMENTED`` pieces a voxel for each value on.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from timing import write_results

ROOT = Path(__file__).resolve().parent.parent


def blobs(rng: np.random.Generator, n: int, labels: int) -> np.ndarray:
    """Each voxel of an ``n^3`` image the value (0 to ``labels``) of its
    nearest of ``2 labels`` random seeds."""
    seeds = rng.integers(0, n, (2 * labels, 3))
    values = rng.integers(0, labels + 1, 2 * labels)
    grid = np.indices((n,) * 3).reshape(3, -1).T
    out = np.zeros(n**3, np.uint32)
    nearest = np.full(n**3, np.inf)
    for seed, value in zip(seeds, values):
        d = ((grid - seed) ** 2).sum(axis=1)
        closer = d < nearest
        nearest[closer], out[closer] = d[closer], value
    return out.reshape((n,) * 3)


def multi_blocks(image: np.ndarray) -> float:
    """The share of the 2x2x2 blocks that hold more than one value."""
    corner = image[:-1, :-1, :-1]
    mixed = np.zeros(corner.shape, bool)
    for dx, dy, dz in np.ndindex(2, 2, 2):
        mixed |= image[dx:image.shape[0] - 1 + dx, dy:image.shape[1] - 1 + dy, dz:image.shape[2] - 1 + dz] != corner
    return float(mixed.mean())


def best(run, repeat: int) -> float:
    run()  # warm
    seconds = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        run()
        seconds = min(seconds, time.perf_counter() - start)
    return seconds


def main(argv=None) -> int:
    import isoflow
    from isoflow.digital.label_by_label import box_rows
    from isoflow.digital.label_table import FRAGMENTED, image_values
    from isoflow.scale.pieces import piece_runs

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--labels", type=int, nargs="+", default=[3, 8, 30])
    ap.add_argument("--salt", type=float, nargs="+", default=[0, 0.01, 0.03, 0.1, 0.3, 1.0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "noisy_segmentations.json"))
    args = ap.parse_args(argv)
    rng = np.random.default_rng(0)
    lines = ["| labels | salt | values | pieces a voxel | mixed blocks | one pass (s) | label by label (s) | auto takes |",
             "|---:|---:|---:|---:|---:|---:|---:|---|"]
    results = []
    for labels in args.labels:
        smooth = blobs(rng, args.size, labels)
        for q in args.salt:
            image = smooth.copy()
            salt = rng.random(image.shape) < q
            image[salt] = rng.integers(0, labels + 1, int(salt.sum()))
            values = image_values(image)
            pieces = piece_runs(image)["n"] / image.size
            one = best(lambda x=image: isoflow.label_table(x, 6, method="compiled"), args.repeat)
            by_label = best(lambda x=image, v=values: box_rows(x, 6, None, True, weighed=True, present=v), args.repeat)
            takes = "label by label" if pieces >= FRAGMENTED * len(values) else "one pass"
            rec = {"size": args.size, "labels": labels, "salt": q, "values": len(values), "pieces_per_voxel": pieces,
                   "mixed_blocks": multi_blocks(image), "one_pass_seconds": one, "label_by_label_seconds": by_label,
                   "auto_takes": takes}
            results.append(rec)
            lines.append(f"| {labels} | {q:g} | {len(values)} | {pieces:.4f} | {rec['mixed_blocks']:.3f} | {one:.3f} | "
                         f"{by_label:.3f} | {takes} |")
            print(lines[-1], file=sys.stderr)
    print("\n".join(lines))
    if args.json:
        write_results(args.json, "bench_noisy_segmentations.py", argv, results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
