"""Benchmark: reading a text point list (``x y z`` per line).

isoflow's ``read_points`` (numpy's compiled ``loadtxt``, then a check that
every coordinate is an integer in range) against ``np.loadtxt(path,
dtype=np.int64)``, which a user would otherwise write, and against isoflow's
line-by-line reader, which reads the files that loadtxt refuses (mixed
separators) and names the line of a bad one. Paired A B C A B C in the same
run, medians; peak memory of each traced by tracemalloc.

Usage::

    PYTHONPATH=src python benchmarks/bench_points.py [--points 1000000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from isoflow.mesh.volumes import _read_points_by_line, read_points  # noqa: E402

READERS = {
    "isoflow read_points": read_points,
    "np.loadtxt(dtype=int64)": lambda p: np.loadtxt(p, dtype=np.int64),
    "isoflow line by line": _read_points_by_line,
}


def peak_mb(read, path: Path) -> float:
    """Peak of the memory allocated during one read (numpy's buffers and
    Python's objects: both are traced)."""
    import tracemalloc

    tracemalloc.start()
    read(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return peak / 2**20


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    rng = np.random.default_rng(2013)
    pts = rng.integers(0, 1000, (args.points, 3))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "points.txt"
        np.savetxt(path, pts, fmt="%d")
        times = {name: [] for name in READERS}
        for _ in range(args.repeat):
            for name, read in READERS.items():
                t = time.perf_counter()
                got = read(path)
                times[name].append(time.perf_counter() - t)
                assert (got == pts).all(), name
        mb = path.stat().st_size / 2**20
        print(f"{args.points:,} points, {mb:.1f} MB of text; medians of {args.repeat} paired runs")
        base = statistics.median(times["isoflow read_points"])
        for name, ts in times.items():
            med = statistics.median(ts)
            print(f"  {name:26s} {med:7.3f} s  {med / base:5.2f}x isoflow's time  "
                  f"peak {peak_mb(READERS[name], path):.0f} MB")


if __name__ == "__main__":
    main()
