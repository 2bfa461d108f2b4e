"""The vertex sweep (numba): one pass over the lattice vertices, read from
the runs of the volume, that gives the configuration histogram and, for
every closed boundary surface, its sheet and face counts, without building
the boundary mesh.

Input: the object's runs along the last axis and the background's runs
(their gaps), both labelled by :func:`isoflow.scale.kernels.join_runs`
with the adjacencies under which the boundary mesh splits its surfaces
(:mod:`isoflow.digital.closed_surfaces` says which and why). A surface is
then identified by the pair (object label, background label) that its faces
separate, and everything it needs is counted per pair:

* along a row of vertices, the configuration only changes where one of the
  four voxel rows around it starts or ends a run (an *event*); between two
  events the configuration is a constant "layer" (the same four voxels
  above and below), whose sheets each have four faces. So the work is per
  run end, not per vertex, and the histogram comes for free;
* every sheet of a vertex configuration (tables from
  :func:`isoflow.digital.surface.sheet_lut`) counts one mesh vertex and a
  quarter of each of its faces for the pair of labels of one of its faces:
  ``V(S)`` and ``4 F(S)``, so that ``chi(S) = V(S) - F(S)``;
* a lattice edge whose spoke is doubled at both ends (the mesh's doubled
  edges) is counted at its lower end; those ends are events too;
* vertex contacts that the connectivity joins but the mesh splits
  (pinches) give a pair of labels to join for the Betti numbers.

The pairs are summed in a small open-addressing hash table per thread (one
entry per surface the slab sees), with the last pair cached, since
neighbouring vertices mostly lie on the same surface.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .compiled import run, slabs, thread_count
from .memory import check_fits

_EMPTY = -1
_GOLDEN = -7046029254386353131  # 0x9E3779B97F4A7C15 as int64: Fibonacci hashing


@njit(cache=True, nogil=True, inline="always")
def _slot(key, mask):
    h = key * _GOLDEN
    return (h ^ (h >> 29)) & mask


@njit(cache=True, nogil=True)
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


@njit(cache=True, nogil=True)
def _config_at(v, i, j, k):
    """Configuration of vertex (i, j, k) read from the volume (zeros outside)."""
    nx, ny, nz = v.shape
    c = 0
    for o in range(8):
        x, y, z = i - 1 + (o & 1), j - 1 + ((o >> 1) & 1), k - 1 + (o >> 2)
        if 0 <= x < nx and 0 <= y < ny and 0 <= z < nz and v[x, y, z] != 0:
            c |= 1 << o
    return c


@njit(cache=True, nogil=True)
def _sweep_rows(v, offsets, start, end, goff, pobj, pbg, i0, i1, hist, keys, vs, qs, pairs,
                nsheet, sheet_obj, sheet_bg, sheet_quarters, spokes, pinch):
    """Sweep the vertex rows (i, j) with i0 <= i < i1. See the module docs.

    ``pobj``/``pbg``: root of every object run / gap (flattened parents),
    the outside being the last gap node. Tables over the 256 configurations:
    ``nsheet``; per sheet the octant of an object voxel and of a background
    voxel one of its faces separates, and its face count; ``spokes``, bit
    ``2 axis + side`` set where that spoke is doubled; ``pinch``, the two
    octants (object or background) to join, or -1.

    Fills ``hist`` (256,), the hash table ``keys`` (``obj << 32 | bg``,
    empty slots -1), ``vs`` (vertices), ``qs`` (quarter faces) and
    ``pairs`` (pinch label pairs, as many as fit). Returns the doubled
    edges, the number of pinch pairs found (all of them, also those that
    did not fit) and whether the table filled up (then nothing is complete
    and the caller runs the slab again with a larger table).
    """
    nx, ny, nz = v.shape
    outside = pbg[len(pbg) - 1]
    used = 0
    full = len(keys) // 2
    npairs = 0
    doubled = 0
    ck, cv, cq = _EMPTY, 0, 0  # the cached pair and its pending counts

    big = nz + 1  # "no more events" in a row
    pos = np.zeros(4, np.int64)  # the run (inside) or the next run (in a gap)
    last = np.zeros(4, np.int64)  # one past the row's last run
    gap = np.zeros(4, np.int64)  # the gap index minus the runs passed
    ins = np.zeros(4, np.bool_)  # the cursor is inside run pos
    nxt = np.zeros(4, np.int64)  # the row's next event
    cur = np.zeros(4, np.int64)  # label of the row's voxel at the cursor
    before = np.zeros(4, np.int64)  # labels of voxel ev-1 at an event

    for i in range(i0, i1):
        for j in range(ny + 1):
            anyrun = False
            for q in range(4):
                ri, rj = i - 1 + (q & 1), j - 1 + (q >> 1)
                ins[q] = False
                cur[q] = outside
                nxt[q] = big
                pos[q] = 0
                last[q] = 0
                if 0 <= ri < nx and 0 <= rj < ny:
                    r = ri * ny + rj
                    a, b = offsets[r], offsets[r + 1]
                    if a < b:
                        anyrun = True
                        pos[q], last[q] = a, b
                        # gap index of the gap before run p: goff[r] + (p - a),
                        # less one when the row starts with a run
                        gap[q] = goff[r] - a - (1 if start[a] == 0 else 0)
                        nxt[q] = start[a]
                        if start[a] > 0:
                            cur[q] = pbg[gap[q] + a]
                    # a row without runs is one gap, on the border of the
                    # volume or not: labelled with its own gap
                    else:
                        cur[q] = pbg[goff[r]]
            if not anyrun:
                hist[0] += nz + 1
                continue
            k = 0  # first vertex not yet counted
            nib = 0  # the four rows' voxels at the cursor
            cprev = 0  # configuration of vertex k - 1
            while True:
                ev = min(min(nxt[0], nxt[1]), min(nxt[2], nxt[3]))
                # the stretch k .. ev-1: a constant layer configuration
                if ev > k:
                    c = nib | (nib << 4)
                    hist[c] += ev - k
                    for s in range(nsheet[c]):
                        key = (cur[sheet_obj[c, s] & 3] << 32) | cur[sheet_bg[c, s] & 3]
                        if key != ck:
                            if ck != _EMPTY:
                                used += _add(keys, vs, qs, ck, cv, cq)
                            if used > full:
                                return doubled, npairs, True
                                if used > full:
                                    return doubled, npairs, True
                            ck, cv, cq = key, 0, 0
                        cv += ev - k
                        cq += (ev - k) * sheet_quarters[c, s]
                    cprev = c
                if ev == big:
                    break
                # the event vertex ev: voxels ev-1 (before) and ev (after)
                old = nib
                for q in range(4):
                    before[q] = outside if ev == 0 else cur[q]
                    if nxt[q] == ev:
                        p = pos[q]
                        if ins[q]:  # run p ends: into the gap after it
                            ins[q] = False
                            nib &= ~(1 << q)
                            p += 1
                            pos[q] = p
                            nxt[q] = start[p] if p < last[q] else big
                            cur[q] = pbg[gap[q] + p] if ev < nz else outside
                        else:  # run p starts
                            ins[q] = True
                            nib |= 1 << q
                            nxt[q] = end[p]
                            cur[q] = pobj[p]
                c = old | (nib << 4)
                hist[c] += 1
                for s in range(nsheet[c]):
                    o, b = sheet_obj[c, s], sheet_bg[c, s]
                    lo = cur[o & 3] if o >= 4 else before[o & 3]
                    lb = cur[b & 3] if b >= 4 else before[b & 3]
                    key = (lo << 32) | lb
                    if key != ck:
                        if ck != _EMPTY:
                            used += _add(keys, vs, qs, ck, cv, cq)
                            if used > full:
                                return doubled, npairs, True
                        ck, cv, cq = key, 0, 0
                    cv += 1
                    cq += sheet_quarters[c, s]
                if pinch[c, 0] >= 0:
                    a, b = pinch[c, 0], pinch[c, 1]
                    la = cur[a & 3] if a >= 4 else before[a & 3]
                    lb = cur[b & 3] if b >= 4 else before[b & 3]
                    if la != lb:
                        if npairs < len(pairs):
                            pairs[npairs, 0], pairs[npairs, 1] = la, lb
                        npairs += 1
                sp = spokes[c]
                if sp != 0:
                    # doubled lattice edges, each counted at its lower end:
                    # the spoke toward +axis here (bit 2 axis + 1) and toward
                    # -axis at the other end (bit 2 axis)
                    if (spokes[cprev] >> 5) & (sp >> 4) & 1:
                        doubled += 1  # the edge from vertex ev-1 to ev
                    if (sp >> 1) & 1 and i < nx:
                        doubled += spokes[_config_at(v, i + 1, j, ev)] & 1
                    if (sp >> 3) & 1 and j < ny:
                        doubled += (spokes[_config_at(v, i, j + 1, ev)] >> 2) & 1
                cprev = c
                k = ev + 1
    if ck != _EMPTY:
        _add(keys, vs, qs, ck, cv, cq)  # fits: the table was at most half full
    return doubled, npairs, False


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


def _slab(v, runs, goff, pobj, pbg, i0, i1, tables, capacity, pair_capacity):
    """One slab of vertex layers: ``(hist, doubled)``, keys, vertices,
    quarters, pinch pairs."""

    def call(keys, vs, qs, pairs):
        hist = np.zeros(256, np.int64)
        doubled, npairs, overflow = _sweep_rows(v, *runs, goff, pobj, pbg, i0, i1, hist, keys, vs, qs, pairs, *tables)
        return npairs, overflow, (hist, doubled)

    return _until_it_fits(call, capacity, pair_capacity)


def sweep(v: np.ndarray, runs, goff: np.ndarray, pobj: np.ndarray, pbg: np.ndarray, surfaces: int, tables,
          pair_capacity: int = 1024) -> dict:
    """Run the sweep over slabs of vertex layers on the threads and add up
    what they found.

    ``v``: the 3D uint8 volume; ``runs``: the object's (offsets, start,
    end); ``goff``: the row offsets of the background's runs; ``pobj``,
    ``pbg``: flattened parents (``pbg`` with the outside node last);
    ``surfaces``: how many surfaces there are, to size the tables (the
    components of the object and of the background form a tree whose edges
    are the surfaces: ``roots(pobj) + roots(pbg) - 1``); ``tables``: those
    of :func:`isoflow.digital.closed_surfaces.sweep_tables`;
    ``pair_capacity``: pinch pairs a slab holds before it is run again.

    Returns ``hist``, ``keys`` (the pairs ``obj << 32 | bg``, sorted),
    ``vertices`` and ``quarters`` per pair, ``doubled`` and the pinch
    ``pairs``.
    """
    parts = slabs(v.shape[0] + 1, thread_count())
    # a slab sees about its share of the surfaces, and those crossing it
    expect = surfaces // len(parts) + surfaces // 8 + 256
    capacity = 1 << int(2 * expect).bit_length()
    check_fits(len(parts) * capacity * 3 * 8, f"counting {surfaces:,} closed surfaces on {len(parts)} threads",
               hint="use fewer threads (--threads)")
    found = run([(_slab, v, runs, goff, pobj, pbg, a, b, tables, capacity, pair_capacity) for a, b in parts])
    keys = np.concatenate([f[1] for f in found])
    uniq, inverse = np.unique(keys, return_inverse=True)

    def total(col):
        out = np.zeros(len(uniq), np.int64)
        np.add.at(out, inverse, np.concatenate([f[col] for f in found]))
        return out

    return {
        "hist": np.sum([f[0][0] for f in found], axis=0),
        "keys": uniq,
        "vertices": total(2),
        "quarters": total(3),
        "doubled": int(sum(f[0][1] for f in found)),
        "pairs": np.concatenate([f[4] for f in found]),
    }


# --------------------------------------------------------------------------
# The same counts on a block of labelled voxels (out of core)
# --------------------------------------------------------------------------


@njit(cache=True, nogil=True, inline="always")
def _box_label(vox, fg, bg, x, y, z, outside):
    """Label of voxel (x, y, z): its object or background label, ``outside``
    beyond the block."""
    nx, ny, nz = vox.shape
    if 0 <= x < nx and 0 <= y < ny and 0 <= z < nz:
        return np.int64(fg[x, y, z]) if vox[x, y, z] else np.int64(bg[x, y, z])
    return np.int64(outside)


@njit(cache=True, nogil=True)
def _box_rows(vox, fg, bg, lo, hi, outside, keys, vs, qs, pairs, nsheet, sheet_obj, sheet_bg, sheet_quarters, pinch):
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
    zero = np.zeros(nz, np.uint8)
    last = np.zeros(4, np.int64)  # the keys of the previous vertex's sheets
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
                                     nsheet, sheet_obj, sheet_bg, quarters, pinch)
        return npairs, overflow, None

    _, keys, vertices, quarter, pairs = _until_it_fits(call, 1 << 12, 1 << 10)
    return {"obj": keys >> 32, "bg": keys & 0xFFFFFFFF, "vertices": vertices, "quarters": quarter, "pairs": pairs}
