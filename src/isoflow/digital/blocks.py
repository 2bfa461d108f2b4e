"""One block of a volume larger than memory, summed up for the report block
by block (:mod:`isoflow.digital.outofcore`).

A 3D block goes through the vertex sweep of the in-memory report
(:func:`isoflow.scale.sweep.sweep` on its bit rows): its runs and gaps are
labelled under the boundary mesh's adjacencies
(:data:`~isoflow.digital.closed_surfaces.MESH_ADJACENCY`), and the
histogram, the components' sums (4 chi and the faces of their boundary)
and the doubled edges are counted at the vertices the block owns. The
block ``[a, b)`` owns along each axis the vertices ``a + 1 .. b`` (and
``0`` when it is the first block), those whose lower voxel is its own;
it counts those whose upper voxel is its own too, ``a + 1 .. b - 1`` (and
``b`` when it is the last, where voxel ``b`` is outside the volume). The
seam between it and the next block counts the vertices ``b``
(:mod:`isoflow.digital.seams`). The background that touches the volume's
border is joined to the outside; elsewhere the block's faces are no
border, and its components end there.

What a block hands on is small:

* the *numbers* of its components on its faces inside the volume (object
  and background in one numbering from 2; 1 is the outside), which become
  node keys ``block << 32 | number`` (:data:`OUTSIDE` for 1), and which
  face voxels are the object's;
* its *pieces*, the components on those faces: their sums at its own
  vertices and cells, together with those of the components they enclose
  that touch no face (whose surfaces are complete: their parent in the tree
  of surfaces, :func:`~isoflow.digital.closed_surfaces.component_parents`,
  is in the block), the place of each piece's first voxel and the key of
  the voxel before it: the component's parent where this is its first
  piece (in block order, then C order in the block; a first voxel at the
  block's low z face that is no border has its voxel before in the block
  below, and is *pending* until the seam between them looks it up);
* the surfaces of its components that touch no face, its histogram and
  voxels, and for the Betti numbers how many of its components touch no
  face once the pinches join them (the connectivity's own components) and
  the pinches between pieces;
* its doubled edges, and the *loose ends* of the doubled spokes whose
  other end it does not count (as keys of the edge: lower vertex, axis).

A 2D block is labelled whole with the connectivity and its complement
(cc3d); it hands on its numbers on the faces, histogram and counts.
"""

from __future__ import annotations

import numpy as np

from ..scale.arrays import binary
from ..scale.compiled import using
from ..scale.labels import label
from .closed_surfaces import MESH_ADJACENCY, component_parents, subtree_sums, surface_counts, sweep_tables
from .configurations import configuration_histogram, configurations
from .connectivity import complement
from .measures import counted_extent, extent_of_rows, shifted

#: a block's numbers live in the low 32 bits of a node key, the block in the high bits
SHIFT = 32
#: the node key of the region outside the array and the background joined to it
OUTSIDE = np.int64(1) << 62
#: a piece's parent is in the block below (see the module docs)
PENDING = -2
#: below this many voxels a block's histogram is one configuration array
_DIRECT_HISTOGRAM = 1 << 18


def node_keys(numbers: np.ndarray, block: int) -> np.ndarray:
    """Node keys of a block's component numbers.

    Parameters
    ----------
    numbers : numpy.ndarray
        A block's numbers (see the module docs): 0 for no component, 1 for
        the outside, 2 and up for the components on its faces.
    block : int
        The block's index in the grid, in C order.

    Returns
    -------
    numpy.ndarray
        int64 keys ``block << 32 | number``; 0 stays 0, 1 becomes
        :data:`OUTSIDE`.

    Examples
    --------
    >>> node_keys(np.array([0, 1, 2, 5], np.uint16), 3).tolist() == [0, int(OUTSIDE), 3 << 32 | 2, 3 << 32 | 5]
    True
    """
    table = np.arange(int(numbers.max(initial=1)) + 1, dtype=np.int64) | (np.int64(block) << SHIFT)
    table[:2] = 0, OUTSIDE
    return table[numbers]


