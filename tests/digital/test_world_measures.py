"""The world measures of one object's report (``analyze``, ``info``):
volume and surface area (area and perimeter in 2D), box and centroid,
against values read independently: nibabel's voxel sizes, boundary faces
counted with NumPy, trimesh's area of the boundary mesh, scikit-image's
regionprops, and the label table's row of the same mask."""

import json

import numpy as np
import pytest
from conftest import random_volume

import isoflow
from isoflow import DigitalObject, analyze, label_table
from isoflow.cli import main
from isoflow.digital.outofcore import analyze_chunked

measure = pytest.importorskip("skimage.measure")


def numpy_faces(vol: np.ndarray) -> np.ndarray:
    """Boundary faces normal to each axis: the object and anything else
    (the outside too) side by side across a face."""
    padded = np.pad(vol.astype(np.int8), 1)
    return np.array([np.count_nonzero(np.diff(padded, axis=d)) for d in range(vol.ndim)])


def face_areas(pitch) -> np.ndarray:
    pitch = np.asarray(pitch, float)
    return np.array([np.prod(np.delete(pitch, d)) for d in range(len(pitch))])


def contacts(rng, shape=(9, 8, 7)) -> np.ndarray:
    """Random voxels, with pairs that touch by one edge or one vertex only."""
    vol = rng.random(shape) < 0.3
    vol[1, 1, 1] = vol[2, 2, 2] = True  # a vertex contact
    vol[2, 1, 1] = vol[1, 2, 1] = vol[1, 1, 2] = vol[2, 2, 1] = vol[2, 1, 2] = vol[1, 2, 2] = False
    vol[5, 5, 3] = vol[6, 6, 3] = True  # an edge contact
    vol[6, 5, 3] = vol[5, 6, 3] = False
    return vol


@pytest.mark.parametrize("method", ["numpy", "compiled"])
@pytest.mark.parametrize("conn", [6, 26])
def test_a_reports_measures_are_its_label_table_row(rng, conn, method):
    pytest.importorskip("numba")
    for _ in range(12):
        vol = contacts(rng, tuple(rng.integers(7, 14, 3)))
        pitch, origin = rng.uniform(0.2, 3.0, 3), rng.uniform(-10, 10, 3)
        row = label_table(vol.astype(np.uint8), conn, pitch=pitch, origin=origin)
        r = analyze(vol, conn, method=method, pitch=pitch, origin=origin, unit="mm")
        assert (r.volume, r.surface_area) == (row["volume"][0], row["surface_area"][0])
        assert r.bbox == [row[f"bbox-{d}"][0] for d in range(6)]
        assert r.centroid == [row[f"centroid-{d}"][0] for d in range(3)]
        assert r.unit == "mm"


@pytest.mark.parametrize("method", ["numpy", "compiled"])
def test_surface_area_counts_every_boundary_face_and_the_box_is_regionprops(rng, method):
    pytest.importorskip("numba")
    for _ in range(15):
        vol = random_volume(rng, 10)
        vol[tuple(rng.integers(0, s) for s in vol.shape)] = True
        pitch, origin = rng.uniform(0.1, 2.0, 3), rng.uniform(-5, 5, 3)
        r = analyze(vol, 26, method=method, pitch=pitch, origin=origin)
        assert r.volume == pytest.approx(np.count_nonzero(vol) * np.prod(pitch), rel=1e-12)
        assert r.surface_area == pytest.approx(numpy_faces(vol) @ face_areas(pitch), rel=1e-12)
        props = measure.regionprops(vol.astype(np.uint8))[0]
        assert r.bbox == pytest.approx(list(np.tile(origin, 2) + np.tile(pitch, 2) * props.bbox))
        assert r.centroid == pytest.approx(list(origin + pitch * (np.array(props.centroid) + 0.5)))


def test_a_placed_objects_box_is_its_own_bbox():
    vol = np.zeros((5, 4, 3), bool)
    vol[1:4, 2, 1:] = True
    obj = DigitalObject(vol, offset=(2, -1, 0), parity=1, pitch=(0.5, 2.0, 1.5), origin=(10, 20, 30), unit="um")
    r = analyze(obj)
    lo, hi = obj.bbox()
    assert r.bbox == pytest.approx(list(lo) + list(hi))
    assert r.unit == "\u00b5m"
    # a placement given replaces the object's, its offset and parity kept
    lo, hi = DigitalObject(vol, offset=(2, -1, 0), parity=1).bbox()
    assert analyze(obj, pitch=1.0, origin=(0, 0, 0), unit="mm").bbox == pytest.approx(list(lo) + list(hi))


