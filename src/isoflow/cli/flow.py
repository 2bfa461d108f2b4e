"""``isoflow flow``: the digital curvature flow (section 5), with its files."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import IsoflowError, coordinates, path_text, terminal_text
from .inputs import (
    add_connectivity,
    add_input_arguments,
    check_input_connectivity,
    label_options,
    load_input,
    one_time_point,
    refuse_mesh_options,
    refuse_options_without,
    refuse_points_option,
    refuse_time_series_store,
    say_plate,
    step_count,
    thread_count,
    why_empty,
)
from .progress import progress_bar, writing_line

if TYPE_CHECKING:
    from ..flow.run import FlowResult


def add_parser(sub: argparse._SubParsersAction, add_command) -> None:
    p = add_command(sub, "flow", "run the digital curvature flow (section 5), its topology changes reported, "
                                 "or prevented with --guard")
    add_input_arguments(p)
    add_connectivity(p, dims=(2, 3))
    p.add_argument("--steps", type=step_count, help="number of steps (default: until the object vanishes)")
    p.add_argument("--guard", action="store_true",
                   help="topology control (Theorem 21): every step by simple deformations, thinning where a step "
                        "cannot be; ends at a thin fixed point")
    p.add_argument("--until-topology-change", action="store_true",
                   help="stop before the first step that would change the Betti numbers (that step is reported, "
                        "not taken; a guarded run never takes one)")
    p.add_argument("--out", metavar="DIR", help="write step_NNN.ply surfaces (3D), flow.csv, flow.png and shapes.png into DIR")
    p.add_argument("--volumes", metavar="SUFFIX",
                   help="also write every non-empty step's volume as step_NNN.SUFFIX into --out (.npz, .nii.gz, .tif, .h5, "
                        "..., .png for a 2D run); a .zarr input with --volumes .zarr is flowed block by block, never read "
                        "into memory (its --out gets no surfaces or shapes.png)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-check", action="store_true", help="do not read the step files back with trimesh")
    p.add_argument("--force", action="store_true", help="overwrite files in a non-empty --out directory")
    p.add_argument("--threads", type=thread_count, metavar="N",
                   help="threads for the compiled passes (default: $ISOFLOW_THREADS, else every CPU); for a .zarr "
                        "store flowed block by block (--volumes .zarr), the threads of dask's threaded scheduler, "
                        "slabs and records alike, each slab's passes on one (default: $ISOFLOW_THREADS, else 2), the "
                        "memory sized for as many at a time")
    p.set_defaults(func=cmd_flow)


def cmd_flow(args: argparse.Namespace) -> int:
    """``isoflow flow``, its compiled passes on ``--threads`` threads (a
    store flowed block by block takes them as its dask threads)."""
    from ..scale.compiled import using

    with using(args.threads):
        return flow_of(args)


def flow_of(args: argparse.Namespace) -> int:
    """``isoflow flow`` of a file, or of a store block by block."""
    if args.out == "":  # (an unset shell variable): no run's files were asked for in silence, nor into "."
        raise IsoflowError("--out '': an empty directory name; give --out DIR for the run's files")
    refuse_options_without(args, "out", {"force": "overwrites files in a non-empty --out directory",
                                         "no_check": "skips the read-back of the --out step surfaces"})
    if args.out:  # before any work (the FlowWriter checks it again when it makes the directory)
        from ..flow.files import check_output_dir

        check_output_dir(args.out, args.force)
    # a time series refused as in memory, on either path (block by block the
    # reader's own line named no way to take one time point)
    refuse_time_series_store(args, "the digital curvature flow is defined for 2D and 3D objects")
    if block_wise(args):
        return flow_store(args)
    refuse_store_read_whole(args)
    obj = load_input(args)
    check_flow_input(args, obj)
    corners = out_placement(args, obj)
    writer = flow_writer(args, obj)
    result = run_with_files(args, obj, writer)
    if args.json:
        print(json.dumps({"input": path_text(args.input), **result.to_dict()}))
    else:
        print(format_flow(result, terminal_text(args.input), pitch=obj.spacing, unit=obj.unit))
        if args.out:
            written = (["surfaces (step_*.ply)"] if obj.ndim == 3 else []) + [
                "flow.csv", "flow.png (figures)", "shapes.png (the object at a few steps)"]
            print(terminal_text(f"{args.out}: {', '.join(written)}"
                                + (f", volumes (step_*{args.volumes})" if args.volumes is not None else "")))
    from ..mesh.export import float64_move_note

    # the step surfaces' corners, or without --out the world coordinates printed
    moved = None if corners is None else (float64_move_note(args.out, corners) if args.out else
                                          float64_move_note(args.input, corners, "the boxes and the limit point printed"))
    if moved:  # moved by float64 itself
        print(terminal_text(f"isoflow flow: warning: {moved}"), file=sys.stderr)
    return 0 if writer is None else say_read_back(args, writer)


def out_placement(args: argparse.Namespace, obj) -> dict | None:
    """The object's placement as
    :func:`isoflow.mesh.export.check_float64_corners` takes it, refused
    before the run where float64 cannot keep the voxel corners apart
    with ``--out``: the step surfaces would collapse in every file (a 2D
    run's boxes in flow.csv, pictures in shapes.png and cropped states'
    origins alike). Else what float64 does to the corners, for the
    warning that says how far it moves them; None for a 2D run with
    ``--out``, which writes no surface, and for a run without ``--out``
    where float64 cannot keep them apart: the run answers as ``info``
    does, its coordinates along such an axis None (``?``, ``null``),
    said in the run's one warning
    (:func:`isoflow.flow.run.held_boxes`)."""
    from ..digital.float64 import beyond_float64_axes, merged_axes
    from ..mesh.export import check_float64_corners

    if not args.out:
        # the flow works on the voxels: only the world coordinates printed are lost there, not its numbers
        if any(merged_axes(obj.origin, obj.spacing, obj.volume.shape)) or any(
                beyond_float64_axes(obj.origin, obj.spacing, obj.volume.shape)):
            return None
        return check_float64_corners(args.input, obj.origin, obj.spacing, obj.volume.shape,
                                     "the boxes and the limit point it prints")
    if obj.ndim == 2:
        what = ("the boxes in flow.csv, the pictures in shapes.png and the --volumes states' origins"
                if args.volumes is not None else "the boxes in flow.csv and the pictures in shapes.png")
        check_float64_corners(args.input, obj.origin, obj.spacing, obj.volume.shape, what)
        return None
    return check_float64_corners(args.input, obj.origin, obj.spacing, obj.volume.shape)


def block_wise(args: argparse.Namespace) -> bool:
    """A .zarr input whose states go to .zarr stores (``--volumes .zarr``,
    or ``zarr``: the dot may be left out, as for every suffix) is flowed
    block by block, never read into memory."""
    from ..mesh.formats.registry import split_dataset

    if split_dataset(args.input)[0].suffix.lower() != ".zarr" or args.volumes is None:
        return False
    return (args.volumes if args.volumes.startswith(".") else "." + args.volumes).lower() == ".zarr"


def refuse_store_read_whole(args: argparse.Namespace) -> None:
    """A 3D .zarr store that this flow would read whole into memory
    (``--volumes`` other than ``.zarr``, ``.ome.zarr`` too, or none) and
    that would not fit there: refused before anything is written, as any
    read is (:func:`~isoflow.mesh.formats.registry.check_shape`), the line
    naming the flow that reads it block by block.

    On this path every state is computed whole in memory, so writing it
    (``--volumes .ome.zarr`` as any other format) through memory is right:
    it costs the stored 0/1 copy, a byte a voxel, beside a flow that holds
    the state already; the store that would not fit is the input, and it
    is refused here, up front.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``input``, ``label``, ``guard``.

    Raises
    ------
    IsoflowError
        One line: the memory the read needs, the budget, what to do.
    """
    from ..mesh.formats.omezarr import open_store
    from ..mesh.formats.registry import check_shape, split_dataset
    from .surface import is_store

    if split_dataset(args.input)[0].suffix.lower() != ".zarr" or not is_store(args.input, args.label):
        return
    # the stored type: the read reads it whole, --label or not (with it, an (X, Y, Z, 1) array is 3D)
    store = open_store(args.input, channel=args.label is not None)
    shape = tuple(int(store.array.shape[i]) for i in store.xyz)
    if args.guard:
        hint = "crop it: --guard is not done block by block"
    elif args.label is not None:
        hint = (f"write label {args.label}'s voxels as a store of their own and flow that block by block "
                "(--out DIR --volumes .zarr, which takes no --label), or crop it")
    else:
        hint = "flow it block by block (--out DIR --volumes .zarr: each state a step_NNN.zarr store), or crop it"
    check_shape(shape, store.array.dtype, str(args.input), hint=hint)


def flow_store(args: argparse.Namespace) -> int:
    """The plain flow of a zarr store block by block
    (:func:`isoflow.flow.chunked.flow_chunked`), its states written into
    ``--out`` as step_NNN.zarr with flow.csv and flow.png; the previous
    run's files stay until this one is complete; ``--threads`` (else
    ``$ISOFLOW_THREADS``) is its ``workers``."""
    from ..flow.chunked import flow_chunked, guard_refusal, source_volume
    from ..flow.files import FlowWriter
    from ..flow.motion import flow_connectivity
    from ..flow.run import reachable_steps
    from ..mesh.export import check_float64_corners, float64_move_note
    from ..mesh.formats.omezarr import open_store
    from ..scale.compiled import asked_threads

    refuse_mesh_options(args, ".zarr")
    refuse_points_option(args, "volume")
    volume, place, _ = source_volume(args.input)
    say_plate(args, tuple(volume.shape))
    # refused before any step store is staged, as the run in memory is
    moved = "the boxes in flow.csv, the limit point and the step stores' origins"
    corners = check_float64_corners(args.input, place.origin, place.spacing, volume.shape, moved)
    if getattr(args, "label", None) is not None:
        raise IsoflowError(f"{args.input}: --label is not read block by block; write the label's voxels as a "
                           "store of their own, or flow it without --volumes .zarr")
    if args.guard:
        raise IsoflowError(guard_refusal(str(args.input), volume.shape))
    check_flow_input(args, None)
    if args.connectivity is not None:  # named with the input, as in memory: the dimension is the store's
        check_input_connectivity(args, 3)
    conn = flow_connectivity(3, args.connectivity)
    last = reachable_steps(args.steps, volume.shape)
    total = bar_total(args.steps, volume.shape)
    workers = asked_threads()  # --threads (cmd_flow's), else the environment's, as info's store is read
    writer = FlowWriter(args.out, conn, args.force, last_step=last, check=False)
    try:  # from the staging directory's making on: an interrupt anywhere (an import, a bar) removes it
        with progress_bar(args, "flow", unit=" steps", noun="step") as show, label_options(args, block_wise=True):
            if show is not None:  # step 0, the store's analysis block by block, takes as long as a step
                show(0, total)
            result = flow_chunked(args.input, writer.stage, steps=args.steps, connectivity=conn, width=writer.width,
                                  until_topology_change=args.until_topology_change,
                                  # neither --threads nor $ISOFLOW_THREADS: flow_chunked's own default (the help's 2)
                                  **({} if workers is None else {"workers": workers}),
                                  progress=None if show is None else (lambda step, state: show(step, total)))
            show_whole_run(show, result, total)
            writer.staged.extend(sorted(p.name for p in writer.stage.glob("step_*.zarr")))
            writer.finish(result)
    except KeyboardInterrupt as exc:
        writer.abort()  # the previous run's files stay as they were
        raise writer.interrupted(exc) from None
    except BaseException:
        writer.abort()
        raise
    unit = open_store(args.input).unit()
    if args.json:
        print(json.dumps({"input": path_text(args.input), **result.to_dict()}))
    else:
        print(format_flow(result, terminal_text(args.input), pitch=place.spacing, unit=unit))
        print(terminal_text(f"{args.out}: volumes (step_*.zarr, read block by block), flow.csv, flow.png (figures)"))
    note = float64_move_note(args.out, corners, moved)
    if note:  # moved by float64 itself, as in memory
        print(terminal_text(f"isoflow flow: warning: {note}"), file=sys.stderr)
    return 0


def check_flow_input(args: argparse.Namespace, obj) -> None:
    """The object (None: read block by block) and the options make a flow,
    or one line says why not."""
    if obj is not None and obj.ndim not in (2, 3):
        hint = one_time_point(args.input, obj.volume.shape, args.label) if obj.ndim == 4 else ""
        raise IsoflowError(f"{args.input}: the digital curvature flow is defined for 2D and 3D objects, "
                           f"this one is {obj.ndim}D{hint}")
    if obj is not None and args.connectivity is not None:
        # run_flow reads 6 and 26 as 4 and 8 in 2D (its default, 6, names the 3D
        # adjacency); one asked for here must fit the object, as for info
        check_input_connectivity(args, obj.ndim)
    if obj is not None and obj.voxels == 0:
        why = why_empty(args, obj)  # a point list with points: say why none is in
        raise IsoflowError(f"{args.input}: the object is empty" + (f": {why}" if why else ", there is nothing to flow"))
    if args.volumes is not None and not args.out:
        raise IsoflowError(f"--volumes {args.volumes or repr('')} writes into the --out directory; give --out DIR")


def flow_writer(args: argparse.Namespace, obj):
    """The writer of ``--out``, or None. Files are written while the flow
    runs, so no state is kept in memory (every state of a box of side s
    would cost about s^4/4 bytes). The step volumes are written with the
    object's length unit, which every state keeps."""
    from ..flow.files import FlowWriter, check_step_volume, step_width
    from ..flow.motion import flow_connectivity
    from ..flow.run import reachable_steps

    last = reachable_steps(args.steps, obj.volume.shape)
    if args.volumes is not None:  # ("" too: refused, not ignored)
        from ..mesh.volumes import check_volume_suffix

        # before the output directory is made: the suffix, and what its
        # format cannot hold of the states (their dimension and pitch are the object's)
        args.volumes = check_volume_suffix(args.volumes)
        if args.out:
            first = Path(args.out) / f"step_{0:0{step_width(last)}d}{args.volumes}"
            check_step_volume(first, 0, obj)
    if not args.out:
        return None
    conn = flow_connectivity(obj.ndim, args.connectivity)
    writer = FlowWriter(args.out, conn, args.force, last_step=last, check=not args.no_check)
    try:  # the staging directory is made: an interrupt from here on removes it
        if args.volumes is not None:
            writer.write_volumes(args.volumes)
    except BaseException:
        writer.abort()
        raise
    return writer


