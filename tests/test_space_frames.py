"""Left and right between volume formats: a volume keeps its anatomical
frame (NIfTI's and MGH's RAS, a NRRD's ``space``), and every writer puts
each voxel at the same anatomical place in its own format's frame. The
expected places come from the other libraries (pynrrd's header: origin
plus the space directions times the index; nibabel's affine), with the
one relation between the two frames: LPS x and y are RAS x and y negated."""

import json
import warnings

import numpy as np
import pytest

import isoflow
from isoflow import DigitalObject, IsoflowError
from isoflow.cli import main

nrrd = pytest.importorskip("nrrd")
nib = pytest.importorskip("nibabel")

#: where a point in LPS is in RAS: x and y negated
LPS_TO_RAS = np.array([-1.0, -1.0, 1.0])
SHAPE = (5, 6, 7)
#: one voxel, off every symmetry of the array (a mirror moves it)
VOXEL = (1, 2, 4)


def run(capsys, *args):
    assert main([*map(str, args)]) == 0, capsys.readouterr().err
    return capsys.readouterr().out


def lps_nrrd(path, directions, values=None):
    """A NRRD in 3D Slicer's frame, one voxel set (or ``values``), and the
    LPS position of that voxel's centre as pynrrd's header gives it."""
    origin = np.array([12.5, -31.25, 47.0])
    if values is None:
        values = np.zeros(SHAPE, np.uint8)
        values[VOXEL] = 1
    nrrd.write(str(path), values, {"space": "left-posterior-superior", "space directions": directions,
                                   "space origin": origin, "kinds": ["domain"] * 3}, index_order="F")
    _, header = nrrd.read(str(path), index_order="F")
    return header["space origin"] + np.asarray(VOXEL) @ header["space directions"]


#: Slicer's usual axes, and one that runs backwards (its array is flipped on reading)
DIRECTIONS = {"diagonal": np.diag([0.5, 0.75, 2.0]), "x backwards": np.diag([-0.5, 0.75, 2.0])}


def nibabel_place(path):
    """The world (RAS) position of the one set voxel's centre, by nibabel."""
    img = nib.load(str(path))
    ijk = np.argwhere(np.asanyarray(img.dataobj) != 0)
    assert len(ijk) == 1
    return nib.affines.apply_affine(img.affine, ijk[0])


@pytest.mark.parametrize("suffix", [".nii.gz", ".mgz"])
@pytest.mark.parametrize("axes", DIRECTIONS)
def test_an_lps_nrrd_written_as_nifti_or_mgh_keeps_the_anatomy(tmp_path, suffix, axes):
    lps = lps_nrrd(tmp_path / "scan.nrrd", DIRECTIONS[axes])
    obj = isoflow.read_volume(tmp_path / "scan.nrrd")
    out = isoflow.write_volume(obj, tmp_path / f"scan{suffix}")
    assert np.allclose(nibabel_place(out), lps * LPS_TO_RAS)
    assert nib.aff2axcodes(nib.load(str(out)).affine) == ("L", "P", "S")
    assert (obj.space, isoflow.read_volume(out).space) == ("LPS", "RAS")


def test_a_ras_nifti_written_as_nrrd_states_its_space(tmp_path):
    # stored LAS (x backwards), as many scanners store it, off the origin
    affine = np.array([[-0.5, 0, 0, 40.25], [0, 0.75, 0, -12.5], [0, 0, 2.0, 7.0], [0, 0, 0, 1]])
    values = np.zeros(SHAPE, np.uint8)
    values[VOXEL] = 1
    nib.save(nib.Nifti1Image(values, affine), str(tmp_path / "scan.nii.gz"))
    ras = nibabel_place(tmp_path / "scan.nii.gz")
    obj = isoflow.read_volume(tmp_path / "scan.nii.gz")
    out = isoflow.write_volume(obj, tmp_path / "scan.nrrd")
    data, header = nrrd.read(str(out), index_order="F")
    ijk = np.argwhere(data)
    assert len(ijk) == 1
    assert np.allclose(header["space origin"] + ijk[0] @ header["space directions"], ras)
    assert header.get("space") == "right-anterior-superior"
    assert obj.space == "RAS"


def test_an_lps_nrrd_written_as_nrrd_stays_lps(tmp_path):
    lps = lps_nrrd(tmp_path / "scan.nrrd", DIRECTIONS["x backwards"])
    out = isoflow.write_volume(isoflow.read_volume(tmp_path / "scan.nrrd"), tmp_path / "copy.nrrd")
    data, header = nrrd.read(str(out), index_order="F")
    ijk = np.argwhere(data)
    assert np.allclose(header["space origin"] + ijk[0] @ header["space directions"], lps)
    assert header.get("space") == "left-posterior-superior"


