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

A large closed mesh (``--large``: the icosphere of ``--subdivisions`` 8,
1,310,720 faces, written as OBJ under ``benchmarks/.cache/``): ``isoflow
genus FILE`` timed as a whole command (a child process, as a user waits
for it) and by stage in a child process (best of ``--repeat``), each for
this tree and, with ``--other SRC``, another one (say main's, for before
and after; the rounds interleaved), next to manifold3d's genus of the same
file (trimesh's read and manifold3d's build and ``genus()``, a child
process too). Results go to ``benchmarks/results/genus_large.json``::

    python benchmarks/bench_genus.py --large --other ../main/src --rounds 2
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


#: a child process timing ``isoflow genus``'s stages on one file, best of N
#: (only functions both this tree and older ones have)
STAGES_CHILD = r"""
import json, sys, time
from pathlib import Path
path, repeat = Path(sys.argv[1]), int(sys.argv[2])
from isoflow.mesh import genus as G
from isoflow.mesh.load import _read_simple, check_mesh, weld
times = {}
def best(name, fn):
    out, times[name] = None, float("inf")
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times[name] = min(times[name], time.perf_counter() - t)
    return out
vf = best("read", lambda: _read_simple(path))
v, f = check_mesh(*vf)
v, f = best("weld", lambda: weld(v, f, stats={}))
best("repeated_faces", lambda: G._drop_repeated_faces(v, f, {}))
_, comp = best("topology", lambda: G.mesh_topology(v, f, return_components=True))
best("manifold3d", lambda: G.manifold3d_report(v, f))
best("pymeshlab", lambda: G.pymeshlab_report(v, f))
best("crossings", lambda: G.self_intersections(v, f, comp))
best("solid", lambda: G.solid_report(v, f))
best("double_sided", lambda: G._double_sided(v, f))
best("witnesses", lambda: G.witnesses(v, f))
best("digital", lambda: G.digital_steps(v, f, list(G.DEFAULT_RESOLUTIONS), 6, target=0))
print(json.dumps(times))
"""

#: manifold3d's genus of a mesh file, as a peer's whole command
PEER_CHILD = r"""
import sys, numpy as np, trimesh, manifold3d as m3
mesh = trimesh.load(sys.argv[1], force="mesh", process=False)
mf = m3.Manifold(m3.Mesh(vert_properties=np.asarray(mesh.vertices, np.float32),
                         tri_verts=np.asarray(mesh.faces, np.uint32)))
print(mf.genus())
"""


def large_mesh(subdivisions: int) -> Path:
    """The icosphere of ``subdivisions`` as OBJ, cached."""
    import trimesh

    path = ROOT / "benchmarks" / ".cache" / f"icosphere{subdivisions}.obj"
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        trimesh.creation.icosphere(subdivisions=subdivisions).export(path)
    return path


def large_case(subdivisions: int, others: dict[str, str], rounds: int, repeat: int) -> dict:
    """The whole ``isoflow genus`` command and its stages on the large
    icosphere for each source tree (``name -> src``), rounds interleaved,
    best of all, and manifold3d's genus of the same file."""
    import os
    import subprocess

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from timing import timed_command

    path = large_mesh(subdivisions)
    rows: dict = {name: {"command_wall_s": float("inf"), "command_cpu_s": float("inf"), "stages_s": {}}
                  for name in others}
    rows["manifold3d"] = {"command_wall_s": float("inf"), "command_cpu_s": float("inf")}
    for _ in range(rounds):
        for name, src in others.items():
            row = rows[name]
            wall, cpu = timed_command([sys.executable, "-m", "isoflow", "genus", str(path)], pythonpath=src)
            row["command_wall_s"], row["command_cpu_s"] = min(row["command_wall_s"], wall), min(row["command_cpu_s"], cpu)
            out = subprocess.run([sys.executable, "-c", STAGES_CHILD, str(path), str(repeat)], check=True,
                                 capture_output=True, text=True, env=dict(os.environ, PYTHONPATH=src))
            for stage, t in json.loads(out.stdout.strip().splitlines()[-1]).items():
                row["stages_s"][stage] = min(row["stages_s"].get(stage, float("inf")), round(t, 3))
        wall, cpu = timed_command([sys.executable, "-c", PEER_CHILD, str(path)])
        peer = rows["manifold3d"]
        peer["command_wall_s"], peer["command_cpu_s"] = min(peer["command_wall_s"], wall), min(peer["command_cpu_s"], cpu)
    for row in rows.values():
        row["command_wall_s"], row["command_cpu_s"] = round(row["command_wall_s"], 2), round(row["command_cpu_s"], 2)
    return {"mesh": path.name, "faces": 20 * 4**subdivisions, "rounds": rounds, "repeat": repeat, "trees": rows}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("paths", nargs="*", type=Path, help="mesh files or folders (default: meshes/ and "
                        "the sample meshes of installed packages)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--resolution", type=int, default=64, help="the sweep's resolution (default 64)")
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "genus.json")
    parser.add_argument("--large", action="store_true", help="only the large icosphere: genus's stages and command")
    parser.add_argument("--subdivisions", type=int, default=8, help="the large icosphere's (default 8)")
    parser.add_argument("--other", help="another tree's src folder, timed beside this one (--large)")
    parser.add_argument("--rounds", type=int, default=2, help="interleaved rounds of --large (default 2)")
    args = parser.parse_args(argv)
    if args.large:
        trees = {"this": str(ROOT / "src")} | ({"other": str(Path(args.other).resolve())} if args.other else {})
        result = large_case(args.subdivisions, trees, args.rounds, args.repeat)
        out = args.out.with_name("genus_large.json") if args.out.name == "genus.json" else args.out
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(result, indent=1) + "\n")
        print(json.dumps(result, indent=1))
        return 0
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
