"""Several meshes into one label image (issue 25 item 6) against the tool a
user would otherwise pick.

    python benchmarks/bench_label_voxels.py                          # 8 and 64 balls at 256
    python benchmarks/bench_label_voxels.py --meshes 64 --radius 0.15 --json benchmarks/results/label_voxels_small.json
    python benchmarks/bench_label_voxels.py --meshes 8 --resolution 128 --repeat 1 --commands 1 --json ''

Input (generated, cached in benchmarks/.cache/label_voxels/): ``--meshes N``
icospheres (20,480 faces each) on a cubic lattice of N = k^3 sites, each of
radius ``--radius`` lattice steps (0.6: neighbours overlap; 0.15: small
parts apart in a large grid); one binary STL each.

In process (the meshes read once before timing; best of ``--repeat``,
the tools alternated):

* ``isoflow.voxelize_meshes(meshes, resolution=R)``: each mesh on the block
  of the union grid its box covers, the overlaps counted;
* isoflow, a mesh at a time on the whole grid
  (``voxelize(v, f, pitch=, grid=)`` then ``labels[vol] = i``): what the
  single-mesh API gives without blocks;
* pyvista: ``voxelize_binary_mask(reference_volume=ref)`` per mesh on one
  reference ``ImageData`` whose points are the same voxel centres (the way
  pyvista's issue 6255 suggests), then ``labels[mask] = i``.

Whole commands (``--commands N``, alternated, medians): ``isoflow voxelize
*.stl --resolution R -o OUT.npz`` against ``python -c`` reading the STLs
with pyvista, doing the above and saving the ``.npz``. Also reported: the
voxels on which the pyvista label image differs from isoflow's (VTK's
stencil rounds centres on a face its own way, and reads overlaps by
parity within one mesh only).

Results go to ``benchmarks/results/label_voxels.json`` (``--json``) and a
Markdown table on stdout; paths in them are relative to the repository.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
CACHE = ROOT / "benchmarks" / ".cache" / "label_voxels"
sys.path.insert(0, str(ROOT / "benchmarks"))
from timing import timed_command  # noqa: E402


def scene(count: int, radius: float = 0.6) -> list[Path]:
    """``count`` (a cube) balls of ``radius`` lattice steps, one STL each, cached."""
    import trimesh

    k = round(count ** (1 / 3))
    if k**3 != count:
        raise SystemExit(f"--meshes must be a cube (8, 27, 64, ...), got {count}")
    folder = CACHE / f"balls{count}_r{radius:g}"
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for n, (x, y, z) in enumerate(np.ndindex(k, k, k)):
        path = folder / f"ball{n:03d}.stl"
        if not path.exists():
            ball = trimesh.creation.icosphere(5, radius)
            ball.apply_translation((x, y + 0.1 * x, z + 0.05 * y))
            ball.export(path)
        paths.append(path)
    return paths


def isoflow_blocks(meshes, resolution):
    from isoflow import voxelize_meshes

    return voxelize_meshes(meshes, resolution=resolution).labels


def isoflow_whole_grid(meshes, resolution):
    from isoflow.mesh.voxelize import voxelize

    pitch, origin, shape = union(meshes, resolution)
    labels = np.zeros(shape, np.uint8)
    for i, (v, f) in enumerate(meshes, 1):
        labels[voxelize(v, f, pitch=pitch, grid=(origin, shape))[0]] = i
    return labels


def union(meshes, resolution):
    """(pitch, origin, shape) of the union grid, as isoflow lays it."""
    from isoflow.mesh.bodies import Body
    from isoflow.mesh.label_voxels import union_grid

    pitch, origin, shape, _ = union_grid([Body("", v, f) for v, f in meshes], None, resolution)
    return pitch, origin, shape


def pyvista_reference(polys, meshes, resolution):
    import pyvista as pv

    pitch, origin, shape = union(meshes, resolution)
    ref = pv.ImageData(dimensions=shape, spacing=(pitch,) * 3, origin=tuple(origin + pitch / 2))
    labels = np.zeros(shape, np.uint8)
    for i, poly in enumerate(polys, 1):
        mask = poly.voxelize_binary_mask(reference_volume=ref)
        labels[mask.point_data["mask"].reshape(shape, order="F").astype(bool)] = i
    return labels


PYVISTA_COMMAND = """
import sys, numpy as np, pyvista as pv
res, out, paths = int(sys.argv[1]), sys.argv[2], sys.argv[3:]
polys = [pv.read(p) for p in paths]
lo = np.min([p.bounds[::2] for p in polys], axis=0); hi = np.max([p.bounds[1::2] for p in polys], axis=0)
pitch = (hi - lo).max() / res
shape = np.maximum(1, np.ceil((hi - lo) / pitch - 1e-9)).astype(int)
origin = (lo + hi) / 2 - shape * pitch / 2
ref = pv.ImageData(dimensions=shape, spacing=(pitch,) * 3, origin=tuple(origin + pitch / 2))
labels = np.zeros(shape, np.uint8)
for i, poly in enumerate(polys, 1):
    labels[poly.voxelize_binary_mask(reference_volume=ref).point_data["mask"].reshape(shape, order="F") > 0] = i
