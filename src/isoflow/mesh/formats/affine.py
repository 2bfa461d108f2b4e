"""Affine voxel-to-world maps (NIfTI, MGH, NRRD) as isoflow's axis-aligned grid.

NIfTI's affine and NRRD's space directions map a voxel's *centre* index
``(i, j, k)`` to world coordinates. isoflow's grid is axis-aligned with a
positive step along each axis (``DigitalObject.world``), so the array is
turned to match: each array axis goes to the world axis it runs along most
(a permutation) and is reversed where it runs backwards (a flip, as in the
LAS or LPS orientations of most scanners). After that every voxel lands
exactly where the affine puts it. What is left is a rotation or shear (an
oblique acquisition); that part cannot be held in a per-axis voxel size, so
the grid keeps the voxel sizes (the column lengths, nibabel's ``zooms``) and
the position of the first voxel, and a warning says by how many degrees the
true grid is turned. The topology never depends on it; exported coordinates
are then off by that rotation about the first voxel.
"""

from __future__ import annotations

import numpy as np

from ...errors import IsoflowError
from .registry import note

#: off-axis entries below this fraction of the largest one are rounding
OBLIQUE_TOLERANCE = 1e-6


def axis_aligned(array: np.ndarray, matrix, centre0, where: str):
    """``(array, pitch, origin)`` on isoflow's grid.

    ``matrix`` (world dims x placed axes): column ``j`` is the world step of
    array axis ``j``; ``centre0``: the world position of voxel ``(0, 0, ...)``'s
    centre. Returns the array permuted and flipped so that axis ``a`` runs
    along the ``a``-th of the world axes it uses, with positive steps (axes
    beyond the matrix's columns, such as time, stay last as they are); the
    voxel size per placed axis; and the world position of voxel 0's lowest
    corner (in those world axes).
    """
    m = np.asarray(matrix, np.float64)
    c0 = np.asarray(centre0, np.float64)
    n = m.shape[1] if m.ndim == 2 else -1
    if not 0 < n <= array.ndim:
        raise IsoflowError(f"{where}: the voxel-to-world map {m.tolist()} does not fit a {n}D array")
    if not (np.isfinite(m).all() and np.isfinite(c0).all()):
        raise IsoflowError(f"{where}: the voxel-to-world map {m.tolist()} with the first voxel at {c0.tolist()} "
                           "holds values that are not finite numbers")
    # each column scaled by its largest entry first: the squares of a step of
    # 1e-300 (or 1e300) underflow to 0 (or overflow to inf) where the step does not
    scale = np.abs(m).max(axis=0)
    norms = scale * np.linalg.norm(m / np.where(scale > 0, scale, 1.0), axis=0)
    if not (norms > 0).all():
        raise IsoflowError(f"{where}: the voxel-to-world map {m.tolist()} has a zero voxel size")
    rows = _world_axes(m, norms)  # the world axis each array axis runs along
    if rows is None:
        raise IsoflowError(
            f"{where}: two array axes run along the same world axis in {np.round(m, 6).tolist()}"
        )
    dominant = m[rows, np.arange(n)]
    off = m.copy()
    off[rows, np.arange(n)] = 0
    if np.abs(off).max() > OBLIQUE_TOLERANCE * np.abs(m).max():
        angle = np.degrees(np.arccos(np.clip(np.abs(dominant) / norms, 0, 1))).max()
        note(
            f"{where}: the voxel grid is rotated or sheared by up to {angle:.3g} degrees against the "
            "world axes; isoflow keeps the voxel sizes and the first voxel's place, so exported "
            "coordinates are axis-aligned (off by that rotation); resample the image to remove it"
        )
    if n < m.shape[0] and sorted(rows) != list(range(n)):
        plane_off_axes(rows, c0, where)
    # voxel 0 of the turned array is the old voxel at the far end of every flipped axis
    flipped = dominant < 0
    first = np.where(flipped, np.array(array.shape[:n]) - 1, 0)
    centre = c0 + m @ first
    order = np.argsort(rows)  # new axis a = old axis order[a]
    out = np.flip(array, axis=tuple(np.flatnonzero(flipped))) if flipped.any() else array
    out = np.transpose(out, [*order, *range(n, array.ndim)])
    pitch = norms[order]
    origin = centre[rows[order]] - pitch / 2
    return out, pitch, origin


def plane_off_axes(rows, centre0, where: str) -> str:
    """Warn that an image of fewer axes than the world (a 2D slice placed
    in 3D) runs along world axes other than the first ones: a sagittal
    slice's axes run along y and z, and are read as the image's x and y,
    so its coordinates (and the letters of its frame) are those of world
    y and z, and its place along world x is not kept.

    Parameters
    ----------
    rows : array_like of int
        The world axis each array axis runs along.
    centre0 : array_like
        The world position of voxel 0's centre.
    where : str
        The file, named in the warning.

    Returns
    -------
    str
        The warning given.

    Examples
    --------
    >>> import warnings
    >>> with warnings.catch_warnings():  # the warning given is also returned
    ...     warnings.simplefilter("ignore")
    ...     print(plane_off_axes([1, 2], [5.0, -10.0, 20.0], "sagittal.nii.gz"))
    sagittal.nii.gz: a 2D image in the world's y-z plane: read with world y and z as its x and y, so its \
coordinates are world y and z (not its frame's x and y), and its place at world x = 5 is not kept
    """
    names = "xyz"
    used = sorted(int(r) for r in rows)
    dropped = [i for i in range(len(centre0)) if i not in used]
    place = ", ".join(f"world {names[i]} = {float(centre0[i]):.6g}" for i in dropped)
    along = [names[i] for i in used]
    text = (f"{where}: a {len(used)}D image in the world's {'-'.join(along)} plane: read with world "
            f"{' and '.join(along)} as its {' and '.join(names[:len(used)])}, so its coordinates are world "
            f"{' and '.join(along)} (not its frame's {' and '.join(names[:len(used)])}), and its place at {place} is "
            "not kept")
    note(text)
    return text


def _world_axes(m: np.ndarray, norms: np.ndarray):
    """The world axis of each array axis (column): distinct axes with the
    largest sum of |cosines|, the first such assignment where several tie
    (a grid turned by exactly 45 degrees runs along two world axes
    equally), or None where every assignment has an axis at right angles
    to its world axis."""
    from itertools import permutations

    cos = np.abs(m) / norms
    d, n = m.shape
    best, rows = -1.0, None
    for perm in permutations(range(d), n):
        picked = cos[list(perm), np.arange(n)]
        if (picked > 0).all() and picked.sum() > best + 1e-12:
            best, rows = picked.sum(), np.array(perm)
    return rows


def centre_affine(pitch, origin) -> tuple[np.ndarray, np.ndarray]:
    """The diagonal voxel-to-world map and voxel 0's centre of a grid with
    voxel size ``pitch`` whose voxel 0 has its lowest corner at ``origin``:
    what NIfTI and NRRD store."""
    pitch = np.asarray(pitch, np.float64)
    return np.diag(pitch), np.asarray(origin, np.float64) + pitch / 2