def run_with_files(args: argparse.Namespace, obj, writer):
    """The flow, each state handed to the writer as it comes."""
    try:  # the writer's staging directory is made: an interrupt anywhere (an import, a bar) removes it
        from ..flow.run import run_flow

        total = bar_total(args.steps, obj.volume.shape)
        with progress_bar(args, "flow", unit=" steps", noun="step") as show:

            def progress(step, state):
                if writer is not None:
                    writer.add(step, state)
                if show is not None:
                    show(step, total)

            if writer is not None:
                if show is not None:  # step 0's surface of a large object takes as long as a step
                    show(0, total)
                writer.add(0, obj.cropped())
            # (no callback when nothing uses the states: a compiled run then
            # never unpacks them)
            result = run_flow(obj, steps=args.steps, guard=args.guard, connectivity=args.connectivity,
                              until_topology_change=args.until_topology_change,
                              progress=progress if writer is not None or show is not None else None,
                              keep_states=False)
            show_whole_run(show, result, total)
        if writer is not None:  # the last surfaces' read-back and the pictures: a line while they take
            with writing_line(args, writer.out):
                writer.finish(result)
    except BaseException as exc:
        if writer is None:
            raise
        writer.abort()  # the previous run's files stay as they were
        if isinstance(exc, KeyboardInterrupt):
            raise writer.interrupted(exc) from None
        raise
    return result


