"""Label names travel with the label image (issue: a label image written by
isoflow forgot which label is which mesh): ``write_labels(..., names=)``
records them where the format has a place for them, each checked with
the format's own library (pynrrd's header keys, zarr's JSON metadata,
h5py's attributes, NumPy's arrays), and ``read_labels`` gives them back;
``voxelize A B -o OUT`` writes each label's mesh, and ``info OUT --labels``
shows it; a format without such a place says so once."""

import csv
import io
import json
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh

import isoflow
from isoflow.cli import main
from isoflow.errors import IsoflowError, IsoflowWarning

NAMES = {1: "liver", 2: "spleen, left", 5: "tumour \u00e9"}
#: names pynrrd reads whole (it drops every byte of a header past ASCII)
ASCII_NAMES = {1: "liver", 2: "spleen, left", 5: 'tumour "b"'}


@pytest.fixture
def image():
    labels = np.zeros((6, 5, 4), np.uint8)
    labels[:2], labels[3:, :2], labels[4:, 3:] = 1, 2, 5
    return labels


def test_nrrd_keeps_the_names_as_3d_slicer_segments(tmp_path, image):
    import nrrd

    path = isoflow.write_labels(image, tmp_path / "seg.seg.nrrd", names=ASCII_NAMES)
    header = nrrd.read_header(str(path))
    segments = {}
    k = 0
    while f"Segment{k}_ID" in header:  # Slicer's reader stops at the first index without an ID
        segments[int(header[f"Segment{k}_LabelValue"])] = header[f"Segment{k}_Name"]
        assert header[f"Segment{k}_Layer"] == "0"
        # the extent of the whole image, in voxel indices (x0 x1 y0 y1 z0 z1)
        assert header[f"Segment{k}_Extent"] == "0 5 0 4 0 3"
        k += 1
    assert segments == ASCII_NAMES
    assert header["Segmentation_MasterRepresentation"] == "Binary labelmap"
    assert header["Segmentation_ReferenceImageExtentOffset"] == "0 0 0"
    data, _ = nrrd.read(str(path), index_order="F")
    assert np.array_equal(data, image)
    back = isoflow.read_labels(path)
    assert back.names == ASCII_NAMES and np.array_equal(back.array, image)
    # isoflow's own reading of a segmentation's layer names them alike
    from isoflow.mesh.formats.slicer import layer_segments

    assert layer_segments(path, None) == 'liver (label 1), spleen, left (label 2), tumour "b" (label 5)'


def header_names(path):
    """Each ``Segment{k}_Name`` of a NRRD header as teem (3D Slicer's
    writer and reader) reads it: the bytes after ``:=`` as UTF-8, ``\\\\``
    a backslash."""
    head = Path(path).read_bytes().split(b"\n\n", 1)[0]
    return [line.split(b":=", 1)[1].decode("utf-8").replace("\\\\", "\\")
            for line in head.split(b"\n") if line.startswith(b"Segment") and b"_Name:=" in line]


def test_a_name_past_ascii_is_written_into_nrrd_in_utf8_as_slicer_writes_it(tmp_path, image):
    """A name past ASCII was written as Python's escape (``tumour \\xe9``),
    which 3D Slicer shows as it is, with a warning: it is written as
    Slicer writes it, UTF-8 (a backslash as two, teem's escape), and read
    back as it was given."""
    names = {**NAMES, 2: "C:\\scans\\spleen", 5: "\u809d\u81d3 tumour \u00e9"}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        path = isoflow.write_labels(image, tmp_path / "seg.nrrd", names=names)
    assert header_names(path) == list(names.values())
    back = isoflow.read_labels(path)
    assert back.names == names and np.array_equal(back.array, image)


def test_voxelize_of_a_mesh_named_past_ascii_into_nrrd_keeps_its_name(tmp_path, capsys):
    a, b = _meshes(tmp_path)
    named = tmp_path / "t\u00f4rus.stl"
    Path(a).rename(named)
    out = tmp_path / "x.nrrd"
    assert main(["voxelize", str(named), b, "--resolution", "16", "-o", str(out)]) == 0
    assert capsys.readouterr().err == ""
    assert header_names(out) == [str(named), b]
    assert isoflow.read_labels(out).names == {1: str(named), 2: b}


