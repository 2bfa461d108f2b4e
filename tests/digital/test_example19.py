"""Example 19 of the paper (eqs. 5.19-5.21), read from its 20 points."""

from pathlib import Path

import numpy as np

from isoflow import DigitalObject, analyze, read_object

ROOT = Path(__file__).resolve().parents[2]


def test_example_19_from_its_twenty_points():
    obj = read_object(ROOT / "meshes" / "example19.txt")
    assert obj.voxels == 4
    # a corner cube and its three face neighbours
    assert sorted(map(tuple, np.argwhere(obj.volume))) == [(0, 0, 0), (0, 0, 1), (0, 1, 0), (1, 0, 0)]
    r = analyze(obj)
    assert r["n"] == [0, 0, 0, 0, 0, 13, 3, 3, 1]
    assert r["a_dot_n"] == 8
    assert r["energy"] == 20
    assert r["betti"] == [1, 0, 0]


def test_point_model_needs_all_eight_corners():
    corners = np.array(list(np.ndindex(2, 2, 2)))
    assert DigitalObject.from_points(corners).voxels == 1
    assert DigitalObject.from_points(corners[:7]).voxels == 0
