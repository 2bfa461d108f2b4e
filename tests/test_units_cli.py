"""The length unit of a volume file, read and reported: ``isoflow info``
says the voxel size, origin and unit it read (text and --json), and
``info --labels`` the unit of its table's world columns, for files written
by each format's own library with a known unit."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from in_process import isoflow_here

import isoflow
from isoflow.cli import main

nib = pytest.importorskip("nibabel")
tifffile = pytest.importorskip("tifffile")

MICRO = "\u00b5m"
PITCH = (0.5, 0.75, 1.25)  # exact in float32 (NIfTI) and as TIFF rationals


def cube() -> np.ndarray:
    """Two labels in an (x, y, z) array of 8x6x4."""
    labels = np.zeros((8, 6, 4), np.uint8)
    labels[2:6, 1:4, 1:3] = 1
    labels[6:8, 4:6, 1:3] = 2
    return labels


def report(capsys, *args) -> dict:
    assert main(["info", *map(str, args), "--json"]) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def both(capsys, path, label=1) -> tuple[dict, dict]:
    """``info --label`` (one object) and ``info --labels`` (the table) of ``path``."""
    return report(capsys, path, "--label", label), report(capsys, path, "--labels")


def same(a, b) -> bool:
    return np.allclose(a, b, rtol=1e-6, atol=1e-9)


# ------------------------------------------------------------------ NIfTI

@pytest.mark.parametrize("written, unit", [("mm", "mm"), ("micron", MICRO), ("meter", "m"), ("unknown", None)])
def test_nifti_unit_is_the_headers_xyzt_unit(tmp_path, capsys, written, unit):
    affine = np.diag([*PITCH, 1.0])
    affine[:3, 3] = (10.0, -20.0, 30.0)  # voxel 0's centre (NIfTI's affine maps centres)
    img = nib.Nifti1Image(cube(), affine)
    img.header.set_xyzt_units(written)
    nib.save(img, tmp_path / "seg.nii.gz")
    back = nib.load(tmp_path / "seg.nii.gz")
    assert back.header.get_xyzt_units()[0] == written
    one, table = both(capsys, tmp_path / "seg.nii.gz")
    zooms = np.asarray(back.header.get_zooms()[:3], np.float64)
    corner = back.affine[:3, 3] - zooms / 2
    for r in one, table:
        assert r["unit"] == unit
        assert same(r["pitch"], zooms) and same(r["origin"], corner)
    assert isoflow.read_labels(tmp_path / "seg.nii.gz").unit == unit


def test_info_text_says_voxel_size_origin_and_unit(tmp_path):
    img = nib.Nifti1Image(cube(), np.diag([*PITCH, 1.0]))
    img.header.set_xyzt_units("mm")
    nib.save(img, tmp_path / "mm.nii.gz")
    nib.save(nib.Nifti1Image(cube(), np.diag([*PITCH, 1.0])), tmp_path / "bare.nii.gz")  # xyzt units 0: unknown

    def second_line(name, *options):
        done = isoflow_here("info", str(tmp_path / name), *options)
        assert done.returncode == 0, done.stderr
        return done.stdout.splitlines()[:2]

    head = second_line("mm.nii.gz", "--label", "1")[1]
    assert head.split()[:2] == ["voxel", "size"]
    assert "0.5 x 0.75 x 1.25 mm, origin [-0.25, -0.375, -0.625] mm" in head
    # a NIfTI's world is RAS (nifti1.h), unit or none
    assert second_line("bare.nii.gz", "--label", "1")[1].endswith(
        "origin [-0.25, -0.375, -0.625] (the file says no unit), frame RAS")
    assert "voxel 0.5x0.75x1.25 mm," in second_line("mm.nii.gz", "--labels")[0]
    assert "voxel 0.5x0.75x1.25," in second_line("bare.nii.gz", "--labels")[0]


def series_json(tmp_path):
    """A time series in mm as nibabel writes it (the fourth axis frames,
    not millimetres) and ``info --json`` of it."""
    series = np.repeat((cube() == 1).astype(np.uint8)[..., None], 3, axis=3)
    img = nib.Nifti1Image(series, np.diag([*PITCH, 1.0]))
    img.header.set_xyzt_units("mm", "sec")
    nib.save(img, tmp_path / "t.nii.gz")
    done = isoflow_here("info", str(tmp_path / "t.nii.gz"), "--json")
    assert done.returncode == 0, done.stderr
    return img, json.loads(done.stdout)


def test_info_text_gives_the_unit_to_the_three_spatial_axes_of_a_4d_file(tmp_path):
    # a time series: the fourth axis is frames, not millimetres
    img, got = series_json(tmp_path)
    assert got["unit"] == img.header.get_xyzt_units()[0] and got["pitch"][:3] == list(img.header.get_zooms()[:3])
    text = isoflow_here("info", str(tmp_path / "t.nii.gz")).stdout.splitlines()[1]
    sizes = " x ".join(f"{p:g}" for p in got["pitch"][:3])
    assert f"{sizes} mm, origin [" in text and text.endswith(
        f"] mm (4th axis: size {got['pitch'][3]:g}, origin {got['origin'][3]:g}), frame RAS"), text


# ------------------------------------------------------------------ TIFF

@pytest.mark.parametrize("written, unit", [("um", MICRO), ("micron", MICRO), ("\\u00B5m", MICRO),
                                           ("cm", "cm"), ("nm", "nm"), ("pixel", None)])
def test_imagej_tiff_unit_is_its_descriptions_unit(tmp_path, capsys, written, unit):
    # ImageJ's FileSaver writes µm as "um"; "\u00B5m" as an escape; "pixel" for an uncalibrated image
    tifffile.imwrite(tmp_path / "seg.tif", cube().T, imagej=True, resolution=(1 / PITCH[0], 1 / PITCH[1]),
                     metadata={"axes": "ZYX", "unit": written, "spacing": PITCH[2]})
    with tifffile.TiffFile(tmp_path / "seg.tif") as tif:
        assert tif.imagej_metadata["unit"] == written
        x, y = (n / d for n, d in (tif.pages[0].tags[t].value for t in (282, 283)))
    one, table = both(capsys, tmp_path / "seg.tif")
    for r in one, table:
        assert r["unit"] == unit
        assert same(r["pitch"], [1 / x, 1 / y, PITCH[2]]) and r["origin"] == [0, 0, 0]


def test_imagej_tiff_without_a_unit_gives_none(tmp_path, capsys):
    tifffile.imwrite(tmp_path / "seg.tif", cube().T, imagej=True, metadata={"axes": "ZYX"})
    for r in both(capsys, tmp_path / "seg.tif"):
        assert r["unit"] is None and r["pitch"] == [1, 1, 1]


@pytest.mark.parametrize("written, unit", [({"PhysicalSizeXUnit": "nm", "PhysicalSizeYUnit": "nm",
                                             "PhysicalSizeZUnit": "nm"}, "nm"),
                                            ({}, MICRO)])  # the OME schema's default
def test_ome_tiff_unit_is_physical_size_x_unit(tmp_path, capsys, written, unit):
    sizes = dict(zip(("PhysicalSizeX", "PhysicalSizeY", "PhysicalSizeZ"), PITCH))
    tifffile.imwrite(tmp_path / "seg.ome.tif", cube().T, ome=True, metadata={"axes": "ZYX", **sizes, **written})
    for r in both(capsys, tmp_path / "seg.ome.tif"):
        assert r["unit"] == unit and same(r["pitch"], PITCH)


@pytest.mark.parametrize("resolution, tag, unit", [(20.0, "CENTIMETER", "cm"), (300.0, "INCH", "in"),
                                                   (72.0, "INCH", None), (4.0, "NONE", None)])
def test_plain_tiff_unit_is_its_resolution_unit_by_imagej_rule(tmp_path, capsys, resolution, tag, unit):
    # ImageJ: ResolutionUnit 3 is cm, 2 inch unless at 72 dpi (no scale), 1 none
    tifffile.imwrite(tmp_path / "seg.tif", cube()[:, :, 1].T, resolution=(resolution, resolution),
                     resolutionunit=tag)
    r = report(capsys, tmp_path / "seg.tif", "--label", 1)
    assert r["unit"] == unit
    assert same(r["pitch"], [1.0, 1.0] if resolution == 72.0 else [1 / resolution] * 2)


def imagej_calibration(tags: dict, description: dict | None, spacing: float = 1.0) -> tuple[list, float, str]:
    """x and y pitch, z spacing and unit as ImageJ 1.x computes them for a
    ResolutionUnit-3 (centimetre) TIFF, transcribed from its source
    (imagej/ImageJ commit 03dc240): TiffDecoder.OpenIFD sets pixelWidth =
    1 / XResolution and unit "cm"; FileOpener.decodeDescriptionString
    multiplies pixelWidth and pixelHeight by 10000 where the unit is "cm"
    and the description's unit is "um", then takes the description's unit;
    FileOpener.setCalibration, with Prefs.convertToMicrons (true by
    default), multiplies them by 10000, and pixelDepth unless it is 1.0,
    where pixelWidth <= 0.0001 and the unit is "cm", and sets "um"."""
    assert int(tags[296]) == 3
    width, height = (d / n for n, d in (tags[282], tags[283]))
    depth, unit = 1.0, "cm"
    if description is not None:
        if unit == "cm" and description.get("unit", "") == "um":
            width, height = width * 10000, height * 10000
        unit = description.get("unit", "")
        depth = abs(spacing)
    if width <= 0.0001 and unit == "cm":
        width, height = width * 10000.0, height * 10000.0
        depth = depth * 10000.0 if depth != 1.0 else depth
        unit = "um"
    return [width, height], depth, unit


# (pixels per cm, ImageJ description's unit or None for no description, spacing)
@pytest.mark.parametrize("per_cm, written, spacing", [
    (1e4 / 0.5, "um", 0.5),  # what tifffile users write for 0.5 um pixels: ImageJ reads 0.5 um
    (2e4, "micron", 0.5),  # only "um" is converted: 1 / resolution, in microns
    (2e4, None, 1.0),  # 0.5 um in cm with no description: ImageJ's convertToMicrons
    (2e4, "cm", 2e-4),  # a description in cm of 1 um or less: in um, z too
    (2e4, "cm", 1.0),  # ... but for a pixelDepth of 1, ImageJ's "no spacing"
    (20.0, None, 1.0),  # 0.05 cm: kept in cm
])
def test_centimetre_tiff_is_read_in_microns_as_imagej_reads_it(tmp_path, capsys, per_cm, written, spacing):
    """A TIFF whose ResolutionUnit is centimetre gives pitch and unit by
    ImageJ's conversions to microns (ij/io/FileOpener.java), computed here
    from the tags and description tifffile reads back."""
    stack = cube().T  # z, y, x
    if written is None:
        tifffile.imwrite(tmp_path / "seg.tif", stack, resolution=(per_cm, per_cm), resolutionunit="CENTIMETER",
                         photometric="minisblack")
    else:
        tifffile.imwrite(tmp_path / "seg.tif", stack, imagej=True, resolution=(per_cm, per_cm),
                         resolutionunit="CENTIMETER", metadata={"axes": "ZYX", "unit": written, "spacing": spacing})
    with tifffile.TiffFile(tmp_path / "seg.tif") as tif:
        tags = {t: tif.pages[0].tags[t].value for t in (282, 283, 296)}
        description = tif.imagej_metadata
        assert (description is not None) == (written is not None)
    xy, z, unit = imagej_calibration(tags, description, spacing)
    for r in both(capsys, tmp_path / "seg.tif"):
        assert r["unit"] == {"um": MICRO, "micron": MICRO, "cm": "cm"}[unit]
        assert same(r["pitch"], [*xy, z])
    if written == "um":  # the case as Fiji shows it: 0.5 x 0.5 x 0.5 um
        assert same(xy + [z], [0.5, 0.5, 0.5]) and unit == "um"


# ------------------------------------------------------------------ HDF5, NRRD, OME-Zarr, NumPy

def test_hdf5_element_size_um_is_in_micrometres(tmp_path, capsys):
    h5py = pytest.importorskip("h5py")
    with h5py.File(tmp_path / "fiji.h5", "w") as f:
        f.create_dataset("volume", data=cube()).attrs["element_size_um"] = PITCH
    isoflow.write_labels(cube(), tmp_path / "own.h5", pitch=PITCH)  # isoflow's pitch attribute: no unit
    for r in both(capsys, tmp_path / "fiji.h5"):
        assert r["unit"] == MICRO and same(r["pitch"], PITCH)
    for r in both(capsys, tmp_path / "own.h5"):
        assert r["unit"] is None and same(r["pitch"], PITCH)


@pytest.mark.parametrize("units, unit", [(["mm", "mm", "mm"], "mm"), (["micron"] * 3, MICRO)])
def test_nrrd_unit_is_its_space_units(tmp_path, capsys, units, unit):
    nrrd = pytest.importorskip("nrrd")
    header = {"space dimension": 3, "space directions": np.diag(PITCH), "space origin": np.array([1.0, 2.0, 3.0]),
              "space units": units, "kinds": ["domain"] * 3}
    nrrd.write(str(tmp_path / "seg.nrrd"), cube(), header, index_order="F")
    assert nrrd.read_header(str(tmp_path / "seg.nrrd"))["space units"] == units
    for r in both(capsys, tmp_path / "seg.nrrd"):
        assert r["unit"] == unit
        # space origin is the first sample's centre
        assert same(r["pitch"], PITCH) and same(r["origin"], np.array([1.0, 2.0, 3.0]) - np.array(PITCH) / 2)


def test_nrrd_without_a_space_takes_the_units_of_its_spacings(tmp_path, capsys):
    nrrd = pytest.importorskip("nrrd")
    nrrd.write(str(tmp_path / "seg.nrrd"), cube(), {"spacings": list(PITCH), "units": ["nm"] * 3}, index_order="F")
    assert nrrd.read_header(str(tmp_path / "seg.nrrd"))["units"] == ["nm"] * 3
    for r in both(capsys, tmp_path / "seg.nrrd"):
        assert r["unit"] == "nm" and same(r["pitch"], PITCH) and r["origin"] == [0, 0, 0]


def test_nrrd_with_space_units_isoflow_does_not_know_says_so(tmp_path):
    nrrd = pytest.importorskip("nrrd")
    header = {"space dimension": 3, "space directions": np.diag(PITCH), "space units": ["mm", "mm", "furlong"],
              "kinds": ["domain"] * 3}
    nrrd.write(str(tmp_path / "seg.nrrd"), cube(), header, index_order="F")
    done = isoflow_here("info", str(tmp_path / "seg.nrrd"), "--labels", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["unit"] is None
    assert "space units' differ by axis (mm, mm, furlong)" in done.stderr


def nrrd_mm_mm_cm(path) -> None:
    """A NRRD written by pynrrd whose z is in cm, x and y in mm: voxel 0's
    centre at (1 mm, 2 mm, 3 cm)."""
    nrrd = pytest.importorskip("nrrd")
    header = {"space dimension": 3, "space directions": np.diag(PITCH), "space origin": np.array([1.0, 2.0, 3.0]),
              "space units": ["mm", "mm", "cm"], "kinds": ["domain"] * 3}
    nrrd.write(str(path), cube(), header, index_order="F")
    assert nrrd.read_header(str(path))["space units"] == ["mm", "mm", "cm"]


def ome_zarr_um_um_mm(path) -> None:
    """An NGFF 0.4 image written with zarr itself whose z axis is in
    millimeter, y and x in micrometer: voxel 0's centre at (1 µm, 2 µm, 3 mm)."""
    ome_zarr(path, "micrometer")
    zarr = pytest.importorskip("zarr")
    group = zarr.open_group(str(path), mode="a")
    multiscales = group.attrs["multiscales"]
    multiscales[0]["axes"][0]["unit"] = "millimeter"  # (z, stored first)
    group.attrs["multiscales"] = multiscales


