"""The pieces of a label image (numba): every label's face-connected
components at once, numbered in one pass, and one pass over the lattice
vertices that reads, for every label a vertex sees, its configuration.

A *piece* is a component of the voxels of one value under 6-adjacency:
every value is cut into pieces, the value 0 too, and the region outside
the array is piece 0. Pieces are what every label's topology is built from
(:mod:`isoflow.digital.label_table`): two voxels of one value that touch
by a face are in one piece, so the 18- and 26-components of a label, and
the components of everything but a label, are unions of pieces joined
where they touch by an edge or a vertex, which the vertex pass records.

:func:`piece_runs` cuts every row of the last axis into *runs* (maximal
stretches of one value) and joins, in a union-find over the runs (a run's
parent is a run before it), each run with the runs of the two rows before
it that it touches by a face and shares a value with; so the labelling
costs 8 bytes per run, not per voxel, and a grain map has few runs per
row. The run starts are found as a bit per voxel (vector compares, 64
voxels a word), and so are the joins of two rows of many runs: where
either row begins a run and both hold one value there (a bit per voxel
too), the two runs there are joined, each found by counting its row's run
starts up to that place. A second pass in C order numbers the roots 1..n
and gives each piece its value; then every slab of layers adds its runs to
the voxel count, coordinate sums and bounding box of their pieces, on its
thread.

:func:`vertex_pass` walks every vertex row along the runs of its four
voxel rows: between two places where one of them begins a run, every
vertex has the same block, which is counted once with the number of those
vertices. Where a block holds more than one piece, it adds, for every
label in the block (octant bit ``o`` set where octant ``o`` holds the
label), one to the piece of the label's first octant in the column of the
configuration's group (configurations with one row of features), and the
configuration's sheets (:func:`isoflow.digital.closed_surfaces.sweep_tables`)
to the pair (object piece, background piece) of each; and it records every
pair of pieces the block holds with the closest way they touch (1 face,
2 edge, 3 vertex). Pairs live in an open-addressing hash table keyed by
the two piece numbers; when it fills, the pairs behind the sweep (one of
whose pieces ends before the layers still to come) leave it as entries,
so that it holds the pairs of the pieces being crossed (:class:`PairSink`).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache

import numpy as np

from ..errors import counted
from .bitrows import popcount, trailing_zeros
from .compiled import run, slabs, thread_count
from .jit import njit
from .kernels import union
from .memory import Growable, check_fits, mapped
from .ticks import Ticks, layer_step, silent

#: the key of an empty slot of the pair table
EMPTY = np.uint64(0xFFFFFFFFFFFFFFFF)
#: how two pieces touch, closest first (the pair table's ``kind``); 4: only
#: through a sheet (a face, which the kinds then say too)
FACE, EDGE, VERTEX, NONE = 1, 2, 3, 4

#: bytes per piece of the statistics (value, count, three sums, two corners)
PIECE_BYTES = 8 + 8 + 24 + 24 + 24
#: bytes per piece of a thread's share of the statistics (all but the value)
STAT_BYTES = PIECE_BYTES - 8
#: bytes per piece that the vertex pass adds beside the statistics: the
#: counts of the 38 distinct rows of the feature table (uint32) and of the
#: doubled edges (int64)
FEATURE_BYTES = 38 * 4 + 8
#: bytes per slot of the pair table (key, kind, sheets and quarters each way)
PAIR_BYTES = 32
#: bytes per pair of :func:`vertex_pass`' entries (key, kind, two packed sums)
PAIR_ENTRY_BYTES = 8 + 1 + 16
#: the pairs of one piece start at slot ``piece << SPREAD`` (a piece of a
#: grain map touches a few dozen others), so that the pairs a vertex row
#: meets lie together
SPREAD = 4


def check_layers(need: int, what: str, layers: int, note: str = "", budget: int | None = None,
                 whole: int | None = None, axis: str = "its first axis") -> None:
    """Refuse ``need`` bytes beyond the budget (default the memory
    available now), naming how many of the ``layers`` voxel layers (along
    the image's first axis, which ``axis`` names: ``"z"`` where a store is
    read in layers along z) would fit ``whole`` bytes (default ``need``:
    what the passes after this one take beside it, where known): what the
    pieces, their runs and their pairs take grows with the layers.

    Examples
    --------
    >>> from isoflow.errors import IsoflowError
    >>> try:
    ...     check_layers(8 << 30, "the runs of 400 layers of a label image", 400, budget=1 << 30)
    ... except IsoflowError as exc:
    ...     print(str(exc).split("; ")[-1])
    about 45 of the 400 voxel layers fit: crop the image along its first axis
    """
    from .memory import default_budget  # read when called: the budget is the memory available now

    budget = default_budget() if budget is None else int(budget)
    if need <= budget:
        return
    # the need of a crop in proportion to its layers, a tenth spared: the
    # pieces of an image are not spread evenly, and a crop cuts some in two
    fit = 9 * layers * budget // (10 * max(need if whole is None else whole, 1))
    if fit >= layers:  # these layers would fit but for what was held before them (earlier slabs of a store)
        hint = f"crop the image along {axis}"
    elif fit >= 1:
        hint = f"about {fit:,} of the {layers:,} voxel layers fit: crop the image along {axis}"
    else:
        hint = f"not even one of the {layers:,} voxel layers fits: crop the image across {axis}"
    check_fits(need, what, hint=hint + (f"; {note}" if note else ""), budget=budget)


def check_threads(per_thread: int, threads: int, what: str, alone: str, budget: int | None = None) -> None:
    """Refuse ``threads`` times ``per_thread`` bytes beyond the budget
    (default the memory available now), naming how many threads would fit
    (``threads=N``, ``isoflow info --labels --threads N``), or ``alone``,
    what to do where not even one does.

    Examples
    --------
    >>> from isoflow.errors import IsoflowError
    >>> try:
    ...     check_threads(3 << 20, 8, "a pair table of 98,304 slots per thread", "crop it", budget=10 << 20)
    ... except IsoflowError as exc:
    ...     print(str(exc).split("; ")[-1])
    3 threads at a time fit (threads=3, isoflow info --labels --threads 3)
    """
    from .memory import default_budget

    budget = default_budget() if budget is None else int(budget)
    if per_thread * threads <= budget:
        return
    fit = budget // max(per_thread, 1)
    hint = (alone if fit < 1 else f"{fit} thread{'s' if fit > 1 else ''} at a time fit{'' if fit > 1 else 's'} "
            f"(threads={fit}, isoflow info --labels --threads {fit})")
    check_fits(per_thread * threads, what, hint=hint, budget=budget)


def unsigned(volume: np.ndarray) -> np.ndarray:
    """The label image as unsigned integers of its width (a view: equal
    values stay equal), C-contiguous; bools as uint8."""
    v = np.ascontiguousarray(volume)
    if v.dtype == np.bool_:
        return v.view(np.uint8)
    if v.dtype.kind not in "iu":
        raise TypeError(f"a label image holds integers, not {v.dtype}")
    return v.view(np.dtype(f"u{v.dtype.itemsize}"))


@njit(cache=True, nogil=True, inline="always")
def _read(data, v, w):
    """Voxel v's value from ``data``, a label image's values as their
    little-endian bytes, w to a value (:func:`value_bytes`)."""
    i = v * w
    out = np.uint64(data[i])
    for b in range(1, w):
        out |= np.uint64(data[i + b]) << np.uint64(8 * b)
    return out


@njit(cache=True, nogil=True)
def _join_rows(flat, w, nz, starts, parent, a0, a1, row_a, b0, b1, row_b):
    """Join the runs [a0, a1) of the voxel row at flat index ``row_a`` with
    the runs [b0, b1) of the row at ``row_b`` that they touch by a face and
    share a value with. Both rows cut [0, nz) into runs, so walking them
    together, always stepping past the run that ends first, meets every
    overlapping pair once. Each run's end is read once, when the walk
    reaches it, and a step where both runs end at once steps both rows:
    fewer loads and branches per step than testing each row's end at every
    step, the part of the labelling that grows with the runs. ``flat``:
    the image's values as bytes, w to a value (:func:`_read`)."""
    ia, ib = a0, b0
    ea = starts[ia + 1] if ia + 1 < a1 else nz
    eb = starts[ib + 1] if ib + 1 < b1 else nz
    va, vb = _read(flat, row_a + starts[ia], w), _read(flat, row_b + starts[ib], w)
    while True:
        if va == vb:
            union(parent, ia, ib)
        if ea < eb:
            ia += 1
            va = _read(flat, row_a + ea, w)
            ea = starts[ia + 1] if ia + 1 < a1 else nz
        elif eb < ea:
            ib += 1
            vb = _read(flat, row_b + eb, w)
            eb = starts[ib + 1] if ib + 1 < b1 else nz
        else:  # both runs end here: at nz, both rows are done
            if ea == nz:
                return
            ia += 1
            ib += 1
            va, vb = _read(flat, row_a + ea, w), _read(flat, row_b + eb, w)
            ea = starts[ia + 1] if ia + 1 < a1 else nz
            eb = starts[ib + 1] if ib + 1 < b1 else nz


@njit(cache=True, nogil=True)
def _change_bits(flat, w, g0, n, words):
    """Bit p of ``words`` (p < n): whether voxel g0 + p of the flattened
    image differs from the one before it (bit 0: no); the bits from n on
    clear. ``flat``: the image's values as bytes, w to a value
    (:func:`_read`); past the first word, the bits where they do not
    equal the ones before them (:func:`_equal_bits`, whose vector compares
    this shares rather than compiling its own for every width)."""
    first = np.uint64(0)
    for p in range(1, min(n, 64)):
        first |= np.uint64(_read(flat, g0 + p, w) != _read(flat, g0 + p - 1, w)) << np.uint64(p)
    if n > 64:
        rest = words[1:]
        _equal_bits(flat, w, g0 + 64, g0 + 63, n - 64, rest)
        used = (n - 64 + 63) // 64
        for k in range(used):
            rest[k] = ~rest[k]
        if n % 64:
            rest[used - 1] &= (np.uint64(1) << np.uint64(n % 64)) - np.uint64(1)
    words[0] = first


