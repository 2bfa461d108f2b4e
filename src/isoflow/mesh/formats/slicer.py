"""3D Slicer segmentations, ``.seg.nrrd``: which layer of a NRRD to read.

3D Slicer (``vtkMRMLSegmentationStorageNode``) saves a segmentation as a
NRRD whose header holds a key per segment property, ``Segment{i}_ID``,
``Segment{i}_Name``, ``Segment{i}_LabelValue``, ``Segment{i}_Layer``, ...
for segments ``i = 0, 1, ...``. A segment is the voxels of its layer that
equal its label value. Segments that do not overlap share a layer, and a
file of one layer is a 3D label image; segments that overlap lie in
different layers, which Slicer stores on the first axis of a 4D array
(``kinds: list domain domain domain``, no space direction). Slicer's reader
takes a segment without ``Layer`` to have a layer of its own (its index:
the files of Slicer 4.10 and before, a 0/1 layer per segment) and one
without ``LabelValue`` to have label 1.

A 4D segmentation is no label image: ``FILE.seg.nrrd:N`` reads its layer
``N`` (0 the first) as one, with the placement of the other three axes.

A label image written with names (:func:`isoflow.write_labels`) is written
as a segmentation of one layer (:func:`segment_fields`): a segment per
name, which Slicer loads by name and isoflow reads back
(:func:`layer_names`).

Slicer writes a segment's name as UTF-8 text, through teem, which escapes
a backslash as ``\\\\`` (and a line break as ``\\n``). pynrrd decodes
every header line as ASCII, dropping the other bytes (``Vena cava \u00f8``
comes back as ``Vena cava``, a Japanese name as nothing, so as its ID):
:func:`read_header` reads each segment's name and ID again from the
header's bytes, and :class:`NamedHeader` writes them so.
"""

from __future__ import annotations

import colorsys
import io
import os
import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ...errors import IsoflowError, line_text

#: the keys of a NRRD header's per-axis fields, which lose the layer axis
AXIS_FIELDS = ("sizes", "space directions", "kinds", "spacings", "thicknesses", "axis mins", "axis maxs",
               "centerings", "labels", "units")

#: the segments a refusal lists per layer before it counts the rest
SHOWN = 8


@dataclass(frozen=True)
class Segment:
    """One segment of a 3D Slicer segmentation: its name (its ID where it
    has none), the layer that holds it and its value there."""

    name: str
    layer: int
    label: int


def segments(header: dict, where: str) -> list[Segment]:
    """The segments a NRRD header declares, in their order (empty for a
    NRRD that is no 3D Slicer segmentation: no ``Segment0_ID``).

    Parameters
    ----------
    header : dict
        The header as pynrrd reads it (its own keys as strings).
    where : str
        The file, as a refusal names it.

    Returns
    -------
    list of Segment
        One per ``Segment{i}_ID``, ``i = 0, 1, ...`` until one is missing,
        as Slicer reads them.

    Raises
    ------
    IsoflowError
        A ``Layer`` or ``LabelValue`` that is no whole number, named with
        its value.

    Examples
    --------
    >>> head = {"Segment0_ID": "Segment_1", "Segment0_Name": "liver", "Segment0_LabelValue": "3",
    ...         "Segment0_Layer": "0", "Segment1_ID": "Segment_2"}
    >>> segments(head, "a.seg.nrrd")
    [Segment(name='liver', layer=0, label=3), Segment(name='Segment_2', layer=1, label=1)]
    """
    found = []
    while f"Segment{len(found)}_ID" in header:
        i = len(found)
        name = str(header.get(f"Segment{i}_Name") or header[f"Segment{i}_ID"])
        found.append(Segment(name, _whole(header, f"Segment{i}_Layer", i, where),
                             _whole(header, f"Segment{i}_LabelValue", 1, where)))
    return found


def _whole(header: dict, key: str, default: int, where: str) -> int:
    """A header's whole number ``key``, ``default`` where it is absent."""
    text = header.get(key)
    if text is None:
        return default
    try:
        return int(str(text).strip())
    except ValueError:
        raise IsoflowError(f"{where}: NRRD field '{key}' {text!r} is no whole number") from None


