"""The sheets of a box of labelled voxels, summed per pair of labels
(numba): the compiled form of
:func:`isoflow.digital.closed_surfaces.box_sheets`, which the out-of-core
report runs block by block and on the face tiles between blocks.

Along each row of vertices the configuration shifts in one nibble per
vertex; every sheet of a configuration (tables from
:func:`isoflow.digital.closed_surfaces.sweep_tables`) counts one mesh vertex
and a quarter of each of its faces for the pair (object label, background
label) of one of its faces. The pairs are summed in a small open-addressing
hash table, with the last pair cached, since neighbouring vertices mostly
lie on the same surface; a table that fills up is made larger and the box
counted again.
"""

from __future__ import annotations

import numpy as np
from .jit import njit

_EMPTY = -1
_GOLDEN = -7046029254386353131  # 0x9E3779B97F4A7C15 as int64: Fibonacci hashing


@njit(cache=True, nogil=True, inline="always")
def _slot(key, mask):
    h = key * _GOLDEN
    return (h ^ (h >> 29)) & mask


@njit(cache=True, nogil=True, inline="always")
def _add(keys, vs, qs, key, dv, dq):
    """Add (dv, dq) to ``key``'s entry of the table; returns 1 for a new
    key. The table never grows here (reassigning arrays inside the sweep's
    loop makes numba's code several times slower); the caller sizes it."""
    mask = len(keys) - 1
    s = _slot(key, mask)
    while keys[s] != _EMPTY and keys[s] != key:
        s = (s + 1) & mask
    if keys[s] == key:
        vs[s] += dv
        qs[s] += dq
        return 0
    keys[s], vs[s], qs[s] = key, dv, dq
    return 1


def _until_it_fits(call, capacity: int, pair_capacity: int):
    """Run ``call(keys, vs, qs, pairs) -> (npairs, overflow, extra)`` on
    fresh buffers, larger ones until the surfaces and the pinches fit.
    Returns ``extra``, the table's filled keys, vertices, quarters and the
    pinch pairs."""
    while True:
        keys = np.full(capacity, _EMPTY, np.int64)
        vs = np.zeros(capacity, np.int64)
        qs = np.zeros(capacity, np.int64)
        pairs = np.empty((pair_capacity, 2), np.int64)
        npairs, overflow, extra = call(keys, vs, qs, pairs)
        if overflow:
            capacity *= 4
        elif npairs > pair_capacity:
            pair_capacity = npairs
        else:
            filled = keys != _EMPTY
            return extra, keys[filled], vs[filled], qs[filled], pairs[:npairs]


@njit(cache=True, nogil=True, inline="always")
def _box_label(vox, fg, bg, x, y, z, outside):
    """Label of voxel (x, y, z): its object or background label, ``outside``
    beyond the block."""
    nx, ny, nz = vox.shape
    if 0 <= x < nx and 0 <= y < ny and 0 <= z < nz:
        return np.int64(fg[x, y, z]) if vox[x, y, z] else np.int64(bg[x, y, z])
    return np.int64(outside)