def test_2d_area_perimeter_box_and_centroid_are_the_planar_table_and_regionprops(rng):
    for conn in (4, 8):
        for _ in range(10):
            vol = random_volume(rng, 15, ndim=2)
            vol[0, 0] = True
            pitch, origin = rng.uniform(0.1, 2.0, 2), rng.uniform(-5, 5, 2)
            r = analyze(vol, conn, pitch=pitch, origin=origin)
            row = label_table(vol.astype(np.uint8), conn, pitch=pitch, origin=origin)
            assert (r.area, r.perimeter) == (row["area"][0], row["perimeter"][0])
            assert r.bbox == [row[f"bbox-{d}"][0] for d in range(4)]
            assert r.centroid == [row[f"centroid-{d}"][0] for d in range(2)]
            props = measure.regionprops(vol.astype(np.uint8))[0]
            assert r.area == pytest.approx(props.area * np.prod(pitch))
            assert r.perimeter == pytest.approx(numpy_faces(vol) @ pitch[::-1])
            assert r.bbox == pytest.approx(list(np.tile(origin, 2) + np.tile(pitch, 2) * props.bbox))
            assert r.centroid == pytest.approx(list(origin + pitch * (np.array(props.centroid) + 0.5)))
            assert "volume" not in r and "surface_area" not in r


def test_empty_objects_box_is_null_and_4d_has_no_measures():
    empty = analyze(np.zeros((3, 3, 3), bool), pitch=2.0)
    assert (empty.volume, empty.surface_area, empty.bbox, empty.centroid) == (0.0, 0.0, None, None)
    text = json.dumps(empty.to_dict(), allow_nan=False)
    assert '"bbox": null' in text and '"centroid": null' in text
    assert isoflow.Report.from_dict(json.loads(text)) == empty
    cells = analyze(np.ones((2, 2, 2, 2), bool), 80)
    assert not {"volume", "surface_area", "area", "perimeter", "bbox", "centroid", "unit"} & set(cells)
    assert not {"volume", "bbox", "unit"} & set(analyze(np.array([0, 1, 1], bool)))


def test_measures_round_trip_through_json(rng):
    r = analyze(contacts(rng), 26, pitch=(0.3, 0.7, 1.1), origin=(1, 2, 3), unit="mm")
    back = isoflow.Report.from_dict(json.loads(json.dumps(r.to_dict(), allow_nan=False)))
    assert back == r and back.bbox == r.bbox and back.unit == "mm"


def test_block_by_block_measures_equal_in_memory(rng):
    da = pytest.importorskip("dask.array")
    for ndim, conn, chunks in ((3, 6, (4, 5, 3)), (3, 26, (3, 3, 4)), (2, 8, (5, 4))):
        for _ in range(6):
            vol = random_volume(rng, 13, ndim=ndim)
            pitch, origin = rng.uniform(0.2, 2.0, ndim), rng.uniform(-5, 5, ndim)
            whole = analyze(vol, conn, pitch=pitch, origin=origin, unit="mm")
            blocks = analyze_chunked(da.from_array(vol, chunks=chunks), conn, pitch=pitch, origin=origin, unit="mm")
            assert blocks == whole


def test_refuses_a_placement_of_a_1d_array_and_a_bad_pitch():
    with pytest.raises(isoflow.IsoflowError, match="2D to 4D"):
        analyze(np.array([1, 0, 1], bool), pitch=2.0)
    with pytest.raises(isoflow.IsoflowError, match="pitch"):
        analyze(np.ones((2, 2, 2), bool), pitch=(1.0, -1.0, 1.0))


# ------------------------------------------------------------------ files

nib = pytest.importorskip("nibabel")

ZOOMS = (0.5, 0.75, 2.0)  # anisotropic, exact in float32


