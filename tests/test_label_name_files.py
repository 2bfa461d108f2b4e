"""Label names from a side file (issue: the label images most people hold
are NIfTI or MGH, which keep no names; the names live in a file beside
them): ``isoflow.read_label_names`` reads a FreeSurfer or 3D Slicer colour
table, an ITK-SNAP label description file, CSV/TSV and JSON (nnU-Net's
``dataset.json`` too), each written here by hand in the tool's own layout
and compared with the names written; ``info --labels --names FILE`` and
``surface --labels --names FILE`` put them in the table and the GLB's node
extras; a file that is none of these is one line, exit 2."""

import csv
import io
import json
import os
import re
import struct
import subprocess
import sys

import numpy as np
import pytest
from in_process import isoflow_here

import isoflow
from isoflow.cli import main
from isoflow.errors import IsoflowError

#: FreeSurferColorLUT.txt's own lines (its header, label 0 and a few structures)
FREESURFER = """#$Id: FreeSurferColorLUT.txt,v 1.70.2.7 2012/08/27 17:20:08 mreuter Exp $

#No. Label Name:                            R   G   B   A

0   Unknown                                 0   0   0   0
2   Left-Cerebral-White-Matter              245 245 245 0
3   Left-Cerebral-Cortex                    205 62  78  0

17  Left-Hippocampus                        220 216 20  0
53  Right-Hippocampus                       220 216 20  0
"""
FREESURFER_NAMES = {2: "Left-Cerebral-White-Matter", 3: "Left-Cerebral-Cortex", 17: "Left-Hippocampus",
                    53: "Right-Hippocampus"}

#: a 3D Slicer colour table (GenericAnatomyColors.ctbl's layout)
SLICER = """# Color table file C:/Slicer/GenericAnatomyColors.ctbl
# 3 values
0 background 0 0 0 0
1 tissue 128 174 128 255
2 bone 241 214 145 255
"""
SLICER_NAMES = {1: "tissue", 2: "bone"}

#: ITK-SNAP's label description file as it saves one
ITKSNAP = """################################################
# ITK-SnAP Label Description File
# File format:
# IDX   -R-  -G-  -B-  -A--  VIS MSH  LABEL
# Fields:
#    IDX:   Zero-based index
#    -R-:   Red color component (0..255)
#    -G-:   Green color component (0..255)
#    -B-:   Blue color component (0..255)
#    -A-:   Label transparency (0.00 .. 1.00)
#    VIS:   Label visibility (0 or 1)
#    IDX:   Label mesh visibility (0 or 1)
#  LABEL:   Label description
################################################
    0     0    0    0        0  0  0    "Clear Label"
    1   255    0    0        1  1  1    "Label 1"
    2     0  255    0        1  1  1    "Left lung"
    7     0    0  255     0.75  1  0    "Tumour, core"
"""
ITKSNAP_NAMES = {1: "Label 1", 2: "Left lung", 7: "Tumour, core"}

#: nnU-Net v2's dataset.json (TotalSegmentator's models are nnU-Net's)
DATASET_JSON = json.dumps({"channel_names": {"0": "CT"},
                           "labels": {"background": 0, "spleen": 1, "kidney_right": 2, "liver": 5},
                           "numTraining": 10, "file_ending": ".nii.gz"}, indent=4)
DATASET_NAMES = {1: "spleen", 2: "kidney_right", 5: "liver"}

FILES = {
    "FreeSurferColorLUT.txt": (FREESURFER, FREESURFER_NAMES),
    "GenericAnatomyColors.ctbl": (SLICER, SLICER_NAMES),
    "labels.txt": (ITKSNAP, ITKSNAP_NAMES),
    "names.csv": ("label,name\n0,background\n1,liver\n3,\"spleen, left\"\n", {1: "liver", 3: "spleen, left"}),
    "names.tsv": ("index\tname\n4\tkidney\n2\tleft lung\n", {2: "left lung", 4: "kidney"}),
    "values.csv": ("value,label_name,volume\n1,liver,20\n2,spleen,3\n", {1: "liver", 2: "spleen"}),
    # 3D Slicer's CSV colour table
    "slicer.csv": ("LabelValue,Name,Color_R,Color_G,Color_B,Color_A\n1,tissue,128,174,128,255\n",
                   {1: "tissue"}),
    "label_names.json": ('{"1": "spleen", "2": "kidney_right"}', {1: "spleen", 2: "kidney_right"}),
    "dataset.json": (DATASET_JSON, DATASET_NAMES),
    # nnU-Net v1's dataset.json, label to name
    "dataset_v1.json": ('{"name": "Task09_Spleen", "labels": {"0": "background", "1": "spleen"}}', {1: "spleen"}),
}


