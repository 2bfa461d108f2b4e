"""World measures of one object: what :func:`~isoflow.digital.label_table.label_table`
gives each label, for the shape report (``isoflow info``).

* ``volume`` (``area`` in 2D) is the voxels times the volume of one;
* ``surface_area`` (``perimeter`` in 2D) is the boundary faces normal to
  each axis times their area, the product of the two other voxel sizes
  (in 2D the pixel size along the edge). The faces need no pass of their
  own: a face normal to axis ``d`` has ``2^(n-1)`` corners, and at each
  the configuration shows it as two octants across ``d`` that differ, so
  the configuration histogram counts every face ``2^(n-1)`` times;
* ``bbox`` is the lowest, then the highest corner of the voxels and
  ``centroid`` the mean of their centres, world coordinates; both need the
  voxels' extent per axis (lowest and highest index, sum of indices), which
  a large volume's compiled pass reads off its bit rows
  (:func:`isoflow.scale.bitrows.row_extents`) and a small one's from one
  sum per axis.

Voxel ``v`` spans ``[v, v + 1]``, placed by the voxel size and the world
position of voxel 0's lowest corner, as in the label table (with unit
voxels at the origin, ``bbox`` is scikit-image's and ``centroid`` its
``centroid + 0.5``). A 4D object has none: its fourth axis is mostly a
time series' frames, whose step is no length (``info`` says it apart), so
a hypervolume and a boundary volume would mix time and space; a bare 1D
array has no placement.
"""

from __future__ import annotations

from functools import cache
from typing import NamedTuple

import numpy as np

from ..errors import warn
from ..scale.arrays import is_host, namespace, to_host
from .configurations import octants
from .float64 import held, lost_axes, scaled_counts, scaled_faces, underflow_line

#: what a far placement's warning says float64 cannot hold of a report
BOX_AND_CENTROID = "the bounding box and centroid"
#: the report's names of the size and of the boundary measure, by dimension
MEASURE_NAMES = {3: ("volume", "surface_area"), 2: ("area", "perimeter")}


class Extent(NamedTuple):
    """Where an object's voxels lie, per axis: the lowest and the highest
    index (int64 arrays) and the sum of the indices (int64, exact)."""

    lo: np.ndarray
    hi: np.ndarray
    sums: np.ndarray


@cache
def _face_lut(ndim: int) -> np.ndarray:
    """(2^(2^n), n): per configuration, per axis, the pairs of octants
    across that axis of which one is the object's."""
    d = octants(ndim)
    codes = np.arange(1 << (1 << ndim))
    out = np.zeros((len(codes), ndim), np.int64)
    for axis in range(ndim):
        for o in np.flatnonzero(d[:, axis] == 0):
            out[:, axis] += ((codes >> int(o)) & 1) != ((codes >> (int(o) | (1 << axis))) & 1)
    return out


def faces_per_axis(hist: np.ndarray, ndim: int) -> np.ndarray:
    """Boundary faces normal to each axis, from the configuration
    histogram of every vertex (the volume padded by one layer).

    Examples
    --------
    >>> from isoflow.digital.configurations import configuration_histogram
    >>> faces_per_axis(configuration_histogram(np.ones((2, 3, 4), bool)), 3).tolist()
    [24, 16, 12]
    """
    return (np.asarray(hist, np.int64) @ _face_lut(ndim)) // (1 << (ndim - 1))


def extent_of(vol) -> Extent | None:
    """The :class:`Extent` of a binary volume (0/1 bytes; a device array
    reduced on its device), None where it has no voxel: two sums over the
    volume, along the last axis and across it.

    Examples
    --------
    >>> v = np.zeros((4, 5), bool); v[1, 2] = v[3, 4] = True
    >>> [a.tolist() for a in extent_of(v)]
    [[1, 2], [3, 4], [4, 6]]
    """
    return counted_extent(vol)[1]


def counted_extent(vol) -> tuple[int, Extent | None]:
    """The voxels of a binary volume and its :class:`Extent`
    (:func:`extent_of`), from the same two sums: the count needs no pass
    of its own.

    Examples
    --------
    >>> v = np.zeros((4, 5), bool); v[1, 2] = v[3, 4] = True
    >>> voxels, extent = counted_extent(v)
    >>> voxels, extent.sums.tolist()
    (2, [4, 6])
    """
    xp = namespace(vol)
    if not is_host(xp):  # the array API sums numbers, not bools (one byte a voxel on the device, for the sums)
        vol = xp.astype(vol, xp.uint8)
    rows = to_host(xp.sum(vol, axis=vol.ndim - 1, dtype=xp.int64))
    last = to_host(xp.sum(vol, axis=tuple(range(vol.ndim - 1)), dtype=xp.int64))
    return int(last.sum()), extent_of_counts([rows.sum(axis=tuple(a for a in range(rows.ndim) if a != axis))
                                              for axis in range(rows.ndim)] + [last])


def extent_of_counts(counts: list[np.ndarray]) -> Extent | None:
    """The :class:`Extent` from the voxels in each slice along each axis.

    Examples
    --------
    >>> [a.tolist() for a in extent_of_counts([np.array([0, 2, 1]), np.array([3, 0])])]
    [[1, 0], [2, 0], [4, 0]]
    """
    where = [np.flatnonzero(c) for c in counts]
    if not len(where[0]):
        return None
    return Extent(np.array([w[0] for w in where], np.int64), np.array([w[-1] for w in where], np.int64),
                  np.array([int(c @ np.arange(len(c), dtype=np.int64)) for c in counts], np.int64))


