"""Bad input found by fuzzing: one line naming the file/field, exit 2, no
traceback, no silently wrong value, nothing written."""

import json
import os
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from in_process import isoflow_here

import isoflow
from isoflow.cli import main
from isoflow.digital.lattice import DigitalObject
from isoflow.errors import IsoflowError
from isoflow.mesh.outputs import check_picture_path
from isoflow.mesh.volumes import read_object, read_points, read_volume, write_volume


def fails(capsys, *args, words=()):
    """Run the CLI, expect exit 2 and one stderr line holding every word."""
    assert main([*map(str, args)]) == 2
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in lines[0], (w, lines[0])
    return lines[0]


def box_stl(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.creation.box().export(path)
    return path


# -------------------------------------------------------------- .npz metadata

@pytest.mark.parametrize(
    "field, value, shown",
    [
        ("offset", [[1, 2, 3]], "[[1, 2, 3]]"),  # was TypeError
        ("pitch", [1.0, 2.0], "got [1, 2]"),  # was TypeError
        ("parity", np.array("x"), "'x'"),  # was ValueError
        ("origin", ["a", "b", "c"], "['a', 'b', 'c']"),  # was ValueError
        ("offset", [np.nan, 0, 0], "nan"),  # was ValueError
        ("offset", [1.5, 2, 3], "1.5"),  # was silently 1
        ("parity", 0.5, "0.5"),  # was silently 0
        ("pitch", -1.0, "got -1"),  # a whole number, as meant: not "-1.0"
        ("offset", [1e300, 0, 0], "1e+300"),  # would overflow later
    ],
)
def test_npz_metadata_is_validated(tmp_path, capsys, field, value, shown):
    path = tmp_path / "meta.npz"
    np.savez(path, volume=np.ones((3, 3, 3), bool), **{field: value})
    fails(capsys, "info", path, words=("meta.npz", f"'{field}'", shown))


@pytest.mark.parametrize("pitch", [np.int64(-1), np.array([1, -1, 1]), np.array([0.5, 0.5, -1e-07])])
def test_a_pitch_refused_is_said_as_the_file_holds_it(tmp_path, capsys, pitch):
    """A negative pitch was said as its conversion to float printed it
    (``got -1.0``, ``got [1.0, -1.0, 1.0]``) where the file holds -1: the
    line gives the numbers as NumPy reads them from the file."""
    path = tmp_path / "meta.npz"
    np.savez(path, volume=np.ones((3, 3, 3), bool), pitch=pitch)
    held = np.load(path)["pitch"].tolist()
    line = fails(capsys, "info", path)
    assert line == f"isoflow info: error: {path}: 'pitch' must be positive (one number, or one per axis), got {held}"


@pytest.mark.parametrize("written", ["-1", "0", "-0.5"])
def test_a_time_limit_refused_is_said_as_written(tmp_path, capsys, written):
    """``genus --time-limit -1`` said ``got -1.0``, argparse's float of
    what was typed: the line gives the number as the user wrote it, and
    names the argument as argparse names every other."""
    with pytest.raises(SystemExit) as refused:  # refused as the command line is read, before the mesh
        main(["genus", str(box_stl(tmp_path)), "--time-limit", written])
    assert refused.value.code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert lines == [f"isoflow genus: error: argument --time-limit: must be a positive number of seconds, got {written}"]


def test_npz_metadata_that_is_valid_is_kept(tmp_path):
    path = tmp_path / "meta.npz"
    np.savez(path, volume=np.ones((2, 2, 2), bool), offset=[1.0, -2, 3], parity=np.int64(1),
             pitch=np.array([0.5]), origin=[1, 2, 3])
    obj = read_volume(path)
    assert obj.offset == (1, -2, 3) and obj.parity == 1 and obj.pitch == 0.5
    assert obj.origin.tolist() == [1.0, 2.0, 3.0]


@pytest.mark.parametrize("arrays", [{"volume"}, {"mask"}, {"labels"}, {"seg", "image"}])
def test_npz_spacing_is_the_voxel_size(tmp_path, capsys, arrays):
    """``np.savez("scan.npz", mask=m, spacing=s)``, spacing as scikit-image,
    SimpleITK and MONAI name a voxel size: the volume was refused ("name
    one as scan.npz:mask"), and named, or saved as ``volume``, read with
    voxels of 1, the spacing dropped without a word. The one array beside
    the fields is the volume, and ``spacing`` its pitch: the volume and
    area are the voxel count and faces in those units (a box of 2x3x4
    voxels, spacing 0.5, 2, 3: 24 voxels of 3, faces 2 x (3*4*6 + 2*4*1.5
    + 2*3*1)); two arrays beside the fields are still refused, naming an
    array, not a field, and the one named reads with the spacing."""
    box = np.zeros((4, 5, 6), np.uint8)
    box[1:3, 1:4, 1:5] = 1
    spacing = np.array([0.5, 2.0, 3.0])
    members = {name: box if name != "image" else np.random.default_rng(0).random(box.shape) for name in arrays}
    path = tmp_path / "scan.npz"
    np.savez(path, spacing=spacing, **members)
    given = str(path) if len(arrays) == 1 else f"{path}:seg"
    if len(arrays) > 1:
        line = fails(capsys, "info", path, words=("holds arrays", f"name one as {path}:"))
        assert f"{path}:spacing" not in line
    assert main(["info", given, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["voxels"] == 24 and report["volume"] == pytest.approx(24 * np.prod(spacing))
    faces = 2 * (3 * 4 * spacing[1] * spacing[2] + 2 * 4 * spacing[0] * spacing[2] + 2 * 3 * spacing[0] * spacing[1])
    assert report["surface_area"] == pytest.approx(faces)
    assert read_volume(given).spacing.tolist() == spacing.tolist()
    assert main(["info", given, "--labels", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["labels"][0]["volume"] == pytest.approx(24 * np.prod(spacing))


def test_npz_spacing_refused_in_its_own_name(tmp_path, capsys):
    """A spacing that is no voxel size is refused naming ``spacing``, as
    the archive does; one beside a ``pitch`` that differs is refused
    naming both; one equal to it reads. A segmentation saved with a
    channel axis, (X, Y, Z, 1), takes a spacing of its three axes in
    space, as it takes such a pitch."""
    vol = np.ones((3, 3, 3), bool)
    np.savez(tmp_path / "bad.npz", volume=vol, spacing=np.array([1.0, -1.0, 1.0]))
    fails(capsys, "info", tmp_path / "bad.npz", words=("bad.npz: 'spacing' must be positive", "[1, -1, 1]"))
    np.savez(tmp_path / "two.npz", volume=vol, pitch=np.array([1.0, 2.0, 3.0]), spacing=np.array([1.0, 2.0, 4.0]))
    fails(capsys, "info", tmp_path / "two.npz", words=("two.npz: holds both 'pitch' [1, 2, 3] and 'spacing' [1, 2, 4]",))
    np.savez(tmp_path / "same.npz", volume=vol, pitch=np.array(2.0), spacing=np.array([2.0, 2.0, 2.0]))
    assert read_volume(tmp_path / "same.npz").pitch == 2.0
    np.savez(tmp_path / "channel.npz", seg=np.ones((3, 3, 3, 1), np.uint8), spacing=np.array([1.0, 2.0, 3.0]))
    assert isoflow.read_labels(tmp_path / "channel.npz").spacing.tolist() == [1.0, 2.0, 3.0]


@pytest.mark.parametrize("field", ["spacing", "pitch"])
def test_a_time_series_placed_by_its_three_axes_in_space(tmp_path, capsys, field):
    """A 4D 0/1 time series saved with the voxel size (and origin) of its
    three axes in space, as a scan's spacing is, was refused ("'pitch'
    must be 4 numbers"). The time axis steps 1 from 0, as a 4D NIfTI's
    does (nibabel's zooms of such a file the reference), and each time
    point is placed by the three."""
    nib = pytest.importorskip("nibabel")
    series = np.zeros((4, 5, 6, 3), np.uint8)
    series[1:3, 1:4, 2:5, :] = 1
    np.savez(tmp_path / "t.npz", volume=series, **{field: np.array([0.5, 1.0, 2.0])}, origin=np.array([1.0, 2, 3]))
    nib.save(nib.Nifti1Image(series, np.diag([0.5, 1.0, 2.0, 1.0])), tmp_path / "t.nii")
    assert main(["info", str(tmp_path / "t.npz"), "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["pitch"] == list(nib.load(tmp_path / "t.nii").header.get_zooms()) and got["origin"] == [1, 2, 3, 0]
    one = read_volume(tmp_path / "t.npz", time=2)
    assert one.spacing.tolist() == [0.5, 1.0, 2.0] and one.origin.tolist() == [1.0, 2.0, 3.0]


def test_npz_arrays_beside_the_volume_that_are_not_read_are_said(tmp_path, capsys):
    """``volume`` beside an ``affine`` (or a ``voxel_size``) was read with
    voxels of 1 from 0 without a word: one warning line names what is not
    read; the volume named as ``ARCHIVE.npz:volume`` is read as asked,
    without it."""
    path = tmp_path / "scan.npz"
    np.savez(path, volume=np.ones((3, 3, 3), bool), affine=np.diag([2.0, 2.0, 2.0, 1.0]))
    assert main(["info", str(path), "--json"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["voxels"] == 27
    assert captured.err.strip().splitlines() == [
        f"isoflow info: warning: {path}: its array affine is not read: the volume is 'volume', placed by its pitch "
        "(or spacing), origin, offset and parity, where given"]
    assert main(["info", f"{path}:volume", "--json"]) == 0
    assert capsys.readouterr().err == ""


# -------------------------------------------------- volume type by content

def test_volume_type_comes_from_the_content_not_the_suffix(tmp_path, capsys):
    upper = tmp_path / "v.NPZ"
    assert main(["voxelize", str(box_stl(tmp_path)), "--resolution", "8", "-o", str(upper)]) == 0
    vol = np.ones((2, 3, 4), bool)
    with open(tmp_path / "npz_named.npy", "wb") as fh:
        np.savez(fh, volume=vol)
    with open(tmp_path / "npy_named.npz", "wb") as fh:
        np.save(fh, vol)
    capsys.readouterr()
    for name, voxels in (("v.NPZ", 512), ("npz_named.npy", 24), ("npy_named.npz", 24)):
        assert main(["info", str(tmp_path / name), "--json", "--no-surfaces"]) == 0, name
        assert f'"voxels": {voxels}' in capsys.readouterr().out


@pytest.mark.parametrize("name", ["v.npy", "v.npz"])
@pytest.mark.parametrize("content, words", [
    (b"\x00garbage" * 50, "not a numpy file: it starts with b'\\x00garbage', not .npy's b'\\x93NUMPY'"),
    (b"", "not a numpy file: it is empty"),
], ids=["garbage", "empty"])
def test_a_file_that_is_no_numpy_file_says_what_it_starts_with(tmp_path, capsys, name, content, words):
    """np.load takes such a file for a pickle ("load it unsafely"), though
    it starts with neither NumPy's magic nor a pickle's b'\\x80'."""
    (tmp_path / name).write_bytes(content)
    line = fails(capsys, "info", tmp_path / name, words=(f"{name}: {words}",))
    assert "pickle" not in line and "unsafely" not in line


def test_a_pickle_named_npy_keeps_numpys_word_on_pickles(tmp_path, capsys):
    import pickle

    (tmp_path / "p.npy").write_bytes(pickle.dumps(np.ones(3)))
    fails(capsys, "info", tmp_path / "p.npy", words=("p.npy: not a readable numpy file", "pickled"))


# ------------------------------------------------------------- point lists

@pytest.mark.parametrize("big", ["1e300", "1e999", "-1e999", "9223372036854775807", "-9223372036854775808"])
@pytest.mark.parametrize("points_are", ["corners", "voxels"])
def test_point_coordinates_out_of_range(tmp_path, capsys, big, points_are):
    path = tmp_path / "far.txt"
    path.write_text(f"0 0 0\n{big} 0 0\n")
    fails(capsys, "info", path, "--points-are", points_are, words=("far.txt:2", big, "out of range"))


def test_point_builders_refuse_coordinates_out_of_range():
    for pts in ([[0, 0, 0], [2**63 - 1, 0, 0]], [[0, 0, 0], [-(2**63), 0, 0]], [[0, 0, 0], [1e300, 0, 0]]):
        for build in (DigitalObject.from_points, DigitalObject.from_voxels):
            with pytest.raises(IsoflowError, match="out of range"):
                build(np.array(pts))



def test_point_list_with_a_byte_order_mark_reads(tmp_path):
    """Windows editors start a UTF-8 file with a byte-order mark: it is no
    coordinate, on either reader (the second file needs the line reader)."""
    for text, want in (("0 0 0\n1 2 3\n", [[0, 0, 0], [1, 2, 3]]), ("0 0 0\n1, 2 3\n", [[0, 0, 0], [1, 2, 3]])):
        (tmp_path / "bom.txt").write_bytes(b"\xef\xbb\xbf" + text.encode())
        assert read_points(tmp_path / "bom.txt").tolist() == want


@pytest.mark.parametrize(
    "text, words",
    [
        ("0 0 0\n1_000 0 0\n", ("bad.txt:2", "not a number", "1_000")),  # Python's float() takes it
        ("0,,0,0\n", ("bad.txt:1", "empty coordinate")),
        ("1 2 3,\n", ("bad.txt:1", "empty coordinate")),
        ("nan 0 0\n", ("bad.txt:1", "nan")),
        ("0 0 0\ninf 1 1\n", ("bad.txt:2", "inf")),
        ("0x10 0 0\n", ("bad.txt:1", "0x10")),
        ("1,2,3\n4,5\n", ("bad.txt:2", "expected 3 coordinates")),
        ("1 2 3\n4 5 6.5\n", ("bad.txt:2", "6.5 is not an integer")),
        ("0 0 0\n\u0661 \u0662 \u0663\n", ("bad.txt:2", "not a number")),  # float() takes Arabic-Indic digits
        ("\uff11 0 0\n", ("bad.txt:1", "not a number")),  # and full-width ones
    ],
)
def test_point_list_fields_are_plain_numbers(tmp_path, capsys, text, words):
    path = tmp_path / "bad.txt"
    path.write_text(text)
    fails(capsys, "info", path, words=words)


@pytest.mark.parametrize("separator", [" ", ",", ", "])  # numpy's reader, and the line reader (", " mixes both)
@pytest.mark.parametrize("written", ["1.00000000000000000001", "10000000000000000000001e-22", "-2.9999999999999999999"])
def test_a_coordinate_with_more_digits_than_float64_holds_is_refused_as_written(tmp_path, separator, written):
    """float64 keeps 15 to 17 digits: ``1.00000000000000000001`` read as
    1.0 was taken for the integer 1, a point the file does not hold. A
    coordinate is whole as written (Python's Fraction of the text), or
    refused as ``1.5`` is, naming the file, the line and the value; whole
    decimals (``1.5e1``, ``2.000``) are read as before."""
    from fractions import Fraction

    assert float(written) == round(float(written)) and Fraction(written).denominator != 1
    bad = tmp_path / "bad.txt"
    bad.write_text(separator.join(["0", "0", "0"]) + "\n" + separator.join([written, "0", "0"]) + "\n")
    done = isoflow_here("info", bad, "--points-are", "voxels")
    assert done.returncode == 2 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.strip() == f"isoflow info: error: {bad}:2: coordinate {written} is not an integer"
    good = tmp_path / "good.txt"
    good.write_text(separator.join(["0", "0", "0"]) + "\n" + separator.join(["1.5e1", "2.000", "1E+1"]) + "\n")
    done = isoflow_here("info", good, "--points-are", "voxels", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["shape"] == [16, 3, 11]  # points (0, 0, 0) and (15, 2, 10)


def test_point_list_with_a_header_of_column_names_reads_its_points(tmp_path, capsys):
    """A CSV written with a header line (csv.DictWriter's, pandas'
    to_csv's: ``x,y,z``) was refused, "not a number: 'x'". The header is
    skipped where the next line holds as many numbers, on either reader
    (the blanks and commas of the second file need the line reader); the
    points are those written, and a line of names before no numbers is
    still refused naming it."""
    import csv

    rng = np.random.default_rng(5)
    points = rng.integers(-50, 50, size=(40, 3))
    with open(tmp_path / "points.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=["x", "y", "z"])
        writer.writeheader()
        writer.writerows({"x": int(a), "y": int(b), "z": int(c)} for a, b, c in points)
    assert read_points(tmp_path / "points.csv").tolist() == points.tolist()
    (tmp_path / "points.txt").write_text("# scanned\n\nX Y Z\n" + "".join(f"{a}, {b} {c}\n" for a, b, c in points))
    assert read_points(tmp_path / "points.txt").tolist() == points.tolist()
    assert main(["info", str(tmp_path / "points.csv"), "--points-are", "voxels", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["voxels"] == len(np.unique(points, axis=0))
    (tmp_path / "words.txt").write_text("x,y,z\nthe points follow\n")
    fails(capsys, "info", tmp_path / "words.txt", words=("words.txt:1", "not a number: 'x'"))


@pytest.mark.parametrize("first", ["", "index"], ids=["to_csv", "reset_index"])
def test_point_list_written_with_its_index_column_reads_its_points(tmp_path, first):
    """pandas' ``DataFrame.to_csv()`` writes the frame's index as a first
    column named "" (``,x,y,z``; "index" after ``reset_index``), 0, 1, 2,
    ... down its rows: the file was refused ("empty coordinate in
    ',x,y,z'"). That column is now skipped, on either reader (the blanks
    and commas mixed of the second file need the line reader), and the
    command reads the points written; a line of the wrong count is still
    refused naming it. pandas is not installed: the files are written as it
    writes them."""
    rng = np.random.default_rng(7)
    points = rng.integers(-20, 20, size=(30, 3))
    rows = "".join(f"{i},{a},{b},{c}\n" for i, (a, b, c) in enumerate(points))
    (tmp_path / "points.csv").write_text(f"{first},x,y,z\n{rows}")
    assert read_points(tmp_path / "points.csv").tolist() == points.tolist()
    spaced = "".join(f"{i}, {a} {b} {c}\n" for i, (a, b, c) in enumerate(points))  # blanks and commas mixed
    (tmp_path / "spaced.csv").write_text(f"{first},x,y,z\n{spaced}")
    assert read_points(tmp_path / "spaced.csv").tolist() == points.tolist()
    (tmp_path / "plane.csv").write_text(f"{first},x,y\n" + "".join(f"{i},{a},{b}\n" for i, (a, b, _) in enumerate(points)))
    assert read_points(tmp_path / "plane.csv").tolist() == points[:, :2].tolist()
    done = isoflow_here("info", str(tmp_path / "points.csv"), "--points-are", "voxels",
                           "--json")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["voxels"] == len(np.unique(points, axis=0)) and report["dimension"] == 3
    (tmp_path / "short.csv").write_text(f"{first},x,y,z\n0,1,2,3\n1,4,5\n")
    with pytest.raises(IsoflowError, match=re.escape("short.csv:3: expected 3 coordinates, got 2")):
        read_points(tmp_path / "short.csv")


def test_point_list_read_whole_equals_line_by_line(tmp_path):
    """numpy's reader (the fast path) and the line-by-line one read the
    same points, with comments, blank lines, signs, exponents and every
    separator."""
    from isoflow.mesh.volumes import _read_points_by_line, read_points

    rng = np.random.default_rng(3)
    pts = rng.integers(-50, 50, (500, 3))
    seps = [" ", "  ", "\t", ",", ", ", " , "]
    for k, sep in enumerate(seps):
        lines = []
        for i, p in enumerate(pts):
            fields = [f"{v:+d}" if i % 7 == 0 else (f"{v}e0" if i % 11 == 0 else str(v)) for v in p]
            lines.append(sep.join(fields) + ("  # a comment" if i % 5 == 0 else ""))
            if i % 13 == 0:
                lines.append("# a line of comment" if i % 2 else "")
        path = tmp_path / f"p{k}.txt"
        path.write_text("\n".join(lines) + "\n")
        got = read_points(path)
        assert got.dtype == np.int64
        assert (got == pts).all()
        assert (got == _read_points_by_line(path)).all()
    # blanks and commas mixed: numpy refuses, the line reader takes it
    path = tmp_path / "mixed.txt"
    path.write_text("1 2 3\n4,5,6\n")
    assert read_points(path).tolist() == [[1, 2, 3], [4, 5, 6]]



def test_point_list_beyond_the_memory_budget_is_refused_before_reading(tmp_path, capsys, monkeypatch):
    from isoflow.scale import memory

    path = tmp_path / "many.txt"
    path.write_text("0 0 0\n" * 200_000)  # 1.2 MB of text: about 4.8 MB read
    monkeypatch.setattr(memory, "default_budget", lambda: 2_000_000)
    read = []
    monkeypatch.setattr(np, "loadtxt", lambda *a, **k: read.append(1))
    fails(capsys, "info", path, words=("many.txt", "point list", "budget"))
    assert not read

@pytest.mark.parametrize("points_are", ["corners", "voxels"])
def test_point_grid_beyond_the_memory_budget(tmp_path, capsys, monkeypatch, points_are):
    from isoflow.scale import memory

    monkeypatch.setattr(memory, "default_budget", lambda: 1_000_000)
    path = tmp_path / "spread.txt"
    path.write_text("0 0 0\n200 200 200\n")  # 8 MB of grid for two points
    fails(capsys, "info", path, "--points-are", points_are, words=("spread.txt", "201x201x201", "budget"))
    with pytest.raises(IsoflowError, match="budget"):
        DigitalObject.from_points([[0, 0, 0], [200, 200, 200]])



# ------------------------------------------------- --points-are: point lists only

@pytest.mark.parametrize("value", ["voxels", "corners"])
@pytest.mark.parametrize("command", ["info", "surface", "flow"])
def test_points_are_is_refused_for_a_mesh(tmp_path, capsys, command, value):
    # was silently ignored: the mesh was voxelised as without it
    out = ["-o", tmp_path / "s.ply"] if command == "surface" else []
    line = fails(capsys, command, box_stl(tmp_path), "--points-are", value, *out,
                 words=("box.stl", "--points-are", "point lists", "not to mesh input"))
    assert line.startswith(f"isoflow {command}: error: {tmp_path / 'box.stl'}:"), line
    assert not (tmp_path / "s.ply").exists()


@pytest.mark.parametrize("command", ["info", "surface", "flow"])
def test_points_are_is_refused_for_a_volume(tmp_path, capsys, command):
    np.save(tmp_path / "ok.npy", np.ones((2, 2, 2), bool))
    out = ["-o", tmp_path / "s.ply"] if command == "surface" else []
    fails(capsys, command, tmp_path / "ok.npy", "--points-are", "voxels", *out,
          words=("ok.npy", "--points-are", "point lists", "not to volume input"))
    fails(capsys, "info", tmp_path / "ok.npy", "--labels", "all", "--points-are", "corners",
          words=("ok.npy", "--points-are", "not to a label image input"))
    with pytest.raises(IsoflowError, match=r"ok\.npy: points_are='voxels' applies to point lists"):
        read_object(tmp_path / "ok.npy", points_are="voxels")
    # the Python default (and saying it) still reads a volume
    assert read_object(tmp_path / "ok.npy").voxels == read_object(tmp_path / "ok.npy", points_are="corners").voxels == 8


@pytest.mark.parametrize("command", ["info", "surface", "flow"])
def test_points_are_is_refused_for_a_store_read_block_by_block(tmp_path, capsys, command):
    pytest.importorskip("zarr")
    store = tmp_path / "v.zarr"
    write_volume(DigitalObject(np.ones((3, 3, 3), bool)), store)
    out = {"info": [], "surface": ["-o", tmp_path / "s.ply"], "flow": ["--out", tmp_path / "f", "--volumes", ".zarr"]}
    fails(capsys, command, store, "--points-are", "voxels", *out[command],
          words=("v.zarr", "--points-are", "not to volume input"))
    fails(capsys, command, store, "--pitch", "2", *out[command], words=("v.zarr", "--pitch", "not to .zarr input"))


def test_points_are_voxels_reads_a_point_list_otherwise(tmp_path, capsys):
    # a 2x2x2 block of corners plus one loose point: the cube they close,
    # against one voxel a point
    pts = {(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)} | {(5, 5, 5)}
    path = tmp_path / "pts.txt"
    path.write_text("".join(f"{x} {y} {z}\n" for x, y, z in sorted(pts)))
    closed = sum(all((x + dx, y + dy, z + dz) in pts for dx in (0, 1) for dy in (0, 1) for dz in (0, 1))
                 for x, y, z in pts)
    reports = {}
    for given in ([], ["--points-are", "corners"], ["--points-are", "voxels"]):
        assert main(["info", str(path), "--json", "--no-surfaces", *given]) == 0, given
        reports[tuple(given)] = json.loads(capsys.readouterr().out)
    default, corners, voxels = reports.values()
    assert default == corners and corners["voxels"] == closed
    assert voxels["voxels"] == len(pts) != closed
    assert voxels["betti"][0] == 2 and corners["betti"][0] == 1  # the loose point is an object only as a voxel
    assert read_object(path).voxels == closed and read_object(path, points_are="voxels").voxels == len(pts)


# ------------------------------------------------------------ output paths

def test_output_that_is_a_directory_is_refused_even_with_force(tmp_path, capsys):
    np.save(tmp_path / "ok.npy", np.ones((2, 2, 2), bool))
    (tmp_path / "adir.ply").mkdir()
    (tmp_path / "vdir.npz").mkdir()
    fails(capsys, "surface", tmp_path / "ok.npy", "-o", tmp_path / "adir.ply", "--force",
          words=("adir.ply", "is a directory"))
    fails(capsys, "voxelize", box_stl(tmp_path), "--resolution", "4", "-o", tmp_path / "vdir.npz", "--force",
          words=("vdir.npz", "is a directory"))


@pytest.mark.parametrize(
    "png, words",
    [("nodir/p.png", ("nodir", "no such directory")),  # was FileNotFoundError after the mesh
     ("pic.txt", ("pic.txt", ".png")),  # was a matplotlib ValueError after the mesh
     ("pdir.png", ("pdir.png", "is a directory"))],
)
def test_bad_picture_path_is_refused_before_anything_is_written(tmp_path, capsys, png, words):
    np.save(tmp_path / "ok.npy", np.ones((2, 2, 2), bool))
    (tmp_path / "pdir.png").mkdir()
    out = tmp_path / "pp.obj"
    fails(capsys, "surface", tmp_path / "ok.npy", "-o", out, "--png", tmp_path / png, "--force", words=words)
    assert not out.exists()
    with pytest.raises(IsoflowError, match="no such directory|.png|is a directory"):
        check_picture_path(tmp_path / png, force=True)  # reusable for other commands' pictures


# ------------------------------------------------------- non-regular input

@pytest.mark.parametrize("command,names_labels", [("info", True), ("surface", True), ("flow", False)])
def test_a_label_image_refusal_names_only_options_the_command_takes(tmp_path, capsys, command, names_labels):
    # flow takes --label N, not --labels: its refusal named an option that
    # the command then refuses as unrecognized
    labels = np.zeros((5, 5, 5), np.uint8)
    labels[1:3, 1:3, 1:3], labels[3, 3, 3] = 2, 7
    np.save(tmp_path / "l.npy", labels)
    extra = ["-o", tmp_path / "s.ply"] if command == "surface" else []
    line = fails(capsys, command, tmp_path / "l.npy", *extra, words=("l.npy", "not a binary volume", "--label N"))
    assert ("--labels" in line) == names_labels
    # a store, checked block by block, says the same (it named no option at all); a block of one label
    # (these blocks of 3 voxels hold one each) is offered that label, as a 0/255 mask's block is 255
    zarr = pytest.importorskip("zarr")
    zarr.create_array(str(tmp_path / "l.zarr"), data=labels, chunks=(3, 3, 3), zarr_format=2)
    extra = ["--out", tmp_path / "run", "--volumes", ".zarr"] if command == "flow" else extra
    # (the flow block by block names that label in the flow in memory)
    offer = "in the flow in memory" if command == "flow" else "select one label with --label "
    line = fails(capsys, command, tmp_path / "l.zarr", *extra,
                 words=("l.zarr", "not a binary volume", "in the block at voxel", offer))
    assert ("--labels" in line) == names_labels


def test_surface_offers_its_labels_option_for_what_it_does_and_only_in_3d(tmp_path, capsys):
    # surface --labels writes a closed surface per label of a 3D image (no
    # table), and surface takes no 2D image at all (docs/labels.md): the
    # refusal of a label image offered "every label its row with --labels"
    # in 3D, and in 2D options (--label N, --labels) that are refused next
    labels = np.zeros((5, 5, 5), np.uint8)
    labels[1:3, 1:3, 1:3], labels[3, 3, 3] = 2, 7
    np.save(tmp_path / "l.npy", labels)
    line = fails(capsys, "surface", tmp_path / "l.npy", "-o", tmp_path / "s.ply")
    assert line.endswith("or write a closed surface per label with --labels"), line
    assert main(["surface", str(tmp_path / "l.npy"), "--labels", "-o", str(tmp_path / "s.glb")]) == 0
    assert sorted(trimesh.load(tmp_path / "s.glb").graph.nodes_geometry) == ["label_2", "label_7"]
    capsys.readouterr()
    np.save(tmp_path / "c.npy", labels[:, :, 1] + labels[:, :, 3])  # 2D, labels 2 and 7
    said = "c.npy: surface needs a 3D object, this one is 2D"
    line = fails(capsys, "surface", tmp_path / "c.npy", "-o", tmp_path / "c.ply", words=(said,))
    assert line == fails(capsys, "surface", tmp_path / "c.npy", "--label", "2", "-o", tmp_path / "c.ply")
    # info's --labels gives the 2D image its table
    line = fails(capsys, "info", tmp_path / "c.npy", words=("c.npy", "--label N"))
    assert line.endswith("or give every label its row with --labels (isoflow.label_table(isoflow.read_labels(path)))")


@pytest.mark.parametrize("points,cell", [("0 0 0\n-5 3 2\n", "cube has all 8"), ("0 0\n1 0\n", "square has all 4")])
def test_a_point_list_that_gives_no_voxel_says_why(tmp_path, capsys, points, cell):
    # points with no cube of the paper's point model among them: the object
    # is empty although the input is not; it said only "the object is empty"
    (tmp_path / "p.txt").write_text(points)
    why = (f"the object is empty: no unit {cell} of its corners among the points (the paper's point model, "
           "Definitions 1-2); --points-are voxels reads each point as a voxel")
    fails(capsys, "flow", tmp_path / "p.txt", words=("p.txt", why))
    if cell.startswith("cube"):
        fails(capsys, "surface", tmp_path / "p.txt", "-o", tmp_path / "p.ply", words=("p.txt", why))
        assert not (tmp_path / "p.ply").exists()
    assert main(["info", str(tmp_path / "p.txt"), "--json"]) == 0  # an empty report, with the reason as a note
    out, err = capsys.readouterr()
    assert json.loads(out)["voxels"] == 0
    assert err.strip().splitlines() == [f"isoflow info: note: {tmp_path / 'p.txt'}: {why.partition(': ')[2]}"]
    assert main(["flow", str(tmp_path / "p.txt"), "--points-are", "voxels", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["steps"][0]["voxels"] == 2


@pytest.mark.parametrize("name", ["v.npy", "v.nii.gz", "v.binvox", "v.h5:/seg", "v.zarr"])
@pytest.mark.parametrize("command", ["voxelize", "genus"])
def test_a_volume_given_where_a_mesh_is_read_says_so(tmp_path, capsys, name, command):
    # trimesh said "file_type 'npy' not supported", failed inside its binvox
    # reader (TypeError), and FILE.h5:/dataset was "file not found"
    v = np.zeros((4, 4, 4), bool)
    v[1:3, 1:3, 1:3] = True
    write_volume(DigitalObject(v), tmp_path / name)
    extra = ["--pitch", "1", "-o", tmp_path / "out.npy"] if command == "voxelize" else []
    fails(capsys, command, tmp_path / name, *extra,
          words=(f"{tmp_path / name}: a volume file, not a triangle mesh; voxelize and genus read meshes",))
    assert not (tmp_path / "out.npy").exists()


@pytest.mark.parametrize("command", ["voxelize", "genus"])
def test_a_point_list_given_where_a_mesh_is_read_says_so(tmp_path, capsys, command):
    # trimesh said "cannot read as a mesh (NotImplementedError: file_type
    # 'txt' not supported)", leaving the user to guess what would read it
    points = Path(__file__).parent.parent / "meshes" / "example19.txt"
    extra = ["--pitch", "1", "-o", tmp_path / "out.npy"] if command == "voxelize" else []
    line = fails(capsys, command, points, *extra,
                 words=(f"{points}: the suffix .txt names no mesh format", "point list", "isoflow info"))
    assert "NotImplementedError" not in line and not (tmp_path / "out.npy").exists()
    # the command the line names reads it: the paper's Example 19, 4 unit cubes (the file's own comment)
    assert main(["info", str(points), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["voxels"] == 4


def test_device_input_is_refused(capsys):
    # /dev/null stands in for /dev/zero (which would never end) and FIFOs
    fails(capsys, "info", os.devnull, words=(os.devnull, "not a regular file"))


@pytest.mark.parametrize("change, words", [
    (lambda d: d + bytes(10), ("counts 12 facets (684 bytes)", "has 694 bytes (12 facets and 10 bytes after")),
    # a header that starts "solid" and names a facet, as some CAD writers fill it: was "not a valid STL file"
    (lambda d: b"solid part; facet normals by CAD".ljust(80) + d[80:300],
     ("counts 12 facets (684 bytes)", "has 300 bytes (4 facets and 16 bytes after")),
    (lambda d: d[:80] + bytes(4) + d[84:], ("counts 0 facets (84 bytes)", "has 684 bytes (12 facets after")),
    (lambda d: d[:300], ("counts 12 facets (684 bytes)", "has 300 bytes (4 facets and 16 bytes after")),
], ids=["padded", "solid header truncated", "count 0", "truncated"])
def test_a_binary_stl_of_the_wrong_size_says_so(tmp_path, capsys, change, words):
    """A box's 12 facets (50 bytes each after the 84-byte header) padded,
    with a count of 0, or cut short: the line said only "not a valid STL
    file", about a file whose facets are all there."""
    path = box_stl(tmp_path)
    path.write_bytes(change(path.read_bytes()))
    fails(capsys, "info", path, words=("box.stl: no triangles read: as a binary STL its header", *words))


def ascii_box_stl() -> list[str]:
    """The lines of a box's ASCII STL, as trimesh writes it."""
    return trimesh.exchange.stl.export_stl_ascii(trimesh.creation.box()).splitlines()


@pytest.mark.parametrize("edit, words", [
    # each was "cannot read as a mesh (ValueError: cannot reshape array of size 37 into shape (3))" or the like
    (lambda ln, k: ln[:k + 1] + ["vertex 9 9 9"] + ln[k + 1:], ("facet 1's loop has 4 vertices, where an STL facet has 3",)),
    (lambda ln, k: ln[:k] + ln[k + 1:], ("facet 1's loop has 2 vertices, where an STL facet has 3",)),
    (lambda ln, k: ln[:k] + [ln[k].replace("-0.5", "-0,5", 1)] + ln[k + 1:],
     ("'-0,5' is not a coordinate (STL writes decimals with a point: -0.5)",)),
])
def test_an_ascii_stl_facet_that_is_no_triangle_names_its_line(tmp_path, capsys, edit, words):
    """Facet 1's third vertex line (file line 6) given a fourth vertex after
    it, dropped, or a decimal comma: the line named is the one where the
    fault shows (the loop's end, or the vertex), which trimesh cannot read."""
    lines = ascii_box_stl()
    third = [i for i, ln in enumerate(lines) if ln.startswith("vertex")][2]
    bad = edit(lines, third)
    path = tmp_path / "box.stl"
    path.write_text("\n".join(bad) + "\n")
    try:
        read = len(trimesh.load(path, force="mesh", process=False).faces) == 12
    except ValueError:
        read = False
    assert not read
    shown = next(i for i, ln in enumerate(bad, 1) if ln.startswith("endloop") or "0,5" in ln)
    fails(capsys, "genus", path, words=(f"box.stl:{shown}: ", *words))


def test_an_ascii_stl_cut_short_says_so(tmp_path, capsys):
    """Cut in facet 6's loop: trimesh read no triangle ("not a valid STL
    file"); the line names the facet and the line it starts on."""
    lines = ascii_box_stl()[:40]
    starts = [i for i, ln in enumerate(lines, 1) if ln.startswith("facet")]
    path = tmp_path / "box.stl"
    path.write_text("\n".join(lines) + "\n")
    fails(capsys, "genus", path, words=(f"box.stl: the file ends inside facet {len(starts)} (line {starts[-1]}, its last)",
                                         "cut short"))


def test_binary_file_is_not_read_as_a_point_list(tmp_path, capsys):
    path = tmp_path / "data.bin"
    path.write_bytes(b"0 0 0\n\0\0\0\0\n1 1 1\n" + bytes(range(256)) * 100)
    fails(capsys, "info", path, words=("data.bin", "binary data"))


def test_a_binary_volume_of_a_format_isoflow_does_not_read_lists_the_volume_suffixes(tmp_path, capsys):
    """A MetaImage (ITK's .mha) falls to the point-list reader; the line
    listed .npy/.npz alone as volumes, not the formats docs/formats.md reads."""
    path = tmp_path / "scan.mha"
    path.write_bytes(b"ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n"
                     b"ElementDataFile = LOCAL\n" + bytes(64))
    line = fails(capsys, "info", path, words=("scan.mha: binary data, not a text point list",))
    for suffix in (".npy", ".tif", ".nii.gz", ".nrrd", ".h5", ".zarr", ".png"):
        assert suffix in line, (suffix, line)


@pytest.mark.parametrize("written, named, renamed", [
    ("v.nii.gz", "scan", "scan.nii.gz"), ("v.nii", "scan.raw", "scan.nii"), ("v.tif", "stack.bin", "stack.tif"),
])
def test_a_volume_without_a_volume_suffix_is_named_by_its_content(tmp_path, capsys, written, named, renamed):
    """It falls to the point-list reader ("binary data"); the line says
    what the content is and the name that reads it."""
    vol = np.zeros((3, 4, 5), bool)
    vol[1:, 1:3, 2:] = True
    write_volume(DigitalObject(vol), tmp_path / written)
    (tmp_path / written).rename(tmp_path / named)
    line = fails(capsys, "info", tmp_path / named, words=(f"{named}: its content is ",))
    assert line.endswith(f"rename it {renamed}"), line
    (tmp_path / named).rename(tmp_path / renamed)
    assert read_volume(tmp_path / renamed).voxels == vol.sum()


MESHES = Path(__file__).resolve().parents[1] / "meshes"


@pytest.mark.parametrize("named", ["torus", "torus.txt", "torus.dat"])
@pytest.mark.parametrize("command", ["info", "surface", "flow"])
def test_a_mesh_without_its_suffix_is_named_by_its_content(tmp_path, capsys, named, command):
    """torus.obj under another name fell to the point-list reader, which
    said "torus:3: not a number: 'v'", as if a point list had a typo. The
    line names the OBJ content and the name that reads it; under that
    name trimesh reads the manifest's mesh."""
    known = next(m for m in json.loads((MESHES / "manifest.json").read_text())["meshes"]
                 if m["filename"] == "torus.obj")
    path = tmp_path / named
    path.write_bytes((MESHES / "torus.obj").read_bytes())
    out = ["-o", tmp_path / "out.ply"] if command == "surface" else []
    line = fails(capsys, command, path, *out, words=(f"{named}: its content is an OBJ file",))
    renamed = re.search(r"rename it (\S+)$", line).group(1)
    path.rename(tmp_path / renamed)
    loaded = trimesh.load(tmp_path / renamed, force="mesh")
    merged = trimesh.Trimesh(loaded.vertices, loaded.faces, process=True)
    assert (len(merged.vertices), len(merged.faces), merged.euler_number) == (
        known["vertices"], known["faces"], known["euler"])
    assert not (tmp_path / "out.ply").exists()


def test_a_text_file_of_no_known_suffix_says_it_was_read_as_a_point_list(tmp_path, capsys):
    """manifest.json is neither volume nor mesh nor point list: its line
    said only "manifest.json:1: not a number: '{'"."""
    path = tmp_path / "manifest.json"
    path.write_bytes((MESHES / "manifest.json").read_bytes())
    line = fails(capsys, "info", path, words=("manifest.json:1: not a number",))
    assert line.endswith("(read as a text point list, x y z per line: the suffix .json names no volume or mesh format)")


def test_zarr_directory_that_is_no_store_says_so(tmp_path, capsys):
    # every command reads .zarr now (info block by block, the others in memory)
    (tmp_path / "v.zarr").mkdir()
    fails(capsys, "surface", tmp_path / "v.zarr", "-o", tmp_path / "s.ply", words=("v.zarr", "not a zarr"))


def test_a_dangling_symlink_output_needs_force(tmp_path, capsys):
    """A link to nothing is an entry all the same: replaced only with
    --force (Path.exists() is False for it, and it was replaced without)."""
    np.save(tmp_path / "v.npy", np.ones((2, 2, 2), bool))
    (tmp_path / "s.ply").symlink_to(tmp_path / "nowhere.ply")
    fails(capsys, "surface", tmp_path / "v.npy", "-o", tmp_path / "s.ply", words=("s.ply", "exists", "--force"))
    assert (tmp_path / "s.ply").is_symlink()
    assert main(["surface", str(tmp_path / "v.npy"), "-o", str(tmp_path / "s.ply"), "--force"]) == 0
    assert (tmp_path / "s.ply").is_file() and not (tmp_path / "s.ply").is_symlink()


# ------------------------------------------------ a mesh's grid beyond memory

TORUS = Path(__file__).resolve().parents[1] / "meshes" / "torus.obj"
#: a budget (1.9 MiB) that refuses the sample torus at a few hundred voxels across
SMALL = 2_000_000


def small_budget(monkeypatch):
    from isoflow.scale import memory

    monkeypatch.setattr(memory, "default_budget", lambda: SMALL)


def command_words(line: str) -> str:
    """A refusal on the command line names its options, never a Python
    parameter or an option that the command does not have."""
    for python in ("max_bytes", "resolution=", "pitch=", "chunks", "voxelize_to_zarr"):
        assert python not in line, (python, line)
    return line


def said_fit(line: str) -> int | float:
    """The finest grid a refusal says fits in the small budget."""
    found = re.search(r"at most --resolution (\d+) fits in 1\.9 MiB", line)
    if found:
        return int(found.group(1))
    found = re.search(r"--pitch (\S+) or coarser fits in 1\.9 MiB", line)
    assert found, line
    return float(found.group(1))


@pytest.mark.parametrize("out", ["v.npy", "v.zarr"])
def test_a_mesh_grid_beyond_the_budget_names_the_largest_resolution_that_fits(tmp_path, capsys, monkeypatch, out):
    """The refusal said no resolution that fits, named ``max_bytes`` (and,
    for a store, "smaller chunks", no option of the command). The one it
    names now fits: it is voxelised under the same budget, one more is not."""
    if out.endswith(".zarr"):
        pytest.importorskip("zarr")
    small_budget(monkeypatch)
    line = fails(capsys, "voxelize", TORUS, "--resolution", 400, "-o", tmp_path / out,
                 words=("torus.obj", "--resolution 400 needs", "budget of 1.9 MiB"))
    assert "zarr" not in command_words(line)  # no store holds it in that budget either
    fit = said_fit(line)
    assert main(["voxelize", str(TORUS), "--resolution", str(fit), "-o", str(tmp_path / out)]) == 0
    capsys.readouterr()
    line = fails(capsys, "voxelize", TORUS, "--resolution", fit + 1, "-o", tmp_path / ("w" + out[1:]))
    assert said_fit(line) == fit


def test_a_pitch_beyond_the_budget_names_the_smallest_pitch_that_fits(tmp_path, capsys, monkeypatch):
    small_budget(monkeypatch)
    line = fails(capsys, "voxelize", TORUS, "--pitch", "0.001", "-o", tmp_path / "v.npy",
                 words=("torus.obj", "--pitch 0.001 needs", "or coarser fits"))
    pitch = said_fit(command_words(line))
    assert main(["voxelize", str(TORUS), "--pitch", repr(pitch), "-o", str(tmp_path / "v.npy")]) == 0
    capsys.readouterr()
    assert said_fit(fails(capsys, "voxelize", TORUS, "--pitch", repr(pitch * 0.9), "-o", tmp_path / "w.npy")) == pitch


@pytest.mark.parametrize("out", ["v.npy", "v.zarr"])
def test_a_grid_that_no_file_holds_is_not_sent_to_a_store(tmp_path, capsys, out):
    """--pitch 1e-300: a grid of 3e900 voxels. The in-memory refusal sent
    it to a zarr store, and a store's slabs were listed (for ever) before
    its columns were refused."""
    if out.endswith(".zarr"):
        pytest.importorskip("zarr")
    line = fails(capsys, "voxelize", TORUS, "--pitch", "1e-300", "-o", tmp_path / out,
                 words=("--pitch 1e-300 needs", "3.125e+900 voxels", "or coarser fits"))
    assert "-o OUT.zarr" not in command_words(line)
    assert ("more columns than a zarr store's slabs can index" in line) == out.endswith(".zarr")


def test_voxelize_suggests_a_store_where_one_holds_the_grid(tmp_path, capsys, monkeypatch):
    from isoflow.scale import memory

    monkeypatch.setattr(memory, "default_budget", lambda: 512 << 20)  # a store at 2048 holds about 360 MiB
    line = fails(capsys, "voxelize", TORUS, "--resolution", 2048, "-o", tmp_path / "v.npy",
                 words=("--resolution 2048 needs", "fits in 512.0 MiB", "or write it slab by slab: -o OUT.zarr"))
    command_words(line)


def test_genus_beyond_the_budget_names_the_largest_resolution_that_fits(capsys, monkeypatch):
    """genus suggested a store (`voxelize -o OUT.zarr`), of no use for the
    Betti numbers; the resolution it names fits the voxels and their
    labelling, as the stepping counts them."""
    small_budget(monkeypatch)
    line = fails(capsys, "genus", TORUS, "--resolution", 400, words=("torus.obj", "--resolution 400 needs", "Betti"))
    assert "zarr" not in command_words(line) and "voxelize" not in line
    fit = said_fit(line)
    assert main(["genus", str(TORUS), "--resolution", str(fit), "--no-step"]) == 0
    capsys.readouterr()
    assert said_fit(fails(capsys, "genus", TORUS, "--resolution", fit + 1)) == fit


def test_surface_of_a_mesh_beyond_the_budget_names_the_largest_resolution_that_fits(tmp_path, capsys, monkeypatch):
    small_budget(monkeypatch)
    line = fails(capsys, "surface", TORUS, "--resolution", 400, "-o", tmp_path / "s.ply",
                 words=("torus.obj", "--resolution 400 needs"))
    assert "zarr" not in command_words(line)
    # its voxels fit (the surface's own memory is checked when it is known)
    assert main(["voxelize", str(TORUS), "--resolution", str(said_fit(line)), "-o", str(tmp_path / "v.npy")]) == 0


# --------------------------------------- option values, as they are read

@pytest.mark.parametrize("argv, words", [
    (["voxelize", "missing.obj", "-o", "v.npy", "--resolution", "0"], ("--resolution", "from 1", "got 0")),
    (["voxelize", "missing.obj", "-o", "v.npy", "--resolution", "-3"], ("--resolution", "got -3")),
    (["voxelize", "missing.obj", "-o", "v.npy", "--resolution", "2.5"], ("--resolution", "'2.5'")),
    (["genus", "missing.obj", "--resolution", "64", "0"], ("--resolution", "got 0")),
    (["genus", "missing.obj", "--max-resolution", "0"], ("--max-resolution", "got 0")),
    (["surface", "missing.obj", "-o", "s.ply", "--resolution", "0"], ("--resolution", "got 0")),
    (["info", "missing.obj", "--pitch", "-1"], ("--pitch", "got -1")),
])
def test_a_resolution_below_one_is_refused_before_the_mesh_is_read(capsys, argv, words):
    """Refused only after the mesh was loaded (minutes for a large one):
    here the mesh does not even exist, and the option is what is said (as
    the arguments are read: nothing is written)."""
    with pytest.raises(SystemExit) as done:
        main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert done.value.code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert "missing.obj" not in lines[0] and all(w in lines[0] for w in words), lines[0]


def test_messages_name_options_on_the_command_line_and_parameters_in_python(tmp_path, capsys):
    """One refusal, two readers: the shell's gets --force, --strict and
    --overlap, Python's force=, strict= and overlap= (both were printed
    side by side, "--force (force=True)", which reads wrong in each)."""
    import trimesh

    from isoflow import voxelize_meshes
    from isoflow.mesh.export import write_mesh_file
    from isoflow.mesh.voxelize import voxelize_file

    vol = np.zeros((4, 4, 4), bool)
    vol[1:3, 1:3, 1:3] = True
    np.save(tmp_path / "v.npy", vol)
    (tmp_path / "s.ply").write_text("taken")
    fails(capsys, "surface", tmp_path / "v.npy", "-o", tmp_path / "s.ply", words=("exists; pass --force to overwrite",))
    from isoflow import boundary_mesh

    with pytest.raises(IsoflowError, match=r"exists; pass force=True to overwrite$"):
        write_mesh_file(tmp_path / "s.ply", boundary_mesh(vol), None)
    open_box = trimesh.creation.box()
    open_box.faces = open_box.faces[1:]
    open_box.export(tmp_path / "open.obj")
    fails(capsys, "voxelize", tmp_path / "open.obj", "-o", tmp_path / "o.npy", "--resolution", "8", "--strict",
          words=("not watertight", "(without --strict it is read"))
    with pytest.raises(IsoflowError, match=r"\(without strict=True it is read") as raised:
        voxelize_file(tmp_path / "open.obj", resolution=8, strict=True)
    assert "--strict" not in str(raised.value)
    a, b = trimesh.creation.box(), trimesh.creation.box()
    b.apply_translation((0.5, 0, 0))
    a.export(tmp_path / "a.obj")
    b.export(tmp_path / "b.obj")
    fails(capsys, "voxelize", tmp_path / "a.obj", tmp_path / "b.obj", "-o", tmp_path / "l.npy", "--resolution", "8",
          "--overlap", "error", words=("the meshes overlap", "--overlap later gives"))
    with pytest.raises(IsoflowError, match=r"overlap='later' gives") as raised:
        voxelize_meshes([str(tmp_path / "a.obj"), str(tmp_path / "b.obj")], resolution=8, overlap="error")
    assert "--overlap" not in str(raised.value)


# ------------------------------------------------------ mesh face indices

TET = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"


@pytest.mark.parametrize(
    "face, words",
    [("f 1 2 5", ("index 5", "past the file's 4 vertices")),  # was IndexError: index 4 is out of bounds
     ("f -1 -2 -5", ("index -5", "before the first vertex (4 vertices")),  # was IndexError: index -5 ...
     ("f 0 2 3", ("index 0", "OBJ numbers vertices from 1"))],  # was read as 'f 1 2 3', without a word
)
@pytest.mark.parametrize("command", [("genus",), ("voxelize", "--resolution", "16", "-o", "out.npy"),
                                     ("surface", "--resolution", "16", "-o", "out.stl")])
def test_an_obj_face_index_that_names_no_vertex_is_one_line_naming_it(tmp_path, capsys, face, words, command):
    path = tmp_path / "bad.obj"
    path.write_text(TET + "f 1 3 2\nf 1 2 4\n# the bad face\n" + face + "\nf 2 3 4\n")  # the bad face: line 8
    name, *rest = command
    rest = [str(tmp_path / w) if w.startswith("out.") else w for w in rest]
    fails(capsys, name, path, *rest, words=(f"bad.obj:8: face '{face}' uses vertex", *words))
    assert not any(tmp_path.glob("out.*"))


@pytest.mark.parametrize("text, words", [
    ("f 1 2 3\n", ":1: face 'f 1 2 3' uses vertex index 1, but the file has no vertices"),  # was "no triangles read"
    ("v 0 0 0\nf 1 2 3\n", ":2: face 'f 1 2 3' uses vertex index 2, past the file's only vertex"),  # "1 vertices"
    ("v 0 0 0\nf -1 -1 -2\n", ":2: face 'f -1 -1 -2' uses vertex index -2, before the first vertex (1 vertex comes "
                             "before the face")])
def test_an_obj_whose_faces_name_no_vertex_it_has_says_which(tmp_path, capsys, text, words):
    """Faces of an OBJ with no vertex, or with one, name indices past them
    (trimesh reads the first file as an empty mesh without a word)."""
    path = tmp_path / "bad.obj"
    path.write_text(text)
    fails(capsys, "genus", path, words=(f"{path}{words}",))


@pytest.mark.parametrize(
    "line, words",  # each was "cannot read as a mesh (ValueError: string or file could not be read to its end ...)"
    [("v 0,5 1 1", ("'v 0,5 1 1': '0,5' is not a coordinate", "decimals with a point: 0.5")),
     ("v 1.0.0 1 1", ("'1.0.0' is not a coordinate",)),
     ("vt 0 a", ("'vt 0 a': 'a' is not a texture coordinate",)),
     ("f 1 3 x", ("'f 1 3 x': 'x' is not a vertex index",)),
     ("v 1 1", ("'v 1 1': 2 coordinates, where a vertex has 3",))],  # was "vertices must have shape (N, 3)"
)
def test_an_obj_word_that_is_no_number_is_one_line_naming_it(tmp_path, capsys, line, words):
    """The bad line is line 6 of the file; trimesh, the reader of such a
    file, cannot read it either."""
    path = tmp_path / "bad.obj"
    path.write_text(TET + "# a comment\n" + line + "\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
        read = mesh.vertices.shape[1:] == (3,) and len(mesh.faces) == 4  # a 2-coordinate vertex: (N, 2)
    except ValueError:
        read = False
    assert not read
    fails(capsys, "voxelize", path, "--resolution", 8, "-o", tmp_path / "out.npy", words=("bad.obj:6: ", *words))
    assert not (tmp_path / "out.npy").exists()


@pytest.mark.parametrize("name", ["e.glb", "e.ply", "e.stl", "e.obj", "e.off", "e.gltf"])
@pytest.mark.parametrize("command", [("genus",), ("info",), ("voxelize", "--resolution", "8", "-o", "out.npy")])
def test_an_empty_mesh_file_is_said_to_be_empty(tmp_path, capsys, name, command):
    """A mesh file of 0 bytes (a download or copy that failed), as the
    volume files are: trimesh said "IndexError: index 0 is out of bounds
    for axis 0 with size 0" of a GLB, "Not a ply file!" of a PLY, and of
    an STL "no triangles read (empty mesh, or not a valid STL file)"."""
    path = tmp_path / name
    path.write_bytes(b"")
    assert os.path.getsize(path) == 0
    what = name.split(".")[-1].upper()
    name_, *rest = command
    rest = [str(tmp_path / w) if w.startswith("out.") else w for w in rest]
    fails(capsys, name_, path, *rest, words=(f"{name}: an empty file (0 bytes), not a readable {what} file",))
    assert not (tmp_path / "out.npy").exists()


STEP = "ISO-10303-21;\nHEADER;\nFILE_NAME('part.step');\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n"


@pytest.mark.parametrize("name", ["part.step", "part.STP", "part.igs"])
@pytest.mark.parametrize("command", [("genus",), ("info",), ("surface", "-o", "out.ply"),
                                     ("voxelize", "--resolution", "8", "-o", "out.npy")])
def test_a_cad_file_says_it_is_one_and_how_to_get_a_mesh(tmp_path, capsys, name, command):
    """A STEP file was "cannot read as a mesh (ModuleNotFoundError: No
    module named 'cascadio')" to genus and voxelize, and a point list to
    info and surface ("part.step:1: not a number: 'ISO-10303-21;'"); an
    IGES file "names no mesh format", or a point list too."""
    import importlib.util

    if importlib.util.find_spec("cascadio") is not None and name.lower().endswith((".step", ".stp")):
        pytest.skip("cascadio tessellates STEP files: trimesh reads them")
    path = tmp_path / name
    path.write_text(STEP)
    if name.lower().endswith((".step", ".stp")):
        with pytest.raises(ModuleNotFoundError, match="cascadio"):  # trimesh's own reader, without cascadio
            trimesh.load(path)
    name_, *rest = command
    rest = [str(tmp_path / w) if w.startswith("out.") else w for w in rest]
    kind = name.rsplit(".", 1)[1].upper()
    fails(capsys, name_, path, *rest, words=(f"{name}: a CAD file ({kind}: surfaces, not triangles)",
                                             "export it from the CAD tool as STL, OBJ, PLY or GLB"))
    assert not any(tmp_path.glob("out.*"))


def test_an_off_face_index_that_names_no_vertex_names_its_line(tmp_path, capsys):
    path = tmp_path / "bad.off"
    path.write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n# a comment\n\n3 0 3 4\n3 1 2 3\n")
    fails(capsys, "genus", path, words=("bad.off:11: OFF face 2 '3 0 3 4' uses vertex 4", "not one of the 4 vertices"))
    path.write_text("OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 -1 2\n")  # was read as vertex 3 (the last)
    fails(capsys, "genus", path, words=("bad.off:7: OFF face 0 '3 0 -1 2' uses vertex -1", "numbered from 0 to 3"))


# ------------------------------------------- mesh content in another format

PLY_TET = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
           "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
OFF_TET = "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
OBJ_TET = TET + "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def tet_stl(binary: bool) -> bytes:
    mesh = trimesh.Trimesh(np.eye(4, 3, -1), [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], process=False)
    out = mesh.export(file_type="stl" if binary else "stl_ascii")
    return out if isinstance(out, bytes) else out.encode()


@pytest.mark.parametrize(
    "content, name, words",  # each was "no triangles read (empty mesh, or not a valid X file)" unless noted
    [(OBJ_TET, "model.stl", ("an OBJ file (lines 'v x y z' and 'f ...'), not STL", "rename it model.obj")),
     (PLY_TET, "model.obj", ("a PLY file", "not OBJ", "rename it model.ply")),
     (PLY_TET, "model.stl", ("a PLY file", "not STL", "rename it model.ply")),
     (OFF_TET, "model.obj", ("an OFF file", "not OBJ", "rename it model.off")),
     (OBJ_TET, "model.ply", ("an OBJ file", "not PLY", "rename it model.obj")),  # was trimesh's 'Not a ply file!'
     (OBJ_TET, "model.off", ("an OBJ file", "not OFF", "rename it model.obj")),  # was 'not an OFF file'
     (tet_stl(binary=False), "model.obj", ("an ASCII STL file", "not OBJ", "rename it model.stl")),
     (tet_stl(binary=True), "model.obj", ("a binary STL file", "not OBJ", "rename it model.stl")),
     (tet_stl(binary=True), "model.glb", ("a binary STL file", "not GLB", "rename it model.stl"))],
)
@pytest.mark.parametrize("command", [("genus",), ("info", "--resolution", "32")])
def test_mesh_content_in_another_format_than_its_suffix_names_it(tmp_path, capsys, content, name, words, command):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    line = fails(capsys, command[0], path, *command[1:], words=(f"{path}: no triangles read: its content is", *words))
    assert "cannot read" not in line and "not a valid" not in line
    renamed = path.rename(tmp_path / words[-1].split()[-1])  # the fix it names reads the file
    assert main(["genus", str(renamed)]) == 0


@pytest.mark.parametrize("content", [bytes(range(256)) * 20, b"hello\nworld\n", b"solid x\nendsolid x\n"])
def test_a_mesh_file_that_is_no_format_keeps_the_plain_line(tmp_path, capsys, content):
    path = tmp_path / "junk.stl"
    path.write_bytes(content)
    fails(capsys, "genus", path, words=(f"{path}: no triangles read (empty mesh, or not a valid STL file)",))


@pytest.mark.parametrize("name, magic", [("junk.ply", "b'ply'"), ("junk.glb", "b'glTF'")])
@pytest.mark.parametrize("content", [b"hello\nworld\n", bytes(range(256)) * 20], ids=["text", "bytes"])
def test_a_file_without_its_formats_magic_word_says_so(tmp_path, capsys, name, magic, content):
    """The PLY and glTF specifications open every file with 'ply' and
    'glTF'; a file named so without them (of text or bytes of no mesh
    format) is said to lack that word, not by trimesh's "IndexError: list
    index out of range" on a PLY of text."""
    path = tmp_path / name
    path.write_bytes(content)
    fmt = name.rsplit(".")[-1].upper()
    line = fails(capsys, "genus", path, words=(f"{path}: not a {fmt} file: it starts with {content[:8]!r}, not {fmt}'s {magic}",))
    assert "Error" not in line


def test_a_file_in_its_suffix_format_without_triangles_says_what_it_holds(tmp_path, capsys):
    """A PLY of its format holding the tetrahedron's 4 points and no face
    is named a point cloud, not another format, nor a broken file."""
    path = tmp_path / "points.ply"
    path.write_text(PLY_TET.replace("element face 4", "element face 0").rsplit("\n", 5)[0] + "\n")  # points only
    held = len(trimesh.load(path).vertices)
    fails(capsys, "genus", path, words=(f"{path}: no triangles read: it holds {held} points and no faces",))


@pytest.mark.parametrize("input_name", ["b.npy", "b.zarr"])
def test_surface_names_a_bad_connectivity_before_an_existing_output(tmp_path, capsys, input_name):
    # a surface is always of a 3D object, so 80 (a 4D connectivity) can never
    # work: it was refused only after "exists; pass --force", and --force
    # then led to the real problem
    vol = np.zeros((5, 5, 5), bool)
    vol[1:4, 1:4, 1:4] = True
    if input_name.endswith(".zarr"):
        zarr = pytest.importorskip("zarr")
        zarr.create_array(str(tmp_path / input_name), data=vol.astype(np.uint8), chunks=(3, 3, 3), zarr_format=2)
    else:
        np.save(tmp_path / input_name, vol)
    (tmp_path / "old.ply").write_text("kept")
    with pytest.raises(SystemExit) as refused:  # argparse's refusal, with the choices
        main(["surface", str(tmp_path / input_name), "--connectivity", "80", "-o", str(tmp_path / "old.ply")])
    assert refused.value.code == 2
    assert capsys.readouterr().err.strip().splitlines() == [
        "isoflow surface: error: argument --connectivity: invalid choice: 80 (choose from 6, 26)"]
    assert (tmp_path / "old.ply").read_text() == "kept"


def test_a_face_far_from_the_rest_is_named_when_the_weld_leaves_no_face(tmp_path, capsys):
    # the weld merges positions closer than 1e-10 of the box's diagonal: one
    # face at 1e300 made that 1e290, every other face lost its corners, and
    # the line said only "every face is degenerate"
    box = trimesh.creation.box()
    far = np.array([[1e300, 0, 0], [1e300, 1, 0], [1e300, 0, 1]])
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.vstack([box.vertices, far]).tolist()]
    lines += [f"f {a} {b} {c}" for a, b, c in (box.faces + 1).tolist()] + ["f 9 10 11"]
    (tmp_path / "stray.obj").write_text("\n".join(lines) + "\n")
    fails(capsys, "info", tmp_path / "stray.obj", "--resolution", 8,
          words=("stray.obj: empty mesh", "1e-10 of the bounding box's diagonal", "[1e+300, 1.0, 1.0]",
                 "a face far from the others"))
    # faces degenerate as written: the plain line
    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nf 1 2 2\nf 1 1 2\n")
    line = fails(capsys, "info", tmp_path / "flat.obj", "--resolution", 8)
    assert "far from the others" not in line


def test_a_float32_file_that_holds_one_point_is_not_blamed_on_a_far_face(tmp_path, capsys):
    """A torus of radius 1.3 saved as float32 at 1e9, where float32 numbers
    lie 64 apart: every corner is the same point in the file (trimesh reads
    one position back). The line blamed a face far from the others
    stretching a box that has no size; it names the one position and the
    float32 spacing there."""
    torus = trimesh.creation.torus(1.0, 0.3)
    torus.apply_translation([1e9, 1e9, 1e9])
    torus.export(tmp_path / "far.ply")  # trimesh writes float32 coordinates
    read = trimesh.load(tmp_path / "far.ply", process=False)
    assert len(np.unique(read.vertices, axis=0)) == 1 and np.spacing(np.float32(1e9)) == 64
    line = fails(capsys, "genus", tmp_path / "far.ply", "--resolution", 8,
                 words=("far.ply: empty mesh", "one position, [1000000000.0, 1000000000.0, 1000000000.0]",
                        "float32 coordinates are 64 apart there"))
    assert "far from the others" not in line


@pytest.mark.parametrize("given", ["float64", "origin.obj"])
def test_one_point_that_float32_did_not_make_is_not_blamed_on_float32(tmp_path, capsys, given):
    """A float64 mesh in memory whose corners all sit at one point, and a
    file whose corners all say 0 0 0: the line spoke of "float32 coordinates
    ... 1.4e-45 apart", which explains nothing there (the corners are one
    point as given). It says what is wrong: one position, no face with
    area. trimesh agrees that the face has no area."""
    import isoflow

    vertices, faces = np.zeros((3, 3)), np.array([[0, 1, 2]])
    assert trimesh.Trimesh(vertices, faces, process=False).area == 0
    if given == "float64":
        with pytest.raises(isoflow.IsoflowError) as info:
            isoflow.verify_genus((vertices, faces), [8])
        line = str(info.value)
    else:
        (tmp_path / given).write_text("v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n")
        line = fails(capsys, "genus", tmp_path / given, "--resolution", 8)
    assert line.endswith("empty mesh: every corner of every face lies at one position, [0.0, 0.0, 0.0]; "
                         "no face has area"), line
    assert "float32 coordinates" not in line and "apart" not in line


def test_a_refused_info_leaves_no_thread_warming_up(tmp_path, capsys, monkeypatch):
    """info loads numba on a second thread while it reads a large input; on
    a refusal that thread was left running after the command, and numba's
    compile (which records the warnings of every thread and says them again
    when it ends) put an earlier command's warning into a later one's
    stderr. The warm-up here takes its time as a first compile does."""
    import threading
    import time

    from isoflow.cli.info import WARM_UP_THREAD
    from isoflow.digital import closed_surfaces
    from isoflow.scale.compiled import have_numba, least_voxels

    if not have_numba():
        pytest.skip("numba not installed: no warm-up")
    side = round(least_voxels(surfaces=True) ** (1 / 3)) + 1
    labels = np.zeros((side,) * 3, np.uint8)
    labels[0, 0, 0], labels[1, 1, 1] = 2, 3  # a label image where a mask is read: refused after the read
    np.save(tmp_path / "big.npy", labels)
    warming = threading.Event()

    def slow_warm_up(surfaces=True):
        warming.set()
        time.sleep(0.5)

    monkeypatch.setattr(closed_surfaces, "warm_up", slow_warm_up)
    fails(capsys, "info", tmp_path / "big.npy", words=("big.npy", "not a binary volume"))
    assert warming.is_set()  # (the warm-up ran: the input is large enough)
    assert not [t.name for t in threading.enumerate() if t.name == WARM_UP_THREAD and t.is_alive()]


# ------------------------------------------------- a missing input, worded once

#: inputs of every kind (volumes, a point list, meshes, a zarr store, an HDF5
#: dataset) and the file the line names
MISSING_INPUTS = {"gone.npy": "gone.npy", "gone.tif": "gone.tif", "gone.txt": "gone.txt", "gone.stl": "gone.stl",
                  "gone.ply": "gone.ply", "gone.off": "gone.off", "gone.zarr": "gone.zarr", "gone.h5:/v": "gone.h5"}


@pytest.mark.parametrize("command", ["info", "voxelize", "surface", "genus", "flow"])
def test_a_missing_input_is_worded_alike_by_every_command(command, tmp_path, capsys):
    """Volumes said "no such file", meshes "file not found", zarr stores
    "no such file or directory"; voxelize and genus said a missing volume
    was "a volume file, not a triangle mesh". Every command, on an input
    of every kind that is not there, now says the one wording."""
    after = {"voxelize": ["--resolution", "8", "-o", tmp_path / "v.npy"], "surface": ["-o", tmp_path / "s.ply"],
             "flow": ["--out", tmp_path / "flow"]}.get(command, [])
    for given, named in MISSING_INPUTS.items():
        line = fails(capsys, command, f"{tmp_path}/{given}", *after)
        assert line == f"isoflow {command}: error: {tmp_path / named}: no such file or directory", given
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("given", sorted(MISSING_INPUTS))
def test_a_missing_input_is_a_file_not_found_error_in_python(given, tmp_path):
    """In Python the same line is also a FileNotFoundError, what open()
    raises, so that ``except FileNotFoundError`` (or OSError) catches a
    missing input of every kind, as ``except IsoflowError`` does."""
    path = f"{tmp_path}/{given}"
    with pytest.raises(FileNotFoundError) as caught:
        open(path.split(":")[0], "rb")  # the error the standard library gives
    mesh, points = given.endswith((".stl", ".ply", ".off")), given.endswith(".txt")
    for read in [isoflow.read_object] + ([isoflow.read_points] if points else [] if mesh else [isoflow.read_volume]):
        with pytest.raises(IsoflowError) as mine:
            read(path)
        assert isinstance(mine.value, type(caught.value)), (read.__name__, given)
        assert str(mine.value) == f"{tmp_path / MISSING_INPUTS[given]}: no such file or directory"
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("command", ["info", "voxelize", "surface", "genus", "flow"])
def test_a_url_is_said_to_be_one_not_a_missing_file(command, tmp_path, capsys, monkeypatch):
    """A store in a bucket (``s3://bucket/scan.zarr``) was "s3:/bucket/scan.zarr:
    no such file or directory", the URL mangled by ``Path``; every command
    now names the URL as given and says that isoflow reads local paths."""
    monkeypatch.chdir(tmp_path)
    after = {"voxelize": ["--resolution", "8", "-o", "v.npy"], "surface": ["-o", "s.ply"],
             "flow": ["--out", "flow"]}.get(command, [])
    for url in ("s3://bucket/scan.zarr", "gs://bucket/scan.ome.zarr:1", "https://example.org/bunny.ply",
                "s3://bucket/ct.nii.gz", "s3://bucket/seg.h5:/v"):
        line = fails(capsys, command, url, *after, words=["a URL", "local"])
        assert line.startswith(f"isoflow {command}: error: {url.split('.')[0]}"), line
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("command", ["info", "surface", "flow"])
def test_a_zipped_zarr_store_is_said_to_be_one(command, tmp_path, capsys):
    """A zarr store in a zip archive (zarr's ZipStore) was opened by trimesh
    as a zip of meshes: "no triangles read (empty mesh, or not a valid ZIP
    file)". It is now one line naming the archive and the command that
    unzips it, whose directory then gives the report of the volume."""

    zarr = pytest.importorskip("zarr")
    v = np.zeros((9, 8, 7), np.uint8)
    v[2:7, 2:6, 1:6] = 1
    v[4, 3:5, :] = 0  # a tunnel
    store = zarr.storage.ZipStore(tmp_path / "scan.zarr.zip", mode="w")
    zarr.create_array(store, shape=v.shape, chunks=(4, 3, 5), dtype="u1")[...] = v
    store.close()
    after = {"surface": ["-o", tmp_path / "s.ply"], "flow": ["--out", tmp_path / "flow"]}.get(command, [])
    line = fails(capsys, command, tmp_path / "scan.zarr.zip", *after, words=["a zipped zarr store"])
    unzip = re.search(r"\((python -m zipfile -e \S+ \S+)\)", line)[1].split()
    subprocess.run([sys.executable, *unzip[1:]], check=True)
    assert main(["info", str(tmp_path / "scan.zarr"), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["betti"] == [1, 1, 0] and report["euler_characteristic"] == 0


@pytest.mark.parametrize("suffix", [".ply", ".glb", ".obj"])
@pytest.mark.parametrize("command", [["genus"], ["voxelize", "--resolution", "8", "-o", "OUT.npy"],
                                     ["voxelize", "--split", "--resolution", "8", "-o", "OUT.npy"]])
def test_a_point_cloud_is_named_with_its_points(tmp_path, capsys, suffix, command):
    """A scan's point cloud given where a surface is taken: one line that
    says it holds points and no faces (as many points as trimesh reads from
    the file), exit 2, nothing written."""
    cloud = tmp_path / f"scan{suffix}"
    points = np.random.default_rng(3).random((37, 3))
    if suffix == ".obj":
        cloud.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in points))
        held = len(trimesh.load(cloud, process=False).vertices)
    else:
        trimesh.PointCloud(points).export(cloud)
        geometry = trimesh.load(cloud, force="scene").geometry.values() if suffix == ".glb" else [trimesh.load(cloud)]
        held = sum(len(g.vertices) for g in geometry if isinstance(g, trimesh.PointCloud))
    assert held == 37
    args = [str(tmp_path / a) if a == "OUT.npy" else a for a in command]
    assert main([args[0], str(cloud), *args[1:]]) == 2
    err = capsys.readouterr().err
    assert f"holds {held} points and no faces, a point cloud, not a surface" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "OUT.npy").exists()


@pytest.mark.parametrize("suffix", [".obj", ".ply"])
@pytest.mark.parametrize("edges", [0, 2], ids=["points", "lines"])
def test_a_faceless_file_is_read_once_for_its_refusal(tmp_path, monkeypatch, suffix, edges):
    """The refusal of a PLY or OBJ of vertices and no face read the file
    twice after its reader gave up, once for its points and once for its
    lines (a PLY's header parsed each time). It reads it once, parses a
    PLY's header once, and the line is the one the shell gives, with the
    3 points and the lines written."""
    import builtins

    from isoflow.mesh import load, ply

    corners = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    path = tmp_path / f"part{suffix}"
    if suffix == ".obj":
        path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners) + "l 1 2\nl 2 3\n" * (edges // 2))
    else:
        path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                        "property float z\n" + ("element edge 2\nproperty int vertex1\nproperty int vertex2\n" * bool(edges))
                        + "end_header\n" + "".join(f"{x} {y} {z}\n" for x, y, z in corners) + "0 1\n1 2\n" * bool(edges))
    reads, parses, refusing = [], [], [False]
    opened, path_open, parse, refusal = builtins.open, Path.open, ply.header_elements, load._point_cloud_line

    def counted_open(file, *args, **kwargs):
        if refusing[0] and os.fspath(file) == str(path):
            reads.append(file)
        return opened(file, *args, **kwargs)

    def counted_path_open(self, *args, **kwargs):
        if refusing[0] and self == path:
            reads.append(self)
        return path_open(self, *args, **kwargs)

    def counted_parse(*args, **kwargs):
        parses.append(refusing[0])
        return parse(*args, **kwargs)

    def watched_refusal(*args, **kwargs):
        refusing[0] = True
        try:
            return refusal(*args, **kwargs)
        finally:
            refusing[0] = False

    monkeypatch.setattr(builtins, "open", counted_open)
    monkeypatch.setattr(Path, "open", counted_path_open)
    monkeypatch.setattr(ply, "header_elements", counted_parse)
    monkeypatch.setattr(load, "_point_cloud_line", watched_refusal)
    with pytest.raises(IsoflowError) as caught:
        load.load_mesh(path)
    assert len(reads) == 1, reads
    assert parses.count(True) == (suffix == ".ply")
    want = (f"{path}: no triangles read: it holds 3 points joined by 2 lines and no faces, a wireframe, not a surface"
            if edges else f"{path}: no triangles read: it holds 3 points and no faces, a point cloud, not a surface")
    assert str(caught.value).startswith(want), caught.value
    monkeypatch.undo()
    done = isoflow_here("genus", str(path))
    assert done.returncode == 2 and done.stderr.strip() == f"isoflow genus: error: {caught.value}", done.stderr


@pytest.mark.parametrize("zipped", [False, True], ids=["file", "zip"])
@pytest.mark.parametrize("suffix", [".obj", ".ply"])
@pytest.mark.parametrize("command", [["genus"], ["voxelize", "--resolution", "8", "-o", "OUT.npy"],
                                     ["voxelize", "--split", "--resolution", "8", "-o", "OUT.npy"]])
def test_a_wireframe_is_named_a_wireframe_not_a_point_cloud(tmp_path, capsys, suffix, command, zipped):
    """A model's edges saved without its faces (OBJ ``l`` lines, a PLY
    ``edge`` element) was called a point cloud and sent to a surface
    reconstruction; it is named by its points and lines (a cube's 8 corners
    and the 18 edges trimesh counts on its triangles), as a glTF of lines
    is, exit 2, nothing written. Inside a zip archive too, where it was
    still a point cloud (an OBJ) or "no triangles read" (a PLY)."""
    cube = trimesh.creation.box()
    edges = cube.edges_unique
    assert (len(cube.vertices), len(edges)) == (8, 18)
    wire = tmp_path / f"cage{suffix}"
    if suffix == ".obj":
        wire.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in cube.vertices)
                        + "".join(f"l {a + 1} {b + 1}\n" for a, b in edges))
    else:
        wire.write_text("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                        "property float z\nelement edge 18\nproperty int vertex1\nproperty int vertex2\n"
                        "end_header\n" + "".join(f"{x} {y} {z}\n" for x, y, z in cube.vertices)
                        + "".join(f"{a} {b}\n" for a, b in edges))
    if zipped:
        with zipfile.ZipFile(tmp_path / "cage.zip", "w") as z:
            z.write(wire, wire.name)
        wire = tmp_path / "cage.zip"
    args = [str(tmp_path / a) if a == "OUT.npy" else a for a in command]
    assert main([args[0], str(wire), *args[1:]]) == 2
    err = capsys.readouterr().err
    assert "holds 8 points joined by 18 lines and no faces, a wireframe, not a surface" in err, err
    assert err.startswith(f"isoflow {args[0]}: error: {wire}:cage{suffix}: " if zipped else f"isoflow {args[0]}: error: {wire}: ")
    assert "point cloud" not in err and len(err.splitlines()) == 1
    assert not (tmp_path / "OUT.npy").exists()


@pytest.mark.parametrize("zipped", [False, True], ids=["file", "zip"])
@pytest.mark.parametrize("suffix", [".obj", ".ply"])
def test_lines_beside_faces_are_named_in_a_note(tmp_path, capsys, suffix, zipped):
    """A cube's faces with its 18 edges beside them (OBJ ``l`` lines, a
    PLY ``edge`` element): the readers take the faces and leave the lines
    out, as trimesh does, and said nothing, where a glTF file's lines
    beside faces are named in a note. The note now names them in the
    glTF note's words; the voxels are the cube's without its lines."""
    cube = trimesh.creation.box()
    edges = cube.edges_unique
    assert len(edges) == 18
    plain, lined = tmp_path / f"cube{suffix}", tmp_path / f"cage{suffix}"
    if suffix == ".obj":
        cube.export(plain)
        lined.write_text(plain.read_text() + "".join(f"l {a + 1} {b + 1}\n" for a, b in edges))
    else:
        cube.export(plain, encoding="ascii")
        head, body = plain.read_text().split("end_header\n")
        lined.write_text(head + "element edge 18\nproperty int vertex1\nproperty int vertex2\nend_header\n" + body
                         + "".join(f"{a} {b}\n" for a, b in edges))
    loaded = trimesh.load(lined, process=False)
    assert len(loaded.faces) == len(cube.faces) == 12  # trimesh reads the faces alone too
    name = str(lined)
    if zipped:
        with zipfile.ZipFile(tmp_path / "cage.zip", "w") as z:
            z.write(lined, lined.name)
        name = f"{tmp_path / 'cage.zip'}:{lined.name}"
        lined = tmp_path / "cage.zip"
    assert main(["voxelize", str(plain), "--resolution", "8", "-o", str(tmp_path / "plain.npz")]) == 0
    assert capsys.readouterr().err == ""
    assert main(["voxelize", str(lined), "--resolution", "8", "-o", str(tmp_path / "lined.npz")]) == 0
    what = "18 lines (OBJ l lines)" if suffix == ".obj" else "18 edges (the PLY edge element)"
    assert f"isoflow voxelize: note: {name}: read without its {what}: they hold no face and bound no solid\n" \
        in capsys.readouterr().err
    assert np.array_equal(np.load(tmp_path / "lined.npz")["volume"], np.load(tmp_path / "plain.npz")["volume"])


@pytest.mark.parametrize("command", ["info", "surface", "flow"])
def test_a_probability_map_is_offered_a_threshold_not_a_label(tmp_path, capsys, command):
    """A probability map refused as a mask was offered ``--label N``, which
    selects no voxel of a map of fractions; it is offered the threshold
    half way through 0 to 1 alone. The map is nibabel's float32, its values
    fractions in 0..1 as nibabel reads them back."""
    nib = pytest.importorskip("nibabel")
    probability = np.random.default_rng(7).random((6, 6, 6)).astype(np.float32)
    nib.save(nib.Nifti1Image(probability, np.eye(4)), tmp_path / "p.nii.gz")
    data = nib.load(tmp_path / "p.nii.gz").get_fdata()
    assert 0 <= data.min() and data.max() <= 1 and np.any(data != np.round(data))
    said = fails(capsys, command, tmp_path / "p.nii.gz", *(["-o", tmp_path / "p.ply"] if command == "surface" else []),
                 words=("p.nii.gz", "threshold it first, e.g. volume > 0.5"))
    assert "--label" not in said and said.endswith("volume > 0.5")


def test_an_8_bit_grey_image_is_offered_a_threshold_first_and_labels_as_a_condition(tmp_path, capsys):
    """An 8-bit grey PNG was offered ``--label N`` as if its hundreds of
    grey levels were labels, and ``volume > 0`` as the threshold; it is
    offered the threshold half way through its grey levels as Pillow reads
    them (``getextrema``), and labels only if its values are labels."""
    from PIL import Image

    grey = np.arange(256, dtype=np.uint8).reshape(16, 16)
    Image.fromarray(grey).save(tmp_path / "g.png")
    low, high = Image.open(tmp_path / "g.png").getextrema()
    assert len(Image.open(tmp_path / "g.png").getcolors()) == 256
    fails(capsys, "info", tmp_path / "g.png",
          words=(f"threshold it first, e.g. image > {(low + high) // 2}, or, if its values are labels, select one "
                 "with --label N",))


@pytest.mark.parametrize("command", ["flow", "info"])
def test_the_threshold_offered_for_negative_labels_keeps_every_labelled_voxel(tmp_path, capsys, command):
    """A label image whose labels are negative (an int16 segmentation
    marking its regions -1 and -2) was offered ``volume > 0``, which keeps
    none of them: following the advice gave an empty object. The test
    offered, applied as NumPy reads it, keeps every voxel not 0."""
    labels = np.zeros((10, 10, 10), np.int16)
    labels[1:4, 1:4, 1:4] = -1
    labels[5:9, 5:9, 5:9] = -2
    np.save(tmp_path / "neg.npy", labels)
    said = fails(capsys, command, tmp_path / "neg.npy", words=("neg.npy", "threshold it first, e.g. volume "))
    test = re.search(r"e\.g\. volume (>|!=) (-?[\d.]+)", said)
    assert test, said
    op, value = test.group(1), float(test.group(2))
    kept = labels > value if op == ">" else labels != value
    assert np.count_nonzero(kept) == np.count_nonzero(labels) == 27 + 64


@pytest.mark.parametrize("members, words", [
    ({}, ["an archive of no file: it holds no mesh"]),
    ({"readme.txt": "notes", "logo.png": "png"}, ["holds no mesh file (its files: logo.png, readme.txt)"]),
    ({"torus.zip": None}, ["holds no mesh file (its files: torus.zip)",
                           "an archive inside it (torus.zip) is not opened: unpack it and give its mesh"]),
], ids=["empty", "no-mesh", "nested"])
@pytest.mark.parametrize("command", ["genus", "info"])
def test_a_valid_archive_without_a_mesh_says_what_it_holds(tmp_path, members, words, command):
    """A zip that Python's zipfile opens (so a valid ZIP file) but holding no
    mesh, or only another zip, was "no triangles read (empty mesh, or not a
    valid ZIP file)": it is valid, and the line now names what it holds."""
    inner = tmp_path / "inner.zip"
    with zipfile.ZipFile(inner, "w") as z:
        z.writestr("torus.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    path = tmp_path / "parts.zip"
    with zipfile.ZipFile(path, "w") as z:
        for name, text in members.items():
            z.writestr(name, inner.read_bytes() if text is None else text)
    with zipfile.ZipFile(path) as z:
        assert z.testzip() is None  # Python's zipfile reads it whole: a valid ZIP file
    r = isoflow_here(command, str(path))
    assert r.returncode == 2 and r.stdout == ""
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr
    assert lines[0].startswith(f"isoflow {command}: error: {path}: ")
    assert "not a valid ZIP file" not in lines[0]
    for w in words:
        assert w in lines[0], (w, lines[0])


@pytest.mark.parametrize("given", ["1e400", "-inf", "nan"])
def test_a_label_that_is_no_finite_number_says_finite(tmp_path, capsys, given):
    # "label must be a number, got inf" of --label 1e400, which is one
    np.save(tmp_path / "v.npy", np.ones((2, 2, 2), np.uint8))
    fails(capsys, "surface", tmp_path / "v.npy", f"--label={given}", "-o", tmp_path / "s.ply",
          words=("v.npy: label must be a finite number, got",))
    assert not (tmp_path / "s.ply").exists()
