"""Simple points: Bertrand's topological numbers, vectorised over candidates.

A point is *simple* for a binary volume when adding it to the object or
deleting it from the object changes no Betti number of the object or of the
background (G. Bertrand, "Simple points, topological numbers and geodesic
neighborhoods in cubic grids", Pattern Recognition Letters 15, 1994). That
holds iff both topological numbers of its ``3^n`` neighbourhood are 1, for
the connectivity pair asked. The flow's topology control (section 5 of the
paper, Theorem 21) is built on this test.

Speed: a neighbourhood is packed into one integer (a *code*, bit
``sum_d (o_d + 1) 3^d`` for offset ``o``, the centre bit clear); a batch of
codes is reduced to its distinct values and only those not seen before are
counted on bitboards. Real surfaces repeat a few hundred neighbourhoods, so
after the first call a test is a gather, a pack and a table look-up.

Points that are two apart along some axis (``p`` and ``q`` with
``|p - q|_inf >= 2``) are outside each other's neighbourhood: changing one
leaves the other's test unchanged, so a whole *subfield* (the points with
the same coordinates modulo 2) can be tested and changed at once
(:func:`delete_simple`), which is a sequence of simple deletions.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .connectivity import is_face_connectivity


@cache
def _neighbourhood(ndim: int):
    """Offsets and bit masks of the ``3^n`` bitboard.

    A neighbourhood is stored as an integer whose bit ``sum_d (o_d + 1) 3^d``
    is offset ``o``; dilations are shifts by ``3^d`` with masks that stop
    them at the border of the 3^n block (as chess engines do on bitboards).
    ``cells`` lists the ``3^n`` offsets in bit order (the centre included).
    """
    coords = np.array([[(i // 3**d) % 3 for d in range(ndim)] for i in range(3**ndim)])
    l1 = np.abs(coords - 1).sum(1)

    def mask(sel):
        return int(sum(1 << int(i) for i in np.flatnonzero(sel)))

    return {
        "cells": coords - 1,
        "centre": (3**ndim) // 2,
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


def topological_numbers(codes: np.ndarray, ndim: int, connectivity: int) -> tuple[np.ndarray, np.ndarray]:
    """Bertrand's topological numbers of the object and of the background.

    ``codes`` are packed neighbourhoods (:func:`neighbourhood_codes`). Face
    connectivity (6 / 4): the object's number counts the face-components of
    the object in the 18- (3D) or 8-neighbourhood (2D) that touch a face
    neighbour, the background's the full-adjacency components of the
    background in the whole neighbourhood; the larger connectivity swaps the
    roles. A point is simple (adding or deleting it changes no Betti number)
    iff both numbers are 1.
    """
    nb = _neighbourhood(ndim)
    board = np.asarray(codes, np.uint32) & np.uint32(nb["all"])
    background = ~board & np.uint32(nb["all"])
    sh = nb["shifts"]

    def face_number(present):
        return _count_components(present & np.uint32(nb["n18"]), nb["face"], sh, full=False)

    def full_number(present):
        return _count_components(present, nb["all"], sh, full=True)

    if is_face_connectivity(connectivity):
        return face_number(board), full_number(background)
    return full_number(board), face_number(background)


@cache
def _relative(shape: tuple[int, ...]) -> np.ndarray:
    """The flat offsets of the ``3^n`` neighbourhood in a C-ordered array
    of ``shape``, in bit order: made once per shape, as the sweeps of one
    step ask for them batch after batch."""
    strides = np.array([int(np.prod(shape[d + 1:])) for d in range(len(shape))], np.int64)
    rel = _neighbourhood(len(shape))["cells"] @ strides
    rel.flags.writeable = False  # one array for every caller
    return rel


def neighbourhood_codes(padded: np.ndarray, flat: np.ndarray) -> np.ndarray:
    """Packed ``3^n`` neighbourhoods (uint32, centre bit clear) of the points
    with flat indices ``flat`` in a C-contiguous boolean volume ``padded``;
    the points must not lie on its border."""
    bits = padded.ravel()[np.asarray(flat, np.int64)[:, None] + _relative(padded.shape)]
    bits[:, _neighbourhood(padded.ndim)["centre"]] = False
    packed = np.packbits(bits, axis=1, bitorder="little")
    out = np.zeros((len(bits), 4), np.uint8)
    out[:, : packed.shape[1]] = packed
    return out.view("<u4").ravel()


#: per (ndim, face connectivity): the codes seen so far (sorted) and whether
#: each is simple; 2D holds all 512 from the start
_SEEN: dict = {}
_SEEN_MAX = 1 << 20


def simple_codes(codes: np.ndarray, ndim: int, connectivity: int) -> np.ndarray:
    """Whether each packed neighbourhood is that of a simple point.

    Distinct codes are counted once (:func:`topological_numbers`) and
    remembered for the next call."""
    key = (ndim, is_face_connectivity(connectivity))
    codes = np.asarray(codes, np.uint32)
    if key not in _SEEN or len(_SEEN[key][0]) > _SEEN_MAX:
        start = np.arange(512, dtype=np.uint32) if ndim == 2 else np.zeros(0, np.uint32)
        start = start & np.uint32(_neighbourhood(ndim)["all"])
        start = np.unique(start)
        t_obj, t_bg = topological_numbers(start, ndim, connectivity)
        _SEEN[key] = (start, (t_obj == 1) & (t_bg == 1))
    known, simple = _SEEN[key]
    if len(codes) == 0:
        return np.zeros(0, bool)
    pos = np.searchsorted(known, codes)
    hit = pos < len(known)
    hit[hit] = known[pos[hit]] == codes[hit]
    if not hit.all():
        new = np.unique(codes[~hit])
        t_obj, t_bg = topological_numbers(new, ndim, connectivity)
        known = np.concatenate([known, new])
        simple = np.concatenate([simple, (t_obj == 1) & (t_bg == 1)])
        order = np.argsort(known, kind="stable")
        known, simple = known[order], simple[order]
        _SEEN[key] = (known, simple)
        pos = np.searchsorted(known, codes)
    return simple[pos]


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
    flat = np.ravel_multi_index(tuple(pts.T), vol.shape)
    return simple_codes(neighbourhood_codes(vol, flat), vol.ndim, connectivity)


def subfields(flat: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """The subfield of every flat index: ``sum_d (x_d mod 2) 2^d``."""
    coords = np.unravel_index(np.asarray(flat, np.int64), shape)
    return sum((c & 1) << d for d, c in enumerate(coords))


def delete_simple(padded: np.ndarray, flat: np.ndarray, connectivity: int) -> np.ndarray:
    """Delete from ``padded`` (in place) those of the object points ``flat``
    that are simple, one subfield after the other; returns the deleted ones.

    Within a subfield the points are two apart, so each is tested against the
    volume left by the previous subfields and all of them go at once: the
    whole is a sequence of simple deletions and keeps every Betti number.
    ``padded`` is C-contiguous, as :func:`neighbourhood_codes` reads it.
    """
    if not padded.flags.c_contiguous:
        # ravel() of another layout is a copy: the deletions would be lost in silence
        raise ValueError("delete_simple deletes in place from a C-contiguous volume")
    flat = np.asarray(flat, np.int64)
    field = subfields(flat, padded.shape)
    gone = []
    for f in range(1 << padded.ndim):
        pts = flat[field == f]
        if len(pts) == 0:
            continue
        ok = simple_codes(neighbourhood_codes(padded, pts), padded.ndim, connectivity)
        padded.ravel()[pts[ok]] = False
        gone.append(pts[ok])
    return np.concatenate(gone) if gone else np.zeros(0, np.int64)
