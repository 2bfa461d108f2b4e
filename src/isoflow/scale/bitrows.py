"""A volume as rows of bits (numba): one bit per voxel along the last axis,
64 voxels to a machine word, and the number of runs and gaps of every row.

The passes over large volumes read each voxel row several times (the vertex
sweep reads every row for the four vertex rows around it). As bits a row of
512 voxels is eight words: the sweep finds where any of four rows changes
with a few word operations and jumps from change to change (count trailing
zeros), instead of testing every voxel. Packing reads the volume once, in
slabs on the threads, and costs 1/8 byte per voxel.

Row ``(i, j)`` of :func:`pack` holds voxel ``k`` at bit ``k % 64`` of word
``k // 64``; a row has ``nz // 64 + 1`` words, so that bit ``nz`` (the
lattice vertex past the last voxel) exists and is always clear.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from .compiled import read_only_view, run, slabs, thread_count
from .jit import njit


def integer_intrinsic(name: str, doc: str, emit):
    """An intrinsic that maps an integer to one of its type, by one LLVM
    instruction that ``emit(builder, value)`` adds.

    Examples
    --------
    >>> bits = integer_intrinsic("bits", "Set bits.", lambda builder, x: builder.ctpop(x))
    >>> int(njit(lambda x: bits(x))(np.uint64(0b1011)))
    3
    """

    def typer(typingctx, x):
        if not isinstance(x, types.Integer):
            return None

        def codegen(context, builder, signature, args):
            return emit(builder, args[0])

        return x(x), codegen

    typer.__name__ = typer.__qualname__ = name
    typer.__doc__ = doc
    return intrinsic(typer)


#: (cttz's and ctlz's flag: the result of 0 may be undefined, which keeps them one instruction)
_UNDEFINED_AT_ZERO = ir.Constant(ir.IntType(1), 1)
popcount = integer_intrinsic("popcount", "Set bits of an integer (one instruction where the CPU has it).",
                             lambda builder, x: builder.ctpop(x))
trailing_zeros = integer_intrinsic("trailing_zeros", "The number of clear bits below the lowest set bit (undefined "
                                   "for x = 0).", lambda builder, x: builder.cttz(x, _UNDEFINED_AT_ZERO))
leading_zeros = integer_intrinsic("leading_zeros", "The number of clear bits above the highest set bit (undefined "
                                  "for x = 0).", lambda builder, x: builder.ctlz(x, _UNDEFINED_AT_ZERO))


@njit(cache=True, nogil=True)
def config_at(bits, nx, ny, nz, i, j, k):
    """Configuration of lattice vertex (i, j, k) read from the bit rows of
    an (nx, ny, nz) volume (voxels outside the array are background)."""
    c = 0
    for o in range(8):
        x, y, z = i - 1 + (o & 1), j - 1 + ((o >> 1) & 1), k - 1 + (o >> 2)
        if 0 <= x < nx and 0 <= y < ny and 0 <= z < nz:
            c |= np.int64((bits[x * ny + y, z >> 6] >> np.uint64(z & 63)) & np.uint64(1)) << o
    return c


@njit(cache=True, nogil=True)
def _pack_rows(v, bits, nruns, ngaps, i0, i1):
    """Bits of rows (i, j), i0 <= i < i1, and their runs of set bits and of
    clear bits (the gaps between runs, and before the first and after the
    last where the row does not start or end with a run). Eight voxels at a
    time: a nonzero byte to a 1 in its lowest bit, then the eight lowest
    bits gathered by one multiplication."""
    _, ny, nz = v.shape
    words = bits.shape[1]
    low7, ones, gather = np.uint64(0x7F7F7F7F7F7F7F7F), np.uint64(0x0101010101010101), np.uint64(0x0102040810204080)
    one, seven, top = np.uint64(1), np.uint64(7), np.uint64(56)
    whole = nz // 8  # bytes of eight voxels
    for i in range(i0, i1):
        for j in range(ny):
            row = v[i, j]
            r = i * ny + j
            runs = 0
            carry = np.uint64(0)
            for w in range(words):
                word = np.uint64(0)
                for e in range(8):
                    q = w * 8 + e
                    if q < whole:
                        p = 8 * q
                        # (compiles to one 8-byte load)
                        x = (np.uint64(row[p]) | (np.uint64(row[p + 1]) << np.uint64(8))
                             | (np.uint64(row[p + 2]) << np.uint64(16)) | (np.uint64(row[p + 3]) << np.uint64(24))
                             | (np.uint64(row[p + 4]) << np.uint64(32)) | (np.uint64(row[p + 5]) << np.uint64(40))
                             | (np.uint64(row[p + 6]) << np.uint64(48)) | (np.uint64(row[p + 7]) << np.uint64(56)))
                        # != 0 per byte: a bool array made by .view(bool) may hold other bytes
                        x = ((((x & low7) + low7) | x) >> seven) & ones
                        word |= ((x * gather) >> top) << np.uint64(8 * e)
                    elif q == whole:
                        for k in range(8 * q, nz):
                            word |= np.uint64(row[k] != 0) << np.uint64(k - 64 * w)
                bits[r, w] = word
                runs += popcount(word & ~((word << one) | carry))
                carry = word >> np.uint64(63)
            nruns[r + 1] = runs
            if nz == 0:
                ngaps[r + 1] = 0
            else:
                first = bits[r, 0] & one
                last = (bits[r, (nz - 1) // 64] >> np.uint64((nz - 1) % 64)) & one
                ngaps[r + 1] = runs + 1 - first - last


def pack(volume: np.ndarray):
    """``(bits, run_offsets, gap_offsets)`` of a 3D volume: the bit rows,
    row ``(i, j)`` at ``i * ny + j`` (uint64, shape ``(nx * ny + 1, nz // 64
    + 1)``: the last row is clear, for rows outside the array), and for the
    runs and for the gaps where each row's start in their C-order numbering
    (int64, two more than rows: the clear row has none)."""
    # read-only whether or not the volume is: one compile for both
    v = read_only_view(np.ascontiguousarray(volume, dtype=bool).view(np.uint8))
    nx, ny, nz = v.shape
    bits = np.empty((nx * ny + 1, nz // 64 + 1), np.uint64)
    bits[-1] = 0
    nruns = np.zeros(nx * ny + 2, np.int64)
    ngaps = np.zeros(nx * ny + 2, np.int64)
    run([(_pack_rows, v, bits, nruns, ngaps, a, b) for a, b in slabs(nx, thread_count(v.size))])
    return bits, np.cumsum(nruns), np.cumsum(ngaps)


@njit(cache=True, nogil=True)
def _row_extents(bits, counts, sums, first, last, r0, r1):
    """Per row ``r0 <= r < r1`` its set bits, the sum of their positions
    and the lowest and highest (-1 in a clear row). A word's position sum
    is that of its bit planes: the bits whose position has bit ``j`` set,
    counted ``2^j`` times each."""
    planes = (np.uint64(0xAAAAAAAAAAAAAAAA), np.uint64(0xCCCCCCCCCCCCCCCC), np.uint64(0xF0F0F0F0F0F0F0F0),
              np.uint64(0xFF00FF00FF00FF00), np.uint64(0xFFFF0000FFFF0000), np.uint64(0xFFFFFFFF00000000))
    zero = np.uint64(0)
    for r in range(r0, r1):
        count, total, lo, hi = 0, 0, -1, -1
        for w in range(bits.shape[1]):
            u = bits[r, w]
            if u == zero:
                continue
            n = np.int64(popcount(u))
            count += n
            total += 64 * w * n
            for j in range(6):
                total += np.int64(popcount(u & planes[j])) << j
            if lo < 0:
                lo = 64 * w + np.int64(trailing_zeros(u))
            hi = 64 * w + 63 - np.int64(leading_zeros(u))
        counts[r], sums[r], first[r], last[r] = count, total, lo, hi


def row_extents(bits: np.ndarray, threads: int = 1) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(counts, sums, first, last)`` of the rows of :func:`pack` (the
    clear last row left out): each row's set bits, the sum of their
    positions along the row, the lowest and the highest (-1 where none),
    int64, on up to ``threads`` threads.

    Examples
    --------
    >>> v = np.zeros((1, 2, 70), bool); v[0, 1, [3, 69]] = True
    >>> [a.tolist() for a in row_extents(pack(v)[0])]
    [[0, 2], [0, 72], [-1, 3], [-1, 69]]
    """
    rows = bits.shape[0] - 1
    counts, sums, first, last = (np.empty(rows, np.int64) for _ in range(4))
    run([(_row_extents, bits, counts, sums, first, last, a, b) for a, b in slabs(rows, threads)])
    return counts, sums, first, last