def edge_keys(ends: np.ndarray, origin, shape) -> np.ndarray:
    """Keys of the lattice edges along which doubled spokes point.

    Parameters
    ----------
    ends : numpy.ndarray
        Rows ``(i, j, k, bit)``: a vertex of a box and a spoke of it, bit
        ``2 axis + side`` (side 1 toward +axis), as the sweep and the seams
        give their loose ends.
    origin : sequence of int
        The box's first voxel in the volume.
    shape : sequence of int
        The volume's shape.

    Returns
    -------
    numpy.ndarray
        int64 keys: the volume's vertex index (C order over ``shape + 1``)
        of the edge's lower end, times 3, plus the axis. The two ends of an
        edge give the same key.

    Examples
    --------
    >>> ends = np.array([[1, 2, 3, 5], [1, 2, 4, 4]])  # +z from (1,2,3), -z from (1,2,4)
    >>> edge_keys(ends, (0, 0, 0), (4, 4, 4)).tolist()
    [116, 116]
    """
    ends = np.asarray(ends, np.int64).reshape(-1, 4)
    axis, side = ends[:, 3] >> 1, ends[:, 3] & 1
    lower = ends[:, :3] + np.asarray(origin, np.int64)
    lower[np.arange(len(ends)), axis] -= 1 - side
    return np.ravel_multi_index(tuple(lower.T), tuple(n + 1 for n in shape)) * 3 + axis


def vertex_histogram(vox: np.ndarray, keep_low, keep_high) -> np.ndarray:
    """Configuration counts of a box of vertices around ``vox``.

    Parameters
    ----------
    vox : numpy.ndarray
        A 2D or 3D box of voxels (bool).
    keep_low, keep_high : sequence of bool
        Per axis, whether the vertices of index ``0`` and ``E =
        vox.shape[axis]`` are counted.

    Returns
    -------
    numpy.ndarray
        The 16 (2D) or 256 (3D) configuration counts (int64, section 4) of
        the vertices ``0 .. E`` along each axis (zeros outside ``vox``), less
        the layers left out.

    Notes
    -----
    The whole box is counted by :func:`configuration_histogram` and the
    dropped vertex layers, a thin shell, are subtracted; layer ``k`` along
    an axis needs only the voxel layers ``k-1`` and ``k``, and a layer
    leaves out the vertices already dropped along the axes before it, so
    that none is subtracted twice.

    Examples
    --------
    >>> v = np.ones((2, 2), bool)
    >>> int(vertex_histogram(v, [True, True], [True, True]).sum()), int(vertex_histogram(v, [False, True], [True, False]).sum())
    (9, 4)
    """
    ndim = vox.ndim
    size = 1 << (1 << ndim)
    if vox.size < _DIRECT_HISTOGRAM:
        keep = tuple(slice(0 if lo else 1, None if hi else -1) for lo, hi in zip(keep_low, keep_high))
        return np.bincount(configurations(vox)[keep].ravel(), minlength=size).astype(np.int64)
    hist = configuration_histogram(vox).astype(np.int64)
    kept = []  # per axis, the kept index range of the axes already done
    for axis in range(ndim):
        end = vox.shape[axis]
        for k, keep in ((0, keep_low[axis]), (end, keep_high[axis])):
            if keep:
                continue
            voxels = slice(0, 1) if k == 0 else slice(end - 1, end)
            slab = vox[tuple(voxels if m == axis else slice(None) for m in range(ndim))]
            pick = [slice(None)] * ndim
            pick[axis] = 0 if k == 0 else -1
            for m, rng in enumerate(kept):
                pick[m] = rng
            hist -= np.bincount(configurations(slab)[tuple(pick)].ravel(), minlength=size)
        kept.append(slice(0 if keep_low[axis] else 1, None if keep_high[axis] else -1))
    return hist


