"""The length unit of a volume, written: ``write_volume(..., unit=)``,
``write_labels`` of a LabelImage (or with ``unit=``) and ``isoflow flow
--volumes`` keep it where the format holds one, as the format's own
library reads it back (nibabel's xyzt units, ImageJ's description through
tifffile, pynrrd's space units, h5py's attributes, the NGFF axes through
zarr), and isoflow's readers give it back."""

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import isoflow
from isoflow import DigitalObject, IsoflowError, read_labels, write_labels, write_volume
from isoflow.mesh.volumes import read_volume_with_unit

MICRO = "\u00b5m"
PITCH = (0.5, 0.75, 1.25)  # exact in float32 (NIfTI) and as TIFF rationals


def box() -> DigitalObject:
    vol = np.zeros((6, 5, 4), bool)
    vol[1:5, 1:4, 1:3] = True
    return DigitalObject(vol, pitch=PITCH, origin=(2.0, -3.0, 4.0))


def labels() -> np.ndarray:
    lab = np.zeros((6, 5, 4), np.uint8)
    lab[1:3, 1:4, 1:3] = 1
    lab[4:6, 1:4, 1:3] = 2
    return lab


def written(path, unit, **kwargs) -> list[str]:
    """The warnings of ``write_volume(box(), path, unit=unit)``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        write_volume(box(), path, unit=unit, **kwargs)
    return [str(w.message) for w in caught]


# ------------------------------------------------------------------ NIfTI

@pytest.mark.parametrize("given, xyzt, unit", [("mm", "mm", "mm"), ("millimetre", "mm", "mm"), ("micron", "micron", MICRO),
                                                ("micrometer", "micron", MICRO), (MICRO, "micron", MICRO),
                                                ("meter", "meter", "m")])
def test_nifti_is_written_with_its_xyzt_unit(tmp_path, given, xyzt, unit):
    nib = pytest.importorskip("nibabel")
    path = tmp_path / "box.nii.gz"
    assert written(path, given) == []
    assert nib.load(path).header.get_xyzt_units()[0] == xyzt
    assert read_volume_with_unit(path)[1] == unit


def test_nifti_without_a_code_for_the_unit_says_so_and_keeps_the_voxel_size(tmp_path):
    # NIfTI-1's xyzt codes name metre, millimetre and micrometre only (nifti1.h: NIFTI_UNITS_METER/MM/MICRON)
    nib = pytest.importorskip("nibabel")
    path = tmp_path / "box.nii.gz"
    said = written(path, "cm")
    assert len(said) == 1 and str(path) in said[0] and "cm" in said[0]
    img = nib.load(path)
    assert img.header.get_xyzt_units()[0] == "unknown"
    assert np.allclose(img.header.get_zooms()[:3], PITCH)  # not rescaled into mm


def test_a_label_image_read_from_nifti_is_written_with_its_unit(tmp_path):
    nib = pytest.importorskip("nibabel")
    img = nib.Nifti1Image(labels(), np.diag([*PITCH, 1.0]))
    img.header.set_xyzt_units("mm")
    nib.save(img, tmp_path / "seg.nii.gz")
    image = read_labels(tmp_path / "seg.nii.gz")
    write_labels(image, tmp_path / "copy.nii.gz")
    copy = nib.load(tmp_path / "copy.nii.gz")
    assert copy.header.get_xyzt_units()[0] == "mm"
    assert np.array_equal(np.asanyarray(copy.dataobj), labels())
    assert read_labels(tmp_path / "copy.nii.gz").unit == "mm"


def test_a_unit_given_replaces_the_label_images(tmp_path):
    nib = pytest.importorskip("nibabel")
    img = nib.Nifti1Image(labels(), np.diag([*PITCH, 1.0]))
    img.header.set_xyzt_units("mm")
    nib.save(img, tmp_path / "seg.nii.gz")
    write_labels(read_labels(tmp_path / "seg.nii.gz"), tmp_path / "copy.nii.gz", unit="micron")
    assert nib.load(tmp_path / "copy.nii.gz").header.get_xyzt_units()[0] == "micron"


@pytest.mark.parametrize("unit", ["pixel", "furlong", "", 3])
def test_a_unit_that_is_no_length_is_refused_naming_it(tmp_path, unit):
    with pytest.raises(IsoflowError, match="unit .* is not a length unit") as exc:
        write_volume(box(), tmp_path / "box.nii.gz", unit=unit)
    assert repr(unit) in str(exc.value) and "\n" not in str(exc.value)
    with pytest.raises(IsoflowError, match="is not a length unit"):
        write_labels(labels(), tmp_path / "seg.nii.gz", unit=unit)
    assert not os.listdir(tmp_path)


# ------------------------------------------------------------------ TIFF, NRRD, HDF5, OME-Zarr, .npz

@pytest.mark.parametrize("given, imagej, unit", [("micron", "um", MICRO), ("mm", "mm", "mm"), ("nm", "nm", "nm")])
def test_imagej_tiff_is_written_with_its_unit(tmp_path, given, imagej, unit):
    # ImageJ's FileSaver.getDescriptionString writes unit=um for \u00b5m, any other unit as it is
    tifffile = pytest.importorskip("tifffile")
    path = tmp_path / "box.tif"
    assert written(path, given) == []
    with tifffile.TiffFile(path) as tif:
        assert tif.imagej_metadata["unit"] == imagej
    assert read_volume_with_unit(path)[1] == unit
    assert read_labels(write_labels(labels(), tmp_path / "seg.tif", unit=given)).unit == unit


@pytest.mark.parametrize("given, unit", [("micron", MICRO), ("mm", "mm"), ("inch", "in")])
def test_nrrd_is_written_with_its_space_units(tmp_path, given, unit):
    nrrd = pytest.importorskip("nrrd")
    path = tmp_path / "box.nrrd"
    assert written(path, given) == []
    header = nrrd.read_header(str(path))
    assert header["space units"] == [{MICRO: "um"}.get(unit, unit)] * 3
    assert read_volume_with_unit(path)[1] == unit


@pytest.mark.parametrize("given, unit", [("micron", MICRO), ("mm", "mm")])
def test_hdf5_is_written_with_its_unit(tmp_path, given, unit):
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "box.h5"
    assert written(path, given) == []
    with h5py.File(path, "r") as f:
        attrs = dict(f["volume"].attrs)
    assert attrs["unit"] == unit
    if unit == MICRO:  # Fiji's and ilastik's attribute: the voxel size per dataset axis in micrometres
        assert np.allclose(attrs["element_size_um"], PITCH)
    else:
        assert "element_size_um" not in attrs
    assert read_volume_with_unit(path)[1] == unit


@pytest.mark.parametrize("given, udunits, unit", [("micron", "micrometer", MICRO), ("mm", "millimeter", "mm"),
                                                   ("angstrom", "angstrom", "\u00c5")])
def test_ome_zarr_is_written_with_its_axis_units(tmp_path, given, udunits, unit):
    zarr = pytest.importorskip("zarr")
    path = tmp_path / "box.zarr"
    assert written(path, given) == []
    axes = zarr.open_group(str(path), mode="r").attrs["multiscales"][0]["axes"]
    assert [a["unit"] for a in axes] == [udunits] * 3
    assert read_volume_with_unit(path)[1] == unit
    assert read_labels(write_labels(labels(), tmp_path / "seg.zarr", unit=given)).unit == unit


def test_npz_is_written_with_its_unit(tmp_path):
    path = tmp_path / "box.npz"
    assert written(path, "millimeter") == []
    with np.load(path, allow_pickle=False) as z:
        assert str(z["unit"]) == "mm"
    assert read_volume_with_unit(path)[1] == "mm"


@pytest.mark.parametrize("suffix", [".npy", ".binvox", ".vox"])
def test_a_format_without_a_unit_says_it_is_not_kept(tmp_path, suffix):
    path = tmp_path / f"box{suffix}"
    obj = DigitalObject(box().volume, pitch=0.5) if suffix == ".binvox" else box()  # binvox: one voxel size
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        write_volume(obj, path, unit="mm")
    said = [str(w.message) for w in caught]
    assert any(str(path) in s and "unit" in s and "mm" in s for s in said), said
    assert read_volume_with_unit(path)[1] is None


def test_a_npy_names_a_far_origin_it_does_not_keep_to_a_fraction_of_a_voxel(tmp_path):
    """The warning of a .npy (every step of `flow --volumes .npy`) names
    the origin to put back by hand; at x = 123455.995 in voxels of 0.01 it
    said 123456, half a voxel off, and 1e+06 for 999999.98, voxels off."""
    import re

    given = np.array([123455.995, -654321.01, 999999.98])
    obj = DigitalObject(box().volume, pitch=(0.01, 0.02, 0.04), origin=given)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        write_volume(obj, tmp_path / "far.npy")
    said = [str(w.message) for w in caught if "origin" in str(w.message)]
    origin = re.search(r"origin \[([^\]]*)\]", said[0]).group(1)
    assert np.allclose([float(x) for x in origin.split(",")], given, rtol=0, atol=np.array([0.01, 0.02, 0.04]) / 200)


# ------------------------------------------------------------------ the command line

def run(*args, cwd):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in [os.path.dirname(os.path.dirname(isoflow.__file__)),
                                                                  os.environ.get("PYTHONPATH", "")] if p))
    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True, cwd=cwd,
                          env=env, timeout=600)


def test_flow_volumes_keep_the_inputs_unit(tmp_path):
    nib = pytest.importorskip("nibabel")
    img = nib.Nifti1Image(labels(), np.diag([*PITCH, 1.0]))
    img.header.set_xyzt_units("mm")
    nib.save(img, tmp_path / "scan.nii.gz")
    done = run("flow", "scan.nii.gz", "--label", "1", "--out", "d", "--volumes", ".nii.gz", "--steps", "2",
               "--no-check", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    steps = sorted((tmp_path / "d").glob("step_*.nii.gz"))
    assert steps
    for step in steps:
        assert nib.load(step).header.get_xyzt_units()[0] == "mm"


def test_flow_of_a_store_block_by_block_keeps_its_unit(tmp_path):
    zarr = pytest.importorskip("zarr")
    pytest.importorskip("dask")
    write_volume(box(), tmp_path / "in.zarr", unit="micron")
    done = run("flow", "in.zarr", "--out", "d", "--volumes", ".zarr", "--steps", "1", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    steps = sorted((tmp_path / "d").glob("step_*.zarr"))
    assert steps
    for step in steps:
        axes = zarr.open_group(str(step), mode="r").attrs["multiscales"][0]["axes"]
        assert [a.get("unit") for a in axes] == ["micrometer"] * 3
