"""Label names from a side file.

NIfTI and FreeSurfer MGH have no place for label names, so the
segmentations held in them (TotalSegmentator's, nnU-Net's, FreeSurfer's
``aseg.mgz``, ITK-SNAP's) keep their names in a file beside the image.
:func:`read_label_names` reads the common ones, the kind told from the
content (the suffix only breaks a tie):

* a FreeSurfer colour table (``FreeSurferColorLUT.txt``), as 3D Slicer's
  colour tables (``.ctbl``, ``.txt``) are too: lines ``index name R G B
  A``;
* an ITK-SNAP label description file: lines ``IDX R G B A VIS MSH
  "LABEL"``;
* a plain list of lines ``index name`` (``1 liver``, ``2 left kidney``:
  the name is the rest of the line), where no line has colour columns;
* CSV or TSV whose header names a label column (``label``, ``index``,
  ``value``, ``labelvalue``) and a name column (``name``, ``label_name``),
  as 3D Slicer's ``.csv`` colour tables do, or without a header, two cells
  ``label,name`` on every row (``1,liver``); its cells separated by
  commas, tabs or semicolons (``index;name``, ``1;liver``, as a European
  Excel writes CSV), whichever splits the header (or the first row) so,
  or by the one Excel's first line ``sep=;`` declares;
* JSON: an object of label to name (``{"1": "spleen"}``, the
  ``label_names`` isoflow writes), or an nnU-Net ``dataset.json`` whose
  ``labels`` map name to label (``{"background": 0, "spleen": 1}``).

The text is UTF-8 (Latin-1 where it is none), or UTF-16 behind its
byte-order mark (Excel's "Unicode Text"), or UTF-16 without one where
every other byte of the first 1024 is NUL and the file decodes in that
byte order. ``#`` starts a comment line and
blank lines are skipped in the text kinds. Label 0 is the background and
is not named; a label named twice is refused naming the line. A file of
numbers alone (a point list, ``0 0 0`` per line, given for the names) is
refused, not read as labels named by their numbers, and so is a line
``index name`` whose name is several numbers (colour columns without a
name).
"""

from __future__ import annotations

import bisect
import csv
import json
import os
import re
import stat
from collections.abc import Iterable, Iterator
from pathlib import Path

from ...errors import IsoflowError, check_path, line_text, missing
from .registry import format_for, one_line_name
from .text_encoding import HEAD_BYTES, utf16_order

#: what a file of label names is, for the refusal of one that is none
EXPECTED = ("expected a FreeSurfer or 3D Slicer colour table (lines 'index name R G B A'), an ITK-SNAP label "
            "description (lines 'IDX R G B A VIS MSH \"LABEL\"'), lines 'index name', CSV or TSV with a header "
            "naming a label column (label, index, value) and a name column (name, label_name) or rows 'label,name', "
            "or JSON of label to name "
            "({\"1\": \"spleen\"}, or a dataset.json's \"labels\")")

#: header cells that name the label column, and the name column, of a CSV or TSV (lower case)
LABEL_COLUMNS = ("label", "index", "value", "labelvalue", "label_value", "id")
NAME_COLUMNS = ("name", "label_name", "labelname")

#: an ITK-SNAP line: IDX R G B A VIS MSH "LABEL" (A a number from 0 to 1)
_ITKSNAP = re.compile(r'\s*(-?[0-9]+)\s+[0-9]+\s+[0-9]+\s+[0-9]+\s+[0-9.eE+-]+\s+[0-9]+\s+[0-9]+\s+"(.*)"\s*',
                      re.ASCII)
