"""The moves of one flow step carried out cell by cell on the grid refined
twice, each change only where the cell is a simple point (numba): the
compiled form of :func:`isoflow.flow.guard.realise_moves`.

The refined grid is never built: new voxel (lattice vertex) ``w`` is a
block of ``2^n`` fine cells whose cell ``e`` lies in octant ``e`` of
``w``, so the old object's fine grid *is* its configuration array, one
byte per vertex, bit ``e`` for cell ``e`` (:func:`blocks`). The ``3^n``
fine cells around cell ``e`` of block ``w`` lie in the ``2^n`` blocks
``w + delta`` with ``delta_d`` in ``{-1, 0}`` where ``e_d = 0`` and ``{0,
1}`` where ``e_d = 1``; their packed neighbourhood (the code of
:func:`isoflow.digital.simple.neighbourhood_codes`: offset ``o`` at bit
``sum_d (o_d + 1) 3^d``) is the OR of one table look-up per block byte.

Whether a code is simple is Bertrand's test (both topological numbers 1,
see :mod:`isoflow.digital.simple`) on the 27-bit board, counted by
dilations of bit masks and remembered in a small hash table per process
(:func:`_memo`): real surfaces repeat a few hundred codes, and a table that
stays in the cache answers them sooner than any table over all 2^26 codes.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .bitrows import around, configuration, octant_planes, popcount, trailing_zeros
from .compiled import run, slabs, thread_count
from .jit import njit

_U1 = np.uint64(1)


@cache
def _board(ndim: int) -> dict:
    """The ``3^n`` bitboard's masks: per axis the shift and the cells that
    may move up (``lo``) or down (``hi``) along it; the face neighbours, the
    18- (3D) or 8-neighbourhood (2D), the whole board less its centre
    (``face``, ``near``, ``all``)."""
    coords = np.array([[(i // 3**d) % 3 for d in range(ndim)] for i in range(3**ndim)])
    l1 = np.abs(coords - 1).sum(1)

    def mask(sel):
        return int(sum(1 << int(i) for i in np.flatnonzero(sel)))

    return {
        "steps": np.array([3**d for d in range(ndim)], np.uint32),
        "lo": np.array([mask(coords[:, d] < 2) for d in range(ndim)], np.uint32),
        "hi": np.array([mask(coords[:, d] > 0) for d in range(ndim)], np.uint32),
        "face": mask(l1 == 1),
        "near": mask((l1 >= 1) & (l1 <= 2)),
        "all": mask(l1 >= 1),
    }


@njit(cache=True, nogil=True)
def _dilate(s, steps, lo, hi, full):
    out = s
    for d in range(len(steps)):
        src = out if full else s
        out = out | ((src & lo[d]) << steps[d]) | ((src & hi[d]) >> steps[d])
    return out


@njit(cache=True, nogil=True)
def _one_component(present, seeds, steps, lo, hi, full):
    """Whether exactly one component of ``present`` meets ``seeds``."""
    left = present
    count = 0
    while left & seeds:
        cand = left & seeds
        comp = cand & (~cand + np.uint32(1))
        while True:
            grown = _dilate(comp, steps, lo, hi, full) & left
            if grown == comp:
                break
            comp = grown
        count += 1
        if count > 1:
            return False
        left &= ~comp
    return count == 1


@njit(cache=True, nogil=True)
def _simple(code, face, steps, lo, hi, masks):
    """Both topological numbers of the packed neighbourhood are 1
    (:func:`isoflow.digital.simple.topological_numbers`): ``face`` for the
    face connectivity (6, 4) of the object; ``masks``: face, near, all."""
    f, near, whole = masks[0], masks[1], masks[2]
    ob = code & whole
    bg = ~code & whole
    if face:
        return _one_component(ob & near, f, steps, lo, hi, False) and _one_component(bg, whole, steps, lo, hi, True)
    return _one_component(ob, whole, steps, lo, hi, True) and _one_component(bg & near, f, steps, lo, hi, False)


#: a remembered code's slot in the table of :func:`_memo`: the code, this
#: bit (taken), and whether it is simple
_TAKEN, _SIMPLE = np.uint32(1 << 31), np.uint32(1 << 30)
_GOLDEN, _LOW32 = np.uint64(0x9E3779B1), np.uint64(0xFFFFFFFF)


@njit(cache=True, nogil=True, inline="always")
def _slot(code, shift):
    """Fibonacci hashing of a code into a table of ``2^(32 - shift)`` slots."""
    return np.int64(((np.uint64(code) * _GOLDEN) & _LOW32) >> np.uint64(shift))


@njit(cache=True, nogil=True, inline="always")
def _look_up(known, code, shift, last):
    """``(found, slot)``: 1 or 0 where the table of :func:`_memo` knows
    whether the code is simple, -1 where not, with the free slot for it."""
    slot, mark = _slot(code, shift), code | _TAKEN
    while True:
        got = known[slot]
        if got == 0:
            return -1, slot
        if (got & ~_SIMPLE) == mark:
            return (1 if got & _SIMPLE else 0), slot
        slot = (slot + 1) & last


@njit(cache=True, nogil=True)
def _decide(known, fill, slot, code, face, steps, lo, hi, masks):
    """Test a code the table does not know (1: simple, 0: not) and put it
    in its free slot, while the table is at most three quarters full
    (``fill[0]``: slots taken)."""
    yes = _simple(code, face, steps, lo, hi, masks)
    if 4 * fill[0] < 3 * len(known):
        known[slot] = code | _TAKEN | (_SIMPLE if yes else np.uint32(0))
        fill[0] += 1
    return 1 if yes else 0


@njit(cache=True, nogil=True)
def _rehash(old, new, bits):
    size = len(new)
    for got in old:
        if got:
            slot = _slot(got & ~(_TAKEN | _SIMPLE), 32 - bits)
            while new[slot]:
                slot = (slot + 1) & (size - 1)
            new[slot] = got


_MEMOS: dict = {}


def _memo(ndim: int, face: bool, thread: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The codes found simple or not in this process, per dimension, kind
    of connectivity and thread (so that threads never write one table):
    ``(table, fill)``, the table twice as large once it is half full (at
    most 2^22 slots, 16 MiB)."""
    key = (ndim, face, thread)
    table, fill = _MEMOS.get(key, (None, None))
    if table is None:
        table, fill = np.zeros(1 << 12, np.uint32), np.array([0, 12], np.int64)
    elif 2 * fill[0] > len(table) and fill[1] < 22:
        fill[1] += 1
        grown = np.zeros(1 << int(fill[1]), np.uint32)
        _rehash(table, grown, fill[1])
        table = grown
    _MEMOS[key] = (table, fill)
    return table, fill


