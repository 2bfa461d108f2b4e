"""Solid voxelisation of triangle meshes: voxel in iff its centre is inside.

``voxelize(vertices, faces, ...)`` is array in, array out; ``voxelize_mesh``
and ``voxelize_file`` wrap it into a :class:`~isoflow.digital.lattice.DigitalObject`
that keeps the grid's pitch and origin, so its surfaces and flows export in
the mesh's coordinates. The grid is :mod:`isoflow.mesh.grid`; closed meshes
go through the exact scanline (:mod:`isoflow.mesh.scanline`), open ones
through the generalised winding number (:mod:`isoflow.mesh.winding`).

Why a winding number and not parity
-----------------------------------
Overlapping watertight solids (trimesh's ``rabbit.obj`` is nine intersecting
primitives) must give their union; with parity (even-odd) counting the
overlaps become holes.  The winding number of a point is +1 inside one
outward-oriented solid, +2 in the overlap of two, 0 outside, so "nonzero"
is the union.  An inverted (inward-oriented) solid has winding -1 and also
counts as solid.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..digital.lattice import DigitalObject
from ..errors import IsoflowError
from .grid import check_grid_memory, voxel_grid
from .load import check_mesh, load_mesh, mesh_defects
from .scanline import PAIR_BYTES, PAIR_CHUNK, diff_dtype, scan_plan, scanline
from .winding import GWN_BYTES, GWN_CHUNK, check_winding_cost, winding_volume

#: default resolution when a mesh is given to a command without --pitch/--resolution
DEFAULT_RESOLUTION = 64


def voxelize(vertices, faces, *, pitch=None, resolution=None, allow_open: bool = False,
             grid=None, max_bytes: int | None = None,
             progress: Callable[[int, int], object] | None = None):
    """Voxelise the solid bounded by a triangle mesh.

    Parameters
    ----------
    vertices, faces
        ``(N, 3)`` float and ``(M, 3)`` integer arrays (weld coincident
        vertices first: :func:`load_mesh` does).
    pitch, resolution
        Exactly one.  ``pitch``: voxel edge length (at most 2**40 times the
        longest side).  ``resolution=R``: an integer from 1 to
        ``MAX_RESOLUTION``; the longest side of the bounding box gets exactly
        R voxels.  The grid is
        centred on the bounding box (module docstring).
    allow_open
        A mesh that is not watertight (see :func:`mesh_defects`) is refused
        unless this is true.  Then, if its edges still balance (no boundary or
        inconsistent edge, only non-manifold ones, e.g. two cubes sharing an
        edge) the exact scanline is used; otherwise every voxel centre gets a
        generalised winding number and is in iff ``|GWN| > 0.5``.  That path
        costs O(voxels x triangles): keep it to modest grids (say up to
        ~50^3 for a 10k-triangle mesh).  More than ``GWN_MAX_PAIRS``
        (1.5e9, a few minutes) voxel-triangle pairs are refused up front with
        the estimate and the largest resolution that fits.
    grid
        Optional ``(origin, shape)``: sample on this grid (with ``pitch``)
        instead of the one centred on the bounding box, e.g. to put voxel
        corners on integer coordinates when digitising unions of unit cubes.
    max_bytes
        Refuse (IsoflowError) before allocating if the grid would need more
        (bool volume + integer difference array + chunk buffers).  Default:
        :func:`isoflow.scale.memory.default_budget` (90 % of the available memory).
    progress
        Optional ``callable(done, total)``, called once per chunk of work.

    Returns
    -------
    volume : bool ndarray (nx, ny, nz)
        ``volume[i, j, k]`` is true iff the centre
        ``origin + pitch * (i + .5, j + .5, k + .5)`` has nonzero winding
        number.  Borders are neither trimmed nor padded.
    origin : float64 (3,)
        Lower corner of voxel (0, 0, 0).
    pitch : float

    Exactness: in/out is decided by the exact scanline described in
    :func:`isoflow.mesh.scanline.scanline`: columns through edges and vertices are counted once;
    a centre lying exactly on a horizontal-ish face counts as above the
    crossing only if strictly above, i.e. a box [z0, z1] holds the centres
    with z0 < z <= z1.
    """
    v, f = check_mesh(vertices, faces, where="voxelize")
    pitch, origin, shape, what, (shift, e, origin_s, pitch_s) = voxel_grid(v, f, pitch, resolution)
    if grid is not None:
        if resolution is not None:
            raise IsoflowError("voxelize: grid= needs pitch=, not resolution=")
        try:
            origin = np.asarray(grid[0], dtype=np.float64).reshape(3)
            shape = tuple(int(n) for n in grid[1])
        except (TypeError, ValueError, IndexError, OverflowError):
            raise IsoflowError(
                f"voxelize: grid must be (origin, shape), three numbers each, got {grid!r}") from None
        if len(shape) != 3 or min(shape) < 1:
            raise IsoflowError(f"voxelize: grid shape must be three positive integers, got {grid[1]!r}")
        with np.errstate(over="ignore", invalid="ignore"):
            origin_s = np.ldexp(origin - shift, -e)
        if not np.all(np.isfinite(origin_s)):
            raise IsoflowError(
                f"voxelize: grid origin {origin.tolist()} is not finite or too far from the mesh")
    defects = mesh_defects(v, f)
    balanced = defects["boundary_edges"] == 0 and defects["inconsistent_edges"] == 0
    if not defects["watertight"] and not allow_open:
        raise IsoflowError(
            "voxelize: mesh is not watertight: "
            f"{defects['boundary_edges']} boundary edges, "
            f"{defects['nonmanifold_edges']} non-manifold edges, "
            f"{defects['inconsistent_edges']} inconsistently oriented edges "
            "(--allow-open / allow_open=True reads it by the generalised winding number)")
    if balanced:
        # bool volume + difference array (one more slot per column)
        per_voxel = 1 + np.dtype(diff_dtype(len(f))).itemsize * (shape[2] + 1) / shape[2]
        check_grid_memory(shape, what, per_voxel, 0, max_bytes)  # before any O(grid) work
    else:
        # generalised winding number: the volume, a float64 result and three
        # float64 coordinates per voxel centre, and one chunk of pairs
        check_grid_memory(shape, what, 1 + 8 + 24, GWN_CHUNK * GWN_BYTES, max_bytes)
        check_winding_cost(v, f, shape, what, pitch, resolution)
    # the arithmetic runs in the scaled frame of voxel_grid (exact power-of-two
    # scaling: no overflow or underflow at any scale, same comparisons)
    with np.errstate(over="ignore", invalid="ignore"):
        vs = np.ldexp(v - shift, -e)  # unused far-off vertices may overflow: never read
    if balanced:
        plan = scan_plan(vs, f, origin_s, pitch_s, shape)
        pairs = min(int(plan[-1][-1]), PAIR_CHUNK)
        check_grid_memory(shape, what, per_voxel, pairs * PAIR_BYTES, max_bytes)
        return scanline(shape, plan, progress), origin, pitch
    return winding_volume(vs, f, origin_s, pitch_s, shape, progress), origin, pitch


def voxelize_mesh(vertices, faces, *, pitch=None, resolution=None, allow_open=False, progress=None) -> DigitalObject:
    """The solid bounded by a triangle mesh as a digital object.

    Voxel in iff its centre is inside (nonzero winding number). The object
    carries the grid's pitch and origin, so its surfaces and flows export in
    the mesh's coordinates.
    """
    if pitch is None and resolution is None:
        resolution = DEFAULT_RESOLUTION
    vol, origin, pitch = voxelize(
        vertices, faces, pitch=pitch, resolution=resolution, allow_open=allow_open, progress=progress
    )
    return DigitalObject(vol, pitch=pitch, origin=origin)


def voxelize_file(path, *, pitch=None, resolution=None, allow_open=False, progress=None) -> DigitalObject:
    """Read a mesh file (STL/OBJ/PLY/OFF/GLB) and voxelise its solid."""
    v, f = load_mesh(path)
    try:
        return voxelize_mesh(v, f, pitch=pitch, resolution=resolution, allow_open=allow_open, progress=progress)
    except IsoflowError as exc:
        raise IsoflowError(f"{path}: {exc}") from None