#: voxels whose changes :func:`_slab_runs` marks at once (a few rows)
MARK_VOXELS = 1 << 13


@njit(cache=True, nogil=True, inline="always")
def _equals(flat, a, b, n, words):
    """:func:`_equal_bits` of the values as integers of their width. The
    full words compare views indexed from 0, so that they compile to
    vector compares."""
    full = n // 64
    for k in range(full):
        x, y = flat[a + 64 * k:a + 64 * k + 64], flat[b + 64 * k:b + 64 * k + 64]
        w = np.uint64(0)
        for t in range(64):
            w |= np.uint64(x[t] == y[t]) << np.uint64(t)
        words[k] = w
    if n % 64:
        w = np.uint64(0)
        for p in range(64 * full, n):
            w |= np.uint64(flat[a + p] == flat[b + p]) << np.uint64(p - 64 * full)
        words[full] = w


@njit(cache=True, nogil=True)
def _equal_bits(flat, w, a, b, n, words):
    """Bit p of ``words`` (p < n): whether voxels a + p and b + p of the
    flattened image hold one value; the bits from n on clear. ``flat``: the
    image's values as bytes, w to a value (:func:`_read`), so that one
    compiled pass serves every width; they are compared as integers of
    their width, a vector compare per width in this one small function
    (bytes compared one by one, then gathered into a bit per value, took
    four times as long)."""
    if w == 1:
        _equals(flat, a, b, n, words)
    elif w == 2:
        _equals(flat.view(np.uint16), a, b, n, words)
    elif w == 4:
        _equals(flat.view(np.uint32), a, b, n, words)
    else:
        _equals(flat.view(np.uint64), a, b, n, words)


@njit(cache=True, nogil=True, inline="always")
def _join_bits(starts_a, layer, yb, equal, a0, b0, parent):
    """Join the runs of two voxel rows that overlap and share a value,
    from bits: ``starts_a`` and ``layer[yb]`` mark where each row begins a
    run (its first voxel too), ``equal`` where the rows hold one value; the
    rows' runs are numbered from ``a0`` and ``b0``. Where either row begins
    a run, the two runs there overlap on up to the next such place; they
    are joined where the rows agree there, each run found by counting the
    run starts of its row up to that place. The same joins in the same
    order as a walk along the two rows' runs (:func:`_join_rows`), without
    its branch on which run ends first, which a map of many small labels
    mispredicts at about every other step."""
    one = np.uint64(1)
    ra, rb = a0 - 1, b0 - 1  # the runs that began before the word
    for k in range(len(starts_a)):
        wa, wb = starts_a[k], layer[yb, k]
        m = (wa | wb) & equal[k]
        while m != 0:
            g = trailing_zeros(m)
            m &= m - one
            upto = (np.uint64(2) << g) - one  # bits 0 .. g (g = 63: all, the shift wrapping to 0)
            union(parent, ra + np.int64(popcount(wa & upto)), rb + np.int64(popcount(wb & upto)))
        ra += np.int64(popcount(wa))
        rb += np.int64(popcount(wb))


#: a row of more than one run per this many voxels is busy: its joins
#: with a busy row before it are found from bits (:func:`_join_bits`), the
#: others by a walk along the two rows' runs (:func:`_join_rows`), which
#: costs a step per run where the bits cost passes over the rows
BITS_VOXELS_PER_RUN = 8


@njit(cache=True, nogil=True, inline="always")
def _row_bits(words, at, nz, out):
    """Bits at .. at + nz - 1 of ``words`` into ``out`` from bit 0 on, the
    bits from nz on clear."""
    k0, shift = at >> 6, np.uint64(at & 63)
    for k in range(len(out)):
        w = words[k0 + k] >> shift
        if shift != 0 and k0 + k + 1 < len(words):
            w |= words[k0 + k + 1] << (np.uint64(64) - shift)
        out[k] = w
    if nz % 64:
        out[len(out) - 1] &= (np.uint64(1) << np.uint64(nz % 64)) - np.uint64(1)


@njit(cache=True, nogil=True, inline="always")
def _join_pair(flat, w, nz, starts, parent, first, used, row, b0, b1, row_b, busy, row_bits, layer, yb, equal):
    """Join the runs [first, used) of the row at flat index ``row`` with
    the runs [b0, b1) of the row at ``row_b``: from bits where both rows
    are busy (``row_bits`` and ``layer[yb]``: where each begins runs), else
    by a walk along their runs."""
    if busy and (b1 - b0) * BITS_VOXELS_PER_RUN > nz:
        _equal_bits(flat, w, row, row_b, nz, equal)
        _join_bits(row_bits, layer, yb, equal, first, b0, parent)
    else:
        _join_rows(flat, w, nz, starts, parent, first, used, row, b0, b1, row_b)


@njit(cache=True, nogil=True, _nrt=False)
def _join_row(flat, w, ny, nz, x_lo, r, first, used, offsets, starts, parent, words, at, layer, row_bits, equal):
    """Join the runs [first, used) of row r = x * ny + y with those of rows
    (x, y - 1) and (x - 1, y) (within the slab). ``words`` holds where row
    r begins runs from bit ``at`` on; ``layer[y]`` holds where the busy
    rows of the layer before begin runs and takes row r's where it is
    busy (:data:`BITS_VOXELS_PER_RUN`); ``row_bits`` and ``equal``: scratch
    of a row's words.

    A call once per row, not compiled inline: :func:`_slab_runs` has two
    call sites, and inline each would hold a copy of both ways of joining
    for numba to compile; a row's joins cost more than the call."""
    x, y = r // ny, r % ny
    row = r * nz
    busy = (used - first) * BITS_VOXELS_PER_RUN > nz
    if busy:
        _row_bits(words, at, nz, row_bits)
    if y > 0:
        _join_pair(flat, w, nz, starts, parent, first, used, row, offsets[r - 1], first, row - nz, busy, row_bits,
                   layer, y - 1, equal)
    if x > x_lo:
        _join_pair(flat, w, nz, starts, parent, first, used, row, offsets[r - ny], offsets[r - ny + 1], row - ny * nz,
                   busy, row_bits, layer, y, equal)
    if busy:
        for k in range(len(row_bits)):
            layer[y, k] = row_bits[k]


