"""A chunked zarr volume analysed out of core on a dask.distributed cluster.

    python examples/zarr_cluster.py [OUT] [--mesh M] [--resolution R]

The mesh is voxelised slab by slab straight into a zarr store (OUT/solid.zarr,
chunks of odd sizes), so the whole volume is never in memory; then a
LocalCluster of two worker processes computes its report block by block
(isoflow.analyze_chunked: each block through the sweep of the in-memory
report, components, closed surfaces and doubled edges joined across block
faces). Because this sample is small, the script also
loads the volume and checks the report against the in-memory one. Prints
both and writes OUT/report.json. Needs isoflow[dask] (dask, distributed, zarr).
"""

import json
import math

import numpy as np
import zarr
from dask.distributed import Client, LocalCluster

import isoflow
from isoflow.mesh.load import load_mesh
from isoflow.mesh.outputs import check_output_path
from isoflow.mesh.voxelize import voxelize
from _common import MESHES, parse_args, run

CHUNKS = (19, 29, 13)  # odd sizes: objects, tunnels and cavities cross block faces, edges and corners


def arguments(parser):
    parser.add_argument("--mesh", default=str(MESHES / "eight.off"), help="a closed triangle mesh")
    parser.add_argument("--resolution", type=int, default=96, help="voxels along the longest side")


def voxelize_to_zarr(mesh, resolution, path):
    """Voxelise slab by slab (one chunk thick along x) into a new zarr array."""
    v, f = load_mesh(mesh)
    lo, hi = v.min(axis=0), v.max(axis=0)
    pitch = float((hi - lo).max()) / resolution
    shape = tuple(math.ceil(e / pitch) + 2 for e in hi - lo)  # one empty voxel around
    origin = (lo + hi) / 2 - pitch * np.array(shape) / 2
    z = zarr.open_array(str(path), mode="w", shape=shape, chunks=CHUNKS, dtype=bool)
    for x0 in range(0, shape[0], CHUNKS[0]):
        nx = min(CHUNKS[0], shape[0] - x0)
        grid = (origin + [x0 * pitch, 0, 0], (nx, *shape[1:]))
        z[x0:x0 + nx], _, _ = voxelize(v, f, pitch=pitch, grid=grid)
    return z


def main():
    args = parse_args(__doc__.splitlines()[0], arguments)
    store = args.out / "solid.zarr"
    if store.exists() and not args.force:
        raise isoflow.IsoflowError(f"{store}: exists; pass --force to overwrite")
    report_path = check_output_path(args.out / "report.json", args.force)
    z = voxelize_to_zarr(args.mesh, args.resolution, store)

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        chunked = isoflow.analyze_chunked(z, connectivity=6, scheduler=client.get)
    in_memory = isoflow.analyze(np.asarray(z[:]), connectivity=6)
    report_path.write_text(json.dumps({"chunked": chunked, "in_memory": in_memory}, indent=1))

    blocks = math.prod(math.ceil(s / c) for s, c in zip(z.shape, CHUNKS))
    print(f"{store}: shape {z.shape}, {blocks} blocks of up to {CHUNKS}, 2 worker processes")
    for name, r in (("out of core", chunked), ("in memory", in_memory)):
        print(f"  {name:<12} voxels {r['voxels']}, chi {r['euler_characteristic']}, betti {r['betti']}, "
              f"energy {r['energy']}, {len(r['surfaces'])} closed surfaces")
    print(f"  the two reports are {'identical' if chunked == in_memory else 'DIFFERENT'}")
    print(f"wrote {report_path}")
    if chunked != in_memory:
        raise SystemExit(1)


if __name__ == "__main__":
    run(main)
