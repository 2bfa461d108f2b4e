"""``isoflow voxelize``: a mesh's solid as a volume file."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .inputs import add_mesh_rule, mesh_fill, say_note, voxelize_input
from .progress import progress_bar


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "voxelize", "voxelise a mesh's solid into a volume file (with pitch and origin)")
    p.add_argument("mesh", help="a mesh file: any format trimesh reads (STL, OBJ, PLY, OFF, GLB, 3MF, DAE, ZIP, ...)")
    grid = p.add_mutually_exclusive_group(required=True)
    grid.add_argument("--pitch", type=float, help="voxel size in mesh units")
    grid.add_argument("--resolution", type=int, help="voxels along the longest side")
    p.add_argument("-o", "--output", required=True,
                   help="OUT.npz (or .npy, .tif, .nii, .nii.gz, .nrrd, .h5[:/dataset], .binvox, .vox), or "
                        "OUT.zarr: written slab by slab as dask tasks, never held in memory")
    add_mesh_rule(p)
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.set_defaults(func=cmd_voxelize)


def cmd_voxelize(args: argparse.Namespace) -> int:
    from ..mesh.volumes import check_volume_output, write_volume

    if Path(args.output).suffix.lower() == ".zarr":
        return voxelize_to_store(args)
    check_volume_output(args.output, args.force)  # suffix, library and path before the voxelisation
    obj = voxelize_input(args.mesh, args)
    out = write_volume(obj, args.output, force=args.force)
    shape = "x".join(map(str, obj.volume.shape))
    print(f"{out}: {obj.voxels} voxels in a {shape} grid, pitch {obj.pitch:.6g}, origin {np.round(obj.origin, 6).tolist()}")
    return 0


def voxelize_to_store(args: argparse.Namespace) -> int:
    """Beyond memory: slab by slab into a chunked zarr array, as dask tasks."""
    from ..mesh.slabs import voxelize_to_zarr

    out = Path(args.output)
    with progress_bar(args, "voxelize", estimate=True) as show:
        z, details = voxelize_to_zarr(args.mesh, out, pitch=args.pitch, resolution=args.resolution,
                                      fill=mesh_fill(args), strict=args.strict, force=args.force, progress=show,
                                      details=True)
    say_note(args, args.mesh, details.note)
    shape = "x".join(map(str, z["shape"]))
    print(f"{out}: {z['voxels']} voxels in a {shape} zarr array (chunks {'x'.join(map(str, z['chunks']))}), "
          f"pitch {z['pitch']:.6g}, origin {np.round(z['origin'], 6).tolist()}")
    return 0
