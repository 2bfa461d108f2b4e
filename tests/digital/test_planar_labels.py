"""The label table of 2D label images: every row equals ``analyze(image ==
label)`` in 2D on random label images whose labels touch by edges and
corners and nest inside each other, at 4 and 8; scikit-image's
regionprops gives the same pixel counts, Euler numbers, boxes and
centroids; the perimeter is the label's boundary pixel edges; and the
command line prints, writes and refuses 2D tables as it does 3D ones."""

import json
import subprocess
import sys

import numpy as np
import pytest

from isoflow import analyze, label_table, read_labels
from isoflow.digital import planar_labels
from isoflow.errors import IsoflowError


def analyze_row(mask, conn):
    r = analyze(mask, conn)
    return [r["voxels"], r["euler_characteristic"], r["betti"][0], r["betti"][1], *r["n"], r["non_well_composed"],
            r["energy"]]


def table_row(table, r):
    keys = ["voxels", "euler_characteristic", "b0", "b1", "n-0", "n-1", "n-2", "non_well_composed", "energy"]
    return [int(table[k][r]) for k in keys]


def edges_of(mask, pitch=(1.0, 1.0)):
    """The mask's boundary pixel edges times their length, counted on the mask alone."""
    m = np.pad(mask, 1).astype(np.int8)
    return (np.count_nonzero(np.diff(m, axis=0)) * pitch[1] + np.count_nonzero(np.diff(m, axis=1)) * pitch[0])


def nested(rng, shape=(23, 29)):
    """Rings of labels around rings around a disc, a ring cut open, in a
    noise of labels and 0 that touch them by edges and corners."""
    image = rng.choice([0, 0, 6, 7, 8], size=shape).astype(np.int64)
    y, x = np.indices(shape) - np.array([11, 13])[:, None, None]
    r = np.hypot(y, x)
    image[(r >= 8) & (r < 10)] = 1
    image[(r >= 5) & (r < 7)] = 2
    image[r < 3] = 3
    image[(r >= 3.5) & (r < 4.5) & (x != 0)] = 4  # a ring cut open: no hole
    image[:, -3:] = rng.choice([-5, 2**40 + 3, 9], size=(shape[0], 3))
    return image


@pytest.mark.parametrize("conn", [4, 8])
def test_random_label_images_equal_analyze_per_label(conn):
    rng = np.random.default_rng(20131122)
    for trial in range(120):
        shape = tuple(int(s) for s in rng.integers(1, 14, 2))
        image = rng.integers(0, int(rng.integers(2, 7)), shape)
        if trial % 3 == 0:  # sparse: labels meeting at single corners
            image = np.where(rng.random(shape) < 0.35, image, 0)
        image = image.astype(rng.choice([np.uint8, np.int16, np.uint32, np.int64]))
        table = label_table(image, conn)
        assert table["label"].tolist() == sorted(set(image[image != 0].tolist()))
        for r, label in enumerate(table["label"]):
            assert table_row(table, r) == analyze_row(image == label, conn), (trial, label)
            assert table["perimeter"][r] == edges_of(image == label)
            ys, xs = np.nonzero(image == label)
            assert [table[f"bbox-{d}"][r] for d in range(4)] == [ys.min(), xs.min(), ys.max() + 1, xs.max() + 1]
            assert [table[f"centroid-{d}"][r] for d in range(2)] == [ys.mean() + 0.5, xs.mean() + 0.5]


@pytest.mark.parametrize("conn", [4, 8])
def test_nested_rings_and_negative_and_wide_labels(conn):
    image = nested(np.random.default_rng(1))
    table = label_table(image, conn)
    for r, label in enumerate(table["label"]):
        assert table_row(table, r) == analyze_row(image == label, conn), label
    at = {int(v): r for r, v in enumerate(table["label"])}
    assert table["b1"][at[1]] >= 1 and table["b1"][at[2]] >= 1  # the rings hold holes
    assert table["b0"][at[3]] == 1 and table["b1"][at[3]] == 0
    assert -5 in at and 2**40 + 3 in at
    extremes = np.array([[-128, 127, 0], [127, -128, -128]], np.int8)  # the type's whole span
    t = label_table(extremes, conn)
    assert t["label"].tolist() == [-128, 127] and t["voxels"].tolist() == [3, 2]
    assert t["b0"].tolist() == ([2, 2] if conn == 4 else [1, 1])
    top = np.array([[2**64 - 1, 0], [2**64 - 3, 2**64 - 1]], np.uint64)  # beyond int64
    assert label_table(top, conn)["label"].tolist() == [2**64 - 3, 2**64 - 1]


