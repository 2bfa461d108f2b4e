"""``--labels``: every label of a label image at once, for ``info`` (one row
per label: a compact table, ``--json``, ``--csv FILE``) and ``surface`` (one
closed surface per label)."""

from __future__ import annotations

import argparse
import bisect
import contextlib
import json
import os
import re
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from ..errors import IsoflowError, counted, line_text, path_text, some_of, terminal_text
from .table_text import csv_rows, json_rows, measure_text

#: rows the terminal shows before the summary
SHOWN_ROWS = 20
#: the columns of the terminal table: (heading, column, width)
TERMINAL_COLUMNS = (("label", "label", 8), ("voxels", "voxels", 10), ("volume", "volume", 11),
                    ("area", "surface_area", 11), ("chi", "euler_characteristic", 6), ("b0", "b0", 4),
                    ("b1", "b1", 5), ("b2", "b2", 4))
#: those of a 2D table (:mod:`isoflow.digital.planar_labels`)
PLANAR_TERMINAL_COLUMNS = (("label", "label", 8), ("pixels", "voxels", 10), ("area", "area", 11),
                           ("perimeter", "perimeter", 11), ("chi", "euler_characteristic", 6), ("b0", "b0", 4),
                           ("b1", "b1", 5))

#: a label or a range A-B (A..B); ASCII digits only, as Python's int() would read "٣" (an Arabic-Indic 3) as 3
_RANGE = re.compile(r"\s*(-?[0-9]+)\s*(?:(?:-|\.\.)\s*(-?[0-9]+)\s*)?", re.ASCII)
#: the most labels a choice may hold, its ranges together (each label once): its parse, filter and list of
#: absent labels hold about 40 bytes a label at their peak, 400 MB at this many
MOST_CHOSEN = 10_000_000


def add_labels_option(p: argparse.ArgumentParser) -> None:
    """``--labels [SPEC]``: every nonzero label, or a choice of them."""
    p.add_argument("--labels", nargs="?", const="all", metavar="SPEC",
                   help="a label image: one row (info; 3D or 2D) or one surface (surface; 3D) per label; every "
                        "nonzero label, or those of SPEC, e.g. 3,7,10-20")
    p.add_argument("--names", metavar="FILE",
                   help="with --labels: the labels' names from a side file (a FreeSurfer or 3D Slicer colour "
                        "table, an ITK-SNAP label description, CSV/TSV of label and name, JSON or nnU-Net's "
                        "dataset.json), over any the image's file records")


def refuse_names_without_labels(args: argparse.Namespace) -> None:
    """One line for ``--names FILE`` without ``--labels``: one object has
    no labels to name."""
    if getattr(args, "names", None) is not None and args.labels is None:
        raise IsoflowError(f"{args.input}: --names names the labels of --labels ({args.command} {args.input} "
                           f"--labels --names {args.names}); one object has no labels to name")


def given_names(args: argparse.Namespace) -> dict[int, str] | None:
    """The names of ``--names FILE`` (None without it), read before the
    image so that a file that is no list of names is refused before any
    work."""
    from ..mesh.formats.label_names import read_label_names

    if getattr(args, "names", None) is None:
        return None
    try:
        return read_label_names(args.names)
    except IsoflowError as exc:  # the line names the file; the option says it is the names' file, not the image
        raise IsoflowError(f"--names {exc}") from None


def merged_names(args: argparse.Namespace, own: dict[int, str] | None,
                 given: dict[int, str] | None) -> dict[int, str] | None:
    """The image file's own names with those of ``--names`` over them,
    and a note (not with ``-q``) where the two name a label differently.

    Examples
    --------
    >>> args = argparse.Namespace(command="info", input="seg.nrrd", names="lut.txt", quiet=True)
    >>> merged_names(args, {1: "liver", 2: "spleen"}, {2: "Spleen", 3: "kidney"})
    {1: 'liver', 2: 'Spleen', 3: 'kidney'}
    """
    if given is None:
        return own
    own = own or {}
    changed = [f"label {k} {line_text(own[k])!r} as {line_text(v)!r}" for k, v in given.items()
               if k in own and own[k] != v]
    if changed and not args.quiet:
        line = (f"isoflow {args.command}: note: {args.input}: the names of --names {args.names} replace those the "
                f"file records for {counted(len(changed), 'label')} ({_some(changed, 4)})")
        print(terminal_text(line), file=sys.stderr)
    return dict(sorted({**own, **given}.items()))


def say_unused_names(args: argparse.Namespace, given: dict[int, str] | None, table: dict) -> None:
    """A note (not with ``-q``) counting the labels ``--names`` names
    that the image does not have: a colour table such as FreeSurfer's
    names over a thousand structures, of which a segmentation holds a few.
    Only where every label was read: with a choice, the labels not chosen
    are not looked for."""
    if given is None or args.quiet or args.labels != "all":
        return
    unused = len(set(given) - set(table["label"].tolist()))
    if unused:
        line = (f"isoflow {args.command}: note: {args.names}: {unused:,} of its {counted(len(given), 'label name')} "
                f"{'is for a label' if unused == 1 else 'are for labels'} the image does not have (not used)")
        print(terminal_text(line), file=sys.stderr)


def label_choice(text: str) -> np.ndarray | None:
    """The labels of ``--labels SPEC`` in order, each once (None: every
    nonzero label). ``A-B`` (or ``A..B``) is the range of A to B.

    The labels are one NumPy array (:func:`choice_array`), never a Python
    integer each: a range of millions costs 8 bytes a label.

    Parameters
    ----------
    text : str
        The option's value (``"all"`` for ``--labels`` alone).

    Returns
    -------
    numpy.ndarray or None
        int64 where every label asked fits it, else uint64 where every
        one is at least 0 and fits that, else Python integers (an object
        array: a choice no one 64-bit type holds).

    Examples
    --------
    >>> label_choice("3,7,10-12,7").tolist()
    [3, 7, 10, 11, 12]
    >>> label_choice("")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: --labels '': an empty choice; give labels and ranges, comma-separated \
(--labels 3,7,10-20), or --labels alone for every nonzero label
    """
    if text == "all":
        return None
    if not text.replace(",", "").strip():  # --labels "" or --labels= (a variable that came out empty)
        raise IsoflowError(f"--labels {text!r}: an empty choice; give labels and ranges, comma-separated "
                           "(--labels 3,7,10-20), or --labels alone for every nonzero label")
    runs: list[tuple[int, int]] = []  # the labels not asked before, as ranges in the order asked
    los: list[int] = []  # the labels asked so far: disjoint ranges that do not touch, in increasing order
    his: list[int] = []
    chosen = 0  # the labels of runs
    for part in text.split(","):
        match = _RANGE.fullmatch(part)
        if not match:
            raise IsoflowError(f"--labels {text}: {part.strip()!r} is not a label or a range A-B of labels")
        first, last = int(match[1]), int(match[2] if match[2] is not None else match[1])
        if last < first:
            raise IsoflowError(f"--labels {text}: the range {part.strip()} runs backwards")
        most = f"more than {MOST_CHOSEN / 1e6:g} million labels"
        if last - first + 1 > MOST_CHOSEN:
            raise IsoflowError(f"--labels {text}: the range {part.strip()} has {most}")
        new = _new_runs(first, last, los, his)
        chosen += sum(b - a + 1 for a, b in new)
        if chosen > MOST_CHOSEN:  # ranges each within the bound, together past it
            raise IsoflowError(f"--labels {text}: the choice has {most}, its ranges together")
        runs += new
    return choice_array(runs)


