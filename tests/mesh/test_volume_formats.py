"""Volume formats (issue 12): every format written by isoflow is read back
by isoflow and by the format's own library with equal voxels, voxel size
and origin; files written by the other tools are read with their placement.

Volumes are small and seeded, with edge and vertex contacts (random fill).
"""

import importlib.util
import re
import warnings

import numpy as np
import pytest

import isoflow
from isoflow.digital.lattice import DigitalObject
from isoflow.errors import IsoflowError, IsoflowWarning
from isoflow.mesh.formats.registry import format_for, split_dataset


@pytest.fixture
def vol(rng):
    v = rng.random((5, 6, 7)) < 0.45
    v[0, 0, 0], v[1, 1, 1], v[1, 1, 0] = True, True, False  # a vertex contact
    v[3, 0, 0], v[4, 1, 0], v[4, 0, 0], v[3, 1, 0] = True, True, False, False  # an edge contact
    return v


# values exact in float32 (NIfTI stores its affine in float32)
PITCH = np.array([0.5, 0.25, 2.0])
OFFSET, PARITY, ORIGIN = (1, -2, 3), 1, np.array([1.5, -2.0, 10.0])


def placed(vol, pitch=PITCH):
    return DigitalObject(vol, pitch=pitch, origin=ORIGIN, offset=OFFSET, parity=PARITY)


def corner(obj):
    """World position of array voxel 0's lowest corner."""
    return obj.world(np.zeros(obj.ndim))


def centre0(obj):
    return corner(obj) + obj.spacing / 2


def check_same_place(back, obj):
    assert np.array_equal(back.volume, obj.volume)
    np.testing.assert_allclose(back.spacing, obj.spacing, rtol=1e-12)
    np.testing.assert_allclose(corner(back), corner(obj), rtol=1e-12, atol=1e-12)


# --------------------------------------------------------------- registry

@pytest.mark.parametrize("name, module", [
    ("a.npy", "npy"), ("a.NPZ", "npy"), ("a.tif", "tiff"), ("a.TIFF", "tiff"), ("scan.nii.gz", "nifti"),
    ("a.nii", "nifti"), ("a.nrrd", "nrrd"), ("a.nhdr", "nrrd"), ("a.h5", "hdf5"), ("a.hdf5", "hdf5"),
    ("a.binvox", "binvox"), ("a.vox", "magicavoxel"), ("a.zarr", "omezarr"), ("a.ome.zarr", "omezarr"),
    ("aseg.mgz", "mgh"), ("T1.MGH", "mgh"), ("scan.hdr", "analyze"), ("scan.img", "analyze"),
])
def test_suffix_finds_the_format(name, module):
    assert format_for(name).module == module


def test_points_and_meshes_are_no_volume_format():
    assert format_for("p.txt") is None and format_for("m.stl") is None and format_for("a.gz") is None


def test_dataset_syntax():
    assert split_dataset("d/f.h5:/seg/mask") == (split_dataset("d/f.h5")[0], "/seg/mask")
    assert split_dataset("img.ome.zarr:1")[1] == "1"
    assert split_dataset("C:/data/scan.nii.gz")[1] is None  # a drive letter is no dataset


# --------------------------------------------------------------- pitch as a 3-vector

def test_vector_pitch_places_every_axis():
    obj = DigitalObject(np.ones((2, 2, 2), bool), pitch=[0.5, 1, 3], origin=[1, 2, 3])
    np.testing.assert_allclose(obj.world([[2, 2, 2]]), [[2.0, 4.0, 9.0]])
    assert DigitalObject(obj.volume, pitch=[2, 2, 2]).pitch == 2.0  # isotropic stays a number
    with pytest.raises(IsoflowError, match="'pitch'"):
        DigitalObject(obj.volume, pitch=[1, 0, 1])


def test_npz_keeps_a_vector_pitch(tmp_path, vol):
    obj = placed(vol)
    back = isoflow.read_volume(isoflow.write_volume(obj, tmp_path / "v.npz"))
    assert back.offset == OFFSET and back.parity == PARITY
    np.testing.assert_array_equal(back.pitch, PITCH)


# --------------------------------------------------------------- written by isoflow, read by the library

def imagej_origin(origin, pitch):
    """ImageJ's ``xorigin``, ``yorigin``, ``zorigin`` for a corner ``origin``:
    ImageJ's Calibration puts pixel coordinate ``p`` at ``(p - xorigin) *
    pixelWidth``, and its Image > Adjust > Coordinates spans an image from
    coordinate 0 (left edge) to its width (right edge), so coordinate 0 is
    voxel 0's lowest corner: ``origin = -xorigin * pitch``."""
    return {f"{axis}origin": -o / p for axis, o, p in zip("xyz", origin, pitch)}


def test_tiff_round_trip(tmp_path, vol):
    tifffile = pytest.importorskip("tifffile")
    obj = placed(vol)
    path = tmp_path / "v.tif"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the origin is written: nothing to warn of
        isoflow.write_volume(obj, path)
    with tifffile.TiffFile(path) as tif:
        assert np.array_equal(tif.asarray(), vol.transpose(2, 1, 0))  # pages, rows, columns = z, y, x
        np.testing.assert_allclose(1 / np.array(tif.pages[0].get_resolution()), PITCH[:2])
        assert tif.imagej_metadata["spacing"] == PITCH[2]
        written = {k: tif.imagej_metadata[k] for k in ("xorigin", "yorigin", "zorigin")}
    assert written == pytest.approx(imagej_origin(corner(obj), PITCH), rel=1e-12)
    back = isoflow.read_volume(path)
    assert np.array_equal(back.volume, vol)
    np.testing.assert_allclose(back.pitch, PITCH)
    np.testing.assert_allclose(corner(back), corner(obj), rtol=1e-12)


@pytest.mark.parametrize("kind", ["volume", "labels"])
def test_tiff_keeps_the_origin_as_imagej_calibration(tmp_path, vol, kind):
    """A TIFF kept no origin (read back at 0, with a warning on writing):
    the origin is written as ImageJ's calibration origin, in pixels, and
    read back, for a volume and for a label image."""
    tifffile = pytest.importorskip("tifffile")
    pitch, origin = (0.5, 0.25, 2.0), (1.0, 2.0, 3.0)
    path = tmp_path / f"{kind}.tif"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        if kind == "volume":
            isoflow.write_volume(DigitalObject(vol, pitch=pitch, origin=origin), path)
            back = isoflow.read_volume(path)
            assert np.array_equal(back.volume, vol)
        else:
            labels = vol.astype(np.uint16) * 300
            isoflow.write_labels(labels, path, pitch=pitch, origin=origin)
            back = isoflow.read_labels(path)
            assert np.array_equal(back.array, labels)
    assert back.origin.tolist() == list(origin) and back.spacing.tolist() == list(pitch)
    with tifffile.TiffFile(path) as tif:
        meta = tif.imagej_metadata
    assert {k: meta[k] for k in ("xorigin", "yorigin", "zorigin")} == imagej_origin(origin, pitch)


@pytest.mark.parametrize("shape", [(4, 5, 1), (1, 5, 4), (4, 1, 5), (1, 1, 5), (1, 1, 1), (5, 1), (1, 1)])
def test_tiff_round_trip_one_voxel_thick(tmp_path, rng, shape):
    # tifffile reads a last axis of length 1 as samples and drops axes of
    # length 1: a volume one voxel thick came back 2D, or with its axes turned
    tifffile = pytest.importorskip("tifffile")
    v = rng.random(shape) < 0.5
    v.flat[0] = True
    path = tmp_path / "thin.tif"
    isoflow.write_volume(v, path)
    with tifffile.TiffFile(path) as tif:  # a page per z slice, x by y: what Fiji opens
        z, y, x = (1, *shape[::-1]) if len(shape) == 2 else shape[::-1]
        assert len(tif.pages) == z and tif.pages[0].shape == (y, x)
    back = isoflow.read_volume(path)
    assert back.volume.shape == shape and np.array_equal(back.volume, v)


