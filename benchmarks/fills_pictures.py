"""The picture of docs/fills.md: one model in the three fills.

The model is a signpost: a closed box (the post) and a zero-thickness
panel (the sign) fixed to it, voxelised at 20 across with ``fill="winding"``,
``"shell"`` and ``"flood"``, cut open at the middle of the post so that the
inside shows (voxels with x beyond the post's axis left out).

    PYTHONPATH=src python benchmarks/fills_pictures.py [docs/fills.png]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))


def signpost():
    """Vertices and faces: a 4 x 4 x 16 post and a 12 x 8 sign panel."""
    import trimesh

    post = trimesh.creation.box(bounds=[[0, 0, 0], [4, 4, 16]])
    v = np.concatenate([post.vertices, [[4, 2, 7], [16, 2, 7], [16, 2, 15], [4, 2, 15]]])
    f = np.concatenate([post.faces, [[8, 9, 10], [8, 10, 11]]])
    return v, f


def main(argv=None) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from isoflow.mesh.voxelize import voxelize

    out = Path((argv or sys.argv[1:] or [str(ROOT / "docs" / "fills.png")])[0])
    v, f = signpost()
    fig = plt.figure(figsize=(12, 4.6))
    for n, fill in enumerate(("winding", "shell", "flood")):
        r = voxelize(v, f, resolution=20, fill=fill, details=True)
        vol = r.volume.copy()
        vol[int(round((2 - r.origin[0]) / r.pitch)):, :int(round((2 - r.origin[1]) / r.pitch))] = False  # cut open
        ax = fig.add_subplot(1, 3, n + 1, projection="3d")
        ax.voxels(vol, facecolors="#5b8bd0", edgecolor="#20344f", linewidth=0.3)
        ax.set_title(f'fill="{fill}": {r.voxels} voxels')
        ax.set_box_aspect(vol.shape)
        ax.view_init(elev=22, azim=-60)
        ax.set_axis_off()
    fig.suptitle("a closed post with a zero-thickness sign, 20 voxels across, cut open at the post's axis")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
