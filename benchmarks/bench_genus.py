"""genus's crossing test and surface's STL, measured on every mesh file found.

    python benchmarks/bench_genus.py                       # meshes/ and the test models of installed packages
    python benchmarks/bench_genus.py DIR_OR_FILE ... --repeat 3

Crossings (in process, best of ``--repeat``, A B C interleaved): isoflow's
exact test (:func:`isoflow.mesh.crossings.crossing_pairs`, compiled and
NumPy) against libigl's CGAL ``remesh_self_intersections(detect_only)`` and
pymeshlab's ``compute_selection_by_self_intersections_per_face`` on the mesh
centred and scaled by a power of two (genus's test before it was exact);
the pairs found by each and whether isoflow's equal CGAL's.

STL sweep (whole commands in process): ``isoflow surface MESH --resolution
R -o X.ply`` and ``-o X.stl`` for every mesh, as given and moved into
units of 1e-6 and 1e6 and 3.7e4 away from the origin; the counts written.

Results go to ``benchmarks/results/genus.json`` (file names only, no paths).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: moves of the sweep: (name, scale, offset)
MOVES = [("as given", 1.0, 0.0), ("units 1e-6", 1e-6, 0.0), ("units 1e6", 1e6, 0.0), ("at 3.7e4", 1.0, 3.7e4)]


def mesh_files(roots: list[Path]) -> list[Path]:
    from isoflow.mesh.load import is_mesh_path

    found = []
    for root in roots:
        paths = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.is_file())
        found += [p for p in paths if is_mesh_path(p)]
    return found


def default_roots() -> list[Path]:
    """meshes/ and the sample meshes shipped inside installed packages."""
    import importlib.util

    roots = [ROOT / "meshes"]
    for package, sub in (("pymeshlab", "tests/sample_meshes"), ("pyvista", "examples")):
        spec = importlib.util.find_spec(package)
        if spec and spec.origin:
            roots.append(Path(spec.origin).parent / sub)
    return [r for r in roots if r.exists()]


def best(fn, repeat: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def crossings_row(path: Path, repeat: int) -> dict:
    import igl.copyleft.cgal as cgal
    import pymeshlab

    from isoflow.mesh.crossings import crossing_pairs
    from isoflow.mesh.genus import normalized
    from isoflow.mesh.load import load_mesh

    v, f = load_mesh(path)

    def old():
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(normalized(v)[0], np.asarray(f, np.int32)))
        ms.compute_selection_by_self_intersections_per_face()
        return int(ms.current_mesh().face_selection_array().sum())

    def ref():
        pairs = cgal.remesh_self_intersections(v, np.asarray(f, np.int64), detect_only=True, cutoff=10**9)[2]
        return {tuple(sorted(p)) for p in pairs.tolist()}

    row = {"file": path.name, "faces": len(f)}
    for name, fn in (("compiled", lambda: crossing_pairs(v, f, method="compiled")),
                     ("numpy", lambda: crossing_pairs(v, f, method="numpy")), ("cgal", ref),
                     ("pymeshlab_centred", old)):
        row[f"{name}_s"], row[name] = best(fn, repeat)
    mine = {tuple(p) for p in row["compiled"].tolist()}
    row.update(compiled=len(mine), numpy=len(row["numpy"]), cgal=len(row["cgal"]),
               equal_to_cgal=mine == row["cgal"], extra_coplanar_overlaps=len(mine - row["cgal"]),
               missed=len(row["cgal"] - mine), faces_hit_pymeshlab=row["pymeshlab_centred"])
    del row["pymeshlab_centred"]
    return row


def run_surface(argv: list[str]) -> tuple[int, str]:
    from isoflow.cli import main

    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        rc = main(argv)
    return rc, err.getvalue().strip().splitlines()[-1] if err.getvalue().strip() else ""


def sweep(paths: list[Path], resolution: int) -> dict:
    import trimesh

    counts = {"meshes": 0, "ply": 0, "stl": 0, "stl_refused": [], "ply_failed": []}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for path in paths:
            try:
                mesh = trimesh.load(path, force="mesh", process=False)
            except Exception:  # the sweep counts what trimesh reads
                continue
            for move, scale, offset in MOVES:
                counts["meshes"] += 1
                src = tmp / f"{path.stem}.ply"
                trimesh.Trimesh(np.asarray(mesh.vertices) * scale + offset, mesh.faces, process=False).export(src)
                rc_ply, err_ply = run_surface(["surface", str(src), "--resolution", str(resolution), "-o",
                                               str(tmp / "out.ply"), "--force", "--quiet"])
                rc_stl, err_stl = run_surface(["surface", str(src), "--resolution", str(resolution), "-o",
                                               str(tmp / "out.stl"), "--force", "--quiet"])
                counts["ply"] += rc_ply == 0
                counts["stl"] += rc_stl == 0
                if rc_ply == 0 and rc_stl != 0:
                    why = err_stl.split(f"{tmp / 'out.stl'}: ", 1)[-1]  # no temporary path in the results
                    counts["stl_refused"].append(f"{path.name} ({move}): {why}")
                if rc_ply != 0:
                    counts["ply_failed"].append(f"{path.name} ({move})")
    return counts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="*", type=Path, help="mesh files or folders (default: meshes/ and "
                        "the sample meshes of installed packages)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--resolution", type=int, default=64, help="the sweep's resolution (default 64)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "genus.json")
    args = parser.parse_args(argv)
    paths = mesh_files(args.paths or default_roots())
    rows = []
    for path in paths:
        try:
            rows.append(crossings_row(path, args.repeat))
        except Exception as exc:  # a file isoflow refuses is reported, not fatal
            rows.append({"file": path.name, "error": f"{type(exc).__name__}: {exc}"})
        print(json.dumps(rows[-1]), file=sys.stderr)
    result = {"crossings": rows, "stl_sweep": sweep(paths, args.resolution), "resolution": args.resolution}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result["stl_sweep"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