def _new_runs(first: int, last: int, los: list[int], his: list[int]) -> list[tuple[int, int]]:
    """The runs of ``first..last`` that the ranges ``los[i]..his[i]``
    (disjoint, not touching, increasing) do not hold, in increasing order;
    ``first..last`` is then merged into those ranges. The runs of a choice
    whose labels repeat (``7,1-3000000``) are found from its ranges alone,
    as many steps as ranges and no set of its labels.

    Examples
    --------
    >>> los, his = [5], [9]
    >>> _new_runs(1, 12, los, his), los, his
    ([(1, 4), (10, 12)], [1], [12])
    """
    i = bisect.bisect_left(his, first - 1)  # the first range that reaches first - 1 (touches or overlaps)
    j, at, runs = i, first, []
    while j < len(los) and los[j] <= last + 1:
        if los[j] > at:
            runs.append((at, min(los[j] - 1, last)))
        at = max(at, his[j] + 1)
        j += 1
    if at <= last:
        runs.append((at, last))
    lo, hi = (min(first, los[i]), max(last, his[j - 1])) if j > i else (first, last)
    los[i:j], his[i:j] = [lo], [hi]
    return runs


def choice_array(runs: list[tuple[int, int]]) -> np.ndarray:
    """The labels of ``runs`` (``(first, last)`` each, in order) as one
    array: int64 where they fit it, else uint64 where they are all at least
    0 and fit it, else an object array of Python integers.

    Parameters
    ----------
    runs : list of tuple of int
        The ranges of labels, each ``first <= last``.

    Returns
    -------
    numpy.ndarray
        Every label of every run, in order.

    Examples
    --------
    >>> choice_array([(7, 7), (1, 3)]).tolist()
    [7, 1, 2, 3]
    >>> choice_array([(2**63 - 1, 2**63)]).dtype.name
    'uint64'
    """
    lo, hi = min(a for a, _ in runs), max(b for _, b in runs)
    kind = next((np.dtype(t) for t in (np.int64, np.uint64)
                 if np.iinfo(t).min <= lo and hi <= np.iinfo(t).max), np.dtype(object))
    sizes = np.array([b - a + 1 for a, b in runs], dtype=np.int64)
    if kind.kind == "O":  # a choice no 64-bit type holds: Python's integers, as few as such a choice asks
        return np.array([v for a, b in runs for v in range(a, b + 1)], dtype=object)
    # each label is the one before plus 1, but where a run starts: one array, summed in place
    # (the steps between runs wrap around in the 64-bit type as the sums do, so they come out exact)
    out = np.ones(int(sizes.sum()), dtype=kind)
    starts = np.array([a for a, _ in runs], dtype=kind)
    ends = np.array([b for _, b in runs], dtype=kind)
    at = np.cumsum(sizes) - sizes
    out[0] = starts[0]
    out[at[1:]] = starts[1:] - ends[:-1]
    return np.cumsum(out, out=out)


def reads_as_choice(text: str) -> bool:
    """Whether ``text`` is written as ``--labels SPEC`` is (labels and
    ranges, comma-separated); else it is most likely the input, taken by
    the option's optional SPEC."""
    return all(_RANGE.fullmatch(part) for part in text.split(","))


def refuse_single_label(args: argparse.Namespace) -> None:
    """One line when --labels comes with options it cannot take."""
    if getattr(args, "label", None) is not None:
        raise IsoflowError(f"{args.input}: --label selects one object, --labels every label: give one of them")
    if getattr(args, "gpu", False):
        raise IsoflowError(f"{args.input}: --labels runs on the host, not with --gpu")
    from .inputs import refuse_mesh_options, refuse_points_option

    refuse_mesh_options(args, "a label image")
    refuse_points_option(args, "a label image")


def read_table(args: argparse.Namespace, surfaces: bool = True):
    """The label image named on the command line and its table, with only
    the labels that occur (a warning names those asked for that do not):
    ``(about, connectivity, table, image, absent)``, ``about`` its shape,
    type, voxel size, origin, their length unit and anatomical frame
    (``space``) (and for ``surface``,
    ``corners``: :func:`isoflow.mesh.export.check_float64_corners` of the
    image, which refused a placement no surface file holds), ``image``
    None for a zarr store (read block by block), ``absent`` the labels
    asked for that have no row, in the order asked."""
    from ..digital.connectivity import resolve_connectivity
    from ..digital.label_table import label_dtype, label_table
    from ..mesh.formats.omezarr import stored_ndim
    from ..mesh.volumes import read_labels
    from .inputs import say_plate
    from .progress import progress_bar

    refuse_single_label(args)
    asked = label_choice(args.labels)
    # info reads a 3D store block by block; a 2D one, and every store whose
    # surfaces are written, whole (as a file is, refused up front where it
    # would not fit)
    blocks = getattr(args, "command", "") != "surface" and (
        (is_store(args.input) and stored_ndim(args.input) != 2) or in_hdf5_slabs(args.input))
    given = given_names(args)
    say_declared_labels(args)
    image = None if blocks else read_labels(args.input)
    names = None if image is None else merged_names(args, image.names, given)
    if given is None and (getattr(args, "command", "") == "surface" or image is None or not image.names):
        # info's table gives each label's name in its name column; surface's files are label_N
        say_segments(args, None if image is None else image.names)
    ndim = 3 if image is None else image.array.ndim
    corners = None
    if image is not None and getattr(args, "command", "") == "surface":
        from ..mesh.export import check_float64_corners

        # a placement no surface file holds: refused before the table, whose boxes would only be warned of
        corners = check_float64_corners(args.input, image.origin, image.spacing, image.array.shape)
    if ndim == 2 and getattr(args, "command", "") == "surface":
        raise IsoflowError(f"{args.input}: surface needs a 3D label image, this one is 2D (isoflow info "
                           f"{args.input} --labels gives its table)")
    try:
        conn = resolve_connectivity(ndim, args.connectivity)
    except IsoflowError as exc:
        raise exc.at(args.input) from None
    # a long choice (a range of millions) is a filter on the whole table:
    # a row of zeros per label asked would cost more than the image
    every = asked is not None and len(asked) > CHOICE_ROWS

    def table_of(chosen, background=False):
        if image is None:
            return table_of_store(args, conn, chosen, surfaces, given, background)
        # the labels' type, as label_table reads them: a bool image as uint8
        kind = label_dtype(image.array.dtype) if image.array.dtype == np.bool_ else image.array.dtype
        about = {"shape": image.array.shape, "dtype": kind, "spacing": image.spacing,
                 "origin": image.origin, "unit": image.unit, "space": image.space,
                 **({} if corners is None else {"corners": corners})}
        wanted = None if chosen is None else _by_type(args.input, chosen, image.array.dtype)[0]
        try:
            with progress_bar(args, "label table") as show:
                return about, label_table(image.array, conn, pitch=image.spacing, origin=image.origin, labels=wanted,
                                          surfaces=surfaces, threads=getattr(args, "threads", None), names=names,
                                          background=background, progress=show)
        except IsoflowError as exc:  # work that would not fit: the line names the file, as a store's does
            raise exc.at(args.input) from None

    # the table of every label has no row of the background, which a choice of 0 asks for: the same one pass
    # gives it (a second pass for 0 alone read the whole image again)
    about, table = table_of(None if every else asked, background=every and bool((asked == 0).any()))
    # a slice saved as (X, Y, 1) is a plate here: info's note gives the line that saves its 2D table's image
    say_plate(args, tuple(about["shape"]))
    # an image without voxels (shape 0x3x3) has no label, as an all-0 one has none: the same empty table, as
    # label_table gives, and the warning says which it is (not "all 0": there is no voxel to hold a label)
    cells = "pixels" if len(about["shape"]) == 2 else "voxels"
    empty = 0 in about["shape"]
    why = (f"the image has no {cells} (shape {'x'.join(map(str, about['shape']))})" if empty else
           "no nonzero label: the image is all 0")
    none = np.zeros(0, np.int64)
    within, beyond = (none, none) if asked is None else _by_type(args.input, asked, about["dtype"])
    if every:
        table, missing = chosen_rows(table, within)
    present = table["voxels"] > 0
    absent = none
    if every or not present.all() or len(beyond):
        absent = in_order_asked((missing if every else table["label"][~present]), beyond, asked)
        if not present.any():
            raise IsoflowError(f"{args.input}: none of the labels asked for occur ({_some(absent)})"
                               + (f": {why}" if empty else ""))
        # a warning, which --quiet keeps: the table lacks rows that were asked for
        verb = "does" if len(absent) == 1 else "do"
        print(terminal_text(f"isoflow {args.command}: warning: {args.input}: {len(absent)} of the labels asked for {verb} not "
                            f"occur ({_some(absent)})"), file=sys.stderr)
        table = {k: v[present] for k, v in table.items()}
    if not len(table["label"]):
        if args.command == "surface":  # no surface to write
            raise IsoflowError(f"{args.input}: {why}")
        # an empty segmentation (no lesion found) is an answer: its table has no row, as
        # label_table's and regionprops_table's, and a warning (kept by --quiet) says why
        print(terminal_text(f"isoflow {args.command}: warning: {args.input}: {why}; the table has no row"), file=sys.stderr)
    say_unused_names(args, given, table)
    if given is not None and args.command == "surface" and "name" in table:
        # the label_N files' names, of the labels written alone (a colour table names hundreds)
        say_segments(args, {k: v for k, v in zip(table["label"].tolist(), table["name"].tolist()) if v}, True)
    return about, conn, table, image, absent