def layer_of(data: np.ndarray, header: dict, layer: str | None, where: str) -> tuple[np.ndarray, dict]:
    """The array and header of a NRRD as one label image: a 3D Slicer
    segmentation's layer ``layer`` (``FILE.seg.nrrd:N``; None: the file's
    one layer), the layer axis dropped from the header's per-axis fields;
    any other NRRD as it is, with ``layer`` None.

    Parameters
    ----------
    data : numpy.ndarray
        The array as pynrrd reads it with ``index_order='F'`` (a layer axis
        first).
    header : dict
        Its header.
    layer : str or None
        What the path names after its colon.
    where : str
        The file, as a refusal names it.

    Returns
    -------
    tuple of numpy.ndarray and dict
        The array and the header to place it by.

    Raises
    ------
    IsoflowError
        A segmentation of several layers without ``layer`` (the line lists
        each layer's segments, names and values), a ``layer`` it has not,
        a layer named in a NRRD that is no segmentation, a segment in a
        layer the array has not.

    Examples
    --------
    >>> head = {"kinds": ["list", "domain", "domain", "domain"], "sizes": [2, 4, 4, 4],
    ...         "Segment0_ID": "a", "Segment0_Layer": "0", "Segment1_ID": "b", "Segment1_Layer": "1"}
    >>> array, placed = layer_of(np.zeros((2, 4, 4, 4)), head, "1", "s.seg.nrrd")
    >>> array.shape, placed["kinds"], placed["sizes"]
    ((4, 4, 4), ['domain', 'domain', 'domain'], [4, 4, 4])
    """
    found = segments(header, where)
    if not found:
        if layer is not None:
            raise IsoflowError(f"{where}:{layer}: names a layer of a 3D Slicer segmentation (.seg.nrrd), and this "
                               f"NRRD is none (its header has no field 'Segment0_ID'); give the file alone")
        return data, header
    layered = data.ndim == 4
    count = data.shape[0] if layered else 1
    _check_layers(found, count, where)
    if layer is None and count > 1:
        raise IsoflowError(f"{where}: a 3D Slicer segmentation of {count} layers, whose segments may overlap: "
                           f"read one layer as {where}:N ({listing(found, count)})")
    index = 0 if layer is None else _layer_index(layer, found, count, where)
    if not layered:
        return data, header
    _check_layer_axis(header, where)
    kept = {k: (v[1:] if k in AXIS_FIELDS and _per_axis(v, data.ndim) else v) for k, v in header.items()}
    return data[index], kept


def _per_axis(value, ndim: int) -> bool:
    """Whether a header field holds one entry per axis."""
    return not isinstance(value, str) and np.ndim(value) >= 1 and len(value) == ndim


def _check_layers(found: list[Segment], count: int, where: str) -> None:
    """Every segment's layer is one the array has."""
    for i, s in enumerate(found):
        if not 0 <= s.layer < count:
            raise IsoflowError(f"{where}: NRRD field 'Segment{i}_Layer' {str(s.layer)!r} names no layer of the "
                               f"array, which has {count} (0 to {count - 1})")


def _check_layer_axis(header: dict, where: str) -> None:
    """The layers lie on the first axis, as 3D Slicer writes them: one
    without a space direction, or of a component kind."""
    directions = header.get("space directions")
    kinds = header.get("kinds")
    placed = directions is not None and np.isfinite(np.asarray(directions[0], np.float64)).all()
    if placed or (kinds is not None and str(kinds[0]).lower() in ("domain", "space", "time")):
        field, value = ("space directions", np.asarray(directions[0]).tolist()) if placed else ("kinds", kinds[0])
        raise IsoflowError(f"{where}: NRRD field '{field}' of axis 0 is {value!r}: a 3D Slicer segmentation keeps "
                           "its layers on axis 0, of kind 'list' without a space direction")


def _layer_index(layer: str, found: list[Segment], count: int, where: str) -> int:
    """The layer that ``FILE.seg.nrrd:N`` names, or one line listing them."""
    text = layer.strip()
    if not (text.isdigit() and text.isascii()) or int(text) >= count:
        layers = "its one layer is 0" if count == 1 else f"its layers are 0 to {count - 1}"
        raise IsoflowError(f"{where}:{layer}: layer {layer!r} is no layer of this 3D Slicer segmentation; {layers} "
                           f"({listing(found, count)})")
    return int(text)


