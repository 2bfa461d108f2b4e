"""``info --labels`` and ``surface --labels`` as run (issue 25): the table
of every label of a file, the NIfTI segmentation's units, the CSV and JSON,
one closed surface per label read back by trimesh and pymeshlab."""

import csv
import json
import math
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from conftest import without_compile_note
from in_process import isoflow_here
from test_input_errors import fails  # one line on stderr, exit 2

from isoflow import analyze, label_table
from isoflow.cli import main
from isoflow.errors import IsoflowError


def run(capsys, *args):
    assert main([*map(str, args)]) == 0, capsys.readouterr().err
    return capsys.readouterr().out


def said(capsys, *args) -> tuple[int, str, list[str]]:
    """A command run in this process (the shell is not what is tested):
    its exit status, its stdout and its stderr's lines."""
    code = main([*map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err.splitlines()


@pytest.fixture
def segmentation(rng):
    """Grains of labels 1-5 with touching faces, edges and vertices, a
    hollow label 9 around label 4's core, 0 between."""
    image = rng.choice([0, 1, 2, 3, 5], size=(16, 14, 12), p=[0.2, 0.2, 0.2, 0.2, 0.2]).astype(np.uint16)
    image[3:11, 3:11, 3:10] = 9
    image[5:9, 5:9, 5:8] = 4
    return image


def test_info_labels_json_rows_equal_analyze_per_label(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    for conn in (6, 26):
        report = json.loads(run(capsys, "info", tmp_path / "seg.npy", "--labels", "--json", "--connectivity", conn))
        rows = report["labels"]
        assert [r["label"] for r in rows] == [1, 2, 3, 4, 5, 9]
        for row in rows:
            want = analyze(segmentation == row["label"], conn)
            assert (row["voxels"], row["euler_characteristic"]) == (want["voxels"], want["euler_characteristic"])
            assert [row["b0"], row["b1"], row["b2"]] == want["betti"]
            assert row["genera"] == [s["genus"] for s in want["surfaces"]]
            assert [row[f"n-{i}"] for i in range(9)] == want["n"]
        assert report["labels"][-1]["b2"] == 1  # 9 holds 4


def test_info_labels_choice_keeps_its_order_and_notes_absent_labels(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    assert main(["info", str(tmp_path / "seg.npy"), "--labels", "9,2-3,40", "--json"]) == 0
    out, err = capsys.readouterr()
    assert [r["label"] for r in json.loads(out)["labels"]] == [9, 2, 3]
    assert "1 of the labels asked for does not occur (40)" in err
    assert main(["info", str(tmp_path / "seg.npy"), "--labels", "9,40-41", "--json"]) == 0
    assert "2 of the labels asked for do not occur (40, 41)" in capsys.readouterr().err
    said = run(capsys, "surface", tmp_path / "seg.npy", "--labels", "3", "-o", tmp_path / "one.glb")
    assert said.startswith(f"{tmp_path / 'one.glb'}: 1 label, ")
    # a label the type cannot hold is noted as absent too (uint16: 0 to 65535)
    assert main(["info", str(tmp_path / "seg.npy"), "--labels", "9,70000", "--json"]) == 0
    assert "1 of the labels asked for does not occur (70000)" in capsys.readouterr().err


def test_labels_asked_for_that_do_not_occur_are_a_warning_quiet_keeps_and_json_lists(tmp_path, capsys, segmentation):
    """A label asked for that no voxel has (or the type cannot hold) was a
    note, which --quiet dropped and --json did not say: a quiet run or a
    script never learnt its table lacked a row it asked for. It is a
    warning line, under --quiet too, and --json lists them as ``absent``;
    the CSV, the JSON's ``labels`` and the surfaces hold the labels that
    occur alone."""
    path = tmp_path / "seg.npy"
    np.save(path, segmentation)
    present = set(np.unique(segmentation).tolist())
    asked = [9, 40, 2, 70000, 3, 41]  # 70000: beyond uint16
    absent = [v for v in asked if v not in present]
    rows = [v for v in asked if v in present]
    assert absent == [40, 70000, 41] and rows == [9, 2, 3]
    spec = ",".join(map(str, asked))
    line = f"warning: {path}: 3 of the labels asked for do not occur (40, 70000, 41)"

    def isoflow(*args):
        code, out, err = said(capsys, *args, "--quiet")
        assert code == 0, err
        return out, err

    # the first as a user's shell runs it, the others in this process
    p = subprocess.run([sys.executable, "-m", "isoflow", "info", str(path), "--labels", spec, "--json", "--csv",
                        str(tmp_path / "seg.csv"), "--quiet"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    out, err = p.stdout, p.stderr.splitlines()
    assert err == [f"isoflow info: {line}"]
    report = json.loads(out)
    assert report["absent"] == absent
    assert [r["label"] for r in report["labels"]] == rows
    with open(tmp_path / "seg.csv", newline="") as fh:
        assert [int(r["label"]) for r in csv.DictReader(fh)] == rows
    out, err = isoflow("info", path, "--labels", "9,2", "--json")
    assert (json.loads(out)["absent"], err) == ([], [])
    assert json.loads(isoflow("info", path, "--labels", "--json")[0])["absent"] == []
    out, err = isoflow("surface", path, "--labels", spec, "-o", f"{tmp_path}/each/", "--suffix", ".ply")
    assert err == [f"isoflow surface: {line}"]
    assert sorted(f.name for f in (tmp_path / "each").iterdir()) == sorted(f"label_{v}.ply" for v in rows)
    out, err = isoflow("surface", path, "--labels", spec, "-o", tmp_path / "seg.glb")
    assert err == [f"isoflow surface: {line}"]
    assert len(trimesh.load(tmp_path / "seg.glb").geometry) == len(rows)


def test_a_float_label_file_names_the_voxel_that_is_no_label(tmp_path, capsys, segmentation):
    scaled = segmentation.astype(np.float16)  # NIfTI's scaling gives floats; float16 warned of an overflow
    np.save(tmp_path / "f.npy", scaled)
    np.save(tmp_path / "i.npy", segmentation)
    assert run(capsys, "info", tmp_path / "f.npy", "--labels", "--json") == run(
        capsys, "info", tmp_path / "i.npy", "--labels", "--json").replace("i.npy", "f.npy").replace("uint16", "int64")
    scaled[4, 5, 6] = np.nan
    np.save(tmp_path / "f.npy", scaled)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fails(capsys, "info", tmp_path / "f.npy", "--labels", words=("f.npy", "voxel (4, 5, 6) holds nan", "not a label"))


def test_a_bool_image_is_label_1_and_holds_no_label_2(tmp_path, capsys, segmentation):
    np.save(tmp_path / "mask.npy", segmentation == 9)
    np.save(tmp_path / "cut.npy", segmentation[8] == 9)  # 2D
    for name in ("mask.npy", "cut.npy"):
        fails(capsys, "info", tmp_path / name, "--labels", "2", words=(name, "none of the labels asked for occur (2)"))
        assert main(["info", str(tmp_path / name), "--labels", "2,1", "--json"]) == 0
        out, err = capsys.readouterr()
        assert [r["label"] for r in json.loads(out)["labels"]] == [1]
        assert "1 of the labels asked for does not occur (2)" in err
    out = run(capsys, "surface", tmp_path / "mask.npy", "--labels", "-o", f"{tmp_path}/out/", "--suffix", "ply")
    assert [p.name for p in (tmp_path / "out").iterdir()] == ["label_1.ply"]
    assert out.startswith(f"{tmp_path}/out/ (1 .ply file): 1 label, ")


def test_info_labels_terminal_table_shows_the_first_rows_and_a_summary(tmp_path, capsys, rng):
    image = np.repeat(np.arange(1, 31, dtype=np.uint8), 2)[:, None, None] * np.ones((1, 3, 3), np.uint8)
    np.save(tmp_path / "slabs.npy", image)
    out = run(capsys, "info", tmp_path / "slabs.npy", "--labels")
    lines = out.splitlines()
    assert "30 labels" in lines[0]
    assert "... 10 more labels" in out
    assert lines[-1].startswith("  all: 30 labels, 540 voxels")
    assert len(lines) == 1 + 1 + 20 + 1 + 1


def test_info_labels_csv_is_the_full_table_and_needs_force(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    out_csv = tmp_path / "t.csv"
    run(capsys, "info", tmp_path / "seg.npy", "--labels", "--csv", out_csv)
    with open(out_csv, newline="") as fh:
        rows = list(csv.DictReader(fh))
    table = label_table(segmentation)
    assert [int(r["label"]) for r in rows] == table["label"].tolist()
    assert list(rows[0]) == list(table)
    assert [r["genera"] for r in rows] == [";".join(map(str, g)) for g in table["genera"]]
    assert [float(r["surface_area"]) for r in rows] == table["surface_area"].tolist()
    fails(capsys, "info", tmp_path / "seg.npy", "--labels", "--csv", out_csv, words=("t.csv", "exists", "--force"))
    run(capsys, "info", tmp_path / "seg.npy", "--labels", "3", "--csv", out_csv, "--force")
    assert len(out_csv.read_text().splitlines()) == 2


def test_info_labels_on_an_anisotropic_nifti_is_in_the_files_units(tmp_path, capsys, segmentation):
    nib = pytest.importorskip("nibabel")
    zooms = (0.5, 0.75, 2.0)
    affine = np.diag([*zooms, 1.0])
    affine[:3, 3] = (10, -20, 30)  # voxel 0's centre
    nib.save(nib.Nifti1Image(segmentation.astype(np.int16), affine), tmp_path / "seg.nii.gz")
    rows = json.loads(run(capsys, "info", tmp_path / "seg.nii.gz", "--labels", "--json"))["labels"]
    read = nib.load(tmp_path / "seg.nii.gz")
    zx, zy, zz = (float(z) for z in read.header.get_zooms())
    assert (zx, zy, zz) == zooms
    unit = label_table(segmentation)  # the same image in voxel units
    for r, row in enumerate(rows):
        mask = segmentation == row["label"]
        assert row["volume"] == pytest.approx(mask.sum() * zx * zy * zz)
        faces = [np.count_nonzero(np.diff(np.pad(mask, 1), axis=d)) for d in range(3)]
        assert row["surface_area"] == pytest.approx(faces[0] * zy * zz + faces[1] * zx * zz + faces[2] * zx * zy)
        assert row["bbox-0"] == pytest.approx(10 - zx / 2 + zx * unit["bbox-0"][r])
        assert row["centroid-2"] == pytest.approx(30 - zz / 2 + zz * unit["centroid-2"][r])


def test_surface_labels_glb_one_closed_manifold_per_label(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    out = tmp_path / "s.glb"
    said = run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", out, "--connectivity", "26")
    assert "6 labels" in said and "read back" in said
    table = label_table(segmentation, 26)
    scene = trimesh.load(out, force="scene", process=False)
    assert sorted(scene.graph.nodes_geometry) == sorted(f"label_{v}" for v in table["label"])
    data = out.read_bytes()
    nodes = json.loads(data[20:20 + int.from_bytes(data[12:16], "little")])["nodes"]
    assert [n["name"] for n in nodes] == [f"label_{v}" for v in table["label"]]  # the labels' order, not the batches'
    for r, label in enumerate(table["label"]):
        _, geometry = scene.graph[f"label_{label}"]
        mesh = scene.geometry[geometry]
        assert mesh.is_watertight and mesh.is_winding_consistent
        # the mesh is split at the pinches and around doubled edges, where
        # its triangles keep their own copies; V - E + F is the table's
        assert mesh.euler_number == table["surface_euler"][r]
        assert abs(mesh.volume) == pytest.approx(table["volume"][r])


def test_surface_labels_glb_names_the_node_that_reads_wrong(tmp_path, capsys, monkeypatch, segmentation):
    """A scene whose label 9 lost a triangle on its way into the file: the
    read-back (against the table's figures) names that node, open, and
    the command exits 1; the other labels read as the table says."""
    from isoflow.mesh import export

    batch_parts = export.batch_glb_parts

    def losing_a_triangle(batch, names, *rest):
        parts = batch_parts(batch, names, *rest)
        if "label_9" in parts.names:
            s = parts.names.index("label_9")
            parts.triangles = np.delete(parts.triangles, parts.tfirst[s], axis=0)
            parts.tfirst[s + 1:] -= 1
        return parts

    monkeypatch.setattr(export, "batch_glb_parts", losing_a_triangle)
    np.save(tmp_path / "seg.npy", segmentation)
    assert main(["surface", str(tmp_path / "seg.npy"), "--labels", "-o", str(tmp_path / "s.glb")]) == 1
    err = capsys.readouterr().err
    assert "node label_9: trimesh reads watertight False" in err and err.count("trimesh reads") == 1
    scene = trimesh.load(tmp_path / "s.glb", force="scene", process=False)
    assert not scene.geometry[scene.graph["label_9"][1]].is_watertight


def test_surface_labels_of_a_zarr_store_in_its_units(tmp_path, capsys, segmentation):
    """A store's surfaces are meshed from the image read whole (info reads
    it block by block): each node closed, with the volume and V - E + F of
    the store's own table, in the OME-Zarr scale's units."""
    pytest.importorskip("zarr")
    from test_formats_cli import ome_group

    ome_group(tmp_path / "seg.zarr", [{"type": "scale", "scale": [2.0, 0.5, 1.0]}], data=segmentation)
    rows = json.loads(run(capsys, "info", tmp_path / "seg.zarr", "--labels", "--json"))["labels"]
    said = run(capsys, "surface", tmp_path / "seg.zarr", "--labels", "-o", tmp_path / "s.glb")
    assert "6 labels" in said and "read back" in said
    scene = trimesh.load(tmp_path / "s.glb", force="scene", process=False)
    for row in rows:
        mask = segmentation == row["label"]
        assert row["volume"] == pytest.approx(mask.sum() * 2.0 * 0.5 * 1.0)
        mesh = scene.geometry[scene.graph[f"label_{row['label']}"][1]]
        assert mesh.is_watertight and mesh.euler_number == row["surface_euler"]
        assert abs(mesh.volume) == pytest.approx(row["volume"])


def test_a_complex_store_s_fill_value_is_no_label(tmp_path, capsys):
    """``info STORE --labels`` of a complex store whose fill value is 2+3j
    warned that its chunks never written "count as label 2" (float() of
    the fill value, with NumPy's ComplexWarning and its source line on
    stderr) before refusing the store: a complex value is no label."""
    zarr = pytest.importorskip("zarr")
    path = tmp_path / "c.zarr"
    zarr.create_array(str(path), shape=(4, 4, 4), chunks=(2, 2, 2), dtype="c16", fill_value=2 + 3j)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        code, _, err = said(capsys, "info", path, "--labels")
    err = [line for line in err if not line.startswith("isoflow info: note: ")]
    assert code == 2 and err == [f"isoflow info: error: {path}: a label image holds integers, not complex128"], err
    assert not [w for w in seen if issubclass(w.category, np.exceptions.ComplexWarning) or "label 2" in str(w.message)]


def test_a_store_read_as_nan_where_never_written_is_refused_with_what_would_read_it(tmp_path, capsys):
    """A float store whose fill value is NaN reads its chunks never written
    as NaN: ``info`` refused it and offered --labels, which refuses NaN as
    no label. The line names the fill value and the ways that read it (a
    threshold, a store written with fill_value=0), not --labels; an
    integer label store is still offered --labels, which reads it."""
    zarr = pytest.importorskip("zarr")

    def info(path, *extra):
        code, out, err = said(capsys, "info", path, *extra)
        # (where numba's cache is cold a process may say so first, in a note line)
        return code, [line for line in err if not line.startswith("isoflow info: note: ")], out

    mask = np.zeros((8, 8, 8), np.float32)
    mask[1:3, 1:3, 1:3] = 1
    z = zarr.create_array(str(tmp_path / "nan.zarr"), shape=(8, 8, 8), chunks=(4, 8, 8), dtype="float32",
                          fill_value=float("nan"))
    z[:4] = mask[:4]  # the second chunk never written
    assert z.nchunks_initialized == 1
    nan = int(np.isnan(z[...]).sum())
    assert nan == 4 * 8 * 8
    code, err, _ = info(tmp_path / "nan.zarr")
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"isoflow info: error: {tmp_path / 'nan.zarr'}: not a binary volume ({nan} voxels "), err
    assert "e.g. nan, the array's fill value, which zarr reads for a chunk never written" in err[0], err
    assert "fill_value=0" in err[0] and "--labels" not in err[0], err
    # --labels refuses NaN as no label: why the line must not offer it
    assert info(tmp_path / "nan.zarr", "--labels")[0] == 2
    # the way out it names: the same voxels in a store whose fill value is 0
    zero = zarr.create_array(str(tmp_path / "zero.zarr"), shape=(8, 8, 8), chunks=(4, 8, 8), dtype="float32",
                             fill_value=0)
    zero[:4] = mask[:4]
    code, err, out = info(tmp_path / "zero.zarr", "--json")
    assert code == 0 and json.loads(out)["voxels"] == int(np.count_nonzero(zero[...] == 1)) == 8, err

    labels = zarr.create_array(str(tmp_path / "labels.zarr"), shape=(8, 8, 8), chunks=(4, 8, 8), dtype="u1",
                               fill_value=0)
    labels[:4] = mask[:4] * 2
    labels[0, 0, 0] = 3  # two labels: a store of 0 and 2 alone is the mask of 2, as in memory
    code, err, _ = info(tmp_path / "labels.zarr")
    assert code == 2 and len(err) == 1 and err[0].endswith("or give every label its row with --labels "
                                                           "(isoflow.label_table(isoflow.read_labels(path)))"), err
    assert "fill_value=0" not in err[0], err
    assert info(tmp_path / "labels.zarr", "--labels")[0] == 0


@pytest.mark.parametrize("fill", [float("nan"), 2.5])
def test_labels_of_a_float_store_name_a_fill_value_that_is_no_label(tmp_path, capsys, fill):
    """``info --labels`` (block by block, 3D; whole, 2D) and ``surface
    --labels`` refuse a float store whose chunks never written read as a
    fill value that is no label: the line says the refused value is the
    fill value zarr reads for those chunks, and names the store that
    reads them as 0. That store gives the rows of the voxels written."""
    zarr = pytest.importorskip("zarr")

    def refused(*args):
        code, _, err = said(capsys, *args)
        return code, [line for line in err if not line.startswith("isoflow info: note: ")]

    for shape, chunks in [((8, 6, 6), (4, 6, 6)), ((8, 6, 6), (8, 6, 1)), ((8, 6), (4, 6))]:
        path = tmp_path / f"s{len(shape)}{chunks[-1]}.zarr"
        z = zarr.create_array(str(path), shape=shape, chunks=chunks, dtype="float32", fill_value=fill)
        written = tuple(slice(0, c) for c in chunks)  # the first chunk alone
        z[written] = 3
        assert z.nchunks_initialized == 1 and z.nchunks > 1
        first = np.argwhere(~(z[...] == 3))[0]  # the first voxel zarr reads as the fill value
        commands = [("info", path, "--labels")] + ([("surface", path, "--labels", "-o", tmp_path / "s.glb")]
                                                   if len(shape) == 3 else [])
        for command in commands:
            code, err = refused(*command)
            assert code == 2 and len(err) == 1, err
            voxel = ", ".join(map(str, first))
            cell = "pixel" if len(shape) == 2 else "voxel"
            assert f"{cell} ({voxel}) holds {fill!r}, the array's fill value, which zarr reads for a chunk never " \
                   "written" in err[0], err
            assert err[0].endswith("write the store with fill_value=0, which a chunk never written then reads as 0")
        zero = zarr.create_array(str(tmp_path / "zero.zarr"), shape=shape, chunks=chunks, dtype="float32",
                                 fill_value=0, overwrite=True)
        zero[written] = 3
        code, out, err = said(capsys, "info", tmp_path / "zero.zarr", "--labels", "--json")
        assert code == 0, err
        assert {r["label"]: r["voxels"] for r in json.loads(out)["labels"]} == {3: int(np.prod(chunks))}


def test_a_volume_holding_a_value_that_is_no_label_is_not_offered_labels(tmp_path, capsys):
    """Where the first value named is a label (2) but the volume also holds
    one that is not (a fraction), the refusal offered --labels, which
    refuses that other value."""

    def info(path, *extra):
        code, _, err = said(capsys, "info", path, *extra)
        return code, [line for line in err if not line.startswith("isoflow info: note: ")]

    volume = np.zeros((8, 8, 8))
    volume[1:3, 1:3, 1:3] = 2
    volume[5, 5, 5] = 2.5
    np.save(tmp_path / "frac.npy", volume)
    code, err = info(tmp_path / "frac.npy")
    assert code == 2 and len(err) == 1 and "not a binary volume" in err[0] and "e.g. 2.0" in err[0], err
    assert "--labels" not in err[0], err
    assert info(tmp_path / "frac.npy", "--labels")[0] == 2  # what it offered is refused
    # a label image of whole numbers in a float file is still offered --labels, which reads it
    volume[5, 5, 5] = 3  # (three values: one nonzero value alone is read as a mask)
    np.save(tmp_path / "whole.npy", volume)
    code, err = info(tmp_path / "whole.npy")
    assert code == 2 and "--labels" in err[0], err
    assert info(tmp_path / "whole.npy", "--labels")[0] == 0


def test_a_float_store_refused_block_by_block_does_not_promise_labels(tmp_path, capsys):
    """A float store is refused at its first block of values other than 0
    and 1; where that block held whole values, the line offered --labels,
    which then refused the NaN or the fraction of a later block, or the
    NaN fill value of a chunk never written. Without reading every block
    it cannot tell: --labels is offered on the condition that every voxel
    holds a whole number, and not at all where the fill value is NaN and a
    chunk was never written."""
    zarr = pytest.importorskip("zarr")
    offer = "or give every label its row with --labels"
    maybe = "or, if every voxel holds a whole number, give every label its row with --labels"

    def isoflow(*args):
        code, _, err = said(capsys, *args, "-q")
        return code, err

    def store(name, values, fill=0.0, written=None):
        z = zarr.create_array(str(tmp_path / name), shape=values.shape, chunks=(4, 8, 8), dtype="float32",
                              fill_value=fill)
        z[: written or len(values)] = values[: written or len(values)]
        return z[...]  # as zarr reads it

    volume = np.zeros((12, 8, 8), np.float32)
    volume[1:3, 1:3, 1:3] = 1  # the first block is binary
    volume[5:7, 5:7, 5:7] = 2  # the second holds a label
    for name, value in (("fraction.zarr", 2.5), ("nan.zarr", np.nan)):
        volume[9, 5, 5] = value  # the third a value that is no label
        read = store(name, volume)
        assert not np.all(read == np.round(read))  # (NaN and 2.5 are no whole numbers)
        code, err = isoflow("info", tmp_path / name)
        assert code == 2 and len(err) == 1 and "e.g. 2.0)" in err[0], err
        assert maybe in err[0] and offer not in err[0], err
        assert isoflow("info", tmp_path / name, "--labels")[0] == 2  # what it would have promised is refused
        code, err = isoflow("surface", tmp_path / name, "-o", tmp_path / "s.ply")
        assert code == 2 and "or, if every voxel holds a whole number, write a closed surface per label" in err[0], err
    # the condition holds: --labels reads it
    volume[9, 5, 5] = 3
    read = store("whole.zarr", volume)
    assert np.all(read == np.round(read))
    code, err = isoflow("info", tmp_path / "whole.zarr")
    assert code == 2 and maybe in err[0], err
    assert isoflow("info", tmp_path / "whole.zarr", "--labels")[0] == 0
    # a NaN fill value: the chunk never written reads as NaN, which --labels refuses
    read = store("nanfill.zarr", volume, fill=float("nan"), written=8)
    assert np.isnan(read[8:]).all() and not np.isnan(read[:8]).any()
    code, err = isoflow("info", tmp_path / "nanfill.zarr")
    assert code == 2 and "--labels" not in err[0], err
    assert "the array's fill value, nan, which is no label" in err[0], err
    assert isoflow("info", tmp_path / "nanfill.zarr", "--labels")[0] == 2


def test_info_labels_of_a_store_notes_chunks_read_as_a_nonzero_fill_value(tmp_path, capsys):
    """zarr reads a chunk never written as the fill value: where that is a
    label, the table counts those voxels as it, and says so once, with
    the count of the chunks (inside a written shard too);
    nothing is said where every chunk is written or the fill value is 0."""
    zarr = pytest.importorskip("zarr")

    def info(path):
        code, out, err = said(capsys, "info", path, "--labels", "--json")
        assert code == 0, err
        notes = [line for line in err if "never written" in line]
        return {r["label"]: r["voxels"] for r in json.loads(out)["labels"]}, notes

    def store(name, fill, shards=None):
        z = zarr.create_array(str(tmp_path / name), shape=(8, 4, 4), chunks=(2, 4, 4), shards=shards,
                              dtype="u1", fill_value=fill)
        z[:2] = 1  # the first chunk; the others never written
        return z

    z = store("fill2.zarr", 2)
    missing = z.nchunks - z.nchunks_initialized
    assert missing == 3
    rows, notes = info(tmp_path / "fill2.zarr")
    assert rows == {1: 32, 2: int(np.count_nonzero(z[...] == 2))} == {1: 32, 2: 96}
    assert notes == [f"isoflow info: warning: {tmp_path / 'fill2.zarr'}: 3 of 4 chunks were never written; zarr "
                     "reads their voxels as the fill value 2, so they count as label 2"]

    z = store("sharded.zarr", 2, shards=(4, 4, 4))
    # the written shard holds its first chunk alone: three chunks read as the fill value
    assert int(np.count_nonzero(z[...] == 2)) // (2 * 4 * 4) == 3
    assert info(tmp_path / "sharded.zarr")[1] == [f"isoflow info: warning: {tmp_path / 'sharded.zarr'}: 3 of 4 "
                                                  "chunks were never written; zarr reads their voxels as the fill "
                                                  "value 2, so they count as label 2"]

    z = store("whole.zarr", 2)
    z[2:] = 3
    assert z.nchunks_initialized == z.nchunks
    assert info(tmp_path / "whole.zarr") == ({1: 32, 3: 96}, [])

    store("fill0.zarr", 0)
    assert info(tmp_path / "fill0.zarr") == ({1: 32}, [])


def test_surface_labels_glb_opens_in_pymeshlab(tmp_path, capsys, segmentation):
    pymeshlab = pytest.importorskip("pymeshlab")
    np.save(tmp_path / "seg.npy", segmentation)
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", tmp_path / "s.glb")
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", f"{tmp_path}/each/", "--suffix", ".ply")
    table = label_table(segmentation)
    for r, label in enumerate(table["label"]):
        ms = pymeshlab.MeshSet()
        ms.load_new_mesh(str(tmp_path / "each" / f"label_{label}.ply"))
        m = ms.current_mesh()
        measures = ms.get_topological_measures()
        assert measures["boundary_edges"] == 0 and measures["non_two_manifold_edges"] == 0
        assert m.vertex_number() - measures["edges_number"] + m.face_number() == table["surface_euler"][r]
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(str(tmp_path / "s.glb"))  # a layer per node
    assert ms.mesh_number() == len(table["label"])
    for layer in range(ms.mesh_number()):
        ms.set_current_mesh(layer)
        measures = ms.get_topological_measures()
        assert measures["boundary_edges"] == 0 and measures["non_two_manifold_edges"] == 0


def test_surface_labels_without_the_check_writes_the_same_file(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    said = run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", tmp_path / "a.glb", "--no-check")
    assert "6 labels" in said and "read back" not in said
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", tmp_path / "b.glb")
    assert (tmp_path / "a.glb").read_bytes() == (tmp_path / "b.glb").read_bytes()


@pytest.mark.parametrize("out, extra, phases", [("s.glb", (), 2), ("s.glb", ("--no-check",), 1),
                                                ("each/", ("--suffix", ".ply", "--no-check"), 2)])
def test_surface_labels_reports_one_growing_count(tmp_path, capsys, monkeypatch, segmentation, out, extra, phases):
    """Long work shows progress: every label meshed, then every label read
    back (or written, a file each), as one count that only grows (after
    the label table's own bar, which reaches its end)."""
    import contextlib

    from isoflow.cli import progress

    bars: dict[str, list] = {}

    @contextlib.contextmanager
    def bar(args, label, unit="it", estimate=False):
        yield lambda done, total: bars.setdefault(label, []).append((done, total))

    monkeypatch.setattr(progress, "progress_bar", bar)
    np.save(tmp_path / "seg.npy", segmentation)
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", f"{tmp_path}/{out}", *extra)
    assert list(bars) == ["label table", "label surfaces"]
    assert bars["label table"][-1][0] == bars["label table"][-1][1]
    seen = bars["label surfaces"]
    done = [d for d, _ in seen]
    assert done == sorted(done) and seen[-1] == (6 * phases, 6 * phases)
    assert {t for _, t in seen} == {6 * phases}


@pytest.mark.parametrize("out, extra", [("each/", ("--suffix", ".ply")), ("s.glb", ())])
def test_surface_labels_time_note_is_paced_after_the_set_up(tmp_path, capsys, monkeypatch, out, extra):
    """Piped, the note on how long ``surface --labels`` will take is paced
    by the labels written (or read back), not by the set-up of the first:
    a first label that costs 5 s more than the others (a writer's imports,
    a compiled pass's loading; added to the notes' clock here) made a run
    of a few seconds say it would take minutes (40 labels of an aseg: "about
    1 min 25 s", the run took 3 s). The note speaks of runs of 30 s or more,
    so a run that took less on that clock, measured here, says none."""
    import time
    import types

    from isoflow.cli import progress
    from isoflow.mesh import export, readback

    lag = {"s": 0.0}
    clock = types.SimpleNamespace(monotonic=lambda: time.monotonic() + lag["s"])
    monkeypatch.setattr(progress, "time", clock)

    def slow_first(real):
        def call(*args, **kwargs):
            lag["s"] = lag["s"] or 5.0  # the first label's set-up
            return real(*args, **kwargs)
        return call

    monkeypatch.setattr(export, "write_mesh_file", slow_first(export.write_mesh_file))
    monkeypatch.setattr(readback, "scene_nodes", slow_first(readback.scene_nodes))
    monkeypatch.setattr(readback, "UNION_TRIANGLES", 1)  # the read-back tells of every node
    image = np.zeros((61, 4, 4), np.uint8)
    for label in range(1, 21):  # 20 cubes, each touching the next by a face
        image[3 * label - 2: 3 * label + 1, 1:3, 1:3] = label
    np.save(tmp_path / "cubes.npy", image)
    start = clock.monotonic()
    assert main(["surface", str(tmp_path / "cubes.npy"), "--labels", "-o", f"{tmp_path}/{out}", *extra]) == 0
    took = clock.monotonic() - start
    err = capsys.readouterr().err
    assert lag["s"] == 5.0 and took < progress.NOTE_LONG
    assert "will take about" not in err, (took, err)


@pytest.mark.parametrize("choice", [["--labels", ""], ["--labels="], ["--labels", " , "]])
def test_an_empty_choice_of_labels_says_so(tmp_path, capsys, segmentation, choice):
    """``--labels "$LABELS"`` of a variable that came out empty was refused
    as "--labels : '' is not a label or a range A-B of labels"; the line
    now says the choice is empty and how to ask for every label."""
    np.save(tmp_path / "seg.npy", segmentation)
    for command in (["info"], ["surface", "-o", tmp_path / "s.glb"]):
        fails(capsys, command[0], tmp_path / "seg.npy", *choice, *command[1:],
              words=("--labels '", "an empty choice", "--labels alone for every nonzero label"))
    assert not (tmp_path / "s.glb").exists()


def test_surface_labels_dir_lists_its_directory_once(tmp_path, capsys, monkeypatch, segmentation):
    """Each file's temporary first sweeps what killed writers left beside
    it, which listed the directory once per label file: a directory of
    10,000 label files read 10^8 names, and the run slowed as it filled.
    Written as one set, the directory is listed once for the sweeps (and
    once for the earlier run's files), whatever the labels; a temporary a
    killed writer left is still removed."""
    import os

    out = tmp_path / "out"
    out.mkdir()
    killed = subprocess.run([sys.executable, "-c", "import sys; from pathlib import Path; from isoflow.mesh.outputs "
                             "import temp_sibling; print(temp_sibling(Path(sys.argv[1])))", str(out / "label_3.ply")],
                            capture_output=True, text=True, check=True).stdout.strip()
    assert Path(killed).exists()  # its process has ended: the temporary is abandoned
    listed = []

    def counted(real):
        def call(path=".", *args):
            if isinstance(path, (str, os.PathLike)) and Path(path) == out:
                listed.append(real.__name__)
            return real(path, *args)
        return call

    monkeypatch.setattr(os, "scandir", counted(os.scandir))
    monkeypatch.setattr(os, "listdir", counted(os.listdir))
    np.save(tmp_path / "seg.npy", segmentation)
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", f"{out}/", "--suffix", ".ply")
    assert len(listed) <= 2, listed
    assert len(list(out.glob("label_*.ply"))) == 6
    assert not Path(killed).exists()


def test_surface_labels_dir_writes_a_file_per_label(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "4,9", "-o", f"{tmp_path}/out/", "--suffix", "obj")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["label_4.obj", "label_9.obj"]
    fails(capsys, "surface", tmp_path / "seg.npy", "--labels", "4", "-o", f"{tmp_path}/out/", "--suffix", "obj",
          words=("label_4.obj", "exists"))


@pytest.mark.parametrize("extra, words", [
    (("--labels", "3-x"), ("--labels 3-x", "'3-x'")),
    (("--labels", "5-2"), ("backwards",)),
    (("--labels", "--label", "3"), ("--label", "--labels")),
    (("--labels", "77"), ("none of the labels", "77")),
    (("--labels=-3",), ("seg.npy", "none of the labels asked for occur (-3)", "uint16 (0 to 65535)")),
    (("--csv", "t.csv"), ("--csv", "--labels")),
])
def test_bad_label_options_are_one_line(tmp_path, capsys, segmentation, extra, words):
    np.save(tmp_path / "seg.npy", segmentation)
    fails(capsys, "info", tmp_path / "seg.npy", *extra, words=words)


@pytest.mark.parametrize("command", ["info", "surface"])
@pytest.mark.parametrize("spec", ["-3--1", "-2,3"])
def test_a_negative_choice_without_its_equals_sign_is_one_line_naming_the_form_that_works(tmp_path, capsys, command,
                                                                                           spec):
    # argparse read it as an unknown option: the usage and "unrecognized
    # arguments", where docs/labels.md gives the form --labels=-5,-3--1
    image = np.zeros((4, 4, 4), np.int8)
    image[0, 0, 0], image[2, 2, 2], image[3, 3, 3] = -2, 3, 5
    np.save(tmp_path / "neg.npy", image)
    out = ["-o", str(tmp_path / "n.glb")] if command == "surface" else ["--json"]
    with pytest.raises(SystemExit) as done:
        main([command, str(tmp_path / "neg.npy"), "--labels", spec, *out])
    err = capsys.readouterr().err
    assert done.value.code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"isoflow {command}: error: --labels {spec}: ") and f"--labels={spec} " in err, err
    assert main([command, str(tmp_path / "neg.npy"), f"--labels={spec}", *out]) == 0
    if command == "info":
        rows = json.loads(capsys.readouterr().out)["labels"]
        assert [row["label"] for row in rows] == {"-3--1": [-2], "-2,3": [-2, 3]}[spec]


def test_surface_labels_needs_glb_or_a_directory(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    fails(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", tmp_path / "s.ply",
          words=(f"-o {tmp_path / 's'}.glb", f"-o {tmp_path / 's'}/ --suffix .ply"))
    fails(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", f"{tmp_path}/d/", words=("--suffix",))
    # --suffix with a new directory's name without its slash: the line says the slash makes it
    fails(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", tmp_path / "new", "--suffix", "ply",
          words=("no such directory", f"-o {tmp_path / 'new'}/ makes it"))
    assert not (tmp_path / "new").exists()


def test_a_label_image_given_for_a_mask_names_labels(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    fails(capsys, "info", tmp_path / "seg.npy", words=("threshold it first", "--label N", "--labels"))


def test_a_4d_label_image_given_for_a_mask_offers_label_n_not_labels(tmp_path, capsys):
    # a label table is 2D or 3D: --labels would be refused in turn
    image = np.zeros((3, 3, 3, 3), np.uint8)
    image[0], image[2] = 1, 2
    np.save(tmp_path / "seg4.npy", image)
    said = fails(capsys, "info", tmp_path / "seg4.npy", words=("threshold it first", "--label N"))
    assert "--labels" not in said
    assert main(["info", str(tmp_path / "seg4.npy"), "--label", "2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["euler_characteristic"] == 1  # one 3x3x3x1 box


def assert_text_as_json_and_csv_write(table: dict) -> None:
    """json_rows (as text and as ASCII bytes) and csv_rows of ``table``
    equal the standard library's writers on the same cells (NaN as null /
    empty; an infinity as null in JSON, which has none, and as csv writes
    it, ``inf``, which float() and pandas read back; an object column's
    tuples as lists / ``0;1``)."""
    import io

    from isoflow.cli import table_text

    def cells(gone) -> list:
        return [[list(v) if isinstance(v, tuple) else None if isinstance(v, float) and gone(v) else v
                 for v in column.tolist()] for column in table.values()]

    want = json.dumps([dict(zip(table, row)) for row in zip(*cells(lambda v: not np.isfinite(v)))])
    assert "".join(table_text.json_rows(table)) == want
    # as bytes for standard output: the same text in ASCII (json escapes every other character)
    assert b"".join(table_text.json_rows(table, binary=True)) == want.encode("ascii")
    fh = io.StringIO()
    writer = csv.writer(fh)
    writer.writerow(list(table))
    writer.writerows(zip(*[[";".join(map(str, v)) if isinstance(v, list) else v for v in column]
                           for column in cells(np.isnan)]))
    assert "".join(table_text.csv_rows(table)) == fh.getvalue()


#: table_text.PLAIN_ROWS and PLAIN_ROWS_COLD for each way of writing a
#: table: every table in Python's text, every table in compiled digits
WRITERS = {"plain": (10**9, 10**9), "compiled": (-1, -1)}


@pytest.mark.parametrize("threads", [1, 3])
@pytest.mark.parametrize("writer", WRITERS)
@pytest.mark.parametrize("rows", [0, 1, 5, 23])
def test_table_text_is_what_the_json_and_csv_modules_write(monkeypatch, rng, rows, writer, threads):
    """Random cells, across blocks of rows (23 rows: six blocks, on three
    threads the compiled ones made three at a time, each thread's buffers
    used again for a block of fewer rows)."""
    from isoflow.cli import table_text
    from isoflow.scale.compiled import using

    monkeypatch.setattr(table_text, "BLOCK_ROWS", 4)
    monkeypatch.setattr(table_text, "PLAIN_ROWS", WRITERS[writer][0])
    monkeypatch.setattr(table_text, "PLAIN_ROWS_COLD", WRITERS[writer][1])
    floats = rng.uniform(-1e3, 1e3, rows) * 10.0 ** rng.integers(-9, 18, rows)
    floats[::3] = np.round(floats[::3])
    floats[1::5] = np.nan
    floats[2::7] = -np.inf
    genera = np.empty(rows, object)
    genera[:] = [tuple(rng.integers(0, 4, rng.integers(0, 4)).tolist()) for _ in range(rows)]
    with using(threads):
        assert_text_as_json_and_csv_write(
            {"label": np.arange(rows, dtype=np.uint64) + np.uint64(2**63), "voxels": rng.integers(-9, 10**12, rows),
             "x": floats, "ok": rng.integers(0, 2, rows).astype(bool), "genera": genera})


def test_table_text_blocks_are_made_on_two_threads_at_once(monkeypatch, rng):
    """A large table's blocks of rows are made two at a time on two
    threads (each of the first two waits for the other: one thread alone
    would wait in vain), and the text is still what json and csv write."""
    import threading

    from isoflow.cli import table_text
    from isoflow.scale.compiled import using

    monkeypatch.setattr(table_text, "BLOCK_ROWS", 8)
    monkeypatch.setattr(table_text, "PLAIN_ROWS", -1)
    monkeypatch.setattr(table_text, "PLAIN_ROWS_COLD", -1)
    made, meet = table_text._rows, threading.Barrier(2, timeout=20)

    def met(table, lo, *rest):
        if lo < 16:  # the first two blocks, of every text
            meet.wait()
        return made(table, lo, *rest)

    monkeypatch.setattr(table_text, "_rows", met)
    rows = 50
    genera = np.empty(rows, object)
    genera[:] = [tuple(rng.integers(0, 3, rng.integers(0, 3)).tolist()) for _ in range(rows)]
    with using(2):
        assert_text_as_json_and_csv_write({"label": np.arange(1, rows + 1, dtype=np.uint32),
                                           "centroid": rng.normal(0, 100, rows), "genera": genera})


@pytest.mark.parametrize("writer", WRITERS)
def test_table_text_of_the_values_at_the_edges_of_each_type(monkeypatch, writer):
    """The integers at the ends of every width (the most negative int64
    has no positive twin), and the floats where ``repr`` changes how it
    writes a whole number (an exponent from 1e16 on), a signed zero, the
    smallest subnormal (left to ``repr``): the compiled digits write what
    json and csv write."""
    from isoflow.cli import table_text

    monkeypatch.setattr(table_text, "BLOCK_ROWS", 5)
    monkeypatch.setattr(table_text, "PLAIN_ROWS", WRITERS[writer][0])
    monkeypatch.setattr(table_text, "PLAIN_ROWS_COLD", WRITERS[writer][1])
    floats = np.array([-0.0, 0.0, 9999999999999998.0, 1e16, -1e16, 2.0**53, 123456789012345.0, -7.0, 0.1,
                       5e-324, 1e300, -np.inf, np.nan, 1.5, 1e22, 100.0])
    rows = len(floats)
    with np.errstate(over="ignore"):  # 1e300 as float32: inf
        table = {"float": floats, "float32": floats.astype(np.float32)}
    for kind in ("int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"):
        info = np.iinfo(kind)
        table[kind] = np.resize(np.array([info.min, info.max, 0, 1, 9, 10, 99, 100, info.max // 10],
                                         kind), rows)
    table["int64"][:4] = [-(2**63), -(2**63) + 1, -10, -9]
    genera = np.empty(rows, object)
    genera[:] = [(), (0,), (0,), (1, 12)] * (rows // 4)
    table["genera"] = genera
    table["ok"] = np.arange(rows) % 3 == 0
    assert_text_as_json_and_csv_write(table)


def test_a_label_table_beyond_the_budget_is_refused_in_one_line(tmp_path, capsys, monkeypatch, rng):
    """Up front where the image's own first buffers would not fit (1 byte a
    voxel); later, still in one line and before it is made, where only the
    many pieces of an image of noise would not. A grain map of few labels
    is not refused for what many labels need (a budget of 2.4 bytes a
    voxel: 4 up front refused it)."""
    from isoflow.scale import memory

    grains = np.repeat(np.arange(1, 5, dtype=np.uint8), 64)[:, None, None] * np.ones((1, 256, 256), np.uint8)
    np.save(tmp_path / "grains.npy", grains)
    monkeypatch.setattr(memory, "default_budget", lambda: 12_000_000)  # below 1 byte a voxel (16.8 MB)
    fails(capsys, "info", tmp_path / "grains.npy", "--labels", words=("256x256x256", "label table", "budget"))
    monkeypatch.setattr(memory, "default_budget", lambda: 40_000_000)
    assert [r["voxels"] for r in json.loads(run(capsys, "info", tmp_path / "grains.npy", "--labels", "--json"))
            ["labels"]] == [64 * 256 * 256] * 4
    # (noise of a few hundred labels is made label by label in that budget: a mask at a time)
    noise = rng.integers(1, 2000, (256, 256, 256)).astype(np.uint16)
    np.save(tmp_path / "noise.npy", noise)
    fails(capsys, "info", tmp_path / "noise.npy", "--labels", words=("label image", "needs about", "budget"))


@pytest.mark.parametrize("shape", [(64, 64, 64), (120, 100)])
def test_a_label_table_beyond_the_budget_names_the_file(tmp_path, capsys, monkeypatch, rng, shape):
    """The one line that refuses a label table beyond the memory budget
    names the file it was asked of, as every other refusal of bad input
    does (a store's did; a file's began "the label table of a 64x64x64
    label image" and left a batch's log to guess which of its images)."""
    from isoflow.scale import memory

    np.save(tmp_path / "cells.npy", rng.integers(0, 3000, shape).astype(np.uint16))
    monkeypatch.setattr(memory, "default_budget", lambda: 100_000)  # below a byte a pixel or voxel
    for command in ["info"] + ["surface"] * (len(shape) == 3):  # surface --labels takes 3D images only
        out = ["-o", tmp_path / "cells.glb"] if command == "surface" else []
        line = fails(capsys, command, tmp_path / "cells.npy", "--labels", *out, words=("budget",))
        assert line.startswith(f"isoflow {command}: error: {tmp_path / 'cells.npy'}: "), line
    assert not (tmp_path / "cells.glb").exists()


def test_surfaces_beyond_the_budget_are_refused_up_front_saying_what_fits(tmp_path, capsys, monkeypatch, rng):
    """``surface --labels`` holds every label's mesh until the set is
    written, so it needs at least the bytes of the scene's triangle indices
    (12 a triangle, as trimesh reads them back from the file). Under a
    budget below that it is refused in one line before any mesh, naming the
    file and the ``--labels`` choice that fits, which then runs."""
    from scipy import ndimage

    from isoflow.scale import memory

    cells = ndimage.zoom(rng.integers(1, 400, (8, 8, 8)), 3, order=0).astype(np.uint16)  # 3x3x3 cells, touching
    np.save(tmp_path / "cells.npy", cells)
    run(capsys, "surface", tmp_path / "cells.npy", "--labels", "-o", tmp_path / "free.glb")
    triangles = sum(len(g.faces) for g in trimesh.load(tmp_path / "free.glb").geometry.values())
    monkeypatch.setattr(memory, "default_budget", lambda: 12 * triangles)
    line = fails(capsys, "surface", tmp_path / "cells.npy", "--labels", "-o", tmp_path / "tight.glb",
                 words=(str(tmp_path / "cells.npy"), "budget", "fit: --labels="))
    assert not (tmp_path / "tight.glb").exists()
    choice = line.split("fit: ")[-1]
    run(capsys, "surface", tmp_path / "cells.npy", choice, "-o", tmp_path / "tight.glb")
    fewer = sum(len(g.faces) for g in trimesh.load(tmp_path / "tight.glb").geometry.values())
    assert 0 < fewer < triangles


@pytest.mark.parametrize("suffix", [".png", ".tif"])
def test_an_image_beyond_the_budget_is_sized_x_first_as_info_says(tmp_path, capsys, monkeypatch, rng, suffix):
    """The refusal of a PNG or TIFF too large to read gives its size in the
    order every other line gives it, x first (Pillow's ``width, height``,
    tifffile's shape reversed): a 300 wide, 200 tall cell mask was "a
    200x300 volume" where ``info`` says "shape 300x200"; and it is an
    image, whose table a .zarr store would not spare the memory of (2D
    tables read a store whole): the line asks to crop it."""
    import tifffile
    from PIL import Image

    from isoflow.scale import memory

    cells = rng.integers(0, 50, (200, 300)).astype(np.uint16)  # rows, columns: as Pillow and tifffile store it
    path = tmp_path / f"cells{suffix}"
    if suffix == ".png":
        Image.fromarray(cells).save(path)
    else:
        tifffile.imwrite(path, cells)
    wide = Image.open(path).size if suffix == ".png" else tifffile.imread(path).shape[::-1]
    assert "shape 300x200," in run(capsys, "info", path, "--labels").splitlines()[0]
    monkeypatch.setattr(memory, "default_budget", lambda: 1_000)
    line = fails(capsys, "info", path, "--labels", words=(f"{path}: a {wide[0]}x{wide[1]} image ", "budget", "crop it"))
    assert "block by block" not in line  # a 2D table reads a .zarr store whole too


@pytest.mark.parametrize("pitch", [1e150, 1e200, 1e-200])
def test_surfaces_fit_check_of_extreme_voxels_prints_no_numpy_warning(tmp_path, capfd, pitch):
    """The memory check before the surfaces counts faces from the table's
    areas, which pass float64's range at such voxel sizes (the area of a
    face of 1e200 is 1e400): it counts none there, without NumPy's
    overflow or invalid-value warnings on the terminal, and the surfaces
    are written."""
    from isoflow import write_labels

    image = np.zeros((6, 6, 6), np.uint8)
    image[1:3, 1:3, 1:3], image[3:5, 3:5, 3:5] = 1, 2
    write_labels(image, tmp_path / "seg.npz", pitch=(pitch,) * 3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # NumPy's, which the command line would print
        code = main(["surface", str(tmp_path / "seg.npz"), "--labels", "-o", str(tmp_path / "s.glb")])
    err = capfd.readouterr().err
    assert code == 0 and "RuntimeWarning" not in err and "encountered" not in err, err
    assert (tmp_path / "s.glb").exists()


def test_info_labels_csv_dash_prints_the_table_alone(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    printed = run(capsys, "info", tmp_path / "seg.npy", "--labels", "--csv", "-")
    run(capsys, "info", tmp_path / "seg.npy", "--labels", "--csv", tmp_path / "t.csv")
    assert printed.encode() == (tmp_path / "t.csv").read_bytes() and not (tmp_path / "-").exists()
    assert [int(r["label"]) for r in csv.DictReader(printed.splitlines())] == [1, 2, 3, 4, 5, 9]
    fails(capsys, "info", tmp_path / "seg.npy", "--labels", "--csv", "-", "--json", words=("--csv -", "--json"))


def test_info_labels_csv_writes_a_volume_past_float64_as_inf_and_an_unknown_box_empty(tmp_path, capsys):
    """Voxels of 1e150: a volume of 8e450 is past float64 (inf; the
    terminal table prints the figure, 8e+450 (beyond float64)), an area
    of 24e300 is not. The CSV writes
    the infinity as csv writes it, ``inf``, which float() and pandas read
    back as inf, not empty, which they read as "unknown" (NaN); JSON has
    no infinity and writes null. A box past float64's reach stays empty."""
    from isoflow import write_labels

    image = np.zeros((4, 4, 4), np.uint8)
    image[1:3, 1:3, 1:3] = 5
    write_labels(image, tmp_path / "huge.npz", pitch=(1e150,) * 3)
    row, = csv.DictReader(run(capsys, "info", tmp_path / "huge.npz", "--labels", "--csv", "-").splitlines())
    assert 8 * 1e150 * 1e150 * 1e150 == math.inf and float(row["volume"]) == math.inf  # 8 voxels of 1e450 each
    assert float(row["surface_area"]) == 24 * 1e150 * 1e150
    assert json.loads(run(capsys, "info", tmp_path / "huge.npz", "--labels", "--json"))["labels"][0]["volume"] is None
    write_labels(image, tmp_path / "far.npz", origin=(1.7e308, 0, 0))  # corners a voxel apart are one float64
    row, = csv.DictReader(run(capsys, "info", tmp_path / "far.npz", "--labels", "--csv", "-").splitlines())
    assert row["bbox-0"] == "" and float(row["bbox-1"]) == 1.0 and float(row["volume"]) == 8.0


def test_info_labels_text_says_a_measure_past_float64_as_info_does(tmp_path, capsys):
    """Voxels of 1e200: 27 of them hold 2.7e601, past float64. The table
    printed ``inf`` in its volume and area columns, where ``info`` of the
    one object prints the figure, said to be beyond float64; the JSON
    stays valid for a strict parser (null), the CSV ``inf`` as csv writes it."""
    from isoflow import write_labels

    def refuse(name):  # Python's json takes Infinity and NaN, which no JSON holds: a strict reader refuses them
        raise ValueError(f"{name} is no JSON")

    image = np.zeros((5, 5, 5), np.uint8)
    image[1:4, 1:4, 1:4] = 3
    write_labels(image, tmp_path / "huge.npz", pitch=(1e200,) * 3)
    one = run(capsys, "info", tmp_path / "huge.npz", "--label", "3")
    table = run(capsys, "info", tmp_path / "huge.npz", "--labels")
    row = table.splitlines()[2].split()
    assert "inf" not in row and row[:2] == ["3", "27"]
    assert "volume                 2.7e+601 (beyond float64)" in one  # 27 * 1e600
    assert " ".join(row[2:8]) == "2.7e+601 (beyond float64) beyond float64's range"
    labels = json.loads(run(capsys, "info", tmp_path / "huge.npz", "--labels", "--json"), parse_constant=refuse)
    assert labels["labels"][0]["volume"] is None and labels["labels"][0]["surface_area"] is None
    row = next(csv.DictReader(run(capsys, "info", tmp_path / "huge.npz", "--labels", "--csv", "-").splitlines()))
    assert float(row["volume"]) == math.inf
    # a 2D image's area of 9 pixels of 1e200 x 1e200: 9e400; its perimeter of 12 pixel edges is in float64
    write_labels(image[2], tmp_path / "flat.npz", pitch=(1e200,) * 2)
    row = run(capsys, "info", tmp_path / "flat.npz", "--labels").splitlines()[2]
    assert row.split()[:7] == ["3", "9", "9e+400", "(beyond", "float64)", "1.2e+201", "1"]


@pytest.mark.parametrize("odd", ["\n", "\t", "\x1b[31m"])
def test_a_file_name_with_a_control_character_keeps_the_reports_lines(tmp_path, capsys, odd):
    """A line break in a file's name split the first line of the report
    (a script reading "NAME: ..." from it got two lines), and an escape
    reached the terminal as a command: the name is written escaped, as a
    label's name is, so the report has the lines it has under a plain
    name, for one object and for a label table with its --csv line."""
    image = np.zeros((6, 6, 6), np.uint8)
    image[1:3, 1:3, 1:3], image[3:5, 3:5, 3:5] = 1, 2
    escaped = odd.encode("unicode_escape").decode("ascii")  # as Python writes it: \n, \t, \x1b[31m
    for labels in ([], ["--labels"]):
        one = image if labels else (image == 1).astype(np.uint8)
        np.save(tmp_path / "plain.npy", one)
        np.save(tmp_path / f"a{odd}b.npy", one)
        csv_out = ["--csv", str(tmp_path / f"t{odd}.csv"), "--force"] if labels else []
        plain = run(capsys, "info", tmp_path / "plain.npy", *labels, *csv_out).splitlines()
        odd_lines = run(capsys, "info", tmp_path / f"a{odd}b.npy", *labels, *csv_out).splitlines()
        assert len(odd_lines) == len(plain)
        assert odd_lines[0] == plain[0].replace("plain.npy", f"a{escaped}b.npy")
        assert all(odd not in line for line in odd_lines)
        assert "\x1b" not in "".join(odd_lines)


def test_the_terminal_table_keeps_its_columns_with_64_bit_labels(tmp_path, capsys):
    image = np.zeros((5, 5, 5), np.uint64)
    image[1, 1, 1], image[3, 3, 3] = 7, np.iinfo(np.uint64).max
    np.save(tmp_path / "u.npy", image)
    lines = run(capsys, "info", tmp_path / "u.npy", "--labels").splitlines()
    head = lines[1].index("  surfaces")
    assert [line.index("  1 (0)") for line in lines[2:4]] == [head, head]
    assert lines[3].split()[0] == str(np.iinfo(np.uint64).max)


def test_surface_labels_files_take_ascii_and_triangulate(tmp_path, capsys, segmentation):
    np.save(tmp_path / "seg.npy", segmentation)
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "4,9", "-o", f"{tmp_path}/d/", "--suffix", "ply",
        "--ascii", "--triangulate")
    for label in (4, 9):
        text = (tmp_path / "d" / f"label_{label}.ply").read_bytes()
        assert text.startswith(b"ply\nformat ascii 1.0\n") and b"comment faces: triangles" in text
        mesh = trimesh.load(tmp_path / "d" / f"label_{label}.ply", process=False)
        assert mesh.is_watertight and mesh.volume == pytest.approx(np.count_nonzero(segmentation == label))
    fails(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", tmp_path / "s.glb", "--triangulate",
          words=("s.glb", "--triangulate", "-o DIR/"))
    fails(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", f"{tmp_path}/e/", "--suffix", "stl", "--ascii",
          words=("--ascii", ".ply", ".stl"))


def test_a_label_no_voxel_has_is_named_in_all_its_digits(tmp_path, capsys):
    """--label N on a label image without N lists the values present as
    they are: 2**40 and 2**40 + 1 are two labels (%g wrote both
    1.09951e+12), a 64-bit label keeps its 20 digits; an image without
    voxels has none to list (its --labels table: below)."""
    image = np.zeros((4, 4, 4), np.uint64)
    image[1, 1, 1], image[2, 2, 2] = 2**40, 2**64 - 1
    np.save(tmp_path / "big.npy", image)
    present = ", ".join(map(str, np.unique(image).tolist()))
    assert present == "0, 1099511627776, 18446744073709551615"
    fails(capsys, "info", tmp_path / "big.npy", "--label", 2**40 + 1,
          words=(f"no voxel has label {2**40 + 1} (values present: {present})",))
    np.save(tmp_path / "none.npy", np.zeros((0, 3, 3), np.uint8))
    fails(capsys, "info", tmp_path / "none.npy", "--label", 1, words=("no voxel has label 1: the array has no voxels",))


def test_surface_labels_into_a_file_named_as_a_directory_is_refused_up_front(tmp_path, capsys, segmentation):
    """-o NAME/ where NAME is a file: one line before any work (was
    FileExistsError from mkdir once every label was meshed)."""
    np.save(tmp_path / "seg.npy", segmentation)
    (tmp_path / "taken").write_text("a file")
    fails(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", f"{tmp_path}/taken/", "--suffix", "ply",
          words=("taken/", "exists and is not a directory"))
    assert (tmp_path / "taken").read_text() == "a file"


def test_labels_before_the_input_names_what_it_took(tmp_path, capsys, segmentation):
    """`info --labels seg.npy`: the optional SPEC takes the file name and
    argparse then said the input was missing; one line names what
    --labels took and where the input goes. A choice that reads as labels
    (`--labels 3` with no input) keeps argparse's message."""
    np.save(tmp_path / "seg.npy", segmentation)
    for command in (["info"], ["surface", "-o", str(tmp_path / "s.glb")]):
        with pytest.raises(SystemExit) as exit_:
            main([*command, "--labels", str(tmp_path / "seg.npy")])
        assert exit_.value.code == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"--labels took '{tmp_path / 'seg.npy'}' as its labels" in err[0]
        assert f"isoflow {command[0]} {tmp_path / 'seg.npy'} --labels" in err[0]
    assert not (tmp_path / "s.glb").exists()
    with pytest.raises(SystemExit):
        main(["info", "--labels", "3"])
    assert capsys.readouterr().err.strip().endswith("the following arguments are required: input")
    assert [r["label"] for r in json.loads(run(capsys, "info", "--labels", "9,3", tmp_path / "seg.npy", "--json"))
            ["labels"]] == [9, 3]


def test_an_ome_tiff_label_image_is_in_its_physical_sizes(tmp_path, capsys, segmentation):
    """An OME-TIFF's voxel size is its OME-XML PhysicalSizeX/Y/Z (it was
    read as 1: volumes and areas in voxels); one that is no size is one line."""
    tifffile = pytest.importorskip("tifffile")
    sizes = {"PhysicalSizeX": 0.5, "PhysicalSizeY": 0.25, "PhysicalSizeZ": 2.0}
    tifffile.imwrite(tmp_path / "seg.ome.tif", segmentation.T, metadata={"axes": "ZYX", **sizes})
    with tifffile.TiffFile(tmp_path / "seg.ome.tif") as tif:
        assert tif.is_ome and all(f'{k}="{v}"' in tif.ome_metadata for k, v in sizes.items())
    report = json.loads(run(capsys, "info", tmp_path / "seg.ome.tif", "--labels", "--json"))
    assert report["pitch"] == [0.5, 0.25, 2.0]
    for row in report["labels"]:
        mask = segmentation == row["label"]
        assert row["volume"] == pytest.approx(mask.sum() * 0.5 * 0.25 * 2.0)
        faces = [np.count_nonzero(np.diff(np.pad(mask, 1), axis=d)) for d in range(3)]
        assert row["surface_area"] == pytest.approx(faces[0] * 0.25 * 2.0 + faces[1] * 0.5 * 2.0 + faces[2] * 0.5 * 0.25)
    tifffile.imwrite(tmp_path / "cut.ome.tif", segmentation[:, :, 4].T, metadata={"axes": "YX", **sizes})
    assert json.loads(run(capsys, "info", tmp_path / "cut.ome.tif", "--labels", "--json"))["pitch"] == [0.5, 0.25]
    tifffile.imwrite(tmp_path / "bad.ome.tif", segmentation.T, metadata={"axes": "ZYX", "PhysicalSizeZ": -1.0})
    fails(capsys, "info", tmp_path / "bad.ome.tif", "--labels", words=("bad.ome.tif", "PhysicalSizeZ '-1.0'"))


def test_surface_labels_as_stl_notes_the_contacts_a_weld_joins(tmp_path, capsys):
    """STL keeps no shared vertices: a label whose voxels meet along an
    edge has two sheets through it, which any reader's weld makes
    non-manifold. surface --label says so of its one file; --labels -o
    DIR/ --suffix stl said nothing, and now names the files."""
    image = np.zeros((5, 5, 5), np.uint8)
    image[1, 1, 1] = image[2, 2, 1] = 1  # an edge contact (6-connectivity: two components)
    image[3:5, 3:5, 3:5] = 2  # a cube
    np.save(tmp_path / "e.npy", image)
    assert main(["surface", str(tmp_path / "e.npy"), "--labels", "-o", f"{tmp_path}/d/", "--suffix", "stl"]) == 0
    err = capsys.readouterr().err
    assert "STL keeps no shared vertices" in err and "of 1 file (label_1.stl)" in err
    welded = {n: trimesh.load(tmp_path / "d" / f"label_{n}.stl") for n in (1, 2)}  # trimesh welds by position
    assert not welded[1].is_watertight and welded[2].is_watertight
    assert main(["surface", str(tmp_path / "e.npy"), "--labels", "2", "-o", f"{tmp_path}/c/", "--suffix", "stl"]) == 0
    assert "STL keeps" not in capsys.readouterr().err
    # a warning (what readers get is not the surface written): --quiet keeps it
    assert main(["surface", str(tmp_path / "e.npy"), "--labels", "-o", f"{tmp_path}/d/", "--suffix", "stl", "--force",
                 "-q"]) == 0
    assert "warning: " in (err := capsys.readouterr().err) and "of 1 file (label_1.stl)" in err, err


def test_surface_labels_as_stl_far_from_the_origin_warns_of_the_float32_move(tmp_path, capsys):
    """surface says how far an STL's float32 positions moved the corners;
    a file per label as STL said nothing of it."""
    from isoflow import DigitalObject, boundary_mesh, write_labels

    image = boxes([3, 4])
    write_labels(image, tmp_path / "far.npz", pitch=0.01, origin=(1e5, 0, 0))
    # numpy's float32 of the corners in world units: the farthest move, in voxels
    moves = []
    for label in (1, 2):
        obj = DigitalObject(image == label, pitch=0.01, origin=(1e5, 0, 0))
        corners = obj.world(boundary_mesh(obj.volume, 6).vertices)
        moves.append(np.abs(corners.astype(np.float32) - corners).max() / 0.01)
    assert max(moves) > 1e-3  # more than a thousandth of a voxel: surface's threshold for saying it
    assert main(["surface", str(tmp_path / "far.npz"), "--labels", "-o", f"{tmp_path}/d/", "--suffix", "stl", "-q"]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "float32" in line]
    assert len(warned) == 1 and warned[0].startswith(f"isoflow surface: warning: {tmp_path}/d/: STL stores float32 "
                                                     "positions, which move the corners by up to "), warned
    assert f"({max(moves):.2g} voxels)" in warned[0], (warned, moves)
    assert main(["surface", str(tmp_path / "far.npz"), "--labels", "-o", f"{tmp_path}/p/", "--suffix", "ply"]) == 0
    assert "float32" not in capsys.readouterr().err  # PLY keeps float64


def test_surface_labels_counts_the_faces_its_files_hold(tmp_path, capsys, segmentation):
    """The summary's faces are those written, of the kind written, as
    surface says of one file: a .glb holds triangles (it gave the quads'
    count, half of them), a PLY at 26 triangles where a label has edge
    midpoints and quads elsewhere."""
    np.save(tmp_path / "seg.npy", segmentation)
    said = run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", tmp_path / "s.glb")
    scene = trimesh.load(tmp_path / "s.glb", force="scene", process=False)
    assert f"6 labels, {sum(len(g.faces) for g in scene.geometry.values())} faces (triangles), " in said
    said = run(capsys, "surface", tmp_path / "seg.npy", "--labels", "-o", f"{tmp_path}/d/", "--suffix", "ply",
               "--connectivity", "26", "--ascii")
    counts, kinds = [], set()
    for path in (tmp_path / "d").iterdir():
        header = path.read_bytes().split(b"end_header")[0].decode().splitlines()
        counts += [int(line.split()[2]) for line in header if line.startswith("element face ")]
        kinds |= {line.split(": ")[1] for line in header if line.startswith("comment faces: ")}
    said_faces = said.split("6 labels, ")[1].split(", one closed")[0]
    assert said_faces.startswith(f"{sum(counts)} faces (")
    assert set(said_faces.split("(")[1].rstrip(")").split(", ")) == kinds


def test_a_choice_of_millions_of_labels_filters_the_table(tmp_path, capsys):
    # --labels 1-3000000 built a row of zeros for each of the three million
    # labels before dropping the absent ones: 1.4 GB and seconds for an image
    # of two labels; it is now a filter on the table of the labels present.
    # A choice of 300000 (past CHOICE_ROWS, so the same filter) under a bound
    # a tenth as high keeps the test's margins: the memory either way grows
    # with the labels asked, and tracemalloc slows each Python allocation
    import tracemalloc

    from isoflow.cli.labels import CHOICE_ROWS

    assert 300000 > CHOICE_ROWS
    image = np.zeros((12, 12, 12), np.uint32)
    image[2:5, 2:5, 2:5], image[6:9, 6:9, 6:9] = 3, 7
    np.save(tmp_path / "two.npy", image)
    tracemalloc.start()
    try:
        assert main(["info", str(tmp_path / "two.npy"), "--labels", "7,1-300000", "--json"]) == 0
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    out, err = capsys.readouterr()
    rows = json.loads(out)["labels"]
    assert [r["label"] for r in rows] == [7, 3]  # in the order asked
    assert [r["voxels"] for r in rows] == [27, 27]
    assert rows[0]["euler_characteristic"] == analyze(image == 7, 6).euler_characteristic
    assert rows == json.loads(run(capsys, "info", tmp_path / "two.npy", "--labels", "7,3", "--json"))["labels"]
    assert "299998 of the labels asked for do not occur (1, 2, 4, 5, 6, 8, 9, 10, and 299990 more)" in err
    assert peak < 80e6, peak


def test_a_range_of_millions_is_parsed_filtered_and_listed_absent_as_arrays():
    """``--labels 7,1-3000000``: the choice, its rows and its absent labels
    are NumPy arrays, not a Python integer per label asked, in the order
    asked, each label once."""
    import tracemalloc

    from isoflow.cli.labels import chosen_rows, in_order_asked, label_choice

    table = {"label": np.array([3, 7], np.uint32), "voxels": np.array([27, 27])}
    tracemalloc.start()
    try:
        asked = label_choice("7,1-3000000")
        rows, missing = chosen_rows(table, asked)
        absent = in_order_asked(missing, asked[:0], asked)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert rows["label"].tolist() == [7, 3]  # in the order asked
    expected = np.r_[1:3, 4:7, 8:3000001]  # 1 to 3,000,000 but the two labels present, 7 asked once
    assert len(absent) == 3000000 - 2 and np.array_equal(absent, expected)
    # the bound catches a Python integer per label asked (28 bytes, and 8 more for its
    # place in a list: 108 MB at 3 million labels); an array of them is 8 bytes a label
    assert peak < 100e6, peak


def test_a_choice_of_more_than_ten_million_labels_is_refused_however_it_is_split():
    """The bound on a choice counted each range alone, and one too few: a
    range of 10,000,001 labels passed, and so did several ranges of ten
    million each, which the choice then held together (about 40 bytes a
    label at the peak: 400 MB at ten million, without bound as ranges are
    added). The labels of A-B are B - A + 1; a label asked twice counts
    once."""
    from isoflow.cli.labels import label_choice

    with pytest.raises(IsoflowError, match="has more than 10 million labels"):
        label_choice("1-10000001")  # 10,000,001 labels
    with pytest.raises(IsoflowError, match="more than 10 million labels"):
        label_choice("1-6000000,6000001-12000000")  # two ranges, 12 million labels together
    # 10 million distinct labels: the repeats of the second range are not counted again
    assert len(label_choice("5000001-10000000,1-10000000")) == 10_000_000


def test_a_mesh_given_for_a_label_image_is_named_a_mesh(capsys):
    # it said "not a volume file (volumes end in .npy, ...)", as for any file,
    # and not how a label image of meshes is made
    line = fails(capsys, "info", Path(__file__).resolve().parents[1] / "meshes" / "torus.obj", "--labels",
                 words=("torus.obj: a mesh, not a label image", "voxelize A.stl B.obj"))
    assert "volumes end in" not in line


def test_a_point_list_given_for_a_label_image_is_named_a_point_list(tmp_path, capsys):
    # it said "not a volume file (volumes end in .npy, ...)", though info
    # reads the same file as one object without --labels
    (tmp_path / "p.txt").write_text("0 0 0\n1 0 0\n")
    line = fails(capsys, "info", tmp_path / "p.txt", "--labels",
                 words=("p.txt: a point list", "not a label image", "without --labels"))
    assert "volumes end in" not in line
    assert main(["info", str(tmp_path / "p.txt"), "--json"]) == 0  # what the line says reports it
    assert json.loads(capsys.readouterr().out)["dimension"] == 3


def test_write_labels_writes_a_2d_label_image_that_info_labels_reads(tmp_path):
    """write_labels took 3D only ("a label image is a 3D array"), though
    read_labels, label_table and ``info --labels`` take a 2D image (a cell
    segmentation): a 2D image is written in every format that holds 2D and
    read back with its pixel size and origin, and ``info --labels`` in the
    shell gives the cells' areas and perimeters known by hand. 4D stays
    refused (read_labels reads no 4D back), saying so."""
    from isoflow import read_labels, write_labels
    from isoflow.errors import IsoflowError

    cells = np.zeros((6, 5), np.uint16)
    cells[0:2, 0:3] = 1  # a 2x3 block
    cells[3:6, 1:4] = 300  # a 3x3 ring
    cells[4, 2] = 0
    out = tmp_path / "cells.nii.gz"
    code = ("import sys, numpy as np, isoflow; cells = np.load(sys.argv[1]); "
            "isoflow.write_labels(cells, sys.argv[2], pitch=(0.5, 0.25), origin=(1, 2))")
    np.save(tmp_path / "cells.npy", cells)
    p = subprocess.run([sys.executable, "-c", code, str(tmp_path / "cells.npy"), str(out)], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    p = isoflow_here("info", str(out), "--labels", "--json")
    assert p.returncode == 0, p.stderr
    table = json.loads(p.stdout)
    assert table["pitch"] == [0.5, 0.25] and table["origin"] == [1.0, 2.0]
    block, ring = table["labels"]
    assert (block["label"], block["voxels"], block["area"], block["perimeter"]) == (1, 6, 6 * 0.125, 2 * (2 * 0.5 + 3 * 0.25))
    assert [block[f"bbox-{i}"] for i in range(4)] == [1.0, 2.0, 1.0 + 2 * 0.5, 2.0 + 3 * 0.25]
    assert (ring["label"], ring["voxels"], ring["b0"], ring["b1"]) == (300, 8, 1, 1)
    for suffix in (".npz", ".tif", ".nii", ".nrrd", ".h5", ".zarr"):
        back = read_labels(write_labels(cells, tmp_path / f"c{suffix}", pitch=(0.5, 0.25)))
        assert np.array_equal(back.array, cells) and back.spacing.tolist() == [0.5, 0.25], suffix
    with pytest.raises(IsoflowError, match=r"holds 3D voxels, this object is 2D"):
        write_labels((cells == 1).astype(np.uint8), tmp_path / "c.binvox")
    with pytest.raises(IsoflowError, match=r"written in 2D or 3D, as read_labels reads it back; this one is 4D"):
        write_labels(np.zeros((2, 2, 2, 2), np.uint8), tmp_path / "c4.npz")
    assert not (tmp_path / "c4.npz").exists()


def boxes(sizes: list[int]) -> np.ndarray:
    """A label image of cubes, label i+1 of edge ``sizes[i]``, apart."""
    image = np.zeros((4 + 6 * len(sizes), 8, 8), np.uint8)
    for i, size in enumerate(sizes):
        image[2 + 6 * i: 2 + 6 * i + size, 2:2 + size, 2:2 + size] = i + 1
    return image


def files_in(directory: Path) -> dict[str, bytes]:
    """Every file in ``directory`` (temporaries too) with its bytes."""
    return {f.name: f.read_bytes() for f in sorted(directory.iterdir())}


def fail_at(monkeypatch, name: str, how: str) -> None:
    """The write of the file ``name`` fails once it is written, before it is
    put in place: a full disk, or SIGTERM arriving."""
    import contextlib
    import errno
    import os
    import signal

    from isoflow.mesh import outputs

    real = outputs.atomic_path

    @contextlib.contextmanager
    def atomic_path(path, *args, **kwargs):
        with real(path, *args, **kwargs) as tmp:
            yield tmp
            if Path(path).name == name:
                if how == "disk full":
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp))
                os.kill(os.getpid(), signal.SIGTERM)

    monkeypatch.setattr(outputs, "atomic_path", atomic_path)


@pytest.mark.parametrize("how, status", [("disk full", 2), ("SIGTERM", 128 + 15)])
def test_surface_labels_failing_at_a_later_label_keeps_the_whole_earlier_set(tmp_path, capsys, monkeypatch, how, status):
    # the first labels' files were replaced and the later ones kept: a mixed set that looked complete
    np.save(tmp_path / "old.npy", boxes([2, 2, 2]))
    np.save(tmp_path / "new.npy", boxes([3, 4, 3]))
    out = tmp_path / "out"
    run(capsys, "surface", tmp_path / "old.npy", "--labels", "-o", f"{out}/", "--suffix", "ply")
    before = files_in(out)
    assert sorted(before) == ["label_1.ply", "label_2.ply", "label_3.ply"]
    fail_at(monkeypatch, "label_3.ply", how)
    code = main(["surface", str(tmp_path / "new.npy"), "--labels", "-o", f"{out}/", "--suffix", "ply", "--force"])
    err = capsys.readouterr().err
    assert code == status, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert err.rstrip().endswith("nothing was replaced"), err
    assert files_in(out) == before  # byte for byte, and no temporary left


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="syncfs flushes a set at once on Linux")
def test_surface_labels_dir_flushes_the_set_at_once_not_file_by_file(tmp_path, capsys, monkeypatch):
    # an fsync per label's file commits the journal once a file: with thousands of labels 40 % of the run
    import os

    from isoflow.mesh import outputs

    fsyncs, flushes = [], []
    real_fsync, real_flush = os.fsync, outputs.flush_set

    def fsync(fd):
        fsyncs.append(fd)
        real_fsync(fd)

    def flush_set(name, written):  # each file flushed before any is in place
        flushes.append((len(written), any(f.exists() for f in Path(name).glob("label_*.ply"))))
        real_flush(name, written)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(outputs, "flush_set", flush_set)
    counts = []
    for sizes in ([2, 3, 4] * 3, [2, 3, 4] * 4):  # sets of more files than FILES_PER_FSYNC
        np.save(tmp_path / "labels.npy", boxes(sizes))
        out = tmp_path / f"out{len(sizes)}"
        fsyncs.clear()
        run(capsys, "surface", tmp_path / "labels.npy", "--labels", "-o", f"{out}/", "--suffix", "ply")
        counts.append(len(fsyncs))
        for label, size in enumerate(sizes, 1):
            mesh = trimesh.load(out / f"label_{label}.ply", process=False)
            assert mesh.is_watertight and mesh.volume == pytest.approx(size ** 3)
    assert counts[0] == counts[1] <= 2, counts  # the directory's, not one per file
    assert flushes == [(9, False), (12, False)]


def test_surface_labels_reads_the_memory_available_once_not_per_file(tmp_path, capsys, monkeypatch):
    # each label's mesh and each file's read-back checked its memory against a budget read anew from
    # /proc/meminfo and the control groups: once a file, thousands of reads for a segmentation's labels
    from isoflow.scale import memory

    reads, real = [], memory.meminfo_available

    def meminfo_available():
        reads.append(1)
        return real()

    monkeypatch.setattr(memory, "meminfo_available", meminfo_available)
    counts = []
    for sizes in ([2, 3], [2, 3, 4, 2, 3, 4]):
        np.save(tmp_path / "labels.npy", boxes(sizes))
        out = tmp_path / f"out{len(sizes)}"
        reads.clear()
        run(capsys, "surface", tmp_path / "labels.npy", "--labels", "-o", f"{out}/", "--suffix", "ply")
        counts.append(len(reads))
        for label, size in enumerate(sizes, 1):  # the files as written, read back by trimesh
            mesh = trimesh.load(out / f"label_{label}.ply", process=False)
            assert mesh.is_watertight and mesh.volume == pytest.approx(size ** 3)
    # the table's, then the surfaces': as many for six files as for two, fewer than the files
    assert counts[0] == counts[1] <= 2, counts


def test_surface_labels_checks_its_placement_once(tmp_path, capsys, monkeypatch):
    # the placement was checked before the table and again before the surfaces, the same numbers twice
    nrrd = pytest.importorskip("nrrd")
    from isoflow.mesh import export

    # a voxel of 1e-9 at 1e6, where float64 keeps the corners apart but moves them (pynrrd writes it)
    nrrd.write(str(tmp_path / "far.nrrd"), boxes([2, 3]), {"space directions": np.eye(3) * 1e-9,
                                                           "space origin": [1e6, 0.0, 0.0]}, index_order="C")
    calls, real = [], export.check_float64_corners

    def check_float64_corners(*args, **kwargs):
        calls.append(args[0])
        return real(*args, **kwargs)

    monkeypatch.setattr(export, "check_float64_corners", check_float64_corners)
    out = tmp_path / "out"
    assert main(["surface", str(tmp_path / "far.nrrd"), "--labels", "-o", f"{out}/", "--suffix", "ply"]) == 0
    err = capsys.readouterr().err
    assert calls == [str(tmp_path / "far.nrrd")]
    assert err.count("float64 holds the voxel corners of this placement") == 1, err
    for label in (1, 2):  # a box each: a closed sphere-like surface, V - E + F = 2
        mesh = trimesh.load(out / f"label_{label}.ply", process=False)
        assert mesh.is_watertight and mesh.euler_number == 2


def test_surface_labels_force_replaces_the_whole_set(tmp_path, capsys):
    # label_4.ply of an earlier image with four labels stayed beside the three files of the new one
    np.save(tmp_path / "old.npy", boxes([2, 2, 2, 2]))
    np.save(tmp_path / "new.npy", boxes([3, 4, 2]))
    out = tmp_path / "out"
    run(capsys, "surface", tmp_path / "old.npy", "--labels", "-o", f"{out}/", "--suffix", "ply")
    assert sorted(files_in(out)) == ["label_1.ply", "label_2.ply", "label_3.ply", "label_4.ply"]
    (out / "notes.txt").write_text("mine")
    run(capsys, "surface", tmp_path / "new.npy", "--labels", "-o", f"{out}/", "--suffix", "ply", "--force")
    assert sorted(files_in(out)) == ["label_1.ply", "label_2.ply", "label_3.ply", "notes.txt"]
    for label, size in ((1, 3), (2, 4), (3, 2)):
        mesh = trimesh.load(out / f"label_{label}.ply", process=False)
        assert mesh.is_watertight and mesh.volume == pytest.approx(size ** 3)


def test_surface_labels_without_force_says_an_earlier_run_s_files_are_kept(tmp_path, capsys):
    np.save(tmp_path / "four.npy", boxes([2, 2, 2, 2]))
    out = tmp_path / "out"
    run(capsys, "surface", tmp_path / "four.npy", "--labels", "4", "-o", f"{out}/", "--suffix", "ply")
    assert main(["surface", str(tmp_path / "four.npy"), "--labels", "1-3", "-o", f"{out}/", "--suffix", "ply"]) == 0
    err = capsys.readouterr().err
    assert "1 label file of an earlier run kept (label_4.ply); a choice of labels replaces those labels' files" in err
    assert sorted(files_in(out)) == ["label_1.ply", "label_2.ply", "label_3.ply", "label_4.ply"]
    run(capsys, "surface", tmp_path / "four.npy", "--labels", "1-3", "-o", f"{out}/", "--suffix", "ply", "--force")
    assert main(["surface", str(tmp_path / "four.npy"), "--labels", "-o", f"{out}/", "--suffix", "stl"]) == 0
    err = capsys.readouterr().err  # every label: --force would make the directory hold this run's alone
    assert "of an earlier run kept" not in err  # the .ply files are of another suffix, none of this set's


@pytest.mark.parametrize(("choice", "replaced", "kept"), [
    (["--labels", "2,4"], {2: 4}, ["label_1.ply", "label_3.ply"]),
    (["--labels=1-2"], {1: 3, 2: 4}, ["label_3.ply", "label_4.ply"]),
])
def test_surface_labels_force_with_a_choice_replaces_the_chosen_labels_files_alone(tmp_path, capsys, choice, replaced,
                                                                                   kept):
    # redoing one label with --force removed every other label's file of the earlier run
    np.save(tmp_path / "old.npy", boxes([2, 2, 2, 2]))
    np.save(tmp_path / "new.npy", boxes([3, 4, 2]))  # label 4 no longer occurs
    out = tmp_path / "out"
    for suffix in ("ply", "obj"):
        run(capsys, "surface", tmp_path / "old.npy", "--labels", "-o", f"{out}/", "--suffix", suffix)
    before = files_in(out)
    assert main(["surface", str(tmp_path / "new.npy"), *choice, "-o", f"{out}/", "--suffix", "ply", "--force"]) == 0
    err = capsys.readouterr().err
    assert f"{len(kept)} label files of an earlier run kept ({', '.join(kept)})" in err, err
    after = files_in(out)
    # the chosen labels' files replaced (label 4's removed: the image has no surface for it), every other one kept
    assert sorted(after) == sorted([f"label_{v}.ply" for v in replaced] + kept + [f"label_{v}.obj" for v in (1, 2, 3, 4)])
    assert {name: after[name] for name in after if name not in {f"label_{v}.ply" for v in replaced}} == \
        {name: before[name] for name in after if name not in {f"label_{v}.ply" for v in replaced}}
    for label, size in replaced.items():
        mesh = trimesh.load(out / f"label_{label}.ply", process=False)
        assert mesh.is_watertight and mesh.volume == pytest.approx(size ** 3)


@pytest.mark.parametrize("choice", [["--labels"], ["--labels", "2"]])
def test_surface_labels_force_leaves_files_of_names_it_never_writes(tmp_path, capsys, choice):
    """A --force run removes the ``label_N`` files an earlier run left, as
    this command names them (``str(N)``): ``label_02.ply`` and
    ``label_002.ply`` (another program's zero-padded names) were read as
    label 2's and removed, though this command never writes them; they
    keep their bytes, while label 4's file of an image that no longer has
    it goes."""
    np.save(tmp_path / "old.npy", boxes([2, 2, 2, 2]))
    np.save(tmp_path / "new.npy", boxes([3, 4]))
    out = tmp_path / "out"
    run(capsys, "surface", tmp_path / "old.npy", "--labels", "4", "-o", f"{out}/", "--suffix", "ply")
    theirs = {"label_02.ply": b"ply padded 2", "label_002.ply": b"ply padded 2 again", "label_+2.ply": b"ply plus"}
    for name, data in theirs.items():
        (out / name).write_bytes(data)
    assert main(["surface", str(tmp_path / "new.npy"), *choice, "-o", f"{out}/", "--suffix", "ply", "--force"]) == 0
    capsys.readouterr()
    after = files_in(out)
    assert {name: after.get(name) for name in theirs} == theirs
    written = ["label_1.ply", "label_2.ply"] if choice == ["--labels"] else ["label_2.ply"]
    kept = ["label_4.ply"] if choice != ["--labels"] else []  # a choice keeps every other label's file
    assert sorted(after) == sorted([*theirs, *written, *kept])
    mesh = trimesh.load(out / "label_2.ply", process=False)
    assert mesh.is_watertight and mesh.volume == pytest.approx(4 ** 3)


def test_a_label_slice_saved_as_3d_gets_the_note_with_the_line_that_saves_its_2d_labels(tmp_path, capsys):
    """``info --labels`` read a segmentation of one slice saved as (X, Y, 1)
    as a plate one voxel thick without a word, where ``info`` of a mask
    says so: its table had volumes and surface areas (the plate's top and
    bottom faces) for the slice's areas and perimeters. It gets info's
    note, whose line saves the 2D label image (read_labels, write_labels,
    the pixel size and unit kept), and that image's table is the slice's
    as scikit-image counts it (area, Euler number at 8) in the file's
    millimetres as nibabel reads them."""
    import shlex

    nib = pytest.importorskip("nibabel")
    measure = pytest.importorskip("skimage.measure")
    cells = np.zeros((9, 8), np.int16)
    cells[1:7, 2:7] = 4
    cells[3:5, 4] = 0  # a hole in label 4
    cells[8, 0] = 4  # and a second piece
    cells[0:3, 0:2] = 9
    image = nib.Nifti1Image(cells[:, :, None], np.diag([0.5, 0.7, 2.0, 1]))
    image.header.set_xyzt_units("mm")
    path = tmp_path / "slice.nii.gz"
    nib.save(image, path)
    assert main(["info", str(path), "--labels", "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["shape"] == [9, 8, 1]  # read as it is, a plate
    [note] = err.splitlines()
    assert note.startswith(f"isoflow info: note: {path}: shape 9x8x1, one voxel along z: read as a 3D plate"), note
    code = shlex.split(note.split("give it: ", 1)[1])
    assert code[:2] == ["python", "-c"]
    p = subprocess.run([sys.executable, "-c", code[2]], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    table = json.loads(run(capsys, "info", tmp_path / "slice_2d.npz", "--labels", "--json", "--connectivity", "8"))
    zooms = [float(z) for z in nib.load(path).header.get_zooms()[:2]]
    assert table["shape"] == [9, 8] and table["pitch"] == pytest.approx(zooms) and table["unit"] == "mm"
    want = measure.regionprops_table(cells, properties=("label", "area", "euler_number"))
    assert [r["label"] for r in table["labels"]] == want["label"].tolist()
    assert [r["area"] for r in table["labels"]] == pytest.approx(want["area"] * zooms[0] * zooms[1])
    assert [r["euler_characteristic"] for r in table["labels"]] == want["euler_number"].tolist()
    # --quiet drops it, and surface (3D only, a plate is its input) does not say it
    assert main(["info", str(path), "--labels", "--quiet"]) == 0
    assert capsys.readouterr().err == ""
    assert main(["surface", str(path), "--labels", "-o", str(tmp_path / "s.glb"), "--no-check"]) == 0
    assert "3D plate" not in capsys.readouterr().err


def test_an_ome_zarr_image_s_segmentation_under_labels_is_read_by_its_name(tmp_path, capsys, segmentation):
    """An OME-Zarr image keeps its segmentations as images of their own in
    its ``labels/`` group (NGFF's image-label: ``image.zarr/labels/cells``).
    Neither ``image.zarr/labels/cells`` ("not a volume file") nor
    ``image.zarr:labels/cells`` ("no resolution level") read it. The name
    after the colon picks the group (and a level after it), and the path
    given as a directory inside the store is one line naming the form that
    reads it. The rows are scikit-image's regionprops of the array zarr
    reads, placed by the label image's own scale and translation."""
    zarr = pytest.importorskip("zarr")
    measure = pytest.importorskip("skimage.measure")
    zyx = np.ascontiguousarray(segmentation.transpose(2, 1, 0))
    axes = [{"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"]
    scale, shift = [2.0, 0.75, 0.5], [5.0, -20.0, 10.0]  # (z, y, x); voxel centres

    def image(group, data):
        group.create_array("0", data=data, chunks=(5, 5, 5))
        group.attrs["multiscales"] = [{"version": "0.4", "axes": axes, "datasets": [{"path": "0", "coordinateTransformations": [
            {"type": "scale", "scale": scale}, {"type": "translation", "translation": shift}]}]}]

    root = zarr.open_group(str(tmp_path / "image.zarr"), mode="w", zarr_format=2)
    image(root, (zyx > 0).astype(np.uint8) * 200)  # the microscope's image
    root.require_group("labels").attrs["labels"] = ["cells"]
    cells = root.require_group("labels/cells")
    image(cells, zyx)
    cells.attrs["image-label"] = {"version": "0.4"}
    stored = zarr.open_array(str(tmp_path / "image.zarr" / "labels" / "cells" / "0"), mode="r")[:]
    want = measure.regionprops_table(stored.astype(np.int64), properties=("label", "area", "bbox", "centroid"))
    pitch = np.array(scale[::-1])
    corner = np.array(shift[::-1]) - pitch / 2
    for name in ("labels/cells", "labels/cells/0"):
        report = json.loads(run(capsys, "info", f"{tmp_path / 'image.zarr'}:{name}", "--labels", "--json"))
        assert report["pitch"] == pytest.approx(pitch) and report["unit"] == "µm"
        rows = report["labels"]
        assert [r["label"] for r in rows] == want["label"].tolist()
        assert [r["voxels"] for r in rows] == want["area"].tolist()
        for r, row in enumerate(rows):  # regionprops' axes are the stored (z, y, x)
            low = np.array([want[f"bbox-{2 - d}"][r] for d in range(3)])
            mean = np.array([want[f"centroid-{2 - d}"][r] for d in range(3)])
            assert [row[f"bbox-{d}"] for d in range(3)] == pytest.approx(corner + pitch * low)
            assert [row[f"centroid-{d}"] for d in range(3)] == pytest.approx(corner + pitch * (mean + 0.5))
    inside = tmp_path / "image.zarr" / "labels" / "cells"
    fails(capsys, "info", inside, "--labels", words=(f"inside the zarr store {tmp_path / 'image.zarr'}; name it as "
                                                     f"{tmp_path / 'image.zarr'}:labels/cells",))
    fails(capsys, "info", f"{tmp_path / 'image.zarr'}:labels", "--labels",
          words=("a zarr group without arrays (its groups: ['cells']; name one", ":labels/cells)"))


def test_absent_labels_beyond_int64_are_named_in_all_their_digits(tmp_path, capsys):
    """An int64 image asked for labels on both sides of 2**63 (a range up
    to the type's end and past it) named them, in its warning and its
    refusal, as NumPy's float64 of the lot: "9.223372036854776e+18" four
    times for four labels. Each is named as asked, in all its digits, as
    Python writes the integers and the JSON's ``absent`` lists them."""
    image = np.zeros((4, 4, 4), np.int64)
    image[1:3, 1:3, 1:3] = 2**40
    np.save(tmp_path / "big.npy", image)
    asked = [2**40, *range(2**63 - 2, 2**63 + 2)]
    spec = f"{asked[0]},{asked[1]}-{asked[-1]}"
    assert main(["info", str(tmp_path / "big.npy"), "--labels", spec, "--json"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["absent"] == asked[1:]
    assert f"4 of the labels asked for do not occur ({', '.join(map(str, asked[1:]))})" in err, err
    fails(capsys, "info", tmp_path / "big.npy", "--labels", f"{asked[1]}-{asked[-1]}",
          words=(f"none of the labels asked for occur ({', '.join(map(str, asked[1:]))})",))


def test_a_big_endian_label_file_s_type_is_named_as_numpy_names_it(tmp_path, capsys, segmentation):
    """A big-endian label image (NRRD's ``endian: big``, a zarr store of
    ``>u2``, an old Analyze or NIfTI file) had ``"dtype": ">i2"`` in
    ``--json`` where the same labels little-endian have ``"int16"``, and
    the refusal of a label the type cannot hold said int16: a script that
    compared types saw two. It is the type's name, as NumPy names what
    pynrrd and zarr read (``dtype.name``), with the rows scikit-image
    counts."""
    nrrd = pytest.importorskip("nrrd")
    zarr = pytest.importorskip("zarr")
    measure = pytest.importorskip("skimage.measure")
    nrrd.write(str(tmp_path / "be.nrrd"), segmentation.astype(">i2"), {"endian": "big"})
    data, header = nrrd.read(str(tmp_path / "be.nrrd"))
    assert header["endian"] == "big" and data.dtype.byteorder == ">"
    store = zarr.open_array(str(tmp_path / "be.zarr"), mode="w", shape=segmentation.shape, chunks=(5, 5, 5),
                            dtype=">u2", zarr_format=2)
    store[:] = segmentation
    want = measure.regionprops_table(segmentation.astype(np.int64), properties=("label", "area"))
    for path, stored in ((tmp_path / "be.nrrd", data.dtype), (tmp_path / "be.zarr", store.dtype)):
        report = json.loads(run(capsys, "info", path, "--labels", "--json"))
        assert report["dtype"] == np.dtype(stored).name, path
        assert [(r["label"], r["voxels"]) for r in report["labels"]] == list(zip(want["label"], want["area"]))


def test_cellpose_s_seg_npy_is_one_line_with_the_line_that_saves_its_masks(tmp_path, capsys):
    """Cellpose saves its segmentation as ``IMG_seg.npy``, a pickled dict
    holding ``masks`` (rows, columns). ``info IMG_seg.npy --labels`` said
    "not a readable numpy file (ValueError: Object arrays cannot be loaded
    when allow_pickle=False)". isoflow still unpickles nothing: the line
    says the file holds Python objects and gives the line that saves the
    masks x first, whose table is scikit-image's regionprops of the masks
    (area, Euler number at 8, the box with columns as x)."""
    import shlex

    measure = pytest.importorskip("skimage.measure")
    masks = np.zeros((7, 9), np.uint16)  # (rows, columns), as Cellpose's
    masks[1:4, 1:8] = 1
    masks[2, 3] = 0  # a hole
    masks[5:7, 0:3] = 2
    np.save(tmp_path / "img_seg.npy", {"masks": masks, "outlines": masks * 0, "filename": "img.tif"},
            allow_pickle=True)
    line = fails(capsys, "info", tmp_path / "img_seg.npy", "--labels",
                 words=(f"{tmp_path / 'img_seg.npy'}: holds Python objects", "Cellpose's _seg.npy"))
    code = shlex.split(line.split("give that: ", 1)[1])
    assert code[:2] == ["python", "-c"]
    p = subprocess.run([sys.executable, "-c", code[2]], cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    rows = json.loads(run(capsys, "info", tmp_path / "masks.npy", "--labels", "--json", "--connectivity", "8"))["labels"]
    want = measure.regionprops_table(masks, properties=("label", "area", "euler_number", "bbox"))
    assert [(r["label"], r["voxels"], r["euler_characteristic"]) for r in rows] == list(
        zip(want["label"], want["area"], want["euler_number"]))
    assert [[r["bbox-0"], r["bbox-1"]] for r in rows] == [[c, r] for r, c in zip(want["bbox-0"], want["bbox-1"])]


@pytest.mark.parametrize("member", ["volume", "pitch", "seg"])
def test_an_npz_array_of_python_objects_is_one_line_naming_the_array(tmp_path, capsys, member):
    """An ``.npz`` whose volume (or its voxel size) is an array of Python
    objects (``dtype=object``, pickled inside the archive) was refused as
    "not a readable numpy file (ValueError: Object arrays cannot be loaded
    when allow_pickle=False)", naming neither the array nor what to do.
    The line names the array and still unpickles nothing; the same
    archive with that array saved as numbers reads, its count numpy's."""
    labels = np.zeros((4, 5, 6), np.uint8)
    labels[1:3, 1:4, 2:5] = 1
    arrays = {"volume": labels, "pitch": np.array([0.5, 0.5, 1.0])} if member != "seg" else {"seg": labels}
    numbers = dict(arrays)
    arrays[member] = arrays[member].astype(object)
    np.savez(tmp_path / "objects.npz", **arrays)
    fails(capsys, "info", tmp_path / "objects.npz", "--labels",
          words=(f"{tmp_path / 'objects.npz'}: its array {member!r} holds Python objects",))
    fails(capsys, "info", tmp_path / "objects.npz",
          words=(f"{tmp_path / 'objects.npz'}: its array {member!r} holds Python objects",))
    np.savez(tmp_path / "numbers.npz", **numbers)
    assert json.loads(run(capsys, "info", tmp_path / "numbers.npz", "--json"))["voxels"] == np.count_nonzero(labels)


def test_labels_of_an_ome_zarr_image_name_the_segmentations_its_labels_group_holds(tmp_path, capsys, segmentation):
    """``info image.zarr --labels`` of an OME-Zarr image that keeps its
    segmentation in ``labels/`` (NGFF's image-label) read the image's
    intensities as labels without a word: a table of grey values. It still
    reads what it is given, with a note naming the segmentations and the
    name that reads one; that name's rows are scikit-image's regionprops
    of the array zarr reads there. --quiet drops the note; a store without
    ``labels/`` gets none."""
    zarr = pytest.importorskip("zarr")
    measure = pytest.importorskip("skimage.measure")
    zyx = np.ascontiguousarray(segmentation.transpose(2, 1, 0))
    axes = [{"name": a, "type": "space"} for a in "zyx"]

    def image(group, data):
        group.create_array("0", data=data, chunks=(5, 5, 5))
        group.attrs["multiscales"] = [{"version": "0.4", "axes": axes, "datasets": [{"path": "0"}]}]

    root = zarr.open_group(str(tmp_path / "image.zarr"), mode="w", zarr_format=2)
    image(root, (zyx * 37 + 5).astype(np.uint16))  # intensities
    root.require_group("labels").attrs["labels"] = ["nuclei", "cells"]
    image(root.require_group("labels/nuclei"), zyx)
    store = str(tmp_path / "image.zarr")
    assert main(["info", store, "--labels"]) == 0
    [note] = [line for line in capsys.readouterr().err.splitlines() if "labels/ group" in line]
    assert note == (f"isoflow info: note: {store}: an OME-Zarr image whose labels/ group holds 2 segmentations (nuclei, "
                    f"cells); this reads the image itself: for a segmentation's labels, give {store}:labels/nuclei")
    named = note.rsplit("give ", 1)[1]
    rows = json.loads(run(capsys, "info", named, "--labels", "--json"))["labels"]
    stored = zarr.open_array(f"{store}/labels/nuclei/0", mode="r")[:]
    want = measure.regionprops_table(stored.astype(np.int64), properties=("label", "area"))
    assert [(r["label"], r["voxels"]) for r in rows] == list(zip(want["label"], want["area"]))
    assert main(["info", store, "--labels", "--quiet"]) == 0
    assert "labels/ group" not in capsys.readouterr().err
    zarr.open_array(str(tmp_path / "plain.zarr"), mode="w", shape=zyx.shape, dtype="u2")[:] = zyx
    assert main(["info", str(tmp_path / "plain.zarr"), "--labels"]) == 0
    assert "labels/ group" not in capsys.readouterr().err


def test_an_empty_segmentation_s_table_has_no_row_and_exit_0(tmp_path, capsys):
    """A segmentation with no label (no lesion found: every voxel 0) was
    refused, exit 2, and ``--csv`` wrote no file, so a batch over a
    cohort's files stopped at the first empty one; label_table gives an
    empty table there, as scikit-image's regionprops_table does. The
    table has no row: the text, ``--json``'s ``labels`` ``[]``, a CSV of
    its header alone with the columns of any 3D table, exit 0, and a
    warning (under --quiet too) says why. surface, with no surface to
    write, still refuses it in one line."""
    nib = pytest.importorskip("nibabel")
    measure = pytest.importorskip("skimage.measure")
    empty = np.zeros((6, 5, 4), np.int16)
    image = nib.Nifti1Image(empty, np.diag([0.5, 0.7, 2.0, 1]))
    image.header.set_xyzt_units("mm")
    nib.save(image, tmp_path / "empty.nii.gz")
    assert len(measure.regionprops_table(empty, properties=("label", "area"))["label"]) == 0
    assert main(["info", str(tmp_path / "empty.nii.gz"), "--labels", "--json", "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert json.loads(out)["labels"] == [] and json.loads(out)["unit"] == "mm"
    assert "no nonzero label: the image is all 0" in err
    assert main(["info", str(tmp_path / "empty.nii.gz"), "--labels", "--csv", str(tmp_path / "empty.csv")]) == 0
    one = empty.copy()
    one[1, 1, 1] = 3
    np.save(tmp_path / "one.npy", one)
    assert main(["info", str(tmp_path / "one.npy"), "--labels", "--csv", str(tmp_path / "one.csv")]) == 0
    capsys.readouterr()
    with open(tmp_path / "empty.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    with open(tmp_path / "one.csv", newline="") as fh:
        header = next(csv.reader(fh))
    assert rows == [header]
    fails(capsys, "surface", tmp_path / "empty.nii.gz", "--labels", "-o", tmp_path / "e.glb",
          words=("no nonzero label: the image is all 0",))
    assert not (tmp_path / "e.glb").exists()


def test_a_2d_label_image_s_refusals_count_pixels(tmp_path, capsys):
    """A 2D image's refusals count its cells as pixels, as info's text
    does: a PNG label map without --label says how many pixels (as Pillow
    reads the file) hold values other than 0 and 1, a label no pixel has
    lists the values Pillow reads, a 2D store read block by block names
    the pixel its block starts at, and the table of an image of no pixels
    says so."""
    from PIL import Image

    cells = np.zeros((6, 9), np.uint8)
    cells[1:3, 1:4], cells[4:6, 2:8] = 1, 7
    Image.fromarray(cells).save(tmp_path / "cells.png")
    with Image.open(tmp_path / "cells.png") as png:
        many = int(np.count_nonzero(np.asarray(png) > 1))
        present = ", ".join(map(str, np.unique(np.asarray(png)).tolist()))
    fails(capsys, "info", tmp_path / "cells.png", words=(f"({many} pixels hold values other than 0 and 1, e.g. 7)",))
    fails(capsys, "info", tmp_path / "cells.png", "--label", 99, words=(f"no pixel has label 99 (values present: {present})",))
    zarr = pytest.importorskip("zarr")
    zarr.create_array(str(tmp_path / "cells.zarr"), data=cells.T, chunks=(5, 5), zarr_format=2)
    fails(capsys, "info", tmp_path / "cells.zarr", words=("pixels in the block at pixel (", "hold values other than 0 and 1"))
    # (a store's --label is selected block by block, the values read in a second pass)
    fails(capsys, "info", tmp_path / "cells.zarr", "--label", 99, words=(f"no pixel has label 99 (values present: {present})",))
    np.save(tmp_path / "none.npy", np.zeros((0, 5), np.uint8))
    code, out, err = said(capsys, "info", tmp_path / "none.npy", "--labels")  # its table of no row, as label_table's
    assert code == 0 and err == [f"isoflow info: warning: {tmp_path / 'none.npy'}: the image has no pixels (shape 0x5); "
                                 "the table has no row"]


@pytest.mark.parametrize("suffix", [".png", ".tif"])
def test_a_2d_label_image_refused_without_label_is_called_an_image(tmp_path, capsys, suffix):
    """A cell segmentation saved as a PNG or TIFF, given to info without
    --label N or --labels, is refused in a 2D image's words (a binary
    image of pixels, thresholded as ``image > ...``), as the other 2D
    refusals are, and still names both ways to its labels; a 2D store
    read block by block says the same, and a 3D one still says volume."""
    from PIL import Image

    cells = np.zeros((8, 12), np.uint8)
    cells[1:4, 1:5], cells[5:8, 6:11] = 2, 3
    path = tmp_path / f"cells{suffix}"
    Image.fromarray(cells).save(path)
    with Image.open(path) as image:  # the pixels as Pillow reads them, not as isoflow does
        held = np.asarray(image)
    many = int(np.count_nonzero((held != 0) & (held != 1)))
    line = fails(capsys, "info", path, words=(f"cells{suffix}: not a binary image ({many} pixels hold values other than 0 and 1",
                                              "threshold it first, e.g. image > ", "--label N", "--labels"))
    assert "volume" not in line and "voxel" not in line, line
    zarr = pytest.importorskip("zarr")
    zarr.create_array(str(tmp_path / "cells.zarr"), data=cells.T, chunks=(5, 5), zarr_format=2)
    line = fails(capsys, "info", tmp_path / "cells.zarr", words=("cells.zarr: not a binary image (", "e.g. image > "))
    assert "volume" not in line and "voxel" not in line, line
    np.save(tmp_path / "stack.npy", np.stack([cells.T] * 3, axis=2))
    fails(capsys, "info", tmp_path / "stack.npy", words=("stack.npy: not a binary volume (", "voxels hold", "e.g. volume > "))


@pytest.mark.parametrize("choice", ["٣", "1,٣-4", "３"])
def test_a_labels_choice_of_non_ascii_digits_is_refused(tmp_path, capsys, segmentation, choice):
    """Python's int() reads an Arabic-Indic or a full-width digit as the
    number (``int("٣") == 3``), so ``--labels ٣`` gave label 3's row; a
    choice is written in ASCII digits, and the line names the part that
    is not."""
    np.save(tmp_path / "a.npy", segmentation)
    part = choice.split(",")[-1]
    assert int(part.split("-")[0]) == 3 and not part.isascii()
    fails(capsys, "info", tmp_path / "a.npy", "--labels", choice,
          words=(f"--labels {choice}", repr(part), "is not a label or a range"))


@pytest.mark.skipif(not Path("/sys/kernel").is_dir(), reason="needs Linux's sysfs, where no directory can be made")
def test_surface_labels_into_a_directory_that_cannot_be_made_fails_before_the_work(tmp_path, capsys, segmentation):
    """``-o /sys/out/``: os.access says root may write in /sys, and making
    the directory after all the labels were meshed raised OSError (a
    traceback, exit 1). It is made before the work, and a failure is one
    line naming it."""
    np.save(tmp_path / "a.npy", segmentation)
    target = Path("/sys/isoflow_test_out")
    with pytest.raises(OSError):
        target.mkdir()  # the system's own answer for this path
    fails(capsys, "surface", tmp_path / "a.npy", "--labels", "-o", f"{target}/", "--suffix", ".ply",
          words=(f"{target}/", "cannot make the directory"))


def test_surface_labels_directory_made_up_front_is_removed_when_the_work_fails(tmp_path, capsys, segmentation):
    """The directory made before the work is not left behind, empty, by
    work that fails (a choice of labels none of which occur)."""
    np.save(tmp_path / "a.npy", segmentation)
    assert not np.any(segmentation == 7)
    assert main(["surface", str(tmp_path / "a.npy"), "--labels", "7", "-o", f"{tmp_path / 'new'}/",
                 "--suffix", ".ply"]) == 2
    assert "none of the labels asked for occur" in capsys.readouterr().err.strip().splitlines()[-1]
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize("command", ["info", "surface"])
def test_a_directory_given_with_labels_is_said_to_be_one(tmp_path, capsys, command):
    """`info DIR --labels` said "not a volume file" where `info DIR` says
    the path is a directory: the same one line with --labels or without,
    for surface too."""
    (tmp_path / "adir").mkdir()
    one, every = ([], []) if command == "info" else (["-o", tmp_path / "s.ply"], ["-o", f"{tmp_path}/s/", "--suffix", "ply"])
    for argv in ([*one], [*every, "--labels"]):
        code, out, err = said(capsys, command, tmp_path / "adir", *argv)
        assert (code, out, err) == (2, "", [f"isoflow {command}: error: {tmp_path / 'adir'}: is a directory, not a "
                                            "volume or point list"]), argv


def test_an_image_without_voxels_gets_the_empty_table_as_label_table_does(tmp_path, capsys):
    """A zero-size array (0x3x3) holds no voxel, so no label: info gave its
    empty report and isoflow.label_table its empty table, while info
    --labels refused it. It gets the table of no row, as an all-0 image
    does: a warning line saying why, [] in --json, the header alone in
    --csv; a choice of labels none of which can occur is refused, and
    surface --labels, with no surface to write, says why."""
    empty = np.zeros((0, 3, 3), np.uint8)
    np.save(tmp_path / "none.npy", empty)
    none = tmp_path / "none.npy"
    assert all(len(column) == 0 for column in label_table(empty).values())  # the Python answer
    code, out, err = said(capsys, "info", none, "--labels")
    assert code == 0 and "0 labels, shape 0x3x3" in out.splitlines()[0]
    assert err == [f"isoflow info: warning: {none}: the image has no voxels (shape 0x3x3); the table has no row"]
    assert json.loads(run(capsys, "info", none, "--labels", "--json"))["labels"] == []
    header, *rows = run(capsys, "info", none, "--labels", "--csv", "-").splitlines()
    assert rows == [] and header.split(",") == list(label_table(empty))
    fails(capsys, "info", none, "--labels=3", words=("none of the labels asked for occur (3)", "has no voxels"))
    fails(capsys, "surface", none, "--labels", "-o", f"{tmp_path}/s/", "--suffix", "ply",
          words=("none.npy: the image has no voxels (shape 0x3x3)",))


#: ``python -c`` code running the command line with trimesh's import
#: watched: which thread begins it (a line on stderr), and, where
#: ``sys.argv[1]`` is not 0, the import held up that many seconds halfway
#: (``trimesh`` half made, ``trimesh.util`` about to run) on a thread other
#: than the main one, the hold marked by the file ``sys.argv[2]`` (held in
#: the module's run, not in the finder, which runs under the lock every
#: import takes)
WATCHED_TRIMESH = """\
import importlib.machinery, sys, threading, time
from pathlib import Path

slow, marker = float(sys.argv[1]), Path(sys.argv[2])

class Held:
    def __init__(self, loader):
        self.loader = loader

    def create_module(self, spec):
        return self.loader.create_module(spec)

    def exec_module(self, module):
        marker.touch()
        time.sleep(slow)
        self.loader.exec_module(module)

class Watch:
    def find_spec(self, name, path=None, target=None):
        main = threading.current_thread() is threading.main_thread()
        if name == "trimesh":
            print("trimesh imported on the", "main thread" if main else "other thread", file=sys.stderr, flush=True)
        if name == "trimesh.util" and slow and not main:
            spec = importlib.machinery.PathFinder.find_spec(name, path, target)
            spec.loader = Held(spec.loader)
            return spec
        return None

sys.meta_path.insert(0, Watch())
from isoflow.cli import main
sys.exit(main(sys.argv[3:]))
"""


def watched(tmp_path, *args, slow=0.0):
    """A command run under :data:`WATCHED_TRIMESH`, its output read when it ends."""
    return subprocess.run([sys.executable, "-c", WATCHED_TRIMESH, str(slow), str(tmp_path / "held"), *map(str, args)],
                          capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("target", ["glb", "dir"])
def test_surface_labels_imports_trimesh_while_the_labels_are_meshed(tmp_path, segmentation, target):
    """trimesh, for the read-back, is imported on a thread of its own as
    the labels are meshed, not on the main thread after they are written
    (a share of the command's time); with --no-check it is not imported;
    and the read-back, held up until the import is whole, still reads every
    label's surface back (a package half made on the other thread would
    fail the main thread's ``from trimesh.exchange.gltf import``)."""
    np.save(tmp_path / "seg.npy", segmentation)
    labels = np.unique(segmentation[segmentation > 0]).size  # NumPy's count
    out = ["-o", tmp_path / "seg.glb"] if target == "glb" else ["-o", f"{tmp_path}/seg/", "--suffix", ".obj"]
    for slow in (0.0, 2.0):
        p = watched(tmp_path, "surface", tmp_path / "seg.npy", "--labels", *out, "--force", slow=slow)
        assert p.returncode == 0, p.stderr
        assert without_compile_note(p.stderr).splitlines() == ["trimesh imported on the other thread"]
        assert f"{labels} labels" in p.stdout and "each read back by trimesh as isoflow counts it" in p.stdout
    assert (tmp_path / "held").exists()  # the held-up import was the other thread's
    p = watched(tmp_path, "surface", tmp_path / "seg.npy", "--labels", *out, "--force", "--no-check")
    assert (p.returncode, without_compile_note(p.stderr)) == (0, "")


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals")
def test_a_signal_while_the_read_back_waits_for_trimesh_ends_the_command(tmp_path, segmentation):
    """SIGTERM while the read-back waits for trimesh's import on the other
    thread (held up for minutes here) ends the command at once as any
    signal during the read-back does (128 + 15, the file named as written,
    not read back): the wait is interrupted, and the importing thread does
    not hold up the exit."""
    import signal
    import time

    np.save(tmp_path / "seg.npy", segmentation)
    glb = tmp_path / "seg.glb"
    proc = subprocess.Popen([sys.executable, "-c", WATCHED_TRIMESH, "600", str(tmp_path / "held"), "surface",
                             str(tmp_path / "seg.npy"), "--labels", "-o", str(glb)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        for _ in range(1200):  # the import held up, and the file in place (the main thread then waits)
            if (tmp_path / "held").exists() and glb.exists() or proc.poll() is not None:
                break
            time.sleep(0.05)
        time.sleep(0.5)
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == 128 + signal.SIGTERM, err
    assert err.splitlines()[-1] == f"isoflow: terminated: {glb} is written, not read back (--no-check skips the read-back)"
    assert trimesh.load(glb).geometry  # the whole file, as written


def test_labels_of_a_channel_axis_of_one_entry(capsys, tmp_path):
    """A 3D segmentation saved with a last axis of one entry (ilastik's HDF5
    export, (z, y, x, 1); an .npy of (X, Y, Z, 1)) holds one 3D label image:
    ``info --labels`` gives its table, each row scikit-image's area, box and
    Euler number of that 3D image (no time series to pick a point of)."""
    h5py = pytest.importorskip("h5py")
    from skimage.measure import regionprops

    image = np.zeros((9, 8, 7), np.uint8)
    image[1:4, 1:4, 1:4] = 1
    image[4:7, 1:4, 1:4] = 2  # touches label 1 by a face
    image[2:8, 4:8, 1:6] = 3
    image[4:6, 5:7, 2:4] = 0  # a cavity in label 3
    with h5py.File(tmp_path / "seg.h5", "w") as f:
        f["exported_data"] = image[..., None]
    np.save(tmp_path / "seg.npy", image[..., None])
    expected = {p.label: p for p in regionprops(image)}
    for name in ("seg.h5", "seg.npy"):
        code, out, err = said(capsys, "info", tmp_path / name, "--labels", "--json", "--connectivity", "26")
        assert code == 0, err
        report = json.loads(out)
        assert report["shape"] == list(image.shape)
        assert [row["label"] for row in report["labels"]] == sorted(expected)
        for row in report["labels"]:
            prop = expected[row["label"]]
            assert row["voxels"] == prop.area
            assert [row[f"bbox-{i}"] for i in range(6)] == list(prop.bbox)
            assert row["euler_characteristic"] == prop.euler_number


def test_a_long_choice_of_labels_takes_the_background(capsys, tmp_path, rng, monkeypatch):
    """A choice of more labels than the table is asked for label by label
    (a range of millions) that holds 0 gives the background's row, as a
    short one does, in a file and in a zarr store read block by block: its
    voxels are the image's zeros, its Euler number scikit-image's, and 0 is
    not called absent. The table is made in one pass over the image (it
    was made twice: every label's, then the background's alone)."""
    from skimage.measure import euler_number

    from isoflow.digital import label_blocks
    from isoflow.digital import label_table as tables

    passes = []

    def counted(real):
        def table(*args, **kwargs):
            passes.append(real.__name__)
            return real(*args, **kwargs)
        return table

    monkeypatch.setattr(tables, "label_table", counted(tables.label_table))
    monkeypatch.setattr(label_blocks, "label_table_blocks", counted(label_blocks.label_table_blocks))

    image = rng.choice([0, 1, 2, 7], size=(12, 11, 10), p=[0.4, 0.2, 0.2, 0.2]).astype(np.uint32)
    np.save(tmp_path / "seg.npy", image)
    paths = [tmp_path / "seg.npy"]
    zarr = pytest.importorskip("zarr")
    store = zarr.create_array(tmp_path / "seg.zarr", shape=image.shape, chunks=(5, 4, 3), dtype=image.dtype)
    store[:] = image
    paths.append(tmp_path / "seg.zarr")
    background = image == 0
    for path, made_by in zip(paths, ["label_table", "label_table_blocks"]):
        passes.clear()
        code, out, err = said(capsys, "info", path, "--labels", "0-200000", "--json", "--connectivity", "26")
        assert code == 0, err
        assert passes == [made_by]
        report = json.loads(out)
        assert [row["label"] for row in report["labels"]] == [0, 1, 2, 7]
        assert 0 not in report["absent"] and len(report["absent"]) == 200001 - 4
        row = report["labels"][0]
        assert row["voxels"] == np.count_nonzero(background)
        assert row["euler_characteristic"] == euler_number(background, connectivity=3)


def test_surface_labels_force_leaves_names_past_every_64_bit_label(tmp_path, capsys):
    """``label_N`` files whose N no 64-bit integer type holds (2**64 and
    past, below -2**63) are names this command never writes, so a --force
    run of every label keeps them; ``label_18446744073709551615.ply``
    (uint64's largest, an earlier run's of another image) goes."""
    out = tmp_path / "out"
    out.mkdir()
    theirs = {f"label_{v}.ply": str(v).encode() for v in
              (int(np.iinfo(np.uint64).max) + 1, int(np.iinfo(np.int64).min) - 1, 10**30)}
    for name, data in theirs.items():
        (out / name).write_bytes(data)
    (out / f"label_{np.iinfo(np.uint64).max}.ply").write_bytes(b"an earlier run's")
    image = np.zeros((4, 4, 4), np.uint8)
    image[1:3, 1:3, 1:3] = 1
    np.save(tmp_path / "seg.npy", image)
    assert main(["surface", str(tmp_path / "seg.npy"), "--labels", "-o", f"{out}/", "--suffix", "ply", "--force"]) == 0
    capsys.readouterr()
    assert files_in(out) == {**theirs, "label_1.ply": files_in(out)["label_1.ply"]}


def test_labels_of_a_zarr_store_with_a_last_axis_of_one_entry(capsys, tmp_path):
    """A zarr array of shape (X, Y, Z, 1), read block by block by ``info
    --labels``, was refused as a time series, while the same labels in an
    .npy of that shape are read as 3D: the store's table is the .npy's
    (each row scikit-image's area of the 3D image), placed by the store's
    pitch and origin attributes without their fourth entries."""
    zarr = pytest.importorskip("zarr")
    from skimage.measure import regionprops

    image = np.zeros((20, 18, 16), np.uint8)
    image[3:10, 4:12, 5:9] = 1
    image[12:17, 2:8, 2:14] = 2
    image[13:16, 3:7, 4:8] = 0  # a cavity in label 2
    store = zarr.create_array(str(tmp_path / "seg.zarr"), shape=image.shape + (1,), chunks=(8, 8, 8, 1),
                              dtype=image.dtype)
    store[...] = image[..., None]
    np.save(tmp_path / "seg.npy", image[..., None])
    reports = {}
    for name in ("seg.zarr", "seg.npy"):
        code, out, err = said(capsys, "info", tmp_path / name, "--labels", "--json")
        assert code == 0, err
        reports[name] = json.loads(out)
        assert reports[name]["shape"] == list(image.shape)
        assert [(row["label"], row["voxels"]) for row in reports[name]["labels"]] == [
            (p.label, p.area) for p in regionprops(image)]
    assert reports["seg.zarr"]["labels"] == reports["seg.npy"]["labels"]
    store.attrs.update(pitch=[0.5, 0.5, 2.0, 1.0], origin=[1.0, 2.0, 3.0, 0.0])
    code, out, err = said(capsys, "info", tmp_path / "seg.zarr", "--labels", "--json")
    assert code == 0, err
    report = json.loads(out)
    assert (report["pitch"], report["origin"]) == ([0.5, 0.5, 2.0], [1.0, 2.0, 3.0])
    assert [row["volume"] for row in report["labels"]] == [p.area * 0.5 for p in regionprops(image)]


@pytest.mark.parametrize("name", ["x1.zarr", "x1.npy", "x1.h5"])
def test_one_label_of_a_last_axis_of_one_entry_is_3d(tmp_path, name):
    """``info X1 --label 1`` and ``surface X1 --label 1`` of labels of shape
    (X, Y, Z, 1) read the label image as ``info --labels`` does, in 3D
    (a zarr store block by block too): ``info`` reported a 4D volume one
    voxel thick with b1 and b2 unknown, and ``surface`` refused it as 4D.
    The report is scikit-image's Euler number and the voxels of the 3D
    mask, whose Betti numbers are ``analyze``'s of ``labels[..., 0] == 1``;
    the surface reads back in trimesh closed, two spheres around the
    label's volume."""
    from skimage.measure import euler_number

    labels = np.zeros((9, 8, 7, 1), np.uint8)
    labels[1:6, 1:6, 1:6, 0] = 1
    labels[3, 3, 3, 0] = 0  # a cavity: b2 = 1, which a 4D report does not count
    labels[7, 5:7, 2:5, 0] = 2
    mask = labels[..., 0] == 1
    pitch = [1.0, 1.0, 1.0]
    path = tmp_path / name
    if name.endswith(".zarr"):  # read block by block, placed by its attributes without their fourth entries
        zarr = pytest.importorskip("zarr")
        store = zarr.create_array(str(path), shape=labels.shape, chunks=(4, 4, 4, 1), dtype=labels.dtype)
        store[...] = labels
        pitch = [0.5, 0.5, 2.0]
        store.attrs.update(pitch=[*pitch, 1.0], origin=[0.0, 0.0, 0.0, 0.0])
    elif name.endswith(".h5"):
        h5py = pytest.importorskip("h5py")
        with h5py.File(path, "w") as f:
            f["labels"] = labels
    else:
        np.save(path, labels)
    done = isoflow_here("info", str(path), "--label", "1", "--json")
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["shape"] == list(mask.shape) and report["pitch"] == pitch
    assert report["voxels"] == np.count_nonzero(mask) == 124
    assert report["euler_characteristic"] == euler_number(mask, connectivity=1) == 2
    assert report["betti"] == analyze(mask)["betti"] == [1, 0, 1]
    assert report["volume"] == 124 * math.prod(pitch)
    out = tmp_path / "x1.stl"
    done = isoflow_here("surface", str(path), "--label", "1", "-o", str(out))
    assert done.returncode == 0, done.stderr
    mesh = trimesh.load(out)
    assert mesh.is_watertight and mesh.euler_number == 4 and len(mesh.split(only_watertight=True)) == 2
    assert mesh.volume == pytest.approx(124 * math.prod(pitch))


def test_info_labels_json_names_a_bool_image_as_its_uint8_labels(tmp_path, capsys):
    # docs/labels.md: a bool image is labels 0 and 1, read as uint8, in memory and from a store alike
    import zarr

    mask = np.zeros((4, 4, 4), bool)
    mask[1:3, 1:3, 1:3] = True
    np.save(tmp_path / "mask.npy", mask)
    store = zarr.create_array(str(tmp_path / "mask.zarr"), shape=mask.shape, chunks=(2, 4, 4), dtype=bool)
    store[...] = mask
    for name in ("mask.npy", "mask.zarr"):
        out = json.loads(run(capsys, "info", tmp_path / name, "--labels", "--json"))
        assert out["dtype"] == np.dtype(np.uint8).name
        assert [row["label"] for row in out["labels"]] == [1] and out["labels"][0]["voxels"] == mask.sum()


@pytest.mark.parametrize("suffix", [".nii.gz", ".zarr"])
def test_a_label_a_float_image_cannot_hold_selects_no_voxel(tmp_path, suffix):
    """--label 16777217 on a float32 label image picked the voxels of
    16777216: NumPy compares the array with the label rounded to float32.
    No voxel of the file holds 16777217 (NumPy in float64 says so); the
    command says so in one line, in memory and block by block alike."""
    nib = pytest.importorskip("nibabel")
    zarr = pytest.importorskip("zarr")
    image = np.zeros((6, 6, 6), np.float32)
    image[1:3, 1:3, 1:3] = 16777216.0
    image[4, 4, 4] = 5.0
    path = tmp_path / f"seg{suffix}"
    if suffix == ".zarr":
        zarr.create_array(str(path), shape=image.shape, chunks=(3, 3, 3), dtype="float32", fill_value=0)[...] = image
    else:
        nib.save(nib.Nifti1Image(image, np.eye(4)), path)
    assert np.count_nonzero(image.astype(np.float64) == 16777217) == 0
    assert np.count_nonzero(image == 16777217) == 8  # the rounding the command made
    for command in (["info", path], ["surface", path, "-o", tmp_path / "s.ply"]):
        done = isoflow_here(*map(str, command), "--label", "16777217")
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
        assert f"{path.name}: no voxel has label 16777217: a float32 array cannot hold it" in lines[0], lines
        assert "16777216" in lines[0], lines
    assert not (tmp_path / "s.ply").exists()
    done = isoflow_here("info", str(path), "--label", "16777216", "--json")
    assert done.returncode == 0 and json.loads(done.stdout)["voxels"] == np.count_nonzero(image == 16777216.0)


def test_a_segmentation_named_without_or_past_its_labels_group_is_offered_by_name(tmp_path, segmentation):
    """``image.zarr:cells`` (without ``labels/``) listed the image's levels
    alone, and ``image.zarr:labels/cell`` said "its arrays: []" of the
    labels/ group, whose segmentations are groups: neither named the
    segmentation the store holds. Each line now names it as it is read
    (the groups zarr lists under labels/), exit 2, one line."""
    zarr = pytest.importorskip("zarr")
    zyx = np.ascontiguousarray(segmentation.transpose(2, 1, 0))
    axes = [{"name": a, "type": "space"} for a in "zyx"]
    root = zarr.open_group(str(tmp_path / "image.zarr"), mode="w", zarr_format=2)
    for group, data in ((root, (zyx > 0).astype(np.uint8)), (root.require_group("labels/cells"), zyx)):
        group.create_array("0", data=data, chunks=(5, 5, 5))
        group.attrs["multiscales"] = [{"version": "0.4", "axes": axes, "datasets": [{"path": "0", "coordinateTransformations": [
            {"type": "scale", "scale": [1.0, 1.0, 1.0]}]}]}]
    root["labels"].attrs["labels"] = ["cells"]
    assert [name for name, _ in zarr.open_group(str(tmp_path / "image.zarr"), mode="r")["labels"].groups()] == ["cells"]
    store = tmp_path / "image.zarr"
    for name, words in (("cells", ("no resolution level 'cells'", f"its segmentations: {store}:labels/cells")),
                        ("labels/cell", ("no array or group 'cell'", f"its groups: ['cells']; name one, "
                                                                     f"{store}:labels/cells"))):
        done = isoflow_here("info", f"{store}:{name}", "--labels")
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
        for word in words:
            assert word in lines[0], (word, lines[0])
    done = isoflow_here("info", f"{store}:labels/cells", "--labels", "--json")
    assert done.returncode == 0 and [r["voxels"] for r in json.loads(done.stdout)["labels"]] == [
        np.count_nonzero(segmentation == v) for v in np.unique(segmentation) if v]


def test_every_line_of_surface_labels_names_its_directory_as_dir_slash(tmp_path):
    """``surface --labels --ascii --suffix .stl -o d2`` (d2 a directory)
    was refused naming ``d2``, and a run's float64 warning named ``out``,
    where the run's summary and its other lines name the directory of a
    file per label ``d2/``, as ``-o DIR/`` is written. From the shell each
    names it DIR/, however -o gave it."""
    import isoflow

    isoflow.write_labels(boxes([2, 3]), tmp_path / "lab.npz", pitch=1e-9, origin=(1e6, 0.0, 0.0))
    (tmp_path / "d2").mkdir()

    def surface(*args):
        return subprocess.run([sys.executable, "-m", "isoflow", "surface", "lab.npz", "--labels", *args],
                              capture_output=True, text=True, cwd=tmp_path)

    for given in ("d2", "d2/", "new/"):
        p = surface("--ascii", "--suffix", ".stl", "-o", given)
        assert p.returncode == 2 and p.stderr.splitlines() == [
            f"isoflow surface: error: {given.rstrip('/')}/: --ascii applies to .ply files only, not --suffix .stl"]
    p = surface("-o", "d2")
    assert p.returncode == 2 and p.stderr.startswith("isoflow surface: error: d2/: a file per label needs --suffix")
    assert not (tmp_path / "new").exists() and not any((tmp_path / "d2").iterdir())
    p = surface("-o", "d2", "--suffix", ".ply")
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("d2/ (2 .ply files): 2 labels"), p.stdout
    warned = [line for line in p.stderr.splitlines() if "float64 holds the voxel corners" in line]
    assert len(warned) == 1 and warned[0].startswith("isoflow surface: warning: d2/: float64 holds"), p.stderr
    for k in (1, 2):  # a box each: a closed surface, V - E + F = 2
        mesh = trimesh.load(tmp_path / "d2" / f"label_{k}.ply", process=False)
        assert mesh.is_watertight and mesh.euler_number == 2


def test_surface_labels_files_name_their_input_by_its_file_name_as_surface_does(tmp_path, capsys, segmentation):
    # the scene's record held the input as given, its whole directory path with it (/home/.../seg.npy),
    # where every other file names the input's file alone
    import struct

    np.save(tmp_path / "seg.npy", segmentation)
    run(capsys, "surface", tmp_path / "seg.npy", "--labels", "4,9", "--connectivity", "26", "-o", tmp_path / "s.glb")
    data = (tmp_path / "s.glb").read_bytes()
    size = struct.unpack("<I", data[12:16])[0]  # the glTF JSON chunk (glTF 2.0 binary container)
    records = {m["extras"]["isoflow"] for m in json.loads(data[20:20 + size])["meshes"]}
    assert records == {"isoflow surface --labels of seg.npy, 26-connectivity"}