def say_declared_labels(args: argparse.Namespace) -> None:
    """A note where the input is an OME-Zarr image that keeps its
    segmentations in its ``labels/`` group: ``--labels`` of the image
    itself takes its intensities for labels, and the note names the
    segmentations (``IMAGE.zarr:labels/NAME``) that hold the labels.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``command``, ``input`` and ``quiet``.
    """
    from ..scale.chunks import declared_labels

    names = declared_labels(args.input) if is_store(args.input) and not args.quiet else []
    if names:
        store = str(args.input).rstrip("/")
        print(terminal_text(f"isoflow {args.command}: note: {args.input}: an OME-Zarr image whose labels/ group holds "
                            f"{counted(len(names), 'segmentation')} ({_some(names)}); this reads the image itself: for a "
                            f"segmentation's labels, give {store}:labels/{names[0]}"), file=sys.stderr)


def say_segments(args: argparse.Namespace, names: dict[int, str] | None = None, given: bool = False) -> None:
    """A note where the input is a 3D Slicer segmentation (``.seg.nrrd``,
    a layer of it read): which label value is which structure, the names
    its header gives the segments, since the ``label_N`` surfaces go by
    value; for ``surface``, a note of the ``names`` of any other label
    image that records them. ``info``'s table says them in its ``name``
    column, and has the note only where it has no such column (a layer of
    no segment).

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``command``, ``input`` and ``quiet``.
    names : dict of int to str, optional
        The image's label names, where its file records them.
    given : bool, optional
        Whether ``names`` include those of ``--names FILE``, which take
        the place of a 3D Slicer segmentation's own.
    """
    from ..mesh.formats.registry import split_dataset
    from ..mesh.formats.slicer import Segment, layer_segments, segment_names

    path, layer = split_dataset(args.input)
    if args.quiet:
        return
    if path.name.lower().endswith(".seg.nrrd") and not given:
        said = layer_segments(path, layer)
        if said:
            print(terminal_text(f"isoflow {args.command}: note: {args.input}: 3D Slicer segments {said}"), file=sys.stderr)
    elif names and getattr(args, "command", "") == "surface":
        said = segment_names([Segment(name, 0, label) for label, name in names.items()], 0)
        print(terminal_text(f"isoflow {args.command}: note: {args.input}: label names {said}"), file=sys.stderr)


def in_order_asked(missing: np.ndarray, beyond: np.ndarray, asked: np.ndarray) -> np.ndarray:
    """The labels asked for that have no row, in the order asked: those
    the image's type holds but no voxel has (``missing``, in that order)
    and those it cannot hold (``beyond``, in that order too).

    Parameters
    ----------
    missing, beyond : numpy.ndarray
        Labels of ``asked``, each in the order asked.
    asked : numpy.ndarray
        The choice (:func:`label_choice`).

    Returns
    -------
    numpy.ndarray
        Those of ``asked`` that are in either, in ``asked``'s type.

    Examples
    --------
    >>> in_order_asked(np.array([7, 9]), np.array([300]), np.array([7, 300, 3, 9])).tolist()
    [7, 300, 9]
    """
    if not len(beyond) or not len(missing):  # each already in the order asked
        return beyond if not len(missing) else missing
    # (missing's labels are asked's, so asked's type holds them)
    return asked[np.isin(asked, missing.astype(asked.dtype)) | np.isin(asked, beyond)]


def is_store(path) -> bool:
    """Whether the input is a zarr store (``IMAGE.zarr:LEVEL`` too), read
    block by block."""
    from ..mesh.formats.registry import split_dataset

    return split_dataset(path)[0].suffix.lower() == ".zarr"


def in_hdf5_slabs(path: str) -> bool:
    """Whether the input is an HDF5 label image whose table is read a slab
    at a time: one of three axes that would not fit in memory whole (one
    that fits is read whole, the sooner).

    Examples
    --------
    >>> in_hdf5_slabs("seg.nii.gz")  # no HDF5 file: not opened
    False
    """
    from ..mesh.formats import hdf5

    return is_hdf5(path) and not hdf5.fits_whole(path)


def is_hdf5(path: str) -> bool:
    """Whether the input is an HDF5 file, by its suffix, that is there and
    may be read (one that is not, a URL, a name too long, a folder closed
    on the way, is refused where every input is, in the same words),
    without opening it.

    Examples
    --------
    >>> is_hdf5("seg.nii.gz"), is_hdf5("absent.h5:/seg"), is_hdf5("a" * 300 + ".h5")
    (False, False, False)
    """
    from ..mesh.formats.registry import format_for, split_dataset

    file = split_dataset(path)[0]
    fmt = format_for(file)
    if fmt is None or fmt.name != "HDF5":
        return False
    try:
        return file.is_file() and os.access(file, os.R_OK)
    except OSError:  # (is_file says False for a missing file, and raises for these)
        return False


def table_of_store(args: argparse.Namespace, conn: int, asked, surfaces: bool, given: dict[int, str] | None = None,
                   background: bool = False):
    """The table of a zarr store (or an HDF5 dataset that would not fit
    in memory), one layer of blocks at a time (never the whole image in
    memory), with a progress bar; the image as read (its shape, type and
    placement, no array); ``given``, the names of ``--names``, over the
    store's own; ``background``, with ``asked`` None, the row of label 0
    too."""
    from ..digital.label_blocks import grouped_layers, label_table_blocks
    from ..digital.label_table import label_dtype, with_names
    from ..digital.lattice import DigitalObject
    from ..mesh.formats import hdf5, omezarr
    from ..scale.compiled import using
    from .progress import progress_bar

    slabs = omezarr.LabelSlabs(args.input) if is_store(args.input) else hdf5.LabelSlabs(args.input)
    try:
        place = DigitalObject.placement(3, pitch=slabs.pitch, origin=slabs.origin)
    except IsoflowError as exc:
        raise exc.at(args.input) from None
    wanted = None if asked is None else _by_type(args.input, asked, slabs.dtype)[0]
    with using(getattr(args, "threads", None)), progress_bar(args, "layers of blocks") as show:
        try:
            # layers of thin chunks read a few at a time: slabs of a million voxels or more, on threads
            area = int(np.prod([slabs.shape[a] for a in slabs.axes[1:]], dtype=np.int64))
            table = label_table_blocks(slabs, conn, layers=grouped_layers(slabs.layers, area), axes=slabs.axes,
                                       pitch=place.spacing, origin=place.origin, labels=wanted, surfaces=surfaces,
                                       progress=show, background=background)
        except IsoflowError as exc:  # a voxel that is no label, a slab that would not fit
            named = (exc.command_line or str(exc)).startswith(f"{slabs.where}: ")  # (a damaged chunk's names it)
            raise (exc if named else exc.at(args.input)) from None
    # a float store's labels are int64, as a float file's are read (read_labels): the same --json
    kind = label_dtype(slabs.dtype) if np.dtype(slabs.dtype).kind in "fb" else slabs.dtype
    return {"shape": slabs.shape, "dtype": kind, "spacing": place.spacing, "origin": place.origin,
            "unit": slabs.unit, "space": slabs.space}, with_names(table, merged_names(args, slabs.names, given))


