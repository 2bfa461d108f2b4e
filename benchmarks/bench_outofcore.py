"""Out-of-core ``isoflow info`` on a porous volume stored as zarr.

    python benchmarks/bench_outofcore.py                   # 512^3
    python benchmarks/bench_outofcore.py --sizes 512 1024  # several sizes
    python benchmarks/bench_outofcore.py --sizes 2048 --dir /big/disk

For each size it

1. writes a smoothed random porous volume to ``DIR/porous-N.zarr`` (zarr v3,
   bool, chunks 256^3, blosc-zstd with bit shuffle), chunk by chunk, so that
   writing never holds more than a few chunks;
2. runs :func:`isoflow.outofcore.analyze_zarr` in a fresh process and
   reports its wall time and peak memory;
3. for sizes up to ``--check-max`` (512) loads the whole volume and checks
   that the report equals the in-memory ``analyze(..., surfaces=False)``
   (in another fresh process, whose peak memory is reported for comparison).

Peak memory: ``ru_maxrss`` of the analysing process and, because large zarr
volumes are analysed by dask's process scheduler, of its largest worker
(``RUSAGE_CHILDREN``), plus the peak of the whole process tree's summed RSS
sampled every 0.1 s from /proc (the number to compare with RAM).

The volume: a coarse grid (one node every ``--feature`` voxels) of Gaussian
noise, smoothed on the coarse grid, then evaluated at every voxel as a cubic
B-spline and thresholded. Each voxel's value depends only on the 4^3 nearest
coarse nodes, so a chunk is computed on its own from a coarse-grid halo and
the volume is seamless across chunks; the separable B-spline is three matrix
products per chunk (BLAS), much faster than smoothing full-resolution noise.
The coarse grid is 1/feature^3 of the volume (4 MB at 1024^3).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

CHUNK = 256
HERE = Path(__file__).resolve().parent


# --------------------------------------------------------------------------
# the volume
# --------------------------------------------------------------------------


def bspline3(t: np.ndarray) -> np.ndarray:
    """The cubic B-spline kernel (support [-2, 2], partition of unity)."""
    t = np.abs(t)
    return np.where(t < 1, 2 / 3 - t**2 + t**3 / 2, np.where(t < 2, (2 - t) ** 3 / 6, 0.0))


def coarse_field(n: int, feature: int, seed: int) -> np.ndarray:
    """Smoothed Gaussian noise on the coarse grid, nodes -2 .. n/feature + 2."""
    from scipy.ndimage import gaussian_filter

    m = n // feature + 5
    noise = np.random.default_rng(seed).standard_normal((m, m, m), dtype=np.float32)
    field = gaussian_filter(noise, 1.0, mode="wrap")
    return (field / field.std()).astype(np.float32)


def weights(start: int, stop: int, feature: int) -> tuple[np.ndarray, int]:
    """B-spline weights of voxels start..stop-1 on the coarse nodes they see.

    Voxel centre x sits at coarse coordinate u = (x + 0.5) / feature; node j
    (array index j + 2) at u = j. Returns the (voxels, nodes) matrix and the
    array index of its first node.
    """
    u = (np.arange(start, stop) + 0.5) / feature
    j0 = int(np.floor(u[0])) - 1
    j1 = int(np.floor(u[-1])) + 3
    j = np.arange(j0, j1)
    return bspline3(u[:, None] - j[None, :]).astype(np.float32), j0 + 2


def chunk_of(coarse: np.ndarray, region, feature: int, level: float) -> np.ndarray:
    """The porous volume on one region (tuple of (start, stop)), as bool."""
    (w0, o0), (w1, o1), (w2, o2) = (weights(a, b, feature) for a, b in region)
    c = coarse[o0 : o0 + w0.shape[1], o1 : o1 + w1.shape[1], o2 : o2 + w2.shape[1]]
    t = np.tensordot(w0, c, axes=(1, 0))  # (L0, J1, J2)
    t = np.tensordot(t, w1, axes=(1, 1))  # (L0, J2, L1)
    t = np.tensordot(t, w2, axes=(1, 1))  # (L0, L1, L2)
    return t > level


def write_volume(path: Path, n: int, feature: int, level: float, seed: int) -> dict:
    import zarr
    from zarr.codecs import BloscCodec

    t0 = time.perf_counter()
    coarse = coarse_field(n, feature, seed)
    z = zarr.create_array(
        store=str(path),
        shape=(n, n, n),
        chunks=(CHUNK,) * 3,
        dtype=bool,
        compressors=BloscCodec(cname="zstd", clevel=3, shuffle="bitshuffle"),
        overwrite=True,
    )
    starts = range(0, n, CHUNK)
    regions = [
        tuple((s, min(s + CHUNK, n)) for s in idx)
        for idx in ((a, b, c) for a in starts for b in starts for c in starts)
    ]

    def one(region):
        block = chunk_of(coarse, region, feature, level)
        z[tuple(slice(a, b) for a, b in region)] = block
        return int(np.count_nonzero(block))

    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        voxels = sum(pool.map(one, regions))
    size = sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    return {
        "write_s": round(time.perf_counter() - t0, 2),
        "voxels": voxels,
        "solid_fraction": round(voxels / n**3, 4),
        "zarr_bytes": size,
        "write_peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
    }


# --------------------------------------------------------------------------
# measuring
# --------------------------------------------------------------------------


def tree_rss_kb(pid: int) -> int:
    """Summed VmRSS of a process and all its descendants, from /proc."""
    total, stack = 0, [pid]
    while stack:
        p = stack.pop()
        try:
            with open(f"/proc/{p}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1])
                        break
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    stack.extend(int(c) for c in f.read().split())
        except (FileNotFoundError, ProcessLookupError, PermissionError):
            continue
    return total


class TreeSampler:
    """Peak of the summed RSS of this process tree, sampled in a thread."""

    def __init__(self, interval: float = 0.1):
        self.interval, self.peak, self._stop = interval, 0, threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        while not self._stop.is_set():
            self.peak = max(self.peak, tree_rss_kb(os.getpid()))
            self._stop.wait(self.interval)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


def child_analyze(path: str, connectivity: int, scheduler: str | None = None, surfaces: bool = True) -> dict:
    from isoflow.digital.outofcore import analyze_zarr

    with TreeSampler() as sampler:
        t0 = time.perf_counter()
        report = analyze_zarr(path, connectivity, scheduler=scheduler, surfaces=surfaces)
        seconds = time.perf_counter() - t0
    return {
        "seconds": round(seconds, 2),
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "peak_worker_rss_mb": round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, 1),
        "peak_tree_rss_mb": round(sampler.peak / 1024, 1),
        # the machine may be shared: the 1-minute load average at the end
        "load_average": round(os.getloadavg()[0], 2),
        "report": report,
    }


def child_inmemory(path: str, connectivity: int, scheduler=None) -> dict:
    import zarr

    from isoflow import DigitalObject, analyze

    t0 = time.perf_counter()
    vol = np.asarray(zarr.open_array(path, mode="r")[...])
    load = time.perf_counter() - t0
    t0 = time.perf_counter()
    report = analyze(DigitalObject(vol), connectivity)
    report["doubled_edges"] = None  # not counted out of core
    return {
        "load_s": round(load, 2),
        "seconds": round(time.perf_counter() - t0, 2),
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
        "report": report,
    }


def run_child(kind: str, path: Path, connectivity: int, scheduler: str | None = None) -> dict:
    cmd = [sys.executable, __file__, "--child", kind, str(path), "--connectivity", str(connectivity)]
    if scheduler:
        cmd += ["--scheduler", scheduler]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode:
        raise SystemExit(f"{kind} child failed:\n{p.stderr}")
    return json.loads(p.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("size", nargs="?", type=int, help="one edge length (default 512)")
    ap.add_argument("--sizes", type=int, nargs="+", help="several edge lengths")
    ap.add_argument("--connectivity", type=int, default=6, choices=(6, 26))
    ap.add_argument("--feature", type=int, default=8, help="pore size scale in voxels")
    ap.add_argument("--level", type=float, default=0.3, help="threshold (in field standard deviations)")
    ap.add_argument("--seed", type=int, default=2013)
    ap.add_argument("--dir", type=Path, help="where to write the zarr volumes (default: a temporary folder)")
    ap.add_argument("--keep", action="store_true", help="keep the zarr volumes")
    ap.add_argument("--check-max", type=int, default=512, help="check against in-memory analyze up to this size")
    ap.add_argument("--scheduler", choices=("threads", "sync", "processes"),
                    help="dask scheduler for analyze_zarr (default: dask's, threads)")
    ap.add_argument("--pairs", type=int, default=1,
                    help="runs of analyze_zarr with and without surfaces, alternated; medians (default 1)")
    ap.add_argument("--json", type=Path, default=HERE / "results" / "outofcore.json")
    ap.add_argument("--child", nargs=2, metavar=("KIND", "PATH"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.child:
        kind, path = args.child
        fn = {"analyze": child_analyze, "inmemory": child_inmemory,
              "analyze-nosurf": lambda *a: child_analyze(*a, surfaces=False)}[kind]
        print(json.dumps(fn(path, args.connectivity, args.scheduler)))
        return 0

    sizes = args.sizes or [args.size or 512]
    workdir = args.dir or Path(tempfile.mkdtemp(prefix="isoflow-bench-"))
    workdir.mkdir(parents=True, exist_ok=True)
    rows = []
    for n in sizes:
        path = workdir / f"porous-{n}.zarr"
        print(f"{n}^3: writing {path} ...", flush=True)
        row = {"size": n, "shape": [n, n, n], "chunks": [CHUNK] * 3, "connectivity": args.connectivity}
        row.update(write_volume(path, n, args.feature, args.level, args.seed))
        print(f"  written in {row['write_s']} s, {row['zarr_bytes'] / 2**20:.0f} MiB on disk", flush=True)
        runs = {"analyze": [], "analyze-nosurf": []}
        for _ in range(args.pairs):  # alternated: A B A B
            for kind in runs:
                runs[kind].append(run_child(kind, path, args.connectivity, args.scheduler))
        nosurf = runs["analyze-nosurf"]
        res = runs["analyze"][0]
        res["seconds"] = float(np.median([r["seconds"] for r in runs["analyze"]]))
        res["peak_rss_mb"] = max(r["peak_rss_mb"] for r in runs["analyze"])
        res["scheduler"] = args.scheduler or "threads (dask default)"
        report = res.pop("report")
        row["analyze_zarr"] = res
        row["analyze_zarr_no_surfaces"] = {"seconds": float(np.median([r["seconds"] for r in nosurf])),
                                           "peak_rss_mb": max(r["peak_rss_mb"] for r in nosurf)}
        row["surfaces_cost_ratio"] = res["seconds"] / row["analyze_zarr_no_surfaces"]["seconds"]
        row["surfaces"] = len(report["surfaces"])
        print(f"  without surfaces: {row['analyze_zarr_no_surfaces']['seconds']} s; with them "
              f"{row['surfaces_cost_ratio']:.2f}x that ({row['surfaces']} surfaces)", flush=True)
        row["result"] = {k: report[k] for k in ("voxels", "euler_characteristic", "betti", "a_dot_n", "energy")}
        print(f"  analyze_zarr: {res['seconds']} s, peak RSS {res['peak_rss_mb']} MB "
              f"(largest worker {res['peak_worker_rss_mb']} MB, whole tree {res['peak_tree_rss_mb']} MB); "
              f"chi {report['euler_characteristic']}, betti {report['betti']}", flush=True)
        assert report["voxels"] == row["voxels"]
        if n <= args.check_max:
            ref = run_child("inmemory", path, args.connectivity)
            ok = ref.pop("report") == report
            row["in_memory"] = ref
            row["equal_to_in_memory"] = ok
            print(f"  in-memory analyze: {ref['seconds']} s (+{ref['load_s']} s load), "
                  f"peak RSS {ref['peak_rss_mb']} MB; reports equal: {ok}", flush=True)
            if not ok:
                raise SystemExit("out-of-core report differs from the in-memory one")
        rows.append(row)
        if not args.keep:
            shutil.rmtree(path)
    if args.dir is None and not args.keep:
        shutil.rmtree(workdir, ignore_errors=True)

    if args.json:
        import dask
        import zarr

        args.json.parent.mkdir(parents=True, exist_ok=True)
        old = json.loads(args.json.read_text()) if args.json.exists() else {}
        by_size = {r["size"]: r for r in old.get("rows", [])}
        by_size.update({r["size"]: r for r in rows})
        meta = {
            "benchmark": "isoflow.outofcore.analyze_zarr on a smoothed random porous zarr volume",
            "machine": platform.platform(),
            "cpus": os.cpu_count(),
            "ram_gb": round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1),
            "python": platform.python_version(),
            "numpy": np.__version__,
            "dask": dask.__version__,
            "zarr": zarr.__version__,
            "feature": args.feature,
            "level": args.level,
            "seed": args.seed,
        }
        args.json.write_text(json.dumps({"meta": meta, "rows": [by_size[k] for k in sorted(by_size)]}, indent=1))
        print(f"results in {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
