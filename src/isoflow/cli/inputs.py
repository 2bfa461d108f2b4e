"""What every command reads: the input argument, its options, and the one
loader that turns a volume, a point list or a mesh into a digital object."""

from __future__ import annotations

import argparse
import contextlib
import re
import sys
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import IsoflowError, IsoflowWarning, number_text, terminal_text
from .progress import progress_bar

if TYPE_CHECKING:
    import numpy as np

    from ..digital.lattice import DigitalObject


def add_input_arguments(p: argparse.ArgumentParser) -> None:
    """The input of ``info``, ``surface`` and ``flow``, and how it is read."""
    # every format of the registry's FORMATS, which the loader reads by suffix (a 2D .png too)
    p.add_argument("input", help="volume (.npy/.npz, .tif/.tiff, .nii(.gz), .mgz/.mgh, .hdr/.img, .nrrd/.nhdr, "
                                 "FILE.h5:/dataset, .binvox, .vox, .zarr, .png), point list (.txt: x y z per line) or "
                                 "mesh (any format trimesh reads)")
    p.add_argument("--label", type=label_value, metavar="N",
                   help="a label image: the voxels of value N are the object (MagicaVoxel: colour index N)")
    p.add_argument(
        "--points-are",
        choices=("corners", "voxels"),
        default=None,
        help="a point list gives cube corners (the paper's point model, default) or voxel indices; "
             "refused for a volume or a mesh",
    )
    grid = p.add_mutually_exclusive_group()
    grid.add_argument("--pitch", type=pitch_value, help="voxel size when the input is a mesh")
    grid.add_argument("--resolution", type=resolution_value, help="voxels along the mesh's longest side (default 64)")
    add_mesh_rule(p)


def add_mesh_rule(p: argparse.ArgumentParser) -> None:
    """How a mesh is read into voxels."""
    from ..mesh.fills import FILLS

    p.add_argument("--fill", choices=FILLS, default=None,
                   help="which voxels a mesh fills: winding (default: the solid it bounds, by the generalised "
                        "winding number), shell (every voxel whose closed cube the surface meets) or flood (the "
                        "shell and what it encloses)")
    p.add_argument("--strict", action="store_true",
                   help="refuse a mesh that is not watertight as written (neither genus nor voxelize mends a "
                        "T-junction for it, nor genus a repeated face) or has double-sided faces, whose voxels lie "
                        "in overlapping layers, or whose winding solid is thin or empty against its shell (a closed "
                        "mesh's: against its own volume; by "
                        "default it is read by the generalised winding number)")


def mesh_fill(args: argparse.Namespace) -> str:
    """The ``--fill`` given, or the default (the winding rule)."""
    return args.fill or "winding"


def fill_hint(args: argparse.Namespace) -> str | None:
    """What to say when the winding rule will take long (a mesh whose
    boundary runs everywhere, summed solid angle by solid angle): the
    fills that sum none. Chosen before the mesh is read, so the time note
    (:class:`~isoflow.cli.progress.TimeNote`) says it only where the core
    tells that the rule does sum solid angles: on a closed mesh (the
    scanline alone) these fills take as long."""
    if mesh_fill(args) != "winding":
        return None
    return "--fill flood (the shell and what it encloses) or --fill shell sum no solid angles and take far less"


def add_connectivity(p: argparse.ArgumentParser, dims: tuple[int, ...] = (2, 3, 4)) -> None:
    """``--connectivity`` of the object, in the dimensions the command
    takes (its choices those of these dimensions only, so that a value
    none of its objects takes is refused before any file is read)."""
    from ..digital.connectivity import VALID, default_connectivity

    choices = sorted({c for d in dims for c in VALID[d]})
    order = sorted(dims, key=lambda d: d != 3)  # 3D first: most commands' objects
    said = ", ".join(f"{' or '.join(map(str, VALID[d]))} in {d}D" for d in order)
    default = " / ".join(str(default_connectivity(d)) for d in order)
    p.add_argument("--connectivity", type=int, choices=choices, default=None,
                   help=f"object connectivity: {said} (default: {default}, the paper's)")