def test_bool_image_is_one_label_and_the_table_by_chunks_or_without_histograms_is_the_same(monkeypatch):
    rng = np.random.default_rng(3)
    image = rng.integers(0, 40, (61, 47))
    whole = label_table(image, 8)
    monkeypatch.setattr(planar_labels, "VERTICES_AT_ONCE", 50)  # one vertex row at a time
    chunked = label_table(image, 8)
    for histogram in (0, 1):  # features summed directly, or a histogram per label
        monkeypatch.setattr(planar_labels, "HISTOGRAM_LABELS", histogram)
        table = label_table(image, 8)
        for key in whole:
            np.testing.assert_array_equal(whole[key], chunked[key], err_msg=key)
            np.testing.assert_array_equal(whole[key], table[key], err_msg=key)
    mask = image > 20
    t = label_table(mask)
    assert t["label"].tolist() == [1] and table_row(t, 0) == analyze_row(mask, 4)


def test_regionprops_gives_the_same_areas_euler_numbers_boxes_and_centroids():
    from skimage.measure import regionprops_table

    rng = np.random.default_rng(7)
    image = rng.integers(0, 9, (40, 33)).astype(np.int32)
    image[5:30, 4:28] = 0
    image[8:26, 8:24] = 3  # a label with holes of other labels inside
    image[12:14, 12:20] = 5
    image[16, 10] = 0
    ours = label_table(image, 8)
    theirs = regionprops_table(image, properties=("label", "area", "euler_number", "bbox", "centroid"))
    np.testing.assert_array_equal(ours["label"], theirs["label"])
    np.testing.assert_array_equal(ours["voxels"], theirs["area"])
    np.testing.assert_array_equal(ours["euler_characteristic"], theirs["euler_number"])
    for d in range(4):
        np.testing.assert_array_equal(ours[f"bbox-{d}"], theirs[f"bbox-{d}"])
    for d in range(2):  # pixel v spans [v, v + 1]: scikit-image's centroid plus 0.5
        np.testing.assert_allclose(ours[f"centroid-{d}"], theirs[f"centroid-{d}"] + 0.5, rtol=0, atol=1e-12)


@pytest.mark.parametrize("by_lines", [True, False])
def test_noise_read_by_rows_and_columns_gives_regionprops_areas_boxes_and_centroids(monkeypatch, by_lines):
    """Noise of a few labels, a run at nearly every pixel: each label's
    pixels are counted per row and per column, not read from the runs;
    its areas, boxes and centroids are scikit-image's either way (the runs
    read where the path is turned off)."""
    from skimage.measure import regionprops_table

    taken = []
    by_rows = planar_labels._places_by_lines
    monkeypatch.setattr(planar_labels, "_places_by_lines", lambda *a: taken.append(1) or by_rows(*a))
    if not by_lines:
        monkeypatch.setattr(planar_labels, "RUNS_PER_PIXEL", 1)  # more runs than pixels: never
    image = np.random.default_rng(8).integers(0, 6, (45, 52)).astype(np.int32)
    image[:3] = 7  # a label of three full rows, its box the image's width
    image[20:, 40:] = 0
    ours = label_table(image, 4)
    assert bool(taken) == by_lines
    theirs = regionprops_table(image, properties=("label", "area", "bbox", "centroid"))
    np.testing.assert_array_equal(ours["label"], theirs["label"])
    np.testing.assert_array_equal(ours["voxels"], theirs["area"])
    for d in range(4):
        np.testing.assert_array_equal(ours[f"bbox-{d}"], theirs[f"bbox-{d}"])
    for d in range(2):
        np.testing.assert_allclose(ours[f"centroid-{d}"], theirs[f"centroid-{d}"] + 0.5, rtol=0, atol=1e-12)
    for row, label in enumerate(ours["label"].tolist()):
        assert ours["euler_characteristic"][row] == analyze(image == label, 4)["euler_characteristic"]


