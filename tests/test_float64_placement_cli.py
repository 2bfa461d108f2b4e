"""Surfaces of volumes placed where float64 itself holds the voxel corners
coarsely: far from the origin against the voxel size. Every surface format
holds world positions in float64 at most (PLY doubles, OBJ's digits, a
GLB's node transform as trimesh applies it).

Where float64 cannot keep neighbouring corners apart (a voxel of 1 at
1e43, where NumPy's ``np.spacing`` is 1.2e27) the surface would collapse in
every file: refused before anything is written, in one line naming the
placement and float64's spacing there. Where it keeps them apart but moves
them by a share of a voxel (1e-9 at 1e6, a spacing of 1.2e-10) the files
are written, said in one line, and read back by trimesh within that move.
The input files are written by their own libraries (pynrrd, nibabel).
"""

from __future__ import annotations

import re
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from in_process import isoflow_here

from isoflow.scale.compiled import COMPILE_NOTE

#: a torus of voxels: a 4^3 block less a 2x2 hole through it
MASK = np.zeros((6, 6, 6), np.uint8)
MASK[1:5, 1:5, 1:5] = 1
MASK[2:4, 2:4, :] = 0


def isoflow(*args) -> subprocess.CompletedProcess:
    """The command as a user runs it."""
    return subprocess.run([sys.executable, "-m", "isoflow", *map(str, args)], capture_output=True, text=True)



def nrrd_at(path, origin, pitch: float) -> None:
    """The mask as pynrrd writes it, voxel 0's centre at ``origin``."""
    nrrd = pytest.importorskip("nrrd")
    nrrd.write(str(path), MASK, {"space": "left-posterior-superior", "space directions": np.eye(3) * pitch,
                                 "space origin": np.asarray(origin, float)}, index_order="C")


def nifti_at(path, origin, pitch: float) -> None:
    """The mask as nibabel writes it, voxel 0's centre at ``origin``."""
    nib = pytest.importorskip("nibabel")
    affine = np.diag([pitch, pitch, pitch, 1.0])
    affine[:3, 3] = origin
    nib.save(nib.Nifti1Image(MASK, affine), str(path))


def nib_zooms(path) -> tuple:
    """The voxel sizes of a NIfTI as nibabel reads them."""
    nib = pytest.importorskip("nibabel")
    return nib.load(str(path)).header.get_zooms()


def one_line(p: subprocess.CompletedProcess) -> str:
    # where numba's cache is cold (a fresh install, a test run first on its
    # worker) the process says so first, in a note line of its own
    lines = [line for line in p.stderr.strip().splitlines() if not line.endswith(COMPILE_NOTE)]
    assert len(lines) == 1 and "Traceback" not in p.stderr, p.stderr
    return lines[0]


def test_float64_cannot_keep_a_voxel_apart_at_1e43():
    # what the refusal rests on, as NumPy reads it: 1e43 and 1e43 + 1 are one float64
    assert np.float64(1e43) + 1.0 == np.float64(1e43) and np.spacing(1e43) > 1e27


@pytest.mark.parametrize("command", [["surface", "-o", "s.ply"], ["surface", "-o", "s.obj"],
                                     ["surface", "-o", "s.glb"], ["surface", "--labels", "-o", "s.glb"],
                                     ["surface", "--labels", "-o", "dir/", "--suffix", ".ply"],
                                     ["flow", "--steps", "1", "--out", "run"]])
def test_corners_float64_cannot_keep_apart_are_refused_before_anything_is_written(tmp_path, command):
    # every format was written and left in place, then the read-back failed with exit 1 and
    # "trimesh reads volume 0 (isoflow: 48)"; --labels ended in an AssertionError's traceback
    nrrd_at(tmp_path / "far.nrrd", (1e43, 0.0, 0.0), 1.0)
    args = [tmp_path / a if a in ("s.ply", "s.obj", "s.glb", "run") else f"{tmp_path}/{a}" if a == "dir/" else a
            for a in command[1:]]
    p = isoflow(command[0], tmp_path / "far.nrrd", *args)
    line = one_line(p)
    assert p.returncode == 2 and sorted(f.name for f in tmp_path.iterdir()) == ["far.nrrd"]
    # NRRD's space origin is voxel 0's centre: its corner half a voxel before
    assert "not distinct in float64" in line and "origin (1e+43, -0.5, -0.5), voxel size (1, 1, 1)" in line
    assert f"{np.spacing(1e43):.3g} apart (np.spacing)" in line