#: a colour table line: index name R G B [A] (FreeSurfer's names have no space; Slicer's may)
_LUT = re.compile(r"\s*(-?[0-9]+)\s+(\S.*?)\s+[0-9]+\s+[0-9]+\s+[0-9]+(?:\s+[0-9]+)?\s*", re.ASCII)
#: a line of a plain list: index name (the name the rest of the line)
_PAIR = re.compile(r"\s*(-?[0-9]+)\s+(\S.*?)\s*", re.ASCII)
#: Excel's first line of a CSV, "sep=;" or "sep=,": the separator of the cells below it, no row of the table
_SEP = re.compile(r"\s*sep=(.)\s*", re.IGNORECASE)
#: a label value in a CSV cell or a JSON key
_INTEGER = re.compile(r"\s*(-?[0-9]+)\s*", re.ASCII)
#: a line of numbers alone, blanks or commas between them (a point list's "0 0 0", "1.5, 2, 3")
_NUMBERS = re.compile(r"\s*[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
                      r"(?:(?:\s*,\s*|\s+)[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?)*\s*", re.ASCII)


def read_label_names(path: str | os.PathLike) -> dict[int, str]:
    """What each label is, from a side file of label names: a FreeSurfer
    or 3D Slicer colour table, an ITK-SNAP label description file, a plain
    list of lines ``index name``, a CSV or TSV table, or JSON (label to
    name, or an nnU-Net ``dataset.json``).

    Parameters
    ----------
    path : str or os.PathLike
        The file. Its kind is told from its content, its suffix only
        where the content fits two (``.json``, ``.csv``, ``.tsv``).

    Returns
    -------
    dict of int to str
        Label value to name, in increasing order of label, label 0 (the
        background) left out. :func:`isoflow.label_table` and
        :func:`isoflow.write_labels` take it as ``names=``.

    Raises
    ------
    IsoflowError
        One line naming the file: unreadable, a label image (whose
        names :func:`isoflow.read_labels` reads), none of these kinds (the
        line says what was expected), a label named twice (naming the
        line), no label but the background.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> lut = pathlib.Path(tempfile.mkdtemp()) / "FreeSurferColorLUT.txt"
    >>> _ = lut.write_text("# index name R G B A\\n0 Unknown 0 0 0 0\\n17 Left-Hippocampus 220 216 20 0\\n")
    >>> read_label_names(lut)
    {17: 'Left-Hippocampus'}
    >>> _ = lut.write_text('{"labels": {"background": 0, "spleen": 1, "kidney_right": 2}}')
    >>> read_label_names(lut)
    {1: 'spleen', 2: 'kidney_right'}
    >>> _ = lut.write_text("1 liver\\n2 left kidney\\n")
    >>> read_label_names(lut)
    {1: 'liver', 2: 'left kidney'}
    """
    path = check_path(path, "path", "read_label_names")
    where = str(path)
    try:
        if not (stat.S_ISREG(mode := os.stat(path).st_mode) or stat.S_ISDIR(mode)):
            # read whole, a pipe would be read until a writer came, /dev/zero until memory ran out
            raise IsoflowError(f"{where}: not a regular file (a device, pipe or socket)")
        if format_for(path) is not None:
            # a label image given for its names (seg.nrrd, labels.zarr): its bytes were "binary data" and
            # an OME-Zarr store "cannot be read (Is a directory)", neither saying where its names are
            raise IsoflowError(f"{where}: a label image, not a side file of label names; the names a label image "
                               "records are read with it (isoflow.read_labels(path).names; --labels without --names)")
        data = Path(path).read_bytes()
    except OSError as exc:
        if isinstance(exc, (FileNotFoundError, NotADirectoryError)):  # said as every reader says a missing input
            raise missing(where) from None
        raise IsoflowError(f"{where}: cannot read the label names ({exc.strerror or type(exc).__name__})") from None
    encoding = utf16_order(data[:HEAD_BYTES])
    if encoding == "utf-16":
        # Excel's "Unicode Text" and PowerShell's ">" write UTF-16 behind its byte-order mark: text, though
        # half its bytes are NUL, which the test below took for binary data
        try:
            text = data.decode("utf-16")
        except UnicodeDecodeError:
            raise IsoflowError(f"{where}: opens as UTF-16 text (its byte-order mark) but is not UTF-16; "
                               f"{EXPECTED}") from None
        return label_names_of(text, where, Path(path).suffix.lower())
    if encoding is not None:
        # UTF-16 without a mark (some Windows tools write none): names may hold any letter, so the whole
        # file must decode in the order its NUL bytes tell; a binary file that does not stays refused below
        try:
            return label_names_of(data.decode(encoding), where, Path(path).suffix.lower())
        except UnicodeDecodeError:
            pass
    if b"\0" in data[:1 << 16]:  # a volume given for its names (seg.nii.gz), or any binary file
        raise IsoflowError(f"{where}: not a file of label names (it holds binary data); {EXPECTED}")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError:  # an older tool's Latin-1 names: a character a byte, as NRRD names are read
        text = data.decode("latin-1")
    return label_names_of(text, where, Path(path).suffix.lower())


