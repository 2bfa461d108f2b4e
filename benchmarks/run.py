"""Speed of isoflow against the tools a user would otherwise pick.

    python benchmarks/run.py                 # 128^3 and 256^3
    python benchmarks/run.py --sizes 128 256 512 --json benchmarks/results/run.json

For each input (a ball, a torus, a smoothed random porous field) it times, in
the same run and on the same array:

* ``isoflow info`` (chi, Betti numbers, n-vector; ``analyze(surfaces=False)``)
  against ``skimage.measure.euler_number`` (chi only);
* the boundary quad mesh (``boundary_mesh``) against
  ``trimesh.voxel.VoxelGrid(vol).as_boxes()`` (skipped above --boxes-max, it
  takes minutes);

and prints times and ratios (other tool's time / isoflow's time: > 1 means
isoflow is faster). Wall-clock times are best of ``--repeat`` runs.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np


def ball(n: int) -> np.ndarray:
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    return (x**2).sum(0) <= (0.45 * n) ** 2


def torus(n: int) -> np.ndarray:
    x = np.indices((n,) * 3, dtype=np.float32) - (n - 1) / 2
    rho = np.sqrt(x[0] ** 2 + x[1] ** 2)
    return (rho - 0.3 * n) ** 2 + x[2] ** 2 <= (0.12 * n) ** 2


def porous(n: int, seed: int = 0) -> np.ndarray:
    from scipy.ndimage import gaussian_filter

    field = np.random.default_rng(seed).random((n,) * 3, dtype=np.float32)
    return gaussian_filter(field, 2.0) > 0.5


INPUTS = {"ball": ball, "torus": torus, "porous": porous}


def best_time(fn, repeat: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[128, 256])
    ap.add_argument("--inputs", nargs="+", default=list(INPUTS), choices=list(INPUTS))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--boxes-max", type=int, default=128, help="largest size for trimesh as_boxes")
    ap.add_argument("--json", type=Path, help="write the table as JSON here")
    args = ap.parse_args(argv)

    from skimage.measure import euler_number

    from isoflow import DigitalObject, analyze, boundary_mesh

    rows = []
    print(f"{'input':<8}{'size':>6}  {'task':<22}{'isoflow s':>10}{'other s':>10}{'ratio':>8}  other tool")
    for size in args.sizes:
        for name in args.inputs:
            vol = INPUTS[name](size)
            obj = DigitalObject(vol)
            t_info, rep = best_time(lambda: analyze(obj, 6, surfaces=False), args.repeat)
            t_sk, chi = best_time(lambda: euler_number(vol, connectivity=1), args.repeat)
            assert chi == rep["euler_characteristic"], (name, size, chi, rep["euler_characteristic"])
            rows.append(dict(input=name, size=size, task="info (chi, betti, n)", isoflow_s=t_info,
                             other_s=t_sk, other="skimage.measure.euler_number (chi only)"))
            t_mesh, mesh = best_time(lambda: boundary_mesh(vol, 6), args.repeat)
            t_box = None
            if size <= args.boxes_max:
                from trimesh.voxel import VoxelGrid

                t_box, _ = best_time(lambda: VoxelGrid(vol).as_boxes(), 1)
            rows.append(dict(input=name, size=size, task="boundary mesh", isoflow_s=t_mesh,
                             other_s=t_box, other="trimesh VoxelGrid.as_boxes()", faces=int(len(mesh.faces))))
            for r in rows[-2:]:
                ratio = f"{r['other_s'] / r['isoflow_s']:.1f}x" if r["other_s"] else "-"
                other = f"{r['other_s']:.3f}" if r["other_s"] else "-"
                print(f"{r['input']:<8}{r['size']:>6}  {r['task']:<22}{r['isoflow_s']:>10.3f}{other:>10}{ratio:>8}  {r['other']}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        meta = {"machine": platform.platform(), "processor": platform.processor(),
                "cpus": __import__("os").cpu_count(), "repeat": args.repeat}
        args.json.write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
