"""Bad arguments to the Python API: one IsoflowError naming the parameter
and its value, never NumPy's own error nor a file written as given."""

import inspect
import os
import re
import shutil
import warnings
from decimal import Decimal
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import isoflow
from isoflow.errors import IsoflowError


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"pitch": -1}, ("'pitch'", "-1")),
    ({"pitch": (1.0, 2.0)}, ("'pitch'", "3 numbers")),
    ({"origin": (1, 2)}, ("'origin'", "[1, 2]")),
    ({"origin": "abc"}, ("'origin'", "'abc'")),
])
def test_write_labels_checks_its_pitch_and_origin(tmp_path, kwargs, words):
    labels = np.zeros((3, 3, 3), np.uint8)
    labels[1, 1, 1] = 2
    path = tmp_path / "labels.nii.gz"
    with pytest.raises(IsoflowError) as info:
        isoflow.write_labels(labels, path, **kwargs)
    for w in words:
        assert w in str(info.value)
    assert not path.exists()


def test_write_labels_keeps_a_good_placement(tmp_path):
    labels = np.zeros((3, 3, 3), np.uint8)
    labels[1, 1, 1] = 2
    path = isoflow.write_labels(labels, tmp_path / "labels.nii.gz", pitch=(1, 2, 3), origin=[4, 5, 6])
    back = isoflow.read_volume(path, label=2)
    assert back.spacing.tolist() == [1.0, 2.0, 3.0] and back.origin.tolist() == [4.0, 5.0, 6.0]


@pytest.mark.parametrize("dtype", [np.uint32, np.uint64])
def test_write_labels_keeps_wide_labels_that_a_tiff_holds(tmp_path, dtype):
    """ImageJ TIFF holds 8 or 16 bits: labels up to 65,535 in a wider array
    are written, not refused by tifffile with a traceback."""
    tifffile = pytest.importorskip("tifffile")
    labels = np.zeros((4, 3, 2), dtype)
    labels[0, 0, 0], labels[3, 2, 1] = 7, 65535
    path = isoflow.write_labels(labels, tmp_path / "labels.tif", pitch=0.5)
    stored = tifffile.imread(path)
    assert stored.dtype == np.uint16 and stored.shape == (2, 3, 4)  # z, y, x
    assert stored[0, 0, 0] == 7 and stored[1, 2, 3] == 65535 and np.count_nonzero(stored) == 2


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"origin": "abc"}, ("'origin'", "'abc'")),
    ({"pitch": "x"}, ("'pitch'", "'x'")),
])
def test_label_table_names_a_pitch_or_origin_that_is_no_number(kwargs, words):
    with pytest.raises(IsoflowError) as info:
        isoflow.label_table(np.ones((2, 2, 2), np.uint8), **kwargs)
    for w in words:
        assert w in str(info.value)


@pytest.mark.parametrize("function", [
    isoflow.euler_characteristic, isoflow.betti_numbers, isoflow.configuration_histogram,
    isoflow.closed_surfaces, isoflow.boundary_mesh, isoflow.label_table,
])
def test_a_digital_object_where_an_array_is_taken_is_named(function):
    # NumPy makes the object a 0D object array: it was refused as "0D" or
    # "of type object" (boundary_mesh: a bare ValueError)
    obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5)
    with pytest.raises(IsoflowError, match=r"a DigitalObject, not an array; pass its \.volume"):
        function(obj)


def test_a_mapping_given_for_an_array_is_named_with_its_article():
    # "volume: a OrderedDict, not an array": the type's name behind the article it is said with
    import collections

    with pytest.raises(IsoflowError, match=r"^analyze: obj: an OrderedDict, not an array$"):
        isoflow.analyze(collections.OrderedDict(volume=np.ones((2, 2, 2), bool)))
    with pytest.raises(IsoflowError, match=r"^analyze: obj: a dict, not an array$"):
        isoflow.analyze({"volume": np.ones((2, 2, 2), bool)})

@pytest.mark.parametrize("call,where", [
    (lambda image, p: isoflow.analyze(image), "analyze: obj"),
    (lambda image, p: isoflow.boundary_mesh(image), "boundary_mesh: volume"),
    (lambda image, p: isoflow.run_flow(image), "run_flow: obj"),
    (lambda image, p: isoflow.DigitalObject(image), "DigitalObject volume"),
    (lambda image, p: isoflow.write_surface(image, p / "s.ply"), "write_surface: obj"),
])
def test_a_label_image_where_a_binary_volume_is_taken_is_named(tmp_path, call, where):
    # NumPy made the LabelImage a 0D object array: refused as "array of type object"
    image = isoflow.read_labels(isoflow.write_labels(np.array([[[1, 2]]], np.uint8), tmp_path / "l.npz", pitch=0.5))
    with pytest.raises(IsoflowError) as e:
        call(image, tmp_path)
    assert str(e.value) == (f"{where}: a LabelImage, not a binary volume; pass one label's mask, "
                            "DigitalObject(image.array == N, pitch=image.spacing, origin=image.origin) "
                            "(label_table reports every label)")
    # what the message says to do runs, and places the label as the file does
    obj = isoflow.DigitalObject(image.array == 2, pitch=image.spacing, origin=image.origin)
    assert obj.voxels == 1 and obj.world(np.zeros((1, 3))).tolist() == [[0.0, 0.0, 0.0]]
    assert isoflow.label_table(image)["voxels"].tolist() == [1, 1]


@pytest.mark.parametrize("function", [
    isoflow.analyze, isoflow.run_flow, isoflow.closed_surfaces, isoflow.boundary_mesh, isoflow.label_table,
])
def test_a_path_where_an_array_is_taken_is_named(tmp_path, function):
    # boundary_mesh and label_table said "got a 0D array" of a file name
    np.save(tmp_path / "v.npy", np.ones((2, 2, 2), bool))
    for path in (str(tmp_path / "v.npy"), tmp_path / "v.npy"):
        reader = "read_labels" if function is isoflow.label_table else "read_object"  # a label image's reader
        with pytest.raises(IsoflowError, match=rf"^{function.__name__}: (obj: |volume: |image: )\S*v\.npy is a path, not an "
                                               rf"array; read it with isoflow\.{reader}"):
            function(path)


def test_boundary_mesh_of_a_2d_array_is_an_isoflow_error():
    with pytest.raises(IsoflowError, match="boundary_mesh needs a 3D volume, got a 2D array"):
        isoflow.boundary_mesh(np.ones((2, 2), bool))


@pytest.mark.parametrize(("volume", "chi"), [(np.ones((3, 3), bool), 5), (np.ones((3, 3, 3), bool), 5)])
def test_betti_numbers_refuses_a_chi_that_is_not_the_volumes(volume, chi):
    # 2D: an assert (skipped under -O); 3D: b1 = 1 + 0 - 5 = -4 returned
    with pytest.raises(IsoflowError, match="chi=5 is not this volume's Euler characteristic"):
        isoflow.betti_numbers(volume, chi=chi)


def test_betti_numbers_takes_the_right_chi():
    ring = np.ones((3, 3, 1), bool)
    ring[1, 1, 0] = False
    assert isoflow.betti_numbers(ring, 6, chi=0) == [1, 1, 0]
    assert isoflow.betti_numbers(ring[:, :, 0], 4, chi=0) == [1, 1]


RAGGED = [[[1, 0], [1]], [[1, 1], [0, 1]]]  # a 2x2x2 volume with one voxel left out of a row


@pytest.mark.parametrize(("call", "where"), [
    (lambda: isoflow.euler_characteristic(RAGGED), "euler_characteristic: volume"),
    (lambda: isoflow.betti_numbers(RAGGED), "betti_numbers: volume"),
    (lambda: isoflow.analyze(RAGGED), "analyze: obj"),
    (lambda: isoflow.closed_surfaces(RAGGED), "closed_surfaces: volume"),
    (lambda: isoflow.boundary_mesh(RAGGED), "boundary_mesh: volume"),
    (lambda: isoflow.configuration_histogram(RAGGED), "configuration_histogram: volume"),
    (lambda: isoflow.flow_step(RAGGED), "flow_step: obj"),
    (lambda: isoflow.run_flow(RAGGED), "run_flow: obj"),
    (lambda: isoflow.to_manifold(RAGGED), "to_manifold: obj"),
    (lambda: isoflow.label_table(RAGGED), "label_table: image"),
    (lambda: isoflow.class_histogram([list(range(255)), [1]]), "config_hist"),
    (lambda: isoflow.planar_index([[1, 0], [1]]), "points"),
    (lambda: isoflow.DigitalObject.from_points([[0, 0, 0], [1, 0]]), "lattice point coordinates"),
    (lambda: isoflow.voxelize_mesh(np.eye(3), [[0, 1, 2], [0, 1]], resolution=4), "voxelize_mesh: faces"),
])
def test_nested_lists_of_uneven_lengths_are_refused_naming_the_argument(call, where):
    # NumPy's own ValueError ("setting an array element with a sequence") came through, naming neither
    with pytest.raises(IsoflowError, match=f"^{re.escape(where)}: nested sequences of uneven lengths are no array"):
        call()


def test_write_labels_of_nested_lists_of_uneven_lengths_names_the_argument(tmp_path):
    with pytest.raises(IsoflowError, match=r"^write_labels: labels: nested sequences of uneven lengths are no array"):
        isoflow.write_labels(RAGGED, tmp_path / "l.npz")
    assert not (tmp_path / "l.npz").exists()


def _two_cubes():
    """Two 3x3x3 cubes, one with a tunnel along z: b = [2, 1, 0], chi = 1."""
    v = np.zeros((9, 5, 5), bool)
    v[1:4, 1:4, 1:4] = v[5:8, 1:4, 1:4] = True
    v[6, 2, 1:4] = False
    return v


def _masked(array, where):
    """``array`` as a masked array whose elements ``where`` are masked."""
    mask = np.zeros(np.shape(array), bool)
    mask[where] = True
    return np.ma.array(array, mask=mask)


def _labels():
    """Label 1: the two cubes; label 2: the last layer, which they leave empty."""
    labels = np.where(_two_cubes(), 1, 0).astype(np.int32)
    labels[8] = 2
    return labels


MASKED = _masked(_two_cubes(), (slice(2, 4), 2, 2))  # two masked voxels of the first cube
MASKED_LABELS = _masked(_labels(), 8)  # label 2 wholly masked: 25 elements


def _masked_mesh(part):
    box = _box()
    v, f = np.asarray(box.vertices), np.asarray(box.faces)
    return (_masked(v, (0, 0)), f) if part == "vertices" else (v, _masked(f, (1, slice(None))))


def _refused_as_masked(call, where, count):
    # numpy.asarray reads the values stored under the mask: a masked voxel counted as in, a
    # wholly masked label given a row
    elements = "element" if count == 1 else "elements"
    with pytest.raises(IsoflowError, match=rf"^{re.escape(where)}: a masked array with {count} masked {elements}; "
                                           r"pass a\.filled\(0\) .* or a\.data "):
        call()


@pytest.mark.parametrize(("function", "where"), [
    (isoflow.analyze, "analyze: obj"),
    *[(f, f"{f.__name__}: volume") for f in (isoflow.euler_characteristic, isoflow.betti_numbers, isoflow.configurations,
                                             isoflow.configuration_histogram, isoflow.closed_surfaces,
                                             isoflow.boundary_mesh)],
    (isoflow.DigitalObject, "DigitalObject volume"),
    *[(f, f"{f.__name__}: obj") for f in (isoflow.flow_step, isoflow.run_flow, isoflow.to_manifold)],
])
def test_a_masked_volume_with_masked_voxels_is_refused_naming_the_count(function, where):
    _refused_as_masked(lambda: function(MASKED), where, 2)


@pytest.mark.parametrize(("call", "where", "count"), [
    (lambda: isoflow.label_table(MASKED_LABELS), "label_table: image", 25),
    (lambda: isoflow.label_table(isoflow.LabelImage(MASKED_LABELS, np.ones(3), np.zeros(3))), "label_table: image", 25),
    (lambda: isoflow.planar_index(MASKED[:, :, 2]), "points", 2),
    (lambda: isoflow.class_histogram(_masked(np.ones(256, np.int64), 3)), "config_hist", 1),
    (lambda: isoflow.voxelize_mesh(*_masked_mesh("vertices"), resolution=4), "voxelize_mesh: vertices", 1),
    (lambda: isoflow.voxelize_mesh(*_masked_mesh("faces"), resolution=4), "voxelize_mesh: faces", 3),
    (lambda: isoflow.voxelize_meshes([_masked_mesh("vertices")], resolution=4), "mesh 1: vertices", 1),
])
def test_a_masked_array_with_masked_elements_is_refused_naming_the_count(call, where, count):
    _refused_as_masked(call, where, count)


def test_write_labels_of_a_masked_array_with_masked_elements_names_the_argument(tmp_path):
    with pytest.raises(IsoflowError, match=r"^write_labels: labels: a masked array with 25 masked elements"):
        isoflow.write_labels(MASKED_LABELS, tmp_path / "l.npz")
    assert not (tmp_path / "l.npz").exists()


@pytest.mark.parametrize("mask", [np.ma.nomask, False], ids=["nomask", "all-False"])
def test_a_masked_array_with_no_masked_element_is_read_as_its_data(mask, tmp_path):
    from scipy import ndimage
    from skimage.measure import euler_number

    plain = _two_cubes()
    unmasked = np.ma.array(plain, mask=mask)
    report = isoflow.analyze(unmasked, 6)
    assert report == isoflow.analyze(plain, 6)
    # counted independently of isoflow: components, then chi of 6-connected voxels
    assert report.betti[0] == ndimage.label(plain)[1] == 2
    assert report.euler_characteristic == euler_number(plain, connectivity=1) == 1
    assert report.betti == [2, 1, 0]
    assert isoflow.DigitalObject(unmasked) == isoflow.DigitalObject(plain)
    assert isoflow.betti_numbers(unmasked) == [2, 1, 0]
    assert isoflow.boundary_mesh(unmasked) == isoflow.boundary_mesh(plain)
    assert isoflow.run_flow(unmasked) == isoflow.run_flow(plain)
    labels = _labels()
    table, expected = isoflow.label_table(np.ma.array(labels, mask=mask)), isoflow.label_table(labels)
    assert table.keys() == expected.keys() and table["label"].tolist() == [1, 2]
    for key in table:
        np.testing.assert_array_equal(table[key], expected[key])
    written = isoflow.write_labels(np.ma.array(labels, mask=mask), tmp_path / "l.npy")
    np.testing.assert_array_equal(np.load(written), labels)
    # the mask alone decides: one masked element and the same call is refused
    with pytest.raises(IsoflowError, match="a masked array with 1 masked element;"):
        isoflow.analyze(_masked(plain, (2, 2, 2)), 6)


@pytest.mark.parametrize(("call", "where"), [
    (lambda x: isoflow.label_table(x), "label_table: image"),
    (lambda x: isoflow.analyze(x != 0), "analyze: obj"),
    (lambda x: isoflow.DigitalObject(x != 0), "DigitalObject volume"),
])
@pytest.mark.parametrize("scheduler", ["threads", "another"])
def test_a_dask_array_of_masked_blocks_with_masked_elements_is_refused(call, where, scheduler):
    """A dask array of masked blocks (dask.array.ma) was read with the
    values stored under its mask: label 2, wholly masked, got a row. Under
    a scheduler whose tasks cannot write into one array (processes,
    distributed: here a wrapper of the synchronous one, which isoflow
    cannot tell from them) it still was."""
    dask = pytest.importorskip("dask")
    da = pytest.importorskip("dask.array")
    labels = _labels()
    lazy = da.ma.masked_equal(da.from_array(labels, chunks=5), 2)  # label 2 masked, 25 elements in 4 blocks
    block = r", the block at \(\d+, \d+, \d+\)" if scheduler == "threads" else ""
    chosen = "threads" if scheduler == "threads" else (lambda graph, keys, **kw: dask.get(graph, keys, **kw))
    with dask.config.set(scheduler=chosen), pytest.raises(
            IsoflowError, match=rf"^{re.escape(where)}: a dask array of masked blocks{block} with \d+ masked "
                                r"elements?; pass dask.array.ma.filled"):
        call(lazy)
    # none masked: read as its data, as NumPy's own masked array is
    unmasked = da.ma.masked_equal(da.from_array(labels, chunks=5), 7)
    assert isoflow.label_table(unmasked)["label"].tolist() == [1, 2]
    assert isoflow.analyze(unmasked != 0) == isoflow.analyze(labels != 0)


def _box():
    import trimesh

    return trimesh.creation.box()


@pytest.mark.parametrize(("call", "name", "how"), [
    (lambda p: isoflow.run_flow(np.ones((3, 3, 3), bool), progress=p), "progress", "progress(step, state)"),
    (lambda p: isoflow.run_flow(np.ones((3, 3, 3), bool), guard=True, progress=p), "progress",
     "progress(step, state)"),
    (lambda p: isoflow.voxelize_mesh(_box(), resolution=4, progress=p), "progress", "progress(done, total)"),
    (lambda p: isoflow.voxelize_meshes([_box()], resolution=4, progress=p), "progress", "progress(done, total)"),
    (lambda p: isoflow.verify_genus(_box(), resolutions=(4,), progress=p), "progress", "progress(done, total)"),
    (lambda p: isoflow.verify_genus(_box(), resolutions=(4,), on_resolution=p), "on_resolution",
     "on_resolution(entry)"),
])
def test_a_callback_that_cannot_be_called_is_refused_naming_it(call, name, how):
    # it failed at its first call, after a flow step or a slab, as "'int' object is not callable"
    with pytest.raises(TypeError, match=re.escape(f"{name} must be a callable, {how}, or None; got 5")):
        call(5)