@pytest.mark.parametrize("command", [["surface", "-o", "s.ply"], ["surface", "-o", "s.obj"],
                                     ["surface", "-o", "s.glb"], ["surface", "--labels", "-o", "s.glb"],
                                     ["flow", "--steps", "1", "--out", "run"]])
def test_corners_past_float64s_largest_are_refused_before_anything_is_written(tmp_path, command):
    """Voxels of 1e306 from 1.75e308: the grid's far corners are past
    float64's largest value (Python's integers say so), so every format
    would hold inf there. The file was written with inf corners, then the
    read-back said "trimesh reads volume NaN", exit 1."""
    from decimal import Decimal

    import isoflow as iso

    origin, pitch = 1.75e308, 1e306
    far = int(origin) + int(pitch) * MASK.shape[0]
    assert far > int(sys.float_info.max)  # the far corner is no float64
    iso.write_volume(iso.DigitalObject(MASK.astype(bool), pitch=pitch, origin=(origin, 0, 0)), tmp_path / "far.npz")
    args = [tmp_path / a if a in ("s.ply", "s.obj", "s.glb", "run") else a for a in command[1:]]
    p = isoflow(command[0], tmp_path / "far.npz", *args)
    line = one_line(p)
    assert p.returncode == 2 and sorted(f.name for f in tmp_path.iterdir()) == ["far.npz"]
    assert f"past float64's largest value ({sys.float_info.max:.3g})" in line and "along axis 0" in line
    assert f"up to {Decimal(far):.3g}" in line


def test_a_zarr_store_read_block_by_block_is_refused_too(tmp_path):
    import isoflow as iso

    iso.write_volume(iso.DigitalObject(MASK.astype(bool), pitch=1.0, origin=(1e43, 0, 0)), tmp_path / "far.zarr")
    p = isoflow("surface", tmp_path / "far.zarr", "-o", tmp_path / "s.ply")
    assert p.returncode == 2 and "not distinct in float64" in one_line(p) and not (tmp_path / "s.ply").exists()


def distinct_positions(path) -> int:
    return len(np.unique(np.asarray(trimesh.load(path, force="mesh", process=False).vertices), axis=0))


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".glb"])
def test_corners_float64_moves_are_written_and_said(tmp_path, suffix):
    # the files were written, then the read-back failed with exit 1 and no reason:
    # "trimesh reads volume 4.74974513e-26 (isoflow: 4.8e-26)"
    pitch = 1e-9
    nifti_at(tmp_path / "far.nii.gz", (1e6, 0.0, 0.0), pitch)
    nifti_at(tmp_path / "near.nii.gz", (0.0, 0.0, 0.0), pitch)
    far, near = tmp_path / f"far{suffix}", tmp_path / f"near{suffix}"
    # one format's line as the shell prints it; the writers of the others in this process
    p = (isoflow if suffix == ".ply" else isoflow_here)("surface", tmp_path / "far.nii.gz", "-o", far, "-q")
    assert p.returncode == 0, p.stderr
    line = one_line(p)
    assert line.startswith(f"isoflow surface: warning: {far}: float64 holds the voxel corners")
    assert f"near 1e+06, {np.spacing(1e6):.3g} (np.spacing)" in line
    assert isoflow_here("surface", tmp_path / "near.nii.gz", "-o", near, "-q").returncode == 0
    # trimesh reads the far file as the surface of the file at the origin: as many distinct
    # corners, closed, of the torus's genus, its volume within float64's move at 1e6
    assert distinct_positions(far) == distinct_positions(near)
    mesh = trimesh.load(far, force="mesh", process=False)
    assert mesh.is_watertight and mesh.euler_number == 0
    box = trimesh.load(near, force="mesh", process=False)
    # 48 voxels of the sizes nibabel reads from the header (float32)
    volume = 48 * float(np.prod(np.asarray(nib_zooms(tmp_path / "far.nii.gz"), np.float64)))
    assert box.volume == pytest.approx(volume, rel=1e-6, abs=0)  # (float32 positions where they hold it)
    slack = 2 * np.spacing(1e6) * box.area
    assert abs(mesh.volume - volume) <= slack and mesh.volume != pytest.approx(volume, rel=1e-4, abs=0)


