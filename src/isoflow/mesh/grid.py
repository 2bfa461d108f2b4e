"""The voxel grid laid over a mesh: pitch, origin and shape, and the memory
it needs.

Grid convention
---------------
Voxel ``(i, j, k)`` is the closed cube ``[origin + pitch*(i, j, k),
origin + pitch*(i+1, j+1, k+1)]`` and its centre is
``origin + pitch*(i + 0.5, j + 0.5, k + 0.5)``.  The grid is laid out from the
bounding box of the vertices the faces use, on every axis the same way::

    n_a      = max(1, ceil(extent_a / pitch))         (exactly R on the longest
                                                       axis for resolution=R)
    origin_a = centre_a - n_a * pitch / 2              (grid centred on the bbox)

so the grid always covers the bounding box, by less than one voxel of slack
per axis, split evenly on both sides.  With ``resolution=R`` the pitch is
``max(extent) / R``.  The returned volume is the whole grid: empty border
layers are **not** trimmed and no padding is added, so the shape depends only
on the bounding box and the pitch (reproducible, and ``origin`` keeps its
simple meaning).  Solids often touch the array border (an axis-aligned face
on the bounding box always has the outermost layer of centres inside); pad
with ``np.pad(volume, 1)`` and shift ``origin`` by ``-pitch`` before anything
that needs an empty frame (Euler numbers, connected components, surfaces).

Why centred: it is symmetric (a mesh and its mirror image give mirrored
volumes) and translation-invariant (the grid moves with the mesh).  Its one
bias: along an axis-aligned extent of e = (n - f) * pitch, 0 <= f < 1, all n
centred layers fall inside, so flat axis-aligned slabs gain up to one layer
(plate_holes.STL at 128 across: 6 layers for a plate 5.3 pitches thick,
+13 % volume).  Centre sampling has to round such a slab to 5 or 6 layers
either way; the test-suite checks generic shapes to 6 % of area * pitch.

Scale
-----
Results do not depend on the units: the grid arithmetic runs on the
coordinates multiplied by a power of two that brings the mesh to about unit
size (exact, see :func:`voxel_grid`), so a mesh at 1e-200 or 1e200 gives the voxels it
gives at 1, with no products underflowing to 0 or overflowing; the weld's
distances are taken the same way.  Only a mesh whose bounding-box extent
overflows the float range (coordinates near +-1.8e308 on both sides) is
refused.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import IsoflowError
from ..scale.memory import default_budget
from .load import mesh_bbox

#: Largest ``resolution=`` accepted (voxels along the longest side).
MAX_RESOLUTION = 2**31 - 1
#: ``pitch=`` may exceed the mesh's longest bounding-box side by at most this
#: factor (beyond it the whole mesh is far inside one voxel, and the rounding
#: error of the voxel centre, ~2**-53 pitch, nears the size of the mesh).
_MAX_PITCH_RATIO = 2.0**40


def fmt_count(n: int, sep: bool = True) -> str:
    """An exact integer (with thousands separators if ``sep``); scientific
    beyond 10^18.  Python ints: no overflow however large."""
    n = int(n)
    if n < 10**18:
        return f"{n:,}" if sep else str(n)
    from decimal import Decimal

    return format(Decimal(n), ".3e")  # exact rounding, no float conversion



def voxel_grid(v: np.ndarray, f: np.ndarray, pitch, resolution):
    """Pitch, origin and shape of the grid (see the module docstring), and the
    scaled frame the arithmetic runs in.

    Returns ``(pitch, origin, shape, what, frame)`` with
    ``frame = (shift, e, origin_s, pitch_s)``: the scanline and the
    generalised winding number work on coordinates ``ldexp(x - shift, -e)``,
    where ``2**e`` is the power of two just above the longest side of the
    bounding box (so the mesh spans about one unit), ``origin_s`` and
    ``pitch_s`` being the grid in those units.  ``shift`` is zero except on an
    axis where the mesh is flat and lies more than 2**60 sizes from zero (it
    would overflow).  Multiplying by a power of two is exact, and rounded
    sums, products and quotients commute with it (barring overflow and
    underflow), so every comparison the scanline makes is bit-for-bit the one
    the unscaled arithmetic makes wherever that neither overflows nor
    underflows: results at ordinary scales are unchanged, a mesh scaled by a
    power of two gives identical voxels, and one scaled by 1e-200 or 1e200
    (whose edge-function products would underflow to 0 or overflow) gives
    the voxels of the unscaled mesh up to the rounding of the scaling itself.
    """
    if (pitch is None) == (resolution is None):
        raise IsoflowError("voxelize: give exactly one of pitch= or resolution=")
    lo, hi, ext = mesh_bbox(v, f, "voxelize")
    longest = float(ext.max())
    if not longest > 0:
        raise IsoflowError("voxelize: mesh bounding box has zero size (all vertices coincide)")
    e = math.frexp(longest)[1]
    far_flat = (ext == 0) & (lo != 0)
    far_flat[far_flat] = np.frexp(lo[far_flat])[1] - e > 60
    shift = np.where(far_flat, lo, 0.0)
    lo_s, hi_s = np.ldexp(lo - shift, -e), np.ldexp(hi - shift, -e)
    ext_s = np.ldexp(ext, -e)
    if resolution is not None:
        if isinstance(resolution, (bool, np.bool_)) or not isinstance(
                resolution, (int, np.integer, float, np.floating)):
            raise IsoflowError(f"voxelize: resolution must be an integer >= 1, got {resolution!r}")
        if not (math.isfinite(resolution) and resolution == int(resolution)
                and 1 <= resolution <= MAX_RESOLUTION):
            raise IsoflowError(
                f"voxelize: resolution must be an integer from 1 to {MAX_RESOLUTION}, "
                f"got {resolution!r}")
        res = int(resolution)
        pitch_s = float(ext_s.max()) / res
        pitch = math.ldexp(pitch_s, e)
        what = f"resolution={res}"
        cells = ext_s / pitch_s
    else:
        try:
            pitch = float(pitch)
        except (TypeError, ValueError, OverflowError):
            raise IsoflowError(f"voxelize: pitch must be a positive number, got {pitch!r}") from None
        if not (math.isfinite(pitch) and pitch > 0):
            raise IsoflowError(f"voxelize: pitch must be a positive finite number, got {pitch!r}")
        if pitch > _MAX_PITCH_RATIO * longest:
            raise IsoflowError(
                f"voxelize: pitch={pitch!r} is more than 2**40 times the mesh's size (longest "
                f"bounding-box side {longest:.6g}): the whole mesh would lie inside one voxel")
        res = None
        pitch_s = math.ldexp(pitch, -e)  # may underflow: then the grid is refused as too big
        what = f"pitch={pitch!r}"
        with np.errstate(over="ignore"):
            cells = ext / pitch  # the exact quantities' ratio, correctly rounded
    shape = []
    for a in range(3):
        if resolution is not None and ext[a] == longest:
            n = res
        else:
            c = float(cells[a])
            if math.isfinite(c) and c < 2.0**53:
                # a relative 1e-9 guard so that an extent that is an exact
                # multiple of the pitch up to rounding does not gain a voxel,
                # but never dropping more than 1e-6 of a voxel of extent (a
                # huge c would otherwise lose whole layers)
                n = max(1, math.ceil(c * (1 - 1e-9)), math.ceil(c - 1e-6))
            else:  # the true count, in Python ints (it is refused as too big)
                from fractions import Fraction

                n = math.ceil(Fraction(float(ext[a])) / Fraction(pitch))
        shape.append(int(n))
    if max(shape) < 2**62:
        centre_s = (lo_s + hi_s) / 2
        origin_s = centre_s - np.asarray(shape, dtype=np.float64) * pitch_s / 2
    else:  # no such grid can be allocated: check_grid_memory refuses it
        origin_s = np.full(3, np.nan)
    with np.errstate(over="ignore", invalid="ignore"):
        origin = np.ldexp(origin_s, e) + shift
    return float(pitch), origin.astype(np.float64), tuple(shape), what, (shift, e, origin_s, pitch_s)


def check_grid_memory(shape, what, bytes_per_voxel: float, extra: int, max_bytes, hint: str = ""):
    """Refuse a grid whose volume (``bytes_per_voxel`` per voxel) and ``extra``
    bytes of temporaries exceed ``max_bytes`` (default: the memory budget),
    naming its size; ``hint`` says what to do instead."""
    if max_bytes is None:
        max_bytes = default_budget()
    nvox = shape[0] * shape[1] * shape[2]  # Python ints: no overflow
    if nvox < 2**53:
        need = int(nvox * bytes_per_voxel) + extra
    else:
        from fractions import Fraction

        need = int(nvox * Fraction(bytes_per_voxel)) + extra
    if need > max_bytes or nvox >= 2**62:
        limit = (f"more than max_bytes={fmt_count(max_bytes)}" if need > max_bytes
                 else "more than one array can index")
        dims = "x".join(fmt_count(n, sep=False) for n in shape)
        raise IsoflowError(
            f"voxelize: {what} needs a {dims} grid "
            f"({fmt_count(nvox)} voxels, about {fmt_count(need)} bytes), {limit}"
            + (f": {hint}" if hint else ""))
