"""Label images written by ``isoflow.write_labels`` in every format isoflow
writes, read back by ``read_labels`` and by the format's own library: what
the file holds against the array as written, and what docs/labels.md says
each format keeps of its voxel size and origin."""

import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import isoflow
from isoflow.errors import IsoflowError, IsoflowWarning

ROOT = Path(__file__).resolve().parents[2]

#: labels 0, 1 and 2 in a 3x4x5 image, each voxel's label known by hand
LABELS = np.zeros((3, 4, 5), np.uint8)
LABELS[0, 0, 0] = LABELS[2, 3, 4] = 1
LABELS[1, 1:3, 2:4] = 2


def own_reading(path: Path) -> np.ndarray:
    """The labels of ``path`` as the format's own library reads them, turned
    into isoflow's (x, y, z) order."""
    name = path.name
    if name.endswith(".npz"):
        with np.load(path) as z:
            return z["volume"]
    if name.endswith(".nii.gz"):
        nib = pytest.importorskip("nibabel")
        return np.asarray(nib.load(path).dataobj)
    if name.endswith(".h5"):
        h5py = pytest.importorskip("h5py")
        with h5py.File(path, "r") as f:
            return f["volume"][()]
    if name.endswith(".tif"):
        return pytest.importorskip("tifffile").imread(path).T
    raise AssertionError(name)


@pytest.mark.parametrize("suffix", [".npz", ".nii.gz", ".h5", ".tif"])
@pytest.mark.parametrize("dtype", [np.bool_, np.float32, np.float64])
def test_write_labels_takes_the_bool_and_float_images_that_label_table_takes(tmp_path, suffix, dtype):
    """write_labels refused a bool or float image ("a 3D or 2D array of
    integers, got 3D float32") that label_table takes: a bool image as
    labels 0 and 1, a float one of whole numbers as its integers. The file
    holds those integers, as its own library reads them, and the image read
    back gives label_table's rows of the array as given."""
    image = (LABELS > 0) if dtype is np.bool_ else LABELS.astype(dtype)
    expected = LABELS > 0 if dtype is np.bool_ else LABELS
    with warnings.catch_warnings():
        warnings.simplefilter("error", IsoflowWarning)  # each of these formats keeps the voxel size and origin
        path = isoflow.write_labels(image, tmp_path / f"labels{suffix}", pitch=(0.5, 0.25, 2.0), origin=(1, 2, 3))
    stored = own_reading(path)
    assert stored.dtype == np.uint8 and np.array_equal(stored, expected.astype(np.uint8))
    back = isoflow.read_labels(path)
    table = isoflow.label_table(back, 6, origin=(1, 2, 3))
    given = isoflow.label_table(image, 6, pitch=(0.5, 0.25, 2.0), origin=(1, 2, 3))
    assert table.keys() == given.keys()
    for column in given:
        assert np.array_equal(table[column], given[column], equal_nan=given[column].dtype.kind == "f"), column
    assert table["voxels"].tolist() == ([6] if dtype is np.bool_ else [2, 4])


@pytest.mark.parametrize(("value", "words"), [
    (1.5, "voxel (2, 1, 3) holds 1.5: not a whole number, so not a label"),
    (np.nan, "voxel (2, 1, 3) holds nan: not a label (a float32 label image holds whole numbers)"),
    (-2.0, "a label image holds labels from 0 on, this one holds -2.0 at voxel (2, 1, 3)"),
])
def test_write_labels_refuses_a_float_that_is_no_label_naming_its_voxel(tmp_path, value, words):
    image = LABELS.astype(np.float32)
    image[2, 1, 3] = value
    path = tmp_path / "labels.nii.gz"
    with pytest.raises(IsoflowError) as info:
        isoflow.write_labels(image, path)
    assert str(info.value) == f"write_labels: labels: {words}"
    assert not path.exists()
    if value >= 0 or np.isnan(value):  # (label_table takes negative labels; a file holds them from 0 on)
        with pytest.raises(IsoflowError, match=re.escape(words)):
            isoflow.label_table(image)


