"""The closed surfaces of an object's boundary and their genus, without
building the boundary mesh.

:func:`isoflow.digital.surface.boundary_mesh` splits the boundary into
closed surfaces by its local rules (docs/mathematics.md): edge contacts are
paired inside the object voxel under 6-connectivity and across the edge
under 26, and every vertex contact is split. Those rules make the mesh the
boundary of a solid ``M`` whose pieces are the object's components under an
adjacency of its own, and the complement's pieces the background's:

========  =================  =====================
object    ``M``'s object     ``M``'s background
========  =================  =====================
6         6 (faces)          18 (faces and edges)
26        18                 6
========  =================  =====================

(the vertex contacts that the split mesh separates although the
connectivity joins them are the *pinches*; they are why 18 appears). Every
boundary face separates an object voxel from a background voxel, so it
carries the pair of their labels under those adjacencies, and the faces of
one surface all carry the same pair (two faces meeting at a mesh edge share
an object voxel, or a background cell, or touch along the edge where the
adjacency joins them). Conversely one pair is one surface: in the 3-sphere
(unicoherent), a component ``D`` of the complement of a connected solid
``A`` has a connected boundary, so the surface between ``A`` and the part of
``D`` next to it is a single one. The closed surfaces are therefore the
label pairs that occur, and each one's

    chi(S) = V(S) - E(S) + F(S) = V(S) - F(S)      (E = 2F, every edge in two faces)

follows from counting, per pair, its mesh vertices (the sheets through a
lattice vertex, from :func:`~isoflow.digital.surface.sheet_lut`) and its
faces (a quarter at each of their four corners). The midpoints that the mesh
puts on doubled edges add one vertex and one edge each, which cancel.
``genus = 1 - chi / 2`` since every surface is a closed orientable manifold.

The surfaces and the components of ``M`` and of its complement form a
tree: every closed surface splits the 3-sphere in two, so it is an edge
between the two components it separates. Large host volumes use that
(:func:`surface_tree`): the compiled sweep of :mod:`isoflow.scale.sweep`, on
the volume as bit rows, labels the runs and gaps under the adjacencies
above and adds up, per component, the mesh vertices and faces of its whole
boundary (every sheet counts for its object and its background component);
a surface's counts are then those of the component below it in the tree
less those of the surfaces below that one. About 1.5 bytes per voxel on a
porous field, no label volume, no table of pairs; the blocks of the
out-of-core pass go through the same sweep and join the trees
(:mod:`isoflow.digital.outofcore`). Small volumes (cc3d labels and the
configuration array) count per label pair. All equal
``boundary_mesh(volume, connectivity).components()`` exactly
(the tests check it on thousands of random volumes).
"""

from __future__ import annotations

from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError
from ..scale.arrays import binary, count_codes, refuse_object
from ..scale.compiled import Method, thread_count, use_compiled
from ..scale.memory import check_fits
from .configurations import configurations
from .connectivity import check_connectivity, resolve_connectivity
from .measures import extent_of_rows
from .report import SurfaceCensus
from .surface import boundary_faces, doubled_spoke_lut, pinch_lut, sheet_lut, slot_octants

#: connectivity -> (object adjacency, background adjacency) of the mesh's solid
MESH_ADJACENCY = {6: (6, 18), 26: (18, 6)}


