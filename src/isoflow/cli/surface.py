"""``isoflow surface``: the boundary quad mesh written as a file, read back."""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
from pathlib import Path

import numpy as np

from ..errors import IsoflowError, counted, terminal_text
from .inputs import (
    add_connectivity,
    add_input_arguments,
    label_options,
    load_input,
    one_time_point,
    refuse_mesh_options,
    refuse_points_option,
    refuse_time_series_store,
    thread_count,
    why_empty,
)
from .labels import add_labels_option, in_hdf5_slabs, refuse_names_without_labels


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "surface", "write the boundary quad mesh (PLY/OBJ/STL/GLB) with curvature attributes")
    add_input_arguments(p)
    add_connectivity(p, dims=(3,))
    p.add_argument("-o", "--output", required=True,
                   help="OUT.ply, OUT.obj, OUT.stl (binary, triangles) or OUT.glb (triangles, vertex colours); "
                        "with --labels OUT.glb (a node per label) or DIR/ (a file per label, see --suffix)")
    add_labels_option(p)
    p.add_argument("--suffix", help="with --labels -o DIR/: the files' format, .ply, .obj, .stl or .glb")
    p.add_argument("--ascii", action="store_true", help="ASCII PLY instead of binary")
    p.add_argument("--triangulate", action="store_true", help="triangles in every format (two per plain quad)")
    p.add_argument("--png", help="also write a picture of the surface coloured by vertex angle")
    p.add_argument("--no-check", action="store_true",
                   help="do not read the written file back (with trimesh; in chunks for a .zarr store)")
    p.add_argument("--force", action="store_true",
                   help="overwrite existing output files; with --labels -o DIR/, a choice of labels replaces those "
                        "labels' files alone, every label makes the directory hold this run's files alone")
    p.add_argument("--threads", type=thread_count, metavar="N",
                   help="threads for the compiled passes; for a .zarr store read block by block, the blocks meshed "
                        "at a time (default: $ISOFLOW_THREADS, else every CPU)")
    p.set_defaults(func=cmd_surface)


def cmd_surface(args: argparse.Namespace) -> int:
    """``isoflow surface``, its compiled passes on ``--threads`` threads
    (a store's blocks take them as the blocks meshed at a time)."""
    from ..scale.compiled import using

    with using(args.threads):
        return surface_of(args)


def surface_of(args: argparse.Namespace) -> int:
    """``isoflow surface`` of a file, a store or a label image."""
    from ..digital.connectivity import default_connectivity
    from ..mesh import export
    from ..mesh.outputs import check_output_path, check_picture_path, output_set
    from .progress import reading_back

    refuse_names_without_labels(args)
    if args.labels is not None:
        from .labels import cmd_surface_labels

        return cmd_surface_labels(args)
    if args.suffix:
        raise IsoflowError(f"{args.output}: --suffix names the files of --labels -o DIR/")
    # a time series refused as in memory, however large (is_store takes 3D stores only)
    refuse_time_series_store(args, "surface needs a 3D object")
    if is_store(args.input, args.label):
        if streams(args):
            return cmd_surface_store(args)
        refuse_store_beyond_memory(args)
    elif streams(args) and in_hdf5_slabs(args.input):  # (one that is not streamed is refused as read whole)
        return cmd_surface_store(args)
    # both outputs checked before loading and before anything is written:
    # a bad --png must not leave the mesh behind
    out = check_output_path(args.output, args.force, suffixes=export.SURFACE_SUFFIXES, what="surface")
    if args.ascii and out.suffix.lower() != ".ply":
        raise IsoflowError(f"{out}: --ascii applies to .ply output only")
    if args.png:
        check_picture_path(args.png, args.force)
    obj = load_input(args)
    if obj.ndim != 3:
        hint = one_time_point(args.input, obj.volume.shape, args.label) if obj.ndim == 4 else ""
        raise IsoflowError(f"{args.input}: surface needs a 3D object, this one is {obj.ndim}D{hint}")
    if obj.voxels == 0:
        why = why_empty(args, obj)  # a point list with points: say why none is in
        raise IsoflowError(f"{args.input}: the object is empty"
                           + (f": {why}" if why else ", there is no surface to write"))
    # a placement no file holds: refused before any work
    corners = export.check_float64_corners(args.input, obj.origin, obj.spacing, obj.volume.shape)
    conn = args.connectivity or default_connectivity(3)
    mesh = checked_mesh(args.input, obj, conn, out.suffix, ascii=args.ascii, picture=bool(args.png))
    comments = surface_comments(args.input, conn)
    # the mesh and its picture replaced together: a failure or a signal between them leaves both as they were,
    # and an interrupt's line names both. The mesh's lines on stdout are held until both are in place: a
    # picture that cannot be written leaves no mesh, and no line may have said it was written and read back
    held = io.StringIO()
    with output_set(f"{out} and {args.png}") if args.png else contextlib.nullcontext():
        written = export.write_mesh_file(out, mesh, obj, ascii=args.ascii, triangulate=args.triangulate,
                                       force=args.force, comments=comments, name=input_stem(args.input))
        # alone, the file is in place from here: an interrupt before or during
        # its check says so (in a set with the picture, nothing is replaced)
        with contextlib.nullcontext() if args.png else reading_back(out, check=not args.no_check), \
                contextlib.redirect_stdout(held) if args.png else contextlib.nullcontext():
            status = report_written(args, out, mesh, obj, written, corners)
        if args.png:  # drawn from isoflow's mesh, so also where the file reads back otherwise: the set stays whole
            from ..mesh.render import render_surface

            render_surface(mesh, obj, Path(args.png), title=Path(args.input).name)
    if args.png:
        sys.stdout.write(held.getvalue())
        print(terminal_text(f"{args.png}: picture of the surface coloured by vertex angle"))
    return status