@pytest.mark.parametrize("write, name, unit, z_factor", [(nrrd_mm_mm_cm, "seg.nrrd", "mm", 10.0),
                                                         (ome_zarr_um_um_mm, "seg.zarr", MICRO, 1000.0)])
def test_axes_in_different_length_units_are_read_in_the_first_axis_unit(tmp_path, write, name, unit, z_factor):
    """A z axis in cm beside x and y in mm was read with no unit and the
    numbers as they were (z 10 times too short): a volume and an area in no
    unit at all, and a surface squashed along z. Each axis is converted to
    x's unit, as an OME-TIFF's PhysicalSizeZ is: 1 cm is 10 mm, 1 mm is
    1000 µm. The surface is read back by trimesh."""
    trimesh = pytest.importorskip("trimesh")
    write(tmp_path / name)
    pitch = np.array(PITCH) * [1.0, 1.0, z_factor]
    centre0 = np.array([1.0, 2.0, 3.0]) * [1.0, 1.0, z_factor]
    done = isoflow_here("info", str(tmp_path / name), "--label", "1", "--json")
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    assert got["unit"] == unit and same(got["pitch"], pitch) and same(got["origin"], centre0 - pitch / 2)
    assert np.isclose(got["volume"], np.count_nonzero(cube() == 1) * np.prod(pitch))
    assert "differ by axis" not in done.stderr
    done = isoflow_here("surface", str(tmp_path / name), "--label", "1", "-o",
                           str(tmp_path / "one.ply"))
    assert done.returncode == 0, done.stderr
    mesh = trimesh.load(tmp_path / "one.ply", process=False)
    index = np.argwhere(cube() == 1)  # label 1's voxels, (x, y, z)
    corner = centre0 - pitch / 2
    assert same(mesh.bounds, [corner + index.min(axis=0) * pitch, corner + (index.max(axis=0) + 1) * pitch])
    assert np.isclose(mesh.volume, np.count_nonzero(cube() == 1) * np.prod(pitch))


