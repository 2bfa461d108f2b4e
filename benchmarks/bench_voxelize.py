"""Benchmark: isoflow.voxelize vs trimesh ``mesh.voxelized(pitch).fill()``.

For every watertight mesh of the public test set (manifest.json) and each
resolution (voxels along the longest bounding-box side), time both
voxelisers at the same pitch and compare the voxel volume (count * pitch^3)
with the exact volume of the solid: trimesh's ``mesh.volume``, except for
meshes with several components, where overlapping parts (rabbit.obj) would be
counted twice, so the volume of their manifold3d union is used.

Usage::

    PYTHONPATH=src python benchmarks/bench_voxelize.py [OUT.json] [--quick]
        [--res 128 256] [--meshes DIR] [--repeat 3]

``--quick`` skips 256 (trimesh's fill takes up to a minute per mesh there).
"""

from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from isoflow.mesh.voxelize import load_mesh, mesh_defects, voxelize  # noqa: E402


def find_meshes(arg: str | None) -> Path:
    for d in ([Path(arg)] if arg else []) + [ROOT / "meshes", Path("/work/shared/meshes")]:
        if (d / "manifest.json").is_file():
            return d
    sys.exit("no mesh directory with a manifest.json found (use --meshes)")


def exact_volume(v, f, components: int) -> tuple[float, str]:
    import trimesh

    mesh = trimesh.Trimesh(v, f, process=False)
    if components == 1:
        return float(mesh.volume), "trimesh mesh.volume"
    import manifold3d as m3

    parts = []
    for part in mesh.split(only_watertight=False):
        parts.append(m3.Manifold(m3.Mesh(vert_properties=np.asarray(part.vertices, np.float32),
                                         tri_verts=np.asarray(part.faces, np.uint32))))
    union = m3.Manifold.batch_boolean(parts, m3.OpType.Add)
    return float(union.volume()), "manifold3d union of components (float32)"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="?", default=str(ROOT / "benchmarks/results/voxelize.json"))
    ap.add_argument("--quick", action="store_true", help="only 128 voxels across")
    ap.add_argument("--res", type=int, nargs="+", default=None)
    ap.add_argument("--meshes", default=None, help="directory with manifest.json")
    ap.add_argument("--repeat", type=int, default=3, help="runs of ours (best is kept)")
    args = ap.parse_args(argv)
    res_list = args.res or ([128] if args.quick else [128, 256])

    import trimesh

    mdir = find_meshes(args.meshes)
    manifest = json.loads((mdir / "manifest.json").read_text())["meshes"]
    rows = []
    hdr = (f"{'mesh':<20}{'res':>5}{'ours s':>9}{'trimesh s':>11}{'speedup':>9}"
           f"{'ours err %':>12}{'trimesh err %':>15}")
    print(hdr)
    print("-" * len(hdr))
    for entry in manifest:
        if not entry.get("watertight"):
            continue
        v, f = load_mesh(mdir / entry["filename"])
        d = mesh_defects(v, f)
        exact, ref = exact_volume(v, f, d["components"])
        mesh = trimesh.Trimesh(v, f, process=False)
        for res in res_list:
            best = float("inf")
            for _ in range(max(1, args.repeat)):
                t = time.perf_counter()
                vol, origin, pitch = voxelize(v, f, resolution=res)
                best = min(best, time.perf_counter() - t)
            ours_vol = float(vol.sum()) * pitch**3
            t = time.perf_counter()
            filled = mesh.voxelized(pitch).fill()
            t_tm = time.perf_counter() - t
            tm_vol = float(filled.matrix.sum()) * pitch**3
            row = {
                "mesh": entry["filename"], "faces": int(len(f)), "resolution": res,
                "pitch": pitch, "shape_ours": list(vol.shape),
                "shape_trimesh": list(filled.matrix.shape),
                "time_ours_s": best, "time_trimesh_s": t_tm, "speedup": t_tm / best,
                "exact_volume": exact, "exact_volume_source": ref,
                "volume_ours": ours_vol, "volume_trimesh": tm_vol,
                "rel_err_ours": ours_vol / exact - 1, "rel_err_trimesh": tm_vol / exact - 1,
            }
            rows.append(row)
            print(f"{entry['filename']:<20}{res:>5}{best:>9.3f}{t_tm:>11.2f}{t_tm / best:>8.0f}x"
                  f"{100 * row['rel_err_ours']:>12.3f}{100 * row['rel_err_trimesh']:>15.3f}",
                  flush=True)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({
        "benchmark": "isoflow.voxelize vs trimesh voxelized(pitch).fill()",
        "python": platform.python_version(), "numpy": np.__version__,
        "trimesh": trimesh.__version__, "machine": platform.machine(),
        "cpus": __import__("os").cpu_count(), "resolutions": res_list,
        "ours_timing": f"best of {max(1, args.repeat)}", "trimesh_timing": "one run",
        "rows": rows,
    }, indent=1))
    print(f"\nwrote {out}")
    for res in res_list:
        sel = [r for r in rows if r["resolution"] == res]
        if sel:
            sp = np.array([r["speedup"] for r in sel])
            eo = np.array([abs(r["rel_err_ours"]) for r in sel])
            et = np.array([abs(r["rel_err_trimesh"]) for r in sel])
            print(f"res {res}: speedup median {np.median(sp):.0f}x (min {sp.min():.0f}x); "
                  f"|volume error| median ours {100 * np.median(eo):.2f} %, "
                  f"trimesh {100 * np.median(et):.2f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