def test_nifti_round_trip(tmp_path, vol):
    nib = pytest.importorskip("nibabel")
    obj = placed(vol)
    path = isoflow.write_volume(obj, tmp_path / "v.nii.gz")
    img = nib.load(path)
    assert np.array_equal(np.asanyarray(img.dataobj), vol)
    np.testing.assert_allclose(img.header.get_zooms(), PITCH)
    np.testing.assert_allclose(nib.affines.apply_affine(img.affine, [0, 0, 0]), centre0(obj))
    check_same_place(isoflow.read_volume(path), obj)


def test_nifti_says_how_far_its_float32_affine_moves_a_far_volume(tmp_path, vol):
    """Voxels of 0.04 at x = 999998.7: float32's positions there are 0.0625
    apart, so nibabel places the file's voxels most of a voxel away from
    where they were; the warning gives that distance, in voxels."""
    nib = pytest.importorskip("nibabel")
    obj = DigitalObject(vol, pitch=0.04, origin=[999998.7, -3.0, 12.0])
    with pytest.warns(IsoflowWarning, match=r"far\.nii\.gz: NIfTI stores the voxel-to-world map as float32") as seen:
        path = isoflow.write_volume(obj, tmp_path / "far.nii.gz")
    said = float(re.search(r"by up to (\S+) voxels", str(seen[0].message)).group(1))
    img = nib.load(path)
    ends = np.array([[0, 0, 0], np.array(vol.shape) - 1])
    asked = centre0(obj) + ends * 0.04
    moved = np.abs(nib.affines.apply_affine(img.affine, ends) - asked).max() / 0.04
    assert moved > 0.5 and said == pytest.approx(moved, rel=1e-2)


def test_nifti_of_an_ordinary_placement_warns_of_nothing(tmp_path, vol):
    obj = DigitalObject(vol, pitch=0.0290063, origin=[-0.916228, -0.51953, -0.741088])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        path = isoflow.write_volume(obj, tmp_path / "v.nii.gz")
    np.testing.assert_allclose(corner(isoflow.read_volume(path)), corner(obj), atol=1e-6 * 0.0290063)


def test_nrrd_round_trip(tmp_path, vol):
    nrrd = pytest.importorskip("nrrd")
    obj = placed(vol, pitch=[0.1, 0.3, 0.7])  # NRRD's text header keeps float64 exactly
    path = isoflow.write_volume(obj, tmp_path / "v.nrrd")
    data, header = nrrd.read(str(path), index_order="F")
    assert np.array_equal(data, vol)
    np.testing.assert_allclose(header["space directions"], np.diag([0.1, 0.3, 0.7]))
    np.testing.assert_allclose(header["space origin"], centre0(obj))
    check_same_place(isoflow.read_volume(path), obj)


@pytest.mark.parametrize("write", ["write_volume", "write_labels"])
def test_nrrd_is_gzipped_at_zlibs_default_level_not_its_slowest(tmp_path, vol, write):
    # gzip's header says how hard the stream was packed (RFC 1952, XFL): 2
    # for the slowest level, 9 (pynrrd's default, several times the time for
    # files a few per cent smaller), 4 for the fastest, 0 for the levels
    # between, zlib's default 6 among them
    nrrd = pytest.importorskip("nrrd")
    image = vol.astype(np.uint16) * 300
    path = tmp_path / "v.nrrd"
    if write == "write_volume":
        isoflow.write_volume(placed(vol), path)
    else:
        isoflow.write_labels(image, path)
    raw = path.read_bytes()
    stream = raw[raw.index(b"\n\n") + 2:]
    assert stream[:3] == b"\x1f\x8b\x08"  # a gzip member of deflate data
    assert stream[8] == 0
    data = nrrd.read(str(path), index_order="F")[0]
    assert np.array_equal(data, vol if write == "write_volume" else image)


def test_hdf5_round_trip_with_a_dataset_path(tmp_path, vol):
    h5py = pytest.importorskip("h5py")
    obj = placed(vol)
    isoflow.write_volume(obj, f"{tmp_path / 'v.h5'}:/seg/mask")
    with h5py.File(tmp_path / "v.h5", "r") as f:
        assert np.array_equal(f["seg/mask"][()], vol)
        np.testing.assert_allclose(f["seg/mask"].attrs["pitch"], PITCH)
    back = isoflow.read_volume(f"{tmp_path / 'v.h5'}:/seg/mask")
    assert back.offset == OFFSET and back.parity == PARITY  # exact: isoflow's own attributes
    check_same_place(back, obj)
    check_same_place(isoflow.read_volume(tmp_path / "v.h5"), obj)  # the file's only dataset


def test_omezarr_round_trip_read_by_ome_zarr_py(tmp_path, vol):
    pytest.importorskip("ome_zarr")
    from ome_zarr.io import parse_url
    from ome_zarr.reader import Reader

    obj = placed(vol)
    path = isoflow.write_volume(obj, tmp_path / "v.ome.zarr")
    node = list(Reader(parse_url(str(path)))())[0]
    assert [a["name"] for a in node.metadata["axes"]] == ["z", "y", "x"]
    assert np.array_equal(np.asarray(node.data[0]), vol.transpose(2, 1, 0))
    scale, shift = node.metadata["coordinateTransformations"][0]
    np.testing.assert_allclose(scale["scale"], PITCH[::-1])
    np.testing.assert_allclose(shift["translation"], centre0(obj)[::-1])
    check_same_place(isoflow.read_volume(path), obj)


def test_binvox_round_trip_read_by_trimesh(tmp_path, vol):
    from trimesh.exchange.binvox import load_binvox, parse_binvox

    obj = placed(vol, pitch=0.5)
    path = isoflow.write_volume(obj, tmp_path / "v.binvox")
    with open(path, "rb") as fh:
        parsed = parse_binvox(fh)
    assert list(parsed.shape) == [7, 7, 7]  # padded to the cube the spec asks for
    np.testing.assert_allclose(parsed.translate, corner(obj))
    assert parsed.scale == 0.5 * 7
    with open(path, "rb") as fh:
        grid = load_binvox(fh)
    padded = np.zeros((7, 7, 7), bool)
    padded[:5, :6, :7] = vol
    assert np.array_equal(grid.matrix, padded)
    back = isoflow.read_volume(path)
    assert np.array_equal(back.volume, padded)
    assert back.pitch == 0.5
    np.testing.assert_allclose(corner(back), corner(obj))


def test_binvox_refuses_anisotropic_voxels(tmp_path, vol):
    with pytest.raises(IsoflowError, match="one voxel size"):
        isoflow.write_volume(placed(vol), tmp_path / "v.binvox")
    assert not (tmp_path / "v.binvox").exists()


def test_the_empty_last_state_of_a_flow_is_written_or_refused_in_one_line(tmp_path):
    # a plain run ends on the empty object, shape (0, 0, 0): the formats that keep it read it back as such,
    # TIFF (tifffile's own ValueError) and NIfTI (a file read back as shape (0,)) refuse it, binvox wrote scale 0
    gone = isoflow.run_flow(np.ones((3, 3, 3), bool)).states[-1]
    assert gone.volume.shape == (0, 0, 0)
    for suffix in (".npz", ".npy", ".h5", ".nrrd", ".zarr", ".vox", ".binvox"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IsoflowWarning)  # what .npy and .vox do not keep
            back = isoflow.read_volume(isoflow.write_volume(gone, tmp_path / f"gone{suffix}"))
        assert back.volume.shape == (0, 0, 0) and back.voxels == 0, suffix
    for suffix, fmt in ((".tif", "TIFF"), (".nii.gz", "NIfTI")):
        for shape in ((0, 0, 0), (0, 4, 5), (4, 0)):
            with pytest.raises(IsoflowError, match=f"{fmt} holds no array with a side of length 0, this one is "
                                                   f"{'x'.join(map(str, shape))}"):
                isoflow.write_volume(np.zeros(shape, bool), tmp_path / f"gone{suffix}")
            assert not list(tmp_path.glob(f"*gone*{suffix}*")), "nothing left behind"


