"""Export the boundary of a voxelised mesh as a curvature-coloured PLY, with a picture.

    python examples/curvature_surface.py [OUT] [--mesh M] [--resolution R]

The boundary quad mesh of the solid carries, at every vertex, its
configuration byte, class, vertex angle gamma (eq. 4.6), curvature index a
(eq. 4.10) and f (eq. 4.8), and an RGB colour by gamma (blue concave, white
flat, red convex), in the mesh's own coordinates: OUT/surface.ply opens in
MeshLab, Blender or trimesh. OUT/surface.png is a picture of it. The sum of a
over the vertices is the digital Gauss-Bonnet theorem, 8 chi (Theorem 10).
"""

from pathlib import Path

import isoflow
from isoflow.mesh.export import mesh_vertex_table, write_ply
from isoflow.mesh.outputs import check_output_path, check_picture_path
from isoflow.mesh.render import render_surface
from _common import MESHES, parse_args, run


def arguments(parser):
    parser.add_argument("--mesh", default=str(MESHES / "bob_small.ply"), help="a closed triangle mesh")
    parser.add_argument("--resolution", type=int, default=48, help="voxels along the longest side")


def main():
    args = parse_args(__doc__.splitlines()[0], arguments)
    ply = check_output_path(args.out / "surface.ply", args.force)
    png = check_picture_path(args.out / "surface.png", args.force)

    solid = isoflow.voxelize_file(args.mesh, resolution=args.resolution)
    mesh = isoflow.boundary_mesh(solid.volume, connectivity=6)
    columns = mesh_vertex_table(mesh, solid)  # x y z (mesh units), config, class, gamma, a, f, red green blue
    write_ply(ply, columns, mesh.polygons(), force=args.force,
              comments=(f"boundary of {Path(args.mesh).name} at {args.resolution} voxels across",))
    render_surface(mesh, solid, png, title=Path(args.mesh).name)

    chi = isoflow.euler_characteristic(solid.volume, 6)
    print(f"{ply}: {len(mesh.vertices)} vertices, {len(mesh.polygons())} quads, V-E+F = {mesh.euler_characteristic}")
    print(f"  sum of a over the vertices = {int(columns['a'].sum())} = 8 chi of the solid (chi = {chi})")
    for i, s in enumerate(mesh.components()):
        print(f"  closed surface {i}: genus {s['genus']}")
    print(f"{png}: picture coloured by vertex angle")


if __name__ == "__main__":
    run(main)
