"""A table of columns (a dict of equal-length NumPy arrays, as
:func:`isoflow.label_table` returns) written out as text a row per label:
JSON objects (``--json``) and CSV rows (``--csv``), a block of rows at a
time.

The text of a whole column comes from C loops: ``repr`` of its values as
a list, split at the separators, is each value's text exactly as
:mod:`json` and :mod:`csv` write it (both use ``repr`` for numbers); then
a row's cells are interleaved with the column names by slice assignment
and joined once. So a table of a million rows is not a million dicts for
the JSON encoder, and the text is written a block of rows at a time
rather than held whole.
"""

from __future__ import annotations

import json
from collections.abc import Iterator

import numpy as np

#: rows turned into text at once (their cells are Python strings meanwhile)
BLOCK_ROWS = 1 << 14


def cell_texts(column: np.ndarray, missing: str, joined: str, booleans: tuple[str, str]) -> list[str]:
    """Every value of a column as text: numbers as ``repr`` writes them,
    NaN and infinities as ``missing``, a tuple of integers (an object
    column) as its values joined by ``joined`` (``"[" ... "]"`` around
    them in JSON), booleans as ``booleans`` (false, true).

    Examples
    --------
    >>> cell_texts(np.array([1.5, np.nan]), "null", ", ", ("false", "true"))
    ['1.5', 'null']
    >>> cell_texts(np.array([(0, 2), ()], dtype=object), "", ";", ("False", "True"))
    ['0;2', '']
    """
    if column.dtype == object:
        if joined == ";":
            return [";".join(map(str, v)) for v in column]
        return ["[" + joined.join(map(str, v)) + "]" for v in column]
    if column.dtype.kind == "b":
        return [booleans[v] for v in column.tolist()]
    if not len(column):
        return []
    texts = repr(column.tolist())[1:-1].split(", ")
    if column.dtype.kind == "f":
        for k in np.flatnonzero(~np.isfinite(column)).tolist():
            texts[k] = missing
    return texts


def _rows(table: dict, lo: int, hi: int, before: list[str], missing: str, joined: str,
          booleans: tuple[str, str]) -> str:
    """Rows lo .. hi - 1 as one text, each cell after its column's
    ``before[c]`` (the first column's holds the end of the row before)."""
    width = 2 * len(before)
    parts: list[str] = [""] * (width * (hi - lo))
    for c, column in enumerate(table.values()):
        parts[2 * c::width] = [before[c]] * (hi - lo)
        parts[2 * c + 1::width] = cell_texts(column[lo:hi], missing, joined, booleans)
    return "".join(parts)


def json_rows(table: dict) -> Iterator[str]:
    """The table as the text of a JSON array of one object per row (what
    ``json.dumps([dict(zip(table, row)) for row in ...])`` writes, NaN as
    null), in blocks of rows.

    Examples
    --------
    >>> table = {"label": np.array([1, 2]), "volume": np.array([8.0, np.nan])}
    >>> "".join(json_rows(table))
    '[{"label": 1, "volume": 8.0}, {"label": 2, "volume": null}]'
    """
    keys = [json.dumps(str(k)) for k in table]
    before = ["}, {" + keys[0] + ": "] + [", " + k + ": " for k in keys[1:]]
    n = len(next(iter(table.values()))) if table else 0
    yield "["
    for lo in range(0, n, BLOCK_ROWS):
        text = _rows(table, lo, min(lo + BLOCK_ROWS, n), before, "null", ", ", ("false", "true"))
        yield text[3:] if lo == 0 else text  # the first row has no "}, " before it
    yield "}]" if n else "]"


def csv_rows(table: dict) -> Iterator[str]:
    """The table as CSV text (what :mod:`csv`'s writer writes with
    ``lineterminator="\\r\\n"``: the header, then a line per row; NaN
    empty, a tuple of integers as ``0;1``), in blocks of rows. The names
    and cells hold no comma, quote or line break, so none is quoted.

    Examples
    --------
    >>> "".join(csv_rows({"label": np.array([1, 2]), "genera": np.array([(0,), (1, 2)], dtype=object)}))
    'label,genera\\r\\n1,0\\r\\n2,1;2\\r\\n'
    """
    yield ",".join(map(str, table))
    before = ["\r\n"] + [","] * (len(table) - 1)
    n = len(next(iter(table.values()))) if table else 0
    for lo in range(0, n, BLOCK_ROWS):
        yield _rows(table, lo, min(lo + BLOCK_ROWS, n), before, "", ";", ("False", "True"))
    yield "\r\n"
