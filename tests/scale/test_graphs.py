"""Components of an edge list against scipy's connected_components."""

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from isoflow.scale.graphs import components


def _scipy(n, a, b):
    return connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)), directed=False)


@pytest.mark.parametrize("seed", range(12))
def test_components_number_and_label_as_scipy_does(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 4000))
    m = int(rng.integers(0, 2 * n))
    a, b = rng.integers(0, n, m), rng.integers(0, n, m)
    if seed % 3 == 0:  # long paths in a shuffled order: deep trees to halve
        perm = rng.permutation(n)
        a, b = np.r_[a[: m // 4], perm[:-1]], np.r_[b[: m // 4], perm[1:]]
    count, labels = components(n, a, b)
    want_count, want = _scipy(n, a, b)
    assert count == want_count
    assert labels.dtype == np.int64 and np.array_equal(labels, want)


def test_no_edges_and_no_nodes():
    count, labels = components(3, np.zeros(0, np.int64), np.zeros(0, np.int64))
    assert count == 3 and labels.tolist() == [0, 1, 2]
    assert components(0, np.zeros(0, np.int64), np.zeros(0, np.int64))[0] == 0