@pytest.mark.parametrize("call", [
    lambda p, tmp: isoflow.analyze_chunked(_zarr_cube(tmp), progress=p),
    lambda p, tmp: isoflow.voxelize_to_zarr(_box(), tmp / "v.zarr", resolution=4, progress=p),
])
def test_a_progress_of_the_block_by_block_work_that_cannot_be_called_is_refused(call, tmp_path):
    pytest.importorskip("zarr")
    with pytest.raises(TypeError, match=re.escape("progress must be a callable, progress(done, total), or None; "
                                                  "got 'log'")):
        call("log", tmp_path)
    assert not (tmp_path / "v.zarr").exists()


def _zarr_cube(folder):
    import zarr

    store = zarr.open(str(folder / "cube.zarr"), mode="w", shape=(4, 4, 4), chunks=(2, 2, 2), dtype=np.uint8)
    store[1:3, 1:3, 1:3] = 1
    return store


@pytest.mark.parametrize("chi", [0.5, "1", True, np.float64(0.5)])
def test_betti_numbers_refuses_a_chi_that_is_no_integer(chi):
    # a cube with a tunnel (chi 0): chi=0.5 gave b1 = 0.5, 1.0 gave [1, 0.0, 0], "1" NumPy's TypeError
    # (a whole float is that integer: tests/test_integer_arguments.py)
    tunnel = np.ones((3, 3, 3), bool)
    tunnel[1, 1, :] = False
    shown = repr(chi.item() if isinstance(chi, np.generic) else chi)  # a NumPy scalar as the number it holds
    with pytest.raises(IsoflowError, match=re.escape(f"chi must be an integer, got {shown}")):
        isoflow.betti_numbers(tunnel, chi=chi)
    result = isoflow.betti_numbers(tunnel, chi=np.int64(0))
    assert result == [1, 1, 0] and all(type(b) is int for b in result)


@pytest.mark.parametrize(("args", "kwargs", "words"), [
    ((16,), {}, "verify_genus: resolutions must be a sequence of integers, got 16; one resolution is [16]"),
    (([16],), {"time_limit": -1}, "verify_genus: time_limit must be a positive number of seconds, got -1"),
    (([16],), {"time_limit": float("nan")}, "verify_genus: time_limit must be a positive number of seconds, got nan"),
    (([16],), {"max_resolution": 0}, "verify_genus: max_resolution must be an integer >= 1, got 0"),
    (([16],), {"max_resolution": 2.5}, "verify_genus: max_resolution must be an integer >= 1, got 2.5"),
])
def test_verify_genus_checks_its_arguments_as_the_command_line_does(args, kwargs, words):
    # a lone int was list()'s TypeError; the others ran and stopped at once
    trimesh = pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError) as info:
        isoflow.verify_genus(trimesh.creation.box(), *args, **kwargs)
    assert str(info.value) == words


@pytest.mark.parametrize(("call", "words"), [
    (lambda s: isoflow.voxelize_mesh(_box(), resolution=4, strict=s), "voxelize_mesh: strict"),
    (lambda s: isoflow.voxelize_meshes([_box()], resolution=4, strict=s), "voxelize_meshes: strict"),
    (lambda s: isoflow.verify_genus(_box(), resolutions=(4,), strict=s), "verify_genus: strict"),
])
@pytest.mark.parametrize("strict", ["no", 1, None])
def test_a_strict_that_is_no_bool_is_refused_naming_it(call, words, strict):
    # strict="no" turned strict mode on (a non-empty string is true), 1 too
    pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError, match=re.escape(f"{words} must be True or False, got {strict!r}")):
        call(strict)


CUBE = np.pad(np.ones((3, 3, 3), bool), 1)


@pytest.mark.parametrize(("call", "words"), [
    (lambda s: isoflow.analyze(CUBE, surfaces=s), "analyze: surfaces"),
    (lambda s: isoflow.label_table(CUBE.astype(np.uint8), surfaces=s), "label_table: surfaces"),
    (lambda s: isoflow.run_flow(CUBE, 1, guard=s), "run_flow: guard"),
    (lambda s: isoflow.run_flow(CUBE, 1, until_topology_change=s), "run_flow: until_topology_change"),
    (lambda s: isoflow.run_flow(CUBE, 1, keep_states=s), "run_flow: keep_states"),
    (lambda s: isoflow.voxelize_mesh(_box(), resolution=4, details=s), "voxelize_mesh: details"),
    (lambda s: isoflow.voxelize_file(isoflow.data.torus(), resolution=4, details=s), "voxelize_file: details"),
    (lambda s: isoflow.voxelize_meshes([_box()], resolution=4, split=s), "voxelize_meshes: split"),
    (lambda s: isoflow.verify_genus(_box(), resolutions=(4,), step=s), "verify_genus: step"),
])
@pytest.mark.parametrize("switch", ["no", 2, None])
def test_a_switch_that_is_no_bool_is_refused_naming_it(call, words, switch):
    # "no" and 2 switched on, None off: run_flow(guard="no") ran the guard
    # and its FlowResult held guard="no" where a bool is documented
    pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError, match=f"^{re.escape(words)} must be True or False, got {re.escape(repr(switch))}$"):
        call(switch)


def test_a_switch_given_as_a_numpy_bool_is_taken_as_the_bool():
    flow = isoflow.run_flow(CUBE, 1, guard=np.True_)
    assert flow.guard is True and flow.to_dict()["guard"] is True
    assert "surfaces" not in isoflow.analyze(CUBE, surfaces=np.False_)


VOXELIZING_CALLS = [
    ("voxelize_to_zarr", lambda tmp, **k: isoflow.voxelize_to_zarr(_box(), tmp / "v.zarr", resolution=4, **k)),
    ("voxelize_file", lambda tmp, **k: isoflow.voxelize_file(tmp / "box.stl", resolution=4, **k)),
    ("voxelize_meshes", lambda tmp, **k: isoflow.voxelize_meshes([_box()], resolution=4, **k)),
    ("voxelize_mesh", lambda tmp, **k: isoflow.voxelize_mesh(_box(), resolution=4, **k)),
]


@pytest.mark.parametrize(("name", "call"), VOXELIZING_CALLS)
@pytest.mark.parametrize(("argument", "words"), [
    ({"strict": "no"}, "strict must be True or False, got 'no'"),
    # voxelize_meshes and voxelize_to_zarr said "voxelize: fill must be ...", a function not called
    ({"fill": "x"}, "fill must be one of winding, shell, flood, got 'x'"),
])
def test_a_bad_fill_or_strict_names_the_function_called_before_a_file_is_written(name, call, argument, words, tmp_path):
    pytest.importorskip("zarr")
    _box().export(tmp_path / "box.stl")
    with pytest.raises(IsoflowError, match=re.escape(f"{name}: {words}")):
        call(tmp_path, **argument)
    assert not (tmp_path / "v.zarr").exists()


VOXELIZING_ANY_GRID = [
    ("voxelize_to_zarr", lambda tmp, **k: isoflow.voxelize_to_zarr(_box(), tmp / "v.zarr", **k)),
    ("voxelize_file", lambda tmp, **k: isoflow.voxelize_file(tmp / "box.stl", **k)),
    ("voxelize_meshes", lambda tmp, **k: isoflow.voxelize_meshes([_box()], **k)),
    ("voxelize_mesh", lambda tmp, **k: isoflow.voxelize_mesh(_box(), **k)),
]


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"pitch": "0.5"}, "pitch must be a positive number, got '0.5'"),
    ({"pitch": True}, "pitch must be a positive number, got True"),
    ({"resolution": "4"}, "resolution must be an integer from 1 to 2147483647, got '4'"),
])
@pytest.mark.parametrize(("name", "voxelize"), VOXELIZING_ANY_GRID)
def test_a_pitch_or_resolution_that_is_no_number_is_refused_naming_it(name, voxelize, kwargs, words, tmp_path):
    # pitch="0.5" was read as the number it spells (and True as 1)
    pytest.importorskip("zarr")
    _box().export(tmp_path / "box.stl")
    with pytest.raises(IsoflowError) as info:
        voxelize(tmp_path, **kwargs)
    assert str(info.value) == f"{name}: {words}"
    # the unit box at pitch 0.5: 2 x 2 x 2 voxels
    assert voxelize(tmp_path, pitch=0.5).voxels in (8, (8,))


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"pitch": 0}, "pitch must be a positive finite number, got 0"),
    ({"pitch": -1}, "pitch must be a positive finite number, got -1"),
    ({"pitch": float("nan")}, "pitch must be a positive finite number, got nan"),
    ({"pitch": [0.5, 0.5]}, "pitch must be a positive number, got [0.5, 0.5]"),
    ({"pitch": 0.5, "resolution": 4}, "give exactly one of pitch= or resolution="),
    ({"resolution": 0}, "resolution must be an integer from 1 to 2147483647, got 0"),
    ({"pitch": 0.5, "details": "yes"}, "details must be True or False, got 'yes'"),
])
@pytest.mark.parametrize(("name", "voxelize"), VOXELIZING_ANY_GRID)
def test_a_bad_pitch_resolution_or_details_names_the_function_called(name, voxelize, kwargs, words, tmp_path):
    # each began "voxelize:", the command's name, and voxelize_to_zarr took
    # details="yes" for True; voxelize_meshes has no details
    pytest.importorskip("zarr")
    if name == "voxelize_meshes" and "details" in kwargs:
        pytest.skip("voxelize_meshes takes no details")
    _box().export(tmp_path / "box.stl")
    with pytest.raises(IsoflowError) as info:
        voxelize(tmp_path, **kwargs)
    assert str(info.value) == f"{name}: {words}"
    assert not (tmp_path / "v.zarr").exists()


@pytest.mark.parametrize(("name", "voxelize"), VOXELIZING_ANY_GRID)
def test_a_pitch_coarser_than_the_mesh_names_the_function_called(name, voxelize, tmp_path):
    # the unit box at a pitch over 2**40 times its size
    pytest.importorskip("zarr")
    _box().export(tmp_path / "box.stl")
    with pytest.raises(IsoflowError, match=re.escape(f"{name}: pitch=1e+300 is more than 2**40 times the mesh's size")):
        voxelize(tmp_path, pitch=1e300)


@pytest.mark.parametrize(("name", "voxelize"), VOXELIZING_ANY_GRID[1:])  # voxelize_to_zarr takes no write_bytes
def test_a_bad_write_bytes_names_the_function_called(name, voxelize, tmp_path):
    pytest.importorskip("trimesh")
    _box().export(tmp_path / "box.stl")
    words = f"{name}: write_bytes must be a number of bytes per voxel from 0 on, got -1"
    with pytest.raises(IsoflowError, match=re.escape(words)):
        voxelize(tmp_path, pitch=0.5, write_bytes=-1)


@pytest.mark.parametrize("resolution", ["4", 4.5, True])
def test_verify_genus_refuses_a_resolution_that_is_no_integer(resolution):
    # int() took "4" and 4.5 (as 4) in silence
    pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError, match=re.escape(f"resolutions must be integers >= 1, got {resolution!r} in")):
        isoflow.verify_genus(_box(), resolutions=[8, resolution])


@pytest.mark.parametrize("voxelize", [
    lambda v, f: isoflow.voxelize_mesh(v, f, resolution=4),
    lambda v, f: isoflow.voxelize_meshes([(v, f)], resolution=4),
    lambda v, f: isoflow.verify_genus((v, f), resolutions=(4,)),
])
def test_complex_vertices_are_refused_naming_them(voxelize):
    # the imaginary part was dropped with NumPy's ComplexWarning alone
    box = _box()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(IsoflowError, match=r"vertices must be real coordinates, got complex numbers \(complex128\)"):
            voxelize(box.vertices + 1j, box.faces)


@pytest.mark.parametrize("voxelize", [
    lambda v, f: isoflow.voxelize_mesh(v, f, resolution=4),
    lambda v, f: isoflow.voxelize_meshes([(v, f)], resolution=4),
    lambda v, f: isoflow.verify_genus((v, f), resolutions=(4,)),
])
@pytest.mark.parametrize("kind", [object, str])
def test_vertices_of_objects_or_strings_are_refused_as_volumes_are(voxelize, kind):
    # they were cast to float64 and voxelised (strings such as "0.5" too), where
    # analyze refuses an array of the same type in one line
    box = _box()
    vertices = np.array(box.vertices.tolist(), dtype=kind)
    with pytest.raises(IsoflowError, match=r"array of type object is not a binary volume"):
        isoflow.analyze(np.ones((2, 2, 2), dtype=object))
    with pytest.raises(IsoflowError) as e:
        voxelize(vertices, box.faces)
    assert str(e.value).endswith(f"vertices: array of type {vertices.dtype} is not an array of coordinates")
    assert "\n" not in str(e.value)


@pytest.mark.parametrize("block_shape", [(0, 2, 2), (2, 2), (2.5, 2, 2), ("2", 2, 2), (True, 2, 2), (2, b"2", 2)])
def test_analyze_chunked_names_a_block_shape_that_does_not_fit_a_dask_array(block_shape):
    # a dask array was rechunked as given: ZeroDivisionError, dask's
    # ValueError, or 2.5 read as 2 (a zarr array was checked already);
    # "2" and True passed the check as the integers int() makes of them
    da = pytest.importorskip("dask.array")
    array = da.from_array(np.ones((5, 5, 5), bool), chunks=2)
    with pytest.raises(IsoflowError, match=r"block_shape .* does not fit a 3D array"):
        isoflow.analyze_chunked(array, 6, block_shape=block_shape)
    assert isoflow.analyze_chunked(array, 6, block_shape=(3, 3, 3)).betti == [1, 0, 0]


@pytest.mark.parametrize("where", [3, b"v.zarr", ["v.zarr"]])
def test_analyze_chunked_refuses_a_where_that_names_no_input(where, tmp_path):
    """``where`` names the input in messages: ``where=3`` was taken
    without a word, to be printed as the input's name ("3: ...") in any
    later refusal. Anything but a str, a path or None is one line naming
    the argument; a path names the input as its text."""
    da = pytest.importorskip("dask.array")
    array = da.from_array(np.ones((4, 4, 4), bool), chunks=2)
    with pytest.raises(IsoflowError, match=r"^analyze_chunked: where names the input in messages"):
        isoflow.analyze_chunked(array, where=where)
    counted = da.from_array(np.full((4, 4, 4), 7, np.uint8), chunks=2)  # no binary volume: refused naming the input
    with pytest.raises(IsoflowError, match=r"^" + re.escape(str(tmp_path / "v.zarr")) + ": "):
        isoflow.analyze_chunked(counted, where=tmp_path / "v.zarr")
    assert isoflow.analyze_chunked(array, where="v.zarr").voxels == 64


@pytest.mark.parametrize("scheduler", [5, "thread", "x"])
def test_analyze_chunked_names_a_scheduler_dask_does_not_know(scheduler):
    # dask's ValueError ("Unexpected scheduler: 5", "Expected one of [...]") named neither the argument nor isoflow
    da = pytest.importorskip("dask.array")
    with pytest.raises(IsoflowError, match=rf"^scheduler must be a dask scheduler's name \(.*\), a get function, "
                                           rf"a client or executor, or None, got {re.escape(repr(scheduler))}$"):
        isoflow.analyze_chunked(da.from_array(np.ones((4, 4, 4), bool), chunks=2), scheduler=scheduler)


def test_analyze_chunked_runs_on_an_executor():
    # dask takes a concurrent.futures executor: it stopped with "get_async() got multiple values for argument
    # 'num_workers'"; the report is scikit-image's and SciPy's reading of the volume
    from concurrent.futures import ThreadPoolExecutor

    da = pytest.importorskip("dask.array")
    measure = pytest.importorskip("skimage.measure")
    from scipy import ndimage

    volume = np.random.default_rng(3).random((9, 8, 7)) < 0.4
    with ThreadPoolExecutor(2) as pool:
        report = isoflow.analyze_chunked(da.from_array(volume, chunks=4), 6, scheduler=pool)
    assert report.euler_characteristic == measure.euler_number(volume, connectivity=1)
    assert report.betti[0] == ndimage.label(volume)[1] and report == isoflow.analyze(volume, 6)


@pytest.mark.parametrize("connectivity", [26, np.int64(26), np.uint8(26)])
def test_an_integer_connectivity_is_reported_as_an_int(connectivity):
    volume = np.ones((2, 2, 2), bool)
    values = [isoflow.analyze(volume, connectivity).to_dict()["connectivity"],
              isoflow.run_flow(volume, connectivity=connectivity, steps=1).to_dict()["connectivity"],
              isoflow.boundary_mesh(volume, connectivity).connectivity]
    assert all(type(v) is int and v == 26 for v in values), values