@njit(cache=True, nogil=True)
def _simple_codes(codes, face, steps, lo, hi, masks, known, fill, out):
    shift, last = 32 - fill[1], len(known) - 1
    for i in range(len(codes)):
        code = np.uint64(codes[i])  # as _batch's: one compile of _decide for both
        found, slot = _look_up(known, code, shift, last)
        if found < 0:
            found = _decide(known, fill, slot, code, face, steps, lo, hi, masks)
        out[i] = found == 1


def _board_tuples(ndim: int):
    """The board's masks as tuples (passed by value: a kernel's inner loop
    then holds no array reference to count): ``steps, lo, hi, masks``."""
    b = _board(ndim)
    steps, lo, hi = (tuple(np.uint32(x) for x in b[k]) for k in ("steps", "lo", "hi"))
    return steps, lo, hi, tuple(np.uint32(b[k]) for k in ("face", "near", "all"))


def simple(codes: np.ndarray, ndim: int, face: bool) -> np.ndarray:
    """Whether each packed neighbourhood is that of a simple point: the
    compiled test that :func:`realise` makes.

    Parameters
    ----------
    codes : numpy.ndarray
        Packed ``3^n`` neighbourhoods, as
        :func:`isoflow.digital.simple.neighbourhood_codes` gives them.
    ndim : int
        2 or 3.
    face : bool
        The object's connectivity is the face one (4, 6), else the full one.

    Returns
    -------
    numpy.ndarray
        bool, one per code.

    Notes
    -----
    Bertrand's topological numbers are both 1 (``T = 1``, ``T-bar = 1``).

    Examples
    --------
    >>> import numpy as np
    >>> simple(np.array([0b000001000, 0b101000101]), 2, True).tolist()  # one neighbour; four corners only
    [True, False]
    """
    codes = np.ascontiguousarray(codes, np.uint32)
    out = np.empty(len(codes), np.bool_)
    _simple_codes(codes, face, *_board_tuples(ndim), *_memo(ndim, face), out)
    return out


