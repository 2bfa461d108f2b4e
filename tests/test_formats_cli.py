"""Volume formats from the shell (issue 12): the acceptance commands give
the numbers of the same volume as .npy, exported PLYs land in the file's
world coordinates, writing by suffix, and bad files give one line, exit 2."""

import json
import os
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest
import trimesh
from in_process import isoflow_here
from test_input_errors import fails  # one line on stderr, exit 2

import isoflow
from isoflow.cli import main

nib = pytest.importorskip("nibabel")
tifffile = pytest.importorskip("tifffile")


def run(capsys, *args):
    assert main([*map(str, args)]) == 0, capsys.readouterr().err
    return capsys.readouterr().out


#: the keys of a report that the file's calibration places: the same
#: volume's differ by format (tests/digital/test_world_measures.py checks them)
PLACED = ("volume", "surface_area", "area", "perimeter", "bbox", "centroid", "unit")


def topology(report: dict) -> dict:
    """A report's JSON less what the calibration places."""
    return {k: v for k, v in report.items() if k not in PLACED}


def info(capsys, *args):
    """The report of ``info --json``, less the file's name, type of values
    and calibration (``pitch``, ``origin``, ``unit``, ``space``: the same volume's differ by format;
    tests/test_units_cli.py and tests/test_space_frames.py check them) and what it places."""
    report = json.loads(run(capsys, "info", *args, "--json"))
    for key in ("input", "dtype", "pitch", "origin", "space"):
        report.pop(key, None)
    return topology(report)


def ply_vertices(path):
    mesh = trimesh.load(path, process=False)
    return np.asarray(mesh.vertices, np.float64)


def same_points(a, b, decimals=4):
    assert len(a) == len(b)
    assert sorted(map(tuple, np.round(a, decimals))) == sorted(map(tuple, np.round(b, decimals)))


@pytest.fixture
def labels(rng):
    """A label image: 3 is a thick torus with random bumps (edge and vertex
    contacts), 5 a slab, 0 the rest."""
    x, y, z = np.indices((14, 16, 12)) - np.array([6.5, 7.5, 5.5]).reshape(3, 1, 1, 1)
    torus = (np.hypot(x, y) - 4.5) ** 2 + z**2 <= 2.2**2
    lab = np.where(torus | (rng.random(torus.shape) < 0.04), 3, 0).astype(np.int16)
    lab[:, :, -1] = 5
    return lab


# --------------------------------------------------------------- the acceptance commands

def test_info_nifti_label_equals_npy_and_its_ply_lands_in_scanner_coordinates(tmp_path, capsys, labels):
    affine = np.array([[-0.8, 0, 0, 40.0], [0, 0.8, 0, -25.0], [0, 0, 2.5, 12.0], [0, 0, 0, 1]])  # LAS, anisotropic
    nib.save(nib.Nifti1Image(labels, affine), tmp_path / "scan.nii.gz")
    np.save(tmp_path / "label3.npy", labels == 3)
    a, b = info(capsys, tmp_path / "scan.nii.gz", "--label", "3"), info(capsys, tmp_path / "label3.npy")
    assert a == b and a["betti"][1] >= 1
    run(capsys, "surface", tmp_path / "scan.nii.gz", "--label", "3", "-o", tmp_path / "s.ply")
    run(capsys, "surface", tmp_path / "label3.npy", "-o", tmp_path / "n.ply")
    # the .npy mesh is in voxel-corner index units; nibabel maps centres, so corners are index - 0.5
    expect = nib.affines.apply_affine(affine, ply_vertices(tmp_path / "n.ply") - 0.5)
    same_points(ply_vertices(tmp_path / "s.ply"), expect)


def test_a_nifti_without_qform_or_sform_is_placed_by_method_1(tmp_path, capsys, labels):
    """qform_code and sform_code 0: nifti1.h's method 1 places voxel (i, j,
    k) at (i pixdim[1], j pixdim[2], k pixdim[3]), unturned; nibabel's own
    affine for it mirrors x and centres the volume, which the file does
    not say. The mesh lands where method 1 puts the voxels' corners, with
    one warning line."""
    img = nib.Nifti1Image(labels, np.diag([0.8, 1.25, 2.5, 1.0]))
    img.set_sform(None, code=0)
    img.set_qform(None, code=0)
    nib.save(img, tmp_path / "bare.nii")
    header = nib.load(tmp_path / "bare.nii").header
    assert int(header["qform_code"]) == int(header["sform_code"]) == 0
    pixdim = np.asarray(header["pixdim"][1:4], np.float64)
    assert main(["surface", str(tmp_path / "bare.nii"), "--label", "3", "-o", str(tmp_path / "s.ply")]) == 0
    assert "no qform or sform (both codes 0)" in capsys.readouterr().err
    np.save(tmp_path / "label3.npy", labels == 3)
    run(capsys, "surface", tmp_path / "label3.npy", "-o", tmp_path / "n.ply")
    # the .npy mesh is in voxel-corner index units: corners are centres' indices - 0.5
    same_points(ply_vertices(tmp_path / "s.ply"), (ply_vertices(tmp_path / "n.ply") - 0.5) * pixdim)


def bare_nifti(path, array, pixdim):
    """A NIfTI-1 file of ``array`` with qform and sform codes 0 and the
    voxel sizes ``pixdim`` as its header bytes hold them, negative ones too
    (nib.save rewrites the forms from the image's affine, so the header is
    written again over the saved one)."""
    nib.save(nib.Nifti1Image(array, np.eye(4)), path)
    header = nib.load(path).header.copy()
    header.set_qform(None, code=0)
    header.set_sform(None, code=0)
    header["pixdim"][1:4] = pixdim
    with open(path, "r+b") as fh:
        header.write_to(fh)
    raw = np.frombuffer(path.read_bytes()[76:108], "<f4").astype(np.float64)  # nifti1.h: float pixdim[8] at byte 76
    assert raw[1:4].tolist() == list(pixdim)
    return raw[1:4]


@pytest.mark.parametrize("pixdim", [(-2.0, 1.5, 1.0), (2.0, -1.5, 1.0)])
def test_a_negative_pixdim_of_a_nifti_without_forms_mirrors_its_axis(tmp_path, labels, pixdim):
    """qform_code = sform_code = 0 and a negative pixdim: nibabel's header
    check reads it as its magnitude as it loads the file, and isoflow took
    that, so pixdim[1] = -2 read unmirrored (x = +2 i). The standard's
    method 1, as nifti1_io reads the header, puts voxel i at i pixdim[1]:
    the axis mirrored. Read from the shell: the voxel sizes positive (as
    nibabel's zooms), the mirror in the placement, the mesh's corners at
    method 1's places computed from the header's bytes; nibabel's affine
    mirrors x the same way (its own x flip, the volume centred)."""
    path = tmp_path / "bare.nii"
    stored = bare_nifti(path, labels, pixdim)
    img = nib.load(path)
    r = isoflow_here("info", str(path), "--label", "3", "--json")
    assert r.returncode == 0, r.stderr
    report = json.loads(r.stdout)
    assert report["pitch"] == [float(z) for z in img.header.get_zooms()] == [abs(p) for p in pixdim]
    warned = r.stderr
    r = isoflow_here("surface", str(path), "--label", "3", "-o", str(tmp_path / "s.ply"))
    assert r.returncode == 0, r.stderr
    np.save(tmp_path / "label3.npy", labels == 3)
    r = isoflow_here("surface", str(tmp_path / "label3.npy"), "-o", str(tmp_path / "n.ply"))
    assert r.returncode == 0, r.stderr
    corners = ply_vertices(tmp_path / "n.ply") - 0.5  # voxel-corner index units: centres' indices - 0.5
    same_points(ply_vertices(tmp_path / "s.ply"), corners * stored)
    if pixdim[0] < 0:  # nibabel's affine, less the translation by which it centres the volume
        linear = img.affine.copy()
        linear[:3, 3] = 0
        same_points(ply_vertices(tmp_path / "s.ply"), nib.affines.apply_affine(linear, corners))
    assert "negative: that axis runs mirrored" in warned and len(warned.splitlines()) == 1


@pytest.mark.parametrize("slope, inter", [(2.0, 0.0), (np.nan, 5.0), (0.0, 5.0), (1.0, 1.0), (1.0, -1.0)])
def test_a_nifti_mask_is_read_with_its_header_scaling_said_where_it_moves_0(tmp_path, slope, inter):
    """NIfTI scales the stored values, ``scl_slope * stored + scl_inter``,
    unless scl_slope is 0 or NaN ("no scaling"). A 0/1 mask with slope 2
    is 0/2, a mask; slope 0 or NaN leave it 0/1. Under scl_inter 1 it is
    1/2 (refused as no mask), under -1 it is -1/0, whose object is the
    voxels stored 0: it read so without a word. The values are nibabel's
    (the voxel count of its scaled array where it is a mask), and a
    scaling that moves the stored 0 is said in a warning naming
    scl_inter and its value."""
    import struct

    mask = np.zeros((6, 5, 4), np.uint8)
    mask[1:4, 1:4, 1:3] = 1
    path = tmp_path / "mask.nii"
    nib.save(nib.Nifti1Image(mask, np.eye(4)), path)
    header = bytearray(path.read_bytes())
    struct.pack_into("<2f", header, 112, slope, inter)  # scl_slope, scl_inter as a writer leaves them
    path.write_bytes(bytes(header))
    values = np.asanyarray(nib.load(path).dataobj)
    r = isoflow_here("info", str(path), "--json")
    said = [line for line in r.stderr.splitlines() if "scl_inter" in line and "warning:" in line]
    if inter == 0 or not slope or np.isnan(slope):  # no scaling of the stored 0: nothing to say
        assert r.returncode == 0 and not said, r.stderr
        assert json.loads(r.stdout)["voxels"] == np.count_nonzero(values) == 18
        return
    assert len(said) == 1, r.stderr
    assert f"scl_inter {inter:g} (value = " in said[0] and f"reads a stored 0 as {inter:g}:" in said[0], r.stderr
    if np.unique(values).tolist() == [1.0, 2.0]:  # two values beside no 0: no mask
        assert r.returncode == 2 and "not a binary volume" in r.stderr
        # the refusal names the scaling its values were read through, beside the warning
        assert any("error:" in line and f"scl_inter {inter:g}" in line for line in r.stderr.splitlines()), r.stderr
    else:
        assert r.returncode == 0, r.stderr
        assert json.loads(r.stdout)["voxels"] == np.count_nonzero(values) == mask.size - 18


def test_nifti_labels_made_fractions_by_scl_slope_are_refused_naming_it(tmp_path):
    """Labels stored 1 and 3 under scl_slope 0.5 read (as nibabel reads
    them) 0.5 and 1.5: refused as "holds 0.5: not a whole number" with no
    word of the header, as if the stored labels were fractions. The
    refusal names scl_slope and its value; under slope 2 the labels are
    nibabel's 2 and 6."""
    labels = np.zeros((6, 6, 6), np.int16)
    labels[1:3, 1:3, 1:3], labels[3:5, 3:5, 3:5] = 1, 3
    for slope in (0.5, 2.0):
        img = nib.Nifti1Image(labels, np.eye(4))
        img.header.set_slope_inter(slope, 0)
        nib.save(img, tmp_path / f"seg{slope}.nii")
    read = np.asanyarray(nib.load(tmp_path / "seg0.5.nii").dataobj)
    assert sorted(np.unique(read).tolist()) == [0, 0.5, 1.5]
    r = isoflow_here("info", str(tmp_path / "seg0.5.nii"), "--labels")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "holds 0.5: not a whole number" in r.stderr and "scl_slope 0.5 and scl_inter 0" in r.stderr, r.stderr
    r = isoflow_here("info", str(tmp_path / "seg2.0.nii"), "--labels", "--json")
    assert r.returncode == 0, r.stderr
    scaled = np.asanyarray(nib.load(tmp_path / "seg2.0.nii").dataobj)
    assert [row["label"] for row in json.loads(r.stdout)["labels"]] == [2, 6] == sorted(np.unique(scaled)[1:].tolist())


def test_a_nifti_mask_made_fractions_by_scl_slope_is_refused_naming_it(tmp_path, capsys):
    """A volume stored 0, 1 and 2 under scl_slope 0.5 reads (as nibabel
    reads it) 0, 0.5 and 1: refused as "not a binary volume ... e.g. 0.5"
    with no word of the header, as if the file stored 0.5. The refusal
    names scl_slope and its value, as the label reader's does."""
    volume = np.zeros((4, 4, 4), np.uint8)
    volume[1, 1, 1], volume[2, 2, 2] = 1, 2
    img = nib.Nifti1Image(volume, np.eye(4))
    img.header.set_slope_inter(0.5, 0)
    nib.save(img, tmp_path / "f.nii")
    assert sorted(np.unique(np.asanyarray(nib.load(tmp_path / "f.nii").dataobj)).tolist()) == [0, 0.5, 1]
    with pytest.raises(isoflow.IsoflowError) as caught:
        isoflow.read_object(tmp_path / "f.nii")
    assert "e.g. 0.5" in str(caught.value) and "scl_slope 0.5 and scl_inter 0" in str(caught.value), caught.value
    assert main(["info", str(tmp_path / "f.nii")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "not a binary volume" in err and "scl_slope 0.5 and scl_inter 0" in err, err


@pytest.mark.parametrize("qform_code", [1, 0])
def test_a_nifti_sform_of_zeros_is_named_and_its_qform_read(tmp_path, qform_code):
    """An sform of zeros under sform_code 1 was refused as "voxel-to-world
    map [[0.0, ...]] has a zero voxel size", naming no header field. It is
    named (sform_code, srow_x..z); the qform places the image where it has
    one (qform_code > 0, as ITK reads it: the volume is nibabel's qform
    voxel size cubed times the voxels), else it is refused in one line."""
    mask = np.zeros((6, 6, 6), np.uint8)
    mask[1:4, 1:4, 1:4] = 1
    img = nib.Nifti1Image(mask, None)
    img.header.set_qform(np.diag([2.0, 2.0, 2.0, 1.0]), code=qform_code)
    img.header.set_sform(np.zeros((4, 4)), code=1)
    nib.save(img, tmp_path / "zs.nii")
    assert not nib.load(tmp_path / "zs.nii").affine[:3, :3].any()  # nibabel's own map: every voxel at one point
    r = isoflow_here("info", str(tmp_path / "zs.nii"), "--json")
    assert r.stderr.count("\n") == 1 and "sform_code 1, srow_x [0.0, 0.0, 0.0, 0.0]" in r.stderr, r.stderr
    if qform_code == 0:
        assert r.returncode == 2 and "qform_code is 0" in r.stderr, r.stderr
        return
    assert r.returncode == 0 and f"placed by its qform (qform_code {qform_code})" in r.stderr, r.stderr
    voxel = np.linalg.norm(img.header.get_qform()[:3, :3], axis=0)
    assert json.loads(r.stdout)["volume"] == pytest.approx(mask.sum() * voxel.prod())


def test_a_2d_slice_off_the_world_xy_plane_says_which_world_axes_it_runs_along(tmp_path):
    """A 2D NIfTI slice whose affine runs its axes along world y and z (a
    sagittal slice), or a 2D NRRD in a 3D space along x and z (coronal),
    was read with those as its x and y and its frame still RAS or LPS,
    its place along the third world axis dropped, without a word: its
    origin (-10.25, 19.65) was world y and z, reported as x and y. One
    warning names the plane (nibabel's axis codes of the affine give the
    world axes) and the place not kept; an axial slice gets none."""
    nrrd = pytest.importorskip("nrrd")
    mask = np.zeros((10, 12), np.uint8)
    mask[2:7, 3:9] = 1
    affine = np.array([[0, 0, 1.0, 5.0], [0.5, 0, 0, -10.0], [0, 0.7, 0, 20.0], [0, 0, 0, 1]])
    nib.save(nib.Nifti1Image(mask, affine), tmp_path / "sagittal.nii.gz")
    codes = nib.orientations.aff2axcodes(nib.load(tmp_path / "sagittal.nii.gz").affine)[:2]
    plane = "-".join("xyz"["RAS".index(c)] for c in codes)
    space = {"space": "left-posterior-superior", "space origin": np.array([1.0, 2.0, 3.0]), "kinds": ["domain"] * 2}
    nrrd.write(str(tmp_path / "coronal.nrrd"), mask, dict(space, **{"space directions": [[0.5, 0, 0], [0, 0, 0.7]]}))
    nrrd.write(str(tmp_path / "axial.nrrd"), mask, dict(space, **{"space directions": [[0.5, 0, 0], [0, 0.7, 0]]}))
    for name, words in (("sagittal.nii.gz", (f"world's {plane} plane", "y-z", "world x = 5 is not kept")),
                        ("coronal.nrrd", ("world's x-z plane", "world y = 2 is not kept")), ("axial.nrrd", None)):
        r = isoflow_here("info", str(tmp_path / name), "--json")
        assert r.returncode == 0, r.stderr
        assert json.loads(r.stdout)["voxels"] == np.count_nonzero(mask)
        said = [line for line in r.stderr.splitlines() if "plane" in line]
        if words is None:
            assert not said, r.stderr
        else:
            assert len(said) == 1 and all(w in said[0] for w in words), r.stderr


def test_surface_tiff_stack_equals_npy_and_lands_in_micrometres(tmp_path, capsys, labels):
    mask = (labels == 3).transpose(2, 1, 0).astype(np.uint8)  # a z, y, x stack as tifffile holds it
    tifffile.imwrite(tmp_path / "stack.tif", mask, imagej=True, resolution=(1 / 0.5, 1 / 0.25),
                     metadata={"spacing": 2.0, "unit": "um", "axes": "ZYX"})
    np.save(tmp_path / "stack.npy", tifffile.imread(tmp_path / "stack.tif"))
    s = run(capsys, "surface", tmp_path / "stack.tif", "-o", tmp_path / "s.ply")
    n = run(capsys, "surface", tmp_path / "stack.npy", "-o", tmp_path / "n.ply")
    first = [out.splitlines()[0].split(":", 1)[1] for out in (s, n)]
    assert first[0] == first[1]  # vertices, faces, surfaces, V-E+F (the read-back's volume is in um^3)
    # .npy axes are (z, y, x) in index units; the TIFF's are x, y, z in micrometres
    same_points(ply_vertices(tmp_path / "s.ply"), ply_vertices(tmp_path / "n.ply")[:, ::-1] * [0.5, 0.25, 2.0])
    assert info(capsys, tmp_path / "stack.tif")["euler_characteristic"] == \
        info(capsys, tmp_path / "stack.npy")["euler_characteristic"]


def test_info_on_omezarr_block_by_block_with_a_label(tmp_path, capsys, labels):
    isoflow.write_volume(isoflow.DigitalObject(labels == 3), tmp_path / "m.npz")
    import zarr

    root = zarr.open_group(str(tmp_path / "l.zarr"), mode="w", zarr_format=2)
    root.create_array("0", data=labels[None].transpose(0, 3, 2, 1), chunks=(1, 5, 5, 5))  # c, z, y, x
    root.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": n} for n in "czyx"],
                                  "datasets": [{"path": "0", "coordinateTransformations": [
                                      {"type": "scale", "scale": [1, 1, 1, 1]}]}]}]
    a = info(capsys, tmp_path / "l.zarr", "--label", "3")
    b = info(capsys, tmp_path / "m.npz", "--no-surfaces")
    assert a["shape"] == b["shape"] == list(labels.shape)
    for key in ("euler_characteristic", "betti", "n", "a_dot_n", "energy", "voxels"):
        assert a[key] == b[key], key