@pytest.mark.parametrize("slab", [0, -2, 1.5])
def test_configuration_histogram_names_a_bad_slab(slab):
    # 0 was range()'s "arg 3 must not be zero"; -2 and 1.5 ran or failed as NumPy's
    with pytest.raises(IsoflowError, match=f"slab must be an integer >= 1, got {slab}"):
        isoflow.configuration_histogram(np.ones((3, 3, 3), bool), slab=slab, method="numpy")
    assert isoflow.configuration_histogram(np.ones((3, 3, 3), bool), slab=1, method="numpy")[255] == 8


@pytest.mark.parametrize(("pitch", "shown"), [
    (True, "True"),
    (np.False_, "False"),
    ((1.0, True, 2.0), "[1.0, True, 2.0]"),
    (np.array([True, True, True]), "[True, True, True]"),
])
def test_digital_object_refuses_a_bool_pitch(pitch, shown):
    # pitch=True was read as a voxel size of 1.0 (and False as 0, "must be
    # positive"); in a tuple of floats asarray made True 1.0 before any check
    with pytest.raises(IsoflowError) as info:
        isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=pitch)
    assert str(info.value) == f"DigitalObject: 'pitch' must be a number (one, or one per axis), not True or False, got {shown}"
    assert isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=(1, 2.0, 1)).pitch.tolist() == [1.0, 2.0, 1.0]


@pytest.mark.parametrize(("parity", "shown"), [(2, "2"), (np.int64(-1), "-1"), (3.0, "3.0")])
def test_a_parity_other_than_0_or_1_is_named_as_given(parity, shown):
    # parity=2 was refused as "got 2.0": the number after its float check, not the one written
    with pytest.raises(IsoflowError) as info:
        isoflow.DigitalObject(np.ones((2, 2, 2), bool), parity=parity)
    assert str(info.value) == f"DigitalObject: 'parity' must be 0 (lattice) or 1 (dual lattice), got {shown}"


def test_numbers_held_as_objects_place_an_object_as_the_same_numbers_do():
    # an object array of Python numbers (what a pandas column or a list
    # through np.array(..., dtype=object) gives) is numbers: the object is
    # placed as by the same values in a float array; strings and None are not
    as_objects = {"pitch": np.array([1, 0.5, 2], dtype=object), "origin": np.array([1, 2.5, 3], dtype=object),
                  "offset": np.array([1, 2, 3], dtype=object)}
    got = isoflow.DigitalObject(np.ones((2, 2, 2), bool), **as_objects)
    want = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=[1.0, 0.5, 2.0], origin=[1.0, 2.5, 3.0], offset=(1, 2, 3))
    assert got.spacing.tolist() == want.spacing.tolist() == [1.0, 0.5, 2.0]
    assert got.origin.tolist() == want.origin.tolist() and got.offset == want.offset == (1, 2, 3)
    for bad, shown in ((np.array(["1", "1", "1"], dtype=object), "['1', '1', '1']"),
                       (np.array([1, None, 1], dtype=object), "[1, None, 1]")):
        with pytest.raises(IsoflowError) as info:
            isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=bad)
        assert str(info.value) == f"DigitalObject: 'pitch' must be 3 numbers, one per axis, got {shown}"


@pytest.mark.parametrize("one", [Fraction(1, 2), np.array(0.5, dtype=object), np.array([Fraction(1, 2)], dtype=object)],
                         ids=["Fraction", "0D object array", "one-element object array"])
def test_one_number_held_as_an_object_is_the_voxel_size_of_every_axis(one):
    """One number stands for every axis (``pitch=0.5``), and numbers held as
    Python objects are numbers (``[Fraction(1, 2)] * 3`` was taken); one
    such number alone was refused as "'pitch' must be 3 numbers, one per
    axis, got Fraction(1, 2)"."""
    cube = np.ones((2, 2, 2), bool)
    assert isoflow.DigitalObject(cube, pitch=one).spacing.tolist() == [0.5, 0.5, 0.5]
    assert isoflow.analyze(cube, pitch=one).volume == 8 * 0.5**3
    assert isoflow.label_table(cube, pitch=one)["volume"].tolist() == [8 * 0.5**3]


@pytest.mark.parametrize(("pitch", "shown"), [("0.25", "'0.25'"), (Decimal("0.5"), "Decimal('0.5')"), (None, "None")])
def test_one_pitch_that_is_no_number_is_refused_as_no_number(pitch, shown):
    """A voxel size is one number or one per axis: one value that is no
    number was refused as "must be 3 numbers, one per axis", a count,
    which reads as if one number were not taken."""
    with pytest.raises(IsoflowError) as info:
        isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=pitch)
    assert str(info.value) == f"DigitalObject: 'pitch' must be a number (one, or one per axis), got {shown}"


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"pitch": 0}, "'pitch' must be positive"),
    ({"pitch": (1, 2, 3)}, "'pitch' must be one number (cubic voxels), got [1, 2, 3]"),
    # a count of numbers other than one per axis was "must be 3 numbers", which from_manifold does not take
    ({"pitch": (1, 2)}, "'pitch' must be one number (cubic voxels), got [1, 2]"),
    ({"origin": (1, 2)}, "'origin' must be 3 numbers, one per axis, got [1, 2]"),
])
def test_from_manifold_checks_its_grid_first(kwargs, words):
    # a zero pitch warned of NumPy's division by zero before voxelize
    # refused it; a short origin was NumPy's broadcast error
    m3 = pytest.importorskip("manifold3d")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(IsoflowError) as info:
            isoflow.from_manifold(m3.Manifold.cube([2.0, 3.0, 4.0]), **kwargs)
    assert words in str(info.value)


def test_from_manifold_names_what_is_not_a_manifold():
    with pytest.raises(IsoflowError, match="from_manifold takes a manifold3d.Manifold, got ndarray"):
        isoflow.from_manifold(np.ones((2, 2, 2), bool))


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"pitch": 1e-20}, "pitch=1e-20 and origin=[0.0, 0.0, 0.0] put the manifold's voxels at index 4e+20"),
    ({"pitch": 1e-300}, "pitch=1e-300 and origin=[0.0, 0.0, 0.0] put the manifold's voxels at index 4e+300"),
    ({"origin": (1e300, 0, 0)}, "pitch=1.0 and origin=[1e+300, 0.0, 0.0] put the manifold's voxels at index 1e+300"),
])
def test_from_manifold_names_a_pitch_or_origin_beyond_the_lattice(kwargs, words):
    # int64 wrapped round: a ZeroDivisionError from inside the voxeliser
    m3 = pytest.importorskip("manifold3d")
    with pytest.raises(IsoflowError, match=re.escape(f"from_manifold: {words}, beyond the +-{2**40}")):
        isoflow.from_manifold(m3.Manifold.cube([2.0, 3.0, 4.0]), **kwargs)
    # a pitch that fits: the 2x3x4 box in voxels of 1/2, 8 a unit cube
    assert isoflow.from_manifold(m3.Manifold.cube([2.0, 3.0, 4.0]), pitch=0.5).voxels == 2 * 3 * 4 * 8


@pytest.mark.parametrize("value", [2, np.nan])
def test_closed_surfaces_refuses_a_volume_that_is_not_binary_as_analyze_does(value):
    # the volume was converted to bool first: 2 and NaN read as True
    volume = np.zeros((3, 3, 3))
    volume[1, 1, 1] = value
    with pytest.raises(IsoflowError, match="not a binary volume"):
        isoflow.closed_surfaces(volume)
    with pytest.raises(IsoflowError, match="not a binary volume"):
        isoflow.analyze(volume)


@pytest.mark.parametrize("call", [isoflow.analyze, isoflow.closed_surfaces, isoflow.betti_numbers, isoflow.euler_characteristic])
def test_a_label_image_given_for_a_mask_names_label_table(call):
    # the refusal said only "threshold it first": a label image has a
    # table of its own, as the command line's refusal says (--labels)
    from skimage.measure import regionprops_table

    labels = np.zeros((6, 5, 4), np.int32)
    labels[1:3, 1:4, 1:3], labels[4, 2:4, 1] = 3, 8
    with pytest.raises(IsoflowError, match=r"threshold it first, e\.g\. volume > 0, or give every label its row with "
                                           r"isoflow\.label_table\(volume\)$"):
        call(labels)
    table, props = isoflow.label_table(labels), regionprops_table(labels, properties=("label", "area"))
    assert table["label"].tolist() == props["label"].tolist() == [3, 8]
    assert table["voxels"].tolist() == props["area"].tolist() == [12, 2]
    with pytest.raises(IsoflowError) as probability:  # fractions are no label image: half way through 0 to 2
        call(labels * 0.25)
    assert str(probability.value).endswith("threshold it first, e.g. volume > 1")


def test_a_2d_label_image_given_for_a_mask_names_label_table_of_the_image():
    # it offered isoflow.label_table(volume) beside "e.g. image > 0"
    from skimage.measure import regionprops_table

    labels = np.zeros((6, 5), np.int32)
    labels[1:3, 1:4], labels[4, 2:4] = 3, 8
    with pytest.raises(IsoflowError) as info:
        isoflow.analyze(labels)
    assert str(info.value).endswith("threshold it first, e.g. image > 0, or give every label its row with "
                                    "isoflow.label_table(image)")
    props = regionprops_table(labels, properties=("label", "area"))
    assert isoflow.label_table(labels)["voxels"].tolist() == props["area"].tolist() == [6, 2]


def _voxels_of_the_surface_written(mask, tmp_path):
    import trimesh

    mesh = trimesh.load(isoflow.write_surface(mask, tmp_path / "one.ply", triangulate=True), force="mesh")
    assert mesh.is_watertight
    return round(mesh.volume)


def _state_voxels(flow):
    return flow["steps"][0]["voxels"]


# each function's remedy, run on the label's mask, and what it gives, known
# apart from isoflow: the mask's voxels, a lattice vertex per histogram count
ONE_LABEL_AT_A_TIME = [
    ("DigitalObject({})", lambda m, tmp: isoflow.DigitalObject(m).voxels, lambda m: int(m.sum())),
    ("flow_step({})", lambda m, tmp: isoflow.flow_step(m).voxels <= m.sum(), lambda m: True),
    ("run_flow({})", lambda m, tmp: _state_voxels(isoflow.run_flow(m, 1)), lambda m: int(m.sum())),
    ("configurations({})", lambda m, tmp: isoflow.configurations(m).shape, lambda m: tuple(n + 1 for n in m.shape)),
    ("configuration_histogram({})", lambda m, tmp: int(isoflow.configuration_histogram(m).sum()),
     lambda m: int(np.prod([n + 1 for n in m.shape]))),
    ("boundary_mesh({})", lambda m, tmp: isoflow.boundary_mesh(m).euler_characteristic, lambda m: 2),  # a box: a sphere
    ("to_manifold({})", lambda m, tmp: round(isoflow.to_manifold(m).volume()), lambda m: int(m.sum())),
    ("write_surface({}, path)", lambda m, tmp: _voxels_of_the_surface_written(m, tmp), lambda m: int(m.sum())),
]


@pytest.mark.parametrize("ndim", [3, 2])
@pytest.mark.parametrize(("call", "remedy", "known"), ONE_LABEL_AT_A_TIME)
def test_a_label_image_given_for_a_mask_offers_the_function_called_on_one_label(call, remedy, known, ndim, tmp_path):
    """``run_flow``, ``write_surface`` and the others that take a mask
    offered ``isoflow.label_table(volume)`` for a label image, a table of
    numbers, which flows nothing and writes no surface: each offers itself
    on one label's mask, which it then takes. A function that takes no 2D
    image offers a 2D one nothing of the kind."""
    name = call.split("(")[0]
    if name == "to_manifold":
        pytest.importorskip("manifold3d")
    if name == "write_surface":
        pytest.importorskip("trimesh")
    labels = np.zeros((6, 5, 4), np.int32)
    labels[1:3, 1:4, 1:3], labels[4, 2:4, 1] = 3, 8
    thing = "volume"
    if ndim == 2:
        labels, thing = labels[:, :, 1], "image"
    function = getattr(isoflow, name)
    with pytest.raises(IsoflowError) as info:
        function(labels, tmp_path / "all.ply") if name == "write_surface" else function(labels)
    message = str(info.value)
    assert "label_table" not in message
    takes_2d = name not in ("boundary_mesh", "to_manifold", "write_surface")
    if ndim == 2 and not takes_2d:
        assert "one label" not in message, message
        return
    assert message.endswith(f", or one label at a time, e.g. {call.format(f'{thing} == 3')}"), message
    mask = labels == 3
    assert remedy(mask, tmp_path) == known(mask)


@pytest.mark.parametrize("method", ["numpy", "compiled"])
@pytest.mark.parametrize("value", [2, 255, 0.5, np.nan])
def test_boundary_mesh_refuses_a_volume_that_is_not_binary_as_analyze_does(method, value):
    # every nonzero value was read as True: a label image or a probability
    # map gave a mesh of all its labels without a word
    if method == "compiled":
        pytest.importorskip("numba")
    volume = np.zeros((3, 3, 3))
    volume[1, 1, 1] = value
    with pytest.raises(IsoflowError, match="not a binary volume"):
        isoflow.boundary_mesh(volume, 6, method=method)
    with pytest.raises(IsoflowError, match="is not a binary volume"):
        isoflow.boundary_mesh(np.full((1, 1, 2), "a"), 6, method=method)


@pytest.mark.parametrize("method", ["numpy", "compiled"])
def test_boundary_mesh_reads_a_0_1_volume_of_any_type_as_the_cube_it_is(method):
    # one voxel is a cube: 8 corners, 6 square faces, V - E + F = 2
    if method == "compiled":
        pytest.importorskip("numba")
    bytes_ = np.zeros((3, 3, 3), np.uint8)
    bytes_[1, 1, 1] = 1
    for volume in (bytes_, bytes_.astype(float), (bytes_ * 2).view(bool)):
        mesh = isoflow.boundary_mesh(volume, 6, method=method)
        assert (len(mesh.vertices), len(mesh.faces), mesh.euler_characteristic) == (8, 6, 2)


def test_class_histogram_names_a_histogram_that_is_not_3d():
    # a 2D histogram (16 counts) or any other length was NumPy's IndexError
    hist2d = isoflow.configuration_histogram(np.ones((3, 3), bool))
    for bad, words in ((hist2d, r"got \(16,\)"), (np.zeros(300), r"got \(300,\)"),
                       (np.array(["x"] * 256), "got an array of type <U1")):
        with pytest.raises(IsoflowError, match="class_histogram takes the 256 counts of a 3D configuration histogram, "
                                               + words):
            isoflow.class_histogram(bad)
    # the box of the paper's example: 8 convex corners (class (+,+,+), index 7), as analyze counts them
    box = np.ones((3, 3, 3), bool)
    assert isoflow.class_histogram(isoflow.configuration_histogram(box)).tolist() == isoflow.analyze(box).n


@pytest.mark.parametrize(("entry", "shown"), [(np.nan, "nan"), (-1.0, "-1.0"), (0.5, "0.5"), (-1, "-1")])
def test_class_histogram_refuses_an_entry_that_is_no_count(entry, shown):
    # NaN came back as the most negative int64 in every class, -1 and 0.5 as class counts
    hist = isoflow.configuration_histogram(np.ones((3, 3, 3), bool)).astype(type(entry))
    hist[7] = entry
    with pytest.raises(IsoflowError, match=rf"^config_hist: entry 7 is {shown}, not a count"):
        isoflow.class_histogram(hist)


def test_class_histogram_counts_a_float_histogram_of_whole_numbers_as_its_integers():
    # a histogram summed as floats (a mean over scans times their number) is still counts
    box = np.ones((3, 3, 3), bool)
    hist = isoflow.configuration_histogram(box)
    assert isoflow.class_histogram(hist.astype(float)).tolist() == isoflow.analyze(box).n