def test_vox_round_trip_read_by_py_vox_io(tmp_path, vol):
    pytest.importorskip("pyvox")
    from pyvox.parser import VoxParser

    path = tmp_path / "v.vox"
    isoflow.write_volume(DigitalObject(vol), path)
    model = VoxParser(str(path)).parse().models[0]
    assert tuple(model.size) == vol.shape
    assert sorted((v.x, v.y, v.z) for v in model.voxels) == sorted(map(tuple, np.argwhere(vol).tolist()))
    assert np.array_equal(isoflow.read_volume(path).volume, vol)


def argwhere_vox(path, volume):
    """The MagicaVoxel writer as it was before it built its list a slab at
    a time (np.argwhere of the whole volume): the bytes to match."""
    import struct

    def chunk(cid, content):
        return cid + struct.pack("<ii", len(content), 0) + content

    xyz = np.argwhere(volume)
    colour = np.ones(len(xyz), np.uint8) if volume.dtype == np.bool_ else volume[tuple(xyz.T)]
    xyzi = np.column_stack([xyz, colour]).astype(np.uint8) if len(xyz) else np.zeros((0, 4), np.uint8)
    children = chunk(b"SIZE", struct.pack("<3i", *volume.shape)) + chunk(b"XYZI", struct.pack("<i", len(xyzi))
                                                                          + xyzi.tobytes())
    with open(path, "wb") as fh:
        fh.write(b"VOX " + struct.pack("<i", 150) + b"MAIN" + struct.pack("<ii", 0, len(children)) + children)


def vox_cases(rng, vol):
    """Masks and label images for the .vox writer: random ones with edge and
    vertex contacts, a full one, empty ones, one as a transposed view, the
    largest side on every axis, labels of many colours."""
    largest = rng.random((256, 256, 256)) < 0.002
    largest[255, 255, 255] = largest[0, 0, 0] = largest[255, 0, 255] = True
    colours = rng.integers(0, 256, (40, 30, 20)).astype(np.uint8)
    return [("vertex and edge contacts", vol), ("random", rng.random((17, 9, 31)) < 0.5),
            ("full", np.ones((12, 20, 9), bool)), ("empty", np.zeros((6, 5, 4), bool)),
            ("no voxels", np.zeros((0, 0, 0), bool)), ("a slab of side 0", np.zeros((3, 0, 4), bool)),
            ("transposed", np.transpose(rng.random((8, 11, 6)) < 0.3, (2, 0, 1))),
            ("largest", largest), ("256 x 1 x 256", rng.random((256, 1, 256)) < 0.5),
            ("labels", colours), ("labels uint16", colours.astype(np.uint16)),
            ("full labels", np.full((7, 7, 7), 255, np.uint8))]


def test_vox_writes_the_bytes_that_the_argwhere_writer_wrote(tmp_path, rng, vol, monkeypatch):
    """The .vox writer builds its voxel list a slab at a time (4 bytes a
    voxel set, where np.argwhere's list held 61): the file is the same byte
    for byte, and py-vox-io reads each voxel with its colour."""
    pytest.importorskip("pyvox")
    from pyvox.parser import VoxParser

    from isoflow.mesh.formats import magicavoxel

    given = []
    write = magicavoxel.write
    monkeypatch.setattr(magicavoxel, "write", lambda path, obj, *a, **k: (given.append(obj.volume), write(path, obj, *a, **k)))
    for what, volume in vox_cases(rng, vol):
        new, old = tmp_path / f"{what}.vox", tmp_path / f"{what} old.vox"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IsoflowWarning)
            if volume.dtype == np.bool_:
                isoflow.write_volume(DigitalObject(volume), new)
            else:
                isoflow.write_labels(volume, new)
        argwhere_vox(old, given[-1])  # the array the writer was handed (write_labels may narrow its type)
        assert new.read_bytes() == old.read_bytes(), what
        if volume.size:  # py-vox-io's parser takes a model of no side for no model
            model = VoxParser(str(new)).parse().models[0]
            assert tuple(model.size) == volume.shape, what
            expect = volume.astype(np.uint8) if volume.dtype != np.bool_ else volume.view(np.uint8)
            got = {(v.x, v.y, v.z): v.c for v in model.voxels}
            assert got == {tuple(p): int(expect[tuple(p)]) for p in np.argwhere(volume).tolist()}, what


def test_vox_writer_holds_four_bytes_a_voxel_set(tmp_path):
    """A .vox lists each voxel set as 4 bytes (x, y, z, colour): a full
    128^3 mask's writer holds that list and one slab's indices (tracemalloc
    sees numpy's arrays), where np.argwhere's int64 list held 61 bytes a
    voxel and its copies into bytes 12 more."""
    import tracemalloc

    side = 128
    obj = DigitalObject(np.ones((side, side, side), bool))
    isoflow.write_volume(DigitalObject(np.ones((2, 2, 2), bool)), tmp_path / "warm.vox")
    tracemalloc.start()
    try:
        isoflow.write_volume(obj, tmp_path / "full.vox")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    listed = 4 * side**3
    assert (tmp_path / "full.vox").stat().st_size == 60 + listed  # "VOX ", version, MAIN, SIZE, XYZI, its count, its list
    assert peak <= 1.1 * listed, peak / side**3


def test_vox_refuses_more_than_256_a_side(tmp_path):
    with pytest.raises(IsoflowError, match="at most 256"):
        isoflow.write_volume(DigitalObject(np.ones((257, 1, 1), bool)), tmp_path / "v.vox")


# --------------------------------------------------------------- written by the other tools

def test_nifti_from_nibabel_with_flips_and_a_permutation(tmp_path, rng):
    """Every voxel lands where nibabel's own apply_affine puts it."""
    nib = pytest.importorskip("nibabel")
    data = (rng.random((4, 5, 6)) < 0.5).astype(np.uint8)
    affine = np.array([[0, 0, -2.0, 30], [0.5, 0, 0, -12], [0, -1.5, 0, 7], [0, 0, 0, 1]])
    nib.save(nib.Nifti1Image(data, affine), tmp_path / "s.nii.gz")
    obj = isoflow.read_volume(tmp_path / "s.nii.gz")
    np.testing.assert_allclose(obj.pitch, [2.0, 0.5, 1.5])
    mine = obj.world(np.argwhere(obj.volume) + 0.5)  # voxel centres
    theirs = nib.affines.apply_affine(affine, np.argwhere(data))
    np.testing.assert_allclose(np.sort(mine, axis=0), np.sort(theirs, axis=0))
    assert sorted(map(tuple, np.round(mine, 9))) == sorted(map(tuple, np.round(theirs, 9)))


@pytest.mark.parametrize("srow_x", [(float("nan"), 0, 0, 0), (1, 0, 0, float("inf"))])
def test_a_nifti_affine_that_is_not_finite_says_so(tmp_path, srow_x):
    """A NaN voxel step or an infinite translation in the sform was said
    not to "fit a 3D array", which it does."""
    import struct

    nib = pytest.importorskip("nibabel")
    nib.save(nib.Nifti1Image(np.ones((3, 4, 5), np.uint8), np.eye(4)), tmp_path / "a.nii")
    raw = bytearray((tmp_path / "a.nii").read_bytes())
    struct.pack_into("<4f", raw, 280, *srow_x)  # srow_x: the sform's first row
    (tmp_path / "a.nii").write_bytes(bytes(raw))
    assert not np.isfinite(nib.load(tmp_path / "a.nii").affine).all()
    with pytest.raises(IsoflowError, match=r"a\.nii: the voxel-to-world map .* holds values that are not finite numbers$"):
        isoflow.read_volume(tmp_path / "a.nii")