# --------------------------------------------------------------- writing by suffix

@pytest.mark.parametrize("radius", [1e-12, 1e-7, 2e10, 1e11])


def test_a_tiff_voxel_size_is_read_back_by_tifffile_or_refused(tmp_path, capsys, radius):
    """TIFF keeps x and y voxel sizes as 1 / size in two uint32s: a size it
    holds is what tifffile's tags give back, one it cannot hold is refused
    (tifffile wrote the resolution 0, read as no calibration, or raised)."""
    mesh = tmp_path / "ball.stl"
    ball = trimesh.creation.icosphere(2, radius=radius)
    ball.export(mesh)
    pitch = float(ball.extents.max()) / 20  # --resolution 20: 20 voxels along the longest side
    out = tmp_path / "ball.tif"
    if 1 / pitch > 2**32 - 1 or pitch > 2**32 - 1:
        fails(capsys, "voxelize", mesh, "--resolution", "20", "-o", out, words=("XResolution", f"{pitch:.6g}", ".nrrd"))
        assert not out.exists()
        return
    run(capsys, "voxelize", mesh, "--resolution", "20", "-o", out)
    with tifffile.TiffFile(out) as tif:
        for tag in ("XResolution", "YResolution"):
            num, den = tif.pages[0].tags[tag].value
            assert den / num == pytest.approx(pitch, rel=1e-6), tag


@pytest.mark.parametrize("suffix", [".nii.gz", ".tif", ".nrrd", ".h5", ".binvox", ".vox", ".zarr"])


def test_voxelize_writes_every_format(tmp_path, capsys, suffix):
    pytest.importorskip({".nrrd": "nrrd", ".h5": "h5py", ".zarr": "zarr"}.get(suffix, "numpy"))
    mesh = tmp_path / "t.stl"
    trimesh.creation.torus(2.0, 0.8).export(mesh)
    run(capsys, "voxelize", mesh, "--resolution", "24", "-o", tmp_path / "ref.npz")
    run(capsys, "voxelize", mesh, "--resolution", "24", "-o", tmp_path / f"v{suffix}")
    ref, back = isoflow.read_volume(tmp_path / "ref.npz"), isoflow.read_volume(tmp_path / f"v{suffix}")
    assert back.voxels == ref.voxels and ref.voxels > 0
    if suffix != ".vox":  # formats with an origin put the solid where the mesh is
        np.testing.assert_allclose(back.bbox(), ref.bbox(), rtol=1e-6, atol=1e-6)
    if suffix == ".nii.gz":
        img = nib.load(tmp_path / "v.nii.gz")
        assert int(np.asarray(img.dataobj).sum()) == ref.voxels
        np.testing.assert_allclose(img.header.get_zooms(), [ref.pitch] * 3, rtol=1e-6)
    fails(capsys, "voxelize", mesh, "--resolution", "24", "-o", tmp_path / f"v{suffix}", words=("exists", "--force"))


def test_flow_step_tiffs_of_thin_states_read_back_3d(tmp_path, capsys):
    # the 3x3x3 box flows to 8 voxels, then to one: that step's TIFF read back as a 2D image of one pixel
    np.save(tmp_path / "box.npy", np.ones((3, 3, 3), bool))
    run(capsys, "flow", tmp_path / "box.npy", "--out", tmp_path / "out", "--volumes", ".tif")
    states = [isoflow.read_volume(p) for p in sorted((tmp_path / "out").glob("step_*.tif"))]
    assert [s.volume.shape for s in states] == [(3, 3, 3), (2, 2, 2), (1, 1, 1)]
    assert [isoflow.analyze(s.volume, 6)["euler_characteristic"] for s in states] == [1, 1, 1]


def test_voxelize_refuses_an_unknown_suffix_before_working(tmp_path, capsys):
    fails(capsys, "voxelize", tmp_path / "missing.stl", "--resolution", "8", "-o", tmp_path / "v.xyz",
          words=("v.xyz", ".nii.gz", ".binvox"))


@pytest.mark.parametrize("meshes", [1, 2])
def test_voxelize_refuses_a_png_before_working(tmp_path, capsys, meshes):
    """PNG is written for 2D images (a 2D flow's steps); a voxelisation is
    3D, so ``-o v.png`` is refused before the mesh is even read (it is not
    there), for one mesh and for a label image of several."""
    missing = [tmp_path / f"missing{k}.stl" for k in range(meshes)]
    fails(capsys, "voxelize", *missing, "--resolution", "8", "-o", tmp_path / "v.png",
          words=("v.png", "PNG holds 2D images, this volume is 3D", ".tif"))


def test_flow_writes_step_volumes(tmp_path, capsys):
    obj = isoflow.DigitalObject(np.ones((3, 4, 5), bool), pitch=[0.5, 1.0, 2.0], origin=[1.0, 2.0, 3.0])
    isoflow.write_volume(obj, tmp_path / "box.nii.gz")
    run(capsys, "flow", tmp_path / "box.nii.gz", "--out", tmp_path / "out", "--volumes", ".nii.gz")
    steps = sorted((tmp_path / "out").glob("step_*.nii.gz"))
    rows = (tmp_path / "out" / "flow.csv").read_text().splitlines()[1:]
    voxels = [int(r.split(",")[1]) for r in rows if int(r.split(",")[1])]
    assert [isoflow.read_volume(p).voxels for p in steps] == voxels == [60, 24, 6]  # the 3x4x5 box
    for p in steps:  # every step keeps the voxel size; its PLY and its volume sit in the same place
        state = isoflow.read_volume(p)
        np.testing.assert_allclose(state.pitch, [0.5, 1.0, 2.0])
        lo, hi = state.bbox()
        verts = ply_vertices(p.with_name(p.name.replace(".nii.gz", ".ply")))
        np.testing.assert_allclose([verts.min(0), verts.max(0)], [lo, hi], atol=1e-5)
    fails(capsys, "flow", tmp_path / "box.nii.gz", "--volumes", ".nii.gz", words=("--out",))
    fails(capsys, "flow", tmp_path / "box.nii.gz", "--out", tmp_path / "o2", "--volumes", ".xyz", words=(".xyz",))


# --------------------------------------------------------------- bad input: one line, exit 2

def test_label_image_without_label_says_threshold_or_label(tmp_path, capsys, labels):
    nib.save(nib.Nifti1Image(labels, np.eye(4)), tmp_path / "l.nii.gz")
    fails(capsys, "info", tmp_path / "l.nii.gz", words=("l.nii.gz", "threshold it first", "--label N"))
    fails(capsys, "info", tmp_path / "l.nii.gz", "--label", "4", words=("no voxel has label 4", "0, 3, 5"))


def test_a_label_image_refusal_counts_voxels_in_memory_and_per_block_in_a_store(tmp_path, capsys, labels):
    # it said "N values other than 0 and 1", read as N distinct values; of
    # a store checked block by block N is the block's count, not the store's
    np.save(tmp_path / "l.npy", labels)
    many = int(np.count_nonzero(labels > 1))
    fails(capsys, "info", tmp_path / "l.npy", words=(f"({many} voxels hold values other than 0 and 1, e.g. ",))
    zarr = pytest.importorskip("zarr")
    zarr.create_array(str(tmp_path / "l.zarr"), data=labels, chunks=(5, 5, 5), zarr_format=2)
    line = fails(capsys, "info", tmp_path / "l.zarr", words=("l.zarr: not a binary volume",))
    found = re.search(r"\((\d+) voxels in the block at voxel \((\d+), (\d+), (\d+)\) hold values other than 0 and 1", line)
    assert found, line
    count, *corner = map(int, found.groups())
    block = labels[tuple(slice(c, c + 5) for c in corner)]
    assert count == np.count_nonzero(block > 1) < many


def block_named(line: str) -> tuple[int, list[int]]:
    """The count and the first voxel of the block a store's refusal names."""
    found = re.search(r"\((\d+) voxels? in the block at voxel \((\d+), (\d+), (\d+)\) holds? values other than 0 and 1",
                      line)
    assert found, line
    count, *corner = map(int, found.groups())
    return count, corner


@pytest.mark.parametrize("threads", ["1", "2"])


def test_surface_of_a_store_counts_the_voxels_of_the_block_it_names(tmp_path, capsys, labels, threads):
    """surface reads each block of a store with a voxel layer of margin
    around it; a refusal named the margin's first voxel, which is no
    block's (4, 9, ...: the chunks start at multiples of 5), and counted
    the margins' voxels too, and where only a block's margin held a value
    other than 0 and 1, it named that block, which holds none. The line
    now names a chunk of the store and counts that chunk's voxels, as
    info's line does."""
    zarr = pytest.importorskip("zarr")
    zarr.create_array(str(tmp_path / "l.zarr"), data=labels, chunks=(5, 5, 5), zarr_format=2)
    line = fails(capsys, "surface", tmp_path / "l.zarr", "-o", tmp_path / "l.ply", "--threads", threads,
                 words=("l.zarr: not a binary volume",))
    count, corner = block_named(line)
    assert all(c % 5 == 0 for c in corner), line
    assert count == np.count_nonzero(labels[tuple(slice(c, c + 5) for c in corner)] > 1) > 0
    # a 2 and a 3 on the first layer of the second chunk: in the margin the first block reads (two
    # labels: a store of 0 and 2 alone is the mask of 2, as in memory)
    lone = np.zeros((10, 10, 10), np.uint8)
    lone[5, 0, 0], lone[5, 0, 1] = 2, 3
    zarr.create_array(str(tmp_path / "m.zarr"), data=lone, chunks=(5, 5, 5), zarr_format=2)
    line = fails(capsys, "surface", tmp_path / "m.zarr", "-o", tmp_path / "m.ply", "--threads", threads,
                 words=("m.zarr: not a binary volume",))
    assert block_named(line) == (2, [5, 0, 0])


def corrupt_files(tmp_path):
    (tmp_path / "junk.tif").write_bytes(b"II*\x00" + b"\xff" * 40)
    (tmp_path / "junk.nii.gz").write_bytes(b"\x1f\x8b\x08\x00garbage")
    (tmp_path / "junk.nrrd").write_bytes(b"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n12")
    (tmp_path / "junk.h5").write_bytes(b"not hdf5 at all")
    (tmp_path / "junk.binvox").write_bytes(b"#binvox 1\ndim 4 4 4\ndata\n\x01\x05")
    (tmp_path / "junk.vox").write_bytes(b"VOX \x96\x00\x00\x00MAIN\x00\x00\x00\x00\xff\x00\x00\x00")
    (tmp_path / "junk.zarr").mkdir()
    (tmp_path / "junk.zarr" / "zarr.json").write_text("{not json")
    return ["junk.tif", "junk.nii.gz", "junk.nrrd", "junk.h5", "junk.binvox", "junk.vox", "junk.zarr"]


@pytest.mark.parametrize("command", ["info", "surface"])


def test_corrupt_files_give_one_line(tmp_path, capsys, command):
    for name in corrupt_files(tmp_path):
        out = ["-o", tmp_path / "s.ply"] if command == "surface" else []
        fails(capsys, command, tmp_path / name, *out, words=(name,))
    assert not (tmp_path / "s.ply").exists()


@pytest.mark.parametrize("name", ["e.nrrd", "e.tif", "e.nii.gz", "e.nii", "e.h5", "e.png"])


def test_an_empty_file_is_said_to_be_empty(tmp_path, capsys, name):
    """A file of 0 bytes (a download or copy that failed): pynrrd said
    "StopIteration", the others each their own words for no header."""
    (tmp_path / name).write_bytes(b"")
    fails(capsys, "info", tmp_path / name, words=(f"{name}: an empty file (0 bytes), not a readable ",))


@pytest.mark.parametrize("written, named, words", [
    ("v.nii.gz", "v.nii", "its content is gzip-compressed NIfTI: rename it v.nii.gz"),
    ("v.nii", "v.nii.gz", "its content is uncompressed NIfTI: rename it v.nii"),
    ("v.tif", "v.nii.gz", "its content is TIFF, not NIfTI: rename it v.tif"),
    ("v.nii", "v.tif", "its content is NIfTI, not TIFF: rename it v.nii"),
    ("v.h5", "v.nrrd", "its content is HDF5, not NRRD: rename it v.h5"),
    ("v.nii.gz", "v.npy", "its content is NIfTI, not NumPy: rename it v.nii.gz"),
    ("v.npy", "v.h5", "its content is NumPy, not HDF5: rename it v.npy"),
])


def test_a_volume_saved_under_another_suffix_is_named_by_its_content(tmp_path, capsys, written, named, words):
    """The reader goes by the suffix (nibabel too: "Cannot work out file
    type" of a gzip-compressed .nii); the line says what the content is
    and what to call the file, as for a mesh."""
    vol = np.zeros((4, 5, 6), bool)
    vol[1:3, 1:4, 1:5] = True
    isoflow.write_volume(isoflow.DigitalObject(vol), tmp_path / written)
    (tmp_path / written).rename(tmp_path / "renamed")
    (tmp_path / "renamed").rename(tmp_path / named)
    fails(capsys, "info", tmp_path / named, words=(f"{named}: not a ", words))
    (tmp_path / named).rename(tmp_path / words.rsplit(" ", 1)[1])  # as the line says: the file reads
    assert info(capsys, tmp_path / words.rsplit(" ", 1)[1])["voxels"] == vol.sum()


def test_a_zip_archive_of_other_files_is_not_called_an_npz(tmp_path, capsys):
    """An .npz is a zip of .npy files; another zip under a volume suffix
    gets the reader's line alone, no "rename it x.npz"."""
    import zipfile

    with zipfile.ZipFile(tmp_path / "x.tif", "w") as z:
        z.writestr("notes.txt", "not a volume")
    line = fails(capsys, "info", tmp_path / "x.tif", words=("x.tif: not a readable TIFF file",))
    assert "its content is" not in line, line


def test_wrong_dataset_or_level(tmp_path, capsys, labels):
    pytest.importorskip("h5py")
    isoflow.write_volume(isoflow.DigitalObject(labels == 3), f"{tmp_path / 'v.h5'}:/a/b")
    fails(capsys, "info", f"{tmp_path / 'v.h5'}:/nope", words=("no dataset '/nope'", "/a/b"))
    fails(capsys, "info", f"{tmp_path / 'v.h5'}:/a", words=("is a group",))
    isoflow.write_volume(isoflow.DigitalObject(labels == 3), tmp_path / "v.zarr")
    fails(capsys, "surface", f"{tmp_path / 'v.zarr'}:7", "-o", tmp_path / "s.ply", words=("no resolution level '7'",))
    fails(capsys, "info", f"{tmp_path / 'v.zarr'}:7", words=("no resolution level '7'",))


def test_a_missing_library_names_the_extra(tmp_path, capsys, monkeypatch, labels):
    nib.save(nib.Nifti1Image(labels, np.eye(4)), tmp_path / "l.nii.gz")
    monkeypatch.setitem(sys.modules, "nibabel", None)  # import nibabel now raises ImportError
    fails(capsys, "info", tmp_path / "l.nii.gz", "--label", "3", words=("nibabel", "pip install 'isoflow[formats]'"))
    fails(capsys, "voxelize", tmp_path / "m.stl", "--resolution", "8", "-o", tmp_path / "v.nii",
          words=("isoflow[formats]",))
    assert not (tmp_path / "v.nii").exists()


