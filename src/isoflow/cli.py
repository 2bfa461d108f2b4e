"""The ``isoflow`` command line: argument parsing and messages only.

Every command reads its input through :func:`load_input`, hands arrays to the
core, and prints either a readable table or one JSON object. Bad input
becomes one line on stderr and exit status 2; heavy libraries (trimesh,
matplotlib) are imported only by the commands that need them, so that
``isoflow info`` starts fast; so are tqdm (the progress bars, only on a
terminal) and shtab (only by ``isoflow completion``).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from pathlib import Path

import numpy as np

from .errors import IsoflowError


# --------------------------------------------------------------------------
# input
# --------------------------------------------------------------------------


def add_input_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", help="volume (.npy/.npz, .tif, .nii(.gz), .nrrd, FILE.h5:/dataset, .binvox, .vox, "
                                 ".zarr), point list (.txt: x y z per line) or mesh (any format trimesh reads)")
    p.add_argument("--label", type=label_value, metavar="N",
                   help="a label image: the voxels of value N are the object (MagicaVoxel: colour index N)")
    p.add_argument(
        "--points-are",
        choices=("corners", "voxels"),
        default="corners",
        help="a point list gives cube corners (the paper's point model, default) or voxel indices",
    )
    grid = p.add_mutually_exclusive_group()
    grid.add_argument("--pitch", type=float, help="voxel size when the input is a mesh")
    grid.add_argument("--resolution", type=int, help="voxels along the mesh's longest side (default 64)")
    add_mesh_rule(p)


def add_mesh_rule(p: argparse.ArgumentParser) -> None:
    p.add_argument("--strict", action="store_true",
                   help="refuse a mesh that is not watertight, or whose voxels lie in overlapping layers "
                        "(by default it is read by the generalised winding number)")
    p.add_argument("--allow-open", action="store_true",
                   help="accepted for compatibility: open meshes are read by default")


def add_connectivity(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--connectivity",
        type=int,
        choices=(4, 6, 8, 26, 80),
        default=None,
        help="object connectivity: 6 or 26 in 3D, 4 or 8 in 2D, 8 or 80 in 4D (default: 6 / 4 / 8, the paper's)",
    )


def label_value(text: str):
    """``--label N``: a number, kept an int when it is one."""
    try:
        return int(text)  # exactly, however large (checked against the array's type)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    return int(value) if value.is_integer() else value


def say_note(args, path, report: dict) -> None:
    """What is unusual about a mesh, and the rule used: one line on stderr
    (dropped by --quiet)."""
    if report.get("note") and not args.quiet:
        print(f"isoflow {args.command}: note: {path}: {report['note']}", file=sys.stderr)


def voxelize_input(path, args):
    """A mesh file voxelised by the one mesh reader of every command."""
    from .mesh.voxelize import voxelize_file

    report: dict = {}
    with progress_bar(args, "voxelize") as show:
        obj = voxelize_file(path, pitch=args.pitch, resolution=args.resolution, strict=args.strict,
                            progress=show, report=report)
    say_note(args, path, report)
    return obj


def load_input(args):
    """The digital object named on the command line (volume, points or mesh)."""
    from .mesh.load import is_mesh_path
    from .mesh.volumes import read_object

    path = Path(args.input)
    if is_mesh_path(path):
        if getattr(args, "label", None) is not None:
            raise IsoflowError(f"{path}: --label selects voxels of a volume, not of a mesh")
        return voxelize_input(path, args)
    if args.pitch is not None or args.resolution is not None or args.allow_open or args.strict:
        raise IsoflowError(
            f"{path}: --pitch/--resolution/--strict/--allow-open apply to meshes, not to {path.suffix or 'this'} input")
    # the name as given: FILE.h5:/dataset and IMAGE.zarr:LEVEL name a part of a file
    return read_object(args.input, points_are=args.points_are, label=args.label)


# --------------------------------------------------------------------------
# commands
# --------------------------------------------------------------------------


def cmd_info(args) -> int:
    from .digital.analysis import analyze

    from .mesh.formats.omezarr import stored_ndim
    from .mesh.formats.registry import split_dataset

    if split_dataset(args.input)[0].suffix.lower() == ".zarr" and stored_ndim(args.input) in (2, 3):
        # out of core: block by block, never the whole volume in memory (4D
        # arrays are read whole, as from the other formats)
        from .mesh.formats.omezarr import analyze_store

        if args.pitch is not None or args.resolution is not None or args.allow_open or args.strict:
            raise IsoflowError(f"{args.input}: --pitch/--resolution/--strict/--allow-open apply to meshes, not to .zarr input")
        if args.gpu:
            raise IsoflowError(f"{args.input}: --gpu takes volumes that fit in memory; .zarr is read block by block on the host")
        with progress_bar(args, "blocks") as show:
            report = analyze_store(args.input, args.connectivity, label=args.label, progress=show,
                                   surfaces=not args.no_surfaces, threads=args.threads)
    else:
        warming = warm_up_while_reading(args)
        obj = load_input(args)
        if warming is not None:
            warming.join()
        if args.gpu:
            from .scale.arrays import to_gpu

            report = analyze(to_gpu(obj.volume), args.connectivity, surfaces=not args.no_surfaces, threads=args.threads)
            report["parity"] = obj.parity  # a bare array has no lattice place
        else:
            report = analyze(obj, args.connectivity, surfaces=not args.no_surfaces, threads=args.threads)
    report["input"] = str(args.input)
    if args.json:
        print(json.dumps(report))
        return 0
    print(format_info(report))
    return 0


def warm_up_while_reading(args):
    """A thread that loads the compiled passes (numba and its cached code:
    about half a second once per process) while the input is read, which
    releases the GIL; only for volumes large enough to use them (a small
    one answers in the NumPy passes, without numba's start)."""
    from .mesh.formats.npy import voxel_count
    from .mesh.formats.registry import split_dataset
    from .mesh.load import is_mesh_path
    from .scale.compiled import have_numba, least_voxels

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
    import threading

    from .digital.closed_surfaces import warm_up

    def quietly():
        with contextlib.suppress(Exception):  # the command itself says what fails
            warm_up(surfaces=not args.no_surfaces)

    thread = threading.Thread(target=quietly, daemon=True)
    thread.start()
    return thread


def thread_count(text: str) -> int:
    """argparse type of ``--threads``: a positive integer."""
    from .scale.compiled import check_threads

    try:
        return check_threads(text, "N")
    except IsoflowError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def format_info(r: dict) -> str:
    lines = [
        f"{r['input']}: {r['dimension']}D, shape {'x'.join(map(str, r['shape']))}, "
        f"{r['voxels']} voxels, {r['connectivity']}-connectivity",
        f"  Euler characteristic   {r['euler_characteristic']}",
    ]
    names = {2: ["components", "holes"], 3: ["components", "tunnels", "cavities"],
             4: ["components", "b1", "b2", "enclosed background"]}[r["dimension"]]
    lines.append(
        "  Betti numbers          "
        + ", ".join(f"{'?' if b is None else b} {name}" for b, name in zip(r["betti"], names))
    )
    lines.append("  vertex classes (eq. 4.9):")
    for label, count in r["classes"].items():
        lines.append(f"    {label:<10} {count:>12}")
    lines.append(f"    {'not well-composed':<10} {r['non_well_composed']:>5}")
    scale = 1 << r["dimension"]
    lines.append(f"  a^T n                  {r['a_dot_n']}  (= {scale} chi)")
    lines.append(f"  energy E = k^T n       {r['energy']}")
    if r.get("surfaces"):
        lines.append(f"  closed surfaces        {len(r['surfaces'])}")
        for i, s in enumerate(r["surfaces"][:10]):
            lines.append(f"    #{i}: genus {s['genus']}, chi {s['euler_characteristic']}, {s['faces']} faces")
        if len(r["surfaces"]) > 10:
            lines.append(f"    ... {len(r['surfaces']) - 10} more")
    if r.get("surfaces", []) is None:  # 4D: the boundary is a 3-manifold, not a surface
        lines.append(f"  closed surfaces        not computed in {r['dimension']}D")
    if r.get("pinched_vertices"):
        lines.append(f"  pinched vertices       {r['pinched_vertices']} (split in the mesh, joined by the connectivity)")
    return "\n".join(lines)


def cmd_surface(args) -> int:
    from .digital.configurations import configuration_histogram
    from .digital.surface import boundary_faces, boundary_mesh, mesh_memory
    from .digital.topology import default_connectivity
    from .mesh import export
    from .mesh.outputs import check_output_path, check_picture_path
    from .mesh.readback import check_surface_file
    from .scale.memory import check_fits

    # both outputs checked before loading and before anything is written:
    # a bad --png must not leave the mesh behind
    out = check_output_path(args.output, args.force, suffixes=export.SURFACE_SUFFIXES, what="surface")
    suffix = out.suffix.lower()
    if args.ascii and suffix != ".ply":
        raise IsoflowError(f"{out}: --ascii applies to .ply output only")
    if args.png:
        check_picture_path(args.png, args.force)
    obj = load_input(args)
    if obj.ndim != 3:
        raise IsoflowError(f"{args.input}: surface needs a 3D object, this one is {obj.ndim}D")
    if obj.voxels == 0:
        raise IsoflowError(f"{args.input}: the object is empty, there is no surface to write")
    conn = args.connectivity or default_connectivity(3)
    hist = configuration_histogram(obj.volume)
    check_fits(
        mesh_memory(hist),
        f"{args.input}: the boundary mesh ({boundary_faces(hist):,} faces)",
        hint="crop or coarsen the volume",
    )
    mesh = boundary_mesh(obj.volume, conn)
    comments = (
        f"isoflow surface of {Path(args.input).name}, {conn}-connectivity",
        "per-vertex: config byte, class (gamma+4; -1 not well-composed; -2 edge midpoint), "
        "gamma (eighths, eq. 4.6), a (eq. 4.10), f (eq. 4.8)",
    )
    written = export.write_surface(out, mesh, obj, ascii=args.ascii, triangulate=args.triangulate,
                                   force=args.force, comments=comments)
    comps = mesh.components()
    print(
        f"{out}: {len(mesh.vertices)} vertices, {written['face_count']} faces ({written['faces']}), "
        f"{len(comps)} closed surfaces, V-E+F = {mesh.euler_characteristic}"
        + (f", {mesh.pinched} pinched vertices" if mesh.pinched else "")
    )
    welded = export.shared_positions(mesh) if suffix == ".stl" else 0
    if welded and not args.quiet:
        print(f"isoflow surface: note: {out}: STL keeps no shared vertices, so readers weld the split copies at "
              f"{welded} edge/vertex contacts into non-manifold points; PLY, OBJ or GLB keep them apart",
              file=sys.stderr)
    check = None if args.no_check else check_surface_file(out, mesh, obj, topology=not welded, components=comps)
    if check is not None and check.get("skipped") and not args.quiet:
        print(f"isoflow surface: note: {out}: not read back ({check['skipped']})", file=sys.stderr)
    elif check is not None and not check["agree"]:
        print(f"isoflow surface: error: {check['problem']}", file=sys.stderr)
        return 1
    elif check is not None:
        t = check["trimesh"]
        if welded:
            print(f"{out}: trimesh reads back volume {t['volume']:.6g} after its weld, as isoflow counts "
                  "(the welded contacts leave no manifold to compare)")
        else:
            print(f"{out}: trimesh reads it back watertight, V-E+F = {t['euler_number']}, genus {t['genus']}, "
                  f"volume {t['volume']:.6g}: as isoflow counts")
    if args.png:
        from .mesh.render import render_surface

        png = Path(args.png)
        render_surface(mesh, obj, png, title=Path(args.input).name)
        print(f"{png}: picture of the surface coloured by vertex angle")
    return 0


def cmd_voxelize(args) -> int:
    from .mesh.volumes import check_volume_output, write_volume

    if Path(args.output).suffix.lower() == ".zarr":
        # beyond memory: slab by slab into a chunked zarr array, as dask tasks
        from .mesh.slabs import voxelize_to_zarr

        report: dict = {}
        out = Path(args.output)
        with progress_bar(args, "voxelize") as show:
            z = voxelize_to_zarr(args.mesh, out, pitch=args.pitch, resolution=args.resolution, strict=args.strict,
                                 force=args.force, progress=show, report=report)
        say_note(args, args.mesh, report)
        shape = "x".join(map(str, z["shape"]))
        print(f"{out}: {z['voxels']} voxels in a {shape} zarr array (chunks {'x'.join(map(str, z['chunks']))}), "
              f"pitch {z['pitch']:.6g}, origin {np.round(z['origin'], 6).tolist()}")
        return 0
    check_volume_output(args.output, args.force)  # suffix, library and path before the voxelisation
    obj = voxelize_input(args.mesh, args)
    out = write_volume(obj, args.output, force=args.force)
    shape = "x".join(map(str, obj.volume.shape))
    print(f"{out}: {obj.voxels} voxels in a {shape} grid, pitch {obj.pitch:.6g}, origin {np.round(obj.origin, 6).tolist()}")
    return 0


def cmd_genus(args) -> int:
    from .mesh.genus import DEFAULT_RESOLUTIONS, verify_genus

    conn = args.connectivity or 6
    res = args.resolution or list(DEFAULT_RESOLUTIONS)
    for name in ("resolution", "max_resolution"):
        values = getattr(args, name)
        for r in values if isinstance(values, list) else [values]:
            if r is not None and r < 1:
                raise IsoflowError(f"--{name.replace('_', '-')} must be a positive integer, got {r}")
    if args.time_limit is not None and not args.time_limit > 0:
        raise IsoflowError(f"--time-limit must be a positive number of seconds, got {args.time_limit}")
    kw = {k: v for k, v in (("max_resolution", args.max_resolution), ("time_limit", args.time_limit)) if v is not None}
    with progress_bar(args, "genus") as show:

        def stepped(entry):  # the automatic stepping, one line per resolution on a terminal
            if show is not None:
                print(f"genus: resolution {entry['resolution']}: Betti numbers {tuple(entry['betti'])} "
                      f"({entry['seconds']:.1f} s)", file=sys.stderr)

        report = verify_genus(args.mesh, res, conn, progress=show, step=not args.no_step, on_resolution=stepped,
                              strict=args.strict, **kw)
    if args.json:
        print(json.dumps(report))
        return 0
    m, m3, pm = report["mesh"], report["manifold3d"], report["pymeshlab"]
    per = ", ".join("?" if g is None else str(g) for g in m["genus_per_component"][:12])
    solid = report["solid"]
    crossings = ("?" if report["self_intersecting_faces"] is None else
                 f"{report['self_intersecting_faces']} faces cross their own component, "
                 f"{report['faces_crossing_other_components']} cross another component")
    lines = [
        f"{args.mesh}: {m['vertices']} vertices, {m['faces']} faces",
        f"  mesh        watertight {m['watertight']}, {m['components']} components, V-E+F {m['euler_number']}, "
        f"genus {m['genus']} (per component: {per}{', ...' if len(m['genus_per_component']) > 12 else ''})",
        f"  crossings   {crossings} (pymeshlab)",
        "  manifold3d  " + (f"refused: {m3['error']}" if "error" in m3 else
                           f"genus {m3['genus']} over {m3['components']} components (genus() of the whole mesh: {m3['genus_whole_mesh']})"),
        "  solid       " + (f"genus {solid['genus']}, {solid['surfaces']} boundary surfaces, volume {solid['volume']:.6g} "
                            "(manifold3d's union of the components)" if "genus" in solid else f"none ({solid['error']})"),
        "  pymeshlab   " + (f"genus {pm.get('genus')}" + (f" ({pm['error']})" if "error" in pm else "")),
    ]
    for d in report["digital"]:
        b = d["betti"]
        lines.append(f"  digital {d['resolution']:>4}  {d['connectivity']}-conn solid: {b[0]} components, {b[1]} tunnels, "
                     f"{b[2]} cavities -> genus {d['genus']}")
    lines.append(f"  verdict     {report['verdict']}")
    print("\n".join(lines))
    return 0


#: the bar once the total is known: the share done and the time left (the
#: core's units, chunks of columns or layers of blocks, mean nothing to a user)
BAR_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| [{elapsed}<{remaining}]"


@contextlib.contextmanager
def progress_bar(args, label: str, unit: str = "it"):
    """A tqdm bar on stderr fed by a core ``progress(done, total)`` callback.

    Yields the callback, or None (no bar, and tqdm not imported) when
    ``--quiet`` is given or stderr is not a terminal, so that logs and pipes
    get no carriage returns. The bar appears at the first report (not while
    a mesh is still being read) and is cleared when the work ends, so the
    terminal keeps only the results. A ``total`` of None gives a counter
    (the flow, whose length is not known in advance).
    """
    if args.quiet or not sys.stderr.isatty():
        yield None
        return
    from tqdm import tqdm

    bars = []

    def show(done, total):
        if not bars:
            bars.append(tqdm(desc=label, total=total, initial=done, unit=unit, file=sys.stderr, leave=False,
                             dynamic_ncols=True, bar_format=None if total is None else BAR_FORMAT))
        if total != bars[0].total:  # genus: the stepping adds a resolution
            bars[0].total = total
        bars[0].update(done - bars[0].n)

    try:
        yield show
    finally:
        for bar in bars:
            bar.close()


def cmd_flow(args) -> int:
    from .flow.files import FlowWriter
    from .flow.motion import flow_connectivity
    from .flow.run import default_max_steps, run_flow

    if args.out:  # before any work (the FlowWriter checks it again when it makes the directory)
        from .flow.files import check_output_dir

        check_output_dir(args.out, args.force)
    obj = load_input(args)
    if obj.ndim not in (2, 3):
        raise IsoflowError(f"{args.input}: the digital curvature flow is defined for 2D and 3D objects, "
                           f"this one is {obj.ndim}D")
    if obj.voxels == 0:
        raise IsoflowError(f"{args.input}: the object is empty, there is nothing to flow")
    if args.steps is not None and args.steps < 0:
        raise IsoflowError(f"--steps must be 0 or more, got {args.steps}")
    # files are written while the flow runs, so no state is kept in memory
    # (every state of a box of side s would cost about s^4/4 bytes)
    writer = None
    if args.volumes is not None and not args.out:
        raise IsoflowError(f"--volumes {args.volumes} writes into the --out directory; give --out DIR")
    if args.volumes is not None:  # ("" too: refused, not ignored)
        from .mesh.volumes import check_volume_suffix

        args.volumes = check_volume_suffix(args.volumes)  # before the output directory is made
    if args.out:
        last = args.steps if args.steps is not None else default_max_steps(obj)
        conn = flow_connectivity(obj.ndim, args.connectivity)
        writer = FlowWriter(args.out, conn, args.force, last_step=last, check=not args.no_check)
        if args.volumes is not None:
            writer.write_volumes(args.volumes)
    with progress_bar(args, "flow", unit=" steps") as show:

        def progress(step, state):
            if writer is not None:
                writer.add(step, state)
            if show is not None:  # a counter unless --steps says how many
                show(step, args.steps)

        try:
            if writer is not None:
                writer.add(0, obj.cropped())
            result = run_flow(obj, steps=args.steps, guard=args.guard, connectivity=args.connectivity,
                              progress=progress, keep_states=False)
            if writer is not None:
                writer.finish(result)
        except BaseException:
            if writer is not None:  # the previous run's files stay as they were
                writer.abort()
            raise
    if args.json:
        print(json.dumps({"input": str(args.input), **result.to_dict()}))
    else:
        print(format_flow(result, str(args.input)))
        if args.out:
            print(f"{args.out}: surfaces (step_*.ply), flow.csv, flow.png (figures), shapes.png (3D: the object at a few steps)"
                  + (f", volumes (step_*{args.volumes})" if args.volumes is not None else ""))
    if writer is None:
        return 0
    read = [c for c in writer.checks.values() if not c.get("skipped")]
    skipped = [c["skipped"] for c in writer.checks.values() if c.get("skipped")]
    if read and not args.json:
        print(f"{args.out}: {len(read) - len(writer.problems)} of {len(read)} step surfaces "
              "read back by trimesh as isoflow counts them (flow.csv: trimesh_* columns)")
    if skipped and not args.quiet:
        print(f"isoflow flow: note: {len(skipped)} step files not read back ({skipped[0]})", file=sys.stderr)
    for line in writer.problems:
        print(f"isoflow flow: error: {line}", file=sys.stderr)
    return 1 if writer.problems else 0


def format_flow(result, name: str) -> str:
    lines = [
        f"{name}: digital curvature flow, {result.connectivity}-connectivity"
        + (", guard" if result.guard else ""),
        f"  {'step':>5} {'voxels':>10} {'parity':>6}  {'betti':<12} {'chi':>4} {'energy':>8}",
    ]
    for s in result.steps:
        lines.append(
            f"  {s['step']:>5} {s['voxels']:>10} {s['parity']:>6}  {str(tuple(s['betti'])):<12} "
            f"{s['euler_characteristic']:>4} {s['energy']:>8}"
        )
    lim = result.limit
    lines.append(f"  stopped: {result.stop_reason}")
    if lim["center"] is not None:
        centre = ", ".join(f"{c:g}" for c in lim["center"])
        lines.append(f"  limit: ({centre}), last non-empty state {lim['last_shape']} at step {lim['last_step']}")
    for c in result.topology_changes:
        lines.append(f"  topology change at step {c['step']}: {tuple(c['before'])} -> {tuple(c['after'])}, in {c['where']}")
    return "\n".join(lines)


# --------------------------------------------------------------------------


def installed_version() -> str:
    """The installed package's version (its metadata, as pip sees it)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("isoflow")
    except PackageNotFoundError:  # run from a source tree that was never installed
        return "(not installed: no package metadata; pip install -e .)"


class VersionAction(argparse.Action):
    """``--version``: the metadata is read only when asked, not at every start."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"isoflow {installed_version()}")
        parser.exit()


def cmd_completion(args) -> int:
    """Print a completion script made by shtab from this very parser."""
    try:
        import shtab
    except ImportError as exc:
        raise IsoflowError(f"shell completion needs shtab: pip install shtab ({exc})") from None
    parser = build_parser()
    # paths complete as files (or directories for --out); everything else
    # (commands, options, choices) shtab reads from the parser itself
    for command in parser.commands.values():
        for action in command._actions:
            if action.dest in ("input", "mesh", "output", "png"):
                action.complete = shtab.FILE
            elif action.dest == "out":
                action.complete = shtab.DIRECTORY
    print(shtab.complete(parser, shell=args.shell), end="")
    return 0


def command_list(parser: argparse.ArgumentParser) -> str:
    """What ``isoflow`` alone prints: usage and one line per command."""
    commands = parser.commands
    width = max(map(len, commands))
    lines = [parser.format_usage().rstrip(), "", parser.description, "", "commands:"]
    lines += [f"  {name:<{width}}  {p.description}" for name, p in commands.items()]
    lines += ["", "'isoflow COMMAND -h' lists a command's options; 'isoflow --version' prints the version."]
    return "\n".join(lines)


def add_command(sub, name: str, summary: str) -> argparse.ArgumentParser:
    """A sub-command whose one-line summary is both its entry in the command
    list and the description of its own -h."""
    return sub.add_parser(name, help=summary, description=summary)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="isoflow",
        description="Digital curvature, Euler characteristic, genus and curvature flow of voxel objects (Imiya 2013).",
    )
    parser.add_argument("--version", action=VersionAction, help="print the installed version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    parser.commands = sub.choices  # name -> sub-command parser, in order

    p = add_command(sub, "info", "topology and curvature-index histogram of an object")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-surfaces", action="store_true", help="skip the per-surface genus")
    p.add_argument("--threads", type=thread_count, metavar="N",
                   help="threads for the compiled passes (default: $ISOFLOW_THREADS, else every CPU)")
    p.add_argument(
        "--gpu",
        action="store_true",
        help="compute chi, Betti numbers and n on a CUDA GPU with CuPy (pip install 'isoflow[gpu]')",
    )
    p.set_defaults(func=cmd_info)

    p = add_command(sub, "surface", "write the boundary quad mesh (PLY/OBJ/STL/GLB) with curvature attributes")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("-o", "--output", required=True,
                   help="OUT.ply, OUT.obj, OUT.stl (binary, triangles) or OUT.glb (triangles, vertex colours)")
    p.add_argument("--ascii", action="store_true", help="ASCII PLY instead of binary")
    p.add_argument("--triangulate", action="store_true", help="triangles in every format (two per plain quad)")
    p.add_argument("--png", help="also write a picture of the surface coloured by vertex angle")
    p.add_argument("--no-check", action="store_true", help="do not read the written file back with trimesh")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.set_defaults(func=cmd_surface)

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

    p = add_command(sub, "genus", "verify a mesh's genus: mesh, manifold3d, pymeshlab and digital side by side")
    p.add_argument("mesh", help="a mesh file: any format trimesh reads")
    p.add_argument("--resolution", type=int, nargs="+",
                   help="voxels along the longest side, tried first (default: 64 128); then doubled until the "
                        "digital Betti numbers of the last two agree")
    p.add_argument("--max-resolution", type=int, help="stop doubling beyond this (default 1024)")
    p.add_argument("--time-limit", type=float, metavar="SECONDS",
                   help="stop doubling when the next resolution would end past this (default 60)")
    p.add_argument("--no-step", action="store_true", help="only the resolutions given, no doubling")
    add_mesh_rule(p)
    p.add_argument("--connectivity", type=int, choices=(6, 26), default=None, help="digital connectivity (default 6)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_genus)

    p = add_command(sub, "flow", "run the digital curvature flow (section 5) with topology control")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("--steps", type=int, help="number of steps (default: until the object vanishes)")
    p.add_argument("--guard", action="store_true", help="topology control (Theorem 21): every step by simple deformations, thinning where a step cannot be; ends at a thin fixed point")
    p.add_argument("--out", metavar="DIR", help="write step_NNN.ply surfaces, flow.csv, flow.png and shapes.png into DIR")
    p.add_argument("--volumes", metavar="SUFFIX",
                   help="also write every step's volume as step_NNN.SUFFIX into --out (.npz, .nii.gz, .tif, .h5, ...)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-check", action="store_true", help="do not read the step files back with trimesh")
    p.add_argument("--force", action="store_true", help="overwrite files in a non-empty --out directory")
    p.set_defaults(func=cmd_flow)

    p = add_command(sub, "completion", "print a shell completion script (bash, zsh, tcsh) made from these options")
    p.add_argument("shell", choices=("bash", "zsh", "tcsh"), help="the shell to complete in")
    p.set_defaults(func=cmd_completion)

    for p in parser.commands.values():
        p.add_argument("-q", "--quiet", action="store_true",
                       help="no progress bars or warnings on stderr (errors are still printed)")
    return parser


@contextlib.contextmanager
def quiet_stderr(quiet: bool):
    """--quiet: informational stderr (library warnings, log records below
    ERROR) is dropped while the command runs; errors still reach stderr as
    one line. Restored afterwards, for callers of :func:`main` in-process."""
    if not quiet:
        yield
        return
    import logging
    import warnings

    before = logging.root.manager.disable
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        logging.disable(logging.WARNING)
        try:
            yield
        finally:
            logging.disable(before)


@contextlib.contextmanager
def termination_as_interrupt(received: list):
    """Treat SIGTERM (``kill``, a batch system's time limit, a closing
    terminal's SIGHUP) as Ctrl-C while a command runs: the same clean-up
    runs (temporary files and the flow's staging directory are removed, an
    existing output stays as it was) and the signal's number is appended
    to ``received``. Python's default for SIGTERM is to die at once, which
    leaves the temporary files behind. Only the main thread may set
    handlers; elsewhere (a command run from a library thread) nothing
    changes."""
    import signal
    import threading

    wanted = [signal.SIGINT, signal.SIGTERM] + ([signal.SIGHUP] if hasattr(signal, "SIGHUP") else [])
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        # kept as well as raised: a library may swallow the KeyboardInterrupt
        # (trimesh's import guards), and no output is then renamed into place
        # (isoflow.mesh.outputs.SIGNALS) and the command still ends as
        # interrupted
        received.append(signum)
        raise KeyboardInterrupt

    before = {sig: signal.signal(sig, interrupt) for sig in wanted}
    try:
        yield
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)


def main(argv: list[str] | None = None) -> int:
    import warnings

    from .errors import IsoflowWarning

    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:  # `isoflow` alone: what it can do, not an error
        print(command_list(parser))
        return 0

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, IsoflowWarning):  # one line, without the source line
            print(f"isoflow {args.command}: warning: {message}", file=sys.stderr)
        else:
            shown(message, category, filename, lineno, file, line)

    import signal

    from .mesh.outputs import SIGNALS
    from .scale import compiled

    terminated = SIGNALS  # the signals received (what the writers look at before renaming)
    terminated.clear()

    def compiling(message):  # numba's first run after installing: a note, not silence
        print(f"isoflow {args.command}: note: {message}", file=sys.stderr, flush=True)

    before = compiled.on_first_compile
    compiled.on_first_compile = None if args.quiet else compiling
    try:
        with quiet_stderr(args.quiet), warnings.catch_warnings(), termination_as_interrupt(terminated):
            shown = warnings.showwarning
            if not args.quiet:
                warnings.simplefilter("always", IsoflowWarning)
                warnings.showwarning = show
            status = args.func(args)
            if terminated:  # a signal a library swallowed: the command still ends as interrupted
                raise KeyboardInterrupt
            return status
    except IsoflowError as exc:
        print(f"isoflow {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except MemoryError:
        name = getattr(args, "input", None) or getattr(args, "mesh", "")
        print(f"isoflow {args.command}: error: out of memory on {name}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:  # a write names its file (mesh.outputs)
        sig = terminated[0] if terminated else signal.SIGINT
        how = "interrupted" if sig == signal.SIGINT else "terminated"
        print(f"isoflow: {how}" + (f": {exc}" if str(exc) else ""), file=sys.stderr)
        # the shell's convention: 128 + the signal's number
        return 128 + int(sig)
    except BrokenPipeError:  # `isoflow info ... | head`: not an error
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    finally:
        compiled.on_first_compile = before
        terminated.clear()  # said: later writes in this process (a library's caller) are not held back


def console() -> None:
    """The ``isoflow`` command: :func:`main`, then exit without the
    interpreter's last garbage collection, which walks every object (numba's
    many, once it is loaded: 0.2 s) only to find nothing to collect."""
    import gc

    code = main()
    gc.freeze()
    sys.exit(code)


if __name__ == "__main__":
    console()