def layer_segments(path, layer: str | None) -> str | None:
    """The segments of the layer of a 3D Slicer segmentation that
    ``FILE.seg.nrrd`` (its one layer) or ``FILE.seg.nrrd:N`` reads, by
    name and label value (:func:`segment_names`), from its header alone:
    the one its read kept (:func:`remember_segments`), else parsed here;
    None for a NRRD that is no segmentation or a layer it has not (the
    reading says why).

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    layer : str or None
        What the path names after its colon.

    Returns
    -------
    str or None
        ``liver (label 1), tumor (label 2)``, or None.

    Examples
    --------
    >>> import nrrd, tempfile
    >>> path = tempfile.mkdtemp() + "/s.seg.nrrd"
    >>> nrrd.write(path, np.zeros((2, 2, 2), np.uint8), {"Segment0_ID": "Segment_1", "Segment0_Name": "liver",
    ...                                                   "Segment0_LabelValue": "1", "Segment0_Layer": "0"})
    >>> layer_segments(path, None)
    'liver (label 1)'
    """
    known = _read.get(file_identity(path))
    try:
        if known is None:
            with open(path, "rb") as fh:
                header = read_header(fh)
            known = segments(header, str(path)), layer_count(header)
        found, count = known
        _check_layers(found, count, str(path))
        index = 0 if layer is None else _layer_index(layer, found, count, str(path))
    except IsoflowError:
        return None
    return segment_names(found, index) if found and (layer is not None or count == 1) else None


def layer_count(header: dict) -> int:
    """The layers of a NRRD as a 3D Slicer segmentation holds them: the
    first axis of a 4D array, else one.

    Parameters
    ----------
    header : dict
        The header as pynrrd reads it.

    Returns
    -------
    int
        The number of layers.

    Examples
    --------
    >>> layer_count({"sizes": [3, 64, 64, 40]}), layer_count({"sizes": [64, 64, 40]})
    (3, 1)
    """
    return int(header["sizes"][0]) if len(header.get("sizes", ())) == 4 else 1


def file_identity(path) -> tuple[int, int, int, int] | None:
    """A file's device, inode, size and modification time in nanoseconds
    (a file rewritten since has another), or None where it cannot be seen.

    Parameters
    ----------
    path : str or os.PathLike
        A file or folder, as ``os.stat`` takes it.

    Returns
    -------
    tuple of int or None
        ``(st_dev, st_ino, st_size, st_mtime_ns)``.

    Examples
    --------
    >>> import tempfile
    >>> path = tempfile.mkdtemp() + "/a.seg.nrrd"
    >>> file_identity(path) is None, len(file_identity(tempfile.gettempdir()))
    (True, 4)
    """
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return None
    return st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns


#: the segments and layer count of the NRRD header read last, by its file's
#: identity (:func:`remember_segments`): one file's at a time
_read: dict[tuple[int, int, int, int] | None, tuple[list[Segment], int]] = {}


def remember_segments(path, header: dict) -> None:
    """Keep the segments and layer count of the header just read from
    ``path``, so that :func:`layer_segments` names them without parsing
    the header again (a segmentation's holds ten fields a segment); the
    file's earlier ones, or another file's, are let go. A header whose
    segments cannot be read is not kept (its reading says why).

    Parameters
    ----------
    path : str or os.PathLike
        The NRRD file the header was read from.
    header : dict
        The header as pynrrd reads it.

    Examples
    --------
    >>> import nrrd, tempfile
    >>> path = tempfile.mkdtemp() + "/s.seg.nrrd"
    >>> header = {"Segment0_ID": "Segment_1", "Segment0_Name": "liver", "Segment0_LabelValue": "2"}
    >>> nrrd.write(path, np.zeros((2, 2, 2), np.uint8), header)
    >>> remember_segments(path, {**header, "Segment0_Name": "spleen", "sizes": [2, 2, 2]})
    >>> layer_segments(path, None)  # from the header kept, not from the file's
    'spleen (label 2)'
    """
    _read.clear()
    key = file_identity(path)
    if key is None:
        return
    try:
        _read[key] = segments(header, str(path)), layer_count(header)
    except IsoflowError:
        return


def segment_names(found: list[Segment], layer: int) -> str:
    """The segments of one layer by name and label value, as
    :func:`listing` names them: ``liver (label 1), tumor (label 2)``.

    Examples
    --------
    >>> segment_names([Segment("liver", 0, 1), Segment("tumor", 0, 2), Segment("vessel", 1, 1)], 0)
    'liver (label 1), tumor (label 2)'
    """
    held = [f"{line_text(s.name)} (label {s.label})" for s in found if s.layer == layer]
    more = f", and {len(held) - SHOWN} more" if len(held) > SHOWN else ""
    return ", ".join(held[:SHOWN]) + more if held else "no segment"


