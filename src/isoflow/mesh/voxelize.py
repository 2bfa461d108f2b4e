"""Solid voxelisation of triangle meshes: voxel in iff its centre is inside.

``voxelize(vertices, faces, ...)`` is array in, array out; ``voxelize_mesh``
and ``voxelize_file`` wrap it into a :class:`~isoflow.digital.lattice.DigitalObject`
that keeps the grid's pitch and origin, so its surfaces and flows export in
the mesh's coordinates. The grid is :mod:`isoflow.mesh.grid`; the exact
scanline is :mod:`isoflow.mesh.scanline`, the generalised winding number of
meshes that are open, non-manifold or inconsistently oriented
:mod:`isoflow.mesh.winding`; :mod:`isoflow.mesh.slabs` writes volumes beyond
memory slab by slab.

The rule
--------
A voxel is in iff the generalised winding number of its centre satisfies
``|w| > 1/2`` (Jacobson et al. 2013).  On a closed, consistently oriented
mesh w is the integer winding number and the rule is the nonzero rule, which
the scanline computes exactly (with a documented tie rule for centres on the
surface).  Any other mesh is first made consistently oriented where it can be
(trimesh's ``fix_winding``), then read by the same scanline on the mesh
closed by a cap, minus the cap's own winding number (exact; see
:mod:`isoflow.mesh.winding`).

Why a winding number and not parity
-----------------------------------
Overlapping watertight solids (trimesh's ``rabbit.obj`` is nine intersecting
primitives) must give their union; with parity (even-odd) counting, as
pyvista's ``voxelize_binary_mask`` and VTK's stencils do, the overlaps become
holes.  The winding number of a point is +1 inside one outward-oriented
solid, +2 in the overlap of two, 0 outside, so "nonzero" is the union.  An
inverted (inward-oriented) solid has winding -1 and also counts as solid; a
shell nested inside another with the opposite orientation is a cavity.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..digital.lattice import DigitalObject
from ..errors import IsoflowError
from .grid import check_grid_memory, voxel_grid
from .load import boundary_chain, check_mesh, load_mesh, merge_coincident, mesh_defects, orient_faces

#: default resolution when a mesh is given to a command without --pitch/--resolution
DEFAULT_RESOLUTION = 64
#: the in-memory voxeliser fills the volume in slabs of about this many
#: voxels (progress is reported per slab; each slab runs on two threads)
SLAB_VOXELS = 1 << 24
#: units of progress per slab
PROGRESS_UNITS = 1000
#: bytes of temporaries per (triangle, column) pair that may cross
PAIR_BYTES = 18
#: what to do when a volume does not fit in memory
ZARR_HINT = "write it slab by slab to a zarr store instead (isoflow voxelize MESH ... -o OUT.zarr)"


class Solid:
    """A triangle mesh made ready to voxelise: its edge census, its
    orientation repaired where needed, and the cap that closes it.

    ``defects`` are the counts of :func:`mesh_defects` on the faces as given;
    after exact duplicates of vertex positions are merged (a triangle soup)
    ``census`` recounts them.  ``flipped`` faces were turned over by
    :func:`orient_faces`; ``chain_edges`` is the length of the boundary
    chain that the cap closes (0: the exact scanline alone decides).
    """

    def __init__(self, v: np.ndarray, f: np.ndarray, *, strict: bool = False):
        self.strict = strict
        self.defects = mesh_defects(v, f)
        if strict and not self.defects["watertight"]:
            d = self.defects
            raise IsoflowError(
                "voxelize: mesh is not watertight: "
                f"{d['boundary_edges']} boundary edges, {d['nonmanifold_edges']} non-manifold edges, "
                f"{d['inconsistent_edges']} inconsistently oriented edges (without --strict / strict=True "
                "it is read by the generalised winding number)")
        faces = f
        self.census = self.defects
        if self.defects["boundary_edges"] or self.defects["inconsistent_edges"]:
            faces = merge_coincident(v, f)
            self.census = mesh_defects(v, faces)
        self.flipped = 0
        if self.census["inconsistent_edges"]:
            faces, self.flipped = orient_faces(v, faces)
        a, b = boundary_chain(faces, len(v))
        self.chain = (a, b)
        self.chain_edges = int(len(a))
        # geometry: the corners of the faces as oriented now
        self.v = v
        self.faces = faces

    def prepare(self, frame, origin_s, pitch_s, shape) -> "VoxelPlan":
        from .winding import close_mesh

        shift, e, _, _ = frame
        with np.errstate(over="ignore", invalid="ignore"):
            vs = np.ldexp(self.v - shift, -e)  # unused far-off vertices may overflow: never read
        Tm = vs[self.faces]
        return VoxelPlan(Tm, close_mesh(vs, self.faces, *self.chain), origin_s, pitch_s, shape)

    def check_layers(self, stats) -> None:
        """With ``strict``, refuse a mesh whose voxels lie inside two or more
        layers or have winding numbers of both signs (overlapping or
        self-intersecting shells, as far as the voxel centres see them:
        ``isoflow genus`` tests every pair of faces); ``stats`` as
        :meth:`note` takes them."""
        if not self.strict:
            return
        what = []
        if stats[0]:
            what.append(_count(int(stats[0]), "voxel") + " inside two or more layers")
        if stats[1] and stats[2]:
            what.append("both positive and negative winding numbers")
        if what:
            raise IsoflowError("voxelize: mesh overlaps or intersects itself: " + " and ".join(what)
                               + " (without --strict / strict=True the union is taken)")

    def note(self, stats=None) -> str | None:
        """One line on what is unusual about the mesh and the rule that read
        it; None for a closed, consistently oriented mesh without overlaps."""
        c = self.census
        what = []
        if c is not self.defects and self.defects["boundary_edges"] > c["boundary_edges"]:
            what.append(_count(self.defects["boundary_edges"] - c["boundary_edges"], "edge")
                        + " joined by merging vertices at equal positions (a triangle soup)")
        if c["boundary_edges"]:
            what.append(_count(c["boundary_edges"], "boundary edge"))
        if c["nonmanifold_edges"]:
            what.append(_count(c["nonmanifold_edges"], "non-manifold edge"))
        if self.flipped:
            what.append(_count(self.flipped, "flipped face") + " (turned over with trimesh.repair.fix_winding)")
        elif c["inconsistent_edges"] and not c["nonmanifold_edges"]:
            what.append(_count(c["inconsistent_edges"], "inconsistently oriented edge"))
        if stats is not None and stats[0]:
            what.append(_count(int(stats[0]), "voxel") + " inside two or more layers (self-intersecting "
                        "or overlapping shells: counted once, the union)")
        if stats is not None and stats[1] and stats[2]:
            what.append("both positive and negative winding numbers (inverted or "
                        "self-intersecting parts)")
        if not what:
            return None
        if self.chain_edges:
            rule = ("read by the generalised winding number, a voxel is in iff |w| > 1/2 "
                    "(Jacobson et al. 2013; --strict refuses such meshes)")
        else:
            rule = "its edges balance, so it bounds a solid: read by the exact nonzero winding number"
        return "mesh has " + ", ".join(what) + "; " + rule


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


class VoxelPlan:
    """Everything needed to fill any slab of the grid: the scanline over the
    mesh and its cap, and the cap's own triangles for the rule.  Small
    (O(triangles)) and picklable, so dask can ship it to workers."""

    def __init__(self, Tm, cap, origin_s, pitch_s, shape):
        from .captree import CapTree
        from .scanline import ScanGrid

        self.shape = tuple(int(n) for n in shape)
        self.origin = np.asarray(origin_s, dtype=np.float64)
        self.pitch = float(pitch_s)
        self.Tm = Tm
        self.E = cap.E
        self.tree = CapTree(cap.T, cap.E, cap.owner)
        # the closed mesh M + C, less the faces that the cap holds reversed (they cancel)
        self.grid = ScanGrid(np.concatenate([Tm[~cap.reversed_faces], cap.cones()]), self.origin, self.pitch,
                             self.shape)

    def fill(self, xa: int, xb: int, out=None, stats=None, threads: int = 1, progress=None) -> np.ndarray:
        """The volume of slab ``[xa, xb)`` (first axis); ``progress(done,
        total)`` as the cap's rule advances."""
        from .scanline import fill_slab
        from .winding import winding_rule

        _, ny, nz = self.shape
        rule = winding_rule(self.tree, self.Tm, self.origin, self.pitch, (xa, xb, 0, ny, 0, nz), threads=threads,
                            progress=progress)
        return fill_slab(self.grid, xa, xb, rule=rule, out=out, stats=stats, threads=threads)

    def slab_bytes(self, rows: int) -> int:
        """Temporaries of a slab of ``rows`` rows beyond its volume, at most:
        the crossings (bounded by the whole grid's pairs), its columns, and
        the rule's box (one byte per voxel of the slab)."""
        _, ny, nz = self.shape
        return self.grid.pairs() * PAIR_BYTES + 16 * rows * ny + rows * ny * nz

    def slabs(self, voxels: int = SLAB_VOXELS) -> list[tuple[int, int]]:
        nx, ny, nz = self.shape
        rows = max(1, voxels // max(1, ny * nz))
        return [(a, min(a + rows, nx)) for a in range(0, nx, rows)]


def plan_voxels(vertices, faces, *, pitch=None, resolution=None, grid=None):
    """Check the mesh and lay out the grid (nothing O(grid) is done):
    ``(v, f, shape, what, frame, origin, pitch)`` with the checked arrays and
    the scaled frame of :func:`isoflow.mesh.grid.voxel_grid`."""
    v, f = check_mesh(vertices, faces, where="voxelize")
    pitch, origin, shape, what, frame = voxel_grid(v, f, pitch, resolution)
    shift, e, origin_s, pitch_s = frame
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
    return v, f, shape, what, (shift, e, origin_s, pitch_s), origin, pitch


def voxelize(vertices, faces, *, pitch=None, resolution=None, strict: bool = False,
             grid=None, max_bytes: int | None = None,
             progress: Callable[[int, int], object] | None = None, report: dict | None = None):
    """Voxelise the solid bounded by a triangle mesh.

    Parameters
    ----------
    vertices, faces
        ``(N, 3)`` float and ``(M, 3)`` integer arrays (weld coincident
        vertices first: :func:`load_mesh` does).  Any triangle mesh: open,
        non-manifold, inconsistently oriented, self-intersecting, a soup.
    pitch, resolution
        Exactly one.  ``pitch``: voxel edge length (at most 2**40 times the
        longest side).  ``resolution=R``: an integer from 1 to
        ``MAX_RESOLUTION``; the longest side of the bounding box gets exactly
        R voxels.  The grid is centred on the bounding box (see
        :mod:`isoflow.mesh.grid`).
    strict
        Refuse a mesh that is not watertight (see :func:`mesh_defects`)
        instead of reading it by the generalised winding number, and one
        whose voxels lie inside two or more layers or have winding numbers
        of both signs (overlapping or self-intersecting shells, as far as
        the voxel centres see them).
    grid
        Optional ``(origin, shape)``: sample on this grid (with ``pitch``)
        instead of the one centred on the bounding box, e.g. to put voxel
        corners on integer coordinates when digitising unions of unit cubes.
    max_bytes
        Refuse (IsoflowError) before allocating if the volume and the
        temporaries of a slab would need more.  Default:
        :func:`isoflow.scale.memory.default_budget` (90 % of the available
        memory).  The message suggests a zarr store.
    progress
        Optional ``callable(done, total)``, called as the work advances
        (``PROGRESS_UNITS`` per slab).
    report
        Optional dict that receives ``defects`` (the edge census of the faces
        as given), ``flipped_faces``, ``chain_edges`` (edges the cap closes; 0 when the exact
        scanline alone decides), ``overlap_voxels`` (voxels inside two or
        more layers) and ``note`` (one line for the user, or None).

    Returns
    -------
    volume : bool ndarray (nx, ny, nz)
        ``volume[i, j, k]`` is true iff the centre
        ``origin + pitch * (i + .5, j + .5, k + .5)`` has ``|w| > 1/2``.
        Borders are neither trimmed nor padded.
    origin : float64 (3,)
        Lower corner of voxel (0, 0, 0).
    pitch : float

    Exactness: on a closed, consistently oriented mesh the volume is the
    exact nonzero winding number with the tie rule of
    :mod:`isoflow.mesh.scanline` (a centre on a horizontal-ish face counts as
    below it: a box [z0, z1] holds the centres with z0 < z <= z1).  On any other mesh it is
    the generalised winding number rule, exact except where |w| is within
    rounding of 1/2 (:mod:`isoflow.mesh.winding`).
    """
    v, f, shape, what, frame, origin, pitch = plan_voxels(
        vertices, faces, pitch=pitch, resolution=resolution, grid=grid)
    # the volume itself, before anything O(grid): one byte per voxel
    check_grid_memory(shape, what, 1, 0, max_bytes, hint=ZARR_HINT)
    solid = Solid(v, f, strict=strict)
    _, _, origin_s, pitch_s = frame
    plan = solid.prepare(frame, origin_s, pitch_s, shape)
    slabs = plan.slabs()
    temp = plan.slab_bytes(max(b - a for a, b in slabs))
    check_grid_memory(shape, what, 1, temp, max_bytes, hint=ZARR_HINT)
    vol = np.zeros(shape, dtype=bool)  # the sweep writes only the voxels inside
    stats = np.zeros(3, dtype=np.int64)
    for n, (a, b) in enumerate(slabs):
        step = None if progress is None else _share(progress, n, len(slabs))
        plan.fill(a, b, out=vol[a:b], stats=stats, threads=2, progress=step)
        if progress is not None:
            progress((n + 1) * PROGRESS_UNITS, len(slabs) * PROGRESS_UNITS)
    solid.check_layers(stats)
    if report is not None:
        report.update(defects=solid.defects, flipped_faces=solid.flipped,
                      chain_edges=len(plan.E), overlap_voxels=int(stats[0]),
                      note=solid.note(stats))
    return vol, origin, pitch


def _share(progress, n: int, slabs: int):
    """Slab n's progress as a share of the whole."""
    return lambda done, total: progress(n * PROGRESS_UNITS + done * (PROGRESS_UNITS - 1) // total,
                                        slabs * PROGRESS_UNITS)


def voxelize_mesh(vertices, faces, *, pitch=None, resolution=None, strict=False,
                  progress=None, report=None) -> DigitalObject:
    """The solid bounded by a triangle mesh as a digital object.

    Voxel in iff the generalised winding number of its centre exceeds 1/2 in
    absolute value (on closed meshes: nonzero winding number). The object
    carries the grid's pitch and origin, so its surfaces and flows export in
    the mesh's coordinates.
    """
    if pitch is None and resolution is None:
        resolution = DEFAULT_RESOLUTION
    vol, origin, pitch = voxelize(vertices, faces, pitch=pitch, resolution=resolution, strict=strict,
                                  progress=progress, report=report)
    return DigitalObject(vol, pitch=pitch, origin=origin)


def voxelize_file(path, *, pitch=None, resolution=None, strict=False, progress=None,
                  report=None) -> DigitalObject:
    """Read a mesh file (any format trimesh reads) and voxelise its solid."""
    v, f = load_mesh(path)
    try:
        return voxelize_mesh(v, f, pitch=pitch, resolution=resolution, strict=strict, progress=progress,
                             report=report)
    except IsoflowError as exc:
        raise IsoflowError(f"{path}: {exc}") from None
