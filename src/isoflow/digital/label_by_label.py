"""The label table label by label: each label's own census, the same rows
as the one pass of :mod:`isoflow.digital.label_table` (every row is what
:func:`~isoflow.digital.analysis.analyze` reports for ``image == label``).

The one pass is the sooner on all but three kinds of image, where this
pass makes the table (:func:`~isoflow.digital.label_table.table_rows`
chooses): a small image before numba is loaded (each label's box through
NumPy's census), an image whose pieces would not fit in memory (noise of
many labels), and a noisy segmentation
(:data:`~isoflow.digital.label_table.FRAGMENTED`), whose one pass adds up
the pairs of pieces of nearly every block where each label's census
sweeps the image once.

A label's voxels are found in one of two ways:

* where the image's values are known (a noisy segmentation: found by its
  pieces, or counted once slabs of its pieces said so) and the compiled
  census is in use, each label's mask of the whole image
  goes through :func:`~isoflow.digital.closed_surfaces.compiled_census`,
  which reads the voxels' extent off its bit rows; its configuration
  histogram gives every feature of the row (its product with
  :func:`~isoflow.digital.vertex_features.feature_table`), so nothing is
  sorted and no box is copied;
* else one stable sort of the image gives every label's voxels, and so
  its box; the box with one voxel round it (outside the box everything is
  the label's complement, so its report is the whole image's) goes
  through ``analyze``.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import TYPE_CHECKING

import numpy as np

from ..scale.memory import budget_held, check_fits
from .closed_surfaces import census_loaded, compiled_census, use_census
from .vertex_features import A_WC, CLASSES, ENERGY, EULER, FACES, NWC, PINCH, WIDTH, feature_table

if TYPE_CHECKING:
    from ..results import ClosedSurfaces
    from ..scale.ticks import Ticks


def box_rows(vol: np.ndarray, conn: int, wanted: np.ndarray | None, surfaces: bool,
             background: bool = False, ticks: Ticks | None = None, weighed: bool = False,
             present: np.ndarray | None = None) -> dict:
    """The rows label by label (see the module docs). ``background``: with
    ``wanted`` None, label 0's row too; ``ticks``: the progress, the rest
    of it counted in labels; ``present``: the image's values, in order,
    where they were found before (by the pieces, or by a count where
    slabs of pieces said so; else the sort finds them).

    Each box's census is NumPy's unless the compiled one is loaded or the
    box is large enough to pay for loading it
    (:func:`~isoflow.digital.closed_surfaces.use_census`); with
    ``weighed`` (numba already in the process: the one pass counted the
    pieces first), the boxes add up as the volumes of a loop do (the
    ski-rental rule of ``"auto"``), so that the census is loaded once they
    reach the size that pays for it (each label of noise has the whole
    image for its box). With ``present``, each label's mask where
    :func:`_by_masks` says so.
    """
    from ..scale.ticks import silent

    ticks = silent(ticks)
    with budget_held():  # the memory available read once, for the checks of the sort or the masks and every census
        labels = _by_masks(vol, wanted, background, present, surfaces)
        if labels is not None:
            found = _mask_rows(vol, conn, labels, present, surfaces, ticks)
        else:
            found = _sorted_rows(vol, conn, wanted, surfaces, background, ticks, weighed)
    ticks.finish()
    return found


def _by_masks(vol: np.ndarray, wanted: np.ndarray | None, background: bool, present: np.ndarray | None,
              surfaces: bool) -> np.ndarray | None:
    """The labels of the rows, to be taken by their masks
    (:func:`_mask_rows`), or None where the sort is to find them: the
    masks are taken where the image's values were found before
    (``present``) and the compiled census is loaded, or where the masks
    together pay for loading it (the ski-rental threshold of ``"auto"``,
    :func:`~isoflow.scale.compiled.weigh`)."""
    from ..scale.compiled import weigh

    if present is None:
        return None
    labels = (present if background else present[present != 0]) if wanted is None else wanted.astype(vol.dtype)
    if census_loaded() or weigh(vol.size * int(np.isin(labels, present).sum()), surfaces):
        return labels
    return None


def _rows_present(labels: np.ndarray, values: np.ndarray, ticks: Ticks) -> Iterator[tuple[int, object, int]]:
    """Each row of ``labels`` whose label is among the image's ``values``
    (in order), with its label and its index there; the rows done told to
    ``ticks``, the rest of whose progress they are."""
    ticks.rest(len(labels))
    for row, label in enumerate(labels):
        ticks.reached(0, row)
        at = int(np.searchsorted(values, label))
        if at < len(values) and values[at] == label:
            yield row, label, at


def _empty_rows(labels: np.ndarray) -> dict:
    """The rows' arrays for ``labels``, each label absent until found."""
    n = len(labels)
    return {"label": labels, "voxels": np.zeros(n, np.int64), "sums": np.zeros((n, 3)),
            "lo": np.zeros((n, 3), np.int64), "hi": np.full((n, 3), -1, np.int64),
            "features": np.zeros((n, WIDTH), np.int64), "doubled": np.zeros(n, np.int64),
            "b0": np.zeros(n, np.int64), "b2": np.zeros(n, np.int64)}