def test_ome_zarr_keeps_the_names_as_image_label_properties(tmp_path, image):
    path = isoflow.write_labels(image, tmp_path / "seg.zarr", names=NAMES)
    attrs = json.loads((path / ".zattrs").read_text())
    assert sorted((p["label-value"], p["name"]) for p in attrs["image-label"]["properties"]) == sorted(NAMES.items())
    assert isoflow.read_labels(path).names == NAMES


def test_ome_zarr_properties_that_name_no_label_are_said_not_dropped(tmp_path, image, capsys):
    """An ``image-label`` ``properties`` entry whose label-value is no
    whole number from 1 on, or whose name is no text, was dropped without
    a word. A name that is a JSON number is kept as its JSON text; the
    others are said in one warning naming each entry and what it holds."""
    path = isoflow.write_labels(image, tmp_path / "seg.zarr")
    attrs = json.loads((path / ".zattrs").read_text())
    entries = [{"label-value": 1, "name": "liver"}, {"label-value": 2, "name": 7},
               {"label-value": "5", "name": "tumour"}, {"label-value": 5.0, "name": ["a"]}]
    attrs["image-label"] = {"version": "0.4", "properties": entries}
    (path / ".zattrs").write_text(json.dumps(attrs))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        names = isoflow.read_labels(path).names
    assert names == {1: "liver", 2: json.dumps(entries[1]["name"])}
    [said] = [str(w.message) for w in caught if issubclass(w.category, IsoflowWarning)]
    assert said.startswith(f"{path}: 2 image-label properties entries")
    assert json.dumps(entries[2]["label-value"]) in said and json.dumps(entries[3]["name"]) in said
    assert main(["info", str(path), "--labels"]) == 0
    assert [line for line in capsys.readouterr().err.splitlines() if "warning:" in line] == [
        f"isoflow info: warning: {said}"]


def test_ome_zarr_names_a_64_bit_label_past_a_float(tmp_path):
    """A ``label-value`` past 2**53 names that label, not the float
    nearest it (uint64 label images hold such values)."""
    big = 2**60 + 1
    labels = np.zeros((2, 2, 2), np.uint64)
    labels[0, 0, 0] = big
    path = isoflow.write_labels(labels, tmp_path / "seg.zarr", names={big: "cell"})
    assert isoflow.read_labels(path).names == {big: "cell"}


def test_hdf5_keeps_the_names_as_a_dataset_attribute(tmp_path, image):
    import h5py

    path = isoflow.write_labels(image, tmp_path / "seg.h5", names=NAMES)
    with h5py.File(path) as f:
        text = f["volume"].attrs["label_names"]
    assert {int(k): v for k, v in json.loads(text).items()} == NAMES
    assert isoflow.read_labels(path).names == NAMES


def test_npz_keeps_the_names_as_a_second_array(tmp_path, image):
    path = isoflow.write_labels(image, tmp_path / "seg.npz", names=NAMES)
    with np.load(path) as z:
        assert {int(k): v for k, v in json.loads(str(z["label_names"])).items()} == NAMES
        assert np.array_equal(z["volume"], image)
    assert isoflow.read_labels(path).names == NAMES


def test_a_sequence_names_labels_from_one_and_a_label_image_passes_its_names_on(tmp_path, image):
    first = isoflow.read_labels(isoflow.write_labels(image, tmp_path / "a.nrrd", names=["a", "b", "c", "d", "e"]))
    assert first.names == {1: "a", 2: "b", 3: "c", 4: "d", 5: "e"}
    again = isoflow.read_labels(isoflow.write_labels(first, tmp_path / "b.h5"))
    assert again.names == first.names
    # names given replace the image's, as pitch and origin do
    other = isoflow.read_labels(isoflow.write_labels(first, tmp_path / "c.npz", names={2: "x"}))
    assert other.names == {2: "x"}