def label_value(text: str) -> int | float:
    """``--label N``: a number, kept an int when it is one.

    Examples
    --------
    >>> label_value("18446744073709551617"), label_value("1e3"), label_value("1e300"), label_value("2.5")
    (18446744073709551617, 1000, 1e+300, 2.5)
    """
    try:
        return int(text)  # exactly, however large (checked against the array's type)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    # a whole float past 2**53 stays a float: as an int, a refusal would name 1e300 in 301 digits, not as typed
    return int(value) if value.is_integer() and abs(value) < 2.0**53 else value


def resolution_value(text: str) -> int:
    """argparse type of ``--resolution`` (and ``--max-resolution``): voxels
    along the mesh's longest side, a whole number from 1 to
    :data:`~isoflow.mesh.grid.MAX_RESOLUTION`, refused as the command line
    is read, before a mesh (however large) is loaded.

    Examples
    --------
    >>> resolution_value("64")
    64
    """
    from ..mesh.grid import MAX_RESOLUTION

    return whole_number(text, "voxels", 1, MAX_RESOLUTION)


def step_count(text: str) -> int:
    """argparse type of ``flow --steps``: a whole number, 0 or more,
    refused as the command line is read, before the input (however large)
    is loaded.

    Examples
    --------
    >>> step_count("3")
    3
    """
    return whole_number(text, "steps", 0)


def whole_number(text: str, noun: str, least: int, most: int | None = None) -> int:
    """``text`` read as a whole number of ``noun`` from ``least`` (up to
    ``most``), or argparse's error saying what it must be.

    Examples
    --------
    >>> whole_number("12", "voxels", 1, 64)
    12
    """
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number of {noun}: {text!r}") from None
    if most is not None and not least <= value <= most:
        raise argparse.ArgumentTypeError(f"must be a whole number of {noun} from {least} to {most}, got {value}")
    if value < least:
        raise argparse.ArgumentTypeError(f"must be {least} or more, got {value}")
    return value


def pitch_value(text: str) -> float:
    """argparse type of ``--pitch``: a voxel size, positive and finite,
    refused as the command line is read (before the mesh is loaded).

    Examples
    --------
    >>> pitch_value("0.5")
    0.5
    """
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive voxel size, got {text}")
    return value


def thread_count(text: str) -> int:
    """argparse type of ``--threads``: a whole number of threads, 1 or
    more, said as argparse says the other counts (not "N must be ...": N is
    only the help's name for the value).

    Examples
    --------
    >>> thread_count("4")
    4
    """
    return whole_number(text, "threads", 1)


def seconds_value(text: str) -> float:
    """argparse type of ``genus --time-limit``: a positive number of
    seconds (``inf``: no limit), refused as the command line is read, the
    number as it was typed.

    Examples
    --------
    >>> seconds_value("2.5")
    2.5
    """
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of seconds: {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text}")
    return value


def say_note(args: argparse.Namespace, path: object, note: str | None, why: bool = False) -> None:
    """What is unusual about an input, and the rule used: one ``note:``
    line on stderr, dropped by --quiet unless it is ``why`` a result came
    out empty for an input that is not: --quiet silences progress and
    notes, and an empty result without its reason reads as a wrong one.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``command`` and ``quiet``.
    path : object
        The input the note is about, as the line names it.
    note : str or None
        The note; None says nothing.
    why : bool, optional
        The note is the reason the result is empty: said under --quiet too.

    Examples
    --------
    >>> import contextlib
    >>> quiet = argparse.Namespace(command="voxelize", quiet=True)
    >>> with contextlib.redirect_stderr(sys.stdout):
    ...     say_note(quiet, "a.obj", "mesh has 3 boundary edges")
    ...     say_note(quiet, "a.obj", "the winding rule leaves no voxel in", why=True)
    isoflow voxelize: note: a.obj: the winding rule leaves no voxel in
    """
    if note and (why or not args.quiet):
        print(terminal_text(f"isoflow {args.command}: note: {path}: {note}"), file=sys.stderr)