@pytest.mark.parametrize("points,ndim", [("0 0 0\n-5 3 2\n", 3), ("0 0\n1 0\n", 2)])
def test_read_object_says_why_a_point_list_gives_no_voxel(tmp_path, points, ndim):
    # the paper's point model keeps a cube only where all 2^n corners are
    # listed: none here, so the object is empty although the file is not,
    # and Python said nothing (the command line gave the reason as a note)
    (tmp_path / "p.txt").write_text(points)
    with pytest.warns(isoflow.IsoflowWarning, match=r"p\.txt: no unit .* points_are='voxels' reads each point") as seen:
        assert isoflow.read_object(tmp_path / "p.txt").voxels == 0
    assert len(seen) == 1 and f"all {2 ** ndim} of its corners" in str(seen[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert isoflow.read_object(tmp_path / "p.txt", points_are="voxels").voxels == len(points.splitlines())


def test_boundary_mesh_of_an_object_says_how_to_place_the_mesh():
    # the refusal said only "pass its .volume", and the mesh of the volume is
    # in array-corner units: the way to the object's place is obj.world
    obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5, origin=(1.0, 2.0, 3.0))
    with pytest.raises(IsoflowError, match=r"obj\.world\(mesh\.vertices\)") as refused:
        isoflow.boundary_mesh(obj)
    assert len(str(refused.value).splitlines()) == 1
    placed = obj.world(isoflow.boundary_mesh(obj.volume).vertices)
    assert placed.min(axis=0).tolist() == [1.0, 2.0, 3.0] and placed.max(axis=0).tolist() == [2.0, 3.0, 4.0]


def test_read_labels_gives_label_table_the_files_units(tmp_path):
    """A segmentation file read in Python keeps its anisotropic voxels: the
    table of ``label_table(read_labels(path))`` is the command line's,
    volumes in the file's units (nibabel's zooms, independently)."""
    nib = pytest.importorskip("nibabel")
    labels = np.zeros((6, 5, 4), np.uint16)
    labels[1:3, 1:4, 1:3], labels[4, 0:5, 0:4] = 3, 9
    affine = np.diag([0.5, 0.25, 2.0, 1.0])
    nib.save(nib.Nifti1Image(labels, affine), tmp_path / "seg.nii.gz")
    zooms = nib.load(tmp_path / "seg.nii.gz").header.get_zooms()
    image = isoflow.read_labels(tmp_path / "seg.nii.gz")
    assert isinstance(image, isoflow.LabelImage) and image.spacing.tolist() == list(zooms)
    table = isoflow.label_table(image)
    assert table["label"].tolist() == [3, 9]
    assert table["volume"].tolist() == [12 * float(np.prod(zooms)), 20 * float(np.prod(zooms))]
    # a pitch given replaces the file's
    assert isoflow.label_table(image, pitch=1.0)["volume"].tolist() == [12.0, 20.0]
    with pytest.raises(IsoflowError, match="seg.nii.gz is a path, not an array; read it with isoflow.read_labels"):
        isoflow.label_table(str(tmp_path / "seg.nii.gz"))

def test_a_trimesh_scene_is_read_as_its_file_is(tmp_path):
    """trimesh.load of a glTF file gives a Scene: voxelize_meshes raised a
    TypeError ('Scene' object is not iterable), the others refused it. Two
    unit cubes three apart, one of them the same geometry moved by its
    node: 2 x 8**3 voxels at 32 across, as from the file."""
    trimesh = pytest.importorskip("trimesh")
    scene = trimesh.Scene()
    cube = trimesh.creation.box((1, 1, 1))
    scene.add_geometry(cube, node_name="a")
    scene.add_geometry(cube, node_name="b", transform=trimesh.transformations.translation_matrix((3, 0, 0)))
    path = tmp_path / "two.glb"
    scene.export(path)
    assert isoflow.voxelize_file(path, resolution=32).voxels == 2 * 8**3
    assert isoflow.voxelize_mesh(scene, resolution=32).voxels == 2 * 8**3
    assert isoflow.voxelize_meshes(scene, resolution=32).voxels == (2 * 8**3,)
    labels = isoflow.voxelize_meshes(scene, resolution=32, split=True)
    assert labels.names == ("mesh 1:a", "mesh 1:b") and labels.voxels == (8**3, 8**3)
    assert isoflow.verify_genus(scene, (16, 32)).verdict == "agree: genus 0"
    with pytest.raises(IsoflowError, match="mesh 1: no node of the scene holds a triangle mesh"):
        isoflow.voxelize_meshes(trimesh.Scene(), resolution=8, split=True)


@pytest.mark.parametrize("name,call", [
    ("s.ply", lambda p, **k: isoflow.write_surface(np.ones((2, 2, 2), bool), p / "s.ply", **k)),
    ("v.npz", lambda p, **k: isoflow.write_volume(np.ones((2, 2, 2), bool), p / "v.npz", **k)),
    ("l.nii.gz", lambda p, **k: isoflow.write_labels(np.ones((2, 2, 2), np.uint8), p / "l.nii.gz", **k)),
    ("m.zarr", lambda p, **k: isoflow.voxelize_to_zarr(_box(), p / "m.zarr", resolution=4, **k)),
])
def test_a_force_that_is_no_bool_is_refused_and_the_file_kept(tmp_path, name, call):
    # force="no" is truthy, and must not replace the existing file
    (tmp_path / name).mkdir() if name.endswith(".zarr") else (tmp_path / name).write_text("kept")
    before = sorted(p.name for p in tmp_path.rglob("*"))
    with pytest.raises(IsoflowError) as e:
        call(tmp_path, force="no")
    assert str(e.value) == f"{tmp_path / name}: force must be True or False, got 'no'"
    assert sorted(p.name for p in tmp_path.rglob("*")) == before
    if not name.endswith(".zarr"):
        assert (tmp_path / name).read_text() == "kept"


@pytest.mark.parametrize("switch", ["ascii", "triangulate"])
def test_write_surface_refuses_a_switch_that_is_no_bool(tmp_path, switch):
    with pytest.raises(IsoflowError, match=rf"s\.ply: {switch} must be True or False, got 'no'$"):
        isoflow.write_surface(np.ones((2, 2, 2), bool), tmp_path / "s.ply", **{switch: "no"})
    assert not (tmp_path / "s.ply").exists()


@pytest.mark.parametrize("method", ["world", "lattice_coordinates"])
def test_points_of_another_dimension_are_refused_naming_array_points(method):
    # NumPy's "operands could not be broadcast together with shapes (2,2) (3,)"
    obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=0.5, origin=(10, 0, 0))
    where = getattr(obj, method)
    with pytest.raises(IsoflowError, match=re.escape("array_points: a 3D object's points have 3 coordinates "
                                                     "(the last axis), got shape (2, 2)")):
        where(np.zeros((2, 2)))
    with pytest.raises(IsoflowError, match="array_points: coordinates must be numbers, got an array of type <U3"):
        where("abc")
    # the corners of the object's box, as trimesh reads them off its surface
    trimesh = pytest.importorskip("trimesh")
    mesh = isoflow.boundary_mesh(obj.volume)
    surface = trimesh.Trimesh(obj.world(mesh.vertices), mesh.triangles(), process=False)
    assert obj.world([[0, 0, 0], [2, 2, 2]]).tolist() == surface.bounds.tolist() == [[10, 0, 0], [11, 1, 1]]


@pytest.mark.parametrize("max_bytes", ["8GB", "1000000", 2.5, 0, -5, True])
@pytest.mark.parametrize("call", [
    lambda b, tmp: isoflow.voxelize_meshes([_box()], resolution=4, max_bytes=b),
    lambda b, tmp: isoflow.voxelize_to_zarr(_box(), tmp / "v.zarr", resolution=4, max_bytes=b),
])
def test_a_max_bytes_that_is_no_byte_count_is_refused_naming_it(call, max_bytes, tmp_path):
    # int() raised its own ValueError for "8GB", and took "1000000", 2.5 and True in silence
    pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError, match=re.escape(f"max_bytes must be a positive whole number of bytes, "
                                                     f"got {max_bytes!r}")):
        call(max_bytes, tmp_path)
    assert not (tmp_path / "v.zarr").exists()


def test_a_max_bytes_given_as_a_whole_float_is_that_many_bytes():
    # 1e6 bytes hold the box at 4 voxels across: its voxels are trimesh's volume over a voxel's
    pytest.importorskip("trimesh")
    box = _box()
    done = isoflow.voxelize_meshes([box], resolution=4, max_bytes=1e6)
    assert done.voxels == (round(box.volume / done.pitch**3),) == (64,)


def test_a_label_image_takes_its_spacing_and_origin_as_lists_or_one_number():
    # a list was kept as given: label_table stopped with "'list' object has no attribute 'tolist'"
    measure = pytest.importorskip("skimage.measure")
    labels = np.zeros((4, 5, 6), np.uint16)
    labels[1:3, 1:4, 2:5] = 7
    for spacing, origin in (([0.5, 1.0, 2.0], [1, 2, 3]), ((0.5, 1.0, 2.0), (1, 2, 3))):
        image = isoflow.LabelImage(labels, spacing, origin)
        assert image.spacing.tolist() == [0.5, 1.0, 2.0] and image.origin.tolist() == [1.0, 2.0, 3.0]
        region = measure.regionprops(labels, spacing=(0.5, 1.0, 2.0))[0]
        assert isoflow.label_table(image)["volume"].tolist() == [region.area]
    assert isoflow.LabelImage(labels, 0.5, [0, 0, 0]).spacing.tolist() == [0.5] * 3


@pytest.mark.parametrize(("spacing", "origin", "words"), [
    ([1, -1, 1], [0, 0, 0], "'spacing' must be positive (one number, or one per axis), got [1, -1, 1]"),
    ([1, 1], [0, 0, 0], "'spacing' must be 3 numbers, one per axis, got [1, 1]"),
    (1, "abc", "'origin' must be 3 numbers, one per axis, got 'abc'"),
])
def test_a_label_image_names_a_bad_spacing_or_origin(spacing, origin, words):
    with pytest.raises(IsoflowError, match=re.escape(f"LabelImage: {words}")):
        isoflow.LabelImage(np.ones((2, 2, 2), np.uint8), spacing, origin)


@pytest.mark.parametrize(("ndim", "origin", "written"), [(3, 0.0, "(0, 0, 0)"), (2, np.float32(1.5), "(1.5, 1.5)")])
def test_one_number_for_an_origin_is_refused_saying_what_to_write(ndim, origin, written):
    """``LabelImage(arr, 1.0, 0.0)``: the spacing takes one number for every
    axis, the origin (a point) one per axis; the refusal says so and what
    to write, which is then taken, as write_labels takes it."""
    labels = np.ones((2,) * ndim, np.uint8)
    with pytest.raises(IsoflowError) as info:
        isoflow.LabelImage(labels, 1.0, origin)
    message = str(info.value)
    assert f"'origin' must be {ndim} numbers, one per axis" in message and f"origin={written}" in message
    point = eval(written)
    assert isoflow.LabelImage(labels, 1.0, point).origin.tolist() == [float(origin)] * ndim
    with pytest.raises(IsoflowError, match=re.escape(f"origin={written}")):
        isoflow.DigitalObject(labels.astype(bool), origin=origin)


@pytest.mark.parametrize("ndim", ["a", 3.5, True])
def test_placement_names_an_ndim_that_is_no_integer(ndim):
    # (1,) * ndim: Python's "can't multiply sequence by non-int of type 'str'"
    with pytest.raises(IsoflowError, match=re.escape(f"placement: ndim must be 2, 3 or 4, got {ndim!r}")):
        isoflow.DigitalObject.placement(ndim)
    assert isoflow.DigitalObject.placement(np.int64(3), pitch=0.5).spacing.tolist() == [0.5] * 3


@pytest.mark.parametrize("label", [2.0**63, np.float64(2.0**63), 2**63])
def test_a_whole_float_label_selects_exactly_that_label_of_a_uint64_image(tmp_path, label):
    # compared as a float, 2.0**63 matched 2**63 + 1 too (both round to it): two voxels for one
    labels = np.zeros((3, 3, 3), np.uint64)
    labels[0, 0, 0], labels[1, 1, 1], labels[2, 2, 2] = 2**63, 2**63 + 1, 2**64 - 1
    np.save(tmp_path / "big.npy", labels)
    obj = isoflow.read_volume(tmp_path / "big.npy", label=label)
    assert obj.voxels == np.count_nonzero(labels == np.uint64(2**63)) == 1
    assert np.argwhere(obj.volume).tolist() == [[0, 0, 0]]


@pytest.mark.parametrize("call", [
    lambda t: isoflow.analyze(CUBE, threads=t),
    lambda t: isoflow.label_table(CUBE.astype(np.uint8), threads=t),
])
def test_a_thread_count_given_as_text_is_refused_as_the_message_says(call):
    # "2" was taken as 2 while 2.0 was refused as no positive integer
    with pytest.raises(IsoflowError, match=re.escape("threads must be a positive integer, got '2'")):
        call("2")
    call(np.int64(2))


@pytest.mark.parametrize("given", [np.array(["numpy", "auto"]), np.zeros(0), np.zeros((3, 3))])
@pytest.mark.parametrize(("call", "words"), [
    (lambda v: isoflow.analyze(CUBE, method=v), "method must be one of auto, numpy, compiled"),
    (lambda v: isoflow.label_table(CUBE.astype(np.uint8), method=v), "method must be one of auto, numpy, compiled"),
    (lambda v: isoflow.label_table(CUBE[2].astype(np.uint8), method=v), "method must be one of auto, numpy, compiled"),
    (lambda v: isoflow.configuration_histogram(CUBE, method=v), "method must be one of auto, numpy, compiled"),
    (lambda v: isoflow.run_flow(CUBE, 1, method=v), "method must be one of auto, numpy, compiled"),
    (lambda v: isoflow.voxelize_mesh(_box(), resolution=4, fill=v), "fill must be one of winding, shell, flood"),
    (lambda v: isoflow.voxelize_meshes([_box()], resolution=4, overlap=v),
     "voxelize_meshes: overlap must be one of later, error"),
    (lambda v: isoflow.verify_genus(_box(), [8], fill=v), "verify_genus: fill must be one of winding, shell, flood"),
    (lambda v: isoflow.read_object(isoflow.data.example19(), points_are=v), "points_are must be 'corners' or 'voxels'"),
])
def test_an_array_where_a_word_is_taken_is_refused_naming_the_argument(call, words, given):
    # ``given in ("auto", ...)`` compared the array element by element: NumPy's ValueError on the
    # truth of an array, naming no argument
    pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError) as e:
        call(given)
    assert str(e.value).endswith(f"{words}, got ndarray of shape {given.shape}"), str(e.value)


def test_a_word_given_as_a_0d_array_is_kept_as_the_plain_string():
    # the result kept the array where a string was taken; its fields are the plain words
    pytest.importorskip("trimesh")
    r = isoflow.voxelize_meshes([_box()], resolution=4, fill=np.array("shell"), overlap=np.array("error"))
    assert (type(r.fill), type(r.overlap)) == (str, str) and (r.fill, r.overlap) == ("shell", "error")


@pytest.mark.parametrize("read", [isoflow.read_labels, lambda path, time: isoflow.read_volume(path, 1, time=time)])
def test_a_time_point_given_as_a_0d_array_is_read(tmp_path, read):
    # a 0D integer array was refused as "time=1 is no time point of this time series of 2 (0 to 1)"
    series = np.zeros((3, 3, 3, 2), np.uint8)
    series[1, 1, 1, 1] = 1
    np.save(tmp_path / "t.npy", series)
    got = read(tmp_path / "t.npy", time=np.array(1))
    assert np.array_equal(np.asarray(got.array if hasattr(got, "array") else got.volume), series[..., 1])


@pytest.mark.parametrize("threads", [float("inf"), np.float64("-inf")])
@pytest.mark.parametrize("call", [
    lambda t: isoflow.analyze(CUBE, threads=t),
    lambda t: isoflow.label_table(CUBE.astype(np.uint8), threads=t),
])
def test_an_infinite_thread_count_is_refused_naming_it(call, threads):
    # int(inf) raised Python's OverflowError from inside the thread check
    with pytest.raises(IsoflowError, match=f"^threads must be a positive integer, got {re.escape(repr(float(threads)))}$"):
        call(threads)


@pytest.mark.parametrize(("array", "ndim"), [(np.array(3), 0), (np.arange(4), 1)])
def test_label_table_of_a_label_image_neither_2d_nor_3d_names_its_dimension(array, ndim):
    # a LabelImage keeps the spacing as given where its array is no image: label_table read it
    # as an array (spacing.tolist()) and raised AttributeError
    image = isoflow.LabelImage(array, 1.0, (0.0, 0.0, 0.0))
    with pytest.raises(IsoflowError, match=f"^label_table: image: a label table needs a 3D or 2D label image, got a "
                                           f"{ndim}D array$"):
        isoflow.label_table(image)


@pytest.mark.parametrize(("ndim", "words"), [(5, "ndim must be 1..4, got 5"), ("3", "ndim must be an integer 1..4, got '3'")])
def test_euler_lut_names_its_ndim(ndim, words):
    # the message spoke of a "dimension n" that euler_lut has no parameter of
    with pytest.raises(IsoflowError, match=f"^{re.escape(words)}$"):
        isoflow.euler_lut(ndim)
    assert len(isoflow.euler_lut(np.int64(2))) == 2**4  # one entry per configuration of a 2x2 window


@pytest.mark.parametrize("bad", [5, None, ["s.ply"]])
def test_a_surface_path_that_is_no_path_is_named(bad):
    """A surface path that is not a str or os.PathLike (the arguments
    swapped, None) is one IsoflowError naming the kind of path and the
    value, not os.fspath's TypeError that names neither."""
    obj = isoflow.DigitalObject(np.ones((2, 2, 2), bool))
    with pytest.raises(IsoflowError, match=r"surface path must be a str or os\.PathLike, got " + type(bad).__name__):
        isoflow.write_surface(obj, bad)


# every public function that takes a file or store by its path, called with
# that path replaced by ``bad``
PATH_CALLS = {
    "read_volume": lambda bad: isoflow.read_volume(bad),
    "read_labels": lambda bad: isoflow.read_labels(bad),
    "read_label_names": lambda bad: isoflow.read_label_names(bad),
    "read_object": lambda bad: isoflow.read_object(bad),
    "read_points": lambda bad: isoflow.read_points(bad),
    "write_volume": lambda bad: isoflow.write_volume(np.ones((2, 2, 2), bool), bad),
    "write_labels": lambda bad: isoflow.write_labels(np.ones((2, 2, 2), np.uint8), bad),
    "write_surface": lambda bad: isoflow.write_surface(np.ones((2, 2, 2), bool), bad),
    "voxelize_file": lambda bad: isoflow.voxelize_file(bad, resolution=4),
    "voxelize_to_zarr": lambda bad: isoflow.voxelize_to_zarr(isoflow.data.torus(), bad, resolution=4),
    "analyze_zarr": lambda bad: isoflow.analyze_zarr(bad),
}


