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


def decimal_width(magnitude: np.ndarray) -> int:
    """Digits of the largest of ``magnitude`` (uint64), at least 1.

    Examples
    --------
    >>> decimal_width(np.array([0, 999, 1000], np.uint64))
    4
    """
    return len(str(int(magnitude.max()))) if len(magnitude) else 1


@njit(cache=True, nogil=True)
def decimal_cells(magnitude, negative, chars, lengths):
    """Integer ``r`` (``magnitude[r]``, uint64, and ``negative[r]``) as
    its decimal digits, ``-`` before them where negative, right-aligned in
    row ``r`` of ``chars`` (uint8, wide enough: :func:`decimal_width` plus
    the sign); its length in ``lengths[r]``.

    Examples
    --------
    >>> chars, lengths = np.zeros((2, 3), np.uint8), np.zeros(2, np.int64)
    >>> decimal_cells(np.array([7, 120], np.uint64), np.array([True, False]), chars, lengths)
    >>> [bytes(row[3 - n:]).decode() for row, n in zip(chars, lengths)]
    ['-7', '120']
    """
    width = chars.shape[1]
    ten = np.uint64(10)
    for r in range(len(magnitude)):
        at = width
        v = magnitude[r]
        while True:  # uint64 with uint64 only: with an int numba would divide floats
            at -= 1
            chars[r, at] = np.uint64(48) + v % ten
            v //= ten
            if v == 0:
                break
        if negative[r]:
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
    at = 0
    for r in range(lengths.shape[1]):
        s = 0
        for c in range(len(starts)):
            for q in range(s, sep_ends[c]):
                out[at] = seps[q]
                at += 1
            s = sep_ends[c]
            end = starts[c] + (r + 1) * widths[c]
            for q in range(end - lengths[c, r], end):
                out[at] = cells[q]
                at += 1
    return at
