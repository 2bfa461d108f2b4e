"""Benchmark: the compiled passes' threads kept per calling thread
(``isoflow.scale.compiled.run``) against a pool started and joined for
each pass, as ``run`` did before (the reference, written out below).

    python benchmarks/bench_pass_threads.py                     # 9^3, 64^3, 160^3 on 1, 2, 7 threads
    python benchmarks/bench_pass_threads.py --sizes 9 128 --threads 2 --json ''

In one process, warm (numba's cached code loaded first): ``analyze(vol, 6,
method="compiled", threads=t)`` on ``--count`` smoothed random volumes of
``size``^3 voxels (edge and vertex contacts included), the two runners
alternated, best of ``--repeat`` loops each; seconds per volume and the
ratio of the reference's time to the kept threads'. A pass over a small
volume takes less time than starting its threads; a volume of millions
of voxels pays a thread's start once against a long pass.

Results: ``benchmarks/results/pass_threads.json`` (``--json``) and a
Markdown table on stdout.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from scipy.ndimage import gaussian_filter

import isoflow
from isoflow.scale import bitrows, compiled, fineblocks, flowbits, kernels, pieces, sweep

#: the modules that take ``run`` by name at import (the others look it up in compiled when called)
USERS = (compiled, bitrows, fineblocks, flowbits, kernels, pieces, sweep)

ROOT = Path(__file__).resolve().parents[1]


def fresh_pool_run(calls: list) -> list:
    """``compiled.run`` as it was: a pool of its own for each pass."""
    if len(calls) <= 1:
        return [fn(*args) for fn, *args in calls]
    with ThreadPoolExecutor(max_workers=len(calls)) as pool:
        futures = [pool.submit(fn, *args) for fn, *args in calls]
        return [f.result() for f in futures]


def volumes(size: int, count: int) -> list[np.ndarray]:
    rng = np.random.default_rng(size)
    return [gaussian_filter(rng.standard_normal((size,) * 3), 1.0) > 0.1 for _ in range(count)]


def loop(vols: list[np.ndarray], threads: int) -> float:
    t0 = time.perf_counter()
    for v in vols:
        isoflow.analyze(v, 6, method="compiled", threads=threads)
    return (time.perf_counter() - t0) / len(vols)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[9, 64, 160])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2, 7])
    ap.add_argument("--count", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "pass_threads.json"))
    args = ap.parse_args()

    kept = compiled.run
    isoflow.analyze(volumes(9, 1)[0], 6, method="compiled", threads=2)  # numba's code loaded
    rows = []
    for size in args.sizes:
        vols = volumes(size, args.count)
        for threads in args.threads:
            best = {"kept": float("inf"), "fresh": float("inf")}
            for _ in range(args.repeat):
                for name, runner in (("fresh", fresh_pool_run), ("kept", kept)):
                    for module in USERS:
                        module.run = runner
                    best[name] = min(best[name], loop(vols, threads))
            for module in USERS:
                module.run = kept
            rows.append({"size": size, "threads": threads, "kept_seconds": best["kept"],
                         "fresh_seconds": best["fresh"], "ratio": best["fresh"] / best["kept"]})
    print("| size | threads | kept threads (ms per volume) | a pool per pass (ms) | ratio |")
    print("|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['size']}^3 | {r['threads']} | {1e3 * r['kept_seconds']:.3f} | {1e3 * r['fresh_seconds']:.3f} "
              f"| {r['ratio']:.2f} |")
    if args.json:
        meta = {"command": "python benchmarks/bench_pass_threads.py", "machine": f"{platform.machine()}, "
                f"{len(__import__('os').sched_getaffinity(0))} CPUs", "python": platform.python_version(),
                "count": args.count, "repeat": args.repeat}
        Path(args.json).write_text(json.dumps({"meta": meta, "results": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
