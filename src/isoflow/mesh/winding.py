"""The generalised winding number (Jacobson et al. 2013) of voxel centres:
the rule for meshes that are open, non-manifold or inconsistently oriented.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import IsoflowError
from .grid import fmt_count
from .load import mesh_bbox

# Number of (point, triangle) pairs per chunk of the generalised winding
# number, and their bytes (about 25 float64 temporaries each).
GWN_CHUNK = 1 << 16
GWN_BYTES = 200

#: Largest ``resolution=`` accepted (voxels along the longest side).
MAX_RESOLUTION = 2**31 - 1
#: Largest number of (voxel centre, triangle) pairs the generalised winding
#: number (``allow_open=True`` on a mesh with holes) may evaluate: about three
#: minutes at the ~8 million pairs per second measured on a 2-core machine.
GWN_MAX_PAIRS = 1_500_000_000
_GWN_PAIRS_PER_S = 8e6


def winding_volume(v, f, origin, pitch, shape, progress):
    """Generalised winding number of every voxel centre (Jacobson et al. 2013).

    Sum over triangles of the signed solid angle (van Oosterom & Strackee
    1983), ``tan(Omega/2) = a.(b x c) / (|a||b||c| + (a.b)|c| + (b.c)|a| +
    (c.a)|b|)`` with a, b, c the corners relative to the point, divided by
    4 pi.  It equals the winding number on closed meshes and degrades
    gracefully across holes.  Cost is O(voxels x triangles) with memory held
    to ``GWN_CHUNK`` point-triangle pairs at a time: fine for grids of a few
    ten thousand voxels, slow beyond (:func:`isoflow.mesh.voxelize.voxelize` refuses more than
    ``GWN_MAX_PAIRS`` pairs up front).  ``progress`` is called after every
    chunk of points.
    """
    nx, ny, nz = shape
    xc = origin[0] + (np.arange(nx) + 0.5) * pitch
    yc = origin[1] + (np.arange(ny) + 0.5) * pitch
    zc = origin[2] + (np.arange(nz) + 0.5) * pitch
    pts = np.stack(np.meshgrid(xc, yc, zc, indexing="ij"), axis=-1).reshape(-1, 3)
    T = v[f]
    # structure of arrays: corner k, coordinate d -> (M,) contiguous
    C = [[np.ascontiguousarray(T[:, k, d]) for d in range(3)] for k in range(3)]
    m = len(f)
    out = np.empty(len(pts), dtype=np.float64)
    tstep = min(m, GWN_CHUNK)
    pstep = max(1, GWN_CHUNK // tstep)
    starts = range(0, len(pts), pstep)
    total = len(starts)
    for done, s in enumerate(starts, 1):
        q = pts[s:s + pstep]
        acc = np.zeros(len(q))
        for ts in range(0, m, tstep):
            sl = slice(ts, ts + tstep)
            a, b, c = ([Ck[d][None, sl] - q[:, d, None] for d in range(3)] for Ck in C)
            la = np.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])
            lb = np.sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2])
            lc = np.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
            det = (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2])
                   + a[2] * (b[0] * c[1] - b[1] * c[0]))
            den = (la * lb * lc
                   + (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * lc
                   + (b[0] * c[0] + b[1] * c[1] + b[2] * c[2]) * la
                   + (c[0] * a[0] + c[1] * a[1] + c[2] * a[2]) * lb)
            acc += np.arctan2(det, den).sum(axis=1)
        out[s:s + pstep] = acc * (2.0 / (4.0 * np.pi))
        if progress is not None:
            progress(done, total)
    return (np.abs(out) > 0.5).reshape(shape)


def _fmt_seconds(s: float) -> str:
    if s < 120:
        return f"{s:.0f} s"
    if s < 2 * 3600:
        return f"{s / 60:.0f} min"
    if s < 2 * 86400:
        return f"{s / 3600:.1f} h"
    return f"{s / 86400:.0f} days"


def check_winding_cost(v, f, shape, what, pitch, resolution):
    """Refuse a generalised winding number costing more than GWN_MAX_PAIRS
    (voxel centre, triangle) pairs, before any O(grid) work, saying what it
    would cost and the largest resolution (or smallest pitch) that fits."""
    m = len(f)
    nvox = shape[0] * shape[1] * shape[2]  # Python ints
    pairs = nvox * m
    if pairs <= GWN_MAX_PAIRS:
        return
    if m > GWN_MAX_PAIRS:
        hint = "the mesh alone has more triangles than that: close its holes"
    else:
        _, _, ext = mesh_bbox(v, f, "voxelize")
        rel = ext / float(ext.max())
        if resolution is not None:
            # voxels grow as the cube of the resolution: start from that
            # estimate and step down to one whose grid fits
            r = max(1, int(int(resolution) * (GWN_MAX_PAIRS / pairs) ** (1 / 3)) + 1)
            while r > 1 and math.prod(max(1, math.ceil(x * r * (1 - 1e-9))) for x in rel) * m > GWN_MAX_PAIRS:
                r -= 1
            hint = f"use a lower resolution (at most {r} here) or close the mesh's holes"
        else:
            p = pitch * (pairs / GWN_MAX_PAIRS) ** (1 / 3)
            hint = f"use a larger pitch (about {p * 1.01:.3g} or more) or close the mesh's holes"
    dims = "x".join(fmt_count(n, sep=False) for n in shape)
    raise IsoflowError(
        f"voxelize: the generalised winding number for this open mesh at {what} would take "
        f"{dims} = {fmt_count(nvox)} voxels x {fmt_count(m)} triangles = {fmt_count(pairs)} "
        f"pairs, about {_fmt_seconds(pairs / _GWN_PAIRS_PER_S)} at ~{_GWN_PAIRS_PER_S / 1e6:.0f} "
        f"million pairs/s (limit {fmt_count(GWN_MAX_PAIRS)} pairs, a few minutes): {hint}")