def test_a_file_without_names_reads_as_none_and_its_table_has_no_name_column(tmp_path, image):
    for suffix in (".nrrd", ".h5", ".npz", ".zarr"):
        back = isoflow.read_labels(isoflow.write_labels(image, tmp_path / f"plain{suffix}"))
        assert back.names is None
        assert "name" not in isoflow.label_table(back)


def test_label_table_gains_a_name_column_only_where_given_names(image):
    plain = isoflow.label_table(image, surfaces=False)
    named = isoflow.label_table(image, surfaces=False, names={5: "tumour"})
    assert list(named) == ["label", "name"] + list(plain)[1:]
    assert named["name"].tolist() == ["", "", "tumour"]
    for column in plain:
        assert np.array_equal(named[column], plain[column])
    image_named = isoflow.LabelImage(image, np.ones(3), np.zeros(3), names=NAMES)
    assert isoflow.label_table(image_named, surfaces=False)["name"].tolist() == ["liver", "spleen, left", "tumour \u00e9"]


def test_nifti_says_once_that_it_keeps_no_names_and_nothing_without_names(tmp_path, image):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        isoflow.write_labels(image, tmp_path / "seg.nii.gz", names=NAMES)
    said = [str(w.message) for w in caught if issubclass(w.category, IsoflowWarning)]
    assert len(said) == 1 and "label names" in said[0] and "not written" in said[0], said
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        isoflow.write_labels(image, tmp_path / "plain.nii.gz")
    assert isoflow.read_labels(tmp_path / "seg.nii.gz").names is None


@pytest.mark.parametrize("names", [{0: "background"}, {1.5: "a"}, {1: 3}, ["a\nb"], "ab"])
def test_names_that_are_no_label_names_are_refused(tmp_path, image, names):
    with pytest.raises(IsoflowError):
        isoflow.write_labels(image, tmp_path / "seg.nrrd", names=names)
    assert not (tmp_path / "seg.nrrd").exists()


def _meshes(tmp_path):
    box = trimesh.creation.box(extents=(2, 2, 2))
    box.export(tmp_path / "a.stl")
    ball = trimesh.creation.icosphere(radius=1.0)
    ball.apply_translation((3, 0, 0))
    ball.export(tmp_path / "b.obj")
    return str(tmp_path / "a.stl"), str(tmp_path / "b.obj")


@pytest.mark.parametrize("suffix", [".nrrd", ".zarr"])
def test_voxelize_writes_each_labels_mesh_and_info_shows_it(tmp_path, capsys, suffix):
    a, b = _meshes(tmp_path)
    out = str(tmp_path / f"x{suffix}")
    assert main(["voxelize", a, b, "--resolution", "16", "-o", out]) == 0
    capsys.readouterr()
    assert main(["info", out, "--labels", "--json", "--no-surfaces"]) == 0
    rows = json.loads(capsys.readouterr().out)["labels"]
    assert [(r["label"], r["name"]) for r in rows] == [(1, a), (2, b)]
    assert main(["info", out, "--labels", "--csv", "-", "--no-surfaces"]) == 0
    table = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert [(r["label"], r["name"]) for r in table] == [("1", a), ("2", b)]
    assert main(["info", out, "--labels"]) == 0
    text = capsys.readouterr().out.splitlines()
    assert text[1].split()[-1] == "name" and text[2].endswith(f"  {a}") and text[3].endswith(f"  {b}")


def test_csv_quotes_a_name_as_the_csv_module_reads_it(tmp_path, capsys, image):
    path = isoflow.write_labels(image, tmp_path / "seg.h5", names=NAMES)
    assert main(["info", str(path), "--labels", "--csv", "-", "--no-surfaces"]) == 0
    table = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert {int(r["label"]): r["name"] for r in table} == NAMES


