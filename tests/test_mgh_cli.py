"""FreeSurfer MGH/MGZ volumes (aseg.mgz, aparc+aseg.mgz) and Analyze 7.5
pairs, read through nibabel: placed as nibabel's affine and zooms place
them, label tables as scikit-image measures the stored array, surfaces read
back by trimesh where the affine puts them, round trips read by nibabel,
damaged files in one line."""

import gc
import gzip
import json
import warnings

import numpy as np
import pytest
import trimesh
from test_input_errors import fails  # one line on stderr, exit 2

import isoflow
from isoflow.cli import main
from isoflow.errors import IsoflowWarning

nib = pytest.importorskip("nibabel")

#: FreeSurfer's conformed orientation (LIA: i to the left, j down, k to the
#: front), anisotropic, and moved off the origin
LIA = np.array([[-0.75, 0, 0, 31.5], [0, 0, 1.5, -12.25], [0, -0.5, 0, 20.0], [0, 0, 0, 1]])


def run(capsys, *args):
    assert main([*map(str, args)]) == 0, capsys.readouterr().err
    return capsys.readouterr().out


@pytest.fixture
def aseg(rng):
    """An aseg-like label image as stored (i, j, k): FreeSurfer's label
    numbers, a ring, random specks with edge and vertex contacts."""
    i, j, k = np.indices((12, 10, 9))
    lab = np.zeros((12, 10, 9), np.int32)
    lab[(np.hypot(i - 5.5, j - 4.5) - 3) ** 2 + (k - 4) ** 2 <= 2.5] = 17  # left hippocampus, a ring
    lab[rng.random(lab.shape) < 0.05] = 41
    lab[:3, :, -1] = 1035
    lab[9:, 2:5, 1:3] = 2
    return lab


def save_mgz(path, data, affine=LIA):
    nib.save(nib.MGHImage(data, affine), path)
    return path


def world_box(affine, low, high):
    """The world box of the voxels from index ``low`` to ``high`` (exclusive),
    voxel centres at the indices, through ``affine``."""
    corners = np.array([[(low, high)[b >> d & 1][d] - 0.5 for d in range(3)] for b in range(8)], np.float64)
    world = nib.affines.apply_affine(affine, corners)
    return world.min(0), world.max(0)


@pytest.mark.parametrize("suffix", [".mgh", ".mgz"])
def test_reading_an_mgh_leaves_no_file_open(tmp_path, rng, suffix):
    """The file is closed once read (nibabel's own opening of an .mgh left
    it open: a ResourceWarning in the user's program), and the voxels are
    nibabel's."""
    data = (rng.random((5, 6, 7)) < 0.4).astype(np.uint8)
    path = tmp_path / f"s{suffix}"
    nib.save(nib.MGHImage(data, LIA), path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ResourceWarning)
        labels = isoflow.read_labels(path)
        obj = isoflow.read_volume(path)
        gc.collect()  # an unclosed file warns when it is collected
    assert [str(w.message) for w in caught if issubclass(w.category, ResourceWarning)] == []
    assert int(np.count_nonzero(labels.array)) == obj.voxels == int(np.count_nonzero(data))


@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.int32, np.float32])
def test_an_mgz_is_read_as_nibabel_places_it(tmp_path, rng, dtype):
    """Every label voxel's centre lands where nibabel's affine puts it, the
    voxel sizes are nibabel's zooms, the type the stored one, the unit mm."""
    data = np.floor(rng.random((5, 6, 7)) * 4).astype(dtype)
    path = save_mgz(tmp_path / "s.mgz", data)
    img = nib.load(path)
    labels = isoflow.read_labels(path)
    assert labels.unit == "mm"
    if dtype != np.float32:  # whole floats are read as int64 labels, as NIfTI's are
        assert labels.array.dtype == np.dtype(dtype)
    # LIA: array axis i runs along x, k along y, j along z
    zooms = img.header.get_zooms()
    assert labels.spacing.tolist() == pytest.approx([zooms[0], zooms[2], zooms[1]])
    for value in (1, 2, 3):
        mine = labels.origin + labels.spacing * (np.argwhere(labels.array == value) + 0.5)
        theirs = nib.affines.apply_affine(img.affine, np.argwhere(np.asanyarray(img.dataobj) == value))
        assert sorted(map(tuple, np.round(mine, 9))) == sorted(map(tuple, np.round(theirs, 9)))