@njit(cache=True, nogil=True, _nrt=False)
def _box_rows(vox, fg, bg, lo, hi, outside, keys, vs, qs, pairs, nsheet, sheet_obj, sheet_bg, sheet_quarters, pinch,
              zero, last):
    """Sheets of the vertices ``lo <= w < hi`` of a block, per pair of the
    block's labels (``fg << 32 | bg``), from its label volumes; octants
    outside the block are background labelled ``outside``. Along each row
    the configuration shifts in one nibble per vertex (as in the histogram
    kernel); labels are read only for the octants a sheet names. Returns the
    number of pinch pairs found and whether the table filled up."""
    nx, ny, nz = vox.shape
    used = 0
    full = len(keys) // 2
    npairs = 0
    ck, cv, cq = _EMPTY, 0, 0
    for i in range(lo[0], hi[0]):
        for j in range(lo[1], hi[1]):
            # octant (dx, dy) is voxel row (i-1+dx, j-1+dy)
            r00 = vox[i - 1, j - 1] if i >= 1 and j >= 1 else zero
            r10 = vox[i, j - 1] if i < nx and j >= 1 else zero
            r01 = vox[i - 1, j] if i >= 1 and j < ny else zero
            r11 = vox[i, j] if i < nx and j < ny else zero
            k0 = lo[2]
            code = 0
            if k0 >= 1:  # the nibble of voxel k0 - 1
                code = ((r00[k0 - 1] != 0) | ((r10[k0 - 1] != 0) << 1) | ((r01[k0 - 1] != 0) << 2)
                        | ((r11[k0 - 1] != 0) << 3)) << 4
            prev = -1
            for k in range(k0, hi[2]):
                nib = 0
                if k < nz:
                    nib = (r00[k] != 0) | ((r10[k] != 0) << 1) | ((r01[k] != 0) << 2) | ((r11[k] != 0) << 3)
                code = (code >> 4) | (nib << 4)
                # A "layer" (the same four voxels on both sides) repeated:
                # voxel k has the label of voxel k-1, so the sheets' keys are
                # those of the vertex before; no label to read.
                same = code == prev and (code >> 4) == (code & 15)
                prev = code
                if code == 0 or code == 255:  # most vertices: off the boundary
                    continue
                for s in range(nsheet[code]):
                    if same:
                        key = last[s]
                    else:
                        o, b = sheet_obj[code, s], sheet_bg[code, s]
                        lo_ = _box_label(vox, fg, bg, i - 1 + (o & 1), j - 1 + ((o >> 1) & 1), k - 1 + (o >> 2), outside)
                        lb = _box_label(vox, fg, bg, i - 1 + (b & 1), j - 1 + ((b >> 1) & 1), k - 1 + (b >> 2), outside)
                        key = (lo_ << 32) | lb
                        last[s] = key
                    if key != ck:
                        if ck != _EMPTY:
                            used += _add(keys, vs, qs, ck, cv, cq)
                            if used > full:
                                return npairs, True
                        ck, cv, cq = key, 0, 0
                    cv += 1
                    cq += sheet_quarters[code, s]
                if pinch[code, 0] >= 0:
                    a, b = pinch[code, 0], pinch[code, 1]
                    la = _box_label(vox, fg, bg, i - 1 + (a & 1), j - 1 + ((a >> 1) & 1), k - 1 + (a >> 2), outside)
                    lb = _box_label(vox, fg, bg, i - 1 + (b & 1), j - 1 + ((b >> 1) & 1), k - 1 + (b >> 2), outside)
                    if la != lb:
                        if npairs < len(pairs):
                            pairs[npairs, 0], pairs[npairs, 1] = la, lb
                        npairs += 1
    if ck != _EMPTY:
        _add(keys, vs, qs, ck, cv, cq)
    return npairs, False


def box_sweep(vox: np.ndarray, fg: np.ndarray, bg: np.ndarray, lo, hi, outside: int, tables) -> dict:
    """:func:`isoflow.digital.closed_surfaces.box_sheets` compiled, for one
    block: ``fg``/``bg`` are its label volumes (labels below 2^31, as
    ``outside``), ``lo``/``hi`` the vertex box to count. Returns ``obj``,
    ``bg`` (the pairs), ``vertices``, ``quarters`` and the pinch ``pairs``."""
    nsheet, sheet_obj, sheet_bg, quarters, _, pinch = tables
    lo, hi = np.asarray(lo, np.int64), np.asarray(hi, np.int64)

    def call(keys, vs, qs, pairs):
        npairs, overflow = _box_rows(vox.view(np.uint8), fg, bg, lo, hi, outside, keys, vs, qs, pairs,
                                     nsheet, sheet_obj, sheet_bg, quarters, pinch, np.zeros(vox.shape[2], np.uint8),
                                     np.zeros(4, np.int64))
        return npairs, overflow, None

    _, keys, vertices, quarter, pairs = _until_it_fits(call, 1 << 12, 1 << 10)
    return {"obj": keys >> 32, "bg": keys & 0xFFFFFFFF, "vertices": vertices, "quarters": quarter, "pairs": pairs}