def test_path_calls_cover_every_public_function_that_takes_a_path_alone():
    import inspect

    taking = {name for name in isoflow.__all__ if inspect.isfunction(f := getattr(isoflow, name))
              and any(str(p.annotation) == "str | os.PathLike" for p in inspect.signature(f).parameters.values())}
    assert taking == set(PATH_CALLS)


@pytest.mark.parametrize("name", sorted(PATH_CALLS))
@pytest.mark.parametrize(("bad", "shown"), [
    (np.zeros((3, 4, 5), bool), "ndarray of shape (3, 4, 5)"),  # the arguments swapped, or an array for its file
    (None, "NoneType None"),
    (5, "int 5"),
    (b"v.npy", "bytes b'v.npy'"),
])
def test_a_path_that_is_no_path_is_refused_in_one_line_naming_it(name, bad, shown, tmp_path, monkeypatch):
    """A path argument that is not a str or os.PathLike is one IsoflowError
    (and TypeError) of one line that names the argument and what was given, and nothing is
    written: open()'s TypeError named neither, a message made of str(path)
    printed a whole array over many lines, and write_volume wrote an array
    to a file named after its str() (OSError: File name too long)."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(IsoflowError) as caught:
        PATH_CALLS[name](bad)
    message = str(caught.value)
    assert "\n" not in message
    assert "path must be a str or os.PathLike, got " + shown in message
    # still the TypeError os.fspath raised, for code that catches that
    assert isinstance(caught.value, TypeError)
    assert list(tmp_path.iterdir()) == []


class FsPath:
    """An os.PathLike as PEP 519 makes one, that is no pathlib.Path: only
    ``__fspath__`` gives its path, its str() is the default repr."""

    def __init__(self, path: str) -> None:
        self.path = path

    def __fspath__(self) -> str:
        return self.path


def test_every_path_argument_takes_an_os_pathlike_that_is_no_pathlib_path(tmp_path, monkeypatch):
    """The readers and writers of volumes, analyze_zarr and read_label_names
    took a path by its str(): an os.PathLike other than pathlib.Path (the
    os.DirEntry of os.scandir) was "<... object at 0x...>: not a volume
    file", and a mesh was named by that repr in a verdict and in the store
    written. Each takes one as it takes the str of its path, and names that
    path."""
    trimesh = pytest.importorskip("trimesh")
    pytest.importorskip("zarr")
    monkeypatch.chdir(tmp_path)
    cube = np.zeros((4, 4, 4), bool)
    cube[1:3, 1:3, 1:3] = True
    np.save("cube.npy", cube)
    np.save("labels.npy", 3 * cube.astype(np.uint8))
    Path("corners.txt").write_text("".join(f"{x} {y} {z}\n" for x in (0, 1) for y in (0, 1) for z in (0, 1)))
    Path("names.txt").write_text("3 liver\n")
    trimesh.creation.box().export("box.stl")
    torus = str(isoflow.data.torus())
    # one unit cube of 8 voxels, its 8 corners one cube (Definitions 1-2), a box: chi 2
    assert isoflow.read_volume(FsPath("cube.npy")).voxels == 8
    assert [isoflow.read_volume(e).voxels for e in os.scandir(".") if e.name == "cube.npy"] == [8]
    assert np.array_equal(isoflow.read_labels(FsPath("labels.npy")).array, 3 * cube)
    assert isoflow.read_label_names(FsPath("names.txt")) == {3: "liver"}
    assert isoflow.read_object(FsPath("cube.npy")).voxels == 8
    assert isoflow.read_object(FsPath("corners.txt")).voxels == 1
    assert isoflow.read_points(FsPath("corners.txt")).shape == (8, 3)
    isoflow.write_volume(cube, FsPath("written.npy"))
    assert np.array_equal(np.load("written.npy"), cube)
    isoflow.write_labels(3 * cube.astype(np.uint8), FsPath("written_labels.npy"))
    assert np.array_equal(np.load("written_labels.npy"), 3 * cube)
    isoflow.write_surface(cube, FsPath("cube.ply"))
    assert trimesh.load("cube.ply").euler_number == 2
    assert isoflow.voxelize_file(FsPath("box.stl"), resolution=4).voxels == 4**3
    isoflow.write_volume(cube, "cube.zarr")
    assert isoflow.analyze_zarr(FsPath("cube.zarr")).betti == [1, 0, 0]
    isoflow.voxelize_to_zarr(FsPath(torus), FsPath("torus.zarr"), resolution=16)
    assert isoflow.analyze_zarr("torus.zarr").betti == [1, 1, 0]
    assert isoflow.verify_genus(FsPath("box.stl"), resolutions=[8], step=False).input == "box.stl"
    assert isoflow.voxelize_meshes([FsPath("box.stl")], resolution=4).names == ("box.stl",)
    for call in (isoflow.read_volume, isoflow.read_labels, isoflow.read_object):
        with pytest.raises(IsoflowError, match=r"^gone\.npy: no such file or directory$"):
            call(FsPath("gone.npy"))
    with pytest.raises(IsoflowError, match=r"^gone\.txt: "):
        isoflow.read_label_names(FsPath("gone.txt"))


@pytest.mark.parametrize("name", ["box.obj", "box.stl", "box.ply", "part.igs"])
@pytest.mark.parametrize("read", [isoflow.read_points, isoflow.read_object])
def test_a_mesh_file_given_for_points_is_named_a_mesh(read, name, tmp_path):
    """read_points and read_object read a file of no volume suffix as a
    point list: a mesh under its own suffix was "its content is an OBJ
    file ..., but meshes are read by their suffix: rename it box.obj",
    the name it has, a binary STL or PLY "binary data, not a text point
    list; volumes are read by their suffix", and a CAD file a point list
    whose first line is no number. Each is named a mesh (or CAD) file, with
    what reads it."""
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path / name
    if name.endswith(".igs"):
        path.write_text("IGES header" + " " * 61 + "S      1\n")
    else:
        trimesh.creation.box().export(path)
    with pytest.raises(IsoflowError) as caught:
        read(path)
    message = str(caught.value)
    assert "\n" not in message and "rename" not in message and "point list" not in message
    assert message.startswith(f"{path}: a CAD file" if name.endswith(".igs") else f"{path}: a mesh file")
    assert "voxelize_file" in message or "export it" in message


@pytest.mark.parametrize("suffix", [".npy", ".npz", ".nii.gz", ".tif", ".nrrd", ".binvox", ".vox", ".zarr"])
def test_a_volume_file_given_for_points_is_named_a_volume(suffix, tmp_path):
    """read_points of a volume under its own suffix said "its content is
    NumPy, but volumes are read by their suffix: rename it v.npy", the name
    it has ("v.nii.nii.gz" for a .nii.gz), a .binvox that its suffix "names
    no volume or mesh format", and a .zarr store "a directory, not a volume
    or point list". Each is named a volume file, with the function that
    reads it, and that function reads it."""
    if suffix in (".nii.gz", ".nrrd", ".tif", ".zarr"):
        pytest.importorskip({".nii.gz": "nibabel", ".nrrd": "nrrd", ".tif": "tifffile", ".zarr": "zarr"}[suffix])
    path = isoflow.write_volume(np.ones((2, 2, 2), bool), tmp_path / f"v{suffix}")
    with pytest.raises(IsoflowError) as caught:
        isoflow.read_points(path)
    message = str(caught.value)
    assert message == f"{path}: a volume file, not a list of lattice points; isoflow.read_volume(path) reads it"
    assert isoflow.read_volume(path).voxels == 8


EMPTY_PATH_CALLS = {**PATH_CALLS, "verify_genus": lambda bad: isoflow.verify_genus(bad, [8]),
                    "voxelize_meshes": lambda bad: isoflow.voxelize_meshes([bad], resolution=4),
                    "voxelize_to_zarr source": lambda bad: isoflow.voxelize_to_zarr(bad, "v.zarr", resolution=4)}


@pytest.mark.parametrize("name", sorted(EMPTY_PATH_CALLS))
def test_an_empty_path_is_refused_as_empty(name, tmp_path, monkeypatch):
    """An empty string for a path (an unset setting, ``os.environ.get("OUT",
    "")``) was read as the current directory: ".: is a directory, not a
    volume or point list", ": is a directory; give a file name" or ".: a
    zarr store must end in .zarr", which name neither the argument nor what
    was wrong with it. Each says the path is empty; nothing is written."""
    monkeypatch.chdir(tmp_path)
    with pytest.raises(IsoflowError) as caught:
        EMPTY_PATH_CALLS[name]("")
    message = str(caught.value)
    assert "path is '', an empty file name" in message and "directory" not in message, message
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("call", "words"), [
    (lambda p: isoflow.write_volume(p, np.ones((2, 2, 2), bool)), "the object comes first: write_volume(obj, path)"),
    (lambda p: isoflow.write_labels(p, np.ones((2, 2, 2), np.uint8)), "the labels come first: write_labels(labels, path)"),
    (lambda p: isoflow.read_volume(np.load(p)), "an array in memory: DigitalObject(array)"),
    (lambda p: isoflow.voxelize_file(trimesh_box(), resolution=4), "a mesh in memory: isoflow.voxelize_mesh(mesh, resolution=N)"),
    # getting-started.md: a mesh in memory is refused as a mesh, naming what voxelises it; a Scene and
    # a Manifold given for a file got "path must be a str" alone, and a reader of volumes named nothing
    (lambda p: isoflow.voxelize_file(trimesh_scene(), resolution=4), "a mesh in memory: isoflow.voxelize_mesh("),
    (lambda p: isoflow.voxelize_file(manifold_cube(), resolution=4), "in memory: isoflow.from_manifold(manifold, pitch=P)"),
    (lambda p: isoflow.read_volume(trimesh_box()), "a mesh in memory: isoflow.voxelize_mesh(mesh, resolution=N)"),
    (lambda p: isoflow.read_object(trimesh_scene()), "a mesh in memory: isoflow.voxelize_mesh(mesh, resolution=N)"),
    (lambda p: isoflow.read_volume(manifold_cube()), "in memory: isoflow.from_manifold(manifold, pitch=P)"),
])
def test_a_path_given_something_else_says_what_takes_it(call, words, tmp_path):
    path = tmp_path / "v.npy"
    np.save(path, np.ones((2, 2, 2), bool))
    with pytest.raises(IsoflowError, match=re.escape(words)):
        call(path)
    assert [p.name for p in tmp_path.iterdir()] == ["v.npy"]


def trimesh_box():
    trimesh = pytest.importorskip("trimesh")
    return trimesh.creation.box()


def trimesh_scene():
    trimesh = pytest.importorskip("trimesh")
    return trimesh.Scene([trimesh.creation.box()])


def manifold_cube():
    return pytest.importorskip("manifold3d").Manifold.cube()


@pytest.mark.parametrize("bad", [np.array(["torus.obj", "eight.off"]), None, ["torus.obj"]])
def test_a_sample_name_that_is_no_str_is_named(bad):
    # an array's ``in`` raised NumPy's "truth value of an array ... is ambiguous"; a list is no dict key
    for call in (isoflow.data.path, isoflow.data.info):
        with pytest.raises(IsoflowError, match=r"^name must be a str, got " + type(bad).__name__):
            call(bad)


@pytest.mark.parametrize("shape", [(4, 5, 6), (5, 7)])
@pytest.mark.parametrize("fraction", [0.0, 0.5])
def test_an_object_of_voxel_indices_is_the_mask_they_come_from_an_empty_one_too(shape, fraction):
    """``from_voxels(np.argwhere(mask))`` of an all-zero mask (a label that
    is absent) is the empty object, as ``DigitalObject(mask)`` is: the
    builders refused (0, n) indices as "expected a list of 3D coordinates"
    although the voxels of a mask are such a list, and an empty one."""
    measure = pytest.importorskip("skimage.measure")
    mask = np.random.default_rng(4).random(shape) < fraction
    for build in (isoflow.DigitalObject.from_voxels, isoflow.DigitalObject.from_points):
        obj = build(np.argwhere(mask), pitch=0.5)
        assert obj.ndim == mask.ndim and obj.spacing.tolist() == [0.5] * mask.ndim
    obj = isoflow.DigitalObject.from_voxels(np.argwhere(mask))
    assert obj.voxels == np.count_nonzero(mask)
    assert isoflow.euler_characteristic(obj.volume) == measure.euler_number(mask, connectivity=1)
    assert isoflow.analyze(obj).betti == isoflow.betti_numbers(mask)
    # no lattice point gives the object that one point gives: no cube has all its corners
    assert isoflow.DigitalObject.from_points(np.zeros((0, mask.ndim), int)).voxels == 0
    assert isoflow.DigitalObject.from_points(np.zeros((1, mask.ndim), int)).voxels == 0


@pytest.mark.parametrize("empty", [[], (), np.array([])])
@pytest.mark.parametrize("build", ["from_points", "from_voxels"])
def test_an_empty_list_of_points_is_said_to_have_no_dimension(build, empty):
    """``from_points([])`` said "got shape (0,)": an empty list says no
    dimension, which the refusal says, with what to pass for the empty 3D
    object, which is then the object with no voxel that an empty mask
    gives."""
    with pytest.raises(IsoflowError) as info:
        getattr(isoflow.DigitalObject, build)(empty)
    message = str(info.value)
    assert "no dimension" in message and "np.empty((0, 3))" in message and "shape (0,)" not in message
    obj = getattr(isoflow.DigitalObject, build)(np.empty((0, 3)))
    assert obj.ndim == 3 and obj.voxels == np.count_nonzero(np.zeros((2, 2, 2), bool)) == 0


# NumPy scalars as a user takes them from an array or np.unique: the message
# says the number as written (time=5), not NumPy 2's repr (np.int64(5))
NUMPY_SCALAR_CALLS = {
    "time of a series": ('isoflow.read_volume("t.nii.gz", label=1, time=np.int64(5))', "time=5 "),
    "time of a 3D volume": ('isoflow.read_volume("v.npy", time=np.int64(0))', "time=0 "),
    "read_labels time": ('isoflow.read_labels("t.nii.gz", time=np.True_)', "time=True "),
    "label": ('isoflow.read_volume("v.npy", label=np.float64("nan"))', "got nan"),
    "steps": ("isoflow.run_flow(vol, steps=np.int64(-1))", "got -1"),
    "max_steps": ("isoflow.run_flow(vol, max_steps=np.float64(1.5))", "got 1.5"),
    "threads": ("isoflow.analyze(vol, threads=np.int64(0))", "got 0"),
    "slab": ("isoflow.configuration_histogram(vol, slab=np.int64(0))", "got 0"),
    "chi": ("isoflow.betti_numbers(vol, chi=np.float64(1.5))", "got 1.5"),
    "ndim": ("isoflow.euler_lut(np.float32(3.5))", "got 3.5"),
    "parity": ("isoflow.DigitalObject(vol, parity=np.int64(2))", "got 2"),
    "placement ndim": ("isoflow.DigitalObject.placement(np.float64(2.5))", "got 2.5"),
    "a label beyond the type": ("isoflow.label_table(vol.astype(np.uint8), labels=[np.int64(300)])", "label 300 "),
    "a label not whole": ("isoflow.label_table(vol.astype(np.uint8), labels=[np.float64(1.5)])", "label 1.5 "),
    "connectivity beside a mesh": ('isoflow.write_surface(vol, "s.ply", np.int64(26), mesh=isoflow.boundary_mesh(vol, 6))',
                                   "connectivity=26 "),
    "a switch": ('isoflow.write_volume(vol, "w.npy", force=np.int64(1))', "got 1"),
    "a callback": ("isoflow.run_flow(vol, steps=1, progress=np.int64(1))", "got 1"),
    "resolution": ('isoflow.voxelize_file("box.stl", resolution=np.int64(0))', "got 0"),
    "pitch": ('isoflow.voxelize_file("box.stl", pitch=np.str_("0.5"))', "got '0.5'"),
    "max_bytes": ('isoflow.voxelize_meshes(["box.stl"], resolution=4, max_bytes=np.int64(0))', "got 0"),
    "write_bytes": ('isoflow.voxelize_file("box.stl", resolution=4, write_bytes=np.int64(-1))', "got -1"),
    "resolutions": ('isoflow.verify_genus("box.stl", resolutions=[np.int64(0)])', "got 0 in [0]"),
    "a lone resolution": ('isoflow.verify_genus("box.stl", resolutions=np.int64(8))', "got 8; one resolution is [8]"),
    "max_resolution": ('isoflow.verify_genus("box.stl", max_resolution=np.int64(0))', "got 0"),
    "time_limit": ('isoflow.verify_genus("box.stl", time_limit=np.float64(-1.0))', "got -1.0"),
    "block_shape": ("isoflow.analyze_chunked(dask.array.from_array(vol, chunks=2), block_shape=(np.int64(0), 2, 2))",
                    "block_shape (0, 2, 2) "),
}


@pytest.mark.parametrize("call", NUMPY_SCALAR_CALLS, ids=list(NUMPY_SCALAR_CALLS))
def test_a_numpy_scalar_is_said_as_its_number(call, tmp_path, monkeypatch):
    import dask.array
    import nibabel
    import trimesh

    code, said = NUMPY_SCALAR_CALLS[call]
    monkeypatch.chdir(tmp_path)
    vol = np.zeros((4, 4, 4), bool)
    vol[1:3, 1:3, 1:3] = True
    np.save("v.npy", vol)
    nibabel.save(nibabel.Nifti1Image(np.stack([vol, vol], axis=-1).astype(np.uint8), np.eye(4)), "t.nii.gz")
    trimesh.creation.box().export("box.stl")
    with pytest.raises((IsoflowError, TypeError)) as info:
        eval(code, {"isoflow": isoflow, "np": np, "vol": vol, "dask": dask})
    message = str(info.value)
    assert said in message and "np." not in message, message


@pytest.mark.parametrize(("call", "voxeliser"), [
    ("isoflow.analyze(trimesh.Scene([box]))", "isoflow.voxelize_mesh(mesh"),
    ("isoflow.analyze(box)", "isoflow.voxelize_mesh(mesh"),
    ("isoflow.to_manifold(box)", "isoflow.voxelize_mesh(mesh"),
    ("isoflow.euler_characteristic(box)", "isoflow.voxelize_mesh(mesh"),
    ("isoflow.label_table(box)", "isoflow.voxelize_mesh(mesh"),
    ("isoflow.analyze(isoflow.to_manifold(np.ones((2, 2, 2), bool)))", "isoflow.from_manifold(manifold"),
    ("isoflow.analyze(isoflow.boundary_mesh(np.ones((2, 2, 2), bool), 6))", "the volume whose surface it is"),
])
def test_a_mesh_given_for_a_volume_is_named_with_its_voxeliser(call, voxeliser):
    """NumPy makes a mesh a 0D array of type object, which was refused as
    'array of type object is not a binary volume'."""
    import trimesh

    box = trimesh.creation.box()
    with pytest.raises(IsoflowError) as info:
        eval(call, {"isoflow": isoflow, "np": np, "trimesh": trimesh, "box": box})
    message = str(info.value)
    assert ("a mesh (" in message or "Manifold" in message) and voxeliser in message and "type object" not in message
    # what the message says to do works: the voxels' surface has the box's Euler characteristic
    solid = isoflow.voxelize_mesh(box, resolution=8)
    assert isoflow.boundary_mesh(solid.volume, 6).euler_characteristic == box.euler_number == 2


@pytest.mark.parametrize(("connectivity", "shown"), [(6.5, "6.5"), (np.float64(6.5), "6.5"), (np.float32(26.5), "26.5"),
                                                     (True, "True"), (np.True_, "True")])
def test_a_connectivity_that_is_no_integer_is_refused(connectivity, shown):
    # True equals 1; 6.5 is no count of neighbours (a whole 6.0 is 6: tests/test_integer_arguments.py)
    from skimage.measure import euler_number

    rng = np.random.default_rng(5)
    volume = rng.random((6, 6, 6)) < 0.5
    assert isoflow.analyze(volume, 6).euler_characteristic == euler_number(volume, connectivity=1)
    said = f"connectivity {shown} is not valid in 3D: it must be an integer (use 6 or 26)"
    for call in (lambda: isoflow.analyze(volume, connectivity), lambda: isoflow.boundary_mesh(volume, connectivity),
                 lambda: isoflow.run_flow(volume, connectivity=connectivity, steps=1)):
        with pytest.raises(IsoflowError) as info:
            call()
        assert str(info.value) == said
    with pytest.raises(IsoflowError) as info:
        isoflow.run_flow(volume[0], connectivity=connectivity, steps=1)
    assert str(info.value) == f"connectivity {shown} is not valid in 2D: it must be an integer (use 4 or 8)"


@pytest.mark.parametrize("parity", [True, np.True_, False])
def test_digital_object_refuses_a_bool_parity(parity):
    # True equals 1: parity=True was taken as the dual lattice
    volume = np.ones((2, 2, 2), bool)
    assert isoflow.DigitalObject(volume, parity=1).parity == 1
    with pytest.raises(IsoflowError) as info:
        isoflow.DigitalObject(volume, parity=parity)
    assert str(info.value) == f"DigitalObject: 'parity' must be 0 (lattice) or 1 (dual lattice), got {bool(parity)}"


@pytest.mark.parametrize("shape", [(2, 3, 4), (3, 4, 4), (3, 4), (4, 5, 6)])
def test_on_dual_lattice_refuses_a_vertex_volume_of_another_shape(shape):
    # a volume of the object's own shape (or another) was placed on the dual lattice as if it had one
    # value per lattice vertex: each voxel half a voxel off, the far vertices missing
    obj = isoflow.DigitalObject(np.ones((2, 3, 4), bool))
    vertices = tuple(n + 1 for n in obj.volume.shape)  # a box of n voxels has n + 1 vertices a side
    assert obj.on_dual_lattice(np.ones(vertices, bool)).volume.shape == vertices
    with pytest.raises(IsoflowError) as info:
        obj.on_dual_lattice(np.ones(shape, bool))
    assert str(info.value).count("\n") == 0
    assert f"shape {shape}, not {vertices}" in str(info.value)


@pytest.mark.parametrize(("field", "value", "kind"), [
    ("origin", (True, 0, 0), "numbers"), ("origin", np.ones(3, bool), "numbers"), ("origin", (np.True_, 0.5, 2.0), "numbers"),
    ("offset", (0, 0, True), "integers"), ("offset", np.zeros(3, bool), "integers"),
])
def test_digital_object_refuses_a_bool_origin_or_offset(field, value, kind):
    # True equals 1: origin=(True, 0, 0) placed the object at x = 1, as pitch=True and parity=True are not taken
    volume = np.ones((2, 2, 2), bool)
    with pytest.raises(IsoflowError, match=rf"^DigitalObject: '{field}' must be {kind}, not True or False, got \["):
        isoflow.DigitalObject(volume, **{field: value})
    if field == "origin":  # the functions that take a place check it as the object does
        for call in (lambda: isoflow.label_table(volume.astype(np.uint8), origin=value),
                     lambda: isoflow.analyze(volume, origin=value)):
            with pytest.raises(IsoflowError, match=r"'origin' must be numbers, not True or False"):
                call()


@pytest.mark.parametrize(("given", "words"), [
    ([[1, 2], [3]], "nested sequences of uneven lengths are no array"),
    (np.ma.masked_array([1.0, 2.0, 3.0], [0, 1, 0]), "a masked array with 1 masked element"),
])
@pytest.mark.parametrize("field", ["pitch", "origin"])
def test_a_ragged_or_masked_place_is_refused_naming_the_field(field, given, words):
    # a ragged list raised NumPy's ValueError; a masked element was read as the number stored under the mask
    volume = np.ones((2, 2, 2), bool)
    for name, call in (("DigitalObject", lambda: isoflow.DigitalObject(volume, **{field: given})),
                       ("analyze", lambda: isoflow.analyze(volume, **{field: given})),
                       ("label_table", lambda: isoflow.label_table(volume.astype(np.uint8), **{field: given}))):
        with pytest.raises(IsoflowError, match=f"^{name}: '{field}': {words}"):
            call()


@pytest.mark.parametrize("label", [True, np.True_])
def test_read_volume_refuses_a_bool_label(tmp_path, label):
    # True equals 1: label=True picked the voxels of label 1
    labels = np.zeros((4, 4, 4), np.uint8)
    labels[:2] = 1
    labels[2:, :3] = 2
    path = tmp_path / "labels.npy"
    np.save(path, labels)
    assert isoflow.read_volume(path, label=1).voxels == np.count_nonzero(labels == 1)
    with pytest.raises(IsoflowError) as info:
        isoflow.read_volume(path, label=label)
    assert str(info.value) == f"{path}: label must be a number, not True or False, got True"


_WORD_OPTIONS = [
    (lambda w: isoflow.analyze(np.ones((3, 3, 3), bool), 6, method=w), "method"),
    (lambda w: isoflow.run_flow(np.ones((3, 3, 3), bool), 6, method=w), "method"),
    (lambda w: isoflow.label_table(np.ones((3, 3, 3), np.uint8), 6, method=w), "method"),
    (lambda w: isoflow.voxelize_mesh(np.eye(3), [[0, 1, 2]], resolution=8, fill=w), "fill"),
    (lambda w: isoflow.voxelize_meshes([(np.eye(3), [[0, 1, 2]])], resolution=8, overlap=w), "overlap"),
]


@pytest.mark.parametrize("call, name", _WORD_OPTIONS)
def test_a_word_option_given_as_a_numpy_string_is_named_as_written(call, name):
    # a word read from a NumPy array (a column of a table of runs) is a
    # np.str_, whose repr under NumPy 2 is np.str_('fast'): the message
    # says the word as the user wrote it, as it says numbers
    with pytest.raises(isoflow.IsoflowError, match=rf"{name} must be one of .*, got 'fast'$"):
        call(np.str_("fast"))


def test_a_word_option_given_as_a_numpy_string_is_taken_as_the_word():
    ring = np.pad(np.ones((3, 3, 3), bool), 1)
    ring[2, 2, :] = False
    assert isoflow.analyze(ring, 6, method=np.str_("numpy")) == isoflow.analyze(ring, 6, method="numpy")


@pytest.mark.parametrize("labels", [np.array([[0, 1], [2, 3]], np.uint8), np.array([[0, 1], [2, 3]], float)])
def test_write_volume_of_a_label_image_offers_write_labels(tmp_path, labels):
    # the refusal offered isoflow.label_table(volume), which writes no file
    with pytest.raises(IsoflowError) as e:
        isoflow.write_volume(labels, tmp_path / "cells.png")
    assert str(e.value).endswith("or write its labels with isoflow.write_labels(labels, path)")
    assert not (tmp_path / "cells.png").exists()
    assert isoflow.read_labels(isoflow.write_labels(labels, tmp_path / "cells.png")).array.tolist() == labels.tolist()


def test_label_table_of_scipy_s_labels_and_count_says_to_pass_the_labels():
    # the pair was refused as "nested sequences of uneven lengths", which a notebook user did not write
    ndimage = pytest.importorskip("scipy.ndimage")
    mask = np.zeros((6, 6, 6), bool)
    mask[1:3, 1:3, 1:3] = mask[4:6, 4:6, 4:6] = True
    labels, count = ndimage.label(mask)
    with pytest.raises(IsoflowError, match=r"^label_table: image: a \(labels, count\) pair, as scipy\.ndimage\.label gives"):
        isoflow.label_table((labels, count))
    assert isoflow.label_table(labels)["label"].tolist() == list(range(1, count + 1))


def test_voxelize_meshes_of_one_pair_not_in_a_list_names_the_fix():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64)
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    with pytest.raises(IsoflowError, match=re.escape("pass [(vertices, faces)]")):
        isoflow.voxelize_meshes((vertices, faces), resolution=4)
    with pytest.raises(IsoflowError, match=re.escape("pass [(vertices, faces)]")):
        isoflow.voxelize_meshes((vertices.tolist(), faces.tolist()), resolution=4)


def results_that_are_no_array(tmp_path) -> dict:
    """isoflow's results that hold an array, or none: mappings, which NumPy
    makes an array of their keys."""
    box = tmp_path / "box.stl"
    pytest.importorskip("trimesh").creation.box().export(box)
    return {"LabelVoxelization": (isoflow.voxelize_meshes([box], resolution=4), "labels"),
            "Voxelization": (isoflow.voxelize_file(box, resolution=4, details=True)[1], "volume"),
            "ZarrStore": (isoflow.voxelize_to_zarr(box, tmp_path / "box.zarr", resolution=4), None),
            "Report": (isoflow.analyze(np.ones((2, 2, 2), bool)), None)}


@pytest.mark.parametrize("call", [
    lambda r, p: isoflow.analyze(r),
    lambda r, p: isoflow.euler_characteristic(r),
    lambda r, p: isoflow.DigitalObject(r),
    lambda r, p: isoflow.write_volume(r, p / "v.npz"),
    lambda r, p: isoflow.write_labels(r, p / "l.nrrd"),
    lambda r, p: isoflow.label_table(r),
], ids=["analyze", "euler_characteristic", "DigitalObject", "write_volume", "write_labels", "label_table"])
def test_a_result_given_for_an_array_is_named_with_the_field_that_holds_one(call, tmp_path):
    """A result given where an array is taken (``label_table(r)`` of
    ``r = voxelize_meshes(...)``, the Voxelization that ``details=True``
    gives beside the object) is a Mapping, which NumPy made a 1D array of
    its keys: "array of type <U14 is not a binary volume", "a label table
    needs a 3D or 2D label image, got a 1D array". Each names the result,
    and the field that holds its array where one does; nothing is written."""
    for name, (result, field) in results_that_are_no_array(tmp_path).items():
        with pytest.raises(IsoflowError) as caught:
            call(result, tmp_path)
        message = str(caught.value)
        assert name in message and "<U" not in message and "1D" not in message, message
        assert field is None or f".{field}" in message, message
    assert not list(tmp_path.glob("[vl].*"))


@pytest.mark.parametrize(("given", "words"), [
    (lambda v: isoflow.DigitalObject(v, pitch=0.5), ("a DigitalObject", ".volume", "write_volume")),
    (lambda v: "labels.npy", ("labels.npy is a path", "isoflow.read_labels")),
    (lambda v: pytest.importorskip("trimesh").creation.box(), ("a mesh (Trimesh)", "voxelize")),
    (lambda v: isoflow.to_manifold(v), ("manifold3d.Manifold",)),
], ids=["DigitalObject", "path", "Trimesh", "Manifold"])
def test_write_labels_names_an_object_a_path_or_a_mesh_given_for_its_labels(given, words, tmp_path):
    """write_labels of a DigitalObject, a mesh or the path of a label image
    said "a label image is a 3D or 2D array of integers ..., got 0D
    object" (or "0D <U10"), which names none of them; each is named, with
    what to pass, as the other functions that take an array name them."""
    cube = np.zeros((3, 3, 3), bool)
    cube[1, 1, 1] = True
    np.save(tmp_path / "labels.npy", cube.astype(np.uint8))
    with pytest.raises(IsoflowError) as caught:
        isoflow.write_labels(given(cube), tmp_path / "out.nrrd")
    message = str(caught.value)
    assert "0D" not in message and all(w in message for w in words), message
    assert not (tmp_path / "out.nrrd").exists()


@pytest.mark.parametrize(("chunks", "shown"), [
    (4, "4"), ((2.5, 4, 4), "(2.5, 4, 4)"), (("4", 4, 4), "('4', 4, 4)"), ((True, 4, 4), "(True, 4, 4)"),
    ((np.nan, 4, 4), "(nan, 4, 4)"), ((4, 4), "(4, 4)"), ((0, 4, 4), "(0, 4, 4)"),
])
def test_voxelize_to_zarr_names_chunks_that_are_not_three_positive_integers(chunks, shown, tmp_path):
    """``chunks=(2.5, 4, 4)`` wrote chunks of 2 in silence (int() of each
    side), ``chunks=4`` (one side, as zarr takes it) was Python's
    "TypeError: 'int' object is not iterable" and ``("4", 4, 4)`` took the
    string as a number; each is refused as the message says, three
    positive integers, naming what was given, and no store is written."""
    with pytest.raises(IsoflowError) as caught:
        isoflow.voxelize_to_zarr(isoflow.data.torus(), tmp_path / "t.zarr", resolution=8, chunks=chunks)
    assert str(caught.value).endswith(f"chunks must be three positive integers, got {shown}")
    # named as the argument of voxelize_to_zarr, not under the mesh's name ("mesh: chunks ...")
    assert str(caught.value).startswith("voxelize_to_zarr: chunks")
    assert not (tmp_path / "t.zarr").exists()
    # sides given as whole floats or NumPy integers are those integers
    store = isoflow.voxelize_to_zarr(isoflow.data.torus(), tmp_path / "t.zarr", resolution=8,
                                     chunks=(4.0, np.int64(4), 4))
    assert store.chunks == (4, 4, 4) and all(type(c) is int for c in store.chunks)


def test_label_table_of_an_analyze_report_says_it_takes_the_label_image():
    report = isoflow.analyze(np.ones((3, 3, 3), bool))
    with pytest.raises(IsoflowError) as info:
        isoflow.label_table(report)
    text = str(info.value)
    assert "Report" in text and "one object" in text and "label image" in text and "1D" not in text


def _edge_pair() -> np.ndarray:
    """Two voxels that share only an edge: two components under 6, one
    under 26 (scikit-image's label at connectivity 1 and 3 says so)."""
    v = np.zeros((2, 2, 1), bool)
    v[0, 0, 0] = v[1, 1, 0] = True
    return v


ZERO_D_CONNECTIVITY = {
    "analyze": lambda v, c: isoflow.analyze(v, c)["betti"][0],
    "euler_characteristic": lambda v, c: isoflow.euler_characteristic(v, c),
    "betti_numbers": lambda v, c: isoflow.betti_numbers(v, c)[0],
    "label_table": lambda v, c: int(isoflow.label_table(v, c)["b0"][0]),
    "boundary_mesh": lambda v, c: len(isoflow.boundary_mesh(v, c).components()),
    "closed_surfaces": lambda v, c: len(isoflow.closed_surfaces(v, c).surfaces),
    "a_lut": lambda v, c: int(isoflow.configuration_histogram(v) @ isoflow.a_lut(c)) // 8,
    "euler_lut": lambda v, c: int(isoflow.configuration_histogram(v) @ isoflow.euler_lut(3, c)) // 8,
}


@pytest.mark.parametrize("name", sorted(ZERO_D_CONNECTIVITY))
def test_a_0d_integer_array_is_the_integer_it_holds(name):
    """A number saved with np.savez comes back from np.load as a 0D array,
    which NumPy indexes by as the integer it holds. Given for the
    connectivity it was refused as "connectivity 6 is not valid in 3D: it
    must be an integer", a line that contradicts itself (steps, slab, chi,
    resolution, resolutions, max_resolution and labels said the same). It
    is now the integer: two voxels meeting at an edge are two components
    under 6 and one under 26, as scikit-image labels them."""
    measure = pytest.importorskip("skimage.measure")
    v = _edge_pair()
    call = ZERO_D_CONNECTIVITY[name]
    for conn, sk in ((6, 1), (26, 3)):
        expected = int(measure.label(v, connectivity=sk).max())
        assert call(v, np.array(conn)) == call(v, conn) == expected
    with pytest.raises(IsoflowError, match=r"^connectivity True is not valid in 3D: it must be an integer"):
        call(v, np.array(True))  # a 0D bool is refused as the bool is


def test_0d_integer_arrays_for_counts_and_sizes(tmp_path):
    """steps, slab, chi, ndim, resolution, resolutions, max_resolution and
    labels take a 0D integer array as the integer it holds (they refused
    it naming its value, "steps must be an integer >= 0, got 2"), and
    refuse a 0D float or bool array as they refuse the float or bool."""
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box((2, 2, 2))
    cube = np.ones((3, 3, 3), bool)
    # the flow peels a 3x3x3 cube to 2x2x2 (8 voxels) and then one voxel (eq. 5.1's lattices in turn)
    run = isoflow.run_flow(cube, steps=np.array(2), max_steps=np.array(5))
    assert [s["voxels"] for s in run.steps] == [27, 8, 1] and run.to_dict()["steps"][-1]["step"] == 2
    assert int(isoflow.configuration_histogram(cube, slab=np.array(1)).sum()) == 4 ** 3  # one per lattice vertex
    assert isoflow.betti_numbers(cube, chi=np.array(1)) == [1, 0, 0]
    assert len(isoflow.euler_lut(np.array(2))) == 2 ** 4
    assert isoflow.voxelize_mesh(box, resolution=np.array(4)).voxels == 4 ** 3  # the box fills its 4^3 grid
    verdict = isoflow.verify_genus(box, np.array([8]), max_resolution=np.array(16))
    assert verdict.agree and verdict.reference == 0
    assert isoflow.label_table(7 * cube.astype(np.uint8), labels=[np.array(7)])["voxels"].tolist() == [27]
    for call, words in [
        (lambda: isoflow.run_flow(cube, steps=np.array(2.5)), "steps must be an integer >= 0, got 2.5"),
        (lambda: isoflow.configuration_histogram(cube, slab=np.array(True)), "slab must be an integer >= 1, got True"),
        (lambda: isoflow.label_table(cube, labels=[np.array(1.5)]), "label 1.5 is not an integer"),
        (lambda: isoflow.verify_genus(box, np.array(8)), "resolutions must be a sequence of integers, got 8; "
                                                           "one resolution is [8]"),
    ]:
        with pytest.raises(IsoflowError, match=re.escape(words)):
            call()


def test_0d_arrays_for_a_label_a_byte_budget_a_time_limit_and_block_and_chunk_sides(tmp_path):
    """A label, ``max_bytes``, ``time_limit`` and the sides of
    ``block_shape`` and ``chunks`` refused a 0D array of a number, each in
    a line that contradicts itself ("label must be a number, got 2",
    "chunks must be three positive integers, got (4, 4, 4)"), and a 0D
    array given for all of ``chunks`` raised NumPy's "iteration over a 0-d
    array". Each is the number it holds: the voxels NumPy counts of the
    label, the genus trimesh gives of a box, the report of the array in
    memory, the chunks zarr reads back; a 0D bool is refused as the bool
    is, and a 0D array of chunks in one line."""
    trimesh = pytest.importorskip("trimesh")
    dask_array = pytest.importorskip("dask.array")
    zarr = pytest.importorskip("zarr")
    labels = np.zeros((5, 5, 5), np.int32)
    labels[1:4, 1:4, 1:4], labels[2, 2, 2] = 2, 3
    path = isoflow.write_labels(labels, tmp_path / "seg.npz")
    assert isoflow.read_volume(path, label=np.array(2)).voxels == np.count_nonzero(labels == 2) == 26
    assert isoflow.read_object(path, label=np.array(3.0)).voxels == np.count_nonzero(labels == 3) == 1
    with pytest.raises(IsoflowError, match="label must be a number, not True or False, got True"):
        isoflow.read_volume(path, label=np.array(True))
    box = trimesh.creation.box((2, 2, 2))
    assert box.euler_number == 2  # genus 0
    verdict = isoflow.verify_genus(box, [8], time_limit=np.array(60.0))
    assert verdict.agree and verdict.reference == 0
    assert isoflow.voxelize_meshes([box], resolution=4, max_bytes=np.array(10**9)).voxels == (4 ** 3,)
    cube = np.pad(np.ones((3, 3, 3), bool), 1)
    chunked = isoflow.analyze_chunked(dask_array.from_array(cube, chunks=2), 6, block_shape=(np.array(2),) * 3)
    assert chunked == isoflow.analyze(cube, 6) and chunked.betti == [1, 0, 0]
    isoflow.voxelize_to_zarr(box, tmp_path / "box.zarr", resolution=8, chunks=(np.array(4),) * 3)
    assert zarr.open(str(tmp_path / "box.zarr"), mode="r")["0"].chunks == (4, 4, 4)  # OME-Zarr level 0
    with pytest.raises(IsoflowError, match=r"^voxelize_to_zarr: chunks must be three positive integers, got 4$"):
        isoflow.voxelize_to_zarr(box, tmp_path / "other.zarr", resolution=8, chunks=np.array(4))


def test_0d_arrays_for_switches_a_write_rate_and_label_names(tmp_path):
    """A 0D array of a bool given for a switch (``surfaces``, ``guard``,
    ``strict``, ``ascii``, ``force``) was refused as "must be True or
    False, got True", one of a number for ``write_bytes`` as "must be a
    number of bytes per voxel from 0 on, got 0", and a name held in a 0D
    array (an element of an array of names) as "the name of label 1 is
    'x', not a string of one line". Each is what it holds: a cube's report
    without surfaces, the file written and read back by trimesh, the
    column of names; a 0D array of a word given for a switch is still
    refused naming it."""
    trimesh = pytest.importorskip("trimesh")
    cube = np.pad(np.ones((2, 2, 2), bool), 1)
    assert "surfaces" not in isoflow.analyze(cube, 6, surfaces=np.array(False))
    assert isoflow.run_flow(cube, guard=np.array(True)).guard is True
    box = trimesh.creation.box((2, 2, 2))
    assert isoflow.voxelize_mesh(box, resolution=4, strict=np.array(False), write_bytes=np.array(0)).voxels == 4 ** 3
    path = isoflow.write_surface(cube, tmp_path / "cube.ply", 6, ascii=np.array(True))
    path = isoflow.write_surface(cube, path, 6, ascii=np.array(True), force=np.array(True))
    assert path.read_bytes().startswith(b"ply\nformat ascii")
    assert trimesh.load(path, process=False).area == 24.0  # a 2x2x2 cube of unit voxels
    labels = cube.astype(np.uint8)
    assert isoflow.label_table(labels, names=np.array(["bone"]))["name"].tolist() == ["bone"]
    assert isoflow.label_table(labels, names=[np.array("bone")])["name"].tolist() == ["bone"]
    with pytest.raises(IsoflowError, match=r"^analyze: surfaces must be True or False, got 'no'$"):
        isoflow.analyze(cube, 6, surfaces=np.array("no"))


@pytest.mark.parametrize("suffix", [".nrrd", ".zarr", ".npz", ".h5"])
def test_a_label_image_given_for_its_names_says_where_they_are(suffix, tmp_path):
    """read_label_names of a label image that records its names (a 3D
    Slicer .nrrd, an OME-Zarr store, HDF5, .npz) said "not a file of label
    names (it holds binary data)" and of a .zarr store "cannot read the
    label names (Is a directory)", neither saying that read_labels gives
    those names. It now says so, and read_labels gives them."""
    if suffix != ".npz":
        pytest.importorskip({".nrrd": "nrrd", ".zarr": "zarr", ".h5": "h5py"}[suffix])
    labels = np.zeros((3, 3, 3), np.uint8)
    labels[0, 0, 0], labels[2, 2, 2] = 1, 2
    path = isoflow.write_labels(labels, tmp_path / f"seg{suffix}", names={1: "liver", 2: "spleen"})
    with pytest.raises(IsoflowError) as caught:
        isoflow.read_label_names(path)
    message = str(caught.value)
    assert message.startswith(f"{path}: a label image, not a side file of label names; ")
    assert "isoflow.read_labels(path).names" in message and "\n" not in message
    assert isoflow.read_labels(path).names == {1: "liver", 2: "spleen"}


MESH_CALLS = {
    "voxelize_mesh": lambda mesh, tmp: isoflow.voxelize_mesh(mesh, resolution=4),
    "voxelize_meshes": lambda mesh, tmp: isoflow.voxelize_meshes([mesh], resolution=4),
    "voxelize_to_zarr": lambda mesh, tmp: isoflow.voxelize_to_zarr(mesh, tmp / "m.zarr", resolution=4),
    "verify_genus": lambda mesh, tmp: isoflow.verify_genus(mesh, [4]),
}


@pytest.mark.parametrize("name", sorted(MESH_CALLS))
def test_a_manifold_given_for_a_mesh_names_its_bridge(name, tmp_path):
    """A manifold3d.Manifold given where a triangle mesh is taken said
    "faces are missing: voxelize_mesh(vertices, faces) ..." (voxelize_mesh)
    or "a mesh is a file, ... got Manifold", naming neither
    isoflow.from_manifold nor where the Manifold's triangles are, as a
    Manifold given for a volume does. The line names both, nothing is
    written, and the triangles it names voxelise to the unit cube's 4^3
    voxels."""
    manifold3d = pytest.importorskip("manifold3d")
    cube = manifold3d.Manifold.cube((1, 1, 1))
    with pytest.raises(IsoflowError) as caught:
        MESH_CALLS[name](cube, tmp_path)
    message = str(caught.value)
    assert "a manifold3d.Manifold, not a triangle mesh: isoflow.from_manifold(manifold, pitch=P) voxelises it" in message
    assert "faces are missing" not in message and "\n" not in message and list(tmp_path.iterdir()) == []
    m = cube.to_mesh()
    assert isoflow.voxelize_mesh((m.vert_properties[:, :3], m.tri_verts), resolution=4).voxels == 4 ** 3
    assert isoflow.from_manifold(cube, pitch=0.25).voxels == 4 ** 3


@pytest.mark.parametrize("threads", [Fraction(8), Decimal("8"), "8"], ids=["Fraction", "Decimal", "text"])
@pytest.mark.parametrize("call", [
    lambda t: isoflow.analyze(CUBE, threads=t),
    lambda t: isoflow.label_table(CUBE.astype(np.uint8), threads=t),
])
def test_a_thread_count_of_another_number_type_is_refused_as_a_float_is(call, threads):
    """``threads`` is an integer argument: ``int``, a NumPy integer or a 0D
    array of one, as ``connectivity`` and ``steps``. ``Fraction(8)`` and
    ``Decimal("8")`` were taken, their text being ``8``, where ``8.0`` was
    refused."""
    with pytest.raises(IsoflowError) as info:
        call(threads)
    assert str(info.value) == f"threads must be a positive integer, got {threads!r}"
    call(np.array(2))


@pytest.mark.parametrize("name", ["workers", "width"])
@pytest.mark.parametrize("given", [Fraction(2), Decimal("2"), "2", 2.5], ids=["Fraction", "Decimal", "text", "float"])
def test_flow_chunked_refuses_a_worker_count_that_is_no_integer_before_writing(tmp_path, name, given):
    # "2", Fraction(2) and Decimal("2") were taken as 2 workers, and 2.5 is none
    zarr = pytest.importorskip("zarr")
    from isoflow.flow.chunked import flow_chunked

    zarr.open_array(str(tmp_path / "in.zarr"), mode="w", shape=(3, 3, 3), chunks=(2, 2, 2), dtype="u1")[...] = 1
    with pytest.raises(IsoflowError) as info:
        flow_chunked(tmp_path / "in.zarr", tmp_path / "out", **{name: given})
    assert str(info.value) == f"{name} must be a positive integer, got {given!r}"
    assert not (tmp_path / "out").exists()


def test_flow_chunked_refuses_a_directory_that_is_a_file(tmp_path):
    """``directory`` is where the step stores go: a file there ended the
    run in NotADirectoryError from ``mkdir`` (after the input was read and
    checked), not one IsoflowError naming it; the file is left as it was."""
    zarr = pytest.importorskip("zarr")
    from isoflow.flow.chunked import flow_chunked

    zarr.open_array(str(tmp_path / "in.zarr"), mode="w", shape=(3, 3, 3), chunks=(2, 2, 2), dtype="u1")[...] = 1
    (tmp_path / "out").write_bytes(b"mine")
    with pytest.raises(IsoflowError) as info:
        flow_chunked(tmp_path / "in.zarr", tmp_path / "out")
    assert str(info.value) == f"{tmp_path / 'out'}: the directory for the step stores is not a directory"
    assert (tmp_path / "out").read_bytes() == b"mine"


def test_flow_chunked_force_keeps_a_users_directory_named_as_a_step_store(tmp_path):
    """force=True removed any ``step_*.zarr`` in the directory, a folder of
    the user's holding no zarr store too (the command line refuses one):
    it is refused, untouched; a real store of an earlier run still goes."""
    zarr = pytest.importorskip("zarr")
    from isoflow.flow.chunked import flow_chunked

    zarr.open_array(str(tmp_path / "in.zarr"), mode="w", shape=(3, 3, 3), chunks=(2, 2, 2), dtype="u1")[...] = 1
    mine = tmp_path / "out" / "step_000.zarr"
    mine.mkdir(parents=True)
    (mine / "notes.txt").write_text("mine")
    with pytest.raises(IsoflowError) as info:
        flow_chunked(tmp_path / "in.zarr", tmp_path / "out", steps=1, force=True)
    assert str(info.value).startswith(f"{mine}: a directory that is not a step store of a run; force=True")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["step_000.zarr"]
    assert (mine / "notes.txt").read_text() == "mine"
    earlier = zarr.open_array(str(tmp_path / "out" / "step_005.zarr"), mode="w", shape=(1,), dtype="u1")
    shutil.rmtree(mine)
    flow_chunked(tmp_path / "in.zarr", tmp_path / "out", steps=1, force=True)
    assert earlier is not None and not (tmp_path / "out" / "step_005.zarr").exists()
    assert zarr.open(str(tmp_path / "out" / "step_000.zarr"), mode="r") is not None  # a store zarr reads


@pytest.mark.parametrize(("name", "voxelize"), [
    ("voxelize_mesh", lambda **k: isoflow.voxelize_mesh(_box(), **k)),
    ("voxelize_meshes", lambda **k: isoflow.voxelize_meshes([_box()], **k)),
])
def test_a_pitch_is_a_real_number_as_digital_objects_pitch_is(name, voxelize):
    """A voxel size is a real number (``numbers.Real``), as
    ``DigitalObject(..., pitch=)`` takes one: ``Fraction(1, 2)`` is 0.5,
    ``Decimal("0.5")``, which is no ``Real``, is refused naming it (it was
    read by ``float()``, where ``DigitalObject`` refused it)."""
    pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError) as info:
        voxelize(pitch=Decimal("0.5"))
    assert str(info.value) == f"{name}: pitch must be a positive number, got Decimal('0.5')"
    with pytest.raises(IsoflowError, match=re.escape("'pitch' must be a number (one, or one per axis), got Decimal('0.5')")):
        isoflow.DigitalObject(np.ones((2, 2, 2), bool), pitch=Decimal("0.5"))
    # the unit box at pitch 1/2: 2 x 2 x 2 voxels
    assert voxelize(pitch=Fraction(1, 2)).voxels in (8, (8,))