#: a choice of more labels than this is read as a filter on the table of every label (:func:`chosen_rows`)
CHOICE_ROWS = 1 << 16


def chosen_rows(table: dict, chosen: np.ndarray) -> tuple[dict, np.ndarray]:
    """The rows of ``table`` (every label present, in increasing order)
    whose labels are ``chosen``, in the order chosen, and the labels
    chosen that have no row (in that order too).

    Examples
    --------
    >>> rows, missing = chosen_rows({"label": np.array([2, 5, 9]), "voxels": np.array([4, 1, 7])}, np.array([9, 3, 2]))
    >>> rows["label"].tolist(), rows["voxels"].tolist(), missing.tolist()
    ([9, 2], [7, 4], [3])
    """
    labels = table["label"]
    wanted = np.asarray(chosen, dtype=labels.dtype)  # each within the type (_by_type)
    order = np.argsort(wanted, kind="stable")
    at = np.minimum(np.searchsorted(wanted[order], labels), len(wanted) - 1)
    hit = wanted[order][at] == labels
    place = order[at[hit]]  # each row's place in the choice
    rows = np.flatnonzero(hit)[np.argsort(place, kind="stable")]
    found = np.zeros(len(wanted), bool)
    found[place] = True
    return {k: v[rows] for k, v in table.items()}, wanted[~found]


def _by_type(name, asked: np.ndarray, dtype) -> tuple[np.ndarray, np.ndarray]:
    """The labels asked for that the image's type can hold, and those it
    cannot (they cannot occur), each in the order asked; an error when it
    holds none of them.

    Parameters
    ----------
    name : str
        The image, as the error names it.
    asked : numpy.ndarray
        The labels asked for (:func:`label_choice`).
    dtype : numpy.dtype
        The image's type (a float image's labels are read as integers:
        :func:`~isoflow.digital.label_table.label_dtype`).

    Returns
    -------
    tuple of numpy.ndarray
        ``(within, beyond)``: ``within`` in the labels' type, ``beyond``
        in ``asked``'s.

    Examples
    --------
    >>> within, beyond = _by_type("cells.tif", np.array([3, 300, -1, 255]), np.uint8)
    >>> within.tolist(), within.dtype.name, beyond.tolist()
    ([3, 255], 'uint8', [300, -1])
    """
    from ..digital.label_table import label_dtype

    kind = label_dtype(dtype)
    info = np.iinfo(kind)
    lo, hi = int(info.min), int(info.max)
    if asked.dtype.kind != "O":  # the bounds as asked's type holds them, so that NumPy compares them exactly
        held = np.iinfo(asked.dtype)
        lo, hi = max(lo, int(held.min)), min(hi, int(held.max))
    keep = np.zeros(len(asked), bool) if lo > hi else \
        (asked >= np.asarray(lo, asked.dtype)) & (asked <= np.asarray(hi, asked.dtype))
    if not keep.any():
        raise IsoflowError(f"{name}: none of the labels asked for occur ({_some(asked)}): its labels are "
                           f"{kind} ({info.min} to {info.max})")
    return asked[keep].astype(kind, copy=False), asked[~keep]


def _some(values, most: int = 8) -> str:
    # each value as it is: NumPy makes float64 of ints that no one integer type
    # holds together (2**63 beside 5, or beside -1), which would print 9.223372036854776e+18
    return some_of(values.tolist() if isinstance(values, np.ndarray) else list(values), most)


def cmd_info_labels(args: argparse.Namespace) -> int:
    """``isoflow info LABELS --labels``."""
    from ..mesh.outputs import check_output_path, check_picture_path, output_set, refuse_nameless
    from ..scale.compiled import using

    to_stdout = args.csv == "-"
    if to_stdout and args.json:
        raise IsoflowError(f"{args.input}: --csv - and --json both print on stdout: give one of them")
    if args.csv and not to_stdout:
        refuse_nameless(args.csv, (".csv",), "table")  # "--csv .csv" would write a hidden file of no name
        check_output_path(args.csv, args.force)
    if args.png:
        check_picture_path(args.png, args.force)
        if args.csv and not to_stdout and Path(args.csv).resolve() == Path(args.png).resolve():
            raise IsoflowError(f"{args.png}: --csv and --png name one file; give each its own")
    about, conn, table, _, absent = read_table(args, surfaces=not args.no_surfaces)
    threads = getattr(args, "threads", None)
    # the table and its picture replaced together: a failure between them leaves both as they were, and an
    # interrupt's line names both
    with output_set(f"{args.csv} and {args.png}") if args.png and args.csv and not to_stdout else contextlib.nullcontext():
        if args.csv and not to_stdout:
            with using(threads):  # a large table's text is made on the passes' threads too
                write_csv(args.csv, table, args.force)
        if args.png:
            draw_table(args, about, conn, table)
    if to_stdout:  # the table alone on stdout, for a pipe
        with using(threads):
            sys.stdout.writelines(csv_rows(table))
        return 0
    if args.json:
        # as bytes where standard output takes them (a table of millions of rows is tens of megabytes of text)
        binary = hasattr(sys.stdout, "write_ascii")
        with using(threads):
            pieces = json_text(args.input, about, conn, table, absent, binary)
            if binary:
                sys.stdout.write_ascii(pieces)
            else:
                sys.stdout.writelines(pieces)
        sys.stdout.write("\n")
        return 0
    # the names escaped as a label's name is: a line break would split the report's lines, an escape act on the terminal
    print(format_table(terminal_text(args.input), about, conn, table))
    if args.csv:
        print(f"{terminal_text(args.csv)}: {len(table['label'])} rows, {len(table)} columns")
    if args.png:
        print(f"{terminal_text(args.png)}: picture of {counted(len(table['label']), 'label')} (Betti numbers, "
              f"{'area, perimeter' if len(about['shape']) == 2 else 'volume, surface area'})")
    return 0


def draw_table(args: argparse.Namespace, about: dict, conn: int, table: dict) -> None:
    """``--png``: the table as a picture
    (:func:`isoflow.mesh.label_picture.render_label_table`), its title
    naming the file and the choice of labels.

    Parameters
    ----------
    args : argparse.Namespace
        The command's arguments: ``input``, ``labels`` and ``png``.
    about : dict
        The image as read (:func:`read_table`): its ``unit`` names the axes.
    conn : int
        The labels' connectivity.
    table : dict
        The rows drawn, those of the labels that occur.
    """
    from ..mesh.formats.registry import split_dataset
    from ..mesh.label_picture import render_label_table

    # the file's name without its folders, a dataset or level of it kept (cells.zarr:labels/nuclei)
    path, dataset = split_dataset(args.input)
    name = path_text(path.name) + (f":{dataset}" if dataset is not None else "")
    name += "" if args.labels == "all" else f" --labels {args.labels}"
    render_label_table(table, args.png, name=name, connectivity=conn, unit=about["unit"])


def json_text(name, about: dict, conn: int, table: dict, absent: np.ndarray, binary: bool = False) -> Iterator:
    """What ``--json`` prints, in pieces: one object, the image, ``absent``
    (the labels asked for that have no row: :func:`json_list`) and then
    ``labels``, one object per label (NaN as null); str, or with
    ``binary`` the text's ASCII bytes (bytes-like: JSON escapes every other
    character).

    Examples
    --------
    >>> about = {"shape": (2, 2, 2), "dtype": np.uint8, "spacing": np.ones(3), "origin": np.zeros(3), "unit": None,
    ...          "space": None}
    >>> text = "".join(json_text("a.npy", about, 6, {"label": np.array([1])}, np.zeros(0, np.int64)))
    >>> json.loads(text)["labels"], b"".join(json_text("a.npy", about, 6, {"label": np.array([1])},
    ...                                                np.zeros(0, np.int64), binary=True)) == text.encode()
    ([{'label': 1}], True)
    """
    # the type by its name, in any byte order: a big-endian file's labels (NRRD's
    # "endian: big", an old Analyze/NIfTI) are int16 as a little-endian file's are, not ">i2"
    head = {"input": path_text(name), "shape": [int(s) for s in about["shape"]], "dtype": np.dtype(about["dtype"]).name,
            "pitch": about["spacing"].tolist(), "origin": about["origin"].tolist(), "unit": about["unit"],
            "space": about["space"], "connectivity": conn}
    texts = [json.dumps(head)[:-1] + ', "absent": ', *json_list(absent), ', "labels": ']
    yield from (text.encode("ascii") for text in texts) if binary else texts
    yield from json_rows(table, binary)
    yield b"}" if binary else "}"


