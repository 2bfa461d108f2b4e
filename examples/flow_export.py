"""
The digital curvature flow, step by step
========================================

Each step of the digital curvature flow (Definition 18) moves the object to
the other lattice (eq. 5.1): a voxel is kept at every old lattice vertex
that is interior or moves outward, so convex parts shrink and concave parts
fill. A voxelised torus (from :mod:`isoflow.data`) shrinks until it
vanishes at its limit point, its centre. At the default 24 voxels across it
keeps its tunnel to its last non-empty step (the step to the empty set is
the limit, not a change of topology); at ``--resolution 16`` its ring
breaks into pieces first, and each change of the Betti numbers is printed
with its step. With ``--guard``, no step may change them (Theorem 21).

Prints every step's figures and writes ``OUT/flow.csv`` (voxels, parity,
Betti numbers, chi and energy per step), ``OUT/step_NNN.ply`` (each step's
boundary surface, in the mesh's coordinates), ``OUT/flow.png`` (the figures
against the step) and ``OUT/shapes.png`` (the object at a few steps).
``isoflow flow MESH --resolution 24 --out DIR`` writes the same from the
command line, while the flow runs (its default resolution is 64).

.. code-block:: bash

    python examples/flow_export.py [OUT] [--mesh M] [--resolution R] [--guard] [--force]
"""

import csv
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import trimesh
from _common import outputs, parse_args, run

import isoflow
from isoflow import data


def arguments(parser):
    parser.add_argument("--mesh", default=str(data.torus()),
                        help="a closed triangle mesh file, or the name of one of isoflow.data's samples")
    parser.add_argument("--resolution", type=int, default=24, help="voxels along the longest side")
    parser.add_argument("--guard", action="store_true", help="topology control (Theorem 21)")


def write_table(result, path):
    """One row per step; the Betti numbers as columns b0, b1, b2."""
    with open(path, "w", newline="") as fh:
        writer = csv.writer(fh)
        writer.writerow(["step", "voxels", "parity", "b0", "b1", "b2", "euler_characteristic", "energy"])
        for s in result.steps:
            writer.writerow([s["step"], s["voxels"], s["parity"], *s["betti"], s["euler_characteristic"], s["energy"]])


def plot_figures(result):
    from matplotlib.ticker import MaxNLocator

    steps = [s["step"] for s in result.steps]
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.5))
    axes[0].plot(steps, [s["voxels"] for s in result.steps], "o-")
    axes[0].set_title("voxels")
    axes[1].plot(steps, [s["energy"] for s in result.steps], "o-", color="tab:red")
    axes[1].set_title("energy E = k^T n")
    for i in range(3):  # each line narrower than the one below it: the torus's b0 = b1 = 1 would hide b0
        width = 5.0 - 2.0 * i
        axes[2].plot(steps, [s["betti"][i] for s in result.steps], "o-", lw=width, ms=2.5 + width, label=f"b{i}")
    axes[2].legend()
    axes[2].set_title("Betti numbers")
    for ax in axes:  # steps, counts and Betti numbers are whole numbers, not 0.2, 0.4, ...
        ax.set_xlabel("step")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    fig.tight_layout()
    return fig


def plot_shapes(result, count=4):
    """The object at ``count`` steps from the first to the last non-empty
    one: each step's boundary surface, shaded by its faces' normals (one
    collection of polygons: matplotlib's ``voxels`` draws a cube per voxel,
    minutes for a modest object)."""
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    steps = [i for i, s in enumerate(result.states) if s.voxels]
    shown = steps[:: max(1, len(steps) // count)][:count]
    light = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    orange = np.array(plt.matplotlib.colors.to_rgb("tab:orange"))
    fig = plt.figure(figsize=(3 * len(shown), 3.2))
    for i, step in enumerate(shown):
        state = result.states[step]
        mesh = isoflow.boundary_mesh(state.volume, 6)
        shade = 0.45 + 0.55 * np.clip(mesh.face_normals.astype(float) @ light, 0, 1)
        ax = fig.add_subplot(1, len(shown), i + 1, projection="3d")
        ax.add_collection3d(Poly3DCollection(mesh.vertices[mesh.faces], facecolors=orange * shade[:, None],
                                             edgecolors="k", linewidths=0.1))
        for setter, n in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), state.volume.shape):
            setter(0, n)
        ax.set_title(f"step {step}: {state.voxels} voxels", fontsize=9)
        ax.set_box_aspect(state.volume.shape)
        ax.set_axis_off()
    fig.tight_layout()
    return fig


def main():
    args = parse_args("Run the digital curvature flow on a voxelised mesh and export every step.", arguments)
    table, figures, shapes = outputs(args, "flow.csv", "flow.png", "shapes.png")
    if any(args.out.glob("step_*.ply")) and not args.force:
        raise isoflow.IsoflowError(f"{args.out}: holds step_*.ply files; pass --force to overwrite")
    solid = isoflow.voxelize_file(args.mesh, resolution=args.resolution)
    result = isoflow.run_flow(solid, guard=args.guard, connectivity=6)  # keeps every state

    print(f"{Path(args.mesh).name} at {args.resolution} voxels across, flow with 6-connectivity"
          f"{', guarded' if args.guard else ''}")
    print(f"  {'step':>4} {'voxels':>7}  betti      chi  energy")
    written = set()
    for s, state in zip(result.steps, result.states):
        print(f"  {s['step']:>4} {s['voxels']:>7}  {str(tuple(s['betti'])):<10} {s['euler_characteristic']:>3} "
              f"{s['energy']:>7}")
        if state.voxels:  # the step's boundary, in the mesh's coordinates
            mesh = isoflow.boundary_mesh(state.volume, 6)
            ply = args.out / f"step_{s['step']:03d}.ply"
            trimesh.Trimesh(state.world(mesh.vertices), mesh.triangles(), process=False).export(ply)
            written.add(ply)
    for stale in set(args.out.glob("step_*.ply")) - written:  # an earlier run's (--force): not steps of this flow
        stale.unlink()
    centre = result.limit["center"]
    where = "none" if centre is None else "(" + ", ".join(f"{c + 0:.3g}" for c in np.round(centre, 9)) + ")"
    print(f"  stopped: {result.stop_reason}; limit point {where}")
    for c in result.topology_changes:
        print(f"  topology change at step {c['step']}: {tuple(c['before'])} -> {tuple(c['after'])}")

    write_table(result, table)
    plot_figures(result).savefig(figures)
    plot_shapes(result).savefig(shapes)
    print(f"wrote {table.name}, {figures.name}, {shapes.name} and the steps' surfaces to {args.out}")


if __name__ == "__main__":
    run(main)