@pytest.mark.parametrize("dtype", [np.int8, ">i4", np.int64])
def test_a_negative_integer_label_is_refused_naming_its_voxel(tmp_path, dtype):
    image = LABELS.astype(dtype)
    image[1, 3, 0] = -7
    path = tmp_path / "labels.npz"
    with pytest.raises(IsoflowError) as info:
        isoflow.write_labels(image, path)
    assert str(info.value) == "write_labels: labels: a label image holds labels from 0 on, this one holds -7 at voxel (1, 3, 0)"
    assert not path.exists()


@pytest.mark.parametrize(("suffix", "fmt"), [(".binvox", "binvox holds 3D voxels"),
                                              (".vox", "MagicaVoxel holds 3D models")])
@pytest.mark.parametrize("top", [2, 300])
def test_a_2d_label_image_for_a_3d_format_is_refused_as_2d(tmp_path, suffix, fmt, top):
    """A 2D image with labels beyond what binvox (one) or MagicaVoxel (255)
    keeps was refused for its labels ("keeps labels up to 255, this image's
    labels go up to 300"), though no label count would make it fit: a 2D
    image is refused as 2D first."""
    cells = np.zeros((4, 5), np.uint16)
    cells[0, 0], cells[3, 4] = 1, top
    path = tmp_path / f"cells{suffix}"
    with pytest.raises(IsoflowError) as info:
        isoflow.write_labels(cells, path)
    assert str(info.value) == f"{path}: {fmt}, this object is 2D"
    assert not path.exists()


def test_a_dataset_named_like_a_3d_format_is_no_such_format(tmp_path):
    """The refusal of a 2D image by a format of 3D only looked at the name
    after the last slash: ``l.h5:/cells.vox`` was refused as MagicaVoxel,
    though it names a dataset of an HDF5 file, which holds 2D."""
    h5py = pytest.importorskip("h5py")
    cells = np.zeros((4, 5), np.uint16)
    cells[0, 0], cells[3, 4] = 1, 300
    file = isoflow.write_labels(cells, f"{tmp_path / 'l.h5'}:/cells.vox", pitch=0.5)
    with h5py.File(file, "r") as f:
        assert np.array_equal(f["cells.vox"][()], cells) and f["cells.vox"].dtype == np.uint16


def test_a_label_image_read_back_is_written_with_its_place(tmp_path):
    """write_labels refused what read_labels gives ("got 0D object"), though
    label_table takes it in place of the array, its pitch and origin: it is
    written with its spacing and origin, which pynrrd reads from the header
    (space origin: voxel 0's centre), unless a pitch or origin is given."""
    nrrd = pytest.importorskip("nrrd")
    first = isoflow.write_labels(LABELS, tmp_path / "first.npz", pitch=(0.5, 0.25, 2.0), origin=(1, 2, 3))
    path = isoflow.write_labels(isoflow.read_labels(first), tmp_path / "again.nrrd")
    data, header = nrrd.read(str(path), index_order="F")
    assert np.array_equal(data, LABELS)
    assert np.allclose(header["space directions"], np.diag([0.5, 0.25, 2.0]))
    assert np.allclose(header["space origin"], [1.25, 2.125, 4.0])
    back = isoflow.read_labels(isoflow.write_labels(isoflow.read_labels(first), tmp_path / "moved.npz", origin=(0, 0, 0)))
    assert back.spacing.tolist() == [0.5, 0.25, 2.0] and back.origin.tolist() == [0.0, 0.0, 0.0]