def test_pitch_origin_and_labels_asked_for():
    image = np.zeros((6, 9), np.uint16)
    image[1:4, 2:7] = 4
    image[2, 4] = 0
    t = label_table(image, pitch=(0.5, 2.0), origin=(10.0, -1.0), labels=[4, 9])
    assert t["label"].tolist() == [4, 9]
    assert t["area"].tolist() == [14 * 1.0, 0.0]
    assert t["perimeter"][0] == edges_of(image == 4, (0.5, 2.0)) == 2 * 3 * 0.5 + 2 * 5 * 2.0 + 2 * 0.5 + 2 * 2.0
    assert [t[f"bbox-{d}"][0] for d in range(4)] == [10.5, 3.0, 12.0, 13.0]
    assert np.isnan(t["bbox-0"][1]) and np.isnan(t["centroid-1"][1])
    assert t["b1"].tolist() == [1, 0] and t["voxels"].tolist() == [14, 0]
    empty = label_table(np.zeros((0, 5), np.int32), labels=[3])  # no pixel: every label asked for absent
    assert empty["label"].tolist() == [3] and empty["voxels"].tolist() == [0] and np.isnan(empty["bbox-0"][0])
    with pytest.raises(IsoflowError, match="connectivity 6 is not valid in 2D"):
        label_table(image, 6)
    with pytest.raises(IsoflowError, match="3D or 2D label image, got a 1D"):
        label_table(image[0])


@pytest.mark.parametrize("pitch", [1e200, 4e307, 1e-200])
def test_a_pixel_size_past_float64_gives_what_a_3d_table_gives_without_numpy_warnings(pitch):
    """A pixel of 1e200 has an area of 1e400 (and a perimeter of four
    pixels of 4e307 is past float64's largest, 1.8e308): the 2D table let
    NumPy's overflow warning out where the 3D one gives inf quietly; both
    now give inf (0 for 1e-200, whose area is 1e-400) and the boxes and
    centroids that still fit."""
    import warnings

    image = np.zeros((4, 4), np.uint8)
    image[1:3, 1:3] = 1
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        flat = label_table(image, pitch=pitch)
        solid = label_table(np.repeat(image[None], 3, axis=0), pitch=pitch)
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    assert flat["area"][0] == solid["volume"][0] == (np.inf if pitch > 1 else 0.0)
    assert flat["perimeter"][0] == (8 * pitch if 8 * pitch < np.finfo(float).max else np.inf)
    for d in range(2):  # a 3D table's axes 1 and 2 are the image's
        assert flat[f"bbox-{d}"][0] == solid[f"bbox-{d + 1}"][0] == pitch
        assert flat[f"bbox-{d + 2}"][0] == solid[f"bbox-{d + 4}"][0] == 3 * pitch
        assert flat[f"centroid-{d}"][0] == solid[f"centroid-{d + 1}"][0] == 2 * pitch


@pytest.mark.parametrize("method", ["numpy", "compiled"])
def test_a_box_corner_past_float64_is_inf_without_numpy_warnings(method):
    """An origin near float64's largest (1.8e308) puts the far corner of a
    box past it: inf, as ``analyze`` gives it and as Python's float sum
    gives it, in a 2D and a 3D table, not NumPy's overflow warning."""
    import warnings

    if method == "compiled":
        pytest.importorskip("numba")
    image = np.zeros((4, 4), np.uint8)
    image[1:3, 1:3] = 1
    far, pitch = 1.7e308, 1e307
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        flat = label_table(image, pitch=pitch, origin=(far, 0.0), method=method)
        solid = label_table(image[None], pitch=pitch, origin=(0.0, far, 0.0), method=method)
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], [str(w.message) for w in caught]
    assert flat["bbox-0"][0] == solid["bbox-1"][0] == far + pitch == np.inf
    assert flat["bbox-2"][0] == solid["bbox-4"][0] == far + 3 * pitch == np.inf
    assert flat["bbox-3"][0] == solid["bbox-5"][0] == 3 * pitch and flat["centroid-1"][0] == 2 * pitch


