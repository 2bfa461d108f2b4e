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

import sys
from functools import cache

import numpy as np
from numpy.typing import ArrayLike

from ..errors import IsoflowError
from ..scale.arrays import binary, refuse_object
from ..scale.compiled import Method, thread_count, use_compiled
from ..scale.memory import check_fits
from .configurations import configurations, empty_histogram
from .connectivity import check_connectivity, resolve_connectivity
from .measures import extent_of_rows
from .report import ClosedSurfaces, SurfaceCensus
from .surface import boundary_faces, doubled_spoke_lut, pinch_lut, sheet_lut, slot_octants

#: connectivity -> (object adjacency, background adjacency) of the mesh's solid
MESH_ADJACENCY = {6: (6, 18), 26: (18, 6)}

#: one more than the most faces a sheet has at one vertex (seven: a vertex
#: with one background octant)
QUARTER_SPAN = 8


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
    # the small path visits the configurations 1 .. 254 as the boundary's
    # and keeps each sheet's faces in one digit of its count
    assert (nsheet[1:255] > 0).all() and quarters.max() < QUARTER_SPAN
    return nsheet, sheet_obj, sheet_bg, quarters, spokes, pinch


def surfaces_from_counts(vertices: np.ndarray, quarters: np.ndarray) -> ClosedSurfaces:
    """The report's surfaces from each pair's mesh vertices and quarter
    faces, largest first (most faces, then least Euler characteristic)."""
    vertices = np.asarray(vertices, np.int64)
    quarters = np.asarray(quarters, np.int64)
    assert (quarters % 4 == 0).all(), "every face has four corners"
    faces = quarters // 4
    chi = vertices - faces
    order = np.lexsort((chi, -faces))
    return ClosedSurfaces(chi[order], faces[order])


def closed_surfaces(volume: ArrayLike, connectivity: int | np.integer | None = 6, method: Method = "auto") -> SurfaceCensus:
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
        One compiled sweep, the NumPy census, or ``"auto"``: the compiled
        sweep from 4 million voxels on, counting those that ``"auto"`` has
        already sent down the NumPy census in this process (many small
        volumes take it once they add up to that), or at any size once it
        is loaded in this process (a compiled pass ran here:
        :func:`use_census`). The answer is the same either way.

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
    refuse_object(volume, "closed_surfaces: volume")
    vol = binary(volume, "closed_surfaces: volume")
    if vol.ndim != 3:
        raise IsoflowError(f"closed_surfaces needs a 3D volume, got a {vol.ndim}D array")
    connectivity = resolve_connectivity(3, connectivity)  # as an int
    if vol.size == 0:
        census = empty_census(vol.shape)
    else:
        compiled = use_census(vol, method=method, record=True)
        census = compiled_census(vol, connectivity) if compiled else small_census(vol, connectivity)
    return SurfaceCensus(surfaces=census["surfaces"], pinched_vertices=census["pinched_vertices"],
                         doubled_edges=census["doubled_edges"], hist=census["hist"],
                         betti_counts=tuple(census["betti_counts"]))


#: peak bytes of :func:`small_census`: per voxel (the int32 labels of both
#: sides on the padded grid, the padded volume, its complement and its
#: configurations) and per mesh vertex (the boundary vertices' indices and
#: configurations, the sheets' labels, offsets and bins); measured with
#: tracemalloc at 13-14 and up to 35 on a ball, a torus, porous fields and
#: noise
SMALL_BYTES_PER_VOXEL = 16
SMALL_BYTES_PER_SHEET = 48


