"""Paired A/B of the out-of-core ``isoflow info X.zarr --json`` between two
source trees (e.g. main's and a branch's), for a machine shared with other
jobs, where only runs side by side compare.

    python benchmarks/ab_outofcore.py DIR/porous-1024.zarr --a MAIN/src --b src --pairs 6

Each command runs in a fresh process with ``PYTHONPATH`` set to one tree,
A and B alternated (A B, B A, A B, ...); the best wall time and the least
CPU time (user + system, ``os.wait4``) of each are kept, with the peak
memory, the load average at every run, and whether the two reports are
equal (they must be). The store is one that ``bench_outofcore.py --keep``
wrote.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def run(store: Path, src: Path) -> tuple[dict, dict]:
    """One ``info`` command with ``src`` first on the path: its times and its report."""
    env = dict(os.environ, PYTHONPATH=str(src))
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-m", "isoflow", "info", str(store), "--json"], env=env,
                         stdout=subprocess.PIPE)
    out = p.stdout.read() if p.stdout else b""
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    if os.waitstatus_to_exitcode(status):
        raise SystemExit(f"isoflow info {store} failed with {src}")
    report = json.loads(out)
    report.pop("input", None)
    return {"wall_s": round(wall, 3), "cpu_s": round(usage.ru_utime + usage.ru_stime, 3),
            "peak_rss_mib": round(usage.ru_maxrss / 1024, 1), "load_average": round(os.getloadavg()[0], 2)}, report


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("store", type=Path, help="a zarr store written by bench_outofcore.py --keep")
    ap.add_argument("--a", type=Path, required=True, help="the first source tree (its src folder)")
    ap.add_argument("--b", type=Path, required=True, help="the second source tree")
    ap.add_argument("--pairs", type=int, default=5, help="runs of each, alternated")
    ap.add_argument("--json", type=Path, help="write the runs here (no absolute paths)")
    args = ap.parse_args(argv)
    trees = {"a": args.a.resolve(), "b": args.b.resolve()}
    runs: dict[str, list[dict]] = {"a": [], "b": []}
    reports = {}
    for i in range(args.pairs):
        for name in ("a", "b") if i % 2 == 0 else ("b", "a"):
            timing, reports[name] = run(args.store, trees[name])
            runs[name].append(timing)
            print(name, timing, flush=True)
    best = {name: {"wall_s": min(r["wall_s"] for r in rs), "cpu_s": min(r["cpu_s"] for r in rs),
                   "peak_rss_mib": max(r["peak_rss_mib"] for r in rs)} for name, rs in runs.items()}
    result = {"store": args.store.name, "equal_reports": reports["a"] == reports["b"], "best": best,
              "b_over_a": {k: round(best["b"][k] / best["a"][k], 3) for k in ("wall_s", "cpu_s")},
              "runs": runs, "machine": platform.platform(), "cpus": os.cpu_count()}
    print(json.dumps({k: result[k] for k in ("equal_reports", "best", "b_over_a")}))
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))
    return 0 if result["equal_reports"] else 1


if __name__ == "__main__":
    sys.exit(main())
