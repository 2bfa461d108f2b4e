"""``isoflow surface``: the boundary quad mesh written as a file, read back."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import IsoflowError
from .inputs import add_connectivity, add_input_arguments, load_input
from .labels import add_labels_option


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "surface", "write the boundary quad mesh (PLY/OBJ/STL/GLB) with curvature attributes")
    add_input_arguments(p)
    add_connectivity(p)
    p.add_argument("-o", "--output", required=True,
                   help="OUT.ply, OUT.obj, OUT.stl (binary, triangles) or OUT.glb (triangles, vertex colours); "
                        "with --labels OUT.glb (a node per label) or DIR/ (a file per label, see --suffix)")
    add_labels_option(p)
    p.add_argument("--suffix", help="with --labels -o DIR/: the files' format, .ply, .obj, .stl or .glb")
    p.add_argument("--ascii", action="store_true", help="ASCII PLY instead of binary")
    p.add_argument("--triangulate", action="store_true", help="triangles in every format (two per plain quad)")
    p.add_argument("--png", help="also write a picture of the surface coloured by vertex angle")
    p.add_argument("--no-check", action="store_true", help="do not read the written file back with trimesh")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.set_defaults(func=cmd_surface)


def cmd_surface(args: argparse.Namespace) -> int:
    from ..digital.topology import default_connectivity
    from ..mesh import export
    from ..mesh.outputs import check_output_path, check_picture_path

    if args.labels is not None:
        from .labels import cmd_surface_labels

        return cmd_surface_labels(args)
    if args.suffix:
        raise IsoflowError(f"{args.output}: --suffix names the files of --labels -o DIR/")
    # both outputs checked before loading and before anything is written:
    # a bad --png must not leave the mesh behind
    out = check_output_path(args.output, args.force, suffixes=export.SURFACE_SUFFIXES, what="surface")
    if args.ascii and out.suffix.lower() != ".ply":
        raise IsoflowError(f"{out}: --ascii applies to .ply output only")
    if args.png:
        check_picture_path(args.png, args.force)
    obj = load_input(args)
    if obj.ndim != 3:
        raise IsoflowError(f"{args.input}: surface needs a 3D object, this one is {obj.ndim}D")
    if obj.voxels == 0:
        raise IsoflowError(f"{args.input}: the object is empty, there is no surface to write")
    conn = args.connectivity or default_connectivity(3)
    mesh = checked_mesh(args.input, obj, conn)
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
    status = read_back(args, out, mesh, obj, comps)
    if status == 0 and args.png:
        from ..mesh.render import render_surface

        png = Path(args.png)
        render_surface(mesh, obj, png, title=Path(args.input).name)
        print(f"{png}: picture of the surface coloured by vertex angle")
    return status


def checked_mesh(name: str, obj, conn: int):
    """The boundary mesh, refused up front when it would not fit in memory."""
    from ..digital.configurations import configuration_histogram
    from ..digital.surface import boundary_faces, boundary_mesh, mesh_memory
    from ..scale.memory import check_fits

    hist = configuration_histogram(obj.volume)
    check_fits(
        mesh_memory(hist),
        f"{name}: the boundary mesh ({boundary_faces(hist):,} faces)",
        hint="crop or coarsen the volume",
    )
    return boundary_mesh(obj.volume, conn)


def read_back(args: argparse.Namespace, out: Path, mesh, obj, comps) -> int:
    """The written file read back by trimesh and compared, in words; 1 when
    it does not agree with isoflow's counts."""
    from ..mesh import export
    from ..mesh.readback import check_surface_file

    welded = export.shared_positions(mesh) if out.suffix.lower() == ".stl" else 0
    if welded and not args.quiet:
        print(f"isoflow surface: note: {out}: STL keeps no shared vertices, so readers weld the split copies at "
              f"{welded} edge/vertex contacts into non-manifold points; PLY, OBJ or GLB keep them apart",
              file=sys.stderr)
    if args.no_check:
        return 0
    check = check_surface_file(out, mesh, obj, topology=not welded, components=comps)
    if check.get("skipped"):
        if not args.quiet:
            print(f"isoflow surface: note: {out}: not read back ({check['skipped']})", file=sys.stderr)
        return 0
    if not check["agree"]:
        print(f"isoflow surface: error: {check['problem']}", file=sys.stderr)
        return 1
    t = check["trimesh"]
    if welded:
        print(f"{out}: trimesh reads back volume {t['volume']:.6g} after its weld, as isoflow counts "
              "(the welded contacts leave no manifold to compare)")
    else:
        print(f"{out}: trimesh reads it back watertight, V-E+F = {t['euler_number']}, genus {t['genus']}, "
              f"volume {t['volume']:.6g}: as isoflow counts")
    return 0
