"""``isoflow info`` on a GPU (CuPy) against the same job on the host.

    python benchmarks/bench_gpu.py                      # 1024^3, CuPy
    python benchmarks/bench_gpu.py --sizes 512 1024 --repeat 3
    python benchmarks/bench_gpu.py --sizes 64 --array array_api_strict   # smoke run, no GPU

Needs CuPy (``pip install 'isoflow[gpu]'``) and a CUDA GPU. For each size and
input (the ``ball`` and ``porous`` generators of ``benchmarks/run.py``, built
on the host, so every tool reads the very same voxels) it times

* ``gpu``: ``analyze(device_volume, 6, surfaces=False)``, the volume already
  on the GPU (chi, Betti numbers and the class vector n; only the 256 counts
  come back), synchronised before the clock stops;
* ``host``: the same call on the NumPy volume (numba kernels, all cores);
* ``skimage``: ``skimage.measure.euler_number(vol, 1)``, chi alone: what a
  user would otherwise call;

best of ``--repeat`` after one warm-up run on the array (CuPy compiles its
kernels on first use). The upload time is reported apart. The GPU report must
equal the host report and chi must equal scikit-image's; the script exits
with 1 otherwise. ``ratio`` = other seconds / GPU seconds.

``--array array_api_strict`` runs the device path on the array API's reference
implementation on the CPU instead: its times mean nothing, it checks the
script and the core's device path on a machine without a GPU.
"""

from __future__ import annotations

import argparse
import importlib
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from run import ball, porous  # noqa: E402  (the same generators as run.py)

from isoflow import analyze  # noqa: E402


def best(fn, repeat: int, sync) -> tuple[float, object]:
    fn()  # warm-up: kernels compiled, memory pools filled
    sync()
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        sync()
        times.append(time.perf_counter() - t)
    return min(times), out


def device_of(name: str):
    """``(upload, sync, description)`` for the array library ``name``."""
    xp = importlib.import_module(name)
    if name == "cupy":
        dev = xp.cuda.Device()
        props = xp.cuda.runtime.getDeviceProperties(dev.id)

        def sync():
            dev.synchronize()

        return xp.asarray, sync, props["name"].decode()
    return (lambda a: xp.asarray(a, device=xp.Device("device1"))), (lambda: None), f"{name} (CPU)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1024])
    ap.add_argument("--inputs", nargs="+", default=["porous", "ball"], choices=["porous", "ball"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--array", default="cupy", help="cupy (default) or array_api_strict")
    ap.add_argument("--json", default=str(HERE / "results" / "gpu.json"))
    args = ap.parse_args(argv)
    try:
        upload, sync, device = device_of(args.array)
    except Exception as exc:  # no CuPy, no CUDA driver, no GPU
        print(f"bench_gpu: cannot use {args.array}: {exc}", file=sys.stderr)
        return 2
    from skimage.measure import euler_number

    rows, ok = [], True
    for size in args.sizes:
        for name in args.inputs:
            vol = {"ball": ball, "porous": porous}[name](size)
            t = time.perf_counter()
            dvol = upload(vol)
            sync()
            upload_s = time.perf_counter() - t
            gpu_s, gpu = best(lambda dvol=dvol: analyze(dvol, 6, surfaces=False), args.repeat, sync)
            host_s, host = best(lambda vol=vol: analyze(vol, 6, surfaces=False), args.repeat, lambda: None)
            sk_s, chi = best(lambda vol=vol: euler_number(vol, connectivity=1), 1, lambda: None)
            same = gpu == host and gpu["euler_characteristic"] == chi
            ok &= same
            del dvol
            row = {
                "input": name,
                "size": size,
                "voxels": int(vol.sum()),
                "upload_s": round(upload_s, 4),
                "gpu_s": round(gpu_s, 4),
                "host_s": round(host_s, 4),
                "skimage_s": round(sk_s, 4),
                "ratio_host": round(host_s / gpu_s, 2),
                "ratio_skimage": round(sk_s / gpu_s, 2),
                "betti": gpu["betti"],
                "same": same,
            }
            rows.append(row)
            print(
                f"{name} {size}^3: gpu {gpu_s:.3f} s (upload {upload_s:.3f} s), "
                f"host {host_s:.3f} s ({row['ratio_host']}x), skimage chi {sk_s:.3f} s "
                f"({row['ratio_skimage']}x), betti {gpu['betti']}, {'same' if same else 'DIFFERENT'}",
                flush=True,
            )
    report = {
        "device": device,
        "machine": platform.platform(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "array": args.array,
        "rows": rows,
    }
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(report, indent=1) + "\n")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
