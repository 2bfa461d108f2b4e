"""Unions of cubes with faces turned over at random: the orientation repair
(``orientation.orient_faces``) across edges of four faces and between
shells nested one in another.

The models are the boundary of a union of unit cubes at random cells (each
exposed unit square two triangles, facing out; cubes that touch only along
an edge give it four faces, only at a corner a vertex shared by two
sheets), with half the faces, drawn at random, turned over; or every face
written both ways in shuffled order. The solid is the union, which NumPy
gives independently (the cells, each 4^3 voxels at a pitch of a quarter).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
from in_process import isoflow_here

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_double_sided_hollows import union_faces, write_obj  # noqa: E402


def turned(n: int, seed: int, full: float, both: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cells (a share ``full`` of an n^3 grid), the corners and the
    faces: half of them turned over, or (``both``) each written both ways
    and shuffled."""
    voxels = np.random.default_rng(seed).random((n, n, n)) < full
    v, f = union_faces(voxels, 0.0)
    rng = np.random.default_rng(seed + 1000)
    if both:
        f = np.concatenate([f, f[:, ::-1]])
        return voxels, v, f[rng.permutation(len(f))]
    flip = rng.random(len(f)) < 0.5
    f[flip] = f[flip][:, ::-1]
    return voxels, v, f


def voxelised(tmp_path, v: np.ndarray, f: np.ndarray) -> np.ndarray:
    path, out = tmp_path / "model.obj", tmp_path / "model.npz"
    write_obj(path, v, f)
    r = isoflow_here("voxelize", str(path), "--pitch", "0.25", "-o", str(out), "-q")  # the voxels are tested, not the shell
    assert r.returncode == 0, r.stderr
    return np.load(out)["volume"]


def expected(voxels: np.ndarray) -> np.ndarray:
    lo, hi = np.argwhere(voxels).min(axis=0), np.argwhere(voxels).max(axis=0) + 1
    return np.kron(voxels[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]], np.ones((4, 4, 4), bool))


@pytest.mark.parametrize(("n", "seed", "full", "both"), [(3, 0, 0.5, False), (4, 0, 0.5, False), (5, 0, 0.5, False),
                                                         (5, 19, 0.5, False), (4, 13, 0.5, True), (3, 0, 0.5, True),
                                                         (6, 24, 0.85, False), (5, 37, 0.85, True)])
def test_union_with_faces_turned_at_random_voxelises_as_the_union(tmp_path, n, seed, full, both):
    """Half the faces turned over (or every face written both ways): the
    command gives the union, 4^3 voxels per cell.  Faces were joined only
    across edges of two faces, so the sheets between edges of four were
    oriented each by most of its area, at random (32 to 139 voxels wrong
    at half full); and a shell inside another, touching it nowhere (a
    cavity, at 85 % full), whose faces were half turned, was as likely to
    be wound as the shell round it, and filled (64 to 256 voxels)."""
    voxels, v, f = turned(n, seed, full, both)
    assert np.array_equal(voxelised(tmp_path, v, f), expected(voxels))


@pytest.mark.parametrize(("n", "seed", "full"), [(4, 0, 0.5), (5, 0, 0.5), (6, 24, 0.85)])
def test_turned_faces_are_oriented_so_that_every_edge_balances(n, seed, full):
    """What the repair gives is a consistently oriented surface: every
    edge run as often one way as the other, and the winding number of a
    point inside each cell (libigl's, from the repaired faces) is 1 or -1,
    of a point in an empty cell 0."""
    igl = pytest.importorskip("igl")
    from isoflow.mesh.orientation import orient_faces

    voxels, v, f = turned(n, seed, full, False)
    fixed, flipped = orient_faces(v, f)
    assert 0 < flipped < len(f)
    a, b = fixed.reshape(-1), fixed[:, [1, 2, 0]].reshape(-1)
    key = np.minimum(a, b) * len(v) + np.maximum(a, b)
    assert np.array_equal(np.bincount(np.unique(key, return_inverse=True)[1].reshape(-1), weights=np.where(a < b, 1, -1)),
                          np.zeros(len(np.unique(key))))
    cells = np.argwhere(np.ones(voxels.shape, bool)) + 0.5
    w = np.rint(igl.winding_number(v, fixed, cells)).astype(int)
    assert np.array_equal(np.abs(w) == 1, voxels.reshape(-1)) and set(np.unique(w)) <= {-1, 0, 1}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_shell_through_another_with_faces_turned_stays_a_solid(tmp_path, seed):
    """A bar through the side of a box, most of it inside, each a closed
    shell, the bar's faces turned over at random: rays from the bar's
    faces inside the box find the winding number of a second layer, yet
    the bar crosses the box, so it is no cavity: the union (NumPy's, from
    the boxes) stays whole."""
    trimesh = pytest.importorskip("trimesh")
    box, bar = trimesh.creation.box(bounds=[[0, 0, 0], [3, 3, 3]]), trimesh.creation.box(bounds=[[1, 1, 1], [3.5, 2, 2]])
    f = bar.faces.copy()
    flip = np.random.default_rng(seed).permutation(len(f))[:4]
    f[flip] = f[flip][:, ::-1]
    volume = voxelised(tmp_path, np.concatenate([box.vertices, bar.vertices]), np.concatenate([box.faces, f + 8]))
    centre = (np.indices((14, 12, 12)).reshape(3, -1).T + 0.5) * 0.25
    inside = np.all(centre < 3, axis=1) | (np.all(centre > 1, axis=1) & (centre[:, 0] < 3.5) & np.all(centre[:, 1:] < 2, axis=1))
    assert np.array_equal(volume.reshape(-1), inside)