def test_info_labels_of_an_mgz_is_scikit_image_s_regionprops_placed_by_the_affine(tmp_path, capsys, aseg):
    measure = pytest.importorskip("skimage.measure")
    path = save_mgz(tmp_path / "aseg.mgz", aseg)
    img = nib.load(path)
    stored = np.asanyarray(img.dataobj).astype(np.int64)
    report = json.loads(run(capsys, "info", path, "--labels", "--json", "--connectivity", "26"))
    assert report["unit"] == "mm"
    assert sorted(report["pitch"]) == pytest.approx(sorted(img.header.get_zooms()))
    want = measure.regionprops_table(stored, properties=("label", "area", "bbox", "centroid", "euler_number"))
    rows = report["labels"]
    assert [r["label"] for r in rows] == want["label"].tolist() == [2, 17, 41, 1035]
    voxel = float(np.prod(img.header.get_zooms()))
    for r, row in enumerate(rows):
        assert row["volume"] == pytest.approx(want["area"][r] * voxel)
        assert row["euler_characteristic"] == want["euler_number"][r]
        low, high = world_box(img.affine, [want[f"bbox-{d}"][r] for d in range(3)],
                              [want[f"bbox-{d + 3}"][r] for d in range(3)])
        assert [row[f"bbox-{d}"] for d in range(3)] == pytest.approx(low)
        assert [row[f"bbox-{d + 3}"] for d in range(3)] == pytest.approx(high)
        centre = nib.affines.apply_affine(img.affine, [want[f"centroid-{d}"][r] for d in range(3)])
        assert [row[f"centroid-{d}"] for d in range(3)] == pytest.approx(centre)


def test_surface_of_an_mgz_lands_where_the_affine_puts_the_labels(tmp_path, capsys, aseg):
    path = save_mgz(tmp_path / "aseg.mgz", aseg)
    img = nib.load(path)
    voxel = float(np.prod(img.header.get_zooms()))
    said = run(capsys, "surface", path, "--labels", "-o", tmp_path / "aseg.glb")
    assert "4 labels" in said and "read back" in said
    scene = trimesh.load(tmp_path / "aseg.glb", force="scene", process=False)
    for label in (2, 17, 41, 1035):
        transform, geometry = scene.graph[f"label_{label}"]
        mesh = scene.geometry[geometry].copy()
        mesh.apply_transform(transform)
        where = np.argwhere(aseg == label)
        low, high = world_box(img.affine, where.min(0), where.max(0) + 1)
        assert mesh.bounds.tolist() == [pytest.approx(low), pytest.approx(high)]
        assert abs(mesh.volume) == pytest.approx((aseg == label).sum() * voxel)
    run(capsys, "surface", path, "--label", "17", "-o", tmp_path / "hippo.ply")
    ring = trimesh.load(tmp_path / "hippo.ply", process=False)
    where = np.argwhere(aseg == 17)
    assert ring.bounds.tolist() == [pytest.approx(b) for b in world_box(img.affine, where.min(0), where.max(0) + 1)]
    assert ring.volume == pytest.approx((aseg == 17).sum() * voxel)


