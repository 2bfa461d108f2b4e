"""How far the cap tree's rigorous remainder is from the true error on a
mesh whose boundary runs through its whole volume (issue 24's last
target, libigl's ``cube_40k.obj`` in kind), and what libigl's approximate
``fast_winding_number`` costs on the same grid.

    python benchmarks/winding_remainder.py [--res 32] [--points 300] [--igl 32 64 128]

The tetrahedral quads of ``benchmarks/generated.py`` are capped by
themselves reversed (:func:`isoflow.mesh.winding.close_mesh`: 74,000
triangles or so). At ``--points`` random voxel centres of a ``--res``
grid, :func:`isoflow.mesh.captree.evaluate` gives the far-field model at
several ``theta`` with its bound; ``theta = 0`` is the exact sum. Printed
per theta: the cost per centre, the median bound, the largest true error,
and the share of centres the bound decides (the bound below the distance
of the exact value to the nearest half-integer). A bound that counts area
without the cancellation of the cap's layers decides few of them.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from generated import tet_quads  # noqa: E402

from isoflow.mesh.captree import MAX_NEAR, CapTree, evaluate  # noqa: E402
from isoflow.mesh.load import boundary_chain  # noqa: E402
from isoflow.mesh.winding import close_mesh  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--res", type=int, default=32)
    ap.add_argument("--points", type=int, default=300)
    ap.add_argument("--igl", type=int, nargs="*", default=[32, 64], help="grids for libigl's fast_winding_number")
    args = ap.parse_args()
    v, f = tet_quads()
    cap = close_mesh(v, f, *boundary_chain(f, len(v)))
    tree = CapTree(cap.T, cap.E, cap.owner)
    print(f"cap: {len(cap.T)} triangles, chain of {len(cap.E)} edges")
    pitch = 2.0 / args.res
    centres = -1 + pitch * (np.random.default_rng(0).integers(0, args.res, (args.points, 3)) + 0.5)
    scratch = (np.empty(64, np.int64), np.empty(MAX_NEAR, np.int64), np.empty(MAX_NEAR, np.int64),
               np.empty((6 * MAX_NEAR, 2, 3)), np.empty(4))
    tol = 1e-6 * pitch

    def model(p, theta):
        return evaluate(p[0], p[1], p[2], 0.0, tol, theta, tol, *tree.arrays(), *scratch)

    model(centres[0], 0.3)
    exact = np.array([model(p, 0.0)[0] for p in centres])
    on_cap = np.array([model(p, 0.0)[4] for p in centres]) != 0  # within tol of a triangle: left to the tie rule
    margin = np.abs(np.abs(exact - np.round(exact)) - 0.5)[~on_cap]
    print(f"distance of w_C to the nearest half-integer: quantiles 5/10/25/50 % "
          f"{np.round(np.quantile(margin, [0.05, 0.1, 0.25, 0.5]), 3).tolist()}")
    for theta in (0.5, 0.3, 0.2, 0.1, 0.05, 0.0):
        t = time.process_time()
        got = [model(p, theta) for p in centres[~on_cap]]
        cost = (time.process_time() - t) / max(1, len(got))
        bound = np.array([g[1] for g in got])
        err = np.abs(np.array([g[0] for g in got]) - exact[~on_cap])
        print(f"theta {theta}: {cost * 1e6:.0f} us a centre, median bound {np.median(bound):.3g}, "
              f"largest true error {err.max():.2g}, decided {(bound < margin).mean():.0%}")
    try:
        import igl
    except ImportError:
        return 0
    for res in args.igl:
        axis = -1 + 2.0 / res * (np.arange(res) + 0.5)
        q = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), -1).reshape(-1, 3)
        t = time.perf_counter()
        igl.fast_winding_number(v, f, q)
        print(f"libigl fast_winding_number at {res} across: {time.perf_counter() - t:.2f} s wall")
    return 0


if __name__ == "__main__":
    sys.exit(main())
