"""CPU time of a plain flow whose steps change the topology, each change
placed (``topology_changes[i]["where"]``).

    python benchmarks/bench_plain_changes.py 96 12
    python benchmarks/bench_plain_changes.py 192 6 --baseline OTHER/src --repeat 2

The input is a smoothed random field of ``N^3`` voxels (uniform noise,
seed 1, gaussian sigma 2, > 0.5): porous, so that nearly every step
changes the Betti numbers. ``run_flow(obj, STEPS, guard=False)`` at 6
(``--connectivity``), by the method ``auto`` takes (bit rows from 2^18
voxels); the CPU seconds of all threads, and the number of changes. With
``--baseline SRC`` each run is a fresh process, this tree's and the tree
``SRC``'s in turn (give each its own ``NUMBA_CACHE_DIR`` if they differ
in compiled code); the two must count the same changes. ``--json PATH``
writes the seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage


def measure(n: int, steps: int, connectivity: int) -> tuple[float, int]:
    """``(CPU seconds, changes)`` of the plain run of the field of side ``n``."""
    import isoflow
    from isoflow.flow.run import run_flow

    rng = np.random.default_rng(1)
    volume = ndimage.gaussian_filter(rng.random((n, n, n)), 2) > 0.5
    start = time.process_time()
    result = run_flow(isoflow.DigitalObject(volume), steps, guard=False, connectivity=connectivity, keep_states=False)
    return time.process_time() - start, len(result.topology_changes)


def in_process(src: Path, args) -> tuple[float, int]:
    """One measurement in a fresh process on the isoflow tree ``src``."""
    env = dict(os.environ, PYTHONPATH=str(src))
    command = [sys.executable, __file__, str(args.n), str(args.steps), "--connectivity", str(args.connectivity), "--one"]
    out = subprocess.run(command, env=env, capture_output=True, text=True, check=True).stdout
    cpu, changes = json.loads(out.splitlines()[-1])
    return cpu, changes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n", type=int)
    parser.add_argument("steps", type=int)
    parser.add_argument("--connectivity", type=int, default=6)
    parser.add_argument("--baseline", type=Path, help="another isoflow source tree, timed in turn")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--json", type=Path, help="write the seconds here")
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure(args.n, args.steps, args.connectivity)))
        return
    trees = {"this tree": Path(__file__).resolve().parents[1] / "src"}
    if args.baseline is not None:
        trees["baseline"] = args.baseline
    seconds: dict = {name: [] for name in trees}
    counts = set()
    for _ in range(args.repeat):
        for name, src in trees.items():
            cpu, changes = in_process(src, args)
            seconds[name].append(round(cpu, 2))
            counts.add(changes)
            print(f"{name}: {args.n}^3, {args.steps} steps: cpu {cpu:.2f} s, changes {changes}", flush=True)
    if len(counts) > 1:
        sys.exit(f"the trees count different topology changes: {sorted(counts)}")
    if args.json is not None:
        args.json.write_text(json.dumps({"n": args.n, "steps": args.steps, "connectivity": args.connectivity,
                                         "changes": counts.pop(), "cpu_seconds": seconds}, indent=1) + "\n")


if __name__ == "__main__":
    main()