def test_metadata_a_format_cannot_keep_is_one_warning_line(tmp_path, capsys):
    isoflow.write_volume(isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5), tmp_path / "v.npz")
    assert main(["flow", str(tmp_path / "v.npz"), "--out", str(tmp_path / "o"), "--volumes", "vox", "--steps", "1"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err and all(line.startswith("isoflow flow: warning: ") and "MagicaVoxel keeps no voxel size, origin or unit" in line
                       for line in err)


# --------------------------------------------------------------- damaged and unusual files (found by fuzzing)

def test_a_tiff_time_series_is_not_read_as_a_z_stack(tmp_path, capsys, labels):
    frames = (labels[:5] == 3).astype(np.uint8)  # five frames of a 16x12 image
    tifffile.imwrite(tmp_path / "tyx_imagej.tif", frames, imagej=True, metadata={"axes": "TYX"})
    tifffile.imwrite(tmp_path / "tyx.ome.tif", frames, metadata={"axes": "TYX"})
    for name in ("tyx_imagej.tif", "tyx.ome.tif"):
        assert tifffile.TiffFile(tmp_path / name).series[0].axes == "TYX"
        fails(capsys, "info", tmp_path / name, words=(name, "axis 't' has 5 entries"))
    # a plain page stack (pages without axis names) is still z
    tifffile.imwrite(tmp_path / "pages.tif", frames, metadata=None)
    assert tifffile.TiffFile(tmp_path / "pages.tif").series[0].axes[0] in "QI"
    assert info(capsys, tmp_path / "pages.tif")["shape"] == [12, 16, 5]


def resaved_as_the_refusal_says(path, channels: int) -> dict:
    """The ``info --json`` report of ``path``'s channels saved as slices by
    the command that the refusal of ``path`` (one line, exit 2) gives, run
    as the user runs it, beside ``path`` (the one file it writes)."""
    import shlex

    done = isoflow_here("info", str(path))
    assert done.returncode == 2 and done.stdout == ""
    line, = done.stderr.splitlines()
    assert f"{path.name}: axis 'c' has {channels} entries" in line and "Traceback" not in line
    command = shlex.split(line.split("save them as one stack and give that: ", 1)[1])
    assert command[:2] == ["python", "-c"]
    before = set(path.parent.iterdir())
    subprocess.run([sys.executable, *command[1:]], check=True, cwd=path.parent)
    stack, = set(path.parent.iterdir()) - before  # what the command wrote, as the user finds it
    return json.loads(subprocess.run([sys.executable, "-m", "isoflow", "info", str(stack), "--json"],
                                     capture_output=True, text=True, check=True).stdout)


@pytest.mark.parametrize("channels", [2, 3, 5])


@pytest.mark.parametrize("save", [{}, {"resolution": (2, 4), "metadata": {"axes": "ZCYX", "unit": "um", "spacing": 2.0}}])
def test_imagej_tiff_of_channels_gives_the_command_that_saves_them_as_slices(tmp_path, labels, save, channels):
    """tifffile's ``imwrite(f, stack, imagej=True)`` stores a (N, Y, X) stack
    as N channels, which Fiji opens as channels and isoflow refuses; the
    refusal, one line, gives the command that re-saves them as slices, and
    what it writes is read as those slices, with the pixel size tifffile
    reads in the original."""
    stack = (labels[:, :, :channels] == 3).T.astype(np.uint8)  # N slices of 16x14, as (z, y, x)
    data = stack[None] if save else stack  # ZCYX: one slice of N channels
    tifffile.imwrite(tmp_path / "c.tif", data, imagej=True, **save)
    with tifffile.TiffFile(tmp_path / "c.tif") as tif:
        assert tif.series[0].axes == "CYX" and tif.imagej_metadata["channels"] == channels
        x, y = (d / n for n, d in (tif.pages[0].tags[t].value for t in (282, 283)))
    report = resaved_as_the_refusal_says(tmp_path / "c.tif", channels)
    with tifffile.TiffFile(tmp_path / "c_stack.tif") as tif:
        series = tif.series[0]
        assert series.axes == "ZYX" and series.shape == stack.shape
    assert report["shape"] == list(series.shape[::-1]) and report["voxels"] == np.count_nonzero(stack)
    assert np.allclose(report["pitch"], [x, y, 2.0 if save else 1.0])
    assert report["unit"] == ("\u00b5m" if save else None)


@pytest.mark.parametrize("channels", [2, 5])


def test_ome_tiff_of_channels_command_keeps_its_physical_size(tmp_path, rng, channels):
    """An OME-TIFF of one slice in several channels holds its voxel size in
    its OME-XML's PhysicalSizeX/Y/Z, not in its resolution tags: the
    command the refusal gives, run as the user would, saves the channels
    as slices with the voxel size and unit tifffile reads in the original."""
    data = (rng.random((1, channels, 6, 7)) < 0.5).astype(np.uint8)
    tifffile.imwrite(tmp_path / "c.ome.tif", data, metadata={
        "axes": "ZCYX", "PhysicalSizeX": 0.5, "PhysicalSizeXUnit": "nm", "PhysicalSizeY": 0.25,
        "PhysicalSizeYUnit": "nm", "PhysicalSizeZ": 3.0, "PhysicalSizeZUnit": "nm"})
    with tifffile.TiffFile(tmp_path / "c.ome.tif") as tif:
        assert tif.series[0].axes == "CYX"
        pixels = tifffile.xml2dict(tif.ome_metadata)["OME"]["Image"]["Pixels"]
    report = resaved_as_the_refusal_says(tmp_path / "c.ome.tif", channels)
    assert report["shape"] == [7, 6, channels] and report["voxels"] == np.count_nonzero(data)
    assert report["pitch"] == [pixels[f"PhysicalSize{axis}"] for axis in "XYZ"]
    assert {pixels[f"PhysicalSize{axis}Unit"] for axis in "XYZ"} == {report["unit"]}


@pytest.mark.parametrize("depth", [2, 4])


def test_an_ome_tiff_resaved_as_ome_tiff_keeps_its_stage_position(tmp_path, rng, depth):
    """``write_volume`` of an OME-TIFF read by isoflow to ``.ome.tif`` wrote
    an ImageJ TIFF, whose OME-XML OME readers would look for in vain: the
    stage position was gone. It writes an OME-TIFF whose first plane is
    centred where tifffile reads the original's (a position in mm beside
    sizes in um), its voxel sizes and unit those of the original;
    ``surface`` of the copy lands on the box the original's OME-XML
    gives."""
    mask = (rng.random((depth, 6, 7)) < 0.5).astype(np.uint8)  # (z, y, x)
    mask[0, 2, 3] = 1
    tifffile.imwrite(tmp_path / "scan.ome.tif", mask, metadata={
        "axes": "ZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.25, "PhysicalSizeZ": 3.0,
        "Plane": {"PositionX": [1.5] * depth, "PositionXUnit": ["mm"] * depth, "PositionY": [-20.0] * depth,
                  "PositionZ": [7.0 + 3.0 * k for k in range(depth)]}})

    def ome(path):
        with tifffile.TiffFile(path) as tif:
            assert tif.is_ome
            return tifffile.xml2dict(tif.ome_metadata)["OME"]["Image"]["Pixels"]

    def first_centre(pixels):
        plane = pixels["Plane"][0]
        scale = {"mm": 1000.0}.get(plane.get("PositionXUnit"), 1.0)  # to the sizes' unit, um
        return np.array([plane["PositionX"] * scale, plane["PositionY"], plane["PositionZ"]])

    original = ome(tmp_path / "scan.ome.tif")
    copy = isoflow.write_volume(isoflow.read_volume(tmp_path / "scan.ome.tif"), tmp_path / "copy.ome.tif")
    resaved = ome(copy)
    pitch = np.array([original[f"PhysicalSize{axis}"] for axis in "XYZ"])
    np.testing.assert_allclose([resaved[f"PhysicalSize{axis}"] for axis in "XYZ"], pitch)
    assert {resaved[f"PhysicalSize{axis}Unit"] for axis in "XYZ"} == {"\u00b5m"}
    np.testing.assert_allclose(first_centre(resaved), first_centre(original))
    np.testing.assert_array_equal(tifffile.imread(copy).reshape(mask.shape), mask)
    p = isoflow_here("surface", str(copy), "-o", str(tmp_path / "s.ply"))
    assert p.returncode == 0, p.stderr
    z, y, x = np.nonzero(mask)
    voxels = np.stack([x, y, z], axis=1)
    corner = first_centre(original) - pitch / 2
    bounds = trimesh.load(tmp_path / "s.ply", process=False).bounds
    np.testing.assert_allclose(bounds, [corner + voxels.min(0) * pitch, corner + (voxels.max(0) + 1) * pitch],
                               rtol=1e-6)


def test_an_ome_tiff_of_one_slice_is_written_with_a_warning_that_it_reads_back_2d(tmp_path):
    """OME-XML says a stack of one slice as it says a 2D image (tifffile
    reads both as (rows, columns)): writing a volume one voxel thick to
    .ome.tif says so, and names the formats that keep it."""
    obj = isoflow.DigitalObject(np.ones((3, 4, 1), bool), pitch=0.5, origin=(1.0, 2.0, 3.0))
    with pytest.warns(isoflow.IsoflowWarning, match=r"one\.ome\.tif: an OME-TIFF of one slice is read back as a 2D image"):
        isoflow.write_volume(obj, tmp_path / "one.ome.tif")
    assert tifffile.imread(tmp_path / "one.ome.tif").shape == (4, 3)
    np.testing.assert_allclose(isoflow.read_volume(tmp_path / "one.ome.tif").origin, [1.0, 2.0])


def test_an_ome_tiff_stage_position_in_mm_without_a_voxel_size_is_not_mixed_with_pixels(tmp_path):
    """An OME-TIFF whose planes give PositionX/Y in mm but no PhysicalSize
    was placed at 1499.5 voxels of size 1 in no unit: the position in um
    beside a pitch in pixels. Its voxel size has no length, so a position
    in one is not read (one warning line naming it) and the report's origin
    is in the pitch's terms, 0; a position in the schema's default
    "reference frame" units is in those terms, and is read."""
    mask = np.zeros((3, 4, 5), np.uint8)
    mask[1, 1:3, 1:4] = 1
    for name, unit in (("mm.ome.tif", ["mm"] * 3), ("frame.ome.tif", None)):
        plane = {"PositionX": [1.5] * 3, "PositionY": [2.0] * 3}
        if unit:
            plane.update(PositionXUnit=unit, PositionYUnit=unit)
        tifffile.imwrite(tmp_path / name, mask, metadata={"axes": "ZYX", "Plane": plane})
        with tifffile.TiffFile(tmp_path / name) as tif:
            pixels = tifffile.xml2dict(tif.ome_metadata)["OME"]["Image"]["Pixels"]
        assert not any(key.startswith("PhysicalSize") for key in pixels)
        done = isoflow_here("info", str(tmp_path / name), "--json")
        assert done.returncode == 0, done.stderr
        report = json.loads(done.stdout)
        assert report["pitch"] == [1.0, 1.0, 1.0] and report["unit"] is None
        if unit:
            line, = done.stderr.splitlines()
            assert line.startswith(f"isoflow info: warning: {tmp_path / name}: OME-XML's PositionX 1.5 mm, PositionY "
                                   "2.0 mm are not read"), line
            assert report["origin"] == [0.0, 0.0, 0.0]
        else:
            assert done.stderr == ""
            first = pixels["Plane"][0]
            assert report["origin"] == [first["PositionX"] - 0.5, first["PositionY"] - 0.5, 0.0]


@pytest.mark.parametrize("count", [2, 5])


def test_ome_tiff_of_channels_command_keeps_its_stage_position(tmp_path, rng, count):
    """The command that saves an OME-TIFF's channels as slices kept the
    voxel size but not the stage position (the first plane's
    PositionX/Y/Z), so the stack it wrote was read at 0: it keeps them, and
    the stack's voxel 0 is centred where tifffile reads the original's
    first plane, in the voxel size's unit (a position in mm beside sizes in
    um), each slice one PhysicalSizeZ above the last."""
    data = (rng.random((count, 6, 7)) < 0.5).astype(np.uint8)
    tifffile.imwrite(tmp_path / "c.ome.tif", data, metadata={
        "axes": "CYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.25, "PhysicalSizeZ": 3.0,
        "Plane": {"PositionX": [1.5] * count, "PositionXUnit": ["mm"] * count, "PositionY": [-20.0] * count,
                  "PositionZ": [7.0] * count}})
    with tifffile.TiffFile(tmp_path / "c.ome.tif") as tif:
        assert tif.series[0].axes == "CYX"
        pixels = tifffile.xml2dict(tif.ome_metadata)["OME"]["Image"]["Pixels"]
    first = pixels["Plane"][0]
    assert (first["TheZ"], first["TheC"], first["TheT"]) == (0, 0, 0)
    centre = np.array([first["PositionX"] * 1000, first["PositionY"], first["PositionZ"]])  # mm in um
    pitch = np.array([pixels[f"PhysicalSize{axis}"] for axis in "XYZ"])
    report = resaved_as_the_refusal_says(tmp_path / "c.ome.tif", count)
    assert report["unit"] == "\u00b5m" and report["voxels"] == np.count_nonzero(data)
    np.testing.assert_allclose(report["pitch"], pitch)
    np.testing.assert_allclose(report["origin"], centre - pitch / 2)
    with tifffile.TiffFile(tmp_path / "c_stack.ome.tif") as tif:
        planes = tifffile.xml2dict(tif.ome_metadata)["OME"]["Image"]["Pixels"]["Plane"]
    np.testing.assert_allclose([plane["PositionZ"] for plane in planes], centre[2] + pitch[2] * np.arange(count))


@pytest.mark.parametrize("slices", [3, 4])


def test_info_of_rgb_planes_saved_by_tifffile_reports_the_array_tifffile_reads(tmp_path, rng, slices):
    """``tifffile.imwrite(f, a)`` of a (3 or 4, Y, X) array stores one RGB(A)
    image in planes, and every Python reader gives ``a`` back: ``isoflow
    info --json``, run as the user runs it, reports that array's shape,
    voxels and Euler characteristic (scikit-image's), with one warning line
    that ``--quiet`` keeps."""
    measure = pytest.importorskip("skimage.measure")
    stack = (rng.random((slices, 12, 10)) < 0.5).astype(np.uint8)
    with warnings.catch_warnings():  # tifffile's notice that a later version writes such data as pages
        warnings.simplefilter("ignore", DeprecationWarning)
        tifffile.imwrite(tmp_path / "t.tif", stack)
    read = tifffile.imread(tmp_path / "t.tif")
    for quiet in ([], ["--quiet"]):
        done = isoflow_here("info", str(tmp_path / "t.tif"), "--json", *quiet)
        assert done.returncode == 0, done.stderr
        line, = done.stderr.splitlines()
        assert line.startswith(f"isoflow info: warning: {tmp_path / 't.tif'}: ")
        assert "PhotometricInterpretation 2" in line and "PlanarConfiguration 2" in line and "colours" in line
        report = json.loads(done.stdout)
        assert report["shape"] == list(read.shape[::-1]) and report["voxels"] == np.count_nonzero(read)
        assert report["euler_characteristic"] == measure.euler_number(read != 0, connectivity=1)


def moving_ball() -> np.ndarray:
    """A ball moving one voxel per frame along x, as stored (t, z, y, x):
    consecutive frames overlap, so the space-time object is one contractible
    piece, chi 1, b0 1, b3 0."""
    t, z, y, x = np.indices((3, 6, 7, 8))
    return (((x - 2 - t) ** 2 + (y - 3) ** 2 + (z - 2.5) ** 2) <= 4).astype(np.uint8)


def time_series_store(path, translation=None):
    """An OME-Zarr time series of :func:`moving_ball` (NGFF 0.4, t z y x),
    one chunk per time point and half z, voxel size 0.5, 0.5, 2 (x, y, z)
    and time step 5; voxel centres moved by ``translation`` (t, z, y, x)."""
    zarr = pytest.importorskip("zarr")
    g = zarr.open_group(path, mode="w", zarr_format=2)
    g.create_array("0", data=moving_ball(), chunks=(1, 3, 7, 8))
    axes = [{"name": "t", "type": "time"}] + [{"name": a, "type": "space"} for a in "zyx"]
    steps = [{"type": "scale", "scale": [5.0, 2.0, 0.5, 0.5]}]
    steps += [] if translation is None else [{"type": "translation", "translation": translation}]
    g.attrs["multiscales"] = [{"version": "0.4", "axes": axes, "datasets": [
        {"path": "0", "coordinateTransformations": steps}]}]


def test_a_time_series_of_3d_volumes_is_read_as_4d(tmp_path):
    """ndim.md says info takes time series of 3D segmentations, but an
    OME-TIFF, an ImageJ hyperstack and an OME-Zarr image with a time axis
    were refused ("axis 't' has 3 entries"): each is now read as (x, y, z,
    t), the same report as the .npy of that array; the surface command still refuses 4D, and a series of 2D
    images is still refused, saying which series are read."""
    data = moving_ball()
    tifffile.imwrite(tmp_path / "ts.ome.tif", data, ome=True,
                     metadata={"axes": "TZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5, "PhysicalSizeZ": 2.0})
    tifffile.imwrite(tmp_path / "ts_imagej.tif", data[:, :, None], imagej=True, metadata={"axes": "TZCYX", "spacing": 2.0})
    time_series_store(tmp_path / "ts.ome.zarr")

    def report(name):
        p = isoflow_here("info", str(tmp_path / name), "--json")
        assert p.returncode == 0, p.stderr
        # the topology; the calibration differs by format (tests/test_units_cli.py)
        return {k: v for k, v in json.loads(p.stdout).items() if k not in ("input", "dtype", "pitch", "origin", "unit")}

    np.save(tmp_path / "ts.npy", np.transpose(data, (3, 2, 1, 0)))
    report_of_npy = report("ts.npy")
    assert report_of_npy["dimension"] == 4 and report_of_npy["shape"] == [8, 7, 6, 3]
    assert report_of_npy["euler_characteristic"] == 1 and report_of_npy["betti"] == [1, None, None, 0]
    assert report_of_npy["voxels"] == int(data.sum())
    for name in ("ts.ome.tif", "ts_imagej.tif", "ts.ome.zarr"):
        assert report(name) == report_of_npy, name
        back = isoflow.read_volume(tmp_path / name)
        assert np.array_equal(back.volume, np.transpose(data, (3, 2, 1, 0)).astype(bool))
        expected = [0.5, 0.5, 2.0, 1.0] if name != "ts_imagej.tif" else [1.0, 1.0, 2.0, 1.0]
        assert back.spacing.tolist() == expected, name  # time: step 1, as a 4D NIfTI's
    p = isoflow_here("surface", str(tmp_path / "ts.ome.tif"), "-o", str(tmp_path / "s.ply"))
    assert p.returncode == 2 and "surface needs a 3D object, this one is 4D" in p.stderr
    tifffile.imwrite(tmp_path / "tyx.ome.tif", data[:, 2], ome=True, metadata={"axes": "TYX"})
    p = isoflow_here("info", str(tmp_path / "tyx.ome.tif"))
    assert p.returncode == 2 and "save one time point (a time series is read as 4D only of 3D volumes)" in p.stderr


@pytest.mark.parametrize("name", ["ts.ome.tif", "ts.ome.zarr"])


@pytest.mark.parametrize("command", [["surface", "-o", "s.ply"], ["flow", "--steps", "1"]])
def test_a_time_series_given_to_surface_or_flow_says_how_to_take_one_time_point(command, name, tmp_path):
    """``surface`` and ``flow`` take one 3D volume; a time series (read as
    4D) got "needs a 3D object" and no way on. The one line now names the
    file and a command that saves its first time point as 3D, run here as
    the user would from the shell: the saved volume is frame 0 as stored,
    with the file's voxel size and origin, and the command then takes it.

    The command read a store whole before taking frame 0, which a
    time-lapse larger than memory cannot be: here the chunks of the other
    time points are damaged, so that reading any of them fails, and the
    command reads frame 0 alone."""
    data = moving_ball()
    if name == "ts.ome.tif":
        tifffile.imwrite(tmp_path / name, data, ome=True,
                         metadata={"axes": "TZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5, "PhysicalSizeZ": 2.0})
        origin = [0.0, 0.0, 0.0]
    else:
        time_series_store(tmp_path / name, translation=[0.0, 1.0, 2.0, 3.0])
        origin = [3.0 - 0.25, 2.0 - 0.25, 1.0 - 1.0]  # NGFF places voxel centres: less half a voxel
        chunks = [c for c in (tmp_path / name / "0").iterdir() if not c.name.startswith(".")]
        assert sorted(c.name for c in chunks) == [f"{t}.{z}.0.0" for t in range(3) for z in range(2)]
        for chunk in chunks:
            if not chunk.name.startswith("0."):
                chunk.write_bytes(b"not a chunk")
        with pytest.raises(isoflow.IsoflowError, match="not a readable zarr file"):
            isoflow.read_volume(tmp_path / name)
    p = subprocess.run([sys.executable, "-m", "isoflow", command[0], name, *command[1:]],
                       capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 2 and p.stderr.count("\n") == 1 and name in p.stderr, p.stderr
    # the OME-Zarr image and the OME-TIFF name their 4th axis t: a time series
    assert "4D, shape 8x7x6x3 (a time series of 3 time points along its 4th axis 't', read as x, y, z, t)" in p.stderr
    line = p.stderr.split("give that: ", 1)[1].strip()
    assert line.startswith("python -c ")
    shell = subprocess.run(sys.executable + line[len("python"):], shell=True, capture_output=True, text=True,
                           cwd=tmp_path)
    assert shell.returncode == 0, shell.stderr
    frame = isoflow.read_volume(tmp_path / "t0.npz")
    assert np.array_equal(frame.volume, data[0].transpose(2, 1, 0).astype(bool))  # stored (z, y, x): x first
    assert frame.pitch.tolist() == [0.5, 0.5, 2.0] and frame.origin.tolist() == origin
    p = subprocess.run([sys.executable, "-m", "isoflow", command[0], "t0.npz", *command[1:]],
                       capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 0, p.stderr


@pytest.mark.parametrize("name", ["ts.ome.tif", "ts.ome.zarr", "ts.npy"])


def test_read_volume_takes_one_time_point_and_refuses_a_time_that_is_not_one(name, tmp_path):
    """``read_volume(path, time=t)`` (and ``read_labels``) is time point
    ``t`` of a time series as 3D, with the voxel size of x, y, z; a time
    before 0 or past the last, or any time of a 3D volume, is one line
    naming the file, the value and the count."""
    data = moving_ball()
    path = tmp_path / name
    if name == "ts.ome.tif":
        tifffile.imwrite(path, data, ome=True, metadata={"axes": "TZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.5,
                                                         "PhysicalSizeZ": 2.0})
    elif name == "ts.ome.zarr":
        time_series_store(path)
    else:
        np.save(path, data.transpose(3, 2, 1, 0))
    pitch = [1.0, 1.0, 1.0] if name == "ts.npy" else [0.5, 0.5, 2.0]
    for t in range(3):
        frame = isoflow.read_volume(path, time=t)
        assert np.array_equal(frame.volume, data[t].transpose(2, 1, 0).astype(bool))
        assert frame.spacing.tolist() == pitch
    labels = isoflow.read_labels(path, time=2)
    assert np.array_equal(labels.array, data[2].transpose(2, 1, 0)) and labels.spacing.tolist() == pitch
    for t in (-1, 3):
        with pytest.raises(isoflow.IsoflowError) as error:
            isoflow.read_volume(path, time=t)
        assert str(error.value) == f"{path}: time={t} is no time point of this time series of 3 (0 to 2)"
    isoflow.write_volume(isoflow.read_volume(path, time=0), tmp_path / "t0.npz")
    with pytest.raises(isoflow.IsoflowError) as error:
        isoflow.read_volume(tmp_path / "t0.npz", time=0)
    assert str(error.value) == (f"{tmp_path / 't0.npz'}: time=0 picks a time point of a 4D volume (x, y, z, t), "
                                "this one is 3D with shape 8x7x6: it has no time points")


@pytest.mark.parametrize(("command", "needs"), [
    (["surface", "-o", "s.ply"], "surface needs a 3D object"),
    (["flow", "--steps", "1", "--out", "f", "--volumes", ".zarr"],
     "the digital curvature flow is defined for 2D and 3D objects"),
])


def test_a_time_series_store_too_large_to_read_whole_says_how_to_take_one_time_point(
        command, needs, tmp_path, capsys, monkeypatch):
    """A 4D OME-Zarr store beyond memory got the memory refusal ("crop it,
    or use a .zarr store with 'isoflow info'") from surface, and from flow
    block by block the reader's "axis 't' has 3 entries": now the line a
    4D volume in memory gets, its (x, y, z, t) shape and the command that
    saves one time point, from the store's metadata alone."""
    from isoflow.scale import memory

    time_series_store(tmp_path / "ts.ome.zarr")
    monkeypatch.setattr(memory, "default_budget", lambda: 50)  # the store (3 KiB) would not fit
    monkeypatch.chdir(tmp_path)
    line = fails(capsys, command[0], "ts.ome.zarr", *command[1:])
    assert line.startswith(f"isoflow {command[0]}: error: ts.ome.zarr: {needs}, this one is 4D, shape 8x7x6x3 "
                           "(a time series of 3 time points along its 4th axis 't', read as x, y, z, t); save one "
                           "time point as 3D and give that: python -c "), line
    assert not list(tmp_path.glob("s.*")) and not (tmp_path / "f").exists()


def test_a_tiff_of_several_image_series_is_refused(tmp_path, capsys):
    with tifffile.TiffWriter(tmp_path / "two.tif") as tif:
        tif.write(np.ones((3, 4, 5), np.uint8), photometric="minisblack")
        tif.write(np.ones((6, 7), np.uint8), photometric="minisblack")
    assert len(tifffile.TiffFile(tmp_path / "two.tif").series) == 2
    fails(capsys, "info", tmp_path / "two.tif", words=("two.tif", "2 image series", "3x4x5", "6x7"))


def test_a_tiff_stack_beside_its_reduced_resolution_thumbnail_is_read(tmp_path, capsys):
    """A microscope or scanner stores a preview beside the stack, its
    NewSubfileType tag 1 (a reduced-resolution version of another image).
    isoflow refused such a file as "holds 2 image series ... save the
    stack on its own", though the file says which is the image, and
    tifffile's imread (as scikit-image's) reads the stack. It is read: the
    count is numpy's of tifffile's array; a second full image is still
    refused."""
    stack = np.zeros((4, 6, 5), np.uint8)  # z, y, x
    stack[1:3, 2:5, 1:4] = 1
    with tifffile.TiffWriter(tmp_path / "thumb.tif") as tif:
        tif.write(stack, photometric="minisblack")
        tif.write(np.full((2, 2), 255, np.uint8), photometric="minisblack", subfiletype=1)
    with tifffile.TiffFile(tmp_path / "thumb.tif") as tif:
        assert len(tif.series) == 2 and tif.series[1].keyframe.subfiletype == 1
    read = tifffile.imread(tmp_path / "thumb.tif")
    report = json.loads(run(capsys, "info", tmp_path / "thumb.tif", "--json"))
    assert report["shape"] == list(read.shape[::-1]) and report["voxels"] == np.count_nonzero(read) == 18
    with tifffile.TiffWriter(tmp_path / "two.tif") as tif:
        tif.write(stack, photometric="minisblack")
        tif.write(np.ones((2, 2), np.uint8), photometric="minisblack", subfiletype=1)
        tif.write(np.ones((6, 7), np.uint8), photometric="minisblack")
    fails(capsys, "info", tmp_path / "two.tif", words=("two.tif: holds 2 image series", "4x6x5", "6x7"))


@pytest.mark.parametrize("how", ["imagej", "ome", "pages"])


def test_a_tiff_stack_cut_short_is_refused_not_read_as_fewer_slices(tmp_path, capsys, rng, how):
    """A stack cut short where tifffile reads on: ImageJ's stack as its
    first page alone (2D), an OME-TIFF without its OME-XML (no voxel size),
    a file written page by page (Pillow) as the pages before the cut."""
    from PIL import Image

    stack = (rng.random((20, 30, 40)) < 0.5).astype(np.uint8) * 255  # (z, y, x)
    whole = tmp_path / f"whole_{how}.tif"
    if how == "imagej":
        tifffile.imwrite(whole, stack, imagej=True, metadata={"axes": "ZYX", "spacing": 2.0})
    elif how == "ome":
        tifffile.imwrite(whole, stack, ome=True, metadata={"axes": "ZYX", "PhysicalSizeX": 0.5})
    else:
        pages = [Image.fromarray(page) for page in stack]
        pages[0].save(whole, save_all=True, append_images=pages[1:])
    report = info(capsys, whole)
    assert report["shape"] == [40, 30, 20] and report["voxels"] == np.count_nonzero(stack)
    cut = tmp_path / f"cut_{how}.tif"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size * 3 // 10])
    fails(capsys, "info", cut, words=(f"cut_{how}.tif: not a readable TIFF file (cut short or damaged: ",))


@pytest.mark.parametrize("name, what", [("scan.nii.gz", "NIfTI"), ("aseg.mgz", "MGH")])
@pytest.mark.parametrize("labels", [[], ["--labels"]])
def test_a_gzip_file_whose_deflate_data_is_damaged_is_one_line(tmp_path, capsys, name, what, labels):
    """A gzip member whose header is whole but whose deflate data is not
    (a bad disk block, a copy cut and spliced): zlib says "invalid block
    type" (its own exception, not OSError), which the look at the content
    for a hint let through as a traceback after the reader's refusal."""
    import gzip
    import zlib

    damaged = tmp_path / name
    # gzip's 10-byte header, then a first deflate block of the reserved type 3
    damaged.write_bytes(b"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\xff" + b"\xff" * 64)
    with pytest.raises(zlib.error), gzip.open(damaged) as fh:
        fh.read(352)
    fails(capsys, "info", damaged, *labels, words=(f"{name}: not a readable {what} file (zlib.error: ",))


def test_a_tiff_whose_private_tag_points_past_its_end_still_reads(tmp_path, capsys, rng):
    """tifffile logs the tag it cannot read as an error, as it does a page
    cut off; a vendor's private tag is no part of the volume, so the file
    is read, not refused as damaged."""
    import struct

    stack = (rng.random((3, 20, 30)) < 0.5).astype(np.uint8)
    tifffile.imwrite(tmp_path / "ok.tif", stack, photometric="minisblack", extratags=[(65000, "s", 0, "x" * 100, True)])
    with tifffile.TiffFile(tmp_path / "ok.tif") as tif:
        entry = tif.pages[0].tags[65000].offset
    raw = bytearray((tmp_path / "ok.tif").read_bytes())
    struct.pack_into("<I", raw, entry + 8, 10**8)  # the tag's value offset, far past the end
    (tmp_path / "tag.tif").write_bytes(bytes(raw))
    report = info(capsys, tmp_path / "tag.tif")
    assert report["shape"] == [30, 20, 3] and report["voxels"] == np.count_nonzero(stack)


def test_a_tiff_written_a_page_at_a_time_says_how_to_save_its_pages_as_one_stack(tmp_path, capsys, rng):
    """tifffile's TiffWriter.write per slice makes one series per page,
    refused as several series ("save the stack on its own", which it is);
    the line gives the command that saves the pages as one stack, whose
    numbers are the slices' (scikit-image)."""
    import shlex

    measure = pytest.importorskip("skimage.measure")
    stack = rng.random((6, 7, 9)) < 0.4  # (z, y, x)
    with tifffile.TiffWriter(tmp_path / "pages.tif") as tif:
        for page in stack:
            tif.write(page.astype(np.uint8) * 255)
    line = fails(capsys, "info", tmp_path / "pages.tif", words=("pages.tif: holds 6 image series", "a page at a time"))
    code = shlex.split(line.split("give that: ", 1)[1])
    p = subprocess.run([sys.executable, *code[1:]], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    report = info(capsys, tmp_path / "pages_stack.tif")
    vol = np.pad(stack.T, 1)  # isoflow's (x, y, z)
    assert report["shape"] == [9, 7, 6] and report["euler_characteristic"] == measure.euler_number(vol, connectivity=1)
    assert report["betti"][0] == measure.label(vol, connectivity=1).max()


def test_tiff_spacing_that_is_not_a_number(tmp_path, capsys, labels):
    description = "ImageJ=1.54f\nimages=5\nslices=5\nspacing=abc\n"
    tifffile.imwrite(tmp_path / "s.tif", (labels[:5] == 3).astype(np.uint8), description=description, metadata=None)
    fails(capsys, "info", tmp_path / "s.tif", words=("s.tif", "spacing 'abc' is not a number"))


@pytest.mark.parametrize("spacing", [0.0, -2.5])


def test_tiff_spacing_that_is_no_voxel_size_is_named(tmp_path, capsys, labels, spacing):
    """The line names ImageJ's field, not isoflow's word for it ("'pitch'
    must be positive")."""
    stack = (labels[:5] == 3).astype(np.uint8)
    tifffile.imwrite(tmp_path / "s.tif", stack, imagej=True, metadata={"axes": "ZYX", "spacing": spacing})
    fails(capsys, "info", tmp_path / "s.tif", words=(f"s.tif: ImageJ's spacing {spacing!r} is not a positive voxel size",))


def test_nibabel_says_nothing_beside_the_error_line(tmp_path):
    import struct
    import subprocess

    nib.save(nib.Nifti1Image(np.ones((3, 4, 5), np.uint8), np.eye(4)), tmp_path / "ok.nii")
    raw = bytearray((tmp_path / "ok.nii").read_bytes())
    struct.pack_into("<h", raw, 70, 1234)  # datatype: no such code
    (tmp_path / "bad.nii").write_bytes(bytes(raw))
    for quiet in ([], ["-q"]):
        p = subprocess.run([sys.executable, "-m", "isoflow.cli", "info", str(tmp_path / "bad.nii"), *quiet],
                           capture_output=True, text=True)
        lines = p.stderr.strip().splitlines()
        assert p.returncode == 2 and len(lines) == 1 and "bad.nii" in lines[0], p.stderr


def nrrd_file(path, fields: str, data: np.ndarray):
    """An NRRD with a hand-written header (pynrrd's writer checks its fields)."""
    sizes = " ".join(map(str, data.shape[::-1]))  # the file lists the fastest axis first
    header = f"NRRD0004\ntype: uint8\ndimension: {data.ndim}\nsizes: {sizes}\nencoding: raw\n{fields}\n\n"
    path.write_bytes(header.encode() + np.ascontiguousarray(data, np.uint8).tobytes())
    return path


@pytest.mark.parametrize("fields, words", [
    ("space dimension: 3\nspace directions: (1,0,0) (0,1,0)", ("'space directions'",)),
    ("space dimension: 3\nspace directions: (1,0,0) (0,1,0) (0,0,1)\nspace origin: (1,2)", ("'space origin'",)),
    ("spacings: 1 nan 3", ("axis 1 has no spacing and 4 entries",)),
])


def test_nrrd_fields_that_do_not_fit_the_array(tmp_path, capsys, fields, words):
    pytest.importorskip("nrrd")
    path = nrrd_file(tmp_path / "v.nrrd", fields, np.ones((5, 4, 3), np.uint8))
    fails(capsys, "info", path, words=("v.nrrd", *words))


def test_an_nrrd_component_axis_is_told_by_its_kind_without_a_space(tmp_path, capsys, rng):
    """Without space directions, "kinds" is what says an axis holds
    components (pynrrd writes no space unless asked): a colour or vector
    axis was read as a fourth lattice axis, a 4D volume of its channels."""
    nrrd = pytest.importorskip("nrrd")
    vol = rng.random((6, 5, 4)) < 0.5
    domain = ["domain"] * 3
    nrrd.write(str(tmp_path / "rgb.nrrd"), np.stack([vol] * 3).astype(np.uint8), {"kinds": ["RGB-color", *domain]})
    fails(capsys, "info", tmp_path / "rgb.nrrd", words=("rgb.nrrd: axis 0 is of NRRD kind 'RGB-color' with 3 entries",))
    nrrd.write(str(tmp_path / "one.nrrd"), vol[None].astype(np.uint8), {"kinds": ["vector", *domain]})
    report = info(capsys, tmp_path / "one.nrrd")
    assert report["shape"] == [6, 5, 4] and report["voxels"] == np.count_nonzero(vol)
    measure = pytest.importorskip("skimage.measure")
    assert report["euler_characteristic"] == measure.euler_number(np.pad(vol, 1), connectivity=1)
    nrrd.write(str(tmp_path / "t.nrrd"), np.stack([vol, vol], -1).astype(np.uint8), {"kinds": [*domain, "time"]})
    assert info(capsys, tmp_path / "t.nrrd")["shape"] == [6, 5, 4, 2]  # a time axis stays the fourth


def test_nrrd_spacings_and_origin_that_are_not_numbers(tmp_path, capsys, recwarn):
    pytest.importorskip("nrrd")
    vol = np.zeros((5, 1, 3), np.uint8)
    vol[1:4, 0, 1] = 1
    # a nan spacing marks an axis that is not spatial: of length 1, it is dropped
    obj = isoflow.read_volume(nrrd_file(tmp_path / "s.nrrd", "spacings: 2 nan 3", vol))
    assert obj.volume.shape == (3, 5) and obj.voxels == 3
    np.testing.assert_allclose(obj.pitch, [2.0, 3.0])
    moved = "space dimension: 3\nspace directions: (1,0,0) (0,1,0) (0,0,1)\nspace origin: (inf,0,0)"
    obj = isoflow.read_volume(nrrd_file(tmp_path / "o.nrrd", moved, np.ones((2, 2, 2), np.uint8)))
    assert obj.voxels == 8
    np.testing.assert_allclose(obj.origin, -0.5)  # voxel 0's centre at the space origin taken as 0
    assert any("space origin" in str(w.message) and "not finite" in str(w.message) for w in recwarn)


@pytest.mark.parametrize("fields, step, centre", [
    # teem's rule (nrrdAxisInfoPos): a cell-centred sample i (the default)
    # at min + (i + 0.5) * step, a node-centred one at min + i * step; the
    # step is the spacing, or (max - min) over the cells (the gaps between nodes)
    ("spacings: 0.5 1 2\naxis mins: 10 20 30", [0.5, 1, 2], lambda i: [10, 20, 30] + (i + 0.5) * [0.5, 1, 2]),
    ("spacings: 0.5 1 2\naxis mins: 10 20 30\ncenterings: node node node", [0.5, 1, 2],
     lambda i: [10, 20, 30] + i * np.array([0.5, 1, 2])),
    ("axis mins: 10 20 30\naxis maxs: 13 26 38", [0.5, 1, 2], lambda i: [10, 20, 30] + (i + 0.5) * [0.5, 1, 2]),
    ("axis mins: 10 20 30\naxis maxs: 12.5 25 36\ncenterings: node node node", [0.5, 1, 2],
     lambda i: [10, 20, 30] + i * np.array([0.5, 1, 2])),
    ("spacings: -0.5 1 2\naxis mins: 10 20 30", [0.5, 1, 2], lambda i: [10, 20, 30] + (i + 0.5) * [-0.5, 1, 2]),
])


def test_nrrd_without_a_space_is_placed_by_its_axis_mins(tmp_path, fields, step, centre):
    """A file without a space places its samples by ``axis mins`` (and
    ``axis maxs``), cell-centred unless ``centerings`` says node: they
    were dropped, every such file read at origin 0 (and at voxel size 1
    where ``axis maxs`` gave the size)."""
    pytest.importorskip("nrrd")
    at = np.array([2, 3, 1])  # file axes (x fastest): sizes 6 6 4
    vol = np.zeros((4, 6, 6), np.uint8)  # C order: z, y, x
    vol[at[2], at[1], at[0]] = 1
    obj = isoflow.read_volume(nrrd_file(tmp_path / "m.nrrd", fields, vol))
    corner = np.argwhere(obj.volume)[0]
    c = np.asarray(centre(at.astype(float)), float)
    np.testing.assert_allclose(obj.world([corner, corner + 1]), [c - np.array(step) / 2, c + np.array(step) / 2])


def test_an_nrrd_negative_spacing_runs_its_axis_backwards(tmp_path):
    """A negative spacing puts each sample below the one before it, as a
    negative space direction does: its sign was dropped, the volume
    mirrored along that axis."""
    pytest.importorskip("nrrd")
    x = {}
    for i in (1, 4):
        vol = np.zeros((2, 2, 6), np.uint8)
        vol[0, 0, i] = 1
        obj = isoflow.read_volume(nrrd_file(tmp_path / f"v{i}.nrrd", "spacings: -0.5 1 2", vol))
        x[i] = obj.world(np.argwhere(obj.volume))[0, 0]
    assert x[4] == pytest.approx(x[1] - 3 * 0.5)


@pytest.mark.parametrize("chunk, content", [(b"SIZE", b"\x02\x00\x00\x00\x02\x00\x00\x00"), (b"XYZI", b"\x01\x00")])


def test_vox_chunks_too_short_for_what_they_hold(tmp_path, capsys, chunk, content):
    import struct

    size = struct.pack("<3i", 2, 2, 2)
    children = {b"SIZE": b"SIZE" + struct.pack("<ii", len(content), 0) + content,
                b"XYZI": b"SIZE" + struct.pack("<ii", 12, 0) + size + b"XYZI" + struct.pack("<ii", len(content), 0)
                + content}[chunk]
    (tmp_path / "v.vox").write_bytes(b"VOX " + struct.pack("<i", 150) + b"MAIN" + struct.pack("<ii", 0, len(children))
                                     + children)
    fails(capsys, "info", tmp_path / "v.vox", words=("v.vox", f"{chunk.decode()} chunk of {len(content)} bytes"))


def ome_group(path, transforms, level="0", data=None):
    import zarr

    root = zarr.open_group(str(path), mode="w", zarr_format=2)
    if data is not None:
        root.create_array(level, data=data, chunks=(2, 2, 2))
    root.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": n, "type": "space"} for n in "zyx"],
                                  "datasets": [{"path": level, "coordinateTransformations": transforms}]}]
    return root


def test_omezarr_levels_and_transformations_that_are_not_what_they_must_be(tmp_path, capsys):
    pytest.importorskip("zarr")
    data = np.ones((3, 4, 5), np.uint8)
    root = ome_group(tmp_path / "g.zarr", [{"type": "scale", "scale": [1, 1, 1]}], level="grp")
    root.create_group("grp")
    fails(capsys, "info", tmp_path / "g.zarr", words=("g.zarr", "level 'grp' is a group"))
    fails(capsys, "surface", tmp_path / "g.zarr", "-o", tmp_path / "g.ply", words=("level 'grp' is a group",))
    ome_group(tmp_path / "s.zarr", [{"type": "scale", "scale": ["a", 1, 1]}], data=data)
    for command in (["surface", "-o", tmp_path / "s.ply"], ["flow", "--steps", "1"]):
        fails(capsys, command[0], tmp_path / "s.zarr", *command[1:], words=("s.zarr", "scale", "finite numbers"))
    assert not (tmp_path / "s.ply").exists()


@pytest.mark.parametrize("scale, axis, shown", [([1.0, 2.0, -0.5], "x", "-0.5"), ([0.0, 2.0, 0.5], "z", "0")])
def test_an_omezarr_scale_that_is_no_voxel_size_is_named_as_the_file_names_it(tmp_path, scale, axis, shown):
    """A level whose scale is negative or 0 was refused as "'pitch' must
    be positive ... got [-0.5, 2, 1]": isoflow's word for a field the file
    does not have, its values turned to x, y, z. The line names the
    level's scale, the axis and its value as the file stores them."""
    pytest.importorskip("zarr")
    ome_group(tmp_path / "n.zarr", [{"type": "scale", "scale": scale}], data=np.ones((3, 4, 5), np.uint8))
    for command in (["info"], ["surface", "-o", str(tmp_path / "n.ply")], ["info", "--labels"]):
        done = subprocess.run([sys.executable, "-m", "isoflow", command[0], str(tmp_path / "n.zarr"), *command[1:]],
                              capture_output=True, text=True)
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
        assert (f"n.zarr: OME-Zarr level '0': the scale of axis '{axis}' is {shown} " in lines[0]
                and "pitch" not in lines[0]), lines[0]
    assert not (tmp_path / "n.ply").exists()


def damaged_store(path, data, chunks=(4, 4, 4), ome=False):
    """A zarr store whose chunk 0.0.0 (0.0.0 of level 0) is garbage."""
    import zarr

    if ome:
        root = ome_group(path, [{"type": "scale", "scale": [1, 1, 1]}])
        root.create_array("0", data=data, chunks=chunks)
        chunk = path / "0" / "0.0.0"
    else:
        zarr.create_array(str(path), data=data, chunks=chunks, zarr_format=2)
        chunk = path / "0.0.0"
    assert chunk.exists()
    chunk.write_bytes(b"garbage")
    return path


@pytest.mark.parametrize("ome", [False, True])


def test_info_on_a_zarr_store_with_a_damaged_chunk(tmp_path, capsys, labels, ome):
    pytest.importorskip("zarr")
    store = damaged_store(tmp_path / "d.zarr", (labels == 3).astype(np.uint8), ome=ome)
    for extra in ([], ["--no-surfaces"], ["--label", "1"]):
        fails(capsys, "info", store, *extra, words=("d.zarr", "cannot read"))
    fails(capsys, "surface", store, "-o", tmp_path / "d.ply", words=("d.zarr",))


def test_info_on_a_zarr_store_refuses_a_label_no_voxel_has(tmp_path, capsys, labels):
    zarr = pytest.importorskip("zarr")
    zarr.create_array(str(tmp_path / "l.zarr"), data=labels, chunks=(5, 5, 5), zarr_format=2)
    np.save(tmp_path / "l.npy", labels)
    for name in ("l.zarr", "l.npy"):
        fails(capsys, "info", tmp_path / name, "--label", "9", words=(name, "no voxel has label 9", "0, 3, 5"))
    assert info(capsys, tmp_path / "l.zarr", "--label", "5")["voxels"] == int((labels == 5).sum())


def test_a_4d_zarr_array_is_read_whole_by_info(tmp_path, capsys, rng):
    zarr = pytest.importorskip("zarr")
    vol = rng.random((4, 5, 3, 6)) < 0.4  # edge and vertex contacts in 4D
    zarr.create_array(str(tmp_path / "v.zarr"), data=vol, chunks=(2, 2, 2, 2), zarr_format=2)
    np.save(tmp_path / "v.npy", vol)
    a, b = info(capsys, tmp_path / "v.zarr"), info(capsys, tmp_path / "v.npy")
    assert a == b and a["dimension"] == 4


def test_writing_names_the_output_not_its_temporary_file(tmp_path, capsys):
    mesh = tmp_path / "t.stl"
    trimesh.creation.torus(2.0, 0.8).export(mesh)
    assert main(["voxelize", str(mesh), "--resolution", "12", "-o", str(tmp_path / "t.vox")]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "isoflow-tmp" not in err[0]
    assert f"{tmp_path / 't.vox'}: MagicaVoxel keeps no voxel size, origin or unit" in err[0]
    fails(capsys, "voxelize", mesh, "--resolution", "300", "-o", tmp_path / "big.vox",
          words=(f"{tmp_path / 'big.vox'}: MagicaVoxel models are at most 256", "; voxelise it coarser (--resolution 256)"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.stl", "t.vox"]  # nothing else left
    pytest.importorskip("zarr")
    isoflow.write_volume(isoflow.DigitalObject(np.ones((2, 3, 4), bool)), tmp_path / "img.zarr")
    import zarr

    assert zarr.open_group(str(tmp_path / "img.zarr"), mode="r").attrs["multiscales"][0]["name"] == "img.zarr"


def test_flow_refuses_a_volume_suffix_before_making_the_output_directory(tmp_path, capsys):
    np.save(tmp_path / "b.npy", np.ones((3, 3, 3), bool))
    for suffix in (".nhdr", ".foo"):
        fails(capsys, "flow", tmp_path / "b.npy", "--steps", "1", "--out", tmp_path / "fo", "--volumes", suffix,
              words=(f"--volumes {suffix}", ".nii.gz"))
        assert not (tmp_path / "fo").exists()


def test_flow_of_a_4d_volume_names_the_file(tmp_path, capsys):
    np.save(tmp_path / "4d.npy", np.ones((2, 2, 2, 2), bool))
    fails(capsys, "flow", tmp_path / "4d.npy", words=("4d.npy", "2D and 3D", "4D"))


def test_axis_names_and_dataset_paths(tmp_path, capsys):
    zarr = pytest.importorskip("zarr")
    root = zarr.open_group(str(tmp_path / "a.zarr"), mode="w", zarr_format=2)
    root.create_array("0", data=np.ones((2, 3, 4), np.uint8), chunks=(2, 2, 2))
    root.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": n} for n in "xxy"], "datasets": [{"path": "0"}]}]
    fails(capsys, "info", tmp_path / "a.zarr", words=("axes xxy name a spatial axis twice",))
    root.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": n} for n in "abc"], "datasets": [{"path": "0"}]}]
    fails(capsys, "info", tmp_path / "a.zarr", words=("axes abc hold fewer than two of x, y, z",))
    pytest.importorskip("h5py")
    isoflow.write_volume(isoflow.DigitalObject(np.ones((2, 3, 4), bool)), f"{tmp_path / 'v.h5'}:/a:b")
    assert isoflow.read_volume(f"{tmp_path / 'v.h5'}:/a:b").voxels == 24


def test_a_grid_turned_by_exactly_45_degrees_is_read_with_the_warning(tmp_path, capsys, labels):
    """A rotation of 45 degrees runs two array axes equally along two world
    axes: they keep their order (the first of the tied assignments), and
    the warning names the angle, as for any other rotation."""
    c = np.cos(np.pi / 4)
    affine = np.array([[c, -c, 0, 0], [c, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    nib.save(nib.Nifti1Image((labels == 3).astype(np.uint8), affine), tmp_path / "rot45.nii.gz")
    np.save(tmp_path / "l.npy", labels == 3)
    assert main(["info", str(tmp_path / "rot45.nii.gz"), "--json"]) == 0
    io = capsys.readouterr()
    got = json.loads(io.out)
    assert "rotated or sheared by up to 45 degrees" in io.err and len(io.err.strip().splitlines()) == 1
    want = info(capsys, tmp_path / "l.npy")
    assert got["shape"] == want["shape"] and got["betti"] == want["betti"] and got["voxels"] == want["voxels"]


def test_flow_force_replaces_step_volumes_of_any_suffix_and_warns_once(tmp_path, capsys):
    """A --force run removes the step volumes of an earlier run that wrote
    another --volumes suffix (or whose volumes this run does not write), and
    a warning every step's file would repeat is said once, naming the
    output's files, not their staging copies."""
    big = np.zeros((10, 10, 10), bool)
    big[1:9, 1:9, 1:9] = True
    np.save(tmp_path / "big.npy", big)
    isoflow.write_volume(isoflow.DigitalObject(np.ones((3, 3, 3), bool), origin=(1.0, 2.0, 3.0)),
                         tmp_path / "small.npz")
    out = tmp_path / "R"
    run(capsys, "flow", tmp_path / "big.npy", "--out", out, "--volumes", ".npz")
    assert len(list(out.glob("step_*.npz"))) > 3
    (out / "step_notes.txt").write_text("mine")  # not a step file: kept
    assert main(["flow", str(tmp_path / "small.npz"), "--out", str(out), "--force", "--volumes", "vox"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"isoflow flow: warning: {out}/step_000.vox: MagicaVoxel keeps no voxel size, origin or unit; "
                   "origin [1, 2, 3] is not written (read back as voxel size 1, origin 0)"], err
    steps = sorted(p.name for p in out.glob("step_*"))
    plys = sorted(p.name for p in out.glob("step_*.ply"))
    assert steps == sorted([*plys, *(n.replace(".ply", ".vox") for n in plys), "step_notes.txt"])
    run(capsys, "flow", tmp_path / "small.npz", "--out", out, "--force")  # no volumes now: none left
    assert sorted(p.name for p in out.glob("step_*")) == sorted([*plys, "step_notes.txt"])


@pytest.mark.parametrize("suffix", [".vox", ".png"])
def test_a_format_without_placement_warns_only_of_what_reads_back_otherwise(tmp_path, suffix):
    """A .vox or .png reads back as voxel size 1 from 0: a pitch of 1 is
    kept and not named among what is lost (MagicaVoxel's warning named
    "pitch [1, 1, 1]"); an origin is; at pitch 1 and origin 0 nothing is
    said. What is said lost is what the file, read back by isoflow, lacks."""
    shape = (3, 3, 3) if suffix == ".vox" else (3, 3)
    placed = isoflow.DigitalObject(np.ones(shape, bool), origin=(4.0,) * len(shape))
    with pytest.warns(isoflow.IsoflowWarning) as said:
        isoflow.write_volume(placed, tmp_path / f"a{suffix}")
    text = " ".join(str(w.message) for w in said)
    back = isoflow.read_volume(tmp_path / f"a{suffix}")
    assert (back.spacing == 1).all() and (back.world(np.zeros(len(shape))) == 0).all()  # as the warning says
    assert f"origin {[4] * len(shape)}".replace(" ", "") in text.replace(" ", "") and "pitch" not in text, text
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        isoflow.write_volume(isoflow.DigitalObject(np.ones(shape, bool)), tmp_path / f"b{suffix}")


def test_flow_refuses_an_empty_volume_suffix(tmp_path, capsys):
    np.save(tmp_path / "b.npy", np.ones((3, 3, 3), bool))
    fails(capsys, "flow", tmp_path / "b.npy", "--out", tmp_path / "V", "--volumes", "", words=("--volumes",))
    fails(capsys, "flow", tmp_path / "b.npy", "--volumes", "", words=("--out",))
    assert not (tmp_path / "V").exists()


def test_the_extras_the_messages_name_bring_those_libraries():
    """Every 'pip install isoflow[formats]' message must name an extra that
    brings the library (it had been lost in a merge): each volume format's
    library and each mesh format's reader are in the formats extra of
    pyproject.toml, and zarr's version is the one its code calls (zarr 3's
    create_array and open_group(zarr_format=...))."""
    import tomllib
    from pathlib import Path

    from isoflow.mesh.formats.registry import EXTRA, FORMATS
    from isoflow.mesh.load import _PACKAGE, FORMAT_NEEDS

    meta = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    extras = meta["project"]["optional-dependencies"]

    def names(extra):
        return {re.split(r"[<>=\[]", req)[0].strip().lower() for req in extras[extra]}

    wanted = {f.library for f in FORMATS if f.library} | {_PACKAGE[m] for ms in FORMAT_NEEDS.values() for m in ms}
    assert wanted <= names(EXTRA), wanted - names(EXTRA)
    for extra in (EXTRA, "dask"):
        zarr_req = next(r for r in extras[extra] if r.startswith("zarr"))
        assert zarr_req == "zarr>=3", (extra, zarr_req)


def test_a_mask_written_0_255_is_that_mask_in_every_format(tmp_path, capsys, labels):
    """Image tools write masks as 0 and 255 (or 0 and -1, 0 and 255.0): a
    volume whose only nonzero value is one v is the mask of v (what --label v
    gives); two nonzero values are still refused."""
    from PIL import Image

    mask = labels == 3
    want = info(capsys, _saved(tmp_path / "mask.npy", mask))
    files = [_saved(tmp_path / "m255.npy", mask.astype(np.uint8) * 255),
             _saved(tmp_path / "m_1.npy", -mask.astype(np.int8)),
             _saved(tmp_path / "m255f.npy", mask * np.float32(255))]
    tifffile.imwrite(tmp_path / "m255.tif", np.ascontiguousarray((mask * 255).astype(np.uint8).T))  # (z, y, x)
    nib.save(nib.Nifti1Image((mask * 255).astype(np.int16), np.eye(4)), tmp_path / "m255.nii.gz")
    files += [tmp_path / "m255.tif", tmp_path / "m255.nii.gz"]
    for path in files:
        got = info(capsys, path)
        assert [got[k] for k in ("voxels", "betti", "n")] == [want[k] for k in ("voxels", "betti", "n")], path
    flat = mask[:, :, 5]
    Image.fromarray((flat.T * 255).astype(np.uint8)).save(tmp_path / "m255.png")  # rows are y
    assert info(capsys, tmp_path / "m255.png")["betti"] == isoflow.analyze(flat)["betti"]
    fails(capsys, "info", _saved(tmp_path / "two.npy", labels), words=("not a binary volume", "--label N"))


def test_what_the_readers_take_for_a_mask_is_written_as_one_and_read_so_block_by_block(tmp_path):
    """A mask is 0 and one other value (docs/formats.md). The readers took
    0/-1 and 0/0.5 arrays for masks, but ``write_volume`` refused the same
    arrays, and a store of 0/0.5 read block by block was refused where read
    whole it was a mask. Now each is that value's mask on every side: as
    nibabel reads the NIfTI written, and as scikit-image counts it."""
    zarr = pytest.importorskip("zarr")
    measure = pytest.importorskip("skimage.measure")
    mask = np.random.default_rng(4).random((9, 10, 11)) < 0.4
    write = "import sys, numpy as np, isoflow; isoflow.write_volume(np.load(sys.argv[1]), sys.argv[2])"
    for name, array in (("minus", -mask.astype(np.int16)), ("half", mask * np.float32(0.5)),
                        ("grey", mask.astype(np.uint8) * 255)):
        done = subprocess.run([sys.executable, "-c", write, _saved(tmp_path / f"{name}.npy", array),
                               tmp_path / f"{name}.nii.gz"], capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        assert np.array_equal(np.asarray(nib.load(tmp_path / f"{name}.nii.gz").dataobj), mask), name
    zarr.create_array(str(tmp_path / "half.zarr"), data=mask * np.float32(0.5), chunks=(4, 4, 4))
    for source in ("half.npy", "half.zarr"):  # read whole, and block by block
        done = isoflow_here("info", tmp_path / source, "--json")
        assert done.returncode == 0, done.stderr
        report = json.loads(done.stdout)
        assert report["voxels"] == np.count_nonzero(mask), source
        assert report["euler_characteristic"] == measure.euler_number(mask, connectivity=1), source
    with pytest.raises(isoflow.IsoflowError, match="not a binary volume"):  # two values beside 0: no mask
        isoflow.write_volume(mask * 0.5 + np.eye(9, 10)[:, :, None] * mask, tmp_path / "two.npy")


def _saved(path, array):
    np.save(path, array)
    return path


def vigra_axistags(keys: str) -> str:
    """The ``axistags`` attribute vigra's ``AxisTags.toJSON()`` writes, as
    ilastik puts it on its exports (typeFlags: 1 channel, 2 space, 8 time)."""
    flags = {"c": 1, "t": 8}
    return json.dumps({"axes": [{"key": k, "typeFlags": flags.get(k, 2), "resolution": 0, "description": ""}
                                for k in keys]}, indent=2)


def test_an_ilastik_export_is_read_by_its_axistags(tmp_path):
    """ilastik exports ``exported_data`` as (z, y, x, c) with vigra's
    ``axistags``. Its channel axis was read as a fourth spatial or time
    axis: a Simple Segmentation (c of 1) as a 4D volume one voxel thick,
    whose b1 and b2 are not counted, and two channels of a mask as a 4D
    series of 336 voxels. A channel of one entry is dropped, as an
    OME-Zarr's and a TIFF's are, and several are refused; the counts are
    numpy's of the array h5py reads."""
    h5py = pytest.importorskip("h5py")
    segmentation = np.ones((8, 7, 6, 1), np.uint8)  # ilastik's labels: 1 background, 2 the object
    segmentation[2:5, 1:4, 1:5] = 2
    segmentation[6, 5, 4] = 2
    with h5py.File(tmp_path / "seg.h5", "w") as f:
        f.create_dataset("exported_data", data=segmentation).attrs["axistags"] = vigra_axistags("zyxc")
    with h5py.File(tmp_path / "two.h5", "w") as f:
        data = np.stack([segmentation[..., 0] == 2, segmentation[..., 0] == 1], axis=-1).astype(np.uint8)
        f.create_dataset("exported_data", data=data).attrs["axistags"] = vigra_axistags("zyxc")

    def isoflow_cli(*args):
        return isoflow_here(*map(str, args))

    done = isoflow_cli("info", tmp_path / "seg.h5", "--label", "2", "--json")
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    with h5py.File(tmp_path / "seg.h5") as f:
        stored = f["exported_data"][()]
    # (z, y, x) as the tags name them: read as isoflow's (x, y, z)
    assert got["shape"] == list(stored.shape[2::-1]) and got["voxels"] == np.count_nonzero(stored == 2)
    from scipy import ndimage

    # a box and a voxel apart: counted in 3D (b1 and b2 of a 4D reading were not counted)
    assert got["betti"] == [ndimage.label(stored[..., 0] == 2)[1], 0, 0] == [2, 0, 0]
    done = isoflow_cli("info", tmp_path / "two.h5")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert "axis 'c' has 2 entries (axistags zyxc, shape (8, 7, 6, 2))" in lines[0], lines[0]


@pytest.mark.parametrize("sizes", [[2.0, 0.5, 0.25, 1.0], [2.0, 0.5, 0.25]])  # per stored axis, or per z, y, x
def test_an_ilastik_export_is_placed_by_its_axistags_not_mirrored(tmp_path, sizes):
    """ilastik stores (z, y, x, c) and names the axes in ``axistags``;
    Fiji's HDF5 plug-in gives ``element_size_um`` in the same order. The
    tagged dataset was read as stored, its z as isoflow's x: a bar along
    x was reported along x from 2 to 6 um (its z extent) with z's voxel
    size, and its surface written mirrored (x and z swapped). The truth is
    h5py's array placed by the tags: the bar's voxels' corners times the
    voxel size of their own axis."""
    h5py = pytest.importorskip("h5py")
    zyx = np.zeros((4, 6, 10, 1), np.uint8)
    zyx[1:3, 1:2, 2:9, 0] = 1  # a bar along x
    with h5py.File(tmp_path / "bar.h5", "w") as f:
        data = f.create_dataset("exported_data", data=zyx)
        data.attrs["axistags"] = vigra_axistags("zyxc")
        data.attrs["element_size_um"] = sizes
    with h5py.File(tmp_path / "bar.h5") as f:
        stored = f["exported_data"][()]
        size_zyx = np.asarray(f["exported_data"].attrs["element_size_um"][:3])
    z, y, x = np.nonzero(stored[..., 0])
    cells = np.stack([x, y, z], axis=1)
    size = size_zyx[::-1]
    low, high = cells.min(0) * size, (cells.max(0) + 1) * size

    def isoflow_cli(*args):
        return isoflow_here(*map(str, args), cwd=tmp_path)

    done = isoflow_cli("info", "bar.h5", "--json")
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    assert got["shape"] == [10, 6, 4] and got["unit"] == "\u00b5m"
    assert np.allclose(got["pitch"], size) and np.allclose(got["bbox"], np.concatenate([low, high]))
    done = isoflow_cli("surface", "bar.h5", "-o", "bar.ply")
    assert done.returncode == 0, done.stderr
    mesh = trimesh.load(tmp_path / "bar.ply", process=False)
    assert np.allclose(mesh.bounds, [low, high])
    assert np.isclose(mesh.volume, len(cells) * np.prod(size))


def test_a_plain_zarr_array_named_z_y_x_is_read_by_its_names(tmp_path, capsys):
    """A plain zarr v3 array (no OME-Zarr metadata) whose
    ``dimension_names`` are z, y, x (as xarray and tensorstore write them)
    was read as stored, its z as x, with a warning: the mirror image of
    the volume its names describe. It is read by its names, as OME-Zarr's
    axes are, in memory and block by block (odd chunks): a bar along the
    stored axis 0 lies along z, its box numpy's of the array transposed,
    the surface trimesh reads back that of the transposed array; a
    ``pitch`` attribute of an entry per stored axis is turned with the
    axes. Names that are not x, y, z in some order (z, y, x, c) are still
    read as stored, and said so."""
    zarr = pytest.importorskip("zarr")
    pytest.importorskip("dask")
    from isoflow.flow.chunked import source_volume

    zyx = np.zeros((9, 4, 5), np.uint8)
    zyx[1:8, 1:3, 2:4] = 1  # a bar along stored axis 0, which the names call z
    xyz = zyx.T
    cells = np.argwhere(xyz)
    box = [*cells.min(0).tolist(), *(cells.max(0) + 1).tolist()]  # voxel corners, as isoflow's bbox
    assert box[5] - box[2] == 7  # the bar runs along z
    zarr.create_array(str(tmp_path / "zyx.zarr"), data=zyx, chunks=(4, 3, 2), dimension_names=["z", "y", "x"])
    np.save(tmp_path / "xyz.npy", xyz)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no word on the axes: they are read as named
        assert np.array_equal(isoflow.read_volume(tmp_path / "zyx.zarr").volume, xyz)
        assert np.array_equal(isoflow.read_labels(tmp_path / "zyx.zarr").array, xyz)
    done = isoflow_here("info", "zyx.zarr", "--json", cwd=tmp_path)
    assert done.returncode == 0 and "dimension_names" not in done.stderr, done.stderr
    stored = json.loads(done.stdout)  # read block by block
    assert stored["shape"] == list(xyz.shape) and stored["bbox"] == box
    stored.pop("input"), stored.pop("dtype")
    whole = json.loads(run(capsys, "info", tmp_path / "xyz.npy", "--json"))
    assert stored == {k: v for k, v in whole.items() if k not in ("input", "dtype")}
    table = json.loads(run(capsys, "info", tmp_path / "zyx.zarr", "--labels", "--json"))  # layers of blocks
    assert np.array_equal(source_volume(tmp_path / "zyx.zarr")[0].compute(), xyz)  # flow --volumes .zarr's input
    assert [table["labels"][0][f"bbox-{i}"] for i in range(6)] == box
    run(capsys, "surface", tmp_path / "zyx.zarr", "-o", tmp_path / "s.ply")  # block by block
    run(capsys, "surface", tmp_path / "xyz.npy", "-o", tmp_path / "t.ply")
    got, want = (trimesh.load(tmp_path / name, process=False) for name in ("s.ply", "t.ply"))
    assert np.allclose(got.bounds, [box[:3], box[3:]]) and np.allclose(want.bounds, got.bounds)
    assert np.isclose(got.volume, len(cells)) and np.isclose(want.volume, got.volume)

    placed = zarr.create_array(str(tmp_path / "p.zarr"), data=zyx, chunks=(4, 3, 2), dimension_names=list("zyx"))
    placed.attrs.update(pitch=[2.0, 1.0, 0.5], origin=[30.0, 20.0, 10.0])  # stored order: z first
    obj = isoflow.read_volume(tmp_path / "p.zarr")
    assert obj.pitch.tolist() == [0.5, 1.0, 2.0] and obj.origin.tolist() == [10.0, 20.0, 30.0]
    world = (np.array(box) * ([0.5, 1.0, 2.0] * 2) + [10.0, 20.0, 30.0] * 2).tolist()
    assert isoflow.analyze_zarr(tmp_path / "p.zarr").bbox == world
    table = json.loads(run(capsys, "info", tmp_path / "p.zarr", "--labels", "--json"))
    assert [table["labels"][0][f"bbox-{i}"] for i in range(6)] == world

    zarr.create_array(str(tmp_path / "yx.zarr"), data=zyx[:, 0], chunks=(4, 3), dimension_names=["y", "x"])
    assert np.array_equal(isoflow.read_volume(tmp_path / "yx.zarr").volume, zyx[:, 0].T)
    zarr.create_array(str(tmp_path / "c.zarr"), data=zyx[..., None], dimension_names=list("zyxc"))
    with pytest.warns(isoflow.IsoflowWarning, match="read as stored"):
        assert np.array_equal(isoflow.read_labels(tmp_path / "c.zarr").array, zyx)


def test_a_dataset_an_hdf5_external_link_names_is_read_and_listed(tmp_path):
    """A file that gathers other files' volumes by external links
    (``f["v"] = h5py.ExternalLink("scan.h5", "/v")``) was "holds no dataset",
    though h5py reads ``f["v"]`` through the link, and the link was left
    out of the list to choose from beside a dataset of the file's own. The
    voxel count is h5py's read through the link; a link whose file is
    not there is named in the refusal."""
    h5py = pytest.importorskip("h5py")
    volume = np.zeros((6, 7, 8), np.uint8)
    volume[1:4, 2:5, 3:6] = 1
    volume[4, 5, 6] = 1
    with h5py.File(tmp_path / "scan.h5", "w") as f:
        f["v"] = volume
    with h5py.File(tmp_path / "links.h5", "w") as f:
        f["v"] = h5py.ExternalLink("scan.h5", "/v")
    with h5py.File(tmp_path / "both.h5", "w") as f:
        f["a"] = np.ones((3, 3, 3), np.uint8)
        f["g/ext"] = h5py.ExternalLink("scan.h5", "/v")
    with h5py.File(tmp_path / "dangling.h5", "w") as f:
        f["v"] = h5py.ExternalLink("gone.h5", "/v")
    with h5py.File(tmp_path / "links.h5") as f:
        voxels = int(np.count_nonzero(f["v"][()]))

    def isoflow_cli(*args):
        return isoflow_here(*map(str, args), cwd=tmp_path)

    done = isoflow_cli("info", "links.h5", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["voxels"] == voxels == 28
    done = isoflow_cli("info", "both.h5")
    assert done.returncode == 2 and done.stderr.strip().splitlines() == [
        "isoflow info: error: both.h5: holds datasets /a, /g/ext; name one, e.g. both.h5:/a"], done.stderr
    done = isoflow_cli("info", "both.h5:/g/ext", "--json")
    assert done.returncode == 0 and json.loads(done.stdout)["voxels"] == voxels, done.stderr
    done = isoflow_cli("info", "dangling.h5")
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "gone.h5:/v" in lines[0], done.stderr


def test_a_dataset_written_into_an_hdf5_file_keeps_its_other_datasets(tmp_path, capsys, labels):
    """``-o FILE.h5:/name`` adds a dataset to an existing file, as h5py's
    own ``File(path, "a")`` would: the other datasets, their attributes and
    the file's groups stay as they were (read back by h5py, not by isoflow);
    the same dataset again is refused without --force and replaced with it."""
    h5py = pytest.importorskip("h5py")
    target = tmp_path / "scan.h5"
    raw = np.arange(24, dtype=np.float32).reshape(2, 3, 4)
    with h5py.File(target, "w") as f:  # a file another tool wrote
        f.create_dataset("raw/image", data=raw).attrs["element_size_um"] = (0.5, 0.5, 2.0)
    trimesh.creation.box((2.0, 3.0, 4.0)).export(tmp_path / "box.stl")
    box = tmp_path / "box.stl"
    assert run(capsys, "voxelize", box, "--pitch", "1", "-o", f"{target}:/seg/box").startswith(f"{target}:/seg/box: 24 voxels")
    with h5py.File(target, "r") as f:
        assert np.array_equal(f["raw/image"][()], raw)
        assert tuple(f["raw/image"].attrs["element_size_um"]) == (0.5, 0.5, 2.0)
        assert int(f["seg/box"][()].sum()) == 2 * 3 * 4  # the box's unit voxels
    fails(capsys, "voxelize", box, "--pitch", "0.5", "-o", f"{target}:/seg/box", words=("holds /seg/box already", "--force"))
    fails(capsys, "voxelize", box, "--pitch", "0.5", "-o", f"{target}:/seg", "--force", words=("/seg is a group",))
    fails(capsys, "voxelize", box, "--pitch", "0.5", "-o", f"{target}:/raw/image/x", words=("/raw/image is a dataset",))
    run(capsys, "voxelize", box, "--pitch", "0.5", "-o", f"{target}:/seg/box", "--force")
    with h5py.File(target, "r") as f:
        assert sorted(k for k in ("raw/image", "seg/box") if k in f) == ["raw/image", "seg/box"]
        assert np.array_equal(f["raw/image"][()], raw)
        assert int(f["seg/box"][()].sum()) == 4 * 6 * 8
    assert isoflow.read_volume(f"{target}:/seg/box").voxels == 4 * 6 * 8
    # the file named without a dataset is the file: --force replaces all of it
    fails(capsys, "voxelize", box, "--pitch", "1", "-o", target, words=("exists", "--force"))
    run(capsys, "voxelize", box, "--pitch", "1", "-o", target, "--force")
    with h5py.File(target, "r") as f:
        assert "raw" not in f and "seg" not in f and int(f["volume"][()].sum()) == 24


APPEND_PEAK = """
import json, re, sys
import numpy as np
import isoflow
from isoflow.scale import memory

def status(key):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))

target, warm = sys.argv[1], sys.argv[2]
obj = isoflow.DigitalObject(np.random.default_rng(1).random((64, 64, 64)) < 0.3)
isoflow.write_volume(obj, warm + ":/seg")  # h5py's modules loaded before the peak is taken
with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")
before = status("VmRSS")
isoflow.write_volume(obj, target + ":/seg")
peak = status("VmHWM") - before
memory.default_budget = lambda: 1
try:
    isoflow.write_volume(obj, target + ":/seg", force=True)
    need = 0.0
except isoflow.IsoflowError as exc:
    need = float(re.search(r"needs about ([0-9.]+) MiB", str(exc)).group(1)) * 2**20
print(json.dumps({"peak": peak, "estimate": need}))
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the peak is read from /proc/self/status")
def test_a_dataset_added_to_a_large_hdf5_file_counts_the_file_in_memory(tmp_path, capsys, monkeypatch):
    """``-o FILE.h5:/name`` reads the existing file whole into memory (and
    holds the image written out beside it), which no memory check
    counted: a dataset of a few voxels added to a file larger than memory
    ran until the system killed it. The file is counted, before any work
    and again with the dataset before the write: the estimate covers the
    peak the kernel measures, and a budget below it is refused in one line
    naming h5copy, the file left as h5py read it."""
    h5py = pytest.importorskip("h5py")
    from isoflow.scale import memory

    target, warm = tmp_path / "scan.h5", tmp_path / "warm.h5"
    raw = np.random.default_rng(0).integers(0, 255, 24 << 20, dtype=np.uint8)  # 24 MiB that gzip cannot shrink
    for path in (target, warm):
        with h5py.File(path, "w") as f:  # a file another tool wrote
            f.create_dataset("raw", data=raw if path == target else raw[:1000])
    size = target.stat().st_size
    if os.access("/proc/self/clear_refs", os.W_OK):
        p = subprocess.run([sys.executable, "-c", APPEND_PEAK, str(target), str(warm)], capture_output=True,
                           text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        got = json.loads(p.stdout)
        assert got["peak"] > 1.5 * size  # the file twice, as the kernel measures it
        assert 0.95 * got["peak"] <= got["estimate"] <= 2 * got["peak"], got
        with h5py.File(target, "a") as f:
            del f["seg"]
    trimesh.creation.box((2.0, 3.0, 4.0)).export(tmp_path / "box.stl")
    monkeypatch.setattr(memory, "default_budget", lambda: size)  # the voxels fit, the file's two copies do not
    err = fails(capsys, "voxelize", tmp_path / "box.stl", "--pitch", "1", "-o", f"{target}:/seg",
                words=(f"{target}: adding /seg holds this file of 24.0 MiB in memory twice", "h5copy -i NEW.h5"))
    assert "Traceback" not in err
    with h5py.File(target, "r") as f:
        assert list(f) == ["raw"] and np.array_equal(f["raw"][:1000], raw[:1000])


WRITE_PEAK = """
import json, sys
import numpy as np
import isoflow

suffix, dtype, top, n, folder = sys.argv[1], np.dtype(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]

def status(key):
    with open("/proc/self/status") as fh:
        return next(int(line.split()[1]) * 1024 for line in fh if line.startswith(key))

def made(n):  # random (what a compressor shrinks least) or full, a slab at a time: no temporary of its size
    vol, rng = np.empty((n, n, n), dtype), np.random.default_rng(1)
    for i in range(n):
        if top == 0:
            vol[i] = rng.random((n, n)) < 0.5
        else:
            vol[i] = True if top == 1 else rng.integers(0, top, (n, n), dtype, endpoint=True)
    if dtype != bool:
        vol.flat[-1] = top  # the labels need their type
    return isoflow.DigitalObject(vol) if dtype == bool else vol

def write(vol, path):
    isoflow.write_volume(vol, path) if dtype == bool else isoflow.write_labels(vol, path)

write(made(4), folder + "/warm" + suffix)  # the library's modules loaded before the peak is taken
vol = made(n)
with open("/proc/self/clear_refs", "w") as fh:
    fh.write("5")
before = status("VmRSS")
write(vol, folder + "/out" + suffix)
print(json.dumps({"peak": status("VmHWM") - before, "voxels": n ** 3, "itemsize": dtype.itemsize}))
"""


def write_peak(tmp_path, suffix: str, dtype: str, top: int, side: int) -> dict:
    """The peak resident memory that writing a volume of ``side``^3 to
    ``suffix`` adds to the volume's, in a fresh process: a random mask
    (``top`` 0), a full one (1), or random labels from 0 to ``top``."""
    folder = tmp_path / f"{dtype}-{side}"
    folder.mkdir()
    p = subprocess.run([sys.executable, "-c", WRITE_PEAK, suffix, dtype, str(top), str(side), str(folder)],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.mark.skipif(not os.access("/proc/self/clear_refs", os.W_OK), reason="the peak is read from /proc/self/status")
@pytest.mark.parametrize("suffix, dtype, top, sides", [
    (".h5", "bool", 0, (256, 384)),  # a random mask: the gzip stream that shrinks least
    (".h5", "uint16", 65535, (192, 256)),  # random labels: a stream as large as they are
    (".mgh", "uint16", 65535, (160,)),  # labels above 32767, which MGH stores as int32
    (".vox", "bool", 1, (64,)),  # every voxel set, each listed by its coordinates
])
def test_the_memory_a_writer_holds_is_what_voxelize_counts_for_it(tmp_path, suffix, dtype, top, sides):
    """``voxelize -o`` lets a grid in only where the output's writer fits
    beside the volume, counting ``write_bytes`` per voxel (per byte of
    labels). HDF5's 0.2 was less than half of what h5py's in-memory file
    holds for a random mask, MGH counted nothing for the int32 copy of uint16
    labels, MagicaVoxel's 32 half of its coordinate lists: a grid let in
    could then run out of memory while it was written. MagicaVoxel's list is
    now a byte each of x, y, z and colour (4 bytes a voxel set), counted 4.5,
    which a writer holding int64 coordinates exceeds. The peak the kernel
    measures for the write (its part that grows with the voxels, from two
    sizes, where the writer holds a fixed amount too) is now within the
    estimate (to 5 %) and at least half of it."""
    from isoflow.mesh.volumes import write_bytes_per_voxel

    got = [write_peak(tmp_path, suffix, dtype, top, side) for side in sides]
    if len(got) == 2:  # what grows with the voxels, less HDF5's fixed buffers
        measured = (got[1]["peak"] - got[0]["peak"]) / (got[1]["voxels"] - got[0]["voxels"])
    else:
        measured = got[0]["peak"] / got[0]["voxels"]
    estimate = write_bytes_per_voxel("out" + suffix, labels=dtype != "bool") * got[0]["itemsize"]
    assert 0.95 * measured <= estimate <= 2 * measured, (measured, estimate, got)


def test_an_array_of_a_plain_zarr_group_is_named_after_a_colon(tmp_path, capsys):
    # a zarr group of several arrays (an image, its segmentation and a mask)
    # was refused with "name the volume 'volume'", and STORE.zarr:NAME with
    # "not an OME-Zarr image, so it has no level": a store that cannot be
    # written to could not be read at all; the name now picks the array
    zarr = pytest.importorskip("zarr")
    skimage_measure = pytest.importorskip("skimage.measure")
    seg = np.zeros((9, 8, 7), np.uint16)
    seg[1:4, 1:5, 1:4], seg[5:8, 0:7, 0:6] = 4, 9
    seg[6, 3, 2] = 0  # a hole inside label 9's slab: b2 = 1
    group = zarr.open_group(str(tmp_path / "user.zarr"), mode="w")
    group.create_array("image", data=np.random.default_rng(0).random(seg.shape), chunks=(4, 3, 5))
    group.create_array("seg", data=seg, chunks=(4, 3, 5))
    group.create_array("mask", data=(seg == 9).astype(np.uint8), chunks=(2, 5, 3))
    store = tmp_path / "user.zarr"
    rows = json.loads(run(capsys, "info", f"{store}:seg", "--labels", "--json"))["labels"]
    props = skimage_measure.regionprops(seg)
    assert [r["voxels"] for r in rows] == [int(p.area) for p in props]
    assert [r["euler_characteristic"] for r in rows] == [p.euler_number for p in props]
    report = info(capsys, f"{store}:mask")
    assert report == topology(isoflow.analyze(seg == 9, 6).to_dict()) and report["betti"] == [1, 0, 1]
    assert info(capsys, f"{store}:seg", "--label", 9) == report
    assert isoflow.analyze_zarr(f"{store}:mask", 6) == isoflow.analyze(seg == 9, 6)
    assert isoflow.read_volume(f"{store}:mask").voxels == int((seg == 9).sum())
    fails(capsys, "info", store, words=(f"user.zarr: a zarr group with arrays ['image', 'mask', 'seg']; name one, "
                                        f"{store}:image",))
    fails(capsys, "info", f"{store}:nope", words=("no array 'nope' in the zarr group (its arrays: ['image', 'mask',",))


def test_an_array_of_an_npz_archive_is_named_after_a_colon(tmp_path, capsys):
    # an archive of several arrays (a segmentation saved beside its image)
    # was refused with "name the volume 'volume'", and could not be read
    # without saving it again; ARCHIVE.npz:NAME reads one array, as
    # FILE.h5:/dataset does
    skimage_measure = pytest.importorskip("skimage.measure")
    seg = np.zeros((7, 6, 5), np.uint16)
    seg[1:3, 1:4, 1:3], seg[4:6, 0:5, 0:4] = 4, 9
    seg[4, 2, 2] = 0  # a hole inside label 9's slab: b2 = 1
    np.savez(tmp_path / "user.npz", seg=seg, image=np.random.default_rng(0).random(seg.shape))
    rows = json.loads(run(capsys, "info", f"{tmp_path / 'user.npz'}:seg", "--labels", "--json"))["labels"]
    props = skimage_measure.regionprops(seg)
    assert [r["label"] for r in rows] == [p.label for p in props]
    assert [r["voxels"] for r in rows] == [int(p.area) for p in props]
    assert [r["euler_characteristic"] for r in rows] == [p.euler_number for p in props]
    assert info(capsys, f"{tmp_path / 'user.npz'}:seg", "--label", 9)["voxels"] == int((seg == 9).sum())
    fails(capsys, "info", tmp_path / "user.npz", "--labels", words=("user.npz: holds arrays seg, image", "user.npz:seg"))
    fails(capsys, "info", f"{tmp_path / 'user.npz'}:nope", "--labels",
          words=("user.npz: holds no array 'nope' (its arrays: seg, image)",))
    # written whole: a name is refused before any work, the file left alone
    fails(capsys, "voxelize", isoflow.data.path("torus.obj"), "--resolution", 8, "-o", f"{tmp_path / 'user.npz'}:new",
          words=("an .npz is written whole",))
    assert sorted(np.load(tmp_path / "user.npz").files) == ["image", "seg"]


def test_magicavoxel_states_its_limit_and_each_caller_its_remedy(tmp_path):
    """MagicaVoxel's check said "voxelise it coarser (--resolution 256)" to
    every writer, a Python caller of write_volume too (no option there),
    and the flow tested the same limit again itself. The format states its
    limit alone; voxelize adds a coarser grid, one mesh or several, in the
    shell; the flow's steps name their own remedy (tests/flow)."""
    from isoflow.mesh.formats.magicavoxel import ModelTooLarge

    with pytest.raises(ModelTooLarge) as raised:
        isoflow.write_volume(isoflow.DigitalObject(np.ones((257, 2, 2), bool)), tmp_path / "big.vox")
    said = "MagicaVoxel models are at most 256 voxels a side, this object is 257x2x2"
    assert str(raised.value) == f"{tmp_path / 'big.vox'}: {said}"
    assert not (tmp_path / "big.vox").exists()
    a, b = tmp_path / "a.stl", tmp_path / "b.stl"
    trimesh.creation.box((1, 1, 1)).export(a)
    trimesh.creation.box((1, 1, 1)).apply_translation((2, 0, 0)).export(b)
    for meshes in ([a], [a, b]):
        p = isoflow_here("voxelize", *map(str, meshes), "--resolution", "300",
                            "-o", str(tmp_path / "big.vox"))
        assert p.returncode == 2 and not (tmp_path / "big.vox").exists()
        assert p.stderr.strip().splitlines()[-1].endswith(
            "MagicaVoxel models are at most 256 voxels a side, this object is "
            + ("300x300x300" if len(meshes) == 1 else "300x100x100") + "; voxelise it coarser (--resolution 256)"), p.stderr


def test_a_level_after_the_slash_a_shell_adds_to_a_store(tmp_path, capsys):
    # a shell completes a store's name as "image.zarr/", and the level
    # typed after it, "image.zarr/:1", was "no such file or directory"
    zarr = pytest.importorskip("zarr")
    trimesh = pytest.importorskip("trimesh")
    v = np.zeros((12, 10, 9), np.uint8)
    v[2:10, 2:8, 1:8] = 1
    v[5:7, 4:6, :] = 0  # a tunnel
    group = zarr.open_group(str(tmp_path / "image.zarr"), mode="w", zarr_format=2)
    for level, step in (("0", 1), ("1", 2)):
        group.create_array(level, data=np.ascontiguousarray(v[::step, ::step, ::step].T), chunks=(3, 4, 5))
    group.attrs["multiscales"] = [{"version": "0.4", "axes": ["z", "y", "x"],
                                   "datasets": [{"path": "0"}, {"path": "1"}]}]
    level = v[::2, ::2, ::2]
    report = topology(isoflow.analyze(level, 6).to_dict())
    for given in (f"{tmp_path / 'image.zarr'}/:1", f"{tmp_path / 'image.zarr'}:1"):
        assert info(capsys, given) == report
        run(capsys, "surface", given, "-o", tmp_path / "s.ply", "--force")
        mesh = trimesh.load(tmp_path / "s.ply", process=False)
        assert mesh.euler_number == sum(s["euler_characteristic"] for s in report["surfaces"])
        assert isoflow.read_volume(given).voxels == int(level.sum())


def test_one_voxel_is_said_in_the_singular(tmp_path, capsys):
    # "1 voxels" in info's first line, voxelize's and the binary check's
    one = np.zeros((3, 3, 3), np.uint8)
    one[1, 1, 1] = 1
    np.save(tmp_path / "one.npy", one)
    assert main(["info", str(tmp_path / "one.npy")]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert f", {int(one.sum())} voxel, 6-connectivity" in first, first
    one[0, 0, 0] = 7
    np.save(tmp_path / "bad.npy", one)
    fails(capsys, "info", tmp_path / "bad.npy", words=("(1 voxel holds values other than 0 and 1, e.g. 7)",))
    trimesh.creation.box().export(tmp_path / "box.stl")
    assert main(["voxelize", str(tmp_path / "box.stl"), "--resolution", "1", "-o", str(tmp_path / "box.npy")]) == 0
    said = capsys.readouterr().out
    assert np.load(tmp_path / "box.npy").sum() == 1 and ": 1 voxel in a 1x1x1 grid" in said, said


@pytest.mark.parametrize("bits", [8, 1])


def test_a_miniswhite_tiff_is_read_as_stored_with_a_warning_that_names_it(tmp_path, bits):
    """A mask saved MinIsWhite (PhotometricInterpretation 0: 0 is shown
    white; 1-bit as fax-style writers save it, 8-bit as Fiji with an
    inverting LUT) was read as stored without a word, though a viewer
    shows its 0s as white: the values are still those that tifffile and
    scikit-image read (and ImageJ keeps under its inverted LUT), and a
    warning names the photometric, which voxels are the object and
    --label 0 for the voxels shown white; given --label 0, that advice
    is not said again."""
    measure = pytest.importorskip("skimage.measure")
    mask = np.zeros((6, 9, 10), bool)  # (z, y, x)
    mask[1:5, 1:4, 1:4] = mask[1:5, 5:8, 5:9] = True  # two boxes
    path = tmp_path / "white.tif"
    tifffile.imwrite(path, mask if bits == 1 else mask.astype(np.uint8), photometric="miniswhite")
    with tifffile.TiffFile(path) as tif:
        assert tif.pages[0].photometric == tifffile.PHOTOMETRIC.MINISWHITE and tif.pages[0].bitspersample == bits
        stored = tif.asarray() != 0

    def report(*extra):
        p = isoflow_here("info", str(path), "--json", *extra)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout), p.stderr.strip().splitlines()

    stored_report, err = report()
    assert stored_report["voxels"] == np.count_nonzero(stored)
    assert stored_report["betti"][0] == measure.label(stored, connectivity=1).max() == 2
    assert err == [f"isoflow info: warning: {path}: stored MinIsWhite (TIFF PhotometricInterpretation 0: 0 is shown "
                   "white); its values are read as stored, as ImageJ, scikit-image and tifffile read them, so a "
                   "mask's object is its nonzero voxels, shown dark; --label 0 (label=0) takes the voxels shown "
                   "white instead"], err
    # --label 0 is the choice the warning offers: nothing is left to say
    shown_white, err = report("--label", "0")
    assert shown_white["voxels"] == np.count_nonzero(~stored)
    assert err == [], err
    # another label is a stored value, as tifffile reads it: said so, with no advice
    shown_dark, err = report("--label", "1")
    assert shown_dark["voxels"] == np.count_nonzero(stored)
    assert len(err) == 1 and err[0].endswith("read them, so label 1 selects the voxels stored as 1"), err


def test_an_ome_tiff_is_placed_by_its_first_planes_stage_position_in_its_voxel_size_unit(tmp_path, capsys):
    """An OME-TIFF's Plane PositionX/Y/Z (the stage's place of the image)
    was not read, so its surface landed at 0 where an OME-Zarr's lands at
    its translation, and a PhysicalSizeZ in nm beside an x in um was read
    as um. The first plane's position is voxel 0's centre, as an
    OME-Zarr translation is, converted to PhysicalSizeX's unit (um), and
    so are the voxel sizes: the surface's box is where the values written
    put it. A position in a unit that is no length is refused in one line."""
    mask = np.zeros((4, 6, 7), np.uint8)  # (z, y, x)
    mask[1:3, 2:5, 1:6] = 1
    pitch = np.array([0.5, 0.25, 400 * 1e-3])  # x, y in um; z written in nm
    centre = np.array([1.5 * 1e3, 20.0, 3000 * 1e-3])  # x written in mm, y in the default unit, z in nm
    planes = {"PositionX": [1.5] * 4, "PositionXUnit": ["mm"] * 4, "PositionY": [20.0] * 4,
              "PositionZ": [3000.0 + 400 * k for k in range(4)], "PositionZUnit": ["nm"] * 4}
    path = tmp_path / "placed.ome.tif"
    tifffile.imwrite(path, mask, ome=True, metadata={"axes": "ZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.25,
                                                     "PhysicalSizeZ": 400.0, "PhysicalSizeZUnit": "nm",
                                                     "Plane": planes})
    xml = tifffile.TiffFile(path).ome_metadata
    assert 'PositionX="1.5" PositionXUnit="mm"' in xml and 'PhysicalSizeZUnit="nm"' in xml
    p = isoflow_here("surface", str(path), "-o", str(tmp_path / "s.ply"))
    assert p.returncode == 0, p.stderr
    vertices = ply_vertices(tmp_path / "s.ply")
    lowest = np.array([1, 2, 1])  # the box's lowest voxel (x, y, z)
    np.testing.assert_allclose(vertices.min(axis=0), centre - pitch / 2 + lowest * pitch, rtol=1e-6)  # PLY: float32
    np.testing.assert_allclose(vertices.max(axis=0) - vertices.min(axis=0), [5, 3, 2] * pitch, rtol=1e-4)

    planes["PositionXUnit"] = ["pixel"] * 4
    tifffile.imwrite(tmp_path / "pixel.ome.tif", mask, ome=True, metadata={"axes": "ZYX", "PhysicalSizeX": 0.5,
                                                                           "Plane": planes})
    fails(capsys, "info", tmp_path / "pixel.ome.tif",
          words=("pixel.ome.tif: OME-XML's PositionXUnit 'pixel' does not convert to PhysicalSizeXUnit",))


def test_a_detached_nrrd_header_whose_data_file_is_gone_names_it(tmp_path, capsys, labels):
    """A ``.nhdr`` names its data in the field ``data file`` (pynrrd reads
    it); with that file gone the line names the field and the file, and the
    same header reads once the file is back."""
    nrrd = pytest.importorskip("nrrd")
    nrrd.write(str(tmp_path / "scan.nhdr"), (labels == 3).astype(np.uint8), detached_header=True)
    name = nrrd.read_header(str(tmp_path / "scan.nhdr"))["data file"]
    data = tmp_path / name
    data.rename(tmp_path / "elsewhere")
    fails(capsys, "info", tmp_path / "scan.nhdr", words=("data file", name, "not there"))
    (tmp_path / "elsewhere").rename(data)
    assert json.loads(run(capsys, "info", tmp_path / "scan.nhdr", "--json"))["voxels"] == np.count_nonzero(labels == 3)


def test_a_detached_nrrd_header_over_several_data_files_is_refused_by_its_field(tmp_path, capsys):
    """NRRD lets a detached header spread its data over several files
    (``data file: LIST`` with one name a line after it, or teem's pattern
    ``slice%03d.raw 0 7 1 2``), which pynrrd does not read: the lines
    were "not a readable NRRD file (ValueError: not enough values to
    unpack ...)" and "(FileNotFoundError: ... 'slice%03d.raw 0 7 1 2')",
    and a ``type: block`` file's "negative dimensions are not allowed".
    Each is one line naming the field and its value. A single data file
    whose name holds a space or starts with LIST reads, its count that
    of pynrrd's array."""
    nrrd = pytest.importorskip("nrrd")
    mask = np.zeros((6, 5, 4), np.uint8)
    mask[1:4, 1:3, 1:3] = 1
    head = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 6 5 4\nencoding: raw\n"
    for k in range(4):
        (tmp_path / f"slice{k:03d}.raw").write_bytes(mask[:, :, k].tobytes(order="F"))
    names = "".join(f"slice{k:03d}.raw\n" for k in range(4))
    (tmp_path / "list.nhdr").write_text(head + "data file: LIST 2\n" + names)
    (tmp_path / "pattern.nhdr").write_text(head + "data file: slice%03d.raw 0 3 1 2\n")
    (tmp_path / "block.nrrd").write_bytes(b"NRRD0004\ntype: block\nblock size: 2\ndimension: 3\nsizes: 6 5 4\n"
                                          b"encoding: raw\n\n" + bytes(2 * mask.size))
    fails(capsys, "info", tmp_path / "list.nhdr", words=("list.nhdr: its field 'data file' (LIST 2)", "several files"))
    fails(capsys, "info", tmp_path / "pattern.nhdr",
          words=("pattern.nhdr: its field 'data file' (slice%03d.raw 0 3 1 2)", "several files"))
    fails(capsys, "info", tmp_path / "block.nrrd", words=("block.nrrd: NRRD field 'type' is 'block'",))
    for name in ("my scan.raw", "LISTING.raw"):
        (tmp_path / name).write_bytes(mask.tobytes(order="F"))
        (tmp_path / "one.nhdr").write_text(head + f"data file: {name}\n")
        voxels = np.count_nonzero(nrrd.read(str(tmp_path / "one.nhdr"))[0])
        assert json.loads(run(capsys, "info", tmp_path / "one.nhdr", "--json"))["voxels"] == voxels == 12


@pytest.mark.parametrize("suffix, meshes", [("tif", 1), ("nrrd", 1), ("binvox", 1), ("nii.gz", 1), ("vox", 1),
                                            ("tif", 2), ("nrrd", 2)])
def test_voxelize_writes_within_the_memory_budget_it_let_the_grid_in(suffix, meshes, tmp_path, capsys, monkeypatch):
    """A grid let in by the memory check is also written within it: the
    peak of the whole command by tracemalloc (numpy reports its arrays to
    it) stays within the budget, or the grid is refused naming one that
    fits, and that one's peak does; one mesh, or two into a label image.
    (A writer's copies were left out: a TIFF of a grid let in under 14 MB
    peaked at 24 MB.)"""
    import tracemalloc

    from isoflow.scale import memory

    mesh = tmp_path / "cube.stl"
    trimesh.creation.box((1, 1, 1)).export(mesh)
    # a second cube at the far corner: their blocks are small beside the label image
    trimesh.creation.box((1, 1, 1)).apply_translation((3, 3, 3)).export(tmp_path / "far.stl")
    given = [str(mesh), str(tmp_path / "far.stl")][:meshes]
    out = tmp_path / f"cube.{suffix}"
    run(capsys, "voxelize", *given, "--resolution", 20, "-o", out, "--force")  # the format's library, imported once
    budget = 14_000_000
    monkeypatch.setattr(memory, "default_budget", lambda: budget)

    def peak(resolution):
        tracemalloc.start()
        try:
            code = main(["voxelize", *given, "--resolution", str(resolution), "-o", str(out), "--force", "-q"])
            return code, tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    code, used = peak(200)
    if code == 2:
        err = capsys.readouterr().err.strip()
        fit = re.search(r"at most --resolution (\d+) fits", err)
        assert len(err.splitlines()) == 1 and fit, err
        code, used = peak(int(fit.group(1)))
    assert code == 0 and used <= budget, (used, budget)
    monkeypatch.undo()  # read back with the memory there is
    back = isoflow.read_labels(out).array
    filled = back.size if meshes == 1 else 2 * round(back.shape[0] / 4) ** 3
    assert abs(np.count_nonzero(back) - filled) < 0.05 * filled and back.shape[0] > 90  # the cubes fill their share

@pytest.mark.parametrize("command", ["info", "surface", "flow"])


def test_the_input_help_names_every_volume_format_read(command, capsys):
    """``isoflow flow -h`` (and info's and surface's) named no ``.png``
    though a 2D PNG is read, nor ``.tiff`` or ``.nhdr``: the help now names
    a suffix of every format the loader reads; a PNG written by Pillow is
    read by the commands of 2D objects, its pixels Pillow's."""
    from isoflow.mesh.formats.registry import FORMATS

    with pytest.raises(SystemExit):
        main([command, "-h"])
    words = set(re.split(r"[\s,()/]+", capsys.readouterr().out))
    assert {".png", ".tiff", ".nhdr"} <= words
    assert all(any(s in words or f"FILE{s}:" in words for s in f.suffixes) for f in FORMATS)


@pytest.mark.parametrize("command", ["info", "flow"])


def test_a_png_written_by_pillow_is_read(tmp_path, capsys, command):
    from PIL import Image

    square = np.zeros((9, 7), np.uint8)
    square[2:6, 1:4] = 255
    Image.fromarray(square).save(tmp_path / "square.png")
    pixels = int(np.count_nonzero(np.asarray(Image.open(tmp_path / "square.png"))))
    capsys.readouterr()
    assert main([command, str(tmp_path / "square.png"), "--json", "-q"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert (printed["voxels"] if command == "info" else printed["steps"][0]["voxels"]) == pixels == 12


@pytest.mark.parametrize("dtype", ["bool", "uint8", ">i2", "float32"])
def test_info_json_of_a_mask_gives_the_type_of_the_values_the_file_holds(tmp_path, capsys, dtype):
    """``info --json`` of a binary volume said nothing of the type of the
    file's values, which ``info --labels --json`` gives as ``dtype``: it
    gives ``dtype`` too, NumPy's name of the type np.load, tifffile and
    nibabel read, and ``Report.from_dict`` still reads the JSON back."""
    mask = np.zeros((5, 6, 7), dtype)
    mask[1:4, 2:5, 1:6] = 1
    np.save(tmp_path / "m.npy", mask)
    tifffile.imwrite(tmp_path / "m.tif", mask, photometric="minisblack")
    read = {"m.npy": np.load(tmp_path / "m.npy").dtype, "m.tif": tifffile.imread(tmp_path / "m.tif").dtype}
    if dtype != "bool":  # NIfTI has no boolean type
        nib.save(nib.Nifti1Image(mask, np.eye(4)), tmp_path / "m.nii")
        read["m.nii"] = np.asanyarray(nib.load(tmp_path / "m.nii").dataobj).dtype
    for name, want in read.items():
        printed = json.loads(run(capsys, "info", tmp_path / name, "--json"))
        assert printed["dtype"] == want.name, name
        assert isoflow.Report.from_dict(printed).voxels == np.count_nonzero(mask)


def test_the_command_that_saves_an_ome_tiffs_channels_as_slices_names_a_clean_ome_tiff(tmp_path):
    """The refusal of an OME-TIFF of one slice in several channels gave a
    command that wrote ``c.ome_stack.tif``, the ``.ome`` left inside the
    name, which OME readers (and tifffile) do not take for an OME-TIFF:
    it writes ``c_stack.ome.tif``, and what it writes holds the channels
    as the slices tifffile reads in the original."""
    import shlex

    rng = np.random.default_rng(9)
    data = (rng.random((1, 3, 6, 7)) < 0.5).astype(np.uint8)
    tifffile.imwrite(tmp_path / "c.ome.tif", data, metadata={"axes": "ZCYX", "PhysicalSizeX": 0.5})
    done = isoflow_here("info", "c.ome.tif", cwd=tmp_path)
    assert done.returncode == 2
    command = shlex.split(done.stderr.split("save them as one stack and give that: ", 1)[1])
    assert 'tifffile.imwrite("c_stack.ome.tif", tifffile.imread("c.ome.tif"), ome=True' in command[2]
    subprocess.run([sys.executable, *command[1:]], check=True, cwd=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.ome.tif", "c_stack.ome.tif"]
    with tifffile.TiffFile(tmp_path / "c_stack.ome.tif") as tif:
        assert tif.is_ome and tif.series[0].axes == "ZYX"
        assert np.array_equal(tif.asarray(), tifffile.imread(tmp_path / "c.ome.tif"))


@pytest.mark.parametrize("command", [["info", "--labels"], ["surface", "--labels", "-o", "s.glb"]])
def test_a_4d_nifti_label_image_is_refused_saying_how_many_time_points(tmp_path, command):
    """A 4D NIfTI given as labels was refused as "a time series of time
    points", where the volume commands say how many. Its count is the
    header's dim[4], as nibabel reads it."""
    labels = np.zeros((6, 6, 6, 5), np.uint8)
    labels[1:3, 1:3, 1:3] = 1
    nib.save(nib.Nifti1Image(labels, np.eye(4)), tmp_path / "ts.nii.gz")
    count = int(nib.load(tmp_path / "ts.nii.gz").header["dim"][4])
    p = subprocess.run([sys.executable, "-m", "isoflow", command[0], "ts.nii.gz", *command[1:]],
                       capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 2 and p.stdout == "" and p.stderr.count("\n") == 1, p.stderr
    assert (f"(a time series of {count} time points along its 4th axis, NIfTI's dim[4], read as x, y, z, t): "
            "read one time point with read_labels(path, time=0)") in p.stderr, p.stderr
    assert not (tmp_path / "s.glb").exists()

@pytest.mark.parametrize("command", [["surface", "-o", "s.ply"], ["info", "--labels"], ["flow", "--steps", "1"]])
def test_a_4d_store_is_called_what_its_axes_metadata_names_it(tmp_path, command):
    """A 4D volume refused by a command that takes 3D was called "a 4th
    axis of 3 entries, time points or channels" whatever the file said: an
    OME-Zarr image whose 4th axis is 't' (NGFF's axes) is a time series, a
    zarr array whose dimension names are x, y, z, c holds channels, and an
    array that names no axes is still "time points or channels". Each
    line's way out (time=0) gives a 3D file that every command reads."""
    zarr = pytest.importorskip("zarr")
    time_series_store(tmp_path / "ts.ome.zarr")
    stored = np.zeros((8, 7, 6, 3), np.uint8)
    stored[2:5, 2:5, 2:4] = 1
    zarr.create_array(str(tmp_path / "c.zarr"), data=stored, dimension_names=list("xyzc"))
    zarr.create_array(str(tmp_path / "u.zarr"), data=stored)
    # the refusal's words with the count (the label table's too: it said "of time points"), one entry's name
    said = {"ts.ome.zarr": ("a time series of 3 time points along its 4th axis 't'", "time point"),
            "c.zarr": ("3 channels along its 4th axis 'c'", "channel"),
            "u.zarr": ("a 4th axis of 3 entries, time points or channels", "entry")}
    for name, (counted, entry) in said.items():
        p = subprocess.run([sys.executable, "-m", "isoflow", command[0], name, *command[1:]],
                           capture_output=True, text=True, cwd=tmp_path)
        assert p.returncode == 2 and p.stderr.count("\n") == 1 and "Traceback" not in p.stderr, p.stderr
        words = (f"({counted}, read as x, y, z, t): read one {entry} with read_labels" if command[0] == "info" else
                 f"this one is 4D, shape 8x7x6x3 ({counted}, read as x, y, z, t); save one {entry} as 3D")
        assert words in p.stderr, p.stderr
        assert ("time series" in p.stderr) == (name == "ts.ome.zarr"), p.stderr
        line = p.stderr.split("give that: ", 1)[1].strip()
        subprocess.run(sys.executable + line[len("python"):], shell=True, check=True, cwd=tmp_path)
        assert isoflow.read_labels(tmp_path / "t0.npz").array.shape == (8, 7, 6)
        (tmp_path / "t0.npz").unlink()


def test_dropped_placement_warnings_write_numbers_as_the_npy_one_does(tmp_path):
    """A flow's step volumes of an object placed at origin [2, 3] (pitch 1)
    or [2, 3, 4] (pitch 0.5): the .npy's warning said `origin [2, 3]`, the
    PNG's and MagicaVoxel's `origin [4.0, 5.0]`, `pitch 0.5`. Every one
    writes whole numbers whole and a pitch per axis, as errors.coordinates
    does; the place each names is the .npy's origin moved by its lattice
    offset (voxel 0's place, which those formats read back as 0)."""
    flat = np.zeros((8, 8), bool)
    flat[2:6, 2:6] = True
    isoflow.write_volume(isoflow.DigitalObject(flat, origin=np.array([2.0, 3.0])), tmp_path / "img.npz")
    cube = np.zeros((8, 8, 8), bool)
    cube[2:6, 2:6, 2:6] = True
    isoflow.write_volume(isoflow.DigitalObject(cube, origin=np.array([2.0, 3.0, 4.0]), pitch=0.5), tmp_path / "vol.npz")

    def warning(name, suffix):
        out = f"out_{suffix[1:]}_{name[:3]}"
        p = isoflow_here("flow", name, "--steps", "1", "--out", out,
                            "--volumes", suffix, cwd=tmp_path)
        assert p.returncode == 0, p.stderr
        return next(line for line in p.stderr.splitlines() if "warning" in line and "step_000" in line)

    for name, suffix, pitch in (("img.npz", ".png", 1.0), ("vol.npz", ".vox", 0.5)):
        kept, dropped = warning(name, ".npy"), warning(name, suffix)
        origin = [float(x) for x in re.search(r"origin \[([^\]]*)\]", kept).group(1).split(", ")]
        offset = [int(x) for x in re.search(r"lattice offset \[([^\]]*)\]", kept).group(1).split(", ")]
        place = [o + k * pitch for o, k in zip(origin, offset)]
        assert all(x == int(x) for x in place), place
        assert f"origin [{', '.join(str(int(x)) for x in place)}]" in dropped, dropped
        assert not re.search(r"\d\.0\b", kept + dropped), (kept, dropped)
        if suffix == ".vox":
            assert "pitch [0.5, 0.5, 0.5]" in dropped and "pitch [0.5, 0.5, 0.5]" in kept, (kept, dropped)


def test_a_4d_nifti_and_an_ngff_axis_typed_time_are_called_time_series(tmp_path):
    """The NIfTI standard reserves dim[4] for time (a vector's entries go
    in dim[5]), yet a 4D NIfTI refused by surface was "a 4th axis of 3
    entries, time points or channels"; an OME-Zarr axis named "time" of
    type "time" (NGFF 0.4 names are free, the type says what it is) was
    refused by every command, info too, with "save one channel"."""
    nib = pytest.importorskip("nibabel")
    zarr = pytest.importorskip("zarr")
    stored = np.zeros((8, 7, 6, 3), np.uint8)
    stored[2:5, 2:5, 2:4] = 1
    nib.save(nib.Nifti1Image(stored, np.eye(4)), tmp_path / "bold.nii.gz")
    assert nib.load(tmp_path / "bold.nii.gz").header["dim"][4] == 3
    g = zarr.open_group(tmp_path / "time.ome.zarr", mode="w")
    g.create_array("0", data=stored.transpose(3, 2, 1, 0))
    g.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": "time", "type": "time"}]
                               + [{"name": a, "type": "space"} for a in "zyx"],
                               "datasets": [{"path": "0", "coordinateTransformations": [
                                   {"type": "scale", "scale": [1.0, 1.0, 1.0, 1.0]}]}]}]
    for name in ("bold.nii.gz", "time.ome.zarr"):
        p = isoflow_here("surface", name, "-o", "s.ply", cwd=tmp_path)
        assert p.returncode == 2 and p.stderr.count("\n") == 1 and "Traceback" not in p.stderr, p.stderr
        assert "this one is 4D, shape 8x7x6x3 (a time series of 3 time points along its 4th axis" in p.stderr, p.stderr
        assert "channel" not in p.stderr and "save one time point as 3D" in p.stderr, p.stderr
        line = p.stderr.split("give that: ", 1)[1].strip()
        subprocess.run(sys.executable + line[len("python"):], shell=True, check=True, cwd=tmp_path)
        with np.load(tmp_path / "t0.npz") as saved:
            assert np.array_equal(saved[saved.files[0]] > 0, stored[..., 0] > 0)
        (tmp_path / "t0.npz").unlink()
    # info analyses a time series as 4D: the store is read, not refused
    p = isoflow_here("info", "time.ome.zarr", cwd=tmp_path)
    assert p.returncode == 0 and "4D, shape 8x7x6x3" in p.stdout, p.stderr


@pytest.mark.parametrize("command", [["surface", "-o", "s.ply"], ["info", "--labels"]])
def test_a_4d_array_of_channels_is_not_called_a_time_series(tmp_path, command):
    """A .npy of shape (X, Y, Z, 3) may hold RGB channels as well as three
    time points: the file does not say, so neither does the refusal, and
    its way out (time=0) still gives a 3D file every command reads."""
    rgb = np.zeros((6, 5, 4, 3), np.uint8)
    rgb[1:4, 1:3, 1:3, 0] = 1
    np.save(tmp_path / "rgb.npy", rgb)
    p = subprocess.run([sys.executable, "-m", "isoflow", command[0], "rgb.npy", *command[1:]],
                       capture_output=True, text=True, cwd=tmp_path)
    assert p.returncode == 2 and p.stderr.count("\n") == 1, p.stderr
    assert "time series" not in p.stderr and "time points or channels" in p.stderr, p.stderr
    line = p.stderr.split("give that: ", 1)[1].strip()
    subprocess.run(sys.executable + line[len("python"):], shell=True, check=True, cwd=tmp_path)
    with np.load(tmp_path / "t0.npz") as saved:
        assert saved[saved.files[0]].shape == rgb.shape[:3]


def test_a_zero_pixdim_of_a_nifti_without_forms_is_said_to_be_read_as_1(tmp_path, capsys, labels):
    """pixdim[1] = 0 with qform and sform codes 0: no voxel size. nifti1_io
    and nibabel read it as 1, and so did isoflow, in silence: the mesh was
    1 wide a voxel along x where the file gives no width. The warning line
    now names it; the mesh is where nifti1_io places the voxels."""
    path = tmp_path / "bare.nii"
    bare_nifti(path, labels, (0.0, 1.5, 1.0))
    assert main(["surface", str(path), "--label", "3", "-o", str(tmp_path / "s.ply")]) == 0
    warned = capsys.readouterr().err
    assert "pixdim[1] 0, no voxel size: read as 1, as nibabel and nifti1_io do" in warned, warned
    assert len(warned.splitlines()) == 1, warned
    np.save(tmp_path / "label3.npy", labels == 3)
    run(capsys, "surface", tmp_path / "label3.npy", "-o", tmp_path / "n.ply")
    same_points(ply_vertices(tmp_path / "s.ply"), (ply_vertices(tmp_path / "n.ply") - 0.5) * [1.0, 1.5, 1.0])
