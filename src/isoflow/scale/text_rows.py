"""Text of a table (numba): integers' decimal digits and a block of rows
joined from its cells, as ASCII bytes.

A table of a million rows as JSON or CSV is tens of millions of short
texts. Python makes each a string object (``repr`` of an int, then the
joins); here an integer column becomes its digits written into the rows
of a byte matrix, right-aligned, with each cell's length, and a block of
rows is copied out of the columns' matrices with the separators between
the cells, once. Floats come as bytes the same way, from
:mod:`isoflow.scale.float_text`.
"""

from __future__ import annotations

import numpy as np

from .jit import njit


@njit(cache=True, nogil=True)
def integer_cells(values, chars, lengths):
    """Integer ``values[r]`` (int64 or uint64) as its decimal digits,
    ``-`` before them where negative, right-aligned in row ``r`` of
    ``chars`` (uint8, wide enough: the longest ``str`` of a value); its
    length in ``lengths[r]``. The sign and the magnitude are taken here,
    value by value, so that a block of a column needs no arrays made for
    them.

    Examples
    --------
    >>> chars, lengths = np.zeros((3, 20), np.uint8), np.zeros(3, np.int64)
    >>> integer_cells(np.array([-7, 120, -(2**63)]), chars, lengths)
    >>> [bytes(row[20 - n:]).decode() for row, n in zip(chars, lengths)]
    ['-7', '120', '-9223372036854775808']
    """
    width = chars.shape[1]
    ten = np.uint64(10)
    for r in range(len(values)):
        at = width
        v = values[r]
        negative = v < v - v  # zero of the values' own type: no float comparison for uint64
        # uint64 with uint64 only (with an int numba would divide floats); the
        # magnitude of a negative int64 in two's complement, 2**63 for the least
        m = np.uint64(0) - np.uint64(v) if negative else np.uint64(v)
        while True:
            at -= 1
            chars[r, at] = np.uint64(48) + m % ten
            m //= ten
            if m == 0:
                break
        if negative:
            at -= 1
            chars[r, at] = 45  # "-"
        lengths[r] = width - at


@njit(cache=True, nogil=True)
def join_cells(cells, starts, widths, lengths, seps, sep_ends, out):
    """Rows of text: row ``r`` is, for every column ``c``, its separator
    ``seps[sep_ends[c - 1]:sep_ends[c]]`` then its cell, the last
    ``lengths[c, r]`` bytes of row ``r`` of the column's cells: a
    (rows, ``widths[c]``) matrix of right-aligned cells that starts at
    ``cells[starts[c]]`` (each column's matrix apart in one buffer, so
    that each is written where it lies, none copied beside the others).
    Written into ``out`` (uint8, at least the text's length); returns the
    length.

    Examples
    --------
    >>> cells = np.frombuffer(b" 1" b"23" b"x" b"y", np.uint8)   # column 0 two wide, column 1 one
    >>> lengths = np.array([[1, 2], [1, 1]])
    >>> seps = np.frombuffer(b";a=,b=", np.uint8)
    >>> out = np.zeros(32, np.uint8)
    >>> n = join_cells(cells, np.array([0, 4]), np.array([2, 1]), lengths, seps, np.array([3, 6]), out)
    >>> bytes(out[:n]).decode()
    ';a=1,b=x;a=23,b=y'
    """
    # unsigned places: numba checks a signed index for a negative one (counted from the end) at every byte,
    # which here, a byte at a time, costs as much as the copy itself
    one = np.uint64(1)
    at = np.uint64(0)
    for r in range(lengths.shape[1]):
        s = np.uint64(0)
        for c in range(len(starts)):
            e = np.uint64(sep_ends[c])
            q = s
            while q < e:
                out[at] = seps[q]
                at += one
                q += one
            s = e
            end = np.uint64(starts[c] + (r + 1) * widths[c])
            q = end - np.uint64(lengths[c, r])
            while q < end:
                out[at] = cells[q]
                at += one
                q += one
    return np.int64(at)
