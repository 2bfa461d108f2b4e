"""Segments of the boundary (Definitions 12-13, 16): the maximal runs of
vertices with one configuration along an axis, and their ends.

Shared by the 3D flow (:mod:`isoflow.flow.motion`: convex edges and flat
vertices) and the planar flow (:mod:`isoflow.flow.planar`: flat vertices):
a vertex on a segment moves outward or inward by the signs of the segment's
ends, so both flows call :func:`segment_moves` after their per-class tables.
"""

from __future__ import annotations

import numpy as np


def segment_moves(cfg: np.ndarray, keep: np.ndarray, negative: np.ndarray, role: np.ndarray) -> None:
    """Set ``keep`` at the convex edges whose two ends are negative and the
    flat vertices with a negative end on a segment along an in-face axis.

    ``role`` is a table over configurations as in
    :func:`isoflow.flow.motion.motion_luts`: edges ``1..n``, flats
    ``n+1..2n``; in 2D (:func:`isoflow.flow.planar.planar_motion_luts`) the
    flats' role is ``1 + segment axis`` and they behave like flats.
    ``negative`` marks the configurations that count as a negative end."""
    nd = cfg.ndim
    r_all = role[cfg]
    points = np.nonzero(r_all)
    if len(points[0]) == 0:
        return
    r = r_all[points]
    del r_all
    if nd == 2:
        edge_axis = np.full(len(r), -1)
        flat_axes = [r == 1 + a for a in range(nd)]
    else:
        edge_axis = np.where(r <= nd, r - 1, -1)
        normal = r - 1 - nd
        flat_axes = [(r > nd) & (normal != a) for a in range(nd)]
    edges_ok = np.ones(len(r), bool)
    flats_ok = np.zeros(len(r), bool)
    for axis in range(nd):
        on_edge = edge_axis == axis
        on_flat = flat_axes[axis]
        sel = np.flatnonzero(on_edge | on_flat)
        if len(sel) == 0:
            continue
        before, after = segment_end_signs(cfg, negative, axis, tuple(p[sel] for p in points))
        e_here = on_edge[sel]
        edges_ok[sel[e_here]] = before[e_here] & after[e_here]
        f_here = on_flat[sel]
        flats_ok[sel[f_here]] |= before[f_here] | after[f_here]
    moved = np.where(edge_axis >= 0, edges_ok, flats_ok)
    keep[tuple(p[moved] for p in points)] = True


def segment_end_signs(
    cfg: np.ndarray, negative: np.ndarray, axis: int, points: tuple[np.ndarray, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Are the two ends of the segment through each of ``points`` negative?

    A segment is the maximal run of equal configurations along ``axis``; its
    ends are the vertices just before and just after the run. ``points`` is a
    tuple of index arrays (as from ``np.nonzero``); returns two boolean arrays
    over them: the end before the run is negative, the end after it is
    negative (``negative`` is a table over configurations). Vertices past the
    array are background (config 0, not negative).

    Run-length work on the lines along ``axis`` laid out contiguously: one
    comparison with the shifted array marks the run starts, one
    ``flatnonzero`` lists them and one cumulative sum numbers the runs; a
    point's run number gives its run's first vertex, the next run's start
    one past its last. A constant number of passes, then work proportional
    to the number of points.
    """
    lines = np.ascontiguousarray(np.moveaxis(cfg, axis, -1))
    n = lines.shape[-1]
    flat = lines.reshape(-1, n)
    total = flat.size
    change = np.empty(flat.shape, bool)
    change[:, 0] = True
    np.not_equal(flat[:, 1:], flat[:, :-1], out=change[:, 1:])
    starts = np.flatnonzero(change)
    itype = np.int32 if total < 2**31 else np.int64
    run_of = np.cumsum(change.ravel(), dtype=itype)  # 1 + run number of every vertex
    del change
    others = [points[d] for d in range(cfg.ndim) if d != axis]
    q = np.ravel_multi_index((*others, points[axis]), lines.shape)
    run = run_of[q] - 1
    del run_of
    first = starts[run]
    nxt = np.append(starts, total)[run + 1]  # start of the next run: one past the end
    values = flat.ravel()
    before = (first % n != 0) & negative[values[first - 1]]
    after_ok = nxt % n != 0  # the run ends inside the line (nxt == total gives 0 too)
    after = after_ok & negative[values[np.minimum(nxt, total - 1)]]
    return before, after
