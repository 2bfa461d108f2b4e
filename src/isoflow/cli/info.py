"""``isoflow info``: the topology and curvature-index histogram of an object."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import threading
import uuid
from pathlib import Path

from ..digital.report import Report
from ..errors import DoesNotFit, IsoflowError, betti_words, coordinates, counted, path_text, terminal_text
from ..results import json_ready
from .inputs import (
    add_connectivity,
    add_input_arguments,
    check_input_connectivity,
    label_options,
    load_input_with_unit,
    mesh_fill,
    refuse_mesh_options,
    refuse_points_option,
    say_note,
    say_plate,
    thread_count,
    why_empty,
)
from .labels import add_labels_option, in_hdf5_slabs, is_hdf5, refuse_names_without_labels
from .progress import progress_bar
from .table_text import json_rows, measure_text


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "info", "topology and curvature-index histogram of an object")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    add_labels_option(p)
    p.add_argument("--csv", metavar="FILE", help="with --labels: write the full table as CSV (- prints it on stdout)")
    p.add_argument("--png", metavar="FILE",
                   help="with --labels: also draw the table as a picture (labels by Betti numbers, the volumes' "
                        "histogram, surface area against volume)")
    p.add_argument("--force", action="store_true", help="overwrite an existing --csv or --png file")
    p.add_argument("--no-surfaces", action="store_true", help="skip the per-surface genus")
    p.add_argument("--threads", type=thread_count, metavar="N",
                   help="threads for the compiled passes; for a 2D or 3D .zarr store without --labels, read block by "
                        "block, the threads of dask's threaded scheduler, each block's passes on one (default: "
                        "$ISOFLOW_THREADS, else every CPU)")
    p.add_argument(
        "--gpu",
        action="store_true",
        help="compute chi, Betti numbers and n on a CUDA GPU with CuPy (pip install 'isoflow[gpu]')",
    )
    p.set_defaults(func=cmd_info)


def cmd_info(args: argparse.Namespace) -> int:
    from ..mesh.formats.omezarr import stored_ndim
    from ..mesh.formats.registry import split_dataset

    if args.force and not (args.csv or args.png):  # alone it would overwrite nothing: a file option is missing
        raise IsoflowError(f"{args.input}: --force overwrites an existing --csv or --png file; without them info "
                           "writes no file (give --csv FILE, or --png FILE with --labels)")
    if args.png and args.labels is None:  # one object's report has no distribution to draw
        raise IsoflowError(f"{args.input}: --png draws the table of --labels (info {args.input} --labels --png "
                           f"{args.png}); one object's report has no picture")
    refuse_names_without_labels(args)
    if args.labels is not None:
        from .labels import cmd_info_labels

        return cmd_info_labels(args)
    if args.csv:
        raise IsoflowError(f"{args.input}: --csv writes the table of --labels; without it, --json prints the report")
    grid = None
    # with --label a plain (X, Y, Z, 1) array is a 3D label image, as in memory
    channel = args.label is not None
    if split_dataset(args.input)[0].suffix.lower() == ".zarr" and stored_ndim(args.input, channel) in (2, 3):
        report = info_of_store(args)
        placed: dict | None = store_placement(args.input, report.unit, channel)
    elif in_hdf5_slabs(args.input):
        report, placed = info_of_dataset(args)
    else:
        try:
            report, grid, placed = info_in_memory(args)
            whole = True
        except DoesNotFit:
            # an HDF5 volume read whole whose report would not fit beside it: read a block at a time instead,
            # once the volume read is let go (the refusal's traceback holds it until this block ends)
            if args.gpu or not hdf5_volume(args.input):
                raise
            whole = False
        if not whole:
            (report, placed), grid = info_of_dataset(args), None
    if args.json:
        print(report_json(report, {**(placed or {}), **({"voxelised": grid} if grid else {}),
                                   "input": path_text(args.input)}))
        return 0
    # escaped as a label's name is: a line break in it would split the report's first line
    print(format_info(report, terminal_text(args.input), grid, placed))
    return 0


def report_json(report: Report, more: dict) -> str:
    """What ``info --json`` prints: the report's keys, then ``more`` (the
    input's), as ``json.dumps`` writes them, infinities as null
    (:func:`finite_or_null`). The surfaces are written from their columns
    (:func:`~isoflow.cli.table_text.json_rows`): a noisy object has a
    million, which as dicts would be made only to be written.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow import analyze
    >>> r = analyze(np.ones((2, 2, 2), bool))
    >>> report_json(r, {"input": "cube.npy"}) == json.dumps({**r.to_dict(), "input": "cube.npy"})
    True
    """
    surfaces = report.get("surfaces")
    # a string no value holds, put where the surfaces go and replaced by their text
    mark = f"surfaces-{uuid.uuid4().hex}"
    fields = {k: (mark if k == "surfaces" else json_ready(report[k])) for k in report}
    text = json.dumps(finite_or_null({**fields, **more}))
    if surfaces is None:
        return text
    return text.replace(json.dumps(mark), "".join(json_rows(surfaces.columns())), 1)


def calibration(obj, unit: str | None, dtype) -> dict:
    """A volume file's type of values by NumPy's name (``uint8``, ``bool``:
    the object is boolean whatever the file held), its voxel size per axis,
    the world position of voxel 0's lowest corner, their length unit
    (None where the file says none) and the anatomical frame of the world
    axes (``space``: ``"RAS"``, ``"LPS"``, ...; None where the file says
    none): what ``info`` says it read, so that a calibration can be
    checked."""
    import numpy as np

    from ..mesh.formats.registry import placement

    spacing, corner = placement(obj)
    return {"dtype": np.dtype(dtype).name, "pitch": [float(p) for p in spacing],
            "origin": [float(c) + 0.0 for c in corner], "unit": unit, "space": obj.space}


def store_placement(path, unit: str | None, channel: bool = False) -> dict:
    """:func:`calibration` of a zarr store read block by block, from its
    metadata (the volume is not read); ``unit`` as the report found it
    (read from the axes again, a warning about them would be said twice);
    ``channel`` as :func:`~isoflow.mesh.formats.omezarr.open_store` takes
    it."""
    from ..digital.lattice import DigitalObject
    from ..mesh.formats.omezarr import open_store

    store = open_store(path, time=True, channel=channel)
    pitch, origin = store.placement()
    try:
        place = DigitalObject.placement(len(store.xyz), pitch=pitch, origin=origin)
    except IsoflowError as exc:
        raise exc.at(path) from None
    return calibration(place, unit, store.array.dtype)


def info_of_store(args: argparse.Namespace) -> Report:
    """Out of core: block by block, never the whole volume in memory (4D
    arrays are read whole, as from the other formats)."""
    from ..mesh.formats.omezarr import analyze_store, stored_shape

    refuse_mesh_options(args, ".zarr")
    refuse_points_option(args, "volume")
    if args.gpu:
        raise IsoflowError(f"{args.input}: --gpu takes volumes that fit in memory; .zarr is read block by block on the host")
    shape = stored_shape(args.input, args.label is not None)
    check_input_connectivity(args, len(shape))
    say_plate(args, shape)
    with progress_bar(args, "blocks") as show, label_options(args):
        return analyze_store(args.input, args.connectivity, label=args.label, progress=show,
                             surfaces=not args.no_surfaces, threads=args.threads)


def hdf5_volume(path: str) -> bool:
    """Whether the input is an HDF5 file's 3D volume, which
    :func:`info_of_dataset` reads a block at a time.

    Examples
    --------
    >>> hdf5_volume("seg.nii.gz")  # no HDF5 file: not opened
    False
    """
    from ..mesh.formats import hdf5

    return is_hdf5(path) and hdf5.is_3d(path)


def info_of_dataset(args: argparse.Namespace) -> tuple[Report, dict]:
    """An HDF5 dataset too large to read whole, a block at a time
    (:func:`isoflow.mesh.formats.hdf5.analyze_dataset`): its report, and
    its voxel size, origin and unit as :func:`calibration` gives them."""
    from ..mesh.formats import hdf5

    refuse_mesh_options(args, "HDF5")
    refuse_points_option(args, "volume")
    if args.gpu:
        raise IsoflowError(f"{args.input}: --gpu takes volumes that fit in memory; this HDF5 dataset does not, and is "
                           "read a block at a time on the host")
    slabs = hdf5.LabelSlabs(args.input)
    check_input_connectivity(args, 3)
    say_plate(args, slabs.shape)
    with progress_bar(args, "blocks") as show, label_options(args):
        report = hdf5.analyze_dataset(slabs, args.connectivity, label=args.label, progress=show,
                                      surfaces=not args.no_surfaces, threads=args.threads)
    return report, calibration(slabs.place, slabs.unit, slabs.dtype)


def info_in_memory(args: argparse.Namespace) -> tuple[Report, dict | None, dict | None]:
    """The report, for a mesh the grid it was voxelised on
    (:func:`mesh_grid`), and for a volume file its voxel size, origin and
    unit (:func:`calibration`)."""
    from ..digital.analysis import analyze
    from ..mesh.volumes import is_volume

    warming = warm_up_while_reading(args)
    try:
        obj, unit, dtype = load_input_with_unit(args)
    finally:
        # joined on a refusal too: a thread left compiling would outlive the
        # command, and numba's compile records the warnings of every thread
        # and says them again when it ends, in whatever runs then
        if warming is not None:
            warming.join()
    check_input_connectivity(args, obj.ndim)
    # an empty report is an answer, but of a point list with points it needs
    # the reason
    say_note(args, args.input, why_empty(args, obj) if obj.voxels == 0 else None, why=True)
    grid = mesh_grid(args, obj)
    placed = calibration(obj, unit, dtype) if grid is None and is_volume(args.input) else None
    if args.gpu:
        from ..scale.arrays import to_gpu

        # a bare array has no lattice place: the object's given with it
        report = analyze(to_gpu(obj.volume), args.connectivity, surfaces=not args.no_surfaces, threads=args.threads,
                         pitch=obj.spacing, origin=obj.world([0] * obj.ndim), unit=obj.unit)
        return dataclasses.replace(report, parity=obj.parity), grid, placed
    # numba loaded while the file was read: its pass is then the faster at
    # any size ("auto" weighs numba's start against the volume, and that
    # start is paid)
    method = "compiled" if warming is not None and warming.loaded and obj.ndim == 3 else "auto"
    report = analyze(obj, args.connectivity, surfaces=not args.no_surfaces, threads=args.threads, method=method)
    return report, grid, placed


def mesh_grid(args: argparse.Namespace, obj) -> dict | None:
    """For a mesh input, the fill and the grid its voxels are (the counts
    differ by fill and pitch, and a report that did not say which could not
    be told from another); None for a volume or a point list."""
    from ..mesh.load import is_mesh_path

    if not is_mesh_path(Path(args.input)):
        return None
    return {"fill": mesh_fill(args), "pitch": float(obj.pitch), "origin": [float(x) for x in obj.origin]}


#: the name of the thread that loads numba while the input is read
WARM_UP_THREAD = "isoflow info: loading the compiled passes"


class WarmUp(threading.Thread):
    """Loads the compiled 3D pass (numba and its cached code, once per
    process) on a thread of its own; ``loaded`` says whether it did."""

    def __init__(self, surfaces: bool) -> None:
        super().__init__(name=WARM_UP_THREAD, daemon=True)
        self.surfaces = surfaces
        self.loaded = False

    def run(self) -> None:
        from ..digital.closed_surfaces import warm_up

        with contextlib.suppress(Exception):  # the command itself says what fails
            warm_up(surfaces=self.surfaces)
            self.loaded = True


def warm_up_while_reading(args: argparse.Namespace) -> WarmUp | None:
    """A thread that loads the compiled passes while the input is read,
    which releases the GIL; only for files that may hold a volume large
    enough to use them (a small one answers in the NumPy passes, without
    numba's start). A file's size says little of its voxels (compression),
    so a volume read while numba loaded takes the compiled pass whatever
    its size (:func:`info_in_memory`)."""
    from ..mesh.formats.npy import voxel_count
    from ..mesh.formats.registry import split_dataset
    from ..mesh.load import is_mesh_path
    from ..scale.compiled import have_numba, least_voxels

    path = split_dataset(args.input)[0]
    least = least_voxels(surfaces=not args.no_surfaces)
    try:
        # the voxels from a .npy's header; elsewhere a bit per voxel at the
        # least (binvox; compressed files: no matter)
        voxels = voxel_count(path) if path.suffix.lower() == ".npy" else None
        big = path.stat().st_size >= least // 8 if voxels is None else voxels >= least
    except OSError:
        return None
    if args.gpu or not big or is_mesh_path(path) or not have_numba():
        return None
    thread = WarmUp(surfaces=not args.no_surfaces)
    thread.start()
    return thread


def format_info(r: Report, name: str, grid: dict | None = None, placed: dict | None = None) -> str:
    """The report as a terminal reads it (``grid``: a mesh's, :func:`mesh_grid`;
    ``placed``: a volume file's, :func:`calibration`)."""
    lines = [
        f"{name}: {r['dimension']}D, shape {'x'.join(map(str, r['shape']))}, "
        f"{counted(r['voxels'], 'pixel' if r['dimension'] == 2 else 'voxel')}, {r['connectivity']}-connectivity",
    ]
    if grid:
        # (as voxelize prints them), in the unit the mesh file declares where it declares one
        said = f" {r.unit}" if r.unit else ""
        lines.append(f"  voxelised              --fill {grid['fill']}, pitch {grid['pitch']:.6g}{said}, "
                     f"origin {coordinates(grid['origin'], step=grid['pitch'])}{said}")
    if placed:
        unit = f" {placed['unit']}" if placed["unit"] else ""
        size = f"{'pixel' if r['dimension'] == 2 else 'voxel'} size"
        # the length unit is of the three spatial axes: a 4D file's fourth
        # axis (a time series' frames) is said apart, without it
        space, beyond = min(3, len(placed["pitch"])), len(placed["pitch"]) > 3
        fourth = (f" (4th axis: size {placed['pitch'][3]:.6g}, origin {placed['origin'][3]:.6g})" if beyond else "")
        origin = coordinates(placed["origin"][:space], step=placed["pitch"][:space])
        lines.append(f"  {size:<23}{' x '.join(f'{p:.6g}' for p in placed['pitch'][:space])}{unit}, "
                     f"origin {origin}{unit}{'' if unit else ' (the file says no unit)'}"
                     + fourth + (f", frame {placed['space']}" if placed.get("space") else ""))
    # a point list's coordinates are lattice units: a voxel is 1 wide, and
    # a box at 1e12 must not print its two sides as the same 1e+12
    lines += format_measures(r, placed["pitch"][:3] if placed else grid["pitch"] if grid else 1.0)
    lines += [
        f"  Euler characteristic   {r['euler_characteristic']}",
    ]
    lines.append("  Betti numbers          " + betti_words(r["betti"]))
    lines.append("  vertex classes (eq. 4.9):")
    # one column for every count: as wide as the widest, so that
    # 10^12 voxels' rows still end where the others do
    rows = [(str(label), count) for label, count in r["classes"].items()]
    rows.append(("not well-composed", r["non_well_composed"]))
    width = max([5] + [len(str(count)) for _, count in rows])
    lines += [f"    {label:<17} {count:>{width}}" for label, count in rows]
    scale = 1 << r["dimension"]
    lines.append(f"  a^T n                  {r['a_dot_n']}  (= {scale} chi)")
    lines.append(f"  energy E = k^T n       {r['energy']}")
    lines += format_surfaces(r)
    return "\n".join(lines)


def finite_or_null(report: dict) -> dict:
    """The report's values with every float beyond float64 (a volume of
    voxels of 1e150: inf) as None, which JSON writes ``null``: ``Infinity``
    is no JSON, and strict parsers refuse the line (as the label table's
    JSON writes such a volume).

    Examples
    --------
    >>> finite_or_null({"volume": float("inf"), "bbox": [0.0, float("inf")], "voxels": 3})
    {'volume': None, 'bbox': [0.0, None], 'voxels': 3}
    """
    def finite(x):
        if isinstance(x, float) and not math.isfinite(x):
            return None
        return [finite(y) for y in x] if isinstance(x, list) else x

    return {key: finite(value) for key, value in report.items()}


def format_measures(r: Report, step=None) -> list[str]:
    """The world measures in two lines, in the report's unit (none said
    where it has none); coordinates to within a 200th of ``step``, the
    voxel size, where known (:func:`~isoflow.errors.coordinates`)."""
    if r.get("bbox", False) is False:  # no measures in this dimension (4D, 1D)
        return []
    size, boundary = ("volume", "surface_area") if r.dimension == 3 else ("area", "perimeter")
    unit = f" {r.unit}" if r.unit else ""
    # the boundary's unit: squared in 3D (an area), a length in 2D
    power = {size: f"{unit}^{r.dimension}" if unit else "", boundary: f"{unit}^2" if unit and r.dimension == 3 else unit}
    lines = [f"  {size:<23}{measure_text(r[size], r.voxels, step, r.dimension)}{power[size]}, "
             f"{boundary.replace('_', ' ')} {measure_text(r[boundary])}{power[boundary]}"]
    if r.bbox is None:
        lines.append("  bounding box           none (no voxels)")
    else:
        lo, hi = r.bbox[:r.dimension], r.bbox[r.dimension:]
        lines.append(f"  bounding box           {coordinates(lo, step=step)} to {coordinates(hi, step=step)}{unit}, "
                     f"centroid {coordinates(r.centroid, step=step)}{unit}")
    return lines


def format_surfaces(r: Report) -> list[str]:
    lines = []
    if r.surfaces is not None:  # counted, and said when none: an empty object's 0 is an answer, as --json's []
        lines.append(f"  closed surfaces        {len(r['surfaces'])}")
        for i, s in enumerate(r["surfaces"][:10]):
            lines.append(f"    #{i}: genus {s['genus']}, chi {s['euler_characteristic']}, {s['faces']} faces")
        if len(r["surfaces"]) > 10:
            lines.append(f"    ... {len(r['surfaces']) - 10} more")
    if r.dimension != 3:  # said outright: no line at all would read as "no surfaces found"
        boundary = "closed curves" if r.dimension == 2 else "a 3-manifold"
        lines.append(f"  closed surfaces        not applicable in {r['dimension']}D (the boundary is {boundary})")
    if r.get("pinched_vertices"):
        said = f"  pinched vertices       {r['pinched_vertices']} (split in the mesh, joined by the connectivity)"
        genera = sum(r.genus) if r.genus is not None else None
        if genera is not None and genera != r["betti"][1]:
            # the surfaces' genus counts the sheets apart at a pinch, b1
            # counts the tunnels the connectivity makes through it
            said = said[:-1] + (f": the surfaces' genus, {genera} in all, counts the sheets apart there, where "
                                f"the connectivity makes {counted(r['betti'][1], 'tunnel')})")
        lines.append(said)
    return lines
