"""
Four dimensions: a solid moving in time, a hollow 4-ball
========================================================

A time series of 3D segmentations is a 4D volume, and isoflow reads its
topology as it reads a 3D one (section 6 of the paper): the Euler
characteristic from the vertex sum ``a^T n = 16 chi``, and ``b0`` and
``b3`` by 4D labelling (chi fixes ``b1 - b2``), at both 4D
connectivities, 8 and 80.

Here the voxelised "eight" of :mod:`isoflow.data` moves one voxel per frame
along x, so consecutive frames overlap and the space-time object has the
topology of the solid itself; the hollow 4-ball (the cells between two
3-spheres) encloses one 4D cavity. Writes the volumes (``OUT/moving.npy``,
``OUT/shell.npy``: try ``isoflow info OUT/shell.npy``), the reports
(``OUT/report.json``) and slices of a few frames (``OUT/frames.png``).

.. code-block:: bash

    python examples/four_d.py [OUT] [--mesh M] [--resolution R] [--frames T] [--force]
"""

import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from _common import outputs, parse_args, run

import isoflow
from isoflow import data


def arguments(parser):
    parser.add_argument("--mesh", default=str(data.eight()),
                        help="a closed triangle mesh file, or the name of one of isoflow.data's samples")
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


def plot_slices(volumes):
    """Each 4D volume as 3D frames, drawn by their middle slices across the last axis."""
    fig, axes = plt.subplots(len(volumes), 6, figsize=(12, 4.4))
    for row, (name, vol) in zip(axes, volumes.items()):
        for ax, t in zip(row, np.linspace(0, len(vol) - 1, len(row)).round().astype(int)):
            # background light grey, not white: the frame's extent shows, and with it the solid's move
            ax.imshow(vol[t, :, :, vol.shape[3] // 2].T, origin="lower", cmap="Greys", vmin=-0.15, vmax=1)
            ax.set_title(f"{name}, t = {t}", fontsize=8)
            ax.set_axis_off()
    fig.tight_layout()
    return fig


def main():
    args = parse_args("The topology of 4D volumes: a solid moving in time, and a hollow 4-ball.", arguments)
    moving_path, shell_path, report_path, picture = outputs(
        args, "moving.npy", "shell.npy", "report.json", "frames.png")

    solid = isoflow.voxelize_file(args.mesh, resolution=args.resolution)
    volumes = {"moving": moving(solid.volume, args.frames), "shell": shell(5.5, 2.5)}
    reports = {}
    for (name, vol), path in zip(volumes.items(), (moving_path, shell_path)):
        np.save(path, vol)
        print(f"{path.name}: 4D, shape {'x'.join(map(str, vol.shape))}, {int(vol.sum())} cells")
        for conn in (8, 80):
            r = isoflow.analyze(vol, connectivity=conn)
            reports[f"{name}_{conn}"] = r.to_dict()
            b0, _, _, b3 = r["betti"]
            print(f"  {conn:>2}-connectivity: chi {r['euler_characteristic']:>2}, b0 {b0}, b3 {b3}, "
                  f"b1 - b2 = {b0 - b3 - r['euler_characteristic']}, a^T n = {r['a_dot_n']} (16 chi)")
    report_path.write_text(json.dumps(reports, indent=1))
    plot_slices(volumes).savefig(picture)
    print(f"{Path(args.mesh).name} moved over {args.frames} frame{'s' * (args.frames != 1)} keeps its own topology; "
          f"the shell encloses one 4D cavity. Wrote {report_path.name} and {picture.name} to {args.out}")


if __name__ == "__main__":
    run(main)