def test_info_json_reports_the_frame(tmp_path, capsys):
    lps_nrrd(tmp_path / "scan.nrrd", DIRECTIONS["diagonal"])
    nib.save(nib.Nifti1Image(np.ones((2, 2, 2), np.uint8), np.eye(4)), str(tmp_path / "ras.nii.gz"))
    np.save(tmp_path / "none.npy", np.ones((2, 2, 2), np.uint8))
    frames = {name: json.loads(run(capsys, "info", tmp_path / name, "--json"))["space"]
              for name in ("scan.nrrd", "ras.nii.gz", "none.npy")}
    assert frames == {"scan.nrrd": "LPS", "ras.nii.gz": "RAS", "none.npy": None}
    assert json.loads(run(capsys, "info", tmp_path / "scan.nrrd", "--labels", "--json"))["space"] == "LPS"
    assert "frame LPS" in run(capsys, "info", tmp_path / "scan.nrrd")


def test_flow_volumes_of_an_lps_nrrd_are_ras_correct_nifti(tmp_path, capsys):
    values = np.zeros(SHAPE, np.uint8)
    values[1:4, 2:5, 3:6] = 1
    values[VOXEL] = 1  # a bump on the box's side: the step that follows removes it, the input keeps it
    lps_nrrd(tmp_path / "scan.nrrd", DIRECTIONS["diagonal"], values)
    _, header = nrrd.read(str(tmp_path / "scan.nrrd"), index_order="F")
    places = header["space origin"] + np.argwhere(values) @ header["space directions"]
    run(capsys, "flow", tmp_path / "scan.nrrd", "--steps", "1", "--out", tmp_path / "run", "--volumes", ".nii.gz")
    first = nib.load(str(tmp_path / "run" / "step_000.nii.gz"))
    written = nib.affines.apply_affine(first.affine, np.argwhere(np.asanyarray(first.dataobj)))
    assert sorted(map(tuple, np.round(written, 9))) == sorted(map(tuple, np.round(places * LPS_TO_RAS, 9)))
    assert nib.aff2axcodes(nib.load(str(tmp_path / "run" / "step_001.nii.gz")).affine) == ("L", "P", "S")


def test_flow_json_reports_the_frame(tmp_path, capsys):
    """``flow --json`` names the frame of its world coordinates (its
    ``bbox``, ``limit.center``), as ``info --json`` does: the NRRD's own
    ``space``, and null for a ``.npy``."""
    values = np.zeros(SHAPE, np.uint8)
    values[1:4, 1:5, 1:6] = 1
    lps_nrrd(tmp_path / "box.nrrd", DIRECTIONS["diagonal"], values)
    np.save(tmp_path / "box.npy", values.astype(bool))
    _, header = nrrd.read(str(tmp_path / "box.nrrd"))
    assert header["space"] == "left-posterior-superior"
    assert json.loads(run(capsys, "flow", tmp_path / "box.nrrd", "--steps", "1", "--json"))["space"] == "LPS"
    assert json.loads(run(capsys, "flow", tmp_path / "box.npy", "--steps", "1", "--json"))["space"] is None


def test_write_labels_of_an_lps_label_image_keeps_the_anatomy(tmp_path):
    values = np.zeros(SHAPE, np.uint8)
    values[0, 0, 0] = 1
    values[VOXEL] = 2
    lps = lps_nrrd(tmp_path / "seg.nrrd", DIRECTIONS["x backwards"], values)
    image = isoflow.read_labels(tmp_path / "seg.nrrd")
    out = isoflow.write_labels(image, tmp_path / "seg.nii.gz")
    img = nib.load(str(out))
    ijk = np.argwhere(np.asanyarray(img.dataobj) == 2)
    assert np.allclose(nib.affines.apply_affine(img.affine, ijk[0]), lps * LPS_TO_RAS)
    assert image.space == "LPS"


def test_a_format_without_a_frame_says_it_is_not_written(tmp_path):
    obj = DigitalObject(np.ones((2, 2, 2), bool), space="lps")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        isoflow.write_volume(obj, tmp_path / "a.tif")
        isoflow.write_volume(DigitalObject(np.ones((2, 2, 2), bool)), tmp_path / "b.tif")
    assert [str(w.message).split(";")[0] for w in caught] == [f"{tmp_path / 'a.tif'}: TIFF keeps no anatomical frame"]


@pytest.mark.parametrize("suffix", [".npz", ".h5"])
def test_isoflows_own_formats_keep_the_frame_for_a_later_nifti(tmp_path, suffix):
    """An LPS NRRD kept as ``.npz`` or ``.h5`` between two runs, then
    written as NIfTI: the same anatomy as written straight away."""
    lps = lps_nrrd(tmp_path / "scan.nrrd", DIRECTIONS["diagonal"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing is lost on the way
        kept = isoflow.write_volume(isoflow.read_volume(tmp_path / "scan.nrrd"), tmp_path / f"scan{suffix}")
    again = isoflow.read_volume(kept)
    assert again.space == "LPS"
    out = isoflow.write_volume(again, tmp_path / "scan.nii.gz")
    assert np.allclose(nibabel_place(out), lps * LPS_TO_RAS)


def test_a_space_that_is_no_anatomical_frame_is_refused():
    with pytest.raises(IsoflowError, match="space 'RSA' is not an anatomical frame"):
        DigitalObject(np.ones((2, 2, 2), bool), space="RSA")