def summarize_block(block, index, numblocks, origin, shape, conn: int, where: str, surfaces: bool) -> dict:
    """What one block of a volume hands on to the report block by block.

    Parameters
    ----------
    block : array_like
        The block's voxels (bool, or numbers 0 and 1), 2D or 3D.
    index, numblocks : tuple of int
        The block's place in the grid of blocks, and the grid's size.
    origin : tuple of int
        The block's first voxel in the volume.
    shape : tuple of int
        The volume's shape.
    conn : int
        The connectivity (6 or 26; 4 or 8 in 2D).
    where : str
        The input's name, for messages.
    surfaces : bool
        Whether the closed surfaces and the doubled edges are counted (3D).

    Returns
    -------
    dict
        ``hist`` (the configurations of the vertices it counts), ``voxels``,
        ``faces`` (per face inside the volume its ``n``umbers and its
        ``vox``els), ``extent`` (the voxels' place, in the volume's indices,
        :class:`~isoflow.digital.measures.Extent`), ``nodes``
        and ``pinches`` (for the Betti numbers); with ``surfaces`` in 3D also
        ``pieces``, ``pending``, ``surfaces``, ``doubled``, ``loose`` and
        ``parents`` (see the module docs).

    Raises
    ------
    IsoflowError
        A value other than 0 and 1, named with ``where`` and the voxel.

    Notes
    -----
    It runs on one thread: the blocks run in parallel.

    Examples
    --------
    >>> v = np.zeros((4, 4, 4), bool); v[1:3, 1:3, 2:] = True
    >>> s = summarize_block(v, (0, 0, 0), (1, 1, 2), (0, 0, 0), (4, 4, 8), 6, "v", True)
    >>> int(s["voxels"]), sorted(s["faces"]), len(s["pieces"][0]["key"])
    (8, [('n', 2, 1), ('vox', 2, 1)], 1)
    """
    with using(1):
        # the sweep packs every nonzero byte as set, as in memory: a 3D bool
        # block needs no pass that makes its bytes 0 and 1 (cc3d, in 2D, does)
        core = binary(block, where, near=origin, canonical=np.ndim(block) != 3)
        if core.ndim == 3:
            return _swept_block(core, index, numblocks, origin, shape, conn, surfaces)
        out = _labelled_block(core, index, numblocks, conn)
        out["voxels"], extent = counted_extent(core)
        out["extent"] = shifted(extent, origin, out["voxels"])
        return out


def _ends(index, numblocks) -> tuple[list[bool], list[bool]]:
    """Per axis, whether the block is the first and the last one."""
    return [i == 0 for i in index], [i == n - 1 for i, n in zip(index, numblocks)]


def _inner_faces(index, numblocks):
    """(axis, side) of the block's faces inside the volume."""
    first, last = _ends(index, numblocks)
    return [(axis, side) for axis in range(len(index)) for side in (0, 1) if not (last if side else first)[axis]]


def _numbering(components: dict, sizes: tuple[int, int], outside: np.ndarray) -> tuple[dict, tuple, tuple]:
    """Number the components seen on the faces: object ones from 2 on, then
    background ones, the ``outside`` background components 1.

    ``components``: per (axis, side) the component of every face voxel
    (object components ``0 .. sizes[0] - 1``, then background ones). Returns
    the faces (per (axis, side) the ``n``umbers and which voxels are the
    object's, ``vox``), and per kind the number of every component (0: not
    seen) and whether it was seen."""
    seen = np.zeros(sizes[0] + sizes[1], bool)
    for comp in components.values():
        seen[comp.ravel()] = True
    seen[sizes[0] + outside] = True
    inner = seen.copy()
    inner[sizes[0] + outside] = False
    numbers = np.zeros(len(seen), np.int64)
    numbers[inner] = 2 + np.arange(np.count_nonzero(inner))
    numbers[sizes[0] + outside] = 1
    small = numbers.astype(np.uint16 if 2 + np.count_nonzero(inner) < 1 << 16 else np.uint32)
    faces = {}
    for (axis, side), comp in components.items():
        faces["n", axis, side], faces["vox", axis, side] = small[comp], comp < sizes[0]
    return faces, (numbers[:sizes[0]], numbers[sizes[0]:]), (seen[:sizes[0]], seen[sizes[0]:])


