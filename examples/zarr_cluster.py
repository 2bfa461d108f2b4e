"""
Out of core: a zarr volume on a dask.distributed cluster
========================================================

A volume that does not fit in memory is written and read block by block.
:func:`isoflow.voxelize_to_zarr` voxelises a mesh (the genus-2 "eight" of
:mod:`isoflow.data`) slab by slab into an OME-Zarr store (``OUT/solid.zarr``,
chunks of odd sizes, so that the object, its tunnels and its boundary cross
block faces, edges and corners), and :func:`isoflow.analyze_zarr` computes
its report block by block on a ``LocalCluster`` of two worker processes:
configuration histograms per block, components and closed surfaces joined
across block faces. Both take any dask scheduler, so the same code runs on
a real cluster.

Because this sample is small, the script also loads the volume and checks
that the report equals the in-memory one in every field, the doubled
edges across block faces included. Prints both and writes
``OUT/report.json`` and a slice with the block faces (``OUT/blocks.png``).
Needs ``pip install 'isoflow[dask]'``.

.. code-block:: bash

    python examples/zarr_cluster.py [OUT] [--mesh M] [--resolution R] [--force]
"""

import json
import logging
import math

import matplotlib.pyplot as plt
import numpy as np
from _common import outputs, parse_args, run

import isoflow
from isoflow import data

CHUNKS = (19, 29, 13)  # odd sizes: objects, tunnels and cavities cross block faces, edges and corners


def arguments(parser):
    parser.add_argument("--mesh", default=str(data.eight()),
                        help="a closed triangle mesh file, or the name of one of isoflow.data's samples")
    parser.add_argument("--resolution", type=int, default=96, help="voxels along the longest side")


def plot_blocks(volume, chunks):
    """The middle slice across z, with the block faces the report was joined across."""
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.imshow(volume[:, :, volume.shape[2] // 2], origin="lower", cmap="Greys")  # x up, y across
    for x in range(chunks[0], volume.shape[0], chunks[0]):
        ax.axhline(x - 0.5, color="tab:red", linewidth=0.8)
    for y in range(chunks[1], volume.shape[1], chunks[1]):
        ax.axvline(y - 0.5, color="tab:red", linewidth=0.8)
    ax.set_xlabel("y")
    ax.set_ylabel("x")
    ax.set_title(f"slice z = {volume.shape[2] // 2}: blocks of {chunks} voxels (red faces)")
    fig.tight_layout()
    return fig


def cluster_classes():
    """dask.distributed's ``Client`` and ``LocalCluster``; imported here so
    that an install without ``isoflow[dask]`` gets one line, not a traceback."""
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError as exc:
        raise isoflow.IsoflowError(f"this example needs dask.distributed: pip install 'isoflow[dask]' ({exc})") from None
    return Client, LocalCluster


def show_worker_notes(client):
    """isoflow's notes from the worker processes, printed here as this
    process's own: on numba's empty cache each worker compiles the
    voxeliser's passes for minutes, which only its note explains."""
    client.run(lambda: logging.getLogger("isoflow").setLevel(logging.INFO))
    client.forward_logging("isoflow", level=logging.INFO)


def main():
    args = parse_args("A chunked zarr volume analysed out of core on a dask.distributed cluster.", arguments)
    store, report_path, picture = outputs(args, "solid.zarr", "report.json", "blocks.png")
    Client, LocalCluster = cluster_classes()

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        show_worker_notes(client)
        written = isoflow.voxelize_to_zarr(args.mesh, store, resolution=args.resolution, chunks=CHUNKS,
                                           scheduler=client.get, force=args.force)
        chunked = isoflow.analyze_zarr(store, connectivity=6, scheduler=client.get)
    solid = isoflow.read_volume(store)  # placed as the store says, as analyze_zarr places it
    volume = solid.volume
    in_memory = isoflow.analyze(solid, connectivity=6)
    report_path.write_text(json.dumps({"chunked": chunked.to_dict(), "in_memory": in_memory.to_dict()}, indent=1))
    plot_blocks(volume, CHUNKS).savefig(picture)

    shape = written.shape
    blocks = math.prod(math.ceil(s / c) for s, c in zip(shape, CHUNKS))
    print(f"{store.name}: shape {shape}, {blocks} blocks of up to {CHUNKS}, 2 worker processes")
    for name, r in (("out of core", chunked), ("in memory", in_memory)):
        surfaces = len(r["surfaces"])
        print(f"  {name:<12} voxels {r['voxels']}, chi {r['euler_characteristic']}, betti {r['betti']}, "
              f"energy {r['energy']}, {surfaces} closed surface{'s' * (surfaces != 1)}")
    print(f"  the two reports are {'identical' if chunked == in_memory else 'DIFFERENT'}")
    print(f"wrote {report_path.name} and {picture.name} to {args.out}")
    if chunked != in_memory or int(np.count_nonzero(volume)) != written.voxels:
        raise SystemExit(1)


if __name__ == "__main__":
    run(main)
