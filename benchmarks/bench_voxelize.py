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

``--real`` instead measures what issue 14 asks, pairs timed A B A B in the
same run (medians), ratios quoted (benchmarks/results/voxelize_real.json):

* open meshes (the Stanford bunny as pymeshlab installs it: the 10k-triangle
  scan with its holes, and the 56k-triangle bunny cut open at its base) at
  256 across: ``voxelize`` in process against libigl's
  ``igl.fast_winding_number`` on the same voxel centres, and the whole
  command ``isoflow voxelize BUNNY --resolution 256 -o OUT.npz``;
* the closed-mesh scanline against pyvista's ``voxelize_binary_mask`` at 512
  and 1024 across on a 5,120-triangle sphere, same spacing.
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
    for d in ([Path(arg)] if arg else []) + [ROOT / "meshes"]:
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


def _pairs(a, b, repeat):
    """Time a() and b() alternately (A B A B ...): medians, and the results
    of the last pair (earlier results are dropped before the next call, so
    that at most one result of each is alive)."""
    ta, tb, ra, rb = [], [], None, None
    for _ in range(repeat):
        ra = rb = None
        t = time.perf_counter()
        ra = a()
        ta.append(time.perf_counter() - t)
        t = time.perf_counter()
        rb = b()
        tb.append(time.perf_counter() - t)
    return float(np.median(ta)), float(np.median(tb)), ra, rb


def _bunnies(tmp: Path):
    """The open bunnies: pymeshlab's scan (holes in the base) and its
    closed 56k bunny with the base cut off (faces below 3 % of the height)."""
    import pymeshlab
    import trimesh

    d = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
    out = {"bunny10k_textured.obj (scan, holes)": d / "bunny10k_textured.obj"}
    v, f = load_mesh(d / "bunny.obj")
    top = v[f][:, :, 1].max(axis=1)
    lo, hi = v[:, 1].min(), v[:, 1].max()
    cut = tmp / "bunny56k_cut.ply"
    trimesh.Trimesh(v, f[top > lo + 0.03 * (hi - lo)], process=False).export(cut)
    out["bunny.obj cut open at its base"] = cut
    return out


def real(args) -> int:
    import subprocess
    import tempfile

    import igl

    rows = []
    tmp = Path(tempfile.mkdtemp())
    exe = str(Path(sys.executable).with_name("isoflow"))
    print(f"{'mesh':<36}{'faces':>7}{'bnd':>5}{'res':>5}{'isoflow s':>11}{'igl fwn s':>11}{'ratio':>8}"
          f"{'command s':>11}{'agree %':>9}")
    for name, path in _bunnies(tmp).items():
        v, f = load_mesh(path)
        bnd = mesh_defects(v, f)["boundary_edges"]
        res = 256
        voxelize(v, f, resolution=16)  # compile once (numba caches on disk)
        vol, origin, pitch = voxelize(v, f, resolution=res)
        idx = np.argwhere(np.ones(vol.shape, dtype=bool))
        q = origin + (idx + 0.5) * pitch
        del idx
        t_iso, t_igl, (vol, _, _), w = _pairs(lambda v=v, f=f, res=res: voxelize(v, f, resolution=res),
                                              lambda v=v, f=f, q=q: igl.fast_winding_number(v, f, q), args.repeat)
        agree = float(np.mean(vol.reshape(-1) == (np.abs(w) > 0.5)))
        cmd = [exe, "voxelize", str(path), "--resolution", str(res), "-o", str(tmp / "o.npz"), "--force"]
        t_cmd = []
        for _ in range(args.repeat):
            t = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            t_cmd.append(time.perf_counter() - t)
        t_cmd = float(np.median(t_cmd))
        rows.append({"mesh": name, "faces": int(len(f)), "boundary_edges": bnd, "resolution": res,
                     "shape": list(vol.shape), "isoflow_s": t_iso, "igl_fast_winding_number_s": t_igl,
                     "ratio": t_igl / t_iso, "command_s": t_cmd, "agree_with_fwn": agree})
        print(f"{name:<36}{len(f):>7}{bnd:>5}{res:>5}{t_iso:>11.3f}{t_igl:>11.3f}{t_igl / t_iso:>7.1f}x"
              f"{t_cmd:>11.2f}{100 * agree:>9.4f}", flush=True)
        del q, w
    import pyvista as pv
    import trimesh

    sphere = trimesh.creation.icosphere(subdivisions=4)
    poly = pv.PolyData(np.asarray(sphere.vertices), np.hstack([np.full((len(sphere.faces), 1), 3),
                                                              sphere.faces]).ravel())
    print(f"\n{'closed sphere':<20}{'faces':>7}{'res':>6}{'isoflow s':>11}{'pyvista s':>11}{'ratio':>8}{'voxels iso/pv':>16}")
    for res in args.res or (512, 1024):
        pitch = 2.0 / res
        voxelize(sphere.vertices, sphere.faces, resolution=16)
        t_iso, t_pv, (vol, _, _), img = _pairs(
            lambda res=res: voxelize(sphere.vertices, sphere.faces, resolution=res),
            lambda pitch=pitch: poly.voxelize_binary_mask(spacing=pitch), args.repeat)
        n_pv = int(np.count_nonzero(img.point_data["mask"]))
        rows.append({"mesh": "icosphere(4)", "faces": int(len(sphere.faces)), "resolution": res,
                     "isoflow_s": t_iso, "pyvista_s": t_pv, "ratio": t_pv / t_iso,
                     "voxels_isoflow": int(vol.sum()), "voxels_pyvista": n_pv})
        print(f"{'icosphere(4)':<20}{len(sphere.faces):>7}{res:>6}{t_iso:>11.3f}{t_pv:>11.3f}{t_pv / t_iso:>7.2f}x"
              f"{vol.sum() / n_pv:>16.4f}", flush=True)
        del vol, img
    out = Path(args.out if args.out != str(ROOT / "benchmarks/results/voxelize.json")
               else ROOT / "benchmarks/results/voxelize_real.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"benchmark": "issue 14: open meshes vs libigl, closed vs pyvista",
                               "timing": f"median of {args.repeat} A B pairs", "cpus": __import__("os").cpu_count(),
                               "python": platform.python_version(), "rows": rows}, indent=1))
    print(f"\nwrote {out}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", nargs="?", default=str(ROOT / "benchmarks/results/voxelize.json"))
    ap.add_argument("--quick", action="store_true", help="only 128 voxels across")
    ap.add_argument("--res", type=int, nargs="+", default=None)
    ap.add_argument("--meshes", default=None, help="directory with manifest.json")
    ap.add_argument("--repeat", type=int, default=3, help="runs of ours (best is kept)")
    ap.add_argument("--real", action="store_true", help="open bunnies vs libigl, closed sphere vs pyvista")
    args = ap.parse_args(argv)
    if args.real:
        return real(args)
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