def test_an_mgz_of_several_frames_is_4d_and_one_frame_3d(tmp_path, capsys):
    frames = np.zeros((4, 5, 6, 3), np.uint8)
    frames[1:3, 1:4, 1:5] = 1
    path = save_mgz(tmp_path / "f.mgz", frames, np.diag([0.5, 2.0, 1.0, 1.0]))
    assert nib.load(path).header["dims"].tolist() == [4, 5, 6, 3]
    report = json.loads(run(capsys, "info", path, "--json"))
    assert report["shape"] == [4, 5, 6, 3] and report["pitch"] == pytest.approx([0.5, 2.0, 1.0, 1.0])
    one = save_mgz(tmp_path / "one.mgz", frames[..., 0], np.diag([0.5, 2.0, 1.0, 1.0]))
    assert nib.load(one).header["dims"].tolist() == [4, 5, 6, 1]  # a frame count of 1 in the file
    assert json.loads(run(capsys, "info", one, "--json"))["shape"] == [4, 5, 6]


def test_an_oblique_mgz_keeps_nibabel_s_zooms_and_warns_as_nifti_does(tmp_path):
    c, s = np.cos(np.radians(10)), np.sin(np.radians(10))
    affine = np.array([[c, -s, 0, 4], [s, c, 0, -3], [0, 0, 1, 2], [0, 0, 0, 1]]) @ np.diag([2.0, 3.0, 4.0, 1])
    path = save_mgz(tmp_path / "o.mgz", np.ones((2, 2, 2), np.uint8), affine)
    with pytest.warns(IsoflowWarning, match="rotated or sheared by up to 10 degrees"):
        obj = isoflow.read_volume(path)
    assert obj.spacing.tolist() == pytest.approx(nib.load(path).header.get_zooms())
    # the first voxel's centre stays where nibabel's affine puts it
    assert (obj.origin + obj.spacing / 2).tolist() == pytest.approx(nib.affines.apply_affine(nib.load(path).affine,
                                                                                             [0, 0, 0]))


@pytest.mark.parametrize("suffix", [".mgz", ".mgh", ".MGZ"])
def test_an_mgh_round_trip_keeps_voxels_pitch_and_origin(tmp_path, rng, suffix):
    vol = rng.random((5, 6, 7)) < 0.5
    obj = isoflow.DigitalObject(vol, pitch=(0.5, 0.25, 2.0), origin=(1.5, -2.0, 10.0))  # exact in float32
    path = isoflow.write_volume(obj, tmp_path / f"v{suffix}")
    assert (path.read_bytes()[:2] == b"\x1f\x8b") == (suffix.lower() == ".mgz")
    img = nib.load(path)
    assert np.array_equal(np.asanyarray(img.dataobj), vol)
    assert img.header.get_zooms() == pytest.approx((0.5, 0.25, 2.0))
    assert nib.affines.apply_affine(img.affine, [0, 0, 0]) == pytest.approx([1.75, -1.875, 11.0])  # voxel 0's centre
    back = isoflow.read_volume(path)
    assert np.array_equal(back.volume, vol) and back.unit == "mm"
    assert back.spacing.tolist() == [0.5, 0.25, 2.0]
    assert back.origin.tolist() == [1.5, -2.0, 10.0]


def test_an_mgz_far_from_the_origin_says_how_far_float32_moves_its_voxels(tmp_path):
    """MGH stores the volume's centre in float32: near 1e6 float32 steps
    are 0.0625, more than a voxel of 0.04 moves. The warning's figure is
    the move the file's numbers make; near the origin nothing is said."""
    vol = np.zeros((64, 64, 16), bool)
    vol[1:-1, 1:-1, 1:-1] = True
    # its centre no float32 number; in mm, MGH's unit (a volume without one gets a note of its own)
    far = isoflow.DigitalObject(vol, pitch=0.04, origin=(999998.7123, 0, 0), unit="mm")
    with pytest.warns(IsoflowWarning, match=r"MGH stores the voxel-to-world map as float32, which moves this "
                                            r"volume's voxels by up to (\S+) voxels") as caught:
        path = isoflow.write_volume(far, tmp_path / "far.mgz")
    said = float(str(caught[0].message).split("by up to ")[1].split(" ")[0])
    # where the file's float32 numbers put the voxels, worked out in float64
    # (nibabel's affine works it out in float32, adding its own rounding)
    hdr = nib.load(path).header
    size, centre = hdr["delta"].astype(float), hdr["Pxyz_c"].astype(float)
    ends = np.array([[0, 0, 0], [63, 63, 15]])
    placed = centre + size * (ends - np.array([64, 64, 16]) / 2)
    moved = np.abs(placed - (far.origin + 0.04 * (ends + 0.5))).max() / 0.04
    assert moved > 1e-3 and said == pytest.approx(moved, rel=1e-2)
    near = isoflow.DigitalObject(vol, pitch=0.04, origin=(-1.5, 2.0, 0.25), unit="mm")
    with warnings.catch_warnings():
        warnings.simplefilter("error", IsoflowWarning)
        isoflow.write_volume(near, tmp_path / "near.mgz")


