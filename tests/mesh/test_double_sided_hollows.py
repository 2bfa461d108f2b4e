"""Models drawn double-sided whose outline has hollows: the sheets of pairs
that no edge decides are decided by rays (``census.one_face_per_pair``).

The models are the boundary of a union of unit cubes (each exposed unit
square two triangles, facing out), with every face, or a share of them,
also written reversed: no face of them is a wall between solids, so every
pair is read as one face and the solid is the union, which NumPy gives
independently (the cells, each 4^3 voxels at a pitch of a quarter).
"""

from __future__ import annotations

import numpy as np
import pytest
from in_process import isoflow_here


def union_faces(voxels: np.ndarray, doubled: float = 1.0, first: bool = False,
                seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Corners and faces of the boundary of the union of the unit cubes at
    ``voxels``: each unit square between a cell and an empty one (or the
    outside) as two triangles, cut along the diagonal through its lowest
    corner, counter-clockwise seen from outside; then the share
    ``doubled`` of them (drawn by ``seed``) also written reversed, after
    the others (``first``: before them)."""
    corners: dict[tuple, int] = {}
    faces = []
    n = np.array(voxels.shape)
    for cell in np.argwhere(voxels):
        for axis in range(3):
            for side in (0, 1):
                beside = cell.copy()
                beside[axis] += 1 if side else -1
                if np.all(beside >= 0) and np.all(beside < n) and voxels[tuple(beside)]:
                    continue
                u, w = [a for a in range(3) if a != axis]
                quad = []
                for du, dw in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = cell.copy()
                    p[axis] += side
                    p[u] += du
                    p[w] += dw
                    quad.append(tuple(int(c) for c in p))
                if (side == 1) != ((axis, u, w) in ((0, 1, 2), (1, 2, 0), (2, 0, 1))):
                    quad = quad[::-1]
                low = min(range(4), key=lambda i: quad[i])
                a, b, c, d = (corners.setdefault(quad[(low + i) % 4], len(corners)) for i in range(4))
                faces += [(a, b, c), (a, c, d)]
    f = np.array(faces, dtype=np.int64)
    back = f[np.random.default_rng(seed).random(len(f)) < doubled][:, ::-1]
    return np.array(list(corners), dtype=np.float64), np.concatenate([back, f] if first else [f, back])


def model(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).random((n, n, n)) < 0.5


def write_obj(path, v: np.ndarray, f: np.ndarray) -> None:
    lines = [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in v] + [f"f {a} {b} {c}" for a, b, c in f + 1]
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize(("n", "seed", "doubled", "first"), [(3, 0, 1.0, False), (4, 96, 1.0, False), (5, 25, 1.0, True),
                                                             (5, 39, 1.0, False), (4, 96, 0.3, True), (5, 25, 0.7, False)])
def test_union_drawn_double_sided_voxelises_as_the_union(tmp_path, n, seed, doubled, first):
    """Random 3^3 ... 5^3 models without cavities, every face (or 30-70 %
    of them) also written reversed: the command gives the union, 4^3 voxels
    per cell.  With every face so written, sheets of pairs in hollows of
    the outline that no edge decides were taken for walls, the first of
    them and those that follow (64 of the 3^3 model's 1,728 voxels wrong,
    64 of the 4^3's, 64 of each 5^3's)."""
    voxels = model(n, seed)
    v, f = union_faces(voxels, doubled, first, seed)
    path, out = tmp_path / "model.obj", tmp_path / "model.npz"
    write_obj(path, v, f)
    r = isoflow_here("voxelize", str(path), "--pitch", "0.25", "-o", str(out), "-q")
    assert r.returncode == 0, r.stderr
    lo, hi = np.argwhere(voxels).min(axis=0), np.argwhere(voxels).max(axis=0) + 1
    expected = np.kron(voxels[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]], np.ones((4, 4, 4), bool))
    assert np.array_equal(np.load(out)["volume"], expected)


@pytest.mark.parametrize(("n", "seed", "turn"), [(3, 0, 2), (4, 13, 0), (5, 0, 1)])
def test_turned_union_drawn_double_sided_has_no_walls(n, seed, turn):
    """The same models turned (no face in a plane of the bounding box, so
    the rays start off the faces' planes and cross faces at any angle),
    moved off the origin: the surface has no wall, and every pair is read
    as one face (12, 76 and 48 pairs were taken for walls)."""
    from scipy.spatial.transform import Rotation

    from isoflow.mesh.census import one_face_per_pair

    voxels = model(n, seed)
    v, f = union_faces(voxels)
    turned = v @ Rotation.random(random_state=turn).as_matrix().T + [3.5, -1e3, 0.1]
    kept, pairs = one_face_per_pair(turned, f)
    assert pairs == len(f) // 2 and len(kept) == len(f) // 2