@pytest.mark.parametrize("name", sorted(FILES))
def test_each_kind_of_side_file_reads_as_the_names_written(tmp_path, name):
    text, names = FILES[name]
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    assert isoflow.read_label_names(path) == names
    # the content tells the kind, not the name: a colour table or JSON under another suffix too
    if not name.endswith((".csv", ".tsv")):
        other = tmp_path / "names.lut"
        other.write_text(text, encoding="utf-8")
        assert isoflow.read_label_names(other) == names
    # label_table and write_labels take what it gives
    assert isoflow.label_table(np.array([[0, 1]]), names=isoflow.read_label_names(path))["name"].tolist() == [
        names.get(1, "")]


def test_a_path_given_for_names_names_the_reader(tmp_path):
    with pytest.raises(IsoflowError, match=r"read_label_names\(path\)"):
        isoflow.label_table(np.array([[0, 1]]), names=str(tmp_path / "lut.txt"))


def test_a_missing_file_of_names_is_said_missing_as_every_missing_input_is(tmp_path, capsys):
    """read_label_names of a file that is not there said "cannot read the
    label names (No such file or directory)", an IsoflowError only, where
    every other reader of a missing input says "no such file or directory"
    in a FileNotFoundError, what open() raises; the command line's --names
    said it so too."""
    gone = tmp_path / "gone.txt"
    with pytest.raises(FileNotFoundError) as caught:
        open(gone, "rb")  # the error the standard library gives
    with pytest.raises(IsoflowError) as mine:
        isoflow.read_label_names(gone)
    assert isinstance(mine.value, type(caught.value))
    assert str(mine.value) == f"{gone}: no such file or directory"
    labels = tmp_path / "labels.npy"
    np.save(labels, np.ones((2, 2, 2), np.uint8))
    code, out, err = said(capsys, "info", labels, "--labels", "--names", gone)
    assert code == 2 and err == [f"isoflow info: error: --names {gone}: no such file or directory"]


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="a named pipe is POSIX's")
def test_a_pipe_given_for_names_is_refused_not_read_forever(tmp_path):
    """read_label_names read its file whole: a named pipe (or a device,
    /dev/zero) was read until a writer came or memory ran out, where the
    volume and point readers refuse "not a regular file". Run in a child
    process, so that a reader that waits fails the test by its timeout."""
    pipe = tmp_path / "names.txt"
    os.mkfifo(pipe)
    code = f"import isoflow\ntry:\n    isoflow.read_label_names({str(pipe)!r})\nexcept isoflow.IsoflowError as e:\n    print(e)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip() == f"{pipe}: not a regular file (a device, pipe or socket)", done.stderr[-2000:]


@pytest.fixture
def seg(tmp_path):
    """A NIfTI label image of FreeSurfer's labels 2, 17 and 53 (NIfTI keeps no names)."""
    labels = np.zeros((10, 8, 6), np.int16)
    labels[1:4, 1:4, 1:4], labels[5:9, 1:3, 1:5], labels[5:8, 4:7, 2:4] = 2, 17, 53
    return isoflow.write_labels(labels, tmp_path / "seg.nii.gz", pitch=1.0)


def said(capsys, *args):
    code = main([*map(str, args)])
    out, err = capsys.readouterr()
    return code, out, [line for line in err.splitlines() if "numba is compiling" not in line]


def test_info_labels_names_each_row_from_the_side_file(tmp_path, capsys, seg):
    lut = tmp_path / "FreeSurferColorLUT.txt"
    lut.write_text(FREESURFER)
    code, out, err = said(capsys, "info", seg, "--labels", "--names", lut, "--json", "--no-surfaces")
    assert code == 0, err
    rows = json.loads(out)["labels"]
    assert [(r["label"], r["name"]) for r in rows] == [(k, FREESURFER_NAMES[k]) for k in (2, 17, 53)]
    # the LUT's name for label 3, which the image has not, is counted in a note that -q drops
    assert err == [f"isoflow info: note: {lut}: 1 of its 4 label names is for a label the image does not have "
                   "(not used)"]
    code, out, err = said(capsys, "info", seg, "--labels", "--names", lut, "--json", "--no-surfaces", "-q")
    assert code == 0 and err == []