def report_written(args: argparse.Namespace, out: Path, mesh, obj, written: dict, corners: dict) -> int:
    """The lines on a surface written from memory, and its read-back (the
    status of :func:`read_back`)."""
    from ..mesh import export

    comps = mesh.components()
    print(
        terminal_text(f"{out}: {len(mesh.vertices)} vertices, {written['face_count']} faces ({written['faces']}), "
                      f"{counted(len(comps), 'closed surface')}, V-E+F = {mesh.euler_characteristic}"
                      + (f", {pinched_words(mesh.pinched)})" if mesh.pinched else ""))
    )
    if written.get("moved_voxels", 0) > export.STL_NOTE_VOXELS:  # the file's surface is not the one asked for
        print(terminal_text(f"isoflow surface: warning: {export.stl_move_note(out, written)}"), file=sys.stderr)
    moved = export.float64_move_note(out, corners)
    if moved:  # nor where float64 itself moves the corners
        print(terminal_text(f"isoflow surface: warning: {moved}"), file=sys.stderr)
    if written.get("framed") and not args.quiet:  # MeshLab reads such a GLB in voxel units
        note = export.glb_transform_note(out, beyond=written["beyond"])
        print(terminal_text(f"isoflow surface: note: {note}"), file=sys.stderr)
    return read_back(args, out, mesh, obj, comps)


def input_stem(name: str) -> str:
    """The input's file name less its volume or mesh suffix (``scan`` of
    ``scan.nii.gz``, of ``scan.h5:/seg`` and of ``scan.ply``), which names
    a GLB's node as ``--labels`` names them ``label_N``."""
    from ..mesh.formats.registry import split_dataset, volume_suffixes

    file = split_dataset(name)[0].name
    known = [s for s in volume_suffixes() if file.lower().endswith(s) and len(s) < len(file)]
    return file[:-len(max(known, key=len))] if known else Path(file).stem or file


def checked_mesh(name: str, obj, conn: int, suffix: str = ".ply", *, ascii: bool = False, picture: bool = False):
    """The boundary mesh, refused up front when it would not fit in memory
    with the file of ``suffix`` (``ascii``: an ASCII PLY) and, with
    ``picture``, its picture (drawn holding the mesh)."""
    from ..digital.configurations import configuration_histogram
    from ..digital.surface import boundary_faces, boundary_mesh, mesh_memory, mesh_method
    from ..mesh.export import write_memory
    from ..mesh.render import PICTURE_BYTES
    from ..scale.memory import check_fits

    hist = configuration_histogram(obj.volume)
    faces = boundary_faces(hist)
    check_fits(
        mesh_memory(hist, mesh_method(obj.volume))  # the way boundary_mesh below takes
        + write_memory(faces, suffix, ascii=ascii) + (PICTURE_BYTES if picture else 0),
        f"{name}: the boundary mesh ({faces:,} faces)" + (" and its picture" if picture else ""),
        hint="crop or coarsen the volume",
    )
    return boundary_mesh(obj.volume, conn)


