"""``isoflow surface STORE.zarr`` (block by block) against the in-memory
``isoflow surface VOLUME.npy``, as whole commands.

    python benchmarks/bench_surface_store.py                         # ball 512^3, mesh 512^3 and 1024^3
    python benchmarks/bench_surface_store.py --mesh 512 1024 2048 --dir /big/disk

Inputs, made once in ``--dir`` (default benchmarks/.cache/):

* ``ball-N.zarr``: a ball of radius 0.45 N (benchmarks/run.py's), zarr v3,
  bool, chunks 128^3, blosc-zstd with bit shuffle, written chunk by chunk;
  ``ball-N.npy`` beside it for the in-memory command;
* ``mesh-N.zarr``: a 94k-triangle mesh (Spot, :func:`isoflow.data.spot`, or
  ``--mesh-file``, subdivided twice) voxelised at N voxels along its
  longest side by ``isoflow voxelize`` (an OME-Zarr store, slab chunks);
  ``mesh-N.npy`` read from it for the in-memory command (N <= 512).

Each command runs in a fresh process, the pairs alternated, ``--repeat``
rounds; wall time and peak memory (``ru_maxrss`` of the process and of its
children). Results go to benchmarks/results/surface_store.json (no
absolute paths). The ratio the issue asks for: the store's time over 64
times the in-memory 512^3 time of the same shape, for 2048^3 (64 times the
voxels, 16 times the surface); the table gives it for every size as the
store's time over (n / 512)^3 times the in-memory 512^3 time.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
CHUNK = 128


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env


def write_ball(path: Path, n: int) -> None:
    import zarr
    from zarr.codecs import BloscCodec

    z = zarr.create_array(store=str(path), shape=(n,) * 3, chunks=(CHUNK,) * 3, dtype=bool, overwrite=True,
                          compressors=BloscCodec(cname="zstd", clevel=3, shuffle="bitshuffle"))
    c, r2 = (n - 1) / 2, (0.45 * n) ** 2
    for x0 in range(0, n, CHUNK):
        x = np.arange(x0, min(x0 + CHUNK, n), dtype=np.float32)[:, None, None] - c
        y = np.arange(n, dtype=np.float32)[None, :, None] - c
        z_ = np.arange(n, dtype=np.float32)[None, None, :] - c
        z[x0:x0 + CHUNK] = x**2 + y**2 + z_**2 <= r2


def mesh_file(arg: str | None, tmp: Path) -> Path:
    """Spot subdivided twice (5856 -> 93,696 triangles), as PLY."""
    import trimesh

    from isoflow import data

    src = Path(arg) if arg else data.spot()
    out = tmp / "spot94k.ply"
    if not out.exists():
        m = trimesh.load(src, force="mesh")
        m = m.subdivide().subdivide()
        m.export(out)
    return out


def ensure(kind: str, n: int, directory: Path, args) -> tuple[Path, Path | None]:
    store, npy = directory / f"{kind}-{n}.zarr", directory / f"{kind}-{n}.npy"
    if not store.exists():
        t = time.perf_counter()
        if kind == "ball":
            write_ball(store, n)
        else:
            subprocess.run([sys.executable, "-m", "isoflow", "voxelize", str(mesh_file(args.mesh_file, directory)),
                            "-o", str(store), "--resolution", str(n), "--quiet"], check=True, env=_env())
        print(f"made {store.name} in {time.perf_counter() - t:.0f} s", flush=True)
    if n <= 512 and not npy.exists():
        code = ("import sys, numpy as np; from isoflow.mesh.volumes import read_object; "
                "np.save(sys.argv[2], read_object(sys.argv[1]).volume)")
        subprocess.run([sys.executable, "-c", code, str(store), str(npy)], check=True, env=_env())
    return store, (npy if n <= 512 else None)


CODE = ("import resource, sys, time; t = time.perf_counter(); from isoflow.cli import main; rc = main(sys.argv[1:]); "
        "s = time.perf_counter() - t; r = resource.getrusage; "
        "print('{\"seconds\": %.3f, \"rc\": %d, \"peak_bytes\": %d}' % (s, rc, 1024 * max("
        "r(resource.RUSAGE_SELF).ru_maxrss, r(resource.RUSAGE_CHILDREN).ru_maxrss)))")


def command(path: Path, threads: int | None) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "s.ply"
        argv = ["surface", str(path), "-o", str(out), "--quiet"] + (["--threads", str(threads)] if threads else [])
        p = subprocess.run([sys.executable, "-c", CODE, *argv], capture_output=True, text=True, env=_env())
        lines = [ln for ln in p.stdout.splitlines() if ln.startswith("{")]
        if p.returncode or not lines:
            return {"error": ((p.stderr or p.stdout).strip().splitlines() or ["?"])[-1]}
        res = json.loads(lines[-1])
        summary = [ln.replace(str(out), out.name) for ln in p.stdout.splitlines() if ln.startswith(str(out))]
        res.update(file_bytes=out.stat().st_size, summary=summary)
        return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ball", type=int, nargs="*", default=[512])
    ap.add_argument("--mesh", type=int, nargs="*", default=[512, 1024])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--threads", type=int, help="--threads of the store's command")
    ap.add_argument("--dir", default=str(HERE / ".cache"))
    ap.add_argument("--mesh-file")
    ap.add_argument("--out", default=str(HERE / "results" / "surface_store.json"))
    args = ap.parse_args(argv)
    directory = Path(args.dir)
    directory.mkdir(parents=True, exist_ok=True)
    rows = []
    for kind, sizes in (("ball", args.ball), ("mesh", args.mesh)):
        for n in sizes:
            store, npy = ensure(kind, n, directory, args)
            runs: dict = {"store": [], "memory": []}
            for r in range(args.repeat):
                order = ["store", "memory"] if r % 2 == 0 else ["memory", "store"]
                for which in order:
                    if which == "memory" and npy is None:
                        continue
                    res = command(store if which == "store" else npy, args.threads if which == "store" else None)
                    runs[which].append(res)
                    print(f"{kind} {n}^3 {which}: {res.get('seconds', float('nan')):.1f} s, "
                          f"{res.get('peak_bytes', 0) / 2**20:.0f} MiB {res.get('error', '')}", flush=True)
            row = {"input": kind, "size": n, "runs": runs}
            for which, got in runs.items():
                ok = [g for g in got if "error" not in g]
                if ok:
                    row[which] = {"seconds": statistics.median(g["seconds"] for g in ok),
                                  "peak_bytes": statistics.median(g["peak_bytes"] for g in ok),
                                  "file_bytes": ok[0]["file_bytes"], "summary": ok[0]["summary"]}
            rows.append(row)
    by = {(r["input"], r["size"]): r for r in rows}
    for (kind, n), r in by.items():
        base = by.get((kind, 512), {}).get("memory")
        if base and "store" in r:
            r["store_over_memory_512_scaled"] = r["store"]["seconds"] / (base["seconds"] * (n / 512) ** 3)
            if n == 512:
                r["peak_ratio_store_over_memory"] = r["store"]["peak_bytes"] / base["peak_bytes"]
    lines = ["| input | store s | store peak MiB | in-memory s | in-memory peak MiB | store / (in-memory 512^3 x (n/512)^3) |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        s, m = r.get("store", {}), r.get("memory", {})
        lines.append(f"| {r['input']} {r['size']}^3 | {s.get('seconds', float('nan')):.1f} | "
                     f"{s.get('peak_bytes', 0) / 2**20:.0f} | {m.get('seconds', float('nan')):.1f} | "
                     f"{m.get('peak_bytes', 0) / 2**20:.0f} | {r.get('store_over_memory_512_scaled', float('nan')):.2f} |")
    print("\n".join(lines))
    meta = {"python": platform.python_version(), "cpus": os.cpu_count(), "date": time.strftime("%Y-%m-%d %H:%M"),
            "argv": [a for a in sys.argv[1:] if not a.startswith("/")], "loadavg_1min": os.getloadavg()[0]}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"meta": meta, "rows": rows, "table": "\n".join(lines)}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
