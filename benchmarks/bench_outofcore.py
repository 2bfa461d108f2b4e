"""Out-of-core ``isoflow info`` on a porous volume stored as zarr, against
the same volume in memory (issue 27's targets).

    python benchmarks/bench_outofcore.py                     # 512^3
    python benchmarks/bench_outofcore.py --sizes 512 2048    # several sizes
    python benchmarks/bench_outofcore.py --sizes 2048 --dir /big/disk

For each size it

1. writes a smoothed random porous volume to ``DIR/porous-N.zarr`` (zarr v3,
   bool, chunks 256^3, blosc-zstd with bit shuffle), chunk by chunk, so that
   writing never holds more than a few chunks; up to ``--npy-max`` (512)
   the same volume as ``DIR/porous-N.npy`` too;
2. runs the whole command ``isoflow info porous-N.zarr --json`` (with the
   surfaces) in a fresh process: wall time, CPU time (user + system) and
   peak memory (``ru_maxrss`` of that process, from ``os.wait4``);
3. where the ``.npy`` exists, runs ``isoflow info porous-N.npy --json`` the
   same way, alternated with the zarr command (``--pairs`` times, best of
   each), checks that the two reports are equal in every field, and gives
   the ratio (target: at most 2);
4. for the largest size, measures the two parts of the issue's yardstick in
   fresh processes of their own: the time to read and decompress every
   block of the store (the blocks the command reads, on as many threads),
   and the in-memory ``analyze`` of a 512^3 volume (in process, best of
   ``--repeat``), and gives ``info N^3 zarr / (read + (N/512)^3 x analyze
   512^3)`` (target: at most 1.5) and the peak memory (target: under 2
   GiB).

Wall times on a shared machine depend on what else runs; CPU times less
so, and both are recorded (the ratios of CPU times beside those of wall
times).

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
import itertools
import json
import os
import platform
import resource
import shutil
import subprocess
import sys
import tempfile
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
    z.attrs.update(written_with(n, feature, level, seed))
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


def write_npy(path: Path, n: int, feature: int, level: float, seed: int) -> None:
    """The same volume as ``write_volume``'s, as one .npy (chunk by chunk
    into a memory map)."""
    coarse = coarse_field(n, feature, seed)
    out = np.lib.format.open_memmap(str(path), mode="w+", dtype=bool, shape=(n, n, n))
    for a in range(0, n, CHUNK):
        out[a:a + CHUNK] = chunk_of(coarse, ((a, min(a + CHUNK, n)), (0, n), (0, n)), feature, level)
    out.flush()
    del out


def run_measured(cmd: list[str]) -> dict:
    """Run a command in a fresh process: its wall time, CPU time (user +
    system), peak memory (MiB, ``ru_maxrss`` from ``os.wait4``) and
    standard output."""
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.perf_counter()
        p = subprocess.Popen(cmd, stdout=out, stderr=err)
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        if p.returncode:
            raise SystemExit(f"{' '.join(cmd)} failed:\n{err.read().decode()}")
        return {"wall_s": round(wall, 3), "cpu_s": round(usage.ru_utime + usage.ru_stime, 3),
                "peak_rss_mib": round(usage.ru_maxrss / 1024, 1), "stdout": out.read().decode()}


def info(path: Path, connectivity: int) -> dict:
    r = run_measured([sys.executable, "-m", "isoflow", "info", str(path), "--json", "--connectivity", str(connectivity)])
    report = json.loads(r.pop("stdout"))
    report.pop("input")
    r["report"] = report
    return r


def best(runs: list[dict]) -> dict:
    """The fastest run (by wall time), with the CPU time of the least."""
    out = dict(min(runs, key=lambda r: r["wall_s"]))
    out["cpu_s"] = min(r["cpu_s"] for r in runs)
    out["peak_rss_mib"] = max(r["peak_rss_mib"] for r in runs)
    out["runs"] = len(runs)
    return out


def child_read(path: str) -> dict:
    """Read and decompress every block of a store, as the out-of-core
    report reads them (its blocks, on as many threads)."""
    from concurrent.futures import ThreadPoolExecutor as Pool

    import zarr

    from isoflow.scale.chunks import block_bounds, zarr_blocks
    from isoflow.scale.compiled import thread_count

    z = zarr.open_array(path, mode="r")
    bounds = block_bounds(zarr_blocks(z, None))
    boxes = [tuple(slice(a, b) for a, b in box) for box in itertools.product(*bounds)]
    t0 = time.perf_counter()
    with Pool(thread_count()) as pool:
        voxels = sum(pool.map(lambda box: int(np.count_nonzero(np.asarray(z[box]))), boxes))
    return {"wall_s": round(time.perf_counter() - t0, 3), "voxels": voxels, "blocks": len(boxes)}


def child_analyze(path: str, repeat: int) -> dict:
    """The in-memory ``analyze`` of a .npy volume, in process, best of
    ``repeat`` (after one run that loads the compiled passes)."""
    from isoflow import analyze

    vol = np.load(path)
    analyze(vol)
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        analyze(vol)
        times.append(time.perf_counter() - t0)
    return {"wall_s": round(min(times), 4), "runs": repeat}


def child(kind: str, *args) -> dict:
    r = run_measured([sys.executable, __file__, "--child", kind, *map(str, args)])
    out = json.loads(r.pop("stdout").strip().splitlines()[-1])
    out["cpu_s"], out["process_wall_s"] = r["cpu_s"], r["wall_s"]
    return out


def written_with(n: int, feature: int, level: float, seed: int) -> dict:
    return {"porous": {"size": n, "feature": feature, "level": level, "seed": seed}}


def reusable(path: Path, n: int, args) -> bool:
    """A store of an earlier run with ``--keep``, written with the same
    parameters."""
    import zarr

    try:
        return dict(zarr.open_array(str(path), mode="r").attrs) == written_with(n, args.feature, args.level, args.seed)
    except Exception:  # no store, or not one of these
        return False


def measure_size(n: int, args, workdir: Path) -> dict:
    zpath, npath = workdir / f"porous-{n}.zarr", workdir / f"porous-{n}.npy"
    row = {"size": n, "chunks": [CHUNK] * 3, "connectivity": args.connectivity}
    if args.reuse and reusable(zpath, n, args):
        print(f"{n}^3: {zpath} as written before", flush=True)
    else:
        print(f"{n}^3: writing {zpath} ...", flush=True)
        row.update(write_volume(zpath, n, args.feature, args.level, args.seed))
        print(f"  written in {row['write_s']} s, {row['zarr_bytes'] / 2**20:.0f} MiB on disk", flush=True)
    if n <= args.npy_max and not (args.reuse and npath.exists()):
        write_npy(npath, n, args.feature, args.level, args.seed)
    runs = {"zarr": [], "npy": []}
    for _ in range(args.pairs):  # alternated: A B A B
        runs["zarr"].append(info(zpath, args.connectivity))
        if n <= args.npy_max:
            runs["npy"].append(info(npath, args.connectivity))
    zarr_run = best(runs["zarr"])
    report = zarr_run.pop("report")
    row["info_zarr"] = zarr_run
    row["result"] = {k: report[k] for k in ("voxels", "euler_characteristic", "betti", "pinched_vertices",
                                            "doubled_edges")}
    row["surfaces"] = len(report["surfaces"])
    print(f"  info .zarr: {zarr_run['wall_s']} s (CPU {zarr_run['cpu_s']} s), peak {zarr_run['peak_rss_mib']} MiB; "
          f"chi {report['euler_characteristic']}, betti {report['betti']}, {row['surfaces']} surfaces", flush=True)
    if runs["npy"]:
        npy_run = best(runs["npy"])
        row["equal_to_in_memory"] = npy_run.pop("report") == report
        row["info_npy"] = npy_run
        row["zarr_over_npy"] = round(zarr_run["wall_s"] / npy_run["wall_s"], 2)
        row["zarr_over_npy_cpu"] = round(zarr_run["cpu_s"] / npy_run["cpu_s"], 2)
        print(f"  info .npy: {npy_run['wall_s']} s (CPU {npy_run['cpu_s']} s), peak {npy_run['peak_rss_mib']} MiB; "
              f"zarr / npy {row['zarr_over_npy']} (CPU {row['zarr_over_npy_cpu']}); "
              f"reports equal: {row['equal_to_in_memory']}", flush=True)
        if not row["equal_to_in_memory"]:
            raise SystemExit("the out-of-core report differs from the in-memory one")
    return row


def yardstick(row: dict, args, workdir: Path) -> None:
    """Issue 27's yardstick for a large store: read + (n/512)^3 in-memory
    analyses of 512^3 (the .npy of 512^3 written if missing)."""
    n = row["size"]
    small = workdir / "porous-512.npy"
    if not small.exists():
        write_npy(small, 512, args.feature, args.level, args.seed)
    read = child("read", workdir / f"porous-{n}.zarr")
    analyze = child("analyze", small, args.repeat)
    scale = (n / 512) ** 3
    row["read_store"] = read
    row["analyze_512"] = analyze
    row["yardstick_s"] = round(read["wall_s"] + scale * analyze["wall_s"], 2)
    row["zarr_over_yardstick"] = round(row["info_zarr"]["wall_s"] / row["yardstick_s"], 2)
    print(f"  read and decompress: {read['wall_s']} s; analyze 512^3 in memory: {analyze['wall_s']} s; "
          f"yardstick {row['yardstick_s']} s; info .zarr / yardstick {row['zarr_over_yardstick']}", flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("size", nargs="?", type=int, help="one edge length (default 512)")
    ap.add_argument("--sizes", type=int, nargs="+", help="several edge lengths")
    ap.add_argument("--connectivity", type=int, default=6, choices=(6, 26))
    ap.add_argument("--feature", type=int, default=8, help="pore size scale in voxels")
    ap.add_argument("--level", type=float, default=0.3, help="threshold (in field standard deviations)")
    ap.add_argument("--seed", type=int, default=2013)
    ap.add_argument("--dir", type=Path, help="where to write the volumes (default: a temporary folder)")
    ap.add_argument("--keep", action="store_true", help="keep the volumes")
    ap.add_argument("--reuse", action="store_true",
                    help="use the volumes an earlier run left in --dir with --keep (same size and parameters)")
    ap.add_argument("--npy-max", type=int, default=512, help="compare with the .npy command up to this size")
    ap.add_argument("--pairs", type=int, default=3, help="runs of each command, alternated; the best is kept")
    ap.add_argument("--repeat", type=int, default=5, help="in-memory analyses of 512^3 for the yardstick")
    ap.add_argument("--json", type=Path, default=HERE / "results" / "outofcore.json")
    ap.add_argument("--child", nargs="+", metavar="ARG", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.child:
        kind, *rest = args.child
        print(json.dumps(child_read(*rest) if kind == "read" else child_analyze(rest[0], int(rest[1]))))
        return 0

    sizes = args.sizes or [args.size or 512]
    workdir = args.dir or Path(tempfile.mkdtemp(prefix="isoflow-bench-"))
    workdir.mkdir(parents=True, exist_ok=True)
    rows = []
    for n in sizes:
        row = measure_size(n, args, workdir)
        if n > args.npy_max:
            yardstick(row, args, workdir)
        rows.append(row)
        if not args.keep:
            shutil.rmtree(workdir / f"porous-{n}.zarr")
            (workdir / f"porous-{n}.npy").unlink(missing_ok=True)
    if not args.keep:
        (workdir / "porous-512.npy").unlink(missing_ok=True)
        if args.dir is None:
            shutil.rmtree(workdir, ignore_errors=True)
    if args.json:
        write_results(args, rows)
    return 0


def write_results(args, rows: list[dict]) -> None:
    import dask
    import zarr

    args.json.parent.mkdir(parents=True, exist_ok=True)
    meta = {
        "benchmark": "isoflow info of a smoothed random porous volume as .zarr (out of core) and as .npy",
        "machine": platform.platform(),
        "cpus": os.cpu_count(),
        "ram_gb": round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1),
        "load_average": round(os.getloadavg()[0], 2),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "dask": dask.__version__,
        "zarr": zarr.__version__,
        "feature": args.feature,
        "level": args.level,
        "seed": args.seed,
        "pairs": args.pairs,
    }
    args.json.write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    print(f"results in {args.json.name}")


if __name__ == "__main__":
    sys.exit(main())