def test_oblique_nifti_keeps_the_voxel_sizes_and_warns(tmp_path):
    nib = pytest.importorskip("nibabel")
    c, s = np.cos(np.radians(10)), np.sin(np.radians(10))
    affine = np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) @ np.diag([2.0, 3.0, 4.0, 1])
    nib.save(nib.Nifti1Image(np.ones((2, 2, 2), np.uint8), affine), tmp_path / "o.nii")
    with pytest.warns(IsoflowWarning, match="rotated or sheared by up to 10 degrees"):
        obj = isoflow.read_volume(tmp_path / "o.nii")
    np.testing.assert_allclose(obj.pitch, [2.0, 3.0, 4.0])


def test_nifti_whose_sform_and_qform_disagree_says_so(tmp_path, rng):
    """A header with a valid sform (code 2, aligned) and a valid qform
    (code 1, scanner) that put the voxels in different places: the volume
    is placed where nibabel's affine (the sform) puts it, and a warning
    says how far the qform, which other readers take, is from it. The
    choice was silent."""
    nib = pytest.importorskip("nibabel")
    data = (rng.random((4, 5, 6)) < 0.5).astype(np.uint8)
    sform = np.diag([2.0, 2.0, 2.0, 1.0])
    sform[:3, 3] = [-50, 0, 0]
    qform = np.eye(4)
    qform[:3, 3] = [100, 100, 100]
    img = nib.Nifti1Image(data, None)
    img.set_sform(sform, code=2)
    img.set_qform(qform, code=1)
    img.header.set_xyzt_units("mm")
    nib.save(img, tmp_path / "d.nii.gz")
    with pytest.warns(IsoflowWarning, match=r"d\.nii\.gz: its sform \(code 'aligned'\) and qform \(code 'scanner'\)") as seen:
        obj = isoflow.read_volume(tmp_path / "d.nii.gz")
    said = float(re.search(r"up to (\S+) mm apart", str(seen[0].message)).group(1))
    box = np.argwhere(np.ones((2, 2, 2))) * (np.array(data.shape) - 1)
    apart = np.linalg.norm(nib.affines.apply_affine(sform, box) - nib.affines.apply_affine(qform, box), axis=1).max()
    assert said == pytest.approx(apart, rel=1e-5)
    mine = obj.world(np.argwhere(obj.volume) + 0.5)
    theirs = nib.affines.apply_affine(nib.load(tmp_path / "d.nii.gz").affine, np.argwhere(data))
    np.testing.assert_allclose(np.sort(mine, axis=0), np.sort(theirs, axis=0))
    img.set_qform(sform, code=1)  # the two agreeing: nothing to say
    nib.save(img, tmp_path / "same.nii.gz")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        isoflow.read_volume(tmp_path / "same.nii.gz")


def test_tiff_stack_from_tifffile(tmp_path, vol):
    tifffile = pytest.importorskip("tifffile")
    stack = vol.transpose(2, 1, 0).astype(np.uint8)  # z, y, x
    tifffile.imwrite(tmp_path / "ij.tif", stack, imagej=True, resolution=(1 / 0.2, 1 / 0.4),
                     metadata={"spacing": 1.5, "unit": "um", "axes": "ZYX"})
    obj = isoflow.read_volume(tmp_path / "ij.tif")
    assert np.array_equal(obj.volume, vol)
    np.testing.assert_allclose(obj.pitch, [0.2, 0.4, 1.5])
    tifffile.imwrite(tmp_path / "plain.tif", stack)  # no ImageJ metadata: a page stack
    plain = isoflow.read_volume(tmp_path / "plain.tif")
    assert np.array_equal(plain.volume, vol) and plain.pitch == 1.0
    tifffile.imwrite(tmp_path / "page.tif", stack[0])  # one page: 2D (x, y)
    assert np.array_equal(isoflow.read_volume(tmp_path / "page.tif").volume, vol[:, :, 0])


def test_tiff_origin_as_fiji_writes_it(tmp_path, vol):
    """Fiji's Image > Properties "Origin" is saved as ImageJ's ``xorigin``,
    ``yorigin``, ``zorigin`` (pixels; a key only for an origin not 0): read
    as the world position of voxel 0's lowest corner, ``-xorigin * pitch``,
    for a stack (a volume and a label image) and a single image."""
    tifffile = pytest.importorskip("tifffile")
    stack = vol.transpose(2, 1, 0).astype(np.uint8)  # z, y, x
    pitch, pixels = (0.2, 0.4, 1.5), {"xorigin": 12.5, "yorigin": -3.0, "zorigin": 4.0}
    tifffile.imwrite(tmp_path / "fiji.tif", stack, imagej=True, resolution=(1 / pitch[0], 1 / pitch[1]),
                     metadata={"spacing": pitch[2], "unit": "micron", "axes": "ZYX", **pixels})
    want = [-pixels[f"{axis}origin"] * p for axis, p in zip("xyz", pitch)]
    obj = isoflow.read_volume(tmp_path / "fiji.tif")
    assert np.array_equal(obj.volume, vol)
    np.testing.assert_allclose(obj.origin, want, rtol=1e-9)
    np.testing.assert_allclose(corner(obj), want, rtol=1e-9)
    np.testing.assert_allclose(isoflow.read_labels(tmp_path / "fiji.tif").origin, want, rtol=1e-9)
    tifffile.imwrite(tmp_path / "flat.tif", stack[0], imagej=True, resolution=(1 / pitch[0], 1 / pitch[1]),
                     metadata={"axes": "YX", "yorigin": 10.0})
    flat = isoflow.read_volume(tmp_path / "flat.tif")
    assert flat.ndim == 2
    np.testing.assert_allclose(flat.origin, [0.0, -10.0 * pitch[1]], rtol=1e-9)


def test_tiff_origin_with_imagej_inverted_y_is_read_from_the_top_row_with_a_warning(tmp_path, vol):
    """ImageJ's ``inverty`` counts y up from the bottom row, which isoflow's
    y down the rows cannot hold: y is read from 0 and a warning says so."""
    tifffile = pytest.importorskip("tifffile")
    stack = vol.transpose(2, 1, 0).astype(np.uint8)
    tifffile.imwrite(tmp_path / "up.tif", stack, imagej=True,
                     metadata={"spacing": 2.0, "axes": "ZYX", "xorigin": 1.0, "yorigin": 5.0, "inverty": True})
    with pytest.warns(IsoflowWarning, match=r"up\.tif: ImageJ's inverted y \(inverty\) is not applied"):
        obj = isoflow.read_volume(tmp_path / "up.tif")
    assert obj.origin.tolist() == [-1.0, 0.0, 0.0] and np.array_equal(obj.volume, vol)


@pytest.mark.parametrize("value", ["abc", "inf"])
def test_tiff_origin_that_is_no_number_is_refused(tmp_path, value):
    tifffile = pytest.importorskip("tifffile")
    tifffile.imwrite(tmp_path / "bad.tif", np.ones((2, 3, 4), np.uint8), imagej=True,
                     metadata={"axes": "ZYX", "zorigin": value})
    with pytest.raises(IsoflowError, match=f"bad.tif: ImageJ's zorigin '?{value}'? is not a"):
        isoflow.read_volume(tmp_path / "bad.tif")