def label_names_of(text: str, where: str, suffix: str = "") -> dict[int, str]:
    """The label names of a side file's text (:func:`read_label_names`).

    Parameters
    ----------
    text : str
        The file's content.
    where : str
        The file, as a refusal names it.
    suffix : str, optional
        Its suffix in lower case, which settles JSON against the text
        kinds and CSV against a colour table.

    Returns
    -------
    dict of int to str
        Label to name, increasing, without label 0.

    Examples
    --------
    >>> label_names_of('0 0 0 0 0 0 0 "Clear Label"\\n1 255 0 0 1 1 1 "Liver"\\n', "seg.label")
    {1: 'Liver'}
    >>> label_names_of("label,name\\n2,spleen\\n1,liver\\n", "names.csv")
    {1: 'liver', 2: 'spleen'}
    >>> label_names_of("sep=;\\n1;liver, left lobe\\n2;spleen\\n", "names.csv")
    {1: 'liver, left lobe', 2: 'spleen'}
    """
    if text.lstrip().startswith(("{", "[")) or suffix == ".json":
        pairs = _json_pairs(text, where)
    else:
        rows = [(n, line) for n, line in enumerate(text.splitlines(), 1) if line.strip()
                and not line.lstrip().startswith("#")]
        declared = None
        if rows and (sep := _SEP.fullmatch(rows[0][1])):
            # Excel honours the line and hides it: the separator is the one it names, whatever the header
            declared, rows = sep[1], rows[1:]
        if not rows:
            after = f" after its 'sep={declared}'" if declared else " but comments"
            raise IsoflowError(f"{where}: holds no label names (no line{after}); {EXPECTED}")
        pairs = _text_pairs(rows, text, where, suffix, declared)
    found: dict[int, str] = {}
    first: dict[int, str] = {}
    for label, name, at in pairs:
        if label == 0:  # the background (FreeSurfer's Unknown, ITK-SNAP's Clear Label) is no structure
            continue
        if label in found:
            raise IsoflowError(f"{where}: {at}: label {label} is named again (first on {first[label]})")
        name = one_line_name(name)  # a name is one line, as the image readers keep it
        if name:
            found[label], first[label] = name, at
    if not found:
        raise IsoflowError(f"{where}: names no label but the background (0)")
    return dict(sorted(found.items()))