@pytest.mark.parametrize(("call", "words"), [
    (lambda v: isoflow.analyze(CUBE, connectivity=v), "connectivity '6' is not valid in 3D: it must be an integer (use 6 or 26)"),
    (lambda v: isoflow.run_flow(CUBE, steps=v), "steps must be an integer >= 0, got '6'"),
])
def test_a_number_given_as_a_numpy_string_is_refused_as_text(call, words):
    # np.str_("6") has a shape () and a dtype: it was indexed as a 0D array, str's
    # indexing raising "TypeError: string indices must be integers, not 'tuple'"
    with pytest.raises(IsoflowError) as info:
        call(np.str_("6"))
    assert str(info.value) == words


def _open_box():
    box = _box()
    box.faces = box.faces[:-1]  # one triangle gone: 3 boundary edges, as trimesh counts them
    return box


def _coincident():
    import trimesh

    return trimesh.Trimesh(np.zeros((3, 3)), [[0, 1, 2]], process=False)


CUBE = np.pad(np.ones((2, 2, 2), bool), 1)
LABELS = CUBE.astype(np.uint8) * 2  # a label image where a mask is taken: values 0 and 2
LABELS_2D = np.array([[0, 1], [2, 2]], np.uint8)

# (function, call, the words that follow its name): each refusal of the
# Python API begins with the function called (after the file or mesh it is
# about, where one is named), never with the command's name "voxelize", a
# class not called ("DigitalObject volume") or no name at all
REFUSALS = [
    # a bad pitch or origin
    ("DigitalObject", lambda tmp: isoflow.DigitalObject(CUBE, pitch=-1), ": 'pitch' must be positive"),
    ("DigitalObject", lambda tmp: isoflow.DigitalObject(CUBE, origin="abc"), ": 'origin' must be 3 numbers"),
    ("analyze", lambda tmp: isoflow.analyze(CUBE, pitch=-1), ": 'pitch' must be positive"),
    ("analyze", lambda tmp: isoflow.analyze(CUBE, origin=(1, 2)), ": 'origin' must be 3 numbers"),
    ("label_table", lambda tmp: isoflow.label_table(LABELS, pitch=-1), ": 'pitch' must be positive"),
    ("analyze_zarr", lambda tmp: isoflow.analyze_zarr(_zarr_cube(tmp) and tmp / "cube.zarr", pitch=-1),
     ": 'pitch' must be positive"),
    ("write_labels", lambda tmp: isoflow.write_labels(LABELS, tmp / "l.npz", pitch=-1), ": 'pitch' must be positive"),
    ("from_manifold", lambda tmp: isoflow.from_manifold(_cube_manifold(), pitch=-1), ": 'pitch' must be positive"),
    ("from_manifold", lambda tmp: isoflow.from_manifold(_cube_manifold(), pitch=(1, 2)), ": 'pitch' must be one number"),
    ("voxelize_mesh", lambda tmp: isoflow.voxelize_mesh(_box(), pitch=1e-300), ": pitch=1e-300 needs a "),
    ("voxelize_meshes", lambda tmp: isoflow.voxelize_meshes([_box()], pitch=1e-300), ": pitch=1e-300 needs a "),
    ("voxelize_file", lambda tmp: isoflow.voxelize_file(_saved(tmp), pitch=1e-300), ": pitch=1e-300 needs a "),
    ("voxelize_to_zarr", lambda tmp: isoflow.voxelize_to_zarr(_box(), tmp / "v.zarr", pitch=1e-300),
     ": pitch=1e-300 needs a "),
    # a bad mesh, or none
    ("voxelize_mesh", lambda tmp: isoflow.voxelize_mesh(_open_box(), pitch=0.5, strict=True), ": mesh is not watertight"),
    ("voxelize_meshes", lambda tmp: isoflow.voxelize_meshes([_open_box()], pitch=0.5, strict=True),
     ": mesh is not watertight"),
    ("voxelize_file", lambda tmp: isoflow.voxelize_file(_saved(tmp, _open_box()), pitch=0.5, strict=True),
     ": mesh is not watertight"),
    ("voxelize_to_zarr", lambda tmp: isoflow.voxelize_to_zarr(_open_box(), tmp / "v.zarr", pitch=0.5, strict=True),
     ": mesh is not watertight"),
    ("voxelize_mesh", lambda tmp: isoflow.voxelize_mesh(np.eye(3), pitch=0.5), ": faces are missing"),
    ("voxelize_mesh", lambda tmp: isoflow.voxelize_mesh(_coincident(), pitch=0.5), ": mesh bounding box has zero size"),
    ("voxelize_to_zarr", lambda tmp: isoflow.voxelize_to_zarr(_coincident(), tmp / "v.zarr", pitch=0.5),
     ": mesh bounding box has zero size"),
    ("voxelize_meshes", lambda tmp: isoflow.voxelize_meshes([], pitch=0.5), ": no meshes given"),
    ("verify_genus", lambda tmp: isoflow.verify_genus(_box(), [16], max_resolution=0), ": max_resolution must be"),
    ("verify_genus", lambda tmp: isoflow.verify_genus(_box(), 16), ": resolutions must be a sequence"),
    # a label image where a mask is taken, named as the argument given
    ("DigitalObject", lambda tmp: isoflow.DigitalObject(LABELS), " volume: not a binary volume"),
    ("run_flow", lambda tmp: isoflow.run_flow(LABELS), ": obj: not a binary volume"),
    ("flow_step", lambda tmp: isoflow.flow_step(LABELS), ": obj: not a binary volume"),
    ("write_surface", lambda tmp: isoflow.write_surface(LABELS, tmp / "s.ply"), ": obj: not a binary volume"),
    ("to_manifold", lambda tmp: isoflow.to_manifold(LABELS), ": obj: not a binary volume"),
    # an array of a dimension the function does not take
    ("DigitalObject", lambda tmp: isoflow.DigitalObject(np.ones(3, bool)), " volume: a digital object is 2D, 3D or 4D"),
    ("run_flow", lambda tmp: isoflow.run_flow(np.ones(3, bool)), ": obj: a digital object is 2D, 3D or 4D"),
    ("flow_step", lambda tmp: isoflow.flow_step(np.ones((1,) * 5, bool)), ": obj: a digital object is 2D, 3D or 4D"),
    ("write_volume", lambda tmp: isoflow.write_volume(np.ones(3, bool), tmp / "v.npy"),
     ": obj: a digital object is 2D, 3D or 4D"),
    # a 2D label image refused as 2D, not first offered a threshold that leaves it 2D
    ("to_manifold", lambda tmp: isoflow.to_manifold(LABELS_2D), " needs a 3D object, got 2D"),
    ("boundary_mesh", lambda tmp: isoflow.boundary_mesh(LABELS_2D), " needs a 3D volume, got a 2D array"),
    ("closed_surfaces", lambda tmp: isoflow.closed_surfaces(np.ones((2, 2), bool)), " needs a 3D volume, got a 2D array"),
    ("write_surface", lambda tmp: isoflow.write_surface(LABELS_2D, tmp / "s.ply"), " needs a 3D object, got 2D"),
]