def organ(rng) -> np.ndarray:
    vol = np.zeros((14, 12, 9), np.uint8)
    vol[2:11, 3:10, 1:7] = 1
    vol[5:7, 5:7, 3] = 0  # a cavity
    vol[rng.random(vol.shape) < 0.08] ^= 1
    return vol


def nifti(tmp_path, vol) -> tuple:
    affine = np.diag([*ZOOMS, 1.0])
    affine[:3, 3] = (10.0, -20.0, 30.0)
    img = nib.Nifti1Image(vol, affine)
    img.header.set_xyzt_units("mm")
    path = tmp_path / "organ.nii.gz"
    nib.save(img, path)
    return path, nib.load(path)


def info(capsys, *args) -> str:
    assert main(["info", *map(str, args)]) == 0, capsys.readouterr().err
    return capsys.readouterr().out


def test_info_of_a_nifti_says_its_volume_and_area_in_mm(tmp_path, capsys, rng):
    vol = organ(rng)
    path, back = nifti(tmp_path, vol)
    zooms = np.asarray(back.header.get_zooms()[:3], np.float64)
    corner = back.affine[:3, 3] - zooms / 2  # NIfTI's affine maps voxel centres
    r = json.loads(info(capsys, path, "--json"))
    assert r["unit"] == "mm"
    assert r["volume"] == pytest.approx(np.count_nonzero(back.get_fdata()) * np.prod(zooms), rel=1e-12)
    assert r["surface_area"] == pytest.approx(numpy_faces(vol > 0) @ face_areas(zooms), rel=1e-12)
    props = measure.regionprops((np.asarray(back.dataobj) > 0).astype(np.uint8))[0]
    assert r["bbox"] == pytest.approx(list(np.tile(corner, 2) + np.tile(zooms, 2) * props.bbox))
    assert r["centroid"] == pytest.approx(list(corner + zooms * (np.array(props.centroid) + 0.5)))
    text = info(capsys, path)
    assert f"volume                 {r['volume']:.6g} mm^3, surface area {r['surface_area']:.6g} mm^2\n" in text
    assert "  bounding box           [" in text and "centroid [" in text


def test_surface_area_is_trimeshs_area_of_the_surface_written(tmp_path, capsys, rng):
    trimesh = pytest.importorskip("trimesh")
    vol = organ(rng)
    path, _ = nifti(tmp_path, vol)
    for conn in ("6", "26"):
        out = tmp_path / f"organ{conn}.ply"
        assert main(["surface", str(path), "--connectivity", conn, "-o", str(out)]) == 0, capsys.readouterr().err
        capsys.readouterr()
        mesh = trimesh.load(out, process=False)
        r = json.loads(info(capsys, path, "--json", "--connectivity", conn))
        assert mesh.area == pytest.approx(r["surface_area"], rel=1e-9)
        assert list(mesh.bounds.ravel()) == pytest.approx(r["bbox"])  # the mesh is where the voxels are


def test_info_of_a_zarr_store_block_by_block_equals_the_same_volume_in_memory(tmp_path, capsys, rng):
    zarr = pytest.importorskip("zarr")
    vol = organ(rng).astype(bool)
    path, _ = nifti(tmp_path, vol.astype(np.uint8))
    whole = json.loads(info(capsys, path, "--json"))
    group = zarr.open_group(str(tmp_path / "organ.zarr"), mode="w")
    stored = group.create_array("0", shape=vol.T.shape, chunks=(4, 5, 6), dtype=bool)
    stored[...] = vol.T  # z, y, x, as OME-Zarr stores it
    scale = [float(z) for z in reversed(whole["pitch"])]
    shift = [o + s / 2 for o, s in zip(reversed(whole["origin"]), scale)]
    group.attrs["multiscales"] = [{"axes": [{"name": a, "type": "space", "unit": "millimeter"} for a in "zyx"],
                                   "datasets": [{"path": "0", "coordinateTransformations": [
                                       {"type": "scale", "scale": scale}, {"type": "translation", "translation": shift}]}]}]
    blocks = json.loads(info(capsys, tmp_path / "organ.zarr", "--json"))
    for key in ("voxels", "volume", "surface_area", "bbox", "centroid", "unit", "pitch", "origin", "shape"):
        assert blocks[key] == pytest.approx(whole[key]) if key != "unit" else blocks[key] == whole[key], key