@njit(cache=True, nogil=True, inline="always")
def word(bits, row, w):
    """Word ``w`` of a row, zero for row -1 (outside the array) and past
    the row's words."""
    if row < 0 or w >= bits.shape[1]:
        return np.uint64(0)
    return bits[row, w]


@njit(cache=True, nogil=True, inline="always")
def around(i, j, nx, ny):
    """The rows of the four voxel rows around vertex row ``(i, j)`` of an
    ``nx x ny`` grid of rows: row ``q = dx + 2 dy`` is voxel row ``(i - 1 +
    dx, j - 1 + dy)``, -1 where that is outside the array."""
    r0 = (i - 1) * ny + j - 1 if i >= 1 and j >= 1 else -1
    r1 = i * ny + j - 1 if i < nx and j >= 1 else -1
    r2 = (i - 1) * ny + j if i >= 1 and j < ny else -1
    r3 = i * ny + j if i < nx and j < ny else -1
    return r0, r1, r2, r3


@njit(cache=True, nogil=True, inline="always")
def shifted(u, previous):
    """The word whose bit ``k`` is voxel ``k - 1`` of the row: ``u`` moved
    up by one, with the top bit of the row's previous word."""
    return (u << np.uint64(1)) | (previous >> np.uint64(63))


@njit(cache=True, nogil=True, inline="always")
def octant_planes(bits, rows, w, previous):
    """The eight octant planes of word ``w`` of a vertex row: ``(s0, s1,
    s2, s3, u0, u1, u2, u3)``, ``u_q`` word ``w`` of voxel row ``rows[q]``
    (see :func:`around`) and ``s_q`` the same shifted by one
    (:func:`shifted`; ``previous``: the rows' words ``w - 1``). Unused
    rows are -1 (a 2D vertex row has two)."""
    u0, u1, u2, u3 = word(bits, rows[0], w), word(bits, rows[1], w), word(bits, rows[2], w), word(bits, rows[3], w)
    return (shifted(u0, previous[0]), shifted(u1, previous[1]), shifted(u2, previous[2]), shifted(u3, previous[3]),
            u0, u1, u2, u3)


@njit(cache=True, nogil=True, inline="always")
def configuration(s0, s1, s2, s3, u0, u1, u2, u3, k):
    """The configuration of vertex ``k`` of a word, from its octant planes
    (octant ``q`` is ``s_q``, voxel ``k - 1``; octant ``q + 4`` is ``u_q``,
    voxel ``k``)."""
    one, kk = np.uint64(1), np.uint64(k)
    return (((s0 >> kk) & one) | (((s1 >> kk) & one) << np.uint64(1)) | (((s2 >> kk) & one) << np.uint64(2))
            | (((s3 >> kk) & one) << np.uint64(3)) | (((u0 >> kk) & one) << np.uint64(4))
            | (((u1 >> kk) & one) << np.uint64(5)) | (((u2 >> kk) & one) << np.uint64(6))
            | (((u3 >> kk) & one) << np.uint64(7)))
