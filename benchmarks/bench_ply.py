"""PLY meshes read with NumPy alone (``isoflow.mesh.ply``) against trimesh.

    python benchmarks/bench_ply.py --baseline ../other/src        # whole commands against another checkout
    python benchmarks/bench_ply.py --repeat 5 --json ''           # in process only, no file written

Inputs: ``meshes/bob_small.ply`` (the README's sample), an icosphere of
327,680 faces written by trimesh as binary PLY and as ASCII PLY (under
``benchmarks/.cache/``).

In process (best of ``--repeat``, alternated): ``read_ply`` of the file's
bytes against ``trimesh.load(path, process=False, force="mesh")``, the
peer a user would otherwise call (trimesh imported before timing: its
import is in the whole-command figures).

Whole commands (``--baseline SRC``, medians of ``--commands`` alternated
pairs): ``isoflow info FILE --resolution 64`` with this tree's ``src`` and
with ``SRC`` (say, a checkout before the PLY reader, which read PLY
through trimesh).

Results go to ``benchmarks/results/ply.json`` and a Markdown table on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / "benchmarks" / ".cache"


def inputs() -> list[Path]:
    """The sample, and the icosphere as binary and ASCII PLY (made once)."""
    binary, ascii_ = CACHE / "ico7.ply", CACHE / "ico7_ascii.ply"
    if not (binary.exists() and ascii_.exists()):
        import trimesh

        CACHE.mkdir(parents=True, exist_ok=True)
        sphere = trimesh.creation.icosphere(7)
        sphere.export(binary)
        sphere.export(ascii_, encoding="ascii")
    return [ROOT / "meshes" / "bob_small.ply", binary, ascii_]


def in_process(path: Path, repeat: int) -> dict:
    import numpy as np
    import trimesh

    from isoflow.mesh.ply import read_ply

    best = {"isoflow": float("inf"), "trimesh": float("inf")}
    for _ in range(repeat):
        t0 = time.perf_counter()
        ours = read_ply(path.read_bytes())
        t1 = time.perf_counter()
        theirs = trimesh.load(path, process=False, force="mesh")
        t2 = time.perf_counter()
        best["isoflow"], best["trimesh"] = min(best["isoflow"], t1 - t0), min(best["trimesh"], t2 - t1)
    assert ours is not None and np.array_equal(ours[1], theirs.faces) and np.array_equal(ours[0], theirs.vertices)
    return {"faces": len(theirs.faces), "isoflow_read_s": best["isoflow"], "trimesh_load_s": best["trimesh"],
            "ratio": best["trimesh"] / best["isoflow"]}


def command(src: Path, path: Path) -> float:
    env = dict(os.environ, PYTHONPATH=str(src))
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "isoflow", "info", str(path), "--resolution", "64", "--quiet"], env=env,
                   check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def whole(path: Path, baseline: Path, pairs: int) -> dict:
    here = ROOT / "src"
    command(here, path), command(baseline, path)  # numba's caches of both trees written
    ours, theirs = [], []
    for _ in range(pairs):
        ours.append(command(here, path))
        theirs.append(command(baseline, path))
    a, b = statistics.median(ours), statistics.median(theirs)
    return {"command_s": a, "baseline_command_s": b, "speedup": b / a}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--baseline", type=Path, help="another checkout's src, for whole commands")
    p.add_argument("--commands", type=int, default=5, help="alternated pairs of whole commands")
    p.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "ply.json"))
    args = p.parse_args(argv)
    rows = []
    for path in inputs():
        row = {"input": path.name, **in_process(path, args.repeat)}
        if args.baseline:
            row.update(whole(path, args.baseline.resolve(), args.commands))
        rows.append(row)
    print("| input | faces | read_ply s | trimesh.load s | ratio | command s | baseline command s | speedup |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        cmd = (f"{r['command_s']:.2f} | {r['baseline_command_s']:.2f} | {r['speedup']:.2f}x" if "speedup" in r
               else "- | - | -")
        print(f"| {r['input']} | {r['faces']} | {r['isoflow_read_s']:.4f} | {r['trimesh_load_s']:.4f} | "
              f"{r['ratio']:.1f}x | {cmd} |")
    if args.json:
        given = [str(a) for a in (argv if argv is not None else sys.argv[1:])]
        given = ["BASELINE_SRC" if args.baseline and a == str(args.baseline) else a for a in given]  # no machine's path
        meta = {"command": "python benchmarks/bench_ply.py " + " ".join(given),
                "cpus": os.cpu_count(), "python": sys.version.split()[0], "load_average": os.getloadavg()}
        Path(args.json).write_text(json.dumps({"meta": meta, "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
