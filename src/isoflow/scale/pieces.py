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

:func:`label_pieces` is a union-find whose parent array is the output
itself (a voxel's parent is the flat index of a voxel before it), so the
labelling costs the 4-byte piece number per voxel and nothing more; a
second pass in C order numbers the roots 1..n and gives each piece its
value, voxel count, coordinate sums and bounding box.

:func:`vertex_pass` visits every lattice vertex; where its 2x2x2 block
holds more than one piece, it adds, for every label in the block (octant
bit ``o`` set where octant ``o`` holds the label), the configuration's row
of a feature table to the piece of the label's first octant, and the
configuration's sheets (:func:`isoflow.digital.closed_surfaces.sweep_tables`)
to the pair (object piece, background piece) of each; and it records every
pair of pieces the block holds with the closest way they touch (1 face,
2 edge, 3 vertex). Pairs live in an open-addressing hash table keyed by
the two piece numbers, which grows as it fills.
"""

from __future__ import annotations

import numpy as np

from .compiled import run, slabs, thread_count
from .jit import njit
from .memory import check_fits

#: the key of an empty slot of the pair table
EMPTY = np.uint64(0xFFFFFFFFFFFFFFFF)
#: how two pieces touch, closest first (the pair table's ``kind``); 4: only
#: through a sheet (a face, which the kinds then say too)
FACE, EDGE, VERTEX, NONE = 1, 2, 3, 4

#: bytes per piece of the statistics (value, count, three sums, two corners)
PIECE_BYTES = 8 + 8 + 24 + 24
#: bytes per slot of the pair table (key, kind, sheets and quarters each way)
PAIR_BYTES = 8 + 1 + 16


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
def _find(parent, x):
    """The root of x, halving the path on the way."""
    while True:
        p = parent[x]
        if p == x:
            return x
        g = parent[p]
        parent[x] = g
        x = g


@njit(cache=True, nogil=True, inline="always")
def _union(parent, a, b):
    """Join the sets of a and b under the smaller root (so that every
    parent precedes its child). Returns 1 when they were apart."""
    ra, rb = _find(parent, a), _find(parent, b)
    if ra == rb:
        return 0
    if ra < rb:
        parent[rb] = ra
    else:
        parent[ra] = rb
    return 1


@njit(cache=True, nogil=True)
def _join_voxels(flat, ids, nx, ny, nz):
    """First pass: ``ids`` becomes a union-find over the voxels (a voxel's
    parent precedes it). A voxel takes its row predecessor's parent when
    they are equal, and is joined to its face neighbours in the rows
    before it where a contact begins (where both predecessors touch too,
    the two are joined already). Returns the number of sets."""
    sy, sx = nz, ny * nz
    n = 0
    for x in range(nx):
        for y in range(ny):
            row = (x * ny + y) * nz
            for z in range(nz):
                v = row + z
                val = flat[v]
                left = z > 0 and flat[v - 1] == val
                if left:
                    ids[v] = ids[v - 1]
                else:
                    ids[v] = v
                    n += 1
                if y > 0 and flat[v - sy] == val and not (left and flat[v - sy - 1] == val):
                    n -= _union(ids, v, v - sy)
                if x > 0 and flat[v - sx] == val and not (left and flat[v - sx - 1] == val):
                    n -= _union(ids, v, v - sx)
    return n


@njit(cache=True, nogil=True)
def _number_pieces(flat, ids, nx, ny, nz, first, last, x0, values, counts, sums, lo, hi):
    """Second pass, in C order: roots get the numbers 1..n, every other
    voxel its parent's number (the parent precedes it, so it has its number
    already). Each run of one piece along a row adds to the piece's count,
    coordinate sums and bounding box, for the layers first <= x < last
    only (at global x offset ``x0``)."""
    n = 0
    for x in range(nx):
        counted = first <= x < last
        gx = x + x0
        for y in range(ny):
            row = (x * ny + y) * nz
            cur = -1
            start = 0
            for z in range(nz + 1):
                if z < nz:
                    v = row + z
                    p = ids[v]
                    if p == v:
                        n += 1
                        ids[v] = n
                        values[n] = flat[v]
                        piece = n
                    else:
                        piece = np.int64(ids[p])
                        ids[v] = piece
                else:
                    piece = -2
                if piece != cur:
                    if cur >= 0 and counted:
                        length = z - start
                        counts[cur] += length
                        sums[cur, 0] += gx * length
                        sums[cur, 1] += y * length
                        sums[cur, 2] += (start + z - 1) * length // 2
                        lo[cur, 0] = min(lo[cur, 0], gx)
                        lo[cur, 1] = min(lo[cur, 1], y)
                        lo[cur, 2] = min(lo[cur, 2], start)
                        hi[cur, 0] = max(hi[cur, 0], gx)
                        hi[cur, 1] = max(hi[cur, 1], y)
                        hi[cur, 2] = max(hi[cur, 2], z - 1)
                    cur = piece
                    start = z


def label_pieces(volume: np.ndarray, first: int = 0, last: int | None = None, x0: int = 0) -> dict:
    """The 6-connected pieces of every value of a 3D integer image.

    Returns ``ids`` (uint32, the volume's shape: each voxel's piece, 1..n in
    C order of their first voxel), ``n``, and per piece (arrays of n + 1,
    index 0 for the outside): ``values`` (uint64: the value's bits),
    ``counts``, ``sums`` (coordinate sums, (n + 1, 3)), ``lo``/``hi``
    (bounding box corners, inclusive). The statistics count the layers
    ``first <= x < last`` of axis 0 only (all by default), at global
    coordinate ``x + x0`` (for slabs of a larger volume).
    """
    flat_vol = unsigned(volume)
    nx, ny, nz = flat_vol.shape
    if flat_vol.size >= 0xFFFFFFFF:
        raise ValueError("label_pieces numbers at most 2^32 - 2 voxels at once (use slabs)")
    ids = np.empty(flat_vol.size, np.uint32)
    n = _join_voxels(flat_vol.reshape(-1), ids, nx, ny, nz)
    check_fits(PIECE_BYTES * (n + 1), f"the statistics of {n:,} pieces of a label image",
               hint="a label image of noise has a piece for about every other voxel")
    values = np.zeros(n + 1, np.uint64)
    counts = np.zeros(n + 1, np.int64)
    sums = np.zeros((n + 1, 3), np.int64)
    lo = np.full((n + 1, 3), np.iinfo(np.int64).max, np.int64)
    hi = np.full((n + 1, 3), -1, np.int64)
    _number_pieces(flat_vol.reshape(-1), ids, nx, ny, nz, first, nx if last is None else last, x0,
                   values, counts, sums, lo, hi)
    return {"ids": ids.reshape(flat_vol.shape), "n": int(n), "values": values, "counts": counts,
            "sums": sums, "lo": lo, "hi": hi}


# --------------------------------------------------------------------------
# the pair table
# --------------------------------------------------------------------------


@njit(cache=True, nogil=True, inline="always")
def _slot(keys, key):
    """The slot of ``key`` in the table, or the empty slot where it goes."""
    mask = np.uint64(len(keys) - 1)
    s = ((key * np.uint64(0x9E3779B97F4A7C15)) >> np.uint64(32)) & mask
    while True:
        k = keys[s]
        if k == key or k == EMPTY:
            return s
        s = (s + np.uint64(1)) & mask


@njit(cache=True, nogil=True)
def _grown(keys, kind, acc):
    """The table moved into one twice as large."""
    cap = 2 * len(keys)
    nkeys = np.full(cap, EMPTY, np.uint64)
    nkind = np.full(cap, NONE, np.uint8)
    nacc = np.zeros((cap, 2), np.int64)
    for s in range(len(keys)):
        k = keys[s]
        if k != EMPTY:
            t = _slot(nkeys, k)
            nkeys[t] = k
            nkind[t] = kind[s]
            nacc[t] = acc[s]
    return nkeys, nkind, nacc


@njit(cache=True, nogil=True, inline="always")
def _add(keys, kind, acc, p, q, how, sheets_pq, quarters_pq, sheets_qp, quarters_qp):
    """Add to the pair of pieces p != q: the closer ``how`` they touch, the
    sheets (and their quarters of faces) whose object voxel is in p and
    background voxel in q, and those the other way, each direction in one
    int64 (sheets in the low half, quarters in the high). Returns 1 for a
    new pair."""
    if p > q:
        p, q = q, p
        sheets_pq, quarters_pq, sheets_qp, quarters_qp = sheets_qp, quarters_qp, sheets_pq, quarters_pq
    key = (np.uint64(p) << np.uint64(32)) | np.uint64(q)
    s = _slot(keys, key)
    new = 0
    if keys[s] == EMPTY:
        keys[s] = key
        new = 1
    kind[s] = min(kind[s], how)
    acc[s, 0] += sheets_pq | (quarters_pq << 32)
    acc[s, 1] += sheets_qp | (quarters_qp << 32)
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


@njit(cache=True, nogil=True)
def _config_at(flat, ny, nz, a, nx, i, j, k, value):
    """Configuration of ``value`` at vertex (i, j, k) (global i; the slab
    starts at voxel layer a; voxels outside the volume hold no value)."""
    c = 0
    for o in range(8):
        x, y, z = i - 1 + (o & 1), j - 1 + ((o >> 1) & 1), k - 1 + (o >> 2)
        if 0 <= x < nx and 0 <= y < ny and 0 <= z < nz and flat[((x - a) * ny + y) * nz + z] == value:
            c |= 1 << o
    return c


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
def _mask_of(id8, piece):
    """The octants of a block that hold ``piece`` (no branches)."""
    m = 0
    for o in range(8):
        m |= np.int64(id8[o] == piece) << o
    return m


@njit(cache=True, nogil=True, inline="always")
def _label(flat, ny, nz, a, nx, i, j, k, piece, c, value, want, base, features, table, doubled, spokes):
    """A label of the block, at its first piece: the configuration's
    features, and the doubled edges where a spoke is doubled."""
    if want[piece - base]:
        for f in range(features.shape[1]):
            features[piece - base, f] += table[c, f]
        if spokes[c] != 0:
            doubled[piece - base] += _doubled(flat, ny, nz, a, nx, i, j, k, value, spokes[c], spokes)


@njit(cache=True, nogil=True, inline="always")
def _several(val8, id8, flat, ny, nz, a, nx, i, j, k, want, base, features, table, nsheet, sheet_obj, sheet_bg,
             quarter, spokes, doubled, contact, keys, kind, acc, pid, pmask, pval, local):
    """A block of three pieces or more: every label of the block (its
    pieces' octants together), its sheets summed per pair of the block's
    pieces in ``local`` (m x m x 2), then one entry per pair. Returns the
    number of new pairs."""
    m = 0
    for o in range(8):
        p = id8[o]
        u = 0
        while u < m and pid[u] != p:
            u += 1
        if u == m:
            pid[m] = p
            pmask[m] = 0
            pval[m] = val8[o]
            m += 1
        pmask[u] |= 1 << o
    for u in range(m):
        for w in range(m):
            local[u, w, 0] = 0
            local[u, w, 1] = 0
    for u in range(m):
        piece = pid[u]
        if piece == 0 or not want[piece - base]:
            continue
        c = pmask[u]
        merged = False
        for w in range(m):
            if w != u and pid[w] != 0 and pval[w] == pval[u]:
                if w < u:  # the label was done at its first piece
                    merged = True
                    break
                c |= pmask[w]
        if merged:
            continue
        _label(flat, ny, nz, a, nx, i, j, k, piece, c, pval[u], want, base, features, table, doubled, spokes)
        for s_ in range(nsheet[c]):
            p, q = id8[sheet_obj[c, s_]], id8[sheet_bg[c, s_]]
            u1 = 0
            while pid[u1] != p:
                u1 += 1
            w1 = 0
            while pid[w1] != q:
                w1 += 1
            local[u1, w1, 0] += 1
            local[u1, w1, 1] += quarter[c, s_]
    new = 0
    for u in range(m):
        for w in range(u + 1, m):
            how = contact[pmask[u], pmask[w]]
            if how < NONE or local[u, w, 0] != 0 or local[w, u, 0] != 0:
                new += _add(keys, kind, acc, pid[u], pid[w], how, local[u, w, 0], local[u, w, 1], local[w, u, 0],
                            local[w, u, 1])
    return new


@njit(cache=True, nogil=True, inline="always")
def _lowest(mask):
    """The lowest set bit's index of a nonzero mask."""
    o = 0
    while not (mask >> o) & 1:
        o += 1
    return o


@njit(cache=True, nogil=True, inline="always")
def _two(val8, id8, m0, o1, flat, ny, nz, a, nx, i, j, k, want, base, features, table, nsheet, qsum, spokes,
         doubled, contact, keys, kind, acc):
    """A block of two pieces (the common case): pieces A (octants ``m0``)
    and B (the others, the first of them ``o1``). Each piece is its
    label's whole configuration there, and all of its sheets separate it
    from the other. Returns the number of new pairs."""
    m1 = 255 ^ m0
    pa, pb = id8[0], id8[o1]
    if pa != 0 and pb != 0 and val8[0] == val8[o1]:  # one label, two pieces touching by an edge or a vertex
        return _add(keys, kind, acc, pa, pb, contact[m0, m1], 0, 0, 0, 0)
    na = nsheet[m0] if pa != 0 and want[pa - base] else 0
    nb = nsheet[m1] if pb != 0 and want[pb - base] else 0
    if pa != 0:
        _label(flat, ny, nz, a, nx, i, j, k, pa, m0, val8[0], want, base, features, table, doubled, spokes)
    if pb != 0:
        _label(flat, ny, nz, a, nx, i, j, k, pb, m1, val8[o1], want, base, features, table, doubled, spokes)
    return _add(keys, kind, acc, pa, pb, contact[m0, m1], na, qsum[m0] if na else 0, nb, qsum[m1] if nb else 0)


@njit(cache=True, nogil=True, _nrt=False)
def _vertex_layers(flat, ids, ny, nz, a, nx, i0, i1, j0, k0, want, base, features, table, nsheet, qsum, sheet_obj,
                   sheet_bg, quarter, spokes, doubled, contact, keys, kind, acc, used, val8, id8, rows, pid, pmask,
                   pval, local):
    """The vertex pass over layers i0 <= i < i1, from vertex (i0, j0, k0)
    on (see the module docs). ``flat``/``ids``: the slab's values and
    pieces (from voxel layer a of a volume of nx layers); ``want[piece]``:
    its label is in the table; ``base``: added to the slab's piece numbers
    (0 stays the outside); ``used``: entries of the table; the rest is
    scratch. A vertex row (i, j) reads its four voxel rows a column at a
    time and skips the columns where all eight voxels are one piece.

    Compiled without reference counting (nothing is allocated here), which
    the helpers' many array arguments would otherwise pay at every vertex.
    Returns ``(used, i, j, k)``: the vertex where it stopped because the
    table might fill up (``i == i1`` when done)."""
    for i in range(i0, i1):
        for j in range(j0 if i == i0 else 0, ny + 1):
            first = k0 if i == i0 and j == j0 else 0
            for q in range(4):  # row q = dx + 2 dy: voxel row (i - 1 + dx, j - 1 + dy), -1 outside
                x, y = i - 1 + (q & 1), j - 1 + (q >> 1)
                rows[q] = ((x - a) * ny + y) * nz if 0 <= x < nx and 0 <= y < ny else -1
            for q in range(4, 8):
                id8[q] = 0
            prev_same = True
            for k in range(nz + 1):
                # column k: the four voxels (dz = 1) of this vertex, which
                # are the dz = 0 voxels of the next
                for q in range(4):
                    id8[q] = id8[q + 4]
                    val8[q] = val8[q + 4]
                    if k < nz and rows[q] >= 0:
                        v = rows[q] + k
                        id8[q + 4] = base + np.int64(ids[v])
                        val8[q + 4] = flat[v]
                    else:
                        id8[q + 4] = 0
                same = id8[4] == id8[5] and id8[4] == id8[6] and id8[4] == id8[7]
                if (same and prev_same and id8[0] == id8[4]) or k < first:
                    prev_same = same
                    continue
                prev_same = same
                if 10 * (used + 64) > 7 * len(keys):  # the most one vertex adds; a table at most 70 % full
                    return used, i, j, k
                m0 = _mask_of(id8, id8[0])
                o1 = _lowest(255 ^ m0)
                if (m0 | _mask_of(id8, id8[o1])) == 255:
                    used += _two(val8, id8, m0, o1, flat, ny, nz, a, nx, i, j, k, want, base, features, table,
                                 nsheet, qsum, spokes, doubled, contact, keys, kind, acc)
                else:
                    used += _several(val8, id8, flat, ny, nz, a, nx, i, j, k, want, base, features, table, nsheet,
                                     sheet_obj, sheet_bg, quarter, spokes, doubled, contact, keys, kind, acc, pid,
                                     pmask, pval, local)
    return used, i1, 0, 0


def vertex_pass(values: np.ndarray, pieces: np.ndarray, want: np.ndarray, table: np.ndarray, sheet_tables,
                layers: tuple[int, int] | None = None, nx: int | None = None, x0: int = 0, base: int = 0) -> dict:
    """The vertex pass (see the module docs) over a slab of a label image.

    ``values``: the slab (voxel layers ``x0 ..`` of a volume of ``nx``
    layers, default: the whole volume); ``pieces``: its :func:`label_pieces`
    numbers; ``want``: per piece (n + 1), whether its label is counted;
    ``table``: (256, F) features per configuration; ``sheet_tables``:
    :func:`isoflow.digital.closed_surfaces.sweep_tables`; ``layers``: the
    vertex layers (global, default all); ``base``: added to piece numbers in
    the pair table. Returns per piece ``features`` (n + 1, F) and
    ``doubled`` (lattice edges doubled at both ends, at their lower end),
    and the pair table's entries: ``keys`` (uint64: the smaller piece in the
    high 32 bits), ``kind`` (how they touch) and ``sums`` (4 columns: the
    sheets whose object voxel is in the smaller piece and background voxel
    in the larger, their quarters of faces, then the same the other way).
    """
    flat = unsigned(values)
    nxs, ny, nz = flat.shape
    nx = nxs if nx is None else nx
    lo, hi = (0, nx + 1) if layers is None else layers
    nsheet, sheet_obj, sheet_bg, quarter, spokes, _ = (np.asarray(t, np.int64) for t in sheet_tables)
    npieces = len(want)
    parts = slabs(hi - lo, thread_count(nxs * ny * nz))
    check_fits(len(parts) * npieces * 8 * (table.shape[1] + 1), f"the vertex pass over {npieces:,} pieces")
    features = [np.zeros((npieces, table.shape[1]), np.int64) for _ in parts]
    doubled = [np.zeros(npieces, np.int64) for _ in parts]
    args = (flat.reshape(-1), pieces.reshape(-1), ny, nz, x0, nx)
    tables = (np.asarray(table, np.int64), nsheet, quarter.sum(axis=1), sheet_obj, sheet_bg, quarter, spokes)

    def call(t):
        keys, kind, acc = np.full(1 << 12, EMPTY, np.uint64), np.full(1 << 12, NONE, np.uint8), np.zeros(
            (1 << 12, 2), np.int64)
        scratch = (np.zeros(8, np.uint64), np.zeros(8, np.int64), np.zeros(4, np.int64), np.zeros(8, np.int64),
                   np.zeros(8, np.int64), np.zeros(8, np.uint64), np.zeros((8, 8, 2), np.int64))
        used, i, j, k = 0, lo + parts[t][0], 0, 0
        while i < lo + parts[t][1]:
            used, i, j, k = _vertex_layers(*args, i, lo + parts[t][1], j, k, want.astype(np.bool_), base, features[t],
                                        *tables, doubled[t], contact_table(), keys, kind, acc, used, *scratch)
            if i < lo + parts[t][1]:
                check_fits(PAIR_BYTES * 2 * len(keys) * len(parts), f"the pairs of {npieces:,} pieces")
                keys, kind, acc = _grown(keys, kind, acc)
        full = keys != EMPTY
        low, high = acc[full] & 0xFFFFFFFF, acc[full] >> 32
        return keys[full], kind[full], np.stack([low[:, 0], high[:, 0], low[:, 1], high[:, 1]], axis=1)

    found = run([(call, t) for t in range(len(parts))])
    keys, kind, sums = (np.concatenate(cols) for cols in zip(*found))
    if len(parts) > 1:
        keys, kind, sums = merge_pairs(keys, kind, sums)
    return {"features": sum(features[1:], features[0]), "doubled": sum(doubled[1:], doubled[0]),
            "keys": keys, "kind": kind, "sums": sums}


def merge_pairs(keys: np.ndarray, kind: np.ndarray, sums: np.ndarray) -> tuple[np.ndarray, ...]:
    """Entries of several pair tables, one entry per key: the closest
    kind, the sums added (sorted by key, reduced per run of equal keys)."""
    if not len(keys):
        return keys, kind, sums
    order = np.argsort(keys, kind="stable")
    keys = keys[order]
    starts = np.flatnonzero(np.concatenate([[True], keys[1:] != keys[:-1]]))
    return (keys[starts], np.minimum.reduceat(kind[order], starts),
            np.add.reduceat(sums[order], starts, axis=0))
