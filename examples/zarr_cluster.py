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
The workers' notes (on numba's empty cache, that they compile isoflow's
passes, for minutes) are asked for every second and printed once on
stderr, as ``zarr_cluster.py: note: ...``.
Needs ``pip install 'isoflow[dask]'``.

.. code-block:: bash

    python examples/zarr_cluster.py [OUT] [--mesh M] [--resolution R] [--force]
"""

import json
import logging
import logging.handlers
import math
import threading
from contextlib import contextmanager

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


NOTES = "isoflow-notes"  # the name of the handler that keeps a worker's notes


def keep_notes() -> None:
    """In a worker process: keep what isoflow logs at level INFO (its
    notes) in a buffer that :func:`take_notes` empties. dask's log
    forwarding (``Client.forward_logging``) only pushes a record to the
    clients subscribed when it reaches the scheduler, and under load the
    client's subscription may come later, and the note is then lost."""
    log = logging.getLogger("isoflow")
    log.setLevel(logging.INFO)
    if not any(h.get_name() == NOTES for h in log.handlers):
        handler = logging.handlers.BufferingHandler(capacity=1000)
        handler.set_name(NOTES)
        log.addHandler(handler)


def take_notes() -> list[str]:
    """In a worker process: the notes kept since the last call (none in a
    worker started after :func:`keep_notes` ran, one the nanny restarted)."""
    handler = next((h for h in logging.getLogger("isoflow").handlers if h.get_name() == NOTES), None)
    if handler is None:
        return []
    with handler.lock:
        notes = [record.getMessage() for record in handler.buffer]
        handler.buffer.clear()
    return notes


def show_worker_notes(client, unless=None):
    """isoflow's notes from the worker processes, logged here as this
    process's own (and so printed once for all workers, as
    ``zarr_cluster.py: note: ...``). A worker that does not answer (one
    that died mid-run) is left out, and a poll that fails (a client
    closing) is skipped in silence: the notes only explain a wait, and the
    run's own result or error is what the script reports. Nothing is
    logged once the event ``unless`` is set (the run gave up on this poll)."""
    try:
        replies = client.run(take_notes, on_error="ignore")
    except Exception:  # the connection's own error, of any class (a closed client's AttributeError)
        return
    if unless is not None and unless.is_set():
        return
    for notes in replies.values():
        for note in notes:
            logging.getLogger("isoflow").info(note)


#: seconds the end of a run waits for the last poll of the workers' notes
#: (a poll answers in milliseconds; one that hangs is given up)
LAST_POLL_SECONDS = 10.0


@contextmanager
def worker_notes(client, every=1.0, wait=None):
    """Show the workers' notes while isoflow's calls run: on numba's empty
    cache each worker compiles the voxeliser's passes for minutes, which
    only its note explains. Asked for every ``every`` seconds, and once
    more at the end, so that none is missed; a poll that fails says
    nothing (:func:`show_worker_notes`), so the run's own error is the one
    raised.

    The polls, the last one too, run on a thread, and the run's end waits
    for them at most ``wait`` seconds (None: :data:`LAST_POLL_SECONDS`): a
    poll that hangs (a worker that never answers: ``client.run`` has no
    time limit) would hold the script for ever once its run is done. One that
    hangs is given up in silence, as a failed one is: the notes only
    explain a wait that is over by then, and a line about them would stand
    beside the run's own result or error, which is what the script
    reports; what the poll brings later is not printed (it would come
    after the run's report)."""
    client.run(keep_notes)
    done, given_up = threading.Event(), threading.Event()

    def ask():
        while not done.wait(every):
            show_worker_notes(client, given_up)
        show_worker_notes(client, given_up)  # the last notes, once the run is over

    asking = threading.Thread(target=ask, daemon=True)  # a hung poll does not hold the interpreter's exit
    asking.start()
    try:
        yield
    finally:
        done.set()
        asking.join(LAST_POLL_SECONDS if wait is None else wait)
        given_up.set()


def main():
    args = parse_args("A chunked zarr volume analysed out of core on a dask.distributed cluster.", arguments)
    store, report_path, picture = outputs(args, "solid.zarr", "report.json", "blocks.png")
    Client, LocalCluster = cluster_classes()

    with LocalCluster(n_workers=2, processes=True, threads_per_worker=1, dashboard_address=":0") as cluster, \
            Client(cluster) as client:
        with worker_notes(client):
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
