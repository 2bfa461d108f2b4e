"""NRRD, ``.nrrd`` and detached ``.nhdr`` headers (pynrrd).

Axes: the file's axes in its own order, fastest first (pynrrd's
``index_order='F'``: axis 0 is the fastest), placed by ``space directions``
(one world vector per axis) and ``space origin`` (the centre of the first
sample), as NIfTI's affine is (:mod:`isoflow.mesh.formats.affine`: turned to
isoflow's x, y, z with positive steps; a rotation is kept as its axis-aligned
part with a warning). World coordinates are the file's ``space`` (3D Slicer
writes LPS), which the volume's ``space`` names by its three letters
(:func:`space_code`: ``left-posterior-superior`` is ``"LPS"``; None for
``scanner-xyz``, ``3D-right-handed`` and a file without a space). Axes
without a direction (``none``: a vector or list axis) must have length 1.
A file without a space is placed per axis by teem's rule
(:func:`axis_samples`): ``spacings`` (or ``axis maxs`` less ``axis mins``
over the cells) the step, a negative one running the axis backwards, and
``axis mins`` the first sample, cell-centred unless ``centerings`` says
``node``; without ``axis mins`` sample 0's edge is at 0. An axis whose
spacing is ``nan`` (the format's "not
a space axis"), or, without a space, whose ``kinds`` entry is a component
kind (``vector``, ``RGB-color``, ``list``, ...), must have length 1 too. A header whose lists do not fit the
array (fewer directions than axes, an origin of another dimension) is
refused; a non-finite ``space origin`` is read as 0 with a warning.
The length unit is ``space units`` (with a space) or ``units`` of the
placed axes (with ``spacings``, ``axis mins`` or ``axis maxs``): the
first axis's, the others' lengths converted to it where they differ
(:func:`~isoflow.mesh.formats.registry.axis_units`).

A 3D Slicer segmentation (``.seg.nrrd``, :mod:`isoflow.mesh.formats.slicer`)
of one layer is a label image; of several (4D, the layers on axis 0),
``FILE.seg.nrrd:N`` reads layer ``N`` and the file alone is refused with
a line listing each layer's segments.

Written with ``space`` where the volume's anatomical frame is known (the
NRRD name of ``RAS``, ``LPS`` or ``LAS``, ``-time`` added in 4D; another
frame is written as RAS, its axes that point the other way negated; a 2D
image in its z = 0 plane, as NRRD's anatomical spaces have three axes), else
``space dimension``; diagonal ``space directions`` (the voxel sizes),
``space origin`` (voxel 0's centre), uint8 0/1, gzip encoding;
float64 in the text header, so pitch and origin are kept exactly; and,
where a length unit is given, ``space units`` (one per axis, in ASCII:
``um`` for \u00b5m, as ImageJ and ITK write it). A label image with names
is written as a 3D Slicer segmentation of one layer, a segment per label
in the image, unnamed ones ``label_N``
(:func:`~isoflow.mesh.formats.slicer.segment_fields`); reading it gives
the names given back (``RawVolume.names``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...digital.frames import grid_in_frame
from ...digital.lattice import DigitalObject
from ...errors import IsoflowError
from .affine import axis_aligned, centre_affine
from .registry import (
    RawVolume,
    ascii_unit,
    axis_units,
    check_shape,
    import_library,
    note,
    placement,
    reading,
    stored_values,
)
from .slicer import NamedHeader, layer_names, layer_of, present_labels, read_header, remember_segments, segment_fields


def _check_data_file(header: dict, path: Path) -> None:
    """Refuse a detached header (``.nhdr``) whose ``data file`` is not
    there, naming the field and the file it names (relative to the
    header's folder, as the format reads it), before the reader fails on
    it; and one whose data lie in several files (``LIST``, a ``%d``
    pattern), which pynrrd does not read (it failed on them as "not enough
    values to unpack" or a file named ``slice%03d.raw 0 7 1``)."""
    name = header.get("data file", header.get("datafile"))
    if not isinstance(name, str):
        return
    parts = name.split()
    # teem's pattern: "slice%03d.raw MIN MAX STEP [SUBDIM]"; a single name may hold a space
    pattern = "%" in name and len(parts) in (4, 5) and all(p.lstrip("+-").isdigit() for p in parts[1:])
    if parts[:1] == ["LIST"] or pattern:
        raise IsoflowError(f"{path}: its field 'data file' ({name.strip()}) spreads the data over several files, "
                           "which isoflow's NRRD reader (pynrrd) does not read; save the volume as one .nrrd "
                           "(3D Slicer, ITK and teem's unu read such a header)")
    target = Path(name) if Path(name).is_absolute() else Path(path).parent / name
    if not target.is_file():
        raise IsoflowError(f"{path}: its data file, {name} (field 'data file'), is not there ({target} not found)")


def read(path: Path, dataset: str | None = None) -> RawVolume:
    nrrd = import_library("nrrd", "NRRD", "pynrrd")
    where = str(path)
    with reading(path, "NRRD"), open(path, "rb") as fh:
        # the header parsed once (a segmentation's holds ten fields a
        # segment), checked, then the data read on from the same handle
        header = read_header(fh)  # pynrrd's, a 3D Slicer segment's UTF-8 name read whole
        sizes = [int(s) for s in header["sizes"]]
        check_shape(sizes, np.uint8, where)
        if str(header.get("type", "")).lower() == "block":
            # opaque blocks: pynrrd fails on them as "negative dimensions are not allowed"
            raise IsoflowError(f"{where}: NRRD field 'type' is 'block' (opaque blocks of "
                               f"{header.get('block size', header.get('blocksize', '?'))} bytes), no numbers; "
                               "isoflow reads NRRD of a number type")
        _check_data_file(header, path)
        data = nrrd.read_data(header, fh, str(path), index_order="F")
    remember_segments(path, header)  # named after the read (isoflow info --labels's note) from this header
    # a 3D Slicer segmentation: the layer named (FILE.seg.nrrd:N), placed as any NRRD
    full = header
    data, header = layer_of(data, header, dataset, where)
    names = layer_names(full, dataset, where)  # (of the whole header: its layers are counted on axis 0)
    directions = header.get("space directions")
    if directions is not None:
        directions = _field(header, "space directions", (data.ndim, None), where)
        placed = [i for i in range(data.ndim) if np.isfinite(directions[i]).all()]
        data = _scalar_axes(data, placed, "space direction", where, _kinds(header, data.ndim))
        dim = directions.shape[1]
        origin = _field(header, "space origin", (dim,), where) if "space origin" in header else np.zeros(dim)
        if not np.isfinite(origin).all():
            note(f"{where}: space origin {origin.tolist()} is not finite; the origin is taken as 0")
            origin = np.zeros(dim)
        # each world axis's coordinates in one unit (space units of mm, mm, cm: z times 10)
        factors, unit = _unit(header, "space units", None, where, dim)
        vol, pitch, corner = axis_aligned(data, directions[placed].T * factors[:, None], origin * factors, where)
        return RawVolume(vol, pitch, corner, unit=unit, names=names, space=space_code(header.get("space")))
    # without space directions, only "kinds" tells a component axis (an
    # RGB colour, a vector, a list of layers) from a domain axis
    kinds = _kinds(header, data.ndim)
    placed = list(range(data.ndim))
    if kinds is not None:
        placed = [i for i in placed if str(kinds[i]).lower() in DOMAIN_KINDS]
    if "spacings" in header:
        spacings = _field(header, "spacings", (data.ndim,), where)
        placed = [i for i in placed if np.isfinite(spacings[i])]
    sizes = data.shape
    if len(placed) < data.ndim:
        data = _scalar_axes(data, placed, "spacing", where, kinds)
    said = [f for f in ("spacings", "axis mins", "axis maxs") if f in header]
    if not said or not placed:
        return RawVolume(data, 1.0, unit=None, names=names)
    step, centre0 = axis_samples(header, sizes, placed, where)
    factors, unit = _unit(header, "units", placed, where, len(placed))
    vol, pitch, corner = axis_aligned(data, np.diag(step * factors), centre0 * factors, where)
    return RawVolume(vol, pitch, corner, unit=unit, names=names)


def axis_samples(header: dict, sizes: tuple[int, ...], placed: list[int], where: str) -> tuple[np.ndarray, np.ndarray]:
    """The step and the place of sample 0's centre along each ``placed``
    axis of a NRRD without a space, by teem's rule (``nrrdAxisInfoPos``).

    Sample ``i`` of a cell-centred axis (the format's default) lies at
    ``min + (i + 0.5) * step``, of a node-centred one at ``min + i * step``;
    the step is ``spacings``, else ``(max - min)`` over the cells (the gaps
    between nodes), else 1. A negative step runs the axis backwards. An axis
    without ``axis mins`` (nor ``axis maxs``) has sample 0's lowest edge at 0.

    Parameters
    ----------
    header : dict
        pynrrd's header.
    sizes : tuple of int
        The length of each file axis.
    placed : list of int
        The file axes (fastest first) that are placed.
    where : str
        The file, as refusals name it.

    Returns
    -------
    step, centre0 : numpy.ndarray
        One entry per placed axis.

    Examples
    --------
    >>> step, centre0 = axis_samples({"axis mins": [10.0], "axis maxs": [13.0]}, (6,), [0], "a.nrrd")
    >>> step.tolist(), centre0.tolist()
    ([0.5], [10.25])
    """
    n = len(sizes)
    given = {f: _field(header, f, (n,), where)[placed] for f in ("spacings", "axis mins", "axis maxs") if f in header}
    nan = np.full(len(placed), np.nan)
    spacing, low, high = (given.get(f, nan) for f in ("spacings", "axis mins", "axis maxs"))
    centerings = header.get("centerings")
    node = np.array([centerings is not None and len(centerings) == n and str(centerings[i]).lower() == "node"
                     for i in placed])
    size = np.asarray(sizes, np.float64)[placed]
    cells = np.where(node, np.maximum(size - 1, 1), size)
    step = np.where(np.isfinite(spacing), spacing,
                    np.where(np.isfinite(low) & np.isfinite(high), (high - low) / cells, 1.0))
    # sample 0's centre: half a step past a cell-centred axis's min, at a node-centred one's;
    # from the max where only it is given; half a step past 0 where neither is
    half = np.where(node, 0.0, step / 2)
    centre0 = np.where(np.isfinite(low), low + half, np.where(np.isfinite(high), high - step * cells + half, step / 2))
    return step, centre0


#: NRRD's anatomical spaces (teem's airEnum names, and its abbreviations)
#: by the three letters of where +x, +y, +z point
SPACES = {"RAS": "right-anterior-superior", "LAS": "left-anterior-superior", "LPS": "left-posterior-superior"}


def space_code(space: object) -> str | None:
    """The three letters of a NRRD ``space`` field's anatomical frame, for
    3D and, ``-time`` added, 4D; None for no field and for the spaces of no
    anatomy (``scanner-xyz``, ``3D-right-handed``, ...), whose axes no
    patient's direction names.

    Parameters
    ----------
    space : str or None
        The field as the header holds it, in any case.

    Returns
    -------
    str or None

    Examples
    --------
    >>> space_code("left-posterior-superior"), space_code("RAS-time"), space_code("LPST")
    ('LPS', 'RAS', 'LPS')
    >>> space_code("scanner-xyz") is None, space_code(None) is None
    (True, True)
    """
    if not isinstance(space, str):
        return None
    name = space.strip().lower()
    name = name.removesuffix("-time")
    for code, full in SPACES.items():
        if name in (full, code.lower(), code.lower() + "t"):
            return code
    return None


def _kinds(header: dict, ndim: int) -> list | None:
    """The header's ``kinds``, one per axis, or None where it has none that fit."""
    kinds = header.get("kinds")
    return list(kinds) if kinds is not None and len(kinds) == ndim else None


def _unit(header: dict, name: str, axes: list[int] | None, where: str, count: int) -> tuple[np.ndarray, str | None]:
    """The length unit of a header's ``space units`` (one per world axis)
    or ``units`` (one per array axis, of which ``axes`` are placed; None:
    none are, the voxel size is 1 in no unit), and the factor that turns
    each of the ``count`` axes' lengths into it (:func:`axis_units`):
    ones where the field is absent or does not give one unit per axis."""
    units = header.get(name)
    if units is None or (name == "units" and axes is None):
        return np.ones(count), None
    units = [units] if isinstance(units, str) else list(units)
    if axes is not None:
        units = [units[i] for i in axes if i < len(units)]
    factors, unit = axis_units(units, where, f"NRRD {name!r}")
    if len(factors) != count:  # (units that do not fit the axes: one unit only where they agree)
        return np.ones(count), unit if (factors == 1).all() else None
    return factors, unit


#: the NRRD kinds of axes along which samples lie ("???" and "none": not
#: said); every other kind (vector, RGB-color, list, ...) is a component axis
DOMAIN_KINDS = ("domain", "space", "time", "???", "none")


def _field(header: dict, name: str, shape: tuple, where: str) -> np.ndarray:
    """A header field as float64 of ``shape`` (None: any length), or one line
    saying what it holds instead."""
    try:
        value = np.asarray(header[name], np.float64)
    except (TypeError, ValueError):
        value = None
    if value is None or value.ndim != len(shape) or any(s is not None and n != s for n, s in zip(value.shape, shape)):
        shown = header[name].tolist() if isinstance(header[name], np.ndarray) else header[name]
        raise IsoflowError(f"{where}: NRRD field '{name}' {shown!r} does not fit the array "
                           f"(sizes {[int(n) for n in header.get('sizes', [])]})")
    return value


def _scalar_axes(data: np.ndarray, placed: list[int], what: str, where: str, kinds=None) -> np.ndarray:
    """``data`` with only its ``placed`` axes; the others (no ``what``, or a
    component kind in ``kinds``: a vector or list axis) must have length 1."""
    others = [i for i in range(data.ndim) if i not in placed]
    for i in others:
        if data.shape[i] != 1:
            component = kinds is not None and str(kinds[i]).lower() not in DOMAIN_KINDS
            why = f"is of NRRD kind {kinds[i]!r} with" if component else f"has no {what} and"
            raise IsoflowError(
                f"{where}: axis {i} {why} {data.shape[i]} entries "
                f"(shape {data.shape}); isoflow reads one scalar volume"
            )
    return np.transpose(data, placed + others).reshape([data.shape[i] for i in placed])


def named_space(space: str, steps: np.ndarray, centre0: np.ndarray, ndim: int) -> dict:
    """The header fields ``space``, ``space directions`` and ``space
    origin`` of a volume of ``ndim`` axes in the anatomical frame
    ``space``: its own NRRD name where it has one, else RAS with the world
    axes that point the other way negated (the voxels keep their
    anatomical places).

    Parameters
    ----------
    space : str
        The frame's three letters (:func:`~isoflow.digital.frames.space_given`).
    steps : numpy.ndarray
        Row ``i``: the world step of array axis ``i``, in three world
        axes (four with time).
    centre0 : numpy.ndarray
        The world position of voxel 0's centre.
    ndim : int
        The array's axes: 2 or 3, or 4 for a time series (``-time`` added
        to the name).

    Returns
    -------
    dict
        The three fields (pynrrd then leaves out ``space dimension``).

    Examples
    --------
    >>> fields = named_space("RPS", np.eye(3), np.array([1.0, 2.0, 3.0]), 3)
    >>> fields["space"], fields["space origin"].tolist()
    ('right-anterior-superior', [1.0, -2.0, 3.0])
    """
    if space not in SPACES:
        steps, centre0 = grid_in_frame(steps, centre0, space)
        space = "RAS"
    return {"space": SPACES[space] + ("-time" if ndim == 4 else ""), "space directions": steps,
            "space origin": centre0}


# zlib's own default, as gzip(1) writes: pynrrd's default, 9, takes 2.5-4
# times as long for files 7-14 % smaller (benchmarks/bench_gzip_levels.py)
GZIP_LEVEL = 6


def write(path: Path, obj: DigitalObject, dataset: str | None = None, name: str | None = None,
          unit: str | None = None, space: str | None = None) -> None:
    nrrd = import_library("nrrd", "NRRD", "pynrrd")
    spacing, corner = placement(obj)
    steps, centre0 = centre_affine(spacing, corner)
    header = {
        "space dimension": obj.ndim,
        "space directions": steps,  # row i: the world step of axis i (diagonal)
        "space origin": centre0,
        "kinds": ["domain"] * obj.ndim,
        "encoding": "gzip",
    }
    if space is not None:
        if obj.ndim == 2:
            # NRRD's anatomical spaces have three axes: a 2D image lies in their z = 0 plane,
            # as NIfTI's writer places it
            steps, centre0 = np.hstack([steps, np.zeros((2, 1))]), np.append(centre0, 0.0)
        header.update(named_space(space, steps, centre0, obj.ndim))
    if unit is not None:
        header["space units"] = [ascii_unit(unit)] * len(header["space origin"])
    names = getattr(obj, "names", None)  # a label image's: Slicer's segments
    texts = {}
    if names:
        fields = segment_fields(names, obj.volume.shape, present_labels(obj.volume))
        # pynrrd writes a header as ASCII: it is given a placeholder for each name, which
        # NamedHeader writes as Slicer does, UTF-8
        texts = {k: v for k, v in fields.items() if k.endswith("_Name")}
        header.update({k: "?" if k in texts else v for k, v in fields.items()})
    with open(path, "wb") as fh:
        nrrd.write(NamedHeader(fh, texts), stored_values(obj.volume), header, index_order="F",
                   compression_level=GZIP_LEVEL)