#: every public function that takes a volume (its first argument, ``obj`` or
#: ``volume``), called on ``v``; a writer writes into ``tmp``
VOLUME_TAKERS = {
    "analyze": lambda v, tmp: isoflow.analyze(v),
    "euler_characteristic": lambda v, tmp: isoflow.euler_characteristic(v),
    "betti_numbers": lambda v, tmp: isoflow.betti_numbers(v),
    "closed_surfaces": lambda v, tmp: isoflow.closed_surfaces(v),
    "configurations": lambda v, tmp: isoflow.configurations(v),
    "configuration_histogram": lambda v, tmp: isoflow.configuration_histogram(v),
    "boundary_mesh": lambda v, tmp: isoflow.boundary_mesh(v),
    "run_flow": lambda v, tmp: isoflow.run_flow(v, 1),
    "flow_step": lambda v, tmp: isoflow.flow_step(v),
    "to_manifold": lambda v, tmp: isoflow.to_manifold(v),
    "write_surface": lambda v, tmp: isoflow.write_surface(v, tmp / "s.ply"),
    "write_volume": lambda v, tmp: isoflow.write_volume(v, tmp / "v.npy"),
}


def test_every_public_function_that_takes_a_volume_is_checked_below():
    takers = {name for name in isoflow.__all__ if inspect.isfunction(getattr(isoflow, name))
              and next(iter(inspect.signature(getattr(isoflow, name)).parameters), None) in ("obj", "volume")}
    assert takers == set(VOLUME_TAKERS)


