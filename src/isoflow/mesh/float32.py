"""What float32 does to positions: a binary STL's coordinates, which
:mod:`isoflow.mesh.export` writes, and the slack of their read-back in
:mod:`isoflow.mesh.readback`. Here, below both, because the writer reads
its files back: readback taking it from export would be an import cycle.
"""

from __future__ import annotations

import numpy as np


def float32_effect(xyz: np.ndarray, spacing) -> dict:
    """What storing the positions ``xyz`` (world units, voxel size
    ``spacing``) as float32 does to them.

    Parameters
    ----------
    xyz : ndarray, shape (N, 3)
        Positions, float64.
    spacing : array_like
        Voxel size per axis.

    Returns
    -------
    dict
        ``positions``: distinct positions; ``merged``: how many of them
        float32 makes equal to another (0: a reader's weld of equal
        positions gives the same surface back); ``finite``: whether every
        coordinate stays within float32's range; ``moved``: the largest
        change of a coordinate, and ``moved_voxels`` in voxels of its axis;
        ``largest``: the largest coordinate magnitude, and ``step``:
        float32's spacing there.

    Examples
    --------
    >>> import numpy as np
    >>> e = float32_effect(np.array([[1e6, 0, 0], [1e6 + 0.1, 0, 0]]), 0.1)
    >>> e["merged"], e["moved"] <= e["step"] / 2, e["step"]
    (0, True, 0.0625)
    """
    xyz = np.asarray(xyz, np.float64).reshape(-1, 3)
    with np.errstate(over="ignore", invalid="ignore"):
        xyz32 = xyz.astype(np.float32)
    finite = bool(np.all(np.isfinite(xyz32)))
    largest = float(np.max(np.abs(xyz))) if len(xyz) else 0.0
    step = float(np.spacing(np.float32(min(largest, float(np.finfo(np.float32).max)))))
    positions = len(np.unique(xyz, axis=0)) if len(xyz) else 0
    if not finite:
        return {"positions": positions, "merged": None, "finite": False, "moved": None, "moved_voxels": None,
                "largest": largest, "step": step}
    change = np.abs(xyz32.astype(np.float64) - xyz)
    moved = float(change.max()) if len(xyz) else 0.0
    moved_voxels = float((change / np.asarray(spacing, np.float64)).max()) if len(xyz) else 0.0
    merged = positions - (len(np.unique(xyz32, axis=0)) if len(xyz) else 0)
    return {"positions": positions, "merged": int(merged), "finite": True, "moved": moved,
            "moved_voxels": moved_voxels, "largest": largest, "step": step}