def voxelize_input(path: str | Path, args: argparse.Namespace, write_bytes: float = 0):
    """A mesh file voxelised by the one mesh reader of every command;
    ``write_bytes`` per voxel are needed beside the volume once it is made
    (the writer of ``voxelize -o``), counted in its memory check."""
    from ..mesh.voxelize import voxelize_file

    with progress_bar(args, "voxelize", estimate=True, hint=fill_hint(args)) as show:
        obj, details = voxelize_file(path, pitch=args.pitch, resolution=args.resolution, fill=mesh_fill(args),
                                     strict=args.strict, write_bytes=write_bytes, progress=show, details=True)
    say_note(args, path, details.note, why=obj.voxels == 0)
    return obj


def mesh_options_given(args: argparse.Namespace) -> bool:
    """Whether an option that only a mesh input takes was given."""
    return args.pitch is not None or args.resolution is not None or args.strict or args.fill is not None


def refuse_mesh_options(args: argparse.Namespace, what: str) -> None:
    """One line when a mesh-only option is given for a volume or points."""
    if mesh_options_given(args):
        raise IsoflowError(f"{args.input}: --pitch/--resolution/--fill/--strict apply to meshes, not to {what} input")


def refuse_points_option(args: argparse.Namespace, what: str) -> None:
    """One line when ``--points-are`` is given for a volume or a mesh: it
    says how a point list is read, and nothing else reads it."""
    if getattr(args, "points_are", None) is not None:
        raise IsoflowError(f"{args.input}: --points-are applies to point lists (x y z per line, .txt), "
                           f"not to {what} input")


def refuse_options_without(args: argparse.Namespace, output: str, meanings: dict[str, str]) -> None:
    """Refuse an option that acts on the file(s) of ``output`` (an
    attribute of ``args``) where that output is not given: the option says
    the output was meant, and was left out, which the command's result
    would not show.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments.
    output : str
        The attribute of the output option (``csv``, ``out``).
    meanings : dict of str to str
        Each such option's attribute and what it does, as the line says it.

    Examples
    --------
    >>> refuse_options_without(argparse.Namespace(force=True, csv=None, command="info"), "csv",
    ...                        {"force": "overwrites an existing --csv file"})
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: --force overwrites an existing --csv file; without --csv info writes no file (give --csv FILE)
    """
    if getattr(args, output):
        return
    for flag, does in meanings.items():
        if getattr(args, flag):
            metavar = "DIR" if output == "out" else "FILE"
            raise IsoflowError(f"--{flag.replace('_', '-')} {does}; without --{output} {args.command} writes no file "
                               f"(give --{output} {metavar})")


def why_empty(args: argparse.Namespace, obj) -> str | None:
    """Why the object read is empty, where the input was not: a point list
    read with the paper's point model, in which no cube has all its corners
    listed (a list of voxel indices read as corners, most often). None
    otherwise (an empty volume is empty as given; a mesh says why in its
    note)."""
    from ..mesh.load import is_mesh_path
    from ..mesh.volumes import is_volume, no_cube_reason

    if obj.voxels or is_volume(args.input) or is_mesh_path(Path(args.input)) or args.points_are == "voxels":
        return None
    return no_cube_reason(obj.ndim, "--points-are voxels")


def load_input(args: argparse.Namespace):
    """The digital object named on the command line (volume, points or mesh)."""
    return load_input_with_unit(args)[0]


def load_input_with_unit(args: argparse.Namespace) -> tuple[DigitalObject, str | None, np.dtype | None]:
    """:func:`load_input`'s object and, for a volume file, the length unit
    of its voxel size and origin as the file says it (None for a mesh, a
    point list, or a file that says none) and the type of its values
    (:func:`~isoflow.mesh.volumes.read_volume_as_stored`; None but for a
    volume file)."""
    from ..mesh.load import is_mesh_path, refuse_cad
    from ..mesh.volumes import NO_CUBE, is_volume, read_object, read_volume_as_stored

    path = Path(args.input)
    refuse_cad(path)  # (else read as a point list: "not a number: 'ISO-10303-21;'")
    if is_mesh_path(path):
        if getattr(args, "label", None) is not None:
            raise IsoflowError(f"{path}: --label selects voxels of a volume, not of a mesh")
        refuse_points_option(args, "mesh")
        return voxelize_input(path, args), None, None
    refuse_mesh_options(args, path.suffix or "this")
    volume = is_volume(args.input)  # anything else is read as a point list
    if volume:
        refuse_points_option(args, "volume")
    unit = dtype = None
    # the name as given: FILE.h5:/dataset and IMAGE.zarr:LEVEL name a part of a file
    with label_options(args), warnings.catch_warnings():
        # an empty point model: each command says why in its own words (why_empty)
        warnings.filterwarnings("ignore", message=re.escape(f"{path}: {NO_CUBE}"), category=IsoflowWarning)
        if volume:
            obj, unit, dtype = read_volume_as_stored(args.input, label=args.label)
        else:
            obj = read_object(args.input, points_are=args.points_are or "corners", label=args.label)
    if volume:
        say_plate(args, obj.volume.shape)
    return obj, unit, dtype


