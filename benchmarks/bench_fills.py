"""Benchmark of the fills (issue 24): what each gives, against trimesh and
pyvista, and how fast, in one run.

Usage::

    PYTHONPATH=src python benchmarks/bench_fills.py [--repeat 3] [--res 256 512 1024]
    PYTHONPATH=src python benchmarks/bench_fills.py --thresholds
    PYTHONPATH=src python benchmarks/bench_fills.py --sphere [--repeat 5]  # the speed rows only

Rows (benchmarks/results/fills.json and fills.md):

* ``chair``: tests/mesh/data/chair_double_sided.obj (thin boxes and zero-thickness
  panels, every face written twice) at 128 across: whether the default
  (winding) run says the note, and ``--fill flood``'s voxel count against
  trimesh's ``voxelized(pitch).fill()`` at the same pitch (the chair puts
  the voxel centres of both on the same points).
* ``double-sided``: every closed sample mesh of meshes/ with every face also
  written reversed (the reversed copy first): voxels equal to the
  single-sided mesh's, at 64 and 256 across.
* ``closed sphere``: an 81,920-triangle icosphere against pyvista's
  ``voxelize_binary_mask`` at the same spacing (in process, A B pairs,
  medians), and ``--fill shell`` against the closed scanline
  (``--fill winding``) at the same sizes.

``--thresholds`` runs the sweep that sets the note's thresholds
(:data:`isoflow.mesh.fills.THIN_SHARE`, ``UNBOUNDED_SHARE``): every mesh of
meshes/, pymeshlab's sample meshes and six trimesh primitives at 64, 128
and 256 across: winding voxels, shell voxels, their ratio, the winding
voxels against the mesh's own volume where its winding number is 0 or 1,
and the share of the area that bounds no voxel; then small closed solids
(boxes, cubes, spheres and cylinders 1 to 7 voxels across, and plates
thinner than a voxel) at random sub-voxel offsets on a shared grid, the
sweep behind ``VOLUME_BAND`` (benchmarks/results/fills_thresholds.json).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from isoflow.mesh.load import load_mesh  # noqa: E402
from isoflow.mesh.voxelize import Solid, voxelize  # noqa: E402

MESHES = ROOT / "meshes"
DATA = ROOT / "tests" / "mesh" / "data"  # the generated meshes (make_thin_models.py)


def pairs(a, b, repeat: int):
    """a() and b() alternately (A B A B ...): their median seconds."""
    ta, tb = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        a()
        ta.append(time.perf_counter() - t)
        t = time.perf_counter()
        b()
        tb.append(time.perf_counter() - t)
    return float(np.median(ta)), float(np.median(tb))


def closed_samples():
    for p in sorted(MESHES.iterdir()):
        if p.suffix.lower() in (".obj", ".ply", ".off", ".stl"):
            v, f = load_mesh(p)
            solid = Solid(v, f)
            if not solid.chain_edges and not solid.double_sided:
                yield p.name, v, f


def chair_row() -> dict:
    import trimesh

    v, f = load_mesh(DATA / "chair_double_sided.obj")
    default = voxelize(v, f, resolution=128, details=True)
    flood = voxelize(v, f, resolution=128, fill="flood", details=True)
    tm = trimesh.load(DATA / "chair_double_sided.obj", force="mesh").voxelized(flood.pitch)
    surface, filled = int(tm.matrix.sum()), int(tm.fill().matrix.sum())
    row = {"mesh": "chair_double_sided.obj", "resolution": 128, "winding_voxels": default.voxels,
           "note": default.note, "thin_note": bool(default.note and "winding rule leaves" in default.note),
           "shell_voxels": voxelize(v, f, resolution=128, fill="shell", details=True).voxels,
           "flood_voxels": flood.voxels, "trimesh_surface": surface, "trimesh_fill": filled,
           "flood_vs_trimesh": flood.voxels / filled - 1}
    print(f"chair at 128: default note {'yes' if row['thin_note'] else 'NO'}; flood {flood.voxels} voxels, "
          f"trimesh fill {filled} ({100 * row['flood_vs_trimesh']:+.2f} %)", flush=True)
    return row


def double_sided_rows() -> list:
    rows = []
    for name, v, f in closed_samples():
        both = np.stack([f[:, ::-1], f], axis=1).reshape(-1, 3)
        for res in (64, 256):
            single = voxelize(v, f, resolution=res)[0]
            double = voxelize(v, both, resolution=res, details=True)
            rows.append({"mesh": name, "resolution": res, "voxels": int(single.sum()),
                         "identical": bool(np.array_equal(single, double.volume)),
                         "double_sided_faces": double.double_sided_faces})
        print(f"double-sided {name:<24} identical at 64 and 256: {all(r['identical'] for r in rows[-2:])}",
              flush=True)
    return rows


def sphere_rows(resolutions, repeat: int) -> list:
    import pyvista as pv
    import trimesh

    s = trimesh.creation.icosphere(subdivisions=6)
    v, f = np.asarray(s.vertices), np.asarray(s.faces)
    poly = pv.PolyData(v, np.hstack([np.full((len(f), 1), 3), f]).ravel())
    voxelize(v, f, resolution=16)
    voxelize(v, f, resolution=16, fill="shell")
    rows = []
    for res in resolutions:
        t_iso, t_pv = pairs(lambda res=res: voxelize(v, f, resolution=res),
                            lambda res=res: poly.voxelize_binary_mask(spacing=2.0 / res), repeat)
        t_wind, t_shell = pairs(lambda res=res: voxelize(v, f, resolution=res),
                                lambda res=res: voxelize(v, f, resolution=res, fill="shell"), repeat)
        rows.append({"mesh": "icosphere(6)", "faces": int(len(f)), "resolution": res, "winding_s": t_iso,
                     "pyvista_s": t_pv, "pyvista_over_winding": t_pv / t_iso, "winding_again_s": t_wind,
                     "shell_s": t_shell, "winding_over_shell": t_wind / t_shell})
        print(f"sphere {len(f)} faces at {res}: winding {t_iso:.3f} s, pyvista {t_pv:.3f} s ({t_pv / t_iso:.2f}x); "
              f"shell {t_shell:.3f} s vs winding {t_wind:.3f} s ({t_wind / t_shell:.2f}x)", flush=True)
    return rows


def markdown_sphere(sphere: list) -> list:
    """The closed sphere's rows of the targets' table."""
    lines = []
    for r in sphere:
        need = 1.0 if r["resolution"] <= 256 else 2.0
        lines.append(f"| 81,920-triangle sphere at {r['resolution']}: winding vs pyvista (need {need:g}x) | "
                     f"{r['winding_s']:.3f} s vs {r['pyvista_s']:.3f} s: {r['pyvista_over_winding']:.2f}x | "
                     f"{'yes' if r['pyvista_over_winding'] >= need else 'no'} |")
    for r in sphere:
        lines.append(f"| sphere at {r['resolution']}: `--fill shell` vs the closed scanline | "
                     f"{r['shell_s']:.3f} s vs {r['winding_again_s']:.3f} s: {r['winding_over_shell']:.2f}x | "
                     f"{'yes' if r['winding_over_shell'] >= 1 else 'no'} |")
    return lines


def markdown(chair: dict, double: list, sphere: list, repeat: int) -> str:
    lines = ["| target | measured | met |", "|---|---|---|",
             f"| chair at 128: the default run says the thin note | "
             f"{'yes' if chair['thin_note'] else 'no'} | {'yes' if chair['thin_note'] else 'no'} |",
             f"| chair at 128: `--fill flood` within 5 % of trimesh `voxelized().fill()` | "
             f"{chair['flood_voxels']} vs {chair['trimesh_fill']} ({100 * chair['flood_vs_trimesh']:+.2f} %) | "
             f"{'yes' if abs(chair['flood_vs_trimesh']) < 0.05 else 'no'} |"]
    same = sum(r["identical"] for r in double)
    lines.append(f"| double-sided closed samples, same voxels at 64 and 256 | {same} of {len(double)} | "
                 f"{'yes' if same == len(double) else 'no'} |")
    lines += markdown_sphere(sphere)
    lines += ["", f"Medians of {repeat} A B pairs in one process, {os.cpu_count()} CPUs; "
              "`PYTHONPATH=src python benchmarks/bench_fills.py`."]
    return "\n".join(lines)


def thresholds() -> int:
    import pymeshlab
    import trimesh

    from isoflow.mesh.fills import unbounded_area
    from isoflow.mesh.voxelize import plan_voxels

    warnings.simplefilter("ignore")
    files = [p for d in (MESHES, DATA) for p in sorted(d.iterdir()) if p.suffix.lower() in (".obj", ".ply", ".off", ".stl")]
    pm = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes"
    files += [pm / n for n in ("airplane.obj", "bone.ply", "bunny.obj", "bunny10k_textured.obj", "cow.obj", "cube.obj")]
    cases = [(p.name, *load_mesh(p)) for p in files if p.exists()]
    for name, m in [("trimesh box", trimesh.creation.box((1, 2, 3))), ("trimesh icosphere", trimesh.creation.icosphere(3)),
                    ("trimesh cylinder", trimesh.creation.cylinder(0.5, 3)),
                    ("trimesh annulus", trimesh.creation.annulus(0.8, 1.0, 0.05)),
                    ("trimesh torus", trimesh.creation.torus(1, 0.2)),
                    ("trimesh thin box", trimesh.creation.box((10, 10, 0.05)))]:
        cases.append((name, np.asarray(m.vertices), np.asarray(m.faces)))
    rows = []
    for name, v, f in cases:
        for res in (64, 128, 256):
            r = voxelize(v, f, resolution=res, details=True)
            shell = voxelize(v, f, resolution=res, fill="shell", details=True).voxels
            _, _, _, _, frame, _, _ = plan_voxels(v, f, resolution=res)
            T = np.ldexp(v - frame[0], -frame[1])[f]
            share = unbounded_area(T, r.volume, frame[2], frame[3])
            own = own_volume(v, f, r)
            rows.append({"mesh": name, "resolution": res, "winding": r.voxels, "shell": shell,
                         "ratio": r.voxels / max(shell, 1), "volume_ratio": None if own is None else r.voxels / own,
                         "unbounded_share": share, "note": bool(r.note and "winding rule leaves" in r.note)})
            by_volume = "" if own is None else f"{r.voxels / own:>8.3f}"
            print(f"{name:<26}{res:>5}{r.voxels:>10}{shell:>9}{rows[-1]['ratio']:>8.3f}{share:>7.3f}{by_volume:>8}"
                  f"{'  note' if rows[-1]['note'] else ''}", flush=True)
    small = small_solids()
    out = ROOT / "benchmarks" / "results" / "fills_thresholds.json"
    out.write_text(json.dumps({"benchmark": "winding voxels / shell voxels and unbounded area share", "rows": rows,
                               "small_solids": small}, indent=1))
    print(f"wrote {out.relative_to(ROOT)}")
    return 0


def own_volume(v, f, r) -> float | None:
    """The mesh's volume in voxels of ``r`` (its voxelisation), where its
    edges balance and no voxel lies inside two layers; None otherwise."""
    from isoflow.mesh.bodies import signed_volume

    solid = Solid(v, f)
    if solid.chain_edges or r.overlap_voxels:
        return None
    own = abs(signed_volume(np.asarray(solid.v, np.float64)[solid.faces])) / r.pitch**3
    return own if own > 0 else None


def small_solids(trials: int = 200) -> dict:
    """Small closed solids at random sub-voxel offsets on a shared grid
    (pitch 1): their winding voxels against their volume, for those the
    shell's share flags as thin (fewer than THIN_SHARE of the shell's
    voxels), and plates thinner than half a voxel, which have no voxel or a
    layer over twice their volume."""
    import trimesh

    from isoflow.mesh.fills import THIN_SHARE, VOLUME_BAND

    rng = np.random.default_rng(1)
    grid = (np.zeros(3), (24, 24, 24))
    flagged, plates, noted = [], [], []
    for _ in range(trials):
        t = rng.uniform(0.02, 0.5)
        shapes = [trimesh.creation.box(rng.uniform(1.0, 6.0, 3)), trimesh.creation.box([rng.uniform(1.0, 6.0)] * 3),
                  trimesh.creation.icosphere(3, radius=rng.uniform(0.7, 3.5)),
                  trimesh.creation.cylinder(rng.uniform(0.6, 3.0), rng.uniform(1.0, 6.0), sections=32),
                  trimesh.creation.box((10, 10, t))]
        for k, m in enumerate(shapes):
            m.apply_translation(12 + rng.random(3) - m.bounds.mean(axis=0))
            r = voxelize(m.vertices, m.faces, pitch=1.0, grid=grid, details=True)
            ratio = r.voxels / m.volume
            if k == 4:
                plates.append(ratio)
                noted.append(bool(r.note and "winding rule leaves" in r.note))
            elif r.shell_voxels is not None and r.voxels < THIN_SHARE * r.shell_voxels:
                flagged.append(ratio)
    a, lo, hi = np.array(flagged), *VOLUME_BAND
    out = {"trials": trials, "flagged_by_shell": len(a), "ratio_min": float(a.min()), "ratio_max": float(a.max()),
           "ratio_percentiles_1_5_50_95_99": np.percentile(a, [1, 5, 50, 95, 99]).tolist(),
           "in_band": float(np.mean((a >= lo) & (a <= hi))), "plates": len(plates),
           "plates_in_band": int(sum(lo <= x <= hi for x in plates)), "plates_noted": int(sum(noted))}
    print(f"small solids the shell flags: {len(a)}, voxels / volume {a.min():.2f} to {a.max():.2f}, "
          f"{100 * out['in_band']:.0f} % within {lo:g} to {hi:g}; plates under half a voxel thick: "
          f"{out['plates_in_band']} of {len(plates)} within, {out['plates_noted']} noted", flush=True)
    return out


def sphere_only(resolutions, repeat: int) -> int:
    """The closed sphere's rows alone (benchmarks/results/fills_sphere.json, .md)."""
    sphere = sphere_rows(resolutions, repeat)
    res_dir = ROOT / "benchmarks" / "results"
    res_dir.mkdir(parents=True, exist_ok=True)
    (res_dir / "fills_sphere.json").write_text(json.dumps(
        {"benchmark": "issue 24: closed-mesh and shell speed", "timing": f"median of {repeat} A B pairs",
         "cpus": os.cpu_count(), "python": platform.python_version(), "sphere": sphere}, indent=1))
    md = "\n".join(markdown_sphere(sphere) + ["", f"Medians of {repeat} A B pairs in one process, {os.cpu_count()} "
                                              "CPUs; `PYTHONPATH=src python benchmarks/bench_fills.py --sphere`."])
    (res_dir / "fills_sphere.md").write_text(md + "\n")
    print("\n" + md)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--res", type=int, nargs="+", default=[256, 512, 1024])
    ap.add_argument("--thresholds", action="store_true", help="the sweep behind the note's thresholds")
    ap.add_argument("--sphere", action="store_true",
                    help="only the closed sphere's rows (speed), written to fills_sphere.json and .md")
    args = ap.parse_args(argv)
    if args.thresholds:
        return thresholds()
    warnings.simplefilter("ignore")
    if args.sphere:
        return sphere_only(args.res, args.repeat)
    chair = chair_row()
    double = double_sided_rows()
    sphere = sphere_rows(args.res, args.repeat)
    res_dir = ROOT / "benchmarks" / "results"
    res_dir.mkdir(parents=True, exist_ok=True)
    (res_dir / "fills.json").write_text(json.dumps(
        {"benchmark": "issue 24: fills, double-sided faces, closed-mesh speed", "timing": f"median of {args.repeat} A B pairs",
         "cpus": os.cpu_count(), "python": platform.python_version(), "chair": chair, "double_sided": double,
         "sphere": sphere}, indent=1))
    md = markdown(chair, double, sphere, args.repeat)
    (res_dir / "fills.md").write_text(md + "\n")
    print("\n" + md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
