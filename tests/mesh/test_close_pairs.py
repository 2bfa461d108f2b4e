"""Close pairs of points against scipy's cKDTree.query_pairs."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from isoflow.mesh.close_pairs import close_pairs


def _as_set(pairs):
    return set(map(tuple, np.sort(np.asarray(pairs), axis=1).tolist()))


@pytest.mark.parametrize("seed", range(16))
def test_close_pairs_are_the_kd_trees(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 3000))
    scale = float(rng.choice([1e-3, 1.0, 1e6]))
    p = rng.random((n, 3)) * scale + float(rng.choice([0.0, -5.0, 1e12]))
    some = rng.integers(0, n, n // 3)  # clusters within the distance
    p[some] = p[rng.integers(0, n, n // 3)] + rng.normal(size=(n // 3, 3)) * 1e-4 * scale
    if seed % 4 == 0:  # a lattice: many points on common planes and at exact distances
        p = np.round(p * 20 / scale) * scale / 20
    r = float(rng.choice([1e-3, 0.05, 0.1])) * scale
    got = close_pairs(p, r, cell=r * float(rng.choice([0.0, 1.0, 3.7, 100.0])))  # cells larger than r too
    assert got.dtype == np.int64 and np.all(got[:, 0] < got[:, 1])
    assert len(got) == len(_as_set(got))  # each pair once
    assert _as_set(got) == _as_set(cKDTree(p).query_pairs(r, output_type="ndarray"))


def test_far_coordinates_keep_exact_cells():
    """Coordinates 2**70 times the distance: cells grow, pairs stay exact."""
    p = np.array([[0.0, 0, 0], [1e-9, 0, 0], [2.0**70, 0, 0], [2.0**70, 0, 1e-9]])
    assert _as_set(close_pairs(p, 2e-9)) == _as_set(cKDTree(p).query_pairs(2e-9, output_type="ndarray"))