def _with_surfaces(found: dict, surfs: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> dict:
    """``found`` with the surfaces of every row (per row its number, Euler
    characteristics and faces, from ``surfs``) as three columns."""
    rows_chi_faces = [np.concatenate(c) if c else np.zeros(0, np.int64) for c in zip(*surfs)] or [np.zeros(0, np.int64)] * 3
    found.update(surface_rows=rows_chi_faces[0], surface_chi=rows_chi_faces[1], surface_faces=rows_chi_faces[2])
    return found


def _surfaces_of(row: int, surfaces: ClosedSurfaces) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One row's entry of ``surfs`` (:func:`_with_surfaces`) from its
    :class:`~isoflow.results.ClosedSurfaces`: their columns, as a label
    of noise has very many surfaces."""
    table = surfaces.columns()
    return np.full(len(surfaces), row, np.int64), table["euler_characteristic"], table["faces"]


def _mask_rows(vol: np.ndarray, conn: int, labels: np.ndarray, present: np.ndarray, surfaces: bool,
               ticks: Ticks) -> dict:
    """The rows of ``labels``, each from the compiled census of its mask of
    the whole image (see the module docs); ``present``: the image's
    values, in order (any other label's row is of no voxel)."""
    from .analysis import voxels_from_histogram

    shape = "x".join(map(str, vol.shape))
    # a mask and its bit rows at a time (each census checks its own need)
    check_fits(vol.size + vol.size // 8, f"the label table of a {shape} label image, label by label")
    table = feature_table(conn)
    found = _empty_rows(labels)
    surfs = []
    for row, label, _ in _rows_present(labels, present, ticks):
        census = compiled_census(vol == label, conn, surfaces)
        hist = census["hist"]
        found["voxels"][row] = voxels_from_histogram(hist)
        found["lo"][row], found["hi"][row], found["sums"][row] = census["extent"]
        found["b0"][row], found["b2"][row] = census["betti_counts"]
        found["features"][row] = hist @ table
        if surfaces:
            found["doubled"][row] = census["doubled_edges"]
            surfs.append(_surfaces_of(row, census["surfaces"]))
    return _with_surfaces(found, surfs)


def _sorted_rows(vol: np.ndarray, conn: int, wanted: np.ndarray | None, surfaces: bool, background: bool,
                 ticks: Ticks, weighed: bool) -> dict:
    """The rows of every label from its box, the labels' voxels found by
    one sort (see the module docs)."""
    from .analysis import analyze

    flat = vol.reshape(-1)
    shape = "x".join(map(str, vol.shape))
    # the voxels' order and the values sorted by it
    check_fits((8 + flat.itemsize) * flat.size, f"the label table of a {shape} label image, label by label")
    order = np.argsort(flat, kind="stable")
    values, starts = np.unique(flat[order], return_index=True)
    labels = (values if background else values[values != 0]) if wanted is None else wanted.astype(values.dtype)
    ends = np.append(starts[1:], flat.size)
    # a label's voxels' coordinates along one axis at a time, and its work on them (each box's analyze checks its
    # own need)
    most = int((ends - starts).max(initial=0))
    check_fits((8 + flat.itemsize) * flat.size + 16 * most, f"the label table of a {shape} label image, label by label")
    found = _empty_rows(labels)
    surfs = []
    for row, label, at in _rows_present(labels, values, ticks):
        lo, hi, sums = _extent(order[starts[at]:ends[at]], vol.shape)
        box = np.pad(vol[tuple(slice(a, b + 1) for a, b in zip(lo, hi))] == label, 1)
        # the boxes count in the tally of "auto" only where numba is loaded already (weighed): where NumPy's pass
        # is the one taken for the whole image, counting them would load numba part way through this call
        census = use_census(box, surfaces, record=weighed)
        report = analyze(box, conn, surfaces=surfaces, method="compiled" if census else "numpy")
        found["voxels"][row], found["sums"][row] = ends[at] - starts[at], sums
        found["lo"][row], found["hi"][row] = lo, hi
        found["b0"][row], found["b2"][row] = report["betti"][0], report["betti"][2]
        found["features"][row] = _report_features(report, box)
        found["doubled"][row] = report.get("doubled_edges", 0)
        if report.surfaces is not None:
            surfs.append(_surfaces_of(row, report.surfaces))
    return _with_surfaces(found, surfs)


def _extent(flat_index: np.ndarray, shape: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The lowest and highest corner and the coordinate sums of the voxels
    at ``flat_index`` (C order) of an image of ``shape``, one axis at a
    time: one array of the voxels' coordinates held at once, not three and
    their stack.

    Examples
    --------
    >>> lo, hi, sums = _extent(np.array([5, 11, 12]), (2, 3, 4))  # (0, 1, 1), (0, 2, 3), (1, 0, 0)
    >>> lo.tolist(), hi.tolist(), sums.tolist()
    ([0, 0, 0], [1, 2, 3], [1, 3, 4])
    """
    lo, hi, sums = (np.zeros(len(shape), np.int64) for _ in range(3))
    step = 1
    for d in range(len(shape) - 1, -1, -1):
        coordinate = flat_index // step % shape[d]
        lo[d], hi[d], sums[d] = coordinate.min(), coordinate.max(), coordinate.sum()
        step *= shape[d]
    return lo, hi, sums


def _report_features(report: Mapping, box: np.ndarray) -> np.ndarray:
    """The feature sums of :func:`~isoflow.digital.vertex_features.feature_table`
    from a report and the (padded) box: the faces per axis counted on the
    box."""
    out = np.zeros(WIDTH, np.int64)
    out[EULER] = 8 * report["euler_characteristic"]
    out[CLASSES] = report["n"]
    out[NWC] = report["non_well_composed"]
    out[A_WC] = report["a_dot_n_well_composed"]
    out[ENERGY] = report["energy"]
    out[PINCH] = report.get("pinched_vertices", 0)
    out[FACES] = [4 * np.count_nonzero(np.diff(box, axis=d)) for d in range(3)]
    return out