def test_labels_are_written_in_a_type_freesurfer_reads(tmp_path, aseg):
    for top, kind in ((200, np.uint8), (2035, np.int16), (14175, np.int16), (70000, np.int32)):
        labels = np.where(aseg > 0, np.minimum(aseg, top), 0).astype(np.uint32)
        labels[0, 0, 0] = top
        path = isoflow.write_labels(labels, tmp_path / f"l{top}.mgz", pitch=(0.75, 1.5, 0.5), unit="mm")
        img = nib.load(path)
        assert img.get_data_dtype() == np.dtype(kind).newbyteorder(">")
        assert np.array_equal(np.asanyarray(img.dataobj), labels)
        assert np.array_equal(isoflow.read_labels(path).array, labels)


def test_what_mgh_cannot_hold_is_refused_or_said(tmp_path, capsys):
    with pytest.raises(isoflow.IsoflowError, match=r"MGH holds 3D volumes \(and 4D frames\), this object is 2D"):
        isoflow.write_volume(np.ones((3, 4), bool), tmp_path / "flat.mgz")
    with pytest.raises(isoflow.IsoflowError, match=r"MGH keeps labels up to 2147483647"):
        isoflow.write_labels(np.full((2, 2, 2), 2**31, np.uint32), tmp_path / "big.mgz")
    with pytest.warns(IsoflowWarning, match=r"MGH keeps millimetres only \(read back as mm\); the unit µm"):
        isoflow.write_volume(isoflow.DigitalObject(np.ones((2, 2, 2), bool), unit="micron"), tmp_path / "um.mgz")
    assert not (tmp_path / "flat.mgz").exists() and not (tmp_path / "big.mgz").exists()
    save_mgz(tmp_path / "kept.mgz", np.ones((2, 2, 2), np.uint8))
    fails(capsys, "voxelize", isoflow_box(tmp_path), "--resolution", "4", "-o", tmp_path / "kept.mgz",
          words=("kept.mgz",))