def _text_pairs(rows: list[tuple[int, str]], text: str, where: str, suffix: str,
                declared: str | None = None) -> list[tuple[int, str, str]]:
    """(label, name, where it is) of each data line of a colour table,
    an ITK-SNAP file, a plain list of lines ``index name`` or a CSV/TSV
    table; ``rows`` the lines of the file ``text`` that are neither blank
    nor comments (number, text), ``declared`` the separator a first line
    ``sep=;`` names (that line left out of ``rows``)."""
    number, head = rows[0]
    first = "\t" if suffix == ".tsv" or ("\t" in head and "," not in head) else ","
    # the header says which: a European Excel separates its cells by ";" ("index;name", "1;liver"), as its
    # list separator is; a delimiter is taken only where it splits the header into a label and a name column
    delimiters = (declared,) if declared is not None else tuple(dict.fromkeys((first, ",", ";", "\t")))
    for delimiter in delimiters:
        cells = [c.strip().lower() for c in next(_csv_records(rows[:1], text, where, delimiter))[1]]
        name_at = next((cells.index(c) for c in NAME_COLUMNS if c in cells), None)
        label_at = next((cells.index(c) for c in LABEL_COLUMNS if c in cells and cells.index(c) != name_at), None)
        if name_at is not None and label_at is not None:
            return _table_pairs(_csv_records(rows[1:], text, where, delimiter), where, label_at, name_at)
    _refuse_numbers(rows, where)
    table = declared is not None or suffix in (".csv", ".tsv")
    if not _ITKSNAP.fullmatch(head) and not _LUT.fullmatch(head) and (table or not _PAIR.fullmatch(head)):
        # a table without a header, as a plain list is one: "1,liver" read as "1 liver" is
        pairs = _headerless_pairs(rows, text, where, delimiters)
        if pairs is not None:
            return pairs
        if table:
            sep = f" after 'sep={declared}'" if declared is not None else ""
            raise IsoflowError(f"{where}: line {number}: a header naming a label column ({', '.join(LABEL_COLUMNS)}) "
                               f"and a name column ({', '.join(NAME_COLUMNS)}), or a row "
                               f"'label{delimiters[0]}name', is expected{sep}, not {_shown(head)}")
    for pattern, kind in ((_ITKSNAP, "an ITK-SNAP line 'IDX R G B A VIS MSH \"LABEL\"'"),
                          (_LUT, "a colour table line 'index name R G B A'")):
        if pattern.fullmatch(head):
            pairs = []
            for n, line in rows:
                match = pattern.fullmatch(line)
                if match is None:
                    raise IsoflowError(f"{where}: line {n}: {kind} is expected, as line {number} is, not "
                                       f"{_shown(line)}")
                pairs.append((int(match[1]), match[2].strip(), f"line {n}"))
            return pairs
    if _PAIR.fullmatch(head):
        return _plain_pairs(rows, where)
    raise IsoflowError(f"{where}: not a file of label names (line {number} reads {_shown(head)}); {EXPECTED}")


def _headerless_pairs(rows: list[tuple[int, str]], text: str, where: str,
                      delimiters: Iterable[str]) -> list[tuple[int, str, str]] | None:
    """(label, name, where it is) of each row of a table without a header,
    two cells ``label,name`` on every row (``1,liver``, ``1;liver``), the
    first delimiter of ``delimiters`` that splits the first row so taken;
    None where none does. A later row of another form is refused naming
    its line, as a name cut at a separator (``2,liver, left``) would be a
    wrong name, and so is a table whose names are all numbers."""
    number, head = rows[0]
    for delimiter in delimiters:
        label, _, name = head.partition(delimiter)
        if delimiter not in head or not _INTEGER.fullmatch(label) or not name.strip():
            continue
        pairs = []
        for n, cells, line in _csv_records(rows, text, where, delimiter):
            if len(cells) != 2 or not _INTEGER.fullmatch(cells[0]):
                raise IsoflowError(f"{where}: line {n}: a row 'label{delimiter}name' of two cells is expected, as "
                                   f"line {number} is, not {_shown(line)}")
            pairs.append((int(cells[0]), cells[1].strip(), f"line {n}"))
        if all(_NUMBERS.fullmatch(name) for _, name, _ in pairs):
            raise IsoflowError(f"{where}: holds numbers, not label names (no row names a label; line {number} reads "
                               f"{_shown(head)}); {EXPECTED}")
        return pairs
    return None


def _refuse_numbers(rows: list[tuple[int, str]], where: str) -> None:
    """Refuse a file whose lines are numbers alone: each would read as a
    label whose "name" is the numbers after the first (``0 0 0`` as label
    0, ``1 1 1`` as label 1 named ``1 1``), a silently wrong answer for a
    point list or a table of values given for the names."""
    if not all(_NUMBERS.fullmatch(line) for _, line in rows):
        return
    number, head = rows[0]
    counts = {len(re.split(r"\s*,\s*|\s+", line.strip())) for _, line in rows}
    if counts in ({2}, {3}):  # x y z (or x y) on each line
        raise IsoflowError(f"{where}: looks like a point list (lines of {('two', 'three')[counts.pop() - 2]} numbers, "
                           f"line {number} reads {_shown(head)}), not label names; {EXPECTED}")
    raise IsoflowError(f"{where}: holds numbers, not label names (no line names a label; line {number} reads "
                       f"{_shown(head)}); {EXPECTED}")


