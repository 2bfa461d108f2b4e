"""The shortest decimal text of a float, as Python's ``repr`` writes it
(numba): Giulietti's Schubfach algorithm.

A table's non-integer floats (a label's centroid, a volume in world units)
are written as :mod:`json` and :mod:`csv` write them: ``repr``, the
shortest decimal that reads back as the same float, the one nearest the
float where several are that short. ``repr`` makes a Python string per
value; here a float column becomes its digits in the rows of a byte
matrix, as :mod:`isoflow.scale.text_rows` does for integers.

The digits come from Schubfach (R. Giulietti, "The Schubfach way to render
doubles", 2020; the algorithm of Java's ``Double.toString`` since JDK 19):
with ``v = c 2^q`` (``c`` the 53-bit significand), one 126-bit power of
ten ``g ~ 10^-k`` (a table, exact from Python's integers) scales ``4c`` and
the two ends of ``v``'s rounding interval to ``vb``, ``vbl``, ``vbr``
(each rounded down with a sticky bit), whose quotient by 4 holds 16 or 17
digits. The shortest decimal in the interval is then one of ``s = vb / 4``
less its last digit, that plus ten, ``s`` or ``s + 1`` (the paper's
theorem), the nearest of them to ``v``, ties to an even last digit, as
``repr`` chooses. The layout is ``repr``'s: positional while the decimal
point lies from 4 places left of the first digit to 16 right of it
(``0.0001``, ``1000000000000000.0``), else with an exponent of two digits
at least (``1e-05``, ``1e+16``).

Subnormal floats (below 2.2e-308) are left to ``repr``: they do not occur
in a table's measures, and their few digits need the paper's special case.
"""

from __future__ import annotations

from functools import cache

import numpy as np
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from .jit import njit

#: the longest text: sign, 17 digits, the point and ``e-308``
FLOAT_WIDTH = 24

#: the powers of ten of the table: k from the smallest normal float's
#: floor(log10 2^q) - 1 to the largest's
_K_MIN, _K_MAX = -325, 292


def _flog2pow10(e: int) -> int:
    """floor(e log2 10), as the compiled code computes it."""
    return (e * 913_124_641_741) >> 38


@cache
def power_table() -> np.ndarray:
    """(K, 2) uint64: for ``k = _K_MIN ..``, ``g = floor(10^-k 2^-r) + 1``
    with ``r`` such that ``2^125 <= g - 1 < 2^126``, as its high and low
    63 bits (the paper's g1, g0). Exact: Python's integers.

    Examples
    --------
    >>> g1, g0 = (int(x) for x in power_table()[0 - _K_MIN])   # k = 0: 10^0 = 2^125 2^-125
    >>> (g1 << 63) + g0 == 2**125 + 1
    True
    """
    out = np.zeros((_K_MAX - _K_MIN + 1, 2), np.uint64)
    for i, k in enumerate(range(_K_MIN, _K_MAX + 1)):
        e = -k
        r = _flog2pow10(e) - 125
        num, den = (10**e, 1) if e >= 0 else (1, 10**-e)
        if r >= 0:
            den <<= r
        else:
            num <<= -r
        g = num // den + 1
        assert 2**125 < g <= 2**126, (k, g.bit_length())  # the shift formula holds here
        out[i] = g >> 63, g & (2**63 - 1)
    return out


@intrinsic
def _mulhi(typingctx, a, b):
    """The high 64 bits of the 128-bit product of two uint64: one
    multiplication of the processor, in LLVM's 128-bit integers (numba has
    none: four 32-bit products and their carries would stand for it)."""
    sig = types.uint64(types.uint64, types.uint64)

    def codegen(context, builder, signature, args):
        wide = ir.IntType(128)
        product = builder.mul(builder.zext(args[0], wide), builder.zext(args[1], wide))
        return builder.trunc(builder.lshr(product, ir.Constant(wide, 64)), ir.IntType(64))

    return sig, codegen


@njit(cache=True, nogil=True, inline="always")
def _rop(g1, g0, cp):
    """``g cp / 2^127`` rounded down, with a sticky last bit where it is
    not whole (the paper's ``rop``)."""
    mask63 = np.uint64(0x7FFFFFFFFFFFFFFF)
    x1 = _mulhi(g0, cp)
    y0 = g1 * cp
    y1 = _mulhi(g1, cp)
    z = (y0 >> np.uint64(1)) + x1
    vbp = y1 + (z >> np.uint64(63))
    return vbp | (((z & mask63) + mask63) >> np.uint64(63))