def test_flow_out_where_float64_moves_the_corners_says_so(tmp_path):
    nifti_at(tmp_path / "far.nii.gz", (1e6, 0.0, 0.0), 1e-9)
    p = isoflow_here("flow", tmp_path / "far.nii.gz", "--steps", "1", "--out", tmp_path / "run", "-q")
    assert p.returncode == 0, p.stderr
    assert "float64 holds the voxel corners" in p.stderr and f"{np.spacing(1e6):.3g} (np.spacing)" in p.stderr
    assert trimesh.load(tmp_path / "run" / "step_000.ply", process=False).is_watertight


def test_write_surface_refuses_and_warns_as_the_command_does(tmp_path):
    import isoflow as iso

    with pytest.raises(iso.IsoflowError, match=r"not distinct in float64"):
        iso.write_surface(iso.DigitalObject(MASK.astype(bool), origin=(1e43, 0, 0)), tmp_path / "s.ply")
    assert not (tmp_path / "s.ply").exists()
    with pytest.warns(iso.IsoflowWarning, match=r"float64 holds the voxel corners"):
        iso.write_surface(iso.DigitalObject(MASK.astype(bool), pitch=1e-9, origin=(1e6, 0, 0)), tmp_path / "s.ply")
    assert trimesh.load(tmp_path / "s.ply", process=False).is_watertight


def test_an_stl_beyond_float32_is_one_line_without_numpys_warning(tmp_path):
    # NumPy's "overflow encountered in spacing" came before the refusal: float32's step at its largest value
    assert np.float64(1e39) > np.finfo(np.float32).max  # beyond float32, as NumPy reads it
    nrrd_at(tmp_path / "far.nrrd", (1e39, 0.0, 0.0), 1e30)
    p = isoflow("surface", tmp_path / "far.nrrd", "-o", tmp_path / "s.stl")
    assert p.returncode == 2 and "exceed float32's range" in one_line(p) and not (tmp_path / "s.stl").exists()


@pytest.mark.parametrize("volumes", [[], ["--volumes", ".nrrd"]])
def test_flow_out_of_a_2d_image_float64_cannot_place_is_refused(tmp_path, volumes):
    """A 2D image at x = 1e43 in pixels of 1 (pynrrd writes it): its run
    wrote flow.csv with every box 0 wide in x (bbox_min_x = bbox_max_x =
    1e43, where the ring is 20 pixels wide), a shapes.png of empty panels
    and --volumes states cropped at x = 1e43, exit 0. It is refused before
    anything is written, as a 3D volume there is; at the origin the run
    writes the boxes 20 pixels wide."""
    nrrd = pytest.importorskip("nrrd")
    ring = np.zeros((24, 24), np.uint8)
    ring[2:22, 2:22] = 1
    ring[8:16, 8:16] = 0
    for name, x in (("far", 1e43), ("near", 0.0)):
        nrrd.write(str(tmp_path / f"{name}.nrrd"), ring, {"space dimension": 2, "space directions": np.eye(2),
                                                         "space origin": np.array([x, 0.0])}, index_order="C")
    p = isoflow("flow", tmp_path / "far.nrrd", "--steps", "2", "--out", tmp_path / "run", *volumes)
    line = one_line(p)
    assert p.returncode == 2 and not (tmp_path / "run").exists()
    assert "not distinct in float64" in line and "origin (1e+43, -0.5), voxel size (1, 1)" in line
    assert f"{np.spacing(1e43):.3g} apart (np.spacing)" in line and "flow.csv" in line
    p = isoflow_here("flow", tmp_path / "near.nrrd", "--steps", "2", "--out", tmp_path / "near", *volumes, "-q")
    assert p.returncode == 0, p.stderr
    first = (tmp_path / "near" / "flow.csv").read_text().splitlines()[1].split(",")
    header = (tmp_path / "near" / "flow.csv").read_text().splitlines()[0].split(",")
    row = dict(zip(header, first))
    assert float(row["bbox_max_x"]) - float(row["bbox_min_x"]) == 20


