"""An upper bound on the number of voxels in a mesh's shell, from boxes.

The shell (:mod:`isoflow.mesh.shell`) holds every voxel whose closed cube
meets a closed triangle of the mesh; such a cube meets the triangle's
bounding box, so the voxels whose cubes meet the boxes, counted once each,
are at least as many as the shell's.  A triangle is first cut in two at
the midpoint of its longest edge, and its pieces likewise, until each piece
spans at most ``extent`` voxels along every axis: the pieces cover the
triangle, and their small boxes hug it.

The winding rule's thin note (:mod:`isoflow.mesh.fills`) needs the shell's
count only to tell whether the solid has fewer voxels than half of it; where
this bound already says it has not, the shell's compiled pass (whose first
compile is a wait of its own) is not run.  The bound is computed with NumPy
alone, on a budget of pieces: past it, the caller counts the shell.
"""

from __future__ import annotations

import numpy as np

#: the largest extent of a piece, in voxels, tried in turn until the bound is small enough
EXTENTS = (1.0, 0.5)
#: at most this many pieces (each stands for up to 27 voxel indices), and
#: this many per voxel of the bound wanted: the bound costs no more than the
#: answer it may spare
MAX_PIECES = 1 << 16
PIECES_PER_VOXEL = 16
#: a cut finer by half is tried only where the bound is within this factor
#: of the one wanted (on the sample meshes, a finer cut took off 5 to 25 %)
CLOSER = 1.25
#: grids of at most this many voxels mark the boxes' voxels in an array of as many bytes
MARKED_VOXELS = 1 << 24
#: each box grows by this share of a voxel (and of the coordinates' size):
#: the pieces' midpoints are rounded, and the boxes must still cover the
#: triangle's every point
GROWTH = 1e-7


def shell_voxels_at_most(T: np.ndarray, planes, need: int) -> int | None:
    """A number at least the shell's voxel count and at most ``need``, or
    None where the boxes of the pieces allowed give none.

    Parameters
    ----------
    T : float64 ndarray (M, 3, 3)
        Triangle corners, in the frame of the planes.
    planes : three float64 ndarrays
        ``planes[a][i]`` is the lower face of voxel i along axis a
        (:func:`isoflow.mesh.shell.grid_planes`).
    need : int
        The bound is wanted at most this large.

    Examples
    --------
    A unit square at mid-height, across the corner where four voxels of a
    grid of 4 x 4 x 2 meet, meets those four; the bound counts no more:

    >>> from isoflow.mesh.shell import grid_planes
    >>> T = np.array([[[0.5, 0.5, 0.5], [1.5, 0.5, 0.5], [1.5, 1.5, 0.5]],
    ...               [[0.5, 0.5, 0.5], [1.5, 1.5, 0.5], [0.5, 1.5, 0.5]]])
    >>> shell_voxels_at_most(T, grid_planes(np.zeros(3), 1.0, (4, 4, 2)), need=10)
    4
    """
    T = np.asarray(T, dtype=np.float64)
    lo_plane = np.array([p[0] for p in planes])
    pitch = (np.array([p[-1] for p in planes]) - lo_plane) / np.array([len(p) - 1 for p in planes])
    limit = min(MAX_PIECES, len(T) + PIECES_PER_VOXEL * need)
    for extent in EXTENTS:
        pieces = _pieces(T, extent * pitch, limit)
        if pieces is None:
            return None
        T = pieces  # a finer cut starts from these
        count = _box_voxels(T, planes, pitch)
        if count <= need:
            return count
        if count > CLOSER * need:  # a finer cut would not bring it down so far
            return None
    return None


def _pieces(T: np.ndarray, most: np.ndarray, limit: int) -> np.ndarray | None:
    """``T`` cut in two at the midpoint of its longest edge until every
    piece spans at most ``most`` along each axis (None past ``limit``
    pieces): a sliver's pieces stay as many as its length needs."""
    done, count = [], len(T)
    while len(T):
        big = ((T.max(axis=1) - T.min(axis=1)) > most).any(axis=1)
        done.append(T[~big])
        B = T[big]
        count += len(B)
        if count > limit:
            return None
        # the corners turned so that the longest edge runs from the first to the second
        length = np.stack([((B[:, (i + 1) % 3] - B[:, i]) ** 2).sum(axis=1) for i in range(3)], axis=1)
        B = np.take_along_axis(B, ((length.argmax(axis=1)[:, None] + np.arange(3)) % 3)[:, :, None], axis=1)
        a, b, c = B[:, 0], B[:, 1], B[:, 2]
        m = (a + b) / 2
        T = np.concatenate([np.stack([a, m, c], axis=1), np.stack([m, b, c], axis=1)])
    return np.concatenate(done)


def _box_voxels(T: np.ndarray, planes, pitch: np.ndarray) -> int:
    """The voxels whose closed cubes meet the (grown) boxes of ``T``,
    each counted once (a box of pieces no wider than a voxel spans at most
    three voxels along an axis)."""
    grow = GROWTH * (pitch + np.abs(T).max(initial=0.0))
    shape = [len(p) - 1 for p in planes]
    lo = np.empty((len(T), 3), dtype=np.int64)
    hi = np.empty((len(T), 3), dtype=np.int64)
    for a in range(3):
        # voxel i meets [m, M] iff planes[i] <= M and planes[i + 1] >= m
        lo[:, a] = np.searchsorted(planes[a][1:], T[:, :, a].min(axis=1) - grow[a], side="left")
        hi[:, a] = np.searchsorted(planes[a][:-1], T[:, :, a].max(axis=1) + grow[a], side="right")
    np.clip(lo, 0, shape, out=lo)
    np.clip(hi, 0, shape, out=hi)
    # the voxels as flat indices, marked in a boolean grid where it is small
    # (else counted once each by sorting)
    first = (lo[:, 0] * shape[1] + lo[:, 1]) * shape[2] + lo[:, 2]
    seen = np.zeros(int(np.prod(shape)), dtype=bool) if np.prod(shape) <= MARKED_VOXELS else None
    keys = []
    span = int((hi - lo).max(initial=0))
    for d in np.ndindex(span, span, span):
        inside = (lo + np.array(d) < hi).all(axis=1)
        key = first[inside] + ((d[0] * shape[1] + d[1]) * shape[2] + d[2])
        if seen is None:
            keys.append(key)
        else:
            seen[key] = True
    return int(np.count_nonzero(seen)) if seen is not None else int(np.unique(np.concatenate(keys)).size)