def bar_total(steps: int | None, shape: tuple[int, ...]) -> int | None:
    """The progress bar's length: ``--steps`` where a run of an array of
    ``shape`` can be expected to reach it (:func:`~isoflow.flow.run.reachable_steps`),
    else None, a counter of the steps done: a bar sized by ``--steps
    1000000000000`` would stand at 0 % with an estimate of millions of
    hours.

    Examples
    --------
    >>> bar_total(10, (20, 20, 20)), bar_total(10**12, (20, 20, 20)), bar_total(None, (20, 20, 20))
    (10, None, None)
    """
    from ..flow.run import reachable_steps

    return steps if steps is not None and reachable_steps(steps, shape) == steps else None


def show_whole_run(show: Callable[[int, int | None], None] | None, result: FlowResult, total: int | None) -> None:
    """Tell the progress bar ``show`` (None: no bar) that the run is whole:
    a run that vanishes or converges before ``--steps`` ends its bar at
    100 %, the total becoming the last step taken, not at that step's
    share of ``--steps``; a counter (``total`` None) ends at the steps
    taken.

    Parameters
    ----------
    show : callable or None
        The bar's ``show(done, total)``, as
        :func:`~isoflow.cli.progress.progress_bar` yields it.
    result : isoflow.FlowResult
        The run, ended.
    total : int or None
        The bar's length (:func:`bar_total`), None for a counter.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow import run_flow
    >>> shown = []
    >>> show_whole_run(lambda done, total: shown.append((done, total)), run_flow(np.ones((3, 4, 5), bool)), 5)
    >>> shown
    [(3, 3)]
    """
    if show is not None:
        last = result.steps[-1]["step"]
        show(last, None if total is None else last)