@njit(cache=True, nogil=True, _nrt=False)
def _slab_runs(flat, w, ny, nz, x_lo, x_hi, x_at, y_at, offsets, starts, parent, used, words, layer, row_bits,
               equal):
    """The runs of the voxel rows (x, y), x_lo <= x < x_hi, from (x_at,
    y_at) on, appended at ``used`` with slab-local indices: ``starts`` (z of
    each run's first voxel), ``offsets[x * ny + y]`` (the row's first run);
    each run joined in ``parent`` with the runs of rows (x, y - 1) and
    (x - 1, y) it touches by a face and shares a value with (x - 1 within
    the slab only). Returns ``(used, x, y)``: where it stopped because the
    buffers might not hold the next rows (``x == x_hi`` when done).
    ``layer``: (ny, words of a row), where the busy rows of the last layer
    begin runs, kept from one call to the next (:func:`_join_row`);
    ``row_bits`` and ``equal``: scratch of a row's words.

    The rows are read a batch at a time: first a bit per voxel that says
    whether it begins a run (every row's first voxel does), in one vector
    pass over the batch (:func:`_change_bits`); then the set bits, each
    found by its word's trailing zeros: a row of long runs costs its runs
    and a word per 64 voxels, not a step per voxel. The joins of two busy
    rows with each other are found from bits too (:func:`_join_bits`).
    Nothing is allocated here: compiled without reference counting, whose
    counts on the arrays passed down cost more per row than a row of few
    runs does."""
    batch = max(1, (64 * len(words) - 64) // nz)
    r = x_at * ny + y_at
    r_end = x_hi * ny
    while r < r_end:
        b = min(batch, r_end - r)
        if used + b * nz > len(starts):
            return used, r // ny, r % ny
        _change_bits(flat, w, r * nz, b * nz, words)
        for t in range(b):
            words[(t * nz) >> 6] |= np.uint64(1) << np.uint64((t * nz) & 63)
        # the set bits in order; each row's first is its start
        row_end = 0
        rr = r - 1
        first = used
        for k in range((b * nz + 63) // 64):
            bits = words[k]
            while bits != 0:
                g = k * 64 + np.int64(trailing_zeros(bits))
                bits &= bits - np.uint64(1)
                if g == row_end:  # the next row begins: the last one is complete
                    if rr >= r:
                        _join_row(flat, w, ny, nz, x_lo, rr, first, used, offsets, starts, parent, words,
                                  (rr - r) * nz, layer, row_bits, equal)
                    rr += 1
                    row_end += nz
                    first = used
                    offsets[rr] = first
                starts[used] = g - (row_end - nz)
                parent[used] = used
                used += 1
        _join_row(flat, w, ny, nz, x_lo, rr, first, used, offsets, starts, parent, words, (rr - r) * nz, layer,
                  row_bits, equal)
        r += b
    return used, x_hi, 0


@njit(cache=True, nogil=True)
def _join_seam(flat, w, ny, nz, x, offsets, starts, parent):
    """Join the runs of voxel layer x with those of layer x - 1 (two slabs'
    runs, numbered globally)."""
    for y in range(ny):
        r = x * ny + y
        _join_rows(flat, w, nz, starts, parent, offsets[r], offsets[r + 1], r * nz, offsets[r - ny],
                   offsets[r - ny + 1], (r - ny) * nz)


@njit(cache=True, nogil=True)
def _count_roots(parent):
    """The number of sets of a union-find (its roots)."""
    n = 0
    for k in range(len(parent)):
        n += parent[k] == k
    return n


@njit(cache=True, nogil=True)
def _number_runs(flat, w, offsets, starts, parent, nz, values):
    """In C order, roots get the piece numbers 1..n and every other run its
    parent's number (the parent precedes it, so it has its number already):
    ``parent`` becomes each run's piece, ``values`` each piece's value."""
    n = 0
    for r in range(len(offsets) - 1):
        for k in range(offsets[r], offsets[r + 1]):
            p = parent[k]
            if p == k:
                n += 1
                parent[k] = n
                values[n] = _read(flat, r * nz + starts[k], w)
            else:
                parent[k] = parent[p]
    return n


@njit(cache=True, nogil=True)
def _add_stats(offsets, starts, runs, ny, nz, r0, r1, x0, p0, counts, sums, lo, hi):
    """Each run of rows r0 <= r < r1 adds to its piece's count, coordinate
    sums and bounding box (at index ``piece - p0``; global x offset
    ``x0``)."""
    for r in range(r0, r1):
        gx, y = r // ny + x0, r % ny
        k1 = offsets[r + 1]
        for k in range(offsets[r], k1):
            piece = np.int64(runs[k]) - p0
            s = starts[k]
            e = starts[k + 1] if k + 1 < k1 else nz
            length = e - s
            counts[piece] += length
            sums[piece, 0] += gx * length
            sums[piece, 1] += y * length
            sums[piece, 2] += (s + e - 1) * length // 2
            lo[piece, 0] = min(lo[piece, 0], gx)
            lo[piece, 1] = min(lo[piece, 1], y)
            lo[piece, 2] = min(lo[piece, 2], s)
            hi[piece, 0] = max(hi[piece, 0], gx)
            hi[piece, 1] = max(hi[piece, 1], y)
            hi[piece, 2] = max(hi[piece, 2], e - 1)


def _empty_stats(size: int) -> tuple[np.ndarray, ...]:
    """Counts, coordinate sums and box corners of ``size`` pieces, empty."""
    return (np.zeros(size, np.int64), np.zeros((size, 3), np.int64),
            np.full((size, 3), np.iinfo(np.int64).max, np.int64), np.full((size, 3), -1, np.int64))


def piece_stats(offsets: np.ndarray, starts: np.ndarray, runs: np.ndarray, shape: tuple[int, int, int], n: int,
                layers: tuple[int, int], x0: int, parts: list) -> tuple[np.ndarray, ...]:
    """Per piece (n + 1): voxel count, coordinate sums and bounding box of
    its runs in the voxel layers ``layers`` (at global x offset ``x0``),
    each slab of ``parts`` on a thread of its own: the first slab adds into
    the whole statistics, each other one into arrays over the range of
    pieces its runs hold (pieces are numbered in C order, so mostly a
    narrow one), added into the whole after."""
    _, ny, nz = shape
    rows = [(max(a, layers[0]) * ny, min(b, layers[1]) * ny) for a, b in parts]
    rows = [(r0, r1) for r0, r1 in rows if r0 < r1]
    counts, sums, lo, hi = _empty_stats(n + 1)
    windows = [pieces_held(offsets, runs, r0, r1) for r0, r1 in rows[1:]]
    # one thread adds into the whole statistics, which fit (checked before): no share of its own
    check_fits(STAT_BYTES * sum(b - a for a, b in windows), f"the statistics of {n:,} pieces, per thread",
               hint="one thread adds them into the whole statistics, which fit (threads=1, isoflow info --labels "
                    "--threads 1)")

    def slab(r0: int, r1: int, p0: int, p1: int) -> tuple[np.ndarray, ...]:
        part = _empty_stats(p1 - p0)
        _add_stats(offsets, starts, runs, ny, nz, r0, r1, x0, p0, *part)
        return part

    # the first slab's pieces need no share of their own: the whole is theirs while the others fill their shares
    first = [(_add_stats, offsets, starts, runs, ny, nz, *rows[0], x0, 0, counts, sums, lo, hi)] if rows else []
    added = run(first + [(slab, *r, *w) for r, w in zip(rows[1:], windows)])
    for (p0, p1), (c, s, a, b) in zip(windows, added[1:]):
        counts[p0:p1] += c
        sums[p0:p1] += s
        np.minimum(lo[p0:p1], a, out=lo[p0:p1])
        np.maximum(hi[p0:p1], b, out=hi[p0:p1])
    return counts, sums, lo, hi


#: bytes per run while the pieces are found: the z of its first voxel
#: (int32) and its parent, then its piece (uint32)
RUN_BYTES = 4 + 4


#: the most voxels :func:`piece_runs` numbers at once: runs and pieces are
#: uint32, and 0xFFFFFFFF marks no piece
MAX_PIECE_VOXELS = 0xFFFFFFFF - 1


def piece_runs(volume: np.ndarray, first: int = 0, last: int | None = None, x0: int = 0,
               axis: str = "its first axis", later: Callable[[int, float], int] | None = None, before: int = 0,
               ticks: Ticks | None = None) -> dict:
    """The 6-connected pieces of every value of a 3D integer image, as runs.

    A run is a maximal stretch of one value along a row of the last axis;
    runs are numbered in C order. Returns ``offsets`` (int64, rows + 1:
    row ``x * ny + y`` holds the runs ``offsets[r]:offsets[r + 1]``),
    ``starts`` (int32: z of each run's first voxel), ``runs`` (uint32: each
    run's piece, 1..n in C order of their first voxel), ``n``, and per
    piece (arrays of n + 1, index 0 for the outside): ``values`` (uint64:
    the value's bits), ``counts``, ``sums`` (coordinate sums, (n + 1, 3)),
    ``lo``/``hi`` (bounding box corners, inclusive). The statistics count
    the layers ``first <= x < last`` of axis 0 only (all by default), at
    global coordinate ``x + x0`` (for slabs of a larger volume). A refusal
    names the image's first axis as ``axis`` (:func:`check_layers`).
    ``later``: the bytes that the passes after this one take for a number
    of pieces of a number of voxels each (the label table's), these and
    ``before`` more (those of the slabs read before): checked with the
    statistics, as soon as the
    pieces are counted, so that an image of too many pieces (noise) is
    refused before the passes that would not fit. ``ticks``: the stage
    ``"pieces"`` of their progress, counted in voxel layers
    (:class:`~isoflow.scale.ticks.Ticks`), and where the work stops on a
    signal.

    The runs of each slab of layers are found and joined with the rows
    before them on a thread of their own, the slabs' seams joined after.
    """
    flat_vol = unsigned(volume)
    nx, ny, nz = flat_vol.shape
    if flat_vol.size > MAX_PIECE_VOXELS:
        raise ValueError(f"label_pieces numbers at most {MAX_PIECE_VOXELS} voxels at once (use slabs)")
    # the values as bytes: one compiled labelling for every integer width
    flat, w = value_bytes(flat_vol.reshape(-1)).reshape(-1), flat_vol.dtype.itemsize
    offsets = np.zeros(nx * ny + 1, np.int64)
    parts = slabs(nx, thread_count(flat_vol.size)) if flat_vol.size else []
    ticks = silent(ticks)
    ticks.stage("pieces", nx)
    found = run([(_slab_pieces, flat, w, ny, nz, lo, hi, offsets, axis, ticks, t) for t, (lo, hi) in enumerate(parts)],
                ticks)
    at = np.cumsum([0] + [used for _, _, used in found]).tolist()
    total = at[-1]
    if found:  # the first slab's buffers become the whole's, in place (its runs are numbered from 0 already)
        for buffer in found[0][:2]:
            buffer.resize(total, at[1])
        starts, parent = found[0][0].array(), found[0][1].array()
    else:
        starts, parent = np.zeros(0, np.int32), np.zeros(0, np.uint32)

    def place(t: int, slab_starts: Growable, slab_parent: Growable) -> None:
        """Slab t's runs at their place in the whole, numbered globally."""
        lo, hi = parts[t]
        starts[at[t]:at[t + 1]] = slab_starts.array()[:at[t + 1] - at[t]]
        np.add(slab_parent.array()[:at[t + 1] - at[t]], np.uint32(at[t]), out=parent[at[t]:at[t + 1]])
        offsets[lo * ny:hi * ny] += at[t]

    calls = [(place, t, *found[t][:2]) for t in range(1, len(parts))]
    del found
    run(calls)
    del calls
    offsets[-1] = total
    for lo, _ in parts[1:]:
        _join_seam(flat, w, ny, nz, lo, offsets, starts, parent)
    n = int(_count_roots(parent))
    what = f"the {'statistics' if later is None else 'label table'} of {n:,} pieces of a label image"
    if later is not None and before:
        what += f" (beside {before:,} of the layers read before)"
    size = flat_vol.size / (n + 1)  # voxels a piece, as those before this slab hold them too
    after = FEATURE_BYTES * (n + 1) if later is None else later(n + 1, size)
    check_layers(PIECE_BYTES * (n + 1) + (0 if later is None else later(n + 1 + before, size)), what, nx,
                 note="noise of many labels has a piece for nearly every voxel",
                 whole=PIECE_BYTES * (n + 1) + after, axis=axis)
    values = np.zeros(n + 1, np.uint64)
    _number_runs(flat, w, offsets, starts, parent, nz, values)
    counts, sums, lo, hi = piece_stats(offsets, starts, parent, (nx, ny, nz), n, (first, nx if last is None else last),
                                       x0, parts)
    return {"offsets": offsets, "starts": starts, "runs": parent, "n": n, "values": values, "counts": counts,
            "sums": sums, "lo": lo, "hi": hi}


def _slab_pieces(flat: np.ndarray, w: int, ny: int, nz: int, x_lo: int, x_hi: int, offsets: np.ndarray,
                 axis: str, ticks: Ticks, call: int) -> tuple[Growable, Growable, int]:
    """The runs of one slab of layers, joined within it (slab-local
    indices), in buffers that grow as they fill: ``(starts, parent,
    used)``, the runs the first ``used`` entries of each. Its layers are
    read a step at a time (:func:`layer_step`), each counted as call
    ``call`` of ``ticks``."""
    size = max(nz, (x_hi - x_lo) * ny * nz // 16)
    buffers = Growable(size, np.int32), Growable(size, np.uint32)
    words = np.zeros(max(MARK_VOXELS, nz) // 64 + 2, np.uint64)
    layer = np.zeros((ny, (nz + 63) // 64), np.uint64)  # a bit per voxel of a layer
    row_bits, equal = np.zeros(layer.shape[1], np.uint64), np.zeros(layer.shape[1], np.uint64)
    used, x, y = 0, x_lo, 0
    step = layer_step(ny * nz)
    while True:
        starts, parent = (buffer.array() for buffer in buffers)
        upto = min(x_hi, x + step)
        was = x
        used, x, y = _slab_runs(flat, w, ny, nz, x_lo, upto, x, y, offsets, starts, parent, used, words, layer,
                                row_bits, equal)
        del starts, parent  # no array of the buffers held: they grow in place
        ticks.add(call, x - was)
        if x == x_hi:
            return (*buffers, used)
        if x == upto:  # a step done, the buffers not full
            continue
        size = min(2 * size, (x_hi - x_lo) * ny * nz)
        check_layers(RUN_BYTES * size, f"the runs of {counted(x_hi - x_lo, 'layer')} of a label image", x_hi - x_lo, axis=axis)
        for buffer in buffers:
            buffer.resize(size, used)


@njit(cache=True, nogil=True)
def _paint(offsets, starts, runs, nz, r0, r1, ids):
    """Each voxel of rows r0 <= r < r1 its run's piece (``ids`` starts at row r0)."""
    for r in range(r0, r1):
        k1 = offsets[r + 1]
        for k in range(offsets[r], k1):
            e = starts[k + 1] if k + 1 < k1 else nz
            for z in range(starts[k], e):
                ids[(r - r0) * nz + z] = runs[k]


def piece_ids(found: dict, shape: tuple[int, int, int], layers: tuple[int, int] | None = None) -> np.ndarray:
    """The piece of every voxel of voxel layers ``layers`` (default all)
    of :func:`piece_runs`' image of ``shape``: uint32, (layers, ny, nz)."""
    nx, ny, nz = shape
    a, b = (0, nx) if layers is None else layers
    ids = np.empty((b - a, ny, nz), np.uint32)
    _paint(found["offsets"], found["starts"], found["runs"], nz, a * ny, b * ny, ids.reshape(-1))
    return ids


def label_pieces(volume: np.ndarray, first: int = 0, last: int | None = None, x0: int = 0) -> dict:
    """The 6-connected pieces of every value of a 3D integer image, voxel
    by voxel: :func:`piece_runs` with ``ids`` (uint32, the volume's shape:
    each voxel's piece) in place of the runs."""
    found = piece_runs(volume, first, last, x0)
    found["ids"] = piece_ids(found, volume.shape)
    for key in ("offsets", "starts", "runs"):
        del found[key]
    return found


# --------------------------------------------------------------------------
# the pair table
# --------------------------------------------------------------------------


@njit(cache=True, nogil=True, inline="always")
def _slot(pairs, key):
    """The slot of ``key`` in the table, or the empty slot where it goes:
    first the ``2^SPREAD`` slots from the smaller piece's home (so that the
    pairs of nearby pieces lie together), then, for a piece that touches
    more pieces than that (the outside, a background around every cell),
    from a slot of the whole key's hash, so that its pairs do not pile up
    over its neighbours' homes."""
    mask = np.uint64(len(pairs) - 1)
    h = key * np.uint64(0x9E3779B97F4A7C15)
    s = (((key >> np.uint64(32)) << np.uint64(SPREAD)) + ((h & np.uint64(0xFFFFFFFF)) >> np.uint64(32 - SPREAD))) & mask
    for _ in range(1 << SPREAD):
        k = pairs[s, 0]
        if k == key or k == EMPTY:
            return s
        s = (s + np.uint64(1)) & mask
    s = (h >> np.uint64(32)) & mask
    while True:
        k = pairs[s, 0]
        if k == key or k == EMPTY:
            return s
        s = (s + np.uint64(1)) & mask


def new_pairs(cap: int) -> np.ndarray:
    """An empty pair table of ``cap`` slots (a power of two): per slot its
    key, kind, and sheets and quarters each way (one cache line holds two
    slots, so that a lookup reads one)."""
    pairs = mapped((cap, 4), np.uint64)
    pairs[:, 0] = EMPTY
    pairs[:, 1] = NONE
    return pairs


@njit(cache=True, nogil=True)
def _tops(offsets, runs, ny, x0, top):
    """Per piece of a slab, the last voxel layer (global, from ``x0``)
    that holds it: rows come in C order, so the last row of a piece wins."""
    for r in range(len(offsets) - 1):
        x = r // ny + x0
        for k in range(offsets[r], offsets[r + 1]):
            top[runs[k]] = x


@njit(cache=True, nogil=True, inline="always")
def _done(key, top, base, below):
    """Whether the pair ``key`` lies behind the sweep: one of its pieces
    (slab numbers from ``base``; 0, the outside, never) ends before voxel
    layer ``below``, so no block from there on holds both."""
    p = np.int64(key >> np.uint64(32))
    q = np.int64(key & np.uint64(0xFFFFFFFF))
    return (p != 0 and top[p - base] < below) or (q != 0 and top[q - base] < below)


@njit(cache=True, nogil=True)
def _rehash(old, new):
    """Every pair of ``old`` moved into the empty, larger table ``new``,
    ``old`` left empty."""
    for s in range(len(old)):
        k = old[s, 0]
        if k != EMPTY:
            t = _slot(new, k)
            for c in range(4):
                new[t, c] = old[s, c]
            old[s, 0] = EMPTY
            old[s, 1] = NONE
            old[s, 2] = 0
            old[s, 3] = 0


@njit(cache=True, nogil=True)
def _drain(old, new, top, base, below, keys, kind, sums, n, s0):
    """From slot ``s0`` of ``old`` on: the pairs behind the sweep (voxel
    layer ``below``) written out as entries at ``n`` of ``keys``/``kind``/
    ``sums``, the others moved into the empty table ``new``, and each slot
    read emptied, so that ``old`` ends empty (the next table, its slots
    cleared while their cache lines are read anyway rather than in a pass
    of their own). Returns ``(s, n, moved)``: the slot where it stopped
    because the entries were full (``len(old)`` when done), the entries
    written, and the pairs moved into ``new``."""
    moved = 0
    for s in range(s0, len(old)):
        k = old[s, 0]
        if k == EMPTY:
            continue
        if _done(k, top, base, below):
            if n == len(keys):
                return s, n, moved
            keys[n] = k
            kind[n] = old[s, 1]
            sums[n, 0] = old[s, 2]
            sums[n, 1] = old[s, 3]
            n += 1
        else:
            t = _slot(new, k)
            for c in range(4):
                new[t, c] = old[s, c]
            moved += 1
        old[s, 0] = EMPTY
        old[s, 1] = NONE
        old[s, 2] = 0
        old[s, 3] = 0
    return len(old), n, moved


#: slots of a thread's cache of the pairs met last (a power of two): the
#: blocks of a vertex row meet mostly the pairs of the rows before, so
#: their sums gather in a table that the processor's nearest cache holds,
#: and only a pair pushed out of it is looked up in the pair table
NEAR_SLOTS = 1 << 10


@njit(cache=True, nogil=True)
def _into(pairs, key, how, pq, qp):
    """Add to the pair ``key`` in the pair table (as :func:`_add`, ``pq``
    and ``qp`` as uint64). Returns 1 for a new pair.

    A call, not compiled inline: :func:`_add` has five call sites in the
    vertex rows' loop and reaches this twice from each, only where the
    near cache misses; inline, the table's probe loops would be ten
    copies for numba to compile."""
    s = _slot(pairs, key)
    new = np.int64(pairs[s, 0] == EMPTY)
    pairs[s, 0] = key
    pairs[s, 1] = min(pairs[s, 1], how)
    pairs[s, 2] += pq
    pairs[s, 3] += qp
    return new


@njit(cache=True, nogil=True, inline="always")
def _spill(pairs, near, c):
    """Slot c of the near cache added into the pair table (and emptied).
    Returns 1 for a new pair."""
    key = near[c, 0]
    near[c, 0] = EMPTY
    return _into(pairs, key, near[c, 1], near[c, 2], near[c, 3])


@njit(cache=True, nogil=True)
def _spill_all(pairs, near):
    """The whole near cache added into the pair table. Returns the new pairs."""
    new = 0
    for c in range(len(near)):
        if near[c, 0] != EMPTY:
            new += _spill(pairs, near, c)
    return new


@njit(cache=True, nogil=True, inline="always")
def _packed(sheets, quarters):
    """Sheets and their quarters of faces in one word of the pair table."""
    return sheets | (quarters << 32)


@njit(cache=True, nogil=True, inline="always")
def _add(pairs, near, p, q, how, pq, qp, evict):
    """Add to the pair of pieces p != q: the closer ``how`` they touch, the
    sheets (and their quarters of faces) whose object voxel is in p and
    background voxel in q (``pq``), and those the other way (``qp``), each
    direction in one word (sheets in the low half, quarters in the high:
    :func:`_packed`). The sums gather in the near cache (``near``: a small
    pair table, one slot per hash), whose slot's pair, if another, goes to
    the pair table first; without ``evict`` (a pair of a block of four
    pieces or more, which mostly touch only there, by an edge or a vertex)
    the pair goes to the pair table itself and leaves the near cache's
    pair, which the next blocks are likely to meet, where it is. Returns
    the new pairs of the pair table (0 or 1)."""
    # the smaller piece first, picked rather than branched on: which one
    # comes first is a coin toss from one block to the next
    swap = p > q
    lo, hi = min(p, q), max(p, q)
    pq, qp = np.uint64(qp) if swap else np.uint64(pq), np.uint64(pq) if swap else np.uint64(qp)
    key = (np.uint64(lo) << np.uint64(32)) | np.uint64(hi)
    c = ((key * np.uint64(0x9E3779B97F4A7C15)) >> np.uint64(32)) & np.uint64(len(near) - 1)
    new = 0
    if near[c, 0] != key:
        if near[c, 0] != EMPTY:
            if not evict:
                return _into(pairs, key, np.uint64(how), pq, qp)
            new = _spill(pairs, near, c)
        near[c, 0] = key
        near[c, 1] = NONE
        near[c, 2] = 0
        near[c, 3] = 0
    near[c, 1] = min(near[c, 1], np.uint64(how))
    near[c, 2] += pq
    near[c, 3] += qp
    return new


# --------------------------------------------------------------------------
# the vertex pass
# --------------------------------------------------------------------------

#: octant pairs of a 2x2x2 block and how they touch, each pair of voxels of
#: the volume in exactly one block: the three faces, the six edges and the
#: four long diagonals of the block at its octant 0 (the others are at the
#: neighbouring vertices' blocks)
BLOCK_PAIRS = np.array(
    [(0, 1, FACE), (0, 2, FACE), (0, 4, FACE),
     (0, 3, EDGE), (0, 5, EDGE), (0, 6, EDGE), (1, 2, EDGE), (1, 4, EDGE), (2, 4, EDGE),
     (0, 7, VERTEX), (1, 6, VERTEX), (2, 5, VERTEX), (3, 4, VERTEX)], np.int64)


@cache
def contact_table() -> np.ndarray:
    """(256, 256) uint8: how two pieces holding the octants of masks ``a``
    and ``b`` of a block touch there, counting only the pairs of
    :data:`BLOCK_PAIRS` (:data:`NONE` where none)."""
    out = np.full((256, 256), NONE, np.uint8)
    masks = np.arange(256)
    for o1, o2, how in BLOCK_PAIRS:
        hit = (((masks[:, None] >> o1) & 1) & ((masks[None, :] >> o2) & 1)) | (
            ((masks[:, None] >> o2) & 1) & ((masks[None, :] >> o1) & 1))
        out[(hit == 1) & (out > how)] = how
    return out


def _halves(group, nsheet, quarter, spokes):
    """What the vertex pass reads for a block of two pieces, per octant
    mask ``m`` of one of them (the other holds the rest), in one row of
    four int64: how the two touch (:func:`contact_table` of ``m`` and
    ``255 - m``), the sheets of configuration ``m`` at one vertex with
    their quarters of faces packed as the pair table adds them
    (:func:`_packed`), its group of configurations (``group``: the
    feature table's row per configuration) and its spokes."""
    m = np.arange(256)
    out = np.empty((256, 4), np.int64)
    out[:, 0] = contact_table()[m, 255 - m]
    out[:, 1] = nsheet | (quarter.sum(axis=1) << 32)
    out[:, 2] = group
    out[:, 3] = spokes
    return out


@njit(cache=True, nogil=True, inline="always")
def _value_at(flat, v):
    """Voxel v's value from ``flat``, the slab's values as their
    little-endian bytes (one row per voxel)."""
    out = np.uint64(0)
    for b in range(flat.shape[1]):
        out |= np.uint64(flat[v, b]) << np.uint64(8 * b)
    return out


@njit(cache=True, nogil=True)
def _config_at(flat, ny, nz, a, nx, i, j, k, value):
    """Configuration of ``value`` at vertex (i, j, k) (global i; the slab
    starts at voxel layer a; voxels outside the volume hold no value;
    ``flat``: as for :func:`_value_at`)."""
    c = 0
    for o in range(8):
        x, y, z = i - 1 + (o & 1), j - 1 + ((o >> 1) & 1), k - 1 + (o >> 2)
        if 0 <= x < nx and 0 <= y < ny and 0 <= z < nz and _value_at(flat, ((x - a) * ny + y) * nz + z) == value:
            c |= 1 << o
    return c


def value_bytes(flat: np.ndarray) -> np.ndarray:
    """A label image's values as :func:`_value_at` reads them: a (voxels,
    width) uint8 view of its little-endian integers (a copy only on a
    big-endian machine), so that the vertex pass is compiled once for
    every integer width rather than once per width."""
    little = flat.astype(flat.dtype.newbyteorder("<"), copy=False)
    return np.ascontiguousarray(little).reshape(-1).view(np.uint8).reshape(-1, flat.dtype.itemsize)


@njit(cache=True, nogil=True)
def _doubled(flat, ny, nz, a, nx, i, j, k, value, sp, spokes):
    """Lattice edges doubled at both ends that start at this vertex (each is
    counted at its lower end): the spoke toward +axis here, toward -axis at
    the next vertex."""
    n = 0
    if (sp >> 1) & 1 and i < nx:
        n += spokes[_config_at(flat, ny, nz, a, nx, i + 1, j, k, value)] & 1
    if (sp >> 3) & 1 and j < ny:
        n += (spokes[_config_at(flat, ny, nz, a, nx, i, j + 1, k, value)] >> 2) & 1
    if (sp >> 5) & 1 and k < nz:
        n += (spokes[_config_at(flat, ny, nz, a, nx, i, j, k + 1, value)] >> 4) & 1
    return n


@njit(cache=True, nogil=True, inline="always")
def _label(flat, ny, nz, a, nx, i, j, k, w, piece, c, value, base, features, table, doubled, spokes):
    """A wanted label of the block, at its first piece: its count of the
    configuration's group (``table[c]``: configurations of one row of
    features) goes up by the ``w`` vertices (i, j, k .. k + w - 1) that
    have this block; and the doubled edges where a spoke is doubled (which
    depend on the next vertices' blocks, so are counted one vertex at a
    time)."""
    _counted(flat, ny, nz, a, nx, i, j, k, w, piece, table[c], spokes[c], value, base, features, doubled, spokes)


@njit(cache=True, nogil=True, inline="always")
def _counted(flat, ny, nz, a, nx, i, j, k, w, piece, group, sp, value, base, features, doubled, spokes):
    """:func:`_label` of a configuration of group ``group`` and spokes
    ``sp`` (read from the tables by the caller)."""
    features[piece - base, group] += w
    if sp != 0:
        for kk in range(k, k + w):
            doubled[piece - base] += _doubled(flat, ny, nz, a, nx, i, j, kk, value, sp, spokes)


@njit(cache=True, nogil=True, inline="always")
def _several(val8, id8, flat, ny, nz, a, nx, i, j, k, w, want, base, features, table, nsheet, sheet_obj, sheet_bg,
             quarter, spokes, doubled, contact, pairs, near, pid, pmask, pval, slot, local, same):
    """A block of any number of pieces (:func:`_block` gives it those of
    four or more): every label of the block (its pieces' octants
    together), its sheets summed per pair of the block's pieces in
    ``local`` (m x m x 2; ``slot[o]``: the index among them of octant o's
    piece), then one entry per pair; ``w`` vertices have this block. The pieces and labels come from masks of equal octants
    (``same[o]``: the octants that hold octant o's piece), compared all at
    once rather than searched for. Returns the number of new pairs."""
    for o in range(8):
        x = id8[o]
        e = 0
        for q in range(8):
            e |= np.int64(id8[q] == x) << q
        same[o] = e
    m = 0
    for o in range(8):
        e = same[o]
        if e & ((1 << o) - 1) == 0:  # the first octant of its piece
            pid[m] = id8[o]
            pmask[m] = e
            pval[m] = val8[o]
            slot[o] = m
            m += 1
        else:
            slot[o] = slot[trailing_zeros(e)]
    for u in range(m):
        for t in range(m):
            local[u, t, 0] = 0
            local[u, t, 1] = 0
    outside = same[0] if id8[0] == 0 else 0
    for o in range(1, 8):
        outside = same[o] if id8[o] == 0 else outside
    for u in range(m):
        piece = pid[u]
        if piece == 0 or not want[piece - base]:
            continue
        v = pval[u]
        c = 0
        for q in range(8):
            c |= np.int64(val8[q] == v) << q
        c &= ~outside  # the label's octants (the outside holds no label)
        if slot[trailing_zeros(c)] != u:  # the label is counted at its first piece
            continue
        _label(flat, ny, nz, a, nx, i, j, k, w, piece, c, v, base, features, table, doubled, spokes)
        for s_ in range(nsheet[c]):
            u1, w1 = slot[sheet_obj[c, s_]], slot[sheet_bg[c, s_]]
            local[u1, w1, 0] += w
            local[u1, w1, 1] += w * quarter[c, s_]
    new = 0
    for u in range(m):
        for t in range(u + 1, m):
            how = contact[pmask[u], pmask[t]]
            if how < NONE or local[u, t, 0] != 0 or local[t, u, 0] != 0:
                new += _add(pairs, near, pid[u], pid[t], how, _packed(local[u, t, 0], local[u, t, 1]),
                            _packed(local[t, u, 0], local[t, u, 1]), False)
    return new


@njit(cache=True, nogil=True, inline="always")
def _mask8(p, a0, a1, a2, a3, b0, b1, b2, b3):
    """The octants of a block (ids a0..a3 at dz = 0, b0..b3 at dz = 1) that
    hold piece p (no branches)."""
    return (np.int64(a0 == p) | (np.int64(a1 == p) << 1) | (np.int64(a2 == p) << 2) | (np.int64(a3 == p) << 3)
            | (np.int64(b0 == p) << 4) | (np.int64(b1 == p) << 5) | (np.int64(b2 == p) << 6)
            | (np.int64(b3 == p) << 7))


@njit(cache=True, nogil=True, inline="always")
def _value(pvalues, vbase, piece):
    """The value of a piece (0 for the outside)."""
    return pvalues[piece - vbase] if piece != 0 else np.uint64(0)


@njit(cache=True, nogil=True, inline="always")
def _slot3(m1, m2, o):
    """Which of a block's three pieces holds octant o: 0, 1 (the octants
    of mask ``m1``) or 2 (of ``m2``)."""
    return ((m1 >> o) & 1) + 2 * ((m2 >> o) & 1)


@njit(cache=True, nogil=True, inline="always")
def _sheets3(c, w, m1, m2, nsheet, sheet_obj, sheet_bg, quarter, s01, s10, s02, s20, s12, s21):
    """The sheets of configuration c at ``w`` vertices added to the sums
    ``s<u><t>`` (:func:`_packed`) of the ordered pairs (u, t) of a block's
    three pieces (:func:`_slot3`). Each sheet adds to the one sum its
    octants pick, the others add zero: no branch per sheet."""
    for s_ in range(nsheet[c]):
        at = 3 * _slot3(m1, m2, sheet_obj[c, s_]) + _slot3(m1, m2, sheet_bg[c, s_])
        add = _packed(w, w * quarter[c, s_])
        s01 += add * (at == 1)
        s02 += add * (at == 2)
        s10 += add * (at == 3)
        s12 += add * (at == 5)
        s20 += add * (at == 6)
        s21 += add * (at == 7)
    return s01, s10, s02, s20, s12, s21


@njit(cache=True, nogil=True, inline="always")
def _three(pa, pb, pc, m0, m1, m2, pvalues, vbase, flat, ny, nz, a, nx, i, j, k, w, want, base, features, table,
           nsheet, sheet_obj, sheet_bg, quarter, spokes, doubled, contact, pairs, near):
    """A block of three pieces, which ``w`` vertices (i, j, k .. k + w - 1)
    have: ``pa`` holds the octants of mask ``m0`` (octant 0 among them),
    ``pb`` those of ``m1`` (the first octant outside ``m0``), ``pc`` the
    rest (``m2``). What :func:`_several` does for any number of pieces,
    written out for three, the most common of them (on a map of small
    grains, most blocks of more than two pieces): the pieces' order is
    known, so each label's octants and the pair of each sheet come from
    the three masks, and the six sums stay in registers. Returns the
    number of new pairs."""
    va, vb, vc = _value(pvalues, vbase, pa), _value(pvalues, vbase, pb), _value(pvalues, vbase, pc)
    # two pieces of one label (the outside, piece 0, holds none)
    ab = pa != 0 and pb != 0 and va == vb
    ac = pa != 0 and pc != 0 and va == vc
    bc = pb != 0 and pc != 0 and vb == vc
    s01, s10, s02, s20, s12, s21 = 0, 0, 0, 0, 0, 0
    # each label at its first piece, with the octants of all of its pieces
    if pa != 0 and want[pa - base]:
        c = m0 | (m1 if ab else 0) | (m2 if ac else 0)
        _label(flat, ny, nz, a, nx, i, j, k, w, pa, c, va, base, features, table, doubled, spokes)
        s01, s10, s02, s20, s12, s21 = _sheets3(c, w, m1, m2, nsheet, sheet_obj, sheet_bg, quarter, s01, s10, s02,
                                                s20, s12, s21)
    if pb != 0 and not ab and want[pb - base]:
        c = m1 | (m2 if bc else 0)
        _label(flat, ny, nz, a, nx, i, j, k, w, pb, c, vb, base, features, table, doubled, spokes)
        s01, s10, s02, s20, s12, s21 = _sheets3(c, w, m1, m2, nsheet, sheet_obj, sheet_bg, quarter, s01, s10, s02,
                                                s20, s12, s21)
    if pc != 0 and not ac and not bc and want[pc - base]:
        _label(flat, ny, nz, a, nx, i, j, k, w, pc, m2, vc, base, features, table, doubled, spokes)
        s01, s10, s02, s20, s12, s21 = _sheets3(m2, w, m1, m2, nsheet, sheet_obj, sheet_bg, quarter, s01, s10, s02,
                                                s20, s12, s21)
    new = 0
    how = contact[m0, m1]
    if how < NONE or s01 != 0 or s10 != 0:
        new += _add(pairs, near, pa, pb, how, s01, s10, True)
    how = contact[m0, m2]
    if how < NONE or s02 != 0 or s20 != 0:
        new += _add(pairs, near, pa, pc, how, s02, s20, True)
    how = contact[m1, m2]
    if how < NONE or s12 != 0 or s21 != 0:
        new += _add(pairs, near, pb, pc, how, s12, s21, True)
    return new


@njit(cache=True, nogil=True, inline="always")
def _outside(m, a1, a2, a3, b0, b1, b2, b3):
    """The piece of the first octant (1 .. 7) outside mask ``m``, which
    holds octant 0 (``b3`` where it holds all eight; no branches): of
    :func:`_mask8` of octant 0's piece, the first other piece."""
    q = b3
    q = b2 if not (m >> 6) & 1 else q
    q = b1 if not (m >> 5) & 1 else q
    q = b0 if not (m >> 4) & 1 else q
    q = a3 if not (m >> 3) & 1 else q
    q = a2 if not (m >> 2) & 1 else q
    return a1 if not (m >> 1) & 1 else q


@njit(cache=True, nogil=True, inline="always")
def _block(a0, a1, a2, a3, b0, b1, b2, b3, pvalues, vbase, flat, ny, nz, a, nx, i, j, k, w, want, fbase, features,
           table, sheets, doubled, contact, pairs, near, deferred, count):
    """A block of two pieces or more (octant ``q`` of the column at dz = 0
    holds piece ``a<q>``, of the column at dz = 1 ``b<q>``), which ``w``
    vertices (i, j, k .. k + w - 1) have. Two pieces, the common case, are
    read from the ids as they are: each piece is its label's whole
    configuration there, and all of its sheets separate it from the other.
    Three pieces, the next most common (where three grains meet along a
    line), are read from their three masks (:func:`_three`). A block of
    four pieces or more is put off (its ids, k and w appended to
    ``deferred``, ``count[0]`` of them) for :func:`_deferred`, so that the
    vertex rows' loop holds no loop over a block's pieces. ``sheets``: the sheet
    tables (``nsheet, halves, sheet_obj, sheet_bg, quarter, spokes``;
    ``halves``: :func:`_halves` of them). Returns the number of new pairs."""
    nsheet, halves, sheet_obj, sheet_bg, quarter, spokes = sheets
    pa = a0
    m0 = _mask8(pa, a0, a1, a2, a3, b0, b1, b2, b3)
    pb = _outside(m0, a1, a2, a3, b0, b1, b2, b3)
    m1 = _mask8(pb, a0, a1, a2, a3, b0, b1, b2, b3)
    if (m0 | m1) != 255:
        pc = _outside(m0 | m1, a1, a2, a3, b0, b1, b2, b3)
        m2 = _mask8(pc, a0, a1, a2, a3, b0, b1, b2, b3)
        if (m0 | m1 | m2) == 255:
            return _three(pa, pb, pc, m0, m1, m2, pvalues, vbase, flat, ny, nz, a, nx, i, j, k, w, want, fbase,
                          features, table, nsheet, sheet_obj, sheet_bg, quarter, spokes, doubled, contact, pairs, near)
        d = count[0]
        deferred[d, 0], deferred[d, 1], deferred[d, 2], deferred[d, 3] = a0, a1, a2, a3
        deferred[d, 4], deferred[d, 5], deferred[d, 6], deferred[d, 7] = b0, b1, b2, b3
        deferred[d, 8], deferred[d, 9] = k, w
        count[0] = d + 1
        return 0
    if pa != 0 and pb != 0 and pvalues[pa - vbase] == pvalues[pb - vbase]:
        # one label, two pieces touching by an edge or a vertex
        return _add(pairs, near, pa, pb, halves[m0, 0], 0, 0, True)
    # one row of _halves per piece, not a read from each of five tables (the
    # contact table alone is 64 KiB): most blocks of more than one piece have two
    pq, qp = np.uint64(0), np.uint64(0)
    if pa != 0 and want[pa - fbase]:
        pq = np.uint64(w) * np.uint64(halves[m0, 1])
        _counted(flat, ny, nz, a, nx, i, j, k, w, pa, halves[m0, 2], halves[m0, 3], pvalues[pa - vbase], fbase,
                 features, doubled, spokes)
    if pb != 0 and want[pb - fbase]:
        qp = np.uint64(w) * np.uint64(halves[m1, 1])
        _counted(flat, ny, nz, a, nx, i, j, k, w, pb, halves[m1, 2], halves[m1, 3], pvalues[pb - vbase], fbase,
                 features, doubled, spokes)
    return _add(pairs, near, pa, pb, halves[m0, 0], pq, qp, True)


@njit(cache=True, nogil=True, inline="always")
def _row_at(offsets, starts, runs, base, nz, inside, r):
    """A voxel row's first run ``c``, its end ``e``, the run's piece and
    where the next run starts (a row outside the volume: one run of the
    outside, piece 0)."""
    if not inside:
        return 0, 0, np.int64(0), nz
    c, e = offsets[r], offsets[r + 1]
    return c, e, base + np.int64(runs[c]), starts[c + 1] if c + 1 < e else nz


@njit(cache=True, nogil=True, _nrt=False)
def _vertex_rows(flat, offsets, starts, runs, pvalues, ny, nz, a, nx, i0, i1, j0, want, base, fbase, features, table,
                 sheets, doubled, contact, pairs, near, used, deferred, count, scratch):
    """The vertex pass over layers i0 <= i < i1, from vertex row (i0, j0)
    on (see the module docs). ``flat``: the slab's values as bytes
    (:func:`value_bytes`; from voxel layer a of a volume of nx layers);
    ``offsets``/``starts``/``runs``: its runs and their pieces
    (:func:`piece_runs`), ``pvalues`` the pieces' values (uint64);
    ``base``: added to the slab's piece numbers (0 stays the outside);
    ``want[piece - fbase]``: its label is in the table, ``features`` and
    ``doubled`` at ``piece - fbase`` too (a thread's window of the pieces);
    ``sheets``: the sheet tables (:func:`_block`); ``used``: entries of
    the table; ``deferred``, ``count``: the blocks put off (at most two per
    run of a vertex row's voxel rows, and one); ``scratch``:
    :func:`_deferred`'s.

    A vertex row (i, j) walks its four voxel rows' runs together (row q =
    dx + 2 dy: voxel row (i - 1 + dx, j - 1 + dy)), the pieces of the
    column before in ``a<q>`` and of the column at ``z`` in ``b<q>``
    (scalars, which stay in registers): where one of the rows begins a
    run, the vertex there has a block of two columns that differ; between
    two such places every vertex has the same block, its two columns
    equal, so it is counted once with the number of those vertices (and
    skipped where the column is one piece). One call site of
    :func:`_block` (each is compiled inline) takes the three kinds of
    block in turn: the vertex at a run's start, the stretch after it, and
    the last vertex (the last column and the outside).

    Compiled without reference counting (nothing is allocated here), which
    the helpers' many array arguments would otherwise pay at every block.
    Returns ``(used, i, j)``: the vertex row where it stopped because the
    table might fill up (``i == i1`` when done)."""
    for i in range(i0, i1):
        for j in range(j0 if i == i0 else 0, ny + 1):
            c0, e0, b0, n0 = _row_at(offsets, starts, runs, base, nz, i >= 1 and j >= 1, (i - 1 - a) * ny + j - 1)
            c1, e1, b1, n1 = _row_at(offsets, starts, runs, base, nz, i < nx and j >= 1, (i - a) * ny + j - 1)
            c2, e2, b2, n2 = _row_at(offsets, starts, runs, base, nz, i >= 1 and j < ny, (i - 1 - a) * ny + j)
            c3, e3, b3, n3 = _row_at(offsets, starts, runs, base, nz, i < nx and j < ny, (i - a) * ny + j)
            blocks = 1 + 2 * ((e0 - c0) + (e1 - c1) + (e2 - c2) + (e3 - c3))
            # a block adds at most 28 pairs, the near cache holds some; a table at most 70 % full
            if 10 * (used + len(near) + 28 * blocks) > 7 * len(pairs):
                return used, i, j
            # the block to count: columns l (dz = 0) and r (dz = 1), from vertex k, w vertices
            l0, l1, l2, l3, r0, r1, r2, r3 = 0, 0, 0, 0, b0, b1, b2, b3
            z, k, w, t = 0, 0, 1, 0
            event, last = True, False
            while True:
                used += _block(l0, l1, l2, l3, r0, r1, r2, r3, pvalues, base, flat, ny, nz, a, nx, i, j, k, w, want,
                               fbase, features, table, sheets, doubled, contact, pairs, near, deferred, count)
                if last:
                    break
                l0, l1, l2, l3 = b0, b1, b2, b3
                if event:  # vertices z + 1 .. t - 1: column z twice, unless it is one piece
                    t = min(min(n0, n1), min(n2, n3))
                    if t - z > 1 and not (b0 == b1 and b0 == b2 and b0 == b3):
                        r0, r1, r2, r3, k, w, event = b0, b1, b2, b3, z + 1, t - z - 1, False
                        continue
                if t == nz:  # vertex nz: the last column and the outside
                    r0, r1, r2, r3, k, w, last = 0, 0, 0, 0, nz, 1, True
                    continue
                # each row that begins a run at t steps to it; written out row by
                # row, as the rows' state is scalars (kept in registers), not arrays
                if n0 == t:
                    c0 += 1
                    b0 = base + np.int64(runs[c0])
                    n0 = starts[c0 + 1] if c0 + 1 < e0 else nz
                if n1 == t:
                    c1 += 1
                    b1 = base + np.int64(runs[c1])
                    n1 = starts[c1 + 1] if c1 + 1 < e1 else nz
                if n2 == t:
                    c2 += 1
                    b2 = base + np.int64(runs[c2])
                    n2 = starts[c2 + 1] if c2 + 1 < e2 else nz
                if n3 == t:
                    c3 += 1
                    b3 = base + np.int64(runs[c3])
                    n3 = starts[c3 + 1] if c3 + 1 < e3 else nz
                z = t
                r0, r1, r2, r3, k, w, event = b0, b1, b2, b3, z, 1, True
            if count[0]:
                used += _deferred(deferred, count, pvalues, base, flat, ny, nz, a, nx, i, j, want, fbase, features,
                                  table, sheets, doubled, contact, pairs, near, scratch)
    return used, i1, 0


@njit(cache=True, nogil=True, _nrt=False)
def _deferred(deferred, count, pvalues, vbase, flat, ny, nz, a, nx, i, j, want, fbase, features, table, sheets,
              doubled, contact, pairs, near, scratch):
    """The blocks of four pieces or more that :func:`_block` put off in
    vertex row (i, j), each by :func:`_several`; ``scratch``: ``val8, id8,
    pid, pmask, pval, slot, local, same``. Returns the number of new pairs.

    Called once per vertex row, so compiled on its own rather than inline
    (as :func:`_vertex_rows`, without reference counting): a shorter first
    compile of the vertex rows, at the same speed."""
    nsheet, halves, sheet_obj, sheet_bg, quarter, spokes = sheets
    val8, id8, pid, pmask, pval, slot, local, same = scratch
    new = 0
    for d in range(count[0]):
        for o in range(8):
            id8[o] = deferred[d, o]
            val8[o] = _value(pvalues, vbase, id8[o])
        new += _several(val8, id8, flat, ny, nz, a, nx, i, j, deferred[d, 8], deferred[d, 9], want, fbase, features,
                        table, nsheet, sheet_obj, sheet_bg, quarter, spokes, doubled, contact, pairs, near, pid,
                        pmask, pval, slot, local, same)
    count[0] = 0
    return new


def vertex_pass(values: np.ndarray, found: dict, want: np.ndarray, table: np.ndarray, sheet_tables,
                layers: tuple[int, int] | None = None, nx: int | None = None, x0: int = 0, base: int = 0,
                keep_runs: bool = True, axis: str = "its first axis", joined: bool = True,
                ticks: Ticks | None = None) -> dict:
    """The vertex pass (see the module docs) over a slab of a label image.

    ``values``: the slab (voxel layers ``x0 ..`` of a volume of ``nx``
    layers, default: the whole volume); ``found``: its :func:`piece_runs`;
    ``want``: per piece (n + 1), whether its label is counted; ``table``:
    (256, F) features per configuration; ``sheet_tables``:
    :func:`isoflow.digital.closed_surfaces.sweep_tables`; ``layers``: the
    vertex layers (global, default all); ``base``: added to piece numbers in
    the pair table. Returns per piece ``features`` (n + 1, F) and
    ``doubled`` (lattice edges doubled at both ends, at their lower end),
    and the pair table's entries: ``keys`` (uint64: the smaller piece in the
    high 32 bits), ``kind`` (how they touch) and ``sums`` (uint64, 2
    columns: the sheets whose object voxel is in the smaller piece and
    background voxel in the larger, plus their quarters of faces times
    2^32; then the same the other way; each count below 2^32, so that
    sums of entries add them both).
    A pair met by two threads has an entry from each (the graph of pieces
    adds them up: :func:`isoflow.scale.piece_graph.pair_graph`). A refusal names the image's first axis as ``axis``
    (:func:`check_layers`). Without ``keep_runs`` the runs of ``found``
    (``starts`` and ``runs``) are let go once the sweep is done, before
    the pairs are read out. Without ``joined`` the entries are given as the
    blocks the threads wrote them out in, not copied into one set of
    arrays: ``entries``, a list of ``(keys, kind, sums)`` in place of the
    three (:func:`isoflow.scale.piece_graph.entries_graph` reads them so).
    ``ticks``: the stage ``"vertices"`` of the progress, counted in vertex
    layers, and where the work stops on a signal.
    """
    flat = unsigned(values)
    nxs, ny, nz = flat.shape
    nx = nxs if nx is None else nx
    lo, hi = (0, nx + 1) if layers is None else layers
    nsheet, sheet_obj, sheet_bg, quarter, spokes, _ = (np.asarray(t, np.int64) for t in sheet_tables)
    npieces = len(want)
    parts = slabs(hi - lo, thread_count(nxs * ny * nz)) if flat.size else []
    rows, group = np.unique(np.asarray(table, np.int64), axis=0, return_inverse=True)
    # a group's count per piece is at most the vertices of the volume
    count = np.uint32 if (nx + 1) * (ny + 1) * (nz + 1) < 2**32 else np.int64
    # the pieces a thread meets: those of its voxel layers (numbered in C
    # order, mostly a narrow range), so its counts cover that range only
    windows = [piece_window(found, ny, x0, nxs, lo + p0 - 1, lo + p1 - 1) for p0, p1 in parts] or [(0, npieces)]
    # the statistics of the pieces are held beside the counts
    check_layers(sum(b - a for a, b in windows) * (len(rows) * np.dtype(count).itemsize + 8) + PIECE_BYTES * npieces,
                 f"the vertex pass over {npieces:,} pieces", nxs, axis=axis)
    features = [mapped((b - a, len(rows)), count) for a, b in windows]
    doubled = [mapped(b - a, np.int64) for a, b in windows]
    # the values as bytes and the pieces' values as uint64: one compiled pass for every width
    args = (value_bytes(flat), found["offsets"], found["starts"], found["runs"],
            found["values"].astype(np.uint64, copy=False), ny, nz, x0, nx)
    table_of = group.reshape(-1).astype(np.int64)
    sheets = (nsheet, _halves(table_of, nsheet, quarter, spokes), sheet_obj, sheet_bg, quarter, spokes)
    contact = contact_table()
    wanted = want.astype(np.bool_)

    top = np.zeros(npieces, np.int64)
    _tops(found["offsets"], found["runs"], ny, x0, top)

    def call(t, args):
        scratch = (np.zeros(8, np.uint64), np.zeros(8, np.int64), np.zeros(8, np.int64), np.zeros(8, np.int64),
                   np.zeros(8, np.uint64), np.zeros(8, np.int64), np.zeros((8, 8, 2), np.int64),
                   np.zeros(8, np.int64))
        put_off = (np.zeros((8 * nz + 2, 10), np.int64), np.zeros(1, np.int64))
        sink = PairSink(top, base, len(parts), axis)
        used, i, j, end = 0, lo + parts[t][0], 0, lo + parts[t][1]
        while i < end:
            at, upto = (i, j), min(end, i + step)
            used, i, j = _vertex_rows(*args, i, upto, j, wanted[windows[t][0]:], base, base + windows[t][0],
                                      features[t], table_of, sheets, doubled[t], contact, sink.pairs,
                                      sink.near, used, *put_off, scratch)
            ticks.add(t, i - at[0])
            if i < upto:  # the table is full: the pairs behind the sweep out, a larger table if none were
                used = sink.drain(used, i - 1, grow=(i, j) == at)
        sink.drain(used, None)
        return sink.blocks

    ticks = silent(ticks)
    ticks.stage("vertices", hi - lo)
    step = layer_step((ny + 1) * (nz + 1))
    filled = run([(call, t, args) for t in range(len(parts))], ticks)
    del args  # the runs: let go here where the caller lets them go
    if not keep_runs:
        for key in ("starts", "runs"):
            found[key] = found[key][:0].copy()  # a view would keep the buffer
    out = {"features": features_of(features, windows, npieces, rows), "doubled": doubled_of(doubled, windows, npieces)}
    if not joined:
        out["entries"] = [(k[:n], c[:n], v[:n]) for thread in filled for k, c, v, n in thread]
        return out
    out["keys"], out["kind"], out["sums"] = read_out(filled, npieces, nxs, axis)
    return out


#: the pair table's first size (slots), and entries per block of the pairs
#: written out
FIRST_SLOTS, ENTRY_BLOCK = 1 << 15, 1 << 16


class PairSink:
    """A thread's pair table and the pairs it has written out.

    The sweep meets the pieces in C order, and a pair of pieces none of
    whose blocks lie ahead of it (one of the two ends behind the sweep) is
    complete: it leaves the table as an entry of a block of entries. So the
    table holds the pairs of the pieces the sweep is crossing, not of the
    whole image: it stays small, and its lookups hit the cache."""

    def __init__(self, top: np.ndarray, base: int, threads: int, axis: str = "its first axis"):
        self.top, self.base, self.threads = top, base, threads
        self.axis = axis  # the image's first axis, as a refusal names it
        self.pairs = new_pairs(FIRST_SLOTS)
        self.near = new_pairs(NEAR_SLOTS)
        self.spare: np.ndarray | None = None
        self.blocks: list[list] = []  # [keys, kind, sums, entries]

    def drain(self, used: int, below: int | None, grow: bool = False) -> int:
        """The pairs of the table that lie behind voxel layer ``below``
        (all of them where None) written out, the others moved into a new
        table, larger where ``grow`` or where they fill more than 30 % of
        it (then moved once more, into a table that they fill less).
        Returns the pairs in the new table."""
        last = below is None  # all out: the new table stays empty
        below = np.iinfo(np.int64).max if below is None else below
        # the vertex rows stop while the table holds the near cache's pairs too
        used += _spill_all(self.pairs, self.near)
        size = 2 * len(self.pairs) if grow else len(self.pairs)
        new = new_pairs(1) if last else self._table(size)
        keep, s = 0, 0
        while s < len(self.pairs):
            if not self.blocks or self.blocks[-1][3] == len(self.blocks[-1][0]):
                self.blocks.append(_entry_block(ENTRY_BLOCK))
            block = self.blocks[-1]
            s, block[3], moved = _drain(self.pairs, new, self.top, self.base, below, *block, s)
            keep += moved
        # the pairs kept are counted as they move, not in a pass before: a
        # table they crowd is rare (the sweep's pairs grow slowly), moving
        # them twice then costs less than counting them at every drain
        if 10 * keep > 3 * size:
            while 10 * keep > 3 * size:
                size *= 2
            crowded, new = new, self._table(size)
            _rehash(crowded, new)
        # the old table, emptied by the drain, is the next one (no fresh pages to fault in)
        self.pairs, self.spare = new, self.pairs
        return keep

    def _table(self, size: int) -> np.ndarray:
        """An empty table of ``size`` slots: the spare where it is that
        size (emptied by the drain that made it the spare), else a new one,
        checked before it is made (the budget is read from /proc)."""
        if self.spare is not None and len(self.spare) == size:
            new, self.spare = self.spare, None
            return new
        alone = (f"crop the image across {self.axis}: a thread's table holds the pairs of the pieces that its "
                 "voxel layers cross" if size > FIRST_SLOTS else "not even one thread's first table fits")
        check_threads(PAIR_BYTES * size, self.threads, f"a pair table of {size:,} slots per thread", alone)
        return new_pairs(size)


def _entry_block(size: int) -> list:
    """An empty block of ``size`` pair entries, ``[keys, kind, sums, 0]``,
    all three in one map of pages (:func:`~isoflow.scale.memory.mapped`):
    the graph of pieces lets a block go once it is placed, and its pages
    go back to the system then. Keys and kind in arrays of their own would
    be small enough for the C allocator's heaps, which keep their memory
    among the blocks still held."""
    pages = mapped(size * PAIR_ENTRY_BYTES, np.uint8)
    keys = pages[:8 * size].view(np.uint64)
    sums = pages[8 * size:24 * size].view(np.uint64).reshape(size, 2)
    return [keys, pages[24 * size:], sums, 0]


def read_out(filled: list, npieces: int, layers: int = 1,
             axis: str = "its first axis") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The threads' blocks of pair entries ``[keys, kind, sums, entries]``
    in one set of arrays, each block let go as soon as it is copied. A
    pair met by two threads (pieces at the seam between their layers) has
    an entry from each: the graph of pieces takes them as they are. A
    refusal names the share of the image's ``layers`` that would fit."""
    blocks = [block for thread in filled for block in thread]
    filled.clear()
    total = sum(block[3] for block in blocks)
    check_layers(PAIR_ENTRY_BYTES * total, f"the {total:,} pairs of {npieces:,} pieces", layers, axis=axis)
    keys, kind, sums = mapped(total, np.uint64), mapped(total, np.uint8), mapped((total, 2), np.uint64)
    at = 0
    while blocks:
        k, c, v, n = blocks.pop(0)
        keys[at:at + n], kind[at:at + n], sums[at:at + n] = k[:n], c[:n], v[:n]
        at += n
        del k, c, v
    return keys, kind, sums


def piece_window(found: dict, ny: int, x0: int, nxs: int, first: int, last: int) -> tuple[int, int]:
    """The range [a, b) of the slab's piece numbers that its voxel layers
    first .. last (global, inclusive, clipped to the slab of nxs layers
    from x0) hold."""
    r0 = max(first - x0, 0) * ny
    r1 = min(last - x0 + 1, nxs) * ny
    return pieces_held(found["offsets"], found["runs"], r0, max(r1, r0))


def pieces_held(offsets: np.ndarray, runs: np.ndarray, r0: int, r1: int) -> tuple[int, int]:
    """The range [a, b) of piece numbers that the runs of rows r0 .. r1 - 1
    hold ((0, 0) where they hold none)."""
    held = runs[offsets[r0]:offsets[r1]]
    if not len(held):
        return 0, 0
    return int(held.min()), int(held.max()) + 1


def features_of(counts: list[np.ndarray], windows: list, npieces: int, rows: np.ndarray) -> np.ndarray:
    """Per piece, the features of its vertices: each thread's counts of
    each group of configurations (over its window of pieces) times the
    group's row of features, added up, window by window (each cut into
    ranges of pieces on threads of their own). The list is taken over:
    a window's counts are let go as soon as they are added, so that the
    counts and the features, whose pages fill window by window, are not
    all held at once."""
    out = mapped((npieces, rows.shape[1]), np.int64)
    weights = np.ascontiguousarray(rows, np.int64)

    def add(part: np.ndarray, lo: int, a: int, b: int) -> None:
        """Pieces lo + a .. lo + b - 1 of a window."""
        _add_features(part[a:b], weights, out[lo + a:lo + b])

    for w, (lo, hi) in enumerate(windows):
        part, counts[w] = counts[w], None
        run([(add, part, lo, a, b) for a, b in slabs(hi - lo, len(windows)) if b > a])
        del part  # the window's pages go back now
    counts.clear()
    return out


@njit(cache=True, nogil=True)
def _add_features(counts, weights, out):
    """``out[p] += counts[p] @ weights``, over the nonzero counts only (a
    piece meets few groups of configurations)."""
    for p in range(len(counts)):
        for g in range(counts.shape[1]):
            c = np.int64(counts[p, g])
            if c != 0:
                for f in range(weights.shape[1]):
                    out[p, f] += c * weights[g, f]


def doubled_of(doubled: list[np.ndarray], windows: list, npieces: int) -> np.ndarray:
    """Per piece, the threads' doubled edges added up."""
    out = np.zeros(npieces, np.int64)
    for (lo, hi), part in zip(windows, doubled):
        out[lo:hi] += part
    return out