def check_input_connectivity(args: argparse.Namespace, ndim: int) -> None:
    """Refuse a ``--connectivity`` that does not fit the input's dimension,
    in one line naming the input: the dimension is the file's, not the
    option's.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``input`` and ``connectivity`` (None: the
        default, which fits any dimension).
    ndim : int
        The input's dimension.

    Examples
    --------
    >>> check_input_connectivity(argparse.Namespace(input="a.npy", connectivity=8), 3)
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: a.npy: connectivity 8 is not valid in 3D (use 6 or 26)
    """
    from ..digital.connectivity import resolve_connectivity

    try:
        resolve_connectivity(ndim, args.connectivity)
    except IsoflowError as exc:
        raise exc.at(args.input) from None


#: the commands that take a 2D image as well as a 3D volume: where a plate
#: one voxel thick is analysed or flowed in 3D, they would take the 2D slice
PLANAR_COMMANDS = ("info", "flow")


def say_plate(args: argparse.Namespace, shape: tuple[int, ...]) -> None:
    """Say, once on stderr (dropped by --quiet), that a 3D volume one voxel
    thick along one axis and two or more along the others is read as a 3D
    plate, as it is: a segmentation of one slice saved as (X, Y, 1) is
    then a plate that the flow empties in one step, with the Euler
    characteristic of a solid; the note gives the line that saves the 2D
    image (:func:`slice_as_2d`). Only ``info`` and ``flow``, which take 2D
    images, say it. ``info`` says it of a 4D volume of one entry along its
    last axis too (a 3D mask saved with a channel axis, as ilastik's
    (z, y, x, 1)): in 4D its b1, b2 and closed surfaces are not counted.
    Not of one voxel along another axis: that may be a time series of 2D
    images (a NIfTI's (x, y, 1, t)), whose time is no third axis.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``command``, ``input``, ``quiet``, and
        ``label`` where it has one.
    shape : tuple of int
        The volume's shape as read (x, y, z), or (x, y, z, t).
    """
    thin = [k for k, n in enumerate(shape) if n == 1]
    if args.quiet or args.command not in PLANAR_COMMANDS or len(shape) not in (3, 4) or len(thin) != 1:
        return
    if len(shape) == 4 and (args.command != "info" or thin[0] != 3):  # (the others refuse 4D in one line)
        return
    if any(n < 2 for k, n in enumerate(shape) if k != thin[0]):
        return
    labels = getattr(args, "labels", None) is not None
    note = slice_as_2d(args.input, shape, thin[0], getattr(args, "label", None), labels=labels)
    print(terminal_text(f"isoflow {args.command}: note: {args.input}: {note}"), file=sys.stderr)


