"""The ``isoflow`` command line: argument parsing and messages only.

Every command reads its input through :func:`load_input`, hands arrays to the
core, and prints either a readable table or one JSON object. Bad input
becomes one line on stderr and exit status 2; heavy libraries (trimesh,
matplotlib) are imported only by the commands that need them, so that
``isoflow info`` starts fast.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from .errors import IsoflowError


# --------------------------------------------------------------------------
# input
# --------------------------------------------------------------------------


def add_input_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", help="volume (.npy/.npz), point list (.txt: x y z per line) or mesh (any format trimesh reads)")
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
                   help="refuse a mesh that is not watertight (by default it is read by the generalised winding number)")
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


def voxelize_input(path, args):
    """A mesh file voxelised by the one mesh reader of every command; what
    is unusual about the mesh is said in one line on stderr."""
    from .mesh.voxelize import voxelize_file

    report: dict = {}
    obj = voxelize_file(path, pitch=args.pitch, resolution=args.resolution, strict=args.strict,
                        progress=progress_callback("voxelize"), report=report)
    if report.get("note"):
        print(f"isoflow {args.command}: note: {path}: {report['note']}", file=sys.stderr)
    return obj


def load_input(args):
    """The digital object named on the command line (volume, points or mesh)."""
    from .mesh.load import is_mesh_path
    from .mesh.volumes import read_object

    path = Path(args.input)
    if is_mesh_path(path):
        return voxelize_input(path, args)
    if args.pitch is not None or args.resolution is not None or args.allow_open or args.strict:
        raise IsoflowError(
            f"{path}: --pitch/--resolution/--strict/--allow-open apply to meshes, not to {path.suffix or 'this'} input")
    if path.suffix.lower() == ".zarr":  # would otherwise be read as a point list
        raise IsoflowError(f"{path}: only 'isoflow info' reads .zarr (block by block); save the volume as .npy or .npz")
    return read_object(path, points_are=args.points_are)


# --------------------------------------------------------------------------
# commands
# --------------------------------------------------------------------------


def cmd_info(args) -> int:
    from .digital.analysis import analyze

    if Path(args.input).suffix.lower() == ".zarr":
        # out of core: block by block, never the whole volume in memory; the
        # closed surfaces need the whole boundary mesh and are not computed
        from .digital.outofcore import analyze_zarr

        if args.pitch is not None or args.resolution is not None or args.allow_open or args.strict:
            raise IsoflowError(f"{args.input}: --pitch/--resolution/--strict/--allow-open apply to meshes, not to .zarr input")
        if args.gpu:
            raise IsoflowError(f"{args.input}: --gpu takes volumes that fit in memory; .zarr is read block by block on the host")
        report = analyze_zarr(args.input, args.connectivity)
        if report["dimension"] == 3:
            report["surfaces"] = None
    else:
        obj = load_input(args)
        if args.gpu:
            from .scale.arrays import to_gpu

            report = analyze(to_gpu(obj.volume), args.connectivity, surfaces=not args.no_surfaces)
            report["parity"] = obj.parity  # a bare array has no lattice place
        else:
            report = analyze(obj, args.connectivity, surfaces=not args.no_surfaces)
    report["input"] = str(args.input)
    if args.json:
        print(json.dumps(report))
        return 0
    print(format_info(report))
    return 0


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
    if r.get("surfaces", []) is None:
        why = r.get("surfaces_skipped", "out-of-core input")
        lines.append(f"  closed surfaces        not computed ({why})")
    if r.get("pinched_vertices"):
        lines.append(f"  pinched vertices       {r['pinched_vertices']} (split in the mesh, joined by the connectivity)")
    return "\n".join(lines)


def cmd_surface(args) -> int:
    from .digital.configurations import configuration_histogram
    from .digital.surface import boundary_faces, boundary_mesh, mesh_memory
    from .digital.topology import default_connectivity
    from .mesh import export
    from .mesh.outputs import check_output_path, check_picture_path
    from .scale.memory import check_fits

    # both outputs checked before loading and before anything is written:
    # a bad --png must not leave the mesh behind
    out = check_output_path(args.output, args.force, suffixes=(".ply", ".obj"))
    if args.png:
        check_picture_path(args.png, args.force)
    suffix = out.suffix.lower()
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
    faces = mesh.triangles() if args.triangulate else mesh.polygons()
    if suffix == ".ply":
        export.write_ply(out, export.mesh_vertex_table(mesh, obj), faces, ascii=args.ascii, force=args.force, comments=comments)
    else:
        export.write_obj(out, obj.world(mesh.vertices), faces, force=args.force, comments=comments)
    chi = mesh.euler_characteristic
    print(
        f"{out}: {len(mesh.vertices)} vertices, {len(faces)} faces, "
        f"{len(mesh.components())} closed surfaces, V-E+F = {chi}"
        + (f", {mesh.pinched} pinched vertices" if mesh.pinched else "")
    )
    if args.png:
        from .mesh.render import render_surface

        png = Path(args.png)
        render_surface(mesh, obj, png, title=Path(args.input).name)
        print(f"{png}: picture of the surface coloured by vertex angle")
    return 0


def cmd_voxelize(args) -> int:
    from .mesh.outputs import check_output_path
    from .mesh.volumes import write_volume

    if Path(args.output).suffix.lower() == ".zarr":
        from .mesh.slabs import voxelize_to_zarr

        report: dict = {}
        out = Path(args.output)
        z = voxelize_to_zarr(args.mesh, out, pitch=args.pitch, resolution=args.resolution, strict=args.strict,
                             force=args.force, progress=progress_callback("voxelize"), report=report)
        if report.get("note"):
            print(f"isoflow voxelize: note: {args.mesh}: {report['note']}", file=sys.stderr)
        shape = "x".join(map(str, z["shape"]))
        print(f"{out}: {z['voxels']} voxels in a {shape} zarr array (chunks {'x'.join(map(str, z['chunks']))}), "
              f"pitch {z['pitch']:.6g}, origin {np.round(z['origin'], 6).tolist()}")
        return 0
    out = check_output_path(args.output, args.force, suffixes=(".npz", ".zarr"))  # before the voxelisation
    obj = voxelize_input(args.mesh, args)
    write_volume(obj, out, force=args.force)
    shape = "x".join(map(str, obj.volume.shape))
    print(f"{out}: {obj.voxels} voxels in a {shape} grid, pitch {obj.pitch:.6g}, origin {np.round(obj.origin, 6).tolist()}")
    return 0


def cmd_genus(args) -> int:
    from .mesh.genus import DEFAULT_RESOLUTIONS, verify_genus

    conn = args.connectivity or 6
    res = args.resolution or list(DEFAULT_RESOLUTIONS)
    report = verify_genus(args.mesh, res, conn, progress=progress_callback("voxelize"), strict=args.strict)
    if args.json:
        print(json.dumps(report))
        return 0
    m, m3, pm = report["mesh"], report["manifold3d"], report["pymeshlab"]
    per = ", ".join("?" if g is None else str(g) for g in m["genus_per_component"][:12])
    lines = [
        f"{args.mesh}: {m['vertices']} vertices, {m['faces']} faces",
        f"  mesh        watertight {m['watertight']}, {m['components']} components, V-E+F {m['euler_number']}, "
        f"genus {m['genus']} (per component: {per}{', ...' if len(m['genus_per_component']) > 12 else ''})",
        "  manifold3d  " + (f"refused: {m3['error']}" if "error" in m3 else
                           f"genus {m3['genus']} over {m3['components']} components (genus() of the whole mesh: {m3['genus_whole_mesh']})"),
        "  pymeshlab   " + (f"genus {pm.get('genus')}" + (f" ({pm['error']})" if "error" in pm else "")),
    ]
    for d in report["digital"]:
        b = d["betti"]
        lines.append(f"  digital {d['resolution']:>4}  {d['connectivity']}-conn solid: {b[0]} components, {b[1]} tunnels, "
                     f"{b[2]} cavities -> genus {d['genus']}")
    lines.append(f"  verdict     {report['verdict']}")
    print("\n".join(lines))
    return 0


def progress_callback(label: str):
    """A one-line progress display on a terminal, nothing otherwise."""
    if not sys.stderr.isatty():
        return None

    def show(done, total):
        frac = done / total if total else 1.0
        bar = "#" * int(30 * frac)
        end = "\n" if done >= total else ""
        print(f"\r{label} [{bar:<30}] {100 * frac:5.1f}%", end=end, file=sys.stderr, flush=True)

    return show


def cmd_flow(args) -> int:
    import time

    from .flow.files import FlowWriter
    from .flow.motion import flow_connectivity
    from .flow.run import default_max_steps, run_flow

    obj = load_input(args)
    if obj.voxels == 0:
        raise IsoflowError(f"{args.input}: the object is empty, there is nothing to flow")
    if args.steps is not None and args.steps < 0:
        raise IsoflowError(f"--steps must be 0 or more, got {args.steps}")
    # files are written while the flow runs, so no state is kept in memory
    # (every state of a box of side s would cost about s^4/4 bytes)
    writer = None
    if args.out:
        last = args.steps if args.steps is not None else default_max_steps(obj)
        conn = flow_connectivity(obj.ndim, args.connectivity)
        writer = FlowWriter(args.out, conn, args.force, last_step=last)
        writer.add(0, obj.cropped())
    # a box of side s vanishes in s steps; the bar appears once the run lasts
    total, show, start = args.steps or max(obj.volume.shape), progress_callback("flow"), time.monotonic()
    drawn = []

    def progress(step, state):
        if writer is not None:
            writer.add(step, state)
        if show and time.monotonic() - start > 1.0:
            show(min(step, total - 1), total)
            drawn.append(step)

    result = run_flow(obj, steps=args.steps, guard=args.guard, connectivity=args.connectivity,
                      progress=progress, keep_states=False)
    if drawn:
        show(total, total)
    if writer is not None:
        writer.finish(result)
    if args.json:
        print(json.dumps({"input": str(args.input), **result.to_dict()}))
        return 0
    print(format_flow(result, str(args.input)))
    if args.out:
        print(f"{args.out}: surfaces (step_*.ply), flow.csv, flow.png (figures), shapes.png (3D: the object at a few steps)")
    return 0


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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="isoflow",
        description="Digital curvature, Euler characteristic, genus and curvature flow of voxel objects (Imiya 2013).",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("info", help="topology and curvature-index histogram of an object")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-surfaces", action="store_true", help="skip the per-surface genus (faster on huge volumes)")
    p.add_argument(
        "--gpu",
        action="store_true",
        help="compute chi, Betti numbers and n on a CUDA GPU with CuPy (pip install 'isoflow[gpu]')",
    )
    p.set_defaults(func=cmd_info)

    p = sub.add_parser("surface", help="write the boundary quad mesh (PLY/OBJ) with curvature attributes")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("-o", "--output", required=True, help="OUT.ply or OUT.obj")
    p.add_argument("--ascii", action="store_true", help="ASCII PLY instead of binary")
    p.add_argument("--triangulate", action="store_true", help="two triangles per quad")
    p.add_argument("--png", help="also write a picture of the surface coloured by vertex angle")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.set_defaults(func=cmd_surface)

    p = sub.add_parser("voxelize", help="voxelise a mesh's solid into an .npz volume or a .zarr store (with pitch and origin)")
    p.add_argument("mesh", help="a mesh file: any format trimesh reads (STL, OBJ, PLY, OFF, GLB, 3MF, DAE, ZIP, ...)")
    grid = p.add_mutually_exclusive_group(required=True)
    grid.add_argument("--pitch", type=float, help="voxel size in mesh units")
    grid.add_argument("--resolution", type=int, help="voxels along the longest side")
    p.add_argument("-o", "--output", required=True,
                   help="OUT.npz, or OUT.zarr: written slab by slab as dask tasks, never held in memory")
    add_mesh_rule(p)
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.set_defaults(func=cmd_voxelize)

    p = sub.add_parser("genus", help="verify a mesh's genus: mesh, manifold3d, pymeshlab and digital side by side")
    p.add_argument("mesh", help="a mesh file: any format trimesh reads")
    p.add_argument("--resolution", type=int, nargs="+", help="voxels along the longest side (default: 64 128)")
    add_mesh_rule(p)
    p.add_argument("--connectivity", type=int, choices=(6, 26), default=None, help="digital connectivity (default 6)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_genus)

    p = sub.add_parser("flow", help="run the digital curvature flow (section 5) with topology control")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("--steps", type=int, help="number of steps (default: until the object vanishes)")
    p.add_argument("--guard", action="store_true", help="refuse steps that change the Betti numbers (Theorem 21)")
    p.add_argument("--out", metavar="DIR", help="write step_NNN.ply surfaces, flow.csv, flow.png and shapes.png into DIR")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--force", action="store_true", help="overwrite files in a non-empty --out directory")
    p.set_defaults(func=cmd_flow)

    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except IsoflowError as exc:
        print(f"isoflow {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except MemoryError:
        name = getattr(args, "input", None) or getattr(args, "mesh", "")
        print(f"isoflow {args.command}: error: out of memory on {name}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("isoflow: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `isoflow info ... | head`: not an error
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0


if __name__ == "__main__":
    sys.exit(main())