def isoflow_box(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.creation.box().export(path)
    return path


def test_voxelize_writes_an_mgz_that_nibabel_reads(tmp_path, capsys):
    run(capsys, "voxelize", isoflow_box(tmp_path), "--resolution", "8", "-o", tmp_path / "box.mgz")
    img = nib.load(tmp_path / "box.mgz")
    obj = isoflow.read_volume(tmp_path / "box.mgz")
    assert np.asanyarray(img.dataobj).sum() == obj.voxels > 0
    corner = nib.affines.apply_affine(img.affine, [0, 0, 0]) - np.asarray(img.header.get_zooms()) / 2
    assert obj.origin == pytest.approx(corner)


def test_a_damaged_mgz_is_one_line_naming_the_file(tmp_path, capsys, aseg):
    raw = save_mgz(tmp_path / "aseg.mgz", aseg).read_bytes()
    (tmp_path / "cut.mgz").write_bytes(raw[: len(raw) // 2])
    fails(capsys, "info", tmp_path / "cut.mgz", "--labels", words=("cut.mgz: not a readable MGH file",))
    (tmp_path / "text.mgz").write_bytes(b"not a volume\n" * 10)
    fails(capsys, "info", tmp_path / "text.mgz", words=("text.mgz: not a readable MGH file",))
    # nibabel goes by the name: an uncompressed file called .mgz, a compressed one called .mgh
    (tmp_path / "plain.mgz").write_bytes(gzip.decompress(raw))
    fails(capsys, "info", tmp_path / "plain.mgz", "--labels",
          words=("its content is uncompressed MGH: rename it plain.mgh",))
    (tmp_path / "packed.mgh").write_bytes(raw)
    fails(capsys, "surface", tmp_path / "packed.mgh", "--labels", "-o", tmp_path / "s.glb",
          words=("its content is gzip-compressed MGH: rename it packed.mgz",))


def test_analyze_is_read_with_its_voxel_sizes_as_stored(tmp_path, capsys, aseg):
    """Analyze 7.5 keeps the voxel sizes but no orientation or origin:
    nibabel reads the zooms written and makes up the rest (x mirrored and
    centred, whatever affine was written), so isoflow reads the array as
    stored from 0 and says so. A NIfTI pair is placed by its affine."""
    nib.save(nib.AnalyzeImage(aseg, LIA), tmp_path / "seg.hdr")
    img = nib.load(tmp_path / "seg.hdr")
    assert not np.allclose(img.affine, LIA)  # the affine written is not the one read
    for name in ("seg.hdr", "seg.img"):
        with pytest.warns(IsoflowWarning, match="Analyze 7.5 stores voxel sizes but no orientation or origin"):
            labels = isoflow.read_labels(tmp_path / name)
        assert np.array_equal(labels.array, np.asanyarray(img.dataobj))
        assert labels.spacing.tolist() == pytest.approx(img.header.get_zooms())
        assert labels.origin.tolist() == [0, 0, 0]
    nib.save(nib.Nifti1Pair(aseg, LIA), tmp_path / "pair.hdr")
    with warnings.catch_warnings():
        warnings.simplefilter("error", IsoflowWarning)
        pair = isoflow.read_labels(tmp_path / "pair.img")
    hippo = pair.origin + pair.spacing * (np.argwhere(pair.array == 17) + 0.5)
    theirs = nib.affines.apply_affine(LIA, np.argwhere(aseg == 17))
    assert sorted(map(tuple, np.round(hippo, 6))) == sorted(map(tuple, np.round(theirs, 6)))
    (tmp_path / "lone.hdr").write_bytes((tmp_path / "seg.hdr").read_bytes())
    fails(capsys, "info", tmp_path / "lone.hdr", "--labels", words=("lone.hdr: not a readable Analyze file",))
    # a single-file NIfTI named as half of a pair
    nib.save(nib.Nifti1Image(aseg, LIA), tmp_path / "single.nii")
    (tmp_path / "single.nii").rename(tmp_path / "single.img")
    line = fails(capsys, "info", tmp_path / "single.img", "--labels", words=("single.img: not a readable Analyze file",))
    assert line.endswith("its content is NIfTI, not Analyze: rename it single.nii"), line


def test_an_analyze_voxel_size_of_0_is_said_to_be_read_as_1(tmp_path, capsys):
    # nibabel reads pixdim[2] = 0 as 1, and the surface was 1 thick a voxel along y in silence
    box = np.zeros((4, 5, 6), np.uint8)
    box[1:3, 1:4, 2:5] = 1
    nib.save(nib.AnalyzeImage(box, np.diag([2.0, 3.0, 0.5, 1.0])), tmp_path / "box.hdr")
    header = bytearray((tmp_path / "box.hdr").read_bytes())
    header[84:88] = np.float32(0).tobytes()  # dbh.h: float pixdim[8] at byte 76, pixdim[2] 8 bytes on
    (tmp_path / "box.hdr").write_bytes(bytes(header))
    assert main(["surface", str(tmp_path / "box.hdr"), "-o", str(tmp_path / "s.ply"), "-q"]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.rstrip().endswith("; pixdim[2] 0, no voxel size: read as 1, as nibabel does"), err
    m = trimesh.load(tmp_path / "s.ply", process=False)
    assert m.bounds.tolist() == [[2.0, 1.0, 1.0], [6.0, 4.0, 2.5]]  # voxel 0's corner at 0, sizes 2, 1, 0.5


@pytest.mark.parametrize("pitch", [0.5, 0.3])
@pytest.mark.parametrize("suffix", [".mgz", ".nii.gz"])
def test_an_origin_that_float32_holds_reads_back_exactly(tmp_path, capsys, suffix, pitch):
    """MGH stores the volume's centre and NIfTI voxel 0's centre in float32,
    beside the float32 voxel size: where the origin plus that size's share
    is a float32 number, the file holds the origin exactly, and so must the
    reading (nibabel's MGH affine, built in float32, is off by ~1e-8)."""
    shape = (7, 11, 15)
    size32 = float(np.float32(pitch))
    share = (np.array(shape) + 1) / 2 if suffix == ".mgz" else np.full(3, 0.5)
    checked = 0
    for origin in (0.0, 1.5, -2.0):
        stored = origin + size32 * share
        held = stored.astype(np.float32) == stored
        checked += held.sum()
        obj = isoflow.DigitalObject(np.ones(shape, bool), pitch=pitch, origin=(origin,) * 3)
        path = isoflow.write_volume(obj, tmp_path / f"o{origin}{suffix}")
        back = isoflow.read_volume(path)
        assert back.origin[held].tolist() == [origin] * int(held.sum())
        assert back.spacing.tolist() == [size32] * 3
    assert checked >= 3
    out = run(capsys, "info", tmp_path / f"o0.0{suffix}")
    assert "origin [0, 0, 0]" in out


def test_a_volume_without_a_unit_written_as_mgz_says_once_that_it_reads_back_in_mm(tmp_path):
    """MGH's sizes are millimetres by definition (FreeSurfer's format has
    no unit field): a volume without a unit (a voxelised STL,
    a bare array) written as .mgz was read back in mm without a word, a
    unit the volume never had. One warning line says so as it is written;
    a volume in mm writes without one, and one in µm keeps its warning."""
    import subprocess
    import sys

    box = isoflow_box(tmp_path)
    out = tmp_path / "box.mgz"
    done = subprocess.run([sys.executable, "-m", "isoflow", "voxelize", str(box), "--resolution", "4", "-o", str(out)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    lines = [line for line in done.stderr.splitlines() if "numba is compiling" not in line]
    assert lines == [f"isoflow voxelize: warning: {out}: the volume has no length unit and MGH's is mm by definition: "
                     "its voxel size and origin are written as given and read back as mm"], lines
    # the numbers as given (trimesh's unit box at resolution 4: 0.25), which every reader takes as mm
    assert nib.load(out).header.get_zooms()[:3] == (0.25, 0.25, 0.25)
    info = subprocess.run([sys.executable, "-m", "isoflow", "info", str(out), "--json"], capture_output=True, text=True)
    assert info.returncode == 0 and json.loads(info.stdout)["unit"] == "mm"
    vol = np.ones((2, 2, 2), bool)
    for unit, said in ((None, ["no length unit"]), ("mm", []), ("micron", ["the unit µm"])):
        for write in (lambda p, u=unit: isoflow.write_volume(isoflow.DigitalObject(vol, unit=u), p),
                      lambda p, u=unit: isoflow.write_labels(vol.astype(np.uint8), p, unit=u)):
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                path = write(tmp_path / f"v{unit}.mgz")
            messages = [str(w.message) for w in caught if issubclass(w.category, IsoflowWarning)]
            assert len(messages) == len(said) and all(s in m for s, m in zip(said, messages)), messages
            assert isoflow.read_labels(path).unit == "mm"
            path.unlink()
