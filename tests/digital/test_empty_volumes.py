"""Volumes with an axis of length 0: answered at once, as an all-background
volume is, however long their other axes (no padded copy of them)."""

import math

import numpy as np
import pytest
from skimage.measure import euler_number

import isoflow

# a padded copy of this volume would take 2 TiB: the answers must not make one
LONG = (0, 1 << 20, 1 << 20)


def test_chi_and_betti_of_an_empty_volume_need_no_copy():
    assert isoflow.euler_characteristic(np.zeros(LONG, bool)) == euler_number(np.zeros((0, 5, 5), bool)) == 0
    assert isoflow.betti_numbers(np.zeros(LONG, bool)) == [0, 0, 0]
    assert isoflow.betti_numbers(np.zeros((1 << 30, 0), bool), 8) == [0, 0]
    assert isoflow.betti_numbers(np.zeros((1 << 16, 0, 1 << 16, 3), bool)) == [0, None, None, 0]


@pytest.mark.parametrize("shape", [LONG, (1 << 21, 1 << 21, 0), (0, 1 << 40)])
def test_histogram_of_an_empty_volume_counts_every_vertex_as_background(shape):
    hist = isoflow.configuration_histogram(np.zeros(shape, bool))
    # every vertex of the lattice, prod(s + 1) of them, sees only background
    assert int(hist[0]) == math.prod(s + 1 for s in shape)
    assert not hist[1:].any()


def test_analyze_of_an_empty_volume_is_that_of_a_small_one():
    big = isoflow.analyze(np.zeros(LONG, bool)).to_dict()
    small = isoflow.analyze(np.zeros((0, 3, 4), bool)).to_dict()
    assert big["betti"] == small["betti"] == [0, 0, 0]
    assert big["euler_characteristic"] == small["euler_characteristic"] == 0
    assert big["surfaces"] == small["surfaces"] == []
    assert big["voxels"] == big["a_dot_n"] == big["energy"] == 0
    assert big["volume"] == big["surface_area"] == 0.0


def test_surfaces_mesh_manifold_and_flow_of_an_empty_volume():
    census = isoflow.closed_surfaces(np.zeros(LONG, bool))
    assert census.surfaces == [] and census.betti_counts == (0, 0)
    assert int(census.hist[0]) == math.prod(s + 1 for s in LONG)
    mesh = isoflow.boundary_mesh(np.zeros(LONG, bool), 26)
    assert len(mesh.vertices) == len(mesh.faces) == 0 and mesh.connectivity == 26
    assert isoflow.to_manifold(np.zeros(LONG, bool)).is_empty()
    assert isoflow.flow_step(np.zeros(LONG, bool)) == isoflow.flow_step(np.zeros((2, 2, 2), bool))
    with pytest.raises(isoflow.IsoflowError, match="not valid in 3D"):
        isoflow.flow_step(np.zeros(LONG, bool), 5)
