"""``isoflow voxelize``: a mesh's solid as a volume file."""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from pathlib import Path

from ..errors import IsoflowError, coordinates, counted, terminal_text
from .inputs import add_mesh_rule, fill_hint, mesh_fill, pitch_value, resolution_value, say_note, voxelize_input
from .progress import progress_bar, writing_line


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "voxelize", "voxelise a mesh's solid into a volume file (with pitch and origin), "
                                     "or several meshes into one label image")
    p.add_argument("mesh", nargs="+",
                   help="a mesh file: any format trimesh reads (STL, OBJ, PLY, OFF, GLB, 3MF, DAE, ZIP, ...); "
                        "several: one label image on one grid over them all, label i for the i-th mesh")
    grid = p.add_mutually_exclusive_group(required=True)
    grid.add_argument("--pitch", type=pitch_value, help="voxel size in mesh units")
    grid.add_argument("--resolution", type=resolution_value, help="voxels along the longest side")
    p.add_argument("-o", "--output", required=True,
                   help="OUT.npz (or .npy, .tif, .nii, .nii.gz, .mgz, .mgh, .nrrd, .h5[:/dataset], .binvox, .vox), or "
                        "OUT.zarr: one mesh's written slab by slab as dask tasks, never held in memory (a label "
                        "image of several meshes or --split is written whole)")
    add_mesh_rule(p)
    add_label_options(p)
    p.add_argument("--force", action="store_true", help="overwrite an existing output")
    p.set_defaults(func=cmd_voxelize)


def add_label_options(p: argparse.ArgumentParser) -> None:
    """How several meshes become one label image."""
    from ..mesh.label_voxels import OVERLAPS

    p.add_argument("--split", action="store_true",
                   help="a label per body: per node of a scene (glTF/GLB, 3MF, DAE, ...; a glTF's in its file's "
                        "order), per solid of an ASCII STL of named solids (FILE:NAME, in its order), per connected "
                        "body of any other mesh (a cavity stays with its body)")
    p.add_argument("--overlap", choices=OVERLAPS, default="later",
                   help="a voxel inside several meshes (or bodies of --split): later (default: the later mesh's "
                        "label wins) or error (refuse, naming the pairs and counts); one mesh without --split has "
                        "nothing to overlap, and --overlap error is refused there (--strict refuses its own "
                        "overlapping shells)")


def cmd_voxelize(args: argparse.Namespace) -> int:
    from ..mesh.grid import GridTooLarge
    from ..mesh.volumes import check_volume_output, write_bytes_per_voxel, write_volume

    if len(args.mesh) > 1 or args.split:
        return voxelize_labels(args)
    args.mesh = args.mesh[0]
    if args.overlap == "error":
        # a check asked for and silently skipped would pass a mesh whose parts overlap; "later" stays
        # accepted, as a script that always passes it for a varying number of meshes asks for nothing
        raise IsoflowError(f"{args.mesh}: --overlap error compares several meshes or the bodies of --split, and one "
                           "mesh has no other to overlap: add --split to label its bodies and refuse their overlaps, "
                           "or --strict to refuse a mesh whose own shells overlap")
    if Path(args.output).suffix.lower() == ".zarr":
        return voxelize_to_store(args)
    check_volume_output(args.output, args.force, ndim=3)  # suffix, library and path before the voxelisation
    try:
        with coarser_for_magicavoxel(args.output):
            obj = voxelize_input(args.mesh, args, write_bytes_per_voxel(args.output))
    except GridTooLarge as exc:
        if exc.store:  # the one way to keep the grid asked: a store, written slab by slab
            raise exc.but(hints=(exc.facts["hints"][0], "or write it slab by slab: -o OUT.zarr")) from None
        raise
    with coarser_for_magicavoxel(), writing_line(args, args.output):
        out = written(write_volume(obj, args.output, force=args.force), args.output)
    shape, padded = "x".join(map(str, obj.volume.shape)), ""
    if Path(args.output).suffix.lower() == ".binvox":  # the grid as a reader finds it, not only as voxelised
        from ..mesh.formats.binvox import written_shape

        cube = written_shape(obj.volume.shape)
        if cube != obj.volume.shape:
            padded = f" (written as {'x'.join(map(str, cube))}: binvox holds a cube, padded with empty voxels)"
    print(terminal_text(f"{out}: {counted(obj.voxels, 'voxel')} in a {shape} grid{padded}, pitch {obj.pitch:.6g}, "
                        f"origin {coordinates(obj.origin, step=obj.pitch)}"))
    return 0


def voxelize_to_store(args: argparse.Namespace) -> int:
    """Beyond memory: slab by slab into a chunked zarr array, as dask tasks."""
    from ..mesh.slabs import voxelize_to_zarr

    out = Path(args.output)
    with progress_bar(args, "voxelize", estimate=True, hint=fill_hint(args)) as show:
        z, details = voxelize_to_zarr(args.mesh, out, pitch=args.pitch, resolution=args.resolution,
                                      fill=mesh_fill(args), strict=args.strict, force=args.force, progress=show,
                                      details=True)
    say_note(args, args.mesh, details.note, why=z.voxels == 0)
    shape = "x".join(map(str, z.shape))
    print(terminal_text(f"{out}: {counted(z.voxels, 'voxel')} in a {shape} zarr array (chunks {'x'.join(map(str, z.chunks))}), "
                        f"pitch {z.pitch:.6g}, origin {coordinates(z.origin, step=z.pitch)}"))
    return 0


