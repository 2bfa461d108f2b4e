"""Write the generated meshes that the fills' tests and benchmark read
(beside this script, in tests/mesh/data/; isoflow's own, under its
licence):

* ``chair_double_sided.obj``: a chair as furniture exports write it: thin
  boxes (a seat cushion 0.6 thick, four legs 0.6 wide, at 128 voxels
  across) and zero-thickness panels (a back, a shelf between the legs),
  every part with its own vertices and every face written twice, once each
  way.  Its bounding box is [-0.3, 59.3] x [-0.3, 59.3] x [-0.5, 127.5],
  so at 128 voxels across the voxel centres are the integer points, where
  trimesh's ``voxelized(1.0)`` puts them too, and every face but the
  legs' feet lies 0.2 to 0.4 of a voxel from a plane between voxels.
* ``panel.obj``: one zero-thickness square panel, single-sided.
* ``soup.obj``: 100 random triangles in the unit cube (every triangle its
  own boundary), seeded.

Run from the repository root::

    python tests/mesh/data/make_thin_models.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def box(lo, hi):
    """Corners and outward triangles of the box [lo, hi]."""
    import trimesh

    b = trimesh.creation.box(bounds=np.array([lo, hi], dtype=float))
    return np.asarray(b.vertices), np.asarray(b.faces)


def panel(corner, a, b):
    """A parallelogram ``corner + s a + t b`` (0 <= s, t <= 1) as two triangles."""
    c = np.asarray(corner, dtype=float)
    v = np.array([c, c + a, c + np.asarray(a) + b, c + b], dtype=float)
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def chair():
    """The parts of the chair (see the module docs)."""
    parts = [box([-0.3, -0.3, 50.3], [59.3, 59.3, 50.9])]  # the seat cushion
    for x in ((-0.3, 0.3), (58.7, 59.3)):
        for y in ((-0.3, 0.3), (58.7, 59.3)):
            parts.append(box([x[0], y[0], -0.5], [x[1], y[1], 50.3]))  # a leg
    parts.append(panel([-0.3, 57.3, 50.9], [59.6, 0, 0], [0, 0, 76.6]))  # the back
    parts.append(panel([0.3, 0.3, 20.4], [58.4, 0, 0], [0, 58.4, 0]))  # a shelf
    return parts


def join(parts, double_sided: bool):
    """One vertex and face list, each part keeping its own vertices; with
    ``double_sided`` every face also written reversed, right after."""
    vs, fs, n = [], [], 0
    for v, f in parts:
        vs.append(v)
        f = f + n
        fs.append(np.stack([f, f[:, ::-1]], axis=1).reshape(-1, 3) if double_sided else f)
        n += len(v)
    return np.concatenate(vs), np.concatenate(fs)


def write_obj(path: Path, v, f, comment: str) -> None:
    text = f"# {comment}\n"
    text += "".join(f"v {x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in v)
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
    path.write_text(text)


def main() -> None:
    out = Path(__file__).resolve().parent
    write_obj(out / "chair_double_sided.obj", *join(chair(), True),
              "a chair of boxes and zero-thickness panels, every face written twice (isoflow, "
              "tests/mesh/data/make_thin_models.py)")
    write_obj(out / "panel.obj", *join([panel([0, 0, 0.3], [1, 0, 0], [0, 1, 0])], False),
              "one zero-thickness square panel (isoflow, tests/mesh/data/make_thin_models.py)")
    rng = np.random.default_rng(24)
    corners = rng.random((100, 3, 3))
    write_obj(out / "soup.obj", corners.reshape(-1, 3), np.arange(300).reshape(-1, 3),
              "100 random triangles in the unit cube, seed 24 (isoflow, tests/mesh/data/make_thin_models.py)")


if __name__ == "__main__":
    main()
