"""The solid angles summed in SIMD lanes: the arc tangent written out
against the C library's ``math.atan2``, and the winding numbers against
libigl's exact ``igl.winding_number``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from isoflow.mesh.solid_angles import atan2_lanes, winding_numbers
from isoflow.scale.jit import njit

igl = pytest.importorskip("igl")


@njit(cache=False)
def _atan2_all(y, x, out):
    for i in range(y.shape[0]):
        out[i] = atan2_lanes(y[i], x[i])


def test_atan2_lanes_matches_the_c_library_in_every_octant(rng):
    """Within 1e-15 (a few units in the last place) of ``math.atan2`` on a million arguments of every sign
    and ratio (octant borders, axes and tiny ratios included)."""
    y = rng.normal(size=1_000_000) * 10.0 ** rng.integers(-8, 8, 1_000_000)
    x = rng.normal(size=1_000_000) * 10.0 ** rng.integers(-8, 8, 1_000_000)
    y[:1000], x[:1000] = x[:1000], x[:1000]  # |y| = |x|: the octant's border
    y[1000:2000] = 0.0
    x[2000:3000] = 0.0
    x[3000:4000] = -np.abs(x[3000:4000])  # the branch cut's side
    out = np.empty_like(y)
    _atan2_all(y, x, out)
    ref = np.array([math.atan2(a, b) for a, b in zip(y.tolist(), x.tolist())])
    assert np.abs(out - ref).max() < 1e-15


def test_winding_numbers_match_libigl_on_soups(rng):
    """Random soups at random points: the lanes' sum equals libigl's exact
    winding number to 1e-12, and points on a triangle's plane are flagged."""
    for n in (1, 7, 100):
        T = rng.random((n, 3, 3))
        P = rng.random((500, 3)) * 1.4 - 0.2
        w, flagged = winding_numbers(P, T, tol=1e-9)
        v, f = T.reshape(-1, 3), np.arange(3 * n).reshape(n, 3)
        ref = igl.winding_number(v, f, P)
        assert np.abs(w - ref).max() < 1e-12
        assert not flagged.any()
    T = np.array([[[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]])
    w, flagged = winding_numbers(np.array([[0.2, 0.2, 0.0], [0.2, 0.2, 1.0]]), T, tol=1e-9)
    assert flagged.tolist() == [True, False]