def small_census(vol: np.ndarray, conn: int) -> dict:
    """What :func:`compiled_census` gives, by NumPy and cc3d, for a 3D host
    volume (bool, 0/1 bytes) below the compiled pass's size.

    The volume is padded by one layer of background once, and everything
    is laid out on that padded grid: the configuration of vertex ``w`` sits
    at the padded voxel ``w`` (:func:`padded_configurations`), so each of
    its octants is the padded voxel at a fixed flat offset from it, and the
    labels of the object and of the background (the outside one component)
    under the mesh's adjacencies are read there without copies. Only the
    boundary vertices (neither all object nor all background) are visited.
    The connectivity's own components, for the Betti counts, are the
    mesh's joined at the pinches (the object's under 26, the background's
    under 6: two voxels that meet at a vertex alone are joined by the
    18-adjacency through any third voxel of their kind at that vertex), as
    the compiled pass joins them, rather than a third labelling."""
    from ..scale.labels import label

    # C ordered whatever the caller's layout: np.pad keeps a Fortran array's
    # order, and the octant steps and the labels' flat indices assume C
    padded = np.zeros(np.add(vol.shape, 2), dtype=bool)
    padded[1:-1, 1:-1, 1:-1] = vol
    cfg = padded_configurations(padded)
    flat = cfg.ravel()
    on = np.flatnonzero(flat - np.uint8(1) < 254)  # (configurations 1 .. 254: the boundary's)
    c_on = flat[on]
    hist = np.bincount(c_on, minlength=256)
    hist[255] = np.count_nonzero(flat == 255)
    hist[0] = np.prod(np.add(vol.shape, 1)) - hist.sum()
    check_fits(SMALL_BYTES_PER_VOXEL * vol.size + SMALL_BYTES_PER_SHEET * int(hist @ sweep_tables(conn)[0]),
               f"labelling a {'x'.join(map(str, vol.shape))} volume for its surfaces and Betti numbers",
               hint="store it as .zarr and run isoflow info on that (block by block)")
    obj_adj, bg_adj = MESH_ADJACENCY[conn]
    obj_labels, nobj = label(padded, obj_adj)
    bg_labels, nbg = label(~padded, bg_adj)
    strides = np.array(padded.strides) // padded.itemsize  # (every array here is C ordered, of this shape)
    rare = np.flatnonzero(_rare_configurations(conn).take(c_on))
    found = _sheet_sums(on, c_on, rare, (obj_labels.ravel(), bg_labels.ravel()), _octant_steps(strides), conn,
                       spans=(nobj + 1, nbg + 1))
    if conn == 6:
        b0, enclosed = nobj, joined_count(nbg, found["pairs"]) - 1
    else:
        b0, enclosed = joined_count(nobj, found["pairs"]), nbg - 1
    return {
        "hist": hist,
        "betti_counts": (b0, enclosed),
        "surfaces": surfaces_from_counts(found["vertices"], found["quarters"]),
        "pinched_vertices": int(hist[pinch_lut(conn)].sum()),
        "doubled_edges": _doubled_edges(on[rare], c_on[rare], strides, conn),
    }


def padded_configurations(padded: np.ndarray) -> np.ndarray:
    """The configurations of a 3D volume padded by one layer of
    background (bool), on the padded grid: vertex ``w`` (``0 <= w <=
    volume.shape``) at index ``w``, its octant ``d`` being the padded voxel
    ``w + d``, as in :func:`~isoflow.digital.configurations.configurations`;
    the last layer along each axis (no vertex) holds 0.

    Examples
    --------
    >>> c = padded_configurations(np.pad(np.ones((1, 1, 1), bool), 1))
    >>> c.shape, sorted(int(x) for x in c[:2, :2, :2].ravel()), int(c[2].max())
    ((3, 3, 3), [1, 2, 4, 8, 16, 32, 64, 128], 0)
    """
    code = padded.astype(np.uint8)
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        # (the shifted copy is made before the in-place or: no overlap)
        code[tuple(lo)] |= code[tuple(hi)] << (1 << axis)
    return code


def _octant_steps(strides: np.ndarray) -> np.ndarray:
    """The flat offsets of the eight octants of a vertex from its own index,
    on a C-ordered grid of these element ``strides`` (octant ``d`` is bit
    ``d_0 + 2 d_1 + 4 d_2``)."""
    octant = np.array([[o & 1, (o >> 1) & 1, o >> 2] for o in range(8)])
    return octant @ strides


@cache
def _rare_configurations(connectivity: int = 6) -> np.ndarray:
    """The configurations (256, bool) with more than one sheet, a pinch or
    a doubled spoke: the few boundary vertices that :func:`_sheet_sums` and
    :func:`_doubled_edges` look at one by one, past every vertex's first
    sheet."""
    nsheet, _, _, _, spokes, pinch = sweep_tables(connectivity)
    return (nsheet > 1) | (pinch[:, 0] >= 0) | (spokes != 0)