@pytest.mark.parametrize("suffix", [".ply", ".obj"])
def test_the_read_back_line_says_the_volume_to_the_digits_it_holds(tmp_path, suffix):
    # the line said "volume 4.74975e-26: as isoflow counts", six digits of which
    # the second on are float64's move of the corners; info says 4.8e-26
    nifti_at(tmp_path / "far.nii.gz", (1e6, 0.0, 0.0), 1e-9)
    p = isoflow_here("surface", tmp_path / "far.nii.gz", "-o", tmp_path / f"s{suffix}")
    assert p.returncode == 0, p.stderr
    volume = 48 * float(np.prod(np.asarray(nib_zooms(tmp_path / "far.nii.gz"), np.float64)))  # as nibabel reads it
    line = p.stdout.splitlines()[-1]
    assert f"volume {volume:.6g} (read within the move of the corners): as isoflow counts" in line, line
    assert re.search(rf"volume +{re.escape(f'{volume:.6g}')},", isoflow_here("info", tmp_path / "far.nii.gz").stdout)


def test_a_store_read_back_in_chunks_says_the_volume_to_the_digits_it_holds(tmp_path):
    zarr = pytest.importorskip("zarr")
    group = zarr.open_group(str(tmp_path / "far.zarr"), mode="w")  # zarr-python writes it, placed by OME metadata
    group.create_array("0", data=MASK, chunks=(4, 4, 4))
    group.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": a, "type": "space"} for a in "xyz"],
                                   "datasets": [{"path": "0", "coordinateTransformations": [
                                       {"type": "scale", "scale": [1e-9] * 3},
                                       {"type": "translation", "translation": [1e6, 0.0, 0.0]}]}]}]
    p = isoflow_here("surface", tmp_path / "far.zarr", "-o", tmp_path / "s.ply")
    assert p.returncode == 0, p.stderr
    volume = int(MASK.sum()) * 1e-9 ** 3
    assert f"volume {volume:.6g} (read within the move of the corners)," in p.stdout.splitlines()[-1], p.stdout


def test_info_where_float64_cannot_keep_corners_apart_warns_and_gives_null(tmp_path):
    """``isoflow info`` at 1e43 printed a box of no width along x, ``[1e+43,
    0.5, 0.5] to [1e+43, 4.5, 4.5]``, and a centroid there, without a word.
    It answers (the topology holds at any placement) with one warning line
    naming the placement and float64's spacing, its box and centroid null
    along x; the other axes, the topology and the volume are scikit-image's
    and NumPy's reading of the mask pynrrd wrote."""
    import json

    from skimage.measure import euler_number, regionprops

    nrrd_at(tmp_path / "far.nrrd", (1e43, 0.0, 0.0), 1.0)
    p = isoflow("info", tmp_path / "far.nrrd", "--json")
    line = one_line(p)
    assert p.returncode == 0 and line.startswith("isoflow info: warning: ")
    assert "origin (1e+43, -0.5, -0.5), voxel size (1, 1, 1)" in line
    assert f"{np.spacing(1e43):.3g} apart (np.spacing)" in line
    report = json.loads(p.stdout)
    # NRRD's space origin is voxel 0's centre: its corner half a voxel before
    box = np.array(regionprops(MASK)[0].bbox, float) - 0.5
    assert report["bbox"] == [None, *box[1:3], None, *box[4:6]]
    assert report["centroid"][0] is None and report["centroid"][1:] == pytest.approx(np.argwhere(MASK).mean(0)[1:])
    assert report["euler_characteristic"] == euler_number(np.pad(MASK, 1), 1) and report["volume"] == MASK.sum()
    text = isoflow_here("info", tmp_path / "far.nrrd")
    assert text.returncode == 0 and "bounding box           [?, 0.5, 0.5] to [?, 4.5, 4.5]" in text.stdout