def test_names_given_replace_the_files_own_with_a_note(tmp_path, capsys):
    labels = np.zeros((6, 5, 4), np.uint8)
    labels[:2], labels[3:] = 1, 2
    path = isoflow.write_labels(labels, tmp_path / "seg.npz", names={1: "liver", 2: "spleen"})
    names = tmp_path / "names.csv"
    names.write_text("label,name\n2,Spleen\n")
    code, out, err = said(capsys, "info", path, "--labels", "--names", names, "--json", "--no-surfaces")
    assert code == 0
    assert [r["name"] for r in json.loads(out)["labels"]] == ["liver", "Spleen"]
    assert len(err) == 1 and "replace those the file records for 1 label (label 2 'spleen' as 'Spleen')" in err[0]


def test_surface_labels_glb_records_the_side_files_names_in_node_extras(tmp_path, capsys, seg):
    lut = tmp_path / "labels.txt"
    lut.write_text(ITKSNAP.replace("    1   255", "   17   255").replace("    2     0", "   53     0")
                   .replace("    7     0", "    2     0"))
    out = tmp_path / "seg.glb"
    code, _, err = said(capsys, "surface", seg, "--labels", "-o", out, "--names", lut)
    assert code == 0, err
    data = out.read_bytes()
    # the GLB's JSON chunk, as the glTF 2.0 specification lays it out: header, chunk length, "JSON"
    length, kind = struct.unpack_from("<I4s", data, 12)
    assert kind == b"JSON"
    nodes = json.loads(data[20:20 + length])["nodes"]
    assert [(n["name"], n["extras"]["name"]) for n in nodes] == [
        ("label_2", "Tumour, core"), ("label_17", "Label 1"), ("label_53", "Left lung")]


@pytest.mark.parametrize(("text", "words"), [
    ("just some words\n", "not a file of label names (line 1 reads 'just some words'); expected a FreeSurfer"),
    ("0 Unknown 0 0 0 0\n17 Left-Hippocampus 220 216 20 0\n17 Right 1 2 3 0\n",
     "line 3: label 17 is named again (first on line 2)"),
    ('{"1": "spleen",\n "1": "liver"}', "line 2: label 1 is named again (first on line 1)"),
    ('{"labels": {"background": 0, "tumour": [1, 2]}}', "is a region of labels [1, 2]"),
    ("0 Unknown 0 0 0 0\n", "names no label but the background (0)"),
    ("a,b\n1,liver\n", "a header naming a label column"),
    ("", "holds no label names"),
])
def test_a_file_that_is_no_list_of_names_is_one_line_exit_2(tmp_path, capsys, seg, text, words):
    bad = tmp_path / ("bad.csv" if text.startswith("a,b") else "bad.txt")
    bad.write_text(text)
    code, out, err = said(capsys, "info", seg, "--labels", "--names", bad)
    assert code == 2 and out == "" and len(err) == 1, err
    assert err[0].startswith(f"isoflow info: error: --names {bad}: ") and words in err[0], err[0]
    with pytest.raises(IsoflowError, match=r"^" + str(bad).replace("\\", r"\\")):
        isoflow.read_label_names(bad)


def test_a_volume_given_for_its_names_and_names_without_labels_are_refused(tmp_path, capsys, seg):
    code, _, err = said(capsys, "surface", seg, "--labels", "-o", tmp_path / "s.glb", "--names", seg)
    assert code == 2 and len(err) == 1 and "a label image, not a side file of label names" in err[0]
    assert not (tmp_path / "s.glb").exists()
    code, _, err = said(capsys, "info", seg, "--names", seg)
    assert code == 2 and len(err) == 1 and "--names names the labels of --labels" in err[0]


def test_a_plain_list_of_index_and_name_reads_as_written(tmp_path):
    names = tmp_path / "labels.txt"
    names.write_text("# label name\n1 liver\n2\tleft kidney  \n\n0 background\n")
    assert isoflow.read_label_names(names) == {1: "liver", 2: "left kidney"}