def run(*args, cwd, flags=()):
    return subprocess.run([sys.executable, *flags, "-m", "isoflow", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd)


def test_info_labels_on_a_2d_image_from_the_shell(tmp_path):
    image = nested(np.random.default_rng(5))[:, :-3].astype(np.int32)
    np.save(tmp_path / "cells.npy", image)
    proc = run("info", "cells.npy", "--labels", "--json", "--connectivity", "8", cwd=tmp_path, flags=("-X", "importtime"))
    assert proc.returncode == 0, proc.stderr
    # NumPy and cc3d, and a table this small written in Python: numba's half-second start is not paid
    imported = {line.split("|")[-1].strip() for line in proc.stderr.splitlines() if line.startswith("import time:")}
    assert "cc3d" in imported and "numba" not in imported
    out = json.loads(proc.stdout)
    assert out["shape"] == [23, 26] and out["connectivity"] == 8 and len(out["pitch"]) == 2
    table = label_table(image, 8)
    assert [row["label"] for row in out["labels"]] == table["label"].tolist()
    for row, r in zip(out["labels"], range(len(table["label"]))):
        assert [row[k] for k in ("voxels", "euler_characteristic", "b0", "b1", "n-0", "n-1", "n-2",
                                 "non_well_composed", "energy")] == table_row(table, r)
        assert row["perimeter"] == edges_of(image == row["label"])
    text = run("info", "cells.npy", "--labels", cwd=tmp_path)
    assert text.returncode == 0 and "pixel 1x1, 4-connectivity" in text.stdout
    assert "perimeter" in text.stdout and "with holes" in text.stdout and "b2" not in text.stdout
    for args, message in ((("info", "cells.npy", "--labels", "--connectivity", "26"),
                           "cells.npy: connectivity 26 is not valid in 2D (use 4 or 8)"),
                          (("surface", "cells.npy", "--labels", "-o", "out.glb"),
                           "cells.npy: surface needs a 3D label image, this one is 2D")):
        proc = run(*args, cwd=tmp_path)
        assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        assert message in proc.stderr
    assert not (tmp_path / "out.glb").exists()


def test_a_2d_zarr_store_is_read_whole(tmp_path):
    """Block by block is for 3D stores; a 2D one is read as a file is."""
    zarr = pytest.importorskip("zarr")
    from isoflow.digital.label_blocks import label_table_blocks
    from isoflow.mesh.formats.omezarr import LabelSlabs

    image = nested(np.random.default_rng(8))[:, :-3].astype(np.uint16)
    store = zarr.open_array(tmp_path / "cells.zarr", mode="w", shape=image.shape, chunks=(5, 7), dtype="u2")
    store[:] = image
    proc = run("info", "cells.zarr", "--labels", "--json", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    rows = json.loads(proc.stdout)["labels"]
    table = label_table(image)
    assert [r["label"] for r in rows] == table["label"].tolist()
    assert [r["b1"] for r in rows] == table["b1"].tolist() and [r["perimeter"] for r in rows] == table["perimeter"].tolist()
    one_line = run("surface", "cells.zarr", "--labels", "-o", "s.glb", cwd=tmp_path)
    assert one_line.returncode == 2 and "surface needs a 3D label image, this one is 2D" in one_line.stderr
    with pytest.raises(IsoflowError, match="this array is 2D; a 2D table reads the image whole"):
        label_table_blocks(LabelSlabs(str(tmp_path / "cells.zarr")), 6)


def test_a_4d_store_is_refused_as_a_4d_file_is(tmp_path):
    """A label table is 2D or 3D, whether the image is read whole or by
    blocks: a 4D store is not told it needs 3D (a 2D one is read)."""
    zarr = pytest.importorskip("zarr")
    image = np.zeros((3, 4, 5, 2), np.uint8)
    image[1] = 2
    np.save(tmp_path / "seg4.npy", image)
    zarr.open_array(tmp_path / "seg4.zarr", mode="w", shape=image.shape, chunks=(2, 3, 2, 1), dtype="u1")[:] = image
    for name in ("seg4.npy", "seg4.zarr"):
        proc = run("info", name, "--labels", cwd=tmp_path)
        assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        assert f"{name}: a label image is read in 3D or 2D, this array is 4D with shape (3, 4, 5, 2)" in proc.stderr


def test_a_4d_label_image_is_told_how_to_take_one_time_point(tmp_path):
    """A time series of label images (a cell-tracking segmentation) was
    refused without a way on: the refusal now ends with the command that
    saves time point 0 as 3D, which, run as printed, gives that time
    point's table (a .npy, a plain zarr array and an OME-Zarr image with a
    t axis, stored t z y x)."""
    zarr = pytest.importorskip("zarr")
    image = np.zeros((5, 4, 3, 2), np.uint16)  # x, y, z, t: a cell that moves and a second one that appears
    image[0:2, 0:2, 0:2, 0] = 7
    image[2:4, 1:3, 1:3, 1] = 7
    image[4, 3, 2, 1] = 9
    np.save(tmp_path / "seg4.npy", image)
    zarr.open_array(tmp_path / "seg4.zarr", mode="w", shape=image.shape, chunks=(2, 3, 2, 1), dtype="u2")[:] = image
    g = zarr.open_group(tmp_path / "seg4.ome.zarr", mode="w", zarr_format=2)
    g.create_array("0", data=image.transpose(3, 2, 1, 0), chunks=(1, 2, 2, 2))
    g.attrs["multiscales"] = [{"version": "0.4", "axes": [{"name": "t", "type": "time"}]
                               + [{"name": a, "type": "space"} for a in "zyx"],
                               "datasets": [{"path": "0", "coordinateTransformations": [
                                   {"type": "scale", "scale": [1.0, 2.0, 0.5, 0.5]}]}]}]
    for name in ("seg4.npy", "seg4.zarr", "seg4.ome.zarr"):
        proc = run("info", name, "--labels", cwd=tmp_path)
        assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1, proc.stderr
        # the OME-Zarr image names its 4th axis 't': a time series; the others say no name
        what = (f"a time series of {image.shape[3]} time points along its 4th axis 't'" if name.endswith(".ome.zarr")
                else f"a 4th axis of {image.shape[3]} entries, time points or channels")
        assert f"this array is 4D with shape (5, 4, 3, 2) ({what}, read as x, y, z, t)" in proc.stderr, proc.stderr
        (tmp_path / "t0.npz").unlink(missing_ok=True)
        command = proc.stderr.split("give that: ", 1)[1].strip()
        subprocess.run(command, shell=True, cwd=tmp_path, check=True)
        frame = read_labels(tmp_path / "t0.npz")
        assert np.array_equal(frame.array, image[..., 0])
        assert frame.spacing.tolist() == ([0.5, 0.5, 2.0] if name == "seg4.ome.zarr" else [1.0, 1.0, 1.0])
        table = run("info", "t0.npz", "--labels", "--json", cwd=tmp_path)
        rows = json.loads(table.stdout)["labels"]
        assert [(r["label"], r["voxels"]) for r in rows] == [(7, 8)]


def test_a_2d_table_beyond_the_budget_is_refused_before_the_work(tmp_path, monkeypatch):
    """Up front for the pixels, then for the labels once their number is
    known: a map of few cells is not refused for what a label per pixel
    needs."""
    from isoflow.scale import memory

    cells = np.repeat(np.arange(1, 5, dtype=np.uint16), 256)[:, None] * np.ones((1, 1024), np.uint16)  # 1M pixels
    noise = np.random.default_rng(0).permutation(cells.size).reshape(cells.shape).astype(np.uint32)
    monkeypatch.setattr(memory, "default_budget", lambda: 20 * cells.size)  # below the pixels' share
    with pytest.raises(IsoflowError, match="label table of a 1024x1024 label image needs about"):
        label_table(cells)
    monkeypatch.setattr(memory, "default_budget", lambda: 50 * cells.size)
    assert label_table(cells)["voxels"].tolist() == [256 * 1024] * 4
    with pytest.raises(IsoflowError, match="1024x1024 label image of 1,048,576 values needs about"):
        label_table(noise)
