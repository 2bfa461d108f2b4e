"""What ``flow --out`` pays for its files and for reading each back with trimesh.

    python benchmarks/bench_flow_files.py                      # 64^3 ball (6) and 48^3 porous (26)
    mkdir -p benchmarks/.cache/base && git archive main src | tar -x -C benchmarks/.cache/base   # another version
    python benchmarks/bench_flow_files.py --baseline-src benchmarks/.cache/base/src --repeat 5

Whole command (what a user waits for): ``isoflow flow X --out D`` of this
tree against ``--baseline-src`` when given (paired: A B A B ..., medians of
wall clock and of the child's CPU time, which survives a shared machine
better), and against ``isoflow flow X`` without files. In process: the
CPU seconds of the step files' trimesh read-back
(:func:`isoflow.mesh.readback.check_surface_file`, on its worker thread)
and of writing them, against the whole run.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import timed_command  # noqa: E402


def objects(tmp: Path) -> list[tuple[str, Path, list[str]]]:
    from scipy.ndimage import gaussian_filter

    x = np.indices((64,) * 3) - 31.5
    np.save(tmp / "ball64.npy", (x**2).sum(0) <= 28**2)
    field = np.random.default_rng(0).random((48,) * 3)
    np.save(tmp / "porous48.npy", gaussian_filter(field, 2.0) > 0.5)
    return [("ball 64^3, 6-conn", tmp / "ball64.npy", []),
            ("porous 48^3, 26-conn", tmp / "porous48.npy", ["--connectivity", "26"])]


def command(src: Path, inp: Path, out: Path | None, extra: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds of one ``isoflow flow`` from the source tree ``src``."""
    args = [sys.executable, "-m", "isoflow.cli", "flow", str(inp), *extra]
    if out is not None:
        shutil.rmtree(out, ignore_errors=True)
        args += ["--out", str(out)]
    return timed_command(args, str(src))


def in_process(inp: Path, out: Path, extra: list[str]) -> dict:
    """CPU seconds of the read-back and of the writes inside one run."""
    sys.path.insert(0, str(ROOT / "src"))
    from isoflow.cli import main
    from isoflow.flow import files

    spent = {"readback": 0.0, "write": 0.0}

    def timed(fn, key):
        def wrapper(*a, **k):
            t = time.thread_time()  # the worker thread's own CPU time
            try:
                return fn(*a, **k)
            finally:
                spent[key] += time.thread_time() - t
        return wrapper

    real_check, real_write = files.check_surface_file, files.export.write_mesh_file
    files.check_surface_file = timed(real_check, "readback")
    files.export.write_mesh_file = timed(real_write, "write")
    try:
        shutil.rmtree(out, ignore_errors=True)
        t = time.process_time()
        with contextlib.redirect_stdout(io.StringIO()):
            main(["flow", str(inp), "--out", str(out), *extra])
        total = time.process_time() - t
    finally:
        files.check_surface_file, files.export.write_mesh_file = real_check, real_write
    steps = len(list(out.glob("step_*.ply")))
    return {"cpu_total": total, "steps": steps, **spent}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--baseline-src", type=Path, help="src/ of another isoflow version to compare with")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="bench_flow_files_"))
    print(f"machine: {os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
    try:
        for name, inp, extra in objects(tmp):
            runs = {"this --out": (ROOT / "src", tmp / "a"), "this, no files": (ROOT / "src", None)}
            if args.baseline_src:
                runs["baseline --out"] = (args.baseline_src, tmp / "b")
            times = {k: ([], []) for k in runs}
            for _ in range(args.repeat):
                for key, (src, out) in runs.items():
                    wall, cpu = command(src, inp, out, extra)
                    times[key][0].append(wall)
                    times[key][1].append(cpu)
            med = {k: (statistics.median(w), statistics.median(c)) for k, (w, c) in times.items()}
            print(f"\n{name}: whole command, medians of {args.repeat} (wall s, CPU s)")
            for key, (w, c) in med.items():
                print(f"  {key:<16} {w:7.2f} {c:7.2f}")
            if args.baseline_src:
                (wa, ca), (wb, cb) = med["this --out"], med["baseline --out"]
                print(f"  ratio this/baseline --out: wall {wa / wb:.2f}, CPU {ca / cb:.2f}")
            r = in_process(inp, tmp / "p", extra)
            print(f"  in process: {r['steps']} step files, CPU {r['cpu_total']:.2f} s in all, "
                  f"read-back {r['readback']:.2f} s ({100 * r['readback'] / r['cpu_total']:.0f} %), "
                  f"writing {r['write']:.2f} s ({100 * r['write'] / r['cpu_total']:.0f} %)")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