@pytest.mark.parametrize("labels", [["--label", "1"], ["--labels"]])
def test_a_unit_isoflow_does_not_know_is_said_once(tmp_path, labels):
    """An OME-Zarr store read block by block whose z is in parsec: the
    warning that no unit is reported came twice (the store's axes are read
    by the report and again by the placement it prints)."""
    ome_zarr(tmp_path / "seg.zarr", "micrometer")
    zarr = pytest.importorskip("zarr")
    group = zarr.open_group(str(tmp_path / "seg.zarr"), mode="a")
    multiscales = group.attrs["multiscales"]
    multiscales[0]["axes"][0]["unit"] = "parsec"
    group.attrs["multiscales"] = multiscales
    done = isoflow_here("info", str(tmp_path / "seg.zarr"), "--json", *labels)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["unit"] is None
    said = [line for line in done.stderr.splitlines() if "differ by axis" in line]
    assert len(said) == 1, done.stderr


def ome_zarr(path, unit: str | None, ndim: int = 3):
    """An NGFF 0.4 image written with zarr itself: (z, y, x), scale and
    translation, each spatial axis in ``unit``."""
    zarr = pytest.importorskip("zarr")
    data = cube().T if ndim == 3 else cube()[:, :, 1].T
    names = "zyx"[3 - ndim:]
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    group.create_array("0", shape=data.shape, dtype=data.dtype, chunks=(2,) * ndim)[...] = data
    axes = [{"name": n, "type": "space", **({"unit": unit} if unit else {})} for n in names]
    scale = list(PITCH[:ndim][::-1])
    transforms = [{"type": "scale", "scale": scale}, {"type": "translation", "translation": [3.0, 2.0, 1.0][3 - ndim:]}]
    group.attrs["multiscales"] = [{"version": "0.4", "axes": axes,
                                   "datasets": [{"path": "0", "coordinateTransformations": transforms}]}]
    return np.array(PITCH[:ndim]), np.array([1.0, 2.0, 3.0][:ndim]) - np.array(PITCH[:ndim]) / 2