def test_analyze_and_run_flow_where_float64_cannot_keep_corners_apart_warn_and_give_none():
    """``isoflow.analyze`` and ``isoflow.run_flow`` of an object at 1e43
    returned boxes of no width along x without a warning. They warn and
    give None along x; along y and z the values are those of the same
    object at the origin (a move along x leaves them), and so are the
    topology and the volume."""
    import isoflow as iso

    far = iso.DigitalObject(MASK.astype(bool), origin=(1e43, 0, 0))
    near = iso.DigitalObject(MASK.astype(bool))
    with pytest.warns(iso.IsoflowWarning, match=re.escape(f"{np.spacing(1e43):.3g} apart (np.spacing)")):
        report = iso.analyze(far)
    expected = iso.analyze(near)
    assert report.bbox == [None, *expected.bbox[1:3], None, *expected.bbox[4:6]]
    assert report.centroid == [None, *expected.centroid[1:]]
    assert (report.betti, report.volume) == (expected.betti, expected.volume) == ([1, 1, 0], MASK.sum())
    with pytest.warns(iso.IsoflowWarning, match="the boxes and the limit point of the flow cannot be held"):
        run = iso.run_flow(far, keep_states=False)
    plain = iso.run_flow(near, keep_states=False)
    boxes = [s["bbox"] for s in run.steps if s["bbox"] is not None]
    assert boxes and all(b[0] is None and b[3] is None for b in boxes)
    assert [b[1:3] + b[4:] for b in boxes] == [s["bbox"][1:3] + s["bbox"][4:] for s in plain.steps if s["bbox"]]
    assert all(c["where"][0] is None for c in run.topology_changes) and len(run.topology_changes) == len(
        plain.topology_changes)
    assert run.limit["center"] == [None, *plain.limit["center"][1:]]


def test_info_of_a_far_zarr_store_read_block_by_block_warns_in_x_y_z_order(tmp_path):
    # the store holds z, y, x: the warning names the placement as written, and x's coordinates are null
    import json

    import isoflow as iso

    iso.write_volume(iso.DigitalObject(MASK.astype(bool), pitch=1.0, origin=(1e43, 0, 0)), tmp_path / "far.zarr")
    p = isoflow("info", tmp_path / "far.zarr", "--json")
    line = one_line(p)
    assert p.returncode == 0 and "origin (1e+43, 0, 0), voxel size (1, 1, 1)" in line and "along axis 0" in line
    assert json.loads(p.stdout)["centroid"][0] is None


def test_info_labels_of_a_far_zyx_store_warns_of_the_axes_a_file_s_table_names(tmp_path):
    # read block by block, a store whose axes are z, y, x must name the axes lost as x, y, z, as the
    # table's columns and info's other warnings do, not in the order it stores them (there 0 and 1)
    import json

    zarr = pytest.importorskip("zarr")
    nrrd = pytest.importorskip("nrrd")
    image = np.zeros((6, 7, 8), np.uint8)
    image[1:5, 1:5, 1:5] = 1
    image[0, 0, 0] = 2
    centre, pitch = [0.0, 1e17, 1e43], [1.0, 2.0, 3.0]  # voxel 0's centre, as both formats place it
    nrrd.write(str(tmp_path / "far.nrrd"), image, {"space directions": np.diag(pitch), "space origin": centre},
               index_order="C")
    group = zarr.open_group(str(tmp_path / "far.zarr"), mode="w")  # zarr-python writes it, z first
    group.create_array("0", data=image.transpose(2, 1, 0), chunks=(4, 4, 4))
    group.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": a, "type": "space"} for a in "zyx"],
                                   "datasets": [{"path": "0", "coordinateTransformations": [
                                       {"type": "scale", "scale": pitch[::-1]},
                                       {"type": "translation", "translation": centre[::-1]}]}]}]
    said, rows = {}, {}
    for name, command in (("far.nrrd", isoflow_here), ("far.zarr", isoflow)):
        p = command("info", tmp_path / name, "--labels", "--json")
        said[name] = one_line(p).replace(str(tmp_path / name), "INPUT")
        rows[name] = json.loads(p.stdout)["labels"]
    assert said["far.zarr"] == said["far.nrrd"] and all(
        f"along axis {axis} are one value" in said["far.zarr"] for axis in (1, 2))
    assert rows["far.zarr"] == rows["far.nrrd"]
    assert all(row[f"bbox-{d}"] is None for row in rows["far.zarr"] for d in (1, 2, 4, 5))