def slice_as_2d(path: str | Path, shape: tuple[int, ...], axis: int, label: float | None = None, *,
                labels: bool = False) -> str:
    """The note on a volume one voxel thick along ``axis``: it is read as
    a 3D plate (a 4D volume), and the one line of Python that saves the
    slice as a 2D image (the 3D volume), voxel size and origin of the other
    axes and the length unit kept; of a label image (``labels``), with ``read_labels`` and
    ``write_labels``, which keep the labels and their unit, so that
    ``info --labels`` gives the 2D table of that slice.

    Parameters
    ----------
    path : str or pathlib.Path
        The input as given on the command line.
    shape : tuple of int
        The volume's shape (x, y, z), or (x, y, z, t).
    axis : int
        The axis of one voxel.
    label : float, optional
        The ``--label`` given: the line reads that label.
    labels : bool
        The input is read as a label image (``--labels``).

    Returns
    -------
    str
        The note, after the input's name.

    Examples
    --------
    >>> print(slice_as_2d("seg.nii.gz", (64, 48, 1), 2, labels=True))
    shape 64x48x1, one voxel along z: read as a 3D plate one voxel thick; to analyse it as the 2D image, save that and give it: \
python -c 'import isoflow; v = isoflow.read_labels("seg.nii.gz"); k = [0, 1]; \
isoflow.write_labels(v.array[:, :, 0], "slice_2d.npz", pitch=v.spacing[k], origin=v.origin[k], unit=v.unit)'
    >>> print(slice_as_2d("slice.nii.gz", (64, 48, 1), 2))
    shape 64x48x1, one voxel along z: read as a 3D plate one voxel thick; to analyse it as the 2D image, save that and give it: \
python -c 'import isoflow; v = isoflow.read_volume("slice.nii.gz"); k = [0, 1]; \
isoflow.write_volume(isoflow.DigitalObject(v.volume[:, :, 0], pitch=v.spacing[k], origin=v.origin[k], unit=v.unit), \
"slice_2d.npz")'
    >>> print(slice_as_2d("seg.h5", (64, 48, 32, 1), 3))
    shape 64x48x32x1, one voxel along axis 3: read as a 4D volume one voxel thick, whose b1, b2 and closed surfaces \
are not counted; to analyse it as the 3D volume, save that and give it: python -c 'import isoflow; \
v = isoflow.read_volume("seg.h5"); k = [0, 1, 2]; \
isoflow.write_volume(isoflow.DigitalObject(v.volume[:, :, :, 0], pitch=v.spacing[k], origin=v.origin[k], unit=v.unit), \
"volume_3d.npz")'
    """
    import json
    import shlex

    n = len(shape)
    kept = [k for k in range(n) if k != axis]
    index = ", ".join("0" if k == axis else ":" for k in range(n))
    label_arg = "" if label is None else f", label={label!r}"
    out = "slice_2d.npz" if n == 3 else "volume_3d.npz"
    if labels:  # (a label image has no 4D note: read_labels reads an (x, y, z, 1) file as 3D)
        code = (f"import isoflow; v = isoflow.read_labels({json.dumps(str(path))}); k = {kept}; "
                f'isoflow.write_labels(v.array[{index}], "{out}", pitch=v.spacing[k], origin=v.origin[k], unit=v.unit)')
    else:
        code = (f"import isoflow; v = isoflow.read_volume({json.dumps(str(path))}{label_arg}); k = {kept}; "
                f"isoflow.write_volume(isoflow.DigitalObject(v.volume[{index}], pitch=v.spacing[k], origin=v.origin[k], "
                f'unit=v.unit), "{out}")')
    if n == 3:
        read = (f"one voxel along {'xyz'[axis]}: read as a 3D plate one voxel thick; "
                "to analyse it as the 2D image")
    else:
        read = (f"one voxel along axis {axis}: read as a 4D volume one voxel thick, whose b1, b2 and closed "
                "surfaces are not counted; to analyse it as the 3D volume")
    return f"shape {'x'.join(map(str, shape))}, {read}, save that and give it: python -c {shlex.quote(code)}"


def one_time_point(path: str | Path, shape: tuple[int, ...], label: float | None = None) -> str:
    """What to do with a 4D volume (read as x, y, z, t) given to a command
    that takes one 3D volume: save one entry of its 4th axis as a 3D file,
    voxel size and origin kept, and give that. A .npy does not say
    whether that axis is time or channels (RGB), so the line names both;
    where the file names it (an OME-Zarr image's or a TIFF's ``t``; a
    NIfTI's dim[4], time by its standard), the line says so
    (:func:`~isoflow.mesh.formats.registry.fourth_axis_words`).

    There is no option that picks a time point: the one line of Python is
    the way, and it names the file as given. It reads that time point
    alone (``read_volume(path, time=0)``): a ``.zarr`` store reads only
    its chunks, so the line works on a time-lapse larger than memory.

    Parameters
    ----------
    path : str or pathlib.Path
        The input as given on the command line.
    shape : tuple of int
        The 4D volume's shape (x, y, z, t).
    label : float, optional
        The ``--label`` given: the line reads that label.

    Returns
    -------
    str
        The end of the refusal, after "this one is 4D".

    Examples
    --------
    >>> print(one_time_point("cells.npy", (8, 8, 8, 3)))
    , shape 8x8x8x3 (a 4th axis of 3 entries, time points or channels, read as x, y, z, t); save one entry as 3D \
and give that: python -c 'import isoflow; isoflow.write_volume(isoflow.read_volume("cells.npy", time=0), "t0.npz")'
    """
    import json
    import shlex

    from ..mesh.formats.registry import fourth_axis_words

    what, entry = fourth_axis_words(path, shape[-1])
    label_arg = "" if label is None else f", label={label!r}"
    code = f'import isoflow; isoflow.write_volume(isoflow.read_volume({json.dumps(str(path))}{label_arg}, time=0), "t0.npz")'
    return (f", shape {'x'.join(map(str, shape))} ({what}, read as x, y, z, t); save one {entry} as 3D and give "
            f"that: python -c {shlex.quote(code)}")


