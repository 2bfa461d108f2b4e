"""The vertex sweep (numba): one pass over the lattice vertices of a volume
held as bit rows (:mod:`isoflow.scale.bitrows`) that gives the
configuration histogram, labels the object's and the background's
components, and adds up what the closed boundary surfaces need, without
building the boundary mesh or a label volume.

The nodes are the runs of the object along the last axis and the gaps
between them, numbered row by row; a voxel's node is its row's numbering
plus the runs (gaps) that start before it in the row, a popcount of the
row's bits, so nothing is stored per voxel. The vertices are swept in
*blocks*: a row of vertices (i, j, 0..nz) and the four voxel rows around
it, read a word (64 voxels) at a time:

* the configuration only changes where one of the four rows does (an
  *event*, found by count-trailing-zeros on the word); between two events
  every vertex has the same "layer" configuration (the same four voxels
  on both sides), whose sheets have four faces each and no curvature. So
  the work is per run end, not per vertex, and the histogram comes with it;
* runs (gaps) of neighbouring rows that touch are joined in a union-find
  under the object's (background's) adjacency, where each contact begins
  (a word operation finds them all), every pair of rows in one block only;
* every sheet of an event's configuration (tables from
  :func:`isoflow.digital.closed_surfaces.sweep_tables`) is one mesh vertex
  with ``q`` quarters of faces around it: it adds ``4 - q`` (four times its
  share of ``chi = V - F``) and ``q`` to the node of its object voxel and to
  that of its background voxel, in the two halves of an int64. Summed over
  a component, they are ``4 chi`` and ``4 F`` of its whole boundary, from
  which :func:`isoflow.digital.closed_surfaces.surface_tree` gets every
  surface's;
* vertex contacts that the connectivity joins but the mesh splits
  (pinches) give a pair of nodes to join for the Betti numbers, and a
  lattice edge doubled at both ends (the mesh's doubled edges) is counted
  at its lower end; both are rare and take a slower path.

Slabs of layers run at once on the threads: a slab touches only the nodes
of its own voxel rows, and the layer on each seam between slabs runs
afterwards. Array indices in the loops are cast to unsigned integers
(``np.uint64``): numba then leaves out its test for a negative index
(counted from the end) on every access, which cost 10-15% of the sweep.
Work per event is a few word operations and two additions, so that a
512^3 porous field (36 million events) takes about 0.5 s on one thread.

A block of a larger volume (:mod:`isoflow.digital.blocks`) is swept with a
box of *counted* vertices: the histogram, the sheets, the pinches and the
doubled edges count there only (the runs' pieces, cells of the block, count
whole), and a doubled spoke of a counted vertex toward a lattice vertex
that is not counted is a *loose end*, handed on to whoever counts that
vertex. Only the block's faces that are the volume's own border join their
gaps to the outside.

The arrays and flags travel as five named tuples: the volume's bit rows
(:data:`BitRows`), the per-configuration :data:`Tables`, the union-find and
sums (:data:`Nodes`), what every slab does alike (:data:`Rules`) and one
slab's part (:data:`Slab`). The helpers that run on every word or row (the
joins of a block's rows, the surface pieces, the events of a word) are
inlined by numba (``inline="always"``); the others are ordinary calls,
which LLVM inlines where it pays. Inlining the twelve copies of
:func:`_join_mask` at numba's level made the sweep's first compile (once
per install) several times longer, for no measured gain.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from .bitrows import config_at, popcount, trailing_zeros
from .compiled import run, slabs, thread_count
from .jit import njit
from .kernels import union
from .memory import check_fits

#: what the sweep does: everything, all but the surfaces' sums, or only
#: find the pinches and the loose ends again (when a slab had more than its
#: buffers hold)
ALL, NO_SURFACES, AGAIN = 0, 1, 2

#: things written by one thread each (spare nodes, histograms) lie this
#: many int64 apart, so that threads never write to the same cache line
_SPREAD = 16


@njit(cache=True, nogil=True)
def _join_outside(parent, gap, rep):
    """Join a gap to the region outside the array, which a slab stands for
    by the first gap it joins to it (``rep[0]``), so that slabs running at
    once never write the same node (the outside's own node is joined to
    each slab's afterwards)."""
    if rep[0] < 0:
        rep[0] = gap
    else:
        union(parent, gap, rep[0])


@njit(cache=True, nogil=True)
def _join_mask(parent, mask, sa, base_a, before_a, sb, base_b, before_b):
    """For every set bit p of ``mask``, join the run (gap) of row a holding
    voxel p (p - 1 if ``before_a``) with row b's holding voxel p (p - 1 if
    ``before_b``). A row's node is its numbering before the word (``base``)
    plus the runs (gaps) that start in the word (``sa``, ``sb``) up to the
    voxel."""
    one = np.uint64(1)
    while mask != 0:
        p = trailing_zeros(mask)
        mask &= mask - one
        below = (one << p) - one
        upto = below | (one << p)
        na = base_a + np.int64(popcount(sa & (below if before_a else upto)))
        nb = base_b + np.int64(popcount(sb & (below if before_b else upto)))
        union(parent, na, nb)


@njit(cache=True, nogil=True, inline="always")
def _join_face_rows(parent, slack, x3, p3, s3, b3, xn, pn, sn, bn):
    """Join the runs of row 3 and of a face-neighbouring row n (2 or 1 of a
    block) that touch in one word: where they overlap, and with ``slack``
    (18 and 26) where voxel k of one meets voxel k - 1 of the other across
    the edge, while the other voxels of that edge's square are clear (see
    :func:`_join_rows` for the arguments)."""
    m = x3 & xn & ~(p3 & pn)  # where an overlap begins
    if m:
        _join_mask(parent, m, s3, b3, False, sn, bn, False)
    if slack > 0:
        m = s3 & pn & ~xn
        if m:
            _join_mask(parent, m, s3, b3, False, sn, bn, True)
        m = sn & p3 & ~x3
        if m:
            _join_mask(parent, m, s3, b3, True, sn, bn, False)


@njit(cache=True, nogil=True, inline="always")
def _join_diagonal_rows(parent, diag, xa, pa, sa, ba, xb, pb, sb, bb, xc, pc, xd, pd):
    """Join the runs of two diagonal rows a and b of a block (3 and 0, or 1
    and 2; c and d are the other two) that touch in one word: along the
    edge between them where c and d are clear there (``diag`` >= 0: 18 and
    26), and with ``diag`` > 0 (26) at a vertex, voxel k of one and k - 1
    of the other, where the rest of that cube is clear (see
    :func:`_join_rows`)."""
    m = xa & xb & ~xc & ~xd & ~(pa & pb & ~pc & ~pd)
    if m:
        _join_mask(parent, m, sa, ba, False, sb, bb, False)
    if diag > 0:  # vertex contacts: two opposite voxels of a cube alone
        m = xa & pb & ~pa & ~xb & ~(xc | pc | xd | pd)
        if m:
            _join_mask(parent, m, sa, ba, False, sb, bb, True)
        m = pa & xb & ~xa & ~pb & ~(xc | pc | xd | pd)
        if m:
            _join_mask(parent, m, sa, ba, True, sb, bb, False)


@njit(cache=True, nogil=True, inline="always")
def _join_rows(parent, slack, diag, x0, x1, x2, x3, p0, p1, p2, p3, s0, s1, s2, s3, b0, b1, b2, b3):
    """Join the runs (or gaps, given the rows' gap bits) that touch in one
    word of a block's four rows, under an adjacency (``slack``, ``diag``:
    see :data:`isoflow.scale.kernels.ADJACENCY`). Row q = dx + 2 dy is voxel
    row (i - 1 + dx, j - 1 + dy) of vertex row (i, j); a block joins the
    face pairs (3, 2), (3, 1) and the diagonal pairs (3, 0), (1, 2), so that
    every pair of neighbouring rows is joined in one block. ``x``: the rows'
    bits, ``p``: those of the voxels before (bit k: voxel k - 1), ``s``:
    where their runs start, ``b``: their runs numbered before the word,
    less one.

    Each contact is joined once, where it begins; contacts that the block's
    other rows join anyway are left out: a diagonal contact where one of
    the two other rows is set, a contact across the rows (voxel k of one,
    k - 1 of the other) where either is set at its other voxel, a vertex
    contact where any other voxel of its cube is set."""
    _join_face_rows(parent, slack, x3, p3, s3, b3, x2, p2, s2, b2)
    _join_face_rows(parent, slack, x3, p3, s3, b3, x1, p1, s1, b1)
    if diag >= 0:
        _join_diagonal_rows(parent, diag, x3, p3, s3, b3, x0, p0, s0, b0, x1, p1, x2, p2)
        _join_diagonal_rows(parent, diag, x1, p1, s1, b1, x2, p2, s2, b2, x0, p0, x3, p3)


#: the volume as bit rows (:func:`isoflow.scale.bitrows.pack`) and its shape
BitRows = namedtuple("BitRows", "bits off goff nx ny nz")
#: per configuration: the sheets that the events count (``nsheet``, each
#: one's ``octant`` on the side that counts sheets and the ``values`` it
#: adds), the doubled ``spokes``, the ``pinch`` octants, and ``info``, a
#: common event's one sheet in one number (see :func:`sweep`)
Tables = namedtuple("Tables", "nsheet octant values spokes pinch info")
#: the union-find of the runs and of the gaps (``pobj``, ``pbg``: parents)
#: and what is added up per node (``acc_obj``, ``acc_bg``)
Nodes = namedtuple("Nodes", "pobj pbg acc_obj acc_bg")
#: what every slab does alike: the object's and the background's
#: ``adjacency`` (slacks, see :data:`isoflow.scale.kernels.ADJACENCY`);
#: ``counted``, the box of vertices that count ((2, 3): the first and one
#: past the last along each axis); ``border``, which of the six faces (low
#: x, high x, low y, high y, low z, high z) are the volume's own, whose gaps
#: join the outside; the ``mode``; whether the pinches join object voxels;
#: whether the object's Euler characteristic comes from the formula over runs
Rules = namedtuple("Rules", "adjacency counted border mode pinch_objects formula_obj")
#: one slab: its vertex layers ``lo <= i < hi``, the voxel ``rows`` whose
#: nodes it sets up (start, end), its first ``spare`` node, and what it
#: writes alone: the outside's representative ``rep``, the ``hist``ogram
#: (``trash`` that of the vertices not counted), the pinch ``pairs``, the
#: ``loose`` ends of doubled edges, and ``scratch`` and ``uscratch`` for the
#: four rows of a block at an event
Slab = namedtuple("Slab", "lo hi rows spare rep hist trash pairs loose scratch uscratch")


@njit(cache=True, nogil=True)
def _node(o, c, k, b, nz, slab, outside):
    """The node of octant ``o`` of configuration ``c`` at the event k (bit
    b of the word): the run or gap of its voxel, the outside for voxels -1
    and nz."""
    q, side = o & 3, o >> 2
    mask = ((np.uint64(1) << b) - np.uint64(1)) | (np.uint64(side) << b)
    if (c >> o) & 1:
        return slab.scratch[0, q] + np.int64(popcount(slab.uscratch[0, q] & mask))
    if k + side - 1 < 0 or k + side - 1 >= nz:
        return outside
    return slab.scratch[1, q] + np.int64(popcount(slab.uscratch[1, q] & mask))


@njit(cache=True, nogil=True)
def _doubled_spokes(rows, tables, rules, slab, i, j, k, c, nloose):
    """The doubled lattice edges at the counted vertex (i, j, k) of
    configuration ``c``. An edge whose other end counts too is counted at
    one end: here toward +x, +y and -z (spoke bits 1, 3 and 4, bit ``2 axis
    + side``); toward -x, -y and +z at the other end. An edge whose other
    end is in the lattice but not counted is a *loose end*, written to
    ``slab.loose`` as (i, j, k, bit) for whoever counts that end. Returns
    the doubled edges and the loose ends so far (also those past the
    buffer)."""
    spokes = tables.spokes
    lo, hi = rules.counted[0], rules.counted[1]
    size = (rows.nx, rows.ny, rows.nz)
    doubled = 0
    for d in range(6):
        if not (spokes[c] >> d) & 1:
            continue
        axis, step = d >> 1, 2 * (d & 1) - 1
        x, y, z = i + step * (axis == 0), j + step * (axis == 1), k + step * (axis == 2)
        at = (x, y, z)[axis]
        if at < 0 or at > size[axis]:
            continue  # past the lattice: no edge
        if lo[axis] <= at < hi[axis]:
            if d == 1 or d == 3 or d == 4:
                doubled += (spokes[config_at(rows.bits, rows.nx, rows.ny, rows.nz, x, y, z)] >> (d ^ 1)) & 1
            continue
        if nloose < len(slab.loose):
            slab.loose[nloose, 0], slab.loose[nloose, 1], slab.loose[nloose, 2], slab.loose[nloose, 3] = i, j, k, d
        nloose += 1
    return doubled, nloose


@njit(cache=True, nogil=True)
def _rare_event(rows, nodes, tables, rules, slab, i, j, k, b, c, outside, nloose):
    """A counted event with several sheets, a pinch or a doubled spoke, or
    at an end of the row: its sheets as in the common case (on the side
    that counts sheets); a pinch adds one to the Euler characteristic of
    the formula side's component around it (see :func:`_pieces`). Returns
    the doubled edges counted here and the loose ends so far (see
    :func:`_doubled_spokes`)."""
    for s in range(tables.nsheet[c]):
        node = _node(tables.octant[c, s], c, k, b, rows.nz, slab, outside)
        if rules.formula_obj:
            nodes.acc_bg[node] += tables.values[c, s]
        else:
            nodes.acc_obj[node] += tables.values[c, s]
    if tables.pinch[c, 0] >= 0:
        # the six other octants are one component of the formula side
        o = 0
        while ((c >> o) & 1) != rules.formula_obj:
            o += 1
        node = _node(o, c, k, b, rows.nz, slab, outside)
        if rules.formula_obj:
            nodes.acc_obj[node] += 8
        else:
            nodes.acc_bg[node] += 8
    if tables.spokes[c] == 0:
        return 0, nloose
    return _doubled_spokes(rows, tables, rules, slab, i, j, k, c, nloose)


@njit(cache=True, nogil=True, inline="always")
def _pieces(acc, x0, x1, x2, x3, p0, p1, p2, p3, starts, base, formula):
    """The faces, and on the formula side the Euler characteristic, of the
    runs (or gaps, given gap bits) of a block's row 3 in one word, added to
    their nodes. ``x``: the rows' bits, ``p``: those of the voxels before,
    ``starts``: where row 3's runs start, ``base``: its runs numbered before
    the word, less one.

    A piece is a run's part in the word. Faces: a component's voxels have
    six each, less two for each pair of face neighbours inside it, so a run
    of length L adds 4 L + 2, less two per voxel it shares with a run of a
    face-neighbouring row; row 3 takes the pairs it makes with rows 2 and 1
    (each pair of rows is row 3's in one block). Euler characteristic under
    6-adjacency (the formula side): the runs, less the overlaps of runs of
    face-neighbouring rows, plus the stretches where the four rows around a
    line all are set (V - E + F - C of the voxels, their face pairs, the
    squares and cubes of four and eight: each overlap of length m is m edges
    and m - 1 squares, each four-row stretch m squares and m - 1 cubes);
    the mesh's solid adds one per pinch (:func:`_rare_event`). Both are
    sums over the boundary's surfaces once doubled (chi of a solid's
    boundary is twice its own), so the low half gets 8 chi to match the
    sheets' 4 chi of the other side.
    """
    one = np.uint64(1)
    left = starts | (x3 & p3 & one)  # and the run going on from the word before
    # where the overlaps with rows 2 and 1 and the four-row stretches begin
    over2 = x3 & x2 & ~(p3 & p2)
    over1 = x3 & x1 & ~(p3 & p1)
    four = x0 & x1 & x2 & x3 & ~(p0 & p1 & p2 & p3)
    while left != 0:
        p = trailing_zeros(left)
        left &= left - one
        rest = ~(x3 >> p)  # the piece ends at its first clear bit
        length = np.int64(trailing_zeros(rest)) if rest != 0 else 64
        piece = ((one << np.uint64(length)) - one if length < 64 else ~np.uint64(0)) << p
        start = np.int64((starts >> p) & one)
        faces = 4 * length + 2 * start - 2 * np.int64(popcount(piece & x2) + popcount(piece & x1))
        value = faces << 32
        if formula:
            value += 8 * (start - np.int64(popcount(piece & over2) + popcount(piece & over1))
                          + np.int64(popcount(piece & four)))
        acc[np.uint64(base + np.int64(popcount(starts & ((one << p << one) - one))))] += value


@njit(cache=True, nogil=True)
def _pinch(c, k, b, nz, slab, tables, rules, outside, gaps, npairs):
    """Record the pinch at an event: the nodes of its two octants (the
    outside as the last gap node) where they differ. Returns the count."""
    na = _node(tables.pinch[c, 0], c, k, b, nz, slab, outside)
    nb = _node(tables.pinch[c, 1], c, k, b, nz, slab, outside)
    if not rules.pinch_objects:
        na, nb = min(na, gaps), min(nb, gaps)
    if na != nb:
        if npairs < len(slab.pairs):
            slab.pairs[npairs, 0], slab.pairs[npairs, 1] = na, nb
        npairs += 1
    return npairs


@njit(cache=True, nogil=True)
def _set_up(parent, acc, a, b):
    """Nodes a <= x < b, each a set of its own with nothing added yet."""
    for x in range(a, b):
        parent[np.uint64(x)] = x
        acc[np.uint64(x)] = 0


@njit(cache=True, nogil=True, inline="always")
def _set_up_row(rows, nodes, rules, slab, i, j):
    """Voxel row (i, j), read as row 3 by the first block that reads it: its
    nodes set up (where the slab owns them, and in cache for the three
    other blocks that read it), and its gaps that touch a face of the
    volume's own border joined to the outside: all of them on such a face
    along x or y, else those at the row's ends."""
    off, goff, nz, border = rows.off, rows.goff, rows.nz, rules.border
    r = i * rows.ny + j
    if slab.rows[0] <= r < slab.rows[1]:
        _set_up(nodes.pobj, nodes.acc_obj, off[r], off[r + 1])
        _set_up(nodes.pbg, nodes.acc_bg, goff[r], goff[r + 1])
    if goff[r + 1] == goff[r]:
        return
    if (i == 0 and border[0]) or (i == rows.nx - 1 and border[1]) or (j == 0 and border[2]) \
            or (j == rows.ny - 1 and border[3]):
        for g in range(goff[r], goff[r + 1]):
            _join_outside(nodes.pbg, g, slab.rep)
        return
    one = np.uint64(1)
    if border[4] and (rows.bits[r, 0] & one) == 0:
        _join_outside(nodes.pbg, goff[r], slab.rep)
    if border[5] and (rows.bits[r, (nz - 1) >> 6] >> np.uint64((nz - 1) & 63)) & one == 0:
        _join_outside(nodes.pbg, goff[r + 1] - 1, slab.rep)


@njit(cache=True, nogil=True, inline="always")
def _four_rows(rows, i, j, outside):
    """The voxel rows q = dx + 2 dy of vertex row (i, j), voxel row (i - 1 +
    dx, j - 1 + dy): their index (the clear row where outside the array),
    their runs and gaps numbered before them, less one (none, and the
    outside, where outside the array), and all ones where inside the
    array."""
    off, goff, ny = rows.off, rows.goff, rows.ny
    zero = np.uint64(0)
    r0 = r1 = r2 = r3 = len(rows.bits) - 1
    b0 = b1 = b2 = b3 = -1
    g0 = g1 = g2 = g3 = outside
    in0 = in1 = in2 = in3 = zero
    if i >= 1 and j >= 1:
        r0 = (i - 1) * ny + j - 1
        b0, g0, in0 = off[r0] - 1, goff[r0] - 1, ~zero
    if i < rows.nx and j >= 1:
        r1 = i * ny + j - 1
        b1, g1, in1 = off[r1] - 1, goff[r1] - 1, ~zero
    if i >= 1 and j < ny:
        r2 = (i - 1) * ny + j
        b2, g2, in2 = off[r2] - 1, goff[r2] - 1, ~zero
    if i < rows.nx and j < ny:
        r3 = i * ny + j
        b3, g3, in3 = off[r3] - 1, goff[r3] - 1, ~zero
    return (r0, r1, r2, r3), (b0, b1, b2, b3), (g0, g1, g2, g3), (in0, in1, in2, in3)


@njit(cache=True, nogil=True, inline="always")
def _clear_ends_not_counted(rules, bits, r0, r1, r2, r3, nz):
    """How many of a vertex row's ends (k = 0 and k = nz) are not counted
    and see four clear voxels: configuration 0, which the sweep counts with
    the layers between events, not as an event."""
    one = np.uint64(1)
    n = 0
    if rules.counted[0, 2] > 0 and ((bits[r0, 0] | bits[r1, 0] | bits[r2, 0] | bits[r3, 0]) & one) == 0:
        n += 1
    w, b = (nz - 1) >> 6, np.uint64((nz - 1) & 63)
    if rules.counted[1, 2] <= nz and ((bits[r0, w] | bits[r1, w] | bits[r2, w] | bits[r3, w]) >> b) & one == 0:
        n += 1
    return n


@njit(cache=True, nogil=True, inline="always")
def _word_events(rows, nodes, tables, rules, slab, h, i, j, w, t, x, counted, outside, state):
    """The events of one word of a vertex row (``t``: the voxels where one
    of the four rows changes; ``x``: the rows' bits), in order: the
    histogram, the sheets of the counted ones (the common ones here, the
    others in :func:`_rare_event`), their pinches. ``state``: the four
    rows' voxels before the first event, the event before it, the pinch
    pairs and loose ends so far. Returns the state after the word and the
    doubled edges counted."""
    x0, x1, x2, x3 = x
    old, last, npairs, nloose = state
    one = np.uint64(1)
    nz, mode, pinch = rows.nz, rules.mode, tables.pinch
    lo, hi = rules.counted[0, 2], rules.counted[1, 2]
    gaps = len(nodes.pbg) - 1
    base, gbase, runs, gruns = slab.scratch[0], slab.scratch[1], slab.uscratch[0], slab.uscratch[1]
    doubled = 0
    while t != 0:
        b = trailing_zeros(t)
        t &= t - one
        k = w * 64 + np.int64(b)
        new = np.int64(((x0 >> b) & one) | (((x1 >> b) & one) << one) | (((x2 >> b) & one) << 2)
                       | (((x3 >> b) & one) << 3))
        c = old | (new << 4)
        if mode == AGAIN:
            here = counted and lo <= k < hi
            if here and pinch[c, 0] >= 0:
                npairs = _pinch(c, k, b, nz, slab, tables, rules, outside, gaps, npairs)
            if here and tables.spokes[c] != 0:
                nloose = _doubled_spokes(rows, tables, rules, slab, i, j, k, c, nloose)[1]
            old = new
            continue
        # the layer since the last event: its voxels are those before k
        # (flat: no curvature; its faces are counted with the runs, see
        # _pieces)
        h[np.uint64(old * 17)] += k - last - 1  # (old | old << 4)
        common = tables.info[np.uint64(c)]
        if common < 0 or k == 0 or k == nz:
            if counted and lo <= k < hi:
                h[np.uint64(c)] += 1
                if mode == ALL:
                    d, nloose = _rare_event(rows, nodes, tables, rules, slab, i, j, k, b, c, outside, nloose)
                    doubled += d
                if pinch[c, 0] >= 0:
                    npairs = _pinch(c, k, b, nz, slab, tables, rules, outside, gaps, npairs)
        else:
            h[np.uint64(c)] += 1
            if mode == ALL and counted:
                # the event's one sheet, on the side that counts sheets: one
                # mesh vertex less a quarter of each face, its share of
                # chi = V - F, times 4
                q, m = np.uint64(common & 3), ((one << b) - one) | (np.uint64((common >> 2) & 1) << b)
                value = (common >> 8) - 128
                if rules.formula_obj:
                    nodes.acc_bg[np.uint64(gbase[q] + np.int64(popcount(gruns[q] & m)))] += value
                else:
                    nodes.acc_obj[np.uint64(base[q] + np.int64(popcount(runs[q] & m)))] += value
        old = new
        last = k
    return (old, last, npairs, nloose), doubled


@njit(cache=True, nogil=True, inline="always")
def _join_and_add(nodes, rules, x, p, s, t, b, g, ins, valid, first):
    """One word of a block's four rows (their bits ``x``, those of the
    voxels before ``p``, where their runs and gaps start ``s``, ``t``, their
    runs and gaps numbered before the word ``b``, ``g``, all ones where
    inside the array ``ins``; ``valid``: the voxels inside the array,
    ``first``: bit 0 in the first word): the joins of the runs and of the
    gaps that touch, and the pieces of row 3 added to their nodes."""
    x0, x1, x2, x3 = x
    p0, p1, p2, p3 = p
    in0, in1, in2, in3 = ins
    a = rules.adjacency
    if rules.mode != AGAIN:
        _join_rows(nodes.pobj, a[0], a[1], x0, x1, x2, x3, p0, p1, p2, p3, s[0], s[1], s[2], s[3], b[0], b[1], b[2],
                   b[3])
        _join_rows(nodes.pbg, a[2], a[3], ~x0 & valid & in0, ~x1 & valid & in1, ~x2 & valid & in2,
                   ~x3 & valid & in3, ~p0 & ~first & in0, ~p1 & ~first & in1, ~p2 & ~first & in2,
                   ~p3 & ~first & in3, t[0], t[1], t[2], t[3], g[0], g[1], g[2], g[3])
    if rules.mode == ALL and in3:
        _pieces(nodes.acc_obj, x0, x1, x2, x3, p0, p1, p2, p3, s[3], b[3], rules.formula_obj)
        _pieces(nodes.acc_bg, ~x0 & valid & in0, ~x1 & valid & in1, ~x2 & valid & in2, ~x3 & valid,
                ~p0 & ~first & in0, ~p1 & ~first & in1, ~p2 & ~first & in2, ~p3 & ~first, t[3], g[3],
                not rules.formula_obj)


@njit(cache=True, nogil=True, inline="always")
def _note_rows(slab, b, s, g, t):
    """Keep a word's numbering of the four rows' runs and gaps for its
    events (see :func:`_node`)."""
    for q in range(4):
        slab.scratch[0, q], slab.uscratch[0, q], slab.scratch[1, q], slab.uscratch[1, q] = b[q], s[q], g[q], t[q]


@njit(cache=True, nogil=True, inline="always")
def _sweep_row(rows, nodes, tables, rules, slab, i, j, counted, outside, npairs, nloose):
    """The vertices (i, j, 0 .. nz), a word of the four voxel rows around
    them at a time: the joins of the rows' runs and gaps, their pieces'
    sums, the events (:func:`_word_events`). Returns the doubled edges
    counted, the pinch pairs and loose ends so far."""
    bits, off, nz, mode = rows.bits, rows.off, rows.nz, rules.mode
    (r0, r1, r2, r3), (b0, b1, b2, b3), (g0, g1, g2, g3), (in0, in1, in2, in3) = _four_rows(rows, i, j, outside)
    h = slab.hist if counted else slab.trash
    if off[r0 + 1] == off[r0] and off[r1 + 1] == off[r1] and off[r2 + 1] == off[r2] and off[r3 + 1] == off[r3] \
            and (rules.border[4] or rules.border[5]):
        # four rows without a voxel of the object: nothing to count, and each
        # row's one gap touches the border at an end, so is the outside's
        if mode != AGAIN:
            h[0] += nz + 1 - _clear_ends_not_counted(rules, bits, r0, r1, r2, r3, nz)
        return 0, npairs, nloose
    zero, one, top = np.uint64(0), np.uint64(1), np.uint64(63)
    doubled = 0
    # the four rows' voxels before the last event, the last event
    state = (np.int64(0), np.int64(-1), npairs, nloose)
    x0 = x1 = x2 = x3 = zero  # the rows' bits in the word
    s0 = s1 = s2 = s3 = zero  # where their runs start
    t0 = t1 = t2 = t3 = zero  # where their gaps start
    for w in range(bits.shape[1]):
        b0 += np.int64(popcount(s0))
        b1 += np.int64(popcount(s1))
        b2 += np.int64(popcount(s2))
        b3 += np.int64(popcount(s3))
        g0 += np.int64(popcount(t0))
        g1 += np.int64(popcount(t1))
        g2 += np.int64(popcount(t2))
        g3 += np.int64(popcount(t3))
        # bit k of p: voxel k - 1
        uw = np.uint64(w)
        y0, y1, y2, y3 = bits[np.uint64(r0), uw], bits[np.uint64(r1), uw], bits[np.uint64(r2), uw], \
            bits[np.uint64(r3), uw]
        p0 = (y0 << one) | (x0 >> top)
        p1 = (y1 << one) | (x1 >> top)
        p2 = (y2 << one) | (x2 >> top)
        p3 = (y3 << one) | (x3 >> top)
        x0, x1, x2, x3 = y0, y1, y2, y3
        s0, s1, s2, s3 = x0 & ~p0, x1 & ~p1, x2 & ~p2, x3 & ~p3
        # gaps: voxels inside the array; before voxel 0 counts as a run's
        # end for numbering them, as no gap for joining them
        valid = ~zero if (w + 1) * 64 <= nz else (one << np.uint64(nz & 63)) - one
        first = one if w == 0 else zero
        t0 = ~x0 & (p0 | first) & valid & in0
        t1 = ~x1 & (p1 | first) & valid & in1
        t2 = ~x2 & (p2 | first) & valid & in2
        t3 = ~x3 & (p3 | first) & valid & in3
        _join_and_add(nodes, rules, (x0, x1, x2, x3), (p0, p1, p2, p3), (s0, s1, s2, s3), (t0, t1, t2, t3),
                      (b0, b1, b2, b3), (g0, g1, g2, g3), (in0, in1, in2, in3), valid, first)
        t = (x0 ^ p0) | (x1 ^ p1) | (x2 ^ p2) | (x3 ^ p3)
        if t == 0:
            continue
        _note_rows(slab, (b0, b1, b2, b3), (s0, s1, s2, s3), (g0, g1, g2, g3), (t0, t1, t2, t3))
        state, d = _word_events(rows, nodes, tables, rules, slab, h, i, j, w, t, (x0, x1, x2, x3), counted, outside,
                                state)
        doubled += d
    if mode != AGAIN:
        # past the last event the four rows are clear
        h[0] += nz - state[1] - _clear_ends_not_counted(rules, bits, r0, r1, r2, r3, nz)
    return doubled, state[2], state[3]


@njit(cache=True, nogil=True, _nrt=False)
def _sweep_layers(rows, nodes, tables, rules, slab):
    """Sweep the vertex layers ``slab.lo <= i < slab.hi`` (see the module
    docs and :func:`sweep`), setting up the nodes of the voxel rows
    ``slab.rows`` (start, end: the slab's own, touched only by the thread
    that uses them) as it goes; ``slab.spare``: the slab's spare nodes,
    past the nodes of ``acc_obj`` and ``acc_bg``. Returns the doubled edges
    counted, the number of pinch pairs and of loose ends (also those past
    their buffers)."""
    ny, again = rows.ny, rules.mode == AGAIN
    first, lo = slab.rows[0], slab.lo * ny
    if not again and slab.rows[1] > first and lo > first:
        # the slab's first voxel layer, which its blocks never take as row 3
        _set_up(nodes.pobj, nodes.acc_obj, rows.off[first], rows.off[lo])
        _set_up(nodes.pbg, nodes.acc_bg, rows.goff[first], rows.goff[lo])
    # the slab's node for the region outside the array, past the gaps': it
    # only adds up (the outside's component has no parent surface)
    outside = len(nodes.pbg) + slab.spare
    counted = rules.counted
    doubled = 0
    npairs = nloose = np.int64(0)  # not the literal 0: numba would compile the rare events' helpers once more
    for i in range(slab.lo, slab.hi):
        for j in range(ny + 1):
            if not again and i < rows.nx and j < ny:
                _set_up_row(rows, nodes, rules, slab, i, j)
            inside = counted[0, 0] <= i < counted[1, 0] and counted[0, 1] <= j < counted[1, 1]
            d, npairs, nloose = _sweep_row(rows, nodes, tables, rules, slab, i, j, inside, outside, npairs, nloose)
            doubled += d
    return doubled, npairs, nloose


def loaded() -> bool:
    """Whether numba holds the sweep's machine code in this process already:
    a sweep ran here, so numba compiled it or loaded it from its cache
    (what :func:`isoflow.digital.closed_surfaces.use_census` asks; a
    question to numba's dispatcher, not a clock).

    Examples
    --------
    >>> loaded() in (True, False)
    True
    """
    return bool(_sweep_layers.signatures)


@njit(cache=True, nogil=True)
def _join_reps(pbg, reps, outside):
    for r in reps:
        if r >= 0:
            union(pbg, r, outside)


@njit(cache=True, nogil=True)
def _mark_roots(parent, lo, hi):
    """First phase of numbering the sets of a finished union-find (see
    :func:`_components`), for the nodes lo <= x < hi: point every node at
    its root, and mark the roots, numbered in this range from 0 on, as
    ``-1 - n``. Returns the number of roots.

    Unions hang the larger root under the smaller, so ``parent[x] <= x``
    and a node's root is marked before the node is reached. Chains into
    earlier ranges are read while their threads change them: a node there
    still points at an ancestor, and its root reads as itself or as marked
    (negative)."""
    n = 0
    for x in range(lo, hi):
        r = parent[np.uint64(x)]
        if r == x:
            parent[np.uint64(x)] = -1 - n
            n += 1
            continue
        if r >= lo:  # a node of this range: done already
            up = parent[np.uint64(r)]
            if up >= 0:
                r = up
        else:
            up = parent[np.uint64(r)]
            while up >= 0 and up != r:
                r = up
                up = parent[np.uint64(r)]
        parent[np.uint64(x)] = r
    return n


@njit(cache=True, nogil=True)
def _halves(value):
    """The two halves of a node's value (see :func:`sweep`): ``value = high
    * 2^32 + low``, the low half signed, ``|low| < 2^31``."""
    low = ((value + (1 << 31)) & 0xFFFFFFFF) - (1 << 31)
    return low, (value - low) >> 32


@njit(cache=True, nogil=True)
def _give_numbers(parent, acc, lo, hi, starts, bases, roots, sums):
    """Second phase (after :func:`_mark_roots` everywhere): give every node
    of lo <= x < hi that is not a root its set's number (the sets of the
    range starting at ``starts[t]`` are numbered from ``bases[t]`` on), list
    the roots in ``roots``, and add every node's ``acc`` to its set's
    ``sums``. The roots keep their marks, which other ranges read; entries
    of ``acc`` past the parents' (spare nodes) count as the last node's.

    Neighbouring nodes are mostly of one set (a large one), so the halves
    are added up in two locals while the set stays the same, and into
    ``sums`` when it changes: adding every node to its row of ``sums``
    made each addition wait for the one before (the same memory), and this
    pass took 45% longer."""
    own = np.uint64(np.searchsorted(starts, lo, side="right") - 1)
    n = cur = 0
    low = high = 0  # set cur's halves since they were last added to sums
    for x in range(lo, hi):
        ux = np.uint64(x)
        r = parent[ux]
        if r < 0:  # a root
            n = bases[own] - 1 - r
            roots[np.uint64(n)] = x
        else:
            t = own
            while starts[t] > r:
                t -= np.uint64(1)
            n = bases[t] - 1 - parent[np.uint64(r)]
            parent[ux] = n
        if n != cur:
            sums[np.uint64(cur), 0] += low
            sums[np.uint64(cur), 1] += high
            cur, low, high = n, 0, 0
        a, b = _halves(acc[ux])
        low += a
        high += b
    if lo < hi == len(parent):  # cur: the last node's set
        for y in range(hi, len(acc)):
            a, b = _halves(acc[np.uint64(y)])
            low += a
            high += b
    if lo < hi:
        sums[np.uint64(cur), 0] += low
        sums[np.uint64(cur), 1] += high


@njit(cache=True, nogil=True)
def _row_ends(bits, off, goff, pobj, pbg, nobj, nz, side, out):
    """Components of every row's first voxel (``side`` 0) or last (1): its
    first or last run or gap (background components after the object's
    ``nobj``)."""
    k = (nz - 1) * side
    for r in range(len(out)):
        if (bits[r, k >> 6] >> np.uint64(k & 63)) & np.uint64(1):
            out[r] = pobj[off[r + side] - side]
        else:
            out[r] = nobj + pbg[goff[r + side] - side]


@njit(cache=True, nogil=True)
def _face_rows(bits, off, goff, pobj, pbg, nobj, rows, nz, out):
    """Components of the voxels of the bit ``rows`` (background components
    after the object's ``nobj``)."""
    one = np.uint64(1)
    for q in range(len(rows)):
        r = rows[q]
        run, gap = off[r] - 1, goff[r] - 1
        before = 0
        for k in range(nz):
            bit = np.int64((bits[r, k >> 6] >> np.uint64(k & 63)) & one)
            if bit and not before:
                run += 1
            elif not bit and (before or k == 0):
                gap += 1
            before = bit
            out[q, k] = pobj[run] if bit else nobj + pbg[gap]


def face_components(bits: np.ndarray, off: np.ndarray, goff: np.ndarray, parents, counts, shape, axis: int,
                    side: int) -> np.ndarray:
    """The component of every voxel of a face layer of a volume swept whole.

    Parameters
    ----------
    bits, off, goff : numpy.ndarray
        :func:`isoflow.scale.bitrows.pack` of the volume.
    parents : tuple of numpy.ndarray
        The runs' and the gaps' components, :func:`sweep`'s ``parents``.
    counts : tuple of int
        How many components of the object and of the background there are.
    shape : tuple of int
        The volume's shape ``(nx, ny, nz)``.
    axis, side : int
        The face: its axis and 0 for its first voxel layer, 1 for its last.

    Returns
    -------
    numpy.ndarray
        int64, the layer's shape (the other two axes): the object
        component of each object voxel, ``counts[0]`` plus the background
        component of each background voxel.

    Examples
    --------
    >>> from isoflow.scale import bitrows, kernels
    >>> from isoflow.digital.closed_surfaces import sweep_tables
    >>> v = np.zeros((2, 2, 3), bool); v[0, 0, 1] = v[1, 1, 1] = True
    >>> bits, off, goff = bitrows.pack(v)
    >>> found = sweep(bits, v.shape, off, goff, kernels.ADJACENCY[6] + kernels.ADJACENCY[18],
    ...               sweep_tables(6), pinch_objects=False)
    >>> counts = [len(r) for r in found["roots"]]
    >>> counts, face_components(bits, off, goff, found["parents"], counts, v.shape, 2, 1).tolist()
    ([2, 1], [[2, 2], [2, 2]])
    >>> face_components(bits, off, goff, found["parents"], counts, v.shape, 0, 0).tolist()
    [[2, 0, 2], [2, 2, 2]]
    """
    nx, ny, nz = shape
    if axis == 2:
        out = np.empty(nx * ny, np.int64)
        _row_ends(bits, off, goff, parents[0], parents[1], counts[0], nz, side, out)
        return out.reshape(nx, ny)
    at = ((nx if axis == 0 else ny) - 1) * side
    rows = at * ny + np.arange(ny, dtype=np.int64) if axis == 0 else np.arange(nx, dtype=np.int64) * ny + at
    out = np.empty((len(rows), nz), np.int64)
    _face_rows(bits, off, goff, parents[0], parents[1], counts[0], rows, nz, out)
    return out


def _components(parent, acc, parts):
    """Number the sets of a union-find in place (node ranges ``parts`` on
    the threads): afterwards ``parent[x]`` is the number of x's set, sets
    in order of their smallest node (their root). Returns every set's
    smallest node and (sets, 2) its totals of the two halves of ``acc``.
    Two passes over the nodes: mark the roots, then number the others."""
    parts = [(a, b) for a, b in parts if b > a]
    counts = run([(_mark_roots, parent, a, b) for a, b in parts])
    starts = np.array([a for a, _ in parts], np.int64)
    bases = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    roots = np.empty(int(bases[-1]), np.int64)
    sums = [np.zeros((len(roots), 2), np.int64) for _ in parts] or [np.zeros((0, 2), np.int64)]
    run([(_give_numbers, parent, acc, a, b, starts, bases, roots, s) for (a, b), s in zip(parts, sums)])
    parent[roots] = np.arange(len(roots), dtype=parent.dtype)
    return roots, (sums[0] if len(sums) == 1 else np.sum(sums, axis=0))


def sheet_tables(tables, formula_obj: bool) -> Tables:
    """The per-configuration :data:`Tables` of the sweep and of the seams.

    Parameters
    ----------
    tables : tuple of numpy.ndarray
        Those of :func:`isoflow.digital.closed_surfaces.sweep_tables`.
    formula_obj : bool
        Whether the object's Euler characteristic comes from the formula
        over runs (its components under 6-adjacency); else the background's
        does, and the object's from the sheets.

    Returns
    -------
    Tables
        ``nsheet``; per sheet its ``octant`` on the side that counts sheets
        and what it adds (``values``), ``4 - q`` for ``q`` quarters of faces
        (four times its share of ``chi = V - F``); the doubled ``spokes``;
        the ``pinch`` octants; ``info``, a common event's one sheet in one
        number (its octant, and 128 + what it adds from bit 8), -1 for the
        configurations that take the slower path.

    Examples
    --------
    >>> from isoflow.digital.closed_surfaces import sweep_tables
    >>> t = sheet_tables(sweep_tables(6), True)
    >>> int(t.nsheet[1]), int(t.values[1, 0])  # one voxel: one sheet, three quarter faces at its corner
    (1, 1)
    """
    nsheet, sheet_obj, sheet_bg, quarters, spokes, pinch = tables
    octant = np.where(nsheet[:, None] > np.arange(4), sheet_bg if formula_obj else sheet_obj, 0).astype(np.int64)
    pinch = pinch.astype(np.int64)  # as octant: _node is compiled for one type of octant
    nsheet = nsheet.astype(np.int64)
    values = np.where(np.arange(4) < nsheet[:, None], 4 - quarters.astype(np.int64), 0)
    # the events that take the slower path: several sheets, a pinch, a
    # doubled spoke
    rare = (nsheet > 1) | (pinch[:, 0] >= 0) | (spokes != 0)
    # the common events' one sheet in one number: its octant (3 bits) and
    # 128 + what it adds (from bit 8); -1: the slower path
    info = np.where(rare, -1, octant[:, 0] | ((values[:, 0] + 128) << 8)).astype(np.int64)
    return Tables(nsheet, octant, values, spokes, pinch, info)


def _new_nodes(runs: int, gaps: int, spares: int) -> Nodes:
    """Parents (int32) and sums (int64) of the runs and of the gaps, with
    one more gap node, the last, for the outside, and past the nodes spare
    ones for each slab and for the seams. The slabs set up every node
    (:func:`_sweep_layers`) but the outside's and the spares."""
    pobj, pbg = np.empty(runs, np.int32), np.empty(gaps + 1, np.int32)
    acc_obj, acc_bg = np.empty(runs + spares, np.int64), np.empty(gaps + 1 + spares, np.int64)
    pbg[gaps] = gaps
    acc_obj[runs:] = acc_bg[gaps:] = 0
    return Nodes(pobj, pbg, acc_obj, acc_bg)


def _new_slabs(parts, ny: int, capacity: int) -> list[Slab]:
    """The slabs of vertex layers (``parts``: voxel layers per thread), and
    after them the seams, one vertex layer each between two slabs, which
    run once the slabs are done."""
    layers = [(a + (s > 0), b + (s == len(parts) - 1)) for s, (a, b) in enumerate(parts)]
    layers += [(a, a + 1) for a, _ in parts[1:]]
    # (the voxel rows whose nodes each slab sets up: none for the seams)
    rows = [np.array([a * ny, b * ny]) for a, b in parts] + [np.zeros(2, np.int64) for _ in parts[1:]]
    reps = np.full(_SPREAD * len(layers), -1, np.int64)[::_SPREAD]
    hists = np.zeros((2 * len(layers), 256 + _SPREAD), np.int64)[:, :256]
    return [Slab(lo, hi, rows[t], _SPREAD * min(t, len(parts)), reps[t:t + 1], hists[2 * t], hists[2 * t + 1],
                 np.empty((capacity, 2), np.int64), np.empty((capacity, 4), np.int64), np.zeros((2, 4), np.int64),
                 np.zeros((2, 4), np.uint64)) for t, (lo, hi) in enumerate(layers)]


def _whole_lattice(shape) -> np.ndarray:
    """The counted box of every vertex of a volume (see :func:`sweep`)."""
    return np.array([[0, 0, 0], [n + 1 for n in shape]], np.int64)


def _rules(adjacency, shape, counted, border, surfaces: bool, pinch_objects: bool) -> Rules:
    """The :data:`Rules` of a sweep (see :func:`sweep`)."""
    counted = _whole_lattice(shape) if counted is None else np.asarray(counted, np.int64)
    assert counted[0, 2] in (0, 1) and counted[1, 2] in (shape[2], shape[2] + 1), "along z all but the ends count"
    border = np.asarray([True] * 6 if border is None else border, np.bool_)
    # the object's components under 6-adjacency (else the background's) get
    # their Euler characteristic from a formula over runs
    formula_obj = tuple(adjacency[:2]) == (0, -1)
    return Rules(np.asarray(adjacency, np.int64), counted, border, ALL if surfaces else NO_SURFACES, pinch_objects,
                 formula_obj)


def _sweep_slabs(rows: BitRows, nodes: Nodes, tables: Tables, rules: Rules, layers: list, threads: int) -> list:
    """The first ``threads`` slabs at once, then the seams; the slabs'
    outside representatives joined to the outside. A slab with more pinch
    pairs or loose ends than its buffers hold is swept again for them alone,
    with room for all. Returns each slab's doubled edges, pinch pairs and
    loose ends."""
    found = run([(_sweep_layers, rows, nodes, tables, rules, s) for s in layers[:threads]])
    found += [_sweep_layers(rows, nodes, tables, rules, s) for s in layers[threads:]]
    _join_reps(nodes.pbg, np.array([s.rep[0] for s in layers]), len(nodes.pbg) - 1)
    for t, (_, npairs, nloose) in enumerate(found):
        if max(npairs, nloose) > len(layers[t].pairs):
            size = max(npairs, nloose)
            layers[t] = layers[t]._replace(pairs=np.empty((size, 2), np.int64), loose=np.empty((size, 4), np.int64))
            _sweep_layers(rows, nodes, tables, rules._replace(mode=AGAIN), layers[t])
    return found


def sweep(bits, shape, off, goff, adjacency, tables, pinch_objects: bool, surfaces: bool = True, *,
          counted: np.ndarray | None = None, border=None, pair_capacity: int | None = None) -> dict:
    """One pass over the lattice vertices, slabs of layers on the threads.

    Parameters
    ----------
    bits, off, goff : numpy.ndarray
        :func:`isoflow.scale.bitrows.pack` of the volume.
    shape : tuple of int
        The volume's shape ``(nx, ny, nz)``.
    adjacency : tuple of int
        The object's and the background's slacks (between neighbouring rows,
        between diagonal rows or -1 each, see
        :data:`isoflow.scale.kernels.ADJACENCY`).
    tables : tuple of numpy.ndarray
        Those of :func:`isoflow.digital.closed_surfaces.sweep_tables`.
    pinch_objects : bool
        Whether the pinches join object voxels (else background ones).
    surfaces : bool
        Add up the surfaces' sums and count the doubled edges.
    counted : numpy.ndarray, optional
        For a block of a larger volume, the box of vertices whose histogram,
        sheets, pinches and doubled edges count ((2, 3): the first and one
        past the last along each axis; along the last axis the first 0 or 1
        and the last n or n + 1). Default: every vertex.
    border : sequence of bool, optional
        Which of the six faces (low x, high x, low y, high y, low z, high z)
        are the volume's own, whose gaps join the outside. Default: all.
    pair_capacity : int, optional
        Pinch pairs and loose ends a slab holds before it is swept again for
        them alone.

    Returns
    -------
    dict
        ``hist``, ``doubled``, the pinch ``pairs`` (nodes), the ``loose``
        ends of doubled edges (rows (i, j, k, spoke bit): a doubled spoke of
        a counted vertex toward a lattice vertex that is not counted), and
        for the runs and the gaps: ``parents``, every node's component
        (numbered in order of their smallest node), ``roots``, each
        component's smallest node, and ``sums``, per component ``4 chi`` and
        ``F`` of its boundary at the counted vertices (zero without
        ``surfaces``).

    Notes
    -----
    The nodes are the runs, numbered row by row (as ``off`` says), and the
    gaps (``goff``), with one more gap node, the last, for the region
    outside the array.

    Examples
    --------
    >>> from isoflow.scale import bitrows, kernels
    >>> from isoflow.digital.closed_surfaces import sweep_tables
    >>> v = np.ones((3, 3, 3), bool); v[1, 1, 1] = False  # a cavity
    >>> bits, off, goff = bitrows.pack(v)
    >>> found = sweep(bits, v.shape, off, goff, kernels.ADJACENCY[6] + kernels.ADJACENCY[18], sweep_tables(6),
    ...               pinch_objects=False)
    >>> int(found["hist"].sum()), [len(r) for r in found["roots"]]  # 4^3 vertices; one object, cavity, outside
    (64, [1, 2])
    """
    nx, ny, nz = shape
    runs, gaps = int(off[-1]), int(goff[-1])
    threads = thread_count(nx * ny * nz)
    parts = slabs(nx, threads)
    # per node: a parent (int32) and a sum (int64)
    check_fits(12 * (runs + gaps), f"labelling the {runs + gaps:,} runs and gaps of a {nx}x{ny}x{nz} volume",
               hint="store it as .zarr and run isoflow info on that (block by block)")
    nodes = _new_nodes(runs, gaps, _SPREAD * (len(parts) + 1))
    rules = _rules(adjacency, shape, counted, border, surfaces, pinch_objects)
    if pair_capacity is None:
        pair_capacity = max(4096, (runs + gaps) // (256 * len(parts)))
    layers = _new_slabs(parts, ny, pair_capacity)
    rows = BitRows(bits, off, goff, nx, ny, nz)
    found = _sweep_slabs(rows, nodes, sheet_tables(tables, rules.formula_obj), rules, layers, len(parts))
    # the sets numbered on the threads, node ranges of about equal size
    obj_roots, obj_sums = _components(nodes.pobj, nodes.acc_obj, slabs(runs, threads))
    bg_roots, bg_sums = _components(nodes.pbg, nodes.acc_bg, slabs(gaps + 1, threads))
    return {
        "hist": np.sum([s.hist for s in layers], axis=0),
        "doubled": int(sum(d for d, _, _ in found)),
        "pairs": np.concatenate([s.pairs[:n] for s, (_, n, _) in zip(layers, found)]),
        "loose": np.concatenate([s.loose[:n] for s, (_, _, n) in zip(layers, found)]),
        "parents": (nodes.pobj, nodes.pbg),
        "roots": (obj_roots, bg_roots),
        "sums": (obj_sums, bg_sums),
    }