def voxelize_labels(args: argparse.Namespace) -> int:
    """Several meshes (or one split into bodies) into one label image."""
    from ..mesh.bodies import mesh_bodies
    from ..mesh.label_voxels import voxelize_meshes
    from ..mesh.volumes import (
        check_volume_output,
        keeps_names,
        names_not_kept,
        refuse_label_count,
        write_bytes_per_voxel,
        write_labels,
    )

    check_volume_output(args.output, args.force, ndim=3)  # suffix, library and path before the meshes are read
    # each file's unit read once, carried by its bodies to the result; different units refused before the meshes
    bodies = mesh_bodies(args.mesh, args.split)
    # and the labels the format keeps, before the voxels
    refuse_label_count(args.output, len(bodies))
    with coarser_for_magicavoxel(args.output), progress_bar(args, "voxelize", estimate=True, hint=fill_hint(args)) as show:
        r = voxelize_meshes(bodies, pitch=args.pitch, resolution=args.resolution, fill=mesh_fill(args),
                            overlap=args.overlap, split=args.split, strict=args.strict,
                            write_bytes=write_bytes_per_voxel(args.output, labels=True), progress=show)
    assert r.labels is not None  # voxelize_meshes keeps its labels; only from_dict's JSON has none
    for body, note, voxels in zip(bodies, r.notes, r.voxels):
        say_note(args, body.name, note, why=voxels == 0)
    # each label's mesh named in the file where its format has a place for names; where it has none, a note
    # (the names are the command's own, not asked for: no warning, as write_labels gives of names given)
    kept = keeps_names(args.output)
    with coarser_for_magicavoxel(), writing_line(args, args.output):
        out = written(write_labels(r.labels, args.output, pitch=r.pitch, origin=r.origin, force=args.force,
                                   names=r.names if kept else None, unit=r.unit), args.output)
    say_note(args, out, r.note, why=0 in r.voxels)  # (it names the labels that got no voxel)
    if not kept:
        say_note(args, out, names_not_kept(args.output, len(r.names)))
    print(label_summary(out, r))
    return 0


@contextlib.contextmanager
def coarser_for_magicavoxel(output: str | None = None) -> Iterator[None]:
    """MagicaVoxel's refusal of a grid past its side, with voxelize's
    remedy: a coarser grid (the format states its limit only, as a flow
    that grew past it needs another remedy). With ``output``, a ``.vox``,
    a grid refused for memory is refused for the format's side too: the
    finest grid that fits in memory is far past that side.

    Examples
    --------
    >>> from isoflow.mesh.formats.magicavoxel import ModelTooLarge
    >>> from isoflow.mesh.grid import GridTooLarge
    >>> try:
    ...     with coarser_for_magicavoxel():
    ...         raise ModelTooLarge("big.vox: MagicaVoxel models are at most 256 voxels a side, this object is 300x2x2")
    ... except IsoflowError as exc:
    ...     print(exc)
    big.vox: MagicaVoxel models are at most 256 voxels a side, this object is 300x2x2; voxelise it coarser (--resolution 256)
    >>> try:
    ...     with coarser_for_magicavoxel("big.vox"):
    ...         raise GridTooLarge("resolution=4096", "a lot", 2**30, shape=(4096, 20, 10), fit=1900)
    ... except IsoflowError as exc:
    ...     print(exc)
    big.vox: MagicaVoxel models are at most 256 voxels a side, this object is 4096x20x10; voxelise it coarser (--resolution 256)
    """
    from ..mesh.formats.magicavoxel import MAX_SIDE, ModelTooLarge
    from ..mesh.formats.registry import split_dataset
    from ..mesh.grid import GridTooLarge, fmt_count

    try:
        yield
    except ModelTooLarge as exc:
        raise IsoflowError(f"{exc}; voxelise it coarser (--resolution {MAX_SIDE})") from None
    except GridTooLarge as exc:
        vox = output is not None and Path(split_dataset(output)[0]).suffix.lower() == ".vox"
        if not vox or not exc.shape or max(exc.shape) <= MAX_SIDE:
            raise
        # the sides as a grid's refusal writes them: 2.000e+200, not its 201 digits
        raise IsoflowError(f"{output}: MagicaVoxel models are at most {MAX_SIDE} voxels a side, this object is "
                           f"{'x'.join(fmt_count(n, sep=False) for n in exc.shape)}; voxelise it coarser "
                           f"(--resolution {MAX_SIDE})") from None


#: the labels listed by name after a label image is written; the rest are counted
LISTED_LABELS = 20


def written(file: Path, output: str) -> str:
    """The file written, with the dataset inside it where one was named
    (``scan.h5:/seg/box``: a file may hold several)."""
    from ..mesh.formats.registry import split_dataset

    dataset = split_dataset(output)[1]
    return str(file) if dataset is None else f"{file}:{dataset}"


def label_summary(out: str | Path, r) -> str:
    """The written label image in words: grid, type, pitch, origin, and a
    row per label (label, voxels, mesh)."""
    shape = "x".join(map(str, r.labels.shape))
    lines = [f"{terminal_text(out)}: {counted(len(r.names), 'label')} in a {shape} grid ({r.labels.dtype}), pitch {r.pitch:.6g}, "
             f"origin {coordinates(r.origin, step=r.pitch)}"]
    width = max(6, len(f"{max(r.voxels, default=0):,}"))
    lines.append(f"{'label':>6}  {'voxels':>{width}}  mesh")
    for i, (name, n) in enumerate(zip(r.names[:LISTED_LABELS], r.voxels), 1):
        lines.append(f"{i:>6}  {n:>{width},}  {terminal_text(name)}")
    if len(r.names) > LISTED_LABELS:
        lines.append(f"{'':>6}  ... {counted(len(r.names) - LISTED_LABELS, 'more label')}")
    return "\n".join(lines)