def read_back(args: argparse.Namespace, out: Path, mesh, obj, comps) -> int:
    """The written file read back by trimesh and compared, in words; 1 when
    it does not agree with isoflow's counts."""
    from ..mesh import export
    from ..mesh.readback import agreed_volume_words, check_surface_file
    from .progress import reading_back

    shared = export.shared_positions(mesh)
    welded = shared if out.suffix.lower() == ".stl" else 0
    if welded:  # readers see other topology than the one written: said under --quiet too
        print(terminal_text(f"isoflow surface: warning: {export.stl_weld_note(out, welded)}"), file=sys.stderr)
    if args.no_check:
        return 0
    with reading_back(out):
        check = check_surface_file(out, mesh, obj, topology=not welded, components=comps)
    if check.get("skipped"):
        if not args.quiet:
            print(terminal_text(f"isoflow surface: note: {out}: not read back ({check['skipped']})"), file=sys.stderr)
        return 0
    if not check["agree"]:
        print(terminal_text(f"isoflow surface: error: {check['problem']}"), file=sys.stderr)
        return 1
    t = check["trimesh"]
    volume = agreed_volume_words(t["volume_units"], obj.voxels, obj.spacing)
    if welded:
        print(terminal_text(f"{out}: trimesh reads back volume {volume} after its weld, as isoflow counts "
                            "(the welded contacts leave no manifold to compare)"))
    else:
        # trimesh.load merges equal positions by default, which joins the
        # split copies into non-manifold points: say how it was read
        how = (f" with process=False (its default merge joins the split copies at {shared} edge/vertex contacts "
               "into non-manifold points)" if shared else "")
        print(terminal_text(f"{out}: trimesh reads it back watertight{how}, V-E+F = {t['euler_number']}, genus {t['genus']}, "
                            f"volume {volume}: as isoflow counts"))
    return 0


def is_store(name: str, label: float | None = None) -> bool:
    """A 3D zarr store: its surface is written block by block (with a
    ``label``, a plain array of shape (X, Y, Z, 1) is a 3D label image)."""
    from ..mesh.formats.omezarr import stored_ndim
    from ..mesh.formats.registry import split_dataset

    return split_dataset(name)[0].suffix.lower() == ".zarr" and stored_ndim(name, label is not None) == 3


def cmd_surface_store(args: argparse.Namespace) -> int:
    """``surface STORE.zarr -o OUT.(ply|stl)``: the mesh written block by
    block, then read back in chunks; of an HDF5 volume too large to read
    whole likewise (:class:`~isoflow.mesh.formats.hdf5.LabelSlabs`)."""
    from ..digital.connectivity import default_connectivity
    from ..digital.lattice import DigitalObject
    from ..mesh.export import check_float64_corners
    from ..mesh.formats import hdf5
    from ..mesh.formats.omezarr import label_absent, one_value_of_store, open_store, store_volume
    from ..mesh.surface_blocks import EmptySurface, write_surface_blocks
    from ..scale.arrays import NotBinary
    from .progress import progress_bar, reading_back

    dataset = None if is_store(args.input, args.label) else hdf5.LabelSlabs(args.input)
    refuse_mesh_options(args, ".zarr" if dataset is None else "HDF5")
    refuse_points_option(args, "volume")
    if dataset is None:
        array, pitch, origin = store_volume(args.input, args.label)
        frame = DigitalObject.placement(3, pitch=pitch, origin=origin)
    else:  # placed by its offset and parity too, as read places it
        array, frame = dataset.reader(args.label), dataset.place
    # a placement no file holds: refused before any block
    corners = check_float64_corners(args.input, frame.origin, frame.spacing, array.shape)
    conn = args.connectivity or default_connectivity(3)

    def write(array):
        return write_surface_blocks(array, args.output, conn, frame=frame, threads=args.threads, progress=show,
                                    force=args.force, where=args.input, triangulate=args.triangulate,
                                    comments=surface_comments(args.input, conn))

    with progress_bar(args, "blocks") as show, label_options(args):
        try:
            try:
                written = write(array)
            except NotBinary as refused:
                # a store of 0 and one other value is that value's mask, as read_volume reads it
                value = None if args.label is not None else one_value_of_store(
                    open_store(args.input) if dataset is None else dataset, refused)
                if value is None:
                    raise
                array = store_volume(args.input, value)[0] if dataset is None else dataset.reader(value)
                written = write(array)
        except EmptySurface:
            if args.label is None:
                raise
            # the label's voxels are none: say that no voxel has it and what
            # the store holds (as in memory), not "the object is empty"
            raise (label_absent(args.input, args.label) if dataset is None else dataset.absent(args.label)) from None
    out = written["path"]
    # the file is in place from here: an interrupt before or during its check says so
    with reading_back(out, check=not args.no_check):
        return report_store_written(args, array, frame, written, corners, zarr=dataset is None)