def extent_of_rows(counts: np.ndarray, sums: np.ndarray, first: np.ndarray, last: np.ndarray,
                   shape: tuple[int, ...]) -> Extent | None:
    """The :class:`Extent` of a 3D volume from its bit rows' counts
    (:func:`isoflow.scale.bitrows.row_extents`): the rows' counts give the
    first two axes, their position sums and ends the last.

    Examples
    --------
    >>> from isoflow.scale import bitrows
    >>> v = np.zeros((2, 2, 70), bool); v[1, 0, [3, 69]] = True
    >>> [a.tolist() for a in extent_of_rows(*bitrows.row_extents(bitrows.pack(v)[0]), v.shape)]
    [[1, 0, 3], [1, 0, 69], [2, 0, 72]]
    """
    grid = counts.reshape(shape[0], shape[1])
    along = extent_of_counts([grid.sum(axis=1), grid.sum(axis=0)])
    if along is None:
        return None
    on = counts > 0
    return Extent(np.append(along.lo, first[on].min()), np.append(along.hi, last.max()),
                  np.append(along.sums, sums.sum()))


def shifted(extent: Extent | None, at, voxels: int) -> Extent | None:
    """A block's :class:`Extent` (indices from its first voxel) in the
    volume's indices: that voxel is ``at``, and the block holds ``voxels``.

    Examples
    --------
    >>> shifted(Extent(np.array([0, 1]), np.array([2, 1]), np.array([2, 2])), (10, 20), 2).sums.tolist()
    [22, 42]
    """
    if extent is None:
        return None
    at = np.asarray(at, np.int64)
    return Extent(extent.lo + at, extent.hi + at, extent.sums + voxels * at)


def joined(extents: list[Extent | None]) -> Extent | None:
    """The :class:`Extent` of a volume from its blocks' (:func:`shifted`).

    Examples
    --------
    >>> a, b = Extent(np.array([1]), np.array([2]), np.array([3])), Extent(np.array([5]), np.array([5]), np.array([5]))
    >>> [x.tolist() for x in joined([a, None, b])]
    [[1], [5], [8]]
    """
    found = [e for e in extents if e is not None]
    if not found:
        return None
    return Extent(np.min([e.lo for e in found], axis=0), np.max([e.hi for e in found], axis=0),
                  np.sum([e.sums for e in found], axis=0))


def world_measures(ndim: int, voxels: int, faces: np.ndarray | None, extent: Extent | None, spacing: np.ndarray,
                   corner: np.ndarray, unit: str | None, shape: tuple[int, ...] | None = None) -> dict:
    """The report's measures (see the module) of a 2D or 3D object, placed
    by its voxel size ``spacing`` and the world position ``corner`` of
    voxel 0's lowest corner, in ``unit``; nothing in another dimension
    (whose ``faces`` may be None).
    The arithmetic is the label table's, so that a mask's report equals
    its row to the last bit. Along an axis where float64 cannot keep the
    corners of the grid of ``shape`` apart (:mod:`isoflow.digital.float64`)
    the box's and the centroid's coordinates are None, with a warning.

    Examples
    --------
    >>> m = world_measures(2, 3, np.array([2, 6]), Extent(np.array([1, 2]), np.array([3, 2]), np.array([6, 6])),
    ...                    np.array([0.5, 2.0]), np.zeros(2), "mm")
    >>> m["area"], m["perimeter"], m["bbox"], m["centroid"]
    (3.0, 7.0, [0.5, 4.0, 2.0, 6.0], [1.25, 5.0])
    """
    if ndim not in MEASURE_NAMES or faces is None:
        return {}
    size, boundary = MEASURE_NAMES[ndim]
    spacing = np.asarray(spacing, np.float64)
    # a voxel size of 1e150 puts a volume past float64: inf, as the label
    # table's columns, without a NumPy warning on the user's terminal
    # (``info --json`` writes inf as null); the products are formed so that
    # a measure float64 holds is given whatever the voxel size, and one
    # below its smallest number is 0 with a warning, not silently
    faces = np.asarray(faces, np.int64)
    measure = float(scaled_counts(voxels, spacing))
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        border = float(scaled_faces(faces, spacing))
        out: dict = {size: measure, boundary: border, "bbox": None, "centroid": None, "unit": unit}
        if extent is not None:
            out["bbox"] = (corner + spacing * extent.lo).tolist() + (corner + spacing * (extent.hi + 1)).tolist()
            out["centroid"] = (corner + spacing * (extent.sums / voxels + 0.5)).tolist()
    lost = [what for what, value, count in ((size, measure, voxels), (boundary, border, faces.sum()))
            if value == 0 and count > 0]
    if lost:
        warn(underflow_line(f"the {' and the '.join(lost).replace('_', ' ')}", spacing))
    if out["bbox"] is not None and shape is not None:
        out["bbox"], out["centroid"] = unheld_dropped([out["bbox"], out["centroid"]], BOX_AND_CENTROID, corner,
                                                      spacing, shape)
    return out


def unheld_dropped(boxes: list, what: str, corner, spacing, shape: tuple[int, ...]) -> list:
    """World points and boxes (flat lists, as :func:`~isoflow.digital.float64.held`
    takes them) of a grid placed by ``corner`` and ``spacing``, their
    coordinates None along the axes where float64 cannot keep its corners
    apart, said in one warning naming ``what``; as they are elsewhere.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     unheld_dropped([[1e43, 2.5]], "the centroid", np.array([1e43, 0.0]), np.ones(2), (4, 4))
    [[None, 2.5]]
    >>> str(caught[0].message).split(" (")[0]
    'the centroid cannot be held in float64 at this placement'
    """
    lost = lost_axes(what, corner, spacing, shape)
    return boxes if lost is None else [held(box, lost) for box in boxes]