@pytest.mark.parametrize("ndim", [3, 2])  # 3D: read block by block; 2D: whole
@pytest.mark.parametrize("written, unit", [("micrometer", MICRO), ("millimeter", "mm"), (None, None)])
def test_ome_zarr_unit_is_its_spatial_axes_unit(tmp_path, capsys, written, unit, ndim):
    pitch, corner = ome_zarr(tmp_path / "seg.zarr", written, ndim)
    for r in both(capsys, tmp_path / "seg.zarr"):
        assert r["unit"] == unit and same(r["pitch"], pitch) and same(r["origin"], corner)
    assert isoflow.read_labels(tmp_path / "seg.zarr").unit == unit


def test_npy_has_no_unit(tmp_path, capsys):
    np.save(tmp_path / "seg.npy", cube())
    for r in both(capsys, tmp_path / "seg.npy"):
        assert r["unit"] is None and r["pitch"] == [1, 1, 1] and r["origin"] == [0, 0, 0]


def test_the_csv_keeps_plain_column_names(tmp_path, capsys):
    img = nib.Nifti1Image(cube(), np.diag([*PITCH, 1.0]))
    img.header.set_xyzt_units("mm")
    nib.save(img, tmp_path / "seg.nii.gz")
    assert main(["info", str(tmp_path / "seg.nii.gz"), "--labels", "--csv", "-"]) == 0
    head = capsys.readouterr().out.splitlines()[0].split(",")
    assert head[:4] == ["label", "voxels", "volume", "surface_area"]  # the unit is said by --json and the text