@pytest.mark.parametrize("version", ["0.4", "0.5"])
def test_omezarr_from_ome_zarr_py(tmp_path, version, rng):
    pytest.importorskip("ome_zarr")
    import zarr
    from ome_zarr.format import FormatV04, FormatV05
    from ome_zarr.io import parse_url
    from ome_zarr.reader import Reader

    with warnings.catch_warnings():  # ome_zarr's own default Scaler(), deprecated by ome_zarr
        warnings.simplefilter("ignore", DeprecationWarning)
        from ome_zarr.writer import write_image

    fmt = FormatV04() if version == "0.4" else FormatV05()
    data = (rng.random((1, 4, 8, 8)) < 0.5).astype(np.uint8)  # c, z, y, x
    path = tmp_path / "img.zarr"
    root = zarr.group(store=parse_url(str(path), mode="w", fmt=fmt).store, zarr_format=fmt.zarr_format)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        write_image(data, root, axes="czyx", fmt=fmt, scale={"z": 2.0, "y": 0.5, "x": 0.25},
                    scale_factors=[2], method="nearest")
    obj = isoflow.read_volume(path)
    assert np.array_equal(obj.volume, data[0].transpose(2, 1, 0))
    np.testing.assert_allclose(obj.pitch, [0.25, 0.5, 2.0])
    node = list(Reader(parse_url(str(path)))())[0]
    levels = [d["path"] for d in (node.zarr.root_attrs.get("ome", node.zarr.root_attrs)["multiscales"][0]["datasets"])]
    low = isoflow.read_volume(f"{path}:{levels[1]}")  # the second level, by its path
    assert np.array_equal(low.volume, np.asarray(node.data[1])[0].transpose(2, 1, 0))
    (scale, shift), = [node.metadata["coordinateTransformations"][1]]
    np.testing.assert_allclose(low.spacing, scale["scale"][:0:-1])
    np.testing.assert_allclose(low.world(np.zeros(3)) + low.spacing / 2, shift["translation"][:0:-1])
    assert np.array_equal(isoflow.read_volume(f"{path}:1").volume, low.volume)  # by index


def test_binvox_from_trimesh(tmp_path, rng):
    """trimesh's export; isoflow places voxels by the binvox spec
    (centre = translate + scale * (index + 0.5) / dim)."""
    import trimesh
    from trimesh.exchange.binvox import export_binvox

    dense = rng.random((6, 6, 6)) < 0.5
    grid = trimesh.voxel.VoxelGrid(dense, transform=trimesh.transformations.scale_and_translate(0.5, [1, 2, 3]))
    (tmp_path / "t.binvox").write_bytes(export_binvox(grid))
    obj = isoflow.read_volume(tmp_path / "t.binvox")
    assert np.array_equal(obj.volume, dense)
    header = (tmp_path / "t.binvox").read_bytes().split(b"data\n")[0].decode().split("\n")
    fields = {line.split()[0]: [float(x) for x in line.split()[1:]] for line in header[1:] if line.strip()
              and not line.startswith("#")}
    (scale,), translate = fields["scale"], np.array(fields["translate"])
    np.testing.assert_allclose(obj.world([[2, 3, 4]]) + obj.spacing / 2, [translate + scale * (np.array([2, 3, 4]) + 0.5) / 6])


def test_nrrd_from_pynrrd_with_a_flipped_space(tmp_path, vol):
    nrrd = pytest.importorskip("nrrd")
    directions = np.array([[-0.5, 0, 0], [0, 0, 2.0], [0, 0.25, 0]])  # axis 1 runs along z, axis 2 along y
    header = {"space": "left-posterior-superior", "space directions": directions, "space origin": [10.0, 20.0, 30.0]}
    nrrd.write(str(tmp_path / "s.nrrd"), vol.astype(np.uint8), header, index_order="F")
    obj = isoflow.read_volume(tmp_path / "s.nrrd")
    np.testing.assert_allclose(obj.pitch, [0.5, 0.25, 2.0])
    mine = obj.world(np.argwhere(obj.volume) + 0.5)
    theirs = np.argwhere(vol) @ directions + [10.0, 20.0, 30.0]
    assert sorted(map(tuple, np.round(mine, 9))) == sorted(map(tuple, np.round(theirs, 9)))


def test_hdf5_from_h5py_with_element_size(tmp_path, vol):
    h5py = pytest.importorskip("h5py")
    with h5py.File(tmp_path / "d.h5", "w") as f:
        f.create_dataset("raw", data=np.zeros((2, 2)))
        f.create_dataset("seg/mask", data=vol.astype(np.uint16)).attrs["element_size_um"] = [1.0, 0.5, 0.5]
    obj = isoflow.read_volume(f"{tmp_path / 'd.h5'}:/seg/mask")
    assert np.array_equal(obj.volume, vol)
    np.testing.assert_allclose(obj.pitch, [1.0, 0.5, 0.5])
    with pytest.raises(IsoflowError, match="holds datasets /raw, /seg/mask; name one"):
        isoflow.read_volume(tmp_path / "d.h5")


