"""What float32 does to positions: a binary STL's coordinates, which
:mod:`isoflow.mesh.export` writes, and the slack of their read-back in
:mod:`isoflow.mesh.readback`; and what float64 itself does to the voxel
corners of a grid placed far from the origin against its voxel size,
which every surface file holds in world units. Here, below both, because
the writer reads its files back: readback taking it from export would be
an import cycle.
"""

from __future__ import annotations

import numpy as np

from ..digital.float64 import merged_axes


def float32_effect(xyz: np.ndarray, spacing) -> dict:
    """What storing the positions ``xyz`` (world units, voxel size
    ``spacing``) as float32 does to them.

    Parameters
    ----------
    xyz : ndarray, shape (N, 3)
        Positions, float64.
    spacing : array_like
        Voxel size per axis.

    Returns
    -------
    dict
        ``positions``: distinct positions; ``merged``: how many of them
        float32 makes equal to another (0: a reader's weld of equal
        positions gives the same surface back); ``finite``: whether every
        coordinate stays within float32's range; ``moved``: the largest
        change of a coordinate, and ``moved_voxels`` in voxels of its axis;
        ``largest``: the largest coordinate magnitude, and ``step``:
        float32's spacing there.

    Examples
    --------
    >>> import numpy as np
    >>> e = float32_effect(np.array([[1e6, 0, 0], [1e6 + 0.1, 0, 0]]), 0.1)
    >>> e["merged"], e["moved"] <= e["step"] / 2, e["step"]
    (0, True, 0.0625)
    """
    xyz = np.asarray(xyz, np.float64).reshape(-1, 3)
    with np.errstate(over="ignore", invalid="ignore"):
        xyz32 = xyz.astype(np.float32)
    finite = bool(np.all(np.isfinite(xyz32)))
    largest = float(np.max(np.abs(xyz))) if len(xyz) else 0.0
    with np.errstate(over="ignore"):  # the spacing at float32's largest value is inf: that step is past its range
        step = float(np.spacing(np.float32(min(largest, float(np.finfo(np.float32).max)))))
    positions = distinct_count(xyz)
    if not finite:
        return {"positions": positions, "merged": None, "finite": False, "moved": None, "moved_voxels": None,
                "largest": largest, "step": step}
    change = np.abs(xyz32.astype(np.float64) - xyz)
    moved = float(change.max()) if len(xyz) else 0.0
    moved_voxels = float((change / np.asarray(spacing, np.float64)).max()) if len(xyz) else 0.0
    merged = positions - distinct_count(xyz32)
    return {"positions": positions, "merged": int(merged), "finite": True, "moved": moved,
            "moved_voxels": moved_voxels, "largest": largest, "step": step}


def distinct_count(rows: np.ndarray) -> int:
    """How many distinct rows ``rows`` (N, K) holds, rows equal where their
    values are (``-0.0`` is ``0.0``): each row numbered by the ranks of its
    values among its column's distinct values, one integer per row, and
    those counted: a sort of each column and one of integers, where
    ``np.unique(rows, axis=0)`` sorts the rows as records of bytes (the
    rows themselves, with each row's number among them, are
    :func:`isoflow.mesh.load.distinct_rows`'s, which a weld needs).

    Parameters
    ----------
    rows : numpy.ndarray
        (N, K) numbers.

    Returns
    -------
    int

    Examples
    --------
    >>> distinct_count(np.array([[0.0, 1.0], [-0.0, 1.0], [0.0, 2.0], [1.0, 1.0]]))
    3
    """
    rows = np.asarray(rows)
    if not len(rows):
        return 0
    key, size = np.zeros(len(rows), np.int64), 1
    for column in rows.T:
        values = np.unique(column)  # (a rank by binary search: unique's own return_inverse sorts again)
        if size * len(values) >= 1 << 62:  # (no integer holds the numbering: the rows as records)
            return len(np.unique(rows + 0.0 if rows.dtype.kind == "f" else rows, axis=0))
        key, size = key * len(values) + np.searchsorted(values, column), size * len(values)
    key.sort()
    return int(np.count_nonzero(key[1:] != key[:-1])) + 1


#: float64 is said to move a grid's voxel corners when its spacing at the
#: corners reaches this many voxels (as an STL's float32 move is said)
FLOAT64_NOTE_VOXELS = 1e-3


def float64_corners(origin, spacing, shape) -> dict:
    """What float64 does to the voxel corners ``origin + spacing * i``
    (``i`` from 0 to the shape, as
    :meth:`isoflow.DigitalObject.world` computes them) of a grid placed
    far from the origin against its voxel size.

    Parameters
    ----------
    origin, spacing : array_like
        The grid's origin and voxel size per axis.
    shape : tuple of int
        Voxels per axis.

    Returns
    -------
    dict
        ``axis``: the axis where float64's spacing is largest against the
        voxel size; ``near``: the largest corner coordinate magnitude
        along it, and ``step``: float64's spacing there (``np.spacing``);
        ``moved_voxels``: ``step`` in voxels, a bound on how far the
        rounding of the product and the sum moves a corner, and ``moved``
        the same in world units; ``merged``: whether two corners next to
        each other along some axis are the same float64 value, so that
        the surface's positions collapse in every format.

    Examples
    --------
    >>> c = float64_corners((1e6, 0.0, 0.0), 1e-9, (6, 6, 6))
    >>> c["axis"], c["step"] == float(np.spacing(1e6)), c["merged"], round(c["moved_voxels"], 3)
    (0, True, False, 0.116)
    >>> float64_corners((1e43, 0.0, 0.0), 1.0, (6, 6, 6))["merged"]
    True
    >>> float64_corners((-120.3, -200.7, 50.2), 0.5, (256, 256, 100))["moved_voxels"] < 1e-12
    True
    """
    origin = np.broadcast_to(np.asarray(origin, np.float64), (len(shape),))
    spacing = np.broadcast_to(np.asarray(spacing, np.float64), (len(shape),))
    worst = None
    for axis, (o, s, n) in enumerate(zip(origin.tolist(), spacing.tolist(), shape)):
        with np.errstate(over="ignore", invalid="ignore"):
            corners = o + s * np.arange(int(n) + 1, dtype=np.float64)
            # the product's rounding is on the scale of s * n, the sum's on the corner's
            near = float(np.max(np.abs(np.concatenate([corners, [s * n]]))))
            step = float(np.spacing(near))
        voxels = step / abs(s) if s else np.inf
        if worst is None or voxels > worst["moved_voxels"]:
            worst = {"axis": axis, "near": near, "step": step, "moved_voxels": voxels, "moved": step}
    return {**worst, "merged": any(merged_axes(origin, spacing, shape))}


def float64_moved(corners: dict) -> float:
    """How far float64 moves a grid's corners (``corners``:
    :func:`float64_corners`), in world units, where that reaches
    :data:`FLOAT64_NOTE_VOXELS` of a voxel, else 0: what a surface's
    read-back allows its volume for it, and what its writer says.

    Examples
    --------
    >>> float64_moved(float64_corners((1e6, 0.0, 0.0), 1e-9, (6, 6, 6))) == float(np.spacing(1e6))
    True
    >>> float64_moved(float64_corners((1.0, 2.0, 3.0), 0.5, (6, 6, 6)))
    0.0
    """
    return corners["moved"] if corners["moved_voxels"] > FLOAT64_NOTE_VOXELS else 0.0
