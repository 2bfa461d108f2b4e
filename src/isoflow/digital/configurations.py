"""Vertex configurations: the 2^n cells around every lattice vertex.

Section 4 of the paper reads the curvature of a digital surface off the
3x3x3 neighbourhood of a boundary point. With voxels as unit cubes (Definition
1: a "digital 3-simplex" is the cube spanned by 8 lattice points), the same
information sits in the 2x2x2 block of voxels around each lattice vertex: the
vertex's *configuration*.

Conventions used everywhere in isoflow:

* voxel ``v`` (an index into the array) is the closed unit cube ``[v, v+1]``;
* lattice vertex ``w`` is the common corner of the cells ``w - 1 + d`` for
  ``d`` in ``{0,1}^n``, its *octants*;
* octant ``d`` is bit ``d_0 + 2 d_1 + 4 d_2`` of the configuration (axis 0 is
  the array's first axis);
* an array of shape ``S`` has vertices ``0 .. S`` on every axis (the volume is
  padded with one layer of background), so the configuration array has shape
  ``S + 1``.

Everything here is array in / array out; the lookup tables over all 256 (3D)
or 16 (2D) configurations are derived in :mod:`isoflow.digital.indices` from the
geometry of the window, never typed in.
"""

from __future__ import annotations

import itertools
import math
from functools import lru_cache

import numpy as np

from ..scale import arrays
from ..scale.compiled import use_compiled

#: octant d -> its bit index, for the 3D window
OCTANTS_3D = [(dx, dy, dz) for dz in (0, 1) for dy in (0, 1) for dx in (0, 1)]
#: pixel d -> its bit index, for the 2D window
OCTANTS_2D = [(dx, dy) for dy in (0, 1) for dx in (0, 1)]


def octant_bit(d) -> int:
    """Bit index of octant ``d`` (a 0/1 tuple): ``d_0 + 2 d_1 + 4 d_2 + ...``."""
    return sum(int(b) << i for i, b in enumerate(d))


def configurations(volume) -> np.ndarray:
    """Configuration code of every lattice vertex of a 2D, 3D or 4D binary volume.

    Returns a uint8 (uint16 in 4D) array of shape ``volume.shape + 1``, in the input's array
    library (a CuPy volume gives a CuPy array on its GPU). Three passes (one
    per axis) build the code: first pairs along axis 0 (bits 0/1), then pairs
    of pairs along axis 1 (bits 0-3), then along axis 2 (bits 0-7), which is
    cheaper than or-ing the 8 shifted copies.
    """
    xp, v = arrays.as_volume(volume)
    # 8 octant bits up to 3D, 16 in 4D
    dtype = xp.uint8 if v.ndim <= 3 else xp.uint16
    # The one layer of background padding, written with the standard's
    # zeros + slice assignment (``pad`` is not in the array API).
    code = arrays.zeros(xp, tuple(s + 2 for s in v.shape), dtype, like=v)
    code[(slice(1, -1),) * v.ndim] = xp.astype(v, dtype)
    for axis in range(v.ndim):
        lo = [slice(None)] * v.ndim
        hi = [slice(None)] * v.ndim
        lo[axis] = slice(None, -1)
        hi[axis] = slice(1, None)
        code = code[tuple(lo)] | (code[tuple(hi)] << (1 << axis))
    return code


def configuration_histogram(volume, slab: int | None = None) -> np.ndarray:
    """Counts of the 2^(2^n) configurations over all vertices (256 in 3D).

    Always a host int64 vector. Large 3D host volumes go through the streaming
    kernel of :mod:`isoflow.scale.kernels`; otherwise (4D, and every device array:
    CuPy, any array-API library) the work goes slab by slab along axis 0, the
    slabs overlapping by one voxel layer so that every vertex is counted
    exactly once. A slab holds ``slab`` rows (default: about 8M voxels), so
    memory stays a few bytes per slab voxel whatever the volume.
    """
    xp, v = arrays.as_volume(volume)
    size = 1 << (1 << v.ndim)
    if v.ndim == 3 and use_compiled(v):
        from ..scale.kernels import histogram3d

        return histogram3d(v)
    if slab is None:
        row = math.prod(v.shape[1:])
        slab = max(1, (1 << 23) // max(row, 1))
    hist = np.zeros(size, dtype=np.int64)
    n0 = v.shape[0]
    with arrays.on_device(v):
        for start in range(0, max(n0, 1), slab):
            stop = min(start + slab, n0)
            # Vertices start..stop-1 (plus the last one n0 on the final slab)
            # need voxels start-1..stop-1; take them and drop the duplicated
            # vertex row.
            lo = max(start - 1, 0)
            part = configurations(v[lo:stop, ...])
            # part's vertex rows are lo .. stop; keep rows start .. stop-1,
            # and row n0 on the last slab.
            first = start - lo
            last = part.shape[0] if stop == n0 else part.shape[0] - 1
            hist += arrays.count_codes(xp, part[first:last, ...], size)
    return hist


@lru_cache(maxsize=None)
def cube_symmetries(ndim: int = 3) -> np.ndarray:
    """The ``2^n n!`` symmetries of the n-cube as permutations of the octant bits.

    Row ``g`` maps octant bit ``b`` to octant bit ``perm[g, b]``: every axis
    permutation combined with every set of reflections (48 in 3D, 8 in 2D).
    """
    octs = list(itertools.product((0, 1), repeat=ndim))
    perms = []
    for axes in itertools.permutations(range(ndim)):
        for flips in itertools.product((0, 1), repeat=ndim):
            row = [0] * (1 << ndim)
            for d in octs:
                image = tuple(d[axes[i]] ^ flips[i] for i in range(ndim))
                row[octant_bit(d)] = octant_bit(image)
            perms.append(row)
    return np.array(perms, dtype=np.int64)


@lru_cache(maxsize=None)
def configuration_symmetries(ndim: int = 3) -> np.ndarray:
    """The cube's symmetries acting on whole configurations.

    Row ``g`` maps configuration ``c`` to ``table[g, c]``; shape (48, 256) in
    3D and (8, 16) in 2D.
    """
    perms = cube_symmetries(ndim)
    nbits = 1 << ndim
    configs = np.arange(1 << nbits)
    bits = (configs[:, None] >> np.arange(nbits)) & 1  # (256, 8)
    out = np.zeros((len(perms), len(configs)), dtype=np.int64)
    for g, perm in enumerate(perms):
        out[g] = (bits << perm[None, :]).sum(axis=1)
    return out


def orbits(ndim: int = 3) -> np.ndarray:
    """Canonical representative (smallest image) of every configuration."""
    return configuration_symmetries(ndim).min(axis=0)


def transform_volume(volume: np.ndarray, g: int) -> np.ndarray:
    """Apply symmetry ``g`` of :func:`cube_symmetries` to a whole volume.

    Used by tests: the configuration of the transformed volume at the image
    vertex is the transformed configuration.
    """
    ndim = volume.ndim
    combos = [
        (axes, flips)
        for axes in itertools.permutations(range(ndim))
        for flips in itertools.product((0, 1), repeat=ndim)
    ]
    axes, flips = combos[g]
    # new axis i takes old axis axes[i], reflected when flips[i]
    out = np.transpose(volume, axes)
    for i, f in enumerate(flips):
        if f:
            out = np.flip(out, axis=i)
    return out
