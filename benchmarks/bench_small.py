"""Benchmark: many small volumes in one process.

A script that reports on N small volumes (64^3 by default, below the
4 million voxels from which ``analyze`` starts with numba) in a loop, as a
fresh process each, the way a user runs it: ``isoflow.analyze(vol, 6)``
against scikit-image's ``euler_number(vol, connectivity=1)`` (chi alone),
and against ``analyze(vol, 6, method="compiled")``: ``"auto"`` chooses the
passes by the volume alone, so every call below 4 million voxels takes
the NumPy census, whatever the process has loaded; the compiled census
pays numba's start once and then answers each small volume in
milliseconds. The volumes are smoothed
random porous fields (the hard case of benchmarks/run.py), four seeds
repeated. Whole-process seconds, imports included; pairs alternated,
medians, the ratios of each pair.

Usage::

    python benchmarks/bench_small.py [--size 64] [--count 1 10 100] [--repeat 3]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import textwrap
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = textwrap.dedent("""
    import sys
    import numpy as np
    from scipy.ndimage import gaussian_filter

    tool, size, count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    vols = []
    for seed in range(4):
        field = np.random.default_rng(seed).random((size,) * 3, dtype=np.float32)
        vols.append(gaussian_filter(field, 2.0) > 0.5)
    if tool == "skimage":
        from skimage.measure import euler_number
        out = [euler_number(vols[i % 4], connectivity=1) for i in range(count)]
    else:
        from isoflow import analyze
        method = "compiled" if tool == "isoflow-compiled" else "auto"
        out = [analyze(vols[i % 4], 6, method=method)["euler_characteristic"] for i in range(count)]
    print(sum(out))
""")

TOOLS = ("isoflow", "isoflow-compiled", "skimage")


def seconds(tool: str, size: int, count: int) -> tuple[float, str]:
    """One fresh process: its wall time and what it printed (the chi sum)."""
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", SCRIPT, tool, str(size), str(count)], capture_output=True,
                         text=True, check=True)
    return time.perf_counter() - start, out.stdout.strip()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--count", type=int, nargs="+", default=[1, 10, 100])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{args.size}^3 porous volumes, one process each, medians of {args.repeat} alternated runs "
          "(input generation included in every column)")
    print(f"{'volumes':>8}" + "".join(f"{t:>18}" for t in TOOLS) + f"{'skimage/auto':>14}{'skimage/compiled':>18}")
    for count in args.count:
        times = {t: [] for t in TOOLS}
        chis = set()
        for _ in range(args.repeat):
            for t in TOOLS:
                s, chi = seconds(t, args.size, count)
                times[t].append(s)
                chis.add(chi)
        if len(chis) != 1:
            print(f"chi differs between the tools: {chis}", file=sys.stderr)
            return 1
        med = {t: statistics.median(v) for t, v in times.items()}
        print(f"{count:>8}" + "".join(f"{med[t]:>16.2f} s" for t in TOOLS)
              + f"{med['skimage'] / med['isoflow']:>13.2f}x{med['skimage'] / med['isoflow-compiled']:>17.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
