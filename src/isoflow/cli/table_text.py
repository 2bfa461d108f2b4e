"""A table of columns (a dict of equal-length NumPy arrays, as
:func:`isoflow.label_table` returns) written out as text a row per label:
JSON objects (``--json``) and CSV rows (``--csv``), a block of rows at a
time.

Every column's cells become ASCII text right-aligned in the rows of a byte
matrix, with each cell's length (:mod:`isoflow.scale.text_rows`):
integers as compiled digits; floats as compiled digits too, the text
``repr`` writes (the shortest that reads back as the float: what
:mod:`json` and :mod:`csv` write), by :mod:`isoflow.scale.float_text`;
tuples of an object column through ``str``, once per distinct tuple.
Each column's matrix lies in its own part of one buffer, so that none is
copied beside the others. A block's rows are then joined from the
columns' cells and the separators and names between them in one compiled
pass. So a table of a million rows is neither a million dicts for the
JSON encoder nor a Python string per number, and the text is written a
block of rows at a time rather than held whole. The blocks are made on
the compiled passes' threads (the digits and the joins release the GIL),
the next ones while one is written out, each thread's cells in buffers it
keeps from one block to the next. A block's text is ASCII bytes, which
``--json`` writes as they are to standard output's buffer of bytes.

A measure as the terminal prints it (:func:`measure_text`: the report of
one object and the label table's rows alike) never reads ``inf``.
"""

from __future__ import annotations

import itertools
import json
import math
import sys
import threading
from collections.abc import Callable, Iterator

import numpy as np

#: rows turned into text at once: a block's cells and text (about 1.4 kB a
#: row of a label table's JSON) are read back from the processor's cache
#: when the rows are joined, and each thread's buffers stay that small
BLOCK_ROWS = 1 << 12
#: a table of at most this many rows is written by Python's own text of
#: each cell (the same text): numba's start would cost a small table (a
#: few organs) more than the compiled digits save; where numba is not
#: loaded at all yet (a 2D table is NumPy's), its start is all the more to
#: pay, so up to PLAIN_ROWS_COLD rows (where the two cost about the same)
PLAIN_ROWS, PLAIN_ROWS_COLD = 2048, 50_000


def cell_texts(column: np.ndarray, joined: str, booleans: tuple[str, str]) -> list[str]:
    """The cells that are not numbers as text: a tuple of integers (an
    object column) as its values joined by ``joined`` (``"[" ... "]"``
    around them in JSON), booleans as ``booleans`` (false, true).

    Examples
    --------
    >>> cell_texts(np.array([True, False]), ", ", ("false", "true"))
    ['true', 'false']
    >>> cell_texts(np.array([(0, 2), ()], dtype=object), ";", ("False", "True"))
    ['0;2', '']

    Text (a label's name) as a JSON string, or as CSV writes it (quoted
    where it holds a comma, a quote or a line break):

    >>> cell_texts(np.array(['a.stl', 'b, "c".obj']), ";", ("False", "True"))
    ['a.stl', '"b, ""c"".obj"']
    >>> cell_texts(np.array(['a.stl']), ", ", ("false", "true"))
    ['"a.stl"']
    """
    if column.dtype.kind == "U":
        if joined != ";":
            return [json.dumps(v) for v in column.tolist()]
        return ['"' + v.replace('"', '""') + '"' if any(c in v for c in ',"\r\n') else v for v in column.tolist()]
    if column.dtype == object:
        values = column.tolist()
        # the texts of the distinct tuples (a table's genera repeat a few)
        if joined == ";":
            text = {v: _joined(v, ";") for v in set(values)}
        else:
            text = {v: "[" + _joined(v, joined) + "]" for v in set(values)}
        return [text[v] for v in values]
    return [booleans[v] for v in column.tolist()]


def _joined(values: tuple, joined: str) -> str:
    """The integers ``values`` as text joined by ``joined``, each distinct
    one made text once (a label of noise has a hundred thousand surfaces,
    nearly all of genus 0)."""
    texts = {v: str(v) for v in set(values)}
    return joined.join(map(texts.__getitem__, values))