@njit(cache=True, nogil=True)
def _digits(c, q, powers):
    """The shortest decimal ``f 10^e`` in the rounding interval of
    ``c 2^q`` (a normal float), the nearest of those to it: ``(f, e)``."""
    out = c & np.uint64(1)
    cb = c << np.uint64(2)
    cbr = cb + np.uint64(2)
    if c != np.uint64(1 << 52) or q == -1074:
        cbl = cb - np.uint64(2)
        k = (q * 661_971_961_083) >> 41  # floor(q log10 2)
    else:  # a power of two: the interval below is half as wide
        cbl = cb - np.uint64(1)
        k = (q * 661_971_961_083 - 274_743_187_321) >> 41  # floor(log10(3/4 2^q))
    h = np.uint64(q + ((-k * 913_124_641_741) >> 38) + 2)
    g1, g0 = powers[k - _K_MIN, 0], powers[k - _K_MIN, 1]
    vb = _rop(g1, g0, cb << h)
    vbl = _rop(g1, g0, cbl << h)
    vbr = _rop(g1, g0, cbr << h)
    s = vb >> np.uint64(2)
    if s >= np.uint64(100):  # always here (s has 16 or 17 digits); Java's two-digit rule for subnormals
        sp10 = np.uint64(10) * _mulhi(s, np.uint64(1844674407370955168))  # 10 floor(s / 10)
        tp10 = sp10 + np.uint64(10)
        upin = vbl + out <= sp10 << np.uint64(2)
        wpin = (tp10 << np.uint64(2)) + out <= vbr
        if upin != wpin:
            return (sp10 if upin else tp10), k
    t = s + np.uint64(1)
    uin = vbl + out <= s << np.uint64(2)
    win = (t << np.uint64(2)) + out <= vbr
    if uin != win:
        return (s if uin else t), k
    twice = (s + t) << np.uint64(1)
    below = vb < twice or (vb == twice and (s & np.uint64(1)) == np.uint64(0))
    return (s if below else t), k


@njit(cache=True, nogil=True, inline="always")
def _put(chars, r, at, byte):
    """Byte ``byte`` before place ``at`` of row ``r``; returns the new place."""
    # unsigned places: numba checks a signed index for a negative one at every byte written
    chars[np.uint64(r), np.uint64(at - 1)] = byte
    return at - 1


@njit(cache=True, nogil=True)
def shortest_cells(bits, powers, chars, lengths):
    """The float of bits ``bits[r]`` (a float64 array viewed as uint64) as
    ``repr`` writes it, right-aligned in row ``r`` of ``chars`` (uint8,
    :data:`FLOAT_WIDTH` wide), its length in ``lengths[r]``; NaN,
    infinities and subnormal floats (length 0) are left to the caller.
    ``powers``: :func:`power_table`. Written from the right, last digit
    first.

    Examples
    --------
    >>> values = np.array([0.1, -2.5e-07, 1e16, 123.0, -0.0, 5e-324])
    >>> chars = np.zeros((len(values), FLOAT_WIDTH), np.uint8)
    >>> lengths = np.zeros(len(values), np.int64)
    >>> shortest_cells(values.view(np.uint64), power_table(), chars, lengths)
    >>> [bytes(row[FLOAT_WIDTH - n:]).decode() for row, n in zip(chars, lengths)]
    ['0.1', '-2.5e-07', '1e+16', '123.0', '-0.0', '']
    """
    ten = np.uint64(10)
    zero = np.uint64(48)  # "0"
    for r in range(len(bits)):
        b = bits[r]
        frac = b & np.uint64((1 << 52) - 1)
        bq = np.int64((b >> np.uint64(52)) & np.uint64(0x7FF))
        if bq == 0x7FF or (bq == 0 and frac != np.uint64(0)):
            lengths[r] = 0  # NaN, infinity, subnormal: the caller's
            continue
        if bq == 0:
            f, e = np.uint64(0), 0
        else:
            c = frac | np.uint64(1 << 52)
            q = bq - 1075
            if 0 < -q < 53 and ((c >> np.uint64(-q)) << np.uint64(-q)) == c:
                f, e = c >> np.uint64(-q), 0  # a whole number below 2^53: its own digits
            else:
                f, e = _digits(c, q, powers)
        n = 1  # the digits without trailing zeros: f 10^e, n of them
        if f != np.uint64(0):
            while f % ten == np.uint64(0):
                f //= ten
                e += 1
            power = ten  # the digits counted against the powers of ten, not by a chain of divisions
            while n < 19 and f >= power:
                n += 1
                power *= ten
        point = n + e  # the decimal point after this many digits
        at = FLOAT_WIDTH
        if not -4 < point <= 16:  # d.ddde+XX
            x = abs(point - 1)
            at = _put(chars, r, at, 48 + x % 10)
            at = _put(chars, r, at, 48 + (x // 10) % 10)
            if x >= 100:
                at = _put(chars, r, at, 48 + x // 100)
            at = _put(chars, r, at, 45 if point - 1 < 0 else 43)
            at = _put(chars, r, at, 101)  # "e"
            for _ in range(n - 1):
                at = _put(chars, r, at, zero + f % ten)
                f //= ten
            if n > 1:
                at = _put(chars, r, at, 46)  # "."
            at = _put(chars, r, at, zero + f)
        elif point <= 0:  # 0.000ddd
            for _ in range(n):
                at = _put(chars, r, at, zero + f % ten)
                f //= ten
            for _ in range(-point):
                at = _put(chars, r, at, 48)
            at = _put(chars, r, at, 46)
            at = _put(chars, r, at, 48)
        elif point < n:  # ddd.ddd
            for _ in range(n - point):
                at = _put(chars, r, at, zero + f % ten)
                f //= ten
            at = _put(chars, r, at, 46)
            for _ in range(point):
                at = _put(chars, r, at, zero + f % ten)
                f //= ten
        else:  # ddd000.0
            at = _put(chars, r, at, 48)
            at = _put(chars, r, at, 46)
            for _ in range(point - n):
                at = _put(chars, r, at, 48)
            for _ in range(n):
                at = _put(chars, r, at, zero + f % ten)
                f //= ten
        if b >> np.uint64(63):
            at = _put(chars, r, at, 45)  # "-"
        lengths[r] = FLOAT_WIDTH - at