def _sheet_sums(base: np.ndarray, c_on: np.ndarray, rare: np.ndarray, labels: tuple[np.ndarray, np.ndarray],
                step: np.ndarray, conn: int, spans: tuple[int, int] | None = None) -> dict:
    """The sheets of some boundary vertices summed per label pair.

    ``base``: the flat index (int64) of each vertex's octant 0 in the flat
    object and background ``labels``, whose octant ``d`` is at ``base +
    step[d]``; ``c_on``: the vertices' configurations (none 0 or 255);
    ``rare``: the positions of those of :func:`_rare_configurations`;
    ``spans``: one more than the largest object and background label,
    where the labels are 0 .. span - 1 (else read off them). Returns what
    :func:`box_sheets` does."""
    nsheet, sheet_obj, sheet_bg, quarters, _, pinch = sweep_tables(conn)
    # per sheet and configuration, the offsets of the sheet's object and
    # background octant from the vertex (an unused sheet's is never read)
    # and its faces
    offsets = step[np.stack([sheet_obj.T, sheet_bg.T], axis=1)]  # (sheet, side, configuration)
    faces = np.ascontiguousarray(quarters.T)
    chunks = [_sheet_labels(base, c_on, offsets[0], faces[0], labels)]
    idx, c = base[rare], c_on[rare]
    for s in range(1, int(nsheet.max(initial=0))):
        more = nsheet[c] > s
        idx, c = idx[more], c[more]
        chunks.append(_sheet_labels(idx, c, offsets[s], faces[s], labels))
    found = _pair_sums(chunks, spans)
    idx, c = base[rare], c_on[rare]
    pinched = pinch[c, 0] >= 0
    # the pinch joins two object octants under 26, two background ones under 6
    ends = labels[1 if conn == 6 else 0].take(step[pinch[c[pinched]]] + idx[pinched, None]).astype(np.int64).reshape(-1, 2)
    found["pairs"] = ends[ends[:, 0] != ends[:, 1]]  # only those that join two pieces
    return found


