"""Peak memory of out-of-core ``isoflow info`` on one porous volume stored
with thin chunks (along the first or the last axis) and with cubic ones.

    python benchmarks/bench_thin_chunks.py                 # 256^3 and 512^3
    python benchmarks/bench_thin_chunks.py --sizes 1024    # one size

The volume is that of ``bench_outofcore.py`` (a smoothed porous field),
written for each size in chunks ``(N, N, 4)``, ``(4, N, N)`` and ``64^3``;
each store's ``isoflow info --json`` runs in a fresh process, whose peak
memory (``ru_maxrss``, from ``/usr/bin/time``) and wall time are printed, and the three
reports are checked equal. Thin chunks make almost every component of a
block touch the block's faces; what the blocks hand on grows with them.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_outofcore import chunk_of, coarse_field  # noqa: E402


def write(path: Path, volume: np.ndarray, chunks: tuple[int, int, int]) -> None:
    import zarr

    z = zarr.create_array(store=str(path), shape=volume.shape, chunks=chunks, dtype=bool, overwrite=True)
    z[...] = volume


def info(path: Path, connectivity: int) -> dict:
    """``isoflow info --json`` in a fresh process under ``/usr/bin/time``:
    its peak memory (``ru_maxrss`` of the command alone: a child forked
    from this process would start with this one's pages, the volume's)."""
    cmd = ["/usr/bin/time", "-f", "%M", sys.executable, "-m", "isoflow", "info", str(path), "--json",
           "--connectivity", str(connectivity)]
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, check=True)
    report = json.loads(done.stdout)
    report.pop("input")
    return {"wall_s": round(time.perf_counter() - t0, 2), "peak_rss_mib": round(int(done.stderr.split()[-1]) / 1024, 1),
            "report": report}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[256, 512])
    ap.add_argument("--connectivity", type=int, default=6, choices=(6, 26))
    ap.add_argument("--dir", type=Path, help="where to write the stores (default: a temporary folder)")
    ap.add_argument("--reuse", action="store_true", help="use the stores an earlier run left in --dir")
    args = ap.parse_args(argv)
    import zarr

    workdir = args.dir or Path(tempfile.mkdtemp(prefix="isoflow-thin-"))
    layouts = ("last", "first", "cubic")
    for n in args.sizes:
        stores = {name: workdir / f"porous-{n}-{name}.zarr" for name in layouts}
        if not (args.reuse and all(path.exists() for path in stores.values())):
            coarse = coarse_field(n, 8, 2013)
            volume = np.concatenate([chunk_of(coarse, ((a, min(a + 64, n)), (0, n), (0, n)), 8, 0.3)
                                     for a in range(0, n, 64)])
            for name, chunks in (("last", (n, n, 4)), ("first", (4, n, n)), ("cubic", (64, 64, 64))):
                write(stores[name], volume, chunks)
            del volume
        reports = {}
        for name, path in stores.items():
            chunks = tuple(int(c) for c in zarr.open_array(str(path), mode="r").chunks)
            r = info(path, args.connectivity)
            reports[name] = r.pop("report")
            print(json.dumps({"size": n, "chunks": chunks, **r}), flush=True)
        assert reports["last"] == reports["first"] == reports["cubic"], "the reports differ"
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