#: labels :func:`json_list` makes text of at a time
JSON_LIST_CHUNK = 1 << 16


def json_list(values: np.ndarray) -> Iterator[str]:
    """The JSON text of a list of integers, in pieces, as ``json.dumps``
    writes the list (``[7, 300, 9]``, ``[]``), a chunk of them at a time:
    an ``absent`` of millions never becomes a Python integer each at once.

    Parameters
    ----------
    values : numpy.ndarray
        Integers (any integer type, or Python's in an object array).

    Returns
    -------
    Iterator of str
        Pieces whose concatenation is the list's JSON.

    Examples
    --------
    >>> "".join(json_list(np.array([7, 300, 9], np.uint16)))
    '[7, 300, 9]'
    >>> "".join(json_list(np.zeros(0, np.int64)))
    '[]'
    """
    yield "["
    for start in range(0, len(values), JSON_LIST_CHUNK):
        yield (", " if start else "") + ", ".join(map(str, values[start:start + JSON_LIST_CHUNK].tolist()))
    yield "]"


def write_csv(path, table: dict, force: bool) -> None:
    """The full table as CSV (genera as ``0;1``, NaN empty), written whole
    or not at all."""
    from ..mesh.outputs import atomic_write

    with atomic_write(path, "w", newline="", encoding="utf-8") as fh:
        for text in csv_rows(table):
            fh.write(text)


#: the measures of a row that are its cells times the cell's size (volume, area in 2D): beyond float64,
#: their figure is worked out from the cells, as info's report gives it
CELL_MEASURES = ("volume", "area")


def _cell(table: dict, column: str, row: int, width: int, spacing) -> str:
    value = table[column][row]
    if isinstance(value, (float, np.floating)):
        # a measure past float64 (voxels of 1e200) as info's report says it, never a bare inf
        voxels = int(table["voxels"][row]) if column in CELL_MEASURES else None
        return f"{measure_text(float(value), voxels, list(spacing), len(spacing)):>{width}}"
    return f"{value:>{width}}"


def format_table(name, about: dict, conn: int, table: dict) -> str:
    """The compact table: the first rows, then a summary of all."""
    n = len(table["label"])
    # the unit of the world columns (bbox, centroid; area, volume in its square, cube), where the file says it
    pitch = "x".join(f"{p:g}" for p in about["spacing"]) + (f" {about['unit']}" if about["unit"] else "") + (
        f", frame {about['space']}" if about["space"] else "")
    shape = "x".join(map(str, about["shape"]))
    planar = len(about["shape"]) == 2
    lines = [f"{name}: {counted(n, 'label')}, shape {shape}, {'pixel' if planar else 'voxel'} {pitch}, "
             f"{conn}-connectivity"]
    surfaces = "genera" in table
    shown = PLANAR_TERMINAL_COLUMNS if planar else TERMINAL_COLUMNS
    # every column as wide as its widest shown value (64-bit labels, a
    # billion voxels), so that the columns stay aligned
    rows = range(min(n, SHOWN_ROWS))
    step = about["spacing"]
    shown = tuple((h, c, max([w] + [len(_cell(table, c, r, 0, step)) + 1 for r in rows])) for h, c, w in shown)
    head = "".join(f"{h:>{w}}" for h, _, w in shown)
    # the genera's cells padded to one width where a name follows them, so that the names line up
    cells = [f"  {table['surfaces'][r]} ({_genera(table['genera'][r])})" for r in rows] if surfaces else []
    wide = max([len("  surfaces (genera)")] + [len(c) for c in cells]) if "name" in table else 0
    lines.append(head + (f"{'  surfaces (genera)':<{wide}}" if surfaces else "") + ("  name" if "name" in table else ""))
    for r in rows:
        row = "".join(_cell(table, c, r, w, step) for _, c, w in shown)
        if surfaces:
            row += f"{cells[r]:<{wide}}"
        if "name" in table:
            row += f"  {line_text(str(table['name'][r]))}"  # a tab or an escape of a file's name is not acted on
        lines.append(row.rstrip())
    if n > SHOWN_ROWS:
        lines.append(f"  ... {n - SHOWN_ROWS} more labels (--json, or --csv FILE, for the full table)")
    lines.append(summary(table))
    return "\n".join(lines)


def _genera(genera: tuple) -> str:
    """A label's genera as the terminal table shows them: the first six."""
    return ",".join(map(str, genera[:6])) + (",..." if len(genera) > 6 else "")


def summary(table: dict) -> str:
    """One line over every label."""
    n = len(table["label"])
    planar = "perimeter" in table
    parts = [counted(n, "label"), counted(int(table["voxels"].sum()), "pixel" if planar else "voxel")]
    for column, what in (("b0", "in several components"), ("b1", "with holes" if planar else "with tunnels"),
                         ("b2", "with cavities")):
        if column not in table:
            continue
        count = int(np.count_nonzero(table[column] > (1 if column == "b0" else 0)))
        parts.append(f"{count} {what}")
    if "pinched_vertices" in table:
        parts.append(f"{int(np.count_nonzero(table['pinched_vertices']))} with pinched vertices")
    return "  all: " + ", ".join(parts)


def surface_outputs(args: argparse.Namespace):
    """Where ``surface --labels`` writes: ``("glb", path)`` for one glTF
    with a node per label, or ``("dir", directory, suffix)`` for a file per
    label (``-o DIR/`` with ``--suffix``), checked before any work."""
    from ..mesh.export import SURFACE_SUFFIXES
    from ..mesh.outputs import check_output_path, check_writable_dir, file_suffix

    out = str(args.output)
    if out.endswith(("/", "\\")) or Path(out).is_dir():
        refuse_suffixed_directory(out, args.suffix)
        named = f"{Path(out)}/"  # a directory of a file per label is named DIR/, as every line of the run names it
        suffix = (args.suffix or "").lower()
        suffix = suffix if suffix.startswith(".") or not suffix else "." + suffix
        if suffix not in SURFACE_SUFFIXES:
            given = f", not {args.suffix}" if args.suffix else ""
            raise IsoflowError(f"{named}: a file per label needs --suffix {'|'.join(SURFACE_SUFFIXES)}{given}")
        directory = Path(out)
        if not directory.is_dir() and (directory.exists() or directory.is_symlink()):  # mkdir would fail, after the work
            raise IsoflowError(f"{named}: exists and is not a directory; give a new or existing directory for a file per label")
        if not directory.is_dir():
            check_writable_dir(directory.parent, f"the directory {directory.name}")
        return "dir", directory, suffix
    if args.suffix:
        if not Path(out).suffix:  # a directory meant, not there yet: only the slash says so
            raise IsoflowError(f"{out}: no such directory; -o {out}/ makes it, for a file per label (--suffix)")
        raise IsoflowError(f"{out}: --suffix names the files of -o DIR/; one file holds every label as .glb")
    given = file_suffix(Path(out).name) or Path(out).suffix
    if given.lower() != ".glb":
        # refused before check_output_path, whose list of one surface's suffixes (.ply, ...) and whose "exists;
        # pass --force" of an earlier .ply would each lead to a second refusal, here
        stem = out[: len(out) - len(given)]
        per_label = given.lower() if given.lower() in SURFACE_SUFFIXES else ".ply"
        raise IsoflowError(f"{out}: a surface per label is written into one .glb (a node per label) or into a "
                           f"directory (a file per label); give -o {stem}.glb or -o {stem}/ --suffix {per_label}")
    return "glb", check_output_path(out, args.force, suffixes=(".glb",), what="surface")