np.savez_compressed(out, volume=labels, pitch=pitch, origin=origin)
"""


def best(fn, repeat):
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def measure(count: int, resolution: int, repeat: int, commands: int, radius: float) -> list[dict]:
    import pyvista as pv

    from isoflow.mesh.load import load_mesh

    paths = scene(count, radius)
    meshes = [load_mesh(p) for p in paths]
    polys = [pv.read(str(p)) for p in paths]
    isoflow_blocks(meshes[:2], 16)  # numba's cached code loaded
    tools = {"voxelize_meshes": lambda: isoflow_blocks(meshes, resolution),
             "isoflow, whole grid per mesh": lambda: isoflow_whole_grid(meshes, resolution),
             "pyvista voxelize_binary_mask": lambda: pyvista_reference(polys, meshes, resolution)}
    seconds = {name: [] for name in tools}
    outs = {}
    for _ in range(repeat):  # alternated
        for name, fn in tools.items():
            t, outs[name] = best(fn, 1)
            seconds[name].append(t)
    ours = outs["voxelize_meshes"]
    rows = []
    for name in tools:
        rows.append({"meshes": count, "radius": radius, "resolution": resolution, "tool": name,
                     "seconds": min(seconds[name]),
                     "voxels_differing": int((outs[name] != ours).sum()), "voxels": int((ours > 0).sum())})
    if commands:
        rows += whole_commands(paths, resolution, commands, count, radius)
    return rows


def whole_commands(paths, resolution, commands, count, radius) -> list[dict]:
    with tempfile.TemporaryDirectory() as tmp:
        iso = [sys.executable, "-m", "isoflow", "voxelize", *map(str, paths), "--resolution", str(resolution),
               "-o", f"{tmp}/iso.npz", "--force", "-q"]
        pv = [sys.executable, "-c", PYVISTA_COMMAND, str(resolution), f"{tmp}/pv.npz", *map(str, paths)]
        walls: dict[str, list[float]] = {"isoflow voxelize (command)": [], "pyvista script (command)": []}
        for _ in range(commands):
            walls["isoflow voxelize (command)"].append(timed_command(iso, str(ROOT / "src"))[0])
            walls["pyvista script (command)"].append(timed_command(pv)[0])
    return [{"meshes": count, "radius": radius, "resolution": resolution, "tool": name,
             "seconds": statistics.median(w)}
            for name, w in walls.items()]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", type=int, nargs="+", default=[8, 64])
    ap.add_argument("--resolution", type=int, default=256)
    ap.add_argument("--radius", type=float, default=0.6, help="of the balls, in lattice steps (0.6: neighbours "
                    "overlap; 0.15: small parts apart in a large grid)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--commands", type=int, default=3)
    ap.add_argument("--json", default=str(ROOT / "benchmarks" / "results" / "label_voxels.json"))
    args = ap.parse_args(argv)
    rows = []
    for count in args.meshes:
        rows += measure(count, args.resolution, args.repeat, args.commands, args.radius)
    print("| meshes | radius | resolution | tool | seconds | vs voxelize_meshes | voxels differing |")
    print("|---:|---:|---:|---|---:|---:|---:|")
    for row in rows:
        base = next(r["seconds"] for r in rows if r["meshes"] == row["meshes"] and (
            r["tool"] == ("voxelize_meshes" if "command" not in row["tool"] else "isoflow voxelize (command)")))
        differ = f"{row['voxels_differing']:,} of {row['voxels']:,}" if "voxels" in row else ""
        print(f"| {row['meshes']} | {row['radius']:g} | {row['resolution']} | {row['tool']} | {row['seconds']:.3f} | "
              f"{row['seconds'] / base:.2f}x | {differ} |")
    if args.json:
        Path(args.json).write_text(json.dumps({
            "benchmark": "issue 25 item 6: several meshes into one label image",
            "command": "python benchmarks/bench_label_voxels.py " + " ".join(argv or sys.argv[1:]),
            "machine": platform.platform(), "rows": rows}, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
