"""One rule for every integer argument of the Python API: a whole number
is taken as an ``int``, a NumPy integer or a whole float (``6.0``); a bool,
a float with a fraction (``6.5``), NaN, an infinity and text are refused in
one line naming the argument and the value.

``voxelize_mesh(..., resolution=8.0)`` was taken where ``analyze(x, 6.0)``
was refused ("connectivity 6.0 ... must be an integer"), and so were
``steps=2.0``, ``threads=2.0``, ``labels=[1.0]``, ``chi=0.0`` and
``time=1.0``. The expected values come from scikit-image (components,
Euler numbers) and from what a grid must hold (a box filling its grid).
"""

import re

import numpy as np
import pytest

import isoflow
from isoflow.errors import IsoflowError


def _edge_pair() -> np.ndarray:
    """Two voxels that share only an edge: two components under 6, one
    under 26 (scikit-image's label at connectivity 1 and 3)."""
    v = np.zeros((2, 2, 1), bool)
    v[0, 0, 0] = v[1, 1, 0] = True
    return v


def _tunnel() -> np.ndarray:
    """A 3x3x3 cube with a tunnel: one component, one tunnel, chi 0."""
    v = np.ones((3, 3, 3), bool)
    v[1, 1, :] = False
    return v


#: each public function that takes an integer argument, called with the
#: value given, and what it answers
CALLS = {
    "analyze connectivity": lambda c: isoflow.analyze(_edge_pair(), c)["betti"][0],
    "euler_characteristic connectivity": lambda c: isoflow.euler_characteristic(_edge_pair(), c),
    "label_table connectivity": lambda c: int(isoflow.label_table(_edge_pair().astype(np.uint8), c)["b0"][0]),
    "boundary_mesh connectivity": lambda c: len(isoflow.boundary_mesh(_edge_pair(), c).components()),
}


@pytest.mark.parametrize("name", sorted(CALLS))
@pytest.mark.parametrize("given", [6.0, np.float64(6), np.float32(26), 26.0, np.array(26.0)], ids=repr)
def test_a_whole_float_connectivity_is_that_connectivity(name, given):
    measure = pytest.importorskip("skimage.measure")
    v = _edge_pair()
    as_int = int(given)
    sk = {6: 1, 26: 3}[as_int]
    expected = (measure.label(v, connectivity=sk).max() if "euler" not in name
                else measure.euler_number(v, connectivity=sk))
    assert CALLS[name](given) == expected


@pytest.mark.parametrize("name", sorted(CALLS))
@pytest.mark.parametrize(("given", "shown"), [(6.5, "6.5"), (True, "True"), (np.True_, "True"),
                                              (float("nan"), "nan"), (float("inf"), "inf"), ("6", "'6'")])
def test_a_connectivity_that_is_no_whole_number_is_refused(name, given, shown):
    with pytest.raises(IsoflowError) as info:
        CALLS[name](given)
    assert str(info.value) == f"connectivity {shown} is not valid in 3D: it must be an integer (use 6 or 26)"


def test_whole_floats_for_counts_sizes_and_labels():
    trimesh = pytest.importorskip("trimesh")
    measure = pytest.importorskip("skimage.measure")
    box = trimesh.creation.box((2, 2, 2))
    # a box fills its whole grid: resolution 4 makes 4^3 voxels
    assert isoflow.voxelize_mesh(box, resolution=4.0).voxels == 4 ** 3
    assert isoflow.voxelize_mesh(box, resolution=np.float32(4)).voxels == 4 ** 3
    # steps=2.0 runs two steps: the record holds the start and two steps after it
    cube = np.ones((3, 3, 3), bool)
    run = isoflow.run_flow(cube, steps=2.0, connectivity=26.0)
    assert len(run.steps) == 3 and run.to_dict()["connectivity"] == 26
    assert type(run.to_dict()["connectivity"]) is int
    # chi given as 0.0: the tunnel's Betti numbers, b1 = b0 + b2 - chi (chi from scikit-image)
    tunnel = _tunnel()
    chi = measure.euler_number(tunnel, connectivity=1)
    assert isoflow.betti_numbers(tunnel, chi=float(chi)) == [1, 1, 0]
    # one label asked as 2.0 gives that label's voxels, a Python int in the table
    image = np.zeros((5, 5, 5), np.uint16)
    image[0:2, 0:2, 0:2], image[3:5, 3:5, 3:5] = 1, 2
    table = isoflow.label_table(image, labels=[2.0], threads=1.0)
    assert table["label"].tolist() == [2] and table["voxels"].tolist() == [np.count_nonzero(image == 2)]
    # the 2x2 window of configurations: 2^4 entries
    assert len(isoflow.euler_lut(2.0)) == 2 ** 4
    assert int(isoflow.configuration_histogram(cube, slab=1.0).sum()) == 4 ** 3  # one per lattice vertex


@pytest.mark.parametrize(("call", "words"), [
    (lambda v: isoflow.voxelize_mesh(_trimesh_box(), resolution=v), "voxelize_mesh: resolution must be an integer from 1 "
                                                                     "to 2147483647, got {}"),
    (lambda v: isoflow.run_flow(np.ones((3, 3, 3), bool), steps=v), "steps must be an integer >= 0, got {}"),
    (lambda v: isoflow.analyze(np.ones((3, 3, 3), bool), threads=v), "threads must be a positive integer, got {}"),
    (lambda v: isoflow.betti_numbers(_tunnel(), chi=v), "chi must be an integer, got {}"),
    (lambda v: isoflow.label_table(np.ones((3, 3, 3), np.uint8), labels=[v]), "label_table: labels: label {} is not an integer"),
    (lambda v: isoflow.euler_lut(v), "ndim must be an integer 1..4, got {}"),
])
@pytest.mark.parametrize(("given", "shown"), [(2.5, "2.5"), (True, "True"), (float("nan"), "nan"), ("2", "'2'")])
def test_counts_sizes_and_labels_that_are_no_whole_number_are_refused(call, words, given, shown):
    pytest.importorskip("trimesh")
    with pytest.raises(IsoflowError, match=f"^{re.escape(words.format(shown))}"):
        call(given)


def test_a_time_point_given_as_a_whole_float_is_read(tmp_path):
    series = np.zeros((3, 3, 3, 2), np.uint8)
    series[1, 1, 1, 1] = 1
    np.save(tmp_path / "t.npy", series)
    assert np.array_equal(np.asarray(isoflow.read_labels(tmp_path / "t.npy", time=1.0).array), series[..., 1])
    with pytest.raises(IsoflowError, match=re.escape("time=0.5 is no time point of this time series of 2 (0 to 1)")):
        isoflow.read_labels(tmp_path / "t.npy", time=0.5)


def _trimesh_box():
    import trimesh

    return trimesh.creation.box()
