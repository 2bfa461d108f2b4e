"""Meshes the winding-number benchmarks generate instead of downloading.

* :func:`random_soup`: triangles with corners uniform in the unit cube, no
  two sharing a corner (every edge a boundary edge): the "100-triangle
  random soup" of issue 24.
* :func:`tet_quads`: the cells of an n x n x n grid cut into six
  tetrahedra each (Kuhn's triangulation), every tetrahedron written as one
  quad (its corners in a random order), which trimesh splits into two
  triangles. At n = 20 this is libigl's tutorial ``cube_40k.obj`` in
  kind: 96,000 faces on 9,261 vertices, tens of thousands of non-manifold
  edges and about 1,200 boundary edges (the file has 55,580 and 1,340; its
  tetrahedra come from another mesher). A surface whose boundary runs
  everywhere through its volume.

    python benchmarks/generated.py OUT_DIR     # writes soup100.obj and cube_40k_like.obj
"""

from __future__ import annotations

import itertools
import sys
from pathlib import Path

import numpy as np


def random_soup(n: int = 100, seed: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """n triangles with corners uniform in [0, 1]^3: (3n, 3) vertices, (n, 3) faces."""
    v = np.random.default_rng(seed).random((3 * n, 3))
    return v, np.arange(3 * n).reshape(n, 3)


def tet_quads(n: int = 20, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The faces of :func:`tet_quads`'s tetrahedra as trimesh reads them:
    ((n + 1)^3, 3) vertices on [-1, 1]^3, (12 n^3, 3) faces."""
    idx = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)
    axis = np.linspace(-1, 1, n + 1)
    v = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
    cells = np.array(list(itertools.product(range(n), repeat=3)))
    tets = []
    for order in itertools.permutations(range(3)):  # a path from a cell's low corner to its high one
        corner = cells.copy()
        path = [corner]
        for ax in order:
            corner = corner.copy()
            corner[:, ax] += 1
            path.append(corner)
        tets.append(np.stack([idx[c[:, 0], c[:, 1], c[:, 2]] for c in path], axis=1))
    tets = np.concatenate(tets)
    rng = np.random.default_rng(seed)
    tets = np.take_along_axis(tets, np.argsort(rng.random(tets.shape), axis=1), axis=1)
    return v, np.concatenate([tets[:, [0, 1, 2]], tets[:, [2, 3, 0]]])


def write_obj(path: Path, v: np.ndarray, f: np.ndarray) -> Path:
    """An OBJ file of triangles (positions written with repr: exact)."""
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in f.tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)
    print(write_obj(out / "soup100.obj", *random_soup()))
    print(write_obj(out / "cube_40k_like.obj", *tet_quads()))