def _labelled_block(core, index, numblocks, conn) -> dict:
    """A 2D block: labels of the object (connectivity) and the background
    (its complement); background labels on the volume's border are the
    outside."""
    first, last = _ends(index, numblocks)
    hist = vertex_histogram(core, first, last)
    labels, sizes = {}, []
    for kind, mask, adj in (("fg", core, conn), ("bg", ~core, complement(core.ndim, conn))):
        labels[kind], n = label(mask, adj, smallest=True)
        sizes.append(n)
    border = [np.take(labels["bg"], 0 if side == 0 else -1, axis=axis) for axis in range(2) for side in (0, 1)
              if (last if side else first)[axis]]
    outside = np.unique(np.concatenate([b.ravel() for b in border] or [np.zeros(0, int)]))
    outside = outside[outside > 0].astype(np.int64) - 1
    components = {}
    for axis, side in _inner_faces(index, numblocks):
        fg, bg = (np.take(labels[kind], -side, axis=axis).astype(np.int64) for kind in ("fg", "bg"))
        components[axis, side] = np.where(fg > 0, fg - 1, sizes[0] + bg - 1)
    faces, _, _ = _numbering(components, tuple(sizes), outside)
    return {"hist": hist, "faces": faces,
            "nodes": {"fg": sizes[0], "bg": sizes[1] - len(outside)}, "pinches": []}


def _swept(core, first, last, conn: int, surfaces: bool):
    """The sweep of a block at the vertices it counts, its background on the
    volume's border joined to the outside; with its bit rows and their
    offsets."""
    from ..scale import bitrows, kernels, sweep

    bits, off, goff = bitrows.pack(core)
    obj_adj, bg_adj = MESH_ADJACENCY[conn]
    counted = np.array([[0 if f else 1 for f in first], [n + 1 if e else n for n, e in zip(core.shape, last)]])
    found = sweep.sweep(bits, core.shape, off, goff, kernels.ADJACENCY[obj_adj] + kernels.ADJACENCY[bg_adj],
                        sweep_tables(conn), pinch_objects=conn == 26, surfaces=surfaces, counted=counted,
                        border=[flag for f, e in zip(first, last) for flag in (f, e)])
    counts, sums, ends_lo, ends_hi = bitrows.row_extents(bits)
    found["voxels"] = int(counts.sum())
    found["extent"] = extent_of_rows(counts, sums, ends_lo, ends_hi, core.shape)
    return found, bits, off, goff


def _swept_block(core, index, numblocks, origin, shape, conn: int, surfaces: bool) -> dict:
    """A 3D block through the sweep (see the module docs)."""
    from ..scale.sweep import face_components

    first, last = _ends(index, numblocks)
    found, bits, off, goff = _swept(core, first, last, conn, surfaces)
    parents = found["parents"]
    sizes = tuple(len(r) for r in found["roots"])
    outside = int(parents[1][-1])
    components = {(axis, side): face_components(bits, off, goff, parents, sizes, core.shape, axis, side)
                  for axis, side in _inner_faces(index, numblocks)}
    faces, numbers, seen = _numbering(components, sizes, np.array([outside]))
    block = int(np.ravel_multi_index(index, numblocks))
    keys = np.concatenate([node_keys(numbers[0], block), node_keys(numbers[1], block)])
    keys[(np.concatenate(seen) == 0)] = -1
    out = {"hist": found["hist"], "voxels": found["voxels"], "faces": faces,
           "extent": shifted(found["extent"], origin, found["voxels"])}
    out.update(_betti_nodes(found, keys, seen, sizes, outside, conn))
    if surfaces:
        starts = (bits[:-1, 0] & 1).astype(np.int64)  # the rows that start with a run
        out.update(_pieces(found, keys, seen, off, goff, starts, block, first[2]))
        out["doubled"] = found["doubled"]
        out["loose"] = [edge_keys(found["loose"], origin, shape)]
    return out