@pytest.mark.parametrize("given", ["labels", "path", "nan"])
@pytest.mark.parametrize("name", sorted(VOLUME_TAKERS))
def test_a_bad_volume_is_refused_naming_the_function_called(name, given, tmp_path):
    """analyze, euler_characteristic and the others that take an array
    refused a label image as "volume: not a binary volume ...", naming the
    argument and not the function, where run_flow said "run_flow: obj:
    ..."; analyze("x.npy") said "x.npy: a path, not an array". Each
    refusal begins with the function called, then its argument."""
    if name == "to_manifold":
        pytest.importorskip("manifold3d")
    volume = {"labels": np.arange(8).reshape(2, 2, 2), "path": "x.npy", "nan": np.full((2, 2, 2), np.nan)}[given]
    _refused_as_called(name, lambda: VOLUME_TAKERS[name](volume, tmp_path), tmp_path)


def _refused_as_called(name: str, call, folder: Path) -> None:
    """``call()`` of the public function ``name`` is refused in one line
    that begins with ``name``, then its first argument, writing nothing
    into ``folder``."""
    argument = next(iter(inspect.signature(getattr(isoflow, name)).parameters))
    with pytest.raises(IsoflowError) as caught:
        call()
    message = str(caught.value)
    assert message.startswith(f"{name}: {argument}: ") and "\n" not in message, message
    assert not any(folder.iterdir())


#: the public functions that take a label image, each called with one
LABEL_TAKERS = {
    "label_table": lambda image, tmp: isoflow.label_table(image),
    "write_labels": lambda image, tmp: isoflow.write_labels(image, tmp / "labels.npz"),
}

#: images that hold no labels, or are no image
BAD_LABEL_IMAGES = {
    "half": np.full((2, 2, 2), 0.5),
    "nan": np.full((2, 2, 2), np.nan),
    "4D": np.zeros((2, 2, 2, 2), np.uint8),
    "path": "x.npy",
    "complex": np.zeros((2, 2, 2), complex),
    "object": np.array([[[None, 1]]], object),
    "negative": np.full((2, 2, 2), -1.0),
}


def test_every_public_function_that_takes_a_label_image_is_checked_below():
    takers = {name for name in isoflow.__all__ if inspect.isfunction(getattr(isoflow, name))
              and next(iter(inspect.signature(getattr(isoflow, name)).parameters), None) in ("image", "labels")}
    assert takers == set(LABEL_TAKERS)


@pytest.mark.parametrize("given", sorted(BAD_LABEL_IMAGES))
@pytest.mark.parametrize("name", sorted(LABEL_TAKERS))
def test_a_bad_label_image_is_refused_naming_the_function_called(name, given, tmp_path):
    """label_table(np.full((2, 2, 2), 0.5)) said "voxel (0, 0, 0) holds
    0.5: not a whole number, so not a label", naming no function; its 4D
    image "a label table needs ...", a list "label_table image: ...", and
    write_labels began with the output file's name. Each refusal begins
    with the function called, then its argument."""
    image = BAD_LABEL_IMAGES[given]
    if name == "label_table" and given == "negative":  # a table takes negative labels; a file holds them from 0 on
        assert isoflow.label_table(image)["label"].tolist() == [-1]
        return
    _refused_as_called(name, lambda: LABEL_TAKERS[name](image, tmp_path), tmp_path)


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"labels": [1.5]}, "label_table: labels: label 1.5 is not an integer"),
    ({"labels": [2, 2]}, "label_table: labels: labels asked twice: 2"),
    ({"labels": [300]}, "label_table: labels: label 300 is not a value"),
    ({"names": 5}, "label_table: names: names are a mapping"),
])
def test_label_table_names_the_argument_refused(kwargs, words):
    with pytest.raises(IsoflowError, match=f"^{re.escape(words)}"):
        isoflow.label_table(np.ones((2, 2, 2), np.uint8), **kwargs)


@pytest.mark.parametrize(("kwargs", "words"), [
    ({"names": 5}, "write_labels: names: names are a mapping"),
    ({"names": {-1: "a"}}, "write_labels: names: a label name is given for -1"),
    ({"unit": 5}, "write_labels: unit 5 is not a length unit"),
])
def test_write_labels_names_the_argument_refused(kwargs, words, tmp_path):
    # each began with the output file's name, as if the file were at fault
    with pytest.raises(IsoflowError, match=f"^{re.escape(words)}"):
        isoflow.write_labels(np.ones((2, 2, 2), np.uint8), tmp_path / "l.npz", **kwargs)
    assert not any(tmp_path.iterdir())


def test_a_store_voxel_that_is_no_label_is_refused_naming_the_function_called(tmp_path):
    """A zarr store of floats holding 0.5 in its second slab: the refusal
    found while the slabs are read named the voxel alone ("voxel (3, 1, 1)
    holds 0.5: ..."), where label_table's begins with the function and its
    argument; the command line names the store, not the function."""
    zarr = pytest.importorskip("zarr")
    from in_process import isoflow_here

    from isoflow.digital.label_blocks import label_table_blocks

    image = np.zeros((4, 4, 4), np.float32)
    image[3, 1, 1] = 0.5
    store = zarr.open_array(tmp_path / "img.zarr", mode="w", shape=image.shape, chunks=(2, 4, 4), dtype="f4")
    store[:] = image
    said = "voxel (3, 1, 1) holds 0.5: not a whole number, so not a label"
    with pytest.raises(IsoflowError, match=f"^label_table_blocks: array .*: {re.escape(said)}$"):
        label_table_blocks(store, layers=[2, 2])
    run = isoflow_here("info", tmp_path / "img.zarr", "--labels")
    assert run.returncode == 2 and run.stderr.count("\n") == 1, run.stderr
    assert f"{tmp_path / 'img.zarr'}: {said}" in run.stderr and "label_table_blocks" not in run.stderr, run.stderr


@pytest.mark.parametrize("unit", ["bad", 5])
def test_write_volume_names_the_unit_refused(unit, tmp_path):
    """write_volume's refusal of a unit began with the output file's name,
    as if the file were at fault; write_labels's begins with the function."""
    with pytest.raises(IsoflowError, match=f"^{re.escape(f'write_volume: unit {unit!r} is not a length unit')}"):
        isoflow.write_volume(np.ones((2, 2, 2), bool), tmp_path / "v.nii.gz", unit=unit)
    assert not any(tmp_path.iterdir())


@pytest.mark.parametrize("call", ["analyze_chunked", "write_surface_blocks"])
def test_a_chunked_label_image_is_refused_naming_the_function_called(call, tmp_path):
    """analyze_chunked(dask labels) said "dask array: not a binary volume
    ...", write_surface_blocks "volume: ...": each begins with the function
    called, then its argument; where= still names the input."""
    da = pytest.importorskip("dask.array")
    from isoflow.mesh.surface_blocks import write_surface_blocks

    labels = np.zeros((4, 4, 4), np.uint8)
    labels[1, 1, 1] = 2
    run = {"analyze_chunked": lambda a, **k: isoflow.analyze_chunked(a, **k),
           "write_surface_blocks": lambda a, **k: write_surface_blocks(a, tmp_path / "s.ply", **k)}[call]
    with pytest.raises(IsoflowError, match=f"^{call}: array: not a binary volume"):
        run(da.from_array(labels, chunks=2))
    with pytest.raises(IsoflowError, match="^seg.zarr: not a binary volume"):
        run(da.from_array(labels, chunks=2), where="seg.zarr")
    assert not any(tmp_path.iterdir())


def _cube_manifold():
    m3 = pytest.importorskip("manifold3d")
    return m3.Manifold.cube()


def _saved(folder: Path, mesh=None) -> Path:
    path = folder / "box.stl"
    (mesh or _box()).export(path)
    return path


@pytest.mark.parametrize(("name", "call", "words"), REFUSALS, ids=[f"{n}-{w.strip(': ')[:24]}" for n, _, w in REFUSALS])
def test_a_refusal_begins_with_the_function_called(name, call, words, tmp_path):
    pytest.importorskip("trimesh")
    if name in ("voxelize_to_zarr", "analyze_zarr"):
        pytest.importorskip("zarr")
    assert name in isoflow.__all__
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a note on the mesh read is no refusal
        with pytest.raises(IsoflowError) as info:
            call(tmp_path)
    message = str(info.value)
    # a file or a mesh the refusal is about comes first, as "box.stl: voxelize_file: ..."
    about = {"voxelize_file": f"{tmp_path / 'box.stl'}: ", "voxelize_to_zarr": "mesh: "}.get(name, "")
    if name == "voxelize_meshes" and "mesh is not watertight" in words:
        about = "mesh 1: "
    assert message.startswith(f"{about}{name}{words}") and "\n" not in message, message
    # the refused writers wrote nothing
    assert not any(tmp_path.glob("[lvs].*"))


@pytest.mark.parametrize(("name", "call", "words"), [r for r in REFUSALS if r[0].startswith("voxelize")])
def test_a_shared_refusal_keeps_the_command_lines_words(name, call, words, tmp_path):
    # the command line prints command_line: the voxelize command's name where the function's stands in Python
    pytest.importorskip("trimesh")
    if name == "voxelize_to_zarr":
        pytest.importorskip("zarr")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(IsoflowError) as info:
            call(tmp_path)
    command_line = info.value.command_line or str(info.value)
    assert name not in command_line.replace("voxelize_mesh(", "")
    assert re.search(r"(^|: )voxelize: ", command_line), command_line
    assert "--pitch 1e-300 needs" in command_line if "pitch=" in words else f"voxelize{words}" in command_line


def test_the_command_line_still_names_the_command(tmp_path):
    # what a user of the shell reads is unchanged: the command and its options
    import subprocess
    import sys

    path = _saved(tmp_path, _open_box())
    done = subprocess.run([sys.executable, "-m", "isoflow", "voxelize", str(path), "-o", str(tmp_path / "v.npy"),
                           "--pitch", "0.5", "--strict"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    assert done.stderr.startswith(f"isoflow voxelize: error: {path}: voxelize: mesh is not watertight: 3 boundary edges")
    assert not (tmp_path / "v.npy").exists()