def _plain_pairs(rows: list[tuple[int, str]], where: str) -> list[tuple[int, str, str]]:
    """(label, name, where it is) of each line of a plain list of lines
    ``index name``, the first of which is one; a line with colour columns
    is refused, as it would make the colours part of a name."""
    number = rows[0][0]
    pairs = []
    for n, line in rows:
        if _ITKSNAP.fullmatch(line) or _LUT.fullmatch(line):
            raise IsoflowError(f"{where}: line {n}: a line 'index name' is expected, as line {number} is, not one "
                               f"with colour columns: {_shown(line)}; a colour table gives each line its colour")
        match = _PAIR.fullmatch(line)
        if match is None:
            raise IsoflowError(f"{where}: line {n}: a line 'index name' is expected, as line {number} is, not "
                               f"{_shown(line)}")
        if _NUMBERS.fullmatch(match[2]) and len(match[2].split()) > 1:
            # "2 255 0 0": colour columns without a name, or a row of values (one number may be a name: "1 17")
            raise IsoflowError(f"{where}: line {n}: a line 'index name' is expected, not one whose name is "
                               f"numbers alone: {_shown(line)}; a colour table line is 'index name R G B A'")
        pairs.append((int(match[1]), match[2], f"line {n}"))
    return pairs


def _csv_records(rows: list[tuple[int, str]], text: str, where: str,
                 delimiter: str) -> Iterator[tuple[int, list[str], str]]:
    """(line number, cells, text) of each record of a CSV or TSV table
    whose lines that are neither blank nor comments, from its first record
    on, are ``rows`` (number, text) of the file ``text``, as Python's csv
    module reads them: a quoted cell may hold line breaks, so a record may
    span lines (a ``#`` at the start of a cell's second line is no
    comment). A cell past the csv module's field limit, and a quoted cell
    still open at the end of the file, are refused naming the line."""
    if not any(line.count('"') % 2 for _, line in rows):
        # no line ends inside a quoted cell (that takes an odd count of quotes): a record a line
        reader = csv.reader([line for _, line in rows], delimiter=delimiter)
        try:
            for (n, line), cells in zip(rows, reader):
                yield n, cells, line
        except csv.Error as exc:
            raise _csv_refusal(exc, where, rows[reader.line_num - 1][0]) from None
        return
    first = rows[0][0]
    lines = text.splitlines(keepends=True)[first - 1:]
    at = 0
    fresh = True  # the reader asks for a record's first line: a comment or blank line is skipped there

    def feed():
        nonlocal at, fresh
        while at < len(lines):
            line = lines[at]
            at += 1
            if fresh and (not line.strip() or line.lstrip().startswith("#")):
                continue
            fresh = False
            yield line

    reader = csv.reader(feed(), delimiter=delimiter)
    while True:
        fresh, begin = True, at
        try:
            cells = next(reader)
        except StopIteration:
            return
        except csv.Error as exc:
            raise _csv_refusal(exc, where, first + at - 1) from None
        begin = next(k for k in range(begin, at) if lines[k].strip() and not lines[k].lstrip().startswith("#"))
        record = "".join(lines[begin:at])
        if at - begin > 1 and at == len(lines) and record.count('"') % 2:
            raise IsoflowError(f"{where}: line {first + begin}: a quoted cell opened here is not closed before the "
                               "end of the file")
        yield first + begin, cells, record.rstrip("\r\n")


def _csv_refusal(exc: csv.Error, where: str, line: int) -> IsoflowError:
    """The one line for the csv module's error on ``line``."""
    if "field limit" in str(exc):
        return IsoflowError(f"{where}: line {line}: a cell of more than {csv.field_size_limit():,} characters, the "
                            "most Python's csv module reads in one cell")
    return IsoflowError(f"{where}: line {line}: not read as CSV ({exc})")