def refuse_time_series_store(args: argparse.Namespace, needs: str) -> None:
    """A zarr store holding a time series (4D): refused from its metadata
    with the line a 4D volume read into memory gets (its shape, and the
    command that saves one time point), before any path is chosen.

    Without it a store too large to read whole got the memory refusal
    ("crop it"), and ``flow --volumes .zarr`` the reader's "axis 't' has N
    entries": neither names the command that takes one time point.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``input``, and ``label`` where it has one.
    needs : str
        What the command needs, as its in-memory refusal says it
        ("surface needs a 3D object").

    Raises
    ------
    IsoflowError
        ``{input}: {needs}, this one is 4D, shape ...; save one time point
        ... python -c '...'``.
    """
    from ..mesh.formats.omezarr import stored_shape
    from ..mesh.formats.registry import split_dataset

    if split_dataset(args.input)[0].suffix.lower() != ".zarr":
        return
    label = getattr(args, "label", None)
    shape = stored_shape(args.input, label is not None)  # with a label, (X, Y, Z, 1) is a 3D label image
    if len(shape) == 4:
        hint = one_time_point(args.input, shape, label)
        raise IsoflowError(f"{args.input}: {needs}, this one is 4D{hint}")


#: what the refusal of a label image flowed block by block adds: that flow
#: takes no --label, so the way to one label is the flow in memory
BLOCK_LABEL = (", or select one label with --label N in the flow in memory (without --volumes .zarr), or write "
               "its voxels as a store of their own")
#: the same for a block of 0 and one other value V, of a store that holds
#: other values too (a store of 0 and V alone is flowed as V's mask): the
#: label that block offers
BLOCK_MASK = (", or select one label with --label {v} in the flow in memory (without --volumes .zarr; {v} is the one "
              "value other than 0 in that block), or write its voxels as a store of their own")


@contextlib.contextmanager
def label_options(args: argparse.Namespace, block_wise: bool = False) -> Iterator[None]:
    """A label image where a mask is expected, in memory or found block by
    block in a store: its refusal names the options of this command that
    select labels (``--label N``; ``--labels`` where the command takes it:
    not flow, which flows one object; surface's writes a surface per label;
    a 2D image is no surface's, whatever its labels); ``block_wise``: the
    flow of a store block by block, which takes neither
    (:data:`BLOCK_LABEL`, :data:`BLOCK_MASK`)."""
    from ..scale.arrays import NotBinary

    try:
        yield
    except NotBinary as exc:
        if block_wise:
            # a probability map has no label to select
            label = BLOCK_LABEL if exc.value is None else BLOCK_MASK.format(v=number_text(exc.value))
            raise NotBinary(exc.bare + ("" if exc.kind == "fractions" else label), bare=exc.bare, every=False,
                            kind=exc.kind, value=exc.value) from None
        from ..mesh.volumes import with_label_options  # (imported where needed: a command's work is not held up)

        if args.command == "surface" and exc.ndim == 2:
            # no choice of labels makes a 2D image a surface: say what would
            raise IsoflowError(f"{args.input}: surface needs a 3D object, this one is 2D") from None
        raise with_label_options(exc, every=args.command != "flow", surfaces=args.command == "surface") from None