def listing(found: list[Segment], count: int) -> str:
    """Each layer's segments as a refusal lists them, by name and value
    in their layer: ``layer 0: liver (label 1), tumor (label 2); layer 1:
    vessel (label 1)``.

    Parameters
    ----------
    found : list of Segment
        The segments (:func:`segments`).
    count : int
        The number of layers.

    Returns
    -------
    str
        A layer's first segments, then how many more it holds.

    Examples
    --------
    >>> listing([Segment("liver", 0, 1), Segment("tumor", 0, 2), Segment("vessel", 1, 1)], 2)
    'layer 0: liver (label 1), tumor (label 2); layer 1: vessel (label 1)'
    """
    return "; ".join(f"layer {n}: {segment_names(found, n)}" for n in range(count))


def layer_names(header: dict, layer: str | None, where: str) -> dict[int, str] | None:
    """The names of the segments of the layer that ``FILE.seg.nrrd`` (its
    one layer) or ``FILE.seg.nrrd:N`` reads, label value to name; None for
    a NRRD that is no segmentation. The header is one :func:`layer_of` has
    checked.

    Parameters
    ----------
    header : dict
        The whole file's header as pynrrd reads it (its layers counted).
    layer, where : str or None, str
        The layer and the file, as :func:`layer_of` takes them.

    Returns
    -------
    dict of int to str, or None
        In increasing order of label value.

    Examples
    --------
    >>> head = {"sizes": [2, 2, 2], "Segment0_ID": "Segment_1", "Segment0_Name": "liver",
    ...         "Segment0_LabelValue": "2", "Segment0_Layer": "0"}
    >>> layer_names(head, None, "s.seg.nrrd")
    {2: 'liver'}
    """
    found = segments(header, where)
    if not found:
        return None
    index = 0 if layer is None else _layer_index(layer, found, layer_count(header), where)
    return dict(sorted((s.label, s.name) for s in found if s.layer == index)) or None


#: a header line that holds a segment's name or ID (``Segment3_Name:=liver``)
_NAME_LINE = re.compile(rb"(Segment[0-9]+_(?:Name|ID)):=(.*?)\r?", re.DOTALL)


def read_header(fh) -> dict:
    r"""A NRRD header as pynrrd reads it from ``fh``, with each segment's
    name and ID (``Segment{k}_Name``, ``Segment{k}_ID``) as 3D Slicer
    writes them: UTF-8 text, a backslash escaped as ``\\`` (teem's
    escape). pynrrd drops every byte past ASCII from a header line and
    keeps the escape; a name is read again from the header's bytes here.
    Bytes that are no UTF-8 are read as Latin-1, one character a byte.

    Parameters
    ----------
    fh : binary file
        The NRRD file, open at its start; left at its data, as pynrrd's
        ``read_header`` leaves it.

    Returns
    -------
    dict
        The header, pynrrd's fields parsed as pynrrd parses them.

    Examples
    --------
    >>> head = b"NRRD0004\ntype: uint8\ndimension: 1\nsizes: 1\nencoding: raw\nSegment0_ID:=Segment_1\n"
    >>> head += "Segment0_Name:=Vena cava \u00f8 \\\\ 2\n\n".encode("utf-8")
    >>> read_header(io.BytesIO(head + b"\x01"))["Segment0_Name"] == "Vena cava \u00f8 \\ 2"
    True
    """
    import nrrd

    start = fh.tell()
    header = nrrd.read_header(fh)
    end = fh.tell()
    fh.seek(start)
    lines = fh.read(end - start).split(b"\n")
    fh.seek(end)
    for line in lines[1:]:
        match = _NAME_LINE.fullmatch(line)
        key = match and match[1].decode("ascii")
        if key in header:
            header[key] = header_text(match[2])
    return header


def header_text(raw: bytes) -> str:
    r"""The text of a key/value pair's value as teem writes it: UTF-8 (a
    value that is no UTF-8 read as Latin-1), ``\\`` a backslash. A ``\n``
    (teem's escaped line break) is kept as written: a label's name is one
    line.

    Examples
    --------
    >>> header_text("Leber \u00f8 a\\\\b".encode("utf-8")) == "Leber \u00f8 a\\b"
    True
    >>> header_text(b"Vena cava \xf8") == "Vena cava \u00f8"  # no UTF-8: Latin-1
    True
    """
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")
    return re.sub(r"\\\\", r"\\", text)


def header_escape(text: str) -> str:
    r"""``text`` as teem writes a key/value pair's value, which
    :func:`header_text` reads back: a backslash as ``\\``.

    Examples
    --------
    >>> header_escape("C:\\scans\\liver.stl")
    'C:\\\\scans\\\\liver.stl'
    """
    return text.replace("\\", "\\\\")


