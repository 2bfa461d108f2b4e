"""What float64 cannot hold of a grid placed far from the origin against
its voxel size (a voxel of 1 at an origin of 1e43): the voxel corners
``origin + spacing * i`` of an axis may round to one value, and then no
world coordinate along that axis says where the object lies. The topology
and the counts do not depend on the placement, nor do the volume and the
boundary measure (products of the voxel size); the world boxes,
centroids and limit points do, and are given as None along such an axis
rather than as the collapsed values. Here, in :mod:`isoflow.digital`, for
the report and the flow; the surface writers refuse such a placement
(:func:`isoflow.mesh.export.check_float64_corners`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..errors import warn


def placement_words(origin, spacing) -> str:
    """A grid's origin and voxel size, as the float64 lines name them.

    Examples
    --------
    >>> placement_words((1e6, 0, 0), (1e-9, 1e-9, 2e-9))
    'origin (1e+06, 0, 0), voxel size (1e-09, 1e-09, 2e-09)'
    """
    def listed(values) -> str:
        return "(" + ", ".join(f"{float(x):.6g}" for x in np.asarray(values, np.float64).ravel()) + ")"

    return f"origin {listed(origin)}, voxel size {listed(spacing)}"


def _per_axis(origin, spacing, shape: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
    """``origin`` and ``spacing`` as float64 arrays of one value per axis
    of ``shape`` (a scalar voxel size is the same along every axis)."""
    return (np.broadcast_to(np.asarray(origin, np.float64), (len(shape),)),
            np.broadcast_to(np.asarray(spacing, np.float64), (len(shape),)))


def merged_axes(origin, spacing, shape: Sequence[int]) -> list[bool]:
    """Per axis, whether two voxel corners next to each other along it,
    ``origin + spacing * i`` for ``i`` from 0 to the shape (as
    :meth:`isoflow.DigitalObject.world` computes them), are one float64
    value.

    Parameters
    ----------
    origin, spacing : array_like
        The world position of voxel 0's lowest corner and the voxel size,
        per axis (or one number for every axis).
    shape : sequence of int
        Voxels per axis.

    Returns
    -------
    list of bool

    Examples
    --------
    >>> merged_axes((1e43, 0.0, 0.0), 1.0, (6, 6, 6))
    [True, False, False]
    >>> merged_axes((1e6, 0.0), 1e-9, (6, 6))
    [False, False]
    """
    origin, spacing = _per_axis(origin, spacing, shape)
    merged = []
    for o, s, n in zip(origin.tolist(), spacing.tolist(), shape):
        with np.errstate(over="ignore", invalid="ignore"):
            merged.append(bool(np.any(np.diff(o + s * np.arange(int(n) + 1, dtype=np.float64)) == 0)))
    return merged


def beyond_float64_axes(origin, spacing, shape: Sequence[int]) -> list[bool]:
    """Per axis, whether a voxel corner ``origin + spacing * i`` (``i``
    from 0 to the shape, as :meth:`isoflow.DigitalObject.world` computes
    them) is past float64's largest value, so that float64 makes it inf.

    Parameters
    ----------
    origin, spacing, shape
        The grid, as :func:`merged_axes` takes it.

    Returns
    -------
    list of bool

    Examples
    --------
    >>> beyond_float64_axes((1.75e308, 0.0), 1e306, (6, 6))
    [True, False]
    >>> beyond_float64_axes((1e307, -1e307), 1e306, (6, 6))
    [False, False]
    """
    origin, spacing = _per_axis(origin, spacing, shape)
    with np.errstate(over="ignore", invalid="ignore"):
        # the corners are monotone along an axis: its two ends are the farthest
        return [not (np.isfinite(o + s * int(n)) and np.isfinite(o)) for o, s, n in zip(origin.tolist(), spacing.tolist(), shape)]


def beyond_axes_reasons(origin, spacing, shape: Sequence[int]) -> str | None:
    """Where the voxel corners pass float64's largest value, axis by axis
    (:func:`beyond_float64_axes`): each such axis with the farthest
    corner's magnitude, in exact decimal arithmetic (float64 makes it
    inf); None where every corner is a float64.

    Parameters
    ----------
    origin, spacing, shape
        The grid, as :func:`merged_axes` takes it.

    Returns
    -------
    str or None

    Examples
    --------
    >>> print(beyond_axes_reasons((1.75e308, 0, 0), 1e306, (6, 6, 6)))
    along axis 0 the voxel corners reach up to 1.81e+308, past float64's largest value (1.8e+308)
    >>> beyond_axes_reasons((0, 0), 1.0, (2, 2)) is None
    True
    """
    from decimal import Decimal

    beyond = beyond_float64_axes(origin, spacing, shape)
    origin, spacing = _per_axis(origin, spacing, shape)
    clauses = []
    for axis in (a for a, b in enumerate(beyond) if b):
        o, s = Decimal(float(origin[axis])), Decimal(float(spacing[axis]))
        far = max(abs(o), abs(o + s * int(shape[axis])))
        clauses.append(f"along axis {axis} the voxel corners reach up to {far:.3g}, past float64's largest value "
                       f"({np.finfo(np.float64).max:.3g})")
    return ", and ".join(clauses) or None


def lost_axes_reasons(origin, spacing, shape: Sequence[int], merged: Sequence[bool] | None = None) -> str | None:
    """Why float64 cannot keep the voxel corners apart, axis by axis,
    along the axes of :func:`merged_axes` (``merged``, where the caller
    has them): each lost axis with float64's spacing (``np.spacing``) at
    its own corner farthest from 0, one clause per axis; None where
    every axis keeps its corners apart.

    Parameters
    ----------
    origin, spacing, shape
        The grid, as :func:`merged_axes` takes it.
    merged : sequence of bool, optional
        :func:`merged_axes` of the grid, where the caller has it.

    Returns
    -------
    str or None

    Examples
    --------
    >>> print(lost_axes_reasons((1e43, 0, 0), 1.0, (2, 2, 2)))
    near 1e+43 float64 values are 1.24e+27 apart (np.spacing), so voxel corners a voxel apart along axis 0 are one value
    >>> print(lost_axes_reasons((0, 1e17, 1e43), 1.0, (2, 2, 2)))  # doctest: +NORMALIZE_WHITESPACE
    near 1e+17 float64 values are 16 apart (np.spacing), so voxel corners a voxel apart along axis 1 are one value,
    and near 1e+43 float64 values are 1.24e+27 apart (np.spacing), so voxel corners a voxel apart along axis 2 are
    one value
    >>> lost_axes_reasons((0, 0), 1.0, (2, 2)) is None
    True
    """
    merged = merged_axes(origin, spacing, shape) if merged is None else merged
    origin, spacing = _per_axis(origin, spacing, shape)
    clauses = []
    for axis in (a for a, m in enumerate(merged) if m):
        # each axis' own farthest corner from 0, where float64's values are sparsest along it
        with np.errstate(over="ignore", invalid="ignore"):
            near = max(abs(float(origin[axis])), abs(float(origin[axis] + spacing[axis] * shape[axis])))
        clauses.append(f"near {near:.3g} float64 values are {float(np.spacing(near)):.3g} apart (np.spacing), so voxel "
                       f"corners a voxel apart along axis {axis} are one value")
    return ", and ".join(clauses) or None


def unheld_line(what: str, origin, spacing, shape: Sequence[int], unknown: str = "None",
                merged: Sequence[bool] | None = None) -> str | None:
    """The warning that float64 cannot hold ``what`` (world coordinates)
    along the axes of :func:`merged_axes` (``merged``, where the caller has
    them), naming the placement and, per such axis, float64's spacing
    there (:func:`lost_axes_reasons`); None where every axis keeps its
    corners apart; ``unknown``: what the coordinates lost are given as.

    Examples
    --------
    >>> print(unheld_line("the bounding box", (1e43, 0, 0), 1.0, (2, 2, 2)))  # doctest: +ELLIPSIS
    the bounding box cannot be held in float64 at this placement (origin (1e+43, 0, 0), voxel size (1, 1, 1)): near
    1e+43 float64 values are 1.24e+27 apart (np.spacing), so voxel corners a voxel apart along axis 0 are one value; ...
    >>> unheld_line("the bounding box", (0, 0, 0), 1.0, (2, 2, 2)) is None
    True
    """
    merged = merged_axes(origin, spacing, shape) if merged is None else merged
    reasons = lost_axes_reasons(origin, spacing, shape, merged)
    if reasons is None:
        return None
    origin, spacing = _per_axis(origin, spacing, shape)
    return (f"{what} cannot be held in float64 at this placement ({placement_words(origin, spacing)}): {reasons}; "
            f"the coordinates along {'it' if sum(map(bool, merged)) == 1 else 'them'} are unknown ({unknown}), the "
            "other values do not depend on the placement; place the object nearer the origin (subtract its origin) "
            "to have them")


def lost_axes(what: str, origin, spacing, shape: Sequence[int], unknown: str = "None") -> list[bool] | None:
    """:func:`merged_axes`, said in one warning (:func:`unheld_line`) where
    float64 cannot keep the corners of some axis apart; None where it
    keeps every axis's.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     lost_axes("the box", (1e43, 0.0), 1.0, (4, 4)), len(caught)
    ([True, False], 1)
    >>> lost_axes("the box", (0.0, 0.0), 1.0, (4, 4)) is None
    True
    """
    merged = merged_axes(origin, spacing, shape)
    if not any(merged):
        return None
    warn(unheld_line(what, origin, spacing, shape, unknown, merged))
    return merged


def held(values: list | None, lost: Sequence[bool]) -> list | None:
    """World coordinates (a point, or a box: its lowest then its highest
    corner, one flat list) with those along the ``lost`` axes as None.

    Examples
    --------
    >>> held([1e43, 0.5, 1e43, 4.5], [True, False])
    [None, 0.5, None, 4.5]
    >>> held(None, [True, False]) is None
    True
    """
    if values is None:
        return None
    return [None if lost[i % len(lost)] else v for i, v in enumerate(values)]


def unheld_columns(table: dict, origin, spacing, shape: Sequence[int]) -> dict:
    """A label table's columns (:func:`isoflow.label_table`) with the box and
    centroid columns NaN along the axes of :func:`merged_axes`, said in one
    warning; as they are where float64 keeps every axis's corners apart.

    Examples
    --------
    >>> import warnings
    >>> table = {"bbox-0": np.array([1e43]), "bbox-1": np.array([1.0]), "bbox-2": np.array([1e43]),
    ...          "bbox-3": np.array([2.0]), "centroid-0": np.array([1e43]), "centroid-1": np.array([1.5])}
    >>> with warnings.catch_warnings(record=True):
    ...     warnings.simplefilter("always")
    ...     out = unheld_columns(table, (1e43, 0.0), 1.0, (4, 4))
    >>> [float(out[k][0]) for k in ("bbox-0", "bbox-1", "bbox-2", "bbox-3", "centroid-0", "centroid-1")]
    [nan, 1.0, nan, 2.0, nan, 1.5]
    """
    n = len(shape)
    lost = lost_axes("the labels' bounding boxes and centroids", origin, spacing, shape, "NaN; null in JSON")
    for axis in range(n) if lost is not None else ():
        for key in (f"bbox-{axis}", f"bbox-{axis + n}", f"centroid-{axis}") if lost[axis] else ():
            table[key] = np.full(len(table[key]), np.nan)
    return table


def scaled_counts(counts: ArrayLike, factors: ArrayLike) -> np.ndarray:
    """``counts * prod(factors)`` in float64, the product kept as a mantissa
    and a power of two so that it neither underflows nor overflows on the
    way: a value that float64 holds is given, however small or large each
    factor (voxels of 1e-200 x 1e-200 x 1e200 have a volume of 1e-200,
    which ``np.prod`` makes 0). A value past float64 is inf, one below its
    smallest number (about 4.9e-324) is 0.

    Parameters
    ----------
    counts : array_like of int
        Voxels, faces: how many cells of the product.
    factors : array_like of float
        The voxel size along the axes that the cells span.

    Returns
    -------
    numpy.ndarray
        float64, of ``counts``'s shape.

    Examples
    --------
    >>> tiny, huge = 2.0**-700, 2.0**700
    >>> float(scaled_counts(8, [tiny, tiny, huge])) == 8 * tiny, float(np.prod([tiny, tiny, huge]))
    (True, 0.0)
    >>> float(scaled_counts(1, [1e-200] * 3)), float(scaled_counts(1, [1e150] * 3))
    (0.0, inf)
    """
    mantissa, exponent = _scale(factors)
    # ldexp rounds once where the result is subnormal, inf past float64: no
    # NumPy warning on the user's terminal, the callers say what was lost
    with np.errstate(over="ignore", under="ignore"):
        return np.ldexp(np.asarray(counts, np.float64) * mantissa, exponent)


def _scale(factors) -> tuple[float, int]:
    """The product of ``factors`` as (mantissa, power of two), rounded as
    ``np.prod`` rounds it where that neither underflows nor overflows."""
    mantissa, exponent = 1.0, 0
    for factor in np.asarray(factors, np.float64).ravel().tolist():
        m, e = math.frexp(factor)
        mantissa, shift = math.frexp(mantissa * m)
        exponent += e + shift
    return mantissa, exponent


def scaled_faces(faces: ArrayLike, spacing: ArrayLike) -> np.ndarray:
    """The boundary measure (area in 3D, perimeter in 2D) of ``faces``
    counted per normal axis (last axis of ``faces``): each axis's count
    times the product of the voxel size along the other axes, as
    :func:`scaled_counts` forms it. Axes whose faces are of one size (all
    of them, for cubic voxels) are counted together before the one
    product, so that 54 faces of a cube are ``54 * s * s`` exactly, not
    three products of 18 added up with two roundings more.

    Parameters
    ----------
    faces : array_like of int
        Face counts, the last axis one entry per normal axis.
    spacing : array_like of float
        The voxel size per axis.

    Returns
    -------
    numpy.ndarray
        float64, of ``faces``'s shape without its last axis.

    Examples
    --------
    >>> s = 1e150
    >>> float(scaled_faces([18, 18, 18], [s, s, s])) == 54 * (s * s)
    True
    >>> scaled_faces([[2, 4, 6]], [1.0, 2.0, 3.0]).tolist()  # 2*6 + 4*3 + 6*2
    [36.0]
    """
    faces = np.asarray(faces, np.int64)
    spacing = np.asarray(spacing, np.float64)
    groups: dict[tuple[float, int], np.ndarray] = {}  # a face's size -> the faces of that size, in axis order
    for axis in range(faces.shape[-1]):
        key = _scale(np.delete(spacing, axis))
        groups[key] = groups[key] + faces[..., axis] if key in groups else faces[..., axis]
    total = np.zeros(faces.shape[:-1], np.float64)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        for (mantissa, exponent), count in groups.items():
            total = total + np.ldexp(np.asarray(count, np.float64) * mantissa, exponent)
    return total


def underflow_line(what: str, spacing: ArrayLike) -> str:
    """The warning that ``what`` (a volume, an area) of cells of this voxel
    size is below float64's smallest number, and so given as 0.

    Examples
    --------
    >>> underflow_line("the volume", [1e-200] * 3)
    "the volume is below float64's smallest number (4.9e-324) at voxel size (1e-200, 1e-200, 1e-200): \
given as 0; give the voxel size in a larger unit (pitch=, --pitch)"
    """
    size = ", ".join(f"{float(x):.6g}" for x in np.asarray(spacing, np.float64).ravel())
    verb = "are" if " and " in what or what.split(" of ")[0].endswith("s") else "is"
    return (f"{what} {verb} below float64's smallest number (4.9e-324) at voxel size ({size}): given as 0; give the "
            f"voxel size in a larger unit (pitch=, --pitch)")
