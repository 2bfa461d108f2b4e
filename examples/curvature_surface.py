"""
A curvature-coloured boundary surface
=====================================

The boundary of a voxelised mesh (Keenan Crane's genus-1 "Bob", from
:mod:`isoflow.data`) is a closed quad mesh
(:func:`isoflow.boundary_mesh`). Every vertex carries its configuration
byte, its curvature class, the vertex angle ``gamma`` (eq. 4.6), the
curvature index ``a`` (eq. 4.10) and ``f`` (eq. 4.8). The sum of ``a`` over
the vertices is the digital Gauss-Bonnet theorem, ``8 chi`` (Theorem 10).

Writes ``OUT/surface.ply`` in the mesh's own coordinates, with those
columns and a colour by ``gamma`` (blue concave, white flat, red convex),
through trimesh, and ``OUT/surface.png``, the picture below.
``isoflow surface MESH --resolution 40 -o OUT.ply --png OUT.png`` writes
the same from the command line, as quads (its default resolution is 64).

.. code-block:: bash

    python examples/curvature_surface.py [OUT] [--mesh M] [--resolution R] [--force]
"""

from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import trimesh
from _common import outputs, parse_args, run
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

import isoflow
from isoflow import data


def arguments(parser):
    parser.add_argument("--mesh", default=str(data.bob()),
                        help="a closed triangle mesh file, or the name of one of isoflow.data's samples")
    parser.add_argument("--resolution", type=int, default=40, help="voxels along the longest side")


def draw(mesh, solid, title):
    """The surface's quads coloured by the mean gamma of their corners,
    shaded by their normal; back faces left out."""
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    elev, azim = 25, -55
    e, a = np.radians([elev, azim])
    view = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    front = mesh.face_normals @ view > 0
    faces = mesh.faces[front]
    colour = plt.get_cmap("bwr")((mesh.gamma[faces].mean(axis=1) + 4) / 8)[:, :3]
    light = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    shade = 0.55 + 0.45 * np.clip(mesh.face_normals[front] @ light, 0, 1)
    xyz = solid.world(mesh.vertices)
    ax.add_collection3d(Poly3DCollection(xyz[faces], facecolors=colour * shade[:, None], edgecolors="none"))
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    for set_limits, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), (lo + hi) / 2):
        set_limits(c - (hi - lo).max() / 2, c + (hi - lo).max() / 2)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_title(f"{title}\nvertex angle: blue concave, white flat, red convex", fontsize=9)
    return fig


def main():
    args = parse_args("Export a curvature-coloured boundary surface with a picture.", arguments)
    ply, png = outputs(args, "surface.ply", "surface.png")
    name = Path(args.mesh).name

    solid = isoflow.voxelize_file(args.mesh, resolution=args.resolution)
    mesh = isoflow.boundary_mesh(solid.volume, connectivity=6)
    columns = {"config": mesh.config, "class": mesh.vertex_class, "gamma": mesh.gamma, "a": mesh.a, "f": mesh.f}
    colours = (plt.get_cmap("bwr")((mesh.gamma + 4) / 8) * 255).astype(np.uint8)
    surface = trimesh.Trimesh(solid.world(mesh.vertices), mesh.triangles(), process=False, vertex_colors=colours,
                              vertex_attributes={k: v.astype(np.int16) for k, v in columns.items()})
    surface.export(ply)
    draw(mesh, solid, f"{name} at {args.resolution} voxels across").savefig(png)

    chi = isoflow.euler_characteristic(solid.volume, 6)
    print(f"{ply.name}: {len(mesh.vertices)} vertices, {len(surface.faces)} triangles ({len(mesh.faces)} quads split), "
          f"V-E+F = {mesh.euler_characteristic}")
    print(f"  sum of a over the vertices = {int(mesh.a.sum())} = 8 chi of the solid (chi = {chi})")
    for i, s in enumerate(mesh.components()):
        print(f"  closed surface {i}: genus {s['genus']}")
    print(f"{png.name}: picture coloured by vertex angle; both in {args.out}")


if __name__ == "__main__":
    run(main)