@cache
def sweep_tables(connectivity: int = 6) -> tuple[np.ndarray, ...]:
    """Per-configuration tables of the sheets, for the passes here.

    Returns ``(nsheet, sheet_obj, sheet_bg, sheet_quarters, spokes, pinch)``:
    the number of sheets (256,); per sheet (256, 4) the octant of the object
    voxel and of the background voxel that one of its faces separates, and
    its number of faces; ``spokes`` (256,) with bit ``2 axis + side`` set
    where :func:`~isoflow.digital.surface.doubled_spoke_lut` is; ``pinch``
    (256, 2), the two opposite octants of a pinch (object ones under 26,
    background ones under 6), -1 elsewhere.
    """
    check_connectivity(3, connectivity)
    sheets = sheet_lut(connectivity)
    nsheet = (sheets.max(axis=1) + 1).astype(np.int8)
    sheet_obj = np.full((256, 4), -1, np.int8)
    sheet_bg = np.full((256, 4), -1, np.int8)
    quarters = np.zeros((256, 4), np.int8)
    for c in range(256):
        for slot in range(12):
            s = sheets[c, slot]
            if s < 0:
                continue
            quarters[c, s] += 1
            lo, hi = slot_octants(slot)
            obj, bg = (lo, hi) if (c >> lo) & 1 else (hi, lo)
            sheet_obj[c, s], sheet_bg[c, s] = obj, bg
    doubled = doubled_spoke_lut(connectivity)
    spokes = np.zeros(256, np.uint8)
    for axis in range(3):
        for side in (0, 1):
            spokes |= doubled[:, axis, side].astype(np.uint8) << (2 * axis + side)
    pinch = np.full((256, 2), -1, np.int8)
    for config in np.flatnonzero(pinch_lut(connectivity)):
        pair = int(config) if connectivity == 26 else 255 ^ int(config)
        pinch[config] = [o for o in range(8) if (pair >> o) & 1]
    # The sweep counts a run of equal "layer" configurations (the same four
    # voxels on both sides of the vertex) in one step: it relies on their
    # sheets having four faces each and no doubled spoke.
    layers = [n | (n << 4) for n in range(1, 15)]
    assert (spokes[layers] == 0).all()
    assert all((quarters[c, : nsheet[c]] == 4).all() for c in layers)
    return nsheet, sheet_obj, sheet_bg, quarters, spokes, pinch