def _table_pairs(records: Iterable[tuple[int, list[str], str]], where: str, label_at: int,
                 name_at: int) -> list[tuple[int, str, str]]:
    """(label, name, where it is) of each record of a CSV or TSV table
    (:func:`_csv_records`)."""
    pairs = []
    for n, cells, line in records:
        if len(cells) <= max(label_at, name_at):
            raise IsoflowError(f"{where}: line {n}: {len(cells)} cells, the header's label and name columns "
                               f"need {max(label_at, name_at) + 1}: {_shown(line)}")
        match = _INTEGER.fullmatch(cells[label_at])
        if match is None:
            raise IsoflowError(f"{where}: line {n}: the label {_shown(cells[label_at])} is no integer")
        pairs.append((int(match[1]), cells[name_at].strip(), f"line {n}"))
    return pairs


def _json_pairs(text: str, where: str) -> list[tuple[int, str, str]]:
    """(label, name, where it is) of a JSON object of label to name, or
    of the name to label of an nnU-Net ``dataset.json``'s ``labels``."""
    try:
        data = json.loads(text, object_pairs_hook=list)
    except ValueError as exc:
        raise IsoflowError(f"{where}: not a file of label names (no JSON: {exc}); {EXPECTED}") from None
    if not isinstance(data, list) or (data and not isinstance(data[0], tuple)):
        raise IsoflowError(f"{where}: JSON of label names is an object, not {type(data).__name__}; {EXPECTED}")
    inner = next((i for i, (k, v) in enumerate(data) if k == "labels" and isinstance(v, list) and all(
        isinstance(p, tuple) for p in v)), None)
    pairs = data if inner is None else data[inner][1]
    keys, children = _json_keys(text)
    lines = keys[0] if inner is None else keys[children[(0, inner)]]
    out = []
    by_label = all(_INTEGER.fullmatch(k) for k, _ in pairs)  # isoflow's label_names, nnU-Net v1's "labels"
    for (key, value), line in zip(pairs, lines):
        at = f"line {line}"
        if by_label:
            if not isinstance(value, str):
                raise IsoflowError(f"{where}: {at}: the name of label {key.strip()} is {json.dumps(value)}, not a "
                                   "string")
            out.append((int(key), value, at))
            continue
        # name to label: a dataset.json's "labels"
        if isinstance(value, list) and all(isinstance(v, int) for v in value):
            raise IsoflowError(f"{where}: {at}: {json.dumps(key)} is a region of labels {value} (nnU-Net's "
                               "region-based training), not one label")
        if isinstance(value, bool) or not isinstance(value, int):
            raise IsoflowError(f"{where}: {at}: {json.dumps(key)}: {json.dumps(value)} is no label; {EXPECTED}")
        out.append((value, key, at))
    return out


def _json_keys(text: str) -> tuple[list[list[int]], dict[tuple[int, int], int]]:
    """Where the keys of valid JSON ``text`` are: the line of each key of
    each object (objects numbered in the order they open, the outermost 0),
    and the object that is the value of key ``k`` of object ``o`` by
    ``(o, k)``. Keys are told by their place, after ``{`` or ``,`` in an
    object, so a key's text inside a string or as a key of another object
    is not taken for it."""
    breaks = [m.start() for m in re.finditer("\n", text)]
    keys: list[list[int]] = []
    children: dict[tuple[int, int], int] = {}
    stack: list[int | None] = []  # the open containers: an object's number, None for an array
    previous = ""
    for match in re.finditer(r'"(?:[^"\\]|\\.)*"|[{}\[\]:,]', text):
        token = match.group()
        if token == "{":
            if previous == ":" and stack and stack[-1] is not None:
                children[(stack[-1], len(keys[stack[-1]]) - 1)] = len(keys)
            stack.append(len(keys))
            keys.append([])
        elif token == "[":
            stack.append(None)
        elif token in "]}":
            stack.pop()
        elif token.startswith('"') and previous in ("{", ",") and stack and stack[-1] is not None:
            keys[stack[-1]].append(bisect.bisect(breaks, match.start()) + 1)
        previous = token if not token.startswith('"') else '"'
    return keys, children


def _shown(line: str, width: int = 60) -> str:
    """A line of the file as a refusal quotes it: one line, cut short."""
    text = line_text(line.strip())
    return repr(text if len(text) <= width else text[:width - 3] + "...")
