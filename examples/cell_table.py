"""
Every cell of a 2D segmentation at once
=======================================

A 2D label image (here a generated cell segmentation: the Voronoi cells of
random seeds, a few cells with holes punched in them, as segmentations of
cells with vacuoles or of grains with pores leave them) is read in one pass
by :func:`isoflow.label_table`: one row per cell with its pixels, area and
perimeter in world units, box, centroid, Euler characteristic and Betti
numbers (``b1``: its holes), the planar curvature classes (eq. 4.9) and the
energy. Every row equals :func:`isoflow.analyze` of that cell's mask. A
hole that reaches its cell's edge, or the image's, is no hole: the table
says which cells hold one.

Writes the table (``OUT/cells.csv``), the image with its pixel size
(``OUT/cells.npz``: ``isoflow info OUT/cells.npz --labels`` gives the same
table) and a picture (``OUT/cells.png``).

.. code-block:: bash

    python examples/cell_table.py [OUT] [--size N] [--cells K] [--force]
"""

import csv

import matplotlib.pyplot as plt
import numpy as np
from _common import outputs, parse_args, run
from scipy.spatial import cKDTree

import isoflow


def arguments(parser):
    parser.add_argument("--size", type=int, default=256, help="pixels along each side")
    parser.add_argument("--cells", type=int, default=120, help="number of cells (labels)")


def cell_map(size: int, cells: int, seed: int = 3) -> np.ndarray:
    """Voronoi cells of random seeds, labels 1..cells; every fifth cell
    gets a round hole at its seed, cell 1 two of them. Axis 0 is x and
    axis 1 is y, as isoflow reads a 2D array."""
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(0, size, (cells, 2))
    centres = np.indices((size, size)).reshape(2, -1).T + 0.5
    image = (cKDTree(seeds).query(centres)[1] + 1).reshape(size, size).astype(np.uint16)
    x, y = np.indices(image.shape) + 0.5
    for label in range(1, cells + 1, 5):
        for dx in ((-2.5, 2.5) if label == 1 else (0.0,)):
            hole = (x - seeds[label - 1, 0] - dx) ** 2 + (y - seeds[label - 1, 1]) ** 2 <= 1.6**2
            image[hole & (image == label)] = 0
    return image


def main():
    args = parse_args("Every cell of a 2D segmentation at once.", arguments)
    table_path, image_path, picture = outputs(args, "cells.csv", "cells.npz", "cells.png")
    image = cell_map(args.size, args.cells)
    table = isoflow.label_table(image, 4, pitch=0.25)  # 0.25 units (say micrometres) per pixel
    holes = table["b1"]
    print(f"{len(table['label'])} cells in a {args.size}^2 segmentation, 4-connectivity, pixel 0.25")
    print(f"{'label':>6} {'pixels':>7} {'area':>8} {'perimeter':>9} {'chi':>4} {'b0':>3} {'b1':>3}")
    for r in np.flatnonzero((holes > 0) | (np.arange(len(holes)) < 3)):
        print(f"{table['label'][r]:>6} {table['voxels'][r]:>7} {table['area'][r]:>8.3f} "
              f"{table['perimeter'][r]:>9.2f} {table['euler_characteristic'][r]:>4} {table['b0'][r]:>3} "
              f"{holes[r]:>3}")
    cells, count = np.count_nonzero(holes), int(holes.sum())
    print(f"{cells} cell{'' if cells == 1 else 's'} with holes, {count} hole{'' if count == 1 else 's'} in all")
    with open(table_path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(list(table))
        writer.writerows(zip(*[column.tolist() for column in table.values()]))
    isoflow.write_labels(image, image_path, pitch=0.25, force=True)  # a .npy would keep no pixel size

    # the cells, those with holes outlined in red, x across and y down as an
    # image viewer shows the image's PNG or TIFF (and isoflow flow's
    # shapes.png); each cell's perimeter against its area
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4.5))
    left.imshow(image.T, cmap="tab20", interpolation="nearest")
    with_holes = np.isin(image, table["label"][holes > 0])
    left.contour(with_holes.T, levels=[0.5], colors="red", linewidths=0.8)
    left.set_xlabel("x (axis 0)")
    left.set_ylabel("y (axis 1)")
    left.set_title("cells; those with holes outlined")
    plain = holes == 0
    right.scatter(table["area"][plain], table["perimeter"][plain], s=12, label="b1 = 0")
    right.scatter(table["area"][~plain], table["perimeter"][~plain], s=30, marker="x", color="tab:red",
                  label="b1 > 0 (holes)")
    right.set_xlabel("area")
    right.set_ylabel("perimeter")
    right.legend()
    right.set_title("one row per cell (isoflow.label_table)")
    fig.tight_layout()
    fig.savefig(picture)
    print(f"wrote {table_path.name} ({len(table['label'])} rows), {image_path.name} and {picture.name} to {args.out}")


if __name__ == "__main__":
    run(main)
