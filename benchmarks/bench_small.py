"""Benchmark: many small volumes in one process.

A script that reports on N small volumes (64^3 by default, below the
4 million voxels from which ``analyze`` starts with numba) in a loop, as a
fresh process each, the way a user runs it: ``isoflow.analyze(vol, 6)``
against scikit-image's ``euler_number(vol, connectivity=1)`` (chi alone),
against ``analyze(vol, 6, method="compiled")``, and against a loop whose
first call asks for ``"compiled"`` and the rest for ``"auto"``. ``"auto"``
takes the NumPy census until the voxels it has sent down it and the
volume at hand reach 4 million (the ski-rental rule: 15 volumes of 64^3),
or the compiled census is loaded in the process (a compiled pass ran
there), and the compiled one after, so one or ten small volumes never
import numba and a long loop pays its start once; the compiled census
then answers each small volume in milliseconds. The volumes are smoothed
random porous fields (the hard case of benchmarks/run.py), four seeds
repeated. Whole-process seconds, imports included; the tools alternated,
medians, the ratios of scikit-image's time to the first two.

Usage::

    python benchmarks/bench_small.py [--size 64] [--count 1 10 100] [--repeat 3]
"""

from __future__ import annotations

import argparse
import resource
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
        def method(i):
            return "compiled" if tool == "isoflow-compiled" or (tool == "compiled-then-auto" and i == 0) else "auto"
        out = [analyze(vols[i % 4], 6, method=method(i))["euler_characteristic"] for i in range(count)]
    print(sum(out))
""")

TOOLS = ("isoflow", "isoflow-compiled", "compiled-then-auto", "skimage")


def seconds(tool: str, size: int, count: int) -> tuple[float, float, str]:
    """One fresh process: its wall time, its CPU time (user and system: on
    a shared machine the wall time also counts the other jobs' share of the
    cores) and what it printed (the chi sum)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", SCRIPT, tool, str(size), str(count)], capture_output=True,
                         text=True, check=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime
    return wall, cpu, out.stdout.strip()


def row(count: int, med: dict) -> str:
    """One line of a table: the medians and scikit-image's time over auto's and compiled's."""
    return (f"{count:>8}" + "".join(f"{med[t]:>18.2f} s" for t in TOOLS)
            + f"{med['skimage'] / med['isoflow']:>13.2f}x{med['skimage'] / med['isoflow-compiled']:>17.2f}x")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--count", type=int, nargs="+", default=[1, 10, 100])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    head = f"{'volumes':>8}" + "".join(f"{t:>20}" for t in TOOLS) + f"{'skimage/auto':>14}{'skimage/compiled':>18}"
    lines = {"wall": [], "cpu": []}
    for count in args.count:
        times = {kind: {t: [] for t in TOOLS} for kind in lines}
        chis = set()
        for _ in range(args.repeat):
            for t in TOOLS:
                wall, cpu, chi = seconds(t, args.size, count)
                times["wall"][t].append(wall)
                times["cpu"][t].append(cpu)
                chis.add(chi)
        if len(chis) != 1:
            print(f"chi differs between the tools: {chis}", file=sys.stderr)
            return 1
        for kind in lines:
            lines[kind].append(row(count, {t: statistics.median(v) for t, v in times[kind].items()}))
            print(f"{kind:>4} {lines[kind][-1]}", flush=True)
    for kind, what in (("wall", "wall-clock"), ("cpu", "CPU (user + system)")):
        print(f"\n{args.size}^3 porous volumes, one process each, {what} seconds, medians of {args.repeat} alternated "
              "runs (input generation included in every column)")
        print(head, *lines[kind], sep="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
