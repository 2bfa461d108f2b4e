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
surface).  Edges that vertices of other faces split (T-junctions, a CAD
export's cracks) are split there first where that closes them
(:func:`~isoflow.mesh.t_junctions.close_t_junctions`): the surface drawn,
and so w off it, is the same, and a mesh closed so takes the scanline
alone.  Any other mesh is first made consistently oriented where its
faces show how (:func:`~isoflow.mesh.orientation.orient_faces`), then read
by the same scanline on the mesh closed by a cap, minus the cap's own
winding number (exact; see :mod:`isoflow.mesh.winding`).

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

import dataclasses
import os
from collections.abc import Callable
from typing import Any, Literal, Protocol, overload, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ..digital.lattice import DigitalObject
from ..errors import (
    IsoflowError,
    MeshNote,
    check_callable,
    check_path,
    check_switch,
    counted,
    given_text,
    scalar_given,
    voxeliser_of,
    warn,
)
from ..results import handed_over
from ..scale import memory
from .fills import (
    NO_AREA,
    THIN_SHARE,
    THIN_TRIGGER,
    UNBOUNDED_SHARE,
    Fill,
    Voxelization,
    check_fill,
    check_strict,
    flood_adds_nothing,
    sampled_points,
    thin_solid,
    unbounded_area,
    unbounded_share,
)
from .grid import (
    GridTooLarge,
    check_grid_request,
    check_placement,
    finest_fit,
    float64_rounding,
    grid_fits,
    grid_need,
    grid_words,
    rounding_words,
    voxel_grid,
)
from .load import (  # noqa: F401
    chain_of,
    check_mesh,
    column_bounds,
    defect_counts,
    is_manifold,
    is_scene,
    load_mesh,
    merge_coincident,
    mesh_arrays,
    mesh_bbox,
    mesh_defects,
    repeated_faces,
)
from .mesh_units import declared_unit
from .t_junctions import close_t_junctions

#: a progress callback: ``progress(done, total)``
Progress = Callable[[int, int], object]


@runtime_checkable
class RuleProgress(Protocol):
    """A ``progress(done, total)`` callback that is also told, per mesh,
    whether the winding rule sums solid angles.

    The voxelisers (:func:`voxelize`, :func:`voxelize_mesh`,
    :func:`voxelize_file`, :func:`~isoflow.mesh.slabs.voxelize_to_zarr`,
    :func:`~isoflow.mesh.label_voxels.voxelize_meshes`) call ``rule`` once
    per mesh, after it is read and closed and before its voxels are
    filled, where the callback has that method; a plain function is only
    called with ``(done, total)``. ``solid_angles`` is True where the
    winding rule sums the solid angles of the cap that closes the mesh's
    boundary chain, the work that the shell and the flood fill do without;
    False for a closed mesh (the exact scanline alone) and for those fills.
    A caller can then say how the work could be cut only where it can.

    Examples
    --------
    >>> import trimesh
    >>> class Told:
    ...     def __init__(self):
    ...         self.said = []
    ...     def __call__(self, done, total):
    ...         pass
    ...     def rule(self, solid_angles):
    ...         self.said.append(solid_angles)
    >>> box, told = trimesh.creation.box((2, 2, 2)), Told()
    >>> isinstance(told, RuleProgress)
    True
    >>> _ = voxelize(box.vertices, box.faces, resolution=4, progress=told, details=True)
    >>> _ = voxelize(box.vertices, box.faces[2:], resolution=4, progress=told, details=True)  # a side open
    >>> told.said
    [False, True]
    """

    def __call__(self, done: int, total: int) -> object: ...

    def rule(self, solid_angles: bool) -> object: ...


def tell_rule(progress: object, solid_angles: bool) -> None:
    """Tell ``progress`` whether the winding rule sums solid angles, where
    it listens (a :class:`RuleProgress`); nothing for a plain callback or
    None.

    Examples
    --------
    >>> told = []
    >>> class Listening:
    ...     def __call__(self, done, total):
    ...         pass
    ...     def rule(self, solid_angles):
    ...         told.append(solid_angles)
    >>> tell_rule(Listening(), True); tell_rule(print, True); tell_rule(None, True)
    >>> told
    [True]
    """
    if isinstance(progress, RuleProgress):
        progress.rule(solid_angles)


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
ZARR_HINT = "or write it slab by slab to a zarr store (isoflow.voxelize_to_zarr)"


def inconsistent_text(n: int, nonmanifold: int, left: str = "") -> str:
    """The inconsistently oriented edges as a line beside the non-manifold
    edges counts them, saying how many of them that count already holds
    (a repeated face makes each of its edges both).

    Parameters
    ----------
    n : int
        The inconsistently oriented edges.
    nonmanifold : int
        Those of them that are also non-manifold.
    left : str
        Words after the count (" left" once faces are turned).

    Returns
    -------
    str

    Examples
    --------
    >>> inconsistent_text(18, 18), inconsistent_text(3, 1), inconsistent_text(2, 0, " left")
    ('18 inconsistently oriented edges (all among the non-manifold ones)', \
'3 inconsistently oriented edges (1 among the non-manifold ones)', '2 inconsistently oriented edges left')
    """
    text = counted(n, "inconsistently oriented edge") + left
    if not nonmanifold:
        return text
    if n == 1:
        return f"{text} (also non-manifold)"
    return f"{text} ({'all' if nonmanifold == n else nonmanifold} among the non-manifold ones)"


class Solid:
    """A triangle mesh made ready to voxelise: its edge census, its
    double-sided faces read as one, its orientation repaired where needed,
    and the cap that closes it.

    ``defects`` are the counts of :func:`mesh_defects` on the faces as given;
    after exact duplicates of vertex positions are merged (a triangle soup),
    boundary edges are split at T-junctions where that closes them
    (``t_junctions``: the facts of
    :func:`~isoflow.mesh.t_junctions.close_t_junctions`, or None; the
    surface drawn is the same, each repeated face kept and split as its
    first) and double-sided faces are read as one (``double_sided`` pairs, see
    :func:`~isoflow.mesh.census.one_face_per_pair`) ``census`` recounts
    them (with ``t_junctions`` False the caller has made that split: it is
    not looked for); ``walls`` pairs lay in walls between solids or inside the solid
    (solids glued face to face, a tetrahedral mesh's cells) and were
    dropped, both faces, whose windings cancel.  ``repeated`` faces list
    the same three corners the same way round as an earlier face (on the
    faces ``census`` counts: :func:`~isoflow.mesh.load.repeated_faces`).
    ``flipped`` faces were turned over by
    :func:`~isoflow.mesh.orientation.orient_faces`, which leaves
    ``inconsistent`` edges still used more often one way than the other;
    ``chain_edges`` is the length of the boundary chain that the cap closes
    (0: the exact scanline alone decides).
    """

    def __init__(self, v: np.ndarray, f: np.ndarray, *, strict: bool = False, fill: Fill = "winding",
                 t_junctions: bool = True):
        from .census import census, one_face_per_pair  # compiled: loaded when a mesh is voxelised
        from .orientation import orient_faces

        self.strict = strict
        self.fill = fill
        self.rounding = float64_rounding(v, f)
        edges = census(f, len(v))
        self.defects = defect_counts(*edges[2:])
        faces = f
        self.census = self.defects
        self.joined = 0  # edges joined by merging vertices at equal positions
        self.double_sided = self.walls = self.flipped = self.chain_edges = self.repeated = 0
        self.t_junctions: dict | None = None  # facts of the edges split at T-junctions, if any closed
        self.inconsistent = self.defects["inconsistent_edges"]
        self.inconsistent_nonmanifold = self.defects["inconsistent_nonmanifold_edges"]
        self.v = v
        self.faces = faces
        self.chain = (np.zeros(0, dtype=np.int64),) * 2
        if fill != "winding":  # a shell takes the faces as they are, in any orientation
            self.refuse_defects()
            return
        # several components may be one surface drawn twice: a model written
        # double-sided with its own corners for the back faces (as exporters
        # write them for their normals) is two closed shells whose windings
        # cancel, and is seen as pairs only once equal corners share an index
        d = self.defects
        if d["boundary_edges"] or d["inconsistent_edges"] or d["components"] > 1:
            faces = merge_coincident(v, f)
            edges = census(faces, len(v))
            self.census = defect_counts(*edges[2:])
            self.joined = max(0, self.defects["boundary_edges"] - self.census["boundary_edges"])
        if self.census["boundary_edges"] and t_junctions:
            # a CAD export's faces tessellated apart leave cracks at
            # T-junctions: split there, the surface drawn is the same (and so
            # is w off it), but the edges balance and the exact scanline reads
            # the mesh without a cap's solid angles; repeated faces are kept,
            # each copy adds its winding, and each is split as its first, so
            # that a copy on a crack leaves no edge of it open
            v, faces, self.t_junctions = close_t_junctions(v, faces)
            if self.t_junctions is not None:
                edges = census(faces, len(v))
                self.census = defect_counts(*edges[2:])
        # a pair shares its three edges, each then used at least twice: on
        # a manifold mesh the pair is a component of its own
        if self.census["nonmanifold_edges"] or self.census["components"] > 1:
            given = len(faces)
            faces, self.double_sided = one_face_per_pair(v, faces)
            self.walls = (given - len(faces) - self.double_sided) // 2
            if self.double_sided:
                edges = census(faces, len(v))
                self.census = defect_counts(*edges[2:])
        self.inconsistent = self.census["inconsistent_edges"]
        self.inconsistent_nonmanifold = self.census["inconsistent_nonmanifold_edges"]
        if self.inconsistent:
            # a repeat uses each of its edges once more the same way: only
            # inconsistently oriented edges can come of one
            first = repeated_faces(faces)
            self.repeated = int((first != np.arange(len(faces))).sum())
            faces, self.flipped = orient_faces(v, faces, first)
            edges = census(faces, len(v))
            oriented = defect_counts(*edges[2:])
            self.inconsistent = oriented["inconsistent_edges"]
            self.inconsistent_nonmanifold = oriented["inconsistent_nonmanifold_edges"]
        a, b = chain_of(*edges[:4])
        self.chain = (a, b)
        self.chain_edges = int(len(a))
        # refused once the chain is known, so that the refusal names the
        # rule the mesh is read by without strict (before any voxel)
        self.refuse_defects()
        # geometry: the corners of the faces as oriented now
        self.v = v
        self.faces = faces

    def refuse_defects(self) -> None:
        """With ``strict``, refuse a mesh that is not watertight or has
        double-sided faces, naming the counts.

        Raises
        ------
        IsoflowError
            One line: the counts, and the rule that reads the mesh without
            ``strict`` (the shell as it is, the generalised winding number
            across a boundary chain, or the exact nonzero rule where the
            edges balance once double-sided faces are read as one).
        """
        found = self.strict_defects()
        if not self.strict or found is None:
            return
        said = "voxelize: mesh is not watertight: " + found[0]
        raise IsoflowError.worded(said + f" (without strict=True {found[1]})", said + f" (without --strict {found[1]})")

    def strict_defects(self) -> tuple[str, str] | None:
        """What ``strict`` refuses in the mesh as given, whatever ``strict``
        is: its counts of open, non-manifold and inconsistently oriented
        edges and of double-sided faces, and the rule that reads the mesh
        without ``strict``; None for a watertight mesh without double-sided
        faces. ``isoflow genus --strict`` refuses the same counts, saying
        what genus does without it."""
        d = self.defects
        if d["watertight"] and not self.double_sided:
            return None
        what = [", ".join([counted(d["boundary_edges"], "boundary edge"), counted(d["nonmanifold_edges"], "non-manifold edge"),
                           inconsistent_text(d["inconsistent_edges"], d["inconsistent_nonmanifold_edges"])])]
        if self.double_sided:
            what.append(counted(self.double_sided, "double-sided face") + " (coincident faces of opposite "
                        "orientation)")
        if self.fill != "winding":
            rule = f"the {self.fill} fill takes its faces as they are"
        elif self.no_area():  # edges that balance or a chain bound nothing without area: NO_AREA's reading
            rule = ("the winding rule leaves no voxel in, as every face has zero area (its corners in a line or at "
                    "one point) and the mesh bounds nothing")
        elif self.chain_edges:
            rule = "it is read by the generalised winding number"
        else:  # double-sided faces read as one, coincident corners joined, T-junctions split: closed
            split = f" once split at its {counted(self.t_junctions['points'], 'T-junction')}" if self.t_junctions else ""
            # the counts above are the edges as given: where they are inconsistently
            # oriented, they balance only once faces are turned over, which the rule says
            turned = (f" once {counted(self.flipped, 'face')} {'is' if self.flipped == 1 else 'are'} turned over to "
                      "agree with their neighbours" if self.flipped else "")
            rule = (f"its edges balance{split}{turned}, so it bounds a solid: it is read by the exact nonzero "
                    "winding number")
        return "; ".join(what), rule

    def no_area(self) -> bool:
        """Whether every face has zero area, as :meth:`VoxelPlan.thin_note`
        finds it (:data:`~isoflow.mesh.fills.NO_AREA`)."""
        from .shell import surface_area

        return not surface_area(np.asarray(self.v, np.float64)[self.faces]) > 0

    def prepare(self, frame, origin_s, pitch_s, shape, start=(0, 0, 0)) -> VoxelPlan:
        """The :class:`VoxelPlan` of the grid ``origin_s``, ``pitch_s`` (in
        the scaled ``frame``), or of its block of ``shape`` at ``start``."""
        from .winding import close_mesh

        shift, e, _, _ = frame
        with np.errstate(over="ignore", invalid="ignore"):
            vs = np.ldexp(self.v - shift, -e)  # unused far-off vertices may overflow: never read
        Tm = np.take(vs, self.faces, axis=0)  # vs[faces]: np.take copies rows, the fancy index takes a general loop
        return VoxelPlan(Tm, close_mesh(vs, self.faces, *self.chain), origin_s, pitch_s, shape, self.fill, start)

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
            what.append(counted(int(stats[0]), "voxel") + " inside two or more layers")
        if stats[1] and stats[2]:
            what.append("both positive and negative winding numbers")
        if what:
            said = "voxelize: mesh overlaps or intersects itself: " + " and ".join(what)
            raise IsoflowError.worded(said + " (without strict=True the union is taken)",
                                      said + " (without --strict the union is taken)")

    def note(self, stats=None) -> str | None:
        """One line on what is unusual about the mesh and the rule that read
        it, and on coordinates that float64 holds coarsely against the edges
        (:func:`~isoflow.mesh.grid.float64_rounding`); None for a closed,
        consistently oriented mesh without overlaps held finely, and for a
        shell (which any surface has) held finely."""
        said = self.defects_note(stats)
        if self.rounding is None:
            return said
        c = self.census
        found = {"joined edges": self.joined, "boundary edges": c["boundary_edges"],
                 "non-manifold edges": c["nonmanifold_edges"],
                 "overlapping layers": stats is not None and stats[0]} if said else {}
        rounding = rounding_words(**self.rounding, defects=tuple(k for k, n in found.items() if n))
        return f"{said}; {rounding}" if said else rounding

    def defects_note(self, stats=None) -> str | None:
        """The defects and the rule that read the mesh, for :meth:`note`."""
        if self.fill != "winding":
            return None
        c = self.census
        what = []
        if self.joined:
            what.append(counted(self.joined, "edge") + " joined by merging vertices at equal positions (a triangle soup)")
        if self.t_junctions:
            t = self.t_junctions
            what.append(counted(t["edges"], "boundary edge") + " closed at T-junctions ("
                        f"{counted(t['points'], 'vertex', 'vertices')} of one face on another face's edge, "
                        "as faces tessellated apart leave them: "
                        f"{counted(t['faces'], 'face')} split there, the surface drawn the same)")
        if self.double_sided:
            what.append(counted(self.double_sided, "double-sided face") + " (coincident faces of opposite "
                        "orientation, each read as one face)")
        if self.walls:
            what.append(counted(self.walls, "pair") + " of coincident faces of opposite orientation in walls "
                        "inside the solid (as solids glued face to face and a tetrahedral mesh's cells give them: "
                        "both faces left out, their windings cancel)")
        if c["boundary_edges"]:
            what.append(counted(c["boundary_edges"], "boundary edge"))
        if c["nonmanifold_edges"]:
            what.append(counted(c["nonmanifold_edges"], "non-manifold edge"))
        if self.repeated:
            what.append(counted(self.repeated, "repeated face") + " (the same three corners the same way round as "
                        "an earlier face: each copy counted)")
        if self.flipped:
            what.append(counted(self.flipped, "flipped face") + " (turned over to agree with their neighbours; where "
                        "the mesh is open or non-manifold, only across edges where they meet almost flat or that "
                        "make half or more of the rim of a part)")
        if self.inconsistent:  # as the faces are read, after any turned over
            what.append(inconsistent_text(self.inconsistent, self.inconsistent_nonmanifold,
                                          " left" if self.flipped else ""))
        if stats is not None and stats[0]:
            what.append(counted(int(stats[0]), "voxel") + " inside two or more layers (self-intersecting "
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


class VoxelPlan:
    """Everything needed to fill any slab of the grid: the scanline over the
    mesh and its cap, and the cap's own triangles for the rule (``fill``
    "winding"), or the mesh's triangles for its shell ("shell", and
    "flood" before the enclosed voxels are added).  Small (O(triangles))
    and picklable, so dask can ship it to workers.

    ``shape`` is the block filled; ``start`` its voxel 0's index in the grid
    of ``origin_s`` and ``pitch_s``, whose voxel centres and planes it
    keeps bit for bit (a mesh among others on their common grid)."""

    def __init__(self, Tm, cap, origin_s, pitch_s, shape, fill: Fill = "winding", start=(0, 0, 0)):
        from .scanline import ScanGrid
        from .shell import grid_planes

        self.shape = tuple(int(n) for n in shape)
        self.start = tuple(int(s) for s in start)
        self.origin = np.asarray(origin_s, dtype=np.float64)
        self.pitch = float(pitch_s)
        self.fill_rule = fill
        self.Tm = Tm
        self.E = cap.E
        if fill == "winding":
            from .captree import CapTree

            self.tree = CapTree(cap.T, cap.E, cap.owner)
            # the closed mesh M + C, less the faces that the cap holds reversed (they cancel)
            self.grid = ScanGrid(np.concatenate([Tm[~cap.reversed_faces], cap.cones()]), self.origin, self.pitch,
                                 self.shape, self.start)
        else:
            from .shell import ShellGrid

            self.shell = ShellGrid(Tm, grid_planes(self.origin, self.pitch, self.shape, self.start))

    @property
    def solid_angles(self) -> bool:
        """Whether the winding rule sums the solid angles of a cap (the
        mesh has a boundary chain); False for a closed mesh, which the
        scanline alone decides, and for the shell."""
        return self.fill_rule == "winding" and len(self.tree.T) > 0

    def fill(self, xa: int, xb: int, out=None, stats=None, threads: int = 1, progress=None) -> np.ndarray:
        """The volume of slab ``[xa, xb)`` (first axis): by the winding rule
        (``progress(done, total)`` as the cap's rule advances), or the shell
        (for "flood" too: its enclosed voxels need the whole grid,
        :func:`fill_enclosed`), whose voxels ``stats[3]`` counts (in by a
        rule other than the winding number's)."""
        from .scanline import fill_slab
        from .winding import winding_rule

        if self.fill_rule != "winding":
            if out is None:
                out = np.zeros((xb - xa,) + self.shape[1:], dtype=bool)
            added = self.shell.fill(xa, xb, out, threads=threads)
            if stats is not None:
                stats[3] += added
            return out
        _, ny, nz = self.shape
        sx, sy, sz = self.start
        rule = winding_rule(self.tree, self.Tm, self.origin, self.pitch, (sx + xa, sx + xb, sy, sy + ny, sz, sz + nz),
                            threads=threads, progress=progress)
        if rule is not None:  # its corner in the grid's indices, the block's for the sweep
            rule = rule[0], (rule[1][0] - sx, rule[1][1] - sy, rule[1][2] - sz)
        return fill_slab(self.grid, xa, xb, rule=rule, out=out, stats=stats, threads=threads)

    def slab_bytes(self, rows: int) -> int:
        """Temporaries of a slab of ``rows`` rows beyond its volume, at most:
        the crossings (bounded by the whole grid's pairs), its columns, and
        the rule's box (one byte per voxel of the slab, where there is a
        cap); none for the shell."""
        if self.fill_rule != "winding":
            return 0
        _, ny, nz = self.shape
        rule = rows * ny * nz if self.solid_angles else 0
        return self.grid.pairs() * PAIR_BYTES + 16 * rows * ny + rule

    def slabs(self, voxels: int | None = None) -> list[tuple[int, int]]:
        """Ranges of rows of about ``voxels`` voxels (default
        :data:`SLAB_VOXELS`; eight times that for a shell, and for a mesh
        without a cap, which need no temporaries of a slab's size and whose
        every slab looks at each triangle)."""
        rows = max(1, self.slab_rows(voxels))
        return [(a, min(a + rows, self.shape[0])) for a in range(0, self.shape[0], rows)]

    def slab_rows(self, voxels: int | None = None) -> int:
        """Rows of the largest of :meth:`slabs` (at most the grid's), found
        without the list: a grid too large to fill has millions of rows,
        which a refusal's search for the finest grid that fits tries."""
        if voxels is None:
            voxels = SLAB_VOXELS if self.solid_angles else 8 * SLAB_VOXELS
        nx, ny, nz = self.shape
        return min(nx, max(1, voxels // max(1, ny * nz)))

    def shellcounted(self) -> int:
        """Voxels of the mesh's shell on this grid that hold some of the
        inside of the mesh's bounding box, counted slab by slab (a slab's
        volume at a time). A voxel past the box that only touches it (a side
        of the box on the plane between voxels) is not counted: on a grid
        of the mesh's own there is none, and on a grid shared with larger
        meshes, it would make a box a few voxels across read as thin
        against its shell (64 voxels against 208 for a cube of 4). Across
        a box of no thickness (a flat mesh on a plane between voxels) every
        shell voxel only touches it: there those on both sides count."""
        from .shell import ShellGrid, grid_planes

        planes = grid_planes(self.origin, self.pitch, self.shape, self.start)
        shell = ShellGrid(self.Tm, planes)
        corners = self.Tm.reshape(-1, 3)
        lo, hi = column_bounds(corners)
        box = []
        for a in range(3):
            held = np.flatnonzero((planes[a][1:] > lo[a]) & (planes[a][:-1] < hi[a]))
            if not len(held) and lo[a] == hi[a]:  # flat on a plane between voxels: the voxels it touches
                held = np.flatnonzero((planes[a][1:] >= lo[a]) & (planes[a][:-1] <= hi[a]))
            box.append((int(held[0]), int(held[-1]) + 1) if len(held) else (0, 0))
        (x0, x1), (y0, y1), (z0, z1) = box
        _, ny, nz = self.shape
        count = 0
        for a, b in self.slabs():
            out = np.zeros((b - a, ny, nz), dtype=bool)
            shell.fill(a, b, out, threads=2)
            count += int(np.count_nonzero(out[max(x0 - a, 0):max(x1 - a, 0), y0:y1, z0:z1]))
        return count

    def holds_mesh(self) -> bool:
        """Whether the block holds every corner of the mesh, so that every
        voxel inside the mesh is one of its voxels (a ``window`` or a
        ``grid`` may cut the mesh)."""
        corners = self.Tm.reshape(-1, 3)
        lo = self.origin + self.pitch * np.asarray(self.start)
        hi = lo + self.pitch * np.asarray(self.shape)
        if not len(corners):
            return False
        least, most = column_bounds(corners)
        return bool(np.all(least >= lo) and np.all(most <= hi))

    def sampled_points(self) -> tuple[np.ndarray, np.ndarray] | None:
        """:func:`~isoflow.mesh.fills.sampled_points` on this grid: the
        voxels (indices in the grid) the share of unbounded area looks up."""
        corner = self.origin + self.pitch * np.asarray(self.start)
        return sampled_points(self.Tm, corner, self.pitch)

    def thin_note(self, volume: np.ndarray | None, voxels: int, double_sided: int,
                  found: np.ndarray | None = None, own: float | None = None) -> tuple[int | None, str | None]:
        """The shell's voxels (counted only where the winding rule's solid
        is small against the area and a bound on the shell does not already
        show it is at least :data:`~isoflow.mesh.fills.THIN_SHARE` of it,
        else None) and :func:`~isoflow.mesh.fills.thin_solid`'s line.
        ``found``: where the grid is not held (``volume`` None), whether each
        of :meth:`sampled_points` is in, looked up as it was written.
        ``own``: the mesh's volume in voxels where it is known
        (:func:`winding_volume`), which the solid is judged against instead
        of the shell."""
        from .shell import grid_planes, surface_area
        from .shell_bound import shell_voxels_at_most

        Tm = self.Tm
        area = surface_area(Tm)
        if not area > 0:  # no area: nothing to bound, whatever the grid
            return None, NO_AREA if voxels == 0 else None
        if volume is not None:
            corner = self.origin + self.pitch * np.asarray(self.start)
            share = unbounded_area(Tm, volume, corner, self.pitch)
        else:
            points = self.sampled_points() if found is not None else None
            share = unbounded_share(points[1], found) if points is not None and found is not None else 0.0
        shell = None
        if voxels < THIN_TRIGGER * area / self.pitch**2:
            # a note for the share names the shell's count; otherwise the
            # count matters only where the solid may be under its share of it
            planes = grid_planes(self.origin, self.pitch, self.shape, self.start)
            if share >= UNBOUNDED_SHARE or shell_voxels_at_most(Tm, planes, int(voxels / THIN_SHARE)) is None:
                shell = self.shellcounted()
        return shell, thin_solid(voxels, shell, share, double_sided, own)


def winding_volume(T: np.ndarray, pitch: float, balanced: bool, stats) -> float | None:
    """The volume the triangles bound, in voxels, where the winding number
    is 0 or 1 (or 0 or -1) at every voxel centre, so that the volume is the
    solid's; None otherwise.

    Parameters
    ----------
    T : float64 ndarray (M, 3, 3)
        The triangles' corners, as the winding rule read them.
    pitch : float
        The voxels' side, in the triangles' units.
    balanced : bool
        Whether every edge is used as often one way as the other (no
        boundary chain: the winding number is an integer off the surface).
    stats : int sequence
        The fill's counts (``scanline._sweep``'s): voxels inside two or
        more layers, voxels of positive and of negative winding number.

    Returns
    -------
    float or None
        The signed volume (:func:`~isoflow.mesh.bodies.signed_volume`) over
        ``pitch**3``, of the sign of the winding numbers seen; None where
        the edges do not balance, a voxel lies inside two layers, both
        signs are seen or the volume has the other sign (overlapping or
        self-intersecting shells).

    Examples
    --------
    >>> import trimesh
    >>> T = trimesh.creation.box((3, 3, 3)).triangles
    >>> winding_volume(T, 1.0, True, [0, 27, 0, 0])
    27.0
    >>> winding_volume(T, 1.0, True, [0, 0, 27, 0]) is None  # inside out, yet the volume is positive
    True
    """
    from .bodies import signed_volume

    layered, positive, negative = (int(n) for n in stats[:3])
    if not balanced or layered or (positive and negative) or len(T) == 0:
        return None
    own = signed_volume(np.asarray(T, dtype=np.float64)) / pitch**3 * (-1 if negative else 1)
    return own if own > 0 else None


def plan_voxels(vertices, faces, *, pitch=None, resolution=None, grid=None):
    """Check the mesh and lay out the grid (nothing O(grid) is done):
    ``(v, f, shape, what, frame, origin, pitch)`` with the checked arrays and
    the scaled frame of :func:`isoflow.mesh.grid.voxel_grid`."""
    v, f = check_mesh(vertices, faces, where="voxelize")
    pitch, origin, shape, what, frame = voxel_grid(v, f, pitch, resolution)
    shift, e, origin_s, pitch_s = frame
    if grid is None:
        lo, hi, _ = mesh_bbox(v, f, "voxelize")
        check_placement(lo, hi, pitch, what)
    else:
        if resolution is not None:
            raise IsoflowError("voxelize: grid= needs pitch=, not resolution=")
        try:
            origin = np.asarray(grid[0], dtype=np.float64).reshape(3)
            shape = tuple(int(n) for n in grid[1])
        except (TypeError, ValueError, IndexError, OverflowError):
            raise IsoflowError(
                f"voxelize: grid must be (origin, shape), three numbers each, got {given_text(grid)}") from None
        if len(shape) != 3 or min(shape) < 1:
            raise IsoflowError(f"voxelize: grid shape must be three positive integers, got {given_text(grid[1])}")
        with np.errstate(over="ignore", invalid="ignore"):
            origin_s = np.ldexp(origin - shift, -e)
        if not np.all(np.isfinite(origin_s)):
            raise IsoflowError(
                f"voxelize: grid origin {origin.tolist()} is not finite or too far from the mesh")
    return v, f, shape, what, (shift, e, origin_s, pitch_s), origin, pitch


def grid_block(shape, window) -> tuple[tuple[int, int, int], tuple[int, ...]]:
    """``(start, shape)`` of the block ``window = (start, stop)`` of a grid
    of ``shape`` (the whole grid for None); IsoflowError for a block that
    is empty or not inside the grid."""
    if window is None:
        return (0, 0, 0), tuple(shape)
    try:
        lo = tuple(int(i) for i in window[0])
        hi = tuple(int(i) for i in window[1])
        ok = len(window) == 2
    except (TypeError, ValueError, IndexError, OverflowError):
        ok = False
    if not ok or len(lo) != 3 or len(hi) != 3 or not all(0 <= a < b <= n for a, b, n in zip(lo, hi, shape)):
        raise IsoflowError(f"voxelize: window must be (start, stop), three indices each with "
                           f"0 <= start < stop <= {tuple(shape)}, got {given_text(window)}")
    return lo, tuple(b - a for a, b in zip(lo, hi))


@overload
def voxelize(vertices: ArrayLike, faces: ArrayLike, *, pitch: float | None = None, resolution: int | np.integer | None = None,
             fill: Fill = "winding", strict: bool = False, grid=None, window=None, max_bytes: int | np.integer | None = None,
             write_bytes: float = 0, progress: Callable[[int, int], object] | None = None,
             details: Literal[False] = False, t_junctions: bool = True) -> tuple[np.ndarray, np.ndarray, float]: ...


@overload
def voxelize(vertices: ArrayLike, faces: ArrayLike, *, pitch: float | None = None, resolution: int | np.integer | None = None,
             fill: Fill = "winding", strict: bool = False, grid=None, window=None, max_bytes: int | np.integer | None = None,
             write_bytes: float = 0, progress: Callable[[int, int], object] | None = None,
             details: Literal[True], t_junctions: bool = True) -> Voxelization: ...


def voxelize(vertices: ArrayLike, faces: ArrayLike, *, pitch: float | None = None, resolution: int | np.integer | None = None,
             fill: Fill = "winding", strict: bool = False, grid=None, window=None, max_bytes: int | np.integer | None = None,
             write_bytes: float = 0, progress: Callable[[int, int], object] | None = None,
             details: bool = False, t_junctions: bool = True) -> tuple[np.ndarray, np.ndarray, float] | Voxelization:
    """Voxelise a triangle mesh: the solid it bounds, its shell, or both.

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
    fill : {"winding", "shell", "flood"}
        ``winding`` (default): voxel in iff the generalised winding number
        of its centre exceeds 1/2 in absolute value (the solid the mesh
        bounds).  ``shell``: every voxel whose closed cube the surface
        meets (:mod:`isoflow.mesh.shell`).  ``flood``: the shell and every
        voxel it encloses (no 6-path outside the shell to the outside of
        the grid).  See :mod:`isoflow.mesh.fills`.
    strict
        Refuse a mesh that is not watertight as given (see
        :func:`mesh_defects`; cracks at T-junctions, which are otherwise
        split and read closed, included) or has double-sided faces,
        instead of reading it by the generalised winding number; with ``fill="winding"`` also one whose voxels lie
        inside two or more layers or have winding numbers of both signs
        (overlapping or self-intersecting shells, as far as the voxel
        centres see them), and one whose solid is thin or empty against its
        shell, or a closed mesh's against its own volume
        (:func:`~isoflow.mesh.fills.thin_solid`).
    grid
        Optional ``(origin, shape)``: sample on this grid (with ``pitch``)
        instead of the one centred on the bounding box, e.g. to put voxel
        corners on integer coordinates when digitising unions of unit cubes.
    window
        Optional ``(start, stop)``, three voxel indices each: only this block
        of the grid is voxelised and returned, its voxel centres those of
        the whole grid bit for bit (``origin`` is then the block's lower
        corner).  Several meshes on one grid each fill the block their
        bounding box covers (:func:`isoflow.mesh.label_voxels.voxelize_meshes`).
    max_bytes
        Refuse (:class:`~isoflow.mesh.grid.GridTooLarge`, an IsoflowError)
        before allocating if the volume and the temporaries of a slab would
        need more.  Default: :func:`isoflow.scale.memory.default_budget`
        (90 % of the available memory).  The message names the finest grid
        that fits (the largest ``resolution=``, or the smallest ``pitch=``
        of three significant digits) and, where one would hold the grid,
        a zarr store (:func:`~isoflow.mesh.slabs.voxelize_to_zarr`).
    write_bytes
        Bytes per voxel that the caller needs beside the volume once it is
        made (0 by default), counted against ``max_bytes`` with the
        volume, up front and for the finest grid a refusal names: the
        copies a file's writer makes
        (:func:`~isoflow.mesh.volumes.write_bytes_per_voxel`), so that a
        volume let in is also written.
    progress
        Optional ``callable(done, total)``, called as the work advances
        (``PROGRESS_UNITS`` per slab); one with a ``rule`` method too
        (:class:`RuleProgress`) is told, before the work, whether the
        winding rule sums solid angles.
    details
        Return a :class:`~isoflow.mesh.fills.Voxelization` (the volume and
        what was found in the mesh) instead of ``(volume, origin, pitch)``;
        without it, the note, if any, is issued as a
        :class:`~isoflow.errors.MeshNote` warning.
    t_junctions
        Split boundary edges at the vertices of other faces that lie on
        them (T-junctions) where that closes them, as
        :func:`~isoflow.mesh.t_junctions.close_t_junctions` does (the
        default). False where the caller has made that split already, or
        knows it splits nothing: the search (a sort of the edges, then the
        boundary vertices tried against the open edges) is not made again;
        :func:`~isoflow.mesh.genus.verify_genus` makes it once for all its
        resolutions.

    Returns
    -------
    volume : bool ndarray (nx, ny, nz)
        With ``fill="winding"``, ``volume[i, j, k]`` is true iff the centre
        ``origin + pitch * (i + .5, j + .5, k + .5)`` has ``|w| > 1/2``.
        Borders are neither trimmed nor padded.
    origin : float64 (3,)
        Lower corner of voxel (0, 0, 0).
    pitch : float
        (Or, with ``details=True``, one :class:`Voxelization` holding them.)

    Raises
    ------
    IsoflowError
        Bad arrays, a grid that does not fit in memory, and what ``strict``
        refuses.

    Notes
    -----
    Exactness: on a closed, consistently oriented mesh the winding volume
    is the exact nonzero winding number with the tie rule of
    :mod:`isoflow.mesh.scanline` (a centre on a horizontal-ish face counts
    as below it: a box [z0, z1] holds the centres with z0 < z <= z1).  On
    any other mesh it is the generalised winding number rule, exact except
    where |w| is within rounding of 1/2 (:mod:`isoflow.mesh.winding`).  The
    shell is exact (closed cubes: touching counts).

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box((2, 2, 2))
    >>> vol, origin, pitch = voxelize(box.vertices, box.faces, resolution=4)
    >>> int(vol.sum()), int(voxelize(box.vertices, box.faces, resolution=4, fill="shell")[0].sum())
    (64, 56)
    """
    fill, strict = check_fill(fill), check_strict(strict)
    t_junctions = check_switch(t_junctions, "t_junctions", "voxelize")
    check_callable(progress, "progress", "progress(done, total)")
    v, f, shape, what, frame, origin, pitch = plan_voxels(
        vertices, faces, pitch=pitch, resolution=resolution, grid=grid)
    start, shape = grid_block(shape, window)
    origin = origin + pitch * np.asarray(start, dtype=np.float64)
    budget = memory.budget_of(max_bytes)
    write_bytes = check_write_bytes(write_bytes)
    solid: Solid | None = None

    def made() -> Solid:  # the mesh made ready once, for the grid asked and for those a refusal tries
        nonlocal solid
        if solid is None:
            solid = Solid(v, f, strict=strict, fill=fill, t_junctions=t_junctions)
        return solid

    def refuse(extra: int):
        # a grid laid by pitch= or resolution= alone: the message names the
        # finest one that fits (grid= and window= leave no other to name)
        whole = grid is None and window is None
        store = whole and store_holds(made(), frame, shape, budget)
        fit = finest_fit(v, f, what, shape,
                         lambda s, fr: in_memory(made(), fr, s, budget, write_bytes=write_bytes)[0]) if whole else None
        need = grid_need(shape, 1, extra)
        return GridTooLarge(what, grid_words(shape, need), budget, shape=shape, fit=fit, sought=whole, store=store,
                            beyond="" if need > budget else "more than one array can index",
                            hints=(ZARR_HINT if store else "", ""))

    # the volume itself, before anything O(grid): one byte per voxel
    if not grid_fits(shape, 1, 0, budget):
        raise refuse(0)
    fits, plan, temp = in_memory(made(), frame, shape, budget, start, write_bytes)
    if not fits:
        raise refuse(temp)
    assert plan is not None
    tell_rule(progress, plan.solid_angles)
    slabs = plan.slabs()
    vol = np.zeros(shape, dtype=bool)  # the sweep writes only the voxels inside
    stats = np.zeros(4, dtype=np.int64)  # see scanline._sweep: the last three add up to the voxels in
    for n, (a, b) in enumerate(slabs):
        step = None if progress is None else _share(progress, n, len(slabs))
        plan.fill(a, b, out=vol[a:b], stats=stats, threads=2, progress=step)
        if progress is not None:
            progress((n + 1) * PROGRESS_UNITS, len(slabs) * PROGRESS_UNITS)
    if fill == "flood":
        from ..scale.kernels import fill_enclosed

        vol = fill_enclosed(vol, inplace=True)
    made().check_layers(stats)
    voxels = int(np.count_nonzero(vol)) if fill == "flood" else int(stats[1:].sum())
    result = voxelization(made(), plan, vol, voxels, origin, pitch, stats, shell_before=int(stats[1:].sum()))
    if details:
        return result
    say_note(result.note)
    return vol, origin, pitch


def in_memory(solid: Solid, frame, shape, budget: int, start=(0, 0, 0),
              write_bytes: float = 0) -> tuple[bool, VoxelPlan | None, int]:
    """Whether voxelising the grid of ``shape`` (in the scaled ``frame`` of
    :func:`~isoflow.mesh.grid.voxel_grid`, or its block at ``start``) fits
    in ``budget`` bytes: its volume, a byte per voxel, and the larger of
    the temporaries of its largest slab and the ``write_bytes`` per voxel
    that the caller needs once the volume is made (the slabs' are freed by
    then). Returns ``(fits, plan, temporaries)``; no plan where the volume
    alone does not fit (nothing O(grid) is made then)."""
    if not grid_fits(shape, 1, 0, budget):
        return False, None, 0
    plan = solid.prepare(frame, frame[2], frame[3], shape, start)
    temp = max(plan.slab_bytes(plan.slab_rows()), grid_need(shape, write_bytes))
    return grid_fits(shape, 1, temp, budget), plan, temp


def check_write_bytes(write_bytes: object) -> float:
    """``write_bytes`` as given, a finite number from 0 on; anything else
    is refused naming it.

    Examples
    --------
    >>> check_write_bytes(2)
    2.0
    >>> check_write_bytes(-1)
    Traceback (most recent call last):
    ...
    isoflow.errors.IsoflowError: voxelize: write_bytes must be a number of bytes per voxel from 0 on, got -1
    """
    write_bytes = scalar_given(write_bytes)  # a 0D array of a number is that number
    ok = isinstance(write_bytes, (int, float, np.integer, np.floating)) and not isinstance(write_bytes, (bool, np.bool_))
    if not ok or not 0 <= float(write_bytes) < float("inf"):  # type: ignore[arg-type]
        raise IsoflowError(f"voxelize: write_bytes must be a number of bytes per voxel from 0 on, got {given_text(write_bytes)}")
    return float(write_bytes)  # type: ignore[arg-type]


def store_holds(solid: Solid, frame, shape, budget: int) -> bool:
    """Whether :func:`~isoflow.mesh.slabs.voxelize_to_zarr` could write
    the grid of ``shape`` (in the scaled ``frame``) to a zarr store within
    ``budget`` bytes, with its default chunks."""
    from .store_plan import in_store

    return in_store(solid, frame, shape, None, solid.fill, budget)[0]


def _share(progress, n: int, slabs: int):
    """Slab n's progress as a share of the whole."""
    return lambda done, total: progress(n * PROGRESS_UNITS + done * (PROGRESS_UNITS - 1) // total,
                                        slabs * PROGRESS_UNITS)


def voxelization(solid: Solid, plan: VoxelPlan, vol, voxels: int, origin, pitch: float, stats,
                 shell_before: int | None = None, found: np.ndarray | None = None) -> Voxelization:
    """The :class:`Voxelization` of a filled grid (``vol`` None for a
    store: then ``found``, whether each of the plan's sampled points is in,
    as the slabs looked them up, gives the share of unbounded area), with
    its note; with ``strict``, a thin or empty winding solid is refused
    here. ``shell_before``: a flood fill's shell, before the voxels it
    encloses."""
    notes = [solid.note(stats)]
    shell = None
    if solid.fill == "flood":  # a flood that leaked is the shell alone: said, not silent
        notes.append(flood_adds_nothing(voxels, shell_before, solid.census["boundary_edges"],
                                        int(np.prod(plan.shape))))
    if solid.fill == "winding":
        # a block that cuts the mesh holds only part of its volume
        own = winding_volume(plan.Tm, plan.pitch, not solid.chain_edges, stats) if plan.holds_mesh() else None
        shell, thin = plan.thin_note(vol, voxels, solid.double_sided, found, own)
        if thin and solid.strict:
            raise IsoflowError.worded(f"voxelize: {thin}; without strict=True the winding rule's answer is kept",
                                      f"voxelize: {thin}; without --strict the winding rule's answer is kept")
        if thin == NO_AREA:
            # no area bounds nothing: the defects' rule ("its edges balance, so it bounds a solid") would contradict it
            notes = [thin]
        else:
            notes.append(thin)
    note = "; ".join(n for n in notes if n) or None
    return Voxelization(volume=vol, origin=np.asarray(origin, dtype=np.float64), pitch=float(pitch),
                        fill=solid.fill, voxels=int(voxels), defects=solid.defects, flipped_faces=solid.flipped,
                        double_sided_faces=solid.double_sided, chain_edges=len(plan.E),
                        overlap_voxels=int(stats[0]), shell_voxels=shell, note=note)


def say_note(note: str | None) -> None:
    """Issue a voxelisation's note as a :class:`~isoflow.errors.MeshNote`
    warning (for callers that did not ask for the details)."""
    if note:
        warn(note, MeshNote)


def voxelized_object(vertices: ArrayLike, faces: ArrayLike, *, pitch: float | None, resolution: int | np.integer | None,
                     fill: Fill, strict: bool, write_bytes: float,
                     progress: Progress | None) -> tuple[DigitalObject, Voxelization]:
    """The mesh's :class:`~isoflow.results.DigitalObject` and its
    :class:`~isoflow.mesh.fills.Voxelization`, for :func:`voxelize_mesh`
    and :func:`voxelize_file`: at ``resolution=DEFAULT_RESOLUTION`` where
    neither ``pitch`` nor ``resolution`` is given (its refusals name the
    command: each function renames them,
    :meth:`~isoflow.errors.IsoflowError.called`).

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box((2, 2, 2))
    >>> obj, v = voxelized_object(box.vertices, box.faces, pitch=None, resolution=4, fill="winding", strict=False,
    ...                           write_bytes=0, progress=None)
    >>> obj.voxels, obj.pitch
    (64, 0.5)
    """
    if pitch is None and resolution is None:
        resolution = DEFAULT_RESOLUTION
    result = voxelize(vertices, faces, pitch=pitch, resolution=resolution, fill=fill, strict=strict,
                      write_bytes=write_bytes, progress=progress, details=True)
    assert result.volume is not None  # voxelize keeps the voxels in memory unless given a store
    # the voxeliser's array, which nothing writes again: held as it is, not copied
    return DigitalObject(handed_over(result.volume), pitch=result.pitch, origin=result.origin), result


@overload
def voxelize_mesh(vertices: ArrayLike | Any, faces: ArrayLike | None = None, *, pitch: float | None = None,
                  resolution: int | np.integer | None = None, fill: Fill = "winding", strict: bool = False,
                  write_bytes: float = 0,
                  progress: Progress | None = None, details: Literal[False] = False) -> DigitalObject: ...


@overload
def voxelize_mesh(vertices: ArrayLike | Any, faces: ArrayLike | None = None, *, pitch: float | None = None,
                  resolution: int | np.integer | None = None, fill: Fill = "winding", strict: bool = False,
                  write_bytes: float = 0,
                  progress: Progress | None = None, details: Literal[True]) -> tuple[DigitalObject, Voxelization]: ...


def voxelize_mesh(vertices: ArrayLike | Any, faces: ArrayLike | None = None, *, pitch: float | None = None,
                  resolution: int | np.integer | None = None, fill: Fill = "winding", strict: bool = False,
                  write_bytes: float = 0,
                  progress: Progress | None = None,
                  details: bool = False) -> DigitalObject | tuple[DigitalObject, Voxelization]:
    """A triangle mesh as a digital object: its solid, shell or flood fill.

    Parameters
    ----------
    vertices, faces
        As :func:`voxelize`; or a mesh alone (a ``trimesh.Trimesh``, any
        object with ``vertices`` and ``faces``, or a ``(vertices, faces)``
        pair) in place of ``vertices``, taken as its arrays are.
    pitch, resolution
        At most one; neither: ``resolution=DEFAULT_RESOLUTION``.
    fill, strict, write_bytes, progress
        As :func:`voxelize`.
    details
        Also return the :class:`~isoflow.mesh.fills.Voxelization`; without
        it, its note, if any, is issued as a
        :class:`~isoflow.errors.MeshNote` warning.

    Returns
    -------
    DigitalObject or (DigitalObject, Voxelization)
        The object carries the grid's pitch and origin, so its surfaces and
        flows export in the mesh's coordinates.

    Raises
    ------
    IsoflowError
        As :func:`voxelize`.

    Examples
    --------
    >>> import trimesh
    >>> box = trimesh.creation.box((2, 2, 2))
    >>> obj, v = voxelize_mesh(box.vertices, box.faces, resolution=4, fill="flood", details=True)
    >>> obj.voxels, v["fill"], v.note is None
    (64, 'flood', True)
    >>> voxelize_mesh(box, resolution=4).voxels
    64
    """
    details = check_switch(details, "details", "voxelize_mesh")
    # checked here too, so that a refusal names the function called
    check_fill(fill, "voxelize_mesh")
    check_strict(strict, "voxelize_mesh")
    if pitch is not None or resolution is not None:  # neither: the default resolution
        check_grid_request(pitch, resolution, "voxelize_mesh")
    try:
        if faces is None:
            # a Manifold goes to mesh_arrays, which names it: it has no faces, and "faces are missing" misled
            if not (isinstance(vertices, tuple) or hasattr(vertices, "faces") or is_scene(vertices)
                    or is_manifold(vertices)):
                raise IsoflowError("voxelize: faces are missing: voxelize_mesh(vertices, faces), or a mesh with "
                                   "vertices and faces (a trimesh.Trimesh or Scene) alone; a file: voxelize_file(path)")
            vertices, faces = mesh_arrays(vertices, "voxelize")
        obj, result = voxelized_object(vertices, faces, pitch=pitch, resolution=resolution, fill=fill, strict=strict,
                                       write_bytes=write_bytes, progress=progress)
    except IsoflowError as exc:  # the voxeliser's refusals, which the command shares, name the function called
        raise exc.called("voxelize_mesh", "voxelize") from None
    if details:
        return obj, result
    say_note(result.note)
    return obj


@overload
def voxelize_file(path: str | os.PathLike, *, pitch: float | None = None, resolution: int | np.integer | None = None,
                  fill: Fill = "winding", strict: bool = False, write_bytes: float = 0,
                  progress: Progress | None = None, details: Literal[False] = False) -> DigitalObject: ...


@overload
def voxelize_file(path: str | os.PathLike, *, pitch: float | None = None, resolution: int | np.integer | None = None,
                  fill: Fill = "winding", strict: bool = False, write_bytes: float = 0,
                  progress: Progress | None = None, details: Literal[True]) -> tuple[DigitalObject, Voxelization]: ...


def voxelize_file(path: str | os.PathLike, *, pitch: float | None = None, resolution: int | np.integer | None = None,
                  fill: Fill = "winding", strict: bool = False, write_bytes: float = 0,
                  progress: Progress | None = None,
                  details: bool = False) -> DigitalObject | tuple[DigitalObject, Voxelization]:
    """Read a mesh file (any format trimesh reads) and voxelise it.

    Parameters
    ----------
    path : str or Path
    pitch, resolution, fill, strict, write_bytes, progress, details
        As :func:`voxelize_mesh`.

    Returns
    -------
    DigitalObject or (DigitalObject, Voxelization)
        The object's ``unit`` is the length unit the file declares
        (:func:`~isoflow.mesh.mesh_units.declared_unit`: a 3MF model's, a
        glTF's metres, a COLLADA file's), None where its format holds none.

    Raises
    ------
    IsoflowError
        As :func:`load_mesh` and :func:`voxelize`, naming the file.

    Examples
    --------
    The sample torus at 32 voxels across: one component, one tunnel.

    >>> from isoflow import data
    >>> from isoflow.digital.topology import betti_numbers
    >>> obj = voxelize_file(data.torus(), resolution=32)
    >>> max(obj.volume.shape), betti_numbers(obj.volume)
    (32, [1, 1, 0])
    """
    # a trimesh, a Scene or a manifold3d.Manifold, or (vertices, faces): what voxelises each is named
    in_memory = voxeliser_of(path) or ("a mesh in memory: isoflow.voxelize_mesh(mesh, resolution=N)"
                                       if isinstance(path, tuple) or hasattr(path, "vertices") else "")
    path = check_path(path, "path", "voxelize_file", hint=in_memory)
    # before the file is read (voxelize checks the others), named as the function called
    check_fill(fill, "voxelize_file")
    check_strict(strict, "voxelize_file")
    details = check_switch(details, "details", "voxelize_file")
    if pitch is not None or resolution is not None:  # neither: the default resolution
        check_grid_request(pitch, resolution, "voxelize_file")
    v, f = load_mesh(path)
    try:
        obj, result = voxelized_object(v, f, pitch=pitch, resolution=resolution, fill=fill, strict=strict,
                                       write_bytes=write_bytes, progress=progress)
    except IsoflowError as exc:  # a refused grid keeps its kind and its command-line words
        raise exc.called("voxelize_file", "voxelize").at(path) from None
    unit = declared_unit(path)
    if unit is not None:  # the pitch and origin are in the file's unit, as a volume file's are
        obj = dataclasses.replace(obj, unit=unit)
    if details:
        return obj, result
    say_note(result.note)
    return obj
