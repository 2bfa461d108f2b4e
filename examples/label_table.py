"""Every label of a label image at once: topology, curvature classes and
closed surfaces, one row per label.

    python examples/label_table.py [OUT] [--size N] [--grains K]

Builds a grain map (Voronoi cells of K random seeds in an N^3 box), hollows
out one grain (a cavity: b2 = 1) and drills a hole through another (a
tunnel: b1 = 1), then prints the table of isoflow.label_table for the
labels whose topology is not a ball's, and writes the whole table as
OUT/labels.csv and the image as OUT/labels.npy (for ``isoflow info
OUT/labels.npy --labels``).
"""

import csv

import numpy as np
from _common import parse_args, run
from scipy.spatial import cKDTree

import isoflow
from isoflow.mesh.outputs import atomic_write, check_output_path


def arguments(parser):
    parser.add_argument("--size", type=int, default=48, help="voxels along each side")
    parser.add_argument("--grains", type=int, default=40, help="number of grains (labels)")


def grain_map(size: int, grains: int, seed: int = 7) -> np.ndarray:
    """Voronoi cells of random seeds, labels 1..grains; grain 1 hollowed,
    grain 2 drilled through along its longest side."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(0, size, (grains, 3))
    centres = np.indices((size,) * 3).reshape(3, -1).T + 0.5
    image = (cKDTree(points).query(centres)[1] + 1).reshape((size,) * 3).astype(np.uint16)
    for label, carve in ((1, "cavity"), (2, "tunnel")):
        voxels = np.argwhere(image == label)
        centre = np.round(np.median(voxels, axis=0)).astype(int)
        if carve == "cavity":
            image[tuple(centre)] = 0  # one voxel of background inside the grain
        else:  # a straight hole through the grain along its longest extent
            axis = int(np.argmax(voxels.max(axis=0) - voxels.min(axis=0)))
            line = [slice(c, c + 1) for c in centre]
            line[axis] = slice(None)
            hole = image[tuple(line)]
            hole[hole == label] = 0
    return image


def main():
    args = parse_args(__doc__.splitlines()[0], arguments)
    table_path = check_output_path(args.out / "labels.csv", args.force)
    image_path = check_output_path(args.out / "labels.npy", args.force)
    image = grain_map(args.size, args.grains)
    table = isoflow.label_table(image, 6, pitch=0.5)  # 0.5 units per voxel
    print(f"{len(table['label'])} labels in a {args.size}^3 grain map, 6-connectivity, voxel 0.5")
    print(f"{'label':>6} {'voxels':>7} {'volume':>8} {'area':>8} {'chi':>4} {'b0':>3} {'b1':>3} {'b2':>3}  genera")
    for r in range(len(table["label"])):
        if (table["b0"][r], table["b1"][r], table["b2"][r]) != (1, 0, 0) or r < 3:
            print(f"{table['label'][r]:>6} {table['voxels'][r]:>7} {table['volume'][r]:>8.2f} "
                  f"{table['surface_area'][r]:>8.2f} {table['euler_characteristic'][r]:>4} {table['b0'][r]:>3} "
                  f"{table['b1'][r]:>3} {table['b2'][r]:>3}  {table['genera'][r]}")
    with atomic_write(table_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(list(table))
        for r in range(len(table["label"])):
            writer.writerow([";".join(map(str, v[r])) if k == "genera" else v[r] for k, v in table.items()])
    with atomic_write(image_path) as fh:
        np.save(fh, image)
    print(f"wrote {table_path.name} ({len(table['label'])} rows) and {image_path.name}")


if __name__ == "__main__":
    run(main)