def _sheet_labels(idx: np.ndarray, c: np.ndarray, offsets: np.ndarray, faces: np.ndarray,
                  labels: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One sheet of each vertex: its object and background labels and its
    faces, read through the offset table of that sheet (2, 256)."""
    at = offsets.take(c, axis=1)
    at += idx
    return labels[0].take(at[0]), labels[1].take(at[1]), faces.take(c)


def _doubled_edges(on: np.ndarray, c_on: np.ndarray, strides: np.ndarray, conn: int) -> int:
    """The doubled lattice edges among boundary vertices ``on`` (flat
    indices on a grid of element ``strides``, ascending) of configurations
    ``c_on``: a spoke doubled at both ends (bit ``2 axis + 1`` of the lower
    end, bit ``2 axis`` of the upper one, the vertex one stride further)."""
    spokes = sweep_tables(conn)[4][c_on]
    some = spokes != 0
    idx, spokes = on[some], spokes[some]
    doubled = 0
    for axis in range(3):
        low = idx[(spokes >> (2 * axis + 1)) & 1 == 1] + strides[axis]
        high = idx[(spokes >> (2 * axis)) & 1 == 1]
        doubled += len(np.intersect1d(low, high, assume_unique=True))
    return doubled


def joined_count(n: int, pairs: np.ndarray) -> int:
    """The components left when pieces labelled ``1 .. n`` are joined by
    the label ``pairs`` (k, 2): hooking every root onto the smallest root
    it is paired with, then pointer jumping, until no pair spans two
    roots.

    Examples
    --------
    >>> joined_count(5, np.array([[1, 2], [4, 2], [5, 5]]))
    3
    """
    root = np.arange(n + 1)
    a, b = pairs[:, 0], pairs[:, 1]
    while True:
        ra, rb = root[a], root[b]
        apart = ra != rb
        if not apart.any():
            return int(np.count_nonzero(root[1:] == np.arange(1, n + 1)))
        a, b, ra, rb = a[apart], b[apart], ra[apart], rb[apart]
        # a root points to a smaller one, so no cycle forms
        np.minimum.at(root, np.maximum(ra, rb), np.minimum(ra, rb))
        while True:
            jumped = root[root]
            if np.array_equal(jumped, root):
                break
            root = jumped


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
    6). The reference of the seams' census (tests/digital/test_outofcore.py);
    :func:`small_census` sums a whole volume's sheets the same way
    (:func:`_sheet_sums`). ``cfg``: ``configurations(vox)``, where the caller
    has it.
    """
    cfg = (configurations(vox) if cfg is None else cfg)[keep]
    origin = np.array([k.indices(n + 1)[0] for k, n in zip(keep, vox.shape)])
    # (C order, both of one shape: the flat views below share these strides)
    obj_padded = np.ascontiguousarray(np.pad(obj_labels, 1))
    bg_padded = np.ascontiguousarray(np.pad(bg_labels, 1, constant_values=outside))
    strides = np.array(obj_padded.strides) // obj_padded.itemsize
    flat = cfg.ravel()
    on = np.flatnonzero(sweep_tables(conn)[0][flat])
    # vertex w's octant d is the padded voxel w + d
    corner = np.unravel_index(on, cfg.shape)
    base = np.asarray(sum((c + o) * s for c, o, s in zip(corner, origin, strides)), np.int64)
    rare = np.flatnonzero(_rare_configurations(conn)[flat[on]])
    return _sheet_sums(base, flat[on], rare, (obj_padded.ravel(), bg_padded.ravel()), _octant_steps(strides), conn)


def _pair_sums(chunks: list[tuple[np.ndarray, np.ndarray, np.ndarray]], spans: tuple[int, int] | None) -> dict:
    """The distinct (``obj``, ``bg``) label pairs of the sheets, in order,
    with each one's ``vertices`` (sheets) and ``quarters`` (summed), from
    chunks of sheets ``(obj, bg, quarter)`` (each quarter below
    :data:`QUARTER_SPAN`).

    A whole volume's labels are 1..n on each side (``spans`` given), so
    the pairs are counted in bins, without sorting, and a sheet's quarters
    in the bin's low digit, so that one unweighted count gives both sums;
    labels spread wider (node keys out of core) are sorted."""
    if spans is None:
        obj, bg = (np.concatenate(part) for part in list(zip(*chunks))[:2])
        if len(obj) == 0:
            return {"obj": obj, "bg": bg, "vertices": np.zeros(0, np.int64), "quarters": np.zeros(0, np.int64)}
        lo_o, lo_b = int(obj.min()), int(bg.min())
        spans = int(obj.max()) - lo_o + 1, int(bg.max()) - lo_b + 1
    else:
        lo_o = lo_b = 0
    span_o, span_b = spans
    if span_o * span_b <= max(1 << 16, 4 * sum(len(chunk[0]) for chunk in chunks)):
        bins = np.zeros(span_o * span_b * QUARTER_SPAN, np.int64)
        for chunk in chunks:
            bins += np.bincount(_pair_keys(*chunk, lo_o, lo_b, span_b), minlength=len(bins))
        counts = bins.reshape(-1, QUARTER_SPAN)
        vertices = counts.sum(axis=1)
        pair = np.flatnonzero(vertices)
        return {"obj": pair // span_b + lo_o, "bg": pair % span_b + lo_b, "vertices": vertices[pair],
                "quarters": counts[pair] @ np.arange(QUARTER_SPAN)}
    obj, bg, quarter = (np.concatenate(part).astype(np.int64) for part in zip(*chunks))
    uo, io = np.unique(obj, return_inverse=True)
    ub, ib = np.unique(bg, return_inverse=True)
    pair, inverse = np.unique(io * len(ub) + ib, return_inverse=True)
    return {
        "obj": uo[pair // len(ub)],
        "bg": ub[pair % len(ub)],
        "vertices": np.bincount(inverse, minlength=len(pair)).astype(np.int64),
        "quarters": np.bincount(inverse, weights=quarter, minlength=len(pair)).astype(np.int64),
    }


def _pair_keys(obj: np.ndarray, bg: np.ndarray, quarter: np.ndarray, lo_o: int, lo_b: int, span_b: int) -> np.ndarray:
    """The bin of every sheet: its pair's, times :data:`QUARTER_SPAN`, plus
    its quarters, computed in place on one int64 array (no temporary per
    step)."""
    key = np.subtract(obj, lo_o, dtype=np.int64)
    key *= span_b
    key += bg
    if lo_b:
        key -= lo_b
    key *= QUARTER_SPAN
    key += quarter
    return key


def empty_census(shape: tuple[int, ...]) -> dict:
    """What :func:`compiled_census` gives for a volume of no voxel (an axis
    of length 0), without the padded copies its passes make.

    Parameters
    ----------
    shape : tuple of int
        The volume's shape (3 axes, one of them 0).

    Returns
    -------
    dict
        No surfaces, pinches, doubled edges or components; the histogram
        of an all-background volume of ``shape``; extent None.

    Examples
    --------
    >>> c = empty_census((0, 2, 2))
    >>> c["surfaces"], c["betti_counts"], int(c["hist"][0])
    ([], (0, 0), 9)
    """
    return {"surfaces": ClosedSurfaces(), "pinched_vertices": 0, "doubled_edges": 0, "hist": empty_histogram(shape),
            "betti_counts": (0, 0), "extent": None}


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


def use_census(vol: np.ndarray, surfaces: bool = True, method: Method = "auto", record: bool = False) -> bool:
    """Whether :func:`compiled_census` counts a 3D volume, with or without
    the ``surfaces``: by :func:`~isoflow.scale.compiled.use_compiled`, whose
    ``"auto"`` threshold is higher with the surfaces (the NumPy census holds
    out to a larger size, as numba's start is then the larger part of the
    compiled one's time) and counts the voxels that ``"auto"`` has already
    sent down the NumPy census in this process (the ski-rental rule: many
    small volumes take the compiled census once they add up to the
    threshold), and with ``"auto"`` also at any size once the compiled
    census is loaded in this process (:func:`census_loaded`): numba's
    start, the one cost that the threshold weighs, is then paid. Both
    passes give the same answer. Never for an empty or a device volume.
    ``record``: the census runs now (the volume is counted in the tally).

    Examples
    --------
    >>> v = np.zeros((4, 4, 4), bool)
    >>> use_census(v, method="numpy"), use_census(np.zeros((0, 4, 4), bool))
    (False, False)
    """
    if vol.ndim != 3 or not isinstance(vol, np.ndarray) or vol.size == 0:
        use_compiled(vol, surfaces, method)  # (refuses "compiled" where it cannot be)
        return False  # (an empty volume: nothing to sweep, no slab to split)
    return use_compiled(vol, surfaces, method, record) or (method == "auto" and census_loaded())


def census_loaded() -> bool:
    """Whether the compiled census is loaded in this process: the sweep's
    module imported and its machine code held by numba, because a compiled
    pass ran here (``method="compiled"``, a large volume, small volumes
    that added up to one under ``"auto"``, ``isoflow info``'s warm-up). A
    question to numba's dispatcher (never a clock, and it never imports
    numba itself).

    Examples
    --------
    >>> from isoflow.scale.compiled import have_numba
    >>> _ = closed_surfaces(np.ones((2, 2, 2), bool), method="compiled") if have_numba() else None
    >>> census_loaded() == have_numba()
    True
    """
    sweep = sys.modules.get("isoflow.scale.sweep")
    return sweep is not None and sweep.loaded()


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
    # a column at a time: NumPy's add.at has a fast path for 1D arrays only
    columns = [np.ascontiguousarray(c) for c in total.reshape(len(total), -1).T]
    order = np.argsort(depth, kind="stable")
    ends = np.searchsorted(depth[order], np.arange(depth.max(initial=0) + 2))
    for d in range(depth.max(initial=0), 0, -1):
        nodes = order[ends[d]:ends[d + 1]]
        parents = up[nodes]
        for column in columns:
            np.add.at(column, parents, column[nodes])
    return np.stack(columns, axis=1).reshape(total.shape)