def _betti_nodes(found: dict, keys: np.ndarray, seen, sizes, outside: int, conn: int) -> dict:
    """For the Betti numbers: per kind the block's nodes (its components
    that touch no face, once the pinches join them, and its pieces; not the
    outside) and the pinches between pieces (pairs of keys to join), on the
    side the pinches join (the object under 26, the background under 6)."""
    from ..scale.kernels import join_pairs

    nodes = {"fg": sizes[0], "bg": sizes[1] - 1}  # (the outside is one node of the whole volume)
    kind = 0 if conn == 26 else 1
    pairs = found["parents"][kind][found["pairs"]]
    if not len(pairs):
        return {"nodes": nodes, "pinches": []}
    cluster = np.arange(sizes[kind], dtype=np.int32)
    join_pairs(cluster, pairs)
    mine = keys[:sizes[0]] if kind == 0 else keys[sizes[0]:]
    has_piece = np.zeros(sizes[kind], bool)
    has_piece[cluster[seen[kind]]] = True
    roots = cluster == np.arange(sizes[kind])
    name = "fg" if kind == 0 else "bg"
    nodes[name] = int(np.count_nonzero(roots & ~has_piece)) + int(np.count_nonzero(seen[kind])) - kind
    pieces = np.flatnonzero(seen[kind])
    pieces = pieces[np.argsort(cluster[pieces], kind="stable")]
    same = cluster[pieces[1:]] == cluster[pieces[:-1]]
    return {"nodes": nodes, "pinches": [np.stack([mine[pieces[:-1][same]], mine[pieces[1:][same]]])]}


def _pieces(found, keys, seen, off, goff, starts, block: int, bottom: bool) -> dict:
    """The pieces (keys, side, sums, order, parent), the pending parents and
    the surfaces of the block's components that touch no face."""
    roots, parents = found["roots"], found["parents"]
    up, outside = component_parents(roots, parents, off, goff, starts)
    n = len(up)
    piece = np.concatenate(seen)
    piece[outside] = True
    # the pieces and the outside are the roots of the block's forest
    cut = np.append(np.where(piece, n, up), n)
    signed = np.concatenate([found["sums"][0], -found["sums"][1], np.zeros((1, 2), np.int64)])
    total = subtree_sums(cut, n, signed)[:n]
    nobj = len(roots[0])
    inner = ~piece
    private = total[inner] * np.where(np.flatnonzero(inner) < nobj, 1, -1)[:, None]
    vertices, faces = surface_counts(private)
    # the key of the voxel before each component's first one: in the block,
    # the outside, or for a first voxel on the low z face, the block below's
    parent = keys[up]
    rows, row_start = _first_rows(roots, off, goff, starts)
    parent[row_start] = OUTSIDE if bottom else PENDING
    mine = piece.copy()
    mine[outside] = False
    first = np.concatenate(roots)
    pending = mine & row_start & (not bottom)
    return {
        "pieces": [{"key": keys[mine], "obj": np.flatnonzero(mine) < nobj, "sums": total[mine],
                    "order": (np.int64(block) << SHIFT) | first[mine], "parent": parent[mine]}],
        "pending": [(rows[pending], keys[pending])],
        "surfaces": [np.stack([vertices, faces], axis=1)],
        "parents": [],
    }


def _first_rows(roots, off, goff, starts) -> tuple[np.ndarray, np.ndarray]:
    """Each component's first row (object components first), and whether
    its first voxel starts the row (its first run, in a row that starts
    with a run; its first gap, in one that starts with a gap)."""
    nrows = len(starts)
    obj = np.minimum(np.searchsorted(off, roots[0], side="right") - 1, nrows - 1)
    bg = np.minimum(np.searchsorted(goff, roots[1], side="right") - 1, nrows - 1)
    at_start = np.concatenate([(roots[0] == off[obj]) & (starts[obj] == 1), (roots[1] == goff[bg]) & (starts[bg] == 0)])
    return np.concatenate([obj, bg]), at_start
