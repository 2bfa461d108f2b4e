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
from llvmlite import ir
from numba import types
from numba.extending import intrinsic

from .jit import njit


def _bytes_array(arr) -> bool:
    """Whether numba's type ``arr`` is a contiguous 1D array of bytes,
    which :func:`_word_at` and :func:`_put_word` address byte by byte."""
    return isinstance(arr, types.Array) and arr.ndim == 1 and arr.layout == "C" and arr.dtype == types.uint8


def _word_address(context, builder, signature, args):
    """The address of ``args[0][args[1]]`` as a pointer to a 64-bit word."""
    ary = context.make_array(signature.args[0])(context, builder, args[0])
    return builder.bitcast(builder.gep(ary.data, [args[1]]), ir.IntType(64).as_pointer())


@intrinsic
def _word_at(typingctx, arr, at):
    """The eight bytes ``arr[at:at + 8]`` of a contiguous uint8 array as
    one uint64, read at once wherever they lie (the caller checks that
    they are in the array). Callable only from compiled code."""
    if not _bytes_array(arr) or not isinstance(at, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        return builder.load(_word_address(context, builder, signature, args), align=1)

    return types.uint64(arr, at), codegen


@intrinsic
def _put_word(typingctx, arr, at, word):
    """The uint64 ``word`` written as the eight bytes ``arr[at:at + 8]``
    at once (as :func:`_word_at` reads them)."""
    if not _bytes_array(arr) or not isinstance(at, types.Integer):
        return None

    def codegen(context, builder, signature, args):
        builder.store(args[2], _word_address(context, builder, signature, args), align=1)
        return context.get_dummy_value()

    return types.void(arr, at, types.uint64), codegen


@njit(cache=True, nogil=True, inline="always")
def _copy(src, a, n, out, at):
    """``out[at:at + n] = src[a:a + n]`` (unsigned places), eight bytes at
    a time where both arrays hold the last word whole: the bytes written
    past ``at + n`` are the next copy's to write (a text written from the
    start on), else one byte at a time."""
    eight, one = np.uint64(8), np.uint64(1)
    whole = (n + np.uint64(7)) & ~np.uint64(7)
    if a + whole <= np.uint64(len(src)) and at + whole <= np.uint64(len(out)):
        q = np.uint64(0)
        while q < n:
            _put_word(out, at + q, _word_at(src, a + q))
            q += eight
    else:
        q = np.uint64(0)
        while q < n:
            out[at + q] = src[a + q]
            q += one


@njit(cache=True, nogil=True)
def integer_cells(values, signed, chars, lengths):
    """Integer ``values[r]`` as its decimal digits, ``-`` before them
    where negative, right-aligned in row ``r`` of ``chars`` (uint8, wide
    enough: the longest ``str`` of a value); its length in ``lengths[r]``.
    ``values``: uint64, the bits of int64 values where ``signed`` (a view,
    so that one compile serves both kinds of column). The sign and the
    magnitude are taken here, value by value, so that a block of a column
    needs no arrays made for them.

    Examples
    --------
    >>> chars, lengths = np.zeros((3, 20), np.uint8), np.zeros(3, np.int64)
    >>> integer_cells(np.array([-7, 120, -(2**63)]).view(np.uint64), True, chars, lengths)
    >>> [bytes(row[20 - n:]).decode() for row, n in zip(chars, lengths)]
    ['-7', '120', '-9223372036854775808']
    """
    width = chars.shape[1]
    ten = np.uint64(10)
    for r in range(len(values)):
        at = width
        v = values[r]
        negative = signed and v >> np.uint64(63) != 0  # the sign bit of an int64
        # uint64 with uint64 only (with an int numba would divide floats); the
        # magnitude of a negative int64 in two's complement, 2**63 for the least
        m = np.uint64(0) - v if negative else v
        row = np.uint64(r)  # unsigned places, as in join_cells: no check for a negative index per digit
        while True:
            at -= 1
            chars[row, np.uint64(at)] = np.uint64(48) + m % ten
            m //= ten
            if m == 0:
                break
        if negative:
            at -= 1
            chars[row, np.uint64(at)] = 45  # "-"
        lengths[r] = width - at


@njit(cache=True, nogil=True)
def join_cells(cells, starts, widths, lengths, seps, sep_ends, out):
    """Rows of text: row ``r`` is, for every column ``c``, its separator
    ``seps[sep_ends[c - 1]:sep_ends[c]]`` then its cell, the last
    ``lengths[c, r]`` bytes of row ``r`` of the column's cells: a
    (rows, ``widths[c]``) matrix of right-aligned cells that starts at
    ``cells[starts[c]]`` (each column's matrix apart in one buffer, so
    that each is written where it lies, none copied beside the others).
    Written into ``out`` (uint8, at least the text's length; what lies
    past the text may be written over too); returns the length. The
    three arrays of bytes are contiguous.

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
    # unsigned places: numba checks a signed index for a negative one (counted from the end) at every byte
    # it copies, an unsigned one needs no such check; the bytes go eight at a time (a row of a label table's
    # JSON is mostly its column names, some ten bytes before each cell)
    at = np.uint64(0)
    for r in range(lengths.shape[1]):
        s = np.uint64(0)
        for c in range(len(starts)):
            e = np.uint64(sep_ends[c])
            _copy(seps, s, e - s, out, at)
            at += e - s
            s = e
            n = np.uint64(lengths[c, r])
            _copy(cells, np.uint64(starts[c] + (r + 1) * widths[c]) - n, n, out, at)
            at += n
    return np.int64(at)
