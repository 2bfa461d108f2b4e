"""Benchmark: the gzip level of a written NRRD, time against size.

``isoflow.write_volume`` / ``write_labels`` write ``.nrrd`` gzip-compressed
through pynrrd, whose default level is 9. This times that write at levels 1,
6 (zlib's and gzip(1)'s default, what isoflow uses) and 9, best of
``--repeat``, with the file's size, on a porous mask (uint8) and a grain map
of 1,000 labels (uint32), both N^3 (the generator of
``benchmarks/bench_labels.py``).

Usage::

    python benchmarks/bench_gzip_levels.py [--size 256] [--repeat 3] [--json OUT.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent
sys.path.insert(0, str(ROOT))

from bench_labels import cached  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default="")
    args = ap.parse_args(argv)
    import nrrd

    labels = np.load(cached(args.size, 1000))
    volumes = {"mask uint8": (labels > 0).astype(np.uint8), "labels uint32": labels}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "v.nrrd")
        for name, data in volumes.items():
            for level in (1, 6, 9):
                best = min(_timed(nrrd.write, path, data, {"encoding": "gzip"}, compression_level=level)
                           for _ in range(args.repeat))
                rows.append({"volume": name, "size": args.size, "level": level, "seconds": best,
                             "bytes": Path(path).stat().st_size})
                print(f"{name:14} level {level}  {best:6.3f} s  {rows[-1]['bytes'] / 2**20:7.2f} MiB", flush=True)
    if args.json:
        meta = {"command": "python benchmarks/bench_gzip_levels.py " + " ".join(argv or sys.argv[1:]),
                "machine": f"{platform.machine()}, python {platform.python_version()}"}
        Path(args.json).write_text(json.dumps({"meta": meta, "results": rows}, indent=1) + "\n")
    return 0


def _timed(f, *a, **k) -> float:
    start = time.perf_counter()
    f(*a, **k)
    return time.perf_counter() - start


if __name__ == "__main__":
    raise SystemExit(main())