def non_finite_text(value: float, missing: str, joined: str) -> str:
    """The text of a float that is no finite number: NaN as ``missing``
    (``null`` in JSON, empty in CSV), and an infinity (a volume past
    float64: voxels of 1e150) as ``missing`` in JSON, which has no
    infinity, but in CSV (``joined`` ``";"``) as :mod:`csv` writes it,
    ``inf`` or ``-inf``, which ``float``, pandas' ``read_csv`` and R read
    back as the infinity (empty, they would read "unknown").

    Parameters
    ----------
    value : float
        NaN or an infinity.
    missing : str
        The text of NaN.
    joined : str
        What joins a tuple's values: ``";"`` in CSV.

    Returns
    -------
    str
        The cell's text.

    Examples
    --------
    >>> non_finite_text(float("-inf"), "", ";"), non_finite_text(float("nan"), "", ";")
    ('-inf', '')
    >>> non_finite_text(float("inf"), "null", ", ")
    'null'
    """
    return repr(value) if joined == ";" and not math.isnan(value) else missing


def measure_text(value: float, voxels: int | None = None, step=None, dimension: int = 3) -> str:
    """A measure as the report prints it: to 6 digits, or where float64
    holds no such number (a volume of voxels of 1e200: inf) the figure
    from exact decimal arithmetic where it is ``voxels`` voxels of sizes
    ``step`` (as ``surface``'s read-back gives the volume), said to be
    beyond float64; else the words alone, never a bare ``inf``.

    Parameters
    ----------
    value : float
        The measure, float64.
    voxels : int, optional
        The voxels whose sizes multiply to it (the volume, or the area in
        2D); None for a measure of faces (the surface area).
    step : float or sequence of float, optional
        The voxel size, one for every axis or one per axis.
    dimension : int
        The number of axes.

    Returns
    -------
    str
        The text.

    Examples
    --------
    >>> measure_text(8.0)
    '8'
    >>> measure_text(float("inf"), 27, [1e200, 1e200, 1e200])
    '2.7e+601 (beyond float64)'
    >>> measure_text(float("inf"))
    "beyond float64's range"
    """
    from decimal import Decimal, localcontext

    if math.isfinite(value):
        return f"{value:.6g}"
    if voxels is None or step is None:
        return "beyond float64's range"
    sizes = list(step) if hasattr(step, "__len__") else [step] * dimension
    with localcontext() as ctx:
        ctx.prec = 40
        exact = Decimal(int(voxels))
        for size in sizes[:dimension]:
            exact *= Decimal(float(size))
        ctx.prec = 6
        exact = (+exact).normalize()
    return f"{exact:g} (beyond float64)"


def _fill_texts(texts: list[str], chars: np.ndarray, lengths: np.ndarray) -> None:
    """ASCII texts right-aligned in the rows of ``chars`` (uint8, (n, at
    least the longest)); their lengths in ``lengths``."""
    n, width = chars.shape
    lengths[:] = np.fromiter(map(len, texts), np.int64, n)
    text = np.frombuffer("".join(texts).encode("ascii"), np.uint8)
    row = np.repeat(np.arange(n), lengths)
    # a character's place: its row's padding, then its place in its text
    chars[row, np.arange(len(text)) - np.repeat(np.cumsum(lengths) - width, lengths)] = text


