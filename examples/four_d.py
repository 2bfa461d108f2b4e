"""The topology of 4D volumes: a solid moving in time, and a hollow 4-ball (section 6).

    python examples/four_d.py [OUT] [--mesh M] [--resolution R] [--frames T]

A time series of 3D segmentations is a 4D volume. Here the voxelised mesh
moves one voxel per frame along x, so consecutive frames overlap and the
space-time object has the topology of the solid itself; the hollow 4-ball (a
3-sphere shell) encloses one 4D cavity. For each, at both 4D connectivities
(8 and 80), prints chi, b0 and b3 (by 4D labelling; chi fixes b1 - b2) and
a^T n = 16 chi, and writes the volumes (OUT/moving.npy, OUT/shell.npy: try
`isoflow info OUT/shell.npy`) and the reports (OUT/report.json).
"""

import json
from pathlib import Path

import numpy as np

import isoflow
from isoflow.mesh.outputs import check_output_path
from _common import MESHES, parse_args, run


def arguments(parser):
    parser.add_argument("--mesh", default=str(MESHES / "eight.off"), help="a closed triangle mesh")
    parser.add_argument("--resolution", type=int, default=24, help="voxels along the mesh's longest side")
    parser.add_argument("--frames", type=int, default=6, help="time steps of the moving solid")


def moving(volume: np.ndarray, frames: int) -> np.ndarray:
    """(t, x, y, z): the solid shifted by t voxels along x in frame t."""
    nx, ny, nz = volume.shape
    out = np.zeros((frames, nx + frames, ny, nz), dtype=bool)
    for t in range(frames):
        out[t, t:t + nx] = volume
    return out


def shell(outer: float, inner: float) -> np.ndarray:
    """The cells of a 4D grid whose centres lie between two 3-spheres."""
    n = int(2 * outer) + 3
    r2 = ((np.indices((n,) * 4) - (n - 1) / 2) ** 2).sum(axis=0)
    return (r2 <= outer**2) & (r2 > inner**2)


def main():
    args = parse_args(__doc__.splitlines()[0], arguments)
    paths = {name: check_output_path(args.out / f"{name}.npy", args.force) for name in ("moving", "shell")}
    report_path = check_output_path(args.out / "report.json", args.force)

    solid = isoflow.voxelize_file(args.mesh, resolution=args.resolution)
    volumes = {"moving": moving(solid.volume, args.frames), "shell": shell(5.5, 2.5)}
    reports = {}
    for name, vol in volumes.items():
        np.save(paths[name], vol)
        print(f"{paths[name]}: 4D, shape {'x'.join(map(str, vol.shape))}, {int(vol.sum())} cells")
        for conn in (8, 80):
            r = isoflow.analyze(vol, connectivity=conn)
            reports[f"{name}_{conn}"] = r.to_dict()
            b0, _, _, b3 = r["betti"]
            print(f"  {conn:>2}-connectivity: chi {r['euler_characteristic']:>2}, b0 {b0}, b3 {b3}, "
                  f"b1 - b2 = {b0 - b3 - r['euler_characteristic']}, a^T n = {r['a_dot_n']} (16 chi)")
    report_path.write_text(json.dumps(reports, indent=1))
    print(f"{Path(args.mesh).name} moved over {args.frames} frames keeps its own topology; "
          f"the shell encloses one 4D cavity. Wrote {report_path}")


if __name__ == "__main__":
    run(main)
