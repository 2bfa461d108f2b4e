"""Verify the genus of every mesh in a folder, as a table.

    python examples/genus_table.py [OUT] [--folder F] [--resolution R ...]

For each mesh: its own genus (from V - E + F per component), manifold3d's,
pymeshlab's, and the digital genus (b1) of its voxelised solid at each
resolution, with the verdict that says why numbers differ (open, non-manifold,
overlapping components, a grid too coarse). Prints the table and writes it as
OUT/genus.csv, one row per mesh.
"""

import csv
from pathlib import Path

import isoflow
from isoflow.mesh.outputs import check_output_path
from _common import MESHES, parse_args, run

SUFFIXES = {".stl", ".obj", ".ply", ".off", ".glb"}


def arguments(parser):
    parser.add_argument("--folder", default=str(MESHES), help="folder of meshes (STL, OBJ, PLY, OFF, GLB)")
    parser.add_argument("--resolution", type=int, nargs="+", default=[32, 64], help="voxels along the longest side")


def show(value):
    return "-" if value is None else str(value)


def main():
    args = parse_args(__doc__.splitlines()[0], arguments)
    table = check_output_path(args.out / "genus.csv", args.force)
    paths = sorted(p for p in Path(args.folder).iterdir() if p.suffix.lower() in SUFFIXES)
    header = ["mesh", "faces", "components", "genus", "manifold3d", "pymeshlab",
              *(f"digital_{r}" for r in args.resolution), "agree", "verdict"]
    rows = []
    for path in paths:
        r = isoflow.verify_genus(path, args.resolution, connectivity=6)
        digital = {d["resolution"]: d["genus"] for d in r["digital"]}
        rows.append([path.name, r["mesh"]["faces"], r["mesh"]["components"], show(r["mesh"]["genus"]),
                     show(r["manifold3d"].get("genus")), show(r["pymeshlab"].get("genus")),
                     *(show(digital.get(res)) for res in args.resolution), r["agree"], r["verdict"]])
    with open(table, "w", newline="") as fh:
        csv.writer(fh).writerows([header, *rows])

    widths = [max(len(str(row[i])) for row in [header, *rows]) for i in range(len(header) - 1)]
    for row in [header, *rows]:  # the verdict last, unpadded: it can be long
        print("  ".join(f"{str(c):<{w}}" for c, w in zip(row, widths)) + "  " + str(row[-1]).split(";")[0])
    print(f"wrote {table}")


if __name__ == "__main__":
    run(main)
