"""The topology and curvature indices of every label of a label image, as
one table (``isoflow info LABELS --labels``).

A label's object is the voxels of that label; everything else (the value
0 and every other label) is its complement. Every row is what
:func:`isoflow.digital.analysis.analyze` reports for ``image == label``,
found for all labels at once:

* every lattice vertex sees at most eight labels, and the configuration of
  each (section 4) comes from the same 2x2x2 block, so one pass over the
  vertices gives every label's class histogram ``n`` (eq. 4.9), its
  ``a^T n = 8 chi`` (Theorems 10-11, eq. 4.12-4.13), its energy
  ``E = k^T n`` (eq. 5.22) and its boundary faces per axis
  (:mod:`isoflow.scale.pieces`);
* the voxels of every value are cut into face-connected *pieces* in one
  labelling; a label's components under 6, 18 or 26, and the components of
  its complement, are unions of pieces joined where they touch by a face,
  an edge or a vertex, which the same pass records; so b0, the cavities b2
  (enclosed components of the complement under the complementary
  connectivity) and ``b1 = b0 + b2 - chi`` come from a graph of pieces,
  label by label, without another pass over the voxels
  (:mod:`isoflow.scale.piece_graph`);
* the closed surfaces of a label's boundary mesh (docs/mathematics.md) are the
  pairs (component of the label, component of its complement) under the
  mesh's adjacencies that its boundary faces separate
  (:mod:`isoflow.digital.closed_surfaces`), each with ``chi = V - F``
  counted from the sheets through the lattice vertices; the pass adds the
  sheets up per pair of pieces.

The columns follow scikit-image's ``regionprops_table``: a dict of NumPy
arrays of one length, which ``pandas.DataFrame`` takes as it is.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError, check_switch, given_text, scalar_given, warn, whole_given
from ..results import fields_repr, same_fields
from ..scale.arrays import FILL_READ, FILL_ZERO, as_array, fill_as, refuse_object
from ..scale.memory import budget_held, check_fits
from .closed_surfaces import sweep_tables
from .connectivity import resolve_connectivity
from .float64 import scaled_counts, scaled_faces, underflow_line, unheld_columns
from .frames import space_given
from .label_by_label import box_rows
from .lattice import DigitalObject
from .report import Report
from .units import unit_given
from .vertex_features import ENERGY, EULER, FACES, NWC, PINCH, feature_table

if TYPE_CHECKING:
    from ..scale.ticks import Ticks

#: the columns of :func:`label_table`, in order ("bbox" and "centroid"
#: stand for their numbered columns, "n" for n-0 .. n-8)
COLUMNS = ("label", "voxels", "volume", "surface_area", "bbox", "centroid", "euler_characteristic", "b0", "b1",
           "b2", "n", "non_well_composed", "energy", "surfaces", "genera", "surface_euler", "pinched_vertices",
           "doubled_edges")
#: the columns that need the surfaces (left out with ``surfaces=False``)
SURFACE_COLUMNS = ("surfaces", "genera", "surface_euler", "pinched_vertices", "doubled_edges")

@dataclass(frozen=True, eq=False, repr=False)
class LabelImage:
    """A label image with its place: integers in (x, y, z) order, the voxel
    size per axis and the world position of voxel (0, 0, 0)'s lowest
    corner, as :func:`~isoflow.mesh.volumes.read_labels` reads a file,
    and ``unit``, the length unit of both as the file says it (``mm``,
    ``µm``, ...; None where it says none). :func:`label_table` takes it in
    place of the array and its ``pitch`` and ``origin``; its world columns
    are in that unit (areas and volumes in its square and cube).
    ``names``: what each label is, label value to name, as the file records
    it (a 3D Slicer segment's name, an OME-Zarr label's ``properties``;
    docs/labels.md lists the formats), or None where it records none; a
    sequence is read as label ``i + 1`` named ``names[i]``.
    :func:`label_table` gives them as its ``name`` column, and
    :func:`~isoflow.mesh.volumes.write_labels` writes them again.
    ``space``: the anatomical frame of the world axes (``"RAS"``,
    ``"LPS"``, ...; :mod:`isoflow.digital.frames`), as the file says it,
    or None; a writer of another frame negates the axes that point the
    other way.

    Examples
    --------
    >>> image = LabelImage(np.array([[1, 1, 1], [0, 2, 2]]), np.array([0.5, 2.0]), np.zeros(2))
    >>> label_table(image)["area"].tolist()  # pixels of 0.5 x 2
    [3.0, 2.0]
    >>> named = LabelImage(image.array, image.spacing, image.origin, names=["bone", "muscle"])
    >>> named.names, label_table(named)["name"].tolist()
    ({1: 'bone', 2: 'muscle'}, ['bone', 'muscle'])
    """

    array: np.ndarray
    spacing: np.ndarray
    origin: np.ndarray
    unit: str | None = None
    names: Mapping[int, str] | None = None
    space: str | None = None

    # equal when the three arrays (and the unit) are, by their elements (the generated
    # __eq__ raised NumPy's ValueError); unhashable, as the label array can change: it is
    # the caller's, not copied (a label image of gigabytes would be held twice)
    __eq__ = same_fields
    __hash__ = None  # type: ignore[assignment]
    __repr__ = fields_repr  # the array by its shape: the generated repr printed every voxel of a small image

    def __post_init__(self):
        # the spacing and origin as float arrays, one number per axis, checked
        # as an object's pitch and origin are, so that label_table can take
        # a list or one number as it takes an array
        if isinstance(self.array, (list, tuple)):
            # nested lists held as an array, as ``array`` says (``image.array.shape``); an array of
            # another library (zarr, dask) is kept as it is, not read into memory here
            object.__setattr__(self, "array", as_array(self.array, "LabelImage array"))
        try:
            n = np.ndim(self.array)
        except ValueError:  # nested lists of uneven lengths: label_table names them
            n = None
        if n in (2, 3, 4):
            try:
                place = DigitalObject.placement(n, pitch=self.spacing, origin=self.origin)
            except IsoflowError as exc:
                raise IsoflowError("LabelImage: " + str(exc).replace("'pitch'", "'spacing'")) from None
            spacing = place.spacing  # (a fresh copy) read-only as the origin is: the image is frozen
            spacing.flags.writeable = False
            object.__setattr__(self, "spacing", spacing)
            object.__setattr__(self, "origin", place.origin)
        object.__setattr__(self, "unit", unit_given(self.unit, "LabelImage"))
        object.__setattr__(self, "names", label_names(self.names, "LabelImage") or None)
        object.__setattr__(self, "space", space_given(self.space, "LabelImage"))


def label_names(names: Mapping[int, str] | Sequence[str] | None, where: str) -> dict[int, str] | None:
    """The names of labels as one mapping, label value to name, checked:
    a sequence names labels 1, 2, ... in order; None where ``names`` is
    None, and an empty mapping where an empty mapping or sequence is given
    (no names: an image's own are not taken in their place).

    Parameters
    ----------
    names : mapping of int to str, or sequence of str, or None
        The names; a label value is a nonzero integer (negative in a
        signed image; 0 is the background), a name a string of one line.
    where : str
        What a refusal names (the file, or the function).

    Returns
    -------
    dict of int to str, or None
        In increasing order of label; empty for no names given as such.

    Raises
    ------
    IsoflowError
        A label that is no nonzero integer, a name that is no string or
        holds a line break.

    Examples
    --------
    >>> label_names(["liver", "spleen"], "seg.nrrd")
    {1: 'liver', 2: 'spleen'}
    >>> label_names({np.uint8(7): "tumour"}, "seg.nrrd"), label_names({}, "seg.nrrd")
    ({7: 'tumour'}, {})
    """
    if names is None:
        return None
    if isinstance(names, (str, bytes)) or not isinstance(names, (Mapping, Sequence, np.ndarray)) \
            or (isinstance(names, np.ndarray) and names.ndim != 1):
        # a side file's path given for its names (lut.txt): the reader that takes it is named
        read = ("; a file of names (a colour table, ITK-SNAP's labels, CSV, JSON) is read by "
                "isoflow.read_label_names(path)") if isinstance(names, (str, os.PathLike)) else ""
        raise IsoflowError(f"{where}: names are a mapping of label to name or a sequence of names (label i + 1 for "
                           f"the i-th), not {given_text(names)}{read}")
    pairs = names.items() if isinstance(names, Mapping) else enumerate(list(names), 1)
    found: dict[int, str] = {}
    for given_label, given_name in pairs:
        # 0D arrays (of an array of names) as what they hold
        label: Any = scalar_given(given_label)
        name: Any = scalar_given(given_name)
        whole = whole_given(label)
        if whole is None or whole == 0:
            raise IsoflowError(f"{where}: a label name is given for {given_text(label)}, and labels are named "
                               "by nonzero integers (0 is the background)")
        if not isinstance(name, str) or "\n" in name or "\r" in name:
            raise IsoflowError(f"{where}: the name of label {whole} is {given_text(name)}, not a string of "
                               "one line")
        found[whole] = str(name)  # a np.str_ (of an array of names) as the plain string
    return dict(sorted(found.items()))


def with_names(table: dict[str, np.ndarray], names: Mapping[int, str] | None) -> dict[str, np.ndarray]:
    """``table`` with a ``name`` column after ``label`` (each row's name,
    ``""`` for a label without one) where ``names`` are given; as it is
    where they are None.

    Examples
    --------
    >>> with_names({"label": np.array([1, 3]), "voxels": np.array([8, 2])}, {3: "tumour"})["name"].tolist()
    ['', 'tumour']
    """
    if not names:
        return table
    column = np.array([names.get(v, "") for v in table["label"].tolist()], dtype=str)
    out = {"label": table["label"], "name": column}
    out.update((k, v) for k, v in table.items() if k != "label")
    return out


def label_table(
    image: ArrayLike | LabelImage,
    connectivity: int | np.integer | None = None,
    *,
    pitch: float | ArrayLike | None = None,
    origin: ArrayLike | None = None,
    labels: Iterable[int | np.integer] | None = None,
    surfaces: bool = True,
    method: Literal["auto", "numpy", "compiled"] = "auto",
    threads: int | np.integer | None = None,
    names: Mapping[int, str] | Sequence[str] | None = None,
    background: bool = False,
    progress: Callable[[int, int], object] | None = None,
) -> dict[str, np.ndarray]:
    """The shape report of every label of a 3D or 2D label image, as columns.

    Parameters
    ----------
    image : array_like or LabelImage
        3D or 2D label image: any integer type up to 64 bits, bool (labels
        0 and 1, as uint8), or float whose values are all whole numbers
        (as NIfTI's scaling gives; read as int64). A :class:`LabelImage`
        (:func:`isoflow.read_labels` of a file) brings its voxel size and
        origin, which ``pitch`` and ``origin`` given replace.
    connectivity : {6, 26} in 3D, {4, 8} in 2D, optional
        Every label's connectivity (default the paper's: 6, in 2D 4); its
        complement takes the other one.
    pitch : float or array_like of floats, optional
        Voxel size (per axis); volumes, areas, boxes and centroids are in
        its units (default 1).
    origin : array_like of floats, optional
        World position of voxel (0, 0, 0)'s lowest corner (default 0).
    labels : sequence of int, optional
        The labels to report, in this order (default: every nonzero label
        present, in increasing order); whole numbers, Python's or NumPy's
        (a whole float, 2.0, is label 2; 1.5 or a bool is refused). A label absent from the image gets
        a row of zeros (NaN box and centroid), as ``analyze`` of an empty
        mask. Label 0 is the background, which the default leaves out;
        asked for, it gets its row as any label does, ``analyze(image ==
        0)``: the space around the labels as a shape (a porous medium's
        pores where 0 marks them), the labels it encloses its cavities,
        never named (as ``info --labels 0,3`` gives it).
    surfaces : bool
        Count the closed surfaces of every label's boundary mesh (the
        columns of :data:`SURFACE_COLUMNS`; 3D only).
    method : {"auto", "numpy", "compiled"}
        "compiled": one pass for all labels (numba); "numpy": ``analyze``
        on each label's box plus one voxel; "auto": the compiled pass
        where numba is installed, unless the NumPy pass answers before
        numba would start (few labels with small boxes, in a process
        that has not imported numba, counting the NumPy work of earlier
        images there; see :func:`compiled_sooner`), and the NumPy pass
        where the compiled one would not fit in memory (noise, a piece
        for nearly every voxel) or, its pieces counted, would be the
        slower (noise of a few labels: :func:`table_rows`). A 2D
        image takes one NumPy pass for all labels
        (:mod:`isoflow.digital.planar_labels`) whatever the method.
    threads : int, optional
        Threads for the compiled passes (default: ``ISOFLOW_THREADS``,
        else every CPU).
    names : mapping of int to str, or sequence of str, optional
        What each label is (label value to name, or the names of labels
        1, 2, ... in order), given as the ``name`` column; default (None):
        a :class:`LabelImage`'s ``names``. An empty mapping means no names,
        a LabelImage's too. Without names the table has no ``name``
        column.
    background : bool
        With ``labels`` None: the background's row too (label 0, as
        ``labels=[0]`` gives it, in its place in increasing order), where
        any voxel is 0, from the same one pass: every label and the space
        around them (the table of ``info --labels 0-100000``).
    progress : callable, optional
        ``progress(done, total)``, called on the calling thread as the
        work goes (``done`` rising to ``total``, which stays the same; its
        units are shares of the work, not voxels or labels), as the
        ``info --labels`` bar shows it. A 2D table, made in one NumPy
        pass, says its end only.

    Returns
    -------
    dict of str to numpy.ndarray
        One row per label: ``label``, ``voxels``, ``volume``,
        ``surface_area`` (boundary faces times their area), ``bbox-0`` ..
        ``bbox-5`` (lowest and highest corner of the label's voxels, world
        units), ``centroid-0`` .. ``centroid-2`` (world units: the voxel
        ``v`` spans ``[v, v + 1]``, so with unit pitch this is
        scikit-image's centroid plus 0.5), ``euler_characteristic``,
        ``b0``, ``b1``, ``b2``, ``n-0`` .. ``n-8`` (the classes of
        :data:`~isoflow.digital.indices.CLASS_LABELS`), ``non_well_composed``,
        ``energy``, and with ``surfaces``: ``surfaces`` (their number),
        ``genera`` (a tuple per label, most faces first, as ``analyze``
        lists them), ``surface_euler`` (V - E + F of the label's whole mesh,
        ``2 chi + 2 pinched``), ``pinched_vertices``, ``doubled_edges``.
        A 2D table has the same columns one dimension down (the paper's
        section 4 in the plane): ``label``, ``voxels`` (pixels), ``area``,
        ``perimeter`` (boundary pixel edges times their length),
        ``bbox-0`` .. ``bbox-3``, ``centroid-0`` .. ``centroid-1``,
        ``euler_characteristic``, ``b0``, ``b1`` (holes), ``n-0`` ..
        ``n-2`` (convex, flat, concave, eq. 4.9), ``non_well_composed``,
        ``energy``. With ``names``: ``name`` after ``label``, each row's
        name (``""`` for a label without one).

    Raises
    ------
    IsoflowError
        An image that is not 2D or 3D, a value that is no label (NaN, not
        whole, beyond int64), a label asked for that the image's type cannot
        hold, a bad connectivity,
        pitch or method, or work that would not fit in memory.

    Notes
    -----
    Each row equals ``analyze(image == label, connectivity)``: ``chi`` from
    ``a^T n = 8 chi`` (Theorems 10-11), ``b1 = b0 + b2 - chi``, ``energy =
    k^T n`` (eq. 5.22), the surfaces' genus ``1 - chi/2``.

    Examples
    --------
    >>> import numpy as np
    >>> image = np.zeros((6, 6, 6), np.uint16)
    >>> image[1:5, 1:5, 1:5] = 7          # a hollow cube
    >>> image[2:4, 2:4, 2:4] = 3          # with a cube of another label inside
    >>> t = label_table(image)
    >>> t["label"].tolist(), t["voxels"].tolist(), t["b2"].tolist(), t["genera"].tolist()
    ([3, 7], [8, 56], [0, 1], [(0,), (0, 0)])

    The background asked for: every voxel but the labels', the labelled
    block one cavity in it

    >>> t = label_table(image, labels=[0, 3])
    >>> t["voxels"].tolist(), int((image == 0).sum()), t["b2"].tolist()
    ([152, 8], 152, [1, 0])
    >>> label_table(image, background=True)["label"].tolist()  # every label, the background among them
    [0, 3, 7]

    Its progress, as a bar would show it (a share of a total)

    >>> said = []
    >>> _ = label_table(image, progress=lambda done, total: said.append((done, total)))
    >>> said[-1][0] == said[-1][1]  # the end reached
    True

    A 2D segmentation: a ring of four cells around a fifth

    >>> cells = np.zeros((5, 5), np.int32)
    >>> cells[0, :], cells[4, :], cells[1:4, 0], cells[1:4, 4] = 1, 2, 3, 4
    >>> cells[2, 2] = 5
    >>> t = label_table(cells, pitch=0.5)
    >>> t["b0"].tolist(), t["b1"].tolist(), t["area"].tolist()
    ([1, 1, 1, 1, 1], [0, 0, 0, 0, 0], [1.25, 1.25, 0.75, 0.75, 0.25])
    >>> label_table(cells > 0)["b1"].tolist()  # one label: the ring holds a hole
    [1]
    """
    from ..scale.compiled import check_method, using

    names = label_names(names, "label_table: names")
    if isinstance(image, LabelImage):  # the file's place and names, unless given
        # as arrays only where the image is 2D or 3D (LabelImage): of any other, checked_image names the array
        pitch = np.asarray(image.spacing).tolist() if pitch is None else pitch
        origin = np.asarray(image.origin).tolist() if origin is None else origin
        names = image.names if names is None else names
        image = image.array
    vol = checked_image(image, "label_table: image")
    conn = resolve_connectivity(vol.ndim, connectivity)
    surfaces = check_switch(surfaces, "surfaces", "label_table")
    # the pitch and origin checked as every object's are, as given (an
    # array of them would make a string's ValueError NumPy's, and a bool
    # among numbers a number)
    place = DigitalObject.placement(vol.ndim, pitch=pitch, origin=origin, function="label_table")
    wanted = None if labels is None else wanted_labels(labels, vol.dtype, "label_table: labels")
    background = checked_background(background, labels, "label_table")
    if vol.ndim == 2:
        from ..scale.ticks import Ticks
        from .planar_labels import planar_table

        _use_compiled(vol, "numpy" if check_method(method) == "auto" else method)  # the method checked as in 3D
        table = planar_table(vol, conn, place.spacing, place.origin, wanted, background)
        Ticks(progress, STAGES).finish()  # one pass, said at its end
        return with_names(unheld_columns(table, place.origin, place.spacing, vol.shape), names)
    with using(threads):
        found = table_rows(vol, conn, wanted, surfaces, background, method, progress)
    return with_names(unheld_columns(columns(found, place.spacing, place.origin, surfaces), place.origin,
                                     place.spacing, vol.shape), names)


def table_rows(vol: np.ndarray, conn: int, wanted: np.ndarray | None, surfaces: bool, background: bool,
               method: str, progress: Callable[[int, int], object] | None = None) -> dict:
    """The rows by the pass that ``method`` takes (:func:`_use_compiled`):
    with ``"auto"``, where the compiled pass would not fit in memory (a
    label image of noise, whose pieces, nearly one a voxel, and their
    graph take hundreds of bytes a voxel), each label's own ``analyze``
    (:func:`box_rows`), which needs tens and gives the same table; where
    neither fits, the compiled pass' refusal, which names what would. And
    where the pieces, once counted, or slabs of them say that pass is the
    sooner (a noisy segmentation, :data:`FRAGMENTED`), unless it does not
    fit. ``progress``: as :func:`label_table`'s, for the passes taken
    (:data:`STAGES`)."""
    from ..errors import DoesNotFit
    from ..scale.ticks import Ticks

    ticks = Ticks(progress, STAGES)
    if not _use_compiled(vol, method):
        return box_rows(vol, conn, wanted, surfaces, background, ticks)
    # from here numba is loaded (it counts the pieces): the label-by-label pass weighs its boxes as a loop's volumes
    first = present = None
    try:
        found = piece_rows(vol, conn, wanted, surfaces, background, rather=method == "auto", ticks=ticks)
        if isinstance(found, dict):
            ticks.finish()
            return found
        present = found
    except DoesNotFit as refusal:
        if method != "auto":
            raise
        first = refusal
    try:
        return box_rows(vol, conn, wanted, surfaces, background, ticks, weighed=True, present=present)
    except DoesNotFit:
        if first is not None:
            raise first from None
        if present is None:
            raise
    # taken on speed, the label-by-label pass does not fit: the one pass, or its refusal, which names what would fit
    found = piece_rows(vol, conn, wanted, surfaces, background, ticks=Ticks(progress, STAGES))
    assert isinstance(found, dict)  # (the values come only where it is asked which pass is the sooner)
    return found


def checked_image(image, where: str) -> np.ndarray:
    """The label image as an array of :func:`label_dtype` (see
    :func:`as_labels`): 3D or 2D; a refusal begins with ``where``, the
    function called and its argument (``label_table: image``).

    Examples
    --------
    >>> checked_image(np.full((2, 2, 2), 0.5), "label_table: image")
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: label_table: image: voxel (0, 0, 0) holds 0.5: not a whole number, so not a label
    """
    refuse_object(image, where, reader="isoflow.read_labels")
    if isinstance(image, Report):  # a Mapping, which NumPy would make a 1D array of its keys
        raise IsoflowError(f"{where}: a Report (isoflow.analyze's result), which describes one object, not a label "
                           "image; label_table takes the label image itself (an integer array or isoflow.read_labels's "
                           "LabelImage)")
    if isinstance(image, tuple) and len(image) == 2 and isinstance(image[0], np.ndarray) \
            and isinstance(image[1], (int, np.integer)) and not isinstance(image[1], (bool, np.bool_)):
        # scipy.ndimage.label's answer, which as_array would call nested lists of uneven lengths
        raise IsoflowError(f"{where}: a (labels, count) pair, as scipy.ndimage.label gives, of an array of shape "
                           f"{image[0].shape} and the count {int(image[1])}; pass its labels: "
                           "labels, count = ndimage.label(mask); label_table(labels)")
    vol = as_array(image, where)
    try:
        if vol.ndim not in (2, 3):
            raise IsoflowError(f"a label table needs a 3D or 2D label image, got a {vol.ndim}D array")
        return as_labels(vol)
    except IsoflowError as exc:
        # the command line names the file before these words (a store's type, as info reads it block by block)
        raise IsoflowError.worded(f"{where}: {exc}", str(exc)) from None


def label_dtype(dtype) -> np.dtype:
    """The type of an image's labels: its own for integers, in the
    machine's byte order (a big-endian image, as NRRD, HDF5 and ``>i4``
    arrays give, would otherwise make a big-endian ``label`` column that
    differs from the native image's), uint8 for a bool image (labels 0
    and 1), int64 for a float image of whole numbers (as NIfTI's scaling
    gives)."""
    dtype = np.dtype(dtype)
    if dtype == np.bool_:
        return np.dtype(np.uint8)
    if dtype.kind in "iu":
        return dtype.newbyteorder("=")
    if dtype.kind == "f":
        return np.dtype(np.int64)
    raise IsoflowError(f"a label image holds integers, not {dtype}")


def as_labels(array, first_layer: int = 0, axis: int = 0, fill: object = None) -> np.ndarray:
    """An image's labels as :func:`label_dtype` (a bool image viewed as
    uint8, a float one converted); an error naming the first value that is
    no label (NaN, infinite, beyond int64, not whole) and its voxel
    (``first_layer``: the index of the array's layer 0 along ``axis``),
    and, where that value is ``fill`` (a zarr array's fill value), that
    zarr reads it for a chunk never written; and one naming the first
    masked voxel of a masked part (:func:`unmasked`)."""
    vol = unmasked(array, first_layer, axis)
    kind = label_dtype(vol.dtype)
    if vol.dtype == np.bool_:
        return vol.view(np.uint8)
    if vol.dtype.kind != "f":
        return vol.astype(kind, copy=False)
    flat = vol.reshape(-1)
    wide = flat.astype(np.float64)  # float16 holds no 2**63 to compare with
    for bad, why in ((~np.isfinite(flat), f"not a label (a {vol.dtype} label image holds whole numbers)"),
                     ((wide >= 2.0**63) | (wide < -(2.0**63)), f"beyond the int64 labels a {vol.dtype} image is read as"),
                     (flat != np.round(flat), "not a whole number, so not a label")):
        if bad.any():
            at = int(np.argmax(bad))
            voxel = np.unravel_index(at, vol.shape)
            where = ", ".join(str(int(i) + (first_layer if d == axis else 0)) for d, i in enumerate(voxel))
            cell = "pixel" if vol.ndim == 2 else "voxel"  # as the other lines of a 2D image say
            if _is_fill(flat[at], fill):
                # a store written sparsely holds the value in voxels nobody wrote: the value alone would not say why
                raise IsoflowError(f"{cell} ({where}) holds {flat[at].item()!r}, {FILL_READ}: {why}; {FILL_ZERO}")
            raise IsoflowError(f"{cell} ({where}) holds {flat[at].item()!r}: {why}")
    return flat.astype(kind).reshape(vol.shape)


def unmasked(array, first_layer: int = 0, axis: int = 0) -> np.ndarray:
    """A part of a label image read as a NumPy array, a part with masked
    elements refused: a masked NumPy array's, or a dask array's of masked
    blocks (``dask.array.ma``), computed as itself, where
    ``numpy.asarray`` would give the values stored under the mask as if
    they were labels. The line names the first masked voxel
    (``first_layer``: the index of the part's layer 0 along ``axis``).

    Examples
    --------
    >>> part = np.ma.masked_equal(np.array([[[1, 2], [2, 1]]]), 2)
    >>> try:
    ...     unmasked(part, first_layer=4)
    ... except IsoflowError as error:
    ...     print(str(error).split(";")[0])
    voxel (4, 0, 1) is masked (2 masked elements in voxel layer 4)
    >>> unmasked(np.ma.masked_equal(np.ones((1, 2, 2), int), 2)).tolist()
    [[[1, 1], [1, 1]]]
    """
    from ..errors import counted
    from ..scale.arrays import is_dask, is_masked_array, masked_remedy

    dask = is_dask(array)
    if dask:
        array = array.compute()
    masked = int(np.ma.count_masked(array)) if is_masked_array(array) else 0
    if not masked:
        return np.asarray(array)
    voxel = np.unravel_index(int(np.argmax(np.ma.getmaskarray(array))), array.shape)
    at = ", ".join(str(int(i) + (first_layer if d == axis else 0)) for d, i in enumerate(voxel))
    layers = array.shape[axis]
    span = f"voxel layer {first_layer}" if layers == 1 else f"voxel layers {first_layer}-{first_layer + layers - 1}"
    raise IsoflowError(f"voxel ({at}) is masked ({counted(masked, 'masked element')} in {span}); {masked_remedy(dask)}")


def _is_fill(value: np.floating, fill: object) -> bool:
    """Whether a float voxel's ``value`` is the array's fill value ``fill``
    (NaN matching NaN), in the voxel's own type."""
    same = fill_as(fill, np.asarray(value).dtype)
    if same is None:
        return False
    return bool(value == same or (np.isnan(value) and np.isnan(same)))


#: with numba already imported, the one pass over the label image answers
#: sooner than :func:`analyze` on each label's box from this many voxels on
LABEL_PASS_VOXELS = 250_000
#: the NumPy pass's work (:func:`numpy_work`) from which the compiled pass,
#: with the import of numba and its cached label kernels that a process
#: pays once before its first answer, is the sooner; somewhat below the
#: measured tie, as a whole command shows no difference near it and the
#: compiled pass is then loaded for the next image
NUMBA_START_WORK = 6_000_000
#: the work of one label's ``analyze`` call beyond its box's voxels, in voxels
LABEL_WORK = 13_000


def numpy_work(labels: int, box_voxels: int) -> int:
    """What :func:`box_rows` costs, in voxels: a fixed share per label and
    the voxels of every label's box (plus one voxel round)."""
    return labels * LABEL_WORK + box_voxels


def compiled_sooner(voxels: int, numba_loaded: bool, labels: int | None = None,
                    box_voxels: int | None = None, spent: int = 0) -> bool:
    """Whether ``method="auto"`` takes the compiled pass for an image of
    ``voxels`` voxels.

    Where numba is already imported (a process that used a compiled pass,
    or ``isoflow info`` that loaded numba while the file was read), the
    compiled pass is the sooner from :data:`LABEL_PASS_VOXELS` on. Where it
    is not, the compiled pass first pays numba's start, which the NumPy
    pass outruns only on few labels with small boxes: the NumPy pass's
    cost grows with the labels and their boxes, not with the image, so the
    choice compares :func:`numpy_work` with :data:`NUMBA_START_WORK`
    (``labels``: the nonzero labels; ``box_voxels``: their boxes' voxels
    together, or a lower bound such as the nonzero voxels, which decides
    for the compiled pass where it already reaches the start's work;
    ``spent``: the NumPy work that ``"auto"`` has already done on earlier
    images in this process, :data:`TALLY`, so that a loop over many
    small images pays numba's start once their work adds up to it, the
    ski-rental rule of :mod:`isoflow.scale.compiled`).
    On grain maps of 100 labels that is about 115^3 voxels; with 1,000
    labels or more, or labels scattered over the image, the compiled pass
    is the sooner from the smallest images on.

    Examples
    --------
    >>> compiled_sooner(64**3, numba_loaded=True)
    True
    >>> compiled_sooner(64**3, numba_loaded=False, labels=100, box_voxels=3 * 64**3)
    False
    >>> compiled_sooner(64**3, numba_loaded=False, labels=1000, box_voxels=3 * 64**3)
    True
    """
    if numba_loaded:
        return voxels >= LABEL_PASS_VOXELS
    if labels is None or box_voxels is None:
        raise IsoflowError("compiled_sooner needs labels and box_voxels where numba is not loaded")
    return numpy_work(labels, box_voxels) + spent >= NUMBA_START_WORK


#: the kind under which ``"auto"`` tallies the NumPy work of label tables
#: (:func:`isoflow.scale.compiled.tallied`)
TALLY = "label_table"


def _use_compiled(vol: np.ndarray, method: str) -> bool:
    """The pass to take (see :func:`compiled_sooner`); the NumPy pass that
    ``"auto"`` takes before numba is imported is counted in :data:`TALLY`."""
    import sys

    from ..scale.compiled import add_to_tally, check_method, have_numba, tallied

    method = check_method(method)
    if method == "compiled" and not have_numba():
        raise IsoflowError("method='compiled' needs numba: pip install numba")
    if method != "auto" or not have_numba():
        return method == "compiled"
    if "numba" in sys.modules or vol.size == 0:
        return compiled_sooner(vol.size, numba_loaded=True)
    # the NumPy pass sorts the image before any box, which costs about as
    # much a voxel as the boxes' analyze: from half the start's work the
    # sort and the labels' own voxels alone take as long
    if 2 * vol.size >= NUMBA_START_WORK:
        return True
    flat = vol.reshape(-1)
    if int(flat.min()) < 0 or int(flat.max()) > flat.size:
        # the count below holds one entry per value up to the largest (8
        # bytes a voxel at most): labels beyond the voxel count take the
        # general pass, as do negative ones
        return True
    # the labels and the nonzero voxels (a lower bound of the boxes) in one
    # count decide on many labels or large ones; else the boxes, from every
    # other voxel along each axis (an estimate only: both passes give the
    # same table)
    counts = np.bincount(flat.astype(np.intp, copy=False), minlength=1)
    labels = int(np.count_nonzero(counts[1:]))
    spent = tallied(TALLY)
    if compiled_sooner(vol.size, False, labels, flat.size - int(counts[0]), spent):
        return True
    boxes = every_other_boxes(vol)
    if compiled_sooner(vol.size, False, labels, boxes, spent):
        return True
    add_to_tally(TALLY, numpy_work(labels, boxes))
    return False


def every_other_boxes(vol: np.ndarray) -> int:
    """The voxels of the nonzero labels' boxes (each with one voxel round
    it, as :func:`box_rows` pads it) estimated from every other voxel
    along each axis: a label missed there has a box a voxel or two thin."""
    step = vol[::2, ::2, ::2]
    flat = step.reshape(-1)
    order = np.argsort(flat, kind="stable")
    values, starts = np.unique(flat[order], return_index=True)
    extent = np.ones((len(starts), vol.ndim), np.int64)
    for axis, coords in enumerate(np.unravel_index(order, step.shape)):
        extent[:, axis] = 2 * (np.maximum.reduceat(coords, starts) - np.minimum.reduceat(coords, starts)) + 4
    return int(np.prod(extent, axis=1)[values != 0].sum())


def checked_background(background: object, labels: object, function: str) -> bool:
    """``background`` as a bool, refused beside a choice of ``labels``
    (which asks for the background's row by holding 0).

    Examples
    --------
    >>> checked_background(True, None, "label_table")
    True
    >>> checked_background(True, [3], "label_table")
    Traceback (most recent call last):
    isoflow.errors.IsoflowError: label_table: background=True adds 0's row to every label's; with labels, ask for 0
    """
    background = check_switch(background, "background", function)
    if background and labels is not None:
        raise IsoflowError(f"{function}: background=True adds 0's row to every label's; with labels, ask for 0")
    return background


def present_labels(piece_values: np.ndarray, dtype) -> np.ndarray:
    """Every label the pieces hold (values as
    :func:`~isoflow.scale.pieces.piece_runs` gives them, piece 0 the
    outside), 0 among them, in increasing order, in the image's type: the
    rows of every label and the background, once the pieces are known."""
    values = distinct(piece_values[1:])[0]
    kind = np.dtype(dtype)
    return np.sort(values.astype(f"u{kind.itemsize}").view(kind))


def wanted_labels(labels, dtype, where: str | None = None) -> np.ndarray:
    """The labels asked for, as values of the image's type: each one a
    whole number (:func:`~isoflow.errors.whole_given`: not ``1.5`` or a
    bool) the type holds, none twice; a refusal begins with ``where`` where
    given (the function called and its argument: ``label_table: labels``)."""
    if isinstance(labels, Iterable) and not isinstance(labels, (str, bytes, np.ndarray)):
        # a generator, a set, dict keys: their labels in their order (NumPy holds such an object as one value)
        labels = list(labels)
    # a 0D array of an integer (np.load of a saved label) is that integer
    head = "" if where is None else f"{where}: "
    asked: list[Any] = [scalar_given(value) for value in np.atleast_1d(np.asarray(labels, dtype=object)).ravel()]
    info = np.iinfo(label_dtype(dtype))
    values: list[int] = []
    for value in asked:
        whole = whole_given(value)
        if whole is None:
            # True taken as label 1, or 1.5 as label 1, would hide a slip (a mask's values, a mean) behind a row
            raise IsoflowError(f"{head}label {given_text(value)} is not an integer: labels are asked for as whole "
                               "numbers")
        if not info.min <= whole <= info.max:
            raise IsoflowError(f"{head}label {given_text(value)} is not a value the labels of this image hold: they are "
                               f"{np.dtype(dtype)} ({info.min} to {info.max})")
        values.append(whole)
    if len(set(values)) != len(values):
        twice = sorted({v for v in values if values.count(v) > 1})
        raise IsoflowError(f"{head}labels asked twice: {', '.join(map(str, twice))}")
    return np.array(values, dtype=dtype)


#: how closely two pieces must touch to be joined (1 face, 2 edge, 3
#: vertex), per connectivity: for the label's mesh solid, its b0, the mesh
#: solid's complement and the complement under the other connectivity (b2)
#: (the mesh's adjacencies: closed_surfaces.MESH_ADJACENCY)
JOINS = {6: (1, 1, 2, 3), 26: (2, 3, 1, 1)}


#: bytes per voxel the compiled path takes beyond the image at the least:
#: the first buffers of the runs (8 bytes a run, a run per 16 voxels: 0.5)
#: and the per-thread tables of a grain map (its peak: 0.5 byte a voxel at
#: 512^3 with 1,000 labels, 1.0 at 256^3); the runs as they are made, and
#: the pieces with what the passes after them take per piece
#: (:func:`later_bytes`) as soon as they are counted (many small labels
#: take far more: 7 bytes a voxel at 256^3 with 100,000 labels, noise of
#: many labels about 660), so that a large image of few labels is not
#: refused for what only many labels need
PIECE_BYTES_PER_VOXEL = 1


#: pairs of pieces per piece that the label table's need is reckoned with,
#: :data:`PAIRS_PER_PIECE` plus :data:`PAIRS_PER_SMALL_PIECE` over the
#: voxels a piece holds on average (measured, ``benchmarks/.cache`` and
#: random images at 64^3): the pieces of a grain map (140 voxels or more
#: each) touch 7 or 8 others, which is what a cell of a 3D tessellation
#: does; pieces of one voxel (noise of many labels) 12.7, of 1.4 voxels
#: (noise of 10 labels) 11.6; thin or sparse pieces fewer (columns 4.9,
#: noise of 2 labels 2.6, sheets 2.0)
PAIRS_PER_PIECE = 8
PAIRS_PER_SMALL_PIECE = 5


def later_bytes(pieces: int, voxels_per_piece: float = 1.0) -> int:
    """Bytes that the label table's passes after the pieces take at their
    peak for ``pieces`` pieces of ``voxels_per_piece`` voxels on average
    (their pairs reckoned as :data:`PAIRS_PER_PIECE` said, or every pair
    of them where they are fewer): the features and doubled edges of each
    piece, and the larger of the pairs' entries (held until the graph is
    made of them, each block let go as it is placed) and the graph (its
    edges both ways and its starts) with the walks' scratch on every
    thread.

    Examples
    --------
    >>> from isoflow.scale.compiled import using
    >>> with using(1):  # noise of many labels, a grain map, three pieces
    ...     later_bytes(10**6) // 10**6, later_bytes(10**6, 140) // 10**6, later_bytes(3)
    (538, 408, 678)
    """
    from ..scale.compiled import thread_count
    from ..scale.piece_graph import GRAPH_EDGE_BYTES, TOPOLOGY_BYTES
    from ..scale.pieces import FEATURE_BYTES, PAIR_ENTRY_BYTES

    per_piece = PAIRS_PER_PIECE + PAIRS_PER_SMALL_PIECE / max(voxels_per_piece, 1.0)
    pairs = min(int(per_piece * pieces), pieces * (pieces - 1) // 2)
    graph = 8 * pieces + pairs * 2 * GRAPH_EDGE_BYTES
    return FEATURE_BYTES * pieces + max(pairs * PAIR_ENTRY_BYTES, graph + TOPOLOGY_BYTES * thread_count() * pieces)


#: ``"auto"`` takes the label-by-label pass, once the pieces are counted,
#: where they are this share of the voxels or more for each value of the
#: image: the one pass spends about 3 us a piece on a noisy segmentation
#: (every block holds pieces of several values, whose pairs it adds up),
#: the census of each label's mask about 3 ns a voxel of the whole image and
#: a third of a microsecond a piece (the measures: docs/labels.md, "NumPy
#: path"); a smooth segmentation, or one of hundreds of labels, keeps the
#: one pass
FRAGMENTED = 0.0015
#: before the pieces of the whole image are counted, slabs of this share of
#: its layers along axis 0 each, at a quarter, a half and three quarters of
#: it, are cut into pieces: where each holds :data:`SAMPLE_MARGIN` times
#: :data:`FRAGMENTED` pieces a voxel for each value of the image or more,
#: the label-by-label pass is taken without the whole count (a slab cuts
#: the pieces that cross it, so it overstates the image's pieces a voxel:
#: the margin)
SAMPLE_LAYERS = 1 / 64
SAMPLE_MARGIN = 2


#: the shares of a label table's progress bar of each stage of its passes
#: (:class:`~isoflow.scale.ticks.Ticks`): of the pieces, of the vertex pass
#: over their blocks, of the graph of pieces, of the walks of the graph
#: label by label; the label-by-label pass takes what is left where it
#: takes over. Noise spends half its time in the graph and the walks, a
#: grain map most of it in the vertex pass: the shares lie between
STAGES = {"pieces": 10, "vertices": 45, "graph": 10, "walks": 35}


def piece_rows(vol: np.ndarray, conn: int, wanted: np.ndarray | None, surfaces: bool,
               background: bool = False, rather: bool = False, ticks: Ticks | None = None) -> dict | np.ndarray:
    """The rows by the compiled passes: the pieces, one vertex pass, the
    graph of pieces label by label (see the module docs); an image of more
    voxels than the pieces are numbered in, in slabs along axis 0 as a
    store is read (:func:`slab_rows`). ``background``: with ``wanted``
    None, label 0's row too. With ``rather``: where the pieces say the
    label-by-label pass is the sooner (:data:`FRAGMENTED`), not the rows
    but the image's values (:func:`present_labels`), which that pass
    takes.
    ``ticks``: the progress (:data:`STAGES`), and where the passes stop on
    a signal."""
    from ..scale.pieces import MAX_PIECE_VOXELS, piece_runs, vertex_pass

    copy = 0 if vol.flags.c_contiguous else vol.nbytes
    check_fits(PIECE_BYTES_PER_VOXEL * vol.size + copy, f"the label table of a {'x'.join(map(str, vol.shape))} "
               f"label image", hint="store it as .zarr and run isoflow info --labels on that (block by block)")
    if vol.size > MAX_PIECE_VOXELS:
        return slab_rows(np.ascontiguousarray(vol), conn, wanted, surfaces, [vol.shape[0]],
                         progress=None if ticks is None or ticks.progress is None else ticks.follow,
                         background=background)
    if rather:
        present = sampled_fragmented(vol)
        if present is not None:
            return present
    pieces = piece_runs(vol, later=later_bytes, ticks=ticks)
    if rather and pieces["n"] >= FRAGMENTED * vol.size:  # (the image holds one value at least)
        present = present_labels(pieces["values"], vol.dtype)
        if pieces["n"] >= FRAGMENTED * len(present) * vol.size:
            return present
    if background:  # every label present, 0 among them: the pieces say which
        wanted = present_labels(pieces["values"], vol.dtype)
    want = wanted_pieces(pieces["values"], vol.dtype, wanted)
    # the pairs' blocks read where they are by the graph of pieces, not copied into one set of arrays first
    passed = vertex_pass(vol, pieces, want, feature_table(conn), pass_tables(conn, surfaces), keep_runs=False,
                         joined=False, ticks=ticks)
    return rows_of_pieces(pieces, passed, vol.dtype, conn, wanted, ticks)


def sampled_fragmented(vol: np.ndarray) -> np.ndarray | None:
    """The image's values (as :func:`present_labels` gives them) where
    slabs of its layers say that the label-by-label pass is the sooner
    (:data:`SAMPLE_LAYERS`), else None (and where its values are spread
    too wide to count in a table, :func:`image_values`: the pieces find
    those).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> sampled_fragmented(rng.integers(0, 3, (64, 32, 32)).astype(np.uint8)).tolist()  # noise of three values
    [0, 1, 2]
    >>> sampled_fragmented(np.repeat(np.arange(64, dtype=np.uint8) // 16, 1024).reshape(64, 32, 32)) is None
    True
    """
    from ..errors import DoesNotFit
    from ..scale.pieces import piece_runs

    nx = vol.shape[0]
    layers = max(2, round(SAMPLE_LAYERS * nx))
    if 3 * layers > nx:
        return None
    least = float("inf")
    with budget_held():  # the memory available read once for the three slabs
        for at in (nx // 4, nx // 2, 3 * nx // 4):
            slab = vol[at - layers // 2:at - layers // 2 + layers]
            try:
                pieces = piece_runs(np.ascontiguousarray(slab))
            except DoesNotFit:  # the whole image's count says what fits
                return None
            share = pieces["n"] / slab.size
            values = len(present_labels(pieces["values"], vol.dtype))
            if share < SAMPLE_MARGIN * FRAGMENTED * values:
                return None
            least = min(least, share)
    present = image_values(vol)
    if present is None or least < SAMPLE_MARGIN * FRAGMENTED * len(present):
        return None
    return present


#: the voxels of an image read at a time by :func:`image_values`
VALUES_STEP = 1 << 20


def image_values(vol: np.ndarray) -> np.ndarray | None:
    """The values of an integer image, in increasing order, in its type,
    read a step of voxels at a time (:data:`VALUES_STEP`) into a table of
    the span of its values; None where that span is wider than
    :func:`distinct` counts in a table.

    Examples
    --------
    >>> image_values(np.array([[[7, -2], [7, 0]]], np.int8)).tolist()
    [-2, 0, 7]
    >>> image_values(np.array([[[0, 2**40]]], np.uint64)) is None  # ids spread wide
    True
    """
    if vol.size == 0:
        return np.zeros(0, vol.dtype)
    lo, hi = int(vol.min()), int(vol.max())
    if hi - lo > DISTINCT_SPAN * vol.size + DISTINCT_SLACK:
        return None
    seen = np.zeros(hi - lo + 1, bool)
    flat = vol.reshape(-1)
    for start in range(0, flat.size, VALUES_STEP):
        seen[_offsets(flat[start:start + VALUES_STEP], lo)] = True
    return _seen_values(seen, lo, vol.dtype)


def rows_in_image_order(found: dict, axes: Sequence[int]) -> dict:
    """The rows' sums of an image read with its axes in the order ``axes``
    (:func:`slab_rows` of its slabs across another axis than the first),
    put back in the image's order: the boxes, the voxels' index sums and
    the faces per normal axis. The rest (classes, energy, the graph of
    pieces) is the same in any order of the axes.

    Parameters
    ----------
    found : dict
        The rows' sums (:func:`rows_of_pieces`), per axis in the order ``axes``.
    axes : sequence of int
        The image's axes in the order they were read.

    Returns
    -------
    dict
        ``found``, its per-axis columns in the image's order.

    Examples
    --------
    >>> found = {"lo": np.array([[2, 0, 1]]), "hi": np.array([[5, 3, 4]]), "sums": np.array([[9, 1, 4]]),
    ...          "features": np.zeros((1, 17), np.int64)}
    >>> rows_in_image_order(found, (2, 0, 1))["lo"].tolist()  # read as (z, x, y)
    [[0, 1, 2]]
    """
    back = np.argsort(np.asarray(axes))
    out = dict(found)
    for key in ("lo", "hi", "sums"):
        out[key] = found[key][:, back]
    out["features"] = found["features"].copy()
    out["features"][:, FACES] = found["features"][:, FACES][:, back]
    return out


def slab_rows(array, conn: int, wanted: np.ndarray | None, surfaces: bool, sizes: list[int],
              progress: Callable[[int, int], object] | None = None, axes: Sequence[int] = (0, 1, 2),
              background: bool = False) -> dict:
    """The rows of a 3D label array read in slabs of ``sizes`` voxel layers
    along axis 0 (``array[a:b]``, never whole; cut further where a slab
    would hold more voxels than the pieces are numbered in; for an array
    that is not in memory, each boundary a layer lower,
    :func:`one_read_sizes`), with
    ``progress(done, total)`` after each slab; ``axes``: the image's axes
    in the order the array reads them, which its refusals name;
    ``background``: with ``wanted`` None, label 0's row too."""
    # every layer's cuts first: a layer too wide for the pieces' numbers is refused before any read
    cuts = [slab_sizes([n], array.shape, axes) for n in sizes]
    if not isinstance(array, np.ndarray):
        # each slab one layer less at its top, so that its read (a voxel layer beyond it on either side)
        # ends where its layer of chunks ends and begins with the two layers the slab before read last
        # (SlabStream.carry): every layer of chunks decoded once, not once more for each neighbour's layer
        shifted = one_read_sizes(sizes)
        shifted_cuts = [slab_sizes([n], array.shape, axes) for n in shifted]
        if all(len(parts) == 1 for parts in shifted_cuts):  # (a layer cut into thinner slabs is held whole)
            cuts = shifted_cuts
    stream = SlabStream(array, conn, wanted, surfaces, axes)
    stream.background = background
    stream.thickest = min(max((max(parts, default=0) for parts in cuts), default=0) + 2, stream.nx)
    total, done, x0 = sum(len(parts) for parts in cuts), 0, 0
    for parts in cuts:
        if len(parts) > 1:  # a layer of chunks cut into thinner slabs: read once where it fits, not once a slab
            stream.hold(x0, x0 + sum(parts), max(parts))
        for part in parts:
            stream.slab(x0, x0 + part)
            x0 += part
            done += 1
            if progress is not None:
                progress(done, total)
        stream.held = None
    pieces, passed = stream.joined()
    if background:  # every label the slabs hold, 0 among them
        wanted = present_labels(pieces["values"], label_dtype(array.dtype))
    return rows_of_pieces(pieces, passed, label_dtype(array.dtype), conn, wanted)


def one_read_sizes(sizes: Sequence[int]) -> list[int]:
    """Slab sizes (voxel layers) that move each boundary between slabs one
    layer down: a slab's read (:meth:`SlabStream.slab`: a voxel layer of
    each neighbour beside its own) then ends where the layer of ``sizes``
    ends, and begins with the two layers the slab before it read last.
    Unchanged where there is one slab or the first is one layer thick.

    Parameters
    ----------
    sizes : sequence of int
        The layers of the slabs, in order (a store's layers of chunks).

    Returns
    -------
    list of int
        The same number of slabs over the same layers.

    Examples
    --------
    >>> one_read_sizes([64, 64, 64, 64])
    [63, 64, 64, 65]
    >>> one_read_sizes([1, 5]), one_read_sizes([256])
    ([1, 5], [256])
    """
    sizes = [int(n) for n in sizes]
    if len(sizes) < 2 or sizes[0] < 2:
        return sizes
    return [sizes[0] - 1, *sizes[1:-1], sizes[-1] + 1]


def label_bits(labels: np.ndarray, dtype) -> np.ndarray:
    """Labels of an image of ``dtype`` as the pieces hold them: their
    bits, unsigned, as uint64."""
    width = np.dtype(dtype).itemsize
    return np.asarray(labels, dtype=dtype).view(f"u{width}").astype(np.uint64)


def wanted_pieces(values: np.ndarray, dtype, wanted: np.ndarray | None, background: bool = False) -> np.ndarray:
    """Per piece (values as :func:`~isoflow.scale.pieces.piece_runs`
    gives them, 0 the outside), whether its label has a row (with
    ``wanted`` None, every nonzero label's, with ``background`` 0's too)."""
    if wanted is None:
        want = np.ones(len(values), bool) if background else values != 0
    else:
        want = np.isin(values, label_bits(wanted, dtype))
    want[0] = False
    return want


def pass_tables(conn: int, surfaces: bool) -> tuple:
    """The sheet tables of the vertex pass; without the surfaces no sheets
    and no doubled spokes (only the histogram and the graph)."""
    tables = sweep_tables(conn)
    if surfaces:
        return tables
    return (np.zeros_like(tables[0]),) + tables[1:4] + (np.zeros_like(tables[4]), tables[5])


def rows_of_pieces(pieces: dict, passed: dict, dtype, conn: int, wanted: np.ndarray | None,
                   ticks: Ticks | None = None) -> dict:
    """The rows' sums from the pieces (values, counts, sums, boxes) and
    what the vertex pass found (features, doubled edges, pairs);
    ``ticks``: the progress of the graph and its walks."""
    from ..scale.piece_graph import grouped

    values, piece_label, rows = label_rows(pieces["values"], dtype, wanted)
    # every label's pieces, for its sums and for the graph (each label has one piece at least)
    lab_start, lab_pieces = grouped(piece_label[1:], len(values), np.arange(1, len(piece_label), dtype=np.int64))
    topology = graph_topology(pieces, piece_label, rows, passed, conn, lab_start, lab_pieces, ticks)
    by_label = label_sums(pieces, piece_label, passed, len(values))
    found = {key: at_rows(column, rows) for key, column in by_label.items()}
    found.update(topology)
    dtype = np.dtype(dtype)
    found["label"] = np.zeros(len(rows), dtype) if wanted is None else wanted.astype(dtype)
    found["label"][rows >= 0] = values[rows[rows >= 0]].astype(f"u{dtype.itemsize}").view(dtype)
    return found


def label_rows(piece_values: np.ndarray, dtype, wanted) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct values of the pieces (their bits, uint64), each piece's
    index among them (-1 for the outside, piece 0) and the index of every
    row of the table (-1 for a label asked for that is absent)."""
    values, inverse = distinct(piece_values[1:])
    piece_label = np.concatenate([[-1], inverse]).astype(np.int64)
    if wanted is None:
        rows = np.flatnonzero(values != 0)
        kind = np.dtype(dtype)
        if kind.kind == "i":  # the bits sort negative labels after the positive ones: rows go by value
            signed = values[rows].astype(f"u{kind.itemsize}").view(kind)
            rows = rows[np.argsort(signed, kind="stable")]
        return values, piece_label, rows
    bits = label_bits(wanted, dtype)
    at = np.minimum(np.searchsorted(values, bits), max(len(values) - 1, 0))
    found = (len(values) > 0) & (values[at] == bits) if len(values) else np.zeros(len(bits), bool)
    return values, piece_label, np.where(found, at, -1)


#: :func:`distinct` counts values spanning up to this many times their
#: number (plus :data:`DISTINCT_SLACK`) in a table over their range, and
#: sorts sparser ones
DISTINCT_SPAN = 4
DISTINCT_SLACK = 1024


def distinct(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(values, return_inverse=True)`` of a 1D integer array:
    the distinct values, in order, and each value's index among them.

    Labels are mostly numbered densely, so their range is counted in a
    table, without a sort (unique's inverse takes NumPy's default argsort,
    slow on many equal keys); sparse values are sorted, as unique does.

    Examples
    --------
    >>> values, inverse = distinct(np.array([7, 3, 7, 5], np.uint32))
    >>> values.tolist(), inverse.tolist()
    ([3, 5, 7], [2, 0, 2, 1])
    """
    if len(values) == 0:
        return np.unique(values, return_inverse=True)
    lo, hi = int(values.min()), int(values.max())
    if hi - lo > DISTINCT_SPAN * len(values) + DISTINCT_SLACK:
        return np.unique(values, return_inverse=True)
    shift = _offsets(values, lo)
    seen = np.zeros(hi - lo + 1, bool)
    seen[shift] = True
    return _seen_values(seen, lo, values.dtype), (np.cumsum(seen) - 1)[shift]


def _wide(dtype) -> type:
    """The 64-bit integer type of ``dtype``'s sign, in which a value less
    the lowest does not wrap round as in a narrow type."""
    return np.int64 if np.dtype(dtype).kind == "i" else np.uint64


def _offsets(values: np.ndarray, lo: int) -> np.ndarray:
    """Each of the integers ``values`` less ``lo`` (their lowest), as
    indices into a table of their span."""
    wide = _wide(values.dtype)
    return (values.astype(wide) - wide(lo)).astype(np.intp)


def _seen_values(seen: np.ndarray, lo: int, dtype) -> np.ndarray:
    """The values marked in a table of a span from ``lo`` (:func:`_offsets`),
    in order, in ``dtype``."""
    wide = _wide(dtype)
    return (np.flatnonzero(seen).astype(wide) + wide(lo)).astype(dtype)


def at_rows(column: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """A per-label column at the table's rows, zero where a row's label is
    absent: a view where the rows are a run of labels (every label, the
    common case), no copy."""
    if len(rows) and rows[0] >= 0 and rows[-1] - rows[0] == len(rows) - 1 and (np.diff(rows) == 1).all():
        return column[rows[0]:rows[-1] + 1]
    out = column[np.maximum(rows, 0)] if len(column) else np.zeros((len(rows),) + column.shape[1:], column.dtype)
    out[rows < 0] = 0
    return out


def label_sums(pieces: dict, piece_label: np.ndarray, passed: dict, nlabels: int) -> dict:
    """Per label (all ``nlabels`` of them, each with one piece at least):
    voxels, coordinate sums, box, features and doubled edges, added up
    over its pieces (``piece_label``: each piece's label, -1 for piece 0,
    the outside)."""
    from ..scale.piece_graph import add_by_label, box_by_label

    of = piece_label[1:]
    lo = np.full((nlabels, 3), np.iinfo(np.int64).max, np.int64)
    hi = np.full((nlabels, 3), -1, np.int64)
    box_by_label(of, pieces["lo"][1:], pieces["hi"][1:], lo, hi)
    totals = {key: np.zeros((nlabels,) + column.shape[1:], np.int64)
              for key, column in (("voxels", pieces["counts"]), ("sums", pieces["sums"]), ("doubled", passed["doubled"]))}
    # a feature per row and a label per column, seen transposed: each feature's column of the table (n-0 ..,
    # energy) is then one contiguous run, which its text (--json, --csv) reads a block at a time, rather than
    # every 17th number of the whole table
    totals["features"] = np.zeros((passed["features"].shape[1], nlabels), np.int64).T
    add_by_label(of, pieces["counts"][1:], pieces["sums"][1:], passed["features"][1:], passed["doubled"][1:],
                 totals["voxels"], totals["sums"], totals["features"], totals["doubled"])
    return {**totals, "lo": lo, "hi": hi}


def graph_topology(pieces: dict, piece_label: np.ndarray, rows: np.ndarray, passed: dict, conn: int,
                   lab_start: np.ndarray, lab_pieces: np.ndarray, ticks: Ticks | None = None) -> dict:
    """b0, b2 and the surfaces of every row from the graph of pieces (each
    label's pieces: ``lab_pieces[lab_start[l]:lab_start[l + 1]]``)."""
    from ..scale.piece_graph import entries_graph, label_topology
    from ..scale.pieces import NONE

    n = len(piece_label)
    # the pairs handed over, not kept here: entries_graph lets each block go once it is placed
    if "entries" in passed:  # the vertex pass' blocks of pairs as they are (vertex_pass(..., joined=False))
        graph = entries_graph(passed.pop("entries"), n, NONE, ticks)
    else:
        graph = entries_graph([tuple(passed.pop(key) for key in ("keys", "kind", "sums"))], n, NONE, ticks)
    present = np.flatnonzero(rows >= 0)
    obj_kind, b0_kind, bg_kind, cc_kind = JOINS[conn]
    found = label_topology(rows[present].astype(np.int64), lab_start, lab_pieces, piece_label, pieces["lo"],
                           pieces["hi"], *graph, obj_kind, b0_kind, bg_kind, cc_kind, ticks)
    b0, b2 = np.zeros(len(rows), np.int64), np.zeros(len(rows), np.int64)
    b0[present], b2[present] = found[0], found[1]
    return {"b0": b0, "b2": b2, "surface_rows": present[found[2]], "surface_chi": found[3],
            "surface_faces": found[4]}


def decoded_at_once() -> int:
    """The chunks that one read of a zarr array decodes at a time: zarr's
    ``async.concurrency`` (10 unless configured), each decoded whole
    before its part is copied out.

    Examples
    --------
    >>> decoded_at_once() >= 1
    True
    """
    import sys

    zarr = sys.modules.get("zarr")
    try:
        return max(int(zarr.config.get("async.concurrency")), 1) if zarr is not None else 10
    except (AttributeError, KeyError, TypeError, ValueError):  # zarr 2, without that setting, decodes one at a time
        return 1


def slab_sizes(sizes: list[int], shape, axes: Sequence[int] = (0, 1, 2)) -> list[int]:
    """The slabs cut where one, with its voxel layer either side, would hold
    more voxels than the pieces' 32-bit numbers reach: a store whose chunks
    are 256 layers of 4096 x 4096 voxels is read in slabs of 253 layers.
    The table is the same for any slabs, so only their size changes.
    ``shape`` is as read, ``axes`` the image's axes in that order (the
    refusal names them as the image has them)."""
    from ..scale.pieces import MAX_PIECE_VOXELS

    area = int(np.prod([int(n) for n in shape[1:]], dtype=np.int64))
    most = MAX_PIECE_VOXELS // max(area, 1) - 2
    if most < 1:
        across, other = "xyz"[axes[0]], " and ".join(sorted("xyz"[a] for a in axes[1:]))
        raise IsoflowError(f"a label image whose layers across {across} hold {area} voxels each is read three "
                           f"layers at a time, more than the {MAX_PIECE_VOXELS} voxels its pieces are numbered in; "
                           f"crop or split it along {other}")
    return [part for n in sizes for part in [most] * (n // most) + [n % most] if part]


class SlabStream:
    """What the slabs found so far: per piece (numbered across slabs) its
    statistics, features and doubled edges, the pairs of pieces, and the
    pairs of numbers that name one piece in two slabs."""

    def __init__(self, array, conn: int, wanted, surfaces: bool, axes: Sequence[int] = (0, 1, 2)):
        self.array, self.conn, self.wanted, self.surfaces = array, conn, wanted, surfaces
        self.axes = tuple(int(a) for a in axes)  # the image's axes as the array reads them
        self.nx = int(array.shape[0])
        self.total = 0  # pieces numbered so far (0: the outside)
        self.parts: dict[str, list] = {k: [] for k in ("values", "counts", "sums", "lo", "hi", "features",
                                                       "doubled", "keys", "kind", "sums_pairs", "same")}
        #: the previous slab's last two voxel layers, numbered as that slab numbers its pieces (uint32), and the
        #: number before its first piece across slabs
        self.tail: tuple[int, np.ndarray] | None = None
        #: the previous slab's read's last two voxel layers (the first of them, the labels), which the next
        #: slab's read begins with: taken from here, not read (and their chunks decoded) again
        self.carry: tuple[int, np.ndarray] | None = None
        #: the voxel layers read for the slabs of one layer of chunks (its first layer, the labels), or None
        self.held: tuple[int, np.ndarray] | None = None
        #: the voxel layers of the thickest slab's read (:func:`slab_rows` sets it), for what chunks would fit
        self.thickest = self.nx
        #: with ``wanted`` None, whether the background's pieces are wanted too (:func:`slab_rows` sets it)
        self.background = False

    def in_image_order(self, sides: Sequence[int]) -> list[int]:
        """Sides given along the axes as the array reads them, in the image's (x, y, z) order."""
        return [int(sides[self.axes.index(axis)]) for axis in range(3)]

    def read_bytes(self) -> int:
        """Bytes a voxel of a read holds as read: its stored value and, for
        a float image, its int64 copy."""
        stored = np.dtype(self.array.dtype)
        return stored.itemsize + (label_dtype(stored).itemsize if stored.kind == "f" else 0)

    @cached_property
    def chunk_layout(self) -> tuple[list[int], int, int] | None:
        """The array's chunks as a read decodes them: a chunk's sides as
        the array reads them, the chunks across one layer of them, and a
        chunk's voxels decoded whole; None for an array in memory (the
        array's metadata, read once for every slab's reads)."""
        from ..scale.chunks import decoded_chunk_voxels

        chunks = None if isinstance(self.array, np.ndarray) else getattr(self.array, "chunks", None)
        if not chunks:
            return None
        voxels = decoded_chunk_voxels(self.array)
        if not voxels:
            return None
        sides = [max(int(c) for c in side) if isinstance(side, tuple) else int(side) for side in chunks]
        across = int(np.prod([-(-int(n) // s) for n, s in zip(self.array.shape[1:], sides[1:])], dtype=np.int64))
        return sides, across, voxels

    def decoded(self, a: int, b: int) -> tuple[int, int, list[int]]:
        """What a read of voxel layers a .. b - 1 decodes beside the voxels
        it gives: the chunks decoded at a time, their bytes, and a chunk's
        sides as the array reads them (0, 0, [] for an array in memory)."""
        layout = self.chunk_layout
        if layout is None:
            return 0, 0, []
        sides, across, voxels = layout
        at_once = min(((b - 1) // sides[0] - a // sides[0] + 1) * across, decoded_at_once())
        return at_once, at_once * voxels * np.dtype(self.array.dtype).itemsize, sides

    def check_read(self, a: int, b: int, need: int, what: str) -> None:
        """Refuse a read of voxel layers a .. b - 1 whose ``need`` bytes,
        with the chunks it decodes whole, would not fit the budget; where
        the voxels fit and the chunks do not, the line names the chunks
        and the largest that would fit."""
        from ..scale import memory

        at_once, decoded, sides = self.decoded(a, b)
        layout = self.chunk_layout
        budget = memory.default_budget()
        along = "xyz"[self.axes[0]]
        hint = f"write the store with smaller chunks along {along}"
        if layout is not None and need + decoded > budget:
            # smaller chunks: the thickest slab's read may cross two layers of them, every chunk of each decoded
            thickest = need // max(b - a, 1) * max(self.thickest, b - a)
            across = layout[1]
            fit = (budget - thickest) // (min(2 * across, decoded_at_once()) * np.dtype(self.array.dtype).itemsize)
            what += (f" and the {'chunk' if at_once == 1 else f'{at_once} chunks'} of "
                     f"{'x'.join(map(str, self.in_image_order(sides)))} voxels its read decodes whole")
            if fit >= 1:
                hint = f"chunks of at most {fit:,} voxels fit: write the store with smaller chunks"
        check_fits(need + decoded, what, hint=hint, budget=budget)

    def hold(self, x0: int, x1: int, most: int) -> None:
        """Read voxel layers x0 .. x1 - 1 (a layer of chunks cut into slabs
        of at most ``most`` layers) with one voxel layer of each neighbour,
        once for all its slabs, where they fit beside the chunks the read
        decodes and one slab's passes and copy: a read of each thin slab
        decodes every chunk it crosses whole again. Where they do not fit
        each slab reads its own layers (and is checked as it does)."""
        from ..scale import memory

        self.held = None
        if isinstance(self.array, np.ndarray):  # a view of it costs nothing: the slabs take theirs
            return
        a, b = max(x0 - 1, 0), min(x1 + 1, self.nx)
        area = int(np.prod([int(s) for s in self.array.shape[1:]], dtype=np.int64))
        slab = (most + 2) * area * (PIECE_BYTES_PER_VOXEL + label_dtype(self.array.dtype).itemsize)
        if (b - a) * area * self.read_bytes() + self.decoded(a, b)[1] + slab > memory.default_budget():
            return
        vol = as_labels(self.array[a:b], first_layer=a, fill=getattr(self.array, "fill_value", None))
        self.held = (a, vol)

    def slab(self, x0: int, x1: int) -> None:
        """The pieces and the vertex pass of voxel layers x0 .. x1 - 1."""
        from ..scale.pieces import piece_ids, piece_runs, vertex_pass

        a, b = max(x0 - 1, 0), min(x1 + 1, self.nx)
        shape = (b - a,) + tuple(int(s) for s in self.array.shape[1:])
        voxels = int(np.prod(shape, dtype=np.int64))
        # refusals name the image's axes as the user has them: the slab's layers go along axes[0]
        along = "xyz"[self.axes[0]]
        what = f"a slab of {'x'.join(map(str, self.in_image_order(shape)))} voxels of the label image"
        if self.held is not None and self.held[0] <= a and b <= self.held[0] + len(self.held[1]):
            view = self.held[1][a - self.held[0]:b - self.held[0]]  # read with its layer of chunks
            copy = 0 if view.flags.c_contiguous else view.nbytes
            check_fits(PIECE_BYTES_PER_VOXEL * voxels + copy, what, hint=f"write the store with smaller chunks along {along}")
            vol = np.ascontiguousarray(view)
        else:
            carried = self.carry[1] if self.carry is not None and self.carry[0] == a and b - a > 2 else None
            start = a if carried is None else a + len(carried)
            self.check_read(start, b, (PIECE_BYTES_PER_VOXEL + self.read_bytes()) * voxels, what)
            read = as_labels(self.array[start:b], first_layer=start,
                             fill=getattr(self.array, "fill_value", None))
            vol = np.ascontiguousarray(read if carried is None else np.concatenate([carried, read]))
        self.carry = None if b == self.nx or isinstance(self.array, np.ndarray) else (b - 2, vol[-2:].copy())
        pieces = piece_runs(vol, first=x0 - a, last=x1 - a, x0=a, axis=along, later=later_bytes, before=self.total)
        want = wanted_pieces(pieces["values"], vol.dtype, self.wanted, self.background)
        passed = vertex_pass(vol, pieces, want, feature_table(self.conn), pass_tables(self.conn, self.surfaces),
                             layers=(x0, x1 + (x1 == self.nx)), nx=self.nx, x0=a, base=self.total, axis=along)
        if self.tail is not None:  # voxel layers x0 - 1 and x0, read by both slabs: one piece, two numbers
            base, tail = self.tail
            # each pair as one 64-bit number (the slabs' own 32-bit numbers, which fit): sorted as numbers, in the
            # pairs' order, where unique over rows would sort them as records, element by element
            packed = np.unique((tail.reshape(-1).astype(np.uint64) << np.uint64(32))
                               | piece_ids(pieces, vol.shape, (0, 2)).reshape(-1))
            pairs = np.empty((len(packed), 2), np.int64)
            pairs[:, 0] = (packed >> np.uint64(32)).astype(np.int64) + base
            pairs[:, 1] = (packed & np.uint64(0xFFFFFFFF)).astype(np.int64) + self.total
            self.parts["same"].append(pairs)
        self.tail = None
        if x1 < self.nx:  # the slab's own numbers (uint32) and what makes them the image's
            self.tail = (self.total, piece_ids(pieces, vol.shape, (x1 - 1 - a, x1 + 1 - a)))
        for key in ("values", "counts", "sums", "lo", "hi"):
            self.parts[key].append(pieces[key][1:])
        self.parts["features"].append(passed["features"][1:])
        self.parts["doubled"].append(passed["doubled"][1:])
        self.parts["keys"].append(passed["keys"])
        self.parts["kind"].append(passed["kind"])
        self.parts["sums_pairs"].append(passed["sums"])
        self.total += pieces["n"]

    def joined(self) -> tuple[dict, dict]:
        """The pieces and the vertex pass's findings of the whole image:
        pieces named in two slabs made one (numbered 1.. in order of their
        first number), their sums added, their boxes joined. A pair of
        pieces met in two slabs keeps an entry from each, as a pair met by
        two threads does: the graph of pieces adds them up
        (:func:`~isoflow.scale.piece_graph.pair_graph`), so they are not
        sorted into one here (a sort of every pair, and its copies). Each
        slab's findings are let go once added: a stream is joined once."""
        from ..scale.memory import mapped
        from ..scale.piece_graph import add_by_label, box_by_label, renumbered_pairs

        one = same_pieces(self.total, self.parts["same"])
        n = int(one.max(initial=0))
        parts, self.parts = self.parts, {k: [] for k in self.parts}
        width = parts["features"][0].shape[1] if parts["features"] else 0
        pieces = {"values": np.zeros(n + 1, np.uint64), "counts": np.zeros(n + 1, np.int64),
                  "sums": np.zeros((n + 1, 3), np.int64), "lo": np.full((n + 1, 3), np.iinfo(np.int64).max),
                  "hi": np.full((n + 1, 3), -1, np.int64)}
        features, doubled = np.zeros((n + 1, width), np.int64), np.zeros(n + 1, np.int64)
        # each slab's findings added into the whole image's by compiled passes (a piece's new number in place
        # of a label): no copy of all slabs' together, no array for each step of the renumbering
        first = 1
        for s, values in enumerate(parts["values"]):
            at = one[first:first + len(values)]
            first += len(values)
            pieces["values"][at] = values
            add_by_label(at, parts["counts"][s], parts["sums"][s], parts["features"][s].astype(np.int64, copy=False),
                         parts["doubled"][s].astype(np.int64, copy=False), pieces["counts"], pieces["sums"], features,
                         doubled)
            box_by_label(at, parts["lo"][s], parts["hi"][s], pieces["lo"], pieces["hi"])
        entries = sum(len(keys) for keys in parts["keys"])
        keys, kind, sums = mapped(entries, np.uint64), mapped(entries, np.uint8), mapped((entries, 2), np.uint64)
        kept = 0
        for s in range(len(parts["keys"])):
            kept = renumbered_pairs(one, parts["keys"][s].astype(np.uint64, copy=False),
                                    parts["kind"][s].astype(np.uint8, copy=False),
                                    parts["sums_pairs"][s].astype(np.uint64, copy=False).reshape(-1, 2), keys, kind,
                                    sums, kept)
            parts["keys"][s] = parts["kind"][s] = parts["sums_pairs"][s] = None  # the whole image's hold them now
        return pieces, {"features": features, "doubled": doubled, "keys": keys[:kept], "kind": kind[:kept],
                        "sums": sums[:kept]}


def same_pieces(total: int, same: list) -> np.ndarray:
    """Per piece number (0 .. total), the number of the piece it is once
    the numbers that name one piece in two slabs are made one: 0 for the
    outside, then 1.. in order of each piece's first number."""
    from ..scale.graphs import components

    pairs = np.concatenate(same) if same else np.zeros((0, 2), np.int64)
    _, comp = components(total + 1, pairs[:, 0], pairs[:, 1])
    first = np.full(comp.max(initial=0) + 1, total + 1)
    np.minimum.at(first, comp, np.arange(total + 1))
    order = np.argsort(first)  # components by their first number: the outside's (0) first
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return rank[comp]


def genera_column(rows: np.ndarray, genera: np.ndarray, n: int) -> np.ndarray:
    """Per row of ``n``, the tuple of the genera of its surfaces
    (``rows``: each surface's row, in order). Rows of none or one surface,
    the common case, share one tuple per genus (and the empty one), taken
    for all rows at once.

    Examples
    --------
    >>> genera_column(np.array([0, 2, 2]), np.array([1, 0, 3]), 4).tolist()
    [(1,), (), (0, 3), ()]
    """
    count = np.bincount(rows, minlength=n)
    cuts = np.concatenate([np.zeros(1, np.int64), np.cumsum(count)])
    one = np.flatnonzero(count == 1)
    kinds, which = distinct(genera[cuts[one]])
    shared = np.empty(len(kinds) + 1, object)  # the empty tuple, then each genus's
    shared[0] = ()
    for k, genus in enumerate(kinds.tolist()):
        shared[k + 1] = (genus,)
    pick = np.zeros(n, np.intp)
    pick[one] = which + 1
    out = shared[pick]
    several = count > 1
    if several.any():  # the genera of those rows alone as Python's integers, not every row's
        every = genera[several[rows]].tolist()
        ends = np.cumsum(count[several]).tolist()
        for r, a, b in zip(np.flatnonzero(several).tolist(), [0] + ends[:-1], ends):
            out[r] = tuple(every[a:b])
    return out


def columns(found: dict, spacing: np.ndarray, origin: np.ndarray, surfaces: bool) -> dict[str, np.ndarray]:
    """The table's columns (see :func:`label_table`) from the rows' sums."""
    voxels = found["voxels"]
    features = found["features"]
    # a voxel size of 1e150 makes volumes and areas past float64: inf in
    # the float columns, not a NumPy warning on the user's terminal; the
    # products are formed so that a value float64 holds is given whatever
    # the voxel size, and one below its smallest number is 0 with a warning
    out: dict[str, np.ndarray] = {"label": found["label"], "voxels": voxels,
                                  "volume": scaled_counts(voxels, spacing)}
    faces = features[:, FACES] // 4
    # as analyze sums them (scaled_faces): the two agree to the last bit
    out["surface_area"] = scaled_faces(faces, spacing)
    lost = [what for what, values, counts in (("volumes", out["volume"], voxels),
                                              ("surface areas", out["surface_area"], faces.sum(axis=1)))
            if bool(((values == 0) & (counts > 0)).any())]
    if lost:
        warn(underflow_line(f"the {' and the '.join(lost)} of labels", spacing))
    present = voxels > 0
    every = bool(present.all())  # the rows of labels that occur, the common case: no NaN to put in

    def world(index: np.ndarray, d: int) -> np.ndarray:
        """``origin + spacing * index`` along axis d (in place on the
        product, the same sums), NaN in the rows of absent labels."""
        at = index * spacing[d]
        at += origin[d]
        return at if every else np.where(present, at, np.nan)

    # an absent label's box is NaN (0 / 0), and a corner past float64 (an
    # origin near 1.8e308) is inf, as ``analyze`` gives it, not a NumPy warning
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        for d in range(3):
            out[f"bbox-{d}"] = world(found["lo"][:, d], d)
        for d in range(3):
            out[f"bbox-{d + 3}"] = world(found["hi"][:, d] + 1, d)
        for d in range(3):
            mean = found["sums"][:, d] / voxels
            mean += 0.5
            out[f"centroid-{d}"] = world(mean, d)
    chi = features[:, EULER] // 8
    out["euler_characteristic"] = chi
    out["b0"], out["b1"], out["b2"] = found["b0"], found["b0"] + found["b2"] - chi, found["b2"]
    for i in range(9):
        out[f"n-{i}"] = features[:, 1 + i]
    out["non_well_composed"] = features[:, NWC]
    out["energy"] = features[:, ENERGY]
    if surfaces:
        rows, chis = found["surface_rows"], found["surface_chi"]
        out["surfaces"] = np.bincount(rows, minlength=len(voxels)).astype(np.int64)
        out["genera"] = genera_column(rows, 1 - np.asarray(chis, np.int64) // 2, len(voxels))
        out["surface_euler"] = np.bincount(rows, chis, len(voxels)).astype(np.int64)
        out["pinched_vertices"] = features[:, PINCH]
        out["doubled_edges"] = found["doubled"]
    return out