def refuse_suffixed_directory(out: str, suffix: str | None) -> None:
    """Refuse ``-o out.ply/`` where no directory ``out.ply`` is there yet:
    the slash asks for a directory, the name for a file, and a directory
    named like a mesh file is what neither reading meant (a program that
    opens or lists ``*.ply`` takes it for a file). A directory of that
    name that is already there is the user's own and is written into.

    Parameters
    ----------
    out : str
        ``-o`` as given.
    suffix : str or None
        ``--suffix`` as given, for the way out the line names.

    Raises
    ------
    IsoflowError
        One line naming ``out``, the suffix and both ways out.

    Examples
    --------
    >>> refuse_suffixed_directory("/no/such/cells/", ".ply")
    >>> refuse_suffixed_directory("/no/such/cells.ply/", None)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    isoflow.errors.IsoflowError: /no/such/cells.ply/: the slash asks for a directory and .ply for a file; give ...
    """
    from ..mesh.export import SURFACE_SUFFIXES
    from ..mesh.outputs import file_suffix

    directory = Path(out)
    given = file_suffix(directory.name)
    if given is None or directory.is_dir():
        return
    stem = str(directory)[: -len(given)]
    per_label = suffix or (given if given in SURFACE_SUFFIXES else ".ply")
    raise IsoflowError(f"{out}: the slash asks for a directory and {directory.name[-len(given):]} for a file; "
                       f"give -o {stem}{os.sep} --suffix {per_label} for a file per label, or -o {stem}.glb "
                       "for one file of every label")


def cmd_surface_labels(args: argparse.Namespace) -> int:
    """``isoflow surface LABELS --labels -o OUT.glb`` (or ``-o DIR/ --suffix``):
    every label's mesh in its box, boxes meshed many at a time
    (:func:`isoflow.digital.label_meshes.label_batches`), the glTF's
    columns computed per batch."""
    if args.png:
        raise IsoflowError(f"{args.input}: --png draws one surface, not --labels")
    target = surface_outputs(args)
    if target[0] == "glb" and (args.ascii or args.triangulate):
        raise IsoflowError(f"{target[1]}: --ascii and --triangulate shape the files of -o DIR/; a .glb holds "
                           "triangles in binary")
    if args.ascii and target[2] != ".ply":
        raise IsoflowError(f"{target[1]}/: --ascii applies to .ply files only, not --suffix {target[2]}")
    if target[0] == "glb":
        return surface_labels(args, target)
    with label_directory(target[1]):
        return surface_labels(args, target)


@contextlib.contextmanager
def label_directory(directory: Path) -> Iterator[None]:
    """The directory of ``surface --labels -o DIR/`` made before the work:
    ``os.access`` answers for root as if it could write anywhere, so
    making it (``/sys/out/``, a read-only mount) is the one test that a
    file per label can be written there. A failure is one line naming the
    directory; a directory made here is removed again, if still empty,
    when the work fails.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp()) / "labels"
    >>> with label_directory(d):
    ...     d.is_dir()
    True
    >>> try:
    ...     with label_directory(d / "more"):
    ...         raise IsoflowError("failed")
    ... except IsoflowError:
    ...     (d / "more").exists()
    False
    """
    from ..mesh.outputs import make_output_dir

    try:
        made = make_output_dir(directory)
    except OSError as exc:
        raise IsoflowError(f"{directory}/: cannot make the directory for a file per label "
                           f"({exc.strerror or type(exc).__name__})") from None
    try:
        yield
    except BaseException:
        if made:  # the directory this run made, left empty: a file of the set written keeps it
            with contextlib.suppress(OSError):
                directory.rmdir()
        raise


def surface_labels(args: argparse.Namespace, target) -> int:
    """:func:`cmd_surface_labels` once its outputs are checked (and
    ``-o DIR/`` made): the table, the meshes, the files."""
    from ..scale.memory import budget_held

    about, conn, table, image, _ = read_table(args)
    # the memory available read once, with the image in memory, for every check that follows (each label's
    # mesh, each file's read-back): not once a file, which costs a read of /proc and the control groups each
    with budget_held():
        return surfaces_of_table(args, target, about, conn, table, image)


def surfaces_of_table(args: argparse.Namespace, target, about: dict, conn: int, table: dict, image) -> int:
    """:func:`surface_labels` once the table is read: the meshes, the
    files, the lines that say what was written."""
    from ..digital.label_meshes import label_batches
    from ..mesh.export import float32_transform_problem, float64_move_note
    from ..mesh.float32 import float64_moved
    from ..mesh.outputs import check_output_path
    from .imports_ahead import import_ahead
    from .progress import TimeNote, progress_bar

    check_surfaces_fit(args.input, table, image.spacing, args.labels == "all")
    corners = about["corners"]  # read_table checks the placement's corners before it counts the table
    names = [f"label_{v}" for v in table["label"].tolist()]
    if target[0] == "dir":
        files = [target[1] / f"{name}{target[2]}" for name in names]
        for f in files:
            if (f.exists() or f.is_symlink()) and not args.force:
                check_output_path(f, args.force)
    # each label's box in voxels, from the table's world corners
    lo, hi = (np.round((np.stack([table[f"bbox-{d}"] for d in axes], axis=1) - image.origin) / image.spacing)
              .astype(np.int64) for axes in ((0, 1, 2), (3, 4, 5)))
    meshes: list = [None] * len(names)
    glb_parts: list = []  # (SceneParts of a batch, its labels' rows)
    with progress_bar(args, "label surfaces", estimate=True) as show:
        # one count: each label meshed, then each written (a file each) or read back
        total = len(names) * (2 if target[0] == "dir" or not args.no_check else 1)
        report = None if show is None else (lambda done, _: show(len(names) + done, total))
        # trimesh, for the read-back, imported while the labels are meshed
        ahead = None if args.no_check else import_ahead("trimesh")
        meshed = 0
        for batch in label_batches(image.array, table["label"], lo, hi, conn):
            meshed += len(batch.rows)
            _take_batch(args, target, batch, table, names, lo, image, meshes, glb_parts)
            if show is not None:
                show(meshed, total)
        expected = None if args.no_check or target[0] != "glb" else scene_expected(table, names, image.spacing,
                                                                                  float64_moved(corners))
        # what of a .glb's node transforms float32 cannot hold: said with the note on them
        beyond = float32_transform_problem(image.spacing, image.array.shape, image.origin)
        if isinstance(show, TimeNote):  # the writing (or the read-back) paces the rest, from its first label on
            show.phase()
        problems, faces, unread = write_label_surfaces(args, target, meshes, glb_parts, report, expected, beyond, ahead)
    where = target[1] if target[0] == "glb" else f"{target[1]}/ ({counted(len(meshes), target[2] + ' file')})"
    # a read-back skipped for memory is said in its note, and the line claims only the files read back
    read = "" if args.no_check or problems or unread >= len(meshes) else (
        ", each read back by trimesh as isoflow counts it" if not unread else
        f", {len(meshes) - unread:,} of them read back by trimesh as isoflow counts it")
    print(terminal_text(f"{where}: {counted(len(meshes), 'label')}, {faces}, one closed surface mesh per label{read}"))
    moved = float64_move_note(target[1] if target[0] == "glb" else f"{target[1]}/", corners)
    if moved:  # every file's corners moved by float64 itself
        print(terminal_text(f"isoflow surface: warning: {moved}"), file=sys.stderr)
    for line in problems:
        print(terminal_text(f"isoflow surface: error: {line}"), file=sys.stderr)
    return 1 if problems else 0


#: bytes a voxel face of the labels' surfaces certainly holds until they are
#: written: its vertex (float64 position, float32 attributes) and its two
#: triangles, in the meshes or the scene's columns and again as read back
#: (measured peaks are higher still), so that only work that cannot fit is
#: refused before the first mesh
SURFACE_BYTES_PER_FACE = 64


