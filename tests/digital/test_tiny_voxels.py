"""Voxel sizes whose products leave float64 on the way: the volume and
area that float64 holds are given, and one below its smallest number is
0 with a warning, not silently."""

import warnings

import numpy as np
import pytest

import isoflow
from isoflow.errors import IsoflowWarning


def cube(ndim: int = 3) -> np.ndarray:
    v = np.zeros((4,) * ndim, bool)
    v[(slice(1, 3),) * ndim] = True  # 2^ndim voxels
    return v


def test_a_volume_that_float64_holds_is_given_whatever_each_voxel_size():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # 8 voxels of 1e-200 x 1e-200 x 1e200: 8e-200, though 1e-200 * 1e-200 is 0 in float64
        r = isoflow.analyze(cube(), pitch=(1e-200, 1e-200, 1e200))
        assert r.volume == pytest.approx(8e-200, rel=1e-12)
        # 8 x (1e-108)^3 = 8e-324: a subnormal, the float nearest to it
        assert isoflow.analyze(cube(), pitch=1e-108).volume == float("8e-324") > 0
        table = isoflow.label_table(cube().astype(np.uint8), pitch=(1e-200, 1e-200, 1e200))
        assert table["volume"][0] == pytest.approx(8e-200, rel=1e-12)
        # the faces of the 2x2x2 cube: 8 across each axis, of 1e-200 x 1e200 (= 1) or 1e-400 (0)
        assert table["surface_area"][0] == pytest.approx(16.0, rel=1e-12)


@pytest.mark.parametrize("ndim", [2, 3])
def test_a_volume_below_float64_is_zero_with_a_warning(ndim):
    with pytest.warns(IsoflowWarning, match=r"below float64's smallest number .* voxel size \(1e-200"):
        r = isoflow.analyze(cube(ndim), pitch=1e-200)
    assert (r.volume if ndim == 3 else r.area) == 0.0
    with pytest.warns(IsoflowWarning, match=r"of labels are below float64's smallest number .* \(1e-300"):
        table = isoflow.label_table(cube(ndim).astype(np.uint8), pitch=1e-300)
    assert table["volume" if ndim == 3 else "area"][0] == 0.0


def test_measures_of_ordinary_voxels_give_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = isoflow.analyze(cube(), pitch=(0.5, 0.5, 2.0))
    assert (r.volume, r.surface_area) == (8 * 0.5 * 0.5 * 2.0, 8 * (0.25 + 1.0 + 1.0))
