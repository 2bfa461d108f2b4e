"""
Every label of a label image at once
====================================

A label image (here a grain map: the Voronoi cells of random seeds in a
box, one grain hollowed out and one drilled through) is read in one pass by
:func:`isoflow.label_table`: one row per label with its voxels, volume and
surface area in world units, Euler characteristic, Betti numbers and the
genera of its closed surfaces. Every row equals :func:`isoflow.analyze` of
that label's mask; the columns go into pandas or a CSV as they are.

Writes the table (``OUT/labels.csv``), the image with its voxel size
(``OUT/labels.npz``: ``isoflow info OUT/labels.npz --labels`` gives the
same table) and a picture (``OUT/labels.png``).

.. code-block:: bash

    python examples/label_table.py [OUT] [--size N] [--grains K] [--force]
"""

import csv

import matplotlib.pyplot as plt
import numpy as np
from _common import outputs, parse_args, run
from scipy.spatial import cKDTree

import isoflow


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
    args = parse_args("Every label of a label image at once.", arguments)
    table_path, image_path, picture = outputs(args, "labels.csv", "labels.npz", "labels.png")
    image = grain_map(args.size, args.grains)
    table = isoflow.label_table(image, 6, pitch=0.5)  # 0.5 units per voxel
    print(f"{len(table['label'])} labels in a {args.size}^3 grain map, 6-connectivity, voxel 0.5")
    print(f"{'label':>6} {'voxels':>7} {'volume':>8} {'area':>8} {'chi':>4} {'b0':>3} {'b1':>3} {'b2':>3}  genera")
    for r in range(len(table["label"])):
        if (table["b0"][r], table["b1"][r], table["b2"][r]) != (1, 0, 0) or r < 3:
            print(f"{table['label'][r]:>6} {table['voxels'][r]:>7} {table['volume'][r]:>8.2f} "
                  f"{table['surface_area'][r]:>8.2f} {table['euler_characteristic'][r]:>4} {table['b0'][r]:>3} "
                  f"{table['b1'][r]:>3} {table['b2'][r]:>3}  {table['genera'][r]}")
    with open(table_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(list(table))
        for r in range(len(table["label"])):
            writer.writerow([";".join(map(str, v[r])) if k == "genera" else v[r] for k, v in table.items()])
    isoflow.write_labels(image, image_path, pitch=0.5, force=True)  # a .npy would keep no voxel size

    # the middle slice of the grain map, and each grain's area against its
    # volume, the grains whose topology is not a ball's marked
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.imshow(image[args.size // 2].T, origin="lower", cmap="tab20", interpolation="nearest")
    left.set_title(f"slice {args.size // 2} of the grain map")
    ball = (table["b0"] == 1) & (table["b1"] == 0) & (table["b2"] == 0)
    right.scatter(table["volume"][ball], table["surface_area"][ball], s=12, label="b = (1, 0, 0)")
    right.scatter(table["volume"][~ball], table["surface_area"][~ball], s=30, marker="x", color="tab:red",
                  label="other topology")
    right.set_xlabel("volume")
    right.set_ylabel("surface area")
    right.legend()
    right.set_title("one row per label (isoflow.label_table)")
    fig.tight_layout()
    fig.savefig(picture)
    print(f"wrote {table_path.name} ({len(table['label'])} rows), {image_path.name} and {picture.name} to {args.out}")


if __name__ == "__main__":
    run(main)