@pytest.mark.parametrize(("text", "words"), [
    ("1 liver\n2 spleen 255 0 0 0\n", "line 2: a line 'index name' is expected, as line 1 is, not one with colour"),
    ("1 liver\nspleen\n", "line 2: a line 'index name' is expected, as line 1 is, not 'spleen'"),
])
def test_a_plain_list_with_a_line_of_another_kind_is_refused_naming_it(tmp_path, text, words):
    bad = tmp_path / "labels.txt"
    bad.write_text(text)
    with pytest.raises(IsoflowError, match=re.escape(words)):
        isoflow.read_label_names(bad)


def test_a_csv_cell_quoted_across_lines_reads_as_the_csv_module_reads_it(tmp_path):
    """A quoted cell may hold a line break (legal CSV, as a spreadsheet
    writes a cell with Alt+Enter); the table was split into lines before
    the csv module saw it, so the cell's second line was refused as a row
    of one cell. Each name is the csv module's cell, its line break
    escaped as any name's is."""
    text = 'label,name\n1,"left\n# lobe, no comment"\n2,"a ""quoted"" name"\n3,spleen\n'
    path = tmp_path / "names.csv"
    path.write_text(text)
    want = {int(row["label"]): row["name"].replace("\n", "\\n") for row in csv.DictReader(io.StringIO(text))}
    assert isoflow.read_label_names(path) == want


def test_a_csv_cell_past_the_csv_module_s_limit_is_one_line_exit_2(tmp_path, capsys, seg):
    """A cell longer than the csv module's field limit raised its
    ``_csv.Error`` through the command line as a traceback."""
    path = tmp_path / "names.csv"
    path.write_text("label,name\n1,liver\n2," + "x" * (csv.field_size_limit() + 1) + "\n")
    code, out, err = said(capsys, "info", seg, "--labels", "--names", path)
    assert code == 2 and out == "" and len(err) == 1, err
    assert err[0].startswith(f"isoflow info: error: --names {path}: line 3: ") and "Traceback" not in err[0]


@pytest.mark.parametrize("lines", [
    # the label's name is also a key of the outer object, on an earlier line
    ['{"name": "kits",', ' "labels": {"background": 0,', '  "kidney": 1,', '  "name": 1}}'],
    # the key's text, quotes and colon, ends another key
    ['{"labels": {"background": 0,', '  "kidney \\"tumour": 1,', '  "tumour": 1}}'],
])
def test_a_json_label_named_twice_is_refused_naming_the_line_of_its_key(tmp_path, lines):
    path = tmp_path / "dataset.json"
    path.write_text("\n".join(lines))
    labels = json.loads(path.read_text(), object_pairs_hook=list)
    assert dict(labels)["labels"][-1][1] == 1  # the last label repeats label 1, on the file's last line
    with pytest.raises(IsoflowError, match=re.escape(f"line {len(lines)}: label 1 is named again (first on line "
                                                     f"{len(lines) - 1})")):
        isoflow.read_label_names(path)


@pytest.mark.parametrize(("text", "words"), [
    ("0 0 0\n1 1 1\n", "looks like a point list (lines of three numbers, line 1 reads '0 0 0')"),
    ("# x y z\n0,0,0\n1, 2, 3\n", "looks like a point list (lines of three numbers, line 2 reads '0,0,0')"),
    ("1 0.5 2\n2 1 1 1\n", "holds numbers, not label names"),
    ("1 liver\n2 255 0 0\n", "line 2: a line 'index name' is expected, not one whose name is numbers alone"),
])
def test_numbers_given_for_names_are_refused_not_read_as_labels(tmp_path, text, words):
    """A point list given for the names read "0 0 0\\n1 1 1" as label 1
    named '1 1': each line of numbers alone took its first as the label and
    the rest as the name. It is one line saying what the file looks like;
    the point list is what numpy reads it as, and a named line still reads."""
    bad = tmp_path / "labels.txt"
    bad.write_text(text)
    if "point list" in words:
        assert np.loadtxt(bad, delimiter="," if "," in text else None).shape[1] == 3
    with pytest.raises(IsoflowError, match=re.escape(words)):
        isoflow.read_label_names(bad)
    bad.write_text("1 liver\n2 17\n")  # one number may be a name (a region's code)
    assert isoflow.read_label_names(bad) == {1: "liver", 2: "17"}


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-be"])
def test_a_utf16_table_of_names_reads_as_the_text_it_is(tmp_path, seg, encoding):
    """Excel's "Unicode Text" (and PowerShell's ``>``) writes UTF-16 behind
    a byte-order mark: its half NUL bytes were refused as "binary data",
    though Python's codecs read it as the table it is. ``--names`` reads
    it so: each row is named as the decoded text says, exit 0."""
    table = "label\tname\r\n2\tLeft-Cerebral-White-Matter\r\n17\tHippocampus ø\r\n53\tRight-Hippocampus\r\n"
    data = table.encode(encoding)
    if encoding == "utf-16-be":  # (Python's utf-16-be writes no byte-order mark; Windows tools do)
        data = b"\xfe\xff" + data
    path = tmp_path / "names.txt"
    path.write_bytes(data)
    assert b"\0" in data and data.decode("utf-16") == table
    want = {int(k): v for k, v in csv.reader(io.StringIO(data.decode("utf-16")), delimiter="\t") if k != "label"}
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", str(seg), "--labels", "--names", str(path),
                           "--json", "--no-surfaces", "-q"], capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert {r["label"]: r["name"] for r in json.loads(done.stdout)["labels"]} == want