def test_info_labels_where_float64_cannot_keep_corners_apart_warns_and_gives_null(tmp_path):
    """The label table at 1e43: each label's box and centroid along x were
    the collapsed 1e+43, without a word. They are null (NaN in Python)
    along x, said in one warning line; along y and z they are
    scikit-image's regionprops of the image pynrrd wrote; ``surface
    --labels`` is refused in one line, before any table is counted."""
    import json

    from skimage.measure import regionprops

    nrrd = pytest.importorskip("nrrd")
    image = MASK.copy()
    image[0, 0, 0] = 2  # a second label, touching the first at a vertex
    nrrd.write(str(tmp_path / "far.nrrd"), image, {"space directions": np.eye(3), "space origin": [1e43, 0.0, 0.0]},
               index_order="C")
    p = isoflow("info", tmp_path / "far.nrrd", "--labels", "--json")
    line = one_line(p)
    assert p.returncode == 0 and line.startswith("isoflow info: warning: ") and "null in JSON" in line
    assert f"{np.spacing(1e43):.3g} apart (np.spacing)" in line
    rows = json.loads(p.stdout)["labels"]
    for row, region in zip(rows, regionprops(image)):
        box = np.array(region.bbox, float) - 0.5  # NRRD's origin is voxel 0's centre
        assert row["label"] == region.label
        assert [row[f"bbox-{d}"] for d in range(6)] == [None, *box[1:3], None, *box[4:6]]
        assert row["centroid-0"] is None and [row["centroid-1"], row["centroid-2"]] == pytest.approx(
            np.array(region.centroid)[1:])
        assert row["voxels"] == region.area
    surface = isoflow("surface", tmp_path / "far.nrrd", "--labels", "-o", tmp_path / "far.glb")
    assert surface.returncode == 2 and "not distinct in float64" in one_line(surface)
    assert not (tmp_path / "far.glb").exists()


@pytest.mark.parametrize("command", [["info"], ["info", "--labels"], ["surface", "-o", "s.ply"],
                                     ["flow", "--steps", "1", "--out", "run"], ["flow", "--steps", "1"]])
def test_every_axis_float64_cannot_keep_apart_is_named_with_its_own_spacing(tmp_path, command):
    """At an origin of (0, 1e17, 1e43) and a voxel of 1 float64 loses the
    corners of two axes. ``surface`` and ``flow --out`` named axis 2 alone,
    and ``info`` named both with float64's spacing near 1e17 (16) as the
    reason for axis 2 too. Every command names both, each with NumPy's
    ``np.spacing`` at that axis' own farthest corner, in one line."""
    nrrd_at(tmp_path / "far.nrrd", (0.0, 1e17, 1e43), 1.0)
    args = [tmp_path / a if a in ("s.ply", "run") else a for a in command[1:]]
    p = isoflow(command[0], tmp_path / "far.nrrd", *args)
    line = one_line(p)
    assert p.returncode == (2 if command[0] == "surface" or "--out" in command else 0), p.stderr
    # NRRD's space origin is voxel 0's centre: the corners run from half a voxel before it, 6 voxels on
    for axis, centre in ((1, 1e17), (2, 1e43)):
        far = max(abs(np.float64(centre) - 0.5), abs(np.float64(centre) - 0.5 + 6.0))
        assert np.float64(far) + 1.0 == np.float64(far)  # float64 cannot keep a voxel apart there
        assert (f"near {far:.3g} float64 values are {np.spacing(far):.3g} apart (np.spacing), so voxel corners a "
                f"voxel apart along axis {axis} are one value") in line, line
    assert line.count("np.spacing") == 2 and "axis 0" not in line