class NamedHeader(io.RawIOBase):
    r"""A binary file that pynrrd writes a segmentation into: the lines of
    its header that hold a segment's name are written as 3D Slicer (teem)
    writes them, UTF-8 with :func:`header_escape`, since pynrrd writes a
    header as ASCII; the rest passes through as written.

    Parameters
    ----------
    fh : binary file
        The file written to (left open).
    names : mapping of str to str
        Header key (``Segment0_Name``) to its text; pynrrd is given the
        key with any ASCII value, which this replaces.

    Examples
    --------
    >>> import nrrd
    >>> out = io.BytesIO()
    >>> nrrd.write(NamedHeader(out, {"Segment0_Name": "t\u00f4rus"}), np.zeros(2, np.uint8),
    ...            {"encoding": "raw", "Segment0_Name": "?"})
    >>> [line for line in out.getvalue().split(b"\n") if line.startswith(b"Segment")]
    [b'Segment0_Name:=t\xc3\xb4rus']
    """

    def __init__(self, fh, names: Mapping[str, str]) -> None:
        super().__init__()
        self._fh = fh
        self._lines = {key.encode("ascii"): header_escape(text).encode("utf-8") for key, text in names.items()}
        self._head: bytearray | None = bytearray()  # the header as written so far; None once it is out

    def writable(self) -> bool:
        return True

    def write(self, data) -> int:
        data = bytes(data)
        if self._head is None:
            return self._fh.write(data) or len(data)
        self._head += data
        end = self._head.find(b"\n\n")  # the blank line that ends a NRRD header
        if end >= 0:
            head, rest = bytes(self._head[:end + 2]), bytes(self._head[end + 2:])
            self._head = None
            self._fh.write(b"\n".join(self._line(line) for line in head.split(b"\n")) + rest)
        return len(data)

    def _line(self, line: bytes) -> bytes:
        key, sep, _ = line.partition(b":=")
        return key + sep + self._lines[key] if sep and key in self._lines else line

    def flush(self) -> None:
        if self._head is not None:  # a header never ended (pynrrd always ends it): written as it is
            self._fh.write(bytes(self._head))
            self._head = None
        self._fh.flush()


def segment_fields(names: Mapping[int, str], shape: tuple[int, ...]) -> dict[str, str]:
    """The NRRD header fields of a label image of ``shape`` whose labels
    are named, as 3D Slicer writes a segmentation of one layer: per
    segment ``k`` its ``Segment{k}_ID``, ``_Name``, ``_LabelValue``,
    ``_Layer`` (0), ``_Extent`` (the whole image) and a ``_Color``, and the
    segmentation's representation and extent offset, which Slicer's reader
    looks for. A name is given as it is: :class:`NamedHeader` writes it as
    Slicer does.

    Parameters
    ----------
    names : mapping of int to str
        Label value to name.
    shape : tuple of int
        The image's shape (x, y, z; x, y in 2D).

    Returns
    -------
    dict of str to str
        The fields, as pynrrd writes custom keys.

    Examples
    --------
    >>> fields = segment_fields({1: "a.stl", 2: "b.obj"}, (4, 3, 2))
    >>> fields["Segment1_Name"], fields["Segment1_LabelValue"], fields["Segment1_Extent"]
    ('b.obj', '2', '0 3 0 2 0 1')
    """
    extent = " ".join(f"0 {n - 1}" for n in (tuple(shape) + (1, 1, 1))[:3])
    fields = {"Segmentation_MasterRepresentation": "Binary labelmap",
              "Segmentation_ContainedRepresentationNames": "Binary labelmap|",
              "Segmentation_ReferenceImageExtentOffset": "0 0 0"}
    for k, (label, name) in enumerate(names.items()):
        # hues a golden angle apart: neighbouring labels in colours far apart, as Slicer's own table does
        rgb = colorsys.hsv_to_rgb((k * 0.618034) % 1.0, 0.6, 0.9)
        fields.update({f"Segment{k}_ID": f"Segment_{label}", f"Segment{k}_Name": name,
                       f"Segment{k}_NameAutoGenerated": "0", f"Segment{k}_LabelValue": str(label),
                       f"Segment{k}_Layer": "0", f"Segment{k}_Extent": extent,
                       f"Segment{k}_Color": " ".join(f"{c:.6g}" for c in rgb), f"Segment{k}_ColorAutoGenerated": "1",
                       f"Segment{k}_Tags": "|"})
    return fields