@pytest.mark.parametrize("encoding", ["utf-16-le", "utf-16-be"])
def test_utf16_names_without_a_byte_order_mark_read_as_their_text(tmp_path, encoding):
    """Some Windows tools write UTF-16 without a byte-order mark; the
    point-list reader took such text, ``--names`` refused it as "binary
    data". Read from the shell, every other byte NUL in one order and the
    file decoding so, the names are the text Python's codec reads, a
    non-ASCII letter kept; a run of NUL bytes stays binary data."""
    labels = np.zeros((6, 6, 6), np.uint8)
    labels[1:3, 1:3, 1:3], labels[4, 4, 4] = 1, 2
    image = tmp_path / "labels.npy"
    np.save(image, labels)
    path = tmp_path / "names.txt"
    path.write_text("1 liver\n2 rein gauche é\n", encoding=encoding)
    assert not path.read_bytes().startswith((b"\xff\xfe", b"\xfe\xff")) and b"\0" in path.read_bytes()
    want = dict(line.split(" ", 1) for line in path.read_text(encoding=encoding).splitlines())
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", str(image), "--labels", "--names", str(path),
                           "--json", "--no-surfaces", "-q"], capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert {str(r["label"]): r["name"] for r in json.loads(done.stdout)["labels"]} == want
    path.write_bytes(bytes(64))
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", str(image), "--labels", "--names", str(path)],
                          capture_output=True, text=True)
    assert done.returncode == 2 and "holds binary data" in done.stderr and "Traceback" not in done.stderr


@pytest.mark.parametrize(("name", "text"), [
    ("names.csv", 'index;name\r\n2;Left-Cerebral-White-Matter\r\n17;"Hippocampus; left"\r\n53;Right, Hippocampus\r\n'),
    ("names.txt", "label;name\n2;white matter\n17;hippocampus\n53;right hippocampus\n"),
    ("names.csv", 'label,name\n2,white matter\n17,"hippocampus, left"\n53,right hippocampus\n'),
])
def test_a_semicolon_csv_reads_by_its_header_and_a_quoted_comma_stays_in_its_name(tmp_path, seg, name, text):
    """A European Excel writes CSV with semicolons (``index;name``,
    ``1;liver``), its list separator; such a table was refused as having
    no header naming a label and a name column. Read from the shell, each
    row is named as Python's csv module reads the table with the
    delimiter the header splits at, and a quoted name holding the other
    separator keeps it."""
    path = tmp_path / name
    path.write_text(text)
    delimiter = ";" if text.startswith(("index;", "label;")) else ","
    want = {int(k): v for k, v in csv.reader(io.StringIO(text), delimiter=delimiter) if k not in ("index", "label")}
    assert len(want) == 3
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", str(seg), "--labels", "--names", str(path),
                           "--json", "--no-surfaces", "-q"], capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert {r["label"]: r["name"] for r in json.loads(done.stdout)["labels"]} == want


