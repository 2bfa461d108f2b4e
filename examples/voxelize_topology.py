"""
Voxelise a mesh and read its digital topology
=============================================

The solid bounded by a triangle mesh (here a torus from :mod:`isoflow.data`)
is voxelised by the generalised winding number, and its digital topology is
read from the histogram of its vertex configurations: the Euler
characteristic (the digital Gauss-Bonnet sum ``a^T n = 8 chi``), the Betti
numbers, the genus of every closed boundary surface, and the counts of the
paper's nine curvature classes (eq. 4.9).

Writes the volume (``OUT/solid.npz``, with its pitch and origin: read it
back with :func:`isoflow.read_volume` or ``isoflow info OUT/solid.npz``),
the report (``OUT/report.json``, what ``isoflow info --json`` prints, less
the input file's keys) and a picture of a slice and the class counts
(``OUT/topology.png``).

.. code-block:: bash

    python examples/voxelize_topology.py [OUT] [--mesh M] [--resolution R] [--force]
"""

import json
from pathlib import Path

import matplotlib.pyplot as plt
from _common import outputs, parse_args, run

import isoflow
from isoflow import data


def arguments(parser):
    parser.add_argument("--mesh", default=str(data.torus()),
                        help="a closed triangle mesh file, or the name of one of isoflow.data's samples")
    parser.add_argument("--resolution", type=int, default=48, help="voxels along the longest side")


def main():
    args = parse_args("Voxelise a mesh and read its digital topology.", arguments)
    volume_path, report_path, picture = outputs(args, "solid.npz", "report.json", "topology.png")

    solid = isoflow.voxelize_file(args.mesh, resolution=args.resolution)
    report = isoflow.analyze(solid, connectivity=6)
    isoflow.write_volume(solid, volume_path, force=args.force)
    report_path.write_text(json.dumps(report.to_dict(), indent=1))

    print(f"{Path(args.mesh).name} at {args.resolution} voxels across: {report['voxels']} voxels, pitch {solid.pitch:.4g}")
    print(f"  Euler characteristic {report['euler_characteristic']}, a^T n = {report['a_dot_n']} (8 chi)")
    b0, b1, b2 = report["betti"]
    print(f"  Betti numbers: {b0} component{'' if b0 == 1 else 's'}, {b1} tunnel{'' if b1 == 1 else 's'}, "
          f"{b2} {'cavity' if b2 == 1 else 'cavities'}")
    for i, s in enumerate(report["surfaces"]):
        print(f"  closed surface {i}: genus {s['genus']}, {s['faces']} faces")
    print("  vertex classes: " + ", ".join(f"{k} {v}" for k, v in report["classes"].items() if v))

    # the middle slice across the thinnest axis (through a torus's tunnel),
    # and the counts of the nine classes
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    axis = int(solid.volume.shape.index(min(solid.volume.shape)))
    middle = solid.volume.shape[axis] // 2
    left.imshow(solid.volume.take(middle, axis=axis).T, origin="lower", cmap="Greys")
    left.set_title(f"the solid's slice {middle} across axis {'xyz'[axis]}")
    classes = report["classes"]
    right.barh(list(classes), list(classes.values()), color="tab:blue")
    right.set_xlabel("lattice vertices")
    right.set_title(f"vertex classes (eq. 4.9): chi = {report['euler_characteristic']}")
    fig.tight_layout()
    fig.savefig(picture)
    print(f"wrote {volume_path.name}, {report_path.name} and {picture.name} to {args.out}")


if __name__ == "__main__":
    run(main)
