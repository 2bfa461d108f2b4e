"""A DigitalObject carries the length unit of its voxel size and origin:
read_volume sets it from the file (as the format's own library wrote it:
nibabel's xyzt units, pynrrd's space units), every step that keeps the
object's place keeps it, and write_volume writes it, as nibabel reads it
back."""


import numpy as np
import pytest
from in_process import isoflow_here

import isoflow
from isoflow import DigitalObject, IsoflowError, read_object, read_volume, run_flow, write_volume

MICRO = "\u00b5m"


def ball_nifti(path, unit: str) -> None:
    """A 9^3 box of 0/1 bytes with a solid 5^3 cube, voxels 0.5 x 0.5 x 2
    in ``unit``, written by nibabel."""
    nib = pytest.importorskip("nibabel")
    vol = np.zeros((9, 9, 9), np.uint8)
    vol[2:7, 2:7, 2:7] = 1
    img = nib.Nifti1Image(vol, np.diag([0.5, 0.5, 2.0, 1.0]))
    img.header.set_xyzt_units(unit)
    nib.save(img, path)


@pytest.mark.parametrize("xyzt, unit", [("mm", "mm"), ("micron", MICRO), ("meter", "m")])
def test_read_volume_gives_the_nifti_headers_unit(tmp_path, xyzt, unit):
    ball_nifti(tmp_path / "scan.nii.gz", xyzt)
    assert read_volume(tmp_path / "scan.nii.gz").unit == unit
    assert read_object(tmp_path / "scan.nii.gz").unit == unit


def test_a_nifti_that_says_no_unit_gives_none(tmp_path):
    ball_nifti(tmp_path / "scan.nii.gz", "unknown")
    assert read_volume(tmp_path / "scan.nii.gz").unit is None


def test_the_object_read_is_written_with_its_unit(tmp_path):
    nib = pytest.importorskip("nibabel")
    ball_nifti(tmp_path / "scan.nii.gz", "mm")
    write_volume(read_volume(tmp_path / "scan.nii.gz"), tmp_path / "o.nii.gz")
    assert nib.load(tmp_path / "o.nii.gz").header.get_xyzt_units()[0] == "mm"


def test_a_unit_given_to_the_writer_replaces_the_objects(tmp_path):
    nib = pytest.importorskip("nibabel")
    ball_nifti(tmp_path / "scan.nii.gz", "mm")
    write_volume(read_volume(tmp_path / "scan.nii.gz"), tmp_path / "o.nii.gz", unit="micron")
    assert nib.load(tmp_path / "o.nii.gz").header.get_xyzt_units()[0] == "micron"


def test_a_unit_given_by_the_user_is_held_in_isoflows_spelling_and_written(tmp_path):
    nrrd = pytest.importorskip("nrrd")
    obj = DigitalObject(np.ones((2, 3, 4), bool), pitch=0.5, unit="micrometre")
    assert obj.unit == MICRO and f"unit={MICRO!r}" in repr(obj)
    write_volume(obj, tmp_path / "o.nrrd")
    # the NRRD writer spells \u00b5m "um", as ImageJ does
    assert nrrd.read_header(str(tmp_path / "o.nrrd"))["space units"] == ["um"] * 3


def test_every_state_of_the_flow_keeps_the_unit(tmp_path):
    ball_nifti(tmp_path / "scan.nii.gz", "mm")
    result = run_flow(read_volume(tmp_path / "scan.nii.gz"))
    assert len(result.states) > 1  # the cube shrinks over several steps
    assert {state.unit for state in result.states} == {"mm"}
    assert {state.cropped().unit for state in result.states} == {"mm"}


def test_the_flows_step_volumes_are_written_with_the_unit(tmp_path):
    nib = pytest.importorskip("nibabel")
    ball_nifti(tmp_path / "scan.nii.gz", "micron")
    done = isoflow_here("flow", str(tmp_path / "scan.nii.gz"), "--out",
                           str(tmp_path / "run"), "--volumes", ".nii.gz", "--no-check")
    assert done.returncode == 0, done.stderr
    steps = sorted((tmp_path / "run").glob("step_*.nii.gz"))
    assert steps and {nib.load(p).header.get_xyzt_units()[0] for p in steps} == {"micron"}


def test_an_nrrd_of_a_unit_isoflow_cannot_write_flows_with_its_step_volumes(tmp_path):
    # NRRD's space units are free text: the object does not carry one that no
    # writer spells, and the step volumes are written without it
    nrrd = pytest.importorskip("nrrd")
    vol = np.zeros((7, 7, 7), np.uint8)
    vol[1:6, 1:6, 1:6] = 1
    nrrd.write(str(tmp_path / "f.nrrd"), vol, {"space dimension": 3, "space directions": np.eye(3),
                                               "space units": ["furlong"] * 3})
    assert read_volume(tmp_path / "f.nrrd").unit is None
    done = isoflow_here("flow", str(tmp_path / "f.nrrd"), "--out",
                           str(tmp_path / "run"), "--volumes", ".nrrd", "--no-check")
    assert done.returncode == 0, done.stderr
    steps = sorted((tmp_path / "run").glob("step_*.nrrd"))
    assert steps and all("space units" not in nrrd.read_header(str(p)) for p in steps)


def test_a_voxelised_mesh_and_an_array_have_no_unit():
    trimesh = pytest.importorskip("trimesh")
    assert isoflow.voxelize_mesh(trimesh.creation.box(), pitch=0.25).unit is None
    obj = DigitalObject(np.ones((3, 3, 3), bool))
    assert obj.unit is None and "unit" not in repr(obj)
    assert DigitalObject.of(np.ones((3, 3), bool)).unit is None


@pytest.mark.parametrize("unit", ["furlong", "pixel", 3])
def test_a_unit_that_is_no_length_is_refused_in_one_line(unit):
    with pytest.raises(IsoflowError, match="is not a length unit") as exc:
        DigitalObject(np.ones((2, 2, 2), bool), unit=unit)
    assert repr(unit) in str(exc.value) and "\n" not in str(exc.value)
