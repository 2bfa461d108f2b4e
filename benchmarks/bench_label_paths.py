"""Which pass ``label_table(..., method="auto")`` should take on a small or
mid-size label image: the compiled pass pays numba's import and loading its
cached code for the label kernels once per process, the NumPy pass pays per
label.

    python benchmarks/bench_label_paths.py                       # 64^3 .. 192^3
    python benchmarks/bench_label_paths.py --sizes 64 128 --repeat 3

Inputs (cached in benchmarks/.cache/): grain maps of
:func:`bench_labels.grains` with 100, 1,000 and 10,000 labels (a count
only where it leaves a grain at least 4 voxels across), and a random label
image: labels drawn at random for blocks of 4^3 voxels (100 labels, each
scattered over the whole image, so each label's box is the image's).

For every input and both methods: the whole command, ``python -c`` running
``label_table(np.load(FILE), 6, method=M)`` in a fresh process, best of
``--repeat`` after one untimed run (numba's cache warm); and in process with
numba and the label kernels already loaded, best of ``--repeat``. The
crossover is the smallest input where the compiled pass as a whole command
beats the NumPy one.

Results go to ``benchmarks/results/label_paths.json`` (``--json``) and a
Markdown table on stdout.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_labels import ROOT, cached, cached_array  # noqa: E402

SCRIPT = ("import sys, numpy as np; from isoflow import label_table; "
          "print(len(label_table(np.load(sys.argv[1]), 6, method=sys.argv[2])['label']))")


def scattered(size: int, count: int, block: int = 4, seed: int = 0) -> Path:
    """Random labels 1..count on blocks of ``block``^3 voxels, cached."""
    def make():
        rng = np.random.default_rng(seed)
        coarse = rng.integers(1, count + 1, (size // block,) * 3).astype(np.uint32)
        return np.kron(coarse, np.ones((block,) * 3, np.uint32))

    return cached_array(f"scattered-{size}-{count}", make)


def inputs(sizes: list[int]) -> list[tuple[str, int, int, Path]]:
    out = []
    for size in sizes:
        for count in (100, 1000, 10_000):
            if size**3 / count >= 4**3:
                out.append(("grains", size, count, cached(size, count)))
        out.append(("scattered", size, 100, scattered(size, 100)))
    return out


def whole(path: Path, method: str, repeat: int) -> float:
    cmd = [sys.executable, "-c", SCRIPT, str(path), method]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)  # numba's cache warm
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
        best = min(best, time.perf_counter() - start)
    return best


def in_process(path: Path, method: str, repeat: int) -> float:
    from isoflow import label_table

    image = np.load(path)
    label_table(image, 6, method=method)
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        label_table(image, 6, method=method)
        best = min(best, time.perf_counter() - start)
    return best


def crossovers(rows: list[dict]) -> dict:
    """For each input and label count, the smallest size from which the
    compiled pass's whole command is the sooner (None: never measured so)."""
    out: dict = {}
    for r in rows:
        key = f"{r['input']}-{r['labels']}"
        out.setdefault(key, None)
        if out[key] is None and r["compiled_command_seconds"] < r["numpy_command_seconds"]:
            out[key] = r["size"]
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 96, 128, 160, 192])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "label_paths.json"))
    args = ap.parse_args(argv)
    rows = []
    print("| input | size | labels | numpy cmd s | compiled cmd s | numpy in process s | compiled in process s |")
    print("|---|---|---|---|---|---|---|")
    for kind, size, count, path in inputs(args.sizes):
        row = {"input": kind, "size": size, "labels": count, "voxels": size**3}
        for method in ("numpy", "compiled"):
            row[f"{method}_command_seconds"] = whole(path, method, args.repeat)
            row[f"{method}_in_process_seconds"] = in_process(path, method, args.repeat)
        rows.append(row)
        print(f"| {kind} | {size} | {count} | {row['numpy_command_seconds']:.3f} | {row['compiled_command_seconds']:.3f} "
              f"| {row['numpy_in_process_seconds']:.3f} | {row['compiled_in_process_seconds']:.3f} |", flush=True)
    summary = {"compiled_command_sooner_from": crossovers(rows)}
    print(summary)
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows, **summary, "repeat": args.repeat}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
