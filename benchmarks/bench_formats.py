"""Benchmark: reading a volume file with isoflow against the format's own library.

What the user would otherwise write is the library's read into a NumPy
array; ``isoflow.read_volume`` does that read plus the 0/1 check, the turn to
(x, y, z) and the placement. The ratio (isoflow / library, paired A B A B in
the same run, medians) is the cost of going through isoflow. Each file holds
the same N^3 ball, written once by ``isoflow.write_volume``; a whole command
(``isoflow info FILE --no-surfaces``) is timed against the same on the .npy.

Usage::

    PYTHONPATH=src python benchmarks/bench_formats.py [--size 256] [--repeat 5] [OUT.json]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import isoflow  # noqa: E402


def library_readers():
    """suffix -> the read a user would write with the format's own library."""
    import h5py
    import nibabel
    import nrrd
    import tifffile
    import zarr
    from trimesh.exchange.binvox import load_binvox

    def h5(p):
        with h5py.File(p, "r") as f:
            return f["volume"][()]

    def binvox(p):
        with open(p, "rb") as fh:
            return load_binvox(fh).matrix

    return {
        ".npz": lambda p: np.load(p)["volume"],
        ".nii.gz": lambda p: np.asanyarray(nibabel.load(p).dataobj),
        ".tif": tifffile.imread,
        ".nrrd": lambda p: nrrd.read(str(p))[0],
        ".h5": h5,
        ".binvox": binvox,
        ".zarr": lambda p: zarr.open_group(str(p), mode="r")["0"][...],
    }


def paired(a, b, repeat):
    ta, tb = [], []
    for _ in range(repeat):
        for f, out in ((a, ta), (b, tb)):
            t = time.perf_counter()
            f()
            out.append(time.perf_counter() - t)
    return statistics.median(ta), statistics.median(tb)


def command(args):
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "isoflow.cli", *map(str, args)], check=True, capture_output=True)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", nargs="?", default=str(ROOT / "benchmarks/results/formats.json"))
    ap.add_argument("--size", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=5)
    opt = ap.parse_args()
    n = opt.size
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    ball = (x**2).sum(0) <= (0.4 * n) ** 2
    del x
    obj = isoflow.DigitalObject(ball, pitch=0.5, origin=[1.0, 2.0, 3.0])
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        np.save(Path(tmp) / "v.npy", ball)
        for suffix, lib in library_readers().items():
            path = Path(tmp) / f"v{suffix}"
            isoflow.write_volume(obj, path)
            t_iso, t_lib = paired(lambda p=path: isoflow.read_volume(p), lambda p=path, f=lib: f(p), opt.repeat)
            c_fmt, c_npy = paired(lambda p=path: command(["info", p, "--no-surfaces"]),
                                  lambda: command(["info", Path(tmp) / "v.npy", "--no-surfaces"]), 3)
            rows.append({"format": suffix, "size": n, "isoflow_read_s": t_iso, "library_read_s": t_lib,
                         "ratio": t_iso / t_lib, "info_command_s": c_fmt, "info_npy_command_s": c_npy,
                         "command_ratio": c_fmt / c_npy})
            print(f"{suffix:8} isoflow {t_iso:7.3f} s  library {t_lib:7.3f} s  ratio {t_iso / t_lib:5.2f}   "
                  f"info {c_fmt:6.2f} s vs .npy {c_npy:6.2f} s ({c_fmt / c_npy:4.2f}x)", flush=True)
    Path(opt.out).write_text(json.dumps({"machine": platform.processor() or platform.machine(),
                                         "python": platform.python_version(), "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