def check_surfaces_fit(name, table: dict, spacing, every: bool, budget: int | None = None) -> None:
    """Refuse up front, in one line, surfaces that would not fit in memory:
    every label's mesh is held until the set is written, about
    :data:`SURFACE_BYTES_PER_FACE` a voxel face (their count from the
    table's ``surface_area``, each face taken as the largest a voxel has,
    so never more than there are). The line says how many of the labels
    fit, in the table's order, and the ``--labels`` choice of them where
    ``every`` label was asked for (the rows ascend).

    Parameters
    ----------
    name : str or os.PathLike
        The label image, as the line names it.
    table : dict
        Its rows to be meshed (:func:`read_table`).
    spacing : array_like
        The voxel size per axis.
    every : bool
        Whether the rows are every label (a bare ``--labels``).
    budget : int, optional
        Bytes that may be used; the memory available now by default.

    Examples
    --------
    >>> table = {"label": np.array([1, 2, 5]), "surface_area": np.array([6e3, 6e3, 6e3])}
    >>> try:
    ...     check_surfaces_fit("seg.npy", table, np.ones(3), True, budget=10**6)
    ... except IsoflowError as exc:
    ...     print(str(exc).split(" needs ")[0], "...", str(exc).split("; ")[-1])
    seg.npy: a surface for each of 3 labels (18,000 voxel faces) ... the first 2 fit: --labels=1-2
    """
    from ..scale.memory import check_fits, default_budget

    wide = sorted(float(p) for p in spacing)[-2:]  # the largest face of a voxel: its two largest sides
    with np.errstate(all="ignore"):  # areas past float64 (a voxel size of 1e200) count no face: nothing refused
        faces = np.asarray(table["surface_area"], np.float64) / (wide[0] * wide[1])
    faces = np.floor(np.where(np.isfinite(faces), faces, 0.0) + 0.5).astype(np.int64)
    need = SURFACE_BYTES_PER_FACE * np.cumsum(faces)
    budget = default_budget() if budget is None else int(budget)
    if not len(need) or need[-1] <= budget:
        return
    fit = int(np.searchsorted(need, budget, side="right"))
    labels = table["label"]
    if not fit:
        hint = f"not even label {labels[0]}'s surface fits"
    elif every:
        hint = f"the first {fit:,} fit: --labels={labels[0]}" + (f"-{labels[fit - 1]}" if fit > 1 else "")
    else:
        hint = f"the first {fit:,} of the labels asked for fit"
    check_fits(int(need[-1]), f"{name}: a surface for each of {counted(len(labels), 'label')} ({int(faces.sum()):,} "
               "voxel faces)", hint=hint, budget=budget)


def _take_batch(args: argparse.Namespace, target, batch, table: dict, names: list[str], lo: np.ndarray, image,
                meshes: list, glb_parts: list) -> None:
    """A batch of labels' meshes (:func:`isoflow.digital.label_meshes.label_batches`),
    each checked against the table's V - E + F: for one glTF file, the
    batch's glTF parts with their labels' rows into ``glb_parts``; for a
    file each, each mesh and its object into ``meshes`` at its row."""
    from ..digital.lattice import DigitalObject
    from ..mesh.export import batch_glb_parts

    if target[0] == "glb":
        # a label's name (where the file records it) in its node's extras: the node keeps its name label_N
        named = table["name"].tolist() if "name" in table else None
        glb_parts.append((batch_glb_parts(batch, names, lo, image.spacing, image.origin, named), batch.rows))
    for s, r in enumerate(batch.rows):
        mesh = batch.part(s)
        if mesh.euler_characteristic != table["surface_euler"][r]:  # the table and the mesh count alike
            raise AssertionError(f"label {table['label'][r]}: the mesh has V-E+F {mesh.euler_characteristic}, "
                                 f"the table {table['surface_euler'][r]}")
        if target[0] == "glb":  # the scene is read back against the table's figures (scene_expected)
            continue
        obj = DigitalObject(batch.masks[s], offset=tuple(int(v) for v in lo[r]), pitch=image.spacing,
                            origin=image.origin, space=image.space)  # (a file's world positions, their frame)
        # the read-back compares the file's genus with the table's surfaces
        # (counted from the pieces, not from this mesh), as info --labels prints them
        surfaces = None if args.no_check else [{"genus": g} for g in table["genera"][r]]
        meshes[r] = (names[r], mesh, obj, surfaces)


def scene_expected(table: dict, names: list[str], spacing, moved: float = 0.0) -> list[tuple[str, dict, float]]:
    """What each label's node of the scene must read as, from the table
    (``info --labels``'s figures, counted from the pieces, not from the
    meshes): its surface's V - E + F, the sum of its closed surfaces'
    genera, and its volume, within ``moved`` (float64's move of the
    corners, :func:`isoflow.mesh.float32.float64_moved`) times twice its
    surface's area; with the unit the volumes are compared in
    (:func:`isoflow.mesh.readback.check_scene_figures`)."""
    from ..mesh.readback import expected_figures_each, unit_of

    unit = unit_of(spacing)
    slack = [2 * moved * area for area in table["surface_area"].tolist()] if moved else None
    found = expected_figures_each(table["surface_euler"].tolist(), [sum(genera) for genera in table["genera"]],
                                  table["voxels"].tolist(), spacing, slack)
    return [(name, figures, unit) for name, figures in zip(names, found)]


def earlier_label_files(directory: str | os.PathLike, suffix: str, names: list[str]) -> list[Path]:
    """The label files (``label_N`` with ``suffix``) in ``directory`` that
    are not among ``names``: an earlier run's, of labels this run has not.
    ``N`` is a label as this command writes it (no leading zero, ASCII
    digits, a value of a 64-bit integer type): ``label_007.ply`` and
    ``label_18446744073709551616.ply`` (2**64) are another program's files.

    Parameters
    ----------
    directory : str or os.PathLike
        The directory of ``-o DIR/``.
    suffix : str
        The files' suffix (``.ply``), as this run writes them.
    names : list of str
        This run's files without their suffix (``label_3``).

    Returns
    -------
    list of Path
        Those files, by name; a directory of such a name is left out.

    Examples
    --------
    >>> import tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> for f in ("label_1.ply", "label_9.ply", "label_9.obj", "label_09.ply", "label_18446744073709551616.ply"):
    ...     _ = (d / f).write_bytes(b"")
    >>> [f.name for f in earlier_label_files(d, ".ply", ["label_1"])]
    ['label_9.ply']
    """
    wanted = set(names)
    found = []
    for f in Path(directory).glob(f"label_*{suffix}"):
        stem = f.name[: -len(suffix)]
        # the names this command writes, str(label): label_07 (or digits other than ASCII) is another program's file
        if re.fullmatch(r"label_(0|-?[1-9][0-9]*)", stem) and stem not in wanted and not f.is_dir() \
                and -(1 << 63) <= int(stem[6:]) < 1 << 64:  # no label image holds another value
            found.append(f)
    return sorted(found)


def retired_label_files(earlier: list[Path], suffix: str, asked: np.ndarray | None,
                        force: bool) -> tuple[list[Path], list[Path]]:
    """Which of an earlier run's label files (:func:`earlier_label_files`)
    a run removes and which it keeps, as ``(retire, kept)``.

    Without ``force`` every one is kept. With it, a run of every label
    (``asked`` None) makes the directory hold its own files alone; a run of
    a choice replaces the files of the labels chosen only: it removes those
    of chosen labels that no longer occur (the image has no surface for
    them) and keeps every other label's.

    Parameters
    ----------
    earlier : list of Path
        The label files of the directory that this run does not write.
    suffix : str
        Their suffix (``.ply``).
    asked : numpy.ndarray or None
        The labels of ``--labels SPEC`` (:func:`label_choice`); None for
        every label.
    force : bool
        Whether ``--force`` was given.

    Returns
    -------
    tuple of list of Path
        ``(retire, kept)``, each in the order of ``earlier``.

    Examples
    --------
    >>> files = [Path("out/label_5.ply"), Path("out/label_7.ply")]
    >>> [[f.name for f in part] for part in retired_label_files(files, ".ply", np.array([3, 5]), True)]
    [['label_5.ply'], ['label_7.ply']]
    >>> [[f.name for f in part] for part in retired_label_files(files, ".ply", None, True)]
    [['label_5.ply', 'label_7.ply'], []]
    """
    if not force:
        return [], list(earlier)
    if asked is None:
        return list(earlier), []
    chosen = _asked_among([int(f.name[len("label_"): -len(suffix)]) for f in earlier], asked)
    return [f for f, c in zip(earlier, chosen) if c], [f for f, c in zip(earlier, chosen) if not c]