@pytest.mark.parametrize(("name", "text", "delimiter"), [
    ("names.csv", "2;white matter\n17;hippocampus, left\n53;right hippocampus\n", ";"),
    ("names.txt", "2;white matter\r\n17;hippocampus, left\r\n53;right hippocampus\r\n", ";"),
    ("names.csv", '2,white matter\n17,"hippocampus, left"\n53,right hippocampus\n', ","),
    ("names.tsv", "2\twhite matter\n17\thippocampus, left\n53\tright hippocampus\n", "\t"),
])
def test_a_table_without_a_header_reads_its_label_and_name_cells(tmp_path, seg, name, text, delimiter):
    """``1;liver`` (a European Excel's CSV without a header row) was refused
    as having no header naming a label and a name column, as ``1,liver``
    was, where the plain list ``1 liver`` reads. Each row of two cells is a
    label and its name, as Python's csv module splits it; a quoted name
    keeps its comma."""
    path = tmp_path / name
    path.write_bytes(text.encode())
    want = {int(k): v for k, v in csv.reader(io.StringIO(text), delimiter=delimiter)}
    done = subprocess.run([sys.executable, "-m", "isoflow", "info", str(seg), "--labels", "--names", str(path),
                           "--json", "--no-surfaces", "-q"], capture_output=True, text=True)
    assert done.returncode == 0 and done.stderr == "", done.stderr
    assert {r["label"]: r["name"] for r in json.loads(done.stdout)["labels"]} == want


@pytest.mark.parametrize(("text", "delimiter"), [
    ("sep=;\nindex;name\n2;white matter\n17;hippocampus, left\n53;right hippocampus\n", ";"),
    ("sep=;\r\n2;white matter\r\n17;hippocampus, left\r\n53;right hippocampus\r\n", ";"),
    ("sep=,\nlabel,name\n2,white matter\n17,hippocampus; left\n53,right hippocampus\n", ","),
    ("SEP=|\n2|white matter\n17|hippocampus; left, too\n53|right hippocampus\n", "|"),
])
def test_excels_sep_line_declares_the_separator_and_is_no_row(tmp_path, seg, text, delimiter):
    """Excel writes (and reads) a first line ``sep=;`` that names the
    separator of the cells below; it was taken for the header and refused
    ("a header naming a label column ... is expected, not 'sep=;'"). The
    line is skipped and its separator used, even where another would split
    the header (``hippocampus; left`` stays one name under ``sep=,``)."""
    path = tmp_path / "names.csv"
    path.write_text(text, newline="")
    rows = list(csv.reader(io.StringIO(text), delimiter=delimiter))[1:]
    want = {int(k): v for k, v in rows if k.isdigit()}
    assert len(want) == 3
    for command in (["info", str(seg), "--labels", "--json", "--no-surfaces"],
                    ["surface", str(seg), "--labels", "-o", str(tmp_path / "s.glb")]):
        done = isoflow_here(*command, "--names", str(path), "-q")
        assert done.returncode == 0 and done.stderr == "", done.stderr
    table = isoflow_here("info", str(seg), "--labels", "--json", "--no-surfaces", "-q", "--names", str(path)).stdout
    assert {r["label"]: r["name"] for r in json.loads(table)["labels"]} == want
    data = (tmp_path / "s.glb").read_bytes()
    # the GLB's JSON chunk, as the glTF 2.0 specification lays it out: header, chunk length, "JSON"
    length, kind = struct.unpack_from("<I4s", data, 12)
    assert kind == b"JSON"
    nodes = json.loads(data[20:20 + length])["nodes"]
    assert {int(n["name"].removeprefix("label_")): n["extras"]["name"] for n in nodes} == want


@pytest.mark.parametrize(("text", "words"), [
    ("2,white matter\n17,hippocampus, left\n", "line 2: a row 'label,name' of two cells is expected, as line 1 is, "
                                               "not '17,hippocampus, left'"),
    ("sep=;\n2 white matter\n", "line 2: a header naming a label column"),
    ("sep=;\n", "holds no label names (no line after its 'sep=;')"),
    ("2;17\n3;18\n", "holds numbers, not label names"),
])
def test_a_table_without_a_header_that_is_no_list_of_names_is_one_line(tmp_path, seg, text, words):
    path = tmp_path / "names.csv"
    path.write_text(text)
    done = isoflow_here("info", str(seg), "--labels", "--names", str(path))
    assert done.returncode == 2 and done.stdout == "" and len(done.stderr.splitlines()) == 1, done.stderr
    assert done.stderr.startswith(f"isoflow info: error: --names {path}: ") and words in done.stderr, done.stderr