def report_store_written(args: argparse.Namespace, array, frame, written: dict, corners: dict,
                         zarr: bool = True) -> int:
    """The lines on a surface written block by block, and its read-back in
    chunks (0, or 1 when the file does not read back as written); of a
    ``zarr`` store, a warning where chunks never written count."""
    from ..mesh.export import float64_move_note, stl_weld_note
    from ..mesh.float32 import float64_moved
    from ..mesh.formats.omezarr import open_store
    from ..mesh.readback import agreed_volume_words
    from ..mesh.streamed_readback import check_streamed
    from ..scale.chunks import never_written, unwritten_fill

    out = written["path"]
    if zarr:
        never_written(str(args.input), unwritten_fill(open_store(args.input).array, args.label), args.label)
    print(terminal_text(f"{out}: {written['vertices']} vertices, {written['faces']} faces ({written['kind']}), "
                        f"V-E+F = {written['euler_characteristic']}"
                        + (f", {pinched_words(written['pinched'])}; " if written["pinched"] else " (")
                        + "written block by block; isoflow info counts its closed surfaces)"))
    moved = float64_move_note(out, corners)
    if moved:  # the corners moved by float64 itself
        print(terminal_text(f"isoflow surface: warning: {moved}"), file=sys.stderr)
    if written["shared"]:  # readers see other topology than the one written: said under --quiet too, as in memory
        print(terminal_text(f"isoflow surface: warning: {stl_weld_note(out, written['shared'])}"), file=sys.stderr)
    if args.no_check:
        return 0
    check = check_streamed(out, dict(written, centre=np.asarray(array.shape) / 2, moved=float64_moved(corners)), frame)
    if not check["agree"]:
        print(terminal_text(f"isoflow surface: error: {check['problem']}"), file=sys.stderr)
        return 1
    print(terminal_text(f"{out}: read back in chunks (every face): closed and consistently wound, volume "
                        f"{agreed_volume_words(check['figures']['volume_units'], written['voxels'], frame.spacing)}"
                        + ("" if out.suffix.lower() == ".stl" else f", V-E+F = {check['figures']['euler_number']}, "
                           "sum of a = 8 chi") + ": as isoflow counts"))
    return 0


def streams(args: argparse.Namespace) -> bool:
    """The output is one that is written block by block: binary PLY or STL
    without a picture."""
    from ..mesh.surface_blocks import STREAM_SUFFIXES

    return Path(args.output).suffix.lower() in STREAM_SUFFIXES and not args.ascii and not args.png


def refuse_store_beyond_memory(args: argparse.Namespace) -> None:
    """A store whose volume would not fit in memory with its mesh, asked
    for what needs the whole mesh in memory: one line naming what streams."""
    from ..mesh.formats.omezarr import store_volume
    from ..mesh.surface_blocks import STREAM_SUFFIXES
    from ..scale.memory import default_budget, sized

    array = store_volume(args.input, args.label)[0]
    need = 2 * int(np.prod(array.shape, dtype=np.int64))  # the volume and its configurations, before the mesh
    if need > default_budget():
        asked = "--ascii" if args.ascii else "--png" if args.png else Path(args.output).suffix.lower() or args.output
        raise IsoflowError(f"{args.input}: {asked} needs the whole surface in memory (more than {sized(default_budget())} "
                           f"here); a store's surface is written block by block as binary PLY or STL "
                           f"({', '.join(STREAM_SUFFIXES)})")


def pinched_words(pinched: int) -> str:
    """The pinched vertices of a surface line, up to its closing
    parenthesis: what the mesh did there, as ``isoflow info`` says it (a
    user who asked for 26-connectivity sees two shells in MeshLab where
    two voxels meet at a corner, and "pinched" alone did not say why).

    Examples
    --------
    >>> pinched_words(1) + ")"
    '1 pinched vertex (split in the mesh, joined by the connectivity)'
    """
    return f"{counted(pinched, 'pinched vertex', 'pinched vertices')} (split in the mesh, joined by the connectivity"


def surface_comments(name: str, conn: int) -> tuple[str, ...]:
    """The PLY header comments of ``surface``."""
    from ..mesh.export import VERTEX_COMMENT

    return f"isoflow surface of {Path(name).name}, {conn}-connectivity", VERTEX_COMMENT