@cache
def _code_tables(ndim: int) -> tuple[np.ndarray, np.ndarray]:
    """Per octant ``e`` (cell of a block) and block ``b`` of its
    neighbourhood (``delta_d = b_d - 1 + e_d``): the code bits that each
    value of block ``b``'s byte sets (``tables[e, b, byte]``, centre left
    out), and the offsets ``delta`` (``deltas[e, b]``, per axis)."""
    cells = 1 << ndim
    tables = np.zeros((cells, cells, 1 << cells), np.uint32)
    deltas = np.zeros((cells, cells, ndim), np.int64)
    for e in range(cells):
        ev = [(e >> d) & 1 for d in range(ndim)]
        for b in range(cells):
            deltas[e, b] = [((b >> d) & 1) - 1 + ev[d] for d in range(ndim)]
        for idx in range(3**ndim):
            o = [(idx // 3**d) % 3 - 1 for d in range(ndim)]
            if not any(o):
                continue
            pos = [ev[d] + o[d] for d in range(ndim)]  # -1 .. 2
            delta = [p // 2 for p in pos]
            b = sum((dl + 1 - ev[d]) << d for d, dl in enumerate(delta))
            cell = sum((p % 2) << d for d, p in enumerate(pos))
            for byte in range(1 << cells):
                if byte >> cell & 1:
                    tables[e, b, byte] |= 1 << idx
    return tables, deltas


@njit(cache=True, nogil=True, inline="always")
def _fill_runs(state, at, word, value):
    """``state[at + k] = value`` for every set bit ``k`` of ``word``, a run
    of bits at a time."""
    while word:
        k = np.int64(trailing_zeros(word))
        rest = ~(word >> np.uint64(k))
        n = 64 - k if rest == 0 else np.int64(trailing_zeros(rest))
        state[at + k: at + k + n] = value
        word &= ~((~np.uint64(0) >> np.uint64(64 - n)) << np.uint64(k))


@njit(cache=True, nogil=True)
def _blocks_layers(bits, nx, ny, keep, state, strides, i0, i1, pending, goal, start, write, planar):
    """Configuration bytes of vertex rows ``i0 <= i < i1`` of a 3D volume
    into the padded ``state`` (flat, ``strides``), and the boundary
    vertices (neither empty nor full) from ``pending[start]`` on, with
    their goal, the keep bit. Without ``write`` only counts the boundary
    vertices (the arrays are sized by that count: growing them in the loop
    would count references to them on every word). Returns the count.
    ``planar``: a 2D image as the layer ``x = 0`` (vertex layer 1 asked;
    its vertices' octants ``dx = 0`` are the pixels; ``keep`` has that
    layer's rows only, ``strides`` the image's padded vertex grid's after a
    0)."""
    nwords = keep.shape[1]
    count = start
    full = 15 if planar else 255
    for i in range(i0, i1):
        for j in range(ny + 1):
            rows = around(i, j, nx, ny)
            base = (i + 1) * strides[0] + (j + 1) * strides[1] + 1
            v = (i - i0 if planar else i) * (ny + 1) + j
            previous = (np.uint64(0), np.uint64(0), np.uint64(0), np.uint64(0))
            for w in range(nwords):
                s0, s1, s2, s3, u0, u1, u2, u3 = octant_planes(bits, rows, w, previous)
                previous = (u0, u1, u2, u3)
                inside = s0 & s2 & u0 & u2 if planar else s0 & s1 & s2 & s3 & u0 & u1 & u2 & u3
                boundary = (s0 | s1 | s2 | s3 | u0 | u1 | u2 | u3) & ~inside
                if not write:
                    count += popcount(boundary)
                    continue
                at = base + 64 * w
                _fill_runs(state, at, inside, full)
                m = boundary
                while m:
                    k = trailing_zeros(m)
                    m &= m - _U1
                    c = configuration(s0, s1, s2, s3, u0, u1, u2, u3, k)
                    if planar:  # octants 0, 2, 4, 6 are pixels 0, 1, 2, 3
                        c = (c & 1) | ((c >> 1) & 2) | ((c >> 2) & 4) | ((c >> 3) & 8)
                    state[at + k] = np.uint8(c)
                    pending[count] = at + k
                    goal[count] = np.uint8((keep[v, w] >> k) & _U1)
                    count += 1
    return count


def blocks(bits: np.ndarray, shape: tuple[int, ...], keep: np.ndarray):
    """The old object on the grid refined twice, and the moves to realise.

    Parameters
    ----------
    bits : numpy.ndarray
        The volume's bit rows (a 2D volume as one layer).
    shape : tuple of int
        The volume's shape (2D or 3D).
    keep : numpy.ndarray
        The step's bit rows (:func:`isoflow.scale.flowbits.moves3` or
        ``moves2``).

    Returns
    -------
    tuple
        ``(state, padded shape, pending, goal)``: the configuration bytes,
        one per lattice vertex, in an array padded by one vertex each side
        (flat); the boundary vertices (flat indices into ``state``) and
        their moves (1 outward, 0 inward).

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow.scale import bitrows
    >>> bits = bitrows.pack(np.ones((1, 1, 1), bool))[0]
    >>> state, padded, pending, goal = blocks(bits, (1, 1, 1), np.zeros((5, 1), np.uint64))
    >>> padded, len(pending), sorted(int(state[p]) for p in pending)[:2]
    ((4, 4, 4), 8, [1, 2])
    """
    nd = len(shape)
    padded = tuple(s + 3 for s in shape)
    state = np.zeros(int(np.prod(padded)), np.uint8)
    strides = np.array([int(np.prod(padded[d + 1:])) for d in range(nd)], np.int64)
    none = np.zeros(0, np.int64), np.zeros(0, np.uint8)
    if nd == 2:  # the image as the layer x = 0 of a volume, its vertex layer 1
        layers, strides, parts = (1, *shape), np.array([0, strides[0]]), [(1, 2)]
    else:
        layers = shape
        parts = slabs(shape[0] + 1, thread_count(int(np.prod([s + 1 for s in shape]))))
    nx, ny, _ = layers
    counts = run([(_blocks_layers, bits, nx, ny, keep, state, strides, a, b, *none, 0, False, nd == 2)
                  for a, b in parts])
    starts = np.concatenate([[0], np.cumsum(counts)])
    pending, goal = np.empty(int(starts[-1]), np.int64), np.empty(int(starts[-1]), np.uint8)
    run([(_blocks_layers, bits, nx, ny, keep, state, strides, a, b, pending, goal, int(start), True, nd == 2)
         for (a, b), start in zip(parts, starts)])
    return state, padded, pending, goal


@njit(cache=True, nogil=True)
def _batch(state, pending, need, e, i0, i1, tables, offsets, steps, lo, hi, masks, known, fill, face):
    """Cell ``e`` of the blocks ``pending[i0:i1]`` that still need it
    (``need``), each changed where it is simple. The cells of one octant
    are two fine cells apart, outside each other's neighbourhoods, so any
    order (and any split among threads) gives the same. Returns whether
    any cell changed."""
    shift, last = 32 - fill[1], len(known) - 1
    bit = np.uint8(1 << e)
    changed = False
    for idx in range(i0, i1):
        if not need[idx] & bit:
            continue
        p = pending[idx]
        code = np.uint64(0)  # the type numba gives ``|=`` here: _decide is compiled for it alone
        for b in range(tables.shape[0]):
            code |= tables[e, b, state[p + offsets[e, b]]]
        found, slot = _look_up(known, code, shift, last)
        if found < 0:
            found = _decide(known, fill, slot, code, face, steps, lo, hi, masks)
        if found:
            state[p] ^= bit
            need[idx] ^= bit
            changed = True
    return changed


@njit(cache=True, nogil=True)
def _needs(state, pending, goal, full):
    """Per block, the cells not yet at its goal."""
    need = np.empty(len(pending), np.uint8)
    for idx in range(len(pending)):
        need[idx] = state[pending[idx]] ^ (full if goal[idx] else 0)
    return need


@njit(cache=True, nogil=True)
def _settle(pending, goal, need, n, changed, flip, reversed_, flips, full):
    """The end of a sweep: the blocks at their goal leave ``pending``;
    when no cell changed, every block left has its move reversed, once
    (``flip``). Returns ``(blocks left, reversed so far or -1, done)``."""
    m = 0
    for idx in range(n):
        if need[idx]:
            pending[m], goal[m], need[m] = pending[idx], goal[idx], need[idx]
            m += 1
    if changed:
        return m, reversed_, False
    if not flip or reversed_ >= 0 or m == 0:
        return m, reversed_, True
    for idx in range(m):
        goal[idx] ^= 1
        need[idx] ^= full
        flips[idx] = pending[idx]
    return m, m, False


@njit(cache=True, nogil=True)
def _realise(state, pending, goal, tables, offsets, steps, lo, hi, masks, known, fill, face, flip, max_sweeps, flips,
             backward):
    """The sweeps of :func:`realise` on one thread (in place on ``state``,
    ``pending`` and ``goal``). Returns ``(stuck, flipped)``: the first
    ``stuck`` of ``pending`` are left half-way, the first ``flipped`` of
    ``flips`` had their move reversed."""
    n = len(pending)
    cells = tables.shape[0]
    full = (1 << cells) - 1
    need = _needs(state, pending, goal, full)
    reversed_ = np.int64(-1)  # not literals: numba would compile _settle once more for them
    for _ in range(max_sweeps):
        changed = np.bool_(False)
        for k in range(cells):
            e = cells - 1 - k if backward else k
            changed |= _batch(state, pending, need, e, 0, n, tables, offsets, steps, lo, hi, masks, known, fill, face)
        n, reversed_, done = _settle(pending, goal, need, n, changed, flip, reversed_, flips, full)
        if done:
            break
    return n, max(reversed_, 0)


#: from this many boundary blocks a step's cells are changed on threads,
#: each batch (one octant) split among them: below it, handing a batch to
#: a thread costs more than it saves
THREADED_BLOCKS = 50_000


def _realise_threaded(state, pending, goal, tables, offsets, board_, nd, face, flip, max_sweeps, flips, threads,
                      backward):
    """:func:`_realise` with every batch split among ``threads`` threads
    (each with its own table of codes, :func:`_memo`)."""
    from concurrent.futures import ThreadPoolExecutor

    n = len(pending)
    cells = tables.shape[0]
    full = (1 << cells) - 1
    need = _needs(state, pending, goal, full)
    memos = [_memo(nd, face, t) for t in range(threads)]
    reversed_ = -1
    with ThreadPoolExecutor(threads, thread_name_prefix="isoflow-realise") as pool:
        for _ in range(max_sweeps):
            parts = slabs(n, threads)
            changed = False
            for e in (range(cells - 1, -1, -1) if backward else range(cells)):
                futures = [pool.submit(_batch, state, pending, need, e, a, b, tables, offsets, *board_, *memos[t], face)
                           for t, (a, b) in enumerate(parts)]
                changed |= any([f.result() for f in futures])
            n, reversed_, done = _settle(pending, goal, need, n, changed, flip, reversed_, flips, full)
            if done:
                break
    return n, max(reversed_, 0)


def _classes(pending: np.ndarray, padded: tuple[int, ...]) -> np.ndarray:
    """Per block (flat index into the padded vertex grid): its vertex's
    class, the vertex modulo 2 in the unpadded grid, axis ``d`` at bit
    ``n - 1 - d`` (``itertools.product``'s order)."""
    coords = np.unravel_index(pending, padded)
    return sum(((c - 1) & 1) << (len(padded) - 1 - d) for d, c in enumerate(coords))


def _realise_by_class(state, pending, goal, tables, offsets, board_, memo, face, flip, max_sweeps, flips, backward,
                      padded):
    """:func:`_realise` with the blocks of one class after the other, each
    class octant by octant. The blocks are sorted by class, stably, and
    stay so as those done leave (:func:`_settle` keeps their order), so a
    class is one run of ``pending`` and a batch one call of :func:`_batch`."""
    cells = tables.shape[0]
    full = (1 << cells) - 1
    order = np.argsort(_classes(pending, padded), kind="stable")
    pending[:], goal[:] = pending[order], goal[order]
    need = _needs(state, pending, goal, full)
    n, reversed_ = len(pending), np.int64(-1)
    for _ in range(max_sweeps):
        bounds = np.searchsorted(_classes(pending[:n], padded), np.arange(cells + 1))
        changed = False
        for k in range(cells):
            for e in (range(cells - 1, -1, -1) if backward else range(cells)):
                changed |= _batch(state, pending, need, e, bounds[k], bounds[k + 1], tables, offsets, *board_, *memo,
                                  face)
        n, reversed_, done = _settle(pending, goal, need, n, changed, flip, reversed_, flips, full)
        if done:
            break
    return n, max(reversed_, 0)


def realise(state: np.ndarray, padded: tuple[int, ...], pending: np.ndarray, goal: np.ndarray, face: bool,
            flip: bool = True, max_sweeps: int = 256, backward: bool = False,
            by_class: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Carry out the moves ``goal`` of the blocks ``pending`` (from
    :func:`blocks`) one fine cell at a time, a cell only when it is simple
    for the object's connectivity (``face``: 6 or 4), as
    :func:`isoflow.flow.guard.realise_moves` does: octant after octant,
    sweeps until nothing changes, then (``flip``) every block still pending
    has its move reversed once. Large steps (:data:`THREADED_BLOCKS`) split
    each octant's batch among the threads.

    Parameters
    ----------
    state, padded, pending, goal
        As :func:`blocks` gives them; ``state``, ``pending`` and ``goal``
        are changed in place.
    face : bool
        The object's connectivity is the face one (6, 4).
    flip : bool
        Reverse the moves of the blocks left stuck, once.
    max_sweeps : int
        Sweeps at most.
    backward : bool
        Take the octants in the reverse order (``realise_moves``'
        ``backward``: the flow reverses it on every other lattice).
    by_class : bool
        The blocks of one class (vertex modulo 2) after the other, each
        class octant by octant, on one thread (``realise_moves``'
        ``by_class``: the order in which a topology change is placed).

    Returns
    -------
    tuple of numpy.ndarray
        ``(stuck, reversed)``: the flat indices (into ``state``) of the
        blocks left half-way and of those whose move was reversed.

    Notes
    -----
    The flow step by simple deformations (Theorem 21; see
    :mod:`isoflow.flow.guard`).

    Examples
    --------
    >>> import numpy as np
    >>> from isoflow.scale import bitrows
    >>> bits = bitrows.pack(np.ones((2, 2, 2), bool))[0]
    >>> keep = np.zeros((10, 1), np.uint64); keep[4] = 2  # the centre vertex (1, 1, 1)
    >>> cells = blocks(bits, (2, 2, 2), keep)
    >>> [len(x) for x in realise(*cells, face=True)]  # no block stuck, no move reversed
    [0, 0]
    """
    nd = len(padded)
    tables, deltas = _code_tables(nd)
    strides = np.array([int(np.prod(padded[d + 1:])) for d in range(nd)], np.int64)
    offsets = deltas @ strides
    board_ = _board_tuples(nd)
    flips = np.empty(len(pending), np.int64)
    threads = thread_count(len(pending) * (1_000_000 // THREADED_BLOCKS))
    if by_class:
        stuck, flipped = _realise_by_class(state, pending, goal, tables, offsets, board_, _memo(nd, face), face, flip,
                                           max_sweeps, flips, backward, padded)
    elif threads > 1 and len(pending) >= THREADED_BLOCKS:
        stuck, flipped = _realise_threaded(state, pending, goal, tables, offsets, board_, nd, face, flip, max_sweeps,
                                           flips, threads, backward)
    else:
        stuck, flipped = _realise(state, pending, goal, tables, offsets, *board_, *_memo(nd, face), face, flip,
                                  max_sweeps, flips, backward)
    return pending[:stuck].copy(), flips[:flipped].copy()