def say_read_back(args: argparse.Namespace, writer) -> int:
    """How many step files trimesh read back as isoflow counts them; 1 when
    any did not agree."""
    read = [c for c in writer.checks.values() if not c.get("skipped")]
    skipped = [c["skipped"] for c in writer.checks.values() if c.get("skipped")]
    if read and not args.json:
        print(terminal_text(f"{args.out}: {len(read) - len(writer.problems)} of {len(read)} step surfaces "
                            "read back by trimesh as isoflow counts them (flow.csv: trimesh_* columns)"))
    if skipped and not args.quiet:
        print(terminal_text(f"isoflow flow: note: {len(skipped)} step files not read back ({skipped[0]})"), file=sys.stderr)
    for line in writer.problems:
        print(terminal_text(f"isoflow flow: error: {line}"), file=sys.stderr)
    return 1 if writer.problems else 0


def format_flow(result, name: str, pitch=None, unit: str | None = None) -> str:
    """The flow's records as a table, its stop and its limit point (a 2D
    object's cells are pixels, as ``isoflow info`` says, and its full box
    a rectangle); the points to as
    many digits as keep them within a 200th of ``pitch`` (the voxel size,
    one number or one per axis), so that a far origin does not round them
    to the same number, followed by their length ``unit`` where the input
    names one.

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow import DigitalObject, run_flow
    >>> far = DigitalObject(np.ones((2, 2, 2), bool), pitch=0.01, origin=(123456.0, 0.0, 0.0))
    >>> format_flow(run_flow(far), "far.npz", pitch=0.01).splitlines()[-1].split(", the")[0]
    '  limit: [123456.01, 0.01, 0.01]'
    """
    planar = bool(result.steps) and len(result.steps[0]["betti"]) == 2
    cells = "pixels" if planar else "voxels"
    lines = [
        f"{name}: digital curvature flow, {result.connectivity}-connectivity"
        + (", guard" if result.guard else ""),
        f"  {'step':>5} {cells:>10} {'parity':>6}  {'betti':<12} {'chi':>4} {'energy':>8}"
        + (f"  {'move'}" if result.guard else ""),
    ]
    for s in result.steps:
        # a guarded step is a whole flow step, a flow step with its stuck blocks resolved, or a thinning step
        lines.append((
            f"  {s['step']:>5} {s['voxels']:>10} {s['parity']:>6}  {str(tuple(s['betti'])):<12} "
            f"{s['euler_characteristic']:>4} {s['energy']:>8}" + (f"  {s.get('move') or ''}" if result.guard else "")
        ).rstrip())
    lim = result.limit
    said = f" {unit}" if unit else ""
    lines.append(f"  stopped: {result.stop_reason}")
    if result.guard and result.guard_steps:
        lines.append("  moves: " + ", ".join(f"{n} {kind}" for kind, n in result.guard_steps.items()))
    if lim["center"] is not None:
        # the JSON's "cuboid" names a full box in either dimension; in the plane that box is a rectangle
        box = "rectangle" if planar else "cuboid"
        shape = {"cuboid": f"a {box}", "other": f"not a {box}", "not-reached": "the run stopped before its end"}
        lines.append(f"  limit: {coordinates(lim['center'], step=pitch)}{said}, the centre of the last non-empty state (step "
                     f"{lim['last_step']}: {shape.get(lim['last_shape'], lim['last_shape'])})")
    for c in result.topology_changes:
        # a store flowed block by block finds changes but does not locate
        # them (where is None): say so, not "in None"; a box in a pitch read
        # from float32 (NIfTI's zooms) prints as that pitch does
        place = "not located (block by block)" if c["where"] is None else f"in the box {box_words(c['where'], pitch)}{said}"
        # the step --until-topology-change stopped before is not in the table: say so, or it reads as taken
        taken = "" if c.get("applied", True) else " (the step is not taken: the run stopped before it)"
        lines.append(f"  topology change at step {c['step']}: {tuple(c['before'])} -> {tuple(c['after'])}, {place}"
                     + taken)
    return "\n".join(lines)


def box_words(box: list, pitch=None) -> str:
    """A flat world box (the lowest corner, then the highest, as the
    records hold it) as ``[lo] to [hi]``, to the digits of
    :func:`~isoflow.errors.coordinates` within a 200th of ``pitch``.

    Examples
    --------
    >>> box_words([1.0, 2.0, 3.0, 4.5, 5.0, 6.0], pitch=0.5)
    '[1, 2, 3] to [4.5, 5, 6]'
    """
    half = len(box) // 2
    return f"{coordinates(box[:half], step=pitch)} to {coordinates(box[half:], step=pitch)}"