def test_voxelize_writes_a_tiff_of_labels_with_the_origin_of_its_nifti(tmp_path, capsys):
    """``voxelize A B -o labels.tif`` writes the labels that the same run
    writes to NIfTI (as tifffile and nibabel read them), and the TIFF keeps
    the origin that the NIfTI keeps (ImageJ's calibration origin): it was
    read back at 0, with a ``warning:`` line. Both are written without a
    word."""
    tifffile = pytest.importorskip("tifffile")
    nib = pytest.importorskip("nibabel")
    from isoflow.cli import main

    meshes = [str(ROOT / "meshes" / "torus.obj"), str(ROOT / "meshes" / "eight.off")]
    warned = {}
    for suffix in (".tif", ".nii.gz"):
        assert main(["voxelize", *meshes, "--resolution", "12", "-o", str(tmp_path / f"l{suffix}")]) == 0
        warned[suffix] = [line for line in capsys.readouterr().err.splitlines() if "warning:" in line]
    stored = tifffile.imread(tmp_path / "l.tif").T
    assert np.array_equal(stored, np.asarray(nib.load(tmp_path / "l.nii.gz").dataobj)) and set(np.unique(stored)) == {0, 1, 2}
    origin = isoflow.read_labels(tmp_path / "l.nii.gz").origin
    assert origin.any()
    np.testing.assert_allclose(isoflow.read_labels(tmp_path / "l.tif").origin, origin, rtol=1e-6)  # NIfTI's float32
    assert warned == {".tif": [], ".nii.gz": []}


def docs_rows() -> dict[str, list[str]]:
    """docs/labels.md's table of label files: its cells (labels, 2D, voxel
    size, origin) by suffix."""
    text = (ROOT / "docs" / "labels.md").read_text()
    table = text[text.index("| format | labels | 2D | voxel size | origin |"):].split("\n\n", 1)[0]
    rows = {}
    for line in table.splitlines()[2:]:
        cells = [c.strip() for c in line.strip("|").split("|")]
        for suffix in re.findall(r"`([^`]+)`", cells[0]):
            rows[suffix] = cells[1:]
    return rows


def kept_by_the_docs() -> dict[str, tuple[str, str]]:
    """(voxel size, origin) as docs/labels.md says each suffix keeps them."""
    return {suffix: (cells[2], cells[3]) for suffix, cells in docs_rows().items()}


#: every format write_labels writes, by one suffix each
WRITTEN = [".npz", ".nii", ".nii.gz", ".mgz", ".mgh", ".nrrd", ".h5", ".zarr", ".tif", ".npy", ".binvox", ".vox", ".png"]


def flat_only(suffix: str) -> bool:
    """Whether docs/labels.md says the format holds 2D images only (PNG)."""
    return docs_rows().get(suffix, ["", ""])[1] == "only"


def test_the_docs_list_every_format_write_labels_writes():
    from isoflow.mesh.formats.registry import format_for, volume_suffixes

    assert {format_for("l" + s, writing=True) for s in volume_suffixes(writable=True)} == {
        format_for("l" + s, writing=True) for s in WRITTEN}
    assert set(kept_by_the_docs()) == set(WRITTEN)


@pytest.mark.parametrize("suffix", WRITTEN)
def test_each_format_keeps_the_voxel_size_and_origin_the_docs_say_and_warns_of_the_rest(tmp_path, suffix):
    """docs/labels.md said write_labels writes a label image "with its pixel
    size and origin" in every format that holds 2D, but a TIFF held no
    origin (and .npy no placement): read back at 0. Each row of the table
    that now says what each format keeps is checked on a file written and
    read back, and a warning is given exactly where something is lost."""
    pitch = (0.5, 0.5, 0.5) if suffix == ".binvox" else (0.5, 0.25, 2.0)
    origin = (1.0, -2.0, 3.5)
    image = (LABELS > 0).astype(np.uint8) if suffix == ".binvox" else LABELS
    if flat_only(suffix):  # a slice of the same labels, placed by two numbers
        image, pitch, origin = LABELS[:, :, 2], pitch[:2], origin[:2]
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        path = isoflow.write_labels(image, tmp_path / f"labels{suffix}", pitch=pitch, origin=origin)
    back = isoflow.read_labels(path)
    corner = tuple(slice(0, n) for n in image.shape)
    assert np.array_equal(back.array[corner], image) and back.array.sum() == image.sum()
    size, place = kept_by_the_docs().get(suffix, ("(no row)", "(no row)"))
    assert np.allclose(back.spacing, pitch) == size.startswith("kept"), (size, back.spacing)
    assert np.allclose(back.origin, origin) == place.startswith("kept"), (place, back.origin)
    if not place.startswith("kept"):
        assert back.origin.tolist() == [0.0] * image.ndim
    # (MGH's note that a volume without a unit is read back in mm is of the unit, not of the placement)
    lost = [str(w.message) for w in said if issubclass(w.category, IsoflowWarning) and "no length unit" not in str(w.message)]
    assert bool(lost) == ("not kept" in (size, place)), lost
    if place == "not kept":
        assert len(lost) == 1 and str(path) in lost[0] and "origin" in lost[0] and "not" in lost[0]