def test_cli_md_says_what_the_4d_json_carries(tmp_path):
    """docs/cli.md said the world measures are 2D and 3D only while a 4D
    file's --json carried "unit": the page names the 4D report's keys, and
    the unit it carries is the file's, nibabel's reading of the spatial
    axes' unit, the one the text's second line gives them."""
    page = (Path(__file__).resolve().parents[1] / "docs" / "cli.md").read_text()
    start = page.index("A 4D report has")
    sentence = page[start:page.index(". A `.zarr`", start)]
    absent, present = sentence.split("but for a volume file", 1)
    assert set(re.findall(r"`([a-z_]+)`", absent)) == {"volume", "surface_area", "bbox", "centroid"}
    assert {"pitch", "origin", "unit"} <= set(re.findall(r"`([a-z_]+)`", present))
    img, got = series_json(tmp_path)
    assert not {"volume", "surface_area", "bbox", "centroid"} & set(got)
    assert got["unit"] == img.header.get_xyzt_units()[0] and len(got["pitch"]) == len(got["origin"]) == 4


@pytest.mark.parametrize("suffix", [".npz", ".h5"])
@pytest.mark.parametrize("stored, unit", [(5, None), (["mm", "mm"], None), (b"mm", "mm"), ("micron", MICRO)])
def test_a_unit_field_that_holds_no_text_is_no_unit(tmp_path, suffix, stored, unit):
    """A ``unit`` field of a number (5) or of several strings was printed
    as the unit ("voxel size 0.5 x 0.5 x 0.5 5", "... ['mm' 'mm']"), and
    bytes as their repr; a field of no text is now no unit, said in one
    warning naming the field and value, and bytes are their text."""
    path = tmp_path / f"v{suffix}"
    volume = (cube() == 1).astype(np.uint8)
    if suffix == ".npz":
        np.savez(path, volume=volume, pitch=np.array(0.5), unit=np.array(stored))
        field = "array 'unit'"
    else:
        h5py = pytest.importorskip("h5py")
        with h5py.File(path, "w") as f:
            f.create_dataset("volume", data=volume).attrs.update({"pitch": 0.5, "unit": stored})
        field = "attribute 'unit'"
    done = isoflow_here("info", str(path), "--json")
    assert done.returncode == 0, done.stderr
    got = json.loads(done.stdout)
    assert got["unit"] == unit and same(got["pitch"], [0.5] * 3)
    assert np.isclose(got["volume"], np.count_nonzero(volume) * 0.125)
    warned = [line for line in done.stderr.splitlines() if "not the text of a length unit" in line]
    assert len(warned) == (unit is None), done.stderr
    if unit is None:
        assert f"{field} is " in warned[0]