def surfaces_from_counts(vertices: np.ndarray, quarters: np.ndarray) -> list[dict]:
    """The report's surfaces from each pair's mesh vertices and quarter
    faces, largest first."""
    vertices = np.asarray(vertices, np.int64)
    quarters = np.asarray(quarters, np.int64)
    assert (quarters % 4 == 0).all(), "every face has four corners"
    faces = quarters // 4
    chi = vertices - faces
    order = np.lexsort((chi, -faces))
    return [
        {"euler_characteristic": int(chi[c]), "genus": int(1 - chi[c] // 2), "faces": int(faces[c])}
        for c in order
    ]


def closed_surfaces(volume: ArrayLike, connectivity: int | None = 6, method: Method = "auto") -> SurfaceCensus:
    """The closed surfaces of the boundary of a 3D host volume and their genus.

    The surfaces are read off the labels of the object and background
    pieces on either side of every boundary face, under the adjacencies
    the boundary mesh's own pairing rules give (see the module), so the
    mesh is never built.

    Parameters
    ----------
    volume : array_like of bool or 0/1, 3D
    connectivity : {6, 26} or None
        The object's (None: the paper's 6, as for :func:`isoflow.analyze`).
    method : {"auto", "numpy", "compiled"}
        One compiled sweep, the NumPy census, or by the volume's size.

    Returns
    -------
    SurfaceCensus
        Each surface's Euler characteristic, genus and faces, the pinched
        vertices and doubled edges, the configuration histogram and the
        Betti counts of the same pass.

    Examples
    --------
    Two voxels meeting along an edge are two spheres under 6-connectivity;
    under 26 one surface passes the edge twice (a doubled edge):

    >>> import numpy as np
    >>> v = np.zeros((2, 2, 1), bool)
    >>> v[0, 0, 0] = v[1, 1, 0] = True
    >>> [s["genus"] for s in closed_surfaces(v, 6).surfaces]
    [0, 0]
    >>> c = closed_surfaces(v, 26)
    >>> [s["genus"] for s in c.surfaces], c.doubled_edges
    ([0], 1)
    """
    # canonical bools (binary makes them: a bool array made by .view(bool)
    # may hold bytes other than 0/1, which the configurations and cc3d would
    # read as values); other values refused as analyze refuses them (a
    # conversion to bool first read 2 or NaN as True)
    refuse_object(volume, "closed_surfaces")
    vol = binary(volume)
    if vol.ndim != 3:
        raise IsoflowError(f"closed_surfaces needs a 3D volume, got a {vol.ndim}D array")
    connectivity = resolve_connectivity(3, connectivity)  # as an int
    census = compiled_census(vol, connectivity) if use_census(vol, method=method) else small_census(vol, connectivity)
    return SurfaceCensus(surfaces=census["surfaces"], pinched_vertices=census["pinched_vertices"],
                         doubled_edges=census["doubled_edges"], hist=census["hist"],
                         betti_counts=tuple(census["betti_counts"]))


#: peak bytes of :func:`small_census`: per voxel (the int32 labels of both
#: sides, their padded copies, the configurations) and per mesh vertex (the
#: sheets' labels, octants and flat indices); measured with tracemalloc at
#: 20-23 and 81-85 on a ball, a torus, porous fields and noise
SMALL_BYTES_PER_VOXEL = 24
SMALL_BYTES_PER_SHEET = 96


def small_census(vol: np.ndarray, conn: int) -> dict:
    """What :func:`compiled_census` gives, by NumPy and cc3d, for a 3D host
    volume (bool, 0/1 bytes) below the compiled pass's size: one
    configuration array, the labels of the volume and of its background
    padded by one layer (the outside is one background component) under the
    mesh's adjacencies, and one more labelling for the Betti counts. The
    mesh's adjacency is the connectivity's on one side (the object's under
    6, the background's under 26); the other side is labelled again under
    the connectivity's own (26 for the background under 6, for the object
    under 26) rather than joined through the pinches."""
    from ..scale.labels import label

    cfg = configurations(vol)
    hist = count_codes(np, cfg, 256)
    sheets = int(hist @ sweep_tables(conn)[0])
    check_fits(SMALL_BYTES_PER_VOXEL * vol.size + SMALL_BYTES_PER_SHEET * sheets,
               f"labelling a {'x'.join(map(str, vol.shape))} volume for its surfaces and Betti numbers",
               hint="store it as .zarr and run isoflow info on that (block by block)")
    obj_adj, bg_adj = MESH_ADJACENCY[conn]
    obj_labels, nobj = label(vol, obj_adj)
    background = np.pad(~vol, 1, constant_values=True)
    bg_padded, nbg = label(background, bg_adj)
    if conn == 6:
        b0, enclosed = nobj, label(background, 26)[1] - 1
    else:
        b0, enclosed = label(vol, 26)[1], nbg - 1
    outside = int(bg_padded[0, 0, 0])
    whole = tuple(slice(None) for _ in range(3))
    found = box_sheets(vol, obj_labels, bg_padded[1:-1, 1:-1, 1:-1], whole, conn, outside, cfg=cfg)
    # doubled lattice edges: a spoke doubled at both ends (bit 2 axis + 1 of
    # the lower end, bit 2 axis of the upper), on small uint8 arrays
    spokes = sweep_tables(conn)[4][cfg]
    doubled = 0
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        doubled += int(np.count_nonzero((spokes[tuple(lo)] >> (2 * axis + 1)) & (spokes[tuple(hi)] >> (2 * axis)) & 1))
    return {
        "hist": hist,
        "betti_counts": (b0, enclosed),
        "surfaces": surfaces_from_counts(found["vertices"], found["quarters"]),
        "pinched_vertices": int(hist[pinch_lut(conn)].sum()),
        "doubled_edges": doubled,
    }


def box_sheets(vox: np.ndarray, obj_labels: np.ndarray, bg_labels: np.ndarray, keep, conn: int, outside,
               cfg: np.ndarray | None = None) -> dict:
    """Sheets of some vertices of a box of voxels, summed per label pair.

    ``vox``: the box (bool); ``obj_labels``/``bg_labels``: integer labels of
    its object / background voxels (any numbering: local labels, node keys);
    ``keep``: slices of the box's vertex array (shape ``vox.shape + 1``)
    choosing the vertices to count; octants outside the box are background
    labelled ``outside`` (only vertices whose octants outside the box really
    are outside the volume may be kept). Returns the distinct pairs
    (``obj``, ``bg`` label arrays), their mesh ``vertices`` and ``quarters``
    of faces, and the pinch ``pairs`` (labels of the two octants to join for
    the connectivity's components: object labels under 26, background under
    6). Used by the small path (:func:`small_census`: no numba below
    :func:`~isoflow.scale.compiled.least_voxels`). ``cfg``:
    ``configurations(vox)``, where the caller has it.
    """
    nsheet, sheet_obj, sheet_bg, quarters, _, pinch = sweep_tables(conn)
    cfg = (configurations(vox) if cfg is None else cfg)[keep]
    origin = np.array([k.indices(n + 1)[0] for k, n in zip(keep, vox.shape)])
    # (C order: the flat views below are indexed with these strides)
    obj_padded = np.ascontiguousarray(np.pad(obj_labels, 1))
    bg_padded = np.ascontiguousarray(np.pad(bg_labels, 1, constant_values=outside))
    # vertex w's octant d is the padded voxel w + d, at flat index base(w) +
    # step[d] of the padded labels
    strides = np.array(obj_padded.strides) // obj_padded.itemsize
    bg_strides = np.array(bg_padded.strides) // bg_padded.itemsize
    octant = np.array([[o & 1, (o >> 1) & 1, o >> 2] for o in range(8)])
    step, bg_step = octant @ strides, octant @ bg_strides
    flat = cfg.ravel()
    on = np.flatnonzero(nsheet[flat])
    c_on = flat[on]
    corner = np.unravel_index(on, cfg.shape)
    base = sum((c + o) * s for c, o, s in zip(corner, origin, strides))
    bg_base = sum((c + o) * s for c, o, s in zip(corner, origin, bg_strides))
    obj_flat, bg_flat = obj_padded.ravel(), bg_padded.ravel()
    objs, bgs, quarter = [], [], []
    for s in range(int(nsheet.max(initial=0))):
        has = nsheet[c_on] > s
        c = c_on[has]
        objs.append(obj_flat[base[has] + step[sheet_obj[c, s]]])
        bgs.append(bg_flat[bg_base[has] + bg_step[sheet_bg[c, s]]])
        quarter.append(quarters[c, s])
    obj, bg = np.concatenate(objs).astype(np.int64), np.concatenate(bgs).astype(np.int64)
    found = _pair_sums(obj, bg, np.concatenate(quarter).astype(np.int64))
    pinched = pinch[c_on, 0] >= 0
    side_obj = conn == 26  # the pinch joins two object octants under 26
    either = []
    for e in (0, 1):
        oct_ = pinch[c_on[pinched], e]
        either.append(obj_flat[base[pinched] + step[oct_]] if side_obj else bg_flat[bg_base[pinched] + bg_step[oct_]])
    ends = np.stack(either, axis=1).astype(np.int64).reshape(-1, 2)
    found["pairs"] = ends[ends[:, 0] != ends[:, 1]]  # only those that join two pieces
    return found


def _pair_sums(obj: np.ndarray, bg: np.ndarray, quarter: np.ndarray) -> dict:
    """The distinct (``obj``, ``bg``) label pairs of the sheets, in order,
    with each one's ``vertices`` (sheets) and ``quarters`` (summed).

    A whole volume's labels are 1..n on each side, so the pairs are counted
    in bins, without sorting (three sorts took two thirds of the small
    path's time); labels spread wider (node keys out of core) are sorted."""
    if len(obj) == 0:
        return {"obj": obj, "bg": bg, "vertices": obj.copy(), "quarters": obj.copy()}
    lo_o, lo_b = int(obj.min()), int(bg.min())
    span_o, span_b = int(obj.max()) - lo_o + 1, int(bg.max()) - lo_b + 1
    if span_o * span_b <= max(1 << 16, 4 * len(obj)):
        key = (obj - lo_o) * span_b + (bg - lo_b)
        vertices = np.bincount(key, minlength=span_o * span_b)
        pair = np.flatnonzero(vertices)
        quarters = np.bincount(key, weights=quarter, minlength=span_o * span_b)[pair]
        return {"obj": pair // span_b + lo_o, "bg": pair % span_b + lo_b, "vertices": vertices[pair],
                "quarters": quarters.astype(np.int64)}
    uo, io = np.unique(obj, return_inverse=True)
    ub, ib = np.unique(bg, return_inverse=True)
    pair, inverse = np.unique(io * len(ub) + ib, return_inverse=True)
    return {
        "obj": uo[pair // len(ub)],
        "bg": ub[pair % len(ub)],
        "vertices": np.bincount(inverse, minlength=len(pair)).astype(np.int64),
        "quarters": np.bincount(inverse, weights=quarter, minlength=len(pair)).astype(np.int64),
    }


def compiled_census(vol: np.ndarray, conn: int, surfaces: bool = True) -> dict:
    """One compiled pass over a large host volume (:func:`use_compiled`):
    ``hist`` (the 256 configuration counts), ``betti_counts`` (b0 and the
    enclosed background components under ``conn``) and, with ``surfaces``,
    what :func:`closed_surfaces` returns.

    The volume as bit rows, then the sweep, which labels the runs and gaps
    under the mesh's adjacencies and adds up, per component, the vertices
    and faces of its whole boundary; the surfaces follow from the tree of
    components (:func:`surface_tree`). The pinches found by the sweep join
    the components into the connectivity's own for the Betti numbers.
    ``extent``: the voxels' :class:`~isoflow.digital.measures.Extent` (None
    where there are none), read off the bit rows, an eighth of the volume."""
    from ..scale import bitrows

    bits, off, goff = bitrows.pack(vol)
    extent = extent_of_rows(*bitrows.row_extents(bits, thread_count(vol.size)), vol.shape)
    return {**census_of_rows(bits, vol.shape, off, goff, conn, surfaces), "extent": extent}


def census_of_rows(bits: np.ndarray, shape: tuple[int, int, int], off: np.ndarray, goff: np.ndarray, conn: int,
                   surfaces: bool = True) -> dict:
    """:func:`compiled_census` of a volume held as bit rows: ``bits``,
    ``off`` and ``goff`` as :func:`isoflow.scale.bitrows.pack` gives them
    for a non-empty volume of ``shape``."""
    from ..scale import kernels, sweep

    obj_adj, bg_adj = MESH_ADJACENCY[conn]
    found = sweep.sweep(bits, shape, off, goff, kernels.ADJACENCY[obj_adj] + kernels.ADJACENCY[bg_adj],
                        sweep_tables(conn), pinch_objects=conn == 26, surfaces=surfaces)
    starts = (bits[:-1, 0] & 1).astype(np.int64)  # 1: the row starts with a run
    del bits
    (pobj, pbg), pairs = found["parents"], found["pairs"]
    nobj, nbg = (len(r) for r in found["roots"])
    # the pinches join components into the connectivity's own: object ones
    # under 26, background ones under 6
    if conn == 26:
        b0, enclosed = kernels.join_pairs(np.arange(nobj, dtype=np.int32), pobj[pairs]), nbg - 1
    else:
        b0, enclosed = nobj, kernels.join_pairs(np.arange(nbg, dtype=np.int32), pbg[pairs]) - 1
    hist = found["hist"]
    out = {"hist": hist, "betti_counts": (b0, enclosed)}
    if surfaces:
        vertices, faces = surface_tree(found["roots"], found["parents"], found["sums"], off, goff, starts)
        # every face is on one surface (the Euler characteristics are
        # checked by the caller: they add up to 2 chi + 2 pinched)
        assert faces.sum() == boundary_faces(hist), "the surfaces' faces do not add up"
        out.update(surfaces=surfaces_from_counts(vertices, 4 * faces),
                   pinched_vertices=int(hist[pinch_lut(conn)].sum()), doubled_edges=found["doubled"])
    return out


def warm_up(surfaces: bool = True) -> None:
    """Load the compiled pass now, on a tiny volume: importing numba and
    loading its cached machine code takes about half a second once per
    process, which a command spends while it reads its input."""
    vol = np.zeros((2, 2, 3), bool)
    vol[0, 0, 1] = True
    vol.flags.writeable = False  # as an object holds its volume: numba compiles read-only arrays apart
    compiled_census(vol, 6, surfaces)


def use_census(vol: np.ndarray, surfaces: bool = True, method: Method = "auto") -> bool:
    """Whether :func:`compiled_census` counts a 3D volume, with or without
    the ``surfaces``: by :func:`~isoflow.scale.compiled.use_compiled`, whose
    ``"auto"`` threshold is higher with the surfaces (the NumPy census holds
    out to a larger size, as numba's start is then the larger part of the
    compiled one's time). Never for an empty or a device volume."""
    if vol.ndim != 3 or not isinstance(vol, np.ndarray) or vol.size == 0:
        use_compiled(vol, surfaces, method)  # (refuses "compiled" where it cannot be)
        return False  # (an empty volume: nothing to sweep, no slab to split)
    return use_compiled(vol, surfaces, method)


def component_parents(roots, parents, off, goff, starts) -> tuple[np.ndarray, int]:
    """Every component's parent in the tree of the surfaces, and the root.

    Parameters
    ----------
    roots : tuple of numpy.ndarray
        The object's and the background's components: each one's smallest
        node (run, gap), :func:`isoflow.scale.sweep.sweep`'s ``roots``.
    parents : tuple of numpy.ndarray
        The component of every run and of every gap (the outside the last
        gap node), the sweep's ``parents``.
    off, goff : numpy.ndarray
        Where each row's runs and gaps start in their numbering
        (:func:`isoflow.scale.bitrows.pack`).
    starts : numpy.ndarray
        1 for the rows that start with a run.

    Returns
    -------
    up : numpy.ndarray
        The parent of every component, the object's first, then the
        background's; the root its own.
    root : int
        The index of the outside's component.

    Notes
    -----
    The components of the object and of the background form a tree whose
    edges are the surfaces, rooted at the outside's component. A
    component's parent is the one holding the voxel just before its first
    voxel in C order: that voxel lies outside the component and everything
    it encloses (else one of those would come first), and is
    face-adjacent to it. A component whose first voxel starts a row has no
    voxel before it in the row: an object one gets the root, a background
    one (which the sweep joins to the outside in a whole volume) the root
    or another component.

    Examples
    --------
    >>> from isoflow.scale import bitrows, kernels, sweep
    >>> v = np.ones((3, 3, 3), bool); v[1, 1, 1] = False  # a cavity
    >>> bits, off, goff = bitrows.pack(v)
    >>> found = sweep.sweep(bits, v.shape, off, goff, kernels.ADJACENCY[6] + kernels.ADJACENCY[18],
    ...                     sweep_tables(6), pinch_objects=False)
    >>> up, root = component_parents(found["roots"], found["parents"], off, goff, (bits[:-1, 0] & 1).astype(int))
    >>> up.tolist(), root  # the object (0) in the outside (2), the cavity (1) in the object
    ([2, 0, 2], 2)
    """
    (obj_roots, bg_roots), (pobj, pbg) = roots, parents
    nobj = len(obj_roots)
    outside = nobj + int(pbg[-1])
    # the object component's first run is the m-th of its row: the gap
    # before it is the row's m-th (less one if the row starts with a run),
    # or the outside where m = 0 and the row starts with a run
    row = np.searchsorted(off, obj_roots, side="right") - 1
    gap = goff[row] + (obj_roots - off[row]) - starts[row]
    up_obj = np.where(gap < goff[row], outside, nobj + pbg[np.maximum(gap, 0)])
    # a background component's first gap (not at a row's start: it would
    # touch the outside) follows the row's m-th run (m-1-th if the row
    # starts with a gap)
    row = np.minimum(np.searchsorted(goff, bg_roots, side="right"), len(starts)) - 1  # the outside: any
    run = off[row] + (bg_roots - goff[row]) - (1 - starts[row])
    inner = (np.arange(len(bg_roots)) != outside - nobj) & (run >= 0) & (run < len(pobj))
    up_bg = np.full(len(bg_roots), outside)
    up_bg[inner] = pobj[run[inner]]
    up = np.concatenate([up_obj, up_bg])
    up[outside] = outside
    return up, outside


def surface_tree(roots, parents, sums, off, goff, starts) -> tuple[np.ndarray, np.ndarray]:
    """The surfaces' mesh vertices and faces from sums over the whole
    boundary of every component.

    A component's boundary is its parent surface and its children's
    (:func:`component_parents`), so from the leaves up, a surface's sums
    (``sums``: per component ``4 chi`` and ``F`` of its boundary) are its
    child's less those of the child's own children: the signed sum (object
    +, background -) over the child's subtree. The root's sums are not
    needed (nor counted right: the sweep's formulas see only the array).
    Returns per surface (as many as non-root components) its mesh vertices
    and faces.
    """
    up, outside = component_parents(roots, parents, off, goff, starts)
    nobj = len(roots[0])
    signed = np.concatenate([sums[0], -sums[1]])
    signed[outside] = 0
    total = subtree_sums(up, outside, signed)
    total[nobj:] *= -1
    edges = np.arange(len(up)) != outside
    return surface_counts(total[edges])


def surface_counts(total: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mesh vertices and faces of closed surfaces from their sums.

    Parameters
    ----------
    total : numpy.ndarray
        Rows ``(4 chi, F)``, one per surface.

    Returns
    -------
    vertices, faces : numpy.ndarray
        ``V = chi + F`` (every edge in two faces: ``chi = V - E + F = V -
        F``) and ``F``.

    Examples
    --------
    >>> [x.tolist() for x in surface_counts(np.array([[8, 6], [0, 16]]))]  # a cube, a torus
    [[8, 16], [6, 16]]
    """
    chi4, faces = total[:, 0], total[:, 1]
    assert (chi4 % 4 == 0).all(), "a surface's Euler characteristic is an integer"
    return chi4 // 4 + faces, faces


def subtree_sums(up: np.ndarray, root: int, values: np.ndarray) -> np.ndarray:
    """Sums of ``values`` (rows) over every node's subtree in the tree given
    by each node's parent ``up`` (the root its own), level by level from
    the deepest."""
    depth = (np.arange(len(up)) != root).astype(np.int64)
    anc = up.copy()
    while (anc != root).any():  # pointer jumping: log(depth) steps
        depth += depth[anc]  # the root's depth stays 0
        anc = anc[anc]
    total = np.array(values, np.int64)
    order = np.argsort(depth, kind="stable")
    ends = np.searchsorted(depth[order], np.arange(depth.max(initial=0) + 2))
    for d in range(depth.max(initial=0), 0, -1):
        nodes = order[ends[d]:ends[d + 1]]
        np.add.at(total, up[nodes], total[nodes])
    return total