@pytest.mark.parametrize("suffix", WRITTEN)
def test_each_format_keeps_the_labels_and_2d_images_the_docs_say(tmp_path, suffix):
    """The table's labels column (the largest label a file keeps) and its
    2D column, on files written: the largest label it gives is written and
    read back, one more is refused; a 2D image is written or refused."""
    labels, flat = docs_rows().get(suffix, ["(no row)", "(no row)"])[:2]
    top = {"any": 2**64 - 1, "one": 1}.get(labels) or int(labels.removeprefix("up to ").replace(",", ""))
    image = np.zeros((3, 4) if flat == "only" else (3, 4, 5), np.uint64)
    at = (1, 2, 3)[:image.ndim]
    image[at] = top
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IsoflowWarning)
        back = isoflow.read_labels(isoflow.write_labels(image, tmp_path / f"top{suffix}"))
        assert int(back.array.max()) == top and tuple(np.argwhere(back.array)[0]) == at
        if labels != "any":
            image[at] = top + 1
            with pytest.raises(IsoflowError, match=f"keeps (one label|labels up to {top})"):
                isoflow.write_labels(image, tmp_path / f"more{suffix}")
        cells = np.array([[0, 1, 1], [0, 0, 1]], np.uint8)
        if flat in ("yes", "only"):
            assert np.array_equal(isoflow.read_labels(isoflow.write_labels(cells, tmp_path / f"c{suffix}")).array, cells)
        else:
            assert flat == "no"
            with pytest.raises(IsoflowError, match="this object is 2D"):
                isoflow.write_labels(cells, tmp_path / f"c{suffix}")
        if flat == "only":
            with pytest.raises(IsoflowError, match="holds a 2D image, this object is 3D"):
                isoflow.write_labels(LABELS, tmp_path / f"v{suffix}")


@pytest.mark.parametrize(("pitch", "origin", "named"), [
    ((0.5, 0.5, 0.5), None, "its pitch [0.5, 0.5, 0.5] is not kept"),
    (1.0, (1, 2, 3), "its origin [1, 2, 3] is not kept"),
    ((0.5, 0.25, 2.0), (1, 2, 3), "its pitch [0.5, 0.25, 2], origin [1, 2, 3] are not kept"),
])
def test_a_npy_of_labels_names_what_it_drops_with_its_value(tmp_path, pitch, origin, named):
    """A label image to .npy was said to lose "pitch, origin, offset and
    parity" whatever it held: a label image has no lattice offset or
    parity. The warning names what this image holds and the file drops,
    with its value; the array as written is in the file."""
    with pytest.warns(IsoflowWarning) as caught:
        path = isoflow.write_labels(LABELS, tmp_path / "labels.npy", pitch=pitch, origin=origin)
    said = [str(w.message) for w in caught]
    assert len(said) == 1 and named in said[0] and "offset" not in said[0] and "parity" not in said[0], said
    assert np.array_equal(np.load(path), LABELS)