def test_hdf5_volume_beside_scalars_and_lists_is_read(tmp_path, vol):
    """A file holding one 3D array beside a name (a scalar string) and a
    voxel size (a list), as acquisition software writes them, was refused
    as holding several datasets, suggesting the scalar string
    (``e.g. f.h5:/name``). The one array of 2 to 4 axes is read (h5py's
    own read of it the reference); of two such arrays the suggestion names
    an array. The voxel size in a dataset of its own is not read (an
    attribute of the volume's is): a warning names it, rather than voxels
    of 1 in silence."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(tmp_path / "f.h5", "w") as f:
        f["a_name"] = "scan 1"
        f["spacing"] = np.array([1.0, 0.5, 0.5])
        f["data/image"] = vol.astype(np.uint8)
    with h5py.File(tmp_path / "f.h5") as f:
        stored = f["data/image"][()]
    with pytest.warns(isoflow.IsoflowWarning, match="f.h5: the dataset /spacing beside it is not read: voxels of 1"):
        assert np.array_equal(isoflow.read_volume(tmp_path / "f.h5").volume, stored.astype(bool))
    with h5py.File(tmp_path / "f.h5", "a") as f:
        f["other"] = vol.astype(np.uint8)
    with pytest.raises(IsoflowError, match="holds datasets /a_name, /data/image, /other, /spacing; name one, "
                                           "e.g. .*f.h5:/data/image$"):
        isoflow.read_volume(tmp_path / "f.h5")


@pytest.mark.parametrize("size", [[1.0, 0.5], [0.0, 1.0, 1.0], [b"x", b"y", b"z"]])
def test_hdf5_element_size_that_is_no_voxel_size_is_named(tmp_path, vol, size):
    """The refusal names the file's attribute and value, not isoflow's
    word for it ("'pitch' must be 3 numbers")."""
    h5py = pytest.importorskip("h5py")
    with h5py.File(tmp_path / "e.h5", "w") as f:
        f.create_dataset("mask", data=vol.astype(np.uint8)).attrs["element_size_um"] = size
    with pytest.raises(IsoflowError, match=r"e\.h5:mask: attribute 'element_size_um' .* is not 3 positive voxel sizes"):
        isoflow.read_volume(f"{tmp_path / 'e.h5'}:mask")
    with h5py.File(tmp_path / "one.h5", "w") as f:  # one number: the same size along every axis, as before
        f.create_dataset("mask", data=vol.astype(np.uint8)).attrs["element_size_um"] = 0.25
    assert isoflow.read_volume(tmp_path / "one.h5").pitch == 0.25


def test_vox_from_py_vox_io_colours_are_paint(tmp_path):
    pytest.importorskip("pyvox")
    from pyvox.models import Vox
    from pyvox.writer import VoxWriter

    dense = np.zeros((3, 4, 5), np.uint8)
    dense[0, 1, 2], dense[2, 3, 4], dense[1, 1, 1] = 1, 7, 7
    VoxWriter(str(tmp_path / "p.vox"), Vox.from_dense(dense)).write()
    # py-vox-io's from_dense takes (y, z, x) with z flipped: map our voxels through its parser
    from pyvox.parser import VoxParser

    model = VoxParser(str(tmp_path / "p.vox")).parse().models[0]
    expect = {(v.x, v.y, v.z): v.c for v in model.voxels}
    obj = isoflow.read_volume(tmp_path / "p.vox")
    assert {tuple(p): 1 for p in np.argwhere(obj.volume).tolist()} == {k: 1 for k in expect}
    seven = isoflow.read_volume(tmp_path / "p.vox", label=7)
    assert sorted(map(tuple, np.argwhere(seven.volume).tolist())) == sorted(k for k, c in expect.items() if c == 7)


# --------------------------------------------------------------- labels

def test_label_selects_one_value_and_a_label_image_is_refused(tmp_path, vol):
    labels = vol.astype(np.uint8) * 3
    labels[0, :, :] = 5
    np.save(tmp_path / "l.npy", labels)
    assert np.array_equal(isoflow.read_volume(tmp_path / "l.npy", label=3).volume, labels == 3)
    with pytest.raises(IsoflowError, match="threshold it first.*--label N"):
        isoflow.read_volume(tmp_path / "l.npy")
    with pytest.raises(IsoflowError, match=r"no voxel has label 4 \(values present: 0, 3, 5\)"):
        isoflow.read_object(tmp_path / "l.npy", label=4)


def test_npy_voxel_count_from_the_header_alone(tmp_path):
    from isoflow.mesh.formats.npy import voxel_count

    a = np.zeros((3, 4, 5), bool)
    np.save(tmp_path / "v1.npy", a)
    with open(tmp_path / "v2.npy", "wb") as fh:
        np.lib.format.write_array(fh, a, version=(2, 0))
    np.savez(tmp_path / "z.npy", volume=a)  # an .npz by another name
    (tmp_path / "bad.npy").write_bytes(b"not numpy")
    assert voxel_count(tmp_path / "v1.npy") == voxel_count(tmp_path / "v2.npy") == 60
    assert voxel_count(tmp_path / "z.npy.npz") is None
    assert voxel_count(tmp_path / "bad.npy") is None
    assert voxel_count(tmp_path / "missing.npy") is None


def test_a_store_read_whole_names_the_fill_value_of_chunks_never_written(tmp_path, capsys):
    """A zarr store read into memory (``read_volume``; ``flow`` without
    ``--volumes .zarr``) whose second chunk was never written reads it as
    the fill value, 2 here: the refusal said "e.g. 2" alone, a value no
    voxel was written with; it now says it is the fill value, as the
    commands that read the store block by block do."""
    zarr = pytest.importorskip("zarr")
    from isoflow.cli import main

    store = tmp_path / "sparse.zarr"
    z = zarr.create_array(str(store), shape=(8, 8, 8), chunks=(4, 8, 8), dtype="u1", fill_value=2)
    z[:4] = 1
    named = "(256 voxels hold values other than 0 and 1, e.g. 2, the array's fill value, which zarr reads"  # 4 x 8 x 8
    with pytest.raises(IsoflowError, match=re.escape(f"{store}: not a binary volume {named}")):
        isoflow.read_volume(store)
    assert main(["flow", str(store), "--steps", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and named in err[0], err
    z[4:] = 0  # every chunk written: 2 is no voxel's value, and the store reads as a mask
    assert isoflow.read_volume(store).voxels == 256


def _pillow_tiff(path, image, **save):
    Image = pytest.importorskip("PIL.Image")
    Image.fromarray(image).save(path, **save)


# ImageJ's rule (ij/io/TiffDecoder.java OpenIFD, ij/io/FileOpener.java
# decodeDescriptionString and setCalibration), row by row as
# docs/formats.md's table gives it: 1 at 72 per inch, ImageJ description or
# not; 1 / resolution where a ResolutionUnit tag or an ImageJ description is
# present, times 10000 where ImageJ converts centimetres to microns; 1 where
# neither is
@pytest.mark.parametrize(("writer", "save", "pitch"), [
    ("pillow", {}, [1.0, 1.0]),  # no resolution tags
    ("pillow", {"dpi": (72, 72)}, [1.0, 1.0]),  # the print default: uncalibrated
    ("pillow", {"dpi": (300, 300)}, [1 / 300, 1 / 300]),  # a scan's inches
    ("pillow", {"tiffinfo": {282: 2.0, 283: 4.0}}, [1.0, 1.0]),  # no ResolutionUnit: no unit
    ("tifffile", {"resolution": (72, 72), "resolutionunit": "INCH"}, [1.0, 1.0]),
    ("tifffile", {"resolution": (2, 4), "resolutionunit": "INCH"}, [0.5, 0.25]),
    ("tifffile", {"resolution": (20, 40), "resolutionunit": "CENTIMETER"}, [0.05, 0.025]),
    # centimetres of 1 um or less (FileOpener.setCalibration, Prefs.convertToMicrons): in um
    ("tifffile", {"resolution": (1e4, 2e4), "resolutionunit": "CENTIMETER"}, [1.0, 0.5]),
    # pixels per cm beside a description in "um" (FileOpener.decodeDescriptionString): times 10000
    ("tifffile", {"resolution": (2e4, 2e4), "resolutionunit": "CENTIMETER", "imagej": True,
                  "metadata": {"unit": "um"}}, [0.5, 0.5]),
    ("tifffile", {"resolution": (2, 4), "resolutionunit": "NONE"}, [0.5, 0.25]),
    ("tifffile", {"resolution": (2, 4), "imagej": True, "metadata": {"unit": "micron"}}, [0.5, 0.25]),
    ("tifffile", {"resolution": (72, 72), "resolutionunit": "INCH", "imagej": True,
                  "metadata": {"unit": "micron"}}, [1.0, 1.0]),
    ("tifffile", {"resolution": (72, 72), "resolutionunit": "INCH", "imagej": True}, [1.0, 1.0]),
    ("tifffile", {"resolution": (2, 4), "resolutionunit": "INCH", "imagej": True}, [0.5, 0.25]),
    # an ImageJ description without a ResolutionUnit tag: calibrated, as ImageJ's unit is then ""
    ("pillow", {"tiffinfo": {270: "ImageJ=1.54f\nunit=micron\n", 282: 2.0, 283: 4.0}}, [0.5, 0.25]),
    ("pillow", {"tiffinfo": {270: "ImageJ=1.54f\n", 282: 2.0, 283: 4.0}}, [0.5, 0.25]),
])
def test_tiff_pixel_size_follows_imagejs_calibration_rule(tmp_path, writer, save, pitch):
    """A TIFF at the print resolution of 72 dpi, or whose resolution has no
    unit, is uncalibrated, as ImageJ opens it: pitch 1 on x and y, as on
    z, not inches beside pixels; a resolution with a unit keeps its size."""
    image = np.zeros((4, 5), np.uint8)
    image[1:3, 1:4] = 255
    if writer == "pillow":
        _pillow_tiff(tmp_path / "a.tif", image, **save)
    else:
        pytest.importorskip("tifffile").imwrite(tmp_path / "a.tif", image, **save)
    obj = isoflow.read_volume(tmp_path / "a.tif")
    assert np.array_equal(obj.volume, image.T == 255)
    np.testing.assert_allclose(np.broadcast_to(obj.pitch, 2), pitch, rtol=1e-9)


def test_tiff_stack_at_72_dpi_has_pitch_1_on_every_axis(tmp_path):
    tifffile = pytest.importorskip("tifffile")
    stack = np.zeros((3, 4, 5), np.uint8)
    stack[1, 1:3, 1:4] = 1
    tifffile.imwrite(tmp_path / "s.tif", stack, resolution=(72, 72), resolutionunit="INCH",
                     photometric="minisblack")
    obj = isoflow.read_volume(tmp_path / "s.tif")
    assert obj.volume.shape == (5, 4, 3)
    np.testing.assert_array_equal(np.broadcast_to(obj.pitch, 3), [1.0, 1.0, 1.0])


@pytest.mark.parametrize("mode", ["RGB", "RGBA"])
def test_tiff_grey_stored_as_colour_is_read_as_grey_as_png_is(tmp_path, mode):
    """Pillow's RGB(A) TIFF of a grey image holds three equal channels (and
    an alpha): read as that grey, as the same image saved as PNG is."""
    grey = np.zeros((6, 7), np.uint8)
    grey[1:5, 2:6] = 255
    grey[2:4, 3:5] = 0  # a hole: Euler number 0
    pixels = np.stack([grey] * 3 + ([np.full_like(grey, 200)] if mode == "RGBA" else []), axis=-1)
    _pillow_tiff(tmp_path / "c.tif", pixels)
    _pillow_tiff(tmp_path / "c.png", pixels)
    tif, png = isoflow.read_volume(tmp_path / "c.tif"), isoflow.read_volume(tmp_path / "c.png")
    assert np.array_equal(tif.volume, grey.T == 255) and np.array_equal(tif.volume, png.volume)
    measure = pytest.importorskip("skimage.measure")
    assert measure.euler_number(tif.volume, connectivity=2) == 0


def test_tiff_colours_that_differ_are_refused_in_one_line(tmp_path):
    tifffile = pytest.importorskip("tifffile")
    pixels = np.zeros((4, 5, 3), np.uint8)
    pixels[1, 1] = (255, 0, 0)
    tifffile.imwrite(tmp_path / "c.tif", pixels)
    with pytest.raises(IsoflowError, match=r"^\S*c\.tif: holds colours, not labels or a mask \(its RGB channels "
                                           r"differ\); save it as a grey \(8- or 16-bit\) TIFF$"):
        isoflow.read_volume(tmp_path / "c.tif")


def _planes_saved_by(writer: str, path, stack: np.ndarray) -> None:
    """``stack``, a (3 or 4, Y, X) array, saved as ``writer`` saves it: one
    RGB(A) image in planes, through tifffile."""
    with warnings.catch_warnings():  # tifffile's notice that a later version writes such data as pages
        warnings.simplefilter("ignore", DeprecationWarning)
        if writer == "tifffile":
            pytest.importorskip("tifffile").imwrite(path, stack)
        elif writer == "skimage":
            pytest.importorskip("skimage.io").imsave(path, stack, check_contrast=False)
        else:
            pytest.importorskip("imageio.v3").imwrite(path, stack)


@pytest.mark.parametrize("writer", ["tifffile", "skimage", "imageio"])
@pytest.mark.parametrize("slices", [3, 4])
def test_tiff_rgb_planes_are_read_as_the_slices_every_python_reader_gives(tmp_path, rng, writer, slices):
    """tifffile, and scikit-image and imageio through it, save a (3 or 4,
    Y, X) array as one RGB(A) image in planes, and read it back as that
    array: isoflow reads the array tifffile reads, with one warning that
    names the storage and says a viewer shows the planes as colours."""
    tifffile = pytest.importorskip("tifffile")
    measure = pytest.importorskip("skimage.measure")
    stack = (rng.random((slices, 9, 11)) < 0.5).astype(np.uint8)
    _planes_saved_by(writer, tmp_path / "p.tif", stack)
    with tifffile.TiffFile(tmp_path / "p.tif") as tif:  # what the file says it holds
        assert tif.pages[0].photometric == 2 and tif.pages[0].planarconfig == 2
    read = tifffile.imread(tmp_path / "p.tif")
    assert read.shape == stack.shape
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        obj = isoflow.read_volume(tmp_path / "p.tif")
    said = [str(w.message) for w in caught if issubclass(w.category, IsoflowWarning)]
    assert len(said) == 1 and said[0].startswith(str(tmp_path / "p.tif"))
    assert "PhotometricInterpretation 2" in said[0] and "PlanarConfiguration 2" in said[0]
    assert "an image viewer shows the planes as the colours of one image" in said[0]
    assert np.array_equal(obj.volume, read.transpose(2, 1, 0) != 0)
    assert obj.volume.sum() == np.count_nonzero(read)
    assert isoflow.analyze(obj)["euler_characteristic"] == measure.euler_number(read != 0, connectivity=1)


@pytest.mark.parametrize("slices", [3, 4])
def test_tiff_equal_rgb_planes_are_slices_and_the_warning_saves_the_grey_image(tmp_path, slices):
    """Equal planes are the slices tifffile reads too (a volume whose slices
    are alike, or empty, is not read as 2D by its values); an image viewer
    shows them as one grey image, and the command the warning gives saves
    that image, which is then read as tifffile reads it."""
    import shlex
    import subprocess
    import sys

    tifffile = pytest.importorskip("tifffile")
    plane = np.zeros((4, 5), np.uint8)
    plane[1:3, 1:4] = 1
    _planes_saved_by("tifffile", tmp_path / "same.tif", np.stack([plane] * 3 + [np.full_like(plane, 255)] * (slices - 3)))
    read = tifffile.imread(tmp_path / "same.tif")
    with pytest.warns(IsoflowWarning, match=r"same\.tif: .* its colour planes are equal, shown as one grey image") as said:
        obj = isoflow.read_volume(tmp_path / "same.tif", label=1)  # (the alpha plane holds 255)
    assert np.array_equal(obj.volume, read.transpose(2, 1, 0) == 1)
    command = shlex.split(str(said[0].message).split("save its first plane as a grey image and give that: ", 1)[1])
    assert command[:2] == ["python", "-c"]
    subprocess.run([sys.executable, *command[1:]], check=True, cwd=tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error", IsoflowWarning)
        grey = isoflow.read_volume(tmp_path / "same_grey.tif")
    assert np.array_equal(grey.volume, tifffile.imread(tmp_path / "same_grey.tif").T == 1)
    assert np.array_equal(grey.volume, plane.T == 1)


def test_tiff_stack_of_rgb_pages_in_planes_is_read_as_rgb_pages_are(tmp_path):
    """A stack of RGB pages stored in planes, a (slices, 3, Y, X) array that
    tifffile reads back 4D, is read as a stack of interleaved RGB pages is:
    grey where the colours are equal, refused in one line where they
    differ."""
    tifffile = pytest.importorskip("tifffile")
    stack = np.zeros((2, 4, 5), np.uint8)
    stack[:, 1:3, 1:4] = 255
    tifffile.imwrite(tmp_path / "s.tif", np.stack([stack] * 3, axis=1), photometric="rgb", planarconfig="separate")
    tifffile.imwrite(tmp_path / "c.tif", np.stack([stack, stack, stack // 5], axis=1), photometric="rgb",
                     planarconfig="separate")
    with tifffile.TiffFile(tmp_path / "s.tif") as tif:
        assert tif.series[0].axes == "QSYX" and tif.pages[0].planarconfig == 2
    with warnings.catch_warnings():
        warnings.simplefilter("error", IsoflowWarning)
        obj = isoflow.read_volume(tmp_path / "s.tif")
    assert np.array_equal(obj.volume, tifffile.imread(tmp_path / "s.tif")[:, 0].transpose(2, 1, 0) == 255)
    with pytest.raises(IsoflowError, match=r"^\S*c\.tif: holds colours, not labels or a mask \(its RGB channels differ\)"):
        isoflow.read_volume(tmp_path / "c.tif")


def test_tiff_stack_of_grey_rgb_pages(tmp_path):
    tifffile = pytest.importorskip("tifffile")
    stack = np.zeros((2, 4, 5), np.uint8)
    stack[:, 1:3, 1:4] = 255
    tifffile.imwrite(tmp_path / "s.tif", np.stack([stack] * 3, axis=-1))
    assert np.array_equal(isoflow.read_volume(tmp_path / "s.tif").volume, stack.transpose(2, 1, 0) == 255)


def test_tiff_compressed_with_a_codec_tifffile_lacks_names_the_package(tmp_path):
    """An LZW TIFF (Pillow's ``tiff_lzw``, as many tools save) is whole;
    tifffile decodes it only with imagecodecs, which the line names."""
    tifffile = pytest.importorskip("tifffile")
    if importlib.util.find_spec("imagecodecs") is not None:
        pytest.skip("imagecodecs is installed: the file reads")
    _pillow_tiff(tmp_path / "lzw.tif", np.eye(4, dtype=np.uint8), compression="tiff_lzw")
    with tifffile.TiffFile(tmp_path / "lzw.tif") as tif:
        assert tif.pages[0].compression == 5  # LZW, as the file records it
    with pytest.raises(IsoflowError, match=r"^\S*lzw\.tif: its pixels are LZW-compressed, which tifffile decodes only "
                                           r"with the imagecodecs package: pip install imagecodecs$"):
        isoflow.read_volume(tmp_path / "lzw.tif")


@pytest.mark.parametrize("planar", [False, True])
def test_tiff_grey_with_alpha_is_read_as_the_grey(tmp_path, planar):
    """Grey with an alpha channel (Pillow's ``LA``, or in planes) is read as
    its grey, the alpha ignored, as a PNG's ``LA`` is."""
    tifffile = pytest.importorskip("tifffile")
    grey = np.zeros((4, 5), np.uint8)
    grey[1:3, 1:4] = 7
    alpha = np.full_like(grey, 255)
    if planar:
        tifffile.imwrite(tmp_path / "la.tif", np.stack([grey, alpha]), photometric="minisblack",
                         planarconfig="separate", extrasamples=["unassalpha"])
    else:
        _pillow_tiff(tmp_path / "la.tif", np.stack([grey, alpha], axis=-1))
    with tifffile.TiffFile(tmp_path / "la.tif") as tif:  # grey and one alpha sample, as the file records it
        assert tif.pages[0].photometric == 1 and tuple(tif.pages[0].extrasamples) == (2,)
    with warnings.catch_warnings():
        warnings.simplefilter("error", IsoflowWarning)
        obj = isoflow.read_volume(tmp_path / "la.tif", label=7)
    assert np.array_equal(obj.volume, grey.T == 7)


@pytest.mark.parametrize("suffix", [".nii.gz", ".mgz"])
@pytest.mark.parametrize(("pitch", "origin"), [(0.5, -3.0), (1e39, 0.0), (1e-300, 0.0), (1.0, 1e39)])
def test_a_float32_affine_is_read_back_by_nibabel_or_refused(tmp_path, suffix, pitch, origin):
    """NIfTI and MGH keep the affine in float32: a placement it holds is
    what nibabel's affine gives back; one past float32 (a size that rounds
    to 0 or to inf, a coordinate past 3.4e38) is refused before the file is
    written, not written as a file nibabel reads as inf, nan or 0."""
    nib = pytest.importorskip("nibabel")
    path = tmp_path / f"v{suffix}"
    obj = DigitalObject(np.ones((2, 3, 4), np.uint8), pitch=pitch, origin=(origin, 0.0, 0.0))
    holds = 1.5e-45 < pitch < 3.4e38 and abs(origin) < 3.4e38
    if not holds:
        with pytest.raises(IsoflowError, match=r"float32.*\.nrrd"):
            isoflow.write_volume(obj, path)
        assert not path.exists()
        return
    isoflow.write_volume(obj, path)
    affine = nib.load(path).affine
    np.testing.assert_allclose(np.diag(affine)[:3], [pitch] * 3, rtol=1e-6)
    np.testing.assert_allclose(affine[:3, 3], [origin + pitch / 2, pitch / 2, pitch / 2], rtol=1e-6)


@pytest.mark.parametrize("size", [1e-300, 1e-170, 1e170, 1e300])
def test_an_nrrd_voxel_size_far_from_1_is_read_as_pynrrd_reads_it(tmp_path, size):
    """A voxel size whose square underflows or overflows float64 is still a
    voxel size: read as the diagonal of the ``space directions`` pynrrd
    gives, not refused as zero or as two axes along one world axis."""
    nrrd = pytest.importorskip("nrrd")
    path = tmp_path / "v.nrrd"
    nrrd.write(str(path), np.ones((2, 3, 4), np.uint8),
               {"space": "left-posterior-superior", "space directions": np.diag([size] * 3), "space origin": [0, 0, 0]})
    _, header = nrrd.read(str(path))
    back = isoflow.read_volume(path)
    np.testing.assert_allclose(back.spacing, np.abs(np.diag(header["space directions"])), rtol=1e-12)
    assert back.volume.shape == (2, 3, 4)


@pytest.mark.parametrize("extents", [(4, 5, 6), (6, 6, 6)])
def test_voxelize_to_binvox_names_the_grid_a_reader_finds(tmp_path, capsys, extents):
    """``voxelize -o x.binvox`` said "in a 4x5x6 grid" of a file whose
    header gives a 6x6x6 cube (binvox holds a cube; the shorter axes are
    padded): the line names the grid trimesh's binvox reader finds too."""
    import trimesh
    from trimesh.exchange.binvox import parse_binvox

    from isoflow.cli.main import main

    trimesh.creation.box(extents=extents).export(tmp_path / "b.stl")
    assert main(["voxelize", str(tmp_path / "b.stl"), "--pitch", "1", "-o", str(tmp_path / "b.binvox")]) == 0
    line = capsys.readouterr().out.strip()
    with open(tmp_path / "b.binvox", "rb") as fh:
        dims = tuple(int(d) for d in parse_binvox(fh).shape)
    grid = "x".join(map(str, extents))
    if dims == extents:
        assert f"in a {grid} grid, pitch 1" in line, line
    else:
        assert f"in a {grid} grid (written as {'x'.join(map(str, dims))}: binvox holds a cube" in line, line
    assert f"{np.prod(extents)} voxels" in line


@pytest.mark.parametrize("suffix", [".png", ".tif", ".zarr"])
def test_a_4d_object_refused_by_a_format_of_images_is_sent_where_4d_is_written(tmp_path, suffix):
    """A 4D object written as PNG was sent to ".tif, .nii.gz, .nrrd, .h5 or
    .npz, which hold 3D" (a TIFF refuses it in turn), and TIFF and OME-Zarr
    refused it naming nowhere. Each names the formats that hold 4D, and
    each of those holds it: nibabel, pynrrd, h5py and NumPy read the
    same (x, y, z, t) array back."""
    nibabel = pytest.importorskip("nibabel")
    nrrd = pytest.importorskip("nrrd")
    h5py = pytest.importorskip("h5py")
    if suffix != ".png":
        pytest.importorskip({".tif": "tifffile", ".zarr": "zarr"}[suffix])
    series = np.random.default_rng(4).random((4, 3, 5, 2)) < 0.5
    with pytest.raises(IsoflowError) as caught:
        isoflow.write_volume(series, tmp_path / f"series{suffix}")
    message = str(caught.value)
    assert "\n" not in message and message.endswith("this object is 4D; write .nii.gz, .nrrd, .h5 or .npz, which hold 4D")
    named = re.findall(r"\.(?:nii\.gz|nrrd|h5|npz)\b", message.split("; write ")[1])
    assert named == [".nii.gz", ".nrrd", ".h5", ".npz"]
    for name in named:
        path = isoflow.write_volume(series, tmp_path / f"series{name}")
        if name == ".nii.gz":
            back = np.asarray(nibabel.load(path).dataobj)
        elif name == ".nrrd":
            back = nrrd.read(str(path))[0]
        elif name == ".h5":
            with h5py.File(path, "r") as f:
                back = next(f[k][()] for k in f if isinstance(f[k], h5py.Dataset))
        else:
            with np.load(path) as archive:
                back = next(archive[k] for k in archive.files if archive[k].ndim == 4)
        assert back.shape == series.shape and np.array_equal(back != 0, series), name