def _asked_among(values: list[int], asked: np.ndarray) -> list[bool]:
    """Whether each of a few labels (Python integers) is one of ``asked``
    (:func:`label_choice`), with no Python integer made per label asked."""
    if asked.dtype.kind == "O":
        return np.isin(np.array(values, dtype=object), asked).tolist()
    held = np.iinfo(asked.dtype)
    fits = [int(held.min) <= v <= int(held.max) for v in values]  # one asked's type cannot hold is not asked
    found = np.isin(np.array([v if ok else 0 for v, ok in zip(values, fits)], dtype=asked.dtype), asked)
    return [ok and hit for ok, hit in zip(fits, found.tolist())]


def write_label_surfaces(args: argparse.Namespace, target, meshes: list, glb_parts: list,
                         progress=None, expected: list | None = None, beyond: str | None = None,
                         ahead: threading.Thread | None = None) -> tuple[list[str], str, int]:
    """Write every label's surface (a glTF node each, in the labels'
    order, from the batches' parts in ``glb_parts``, and read back against
    ``expected``, :func:`scene_expected`; or a file each, read back
    against ``meshes``) unless --no-check, telling ``progress(done,
    total)`` of the labels written (a file each) or read back. Returns
    the problems found, the faces written in words (``18944 faces
    (triangles)``: as the files hold them, as surface says of one) and
    how many labels were not read back, whose read-back would not fit in
    memory (each file asked what ``surface`` asks of one, the scene what
    it asks of a GLB of as many triangles; said in a note).
    ``beyond``: what of the image's placement a GLB node's transform
    cannot hold in float32, said in the note on the transforms.
    ``ahead``: the thread importing trimesh
    (:func:`isoflow.cli.imports_ahead.import_ahead`), joined before
    trimesh is first used."""
    from ..mesh import export
    from ..mesh.readback import check_scene_figures, check_surface_file, readback_bytes, readback_skipped
    from .progress import reading_back

    if target[0] == "glb":
        triangles = sum(len(parts.triangles) for parts, _ in glb_parts)
        faces = f"{triangles} faces (triangles)"
        rows = np.concatenate([r for _, r in glb_parts]) if glb_parts else np.zeros(0, np.int64)
        export.write_glb_sets(target[1], [parts for parts, _ in glb_parts], np.argsort(rows), force=args.force,
                              comment=f"isoflow surface --labels of {Path(args.input).name}, "
                                      f"{args.connectivity or 6}-connectivity")
        framed = sum(len(parts.matrices) for parts, _ in glb_parts)
        if framed and not args.quiet:  # MeshLab reads those nodes in voxel units
            note = export.glb_transform_note(target[1], framed, len(rows), beyond=beyond,
                                             instead="-o DIR/ --suffix .ply or .obj")
            print(terminal_text(f"isoflow surface: note: {note}"), file=sys.stderr)
        glb_parts.clear()  # written: let the columns go before trimesh reads the file back
        with reading_back(target[1]):
            if ahead is not None:  # (the file is in place: a signal during the wait says so)
                ahead.join()
            why = None if expected is None else readback_skipped(readback_bytes(triangles, ".glb"))
            if why is not None:
                if not args.quiet:
                    print(terminal_text(f"isoflow surface: note: {target[1]}: not read back ({why})"), file=sys.stderr)
                return [], faces, len(rows)
            return ([] if expected is None else check_scene_figures(target[1], expected, progress)), faces, 0
    from ..mesh.outputs import output_set

    if ahead is not None:  # each file is read back as soon as it is written (and an STL is written by trimesh)
        ahead.join()
    problems, unread = [], {}  # label file -> why its read-back is skipped (it would not fit in memory)
    count, kinds = 0, {}  # faces written, of each kind (a label with edge midpoints: triangles in PLY)
    welds = {}  # label file -> the contacts STL cannot keep apart
    moved = {"moved": 0.0, "moved_voxels": 0.0}  # the farthest float32 moved an STL's corners, of every file
    framed = 0  # GLB files whose positions are in voxel units under the node's transform
    earlier = earlier_label_files(target[1], target[2], [name for name, *_ in meshes])
    asked = label_choice(args.labels) if earlier and args.force else None
    retire, kept = retired_label_files(earlier, target[2], asked, args.force)
    if kept and not args.quiet:
        print(terminal_text(f"isoflow surface: note: {target[1]}/: {counted(len(kept), 'label file')} of an earlier run kept "
                            f"({_some([f.name for f in kept])}); "
                            + ("--force makes the directory hold this run's alone" if args.labels == "all" else
                               "a choice of labels replaces those labels' files alone, with --force too")), file=sys.stderr)
    # one set: a folder holding some labels' new files beside others' old ones would look complete
    # (the directory is made before the work, by label_directory, which removes it if the work fails)
    with output_set(f"{target[1]}/", retire=retire):
        for done, (name, mesh, obj, comps) in enumerate(meshes, 1):
            path = target[1] / f"{name}{target[2]}"
            # the connectivity as surface records it: genus reads the file at it
            comments = (f"isoflow surface --labels of {Path(args.input).name}, {mesh.connectivity}-connectivity: "
                        f"{name}", export.VERTEX_COMMENT)
            written = export.write_mesh_file(path, mesh, obj, ascii=args.ascii, triangulate=args.triangulate,
                                           force=args.force, comments=comments)
            count += written["face_count"]
            framed += bool(written.get("framed"))
            kinds[written["faces"]] = None
            if (written.get("moved_voxels") or 0) > moved["moved_voxels"]:
                moved = {"moved": written["moved"], "moved_voxels": written["moved_voxels"]}
            welded = export.shared_positions(mesh) if target[2] == ".stl" else 0
            if welded:
                welds[path.name] = welded
            if not args.no_check:
                with reading_back(path):
                    check = check_surface_file(path, mesh, obj, topology=not welded, components=comps)
                if check.get("skipped"):
                    unread[path.name] = check["skipped"]
                elif check.get("agree") is False:
                    problems.append(check["problem"])
            if progress is not None:
                progress(done, len(meshes))
    if framed and not args.quiet:  # as surface says of one GLB file
        where = f"{target[1]}/" if len(meshes) > 1 else target[1] / f"{meshes[0][0]}{target[2]}"
        note = export.glb_transform_note(where, framed, len(meshes), "file", beyond=beyond,
                                         instead="--suffix .ply or .obj")
        print(terminal_text(f"isoflow surface: note: {note}"), file=sys.stderr)
    if unread and not args.quiet:  # as surface says of one file
        first = next(iter(unread))
        print(terminal_text(f"isoflow surface: note: {target[1]}/: {counted(len(unread), 'label file')} not read back "
                            f"({first}: {unread[first]})"), file=sys.stderr)
    if moved["moved_voxels"] > export.STL_NOTE_VOXELS:  # as surface says of one STL file, under --quiet too
        print(terminal_text(f"isoflow surface: warning: {export.stl_move_note(f'{target[1]}/', moved)}"), file=sys.stderr)
    if welds:  # as surface says of one STL file, under --quiet too
        line = (f"isoflow surface: warning: {target[1]}/: STL keeps no shared vertices, so readers weld the split "
                f"copies at {sum(welds.values())} edge/vertex contacts of {counted(len(welds), 'file')} "
                f"({_some(list(welds))}) into non-manifold points; PLY, OBJ or GLB keep them apart")
        print(terminal_text(line), file=sys.stderr)
    return problems, f"{count} faces ({', '.join(kinds)})", len(unread)