def _text_cells(texts: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """ASCII texts right-aligned in the rows of a (n, longest) uint8
    matrix, and their lengths."""
    chars = np.zeros((len(texts), max(map(len, texts), default=0)), np.uint8)
    lengths = np.zeros(len(texts), np.int64)
    _fill_texts(texts, chars, lengths)
    return chars, lengths


def _float_cells(values: np.ndarray, missing: str, joined: str, chars: np.ndarray, lengths: np.ndarray) -> None:
    """Float64 ``values`` as ``repr`` writes them (NaN and infinities as
    :func:`non_finite_text` writes them) into ``chars`` ((n, FLOAT_WIDTH)
    uint8) and ``lengths``: compiled, but for the subnormal floats, which
    go through ``repr``."""
    from ..scale.float_text import FLOAT_WIDTH, power_table, shortest_cells

    shortest_cells(values.view(np.uint64), power_table(), chars, lengths)
    if lengths.min(initial=1) == 0:  # NaN, infinities, subnormal floats (seldom: looked for only then)
        left = np.flatnonzero(lengths == 0)
        texts = [repr(v) if math.isfinite(v) else non_finite_text(v, missing, joined) for v in values[left].tolist()]
        some, their = _text_cells(texts)
        chars[left, FLOAT_WIDTH - some.shape[1]:] = some
        lengths[left] = their


def _distinct_cells(column: np.ndarray, joined: str, booleans: tuple[str, str]) -> tuple[np.ndarray, ...]:
    """The cells of a column that are not numbers (a tuple, a boolean, a
    name) as the text of each distinct value (:func:`cell_texts`), made
    once: the texts right-aligned in a (values, longest) uint8 matrix,
    their lengths, and each row's value among them. A label table's genera
    are a few distinct tuples over many rows."""
    values = column.tolist()
    # each row's first row of its value (no Python loop of our own), then
    # those first rows numbered in order
    first = np.fromiter(map({}.setdefault, values, itertools.count()), np.intp, len(values))
    seen = np.zeros(len(values), bool)
    seen[first] = True
    kinds = np.empty(int(seen.sum()), column.dtype)
    for k, row in enumerate(np.flatnonzero(seen).tolist()):  # one by one: a tuple is one object cell
        kinds[k] = values[row]
    chars, lengths = _text_cells(cell_texts(kinds, joined, booleans))
    return chars, lengths, (np.cumsum(seen) - 1)[first]


def _cells(column: np.ndarray, missing: str, joined: str, booleans: tuple[str, str]) -> tuple[int, Callable]:
    """A column's cells before they are written: their width, and a call
    ``write(lo, hi, chars, lengths)`` that writes those of rows lo .. hi -
    1 right-aligned into the rows of a (hi - lo, width) uint8 matrix and
    their lengths into ``lengths``. What a pass over the whole column
    gives (the widest integer, the text of each distinct tuple) is found
    here once, not again for each block of rows."""
    if column.dtype.kind in "iu":
        from ..scale.text_rows import integer_cells  # numba: not for a command without a table

        # uint64, or int64 (which holds every narrower integer) seen as uint64: one compile for both
        signed = column.dtype != np.uint64
        kind = np.int64 if signed else np.uint64
        width = max(len(str(column.min())), len(str(column.max()))) if len(column) else 1

        def integers(lo: int, hi: int, chars: np.ndarray, lengths: np.ndarray) -> None:
            integer_cells(np.ascontiguousarray(column[lo:hi], kind).view(np.uint64), signed, chars, lengths)

        return width, integers
    if column.dtype.kind == "f":
        from ..scale.float_text import FLOAT_WIDTH

        values = np.ascontiguousarray(column, dtype=np.float64)
        return FLOAT_WIDTH, lambda lo, hi, chars, lengths: _float_cells(values[lo:hi], missing, joined, chars, lengths)
    texts, sizes, which = _distinct_cells(column, joined, booleans)

    def distinct(lo: int, hi: int, chars: np.ndarray, lengths: np.ndarray) -> None:
        np.take(texts, which[lo:hi], axis=0, out=chars)
        np.take(sizes, which[lo:hi], out=lengths)

    return texts.shape[1], distinct


def cell_bytes(column: np.ndarray, missing: str, joined: str,
               booleans: tuple[str, str]) -> tuple[np.ndarray, np.ndarray]:
    """Every value of a column as :mod:`json` (``missing`` for NaN and
    infinities, ``joined`` between a tuple's values, ``booleans``) or
    :mod:`csv` (``missing`` for NaN, ``joined`` ``";"``) write it, in ASCII right-aligned in the rows of a (n,
    longest) uint8 matrix, and each value's length.

    Examples
    --------
    >>> chars, lengths = cell_bytes(np.array([-12, 3]), "", "", ("", ""))
    >>> [bytes(row[len(row) - n:]).decode() for row, n in zip(chars, lengths)]
    ['-12', '3']
    >>> chars, lengths = cell_bytes(np.array([8.0, 0.1, np.inf]), "null", "", ("", ""))
    >>> [bytes(row[len(row) - n:]).decode() for row, n in zip(chars, lengths)]
    ['8.0', '0.1', 'null']
    """
    width, write = _cells(column, missing, joined, booleans)
    chars = np.zeros((len(column), width), np.uint8)
    lengths = np.zeros(len(column), np.int64)
    write(0, len(column), chars, lengths)
    return chars[:, width - int(lengths.max(initial=0)):], lengths


def plain(n: int) -> bool:
    """Whether a table of ``n`` rows is written by :func:`_plain_rows`."""
    return n <= PLAIN_ROWS or (n <= PLAIN_ROWS_COLD and "numba" not in sys.modules)


def _plain_rows(table: dict, lo: int, hi: int, before: list[bytes], missing: str, joined: str,
                booleans: tuple[str, str]) -> str:
    """:func:`_rows` in Python: each cell's text from ``str`` (integers)
    and ``repr`` (floats: the text :mod:`json` and :mod:`csv` write)."""
    columns = []
    for column in table.values():
        part = column[lo:hi]
        if part.dtype.kind in "iu":
            columns.append(list(map(str, part.tolist())))
        elif part.dtype.kind == "f":
            columns.append([repr(v) if math.isfinite(v) else non_finite_text(v, missing, joined)
                            for v in part.astype(np.float64).tolist()])
        else:
            columns.append(cell_texts(part, joined, booleans))
    seps = [b.decode("ascii") for b in before]
    return "".join("".join(sep + cell for sep, cell in zip(seps, row)) for row in zip(*columns))


def _scratch(held: threading.local, name: str, size: int, dtype: type) -> np.ndarray:
    """``size`` entries of the calling thread's buffer ``name``, made anew
    only where the one it holds is smaller: the blocks of a table are
    alike, and memory a process touches for the first time costs about
    what writing the text into it does."""
    buffers = held.__dict__
    if name not in buffers or len(buffers[name]) < size:
        buffers[name] = np.empty(size, dtype)
    return buffers[name][:size]


def _rows(columns: list, lo: int, hi: int, before: list[bytes], held: threading.local | None = None) -> np.ndarray:
    """Rows lo .. hi - 1 as one ASCII text, in an array of bytes (uint8)
    of its own, each cell after its column's
    ``before[c]`` (the first column's holds the end of the row before):
    each column's cells (``columns``: its :func:`_cells`, made once for
    every block) written into their own part of one buffer, then the rows
    joined from them. The cells' buffers are the calling thread's in
    ``held`` (new ones where None); the text's is new, as the caller holds
    it while the next block is made (freed blocks of its size come back
    from the allocator, not as pages touched anew)."""
    from ..scale.compiled import read_only_view
    from ..scale.text_rows import join_cells

    held = threading.local() if held is None else held
    n = hi - lo
    widths = np.array([width for width, _ in columns], np.int64)
    starts = np.cumsum(widths * n) - widths * n
    cells = _scratch(held, "cells", int(widths.sum()) * n, np.uint8)
    lengths = _scratch(held, "lengths", len(columns) * n, np.int64).reshape(len(columns), n)
    for c, (width, write) in enumerate(columns):
        write(lo, hi, cells[starts[c]:starts[c] + width * n].reshape(n, width), lengths[c])
    seps = np.frombuffer(b"".join(before), np.uint8)
    out = np.empty(int(lengths.sum()) + n * len(seps), np.uint8)
    # both read-only, as seps (a view of bytes) is anyway: one compile
    size = join_cells(read_only_view(cells), starts, widths, lengths, seps, np.cumsum([len(b) for b in before]), out)
    return out[:size]


def _blocks(table: dict, before: list[bytes], missing: str, joined: str, booleans: tuple[str, str],
            binary: bool = False) -> Iterator:
    """The rows' text a block of :data:`BLOCK_ROWS` rows at a time, in
    order: as str, or with ``binary`` (where every cell is ASCII: JSON's)
    as its ASCII bytes (bytes-like). The compiled blocks are made on the
    threads of the compiled
    passes (:func:`isoflow.scale.compiled.run_ahead`: their digits and
    joins release the GIL), the next ones while the caller writes one out;
    Python's text of a small table on the calling thread."""
    n = len(next(iter(table.values()))) if table else 0
    # text (a name column) may hold any character: Python's rows, not the compiled ASCII ones
    if plain(n) or any(c.dtype.kind == "U" for c in table.values()):
        for lo in range(0, n, BLOCK_ROWS):
            text = _plain_rows(table, lo, min(lo + BLOCK_ROWS, n), before, missing, joined, booleans)
            yield text.encode("ascii") if binary else text
        return
    from ..scale.compiled import run_ahead

    columns = [_cells(column, missing, joined, booleans) for column in table.values()]
    held = threading.local()  # each thread's buffers, let go with the text
    for text in run_ahead([(_rows, columns, lo, min(lo + BLOCK_ROWS, n), before, held)
                           for lo in range(0, n, BLOCK_ROWS)]):
        yield text if binary else str(text, "ascii")


def json_rows(table: dict, binary: bool = False) -> Iterator:
    """The table as the text of a JSON array of one object per row (what
    ``json.dumps([dict(zip(table, row)) for row in ...])`` writes, NaN and
    infinities as null), in blocks of rows: str, or with ``binary`` the
    text's ASCII bytes (bytes-like pieces, for a stream of bytes: no
    string made and encoded again).

    Examples
    --------
    >>> table = {"label": np.array([1, 2]), "volume": np.array([8.0, np.nan])}
    >>> "".join(json_rows(table))
    '[{"label": 1, "volume": 8.0}, {"label": 2, "volume": null}]'
    >>> b"".join(json_rows(table, binary=True))
    b'[{"label": 1, "volume": 8.0}, {"label": 2, "volume": null}]'
    """
    keys = [json.dumps(str(k)) for k in table]  # ASCII: json escapes any other character
    before = [("}, {" + keys[0] + ": ").encode()] + [(", " + k + ": ").encode() for k in keys[1:]]
    yield b"[" if binary else "["
    n = 0
    for text in _blocks(table, before, "null", ", ", ("false", "true"), binary):
        yield text if n else text[3:]  # the first row has no "}, " before it
        n += 1
    end = "}]" if n else "]"
    yield end.encode() if binary else end


def csv_rows(table: dict) -> Iterator[str]:
    """The table as CSV text (what :mod:`csv`'s writer writes with
    ``lineterminator="\\r\\n"``: the header, then a line per row; NaN
    empty, infinities ``inf`` and ``-inf``, a tuple of integers as
    ``0;1``), in blocks of rows. The names
    and cells hold no comma, quote or line break, so none is quoted, but
    for a text column's (a label's name), quoted as :mod:`csv` quotes it.

    Examples
    --------
    >>> "".join(csv_rows({"label": np.array([1, 2]), "genera": np.array([(0,), (1, 2)], dtype=object)}))
    'label,genera\\r\\n1,0\\r\\n2,1;2\\r\\n'
    """
    yield ",".join(map(str, table))
    before = [b"\r\n"] + [b","] * (len(table) - 1)
    yield from _blocks(table, before, "", ";", ("False", "True"))
    yield "\r\n"