def test_voxelize_into_nifti_notes_once_that_the_names_are_not_written(tmp_path, capsys):
    a, b = _meshes(tmp_path)
    out = tmp_path / "x.nii.gz"
    assert main(["voxelize", a, b, "--resolution", "16", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert [line for line in err.splitlines() if "label names" in line] == [
        f"isoflow voxelize: note: {out}: NIfTI has no place for label names; the names of 2 labels are not "
        "written (.nrrd, .h5, .zarr and .npz keep them)"]
    assert "warning:" not in err  # the names are the command's own: a note, which -q drops
    assert main(["voxelize", a, b, "--resolution", "16", "-o", str(out), "--force", "-q"]) == 0
    assert "label names" not in capsys.readouterr().err


def test_surface_labels_glb_keeps_node_names_label_n_and_records_the_name_in_extras(tmp_path, capsys, image):
    import struct

    path = isoflow.write_labels(image, tmp_path / "seg.h5", names=NAMES)
    out = tmp_path / "s.glb"
    assert main(["surface", str(path), "--labels", "-o", str(out)]) == 0
    data = out.read_bytes()
    # the GLB's JSON chunk, as the glTF 2.0 specification lays it out: header, chunk length, "JSON"
    length, kind = struct.unpack_from("<I4s", data, 12)
    assert kind == b"JSON"
    nodes = json.loads(data[20:20 + length])["nodes"]
    assert [(n["name"], n["extras"]["name"]) for n in nodes] == [(f"label_{k}", v) for k, v in NAMES.items()]


def test_a_name_with_a_line_break_or_a_control_character_in_a_file_is_read_as_one_line(tmp_path, capsys, image):
    """HDF5's and an ``.npz``'s JSON, and NGFF's ``properties``, hold any
    name: a name with a line break, written by h5py, made the file
    unreadable (``LabelImage: the name of label 1 is 'a\\nb', not a string
    of one line``), and a name holding a terminal's escape was printed for
    the terminal to act on. The file is read, each name one line that
    ``write_labels`` writes again, and the table's rows are one line each,
    of printable text."""
    import h5py

    given = {1: "left\nlobe", 2: "\x1b[31mred\x1b[0m", 5: "tab\there"}
    path = tmp_path / "foreign.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("volume", data=image).attrs["label_names"] = json.dumps(given)
    names = isoflow.read_labels(path).names
    assert sorted(names) == sorted(given) and not any("\n" in n or "\r" in n for n in names.values())
    assert names[2] == given[2] and names[5] == given[5]
    again = isoflow.read_labels(isoflow.write_labels(isoflow.read_labels(path), tmp_path / "again.zarr"))
    assert again.names == names
    assert main(["info", str(path), "--labels", "--no-surfaces"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert len(lines) == 2 + len(given) + 1 and all(line.isprintable() for line in lines)
    assert main(["info", str(path), "--labels", "--json", "--no-surfaces"]) == 0
    assert {r["label"]: r["name"] for r in json.loads(capsys.readouterr().out)["labels"]} == names


def test_surface_labels_of_a_named_image_notes_which_label_file_is_which(tmp_path, capsys, image):
    """``surface LABELS.h5 --labels -o DIR/`` writes ``label_N`` files,
    which keep no name: a note says each label's name, as a 3D Slicer
    segmentation's note does; ``-q`` drops it."""
    import h5py

    path = tmp_path / "seg.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("volume", data=image).attrs["label_names"] = json.dumps(NAMES)
    assert main(["surface", str(path), "--labels", "-o", str(tmp_path / "out") + "/", "--suffix", ".ply"]) == 0
    said = ", ".join(f"{name} (label {label})" for label, name in NAMES.items())
    assert f"isoflow surface: note: {path}: label names {said}\n" in capsys.readouterr().err
    assert main(["surface", str(path), "--labels", "-q", "-o", str(tmp_path / "q") + "/", "--suffix", ".ply"]) == 0
    assert "label names" not in capsys.readouterr().err

def test_an_array_of_names_gives_plain_strings(tmp_path, image):
    # NumPy's np.str_ was kept: the names printed as np.str_('liver') in the image's repr
    named = isoflow.LabelImage(image, 1.0, (0, 0, 0), names=np.array(["liver", "spleen"]))
    assert named.names == {1: "liver", 2: "spleen"}
    assert all(type(name) is str for name in named.names.values())
    assert "np.str_" not in repr(named)


@pytest.mark.parametrize("names", [np.array("liver"), np.array([["liver"]])])
def test_an_array_of_names_that_is_not_one_row_is_refused_naming_them(image, names):
    # a 0D array raised NumPy's TypeError "iteration over a 0-d array", naming no argument
    with pytest.raises(IsoflowError, match=r"^label_table: names: names are a mapping of label to name or a sequence"):
        isoflow.label_table(image, names=names)


def slicer_segments(header):
    """Label value to (name, NameAutoGenerated) of each segment of a NRRD
    header as pynrrd reads it, as 3D Slicer's reader walks them."""
    found, k = {}, 0
    while f"Segment{k}_ID" in header:
        found[int(header[f"Segment{k}_LabelValue"])] = (header[f"Segment{k}_Name"],
                                                        header.get(f"Segment{k}_NameAutoGenerated"))
        k += 1
    return found


def test_every_label_in_the_image_has_a_segment_the_unnamed_ones_auto_named(tmp_path, image):
    import nrrd

    path = isoflow.write_labels(image, tmp_path / "seg.nrrd", names={1: "liver"})
    data, header = nrrd.read(str(path), index_order="F")
    present = set(np.unique(data).tolist()) - {0}
    segments = slicer_segments(header)
    # Slicer shows a label's voxels only through a segment of its value
    assert set(segments) == present == {1, 2, 5}
    assert segments == {1: ("liver", "0"), 2: ("label_2", "1"), 5: ("label_5", "1")}
    # the names isoflow made up are not read back as names given
    assert isoflow.read_labels(path).names == {1: "liver"}


def test_an_empty_mapping_of_names_means_no_names_not_the_images(tmp_path, image):
    import nrrd

    named = isoflow.LabelImage(image, np.ones(3), np.zeros(3), names=NAMES)
    path = isoflow.write_labels(named, tmp_path / "seg.nrrd", names={})
    assert "Segment0_ID" not in nrrd.read_header(str(path))
    assert isoflow.read_labels(path).names is None
    assert "name" not in isoflow.label_table(named, surfaces=False, names={})
    # None still takes the image's
    assert isoflow.label_table(named, surfaces=False)["name"].tolist() == list(NAMES.values())


def test_a_signed_images_negative_labels_take_their_names(tmp_path, capsys):
    """An int16 segmentation's negative labels have rows, so a side file or
    an OME-Zarr ``image-label`` entry names them as it names the others
    (the names are the file's own text); a file that write_labels writes
    holds no negative label, so it refuses a name for one."""
    import zarr

    image = np.zeros((6, 5, 4), np.int16)
    image[0:2] = -4
    image[3:5] = 1
    side = tmp_path / "names.txt"
    side.write_text("-4 vessel\n1 liver\n")
    np.save(tmp_path / "seg.npy", image)
    assert main(["info", str(tmp_path / "seg.npy"), "--labels", "--names", str(side), "--csv", "-"]) == 0
    rows = list(csv.DictReader(io.StringIO(capsys.readouterr().out)))
    assert [(row["label"], row["name"]) for row in rows] == [("-4", "vessel"), ("1", "liver")]

    store = zarr.open_group(tmp_path / "seg.zarr", mode="w", zarr_format=2)
    store.create_array("0", shape=image.shape[::-1], dtype=image.dtype)[:] = image.T
    store.attrs["multiscales"] = [{"version": "0.4", "axes": ["z", "y", "x"], "datasets": [{"path": "0"}]}]
    store.attrs["image-label"] = {"version": "0.4", "properties": [{"label-value": -4, "name": "vessel"}]}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert isoflow.read_labels(tmp_path / "seg.zarr").names == {-4: "vessel"}
    with pytest.raises(IsoflowError, match="a label name is given for -4"):
        isoflow.write_labels(np.abs(image), tmp_path / "out.h5", names={-4: "vessel"})
    assert not (tmp_path / "out.h5").exists()
