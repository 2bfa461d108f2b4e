"""Simple points: Bertrand's topological numbers, vectorised over candidates.

A point is *simple* for a binary volume when adding it to the object or
deleting it from the object changes no Betti number of the object or of the
background (G. Bertrand, "Simple points, topological numbers and geodesic
neighborhoods in cubic grids", Pattern Recognition Letters 15, 1994). That
holds iff both topological numbers of its ``3^n`` neighbourhood are 1, for
the connectivity pair asked. The flow's topology control (section 5 of the
paper, Theorem 21) is built on this test.
"""

from __future__ import annotations

import itertools
from functools import lru_cache

import numpy as np

from .topology import is_face_connectivity


@lru_cache(maxsize=None)
def _neighbourhood(ndim: int):
    """The 3^n - 1 neighbour offsets and the bit masks of the 3^n bitboard.

    A neighbourhood is stored as an integer whose bit ``sum_d (o_d + 1) 3^d``
    is offset ``o``; dilations are shifts by ``3^d`` with masks that stop
    them at the border of the 3^n block (as chess engines do on bitboards).
    """
    offs = np.array([o for o in itertools.product((-1, 0, 1), repeat=ndim) if any(o)], np.int64)
    pos = (offs + 1) @ (3 ** np.arange(ndim))
    coords = np.array([[(i // 3**d) % 3 for d in range(ndim)] for i in range(3**ndim)])
    l1 = np.abs(coords - 1).sum(1)

    def mask(sel):
        return int(sum(1 << int(i) for i in np.flatnonzero(sel)))

    return {
        "offsets": offs,
        "bitpos": pos.astype(np.uint32),
        "shifts": [
            (np.uint32(3**d), np.uint32(mask(coords[:, d] < 2)), np.uint32(mask(coords[:, d] > 0)))
            for d in range(ndim)
        ],
        "face": mask(l1 == 1),
        "n18": mask((l1 >= 1) & (l1 <= 2)),
        "all": mask(l1 >= 1),
    }


def _dilate(s: np.ndarray, shifts, full: bool) -> np.ndarray:
    """One step of face (``full=False``) or full adjacency on bitboards."""
    out = s
    for step, lo, hi in shifts:
        src = out if full else s
        out = out | ((src & lo) << step) | ((src & hi) >> step)
    return out


def _count_components(present: np.ndarray, seeds_mask: int, shifts, full: bool) -> np.ndarray:
    """Per row: the components of ``present`` (bitboards) that meet ``seeds_mask``."""
    count = np.zeros(len(present), np.int64)
    left = present.copy()
    seeds = np.uint32(seeds_mask)
    while True:
        cand = left & seeds
        active = cand != 0
        if not active.any():
            return count
        comp = cand & (~cand + np.uint32(1))  # lowest set bit
        while True:
            grown = _dilate(comp, shifts, full) & left
            if np.array_equal(grown, comp):
                break
            comp = grown
        count += active
        left &= ~comp




def topological_numbers(bits: np.ndarray, connectivity: int) -> tuple[np.ndarray, np.ndarray]:
    """Bertrand's topological numbers of the object and of the background.

    ``bits`` is ``(K, 3^n - 1)``: the neighbours of K points in the order of
    ``_neighbourhood(n)['offsets']``. Face connectivity (6 / 4): the object's
    number counts the face-components of the object in the 18- (3D) or
    8-neighbourhood (2D) that touch a face neighbour, the background's the
    full-adjacency components of the background in the whole neighbourhood;
    the larger connectivity swaps the roles. A point is simple (adding or
    deleting it changes no Betti number) iff both numbers are 1.
    """
    ndim = 3 if bits.shape[1] == 26 else 2
    nb = _neighbourhood(ndim)
    board = (bits.astype(np.uint32) << nb["bitpos"][None, :]).sum(axis=1, dtype=np.uint32)
    background = ~board & np.uint32(nb["all"])
    sh = nb["shifts"]

    def face_number(present):
        return _count_components(present & np.uint32(nb["n18"]), nb["face"], sh, full=False)

    def full_number(present):
        return _count_components(present, nb["all"], sh, full=True)

    if is_face_connectivity(connectivity):
        return face_number(board), full_number(background)
    return full_number(board), face_number(background)


def neighbour_bits(vol_padded: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """Neighbour bits of points ``idx`` (K, n) of a padded volume, as
    :func:`topological_numbers` takes them."""
    nb = _neighbourhood(vol_padded.ndim)
    strides = np.array([int(np.prod(vol_padded.shape[d + 1:])) for d in range(vol_padded.ndim)], np.int64)
    flat = idx @ strides
    return vol_padded.ravel()[flat[:, None] + nb["offsets"] @ strides]


def simple_points(volume: np.ndarray, points: np.ndarray, connectivity: int) -> np.ndarray:
    """Which of ``points`` (K, n array indices) are simple for ``volume``.

    A point is simple when adding it to or deleting it from the object leaves
    every Betti number of object and background unchanged: both topological
    numbers equal 1 (the point itself is ignored, so the same test serves
    for deletion and addition).
    """
    vol = np.pad(np.asarray(volume, bool), 1)
    pts = np.asarray(points, np.int64).reshape(-1, vol.ndim) + 1
    if len(pts) == 0:
        return np.zeros(0, bool)
    t_obj, t_bg = topological_numbers(neighbour_bits(vol, pts), connectivity)
    return (t_obj == 1) & (t_bg == 1)
